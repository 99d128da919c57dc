//! Physical-range checks on a parsed [`Design`]: every number finite and inside what a clay printer
//! can do. Each failure names the field (as a dotted path, e.g. `printer.layer_height`) and why.

use crate::design::{BedShape, ContourSpec, DESIGN_VERSION, Design, Printer, Wave};
use crate::fields::{self, MAX_LENGTH};

/// A problem with one field of a design. `field` is a dotted path such as
/// `control.vertical[1].points[2]`; the loader turns it into a line number.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{field}: {message}")]
pub struct FieldError {
    pub field: String,
    pub message: String,
}

impl FieldError {
    pub fn new(field: impl Into<String>, message: impl Into<String>) -> Self {
        FieldError {
            field: field.into(),
            message: message.into(),
        }
    }
}

/// Largest number of samples per section: far beyond any printer's resolution, small enough that
/// a typo (an extra zero or three) cannot exhaust memory.
pub const MAX_SAMPLES: usize = 100_000;
/// Most points a design's path may have (wall sections and spiral base together): 18 times the
/// 720 × 300 benchmark vessel, a few hundred MB of working memory; beyond it a typo (a layer
/// height of 0.0001, a huge foot with a fine bead) is an error instead of an exhausted machine.
pub const MAX_PATH_POINTS: usize = 4_000_000;

type Check = Result<(), FieldError>;

fn finite(field: &str, v: f64) -> Check {
    if v.is_finite() {
        Ok(())
    } else {
        Err(FieldError::new(
            field,
            format!("must be a finite number, got {v}"),
        ))
    }
}

fn count_in(field: String, v: usize, lo: usize, hi: usize) -> Check {
    if (lo..=hi).contains(&v) {
        Ok(())
    } else {
        Err(FieldError::new(
            field,
            format!("{v} is outside {lo} ..= {hi}"),
        ))
    }
}

fn in_range(field: &str, v: f64, lo: f64, hi: f64, why: &str) -> Check {
    finite(field, v)?;
    if v < lo || v > hi {
        return Err(FieldError::new(
            field,
            format!("{v} is outside {lo} ..= {hi} ({why})"),
        ));
    }
    Ok(())
}

/// The wall's beads (SPEC §13): 1 ..= [`crate::walls::MAX_WALLS`]; ties need a second bead;
/// each bead's turn must rise at least `min_layer_height` (it ends over its own start), so the
/// layer height must hold W of them; and the first revolution, which leaves the flat layer by
/// `min_layer_height` ([`crate::toolpath::first_revolution_top`]), must be a layer the printer
/// can lay.
fn walls(s: &crate::design::Shape, p: &Printer) -> Check {
    let max = crate::walls::MAX_WALLS;
    if s.walls < 1 || s.walls > max {
        return Err(FieldError::new(
            "shape.walls",
            format!("{} is outside 1 ..= {max} beads side by side", s.walls),
        ));
    }
    if s.wall_ties && s.walls < 2 {
        return Err(FieldError::new(
            "shape.wall_ties",
            "ties join the beads of a wall of two or three beads: set walls = 2 or 3",
        ));
    }
    let (h, a, w) = (p.layer_height, p.min_layer_height, s.walls);
    if w > 1 && h < w as f64 * a * (1.0 - 1e-9) {
        return Err(FieldError::new(
            "shape.walls",
            format!(
                "with {w} beads each turn rises {:.3} mm and ends over its own start, outside the printer's range of layers (min_layer_height = {a} mm; a taller layer_height, a lower min_layer_height if the clay takes it, or fewer beads)",
                h / w as f64
            ),
        ));
    }
    let top = crate::toolpath::first_revolution_top(h, a, w);
    if top > p.max_layer_height * (1.0 + 1e-9) {
        let beads = if w > 1 {
            format!("its {w} turns each rise at least min_layer_height, so ")
        } else {
            String::new()
        };
        return Err(FieldError::new(
            if w > 1 {
                "shape.walls"
            } else {
                "printer.min_layer_height"
            },
            format!(
                "the wall leaves the flat layer by printer.min_layer_height = {a} mm and {beads}its first revolution ends {top:.3} mm above that layer, outside the printer's range of layers (max_layer_height = {} mm; a lower min_layer_height if the clay takes it{})",
                p.max_layer_height,
                if w > 1 { ", or fewer beads" } else { "" }
            ),
        ));
    }
    Ok(())
}

