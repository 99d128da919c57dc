//! The collision of a node (the paper's equations 2–5), in pieces the kernel ([`crate::kernel`])
//! runs as passes over many nodes — interior and gathered wall nodes alike:
//!
//! - moments `ρ = Σfᵢ`, `ρu = Σcᵢfᵢ + F/2`;
//! - relaxation `fᵢ ← fᵢ − ω(fᵢ − fᵢᵉᑫ)` with `ω = 1/τ`;
//! - for generalised-Newtonian fluids `τ` from the shear rate of the non-equilibrium moments,
//!   `Πⁿᵉ = Σcᵢcᵢ(fᵢ − fᵢᵉᑫ)`, `γ̇ = 3/(2ρτ)·√(2 Πⁿᵉ:Πⁿᵉ)`, using the node's τ of the previous step
//!   (the lagged scheme), then `τ = 3ν(γ̇) + ½` clamped;
//! - Guo's forcing `Fᵢ = (1 − ω/2)·wᵢ·[3(cᵢ − u) + 9(cᵢ·u)cᵢ]·F` when a body force drives the flow.
//!
//! Everything is `#[inline(always)]` and branch-free so that a loop over nodes vectorises.

// The passes index several arrays by the same node k: a range loop says that most plainly.
#![allow(clippy::needless_range_loop)]

use crate::fastmath;
use crate::rheology::{Fluid, GAMMA_MIN};

/// How a node's relaxation rate ω = 1/τ is found.
pub trait Relaxation: Copy + Send + Sync {
    /// Whether ω varies from node to node (and so is read and written per node).
    const PER_NODE: bool;
    /// ω at the squared shear rate γ̇² (for a constant ω, ignored). Squared because the square
    /// root is part of the law's cheaper single-precision arithmetic.
    fn omega_at(&self, gamma_sq: f64) -> f64;

    /// ω at each of the squared shear rates `gamma_sq` (at most [`CHUNK`] of them, in single
    /// precision: see [`single_precision_rate`]).
    #[inline(always)]
    fn omega_at_each(&self, gamma_sq: &[f32], omega: &mut [f64]) {
        let omega = &mut omega[..gamma_sq.len()];
        for k in 0..gamma_sq.len() {
            omega[k] = self.omega_at(gamma_sq[k] as f64);
        }
    }
}

/// Nodes per chunk of the kernel's passes: a few arrays of it fit the L1 data cache.
pub const CHUNK: usize = 256;

/// A Newtonian fluid: one ω everywhere.
#[derive(Debug, Clone, Copy)]
pub struct ConstantRate(pub f64);

impl Relaxation for ConstantRate {
    const PER_NODE: bool = false;
    #[inline(always)]
    fn omega_at(&self, _: f64) -> f64 {
        self.0
    }
}

/// A power-law or Herschel–Bulkley fluid, `ν = K·γ̇ⁿ⁻¹ + τ₀·(1 − e^(−mγ̇))/γ̇` (τ₀ = 0 for the
/// power law), τ = 3ν + ½ clamped to `[tau_min, tau_max]`.
#[derive(Debug, Clone, Copy)]
pub struct ShearDependent {
    pub k: f64,
    pub n: f64,
    pub tau0: f64,
    pub m: f64,
    pub tau_min: f64,
    pub tau_max: f64,
}

impl ShearDependent {
    /// The law of a non-Newtonian fluid; `None` for a Newtonian one.
    pub fn of(fluid: Fluid, tau_min: f64, tau_max: f64) -> Option<ShearDependent> {
        let (k, n, tau0, m) = match fluid {
            Fluid::Newtonian { .. } => return None,
            Fluid::PowerLaw { k, n } => (k, n, 0.0, 0.0),
            Fluid::HerschelBulkley { tau0, k, n, m } => (k, n, tau0, m),
        };
        Some(ShearDependent {
            k,
            n,
            tau0,
            m,
            tau_min,
            tau_max,
        })
    }
}

