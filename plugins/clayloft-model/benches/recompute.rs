//! Interactive speed: one handle drag on a 360-sample × 200-layer design, through the session
//! update (sections in the line's span, constraints, texture, toolpath, and the wall's mesh
//! beside the toolpath), the copy into the entities and into a Bevy mesh, and the toolpath
//! lines. Target: under 8 ms (half a 60 fps frame).

use bevy::math::DVec3;
use bevy::prelude::*;
use clayloft_model::handles::{HandleRole, nudge_handle};
use clayloft_model::preview::{toolpath_gizmo, wall_mesh};
use clayloft_model::*;
use criterion::{Criterion, criterion_group, criterion_main};

const DESIGN: &str = r#"
version = 1
name = "bench 360 x 200"
[printer]
layer_height = 1.0
[shape]
height = 200.0
samples = 360
base_layers = 2
lower = { type = "rose", radius = 40.0, amplitude = 4.0, petals = 6 }
upper = { type = "circle", radius = 34.0 }
[[control.vertical]]
points = [[0.0, 0.0], [0.3, 0.0], [0.5, 8.0], [0.7, 0.0], [1.0, 0.0]]
angle = 90.0
width = 60.0
[[control.vertical]]
points = [[0.0, 0.0], [0.5, -5.0], [1.0, 0.0]]
[texture]
combine = "product"
x = { wave = "sine", period = 20.0, amplitude = 1.0 }
y = { wave = "sine", period = 10.0, amplitude = 1.0 }
"#;

fn drag_once(app: &mut App, sign: f64) {
    let role = HandleRole::Line {
        kind: LineKind::Vertical,
        line: 0,
        point: 2,
    };
    drag(app, role, DVec3::new(0.0, sign, 0.0));
}

fn drag(app: &mut App, role: HandleRole, delta: DVec3) {
    nudge_handle(app.world_mut(), role, delta);
}

/// What the view does with a new wall and toolpath: the session's mesh (built during the update)
/// copied into a Bevy mesh, and the toolpath's coloured lines as a retained gizmo. The view's two
/// systems that do this share no data Bevy guards (they only read the rebuild counters), so
/// Bevy's executor runs them side by side: here on the two cores as well.
fn rebuild_mesh(app: &mut App) {
    let world = app.world_mut();
    let mesh = world
        .query::<&VesselMesh>()
        .single(world)
        .unwrap()
        .0
        .clone();
    let path = world
        .query::<&ToolpathPath>()
        .single(world)
        .unwrap()
        .0
        .clone();
    clayloft_core::parallel::both(
        true,
        || std::hint::black_box(wall_mesh((*mesh).clone())),
        || std::hint::black_box(toolpath_gizmo(&path)),
    );
}

fn bench(c: &mut Criterion) {
    let design = clayloft_core::load::parse_design(DESIGN).unwrap();
    let mut app = App::new();
    app.add_plugins((MinimalPlugins, ModelPlugin));
    app.insert_resource(DesignDoc { design, path: None });
    app.update();
    let mut sign = 1.0;
    c.bench_function("drag_local_line_360x200_recompute_and_mesh", |b| {
        b.iter(|| {
            sign = -sign;
            drag_once(&mut app, sign);
            app.update();
            rebuild_mesh(&mut app);
        })
    });
    // A contour handle: resample that contour, rebuild the loft, reshape every section.
    let radius = HandleRole::Contour {
        contour: ContourRole::Upper,
        param: clayloft_model::handles::ContourParam::Radius,
    };
    c.bench_function("drag_upper_contour_360x200_recompute_and_mesh", |b| {
        b.iter(|| {
            sign = -sign;
            drag(&mut app, radius, DVec3::new(0.5 * sign, 0.0, 0.0));
            app.update();
            rebuild_mesh(&mut app);
        })
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
