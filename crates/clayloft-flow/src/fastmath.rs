//! `ln` and `exp` in single precision, written as straight-line arithmetic on the bits of an
//! `f32` so that a loop over nodes that calls them is vectorised by the compiler (16 nodes per
//! AVX-512 instruction). The `std` versions are calls into libm, which stop vectorisation and
//! cost about as much as the rest of a node's collision together.
//!
//! Single precision is enough for the viscosity law: the shear rate it is applied to comes from
//! the non-equilibrium part of single-precision populations (see [`crate::lattice::Stored`]) and
//! carries a larger relative error than these functions add (a few 10⁻⁷ relative):
//!
//! - `exp(x) = 2ᵏ·eʳ` with `k = round(x/ln 2)`, `r = x − k·ln 2` (Cody–Waite: ln 2 split in a
//!   high and a low part), `|r| ≤ ln2/2`, and `eʳ` by its Taylor series to degree 7; x is clamped
//!   to `[−87, 87]`, where 2ᵏ stays a normal number;
//! - `ln(x) = e·ln 2 + 2·atanh(s)` with `x = 2ᵉ·m`, `m ∈ [√½, √2)`, `s = (m − 1)/(m + 1)`,
//!   `|s| ≤ 0.172`, and `atanh(s) = s + s³/3 + s⁵/5 + …` to degree 9, for positive normal x;
//! - `1 − e^(−x)` by its own series at small x, where the subtraction would cancel.
//!
//! Polynomials are evaluated by Estrin's scheme and without fused multiply–adds, so the result is
//! the same bit for bit whatever the vector width.

/// 1.5·2²³: adding it to a number below 2²² in magnitude rounds it to an integer, which then
/// sits in the low mantissa bits.
const ROUNDER: f32 = 12_582_912.0;
/// ln 2 = LN2_HI + LN2_LO (Cephes), the high part 355/512, short enough that k·LN2_HI is exact.
const LN2_HI: f32 = 0.693_359_4;
const LN2_LO: f32 = -2.121_944_4e-4;
const LN2: f32 = std::f32::consts::LN_2;
const MANTISSA: u32 = (1 << 23) - 1;
const ONE_BITS: u32 = 0x3f80_0000;
/// 2²³, whose mantissa bits are all zero: OR-ing a small integer into them and subtracting 2²³
/// converts that integer to `f32` without an int→float instruction.
const TWO23: f32 = 8_388_608.0;

/// 1/k! for k = 0 … 7.
const EXP_TAYLOR: [f32; 8] = [
    1.0,
    1.0,
    1.0 / 2.0,
    1.0 / 6.0,
    1.0 / 24.0,
    1.0 / 120.0,
    1.0 / 720.0,
    1.0 / 5040.0,
];
/// 1/(2j + 1) for j = 0 … 4.
const ATANH_SERIES: [f32; 5] = [1.0, 1.0 / 3.0, 1.0 / 5.0, 1.0 / 7.0, 1.0 / 9.0];

/// `Σ c[k]·xᵏ` by Estrin's scheme: pairs `c[2i] + c[2i+1]·x`, then pairs of those with x², then
/// with x⁴: a dependency chain of about log₂(degree) multiply–adds instead of one per degree
/// (Horner), so the processor overlaps the nodes of a vectorised loop better.
#[inline(always)]
fn estrin<const N: usize>(c: &[f32; N], x: f32) -> f32 {
    let mut terms = [0.0f32; 8];
    let mut len = N.div_ceil(2);
    for i in 0..len {
        let hi = if 2 * i + 1 < N { c[2 * i + 1] } else { 0.0 };
        terms[i] = c[2 * i] + hi * x;
    }
    let mut power = x * x;
    while len > 1 {
        let half = len.div_ceil(2);
        for i in 0..half {
            let hi = if 2 * i + 1 < len {
                terms[2 * i + 1]
            } else {
                0.0
            };
            terms[i] = terms[2 * i] + hi * power;
        }
        len = half;
        power = power * power;
    }
    terms[0]
}

