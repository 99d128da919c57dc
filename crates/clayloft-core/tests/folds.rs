//! A belly pushed out of a rose's valleys past their radius of curvature folds the offset wall
//! into swallowtails; the shape cuts them off at their corners and the texture fades over the
//! squeezed columns, so the printed path turns each corner once instead of tracing a loop. A
//! texture deeper than a sharp tip is wide folds it too; it fades there.

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

/// Found by random designs (2026-12-06): a texture deeper than a star's tips are wide. A square
/// wave 1.78 mm deep on a four-pointed star's foot made an X at every tip, every layer (55
/// looping segments); a zig-zag of ±1.41 mm every other point, 37 loops 3.3 mm across. Both
/// printed with every limit holding. The texture now fades where it would fold the wall.
#[test]
fn textures_deeper_than_a_tip_is_wide_print_without_loops() {
    let square_on_tips = r#"
version = 1
name = "star foot, square wave"
[printer]
layer_height = 0.5
[shape]
height = 113.0
samples = 60
base_layers = 3
[shape.lower]
type = "star"
points = 4
outer_radius = 26.75
inner_radius = 13.23
[shape.upper]
type = "ellipse"
rx = 27.12
ry = 24.35
[texture]
combine = "sum"
x = { wave = "square", period = 25, amplitude = 1.78 }
"#;
    let zig_zag = r#"
version = 1
name = "star foot, zig-zag"
[printer]
layer_height = 0.8
[shape]
height = 87.1
samples = 200
base_layers = 0
[shape.lower]
type = "star"
points = 4
outer_radius = 24.53
inner_radius = 16.49
[shape.upper]
type = "spline"
points = [[27.07, 5.97], [-10.00, 14.50], [-12.32, -23.98]]
[texture]
x = { wave = "triangle", period = 4, amplitude = 1.41 }
"#;
    for (text, z_min, window) in [(square_on_tips, 2.0, 30), (zig_zag, 0.9, 60)] {
        let design = clayloft_core::load::parse_design(text).unwrap();
        let job = clayloft_core::run(&design).unwrap();
        let points: Vec<glam::DVec3> = job.toolpath.points.iter().map(|q| q.pos).collect();
        assert_eq!(
            looping_segments(&points, z_min, window),
            0,
            "{}",
            design.name
        );
        let said = job.findings().map(|f| f.to_string()).collect::<Vec<_>>();
        assert!(
            said.iter()
                .any(|f| f.contains("does not fold back on itself")),
            "{}: {said:?}",
            design.name
        );
    }
}

/// Found by random designs (2026-12-06, seed 177): a two-bead wall with a square wave 2.77 mm
/// deep. Where the outer bead's point 0 is a crest's tip that leans back over the flank before
/// it, the straight step to the inner bead's nearest point crossed that flank: a loop reaching
/// 3.4 mm at the seam of five layers, which the checker now refuses. The step now lands on the
/// nearest point of the inner bead it reaches without crossing anything.
#[test]
fn a_two_bead_seam_steps_inward_without_crossing_a_deep_texture() {
    let design = clayloft_core::load::parse_design(
        r#"
version = 1
name = "random 177"
[printer]
layer_height = 0.5
[shape]
height = 84.8
samples = 120
base_layers = 3
walls = 2
[shape.lower]
type = "spline"
points = [[41.92, 8.11], [18.31, 13.91], [10.13, 43.89], [-24.45, 19.30], [-31.43, 1.72], [-16.18, -30.10], [6.09, -31.94], [17.93, -13.67]]
[shape.upper]
type = "circle"
radius = 48.96
[texture]
combine = "sum"
x = { wave = "square", period = 6, amplitude = 2.77 }
"#,
    )
    .unwrap();
    let job = clayloft_core::run(&design).unwrap();
    let points: Vec<glam::DVec3> = job.toolpath.points.iter().map(|q| q.pos).collect();
    assert_eq!(looping_segments(&points, 1.6, 60), 0);
    let limits = clayloft_core::check::Limits::from(&design.printer);
    let report = clayloft_core::check::check_path(&points, &limits);
    assert!(
        !report
            .violations
            .iter()
            .any(|v| v.what == clayloft_core::check::CROSSING),
        "{report}"
    );
}
