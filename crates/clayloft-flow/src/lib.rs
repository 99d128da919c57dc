//! Why clay moves the way it does in a screw extruder (SPEC §10; the paper's §3.1–3.2): a D2Q9
//! lattice-Boltzmann BGK solver with a per-cell relaxation time for shear-thinning and
//! yield-stress (Herschel–Bulkley) fluids.
//!
//! - [`lattice`]: the D2Q9 velocity set, weights and equilibrium
//!   `fᵢᵉᑫ = wᵢρ(1 + 3cᵢ·u + 9/2 (cᵢ·u)² − 3/2 u²)`, and how populations are stored (single
//!   precision, less their weight);
//! - [`rheology`]: apparent viscosity from the shear rate (Newtonian, power law, regularised
//!   Herschel–Bulkley) and the relaxation time `τ = 3ν + ½`, clamped to a stable range;
//! - [`collision`]: one node's collision — moments, the shear rate of the non-equilibrium
//!   moments `γ̇ = 3/(2ρτ)·√(2 Πⁿᵉ:Πⁿᵉ)`, the relaxation rate from the viscosity law, BGK
//!   relaxation and Guo's forcing;
//! - [`kernel`]: the vectorised sweep over a run of nodes, compiled for AVX-512, AVX2 and the
//!   baseline; [`fastmath`]: the branch-free `ln`/`exp` it needs;
//! - [`solver`]: the lattice, pull streaming, half-way bounce-back walls, a moving lid (Ladd),
//!   periodic channels with a body force (Guo), time steps on one or several threads
//!   ([`parallel`]: bands of rows and a spinning barrier);
//! - [`cavity`]: the lid-driven cavity benchmarks, Newtonian and Bingham;
//! - [`groove`]: the screw groove in physical units and its conversion to the lattice;
//! - [`analysis`]: vortex centre, dead zones, unyielded share, streamlines, the analytic channel
//!   profile.

pub mod analysis;
pub mod cavity;
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
