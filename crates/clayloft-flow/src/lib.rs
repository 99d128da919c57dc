//! Why clay moves the way it does in a screw extruder (SPEC §10; the paper's §3.1–3.2): a D2Q9
//! lattice-Boltzmann BGK solver with a per-cell relaxation time for shear-thinning and
//! yield-stress (Herschel–Bulkley) fluids.
//!
//! - [`lattice`]: the D2Q9 velocity set, weights and equilibrium
//!   `fᵢᵉᑫ = wᵢρ(1 + 3cᵢ·u + 9/2 (cᵢ·u)² − 3/2 u²)`;
//! - [`rheology`]: apparent viscosity from the shear rate (Newtonian, power law, regularised
//!   Herschel–Bulkley) and the relaxation time `τ = 3ν + ½`, clamped to a stable range;
//! - [`solver`]: streaming (pull), half-way bounce-back walls, a moving lid (Ladd), periodic
//!   channels with a body force (Guo), collision with the shear rate from the non-equilibrium
//!   moments `γ̇ = 3/(2ρτ)·√(2 Πⁿᵉ:Πⁿᵉ)`.

pub mod analysis;
pub mod collision;
pub mod fastmath;
pub mod groove;
pub mod kernel;
pub mod lattice;
pub mod parallel;
pub mod rheology;
pub mod solver;

pub use rheology::Fluid;
pub use solver::{Boundaries, Solver};
