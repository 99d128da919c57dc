//! The G-code checker (SPEC §2, §7): re-measures a G-code file alone against the printer's limits.
//!
//! * Single continuous path: between the first and the last extruding move every move extrudes;
//!   no retraction anywhere.
//! * Inside the machine: every move's end point on the bed and within 0 ..= max_z.
//! * Layer height and overhang: for each path vertex p, the layer below is the topmost earlier
//!   path (more than a few line widths back along the path, at least a quarter of the minimum
//!   layer height lower) within a search radius in XY. Local layer height = p.z − z below; the lean
//!   is `atan(d / height)` with d the XY distance to that layer. Points low enough rest on the bed.
//! * Collision: the highest earlier printed point may rise at most `nozzle_length` above the
//!   nozzle tip (the holder is treated as a plane `nozzle_length` above the tip).

use std::collections::HashMap;
use std::fmt;

use glam::{DVec2, DVec3};

use crate::design::Printer;
use crate::gcode::LIMITS_KEY;
use crate::geometry::point_segment_distance;

/// The printer limits a G-code file is checked against.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Limits {
    pub bed_x: f64,
    pub bed_y: f64,
    pub max_z: f64,
    pub line_width: f64,
    pub min_layer_height: f64,
    pub max_layer_height: f64,
    pub nozzle_length: f64,
    pub max_overhang_deg: f64,
}

impl From<&Printer> for Limits {
    fn from(p: &Printer) -> Limits {
        Limits {
            bed_x: p.bed_x,
            bed_y: p.bed_y,
            max_z: p.max_z,
            line_width: p.line_width,
            min_layer_height: p.min_layer_height,
            max_layer_height: p.max_layer_height,
            nozzle_length: p.nozzle_length,
            max_overhang_deg: p.max_overhang_deg,
        }
    }
}

impl Limits {
    /// Limits written in a Clayloft G-code header, if present; missing keys keep the defaults.
    pub fn from_header(text: &str) -> Option<Limits> {
        let line = text.lines().take(200).find(|l| l.starts_with(LIMITS_KEY))?;
        let mut l = Limits::from(&Printer::default());
        for kv in line[LIMITS_KEY.len()..].split_whitespace() {
            let Some((k, v)) = kv.split_once('=') else {
                continue;
            };
            let Ok(v) = v.parse::<f64>() else { continue };
            if !v.is_finite() || v <= 0.0 {
                continue;
            }
            match k {
                "bed_x" => l.bed_x = v,
                "bed_y" => l.bed_y = v,
                "max_z" => l.max_z = v,
                "line_width" => l.line_width = v,
                "min_layer_height" => l.min_layer_height = v,
                "max_layer_height" => l.max_layer_height = v,
                "nozzle_length" => l.nozzle_length = v,
                "max_overhang_deg" => l.max_overhang_deg = v,
                _ => {}
            }
        }
        Some(l)
    }
}

/// A G-code file that cannot be read as G-code.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("line {line}: {message}")]
pub struct GcodeError {
    pub line: usize,
    pub message: String,
}

/// One positioning move.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Move {
    pub to: DVec3,
    /// Filament/clay advanced by this move (negative = retraction).
    pub de: f64,
    /// 1-based line number in the file.
    pub line: usize,
}

