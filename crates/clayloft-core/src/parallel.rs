//! The helpers every stage that uses both cores shares (scoped threads from `std`; the work is
//! split by each stage into contiguous ranges, so results come back in order and do not depend
//! on the number of cores).

use std::ops::Range;

/// Threads worth starting for independent work: the machine's cores (1 if unknown), asked once
/// (on Linux the answer reads the cgroup files, a few system calls each time).
pub fn cores() -> usize {
    static CORES: std::sync::OnceLock<usize> = std::sync::OnceLock::new();
    *CORES.get_or_init(|| std::thread::available_parallelism().map_or(1, |n| n.get()))
}

/// Waits for a scoped thread; a panic in it goes on in the caller (as if it ran there).
pub fn join<T>(handle: std::thread::ScopedJoinHandle<'_, T>) -> T {
    handle
        .join()
        .unwrap_or_else(|e| std::panic::resume_unwind(e))
}

/// `0..len` cut into one contiguous range per core, or a single range when `len` is below
/// `serial_below` (starting a thread costs more than small work).
pub fn ranges(len: usize, serial_below: usize) -> Vec<Range<usize>> {
    let threads = cores().min(len.max(1));
    if threads < 2 || len < serial_below {
        return std::iter::once(0..len).collect();
    }
    let chunk = len.div_ceil(threads);
    (0..len)
        .step_by(chunk)
        .map(|s| s..(s + chunk).min(len))
        .collect()
}

/// `f` on contiguous parts of `0..len`, one per core, results concatenated in order.
pub fn map_ranges<R: Send>(
    len: usize,
    serial_below: usize,
    f: impl Fn(Range<usize>) -> Vec<R> + Sync,
) -> Vec<R> {
    let parts = ranges(len, serial_below);
    if parts.len() == 1 {
        return f(0..len);
    }
    let f = &f;
    // The last part runs on the calling thread: one thread fewer to start.
    let (last, others) = parts.split_last().expect("two parts or more");
    std::thread::scope(|scope| {
        let handles: Vec<_> = others
            .iter()
            .map(|r| {
                let r = r.clone();
                scope.spawn(move || f(r))
            })
            .collect();
        let tail = f(last.clone());
        let mut out: Vec<R> = handles.into_iter().flat_map(join).collect();
        out.extend(tail);
        out
    })
}

/// `a()` and `b()`, `a` on a second thread when `beside` (else both on this one, `a` first).
pub fn both<A: Send, B>(
    beside: bool,
    a: impl FnOnce() -> A + Send,
    b: impl FnOnce() -> B,
) -> (A, B) {
    if !beside {
        let a = a();
        return (a, b());
    }
    std::thread::scope(|scope| {
        let handle = scope.spawn(a);
        let b = b();
        (join(handle), b)
    })
}

/// `f(offset, part)` on contiguous parts of `items`, one per core (`offset`: the index of the
/// part's first item).
pub fn for_each_part<T: Send>(
    items: &mut [T],
    serial_below: usize,
    f: impl Fn(usize, &mut [T]) + Sync,
) {
    let parts = ranges(items.len(), serial_below);
    if parts.len() == 1 {
        return f(0, items);
    }
    let f = &f;
    let chunk = parts[0].len();
    std::thread::scope(|scope| {
        let mut chunks: Vec<(usize, &mut [T])> = items
            .chunks_mut(chunk)
            .enumerate()
            .map(|(j, part)| (j * chunk, part))
            .collect();
        // The last part runs on the calling thread: one thread fewer to start.
        let (offset, last) = chunks.pop().expect("two parts or more");
        let handles: Vec<_> = chunks
            .into_iter()
            .map(|(offset, part)| scope.spawn(move || f(offset, part)))
            .collect();
        f(offset, last);
        handles.into_iter().for_each(join);
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parts_cover_the_range_in_order() {
        for len in [0, 1, 2, 7, 100, 1001] {
            for serial in [0, 10, 10_000] {
                let all: Vec<usize> = map_ranges(len, serial, |r| r.collect());
                assert_eq!(all, (0..len).collect::<Vec<_>>());
                let mut v = vec![0usize; len];
                for_each_part(&mut v, serial, |off, part| {
                    for (j, x) in part.iter_mut().enumerate() {
                        *x = off + j;
                    }
                });
                assert_eq!(v, (0..len).collect::<Vec<_>>());
            }
        }
    }
}
