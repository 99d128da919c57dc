//! The helpers every stage that uses both cores shares. The work is split by each stage into
//! contiguous ranges, so results come back in order and do not depend on the number of cores or
//! on which thread ran which part.
//!
//! **Helper threads.** Parts run on the calling thread and on `cores − 1` helper threads that
//! live as long as the process. A thread started for each part cost about 50 µs here, and a
//! sleeping thread about as much to wake (a virtual machine's idle core is halted): more than
//! many parts take. So a helper that has finished a part keeps spinning for `LINGER` (200 µs) before it
//! sleeps, and inside [`awake`] (a session update, a whole command) it spins until the end: a
//! part handed over starts within a microsecond. A part is handed to a free helper or, when
//! none is free (a part started from a part, or two threads at once), run on the calling thread:
//! the cores are busy then anyway. A part the helper has not started by the time the calling
//! thread waits for it is taken back and run there (the helper may be faulting pages in).

use std::any::Any;
use std::ops::Range;
use std::panic::AssertUnwindSafe;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Mutex, OnceLock};
use std::time::{Duration, Instant};

/// Points (or moves, or chords) of a pass below which it stays on one core: handing part of it
/// to a helper costs more than it saves (a few microseconds to wake one, tens when the part's
/// data is cold). Each stage's own cut-off, where it has one, is this.
pub const PARALLEL_POINTS: usize = 20_000;

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

/// How long a helper keeps spinning after a part outside [`awake`] before it sleeps.
const LINGER: Duration = Duration::from_micros(200);

/// A part handed to a helper, its lifetime erased (see [`Helper::hand`]).
type Part = Box<dyn FnOnce() + Send + 'static>;

/// One helper thread and the part it is given.
struct Helper {
    /// Taken by the thread that hands it a part, until that part is done.
    claimed: AtomicBool,
    /// Set once a part waits in `part`, so that the spinning helper need not lock.
    posted: AtomicBool,
    part: Mutex<Option<Part>>,
    /// Set by the helper when the part has run.
    done: AtomicBool,
    /// The part's panic, to go on in the thread that handed it over.
    panic: Mutex<Option<Box<dyn Any + Send>>>,
    thread: OnceLock<std::thread::Thread>,
}

/// The helpers.
struct Pool {
    helpers: Vec<&'static Helper>,
}

/// How many [`awake`] scopes are open. Apart from the pool, which a helper started while the
/// pool is being made would wait for (asleep, its core then to be woken) before it spins and
/// faults the heap in: `clayloft gcode` of the benchmark vase 0.993 of the wall (alternating,
/// 674 rounds, 2026-12-07).
static AWAKE: AtomicUsize = AtomicUsize::new(0);

fn pool() -> &'static Pool {
    static POOL: OnceLock<Pool> = OnceLock::new();
    POOL.get_or_init(|| {
        let mut helpers = Vec::new();
        // A thread that ends at once, started first, wakes the idle cores (see [`wake_cores`]).
        if cores() > 1 {
            wake_cores();
        }
        for k in 1..cores() {
            let helper: &'static Helper = Box::leak(Box::new(Helper {
                claimed: AtomicBool::new(false),
                posted: AtomicBool::new(false),
                part: Mutex::new(None),
                done: AtomicBool::new(false),
                panic: Mutex::new(None),
                thread: OnceLock::new(),
            }));
            let started = std::thread::Builder::new()
                .name(format!("clayloft helper {k}"))
                .spawn(move || helper.serve());
            // Without a helper the parts run on the calling thread.
            if let Ok(handle) = started {
                let _ = helper.thread.set(handle.thread().clone());
                helpers.push(helper);
            }
        }
        Pool { helpers }
    })
}

/// The value in `slot`, taken out (a thread that panicked holding the lock left it whole).
fn take<T>(slot: &Mutex<Option<T>>) -> Option<T> {
    slot.lock().unwrap_or_else(|e| e.into_inner()).take()
}

/// Wakes the machine's idle cores for the helpers started next, with a thread that ends at
/// once. An idle core of a virtual machine is halted, and the first thread started on it ran a
/// millisecond or more late: the first stages of a command ran on one core, and in 7 runs of 40
/// of `clayloft gcode` the helper's first part even ran on the starting thread's core (those
/// runs 1.6× slower). Woken first, the core runs the helpers started a moment later at once:
/// the benchmark vase's sections 3.1 → 2.0 ms, `clayloft stl` of the petal vase 31.9 → 22.8 ms
/// (medians, alternating, 2026-12-07).
fn wake_cores() {
    let _ = std::thread::Builder::new()
        .name("clayloft waker".into())
        .spawn(|| {});
}

