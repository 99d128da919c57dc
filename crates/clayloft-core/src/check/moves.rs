//! The moves of a G-code program (G0/G1 with G90/G91, M82/M83, G92, G20/G21), as the
//! checker reads them.

use glam::DVec3;

use super::limits::truncated;

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
                        message: format!("`{}` is not a number", truncated(w)),
                    })?;
                    if !v.is_finite() {
                        return Err(GcodeError {
                            line,
                            message: format!("`{}` is not finite", truncated(w)),
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
                if !to.is_finite() {
                    return Err(GcodeError {
                        line,
                        message: "the position runs past any finite number".into(),
                    });
                }
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
            // Klipper's and RepRapFirmware's named commands (`SET_PRINT_STATS_INFO …`,
            // `TURN_OFF_HEATERS`): no moves.
            _ if cmd.len() >= 3
                && cmd.starts_with(|c: char| c.is_ascii_uppercase())
                && cmd
                    .chars()
                    .all(|c| c.is_ascii_uppercase() || c.is_ascii_digit() || c == '_') => {}
            other => {
                return Err(GcodeError {
                    line,
                    message: format!("`{}` is not a G-code command", truncated(other)),
                });
            }
        }
    }
    Ok((moves, start.unwrap_or(DVec3::ZERO)))
}
