//! The lid-driven square cavity, the benchmark of the solver: Newtonian at a Reynolds number
//! (Ghia, Ghia & Shin 1982) and a Bingham plastic in creeping flow, where the only parameter is
//! the Bingham number `Bn = τ₀·L/(μ_p·U)` (yield stress over the viscous stress of the lid's
//! shear rate; Mitsoulis & Zisis, J. Non-Newtonian Fluid Mech. 101 (2001) 173–180; Syrakos,
//! Georgiou & Alexandrou, ibid. 195 (2013) 19–31). As Bn grows the vortex climbs towards the
//! lid and an unyielded, still region fills the bottom of the cavity.

use crate::groove::LATTICE_REYNOLDS;
use crate::rheology::Fluid;
use crate::solver::{Boundaries, Solver};

/// The relaxation-time clamp of the yield-stress cases: cells at τ_max are, for practical
/// purposes, unyielded (see [`crate::rheology`] on why τ_max stays near 10).
pub const TAU_MIN: f64 = 0.51;
pub const TAU_MAX: f64 = 10.0;

/// A Bingham cavity of `cells × cells` at Bingham number `bn` (0: Newtonian), in creeping flow:
/// the lid at the lattice Reynolds number [`LATTICE_REYNOLDS`], the apparent viscosity at the
/// lid's shear rate γ̇c = U/L equal to `nu_ref` (so that the plastic viscosity is
/// `nu_ref/(1 + Bn)` and `τ₀ = Bn·μ_p·γ̇c`). Returns the solver and the yield stress (lattice
/// units).
pub fn bingham(cells: usize, bn: f64, nu_ref: f64) -> (Solver, f64) {
    let n = cells as f64;
    let lid = LATTICE_REYNOLDS * nu_ref / n;
    let gamma_c = lid / n;
    let mu_p = nu_ref / (1.0 + bn);
    let tau0 = bn * mu_p * gamma_c;
    let fluid = if bn > 0.0 {
        Fluid::HerschelBulkley {
            tau0,
            k: mu_p,
            n: 1.0,
            // Papanastasiou exponent m·γ̇c = 1000: the yield term is exact above γ̇c/1000.
            m: 1000.0 / gamma_c,
        }
    } else {
        Fluid::Newtonian { nu: nu_ref }
    };
    let solver = Solver::new(
        cells,
        cells,
        fluid,
        Boundaries::cavity(lid),
        TAU_MIN,
        TAU_MAX,
    );
    (solver, tau0)
}

/// Steps for momentum to cross the cavity a few times at viscosity ν: `3·N²/ν`.
pub fn diffusion_steps(cells: usize, nu: f64) -> u64 {
    (3.0 * (cells * cells) as f64 / nu) as u64
}
