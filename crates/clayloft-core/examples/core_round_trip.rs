//! How long a cache line takes to go from one core to another and back, in nanoseconds: two
//! threads hand a counter to each other 100 000 times. On the development machine (a virtual
//! machine of two cores) it reads about 55 ns while the two cores share a cache and about
//! 350 ns while the host has placed them apart, which it does for seconds to minutes at a time;
//! `clayloft gcode` then takes a fifth to a half longer (a core writing into memory the other
//! just wrote or read waits for the line to cross). `scripts/whole-process.py --placement` runs
//! this between rounds and gives the two placements' figures apart.
//!
//!     cargo run --release -p clayloft-core --example core_round_trip

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

const ROUND_TRIPS: u64 = 100_000;

fn main() {
    let counter = Arc::new(AtomicU64::new(0));
    let other = Arc::clone(&counter);
    // The other thread answers each odd value with the next even one.
    let answer = std::thread::spawn(move || {
        for i in 0..ROUND_TRIPS {
            while other.load(Ordering::Acquire) != 2 * i + 1 {
                std::hint::spin_loop();
            }
            other.store(2 * i + 2, Ordering::Release);
        }
    });
    let start = std::time::Instant::now();
    for i in 0..ROUND_TRIPS {
        counter.store(2 * i + 1, Ordering::Release);
        while counter.load(Ordering::Acquire) != 2 * i + 2 {
            std::hint::spin_loop();
        }
    }
    let elapsed = start.elapsed();
    answer.join().expect("the answering thread ran");
    println!("{:.0}", elapsed.as_nanos() as f64 / ROUND_TRIPS as f64);
}
