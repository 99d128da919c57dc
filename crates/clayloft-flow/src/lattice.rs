//! The D2Q9 velocity set: cᵢ, weights wᵢ (4/9, 1/9, 1/36), c_s² = 1/3.

/// Velocities: rest, the four axes, the four diagonals.
pub const C: [(i32, i32); 9] = [
    (0, 0),
    (1, 0),
    (0, 1),
    (-1, 0),
    (0, -1),
    (1, 1),
    (-1, 1),
    (-1, -1),
    (1, -1),
];
pub const W: [f64; 9] = [
    4.0 / 9.0,
    1.0 / 9.0,
    1.0 / 9.0,
    1.0 / 9.0,
    1.0 / 9.0,
    1.0 / 36.0,
    1.0 / 36.0,
    1.0 / 36.0,
    1.0 / 36.0,
];
/// The opposite direction of each.
pub const OPP: [usize; 9] = [0, 3, 4, 1, 2, 7, 8, 5, 6];

/// How populations are kept in memory: single precision, less their rest weight,
/// `f̃ᵢ = fᵢ − wᵢ` (the "shifted" storage of FluidX3D). At rest f̃ is 0 and it stays of the
/// order of wᵢ·3cᵢ·u, so single precision resolves it to about 10⁻¹⁰ — as fine as double
/// precision resolves fᵢ itself near the velocities here — with half the memory traffic: the two
/// 120 × 120 lattices then fit in a core's L2 cache. All arithmetic is in double precision.
pub type Stored = f32;

/// The population of direction i from its stored form.
#[inline(always)]
pub fn unshift(i: usize, stored: Stored) -> f64 {
    stored as f64 + W[i]
}

/// The stored form of population `f` of direction i.
#[inline(always)]
pub fn shift(i: usize, f: f64) -> Stored {
    (f - W[i]) as Stored
}

/// Equilibrium population i at density ρ and velocity u.
#[inline(always)]
pub fn equilibrium(i: usize, rho: f64, ux: f64, uy: f64) -> f64 {
    let cu = C[i].0 as f64 * ux + C[i].1 as f64 * uy;
    W[i] * rho * (1.0 + 3.0 * cu + 4.5 * cu * cu - 1.5 * (ux * ux + uy * uy))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn equilibrium_has_the_right_moments() {
        let (rho, ux, uy) = (1.1, 0.05, -0.02);
        let f: Vec<f64> = (0..9).map(|i| equilibrium(i, rho, ux, uy)).collect();
        let m0: f64 = f.iter().sum();
        let mx: f64 = (0..9).map(|i| f[i] * C[i].0 as f64).sum();
        let my: f64 = (0..9).map(|i| f[i] * C[i].1 as f64).sum();
        assert!((m0 - rho).abs() < 1e-14);
        assert!((mx - rho * ux).abs() < 1e-14 && (my - rho * uy).abs() < 1e-14);
        assert!((W.iter().sum::<f64>() - 1.0).abs() < 1e-15);
        for i in 0..9 {
            assert_eq!(C[OPP[i]], (-C[i].0, -C[i].1));
        }
    }
}
