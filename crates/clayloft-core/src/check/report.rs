//! What the checker measured and which limits were broken, and how that reads.

use std::fmt;

use glam::DVec3;

/// One kind of limit broken, with how often, how badly and where first.
#[derive(Debug, Clone, PartialEq)]
pub struct Violation {
    pub what: &'static str,
    pub count: usize,
    pub worst: f64,
    /// What `worst` measures, written after it (" mm short", "°"); empty where it measures
    /// nothing (a point off the bed).
    pub unit: &'static str,
    pub first_line: usize,
    pub detail: String,
}

/// The checker's line for a violation: "VIOLATION overhang: 528 moves, worst 77.528°, first at
/// line 1552 (wall leans past 45°)".
impl fmt::Display for Violation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "VIOLATION {}: {} {}{}, first at line {} ({})",
            self.what,
            self.count,
            if self.count == 1 { "move" } else { "moves" },
            self.worst_said(3),
            self.first_line,
            self.detail
        )
    }
}

impl Violation {
    /// ", worst 0.19 mm short" with `decimals`, or nothing where `worst` measures nothing.
    pub fn worst_said(&self, decimals: usize) -> String {
        if self.unit.is_empty() {
            String::new()
        } else {
            format!(", worst {:.*}{}", decimals, self.worst, self.unit)
        }
    }
}

/// What the checker measured.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct CheckReport {
    pub moves: usize,
    pub extruding_moves: usize,
    pub path_length_mm: f64,
    pub max_overhang_deg: f64,
    pub min_layer_height: f64,
    pub max_layer_height: f64,
    /// Largest height of already printed material above the nozzle tip, mm.
    pub max_rise_above_tip: f64,
    pub bounds_min: DVec3,
    pub bounds_max: DVec3,
    pub violations: Vec<Violation>,
    /// Every point that broke the overhang, support or collision limit, in path order.
    pub events: Vec<PathEvent>,
}

/// One point of the path that broke a limit: where (G-code line, or point index for
/// [`check_path`](super::check_path)), which limit and by how much (degrees or mm).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PathEvent {
    pub line: usize,
    pub what: &'static str,
    pub value: f64,
}

/// What the nozzle holder hitting the printed part is called in reports.
pub const COLLISION: &str = "nozzle collision";
/// What a point leaning past the overhang limit is called in reports.
pub const OVERHANG: &str = "overhang";
/// What a point with nothing under it is called in reports.
pub const UNSUPPORTED: &str = "unsupported";
/// What a path the layer search could not measure within its budget is called in reports.
pub const NOT_MEASURED: &str = "not measurable";
/// What a point outside the bed or above the build height is called in reports.
pub const OUTSIDE: &str = "outside the machine";
/// What a move without extrusion between the first and last extruding move is called in
/// reports.
pub const NOT_CONTINUOUS: &str = "not one continuous path";
/// What the path crossing itself within its layer is called in reports.
pub const CROSSING: &str = "path crosses itself";
/// What a move that draws the paste back is called in reports.
pub const RETRACTION: &str = "retraction";

impl CheckReport {
    pub fn ok(&self) -> bool {
        self.violations.is_empty()
    }
}

impl fmt::Display for CheckReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "moves: {} ({} extruding), path length {:.1} mm",
            self.moves, self.extruding_moves, self.path_length_mm
        )?;
        writeln!(
            f,
            "printed extent: x {:.1} … {:.1}, y {:.1} … {:.1}, z {:.2} … {:.2} mm",
            self.bounds_min.x,
            self.bounds_max.x,
            self.bounds_min.y,
            self.bounds_max.y,
            self.bounds_min.z,
            self.bounds_max.z
        )?;
        writeln!(f, "max overhang: {:.1}°", self.max_overhang_deg)?;
        writeln!(
            f,
            "layer height: {:.3} … {:.3} mm",
            self.min_layer_height, self.max_layer_height
        )?;
        writeln!(
            f,
            "printed part above nozzle tip: up to {:.2} mm",
            self.max_rise_above_tip
        )?;
        if self.ok() {
            write!(f, "all limits hold")
        } else {
            for v in &self.violations {
                writeln!(f, "{v}")?;
            }
            write!(f, "{} limit(s) broken", self.violations.len())
        }
    }
}

/// Collects violations of one kind.
#[derive(Debug, Default, PartialEq)]
pub(super) struct Tally {
    count: usize,
    worst: f64,
    first_line: usize,
}

impl Tally {
    /// The violation this tally records, if any.
    pub(super) fn into_violation(
        self,
        what: &'static str,
        unit: &'static str,
        detail: String,
    ) -> Option<Violation> {
        (self.count > 0).then_some(Violation {
            what,
            count: self.count,
            worst: self.worst,
            unit,
            first_line: self.first_line,
            detail,
        })
    }

    /// This tally followed by `later`'s (of what comes after in the path): as if every value
    /// had been added to one, in order.
    pub(super) fn then(self, later: Tally) -> Tally {
        match (self.count, later.count) {
            (0, _) => later,
            (_, 0) => self,
            _ => Tally {
                count: self.count + later.count,
                worst: self.worst.max(later.worst),
                first_line: self.first_line,
            },
        }
    }

    pub(super) fn add(&mut self, value: f64, line: usize) {
        if self.count == 0 {
            self.first_line = line;
            self.worst = value;
        }
        self.count += 1;
        self.worst = self.worst.max(value);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One move is "1 move", more are "moves" (a refusal quoted "1 moves").
    #[test]
    fn a_violation_counts_its_moves_in_words() {
        let mut v = Violation {
            what: "layer too thin",
            count: 1,
            worst: 0.015,
            unit: " mm short",
            first_line: 20421,
            detail: "below min_layer_height 0.25 mm".into(),
        };
        assert_eq!(
            v.to_string(),
            "VIOLATION layer too thin: 1 move, worst 0.015 mm short, first at line 20421 (below min_layer_height 0.25 mm)"
        );
        v.count = 2;
        assert!(v.to_string().contains(": 2 moves, worst"), "{v}");
    }
}
