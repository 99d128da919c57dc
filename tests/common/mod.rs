//! Helpers shared by the end-to-end tests (each test file uses some of them).
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output};
use std::time::{Duration, Instant};

/// Runs the `clayloft` binary in the repository root.
pub fn clayloft(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_clayloft"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("run clayloft")
}

pub fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

/// `clayloft gcode DESIGN [EXTRA…] -o OUT`: it prints, and `clayloft check OUT` (the limits of
/// the file's header) accepts the file. What the summary said; `label` names the case in a
/// failure.
pub fn gcode_and_check(design: &str, extra: &[&str], out: &Path, label: &str) -> String {
    let mut args = vec!["gcode", design];
    args.extend_from_slice(extra);
    args.extend_from_slice(&["-o", out.to_str().unwrap()]);
    let run = clayloft(&args);
    assert!(run.status.success(), "{label}: {}", text(&run.stderr));
    let check = clayloft(&["check", out.to_str().unwrap()]);
    assert_eq!(
        check.status.code(),
        Some(0),
        "{label}: {}",
        text(&check.stdout)
    );
    text(&run.stdout)
}

/// The `.toml` files of a repository folder, sorted.
pub fn toml_files(dir: &str) -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join(dir);
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    v.sort();
    v
}

/// Waits for a process at most `limit`; a hang is a test failure (with the process's stderr),
/// not a stuck CI.
pub fn wait_bounded(mut child: Child, limit: Duration) -> Output {
    let start = Instant::now();
    loop {
        if child.try_wait().unwrap().is_some() {
            return child.wait_with_output().unwrap();
        }
        if start.elapsed() > limit {
            let _ = child.kill();
            let out = child.wait_with_output().unwrap();
            panic!("no exit within {limit:?}: {}", text(&out.stderr));
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}