/// The mesh a design takes its shape from: a path, a positive scale, a turn in degrees.
fn mesh_source(m: &crate::design::MeshSource) -> Check {
    if m.path.as_os_str().is_empty() {
        return Err(FieldError::new(
            "shape.mesh.path",
            "is empty: name an STL file",
        ));
    }
    in_range("shape.mesh.scale", m.scale, 1e-4, 1e4, "a factor")?;
    in_range("shape.mesh.rotate_x", m.rotate_x, -360.0, 360.0, "degrees")
}

/// Most problems [`validate_all`] lists.
pub const MAX_REPORTED: usize = 12;

/// Every problem of a design, not only the first [`validate`] stops at: each refused field is
/// reported and then set back to its default (removed from the design's TOML form) to look for
/// the next, up to [`MAX_REPORTED`]. A problem in a list entry (`control.vertical[1]…`), or in a
/// field whose default is refused too, ends the search there.
pub fn validate_all(d: &Design) -> Vec<FieldError> {
    let mut found = Vec::new();
    let mut current = d.clone();
    while found.len() < MAX_REPORTED {
        let Err(e) = validate(&current) else { break };
        let next = without_field(&current, &e.field);
        found.push(e);
        match next {
            Some(n) => current = n,
            None => break,
        }
    }
    found
}

/// `d` with the field at dotted `path` back at its default; `None` where that cannot be done or
/// changes nothing.
fn without_field(d: &Design, path: &str) -> Option<Design> {
    if path.contains('[') {
        return None;
    }
    let mut value = toml::Value::try_from(d).ok()?;
    let mut keys: Vec<&str> = path.split('.').collect();
    let last = keys.pop()?;
    let mut table = value.as_table_mut()?;
    for k in keys {
        table = table.get_mut(k)?.as_table_mut()?;
    }
    table.remove(last)?;
    let next: Design = value.try_into().ok()?;
    (next != *d).then_some(next)
}

/// Checks the printer fields alone (a printer profile is checked with this before it is merged
/// into a design).
pub fn validate_printer(p: &Printer) -> Check {
    for (field, template) in [
        ("printer.start_gcode", &p.start_gcode),
        ("printer.end_gcode", &p.end_gcode),
        ("printer.cancel_gcode", &p.cancel_gcode),
    ] {
        if let Some(t) = template {
            crate::templates::check(t).map_err(|e| FieldError::new(field, e.to_string()))?;
            if !t.is_ascii() {
                return Err(FieldError::new(field, "G-code must be plain ASCII"));
            }
        }
    }
    if p.bed_shape == BedShape::Circle {
        let Some(dia) = p.bed_diameter else {
            return Err(FieldError::new(
                "printer.bed_shape",
                "a round bed needs printer.bed_diameter (mm)",
            ));
        };
        fields::check("printer.bed_diameter", dia)?;
    } else if p.bed_diameter.is_some() {
        return Err(FieldError::new(
            "printer.bed_diameter",
            "is for round beds; set printer.bed_shape = \"circle\" or give bed_x and bed_y",
        ));
    }
    // Every plain number against its one range (crate::fields), then the relations.
    for (path, v) in [
        ("printer.bed_x", p.bed_x),
        ("printer.bed_y", p.bed_y),
        ("printer.max_z", p.max_z),
        ("printer.nozzle_diameter", p.nozzle_diameter),
        ("printer.line_width", p.line_width),
        ("printer.min_layer_height", p.min_layer_height),
        ("printer.max_layer_height", p.max_layer_height),
        ("printer.layer_height", p.layer_height),
        ("printer.nozzle_length", p.nozzle_length),
        ("printer.max_overhang_deg", p.max_overhang_deg),
        ("printer.max_acceleration", p.max_acceleration),
        ("printer.junction_deviation", p.junction_deviation),
        ("printer.print_speed", p.print_speed),
        ("printer.travel_speed", p.travel_speed),
        ("printer.feed_diameter", p.feed_diameter),
        ("printer.flow_multiplier", p.flow_multiplier),
        ("printer.min_layer_time", p.min_layer_time),
        ("printer.flow_ramp_start", p.flow_ramp_start),
        ("printer.flow_ramp_end", p.flow_ramp_end),
    ] {
        fields::check(path, v)?;
    }
    if p.max_layer_height < p.min_layer_height {
        return Err(FieldError::new(
            "printer.max_layer_height",
            format!(
                "{} mm is below printer.min_layer_height = {} mm",
                p.max_layer_height, p.min_layer_height
            ),
        ));
    }
    if p.layer_height < p.min_layer_height || p.layer_height > p.max_layer_height {
        return Err(FieldError::new(
            "printer.layer_height",
            format!(
                "{} mm is outside the printer's range {} ..= {} mm",
                p.layer_height, p.min_layer_height, p.max_layer_height
            ),
        ));
    }
    Ok(())
}

