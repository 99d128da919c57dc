//! The heap's settings for a batch command (`clayloft gcode`, `stl`, `check`).
//!
//! Such a command allocates and frees buffers of megabytes one after another: sections,
//! surfaces, the toolpath, the program's text, the self-check's moves, chords and boxes. glibc
//! gives a freed buffer of more than its mmap threshold back to the system (128 kB at first,
//! rising with the buffers freed up to 32 MB), and trims the heap's top when more than 128 kB
//! is free, so the next buffer is mapped afresh: every page faulted in and zeroed again, about a
//! microsecond a page here. [`tune_for_batch_command`] keeps freed memory in the heap for the
//! next buffer instead. On the 720 × 300 benchmark vase that took `clayloft gcode` from 11 500
//! page faults to 9 400 and its processor time by about a tenth (`perf stat -r 20`, 2026-12-05).
//!
//! It also puts every thread's buffers in one heap grown in huge pages:
//! * glibc gives each new thread a heap of its own (an arena), so the memory one core frees is
//!   not reused by the other, and the helper's buffers fault their pages in afresh; with one
//!   arena (`M_ARENA_MAX`) both cores reuse it;
//! * the heap is grown by 96 MB at once (`M_TOP_PAD`) and marked for transparent huge
//!   pages (`madvise(MADV_HUGEPAGE)`), so a first touch maps 2 MB, not 4 kB: the benchmark
//!   vase's `clayloft gcode` takes about 1 000 page faults instead of 10 000, and its median
//!   whole process went 136.5 → 126.7 ms, its processor time 260 → 242 ms
//!   (`scripts/whole-process.py`, 40 rounds, 2026-12-06). What glibc's own
//!   `GLIBC_TUNABLES=glibc.malloc.hugetlb=1:glibc.malloc.arena_max=1` does, without having to
//!   be set before the process starts. Where the kernel has huge pages off, the mark does
//!   nothing; where memory is fragmented, a first touch may wait for the kernel to compact it
//!   (its default `defrag` setting for marked memory), as with glibc's setting.
//!
//! Once the design is known, [`fault_ahead_for`] has the idle helper fault in the part of that
//! room the job will fill, so that the kernel's zeroing of fresh pages (about a tenth of a
//! millisecond a huge page) is done beside the work, not by the thread that first writes them.
//!
//! The memory is returned when the process ends, a fraction of a second later.

/// Largest buffer, bytes, that the heap serves from memory freed before (glibc's maximum for
/// the mmap threshold on 64-bit systems, `DEFAULT_MMAP_THRESHOLD_MAX`): the benchmark vase's
/// largest buffer, its 8 MB program text, is well within it. Larger ones are mapped as before.
const REUSE_UP_TO: i32 = 32 << 20;

/// How much the heap grows by at once, bytes: more than the benchmark vase's `clayloft gcode`
/// holds at its peak (68 MB resident), so that the heap is marked for huge pages once.
const HEAP_ROOM: usize = 96 << 20;

/// Sets the heap up for a batch command (see the module documentation): freed memory kept for
/// the next buffer, one heap for every thread, grown in huge pages. Call it once at the start
/// of a batch command, before other threads allocate; not for the interactive app, which runs
/// for hours and should give memory back. Gives the heap's stretch marked for huge pages
/// (none where the mark was refused).
#[cfg(all(target_os = "linux", target_env = "gnu"))]
pub fn tune_for_batch_command() -> Option<std::ops::Range<usize>> {
    // SAFETY: mallopt only sets the allocator's parameters; a value it refuses leaves them.
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, REUSE_UP_TO);
        libc::mallopt(libc::M_TRIM_THRESHOLD, i32::MAX);
        libc::mallopt(libc::M_ARENA_MAX, 1);
        libc::mallopt(libc::M_TOP_PAD, HEAP_ROOM as i32);
    }
    // A block larger than what is free at the heap's top grows it by HEAP_ROOM more: the new
    // room runs from the block to the break.
    let probe: Vec<u8> = Vec::with_capacity(1 << 20);
    let from = (probe.as_ptr() as usize).next_multiple_of(HUGE_PAGE);
    drop(std::hint::black_box(probe));
    // SAFETY: sbrk(0) only reads the break.
    let end = unsafe { libc::sbrk(0) } as usize;
    // Not grown (the room was there already), or the block is not in the heap that sbrk grows
    // (a thread given a heap of its own before this was called): nothing is marked.
    if from >= end || end - from > HEAP_ROOM + (4 << 20) {
        return None;
    }
    // SAFETY: the range lies within the heap (from the block it just held to the break), and
    // MADV_HUGEPAGE changes how its pages are backed, not their contents.
    let marked =
        unsafe { libc::madvise(from as *mut libc::c_void, end - from, libc::MADV_HUGEPAGE) } == 0;
    let room = marked.then_some(from..end);
    if let Some(room) = &room {
        let _ = ROOM.set(room.clone());
        // The helpers fault in the first of it while this thread reads the design, before
        // [`fault_ahead_for`] knows how much the job fills (and starts again from the room's
        // start: pages already in place cost a few microseconds).
        crate::parallel::fault_in_while_idle(
            room.start..room.start + FIRST_FAULTED.min(room.len()),
        );
    }
    room
}