/// Parses the moves of a G-code program (G0/G1 with G90/G91, M82/M83, G92, G20/G21).
pub fn parse_moves(text: &str) -> Result<(Vec<Move>, DVec3), GcodeError> {
    let mut moves = Vec::new();
    let mut pos = DVec3::ZERO;
    let mut start = None;
    let mut e = 0.0;
    let (mut absolute_xyz, mut absolute_e) = (true, true);
    for (idx, raw) in text.lines().enumerate() {
        let line = idx + 1;
        // Drop the comment and a host checksum (`*nn`).
        let code = raw
            .split(';')
            .next()
            .unwrap_or("")
            .split('*')
            .next()
            .unwrap_or("")
            .trim();
        if code.is_empty() {
            continue;
        }
        let mut words = code.split_whitespace();
        let Some(mut cmd) = words.next() else {
            continue;
        };
        // A line number (`N12 G1 …`) comes before the command.
        if cmd.starts_with(['N', 'n']) && cmd[1..].parse::<u64>().is_ok() {
            let Some(next) = words.next() else { continue };
            cmd = next;
        }
        let arg = |letter: char| -> Result<Option<f64>, GcodeError> {
            for w in code.split_whitespace().skip(1) {
                let mut chars = w.chars();
                if chars.next().map(|c| c.to_ascii_uppercase()) == Some(letter) {
                    let v: f64 = chars.as_str().parse().map_err(|_| GcodeError {
                        line,
                        message: format!("`{w}` is not a number"),
                    })?;
                    if !v.is_finite() {
                        return Err(GcodeError {
                            line,
                            message: format!("`{w}` is not finite"),
                        });
                    }
                    return Ok(Some(v));
                }
            }
            Ok(None)
        };
        match cmd.to_ascii_uppercase().as_str() {
            "G0" | "G1" | "G00" | "G01" => {
                let (x, y, z, ev) = (arg('X')?, arg('Y')?, arg('Z')?, arg('E')?);
                let mut to = pos;
                for (v, c) in [(x, 0), (y, 1), (z, 2)] {
                    if let Some(v) = v {
                        to[c] = if absolute_xyz { v } else { to[c] + v };
                    }
                }
                let de = match ev {
                    Some(v) if absolute_e => {
                        let d = v - e;
                        e = v;
                        d
                    }
                    Some(v) => v,
                    None => 0.0,
                };
                if start.is_none() {
                    start = Some(pos);
                }
                moves.push(Move { to, de, line });
                pos = to;
            }
            "G90" => absolute_xyz = true,
            "G91" => absolute_xyz = false,
            "M82" => absolute_e = true,
            "M83" => absolute_e = false,
            "G92" => {
                if let Some(v) = arg('E')? {
                    e = v;
                }
                for (letter, c) in [('X', 0), ('Y', 1), ('Z', 2)] {
                    if let Some(v) = arg(letter)? {
                        pos[c] = v;
                    }
                }
            }
            "G20" => {
                return Err(GcodeError {
                    line,
                    message: "inch units (G20) are not supported".into(),
                });
            }
            "G28" => pos = DVec3::ZERO,
            c if c.starts_with(['G', 'M', 'T', 'N', 'F', 'S']) && c[1..].parse::<f64>().is_ok() => {
            }
            other => {
                return Err(GcodeError {
                    line,
                    message: format!("`{other}` is not a G-code command"),
                });
            }
        }
    }
    Ok((moves, start.unwrap_or(DVec3::ZERO)))
}

/// One kind of limit broken, with how often, how badly and where first.
#[derive(Debug, Clone, PartialEq)]
pub struct Violation {
    pub what: &'static str,
    pub count: usize,
    pub worst: f64,
    pub first_line: usize,
    pub detail: String,
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
/// [`check_path`]), which limit and by how much (degrees or mm).
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
                writeln!(
                    f,
                    "VIOLATION {}: {} moves, worst {:.3}, first at line {} ({})",
                    v.what, v.count, v.worst, v.first_line, v.detail
                )?;
            }
            write!(f, "{} limit(s) broken", self.violations.len())
        }
    }
}

/// Collects violations of one kind.
#[derive(Default)]
struct Tally {
    count: usize,
    worst: f64,
    first_line: usize,
}

impl Tally {
    /// The violation this tally records, if any.
    fn into_violation(self, what: &'static str, detail: String) -> Option<Violation> {
        (self.count > 0).then_some(Violation {
            what,
            count: self.count,
            worst: self.worst,
            first_line: self.first_line,
            detail,
        })
    }

    fn add(&mut self, value: f64, line: usize) {
        if self.count == 0 {
            self.first_line = line;
            self.worst = value;
        }
        self.count += 1;
        self.worst = self.worst.max(value);
    }
}

