//! End-to-end tests of the printer link over real pseudo-terminals: `clayloft fake-printer`
//! plays Marlin with injected faults, `clayloft print` streams to it.

use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::Duration;

mod common;
use common::wait_bounded;

const BIN: &str = env!("CARGO_BIN_EXE_clayloft");

/// Starts a fake printer and returns it with the port it listens on.
fn fake_printer(args: &[&str]) -> (Child, String) {
    let mut child = Command::new(BIN)
        .arg("fake-printer")
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start the fake printer");
    let mut port = String::new();
    BufReader::new(child.stdout.take().unwrap())
        .read_line(&mut port)
        .unwrap();
    (child, port.trim().to_string())
}

fn print(file: &Path, port: &str) -> Child {
    Command::new(BIN)
        .args([
            "print",
            file.to_str().unwrap(),
            "--port",
            port,
            "--timeout",
            "0.03",
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

/// A job of `n` moves with the comments and blank lines real files have.
fn job(n: usize) -> String {
    let mut s = String::from("; a test job\nG21 ; millimetres\n\nM83\n");
    for i in 0..n {
        s += &format!(
            "G1 X{}.{:03} Y{}.{:03} Z{:.2} E0.{:04}\n",
            20 + i % 140,
            i % 997,
            20 + i % 150,
            i % 991,
            i as f64 * 0.001,
            i % 9973
        );
        if i % 1000 == 0 {
            s += &format!("; layer {}\n\n", i / 1000);
        }
    }
    s
}

fn stripped(program: &str) -> Vec<String> {
    program
        .lines()
        .map(|l| l.split(';').next().unwrap().trim())
        .filter(|l| !l.is_empty())
        .map(str::to_string)
        .collect()
}

#[test]
fn hundred_thousand_lines_with_five_percent_faults_arrive_exactly_once_in_order() {
    let dir = tempfile::tempdir().unwrap();
    let gcode = dir.path().join("job.gcode");
    let program = job(100_000);
    std::fs::write(&gcode, &program).unwrap();
    let log = dir.path().join("accepted.log");
    let (fake, port) = fake_printer(&[
        "--faults",
        "0.05",
        "--seed",
        "42",
        "--log",
        log.to_str().unwrap(),
    ]);
    let out = wait_bounded(print(&gcode, &port), Duration::from_secs(400));
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // The recovered errors are one summary line, not a line each.
    let said = String::from_utf8_lossy(&out.stdout);
    let summary: Vec<&str> = said
        .lines()
        .filter(|l| l.contains("transmission errors caught by the printer, each line resent"))
        .collect();
    assert_eq!(summary.len(), 1, "{said}");
    assert!(!said.contains("checksum"), "{said}");
    let fake_out = wait_bounded(fake, Duration::from_secs(20));
    let err = String::from_utf8_lossy(&fake_out.stderr);
    assert!(err.contains("faults 5.0 %"), "{err}");
    let accepted: Vec<String> = std::fs::read_to_string(&log)
        .unwrap()
        .lines()
        .map(str::to_string)
        .collect();
    let want = stripped(&program);
    assert_eq!(accepted.len(), want.len());
    assert!(
        accepted == want,
        "the printer's log differs from the stripped G-code"
    );
}

#[test]
fn a_reset_mid_job_stops_it_with_a_clear_error() {
    let dir = tempfile::tempdir().unwrap();
    let gcode = dir.path().join("job.gcode");
    std::fs::write(&gcode, job(3000)).unwrap();
    let (fake, port) = fake_printer(&["--reset-after", "700"]);
    let out = wait_bounded(print(&gcode, &port), Duration::from_secs(30));
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains("reset itself") && err.contains("after line 69"),
        "{err}"
    );
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    wait_bounded(fake, Duration::from_secs(10));
}

#[test]
fn a_vanished_port_ends_the_job_without_hanging() {
    let dir = tempfile::tempdir().unwrap();
    let gcode = dir.path().join("job.gcode");
    std::fs::write(&gcode, job(3000)).unwrap();
    let (fake, port) = fake_printer(&["--vanish-after", "500", "--faults", "0.02"]);
    let out = wait_bounded(print(&gcode, &port), Duration::from_secs(30));
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains(&port) && (err.contains("went away") || err.contains("no reply")),
        "{err}"
    );
    wait_bounded(fake, Duration::from_secs(10));
}

#[test]
fn bad_print_input_exits_2_naming_the_problem() {
    let dir = tempfile::tempdir().unwrap();
    let run = |args: &[&str]| Command::new(BIN).args(args).output().unwrap();
    let out = run(&["print", "/nonexistent/job.gcode", "--port", "/dev/null"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        String::from_utf8_lossy(&out.stderr)
            .contains("/nonexistent/job.gcode: cannot read: no such file")
    );
    let long = dir.path().join("long.gcode");
    std::fs::write(&long, format!("G28\nM117 {}\n", "x".repeat(100))).unwrap();
    let out = run(&["print", long.to_str().unwrap(), "--port", "/dev/null"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("line 2: 110 bytes"),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let ok = dir.path().join("ok.gcode");
    std::fs::write(&ok, "G28\n").unwrap();
    let out = run(&["print", ok.to_str().unwrap(), "--port", "/dev/ttyNOPE0"]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("/dev/ttyNOPE0: cannot open"), "{err}");
    assert_eq!(err.trim_end().lines().count(), 1);
}
