//! A Marlin-like printer as a state machine, for tests and for teaching: it checks line numbers
//! and checksums like Marlin (`Error:` + `Resend:` + `ok`), keeps a 4-command buffer, answers
//! `M105` with temperatures and `M112` with a halt, logs every command it accepts — and, on
//! request, misbehaves the way real printers and cables do.

use std::time::Duration;

use crate::line::checksum;

/// Which faults to inject and how often (probabilities per received line, 0–1).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Faults {
    /// Noise: the printer asks again for a line it received intact.
    pub resend: f64,
    /// A byte of the line is flipped on the way in (checksum or line-number error).
    pub corrupt: f64,
    /// The `ok` of an accepted line is lost.
    pub drop_ok: f64,
    /// `echo:busy: processing` lines before the `ok`.
    pub busy: f64,
    /// The `ok` comes late (by `slow_by`).
    pub slow: f64,
    pub slow_by: Duration,
    /// A `Resend` without the `ok` that should follow it.
    pub resend_without_ok: f64,
    /// After this many accepted commands the printer reboots (`start`).
    pub reset_after: Option<u64>,
    /// After this many accepted commands the port disappears.
    pub vanish_after: Option<u64>,
    pub seed: u64,
}

impl Faults {
    /// Every kind of fault, `total` of the lines in all (split evenly over six kinds).
    pub fn mixed(total: f64, seed: u64) -> Faults {
        let each = total / 6.0;
        Faults {
            resend: each,
            corrupt: each,
            drop_ok: each,
            busy: each,
            slow: each,
            slow_by: Duration::from_millis(5),
            resend_without_ok: each,
            reset_after: None,
            vanish_after: None,
            seed,
        }
    }
}

/// What the fake printer does next.
#[derive(Debug, Clone, PartialEq)]
pub enum Action {
    /// Write this line (a newline is added).
    Say(String),
    /// Wait before the following actions.
    Wait(Duration),
    /// The port goes away.
    Vanish,
}

/// The printer.
#[derive(Debug)]
pub struct FakePrinter {
    faults: Faults,
    rng: u64,
    last_n: u64,
    /// Every command accepted, in order (line numbers and checksums removed).
    pub log: Vec<String>,
    accepted: u64,
    halted: bool,
    reset_done: bool,
}

impl FakePrinter {
    pub fn new(faults: Faults) -> FakePrinter {
        FakePrinter {
            faults,
            rng: faults
                .seed
                .wrapping_mul(2685821657736338717)
                .wrapping_add(1),
            last_n: 0,
            log: Vec::new(),
            accepted: 0,
            halted: false,
            reset_done: false,
        }
    }

    /// Uniform in [0, 1) (xorshift64*).
    fn chance(&mut self, p: f64) -> bool {
        if p <= 0.0 {
            return false;
        }
        self.rng ^= self.rng >> 12;
        self.rng ^= self.rng << 25;
        self.rng ^= self.rng >> 27;
        let v = (self.rng.wrapping_mul(0x2545F4914F6CDD1D) >> 11) as f64 / (1u64 << 53) as f64;
        v < p
    }

    /// What Marlin prints when it boots.
    pub fn greeting() -> Vec<Action> {
        vec![
            Action::Say("start".into()),
            Action::Say("echo:Marlin 2.1 (clayloft fake printer)".into()),
        ]
    }

    fn resend(&self, why: &str) -> Vec<Action> {
        vec![
            Action::Say(format!("Error:{why}, Last Line: {}", self.last_n)),
            Action::Say(format!("Resend: {}", self.last_n + 1)),
            Action::Say("ok".into()),
        ]
    }