impl ShearDependent {
    /// The law's constants in single precision: K, n, τ₀, m, and the clamp on ω.
    #[inline(always)]
    fn single(&self) -> [f32; 6] {
        [
            self.k as f32,
            self.n as f32,
            self.tau0 as f32,
            self.m as f32,
            (1.0 / self.tau_max) as f32,
            (1.0 / self.tau_min) as f32,
        ]
    }
}

impl Relaxation for ShearDependent {
    const PER_NODE: bool = true;
    /// With both terms over γ̇, one division gives ω:
    /// `τ = (3(K·γ̇ⁿ + τ₀(1 − e^(−mγ̇))) + γ̇/2)/γ̇`, so `ω = γ̇/(3(K·γ̇ⁿ + τ₀(1 − e^(−mγ̇))) + γ̇/2)`,
    /// with `γ̇ⁿ = e^(n·ln γ̇)`; the clamp on τ is a clamp on ω. In single precision with
    /// [`fastmath`] (see there why that is enough).
    #[inline(always)]
    fn omega_at(&self, gamma_sq: f64) -> f64 {
        let [k, n, tau0, m, lo, hi] = self.single();
        let g = fastmath::clamp(single_precision_rate(gamma_sq).sqrt(), GAMMA_MIN, f32::MAX);
        let power = k * fastmath::exp(n * fastmath::ln(g));
        let yielded = tau0 * fastmath::one_minus_exp_neg(m * g);
        fastmath::clamp(g / (3.0 * (power + yielded) + 0.5 * g), lo, hi) as f64
    }

    /// The same law in three passes — the logarithm, the power, then the yield term and ω — so
    /// that each pass is a short chain the processor can overlap across many nodes.
    #[inline(always)]
    fn omega_at_each(&self, gamma_sq: &[f32], omega: &mut [f64]) {
        let [k, n, tau0, m, lo, hi] = self.single();
        let len = gamma_sq.len();
        let omega = &mut omega[..len];
        let mut g = [0.0f32; CHUNK];
        let mut power = [0.0f32; CHUNK];
        let (g, power) = (&mut g[..len], &mut power[..len]);
        for i in 0..len {
            g[i] = fastmath::clamp(gamma_sq[i].sqrt(), GAMMA_MIN, f32::MAX);
            power[i] = fastmath::ln(g[i]);
        }
        for i in 0..len {
            power[i] = k * fastmath::exp(n * power[i]);
        }
        for i in 0..len {
            let yielded = tau0 * fastmath::one_minus_exp_neg(m * g[i]);
            omega[i] =
                fastmath::clamp(g[i] / (3.0 * (power[i] + yielded) + 0.5 * g[i]), lo, hi) as f64;
        }
    }
}

const W0: f64 = 4.0 / 9.0;
const W1: f64 = 1.0 / 9.0;
const W2: f64 = 1.0 / 36.0;

/// Density, its inverse and velocity of a node.
#[derive(Debug, Clone, Copy)]
pub struct Moments {
    pub rho: f64,
    pub inv_rho: f64,
    pub ux: f64,
    pub uy: f64,
}

/// `ρ = Σfᵢ`, `ρu = Σcᵢfᵢ + F/2`.
#[inline(always)]
pub fn moments<const FORCED: bool>(f: &[f64; 9], force_x: f64) -> Moments {
    let [f0, f1, f2, f3, f4, f5, f6, f7, f8] = *f;
    // Summed as a tree: a shorter chain of dependent additions than left to right.
    let rho = ((f0 + f1) + (f2 + f3)) + ((f4 + f5) + (f6 + f7)) + f8;
    let inv_rho = 1.0 / rho;
    let mut jx = (f1 - f3) + (f5 - f6) + (f8 - f7);
    if FORCED {
        jx += 0.5 * force_x;
    }
    let jy = (f2 - f4) + (f5 + f6) - (f7 + f8);
    Moments {
        rho,
        inv_rho,
        ux: jx * inv_rho,
        uy: jy * inv_rho,
    }
}