/// eˣ, x clamped to `[−87, 87]`.
#[inline(always)]
pub fn exp(x: f32) -> f32 {
    let x = clamp(x, -87.0, 87.0);
    let shifted = x * std::f32::consts::LOG2_E + ROUNDER;
    let k = shifted - ROUNDER;
    let r = (x - k * LN2_HI) - k * LN2_LO;
    let p = estrin(&EXP_TAYLOR, r);
    let k_int = shifted.to_bits().wrapping_sub(ROUNDER.to_bits());
    let scale = f32::from_bits(k_int.wrapping_add(127) << 23);
    p * scale
}

/// 1/(k+1)! with alternating signs for k = 0 … 6: `(1 − e^(−x))/x = Σ (−x)ᵏ/(k+1)!`.
const ONE_MINUS_EXP_SERIES: [f32; 7] = [
    1.0,
    -1.0 / 2.0,
    1.0 / 6.0,
    -1.0 / 24.0,
    1.0 / 120.0,
    -1.0 / 720.0,
    1.0 / 5040.0,
];

/// `1 − e^(−x)` for x ≥ 0 without the cancellation of the subtraction at small x: below 0.35 by
/// its series (remainder below 6·10⁻⁹ relative), above by `1 − exp(−x)` (then at least 0.29).
#[inline(always)]
pub fn one_minus_exp_neg(x: f32) -> f32 {
    let series = x * estrin(&ONE_MINUS_EXP_SERIES, x);
    let direct = 1.0 - exp(-x);
    if x < 0.35 { series } else { direct }
}

/// Natural logarithm of a positive normal number.
#[inline(always)]
pub fn ln(x: f32) -> f32 {
    let bits = x.to_bits();
    let mut m = f32::from_bits((bits & MANTISSA) | ONE_BITS);
    // Biased exponent as f32, then unbiased.
    let mut e = f32::from_bits((bits >> 23) | TWO23.to_bits()) - (TWO23 + 127.0);
    let big = m > std::f32::consts::SQRT_2;
    m = if big { m * 0.5 } else { m };
    e = if big { e + 1.0 } else { e };
    let s = (m - 1.0) / (m + 1.0);
    let p = estrin(&ATANH_SERIES, s * s);
    e * LN2 + 2.0 * s * p
}

/// `x` limited to `[lo, hi]` by two compare-and-selects, which vectorise (`f32::clamp` checks its
/// bounds and `f32::max`/`min` are libm-style calls that stop the loop vectoriser).
#[inline(always)]
pub fn clamp(x: f32, lo: f32, hi: f32) -> f32 {
    let x = if x < lo { lo } else { x };
    if x > hi { hi } else { x }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rel(a: f32, b: f64) -> f64 {
        ((a as f64 - b) / b).abs()
    }

    #[test]
    fn exp_matches_std() {
        let mut worst: f64 = 0.0;
        let mut x: f32 = -87.0;
        while x <= 87.0 {
            worst = worst.max(rel(exp(x), (x as f64).exp()));
            x += 0.00137;
        }
        assert!(worst < 2e-7, "worst relative error {worst:e}");
        assert_eq!(exp(0.0), 1.0);
        assert_eq!(exp(-1e6), exp(-87.0));
        assert!(exp(-87.0) > 0.0 && exp(87.0).is_finite());
    }

    #[test]
    fn one_minus_exp_neg_keeps_its_digits_near_zero() {
        let mut worst: f64 = 0.0;
        let mut x: f32 = 1e-12;
        while x < 100.0 {
            let want = -(-(x as f64)).exp_m1();
            worst = worst.max(rel(one_minus_exp_neg(x), want));
            x *= 1.0013;
        }
        assert!(worst < 3e-7, "worst relative error {worst:e}");
    }

    #[test]
    fn ln_matches_std() {
        let mut worst: f64 = 0.0;
        let mut x: f32 = 1e-30;
        while x < 1e30 {
            let want = (x as f64).ln();
            let err = if want.abs() > 1e-2 {
                rel(ln(x), want)
            } else {
                (ln(x) as f64 - want).abs()
            };
            worst = worst.max(err);
            x *= 1.000_173;
        }
        assert!(worst < 4e-7, "worst error {worst:e}");
        assert_eq!(ln(1.0), 0.0);
        assert!((ln(std::f32::consts::E) - 1.0).abs() < 2e-7);
    }
}
