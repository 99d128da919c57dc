//! The groove case (SPEC §10): a square section of the screw channel, the barrel wall (top)
//! moving at the screw's surface speed `U = π·D·rpm/60`, in physical units, converted to the
//! lattice through the numbers that decide a creeping flow.
//!
//! The clay moves so slowly for its viscosity that inertia plays no part: the Reynolds number
//! `Re = U·H/ν(γ̇c)` (γ̇c = U/H, the characteristic shear rate) is 10⁻² … 10⁻⁵. The flow then
//! depends only on the flow index n and the **Bingham number** `Bn = τ₀/(K·γ̇cⁿ)`, the yield
//! stress against the viscous stress: as the screw slows, γ̇c falls, Bn grows and more of the
//! slurry stands still. The lattice is given the physical n and Bn, a reference viscosity
//! `ν_lu = (τ_ref − ½)/3` at γ̇c, and a wall speed for a small lattice Reynolds number
//! ([`LATTICE_REYNOLDS`]): `U_lu = Re_lu·ν_lu/N`, `γ̇c,lu = U_lu/N`,
//! `τ₀,lu = ν_lu·γ̇c,lu·Bn/(1 + Bn)`, `K_lu = ν_lu·γ̇c,lu^(1−n)/(1 + Bn)` (so that
//! `ν(γ̇c) = ν_lu` and the ratio of the two is Bn). Velocities scale back by `U/U_lu`.
//!
//! Matching the physical Reynolds number instead (as this module once did) put the lattice wall
//! speed at 2·10⁻⁷ for a slow screw, its shear rates at the floor of the viscosity law
//! ([`crate::rheology::GAMMA_MIN`]), and so gave the slurry *less* yield the slower the screw
//! turned: 0 % unyielded at 5 rpm against 58 % at 45 rpm.

use crate::rheology::Fluid;

/// A slurry in physical units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Material {
    pub name: &'static str,
    /// Yield stress, Pa.
    pub tau0: f64,
    /// Consistency, Pa·sⁿ.
    pub k: f64,
    /// Flow index.
    pub n: f64,
    /// Density, kg/m³.
    pub rho: f64,
    /// Where the numbers come from.
    pub source: &'static str,
}

/// Presets: a Newtonian reference, a shear-thinning clay paste, a Herschel–Bulkley slurry.
pub const MATERIALS: [Material; 3] = [
    Material {
        name: "newtonian",
        tau0: 0.0,
        k: 30.0,
        n: 1.0,
        rho: 1900.0,
        source: "reference: a Newtonian fluid of 30 Pa·s (a thick syrup), same density as the paste",
    },
    Material {
        name: "clay-paste",
        tau0: 0.0,
        k: 800.0,
        n: 0.23,
        rho: 1900.0,
        source: "85 % clay paste, Brookfield 828 Pa·s at 1 rpm falling to 40 Pa·s at 50 rpm: n ≈ 0.23 (ASME IMECE2020-V003T03A034)",
    },
    Material {
        name: "ceramic-slurry",
        tau0: 300.0,
        k: 30.0,
        n: 0.4,
        rho: 1900.0,
        source: "Herschel–Bulkley ceramic ink in the robocasting range (τ₀ 50–1000 Pa, K 5–300 Pa·sⁿ, n 0.2–0.6; del-Mazo-Barbara & Ginebra 2021 review)",
    },
];

pub fn material(name: &str) -> Option<Material> {
    MATERIALS.iter().copied().find(|m| m.name == name)
}

/// The groove problem in physical units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Groove {
    pub width_m: f64,
    pub depth_m: f64,
    pub screw_diameter_m: f64,
    pub rpm: f64,
    pub material: Material,
}

/// The lattice Reynolds number the groove is solved at: small enough that inertia changes the
/// creeping flow by well under a per cent (the Stokes cavity test keeps its mirror symmetry to
/// 1 % at 0.02), large enough that the lattice wall speed (≈ 7·10⁻⁵ on 120 cells) keeps the
/// shear rates far above the viscosity law's floor and single-precision round-off.
pub const LATTICE_REYNOLDS: f64 = 0.05;

/// The lattice version of a groove.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LatticeGroove {
    pub nx: usize,
    pub ny: usize,
    /// Cell size, m.
    pub dx: f64,
    /// Wall speed in lattice units.
    pub lid_u: f64,
    pub fluid: Fluid,
    /// The physical Reynolds number `U·H/ν(γ̇c)`.
    pub reynolds: f64,
    /// The Bingham number `τ₀/(K·γ̇cⁿ)` (0 without a yield stress).
    pub bingham: f64,
    /// The wall speed, m/s: a lattice velocity times `lid_speed / lid_u` is in m/s.
    pub lid_speed: f64,
}

impl LatticeGroove {
    /// The solver of this groove: the slurry at rest, the barrel wall moving, the yield-stress
    /// clamp of [`crate::cavity`].
    pub fn solver(&self) -> crate::Solver {
        crate::Solver::new(
            self.nx,
            self.ny,
            self.fluid,
            crate::Boundaries::cavity(self.lid_u),
            crate::cavity::TAU_MIN,
            crate::cavity::TAU_MAX,
        )
    }

    /// The yield stress in lattice units (0 without one): where a cell's shear stress
    /// ([`crate::Solver::shear_stresses`]) stays below it, the slurry does not yield.
    pub fn yield_stress(&self) -> f64 {
        match self.fluid {
            Fluid::HerschelBulkley { tau0, .. } => tau0,
            _ => 0.0,
        }
    }
}