/// γ̇² in single precision for the viscosity law, floored at GAMMA_MIN² first so that a still
/// node never makes a subnormal float (slow on x86).
#[inline(always)]
pub fn single_precision_rate(gamma_sq: f64) -> f32 {
    const FLOOR: f64 = (GAMMA_MIN as f64) * (GAMMA_MIN as f64);
    (if gamma_sq > FLOOR { gamma_sq } else { FLOOR }) as f32
}

/// Squared shear rate of a node from its non-equilibrium momentum flux, using its relaxation
/// rate ω = 1/τ of the last step: `Πⁿᵉ = Σcᵢcᵢfᵢ − ρ(I/3 + uu)` (the equilibrium's second moment
/// is exact on D2Q9), and `γ̇² = (3ω/(2ρ))²·2 Πⁿᵉ:Πⁿᵉ`.
#[inline(always)]
pub fn shear_rate_squared(f: &[f64; 9], m: Moments, omega_old: f64) -> f64 {
    let Moments {
        rho,
        inv_rho,
        ux,
        uy,
    } = m;
    let diagonals = (f[5] + f[6]) + (f[7] + f[8]);
    let pxx = (f[1] + f[3]) + diagonals - rho * (1.0 / 3.0 + ux * ux);
    let pyy = (f[2] + f[4]) + diagonals - rho * (1.0 / 3.0 + uy * uy);
    let pxy = (f[5] - f[6]) + (f[7] - f[8]) - rho * ux * uy;
    let scale = 1.5 * omega_old * inv_rho;
    scale * scale * 2.0 * (pxx * pxx + pyy * pyy + 2.0 * pxy * pxy)
}

/// Collides the nine populations `f` of one node (in the order of [`crate::lattice::C`]) in
/// place, given its relaxation rate ω = 1/τ of the last step; returns its new ω. `FORCED` adds
/// Guo's term for the body force `force_x`. The kernel does the same in passes over many nodes;
/// this one-node form is the plain reference the tests hold the kernel to.
#[cfg(test)]
pub(crate) fn collide<R: Relaxation, const FORCED: bool>(
    f: &mut [f64; 9],
    relax: &R,
    omega_old: f64,
    force_x: f64,
) -> f64 {
    let m = moments::<FORCED>(f, force_x);
    let omega = relax.omega_at(shear_rate_squared(f, m, omega_old));
    relax_towards_equilibrium::<FORCED>(f, m.rho, m.ux, m.uy, omega, force_x);
    omega
}