    /// One line received (without its newline).
    pub fn receive(&mut self, raw: &str) -> Vec<Action> {
        if self.halted {
            return vec![];
        }
        let mut line = raw.trim().to_string();
        if line.is_empty() {
            return vec![];
        }
        if line.starts_with('N') && self.chance(self.faults.corrupt) {
            // Flip one bit of a byte before the '*' (noise on the wire).
            let mut b = line.into_bytes();
            let star = b.iter().position(|c| *c == b'*').unwrap_or(b.len());
            // Never the leading `N`: a line without it would be a different (unnumbered) command.
            let i = 1 + (self.rng as usize) % star.saturating_sub(1).max(1);
            b[i] ^= 0x04;
            line = String::from_utf8_lossy(&b).into_owned();
        }
        let Some(rest) = line.strip_prefix('N') else {
            return self.execute(&line.clone(), false);
        };
        // Numbered: `N<n> <cmd>*<cs>`.
        let Some((body, cs)) = line.rsplit_once('*') else {
            return self.resend("No Checksum with line number");
        };
        if cs.trim().parse::<u8>().ok() != Some(checksum(body.as_bytes())) {
            return self.resend("checksum mismatch");
        }
        let digits: String = rest.chars().take_while(|c| c.is_ascii_digit()).collect();
        let Ok(n) = digits.parse::<u64>() else {
            return self.resend("format error");
        };
        let cmd = body[1 + digits.len()..].trim().to_string();
        if cmd.starts_with("M110") {
            self.last_n = n;
            return vec![Action::Say("ok".into())];
        }
        if n == self.last_n {
            // A line it already has (a resend after a lost ok): dropped, acknowledged.
            return vec![Action::Say("ok".into())];
        }
        if n != self.last_n + 1 {
            return self.resend("Line Number is not Last Line Number+1");
        }
        if self.chance(self.faults.resend) {
            return self.resend("checksum mismatch");
        }
        if self.chance(self.faults.resend_without_ok) {
            return vec![
                Action::Say(format!(
                    "Error:checksum mismatch, Last Line: {}",
                    self.last_n
                )),
                Action::Say(format!("Resend: {}", self.last_n + 1)),
            ];
        }
        self.last_n = n;
        self.execute(&cmd, true)
    }

    fn execute(&mut self, cmd: &str, numbered: bool) -> Vec<Action> {
        let word = cmd.split_whitespace().next().unwrap_or("");
        match word {
            "M112" => {
                self.halted = true;
                return vec![Action::Say("Error:Printer halted. kill() called!".into())];
            }
            "M105" if !numbered => {
                return vec![Action::Say("ok T:20.0 /0.0 B:20.0 /0.0 @:0 B@:0".into())];
            }
            _ => {}
        }
        self.log.push(cmd.to_string());
        self.accepted += 1;
        let mut actions = Vec::new();
        if self.faults.vanish_after == Some(self.accepted) {
            return vec![Action::Vanish];
        }
        if !self.reset_done && self.faults.reset_after == Some(self.accepted) {
            self.reset_done = true;
            self.last_n = 0;
            return FakePrinter::greeting();
        }
        if self.chance(self.faults.busy) {
            actions.push(Action::Say("echo:busy: processing".into()));
            actions.push(Action::Wait(Duration::from_millis(2)));
            actions.push(Action::Say("echo:busy: processing".into()));
        }
        if self.chance(self.faults.slow) {
            actions.push(Action::Wait(self.faults.slow_by));
        }
        if word == "M105" {
            actions.push(Action::Say("ok T:20.0 /0.0 B:20.0 /0.0 @:0 B@:0".into()));
        } else if !self.chance(self.faults.drop_ok) {
            actions.push(Action::Say("ok".into()));
        }
        actions
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::line::numbered;

    fn say(p: &mut FakePrinter, bytes: Vec<u8>) -> Vec<String> {
        p.receive(std::str::from_utf8(&bytes).unwrap())
            .into_iter()
            .filter_map(|a| match a {
                Action::Say(s) => Some(s),
                _ => None,
            })
            .collect()
    }

    #[test]
    fn behaves_like_marlin() {
        let mut p = FakePrinter::new(Faults::default());
        assert_eq!(say(&mut p, numbered(0, "M110 N0")), vec!["ok"]);
        assert_eq!(say(&mut p, numbered(1, "G28")), vec!["ok"]);
        assert_eq!(
            say(&mut p, numbered(1, "G28")),
            vec!["ok"],
            "duplicate dropped"
        );
        assert_eq!(
            say(&mut p, numbered(3, "G1 X1")),
            vec![
                "Error:Line Number is not Last Line Number+1, Last Line: 1",
                "Resend: 2",
                "ok"
            ]
        );
        assert_eq!(
            say(&mut p, b"N2 G1 X1*98\n".to_vec()),
            vec!["Error:checksum mismatch, Last Line: 1", "Resend: 2", "ok"]
        );
        assert_eq!(
            say(&mut p, b"M105".to_vec()),
            vec!["ok T:20.0 /0.0 B:20.0 /0.0 @:0 B@:0"]
        );
        assert_eq!(
            say(&mut p, b"M112".to_vec()),
            vec!["Error:Printer halted. kill() called!"]
        );
        assert_eq!(p.log, vec!["G28"]);
    }

    #[test]
    fn faults_happen_at_about_their_rate() {
        let mut p = FakePrinter::new(Faults {
            drop_ok: 0.1,
            seed: 3,
            ..Default::default()
        });
        p.receive("N0 M110 N0*125");
        let mut dropped = 0;
        for n in 1..=2000u64 {
            let l = numbered(n, "G1 X1");
            let a = p.receive(std::str::from_utf8(&l).unwrap());
            dropped += a.is_empty() as usize;
        }
        assert!((150..250).contains(&dropped), "{dropped}");
    }
}
