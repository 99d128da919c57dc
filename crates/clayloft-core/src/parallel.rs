//! The two helpers every stage that uses both cores shares (scoped threads from `std`; the
//! work is split by each stage, where the split is part of its math).

/// Threads worth starting for independent work: the machine's cores (1 if unknown).
pub fn cores() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// Waits for a scoped thread; a panic in it goes on in the caller (as if it ran there).
pub fn join<T>(handle: std::thread::ScopedJoinHandle<'_, T>) -> T {
    handle
        .join()
        .unwrap_or_else(|e| std::panic::resume_unwind(e))
}
