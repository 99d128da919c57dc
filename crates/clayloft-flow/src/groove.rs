//! The groove case (SPEC §10): a square section of the screw channel, the barrel wall (top)
//! moving at the screw's surface speed `U = π·D·rpm/60`, in physical units, converted to the
//! lattice through the Reynolds number.
//!
//! With a reference relaxation time τ_ref (ν_lu = (τ_ref − ½)/3), the time step follows from
//! matching the viscosity at the characteristic shear rate γ̇c = U/W:
//! `Δt = ν_lu·Δx²/ν(γ̇c)`, so that `U_lu = U·Δt/Δx` gives the lattice the physical Reynolds
//! number `Re = U·W/ν(γ̇c)`. Kinematic Herschel–Bulkley parameters convert as
//! `τ₀,lu = τ₀/ρ·Δt²/Δx²` and `K_lu = K/ρ·Δt^(2−n)/Δx²`.

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

/// The lattice version of a groove.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LatticeGroove {
    pub nx: usize,
    pub ny: usize,
    pub dx: f64,
    pub dt: f64,
    pub lid_u: f64,
    pub fluid: Fluid,
    pub reynolds: f64,
    pub lid_speed: f64,
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

    /// Converts to a lattice of `cells` across the width, at reference relaxation time `tau_ref`.
    pub fn to_lattice(&self, cells: usize, tau_ref: f64) -> LatticeGroove {
        let u = self.wall_speed();
        let gamma_c = u / self.depth_m;
        let nu_c = self.nu(gamma_c);
        let dx = self.width_m / cells as f64;
        let nu_lu = (tau_ref - 0.5) / 3.0;
        let dt = nu_lu * dx * dx / nu_c;
        let m = &self.material;
        let fluid = if m.tau0 == 0.0 && m.n == 1.0 {
            Fluid::Newtonian { nu: nu_lu }
        } else if m.tau0 == 0.0 {
            Fluid::PowerLaw {
                k: m.k / m.rho * dt.powf(2.0 - m.n) / (dx * dx),
                n: m.n,
            }
        } else {
            let tau0 = m.tau0 / m.rho * dt * dt / (dx * dx);
            // Papanastasiou exponent: the yield term is exact above a hundredth of γ̇c.
            let m_reg = 100.0 / (gamma_c * dt);
            Fluid::HerschelBulkley {
                tau0,
                k: m.k / m.rho * dt.powf(2.0 - m.n) / (dx * dx),
                n: m.n,
                m: m_reg,
            }
        };
        LatticeGroove {
            nx: cells,
            ny: ((self.depth_m / dx).round() as usize).max(4),
            dx,
            dt,
            lid_u: u * dt / dx,
            fluid,
            reynolds: u * self.depth_m / nu_c,
            lid_speed: u,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn units_convert_through_the_reynolds_number() {
        let g = Groove {
            width_m: 4e-3,
            depth_m: 4e-3,
            screw_diameter_m: 20e-3,
            rpm: 45.0,
            material: material("ceramic-slurry").unwrap(),
        };
        assert!((g.wall_speed() - 0.04712).abs() < 1e-4);
        let l = g.to_lattice(120, 1.0);
        // The lattice Reynolds number equals the physical one.
        let nu_lu = 1.0 / 6.0;
        assert!((l.lid_u * l.ny as f64 / nu_lu - l.reynolds).abs() / l.reynolds < 0.02);
        assert!(l.reynolds < 0.05, "Stokes flow: Re = {}", l.reynolds);
        // The lattice viscosity at the characteristic shear rate is ν_lu.
        let gamma_lu = l.lid_u / l.ny as f64;
        assert!((l.fluid.viscosity(gamma_lu) - nu_lu).abs() / nu_lu < 0.02);
    }
}
