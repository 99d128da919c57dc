//! The I/O around the state machines: the sender over a serial port, the fake printer over the
//! master side of a pseudo-terminal. Both read with a short timeout so the clock keeps running.

use std::io::ErrorKind;
use std::time::{Duration, Instant};

use serialport::SerialPort;

use crate::fake::{Action, FakePrinter};
use crate::sender::{Event, Sender};

/// How long one read waits for bytes before the clock is looked at again.
const POLL: Duration = Duration::from_millis(5);

/// Serial ports on this machine (from /sys/class/tty; no libudev).
pub fn list_ports() -> Vec<String> {
    serialport::available_ports()
        .map(|v| v.into_iter().map(|p| p.port_name).collect())
        .unwrap_or_default()
}

/// Opens a printer's port, 8N1, with the read timeout the link loop uses.
pub fn open_port(path: &str, baud: u32) -> Result<Box<dyn SerialPort>, String> {
    serialport::new(path, baud)
        .timeout(POLL)
        .open()
        .map_err(|e| format!("{path}: cannot open: {}", e.description))
}

/// Splits a byte stream into lines (`\n`, `\r\n` or `\r`), keeping the unfinished tail.
#[derive(Debug, Default)]
pub struct LineBuffer {
    buf: Vec<u8>,
}

impl LineBuffer {
    pub fn push(&mut self, bytes: &[u8], mut line: impl FnMut(&str)) {
        for &b in bytes {
            if b == b'\n' || b == b'\r' {
                if !self.buf.is_empty() {
                    line(&String::from_utf8_lossy(&self.buf));
                    self.buf.clear();
                }
            } else if self.buf.len() < 4096 {
                self.buf.push(b);
            }
        }
    }
}

/// Runs a job to its end over a port: writes what the sender wants written, feeds it every line
/// and the clock, and reports events. Returns when the job finished, failed or was stopped
/// (`control` is asked between reads and may pause, resume, cancel or stop the sender).
pub fn run_job(
    port: &mut dyn SerialPort,
    sender: &mut Sender,
    mut on_event: impl FnMut(&Event),
    mut control: impl FnMut(&mut Sender),
) {
    let name = port.name().unwrap_or_else(|| "the port".into());
    let mut lines = LineBuffer::default();
    let mut buf = [0u8; 4096];
    loop {
        control(sender);
        let outgoing: Vec<Vec<u8>> = sender.outgoing().collect();
        for bytes in outgoing {
            if let Err(e) = port.write_all(&bytes).and_then(|_| port.flush()) {
                // The same words as a failed read: it is the same fault, seen on the other side.
                sender.receive_port_error(&format!(
                    "{name}: the port went away: cannot write: {e} (was the printer unplugged?)"
                ));
            }
        }
        for ev in sender.events() {
            on_event(&ev);
        }
        if sender.is_over() {
            return;
        }
        match port.read(&mut buf) {
            Ok(0) => {}
            Ok(k) => {
                let now = Instant::now();
                lines.push(&buf[..k], |l| sender.receive(l, now));
            }
            Err(e)
                if e.kind() == ErrorKind::TimedOut
                    || e.kind() == ErrorKind::WouldBlock
                    || e.kind() == ErrorKind::Interrupted => {}
            Err(e) => sender.receive_port_error(&format!(
                "{name}: the port went away: {e} (was the printer unplugged?)"
            )),
        }
        sender.tick(Instant::now());
    }
}

/// Serves a fake printer on the master side of a pseudo-terminal until the host closes the port
/// (after having talked), the printer "vanishes", or `stop` says so. Returns the printer (with
/// its log).
pub fn serve_fake(
    port: &mut dyn SerialPort,
    mut printer: FakePrinter,
    mut stop: impl FnMut(&FakePrinter) -> bool,
) -> FakePrinter {
    let mut connected = false;
    let mut lines = LineBuffer::default();
    let mut buf = [0u8; 4096];
    let say = |port: &mut dyn SerialPort, actions: Vec<Action>| -> bool {
        for a in actions {
            match a {
                Action::Say(s) => {
                    let _ = port.write_all(format!("{s}\n").as_bytes());
                }
                Action::Wait(d) => std::thread::sleep(d),
                Action::Vanish => return false,
            }
        }
        let _ = port.flush();
        true
    };
    if !say(port, FakePrinter::greeting()) {
        return printer;
    }
    loop {
        if stop(&printer) {
            return printer;
        }
        match port.read(&mut buf) {
            Ok(k) if k > 0 => {
                connected = true;
                let mut received = Vec::new();
                lines.push(&buf[..k], |l| received.push(l.to_string()));
                for l in received {
                    let actions = printer.receive(&l);
                    if !say(port, actions) {
                        return printer;
                    }
                }
            }
            Ok(_) => {}
            Err(e)
                if e.kind() == ErrorKind::TimedOut
                    || e.kind() == ErrorKind::WouldBlock
                    || e.kind() == ErrorKind::Interrupted => {}
            // The host side is not open: not yet (wait), or not any more (done).
            Err(_) if connected => return printer,
            Err(_) => std::thread::sleep(POLL),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_split_on_any_line_end_and_keep_the_tail() {
        let mut b = LineBuffer::default();
        let mut got = Vec::new();
        b.push(b"ok\r\nResend: 3\nT:20", |l| got.push(l.to_string()));
        b.push(b".0 /0.0\rok\n", |l| got.push(l.to_string()));
        assert_eq!(got, vec!["ok", "Resend: 3", "T:20.0 /0.0", "ok"]);
    }
}