impl Helper {
    /// The helper thread: runs the parts handed to it; spins while an [`awake`] scope is open
    /// or for [`LINGER`] after a part, else sleeps until the next part.
    fn serve(&'static self) {
        let mut last = Instant::now();
        let mut spins = 0u32;
        loop {
            if self.posted.swap(false, Ordering::Acquire) {
                let part = take(&self.part);
                if let Some(part) = part
                    && let Err(panic) = std::panic::catch_unwind(AssertUnwindSafe(part))
                {
                    *self.panic.lock().unwrap_or_else(|e| e.into_inner()) = Some(panic);
                }
                self.done.store(true, Ordering::Release);
                last = Instant::now();
                continue;
            }
            spins = spins.wrapping_add(1);
            let awake = AWAKE.load(Ordering::Relaxed) > 0;
            if awake && spins.is_multiple_of(64) && IDLE_FAULT.step() {
                continue;
            }
            if awake || !spins.is_multiple_of(64) || last.elapsed() < LINGER {
                std::hint::spin_loop();
            } else {
                std::thread::park();
                last = Instant::now();
            }
        }
    }

    /// A free helper, claimed for one part; none when every helper is busy.
    fn claim() -> Option<&'static Helper> {
        pool().helpers.iter().copied().find(|h| {
            h.claimed
                .compare_exchange(false, true, Ordering::Acquire, Ordering::Relaxed)
                .is_ok()
        })
    }

    /// Hands `part` to this (claimed) helper. The part may borrow from the caller's stack: the
    /// returned [`Handed`] waits for it to finish when dropped, on unwinding too, so that nothing
    /// it borrows goes away while it runs (the guarantee `std::thread::scope` gives).
    fn hand<'a>(&'static self, part: Box<dyn FnOnce() + Send + 'a>) -> Handed {
        // SAFETY: the part only runs before `Handed::wait` returns, and `Handed` (which cannot
        // be leaked by the callers in this module) waits in its `Drop`, so the borrows of `'a`
        // outlive the part's run.
        let part: Part =
            unsafe { std::mem::transmute::<Box<dyn FnOnce() + Send + 'a>, Part>(part) };
        *self.part.lock().unwrap_or_else(|e| e.into_inner()) = Some(part);
        self.done.store(false, Ordering::Relaxed);
        self.posted.store(true, Ordering::Release);
        if let Some(thread) = self.thread.get() {
            thread.unpark();
        }
        Handed {
            helper: self,
            waited: false,
        }
    }
}

/// A part handed to a helper; waiting for it frees the helper and passes its panic on.
struct Handed {
    helper: &'static Helper,
    waited: bool,
}

impl Handed {
    /// Waits for the part and frees the helper, giving the part's panic. A part the helper has
    /// not started yet is taken back and run here when `run_here` (else dropped unrun: this
    /// thread is unwinding): the helper may be in the middle of something long (a huge page it
    /// faults in while idle, a millisecond or more when the host must find the memory), and this
    /// thread has nothing left to do but wait.
    fn finish(&mut self, run_here: bool) -> Option<Box<dyn Any + Send>> {
        if self.helper.posted.swap(false, Ordering::Acquire) {
            let part = take(&self.helper.part);
            // The helper is free again (for the part's own parallel work, say).
            self.free_helper();
            return part
                .filter(|_| run_here)
                .and_then(|part| std::panic::catch_unwind(AssertUnwindSafe(part)).err());
        }
        let started = Instant::now();
        let mut spins = 0u32;
        while !self.helper.done.load(Ordering::Acquire) {
            spins = spins.wrapping_add(1);
            // Spin while the part is short; then give the core to other threads.
            if spins.is_multiple_of(64) && started.elapsed() > Duration::from_micros(100) {
                std::thread::yield_now();
            } else {
                std::hint::spin_loop();
            }
        }
        let panic = take(&self.helper.panic);
        self.free_helper();
        panic
    }

    /// The part is done (or taken back): the helper may be claimed again.
    fn free_helper(&mut self) {
        self.waited = true;
        self.helper.claimed.store(false, Ordering::Release);
    }

    /// Waits for the part; its panic goes on here.
    fn wait(mut self) {
        if let Some(panic) = self.finish(true) {
            std::panic::resume_unwind(panic);
        }
    }
}

impl Drop for Handed {
    fn drop(&mut self) {
        if !self.waited {
            // Unwinding from the caller's own part: wait (a part not started is dropped unrun),
            // and let the caller's panic go on; or left unjoined: it runs, here if not started.
            let _ = self.finish(!std::thread::panicking());
        }
    }
}

/// Runs `f` with the helpers spinning throughout (a burst of parallel stages: a session update,
/// a whole command), so that handing a part over costs no wake-up. Scopes may nest and overlap.
pub fn awake<R>(f: impl FnOnce() -> R) -> R {
    struct Open;
    impl Drop for Open {
        fn drop(&mut self) {
            AWAKE.fetch_sub(1, Ordering::Relaxed);
        }
    }
    // Open before the pool is made (the first scope makes it), so that its helpers spin from
    // their start.
    AWAKE.fetch_add(1, Ordering::Relaxed);
    let _open = Open;
    let pool = pool();
    for h in &pool.helpers {
        if let Some(thread) = h.thread.get() {
            thread.unpark();
        }
    }
    f()
}

