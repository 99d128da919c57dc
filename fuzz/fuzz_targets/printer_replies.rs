//! The printer reply parser and the sender on any byte stream from a "printer": lines split as
//! the link splits them, fed to a sender of a small job with the clock advancing. Nothing may
//! panic, and the sender's invariants hold: never more lines acknowledged than the job has,
//! every written line numbered and checksummed (or a bare probe / emergency stop).
#![no_main]

use std::time::{Duration, Instant};

use libfuzzer_sys::fuzz_target;

use clayloft_serial::link::LineBuffer;
use clayloft_serial::{Sender, SenderConfig};

fuzz_target!(|data: &[u8]| {
    let job: Vec<String> = (0..8).map(|i| format!("G1 X{i} Y{i} E0.1")).collect();
    let t0 = Instant::now();
    let Ok(mut sender) = Sender::new(job, SenderConfig::default(), t0) else {
        return;
    };
    let mut clock = t0;
    let mut lines = Vec::new();
    LineBuffer::default().push(data, |l| lines.push(l.to_string()));
    for (k, line) in lines.iter().enumerate() {
        let _ = clayloft_serial::reply::parse(line);
        sender.receive(line, clock);
        // Every third line, some time passes (up to a minute): probes, grace periods, timeouts.
        if k % 3 == 2 {
            let step = line.len() as u64 * 97 % 60_000;
            clock += Duration::from_millis(step);
            sender.tick(clock);
        }
        match k % 17 {
            5 => sender.pause(),
            6 => sender.resume(),
            _ => {}
        }
        for bytes in sender.outgoing() {
            let text = String::from_utf8(bytes).expect("the sender writes ASCII");
            assert!(text.ends_with('\n'));
            let body = text.trim_end();
            assert!(
                body == "M105" || body == "M112" || (body.starts_with('N') && body.contains('*')),
                "{body:?}"
            );
        }
        for _ in sender.events() {}
        assert!(sender.done() <= sender.total());
    }
});
