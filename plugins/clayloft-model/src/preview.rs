//! The wall as a triangle mesh for the 3D view, coloured by how far each point leans from
//! vertical (the overhang of SPEC §2). Plain buffers, so the benchmark and tests need no GPU.

use bevy::asset::RenderAssetUsages;
use bevy::mesh::{Indices, PrimitiveTopology};
use bevy::prelude::*;
use clayloft_core::pipeline::Surface;

use crate::coords::to_world;

/// Vertex and index buffers of the wall, in world coordinates.
#[derive(Debug, Clone, Default)]
pub struct WallBuffers {
    pub positions: Vec<[f32; 3]>,
    pub normals: Vec<[f32; 3]>,
    pub colors: Vec<[f32; 4]>,
    pub indices: Vec<u32>,
    /// Points whose lean exceeds the limit.
    pub violating: usize,
}

/// Colour of a wall point leaning `lean` degrees when the limit is `limit` degrees: clay when
/// upright, through amber towards the limit, red past it.
pub fn lean_color(lean: f32, limit: f32) -> [f32; 4] {
    let clay = [0.80, 0.52, 0.38];
    let amber = [0.95, 0.75, 0.20];
    let red = [0.90, 0.08, 0.08];
    if lean > limit + 0.5 {
        return [red[0], red[1], red[2], 1.0];
    }
    let f = (lean / limit.max(1e-3)).clamp(0.0, 1.0);
    // Stay clay-coloured up to 60 % of the limit, then blend to amber at the limit.
    let w = ((f - 0.6) / 0.4).clamp(0.0, 1.0);
    let mix = |a: f32, b: f32| a + (b - a) * w;
    [
        mix(clay[0], amber[0]),
        mix(clay[1], amber[1]),
        mix(clay[2], amber[2]),
        1.0,
    ]
}

/// Builds the wall buffers: one vertex per surface point, two triangles per quad between
/// consecutive sections (closed around), normals from central differences.
pub fn wall_buffers(surface: &Surface, limit_deg: f64) -> WallBuffers {
    let sections = &surface.sections;
    let rows = sections.len();
    let n = sections.first().map_or(0, |s| s.points.len());
    if rows < 2 || n < 3 {
        return WallBuffers::default();
    }
    // The surface's own leans (measured once by the core); a surface put together by hand may
    // lack them.
    let computed;
    let leans = if surface.point_leans_deg.len() == rows * n {
        &surface.point_leans_deg
    } else {
        computed = clayloft_core::constraint::point_leans_deg(sections);
        &computed
    };
    let positions: Vec<[f32; 3]> = sections
        .iter()
        .flat_map(|s| s.points.iter().map(|p| to_world(*p).to_array()))
        .collect();
    let at = |k: usize, i: usize| Vec3::from_array(positions[k * n + i]);
    let mut normals = Vec::with_capacity(positions.len());
    for k in 0..rows {
        let (kd, ku) = (k.saturating_sub(1), (k + 1).min(rows - 1));
        for i in 0..n {
            let around = at(k, (i + 1) % n) - at(k, (i + n - 1) % n);
            let up = at(ku, i) - at(kd, i);
            // Contours run counter-clockwise seen from above: around × up points outward.
            normals.push(around.cross(up).normalize_or_zero().to_array());
        }
    }
    let limit = limit_deg as f32;
    let colors: Vec<[f32; 4]> = leans.iter().map(|a| lean_color(*a, limit)).collect();
    let violating = leans.iter().filter(|a| **a > limit + 0.5).count();
    let mut indices = Vec::with_capacity((rows - 1) * n * 6);
    for k in 0..rows - 1 {
        let (r0, r1) = ((k * n) as u32, ((k + 1) * n) as u32);
        for i in 0..n as u32 {
            let j = (i + 1) % n as u32;
            indices.extend_from_slice(&[r0 + i, r0 + j, r1 + j, r0 + i, r1 + j, r1 + i]);
        }
    }
    WallBuffers {
        positions,
        normals,
        colors,
        indices,
        violating,
    }
}

impl WallBuffers {
    /// A Bevy mesh that keeps its data on the CPU too, so it can be rewritten in place.
    pub fn into_mesh(self) -> Mesh {
        Mesh::new(
            PrimitiveTopology::TriangleList,
            RenderAssetUsages::default(),
        )
        .with_inserted_attribute(Mesh::ATTRIBUTE_POSITION, self.positions)
        .with_inserted_attribute(Mesh::ATTRIBUTE_NORMAL, self.normals)
        .with_inserted_attribute(Mesh::ATTRIBUTE_COLOR, self.colors)
        .with_inserted_indices(Indices::U32(self.indices))
    }
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn colours_run_from_clay_to_red() {
        let close = |a: [f32; 4], b: [f32; 4]| a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-6);
        assert!(close(lean_color(0.0, 45.0), [0.80, 0.52, 0.38, 1.0]));
        assert!(close(lean_color(20.0, 45.0), [0.80, 0.52, 0.38, 1.0]));
        assert!(close(lean_color(45.0, 45.0), [0.95, 0.75, 0.20, 1.0]));
        assert!(close(lean_color(50.0, 45.0), [0.90, 0.08, 0.08, 1.0]));
    }

    #[test]
    fn cylinder_mesh_has_outward_normals_and_closed_rings() {
        let d = clayloft_core::load::parse_design(
            "version = 1\n[shape]\nheight = 10.0\nsamples = 36\nbase_layers = 0\n\
             lower = { type = \"circle\", radius = 20.0 }\nupper = { type = \"circle\", radius = 20.0 }\n",
        )
        .unwrap();
        let s = clayloft_core::pipeline::build_surface(&d).unwrap();
        let b = wall_buffers(&s, 45.0);
        assert_eq!(b.positions.len(), 36 * 11);
        assert_eq!(b.indices.len(), 36 * 10 * 6);
        assert_eq!(b.violating, 0);
        let c = crate::coords::to_world(s.center.extend(0.0));
        for (p, nrm) in b.positions.iter().zip(&b.normals) {
            let radial = (Vec3::from_array(*p) - c).with_y(0.0).normalize();
            assert!(radial.dot(Vec3::from_array(*nrm)) > 0.999, "{p:?} {nrm:?}");
        }
    }
}