/// Runs every part, the last on this thread and the others on free helpers (or on this thread,
/// in order, when none is free); the results in the parts' order.
pub fn run_parts<R: Send, F: FnOnce() -> R + Send>(parts: Vec<F>) -> Vec<R> {
    let mut results: Vec<Option<R>> = parts.iter().map(|_| None).collect();
    let mut here = Vec::new();
    let mut handed = Vec::new();
    let count = parts.len();
    for ((k, part), slot) in parts.into_iter().enumerate().zip(results.iter_mut()) {
        let helper = if k + 1 < count { Helper::claim() } else { None };
        match helper {
            Some(h) => handed.push(h.hand(Box::new(move || *slot = Some(part())))),
            None => here.push((part, slot)),
        }
    }
    for (part, slot) in here {
        *slot = Some(part());
    }
    handed.into_iter().for_each(Handed::wait);
    results
        .into_iter()
        .map(|r| r.expect("every part ran"))
        .collect()
}

/// Runs every part, shared out as the cores get free ([`map_shared`]: parts of uneven cost,
/// more of them than cores); the results in the parts' order.
pub fn run_shared<R: Send, F: FnOnce() -> R + Send>(parts: Vec<F>) -> Vec<R> {
    let parts: Vec<Mutex<Option<F>>> = parts.into_iter().map(|f| Mutex::new(Some(f))).collect();
    map_shared(
        parts.len(),
        || (),
        |(), k| {
            let part = take(&parts[k]);
            part.expect("each part taken once")()
        },
    )
}

/// Work started on a free helper while this thread goes on ([`beside`]); [`Beside::join`]
/// gives its result.
pub struct Beside<T> {
    state: BesideState<T>,
}

enum BesideState<T> {
    /// Running on a helper; the result lands in the slot.
    Handed(Handed, std::sync::Arc<Mutex<Option<T>>>),
    /// No helper was free: it runs on joining.
    Later(Box<dyn FnOnce() -> T + Send>),
}

/// Starts `f` on a free helper and returns at once (the work owns what it uses, so that it can
/// outlive the caller's frame); without a free helper, `f` runs when joined. For work that
/// the next stages do not wait for (the view's mesh beside the base fill and the toolpath).
pub fn beside<T: Send + 'static>(f: impl FnOnce() -> T + Send + 'static) -> Beside<T> {
    match Helper::claim() {
        Some(h) => h.beside(f),
        None => Beside {
            state: BesideState::Later(Box::new(f)),
        },
    }
}

/// Has a free helper fault in the pages of `v`'s unused capacity (a fresh buffer this thread
/// is about to fill) while this thread goes on, so that its writes find them mapped: a page's
/// first write costs about a microsecond here (the fault, the page zeroed), 3 ms for the
/// benchmark vase's 10 MB toolpath. Only a hint: nothing is done where no helper is free, or
/// where the system has no such call. The buffer is not touched (`MADV_POPULATE_WRITE` maps
/// pages without writing), so it may be written, grown or freed meanwhile; joining waits for
/// the helper.
pub fn fault_in_spare<T>(v: &Vec<T>) -> Beside<()> {
    let size = std::mem::size_of::<T>();
    let start = v.as_ptr() as usize + v.len() * size;
    let end = v.as_ptr() as usize + v.capacity() * size;
    match Helper::claim() {
        Some(h) if end > start => h.beside(move || populate(start..end)),
        // A claimed helper that is not needed is freed at once.
        Some(h) => {
            h.claimed.store(false, Ordering::Release);
            Beside::done()
        }
        None => Beside::done(),
    }
}

/// Memory that idle helpers fault in ahead of use ([`fault_in_while_idle`]): from `next` to
/// `end`, a step at a time.
struct IdleFault {
    next: AtomicUsize,
    end: AtomicUsize,
}

/// What one idle moment of a helper faults in: a huge page (2 MB on x86-64), about 100 µs of
/// zeroing here, so that a part handed over meanwhile waits no longer than that.
const IDLE_FAULT_STEP: usize = 2 << 20;

static IDLE_FAULT: IdleFault = IdleFault {
    next: AtomicUsize::new(0),
    end: AtomicUsize::new(0),
};

impl IdleFault {
    /// Faults in the next step, if any is left (up to the next multiple of the step, so that
    /// no page straddles two steps); whether it did.
    fn step(&self) -> bool {
        let end = self.end.load(Ordering::Relaxed);
        let mut at = self.next.load(Ordering::Relaxed);
        while at < end {
            let to = (at + 1).next_multiple_of(IDLE_FAULT_STEP).min(end);
            match self
                .next
                .compare_exchange_weak(at, to, Ordering::Relaxed, Ordering::Relaxed)
            {
                Ok(_) => {
                    populate(at..to);
                    return true;
                }
                Err(now) => at = now,
            }
        }
        false
    }
}

