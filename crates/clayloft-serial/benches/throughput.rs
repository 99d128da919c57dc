//! Lines per second streamed to the fake printer over a real pseudo-terminal, no delays, no
//! faults: the link's own overhead (ping-pong round trips through the kernel).

use clayloft_serial::fake::{FakePrinter, Faults};
use clayloft_serial::link::{run_job, serve_fake};
use clayloft_serial::{Sender, SenderConfig};
use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use serialport::{SerialPort, TTYPort};
use std::time::{Duration, Instant};

const LINES: usize = 5_000;

fn bench(c: &mut Criterion) {
    let cmds: Vec<String> = (0..LINES)
        .map(|i| format!("G1 X{}.{} Y{} E0.0{}", i % 150, i % 10, i % 170, i % 7))
        .collect();
    let mut g = c.benchmark_group("link");
    g.throughput(Throughput::Elements(LINES as u64));
    g.sample_size(10);
    g.bench_function("stream_5000_lines_to_fake_printer_over_pty", |b| {
        b.iter(|| {
            let (mut master, mut slave) = TTYPort::pair().unwrap();
            master.set_timeout(Duration::from_millis(5)).unwrap();
            slave.set_timeout(Duration::from_millis(5)).unwrap();
            let done = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
            let stop = done.clone();
            let fake = std::thread::spawn(move || {
                serve_fake(&mut master, FakePrinter::new(Faults::default()), |_| {
                    stop.load(std::sync::atomic::Ordering::Relaxed)
                })
            });
            let mut s = Sender::new(cmds.clone(), SenderConfig::default(), Instant::now()).unwrap();
            run_job(&mut slave as &mut dyn SerialPort, &mut s, |_| {}, |_| {});
            assert!(
                s.state() == &clayloft_serial::sender::State::Finished,
                "{:?}",
                s.state()
            );
            done.store(true, std::sync::atomic::Ordering::Relaxed);
            assert_eq!(fake.join().unwrap().log.len(), LINES);
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
