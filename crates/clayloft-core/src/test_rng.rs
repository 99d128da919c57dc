//! Numbers for the tests that draw many random cases inline (xorshift64, fixed seed): the
//! same cases every run, nothing to keep.

/// Uniform numbers in 0 … 1 from `seed` (not zero).
pub fn uniform(seed: u64) -> impl FnMut() -> f64 {
    let mut state = seed;
    move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    }
}
