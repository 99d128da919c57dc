//! The design loader on any text: parse, validate and locate errors, and for designs small
//! enough to run in a fuzzing time slice the whole pipeline to G-code. Nothing may panic.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(loaded) = clayloft_core::load::load_design_text(Path::new("fuzz.toml"), text.into())
    else {
        return;
    };
    let d = &loaded.design;
    // Small designs only: a valid 4-million-point vessel takes seconds, which is not a hang.
    let layers = d.shape.height / d.printer.min_layer_height;
    if d.shape.samples > 400 || layers > 400.0 || d.printer.line_width < 1.0 {
        return;
    }
    match clayloft_core::pipeline::run(d) {
        Ok(job) => {
            let mut out = Vec::new();
            clayloft_core::gcode::write_gcode(d, &job, &mut out).expect("writing to memory");
            let text = String::from_utf8(out).expect("G-code is text");
            let limits = clayloft_core::check::Limits::from(&d.printer);
            clayloft_core::check::check_gcode(&text, &limits).expect("our own G-code reads back");
        }
        Err(e) => {
            let _ = loaded.locate(e).to_string();
        }
    }
});
