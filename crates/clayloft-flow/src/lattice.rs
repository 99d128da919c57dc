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