/// Re-measures a G-code program against `limits`. Errors only when the text is not G-code.
pub fn check_gcode(text: &str, limits: &Limits) -> Result<CheckReport, GcodeError> {
    let (moves, start) = parse_moves(text)?;
    if moves.is_empty() {
        return Err(GcodeError {
            line: 1,
            message: "there are no moves to check".into(),
        });
    }
    let mut report = CheckReport {
        moves: moves.len(),
        ..Default::default()
    };
    let mut lo = DVec3::splat(f64::INFINITY);
    let mut hi = DVec3::splat(f64::NEG_INFINITY);
    let (mut outside, mut travel, mut retract) =
        (Tally::default(), Tally::default(), Tally::default());
    let first_ext = moves.iter().position(|m| m.de > 0.0);
    let last_ext = moves.iter().rposition(|m| m.de > 0.0);
    let mut prev = start;
    for (k, m) in moves.iter().enumerate() {
        if m.de > 0.0 {
            lo = lo.min(m.to);
            hi = hi.max(m.to);
        }
        let eps = 1e-6;
        if m.to.x < -eps
            || m.to.y < -eps
            || m.to.x > limits.bed_x + eps
            || m.to.y > limits.bed_y + eps
            || m.to.z < -eps
            || m.to.z > limits.max_z + eps
        {
            outside.add(0.0, m.line);
        }
        if m.de < 0.0 {
            retract.add(-m.de, m.line);
        }
        if let (Some(a), Some(b)) = (first_ext, last_ext)
            && k > a
            && k <= b
            && m.de <= 0.0
            && m.to != prev
        {
            travel.add(m.to.distance(prev), m.line);
        }
        prev = m.to;
    }
    if lo.is_finite() {
        report.bounds_min = lo;
        report.bounds_max = hi;
    }
    report.violations.extend(
        [
            outside.into_violation(
                "outside the machine",
                format!("bed 0 … {} × 0 … {} mm, height 0 … {} mm", limits.bed_x, limits.bed_y, limits.max_z),
            ),
            travel.into_violation(
                "not one continuous path",
                "moves without extrusion between the first and last extruding move (worst = longest, mm)".into(),
            ),
            retract.into_violation("retraction", "clay printing allows no retraction (worst = mm of E)".into()),
        ]
        .into_iter()
        .flatten(),
    );
    if let (Some(a), Some(b)) = (first_ext, last_ext) {
        let mut vertices = Vec::with_capacity(b - a + 2);
        let mut lines = Vec::with_capacity(b - a + 2);
        vertices.push(if a == 0 { start } else { moves[a - 1].to });
        lines.push(moves[a].line);
        for m in &moves[a..=b] {
            vertices.push(m.to);
            lines.push(m.line);
        }
        report.extruding_moves = moves[a..=b].iter().filter(|m| m.de > 0.0).count();
        measure_layers(&vertices, &lines, limits, &mut report);
    }
    Ok(report)
}

/// Measures an extruding path (layer heights, overhang, support, holder collision) given as
/// points; the `line` of each event and violation is the point index. The app's nozzle replay
/// uses this on the toolpath so that it flags exactly what `clayloft check` would.
pub fn check_path(points: &[DVec3], limits: &Limits) -> CheckReport {
    let mut report = CheckReport {
        moves: points.len(),
        extruding_moves: points.len().saturating_sub(1),
        ..Default::default()
    };
    if points.len() >= 2 {
        let lines: Vec<usize> = (0..points.len()).collect();
        measure_layers(points, &lines, limits, &mut report);
    }
    report
}

/// Spatial hash of path segments in (x, y, z-band) cells.
struct SegmentGrid {
    cell: f64,
    band: f64,
    cells: HashMap<(i32, i32, i32), Vec<u32>>,
}

impl SegmentGrid {
    fn key(&self, p: DVec2, z: f64) -> (i32, i32, i32) {
        (
            (p.x / self.cell).floor() as i32,
            (p.y / self.cell).floor() as i32,
            (z / self.band).floor() as i32,
        )
    }

    fn insert(&mut self, id: u32, a: DVec3, b: DVec3) {
        let (k0, k1) = (
            self.key(a.truncate().min(b.truncate()), a.z.min(b.z)),
            self.key(a.truncate().max(b.truncate()), a.z.max(b.z)),
        );
        for x in k0.0..=k1.0 {
            for y in k0.1..=k1.1 {
                for z in k0.2..=k1.2 {
                    self.cells.entry((x, y, z)).or_default().push(id);
                }
            }
        }
    }
}

