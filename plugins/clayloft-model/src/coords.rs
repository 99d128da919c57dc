//! Design space (millimetres, z up, the printer's axes) and Bevy's world space (y up).
//!
//! `world = (x, z, −y)`: a right-handed rotation, so the vessel stands on the bed the way it prints.

use bevy::math::{DVec3, Vec3};

/// Design-space point (mm, z up) to a Bevy world position: the core's view frame
/// ([`clayloft_core::view_mesh::to_view`]), in which the wall's mesh comes.
#[inline]
pub fn to_world(p: DVec3) -> Vec3 {
    clayloft_core::view_mesh::to_view(p)
}

/// Bevy world position to a design-space point (mm, z up).
#[inline]
pub fn from_world(w: Vec3) -> DVec3 {
    clayloft_core::view_mesh::from_view(w)
}
