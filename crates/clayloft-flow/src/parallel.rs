//! Running a stretch of time steps on several cores: the lattice is cut into horizontal bands of
//! rows, one per thread; the threads live for the whole stretch (a thread start costs about as
//! much as a step of a 120 × 120 lattice) and meet at a spinning barrier after every step, since
//! a step reads rows of its neighbours' bands from the previous step.

use std::sync::atomic::{AtomicUsize, Ordering};

/// The first row of each of `bands` bands of `ny` rows, then `ny`: as even as possible, and
/// never more bands than rows.
pub fn band_starts(ny: usize, bands: usize) -> Vec<usize> {
    let bands = bands.clamp(1, ny.max(1));
    (0..=bands).map(|k| ny * k / bands).collect()
}

/// A barrier for a fixed number of threads that spins (then yields) instead of sleeping: the
/// wait between two steps is a few microseconds, shorter than a sleep and wake-up.
pub struct SpinBarrier {
    threads: usize,
    arrived: AtomicUsize,
    generation: AtomicUsize,
}

impl SpinBarrier {
    pub fn new(threads: usize) -> SpinBarrier {
        SpinBarrier {
            threads,
            arrived: AtomicUsize::new(0),
            generation: AtomicUsize::new(0),
        }
    }

    /// Returns once all `threads` threads have called `wait` for this generation; everything a
    /// thread wrote before its call is visible to every thread after.
    pub fn wait(&self) {
        let generation = self.generation.load(Ordering::Acquire);
        if self.arrived.fetch_add(1, Ordering::AcqRel) + 1 == self.threads {
            // The last to arrive resets the count before it releases the others.
            self.arrived.store(0, Ordering::Relaxed);
            self.generation.fetch_add(1, Ordering::Release);
            return;
        }
        let mut spins = 0u32;
        while self.generation.load(Ordering::Acquire) == generation {
            if spins < 20_000 {
                std::hint::spin_loop();
                spins += 1;
            } else {
                std::thread::yield_now();
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bands_cover_every_row_once() {
        assert_eq!(band_starts(120, 2), vec![0, 60, 120]);
        assert_eq!(band_starts(7, 3), vec![0, 2, 4, 7]);
        assert_eq!(band_starts(2, 5), vec![0, 1, 2]);
        assert_eq!(band_starts(10, 0), vec![0, 10]);
    }

    #[test]
    fn barrier_orders_the_rounds() {
        // Each thread adds its round number; after each barrier every thread must see all
        // additions of that round.
        let total = AtomicUsize::new(0);
        let barrier = SpinBarrier::new(3);
        std::thread::scope(|s| {
            for _ in 0..3 {
                s.spawn(|| {
                    for round in 1..=200 {
                        total.fetch_add(round, Ordering::Relaxed);
                        barrier.wait();
                        let want = 3 * round * (round + 1) / 2;
                        assert_eq!(total.load(Ordering::Relaxed), want, "round {round}");
                        barrier.wait();
                    }
                });
            }
        });
    }
}