/// Has the helpers fault in the pages of `range` (heap that this process is about to fill)
/// whenever they wait for work inside [`awake`], a step at a time from its start, so that the
/// pages' first writes find them mapped and zeroed: on the calling thread a first write costs
/// the kernel's zeroing of the page (a few milliseconds for a batch command's heap), which an
/// idle core can do ahead of it. Only a hint, like [`fault_in_spare`]: the contents are never
/// touched, and memory freed or never used meanwhile is only mapped. Replaces any range given
/// before.
pub fn fault_in_while_idle(range: Range<usize>) {
    IDLE_FAULT.end.store(0, Ordering::Relaxed);
    IDLE_FAULT.next.store(range.start, Ordering::Relaxed);
    IDLE_FAULT.end.store(range.end, Ordering::Relaxed);
}

/// Maps the whole pages within the addresses `range` writable, as a write to each would,
/// without writing (Linux's `MADV_POPULATE_WRITE`, 5.14 and later): their contents stay as
/// they are. A failure (an older kernel, a range freed meanwhile) leaves the pages to fault
/// when written.
#[cfg(target_os = "linux")]
fn populate(range: Range<usize>) {
    static PAGE: OnceLock<usize> = OnceLock::new();
    // SAFETY: sysconf only reads a system constant.
    let page = *PAGE.get_or_init(|| {
        usize::try_from(unsafe { libc::sysconf(libc::_SC_PAGESIZE) })
            .unwrap_or(4096)
            .max(1)
    });
    let (start, end) = (range.start.next_multiple_of(page), range.end / page * page);
    if end > start {
        // SAFETY: the call reads and writes no memory of this process: it maps pages (or fails
        // on addresses not mapped writable), leaving their contents unchanged.
        unsafe {
            libc::madvise(
                start as *mut libc::c_void,
                end - start,
                libc::MADV_POPULATE_WRITE,
            );
        }
    }
}

#[cfg(not(target_os = "linux"))]
fn populate(_: Range<usize>) {}

impl Helper {
    /// Starts `f` on this (claimed) helper.
    fn beside<T: Send + 'static>(
        &'static self,
        f: impl FnOnce() -> T + Send + 'static,
    ) -> Beside<T> {
        let slot = std::sync::Arc::new(Mutex::new(None));
        let out = std::sync::Arc::clone(&slot);
        let handed = self.hand(Box::new(move || {
            *out.lock().unwrap_or_else(|e| e.into_inner()) = Some(f());
        }));
        Beside {
            state: BesideState::Handed(handed, slot),
        }
    }
}

impl Beside<()> {
    /// Work that is already done (nothing to wait for).
    fn done() -> Beside<()> {
        Beside {
            state: BesideState::Later(Box::new(|| ())),
        }
    }
}

impl<T> Beside<T> {
    /// Waits for the work (or does it now); its panic goes on here.
    pub fn join(self) -> T {
        match self.state {
            BesideState::Handed(handed, slot) => {
                handed.wait();
                let result = take(&slot);
                result.expect("the helper ran the work")
            }
            BesideState::Later(f) => f(),
        }
    }
}

/// Runs every part at the same time, the last on this thread and each other on a helper of its
/// own, for parts that wait on each other's progress (they would wait forever run one after
/// another); gives the parts back unrun when not enough helpers are free.
pub fn run_together<R: Send, F: FnOnce() -> R + Send>(parts: Vec<F>) -> Result<Vec<R>, Vec<F>> {
    let wanted = parts.len().saturating_sub(1);
    let mut helpers = Vec::with_capacity(wanted);
    while helpers.len() < wanted {
        match Helper::claim() {
            Some(h) => helpers.push(h),
            None => {
                for h in helpers {
                    h.claimed.store(false, Ordering::Release);
                }
                return Err(parts);
            }
        }
    }
    let mut results: Vec<Option<R>> = parts.iter().map(|_| None).collect();
    let (last_slot, slots) = results.split_last_mut().expect("one part or more");
    let mut parts = parts;
    let last = parts.pop().expect("one part or more");
    let handed: Vec<Handed> = parts
        .into_iter()
        .zip(slots.iter_mut())
        .zip(helpers)
        .map(|((part, slot), h)| h.hand(Box::new(move || *slot = Some(part()))))
        .collect();
    *last_slot = Some(last());
    handed.into_iter().for_each(Handed::wait);
    Ok(results
        .into_iter()
        .map(|r| r.expect("every part ran"))
        .collect())
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
    run_parts(parts.into_iter().map(|r| move || f(r)).collect())
        .into_iter()
        .flatten()
        .collect()
}