impl Groove {
    /// Barrel speed relative to the screw, m/s.
    pub fn wall_speed(&self) -> f64 {
        std::f64::consts::PI * self.screw_diameter_m * self.rpm / 60.0
    }

    /// Apparent kinematic viscosity at γ̇, m²/s.
    pub fn nu(&self, gamma: f64) -> f64 {
        let m = &self.material;
        (m.k * gamma.powf(m.n - 1.0) + m.tau0 / gamma) / m.rho
    }

    /// The characteristic shear rate U/H, 1/s.
    pub fn shear_rate(&self) -> f64 {
        self.wall_speed() / self.depth_m
    }

    /// The Bingham number `τ₀/(K·γ̇cⁿ)`: yield stress over viscous stress.
    pub fn bingham(&self) -> f64 {
        let m = &self.material;
        m.tau0 / (m.k * self.shear_rate().powf(m.n))
    }

    /// Converts to a lattice of `cells` across the width, at reference relaxation time `tau_ref`
    /// (the module's doc gives the scaling).
    pub fn to_lattice(&self, cells: usize, tau_ref: f64) -> LatticeGroove {
        let u = self.wall_speed();
        let gamma_c = self.shear_rate();
        let dx = self.width_m / cells as f64;
        let ny = ((self.depth_m / dx).round() as usize).max(4);
        let nu_lu = (tau_ref - 0.5) / 3.0;
        let reynolds = u * self.depth_m / self.nu(gamma_c);
        // Inertia kept where it is real (never here in practice), the lattice Mach number low.
        let lid_u = (reynolds.max(LATTICE_REYNOLDS) * nu_lu / ny as f64).min(0.05);
        let gamma_lu = lid_u / ny as f64;
        let m = &self.material;
        let bingham = self.bingham();
        let fluid = if m.tau0 == 0.0 && m.n == 1.0 {
            Fluid::Newtonian { nu: nu_lu }
        } else if m.tau0 == 0.0 {
            Fluid::PowerLaw {
                k: nu_lu * gamma_lu.powf(1.0 - m.n),
                n: m.n,
            }
        } else {
            Fluid::HerschelBulkley {
                tau0: nu_lu * gamma_lu * bingham / (1.0 + bingham),
                k: nu_lu * gamma_lu.powf(1.0 - m.n) / (1.0 + bingham),
                n: m.n,
                // Papanastasiou exponent: the yield term is exact above a hundredth of γ̇c.
                m: 100.0 / gamma_lu,
            }
        };
        LatticeGroove {
            nx: cells,
            ny,
            dx,
            lid_u,
            fluid,
            reynolds,
            bingham,
            lid_speed: u,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rheology::GAMMA_MIN;

    fn groove(rpm: f64) -> Groove {
        Groove {
            width_m: 4e-3,
            depth_m: 4e-3,
            screw_diameter_m: 20e-3,
            rpm,
            material: material("ceramic-slurry").unwrap(),
        }
    }

    #[test]
    fn the_lattice_keeps_the_bingham_number_and_the_reference_viscosity() {
        for rpm in [1.0, 5.0, 45.0, 120.0] {
            let g = groove(rpm);
            let l = g.to_lattice(120, 1.0);
            assert!(l.reynolds < 0.1, "creeping flow: Re = {}", l.reynolds);
            let Fluid::HerschelBulkley { tau0, k, n, .. } = l.fluid else {
                panic!("{:?}", l.fluid)
            };
            let gamma_lu = l.lid_u / l.ny as f64;
            // The same Bingham number on the lattice as in the groove.
            let bn_lu = tau0 / (k * gamma_lu.powf(n));
            assert!(
                (bn_lu - g.bingham()).abs() < 1e-9 * g.bingham(),
                "{rpm} rpm"
            );
            // The lattice viscosity at the characteristic shear rate is ν_lu = 1/6.
            let nu = l.fluid.viscosity(gamma_lu);
            assert!((nu - 1.0 / 6.0).abs() < 0.01 / 6.0, "{rpm} rpm: ν = {nu}");
            // The lattice Reynolds number is the small fixed one, and the floor of the viscosity
            // law lies far below the shear rates where the slurry reaches the viscosity limit
            // (a few hundredths of γ̇c): below the floor it is unyielded either way.
            let re_lu = l.lid_u * l.ny as f64 * 6.0;
            assert!((re_lu - l.reynolds.max(LATTICE_REYNOLDS)).abs() < 1e-12);
            assert!(
                gamma_lu > 100.0 * GAMMA_MIN as f64,
                "{rpm} rpm: γ̇c = {gamma_lu:e}"
            );
        }
    }

    #[test]
    fn a_slower_screw_has_the_larger_bingham_number() {
        // At 45 rpm the wall moves at π·20 mm·45/60 = 47.1 mm/s over a 4 mm groove: γ̇c = 11.8/s,
        // Bn = 300/(30·11.8^0.4) = 3.7; at 5 rpm γ̇c = 1.31/s and Bn = 9.0.
        let fast = groove(45.0);
        assert!((fast.wall_speed() - 0.04712).abs() < 1e-4);
        assert!((fast.bingham() - 3.73).abs() < 0.01, "{}", fast.bingham());
        assert!((groove(5.0).bingham() - 8.98).abs() < 0.01);
        let bns: Vec<f64> = [120.0, 45.0, 15.0, 5.0, 1.0]
            .iter()
            .map(|&r| groove(r).bingham())
            .collect();
        assert!(bns.windows(2).all(|w| w[0] < w[1]), "{bns:?}");
    }
}
