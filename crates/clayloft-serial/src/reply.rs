//! Printer replies, as Marlin (and firmwares that copy it) write them.

/// One line from the printer, classified.
#[derive(Debug, Clone, PartialEq)]
pub enum Reply {
    /// `ok`, `ok T:…` (with a temperature report), `ok N12 P15 B3` (ADVANCED_OK).
    Ok { temperatures: Option<Temperatures> },
    /// `Resend: 12`, `Resend:12`, `Resend: N:12`, `rs N12 …`, `rs 12`.
    Resend(u64),
    /// `echo:busy: processing`, `echo:busy: paused for user`: keep-alive, not an ack.
    Busy,
    /// `start`: the firmware (re)booted.
    Start,
    /// An `Error:` the printer follows with a `Resend` (checksum, line number, format).
    ErrorAwaitResend(String),
    /// `Error:No Line Number with checksum`: no Resend follows; counts as an ack.
    ErrorCountsAsOk(String),
    /// Any other `Error:`, `fatal:` or `kill() called`: the printer stopped.
    Fatal(String),
    /// A temperature report without `ok` (auto-report).
    Temperatures(Temperatures),
    /// Anything else (`echo:…`, firmware info): shown to the user.
    Message(String),
}

/// Hotend and bed temperatures, actual and target (°C).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Temperatures {
    pub tool: Option<(f64, f64)>,
    pub bed: Option<(f64, f64)>,
}

fn parse_temperatures(s: &str) -> Option<Temperatures> {
    let mut t = Temperatures::default();
    let words: Vec<&str> = s.split_whitespace().collect();
    for (i, w) in words.iter().enumerate() {
        let (key, val) = match w.split_once(':') {
            Some(kv) => kv,
            None => continue,
        };
        let Ok(actual) = val.parse::<f64>() else {
            continue;
        };
        let target = words
            .get(i + 1)
            .and_then(|n| n.strip_prefix('/'))
            .and_then(|n| n.parse::<f64>().ok())
            .unwrap_or(0.0);
        match key {
            "T" | "T0" if t.tool.is_none() => t.tool = Some((actual, target)),
            "B" => t.bed = Some((actual, target)),
            _ => {}
        }
    }
    (t.tool.is_some() || t.bed.is_some()).then_some(t)
}

/// The first run of digits after `prefix`-like noise (`N`, `N:`, spaces).
fn line_number(s: &str) -> Option<u64> {
    let start = s.find(|c: char| c.is_ascii_digit())?;
    let digits: String = s[start..]
        .chars()
        .take_while(|c| c.is_ascii_digit())
        .collect();
    digits.parse().ok()
}

/// Classifies one line from the printer.
pub fn parse(line: &str) -> Reply {
    let l = line.trim();
    let lower = l.to_ascii_lowercase();
    if lower == "ok" || lower.starts_with("ok ") {
        return Reply::Ok {
            temperatures: parse_temperatures(&l[2..]),
        };
    }
    if let Some(n) = lower
        .strip_prefix("resend:")
        .or_else(|| lower.strip_prefix("rs "))
        .and_then(line_number)
    {
        return Reply::Resend(n);
    }
    if lower.starts_with("echo:busy:") || lower.starts_with("busy:") {
        return Reply::Busy;
    }
    if lower == "start" {
        return Reply::Start;
    }
    if lower.starts_with("fatal:") || lower.contains("kill() called") {
        return Reply::Fatal(l.to_string());
    }
    if let Some(msg) = lower.strip_prefix("error:") {
        if msg.contains("no line number with checksum") {
            return Reply::ErrorCountsAsOk(l.to_string());
        }
        let awaits = [
            "checksum mismatch",
            "line number",
            "expected line",
            "format error",
            "no checksum",
        ];
        if awaits.iter().any(|a| msg.contains(a)) {
            return Reply::ErrorAwaitResend(l.to_string());
        }
        if msg.contains("unknown command") {
            return Reply::Message(l.to_string());
        }
        return Reply::Fatal(l.to_string());
    }
    if lower.starts_with("t:")
        && let Some(t) = parse_temperatures(l)
    {
        return Reply::Temperatures(t);
    }
    Reply::Message(l.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn real_marlin_replies() {
        let temps = Temperatures {
            tool: Some((210.0, 210.0)),
            bed: Some((60.0, 60.0)),
        };
        let table: Vec<(&str, Reply)> = vec![
            ("ok", Reply::Ok { temperatures: None }),
            (
                "ok T:210.0 /210.0 B:60.0 /60.0 T0:210.0 /210.0 @:0 B@:0",
                Reply::Ok {
                    temperatures: Some(temps),
                },
            ),
            ("ok N12 P15 B3", Reply::Ok { temperatures: None }),
            ("Resend: 23", Reply::Resend(23)),
            ("Resend:23", Reply::Resend(23)),
            ("Resend: N:23", Reply::Resend(23)),
            ("rs N23 expected checksum 109", Reply::Resend(23)),
            ("rs 7", Reply::Resend(7)),
            ("Resend: 034497", Reply::Resend(34497)),
            ("echo:busy: processing", Reply::Busy),
            ("echo:busy: paused for user", Reply::Busy),
            ("start", Reply::Start),
            (
                "Error:checksum mismatch, Last Line: 22",
                Reply::ErrorAwaitResend("Error:checksum mismatch, Last Line: 22".into()),
            ),
            (
                "Error:Line Number is not Last Line Number+1, Last Line: 22",
                Reply::ErrorAwaitResend(
                    "Error:Line Number is not Last Line Number+1, Last Line: 22".into(),
                ),
            ),
            (
                "Error:No Checksum with line number, Last Line: 5",
                Reply::ErrorAwaitResend("Error:No Checksum with line number, Last Line: 5".into()),
            ),
            (
                "Error:No Line Number with checksum, Last Line: 5",
                Reply::ErrorCountsAsOk("Error:No Line Number with checksum, Last Line: 5".into()),
            ),
            (
                "Error:Printer halted. kill() called!",
                Reply::Fatal("Error:Printer halted. kill() called!".into()),
            ),
            (
                "Error:MINTEMP triggered, system stopped! Heater_ID: 0",
                Reply::Fatal("Error:MINTEMP triggered, system stopped! Heater_ID: 0".into()),
            ),
            (
                "echo:Unknown command: \"G999\"",
                Reply::Message("echo:Unknown command: \"G999\"".into()),
            ),
            (
                " T:20.5 /0.0 B:21.0 /0.0 @:0 B@:0",
                Reply::Temperatures(Temperatures {
                    tool: Some((20.5, 0.0)),
                    bed: Some((21.0, 0.0)),
                }),
            ),
            ("echo:SD card ok", Reply::Message("echo:SD card ok".into())),
        ];
        for (line, want) in table {
            assert_eq!(parse(line), want, "{line}");
        }
    }
}
