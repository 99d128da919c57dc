//! A belly pushed out of a rose's valleys past their radius of curvature folds the offset wall
//! into swallowtails; the shape cuts them off at their corners and the texture fades over the
//! squeezed columns, so the printed path turns each corner once instead of tracing a loop.

use clayloft_core::geometry::segments_intersect;
use glam::DVec2;
use std::path::Path;

/// Segments of the path above `z_min` that the path crosses again within `window` points: the
/// small loops a fold (or a texture folded at a corner) would make.
fn looping_segments(points: &[glam::DVec3], z_min: f64, window: usize) -> usize {
    let xy: Vec<DVec2> = points.iter().map(|p| p.truncate()).collect();
    (0..xy.len().saturating_sub(1))
        .filter(|&i| points[i + 1].z > z_min)
        .filter(|&i| {
            (i + 2..(i + window).min(xy.len() - 1))
                .any(|j| segments_intersect(xy[i], xy[i + 1], xy[j], xy[j + 1]))
        })
        .count()
}

fn toolpath_of(path: &str) -> Vec<glam::DVec3> {
    let file = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join(path);
    let design = clayloft_core::load::load_design(&file).unwrap().design;
    let job = clayloft_core::run(&design).unwrap();
    job.toolpath.points.iter().map(|q| q.pos).collect()
}

/// The petal vase (the app's first design): its belly folds its six valleys in 71 of its
/// sections, 417 segments of its path looped before the folds were cut off. The benchmark vase:
/// 1 755. Now none, above the base (whose rings turn sharply by design).
#[test]
fn bellied_roses_print_without_loops() {
    for (design, z_min) in [
        ("assets/designs/petal-vase.toml", 1.5),
        ("assets/benchmarks/vase-720x300.toml", 1.5),
    ] {
        let points = toolpath_of(design);
        assert!(points.len() > 40_000, "{design}");
        assert_eq!(looping_segments(&points, z_min, 60), 0, "{design}");
    }
}
