//! The G-code checker on any text: header limits, the whole check and the self-check
//! (`verify_gcode`, which must agree with it). Nothing may panic, and the time per input stays
//! bounded (libFuzzer's -timeout flags a slow input).
#![no_main]

use libfuzzer_sys::fuzz_target;

use clayloft_core::check::{Limits, NOT_MEASURED, check_gcode, verify_gcode};

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let limits = match Limits::from_header(text) {
        Ok(Some((l, _))) => l,
        Ok(None) => Limits::from(&clayloft_core::design::Printer::default()),
        Err(_) => return,
    };
    let checked = check_gcode(text, &limits);
    if let Ok(report) = &checked {
        let _ = report.to_string();
    }
    // The self-check agrees with the checker: it passes what the checker passes (or gave up
    // measuring), and otherwise gives the checker's report.
    match (verify_gcode(text, &limits), checked) {
        (Ok(None), Ok(report)) => assert!(
            report.violations.iter().all(|v| v.what == NOT_MEASURED),
            "verified, but {report}"
        ),
        (Ok(Some(verified)), Ok(report)) => assert_eq!(verified, report),
        (Err(a), Err(b)) => assert_eq!(a, b),
        (a, b) => panic!("verify {a:?} against check {b:?}"),
    }
});