fn measure_layers(v: &[DVec3], lines: &[usize], limits: &Limits, report: &mut CheckReport) {
    let tan_max = limits.max_overhang_deg.to_radians().tan();
    let radius = limits.line_width + 2.0 * limits.max_layer_height * tan_max;
    let gap = 3.0 * radius;
    let below_tol = 0.25 * limits.min_layer_height;
    let reach = 2.0 * limits.max_layer_height + below_tol;
    let mut grid = SegmentGrid {
        cell: radius,
        band: limits.max_layer_height,
        cells: HashMap::new(),
    };
    let mut cum = vec![0.0; v.len()];
    for j in 1..v.len() {
        cum[j] = cum[j - 1] + v[j - 1].distance(v[j]);
    }
    report.path_length_mm = cum[v.len() - 1];
    let (mut thin, mut thick, mut lean, mut unsupported, mut collide) = (
        Tally::default(),
        Tally::default(),
        Tally::default(),
        Tally::default(),
        Tally::default(),
    );
    report.min_layer_height = f64::INFINITY;
    let mut running_max_z = f64::NEG_INFINITY;
    let mut pending = 0usize; // next segment (pending → pending + 1) to insert
    let layer_tol = 0.01 * limits.max_layer_height + 0.002;
    // Degrees: G-code coordinates are rounded to 1 µm and the lean is measured against polyline
    // segments; the seam step where the helix leaves the flat revolution leans up to ~2° more
    // than the sections around it for one point.
    let angle_tol = 2.0;
    for j in 0..v.len() {
        let p = v[j];
        // Every earlier segment is a candidate; the bead just laid is told apart below.
        while pending < j {
            grid.insert(pending as u32, v[pending], v[pending + 1]);
            pending += 1;
        }
        if running_max_z - p.z > report.max_rise_above_tip {
            report.max_rise_above_tip = running_max_z - p.z;
        }
        if running_max_z - p.z > limits.nozzle_length + 1e-6 {
            collide.add(running_max_z - p.z, lines[j]);
            report.events.push(PathEvent {
                line: lines[j],
                what: COLLISION,
                value: running_max_z - p.z,
            });
        }
        running_max_z = running_max_z.max(p.z);
        if j == 0 {
            continue;
        }
        // The topmost earlier layer below p within the search radius.
        let pxy = p.truncate();
        let (k_lo, k_hi) = (
            grid.key(pxy - radius, p.z - reach),
            grid.key(pxy + radius, p.z - below_tol),
        );
        let mut found: Vec<(f64, f64)> = Vec::new();
        for x in k_lo.0..=k_hi.0 {
            for y in k_lo.1..=k_hi.1 {
                for z in k_lo.2..=k_hi.2 {
                    let Some(ids) = grid.cells.get(&(x, y, z)) else {
                        continue;
                    };
                    for &id in ids {
                        let (a, b) = (v[id as usize], v[id as usize + 1]);
                        // Distance across the segment's line, for feet of the perpendicular on
                        // the segment or just past its ends; a segment entirely ahead of or
                        // behind p along its own direction is beside p, not under it.
                        let (a2, b2) = (a.truncate(), b.truncate());
                        let ab = b2 - a2;
                        let len2 = ab.length_squared();
                        // A steep segment (rising more than it runs) is a step between layers,
                        // not a layer to rest on.
                        if (b.z - a.z).powi(2) > len2 {
                            continue;
                        }
                        let f_line = if len2 > 0.0 {
                            (pxy - a2).dot(ab) / len2
                        } else {
                            0.0
                        };
                        if !(-0.5..=1.5).contains(&f_line) {
                            continue;
                        }
                        let (d_end, f) = point_segment_distance(pxy, a2, b2);
                        let d = if len2 > 0.0 {
                            ab.perp_dot(pxy - a2).abs() / len2.sqrt()
                        } else {
                            d_end
                        };
                        let zq = a.z + (b.z - a.z) * f;
                        // The bead just laid: reached from p along an almost straight stretch of
                        // path. Where the path has come back over itself (the next revolution,
                        // the centre of a spiral base) the layer below is much nearer in XY than
                        // along the path.
                        let along = cum[j]
                            - (cum[id as usize] + f * (cum[id as usize + 1] - cum[id as usize]));
                        if along < gap && d >= 0.5 * along {
                            continue;
                        }
                        if d <= radius && zq <= p.z - below_tol && zq >= p.z - reach {
                            found.push((zq, d));
                        }
                    }
                }
            }
        }
        // Support: the topmost layer within half a bead of p; failing that, the nearest layer.
        let half_bead = 0.5 * limits.line_width;
        let top_under = found
            .iter()
            .filter(|(_, d)| *d <= half_bead)
            .map(|(z, _)| *z)
            .fold(f64::NEG_INFINITY, f64::max);
        let (height, offset) = if top_under.is_finite() {
            let offset = found
                .iter()
                .filter(|(z, _)| *z >= top_under - below_tol)
                .map(|(_, d)| *d)
                .fold(f64::INFINITY, f64::min);
            (p.z - top_under, offset)
        } else if let Some(&(z, d)) = found.iter().min_by(|a, b| a.1.total_cmp(&b.1)) {
            (p.z - z, d)
        } else if p.z <= limits.max_layer_height + layer_tol {
            (p.z, 0.0) // on the bed
        } else {
            unsupported.add(p.z, lines[j]);
            report.events.push(PathEvent {
                line: lines[j],
                what: UNSUPPORTED,
                value: p.z,
            });
            continue;
        };
        report.min_layer_height = report.min_layer_height.min(height);
        report.max_layer_height = report.max_layer_height.max(height);
        if height < limits.min_layer_height - layer_tol {
            thin.add(limits.min_layer_height - height, lines[j]);
        }
        if height > limits.max_layer_height + layer_tol {
            thick.add(height - limits.max_layer_height, lines[j]);
        }
        let angle = offset.atan2(height.max(1e-9)).to_degrees();
        report.max_overhang_deg = report.max_overhang_deg.max(angle);
        if angle > limits.max_overhang_deg + angle_tol {
            lean.add(angle, lines[j]);
            report.events.push(PathEvent {
                line: lines[j],
                what: OVERHANG,
                value: angle,
            });
        }
    }
    if !report.min_layer_height.is_finite() {
        report.min_layer_height = 0.0;
    }
    let mut push = |t: Tally, what: &'static str, detail: String| {
        report.violations.extend(t.into_violation(what, detail))
    };
    push(
        thin,
        "layer too thin",
        format!(
            "below min_layer_height {} mm (worst = mm short)",
            limits.min_layer_height
        ),
    );
    push(
        thick,
        "layer too thick",
        format!(
            "above max_layer_height {} mm (worst = mm over)",
            limits.max_layer_height
        ),
    );
    push(
        lean,
        OVERHANG,
        format!(
            "wall leans past {}° (worst = degrees)",
            limits.max_overhang_deg
        ),
    );
    push(
        unsupported,
        UNSUPPORTED,
        format!("no printed layer within {radius:.1} mm below (worst = z, mm)"),
    );
    push(
        collide,
        COLLISION,
        format!(
            "printed part rises above the holder, nozzle_length {} mm (worst = mm)",
            limits.nozzle_length
        ),
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    fn limits() -> Limits {
        Limits::from(&Printer::default())
    }

    fn helix(radius_per_layer: f64, layers: usize, h: f64) -> String {
        let mut s = String::from("G21\nG90\nM83\nG0 X120 Y95 Z1\n");
        let n = 100;
        for k in 0..layers * n {
            let t = (k + 1) as f64 / n as f64;
            let a = std::f64::consts::TAU * t;
            let r = 30.0 + radius_per_layer * t;
            // Flat first revolution, then a helix that leaves it by the minimum layer height.
            let z = if k < n {
                h
            } else if t <= 2.0 {
                h + 0.25 + (h - 0.25) * (t - 1.0)
            } else {
                h * t
            };
            s += &format!(
                "G1 X{:.3} Y{:.3} Z{:.3} E0.5\n",
                90.0 + r * a.cos(),
                95.0 + r * a.sin(),
                z
            );
        }
        s
    }

    #[test]
    fn check_path_flags_each_point_like_the_gcode_checker() {
        let text = helix(1.5, 10, 1.0);
        let from_gcode = check_gcode(&text, &limits()).unwrap();
        let (moves, start) = parse_moves(&text).unwrap();
        let points: Vec<DVec3> = std::iter::once(start)
            .chain(moves.iter().map(|m| m.to))
            .collect();
        let r = check_path(&points[1..], &limits());
        let lean = |r: &CheckReport| {
            r.violations
                .iter()
                .find(|v| v.what == OVERHANG)
                .map(|v| v.count)
        };
        assert!(lean(&r).unwrap() > 0);
        assert_eq!(lean(&r), lean(&from_gcode));
        let overhangs: Vec<&PathEvent> = r.events.iter().filter(|e| e.what == OVERHANG).collect();
        assert_eq!(overhangs.len(), lean(&r).unwrap());
        assert!(overhangs.windows(2).all(|w| w[0].line < w[1].line));
        assert!(overhangs.iter().all(|e| e.value > 45.0));
        // A point far below a tall printed part is a holder collision at that index.
        let mut tower: Vec<DVec3> = (0..200)
            .map(|k| {
                DVec3::new(
                    90.0 + 30.0 * (k as f64 * 0.1).cos(),
                    95.0 + 30.0 * (k as f64 * 0.1).sin(),
                    1.0 + k as f64 * 0.2,
                )
            })
            .collect();
        tower.push(DVec3::new(90.0, 95.0, 1.0));
        let r = check_path(&tower, &limits());
        let hit: Vec<&PathEvent> = r.events.iter().filter(|e| e.what == COLLISION).collect();
        assert_eq!(hit.len(), 1);
        assert_eq!(hit[0].line, 200);
        assert!((hit[0].value - 39.8).abs() < 1e-9);
    }

    #[test]
    fn vertical_spiral_passes() {
        let r = check_gcode(&helix(0.0, 10, 1.0), &limits()).unwrap();
        assert!(r.ok(), "{r}");
        assert!(r.max_overhang_deg < 1.0, "{}", r.max_overhang_deg);
        assert!((r.max_layer_height - 1.0).abs() < 0.01);
    }

    #[test]
    fn flare_past_45_is_an_overhang() {
        let r = check_gcode(&helix(1.5, 10, 1.0), &limits()).unwrap();
        let v = r
            .violations
            .iter()
            .find(|v| v.what == "overhang")
            .expect("overhang found");
        // 1.5 mm outward per 1 mm layer is 56°; steeper where the helix leaves the flat revolution.
        assert!(v.worst >= 56.0, "{}", v.worst);
        assert!(v.count > 500, "{}", v.count);
        // 0.8 mm per layer in the steady helix is 38.7°: only the thin helix start breaks 45°.
        let mild = check_gcode(&helix(0.8, 10, 1.0), &limits()).unwrap();
        assert!(mild.violations.iter().all(|v| v.count < 200), "{mild}");
    }

    #[test]
    fn travel_and_retraction_break_continuity() {
        let g = "M83\nG1 X10 Y10 Z1 E1\nG1 X20 Y10 Z1 E1\nG0 X30 Y10\nG1 X40 Y10 Z1 E-1\nG1 X50 Y10 Z1 E1\n";
        let r = check_gcode(g, &limits()).unwrap();
        let kinds: Vec<_> = r.violations.iter().map(|v| v.what).collect();
        assert!(kinds.contains(&"not one continuous path"), "{kinds:?}");
        assert!(kinds.contains(&"retraction"), "{kinds:?}");
    }

    #[test]
    fn off_the_bed_and_too_high() {
        let r = check_gcode("G1 X500 Y10 Z1 E1\nG1 X10 Y10 Z900 E1\n", &limits()).unwrap();
        assert_eq!(r.violations[0].what, "outside the machine");
        assert_eq!(r.violations[0].count, 2);
    }

    #[test]
    fn absolute_extrusion_and_header_limits() {
        let g = "; clayloft-limits: bed_x=50 bed_y=50 max_z=20\nM82\nG1 X10 Y10 Z1 E1\nG1 X20 Y10 Z1 E2\nG1 X30 Y10 Z1 E3\n";
        let l = Limits::from_header(g).unwrap();
        assert_eq!((l.bed_x, l.max_z, l.line_width), (50.0, 20.0, 3.0));
        let r = check_gcode(g, &l).unwrap();
        assert!(r.ok(), "{r}");
        assert_eq!(r.extruding_moves, 3);
    }

    #[test]
    fn line_numbers_and_checksums_are_understood() {
        let (moves, _) = parse_moves("N1 G1 X10 Y10 Z1 E1*37\nN2 G1 X20 Y10 Z1 E1*38\n").unwrap();
        assert_eq!(moves.len(), 2);
        assert_eq!(moves[1].to, DVec3::new(20.0, 10.0, 1.0));
    }

    #[test]
    fn garbage_is_an_error_with_a_line() {
        let e = check_gcode("G1 X10\nhello world\n", &limits()).unwrap_err();
        assert_eq!(e.line, 2);
        let e = check_gcode("G1 Xabc\n", &limits()).unwrap_err();
        assert!(e.message.contains("Xabc"));
        assert!(check_gcode("; nothing\n", &limits()).is_err());
    }
}
