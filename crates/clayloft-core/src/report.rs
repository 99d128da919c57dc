//! What the constraint stages found and did: each correction (or, with enforcement off, each
//! violation) with where it is (layers, number of points) and how much (mm).

use std::fmt;

/// Which limit a finding is about.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FindingKind {
    /// The large-scale shape leaned past the overhang limit.
    Overhang,
    /// Horizontal control lines: layer heights or the z range under the nozzle holder.
    HorizontalLines,
    /// The texture's amplitude would break the overhang limit.
    Texture,
    /// The base fill: a foot narrower than a bead somewhere.
    Base,
    /// The wall's layers where the spiral leaves the flat layer (the path ahead of the design).
    Layers,
    /// Vertical control lines pushing a concave stretch out past its curvature: the wall's
    /// folds cut off at their corners (`geometry::trim_swallowtails`).
    Folds,
}

/// One correction or violation, over a range of layers.
#[derive(Debug, Clone, PartialEq)]
pub struct Finding {
    pub kind: FindingKind,
    /// True when the surface was changed to satisfy the limit; false when only reported.
    pub corrected: bool,
    /// First and last layer concerned (inclusive).
    pub layers: (usize, usize),
    /// Number of surface points concerned.
    pub points: usize,
    /// Largest change (corrected) or excess (violation), mm.
    pub amount_mm: f64,
    pub message: String,
}

impl fmt::Display for Finding {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let verb = if self.corrected {
            "corrected"
        } else {
            "VIOLATION"
        };
        let (first, last) = self.layers;
        if first == last {
            write!(f, "{verb}: layer {first}, ")?;
        } else {
            write!(f, "{verb}: layers {first}–{last}, ")?;
        }
        let points = if self.points == 1 { "point" } else { "points" };
        write!(
            f,
            "{} {points}, up to {:.2} mm: {}",
            self.points, self.amount_mm, self.message
        )
    }
}

/// A single point that a stage moved (or would have to move): layer, sample, amount in mm.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointEvent {
    pub layer: usize,
    pub sample: usize,
    pub amount_mm: f64,
}

/// Groups point events into findings, one per run of consecutive layers (a gap of more than
/// `gap` layers starts a new finding). `describe` writes the message for a run.
pub fn group_events(
    events: &[PointEvent],
    kind: FindingKind,
    corrected: bool,
    gap: usize,
    describe: impl Fn(f64) -> String,
) -> Vec<Finding> {
    let mut sorted: Vec<PointEvent> = events.to_vec();
    sorted.sort_by_key(|e| (e.layer, e.sample));
    let mut out: Vec<Finding> = Vec::new();
    for e in sorted {
        match out.last_mut() {
            Some(f) if e.layer <= f.layers.1.saturating_add(gap) => {
                f.layers.1 = f.layers.1.max(e.layer);
                f.points += 1;
                f.amount_mm = f.amount_mm.max(e.amount_mm);
            }
            _ => out.push(Finding {
                kind,
                corrected,
                layers: (e.layer, e.layer),
                points: 1,
                amount_mm: e.amount_mm,
                message: String::new(),
            }),
        }
    }
    for f in &mut out {
        f.message = describe(f.amount_mm);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn events_group_into_layer_runs() {
        let ev = |layer, amount_mm| PointEvent {
            layer,
            sample: 0,
            amount_mm,
        };
        let f = group_events(
            &[ev(3, 0.5), ev(4, 1.5), ev(5, 0.2), ev(40, 0.1)],
            FindingKind::Overhang,
            true,
            2,
            |a| format!("max {a}"),
        );
        assert_eq!(f.len(), 2);
        assert_eq!((f[0].layers, f[0].points, f[0].amount_mm), ((3, 5), 3, 1.5));
        assert_eq!(f[1].layers, (40, 40));
        assert!(
            f[0].to_string()
                .starts_with("corrected: layers 3–5, 3 points")
        );
        // One layer, one point: said so ("layers 40–40, 1 points" before).
        assert_eq!(
            f[1].to_string(),
            "corrected: layer 40, 1 point, up to 0.10 mm: max 0.1"
        );
    }
}
