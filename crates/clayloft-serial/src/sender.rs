//! The host side of the Marlin protocol as a sans-I/O state machine: [`Sender::receive`] takes a
//! line from the printer, [`Sender::tick`] the clock; [`Sender::outgoing`] gives the bytes to
//! write and [`Sender::events`] what to tell the user. No threads, no port: tests drive it with
//! real Marlin replies, the transport ([`crate::link`]) with a serial port.
//!
//! Flow control is ping-pong (one numbered line unacknowledged, as OctoPrint and Printrun do):
//! every line is acknowledged before the next is sent, so a resend never has to untangle lines in
//! flight. Exactly-once delivery rests on the printer's line numbers: a line it already has is
//! dropped by it, a missing one makes it ask again.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use crate::line::{LineError, check_job, numbered};
use crate::reply::{HostAction, Reply, Temperatures, parse};

/// Timeouts and limits of the protocol.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SenderConfig {
    /// Silence after which the printer is probed with `M105`.
    pub timeout: Duration,
    /// Shorter silence allowed once the printer has shown it sends `busy` keep-alives.
    pub busy_timeout: Duration,
    /// Probes in a row without any reply before the job is stopped.
    pub max_probes: u32,
    /// Requests in a row for the same line before the link is declared stuck.
    pub max_resends_of_one_line: u32,
    /// Numbered lines kept for resends.
    pub history: usize,
    /// How long to wait for the `ok` that should follow a `Resend` before acting on the resend
    /// anyway (Smoothieware never sends it; Marlin #18955, Prusa #331). OctoPrint waits 0.5 s.
    pub resend_ok_grace: Duration,
}

impl Default for SenderConfig {
    fn default() -> Self {
        SenderConfig {
            timeout: Duration::from_secs(10),
            busy_timeout: Duration::from_secs(4),
            max_probes: 5,
            max_resends_of_one_line: 10,
            history: 64,
            resend_ok_grace: Duration::from_millis(500),
        }
    }
}

/// What the user (progress bar, printer panel) is told.
#[derive(Debug, Clone, PartialEq)]
pub enum Event {
    /// Job lines acknowledged so far, of the total.
    Progress {
        done: usize,
        total: usize,
    },
    Temperatures(Temperatures),
    /// A message from the printer worth showing.
    Message(String),
    /// A transmission error the printer caught (a checksum or line-number mismatch) and that a
    /// resend recovers: `count` of them so far in this job, and the printer's words for the last.
    Recovered {
        count: u64,
        last: String,
    },
    /// An error the printer reported that does not stop the job (a refused command, an unknown
    /// `Error:`): shown prominently; the job goes on with the printer's next `ok`.
    PrinterError(String),
    /// Every line was acknowledged.
    Finished,
    /// The job stopped, and why (one line).
    Failed(String),
}

/// Where the job is.
#[derive(Debug, Clone, PartialEq)]
pub enum State {
    /// `M110 N0` sent, waiting for its acknowledgement.
    Connecting,
    Printing,
    /// No new job lines are sent; numbering is kept.
    Paused,
    Finished,
    Cancelled,
    Failed(String),
}

/// The host protocol for one job.
#[derive(Debug)]
pub struct Sender {
    cfg: SenderConfig,
    cmds: Vec<String>,
    /// Index of the next job command to send; job command i is line number i + 1.
    next_cmd: usize,
    /// Sent numbered lines, oldest first, for resends.
    history: VecDeque<(u64, Vec<u8>)>,
    /// The numbered line awaiting its `ok`.
    in_flight: Option<u64>,
    /// A resend asked for: the line to send at the next `ok` (or after the grace period), and
    /// when it was asked for.
    resend_from: Option<u64>,
    resend_asked_at: Option<Instant>,
    last_resend: Option<(u64, u32)>,
    /// Highest line number acknowledged.
    acked: u64,
    probes: u32,
    seen_busy: bool,
    last_heard: Instant,
    state: State,
    /// Cancelling: the job's lines after `next_cmd` were replaced by the cancel sequence; the
    /// job ends `Cancelled` once it is acknowledged. Holds the line the job was cancelled after.
    cancelled_after: Option<usize>,
    /// The job's length before a cancel sequence replaced its end.
    job_lines: Option<usize>,
    /// Transmission errors the printer caught and a resend recovered.
    recovered: u64,
    out: VecDeque<Vec<u8>>,
    events: VecDeque<Event>,
}

