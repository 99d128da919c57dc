//! The core's previews as Bevy assets: the wall's mesh (built by the session,
//! [`clayloft_core::view_mesh`]) and the toolpath as coloured lines.

use bevy::asset::RenderAssetUsages;
use bevy::mesh::{Indices, PrimitiveTopology};
use bevy::prelude::*;
use clayloft_core::view_mesh::WallBuffers;

use crate::coords::to_world;

/// The wall's buffers as a Bevy mesh that keeps its data on the CPU too, so it can be
/// rewritten in place.
pub fn wall_mesh(b: WallBuffers) -> Mesh {
    Mesh::new(
        PrimitiveTopology::TriangleList,
        RenderAssetUsages::default(),
    )
    .with_inserted_attribute(Mesh::ATTRIBUTE_POSITION, b.positions)
    .with_inserted_attribute(Mesh::ATTRIBUTE_NORMAL, b.normals)
    .with_inserted_attribute(Mesh::ATTRIBUTE_COLOR, b.colors)
    .with_inserted_indices(Indices::U32(b.indices))
}

/// The spiral toolpath as a coloured line strip in world coordinates: blue at the foot to warm
/// at the rim, so the climb of the spiral reads at a glance.
pub fn toolpath_line(path: &clayloft_core::toolpath::Toolpath) -> Vec<(Vec3, Color)> {
    let pts = &path.points;
    let top = pts.iter().map(|p| p.pos.z).fold(1.0_f64, f64::max);
    pts.iter()
        .map(|p| {
            let f = (p.pos.z / top) as f32;
            (
                to_world(p.pos),
                Color::srgb(0.25 + 0.7 * f, 0.55 + 0.2 * (1.0 - f), 1.0 - 0.6 * f),
            )
        })
        .collect()
}
