//! What each number of a design means, once: its label, unit, valid range and explanation. The
//! validator checks the ranges and the app's form shows the same labels, units, ranges and help
//! (so the form can never offer a value the validator refuses, or refuse one it accepts).
//!
//! Ranges are what a clay printer can physically do, wide enough for every machine of the
//! shipped profiles (a 40 × 100 cm WASP, a desktop Eazao) and narrow enough that a typo (an extra
//! zero or three) is an error rather than an exhausted machine. Relations between fields (layer
//! height within min … max, the vessel on the bed) are checked by [`crate::validate`].

use crate::validate::FieldError;

/// Largest size of anything (bed, height, offsets), mm: 10 m.
pub const MAX_LENGTH: f64 = 10_000.0;

/// One number of a design.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FieldMeta {
    /// Dotted path in the design file, e.g. `printer.print_speed`.
    pub path: &'static str,
    /// Short label for forms.
    pub label: &'static str,
    /// Unit as shown after the value (empty for none).
    pub unit: &'static str,
    pub min: f64,
    pub max: f64,
    /// The minimum itself is not allowed (the value must be greater than `min`).
    pub min_exclusive: bool,
    /// What it means, in words a potter understands.
    pub help: &'static str,
}

impl FieldMeta {
    /// Checks a value against the range; the error names the field and the range.
    pub fn check(&self, v: f64) -> Result<(), FieldError> {
        if !v.is_finite() {
            return Err(FieldError::new(
                self.path,
                format!("must be a finite number, got {v}"),
            ));
        }
        let unit = if self.unit.is_empty() {
            String::new()
        } else {
            format!(" {}", self.unit)
        };
        if self.min_exclusive && v <= self.min {
            return Err(FieldError::new(
                self.path,
                format!("must be greater than {}{unit}, got {v}", self.min),
            ));
        }
        if v < self.min || v > self.max {
            return Err(FieldError::new(
                self.path,
                format!(
                    "{v}{unit} is outside {} ..= {}{unit} ({})",
                    self.min,
                    self.max,
                    self.label.to_lowercase()
                ),
            ));
        }
        Ok(())
    }

    /// The range a form's input offers: the valid range, an exclusive minimum nudged up.
    pub fn form_range(&self) -> std::ops::RangeInclusive<f64> {
        let lo = if self.min_exclusive {
            self.min + (self.max - self.min).min(1.0) * 1e-3
        } else {
            self.min
        };
        lo..=self.max
    }
}

const fn field(
    path: &'static str,
    label: &'static str,
    unit: &'static str,
    min: f64,
    max: f64,
    min_exclusive: bool,
    help: &'static str,
) -> FieldMeta {
    FieldMeta {
        path,
        label,
        unit,
        min,
        max,
        min_exclusive,
        help,
    }
}

