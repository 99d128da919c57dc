//! Start and end G-code (SPEC §12): templates with named placeholders in braces, and each
//! dialect's defaults. The written program is: header comments → start template → approach →
//! the one continuous path → exit → end template; nothing a template adds lies between the first
//! and the last extruding move.
//!
//! Placeholders ([`PLACEHOLDERS`]): `{bed_x}`, `{bed_y}`, `{max_z}`, `{first_x}`, `{first_y}`,
//! `{first_z}`, `{last_z}`, `{top_z}`, `{park_z}`, `{park_x}`, `{park_y}`, `{layer_height}`,
//! `{line_width}`, `{nozzle_diameter}`, `{layers}`, `{print_time_s}`, `{print_time}`,
//! `{clay_volume_cm3}`, `{design_name}`, `{e_mode}` (`M83` or `M82`), `{travel_feed}` (mm/min).
//! `{{` and `}}` write braces.

use crate::design::{Dialect, Kinematics, Printer};

/// Every placeholder a template may use.
pub const PLACEHOLDERS: [&str; 21] = [
    "bed_x",
    "bed_y",
    "max_z",
    "first_x",
    "first_y",
    "first_z",
    "last_z",
    "top_z",
    "park_z",
    "park_x",
    "park_y",
    "layer_height",
    "line_width",
    "nozzle_diameter",
    "layers",
    "print_time_s",
    "print_time",
    "clay_volume_cm3",
    "design_name",
    "e_mode",
    "travel_feed",
];

/// Values for the placeholders, in the printer's own coordinates.
pub type Values = Vec<(&'static str, String)>;

/// Why a template cannot be filled.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TemplateError {
    #[error("unknown placeholder {{{0}}} (known: {known})", known = PLACEHOLDERS.join(", "))]
    Unknown(String),
    #[error("a `{{` without its `}}`")]
    Unclosed,
}

/// Fills `template` with `values`. An unknown name is an error naming it.
pub fn fill(template: &str, values: &[(&'static str, String)]) -> Result<String, TemplateError> {
    let mut out = String::with_capacity(template.len() + 64);
    let mut rest = template;
    while let Some(i) = rest.find(['{', '}']) {
        out.push_str(&rest[..i]);
        let c = rest.as_bytes()[i];
        rest = &rest[i + 1..];
        if rest.as_bytes().first() == Some(&c) {
            out.push(c as char); // `{{` or `}}`
            rest = &rest[1..];
            continue;
        }
        if c == b'}' {
            out.push('}');
            continue;
        }
        let end = rest.find('}').ok_or(TemplateError::Unclosed)?;
        let name = rest[..end].trim();
        let value = values
            .iter()
            .find(|(k, _)| *k == name)
            .map(|(_, v)| v.as_str())
            .ok_or_else(|| TemplateError::Unknown(name.chars().take(40).collect()))?;
        out.push_str(value);
        rest = &rest[end + 1..];
    }
    out.push_str(rest);
    Ok(out)
}

/// Checks a template's placeholders without values (for the design validator).
pub fn check(template: &str) -> Result<(), TemplateError> {
    let dummy: Values = PLACEHOLDERS.iter().map(|k| (*k, String::new())).collect();
    fill(template, &dummy).map(|_| ())
}

/// The dialect's start G-code: units, absolute positions, home, the E mode, cold extrusion
/// allowed (clay is not heated), E zeroed. No heating anywhere.
pub fn default_start(p: &Printer) -> &'static str {
    match p.dialect {
        // Marlin: M302 P1 switches off the cold-extrusion check (Marlin's M302; the FabLab BCN
        // PastePrinter's Cura start G-code does the same).
        Dialect::Marlin => {
            "; start (Marlin, no heating: clay is cold)\nG21 ; millimetres\nG90 ; absolute positions\nG28 ; home\n{e_mode} ; extrusion mode\nM302 P1 ; allow cold extrusion\nG92 E0\n"
        }
        // Klipper: cold extrusion is set in printer.cfg (min_extrude_temp: 0 on the extruder);
        // SET_PRINT_STATS_INFO gives Mainsail/Fluidd the layer count.
        Dialect::Klipper => {
            "; start (Klipper, no heating: clay is cold; set min_extrude_temp: 0 in printer.cfg)\nG21\nG90\nG28\n{e_mode}\nG92 E0\nSET_PRINT_STATS_INFO TOTAL_LAYER={layers}\n"
        }
        // RepRapFirmware: M302 P1 allows cold extrusion (RRF's M302).
        Dialect::RepRapFirmware => {
            "; start (RepRapFirmware, no heating: clay is cold)\nG21\nG90\nG28\n{e_mode}\nM302 P1 ; allow cold extrusion\nG92 E0\n"
        }
    }
}

/// The dialect's end G-code: lift clear of the rim, present the part (a delta homes to the top;
/// a cartesian printer parks at the back corner), motors off.
pub fn default_end(p: &Printer) -> &'static str {
    match (p.dialect, p.kinematics) {
        (_, Kinematics::Delta) => {
            "; end: lift clear of the rim, home to the top to present the part, motors off\nG90\nG0 Z{park_z} F{travel_feed}\nG28\nM84\n"
        }
        (Dialect::RepRapFirmware, _) => {
            "; end: lift clear of the rim, present the part, motors off\nG90\nG0 Z{park_z} F{travel_feed}\nG0 X{park_x} Y{park_y} F{travel_feed}\nM18\n"
        }
        _ => {
            "; end: lift clear of the rim, present the part, motors off\nG90\nG0 Z{park_z} F{travel_feed}\nG0 X{park_x} Y{park_y} F{travel_feed}\nM84\n"
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn placeholders_are_filled_and_unknown_ones_named() {
        let v: Values = vec![("bed_x", "180".into()), ("first_z", "0.500".into())];
        assert_eq!(
            fill("G0 X{bed_x} Z{ first_z } ; {{literal}}", &v).unwrap(),
            "G0 X180 Z0.500 ; {literal}"
        );
        assert_eq!(
            fill("G1 X{bedx}", &v),
            Err(TemplateError::Unknown("bedx".into()))
        );
        assert_eq!(fill("G1 X{bed_x", &v), Err(TemplateError::Unclosed));
        assert!(check("{e_mode}\n{park_z}").is_ok());
        assert!(check("{nope}").unwrap_err().to_string().contains("{nope}"));
    }
}
