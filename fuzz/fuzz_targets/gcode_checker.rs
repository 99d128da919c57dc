//! The G-code checker on any text: header limits and the whole check. Nothing may panic, and
//! the time per input stays bounded (libFuzzer's -timeout flags a slow input).
#![no_main]

use libfuzzer_sys::fuzz_target;

use clayloft_core::check::{Limits, check_gcode};

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let limits = match Limits::from_header(text) {
        Ok(Some((l, _))) => l,
        Ok(None) => Limits::from(&clayloft_core::design::Printer::default()),
        Err(_) => return,
    };
    if let Ok(report) = check_gcode(text, &limits) {
        let _ = report.to_string();
    }
});
