//! The limits a G-code file is checked against: from a design's printer or a Clayloft header,
//! each within the physical range a clay printer can have (the design validator's ranges) (so that no header can make the
//! checker's search grid microscopic or its numbers meaningless).

use crate::design::{BedShape, Origin, Printer};
use crate::gcode::LIMITS_KEY;
use crate::validate::validate_printer;

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
    /// A round bed is `bed_x` across (and `bed_y` = `bed_x`).
    pub bed_shape: BedShape,
    /// Where the file's (0, 0) is: the bed's corner or its centre.
    pub origin: Origin,
}

/// A limit outside what a clay printer can have: which, the value, and the range.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{key}={value}: {why}")]
pub struct LimitsError {
    /// The header's line (1-based), where the limits came from a file.
    pub line: Option<usize>,
    pub key: &'static str,
    pub value: f64,
    pub why: String,
}

/// The header keys of the numeric limits (the design file's `[printer]` field names).
const KEYS: [&str; 8] = [
    "bed_x",
    "bed_y",
    "max_z",
    "line_width",
    "min_layer_height",
    "max_layer_height",
    "nozzle_length",
    "max_overhang_deg",
];

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
            bed_shape: p.bed_shape,
            origin: p.origin,
        }
    }
}

impl Limits {
    fn field(&mut self, key: &str) -> Option<&mut f64> {
        Some(match key {
            "bed_x" => &mut self.bed_x,
            "bed_y" => &mut self.bed_y,
            "max_z" => &mut self.max_z,
            "line_width" => &mut self.line_width,
            "min_layer_height" => &mut self.min_layer_height,
            "max_layer_height" => &mut self.max_layer_height,
            "nozzle_length" => &mut self.nozzle_length,
            "max_overhang_deg" => &mut self.max_overhang_deg,
            _ => return None,
        })
    }

    /// The file's (0, 0) in the bed frame (see [`Printer::origin_offset`]).
    pub fn origin_offset(&self) -> [f64; 2] {
        self.origin.offset(self.bed_x, self.bed_y)
    }

    /// True when the bed-frame point (x, y) lies on the bed's real shape.
    pub fn on_bed(&self, x: f64, y: f64, eps: f64) -> bool {
        self.bed_shape.contains(self.bed_x, self.bed_y, x, y, eps)
    }

    /// Every limit finite and inside its physical range, the layer range not inverted: the
    /// design validator's own checks of these printer fields ([`validate_printer`]), so a
    /// header and a design are held to the same ranges.
    pub fn validate(&self) -> Result<(), LimitsError> {
        let printer = Printer {
            bed_x: self.bed_x,
            bed_y: self.bed_y,
            bed_shape: self.bed_shape,
            bed_diameter: (self.bed_shape == BedShape::Circle).then_some(self.bed_x),
            origin: self.origin,
            max_z: self.max_z,
            line_width: self.line_width,
            layer_height: self.min_layer_height,
            min_layer_height: self.min_layer_height,
            max_layer_height: self.max_layer_height,
            nozzle_length: self.nozzle_length,
            max_overhang_deg: self.max_overhang_deg,
            ..Printer::default()
        };
        validate_printer(&printer).map_err(|e| {
            let name = e.field.strip_prefix("printer.").unwrap_or(&e.field);
            let key = KEYS
                .iter()
                .copied()
                .find(|k| *k == name)
                .unwrap_or("limits");
            let mut copy = *self;
            LimitsError {
                line: None,
                key,
                value: copy.field(key).map_or(f64::NAN, |v| *v),
                why: e.message,
            }
        })
    }

    /// Limits written in a Clayloft header (`; clayloft-limits: bed_x=… …` in the first 200
    /// lines), if there is one; keys it does not give keep the paper's printer's values. A value
    /// that is no number, or outside its range, is an error naming the key.
    pub fn from_header(text: &str) -> Result<Option<(Limits, usize)>, LimitsError> {
        let Some((index, line)) = text
            .lines()
            .take(200)
            .enumerate()
            .find(|(_, l)| l.starts_with(LIMITS_KEY))
        else {
            return Ok(None);
        };
        let mut l = Limits::from(&Printer::default());
        for kv in line[LIMITS_KEY.len()..].split_whitespace().take(64) {
            let Some((k, v)) = kv.split_once('=') else {
                continue;
            };
            let unknown = |key: &'static str| LimitsError {
                line: Some(index + 1),
                key,
                value: f64::NAN,
                why: format!("`{}` is not a known value", truncated(v)),
            };
            match k {
                "bed_shape" => {
                    l.bed_shape = BedShape::from_name(v).ok_or_else(|| unknown("bed_shape"))?
                }
                "origin" => l.origin = Origin::from_name(v).ok_or_else(|| unknown("origin"))?,
                _ => {}
            }
            let Some(key) = KEYS.iter().copied().find(|name| *name == k) else {
                continue; // a key of a later version
            };
            let value = v.parse::<f64>().map_err(|_| LimitsError {
                line: Some(index + 1),
                key,
                value: f64::NAN,
                why: format!("`{}` is not a number", truncated(v)),
            })?;
            *l.field(key).expect("every range names a field") = value;
        }
        if l.bed_shape == BedShape::Circle {
            l.bed_y = l.bed_x;
        }
        l.validate().map_err(|e| LimitsError {
            line: Some(index + 1),
            ..e
        })?;
        Ok(Some((l, index + 1)))
    }
}

/// At most 40 characters of user text, for messages.
pub(crate) fn truncated(s: &str) -> String {
    if s.chars().count() <= 40 {
        s.to_string()
    } else {
        format!("{}…", s.chars().take(40).collect::<String>())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn header_limits_are_read_and_range_checked() {
        let (l, line) = Limits::from_header("G21\n; clayloft-limits: bed_x=50 bed_y=60 max_z=20\n")
            .unwrap()
            .unwrap();
        assert_eq!(
            (l.bed_x, l.bed_y, l.max_z, l.line_width),
            (50.0, 60.0, 20.0, 3.0)
        );
        assert_eq!(line, 2);
        assert_eq!(Limits::from_header("G1 X1\n").unwrap(), None);
        for (header, key) in [
            ("; clayloft-limits: line_width=1e-9", "line_width"),
            (
                "; clayloft-limits: max_layer_height=0.000001",
                "max_layer_height",
            ),
            ("; clayloft-limits: bed_x=1e300", "bed_x"),
            (
                "; clayloft-limits: min_layer_height=nan",
                "min_layer_height",
            ),
            (
                "; clayloft-limits: max_overhang_deg=inf",
                "max_overhang_deg",
            ),
            ("; clayloft-limits: nozzle_length=abc", "nozzle_length"),
            (
                "; clayloft-limits: min_layer_height=2 max_layer_height=1",
                "max_layer_height",
            ),
        ] {
            let e = Limits::from_header(header).unwrap_err();
            assert_eq!(e.key, key, "{header}: {e}");
            assert_eq!(e.line, Some(1));
        }
        assert!(Limits::from(&Printer::default()).validate().is_ok());
    }
}