/// Checks every field of a design against physical ranges. Fit on the bed and under the build
/// height is checked after the shape is computed (see [`crate::pipeline`]).
pub fn validate(d: &Design) -> Check {
    if d.version != DESIGN_VERSION {
        return Err(FieldError::new(
            "version",
            format!(
                "this Clayloft reads design version {DESIGN_VERSION}, the file says {}",
                d.version
            ),
        ));
    }
    validate_printer(&d.printer)?;
    crate::clay::resolve(d.clay.as_ref())?;
    let p = &d.printer;
    let s = &d.shape;
    if let Some(m) = &s.mesh {
        mesh_source(m)?;
        if !d.control.vertical.is_empty() || !d.control.horizontal.is_empty() {
            return Err(FieldError::new(
                "control",
                "control lines shape a lofted vessel: a vessel from [shape.mesh] takes its shape from the mesh",
            ));
        }
    } else {
        fields::check("shape.height", s.height)?;
        if s.height > p.max_z {
            return Err(FieldError::new(
                "shape.height",
                format!(
                    "{} mm is taller than the printer's build height printer.max_z = {} mm",
                    s.height, p.max_z
                ),
            ));
        }
        if s.height < p.layer_height {
            return Err(FieldError::new(
                "shape.height",
                format!(
                    "{} mm is less than one layer ({} mm)",
                    s.height, p.layer_height
                ),
            ));
        }
    }
    if s.samples < 3 || s.samples > MAX_SAMPLES {
        return Err(FieldError::new(
            "shape.samples",
            format!(
                "{} is outside 3 ..= {MAX_SAMPLES} points per section",
                s.samples
            ),
        ));
    }
    if let Some([cx, cy]) = s.center {
        // In the printer's own coordinates: 0 … bed size from a corner origin, ± half from a
        // centre origin.
        let [ox, oy] = p.origin_offset();
        in_range(
            "shape.center",
            cx,
            -ox,
            p.bed_x - ox,
            "x must lie on the bed",
        )?;
        in_range(
            "shape.center",
            cy,
            -oy,
            p.bed_y - oy,
            "y must lie on the bed",
        )?;
        let [bx, by] = d.center();
        if !p.on_bed(bx, by, 1e-9) {
            return Err(FieldError::new(
                "shape.center",
                format!(
                    "[{cx}, {cy}] is off the round bed (diameter {} mm)",
                    p.bed_x
                ),
            ));
        }
    }
    let layers_nominal = s.height / p.layer_height;
    if s.mesh.is_none() && s.base_layers as f64 >= layers_nominal {
        return Err(FieldError::new(
            "shape.base_layers",
            format!(
                "{} base layers leave no wall in a {} mm tall vessel",
                s.base_layers, s.height
            ),
        ));
    }
    walls(s, p)?;
    if s.mesh.is_none() {
        for (field, c) in [("shape.lower", &s.lower), ("shape.upper", &s.upper)] {
            if c.is_missing() {
                return Err(FieldError::new(
                    field,
                    "missing: a design needs a lower and an upper contour, or [shape.mesh]",
                ));
            }
            contour(field, c)?;
        }
    }

    for (n, line) in d.control.vertical.iter().enumerate() {
        let f = format!("control.vertical[{n}]");
        if line.points.is_empty() {
            return Err(FieldError::new(
                format!("{f}.points"),
                "needs at least one [t, offset] point",
            ));
        }
        let mut last_t = f64::NEG_INFINITY;
        for (k, [t, off]) in line.points.iter().copied().enumerate() {
            let pf = format!("{f}.points[{k}]");
            in_range(&pf, t, 0.0, 1.0, "t is a height fraction")?;
            in_range(&pf, off, -MAX_LENGTH, MAX_LENGTH, "offset in mm")?;
            if t <= last_t {
                return Err(FieldError::new(
                    pf,
                    "t values must increase from point to point",
                ));
            }
            last_t = t;
        }
        match (line.angle, line.width) {
            (Some(a), w) => {
                in_range(&format!("{f}.angle"), a, -360.0, 360.0, "degrees")?;
                in_range(
                    &format!("{f}.width"),
                    w.unwrap_or(60.0),
                    1.0,
                    360.0,
                    "degrees of influence",
                )?;
            }
            (None, Some(_)) => {
                return Err(FieldError::new(
                    format!("{f}.width"),
                    "a width needs an angle to act around",
                ));
            }
            (None, None) => {}
        }
    }
    for (n, line) in d.control.horizontal.iter().enumerate() {
        let f = format!("control.horizontal[{n}]");
        in_range(&format!("{f}.at"), line.at, 0.0, 1.0, "a height fraction")?;
        in_range(
            &format!("{f}.reach"),
            line.reach,
            0.001,
            1.0,
            "a height fraction",
        )?;
        if line.points.is_empty() {
            return Err(FieldError::new(
                format!("{f}.points"),
                "needs at least one [angle, dz] point",
            ));
        }
        let mut last_a = f64::NEG_INFINITY;
        for (k, [a, dz]) in line.points.iter().copied().enumerate() {
            let pf = format!("{f}.points[{k}]");
            in_range(&pf, a, 0.0, 359.999_999, "angle in degrees, 0 ..< 360")?;
            in_range(
                &pf,
                dz,
                -p.max_z,
                p.max_z,
                "dz in mm within the build height",
            )?;
            if a <= last_a {
                return Err(FieldError::new(
                    pf,
                    "angles must increase from point to point",
                ));
            }
            last_a = a;
        }
    }
    if let Some(t) = &d.texture {
        if let Some(w) = &t.x {
            wave("texture.x", w)?;
        }
        if let Some(w) = &t.y {
            wave("texture.y", w)?;
        }
        fields::check("texture.phase_drift", t.phase_drift)?;
        fields::check("texture.start", t.start)?;
        fields::check("texture.end", t.end)?;
        if t.end < t.start {
            return Err(FieldError::new(
                "texture.end",
                "must not be below texture.start",
            ));
        }
    }
    Ok(())
}

