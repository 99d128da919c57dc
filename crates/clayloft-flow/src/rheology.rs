//! Apparent viscosity of the slurry (kinematic, lattice units) and the relaxation time.
//!
//! - Newtonian: ν.
//! - Power law: ν = K·γ̇ⁿ⁻¹.
//! - Herschel–Bulkley with Papanastasiou regularisation:
//!   ν = K·γ̇ⁿ⁻¹ + τ₀·(1 − e^(−mγ̇))/γ̇, so the yield term stays finite (→ τ₀·m) as γ̇ → 0.
//!
//! γ̇ is floored at `GAMMA_MIN` (the power-law term diverges for n < 1) and τ = 3ν + ½ is
//! clamped to `[tau_min, tau_max]`; cells at the upper clamp are, for practical purposes,
//! unyielded. Keep τ_max near 10: BGK is a continuum model only while populations relax within a
//! few cells; at τ of 50 and more a plug of 20 cells visibly shears (measured in the
//! Herschel–Bulkley channel test).

/// Smallest shear rate used in the viscosity law (lattice units).
pub const GAMMA_MIN: f32 = 1e-9;

/// A fluid, in lattice units (kinematic: stresses divided by density).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Fluid {
    Newtonian { nu: f64 },
    PowerLaw { k: f64, n: f64 },
    HerschelBulkley { tau0: f64, k: f64, n: f64, m: f64 },
}

impl Fluid {
    /// Kinematic viscosity at shear rate γ̇.
    #[inline(always)]
    pub fn viscosity(&self, gamma: f64) -> f64 {
        let g = gamma.max(GAMMA_MIN as f64);
        match *self {
            Fluid::Newtonian { nu } => nu,
            Fluid::PowerLaw { k, n } => k * g.powf(n - 1.0),
            Fluid::HerschelBulkley { tau0, k, n, m } => {
                k * g.powf(n - 1.0) + tau0 * (1.0 - (-m * g).exp()) / g
            }
        }
    }

    pub fn is_newtonian(&self) -> bool {
        matches!(self, Fluid::Newtonian { .. })
    }
}

/// τ = 3ν + ½ (c_s² = 1/3, Δt = 1).
#[inline(always)]
pub fn tau_of(nu: f64) -> f64 {
    3.0 * nu + 0.5
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn viscosity_laws() {
        assert_eq!(Fluid::Newtonian { nu: 0.1 }.viscosity(3.0), 0.1);
        let p = Fluid::PowerLaw { k: 0.02, n: 0.5 };
        assert!((p.viscosity(0.04) - 0.02 / 0.2).abs() < 1e-12);
        let hb = Fluid::HerschelBulkley {
            tau0: 1e-4,
            k: 0.01,
            n: 1.0,
            m: 1e4,
        };
        // At high shear the regularised yield term is τ₀/γ̇.
        assert!((hb.viscosity(0.01) - (0.01 + 1e-2)).abs() < 1e-9);
        // At rest it stays finite: K + τ₀·m.
        assert!((hb.viscosity(0.0) - (0.01 + 1.0)).abs() < 1e-3);
        assert_eq!(tau_of(1.0 / 6.0), 1.0);
    }
}
