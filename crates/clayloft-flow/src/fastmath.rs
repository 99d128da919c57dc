//! `ln` and `exp` written as straight-line arithmetic on the bits of an `f64`, so that a loop over
//! cells that calls them is vectorised by the compiler (the `std` versions are calls into libm,
//! which stop vectorisation and cost about as much as the rest of a cell's collision together).
//!
//! Both are accurate to a few units in the last place over the range the rheology needs
//! (`ln` of positive normal numbers; `exp` of `[−700, 700]`, clamped outside):
//!
//! - `exp(x) = 2ᵏ·eʳ` with `k = round(x/ln 2)`, `r = x − k·ln 2` (Cody–Waite: ln 2 split in a
//!   high and a low part), `|r| ≤ ln2/2`, and `eʳ` by its Taylor series to degree 12;
//! - `ln(x) = e·ln 2 + 2·atanh(s)` with `x = 2ᵉ·m`, `m ∈ [√½, √2)`, `s = (m − 1)/(m + 1)`,
//!   `|s| ≤ 0.172`, and `atanh(s) = s + s³/3 + s⁵/5 + …` to degree 17.
//!
//! No fused multiply–adds: the result is the same bit for bit whatever the vector width.

/// 1.5·2⁵²: adding it to a number below 2⁵¹ in magnitude rounds it to an integer, which then
/// sits in the low mantissa bits.
const ROUNDER: f64 = 6_755_399_441_055_744.0;
/// ln 2 = LN2_HI + LN2_LO, the high part with its last 21 bits zero so that k·LN2_HI is exact.
const LN2_HI: f64 = f64::from_bits(0x3fe6_2e42_fee0_0000);
const LN2_LO: f64 = f64::from_bits(0x3dea_39ef_3579_3c76);
const LN2: f64 = std::f64::consts::LN_2;
const MANTISSA: u64 = (1 << 52) - 1;
const ONE_BITS: u64 = 0x3ff0_0000_0000_0000;
/// 2⁵², whose mantissa bits are all zero: OR-ing a small integer into them and subtracting 2⁵²
/// converts that integer to `f64` without an int→float instruction (AVX2 has none for i64).
const TWO52: f64 = 4_503_599_627_370_496.0;

/// 1/k! for k = 0 … 12.
const EXP_TAYLOR: [f64; 13] = {
    let mut c = [0.0; 13];
    let mut k = 0;
    let mut factorial = 1.0;
    while k < 13 {
        c[k] = 1.0 / factorial;
        k += 1;
        factorial *= k as f64;
    }
    c
};
/// 1/(2j + 1) for j = 0 … 8.
const ATANH_SERIES: [f64; 9] = {
    let mut c = [0.0; 9];
    let mut j = 0;
    while j < 9 {
        c[j] = 1.0 / (2 * j + 1) as f64;
        j += 1;
    }
    c
};

/// `Σ c[k]·xᵏ` by Estrin's scheme: pairs `c[2i] + c[2i+1]·x`, then pairs of those with x², then
/// with x⁴: a dependency chain of about log₂(degree) multiply–adds instead of one per degree
/// (Horner), so the processor overlaps the cells of a vectorised loop better.
#[inline(always)]
fn estrin<const N: usize>(c: &[f64; N], x: f64) -> f64 {
    let mut terms: [f64; 16] = [0.0; 16];
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

/// eˣ; clamped to `[−700, 700]` (far below and above any value the rheology uses).
#[inline(always)]
pub fn exp(x: f64) -> f64 {
    let x = clamp(x, -700.0, 700.0);
    let shifted = x * std::f64::consts::LOG2_E + ROUNDER;
    let k = shifted - ROUNDER;
    let r = (x - k * LN2_HI) - k * LN2_LO;
    // Taylor series of eʳ to r¹²/12! (remainder below 2·10⁻¹⁶ for |r| ≤ ln2/2).
    let p = estrin(&EXP_TAYLOR, r);
    let k_int = shifted.to_bits().wrapping_sub(ROUNDER.to_bits());
    let scale = f64::from_bits(k_int.wrapping_add(1023) << 52);
    p * scale
}

/// Natural logarithm of a positive normal number.
#[inline(always)]
pub fn ln(x: f64) -> f64 {
    let bits = x.to_bits();
    let mut m = f64::from_bits((bits & MANTISSA) | ONE_BITS);
    // Biased exponent as f64, then unbiased.
    let mut e = f64::from_bits((bits >> 52) | TWO52.to_bits()) - (TWO52 + 1023.0);
    let big = m > std::f64::consts::SQRT_2;
    m = if big { m * 0.5 } else { m };
    e = if big { e + 1.0 } else { e };
    let s = (m - 1.0) / (m + 1.0);
    // atanh(s)/s = Σ s²ʲ/(2j + 1), j = 0 … 8 (remainder below 3·10⁻¹⁶ for |s| ≤ 0.172).
    let p = estrin(&ATANH_SERIES, s * s);
    e * LN2 + 2.0 * s * p
}

/// `x` limited to `[lo, hi]` by two compare-and-selects, which vectorise (`f64::clamp` checks its
/// bounds and `f64::max`/`min` are libm-style calls that stop the loop vectoriser).
#[inline(always)]
pub fn clamp(x: f64, lo: f64, hi: f64) -> f64 {
    let x = if x < lo { lo } else { x };
    if x > hi { hi } else { x }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rel(a: f64, b: f64) -> f64 {
        ((a - b) / b).abs()
    }

    #[test]
    fn exp_matches_std() {
        let mut worst: f64 = 0.0;
        let mut x: f64 = -700.0;
        while x <= 700.0 {
            worst = worst.max(rel(exp(x), x.exp()));
            x += 0.0137;
        }
        assert!(worst < 4e-15, "worst relative error {worst:e}");
        assert_eq!(exp(0.0), 1.0);
        assert_eq!(exp(-1e6), (-700.0f64).exp().max(exp(-700.0)));
    }

    #[test]
    fn ln_matches_std() {
        let mut worst: f64 = 0.0;
        let mut x: f64 = 1e-12;
        while x < 1e12 {
            let want = x.ln();
            let err = if want.abs() > 1e-3 {
                rel(ln(x), want)
            } else {
                (ln(x) - want).abs()
            };
            worst = worst.max(err);
            x *= 1.000_731;
        }
        assert!(worst < 4e-15, "worst error {worst:e}");
        assert_eq!(ln(1.0), 0.0);
        assert!((ln(std::f64::consts::E) - 1.0).abs() < 1e-15);
    }
}