fn wave(f: &str, w: &Wave) -> Check {
    fields::check_as("wave.period", &format!("{f}.period"), w.period)?;
    fields::check_as("wave.amplitude", &format!("{f}.amplitude"), w.amplitude)
}

fn contour(f: &str, c: &ContourSpec) -> Check {
    let fld = |name: &str| format!("{f}.{name}");
    let size = |name: &str, v: f64| fields::check_as(&format!("contour.{name}"), &fld(name), v);
    match c {
        ContourSpec::Circle { radius } => size("radius", *radius),
        ContourSpec::Ellipse { rx, ry } => {
            size("rx", *rx)?;
            size("ry", *ry)
        }
        ContourSpec::Polygon {
            sides,
            radius,
            corner_radius,
        } => {
            count_in(fld("sides"), *sides, 3, 1000)?;
            size("radius", *radius)?;
            let inradius = radius * (std::f64::consts::PI / *sides as f64).cos();
            in_range(
                &fld("corner_radius"),
                *corner_radius,
                0.0,
                inradius * 0.999,
                "must fit inside the polygon",
            )
        }
        ContourSpec::Star {
            points,
            outer_radius,
            inner_radius,
        } => {
            count_in(fld("points"), *points, 2, 1000)?;
            size("outer_radius", *outer_radius)?;
            size("inner_radius", *inner_radius)?;
            if inner_radius >= outer_radius {
                return Err(FieldError::new(
                    fld("inner_radius"),
                    "must be smaller than outer_radius",
                ));
            }
            Ok(())
        }
        ContourSpec::Rose {
            radius,
            amplitude,
            petals,
        } => {
            size("radius", *radius)?;
            finite(&fld("amplitude"), *amplitude)?;
            if amplitude.abs() >= *radius {
                return Err(FieldError::new(
                    fld("amplitude"),
                    format!(
                        "|{amplitude}| mm must be smaller than radius = {radius} mm so the curve stays closed"
                    ),
                ));
            }
            count_in(fld("petals"), *petals, 1, 500)?;
            Ok(())
        }
        ContourSpec::Spline { points } => {
            if points.len() < 3 {
                return Err(FieldError::new(
                    fld("points"),
                    "a closed spline needs at least 3 points",
                ));
            }
            if points.len() > MAX_SAMPLES {
                return Err(FieldError::new(fld("points"), "too many points"));
            }
            for (k, xy) in points.iter().enumerate() {
                for v in xy {
                    in_range(
                        &format!("{f}.points[{k}]"),
                        *v,
                        -MAX_LENGTH,
                        MAX_LENGTH,
                        "mm",
                    )?;
                }
            }
            Ok(())
        }
        ContourSpec::Image { path, size, .. } | ContourSpec::Svg { path, size, .. } => {
            if path.trim().is_empty() {
                return Err(FieldError::new(fld("path"), "names no file"));
            }
            in_range(
                &fld("size"),
                *size,
                1.0,
                MAX_LENGTH,
                "mm across the longer side",
            )
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn design(extra: &str) -> Design {
        let text = format!(
            "version = 1\n[shape]\nheight = 100.0\nlower = {{ type = \"circle\", radius = 40.0 }}\nupper = {{ type = \"circle\", radius = 50.0 }}\n{extra}"
        );
        toml::from_str(&text).expect("a design")
    }

    #[test]
    fn every_problem_is_listed_not_only_the_first() {
        assert!(validate_all(&design("")).is_empty());
        let d = design("[printer]\nprint_speed = -3.0\nlayer_height = 80.0\n");
        let all = validate_all(&d);
        let fields: Vec<&str> = all.iter().map(|e| e.field.as_str()).collect();
        assert!(fields.contains(&"printer.print_speed"), "{all:?}");
        assert!(fields.contains(&"printer.layer_height"), "{all:?}");
        // The first is the one `validate` reports.
        assert_eq!(Err(all[0].clone()), validate(&d));
        // A bad list entry ends the search: still reported.
        let mut bad = design("");
        bad.shape.samples = 0;
        bad.shape.height = -5.0;
        let all = validate_all(&bad);
        assert!(all.iter().any(|e| e.field == "shape.height"), "{all:?}");
        assert!(all.len() <= MAX_REPORTED);
    }

    /// A wall must be able to leave the flat layer: each bead's turn rises at least the minimum
    /// layer height, and the first revolution must be a layer the printer can lay.
    #[test]
    fn walls_that_cannot_leave_the_flat_layer_are_refused_with_why() {
        let printer = |h: f64, a: f64, max: f64, walls: usize| {
            let mut d = design(&format!(
                "[printer]\nlayer_height = {h}\nmin_layer_height = {a}\nmax_layer_height = {max}\n"
            ));
            d.shape.walls = walls;
            d
        };
        // The paper's printer: two and three beads.
        assert_eq!(validate(&printer(1.0, 0.25, 1.0, 2)), Ok(()));
        assert_eq!(validate(&printer(1.0, 0.25, 1.0, 3)), Ok(()));
        // One bead of the Klipper delta's 0.5 mm at a = 0.5: the first revolution ends 1.0 up.
        assert_eq!(validate(&printer(0.5, 0.5, 1.0, 1)), Ok(()));
        // The Eazao's layers hold two beads, first revolution 1.5 mm: just.
        assert_eq!(validate(&printer(1.0, 0.5, 1.5, 2)), Ok(()));
        // The WASP's: 0.9 mm over the flat layer, past its 0.8.
        let e = validate(&printer(0.6, 0.3, 0.8, 2)).unwrap_err();
        assert_eq!(e.field, "shape.walls");
        assert!(e.message.contains("ends 0.900 mm above"), "{}", e.message);
        // Three beads of 0.2 mm turns over a = 0.3.
        let e = validate(&printer(0.6, 0.3, 0.8, 3)).unwrap_err();
        assert!(
            e.message.contains("each turn rises 0.200 mm"),
            "{}",
            e.message
        );
        // One bead whose minimum is more than half the maximum.
        let e = validate(&printer(0.8, 0.6, 1.0, 1)).unwrap_err();
        assert_eq!(e.field, "printer.min_layer_height");
    }
}
