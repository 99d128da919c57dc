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
        let Some(first) = words.next() else {
            continue;
        };
        let mut cmd = first;
        // The first word of each axis letter after the first word, found in one pass over
        // the line and parsed only where the command reads it.
        let mut letters: [Option<&str>; 4] = [None; 4];
        let mut numbered = cmd.starts_with(['N', 'n']) && cmd[1..].parse::<u64>().is_ok();
        for w in words {
            if numbered {
                // A line number (`N12 G1 …`) comes before the command.
                cmd = w;
                numbered = false;
            }
            let slot = match w.as_bytes()[0].to_ascii_uppercase() {
                b'X' => 0,
                b'Y' => 1,
                b'Z' => 2,
                b'E' => 3,
                _ => continue,
            };
            letters[slot].get_or_insert(w);
        }
        if numbered {
            continue;
        }
        let arg = |letter: char| -> Result<Option<f64>, GcodeError> {
            let slot = match letter {
                'X' => 0,
                'Y' => 1,
                'Z' => 2,
                _ => 3,
            };
            let Some(w) = letters[slot] else {
                return Ok(None);
            };
            let v: f64 = w[1..].parse().map_err(|_| GcodeError {
                line,
                message: format!("`{}` is not a number", truncated(w)),
            })?;
            if !v.is_finite() {
                return Err(GcodeError {
                    line,
                    message: format!("`{}` is not finite", truncated(w)),
                });
            }
            Ok(Some(v))
        };
        let is = |name: &str| cmd.eq_ignore_ascii_case(name);
        if is("G1") || is("G0") || is("G01") || is("G00") {
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
        } else if is("G90") {
            absolute_xyz = true;
        } else if is("G91") {
            absolute_xyz = false;
        } else if is("M82") {
            absolute_e = true;
        } else if is("M83") {
            absolute_e = false;
        } else if is("G92") {
            if let Some(v) = arg('E')? {
                e = v;
            }
            for (letter, c) in [('X', 0), ('Y', 1), ('Z', 2)] {
                if let Some(v) = arg(letter)? {
                    pos[c] = v;
                }
            }
        } else if is("G20") {
            return Err(GcodeError {
                line,
                message: "inch units (G20) are not supported".into(),
            });
        } else if is("G28") {
            pos = DVec3::ZERO;
        } else if cmd.starts_with(['G', 'M', 'T', 'N', 'F', 'S', 'g', 'm', 't', 'n', 'f', 's'])
            && cmd[1..].parse::<f64>().is_ok()
        {
            // Other numbered commands: no moves.
        } else if cmd.len() >= 3
            && cmd.starts_with(|c: char| c.is_ascii_uppercase())
            && cmd
                .chars()
                .all(|c| c.is_ascii_uppercase() || c.is_ascii_digit() || c == '_')
        {
            // Klipper's and RepRapFirmware's named commands (`SET_PRINT_STATS_INFO …`,
            // `TURN_OFF_HEATERS`): no moves.
        } else {
            return Err(GcodeError {
                line,
                message: format!(
                    "`{}` is not a G-code command",
                    truncated(&cmd.to_ascii_uppercase())
                ),
            });
        }
    }
    Ok((moves, start.unwrap_or(DVec3::ZERO)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_pass_reading_keeps_the_words_rules() {
        // Lower case, a line number, a checksum, a comment; the first X of a line counts; F is
        // not read; relative moves and E; G92 resets E.
        let text = "g90\nN7 g1 x10 Y5 Z0.5 X99 F1200 e1*12 ; first\nM83\nG91\nG1 X1 E0.5\n\
                    G90\nM82\nG92 E0\nG1 X20 E2\nSET_VELOCITY_LIMIT VELOCITY=50\n";
        let (moves, start) = parse_moves(text).unwrap();
        assert_eq!(start, DVec3::ZERO);
        assert_eq!(moves.len(), 3);
        assert_eq!(moves[0].to, DVec3::new(10.0, 5.0, 0.5));
        assert_eq!((moves[0].de, moves[0].line), (1.0, 2));
        assert_eq!(moves[1].to, DVec3::new(11.0, 5.0, 0.5));
        assert_eq!(moves[1].de, 0.5);
        assert_eq!((moves[2].to.x, moves[2].de), (20.0, 2.0));
        // A bad number is named only where the command reads it.
        assert!(parse_moves("M117 Xhello\n").is_ok());
        let e = parse_moves("G1 X1\nG1 Xhello\n").unwrap_err();
        assert_eq!(
            (e.line, e.message.as_str()),
            (2, "`Xhello` is not a number")
        );
        let e = parse_moves("N3\nfrobnicate\n").unwrap_err();
        assert!(e.message.contains("FROBNICATE"), "{}", e.message);
    }
}