/// Every plain number of a design, in form order.
#[rustfmt::skip]
pub const FIELDS: &[FieldMeta] = &[
    field("clay.wet_density", "Wet density", "kg/m³", 1000.0, 3000.0, false,
        "Mass of a litre of the wet paste, in grams: water is 1000, printing clay about 1850."),
    field("clay.yield_stress", "Yield stress", "Pa", 0.0, 1e6, true,
        "Stress the fresh bead carries before it flows: the stiffer the paste, the higher."),
    field("clay.fall_cone_mm", "Fall-cone depth", "mm", 1.0, 60.0, false,
        "How far an 80 g, 30° cone sinks into the paste; sets the yield stress (20 mm = liquid limit)."),
    field("clay.structuration_rate", "Stiffening rate", "Pa/s", 0.0, 1000.0, false,
        "How fast the laid clay gains strength while it rests (it dries and sets)."),
    field("clay.elastic_modulus", "Stiffness", "Pa", 0.0, 1e9, true,
        "Young's modulus of the fresh paste: what keeps a thin wall from buckling."),
    field("clay.firing_shrinkage_percent", "Firing shrinkage", "%", 0.0, 40.0, false,
        "How much smaller the fired piece is than the wet print (drying and firing)."),
    field("clay.firing_shrinkage_z_percent", "Firing shrinkage in height", "%", 0.0, 40.0, false,
        "Shrinkage in height when it differs from the shrinkage across."),
    field("shape.height", "Height", "mm", 0.0, MAX_LENGTH, true,
        "Height of the vessel from the bed to the rim."),
    field("printer.bed_x", "Bed x", "mm", 0.0, MAX_LENGTH, true, "Bed size along x."),
    field("printer.bed_y", "Bed y", "mm", 0.0, MAX_LENGTH, true, "Bed size along y."),
    field("printer.bed_diameter", "Bed diameter", "mm", 0.0, MAX_LENGTH, true,
        "Diameter of a round (delta) bed."),
    field("printer.max_z", "Build height", "mm", 0.0, MAX_LENGTH, true,
        "Highest the nozzle can go."),
    field("printer.nozzle_diameter", "Nozzle diameter", "mm", 0.0, 50.0, true,
        "Opening of the nozzle."),
    field("printer.line_width", "Line width", "mm", 0.1, 50.0, false,
        "Width of the clay bead: the wall is this thick."),
    field("printer.layer_height", "Layer height", "mm", 0.01, 50.0, false,
        "Nominal height of each layer (between the min and max layer heights)."),
    field("printer.min_layer_height", "Min layer height", "mm", 0.01, 50.0, false,
        "Thinner layers smear the bead."),
    field("printer.max_layer_height", "Max layer height", "mm", 0.01, 50.0, false,
        "Thicker layers do not bond."),
    field("printer.nozzle_length", "Nozzle length", "mm", 0.0, MAX_LENGTH, true,
        "Tube length below the holder: printed clay may rise at most this far above the tip."),
    field("printer.max_overhang_deg", "Max overhang", "°", 1.0, 80.0, false,
        "Largest lean from vertical that clay holds without support (degrees from vertical)."),
    field("printer.max_acceleration", "Acceleration", "mm/s²", 1.0, 100_000.0, false,
        "The firmware's print acceleration: sets the time estimate."),
    field("printer.junction_deviation", "Junction deviation", "mm", 0.0001, 10.0, false,
        "How fast the firmware takes corners (Marlin's range is 0.001 … 0.5 mm)."),
    field("printer.print_speed", "Print speed", "mm/s", 0.1, 1000.0, false,
        "Speed along the wall."),
    field("printer.travel_speed", "Travel speed", "mm/s", 0.1, 1000.0, false,
        "Approach and exit moves only."),
    field("printer.feed_diameter", "Feed diameter", "mm", 0.0, MAX_LENGTH, true,
        "Calibration of E: the extruder's equivalent filament diameter."),
    field("printer.flow_multiplier", "Flow multiplier", "×", 0.01, 10.0, false,
        "Scales all extrusion (a factor on the extruded volume)."),
    field("printer.min_layer_time", "Min layer time", "s", 0.0, 3600.0, false,
        "Small layers slow down so the clay stiffens, seconds per revolution (0 = off)."),
    field("printer.flow_ramp_start", "Flow ramp start", "mm", 0.0, MAX_LENGTH, false,
        "Path length over which flow rises at the start."),
    field("printer.flow_ramp_end", "Flow ramp end", "mm", 0.0, MAX_LENGTH, false,
        "Path length over which flow falls at the end."),
    // Contour sizes, for both contours (`shape.lower.radius`, `shape.upper.rx`, …): the entry
    // is named by the last part of the path.
    field("contour.radius", "Radius", "mm", 0.0, MAX_LENGTH, true,
        "Distance from the centre to the curve (a polygon's corner, a rose's mean radius)."),
    field("contour.rx", "Radius x", "mm", 0.0, MAX_LENGTH, true, "Semi-axis along x."),
    field("contour.ry", "Radius y", "mm", 0.0, MAX_LENGTH, true, "Semi-axis along y."),
    field("contour.outer_radius", "Outer radius", "mm", 0.0, MAX_LENGTH, true,
        "Centre to a tip of the star."),
    field("contour.inner_radius", "Inner radius", "mm", 0.0, MAX_LENGTH, true,
        "Centre to a notch of the star."),
    // Texture waves, for both directions (`texture.x.period`, `texture.y.amplitude`).
    field("wave.period", "Period", "", 1e-3, 1e6, false,
        "Length of one wave: samples around (x) or layers up (y)."),
    field("wave.amplitude", "Amplitude", "mm", -100.0, 100.0, false,
        "How far the surface moves along its normal."),
    field("texture.phase_drift", "Phase drift", "samples/layer", -1e4, 1e4, false,
        "How far the x wave shifts per layer: twists the pattern up the wall."),
    field("texture.start", "Start", "", 0.0, 1.0, false,
        "Height fraction where the texture begins."),
    field("texture.end", "End", "", 0.0, 1.0, false,
        "Height fraction where the texture ends."),
];

/// The metadata of the field at `path`.
///
/// # Panics
/// If `path` is not in [`FIELDS`] (a programming error: every caller names a fixed path).
pub fn meta(path: &str) -> &'static FieldMeta {
    FIELDS
        .iter()
        .find(|f| f.path == path)
        .unwrap_or_else(|| panic!("no field metadata for {path}"))
}

/// Checks `v` against the range of the field at `path`.
pub fn check(path: &str, v: f64) -> Result<(), FieldError> {
    meta(path).check(v)
}

/// Checks `v` against the range of the shared entry `entry` (e.g. `contour.radius`), the error
/// naming the actual field `path` (e.g. `shape.upper.radius`).
pub fn check_as(entry: &str, path: &str, v: f64) -> Result<(), FieldError> {
    meta(entry).check(v).map_err(|mut e| {
        e.field = path.to_string();
        e
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_are_checked_with_the_field_named() {
        assert!(check("printer.print_speed", 20.0).is_ok());
        let e = check("printer.print_speed", 5000.0).unwrap_err();
        assert_eq!(e.field, "printer.print_speed");
        assert!(e.message.contains("0.1 ..= 1000 mm/s"), "{e}");
        assert!(check("printer.bed_x", 0.0).is_err());
        assert!(check("printer.min_layer_time", 0.0).is_ok());
        assert!(check("printer.line_width", f64::NAN).is_err());
    }

    #[test]
    fn the_form_range_holds_only_valid_values() {
        for f in FIELDS {
            let r = f.form_range();
            assert!(f.check(*r.start()).is_ok(), "{} start", f.path);
            assert!(f.check(*r.end()).is_ok(), "{} end", f.path);
            assert!(!f.label.is_empty() && !f.help.is_empty());
        }
        let paths: std::collections::HashSet<_> = FIELDS.iter().map(|f| f.path).collect();
        assert_eq!(paths.len(), FIELDS.len(), "one entry per field");
    }
}
