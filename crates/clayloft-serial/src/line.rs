//! Lines as Marlin reads them: `N<n> <command>*<checksum>\n`, the checksum being the XOR of every
//! byte before `*`. Comments (`;` to the end of the line, `( … )`) and blank lines never reach the
//! printer, and are removed before numbering.

/// Marlin's `MAX_CMD_SIZE` is 96 bytes including the terminating NUL: 95 on the wire.
pub const MAX_LINE_BYTES: usize = 95;

/// A G-code line without its comment and surrounding whitespace; `None` if nothing is left.
pub fn strip(line: &str) -> Option<&str> {
    let code = match line.find(';') {
        Some(i) => &line[..i],
        None => line,
    };
    let code = code.trim();
    if code.is_empty() || code.starts_with('(') && code.ends_with(')') {
        None
    } else {
        Some(code)
    }
}

/// The commands of a G-code program, in order: comments and blank lines gone.
pub fn commands(program: &str) -> Vec<String> {
    program
        .lines()
        .filter_map(strip)
        .map(str::to_string)
        .collect()
}

/// XOR of the bytes.
pub fn checksum(bytes: &[u8]) -> u8 {
    bytes.iter().fold(0, |c, b| c ^ b)
}

/// Why a command cannot be sent.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum LineError {
    #[error(
        "line {index}: {len} bytes with its number and checksum; the firmware reads at most {MAX_LINE_BYTES}"
    )]
    TooLong { index: usize, len: usize },
    #[error("line {index}: not plain ASCII")]
    NotAscii { index: usize },
}

/// `N<n> <cmd>*<checksum>\n`.
pub fn numbered(n: u64, cmd: &str) -> Vec<u8> {
    let body = format!("N{n} {cmd}");
    let cs = checksum(body.as_bytes());
    format!("{body}*{cs}\n").into_bytes()
}

/// Checks every command of a job before anything is sent: ASCII, and short enough with the
/// largest line number it will carry (`index` is 1-based in the stripped program).
pub fn check_job(cmds: &[String]) -> Result<(), LineError> {
    for (i, c) in cmds.iter().enumerate() {
        if !c.is_ascii() {
            return Err(LineError::NotAscii { index: i + 1 });
        }
        let len = numbered(i as u64 + 1, c).len() - 1;
        if len > MAX_LINE_BYTES {
            return Err(LineError::TooLong { index: i + 1, len });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn checksums_of_real_lines() {
        // From the Marlin/OctoPrint notes.
        assert_eq!(numbered(0, "M110 N0"), b"N0 M110 N0*125\n".to_vec());
        assert_eq!(
            numbered(12, "G1 X1 Y-11 Z2 F12000"),
            b"N12 G1 X1 Y-11 Z2 F12000*27\n".to_vec()
        );
        assert_eq!(
            numbered(123, "G1 X10.5 Y20 E1.25 F1200"),
            b"N123 G1 X10.5 Y20 E1.25 F1200*41\n".to_vec()
        );
    }

    #[test]
    fn comments_and_blank_lines_go_before_numbering() {
        let p = "; header\nG28 ; home\n\n   \nG1 X1\n(a paren comment)\nM104 S0\n";
        assert_eq!(commands(p), vec!["G28", "G1 X1", "M104 S0"]);
    }

    #[test]
    fn long_and_non_ascii_lines_are_refused_before_sending() {
        let long = format!("M117 {}", "x".repeat(90));
        assert_eq!(
            check_job(&["G28".into(), long]),
            Err(LineError::TooLong { index: 2, len: 100 })
        );
        assert_eq!(
            check_job(&["M117 café".into()]),
            Err(LineError::NotAscii { index: 1 })
        );
        assert!(check_job(&["G1 X1".into()]).is_ok());
    }
}
