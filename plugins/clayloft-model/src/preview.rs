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

/// Steps of the toolpath's colour ramp: finer than an 8-bit colour step of the ramp.
const RAMP_STEPS: usize = 1024;

/// The toolpath's colour at height fraction `f` (0 at the foot, 1 at the rim): blue to warm, so
/// the climb of the spiral reads at a glance.
pub fn toolpath_color(f: f32) -> Color {
    Color::srgb(0.25 + 0.7 * f, 0.55 + 0.2 * (1.0 - f), 1.0 - 0.6 * f)
}

/// The ramp's colours in [`RAMP_STEPS`] steps, linear (as a gizmo keeps them), made once: the
/// sRGB-to-linear conversion is three powers per colour.
fn ramp() -> &'static [LinearRgba] {
    static RAMP: std::sync::OnceLock<Vec<LinearRgba>> = std::sync::OnceLock::new();
    RAMP.get_or_init(|| {
        (0..RAMP_STEPS)
            .map(|i| toolpath_color(i as f32 / (RAMP_STEPS - 1) as f32).into())
            .collect()
    })
}

/// The spiral toolpath as a retained gizmo's line strip in world coordinates, coloured by
/// height ([`toolpath_color`]): what `GizmoAsset::linestrip_gradient` makes, written in one
/// pass over the path (that call converts every colour through `Color`: 14 ns a point, 1 ms for
/// a 360 × 200 design). The colours come from a table of the ramp.
pub fn toolpath_gizmo(path: &clayloft_core::toolpath::Toolpath) -> GizmoAsset {
    let pts = &path.points;
    let top = pts.iter().map(|p| p.pos.z).fold(1.0_f64, f64::max);
    let ramp = ramp();
    // The step nearest the point's height fraction: ⌊x + ½⌋ for x ≥ 0 (no call to `round`,
    // which the baseline x86-64 target makes a library call).
    let last = (RAMP_STEPS - 1) as f64;
    let per_mm = last / top;
    let mut asset = GizmoAsset::new();
    let (mut positions, mut colors) = (
        Vec::with_capacity(pts.len() + 1),
        Vec::with_capacity(pts.len() + 1),
    );
    // One pass over the path (it is read from memory, not cache, at this size).
    for p in pts {
        positions.push(to_world(p.pos));
        let step = ((p.pos.z * per_mm).clamp(0.0, last) + 0.5) as usize;
        colors.push(ramp[step]);
    }
    asset.strip_positions = positions;
    asset.strip_colors = colors;
    // The end of the strip, as `linestrip_gradient` marks it.
    asset.strip_positions.push(Vec3::NAN);
    asset.strip_colors.push(LinearRgba::NAN);
    asset
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The table's colours are the ramp's within a tenth of an 8-bit step, from the foot (blue)
    /// to the rim (warm).
    #[test]
    fn the_toolpath_ramp_runs_from_blue_to_warm() {
        use clayloft_core::toolpath::{PathPoint, Toolpath};
        let points: Vec<PathPoint> = (0..=1000)
            .map(|i| PathPoint {
                pos: bevy::math::DVec3::new(0.0, 0.0, 0.1 * i as f64),
                thickness: 1.0,
                flow: 1.0,
                speed: 20.0,
            })
            .collect();
        let path = Toolpath {
            points,
            ..Toolpath::default()
        };
        let asset = toolpath_gizmo(&path);
        // As `linestrip_gradient` has it: the points, then a NaN to end the strip.
        let mut expected = GizmoAsset::new();
        expected.linestrip_gradient(path.points.iter().map(|p| {
            let f = (p.pos.z / 100.0) as f32;
            (to_world(p.pos), toolpath_color(f))
        }));
        assert_eq!(asset.strip_positions.len(), expected.strip_positions.len());
        for (a, b) in asset.strip_positions.iter().zip(&expected.strip_positions) {
            assert!(a == b || (a.is_nan() && b.is_nan()));
        }
        assert!(asset.strip_colors.last().unwrap().red.is_nan());
        let line: Vec<Color> = asset.strip_colors.iter().map(|c| Color::from(*c)).collect();
        for (p, c) in path.points.iter().zip(&line) {
            let want = toolpath_color((p.pos.z / 100.0) as f32).to_srgba();
            let got = c.to_srgba();
            for (a, b) in [
                (got.red, want.red),
                (got.green, want.green),
                (got.blue, want.blue),
            ] {
                assert!((a - b).abs() < 0.1 / 255.0 + 1e-6, "{got:?} {want:?}");
            }
        }
        let (foot, rim) = (line[0].to_srgba(), line[1000].to_srgba());
        assert!(foot.blue > foot.red && rim.red > rim.blue);
    }
}