/// `fᵢ ← fᵢ − ω(fᵢ − fᵢᵉᑫ(ρ, u))`, plus Guo's force term when `FORCED`.
#[inline(always)]
pub fn relax_towards_equilibrium<const FORCED: bool>(
    f: &mut [f64; 9],
    rho: f64,
    ux: f64,
    uy: f64,
    omega: f64,
    force_x: f64,
) {
    let usq = 1.5 * (ux * ux + uy * uy);
    let eq = |w: f64, cu: f64| w * rho * (1.0 + 3.0 * cu + 4.5 * cu * cu - usq);
    let feq = [
        eq(W0, 0.0),
        eq(W1, ux),
        eq(W1, uy),
        eq(W1, -ux),
        eq(W1, -uy),
        eq(W2, ux + uy),
        eq(W2, -ux + uy),
        eq(W2, -ux - uy),
        eq(W2, ux - uy),
    ];
    for i in 0..9 {
        f[i] -= omega * (f[i] - feq[i]);
    }
    if FORCED {
        // 3(cᵢ − u)·x̂ + 9(cᵢ·u)cᵢₓ for each direction, times (1 − ω/2)·wᵢ·F.
        let pre = (1.0 - 0.5 * omega) * force_x;
        let guo = |w: f64, cx: f64, cu: f64| pre * w * (3.0 * (cx - ux) + 9.0 * cu * cx);
        f[0] += guo(W0, 0.0, 0.0);
        f[1] += guo(W1, 1.0, ux);
        f[2] += guo(W1, 0.0, uy);
        f[3] += guo(W1, -1.0, -ux);
        f[4] += guo(W1, 0.0, -uy);
        f[5] += guo(W2, 1.0, ux + uy);
        f[6] += guo(W2, -1.0, -ux + uy);
        f[7] += guo(W2, -1.0, -ux - uy);
        f[8] += guo(W2, 1.0, ux - uy);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lattice::{C, W, equilibrium};
    use crate::rheology::tau_of;

    #[test]
    fn fast_law_matches_the_reference_relaxation_time() {
        for fluid in [
            Fluid::PowerLaw { k: 0.02, n: 0.5 },
            Fluid::PowerLaw { k: 0.02, n: 1.5 },
            Fluid::HerschelBulkley {
                tau0: 1e-4,
                k: 0.01,
                n: 0.4,
                m: 1e4,
            },
        ] {
            // A wide clamp so that the law itself is compared, then the usual one.
            for (tau_min, tau_max) in [(0.5, 1e12), (0.51, 10.0)] {
                let law = ShearDependent::of(fluid, tau_min, tau_max).unwrap();
                let mut gammas = vec![];
                let mut g = 1e-10;
                while g < 1.0 {
                    gammas.push(g);
                    g *= 1.37;
                }
                let mut each = vec![0.0; gammas.len()];
                let squares: Vec<f32> = gammas
                    .iter()
                    .map(|g| single_precision_rate(g * g))
                    .collect();
                law.omega_at_each(&squares, &mut each);
                for (&g, &passes) in gammas.iter().zip(&each) {
                    let want = 1.0 / tau_of(fluid.viscosity(g)).clamp(tau_min, tau_max);
                    let got = law.omega_at(g * g);
                    // Single precision: a few parts in 10⁷.
                    assert!(
                        ((got - want) / want).abs() < 1e-6,
                        "{fluid:?} at {g}: {got} vs {want}"
                    );
                    assert_eq!(got, passes, "the passes compute the same law");
                }
            }
        }
    }

    #[test]
    fn collision_conserves_mass_and_relaxes_towards_equilibrium() {
        let (rho, ux, uy) = (1.02, 0.04, -0.01);
        let mut f: [f64; 9] =
            std::array::from_fn(|i| equilibrium(i, rho, ux, uy) + 1e-4 * i as f64);
        let before = f;
        collide::<_, false>(&mut f, &ConstantRate(1.0), 1.0, 0.0);
        // τ = 1 lands exactly on the equilibrium of the node's own moments.
        let m: f64 = before.iter().sum();
        let jx: f64 = (0..9).map(|i| before[i] * C[i].0 as f64).sum();
        let jy: f64 = (0..9).map(|i| before[i] * C[i].1 as f64).sum();
        for i in 0..9 {
            let want = equilibrium(i, m, jx / m, jy / m);
            assert!((f[i] - want).abs() < 1e-15, "direction {i}");
        }
        // The force adds its momentum F and no mass.
        let mut g = before;
        collide::<_, true>(&mut g, &ConstantRate(1.0 / 0.8), 1.0 / 0.8, 1e-5);
        let mass: f64 = g.iter().sum();
        let gx: f64 = (0..9).map(|i| g[i] * C[i].0 as f64).sum();
        assert!((mass - m).abs() < 1e-15);
        assert!((gx - (jx + 1e-5)).abs() < 1e-15, "{gx} vs {}", jx + 1e-5);
        assert!((W.iter().sum::<f64>() - 1.0).abs() < 1e-15);
    }
}