/// [`map_ranges`] with the items shared out in runs of `run` as the cores get free (see
/// [`map_shared`]), results concatenated in order: for work whose cost varies along the range
/// (the sections whose folds are cut off or faded, say), where halves fixed in advance leave
/// one core idle while the other finishes the harder half.
pub fn map_runs<R: Send>(
    len: usize,
    serial_below: usize,
    run: usize,
    f: impl Fn(Range<usize>) -> Vec<R> + Sync,
) -> Vec<R> {
    let runs = runs(len, serial_below, run);
    if runs.len() == 1 {
        return f(0..len);
    }
    map_shared(runs.len(), || (), |(), k| f(runs[k].clone()))
        .into_iter()
        .flatten()
        .collect()
}

/// `0..len` cut into runs of `run` items to be shared out as the cores get free (no longer than
/// a core's even share, so that a short range is still split), or left whole where
/// [`ranges`] leaves it whole (one core, or fewer than `serial_below` items).
pub fn runs(len: usize, serial_below: usize, run: usize) -> Vec<Range<usize>> {
    if ranges(len, serial_below).len() < 2 {
        return std::iter::once(0..len).collect();
    }
    let run = run.min(len.div_ceil(cores())).max(1);
    (0..len)
        .step_by(run)
        .map(|s| s..(s + run).min(len))
        .collect()
}

/// `a()` and `b()`, `a` on a helper when `beside` and one is free (else on this thread after
/// `b`: a part that waits on `b`'s results may be given as `a`).
pub fn both<A: Send, B>(
    beside: bool,
    a: impl FnOnce() -> A + Send,
    b: impl FnOnce() -> B,
) -> (A, B) {
    let mut out_a = None;
    let helper = if beside { Helper::claim() } else { None };
    let Some(helper) = helper else {
        let b = b();
        return (a(), b);
    };
    let handed = helper.hand(Box::new(|| out_a = Some(a())));
    let b = b();
    handed.wait();
    (out_a.expect("the helper ran a"), b)
}

/// [`both`] where a helper is free: `a` on it while `b` runs here (or here after `b`, where the
/// helper has not started it by then); `None`, with neither run, where none is (for work split
/// in a way that costs more than the whole on one core).
pub fn try_both<A: Send, B>(a: impl FnOnce() -> A + Send, b: impl FnOnce() -> B) -> Option<(A, B)> {
    let helper = Helper::claim()?;
    let mut out_a = None;
    let handed = helper.hand(Box::new(|| out_a = Some(a())));
    let b = b();
    handed.wait();
    Some((out_a.expect("the helper ran a"), b))
}

/// `f(&mut state, k)` for every task k in `0..count`, the results in the order of k. The tasks
/// are shared out as they go: this thread and every free helper take the next task not yet
/// taken whenever they finish one, each with a `state` of its own from `init` (scratch space
/// reused from task to task). For work whose cost varies along its range, where halves fixed in
/// advance leave one core idle while the other finishes the harder half. The tasks' results
/// must not depend on the state they find (nor on which thread ran them), so that the whole
/// is the same however the tasks fell.
pub fn map_shared<S, R: Send>(
    count: usize,
    init: impl Fn() -> S + Sync,
    f: impl Fn(&mut S, usize) -> R + Sync,
) -> Vec<R> {
    let next = AtomicUsize::new(0);
    let (next, init, f) = (&next, &init, &f);
    let worker = move || {
        let mut state = None;
        let mut done = Vec::new();
        loop {
            let k = next.fetch_add(1, Ordering::Relaxed);
            if k >= count {
                return done;
            }
            let state = state.get_or_insert_with(init);
            done.push((k, f(state, k)));
        }
    };
    let workers = if count > 1 { cores().min(count) } else { 1 };
    let mut results: Vec<Option<R>> = (0..count).map(|_| None).collect();
    for (k, r) in run_parts(vec![worker; workers]).into_iter().flatten() {
        results[k] = Some(r);
    }
    results
        .into_iter()
        .map(|r| r.expect("every task ran"))
        .collect()
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
    run_parts(
        items
            .chunks_mut(chunk)
            .enumerate()
            .map(|(j, part)| move || f(j * chunk, part))
            .collect(),
    );
}

