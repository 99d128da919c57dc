//! `clayloft print` and `clayloft fake-printer` (SPEC §9): thin wrappers around
//! `clayloft-serial`.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::{Duration, Instant};

use clayloft_serial::fake::{FakePrinter, Faults};
use clayloft_serial::line::commands;
use clayloft_serial::link::{open_port, run_job, serve_fake};
use clayloft_serial::sender::State;
use clayloft_serial::{Event, Sender, SenderConfig};
use indicatif::{ProgressBar, ProgressStyle};
use serialport::{SerialPort, TTYPort};

use crate::Failure;

/// Streams a G-code file to a printer. Exit 0 when every line was acknowledged, 1 when the job
/// stopped (printer reset, port gone, no reply, printer error), 2 on bad input.
pub fn print(file: &Path, port: &str, baud: u32, timeout_s: f64) -> Result<ExitCode, Failure> {
    let text = std::fs::read(file).map_err(|e| {
        let why = if e.kind() == std::io::ErrorKind::NotFound {
            "no such file".to_string()
        } else {
            e.to_string()
        };
        Failure(format!("{}: cannot read: {why}", file.display()))
    })?;
    let text = String::from_utf8(text)
        .map_err(|_| Failure(format!("{}: not a text G-code file", file.display())))?;
    let cmds = commands(&text);
    if cmds.is_empty() {
        return Err(Failure(format!(
            "{}: no G-code commands to send",
            file.display()
        )));
    }
    if !(timeout_s.is_finite() && (0.01..=600.0).contains(&timeout_s)) {
        return Err(Failure(format!(
            "--timeout {timeout_s}: must lie in 0.01 … 600 s"
        )));
    }
    let cfg = SenderConfig {
        timeout: Duration::from_secs_f64(timeout_s),
        busy_timeout: Duration::from_secs_f64(timeout_s.min(4.0)),
        ..Default::default()
    };
    let mut sender = Sender::new(cmds, cfg, Instant::now())
        .map_err(|e| Failure(format!("{}: {e}", file.display())))?;
    let mut link = open_port(port, baud).map_err(Failure)?;
    let bar = ProgressBar::new(sender.total() as u64);
    bar.set_style(
        ProgressStyle::with_template("{bar:40} {pos}/{len} lines {percent}% ETA {eta} {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let mut last_message = String::new();
    let mut recovered = 0;
    run_job(
        link.as_mut(),
        &mut sender,
        |ev| match ev {
            Event::Progress { done, .. } => bar.set_position(*done as u64),
            Event::Temperatures(t) => {
                if let Some((a, b)) = t.tool {
                    bar.set_message(format!("nozzle {a:.0}/{b:.0} °C"));
                }
            }
            Event::Message(m) => last_message = m.clone(),
            Event::Recovered { count, .. } => recovered = *count,
            Event::PrinterError(m) => {
                // Shown above the bar, kept in the terminal: the job goes on.
                bar.println(format!("printer error (the job goes on): {m}"));
                last_message = m.clone();
            }
            _ => {}
        },
        |_| {},
    );
    bar.finish_and_clear();
    if recovered > 0 {
        println!("{recovered} transmission errors caught by the printer, each line resent");
    }
    match sender.state() {
        State::Finished => {
            println!("printed {} lines to {port}", sender.total());
            Ok(ExitCode::SUCCESS)
        }
        State::Failed(why) => {
            let extra = if last_message.is_empty() {
                String::new()
            } else {
                format!(" (last message: {last_message})")
            };
            // The link's port errors name the port already.
            if why.starts_with(port) {
                eprintln!("error: {why}{extra}");
            } else {
                eprintln!("error: {port}: {why}{extra}");
            }
            Ok(ExitCode::from(1))
        }
        other => {
            eprintln!("error: {port}: the job ended {other:?}");
            Ok(ExitCode::from(1))
        }
    }
}

/// Fault knobs of `clayloft fake-printer`.
pub struct FakeOptions {
    pub faults: f64,
    pub seed: u64,
    pub reset_after: Option<u64>,
    pub vanish_after: Option<u64>,
    pub log: Option<PathBuf>,
}

/// Opens a pseudo-terminal, prints the port to connect to, and plays a Marlin printer on it until
/// the host disconnects (or the printer is told to vanish). Logs every accepted command.
pub fn fake_printer(o: FakeOptions) -> Result<ExitCode, Failure> {
    if !(0.0..=0.5).contains(&o.faults) {
        return Err(Failure(format!(
            "--faults {}: must lie in 0 … 0.5 (a fraction of the lines)",
            o.faults
        )));
    }
    let (mut master, slave) = TTYPort::pair()
        .map_err(|e| Failure(format!("cannot open a pseudo-terminal: {}", e.description)))?;
    let name = slave
        .name()
        .ok_or_else(|| Failure("the pseudo-terminal has no name".into()))?;
    master
        .set_timeout(Duration::from_millis(5))
        .map_err(|e| Failure(e.description))?;
    // The host opens the port by name; our own handle on it is not needed.
    drop(slave);
    println!("{name}");
    let _ = std::io::stdout().flush();
    eprintln!(
        "fake printer listening on {name} (faults {:.1} %, seed {})",
        o.faults * 100.0,
        o.seed
    );
    let mut faults = Faults::mixed(o.faults, o.seed);
    faults.reset_after = o.reset_after;
    faults.vanish_after = o.vanish_after;
    let printer = serve_fake(
        &mut master as &mut dyn SerialPort,
        FakePrinter::new(faults),
        |_| false,
    );
    drop(master);
    eprintln!("fake printer: {} commands accepted", printer.log.len());
    if let Some(path) = o.log {
        let mut text = printer.log.join("\n");
        text.push('\n');
        clayloft_core::atomic::write_atomically(&path, |w| w.write_all(text.as_bytes()))?;
    }
    Ok(ExitCode::SUCCESS)
}
