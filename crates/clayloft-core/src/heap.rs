//! The heap's settings for a batch command (`clayloft gcode`, `stl`, `check`).
//!
//! Such a command allocates and frees buffers of megabytes one after another: sections,
//! surfaces, the toolpath, the program's text, the self-check's moves, chords and boxes. glibc
//! gives a freed buffer of more than its mmap threshold back to the system (128 kB at first,
//! rising with the buffers freed up to 32 MB), and trims the heap's top when more than 128 kB
//! is free, so the next buffer is mapped afresh: every page faulted in and zeroed again, about a
//! microsecond a page here. [`keep_freed_memory`] keeps freed memory in the heap for the next
//! buffer instead. On the 720 × 300 benchmark vase it took `clayloft gcode` from 11 500 page
//! faults to 9 400 and its processor time by about a tenth (`perf stat -r 20`, 2026-12-05).
//! The memory is returned when the process ends, a fraction of a second later.

/// Largest buffer, bytes, that the heap serves from memory freed before (glibc's maximum for
/// the mmap threshold on 64-bit systems, `DEFAULT_MMAP_THRESHOLD_MAX`): the benchmark vase's
/// largest buffer, its 8 MB program text, is well within it. Larger ones are mapped as before.
const REUSE_UP_TO: i32 = 32 << 20;

/// Keeps freed memory in the heap for the rest of the process (see the module documentation),
/// for the calling thread and any started after. Call it once at the start of a batch command;
/// not for the interactive app, which runs for hours and should give memory back.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
pub fn keep_freed_memory() {
    // SAFETY: mallopt only sets the allocator's parameters; a value it refuses leaves them.
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, REUSE_UP_TO);
        libc::mallopt(libc::M_TRIM_THRESHOLD, i32::MAX);
    }
}

/// Elsewhere the allocator's own behaviour stays.
#[cfg(not(all(target_os = "linux", target_env = "gnu")))]
pub fn keep_freed_memory() {}

#[cfg(all(test, target_os = "linux", target_env = "gnu"))]
mod tests {
    use super::*;

    /// Page faults of the calling thread so far.
    fn faults() -> i64 {
        // SAFETY: getrusage writes the struct it is given.
        unsafe {
            let mut usage: libc::rusage = std::mem::zeroed();
            libc::getrusage(libc::RUSAGE_THREAD, &mut usage);
            usage.ru_minflt
        }
    }

    /// Faults taken to fill a 20 MB buffer (5 120 pages) and free it.
    fn fill_and_free() -> i64 {
        let before = faults();
        let v = vec![1u8; 20 << 20];
        std::hint::black_box(&v);
        drop(v);
        faults() - before
    }

    /// The second 20 MB buffer reuses the first one's pages: a few faults, not 5 120. (By
    /// default glibc maps the first afresh and gives it back, raising its threshold; the second
    /// then grows the heap, faulting every page again.)
    #[test]
    fn a_freed_buffer_is_reused_without_faulting_its_pages_again() {
        // On a thread of its own: its heap holds no other test's buffers.
        std::thread::spawn(|| {
            keep_freed_memory();
            fill_and_free();
            let again = fill_and_free();
            assert!(again < 64, "{again} faults for a reused buffer");
        })
        .join()
        .unwrap();
    }
}