/// `v.extend_from_slice(items)`, the copy in parts on every core where `items` has at least
/// `serial_below` of them (a copy of megabytes, which one core makes at the memory's pace).
pub fn extend_from_slice<T: Copy + Send + Sync>(v: &mut Vec<T>, items: &[T], serial_below: usize) {
    v.reserve(items.len());
    let room = &mut v.spare_capacity_mut()[..items.len()];
    for_each_part(room, serial_below, |offset, part| {
        part.write_copy_of_slice(&items[offset..offset + part.len()]);
    });
    // SAFETY: the parts cover the first `items.len()` places of the spare capacity, each
    // written above.
    unsafe { v.set_len(v.len() + items.len()) };
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Parts, runs shared out and parts of a slice cover the range in order, each item once.
    #[test]
    fn parts_cover_the_range_in_order() {
        for len in [0, 1, 2, 7, 100, 1001] {
            for serial in [0, 10, 10_000] {
                let all: Vec<usize> = map_ranges(len, serial, |r| r.collect());
                assert_eq!(all, (0..len).collect::<Vec<_>>());
                for run in [0, 1, 3, 8, 5000] {
                    let all: Vec<usize> = awake(|| map_runs(len, serial, run, |r| r.collect()));
                    assert_eq!(all, (0..len).collect::<Vec<_>>(), "{len} {serial} {run}");
                    let cut: Vec<usize> = runs(len, serial, run).into_iter().flatten().collect();
                    assert_eq!(cut, (0..len).collect::<Vec<_>>(), "{len} {serial} {run}");
                }
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

    /// A slice appended in parts is the slice appended, whatever its length.
    #[test]
    fn a_slice_appended_in_parts_is_appended_whole() {
        for len in [0, 1, 2, 7, 1001, 50_000] {
            let items: Vec<u64> = (0..len as u64).map(|k| k * 7 + 3).collect();
            let mut v = vec![1u64, 2];
            awake(|| extend_from_slice(&mut v, &items, 10));
            let mut whole = vec![1u64, 2];
            whole.extend_from_slice(&items);
            assert_eq!(v, whole);
        }
    }

    /// Shared tasks come back in their order whoever took them, each run once, with each
    /// thread's state reused from task to task; uneven tasks, tasks inside tasks, and none.
    #[test]
    fn shared_tasks_come_back_in_order_each_run_once() {
        let runs = AtomicUsize::new(0);
        let states = AtomicUsize::new(0);
        awake(|| {
            for count in [0, 1, 2, 3, 17, 200] {
                runs.store(0, Ordering::Relaxed);
                states.store(0, Ordering::Relaxed);
                let got = map_shared(
                    count,
                    || {
                        states.fetch_add(1, Ordering::Relaxed);
                        Vec::<usize>::new()
                    },
                    |scratch, k| {
                        runs.fetch_add(1, Ordering::Relaxed);
                        scratch.push(k);
                        // Early tasks cost far more than late ones.
                        let spin = if k < 2 { 200_000 } else { 100 };
                        let inner: u64 =
                            map_shared(3, || (), |(), j| (0..spin).sum::<u64>() + j as u64)
                                .into_iter()
                                .sum();
                        (k, inner)
                    },
                );
                let spin_sum = |spin: u64| 3 * (0..spin).sum::<u64>() + 3;
                let expected: Vec<(usize, u64)> = (0..count)
                    .map(|k| (k, spin_sum(if k < 2 { 200_000 } else { 100 })))
                    .collect();
                assert_eq!(got, expected);
                assert_eq!(runs.load(Ordering::Relaxed), count);
                assert!(states.load(Ordering::Relaxed) <= cores().min(count.max(1)));
            }
        });
    }

    /// Parts shared out come back in their order, each run once, however uneven.
    #[test]
    fn shared_parts_come_back_in_order_each_run_once() {
        let runs = AtomicUsize::new(0);
        for count in [0, 1, 2, 13] {
            runs.store(0, Ordering::Relaxed);
            let runs = &runs;
            let parts: Vec<_> = (0..count)
                .map(|k| {
                    move || {
                        runs.fetch_add(1, Ordering::Relaxed);
                        let spin = if k % 5 == 0 { 100_000 } else { 10 };
                        (k, (0..spin).sum::<u64>())
                    }
                })
                .collect();
            let got = awake(|| run_shared(parts));
            let expected: Vec<(usize, u64)> = (0..count)
                .map(|k| (k, (0..if k % 5 == 0 { 100_000 } else { 10 }).sum::<u64>()))
                .collect();
            assert_eq!(got, expected);
            assert_eq!(runs.load(Ordering::Relaxed), count);
        }
    }

    /// Parts handed to the helpers: results in order whoever runs them, parts started from
    /// parts (run where they are, the helpers being busy), two threads asking at once, inside
    /// and outside [`awake`].
    #[test]
    fn parts_give_the_same_results_from_any_thread() {
        let sum = |r: Range<usize>| -> Vec<u64> { vec![r.map(|i| i as u64 * i as u64).sum()] };
        let expected: u64 = (0..10_000u64).map(|i| i * i).sum();
        let total = |parts: Vec<u64>| parts.into_iter().sum::<u64>();
        assert_eq!(total(map_ranges(10_000, 0, sum)), expected);
        awake(|| {
            std::thread::scope(|s| {
                let other = s.spawn(|| total(map_ranges(10_000, 0, sum)));
                for _ in 0..50 {
                    let (a, b) = both(
                        true,
                        || total(map_ranges(10_000, 0, sum)),
                        || total(map_ranges(10_000, 0, sum)),
                    );
                    assert_eq!((a, b), (expected, expected));
                }
                assert_eq!(join(other), expected);
            })
        });
    }

    /// A panic in a part on a helper goes on in the caller, and the helper serves again.
    #[test]
    fn a_panic_in_a_helper_goes_on_in_the_caller() {
        for _ in 0..3 {
            let caught = std::panic::catch_unwind(|| {
                run_parts(vec![
                    Box::new(|| -> u32 { panic!("part 0") }) as Box<dyn FnOnce() -> u32 + Send>,
                    Box::new(|| 1),
                ])
            });
            assert!(caught.is_err());
        }
        assert_eq!(run_parts(vec![|| 1, || 2, || 3]), vec![1, 2, 3]);
    }

    /// A part that waits for what the calling thread's part makes (the base fill's middle
    /// rings): on a helper it runs beside it, else after it; it never waits forever.
    #[test]
    fn a_part_given_as_a_may_wait_for_b() {
        for beside in [false, true] {
            let (send, receive) = std::sync::mpsc::channel::<u32>();
            let (got, ()) = both(
                beside,
                move || {
                    let mut got = Vec::new();
                    loop {
                        match receive.try_recv() {
                            Ok(x) => got.push(x),
                            Err(std::sync::mpsc::TryRecvError::Empty) => std::hint::spin_loop(),
                            Err(std::sync::mpsc::TryRecvError::Disconnected) => return got,
                        }
                    }
                },
                move || (0..100).for_each(|x| send.send(x).unwrap()),
            );
            assert_eq!(got, (0..100).collect::<Vec<_>>());
        }
    }

    /// Two parts tried together run both, the first on a helper (or taken back by this thread),
    /// or neither (no helper free: other tests may hold it); seen both ways, the second from
    /// inside a part that holds every helper there is.
    #[test]
    fn parts_tried_together_run_both_or_not_at_all() {
        let try_once = || {
            let ran = AtomicUsize::new(0);
            let out = try_both(
                || {
                    ran.fetch_add(1, Ordering::Relaxed);
                    1
                },
                || {
                    ran.fetch_add(1, Ordering::Relaxed);
                    7
                },
            );
            match out {
                Some((a, b)) => {
                    assert_eq!((a, b, ran.load(Ordering::Relaxed)), (1, 7, 2));
                    true
                }
                None => {
                    assert_eq!(ran.load(Ordering::Relaxed), 0);
                    false
                }
            }
        };
        let started = Instant::now();
        while !awake(try_once) {
            assert!(
                started.elapsed() < Duration::from_secs(30),
                "never a helper free"
            );
        }
        let helpers = pool().helpers.len();
        let held: Vec<_> = (0..helpers).filter_map(|_| Helper::claim()).collect();
        if held.len() == helpers {
            assert!(!try_once(), "no helper was free");
        }
        held.iter()
            .for_each(|h| h.claimed.store(false, Ordering::Release));
    }

    /// A part handed to a helper that has not started it when the caller waits (here a helper
    /// with no thread: it never will) is taken back and run by the caller, its panic going on
    /// there; one dropped while the caller unwinds is dropped unrun; and the helper is free
    /// again either way.
    #[test]
    fn a_part_not_started_is_taken_back() {
        let idle: &'static Helper = Box::leak(Box::new(Helper {
            claimed: AtomicBool::new(true),
            posted: AtomicBool::new(false),
            part: Mutex::new(None),
            done: AtomicBool::new(false),
            panic: Mutex::new(None),
            thread: OnceLock::new(),
        }));
        let mut ran_on = None;
        idle.hand(Box::new(|| ran_on = Some(std::thread::current().id())))
            .wait();
        assert_eq!(ran_on, Some(std::thread::current().id()));
        assert!(!idle.claimed.load(Ordering::Acquire));
        idle.claimed.store(true, Ordering::Release);
        let failed = idle.hand(Box::new(|| panic!("taken back")));
        assert!(std::panic::catch_unwind(AssertUnwindSafe(|| failed.wait())).is_err());
        idle.claimed.store(true, Ordering::Release);
        let ran = AtomicBool::new(false);
        let unwound = std::panic::catch_unwind(AssertUnwindSafe(|| {
            let _handed = idle.hand(Box::new(|| ran.store(true, Ordering::Relaxed)));
            panic!("the caller's own part");
        }));
        assert!(unwound.is_err() && !ran.load(Ordering::Relaxed));
        assert!(!idle.claimed.load(Ordering::Acquire));
    }

    /// Work started beside the caller gives its result on joining, whether a helper took it
    /// or not, and its panic goes on in the joining thread.
    #[test]
    fn work_beside_gives_its_result_on_joining() {
        let data = std::sync::Arc::new((0..10_000u64).collect::<Vec<_>>());
        let d = std::sync::Arc::clone(&data);
        let sum = beside(move || d.iter().sum::<u64>());
        // Meanwhile the helper may be busy: parts started here run here.
        assert_eq!(run_parts(vec![|| 1, || 2]), vec![1, 2]);
        assert_eq!(sum.join(), 49_995_000);
        let failed = beside(|| -> u32 { panic!("beside") });
        assert!(std::panic::catch_unwind(AssertUnwindSafe(|| failed.join())).is_err());
        assert_eq!(beside(|| 7).join(), 7);
    }

    /// A block of fresh memory straight from the system (none of it in memory yet), whatever
    /// the heap holds (other tests' freed buffers, once a test tunes the heap).
    #[cfg(target_os = "linux")]
    struct Fresh {
        at: usize,
        bytes: usize,
    }

    #[cfg(target_os = "linux")]
    impl Fresh {
        fn new(bytes: usize) -> Fresh {
            // SAFETY: an anonymous private mapping, owned by the value and unmapped on drop.
            let at = unsafe {
                libc::mmap(
                    std::ptr::null_mut(),
                    bytes,
                    libc::PROT_READ | libc::PROT_WRITE,
                    libc::MAP_PRIVATE | libc::MAP_ANONYMOUS,
                    -1,
                    0,
                )
            };
            assert_ne!(at, libc::MAP_FAILED);
            Fresh {
                at: at as usize,
                bytes,
            }
        }

        /// Its first `n` words.
        fn words(&mut self, n: usize) -> &mut [u64] {
            assert!(n * 8 <= self.bytes);
            // SAFETY: the mapping is this value's, writable, page-aligned and `bytes` long.
            unsafe { std::slice::from_raw_parts_mut(self.at as *mut u64, n) }
        }

        /// Its pages in memory, as `mincore` sees them.
        fn resident(&self) -> usize {
            let mut flags = vec![0u8; self.bytes.div_ceil(4096)];
            // SAFETY: the range is this value's mapping; mincore only fills `flags`.
            let rc = unsafe {
                libc::mincore(self.at as *mut libc::c_void, self.bytes, flags.as_mut_ptr())
            };
            assert_eq!(rc, 0);
            flags.iter().filter(|&&f| f & 1 == 1).count()
        }
    }

    #[cfg(target_os = "linux")]
    impl Drop for Fresh {
        fn drop(&mut self) {
            // SAFETY: the mapping made in `new`, no longer borrowed.
            unsafe { libc::munmap(self.at as *mut libc::c_void, self.bytes) };
        }
    }

    /// Populating maps every whole page of a fresh block (as `mincore` sees it) and leaves the
    /// bytes written before it as they were; the buffer filled afterwards reads back.
    #[cfg(target_os = "linux")]
    #[test]
    fn populated_pages_are_mapped_and_keep_their_contents() {
        let pages = 4096;
        let mut block = Fresh::new(pages * 4096);
        for (w, k) in block.words(1000).iter_mut().zip(0..) {
            *w = k;
        }
        let before = block.resident();
        // From inside the first page to inside the last: the whole pages between are mapped.
        populate(block.at + 100..block.at + block.bytes - 100);
        let after = block.resident();
        assert!(before < pages / 2, "{before} pages in memory before");
        assert!(after >= pages - 2, "{after} pages in memory after");
        assert!(block.words(1000).iter().copied().eq(0..1000));
        // Faulted in beside (or not, when no helper is free): the buffer fills as ever.
        let mut w: Vec<u64> = Vec::with_capacity(1 << 20);
        w.push(7);
        let faulted = fault_in_spare(&w);
        w.extend(0..1000);
        faulted.join();
        w.extend(0..(1 << 19));
        assert_eq!((w[0], w[1000], w.len()), (7, 999, 1001 + (1 << 19)));
    }

    /// Memory given to [`fault_in_while_idle`] is mapped by a helper while this thread works
    /// inside [`awake`], and what it holds stays.
    #[cfg(target_os = "linux")]
    #[test]
    fn idle_helpers_fault_memory_in_ahead_of_use() {
        if cores() < 2 {
            return;
        }
        let pages = 2048;
        let mut block = Fresh::new(pages * 4096);
        for (w, k) in block.words(1000).iter_mut().zip(0..) {
            *w = k;
        }
        assert!(block.resident() < pages / 2);
        fault_in_while_idle(block.at..block.at + block.bytes);
        let started = Instant::now();
        let mapped = awake(|| {
            // This thread's own work meanwhile (the helpers wait for none).
            while block.resident() < pages && started.elapsed() < Duration::from_secs(5) {
                std::thread::sleep(Duration::from_millis(1));
            }
            block.resident()
        });
        fault_in_while_idle(0..0);
        assert_eq!(mapped, pages);
        assert!(block.words(1000).iter().copied().eq(0..1000));
    }
}