/// What the helpers fault in of the room before the design is read ([`tune_for_batch_command`]):
/// two huge pages, about what they fault in while the benchmark vase's design is read (0.35
/// ms; its whole process 40.9 → 40.6 ms, medians of 750 alternating rounds). A smaller job
/// leaves some of it unused: 4 MB mapped, faulted in while the helper had nothing else to do.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
const FIRST_FAULTED: usize = 2 * HUGE_PAGE;

/// The heap's room marked by [`tune_for_batch_command`].
#[cfg(all(target_os = "linux", target_env = "gnu"))]
static ROOM: std::sync::OnceLock<std::ops::Range<usize>> = std::sync::OnceLock::new();

/// Heap a batch command fills per path point, bytes: the benchmark vase's `clayloft gcode`
/// fills 36.9 MB of the room for its 216 000 points (the heap's resident size with nothing
/// faulted in ahead, since the self-check lets the moves go), 172 bytes a point, rounded up
/// to whole huge pages. Faulting in 190 a point (as before) zeroed two huge pages no stage
/// used: 40.5 → 40.1 ms median with 172; with 150 the rest faulted on the stage's own thread,
/// 40.5 ms again (alternating, 600 rounds, 2026-12-07).
#[cfg(all(target_os = "linux", target_env = "gnu"))]
const BYTES_PER_POINT: usize = 172;

/// Has the idle helper fault in, ahead of use, the part of the heap's room that a job of
/// `design` fills ([`crate::parallel::fault_in_while_idle`]): the kernel's zeroing of those
/// pages moves off the thread that first writes them (on the benchmark vase, median 67.1 →
/// 62.1 ms, processor time 126.9 → 118.3 ms, alternating, 40 rounds, 2026-12-06). Nothing
/// before [`tune_for_batch_command`], or where it marked no room.
pub fn fault_ahead_for(design: &crate::design::Design) {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    if let Some(room) = ROOM.get() {
        let layers = (design.shape.height / design.printer.layer_height).ceil() as usize;
        let points = design
            .shape
            .samples
            .saturating_mul(layers.saturating_add(design.shape.base_layers))
            .saturating_mul(design.shape.walls.max(1));
        let bytes = points.saturating_mul(BYTES_PER_POINT).min(room.len());
        crate::parallel::fault_in_while_idle(room.start..room.start + bytes);
    }
    #[cfg(not(all(target_os = "linux", target_env = "gnu")))]
    let _ = design;
}

/// A huge page of x86-64 and of most 64-bit Arm kernels, bytes: where a marked stretch starts.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
const HUGE_PAGE: usize = 2 << 20;

/// Elsewhere the allocator's own behaviour stays.
#[cfg(not(all(target_os = "linux", target_env = "gnu")))]
pub fn tune_for_batch_command() -> Option<std::ops::Range<usize>> {
    None
}

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

    /// Faults taken to fill a 20 MB buffer (5 120 pages) and free it, and where it was.
    fn fill_and_free() -> (i64, usize) {
        let before = faults();
        let v = vec![1u8; 20 << 20];
        std::hint::black_box(&v);
        let at = v.as_ptr() as usize;
        drop(v);
        (faults() - before, at)
    }

    /// The second 20 MB buffer reuses the first one's memory, and so faults a few times, not
    /// 5 120. (By default glibc maps the first afresh and gives it back, raising its threshold;
    /// the second then grows the heap, faulting every page again.) Tried three times: with one
    /// heap for every thread, another test's thread may take the freed buffer in between.
    #[test]
    fn a_freed_buffer_is_reused_without_faulting_its_pages_again() {
        std::thread::spawn(|| {
            tune_for_batch_command();
            let tries: Vec<_> = (0..3)
                .map(|_| {
                    let (_, first) = fill_and_free();
                    let (again, second) = fill_and_free();
                    (first == second, again)
                })
                .collect();
            assert!(
                tries.iter().any(|&(reused, again)| reused && again < 64),
                "(reused, faults) {tries:?}"
            );
        })
        .join()
        .unwrap();
    }
}
