//! The G-code checker on any text: header limits, the whole check and the self-check
//! (`verify_gcode`, which must agree with it, and `GcodeVerifier`, the self-check fed the text
//! in pieces as `clayloft gcode` writes it, which must agree with `verify_gcode`). Nothing may
//! panic, and the time per input stays bounded (libFuzzer's -timeout flags a slow input).
#![no_main]

use libfuzzer_sys::fuzz_target;

use clayloft_core::check::{GcodeVerifier, Limits, NOT_MEASURED, check_gcode, verify_gcode};

fuzz_target!(|data: &[u8]| {
    // Pieces of 1 to 256 bytes (the first byte's worth), cut anywhere: in a line, a number, a
    // CRLF, a multi-byte character.
    let piece = usize::from(data.first().copied().unwrap_or(0)) + 1;
    let mut pieces = GcodeVerifier::with_capacity(0);
    for bytes in data.chunks(piece) {
        std::io::Write::write_all(&mut pieces, bytes).expect("the verifier takes any bytes");
    }
    let Ok(text) = std::str::from_utf8(data) else {
        let _ = pieces.finish(&Limits::from(&clayloft_core::design::Printer::default()));
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
    let verified = verify_gcode(text, &limits);
    assert_eq!(pieces.finish(&limits), verified, "in pieces of {piece}");
    // The self-check agrees with the checker: it passes what the checker passes (or gave up
    // measuring), and otherwise gives the checker's report.
    match (verified, checked) {
        (Ok(None), Ok(report)) => assert!(
            report.violations.iter().all(|v| v.what == NOT_MEASURED),
            "verified, but {report}"
        ),
        (Ok(Some(verified)), Ok(report)) => assert_eq!(verified, report),
        (Err(a), Err(b)) => assert_eq!(a, b),
        (a, b) => panic!("verify {a:?} against check {b:?}"),
    }
});
