//! Printer profiles (SPEC §12): TOML files of `[printer]` fields with a `name`, one per real
//! clay printer, shipped in `assets/printers/` (compiled in, so the binary finds them from any
//! folder) or given as a file. A design names one with `printer.profile`; its own `[printer]`
//! fields override the profile's.
//!
//! ```toml
//! name = "Eazao Zero"
//! [printer]
//! bed_x = 150.0   # source …
//! ```

use std::path::{Path, PathBuf};

use serde::Deserialize;

use crate::design::Printer;

/// The shipped profiles: (name to pick them by, file text).
pub const SHIPPED: &[(&str, &str)] = &[
    (
        "paper-cerambot",
        include_str!("../../../assets/printers/paper-cerambot.toml"),
    ),
    (
        "eazao-zero",
        include_str!("../../../assets/printers/eazao-zero.toml"),
    ),
    (
        "fablab-bcn-paste",
        include_str!("../../../assets/printers/fablab-bcn-paste.toml"),
    ),
    (
        "potterbot-super-10",
        include_str!("../../../assets/printers/potterbot-super-10.toml"),
    ),
    (
        "potterbot-baby",
        include_str!("../../../assets/printers/potterbot-baby.toml"),
    ),
    (
        "wasp-2040-clay",
        include_str!("../../../assets/printers/wasp-2040-clay.toml"),
    ),
    (
        "wasp-40100-ldm",
        include_str!("../../../assets/printers/wasp-40100-ldm.toml"),
    ),
    (
        "klipper-paste-delta",
        include_str!("../../../assets/printers/klipper-paste-delta.toml"),
    ),
];

/// A profile file: a display name and the printer fields.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ProfileFile {
    /// The printer's name, as its maker writes it.
    pub name: String,
    pub printer: Printer,
}

/// Where a profile came from and its text, before it is parsed.
#[derive(Debug, Clone, PartialEq)]
pub struct ProfileSource {
    /// What to call it in messages: the shipped file's path, or the file's.
    pub file: PathBuf,
    pub text: String,
}

/// Why a profile cannot be found.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ProfileLookupError {
    #[error("no printer profile called \"{name}\" (shipped: {known}; or give a .toml file)")]
    Unknown { name: String, known: String },
    #[error("{file}: cannot read: {reason}")]
    Read { file: String, reason: String },
}

/// Finds profile `name`: a shipped profile's name, else a file path (relative to `base_dir`).
pub fn find(name: &str, base_dir: Option<&Path>) -> Result<ProfileSource, ProfileLookupError> {
    if let Some((stem, text)) = SHIPPED.iter().find(|(n, _)| *n == name) {
        return Ok(ProfileSource {
            file: PathBuf::from(format!("assets/printers/{stem}.toml")),
            text: (*text).to_string(),
        });
    }
    let looks_like_file = name.ends_with(".toml") || name.contains('/') || name.contains('\\');
    if !looks_like_file {
        return Err(ProfileLookupError::Unknown {
            name: name.to_string(),
            known: SHIPPED
                .iter()
                .map(|(n, _)| *n)
                .collect::<Vec<_>>()
                .join(", "),
        });
    }
    let path = match base_dir {
        Some(dir) if Path::new(name).is_relative() => dir.join(name),
        _ => PathBuf::from(name),
    };
    let read_err = |reason: String| ProfileLookupError::Read {
        file: path.display().to_string(),
        reason,
    };
    let meta = std::fs::metadata(&path).map_err(|e| {
        read_err(if e.kind() == std::io::ErrorKind::NotFound {
            "no such file".into()
        } else {
            e.to_string()
        })
    })?;
    if meta.len() > 1 << 20 {
        return Err(read_err("far too large for a printer profile".into()));
    }
    let bytes = std::fs::read(&path).map_err(|e| read_err(e.to_string()))?;
    let text = String::from_utf8(bytes).map_err(|_| read_err("not a text file".into()))?;
    Ok(ProfileSource { file: path, text })
}

/// A shipped profile, parsed, with its printer fields normalised (a round bed's size in `bed_x`
/// and `bed_y`).
pub fn parse_shipped(name: &str, text: &str) -> Result<ProfileFile, String> {
    let mut file: ProfileFile = toml::from_str(text)
        .map_err(|e| format!("assets/printers/{name}.toml: {}", e.message()))?;
    file.printer.normalize();
    Ok(file)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::design::{BedShape, Kinematics, Origin};

    #[test]
    fn every_shipped_profile_parses_and_validates_and_one_is_a_round_delta() {
        assert!(SHIPPED.len() >= 7, "six real printers besides the paper's");
        let mut round_centre_delta = false;
        for (name, text) in SHIPPED {
            let f = parse_shipped(name, text).unwrap();
            crate::validate::validate_printer(&f.printer).unwrap_or_else(|e| panic!("{name}: {e}"));
            // Every number carries its source: each value line has a comment.
            for line in text
                .lines()
                .filter(|l| l.contains('=') && !l.trim_start().starts_with('#'))
            {
                let key = line.split('=').next().unwrap().trim();
                if key != "name" {
                    assert!(line.contains('#'), "{name}: `{line}` has no source comment");
                }
            }
            round_centre_delta |= f.printer.bed_shape == BedShape::Circle
                && f.printer.origin == Origin::Centre
                && f.printer.kinematics == Kinematics::Delta;
        }
        assert!(round_centre_delta);
    }

    #[test]
    fn unknown_names_and_missing_files_are_errors() {
        let e = find("no-such-printer", None).unwrap_err().to_string();
        assert!(
            e.contains("no-such-printer") && e.contains("eazao-zero"),
            "{e}"
        );
        let e = find("missing/printer.toml", None).unwrap_err().to_string();
        assert!(
            e.contains("missing/printer.toml") && e.contains("no such file"),
            "{e}"
        );
        assert!(find("eazao-zero", None).is_ok());
    }
}