impl Sender {
    /// A sender for `cmds` (already stripped, see [`crate::line::commands`]); checks every line
    /// before anything is sent, then queues `N0 M110 N0`.
    pub fn new(cmds: Vec<String>, cfg: SenderConfig, now: Instant) -> Result<Sender, LineError> {
        check_job(&cmds)?;
        let mut s = Sender {
            cfg,
            cmds,
            next_cmd: 0,
            history: VecDeque::new(),
            in_flight: None,
            resend_from: None,
            resend_asked_at: None,
            last_resend: None,
            acked: 0,
            probes: 0,
            seen_busy: false,
            last_heard: now,
            state: State::Connecting,
            cancelled_after: None,
            job_lines: None,
            recovered: 0,
            out: VecDeque::new(),
            events: VecDeque::new(),
        };
        s.send_numbered(0, "M110 N0");
        Ok(s)
    }

    pub fn state(&self) -> &State {
        &self.state
    }

    /// Job lines acknowledged.
    pub fn done(&self) -> usize {
        (self.acked as usize).min(self.cmds.len())
    }

    pub fn total(&self) -> usize {
        self.cmds.len()
    }

    /// Index (0-based, in the stripped program) of the line being printed, for the 3D view.
    pub fn current_line(&self) -> usize {
        self.done().saturating_sub(1)
    }

    /// True once the job finished, failed or was cancelled.
    pub fn is_over(&self) -> bool {
        matches!(
            self.state,
            State::Finished | State::Cancelled | State::Failed(_)
        )
    }

    /// Bytes to write to the port, in order.
    pub fn outgoing(&mut self) -> impl Iterator<Item = Vec<u8>> + '_ {
        self.out.drain(..)
    }

    /// What happened since the last call.
    pub fn events(&mut self) -> impl Iterator<Item = Event> + '_ {
        self.events.drain(..)
    }

    fn send_numbered(&mut self, n: u64, cmd: &str) {
        let bytes = numbered(n, cmd);
        self.history.push_back((n, bytes.clone()));
        while self.history.len() > self.cfg.history {
            self.history.pop_front();
        }
        self.out.push_back(bytes);
        self.in_flight = Some(n);
    }

    fn resend(&mut self, n: u64) {
        match self.history.iter().find(|(k, _)| *k == n) {
            Some((_, bytes)) => {
                self.out.push_back(bytes.clone());
                self.in_flight = Some(n);
            }
            None => self.fail(format!(
                "the printer asked for line {n} again, which is no longer in the history"
            )),
        }
    }

    fn fail(&mut self, why: String) {
        if !self.is_over() {
            self.state = State::Failed(why.clone());
            self.events.push_back(Event::Failed(why));
        }
    }

    /// The line after `n` has been acknowledged: the next resend, or the next job line.
    fn advance(&mut self) {
        if let Some(r) = self.resend_from.take() {
            self.resend_asked_at = None;
            let last_sent = self.history.back().map_or(0, |(k, _)| *k);
            if r < last_sent {
                self.resend_from = Some(r + 1);
            }
            self.resend(r);
            return;
        }
        self.in_flight = None;
        match self.state {
            State::Printing if self.next_cmd < self.cmds.len() => {
                let n = self.next_cmd as u64 + 1;
                let cmd = self.cmds[self.next_cmd].clone();
                self.next_cmd += 1;
                self.send_numbered(n, &cmd);
            }
            State::Printing => match self.cancelled_after {
                Some(done) => self.end_cancelled(done),
                None => {
                    self.state = State::Finished;
                    self.events.push_back(Event::Finished);
                }
            },
            _ => {}
        }
    }

    fn acknowledge(&mut self) {
        if let Some(n) = self.in_flight {
            // The `ok` after a `Resend` only says "go on": the line in flight was not taken.
            let resend_pending = self.resend_asked_at.is_some();
            if !resend_pending && n > self.acked || (n == 0 && self.state == State::Connecting) {
                self.acked = self.acked.max(n);
                if n > 0 {
                    self.events.push_back(Event::Progress {
                        done: self.done(),
                        total: self.cmds.len(),
                    });
                }
            }
            if self.state == State::Connecting {
                self.state = State::Printing;
            }
            self.advance();
        }
    }

    /// One line from the printer.
    pub fn receive(&mut self, line: &str, now: Instant) {
        self.last_heard = now;
        if self.is_over() {
            return;
        }
        match parse(line) {
            Reply::Ok { temperatures } => {
                if let Some(t) = temperatures {
                    self.events.push_back(Event::Temperatures(t));
                    if self.probes > 0 {
                        // The answer to our M105 probe: the printer is alive but our line's ok
                        // was lost (or the line was). Send it again; the printer drops it if it
                        // already has it.
                        self.probes = 0;
                        if let Some(n) = self.in_flight {
                            self.resend(n);
                        }
                        return;
                    }
                }
                self.probes = 0;
                self.acknowledge();
            }
            Reply::ErrorCountsAsOk(m) => {
                self.events.push_back(Event::Message(m));
                self.acknowledge();
            }
            Reply::Resend(n) => {
                let last_sent = self.history.back().map_or(0, |(k, _)| *k);
                if n > last_sent {
                    return; // a line not sent yet: nothing to resend
                }
                let count = match self.last_resend {
                    Some((k, c)) if k == n => c + 1,
                    _ => 1,
                };
                self.last_resend = Some((n, count));
                if count > self.cfg.max_resends_of_one_line {
                    self.fail(format!(
                        "communication stuck: the printer asked for line {n} {count} times"
                    ));
                    return;
                }
                // Sent at the printer's `ok` that follows (or after the grace period if it
                // never comes).
                self.resend_from = Some(n);
                self.resend_asked_at = Some(now);
            }
            Reply::Busy => self.seen_busy = true,
            Reply::Wait | Reply::Duplicate => {}
            Reply::Error(m) => self.events.push_back(Event::PrinterError(m)),
            Reply::Action(action) => self.host_action(action),
            Reply::Start => {
                if self.state != State::Connecting {
                    let at = self.done();
                    self.fail(format!(
                        "the printer reset itself (it said `start`) after line {at} of {}: the job is stopped; check its power and the USB cable",
                        self.cmds.len()
                    ));
                }
            }
            Reply::ErrorAwaitResend(m) => {
                self.recovered += 1;
                self.events.push_back(Event::Recovered {
                    count: self.recovered,
                    last: m,
                });
            }
            Reply::Fatal(m) => self.fail(format!("the printer stopped: {m}")),
            Reply::Temperatures(t) => self.events.push_back(Event::Temperatures(t)),
            Reply::Message(m) => self.events.push_back(Event::Message(m)),
        }
    }

    /// What the printer's own screen or buttons ask of the host (OctoPrint's action commands).
    fn host_action(&mut self, action: HostAction) {
        match action {
            HostAction::Pause => {
                self.events
                    .push_back(Event::Message("paused on the printer".into()));
                self.pause();
            }
            HostAction::Resume => {
                self.events
                    .push_back(Event::Message("resumed on the printer".into()));
                self.resume();
            }
            HostAction::Cancel => {
                if !self.is_over() {
                    self.state = State::Cancelled;
                    self.events.push_back(Event::Failed(format!(
                        "cancelled on the printer after line {} of {}",
                        self.done(),
                        self.cmds.len()
                    )));
                }
            }
            HostAction::Disconnect => {
                self.fail("the printer asked the host to disconnect".into());
            }
            HostAction::Other(what) => self
                .events
                .push_back(Event::Message(format!("the printer says: {what}"))),
        }
    }

    /// The port failed (unplugged, closed): the job ends with this reason.
    pub fn receive_port_error(&mut self, why: &str) {
        self.fail(why.to_string());
    }

    /// The clock: after a silence, probe with `M105`; after too many, give up.
    pub fn tick(&mut self, now: Instant) {
        if self.is_over() || self.in_flight.is_none() {
            return;
        }
        if let (Some(r), Some(at)) = (self.resend_from, self.resend_asked_at)
            && now.duration_since(at) >= self.cfg.resend_ok_grace
        {
            // A Resend without its ok (Smoothieware's `rs N`): act on it.
            self.resend_from = None;
            self.resend_asked_at = None;
            self.last_heard = now;
            self.resend(r);
            return;
        }
        let limit = if self.seen_busy {
            self.cfg.busy_timeout
        } else {
            self.cfg.timeout
        };
        if now.duration_since(self.last_heard) < limit {
            return;
        }
        self.last_heard = now;
        if let Some(r) = self.resend_from.take() {
            // A Resend without its ok: act on it.
            self.resend_asked_at = None;
            self.resend(r);
            return;
        }
        self.probes += 1;
        if self.probes > self.cfg.max_probes {
            let silent = limit * self.cfg.max_probes;
            self.fail(format!(
                "no reply from the printer for {:.0} s: the job is stopped",
                silent.as_secs_f64()
            ));
            return;
        }
        if self.state == State::Connecting {
            self.resend(0);
        } else {
            self.out.push_back(b"M105\n".to_vec());
        }
    }

    /// Stops feeding job lines (the line in flight completes).
    pub fn pause(&mut self) {
        if self.state == State::Printing {
            self.state = State::Paused;
        }
    }

    pub fn resume(&mut self) {
        if self.state == State::Paused {
            self.state = State::Printing;
            if self.in_flight.is_none() {
                self.advance();
            }
        }
    }

    /// Stops the job after the line in flight; the printer keeps what it has.
    pub fn cancel(&mut self) {
        if !self.is_over() {
            let done = self.done();
            self.end_cancelled(done);
        }
    }

    /// Cancels the job the way hosts do: the job's lines not yet sent are replaced by `sequence`
    /// (stop extruding, lift clear of the part, park; numbered and checked like the job), and
    /// the job ends `Cancelled` once the printer has acknowledged it. A paused job is resumed
    /// to send it. An empty or malformed sequence cancels at once, as [`Sender::cancel`].
    pub fn cancel_with(&mut self, sequence: Vec<String>) {
        if self.is_over() || self.cancelled_after.is_some() {
            return;
        }
        if sequence.is_empty() || check_job(&sequence).is_err() {
            return self.cancel();
        }
        self.cancelled_after = Some(self.next_cmd);
        self.job_lines = Some(self.cmds.len());
        self.cmds.truncate(self.next_cmd);
        self.cmds.extend(sequence);
        if self.state == State::Paused {
            self.resume();
        }
    }

    fn end_cancelled(&mut self, done: usize) {
        self.state = State::Cancelled;
        let total = self.job_len();
        let tail = if self.cancelled_after.is_some() {
            "; the cancel sequence ran"
        } else {
            ""
        };
        self.events.push_back(Event::Failed(format!(
            "cancelled after line {done} of {total}{tail}"
        )));
    }

    /// Lines of the job as it was given (before a cancel sequence replaced its end).
    fn job_len(&self) -> usize {
        self.job_lines.unwrap_or(self.cmds.len())
    }

    /// `M112` at once (bare: Marlin's emergency parser reads it even with a full queue) and stop.
    pub fn emergency_stop(&mut self) {
        self.out.push_front(b"M112\n".to_vec());
        if !self.is_over() {
            self.state = State::Failed("emergency stop (M112) sent".into());
            self.events
                .push_back(Event::Failed("emergency stop (M112) sent".into()));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn job(n: usize) -> Vec<String> {
        (0..n).map(|i| format!("G1 X{i}")).collect()
    }

    fn out(s: &mut Sender) -> Vec<String> {
        s.outgoing()
            .map(|b| String::from_utf8(b).unwrap().trim_end().to_string())
            .collect()
    }

    fn start(n: usize) -> (Sender, Instant) {
        let t = Instant::now();
        let mut s = Sender::new(job(n), SenderConfig::default(), t).unwrap();
        assert_eq!(out(&mut s), vec!["N0 M110 N0*125"]);
        s.receive("ok", t);
        (s, t)
    }

    #[test]
    fn ping_pong_to_the_end() {
        let (mut s, t) = start(2);
        assert_eq!(
            out(&mut s),
            vec![String::from_utf8(numbered(1, "G1 X0")).unwrap().trim_end()]
        );
        s.receive("ok", t);
        assert_eq!(out(&mut s).len(), 1);
        s.receive("ok T:20.0 /0.0", t); // an ok with temperatures is still an ok
        assert!(out(&mut s).is_empty());
        assert_eq!(s.state(), &State::Finished);
        let ev: Vec<Event> = s.events().collect();
        assert!(ev.contains(&Event::Progress { done: 2, total: 2 }));
        assert!(ev.contains(&Event::Finished));
    }

    #[test]
    fn resend_forms_replay_from_history_and_ignore_unsent_lines() {
        for resend in [
            "Resend: 2",
            "Resend:2",
            "rs N2 expected checksum 9",
            "Resend: N:2",
        ] {
            let (mut s, t) = start(5);
            s.receive("ok", t); // line 1 acked
            s.receive("ok", t); // line 2 acked, line 3 sent
            out(&mut s);
            s.receive("Error:checksum mismatch, Last Line: 1", t);
            s.receive(resend, t);
            s.receive("Resend: 9", t); // not sent yet: ignored
            assert!(out(&mut s).is_empty(), "wait for the ok");
            s.receive("ok", t);
            assert_eq!(
                out(&mut s),
                vec![String::from_utf8(numbered(2, "G1 X1")).unwrap().trim_end()]
            );
            s.receive("ok", t);
            assert_eq!(
                out(&mut s),
                vec![String::from_utf8(numbered(3, "G1 X2")).unwrap().trim_end()]
            );
            s.receive("ok", t);
            assert_eq!(
                out(&mut s),
                vec![String::from_utf8(numbered(4, "G1 X3")).unwrap().trim_end()]
            );
        }
    }

    #[test]
    fn busy_is_a_keep_alive_not_an_ack() {
        let (mut s, t) = start(3);
        out(&mut s);
        s.receive("echo:busy: processing", t);
        assert!(out(&mut s).is_empty());
        assert_eq!(s.done(), 0);
    }

    #[test]
    fn lost_ok_is_probed_with_m105_then_the_line_is_sent_again() {
        let (mut s, t) = start(3);
        out(&mut s);
        s.tick(t + Duration::from_secs(11));
        assert_eq!(out(&mut s), vec!["M105"]);
        s.receive("ok T:20.0 /0.0 B:20.0 /0.0", t + Duration::from_secs(11));
        assert_eq!(
            out(&mut s),
            vec![String::from_utf8(numbered(1, "G1 X0")).unwrap().trim_end()]
        );
        s.receive("ok", t + Duration::from_secs(11));
        assert_eq!(s.done(), 1);
    }

    #[test]
    fn silence_ends_the_job_with_a_reason() {
        let (mut s, t) = start(3);
        for k in 1..=6 {
            s.tick(t + Duration::from_secs(11 * k));
        }
        assert!(matches!(s.state(), State::Failed(m) if m.contains("no reply")));
    }

    #[test]
    fn start_mid_job_is_a_reset_and_errors_stop_it() {
        let (mut s, t) = start(3);
        s.receive("ok", t);
        s.receive("start", t);
        assert!(
            matches!(s.state(), State::Failed(m) if m.contains("reset") && m.contains("after line 1 of 3"))
        );
        let (mut s, t) = start(3);
        s.receive("Error:Printer halted. kill() called!", t);
        assert!(matches!(s.state(), State::Failed(m) if m.contains("kill()")));
    }

    #[test]
    fn stuck_resend_and_lost_history() {
        let (mut s, t) = start(3);
        for _ in 0..11 {
            s.receive("Resend: 1", t);
            s.receive("ok", t);
        }
        assert!(matches!(s.state(), State::Failed(m) if m.contains("stuck")));
        let t = Instant::now();
        let cfg = SenderConfig {
            history: 2,
            ..Default::default()
        };
        let mut s = Sender::new(job(5), cfg, t).unwrap();
        for _ in 0..4 {
            s.receive("ok", t);
        }
        s.receive("Resend: 1", t);
        s.receive("ok", t);
        assert!(matches!(s.state(), State::Failed(m) if m.contains("history")));
    }

    #[test]
    fn pause_resume_cancel_and_emergency_stop() {
        let (mut s, t) = start(4);
        out(&mut s);
        s.pause();
        s.receive("ok", t);
        assert!(out(&mut s).is_empty(), "paused: no new line");
        s.resume();
        assert_eq!(out(&mut s).len(), 1);
        s.emergency_stop();
        assert_eq!(out(&mut s), vec!["M112"]);
        assert!(s.is_over());
        let (mut s, _) = start(4);
        s.cancel();
        assert_eq!(s.state(), &State::Cancelled);
    }

    #[test]
    fn cancel_sends_the_cancel_sequence_in_place_of_the_rest() {
        let (mut s, t) = start(10);
        assert_eq!(out(&mut s), vec![line(1, "G1 X0")]);
        s.receive("ok", t);
        assert_eq!(out(&mut s), vec![line(2, "G1 X1")]);
        // Paused, then cancelled: the sequence goes out after the line in flight.
        s.pause();
        s.cancel_with(vec!["G91".into(), "G1 Z10 F600".into(), "G90".into()]);
        s.receive("ok", t);
        let mut sent = out(&mut s);
        for _ in 0..3 {
            s.receive("ok", t);
            sent.extend(out(&mut s));
        }
        assert_eq!(
            sent,
            vec![line(3, "G91"), line(4, "G1 Z10 F600"), line(5, "G90")]
        );
        assert_eq!(s.state(), &State::Cancelled);
        let said: Vec<Event> = s.events().collect();
        assert!(
            said.iter().any(|e| matches!(e, Event::Failed(m) if m == "cancelled after line 2 of 10; the cancel sequence ran")),
            "{said:?}"
        );
        // A malformed sequence cancels at once.
        let (mut s, _) = start(4);
        s.cancel_with(vec![format!("G1 X{}", "9".repeat(200))]);
        assert_eq!(s.state(), &State::Cancelled);
    }

    fn line(n: u64, cmd: &str) -> String {
        String::from_utf8(numbered(n, cmd))
            .unwrap()
            .trim_end()
            .to_string()
    }

    #[test]
    fn an_unknown_error_is_shown_and_the_job_goes_on() {
        for error in [
            "Error: G0/G1: insufficient axes homed",
            "!! Move out of range: 250.000 10.000 0.200 [0.000]",
            "Error:Printer set into dry run mode until restart!",
            "Error:something no firmware here says",
        ] {
            let (mut s, t) = start(3);
            out(&mut s);
            s.receive(error, t);
            assert_eq!(s.state(), &State::Printing, "{error}");
            assert!(out(&mut s).is_empty(), "wait for the printer's next ok");
            s.receive("ok", t);
            assert_eq!(out(&mut s), vec![line(2, "G1 X1")], "{error}");
            let ev: Vec<Event> = s.events().collect();
            assert!(
                ev.contains(&Event::PrinterError(error.trim().into())),
                "{error}"
            );
        }
    }

    #[test]
    fn an_unknown_error_without_ok_runs_into_the_silence_timeout() {
        let (mut s, t) = start(3);
        out(&mut s);
        s.receive("Error:Something odd", t);
        for k in 1..=6 {
            s.tick(t + Duration::from_secs(11 * k));
        }
        assert!(matches!(s.state(), State::Failed(m) if m.contains("no reply")));
    }

    #[test]
    fn octoprints_virtual_printer_missing_checksum_is_recovered() {
        // Its simulated error at line 100: `Error: Missing checksum`, `Resend:N`, `ok`.
        let (mut s, t) = start(3);
        s.receive("ok", t); // line 1 acked, 2 sent
        out(&mut s);
        s.receive("Error: Missing checksum", t);
        s.receive("Resend:2", t);
        s.receive("ok", t);
        assert_eq!(s.state(), &State::Printing);
        assert_eq!(out(&mut s), vec![line(2, "G1 X1")]);
        assert_eq!(s.done(), 1, "the ok after a Resend is no acknowledgement");
        s.receive("ok", t);
        assert_eq!(s.done(), 2);
        assert_eq!(out(&mut s), vec![line(3, "G1 X2")]);
    }

    #[test]
    fn a_resend_without_ok_is_acted_on_after_the_grace_period() {
        // Smoothieware: `rs N2` and nothing else.
        let (mut s, t) = start(3);
        s.receive("ok", t);
        out(&mut s);
        s.receive("rs N2", t);
        s.tick(t + Duration::from_millis(100));
        assert!(out(&mut s).is_empty(), "still in the grace period");
        s.tick(t + Duration::from_millis(600));
        assert_eq!(out(&mut s), vec![line(2, "G1 X1")]);
        s.receive("ok", t + Duration::from_millis(700));
        assert_eq!(s.done(), 2);
        assert_eq!(out(&mut s), vec![line(3, "G1 X2")]);
    }

    #[test]
    fn known_fatal_messages_of_each_firmware_end_the_job() {
        for fatal in [
            "Error:Printer halted. kill() called!",
            "Error:Thermal Runaway, system stopped! Heater_ID: 0",
            "Error:MAXTEMP triggered, system stopped! Heater_ID: 0",
            "Error:: Extruder switched off. MINTEMP triggered !",
            "!! Shutdown due to M112 command",
            "// Klipper state: Shutdown",
            "Emergency Stop! Reset the controller to continue.",
            "fatal:Heater/sensor error - Printer stopped and heaters disabled due to this error. Fix error and restart with M999.",
            "!!",
            "ALARM: Kill button pressed - reset or M999 to continue",
        ] {
            let (mut s, t) = start(3);
            s.receive(fatal, t);
            assert!(
                matches!(s.state(), State::Failed(m) if m.contains(fatal.trim())),
                "{fatal}: {:?}",
                s.state()
            );
        }
    }

    #[test]
    fn host_actions_from_the_printers_screen() {
        let (mut s, t) = start(4);
        out(&mut s);
        s.receive("//action:pause", t);
        s.receive("ok", t);
        assert!(out(&mut s).is_empty(), "paused from the printer");
        s.receive("//action:resume", t);
        assert_eq!(out(&mut s), vec![line(2, "G1 X1")]);
        s.receive("//action:cancel", t);
        assert_eq!(s.state(), &State::Cancelled);
        let (mut s, t) = start(4);
        s.receive("//action:disconnect", t);
        assert!(matches!(s.state(), State::Failed(m) if m.contains("disconnect")));
    }

    #[test]
    fn recovered_transmission_errors_are_counted_not_listed() {
        let (mut s, t) = start(5);
        out(&mut s);
        for _ in 0..3 {
            s.receive("Error:checksum mismatch, Last Line: 0", t);
            s.receive("Resend: 1", t);
            s.receive("ok", t);
        }
        let said: Vec<Event> = s.events().collect();
        assert!(
            said.iter().all(|e| !matches!(e, Event::Message(_))),
            "{said:?}"
        );
        assert!(said.contains(&Event::Recovered {
            count: 3,
            last: "Error:checksum mismatch, Last Line: 0".into()
        }));
    }

    #[test]
    fn keep_alives_are_no_acknowledgements() {
        let (mut s, t) = start(3);
        out(&mut s);
        for keep_alive in ["wait", "echo:busy processing", "busy:processing", "skip 1"] {
            s.receive(keep_alive, t);
        }
        assert_eq!(s.done(), 0);
        assert!(out(&mut s).is_empty());
        assert!(s.events().all(|e| !matches!(e, Event::Message(_))));
    }
}
