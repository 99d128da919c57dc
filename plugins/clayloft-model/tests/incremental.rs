//! Headless app tests (MinimalPlugins, no window): handle moves recompute exactly the sections
//! that depend on them, and the result equals the core pipeline's output for the same design.

use std::path::Path;

use bevy::prelude::*;
use clayloft_core::Design;
use clayloft_model::handles::{HandleRole, nudge_handle};
use clayloft_model::*;

fn app_with(design: Design) -> App {
    let mut app = App::new();
    app.add_plugins((MinimalPlugins, ModelPlugin));
    app.insert_resource(DesignDoc { design, path: None });
    app.update();
    app
}

fn load(name: &str) -> Design {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../assets/designs")
        .join(name);
    clayloft_core::load_design(&path).unwrap().design
}

fn surface(app: &mut App) -> VesselSurface {
    let mut q = app.world_mut().query::<&VesselSurface>();
    q.single(app.world()).unwrap().clone()
}

fn toolpath(app: &mut App) -> ToolpathPath {
    let mut q = app.world_mut().query::<&ToolpathPath>();
    q.single(app.world()).unwrap().clone()
}

/// The app's surface and toolpath are exactly the core pipeline's for the current design.
fn assert_matches_pipeline(app: &mut App) {
    let design = app.world().resource::<DesignDoc>().design.clone();
    let job = clayloft_core::run(&design).unwrap();
    let s = surface(app);
    assert_eq!(s.0.layers, job.surface.layers);
    assert_eq!(s.0.sections, job.surface.sections);
    assert_eq!(s.0.findings, job.surface.findings);
    assert_eq!(toolpath(app).0.points, job.toolpath.points);
}

/// Drags the handle of `role` to where it is plus `delta` (design space, mm).
fn drag(app: &mut App, role: HandleRole, delta: bevy::math::DVec3) {
    assert!(nudge_handle(app.world_mut(), role, delta));
}

/// How many entities have component `C`.
fn count<C: Component>(app: &mut App) -> usize {
    app.world_mut().query::<&C>().iter(app.world()).count()
}

#[test]
fn first_frame_builds_everything_and_matches_the_pipeline() {
    let mut app = app_with(load("pebble-spout.toml"));
    let log = app.world().resource::<RecomputeLog>().clone();
    let layers = surface(&mut app).0.layers;
    assert_eq!(log.passes, 1);
    assert_eq!(log.resampled, ContourRole::BOTH.to_vec());
    assert_eq!(log.sections, (0..=layers).collect::<Vec<_>>());
    assert_matches_pipeline(&mut app);
    // One entity per section, per handle (6 + 6 spline points, 3 + 3 line points), per line.
    let sections = count::<SectionIndex>(&mut app);
    assert_eq!(sections, layers + 1);
    let handles = count::<EditHandle>(&mut app);
    assert_eq!(handles, 18);
    let lines = count::<ControlLine>(&mut app);
    assert_eq!(lines, 2);
}

#[test]
fn no_change_no_recompute() {
    let mut app = app_with(load("pebble-spout.toml"));
    for _ in 0..5 {
        app.update();
    }
    assert_eq!(app.world().resource::<RecomputeLog>().passes, 1);
}

#[test]
fn local_line_handle_recomputes_only_its_span() {
    let mut app = app_with(load("pebble-spout.toml"));
    let layers = surface(&mut app).0.layers;
    // The spout line is zero up to t = 0.7, then grows to the rim.
    let tip = HandleRole::Line {
        kind: LineKind::Vertical,
        line: 0,
        point: 2,
    };
    drag(&mut app, tip, bevy::math::DVec3::new(3.0, 0.0, 0.0));
    app.update();
    let log = app.world().resource::<RecomputeLog>().clone();
    assert_eq!(log.passes, 2);
    assert!(log.resampled.is_empty());
    // Exactly the sections above t = 0.7, where the line's offset is not zero.
    let first = (0.7 * layers as f64).floor() as usize + 1;
    assert_eq!(log.sections, (first..=layers).collect::<Vec<_>>());
    assert!(log.sections.len() < layers / 2);
    assert_matches_pipeline(&mut app);
}

#[test]
fn contour_handle_resamples_that_contour_then_all_sections() {
    let mut app = app_with(load("pebble-spout.toml"));
    let p = HandleRole::Contour {
        contour: ContourRole::Upper,
        param: handles::ContourParam::Point(1),
    };
    drag(&mut app, p, bevy::math::DVec3::new(0.0, 4.0, 0.0));
    app.update();
    let log = app.world().resource::<RecomputeLog>().clone();
    assert_eq!(log.resampled, vec![ContourRole::Upper]);
    assert_eq!(log.sections.len(), surface(&mut app).0.layers + 1);
    assert_matches_pipeline(&mut app);
}

#[test]
fn texture_edit_reshapes_no_section() {
    let mut app = app_with(load("ellipse-ripple.toml"));
    {
        let mut doc = app.world_mut().resource_mut::<DesignDoc>();
        let tex = doc.design.texture.as_mut().unwrap();
        tex.phase_drift += 0.5;
    }
    app.update();
    let log = app.world().resource::<RecomputeLog>().clone();
    assert_eq!(log.passes, 2);
    assert!(log.sections.is_empty() && log.resampled.is_empty());
    assert_matches_pipeline(&mut app);
}

#[test]
fn height_edit_replans_layers_and_respawns_sections() {
    let mut app = app_with(load("petal-vase.toml"));
    app.world_mut()
        .resource_mut::<DesignDoc>()
        .design
        .shape
        .height -= 30.0;
    app.update();
    let layers = surface(&mut app).0.layers;
    let sections = count::<SectionIndex>(&mut app);
    assert_eq!(sections, layers + 1);
    assert_matches_pipeline(&mut app);
}

#[test]
fn invalid_edit_keeps_the_last_good_surface_and_says_why() {
    let mut app = app_with(load("petal-vase.toml"));
    let before = surface(&mut app).0.sections.clone();
    app.world_mut()
        .resource_mut::<DesignDoc>()
        .design
        .printer
        .layer_height = -1.0;
    app.update();
    let status = app.world().resource::<ModelStatus>().clone();
    assert!(status.error().unwrap().contains("printer.layer_height"));
    assert!(status.is_stale());
    assert_eq!(surface(&mut app).0.sections, before);
    // Two problems at once: both are listed, each under its own field.
    app.world_mut()
        .resource_mut::<DesignDoc>()
        .design
        .printer
        .print_speed = -5.0;
    app.update();
    let status = app.world().resource::<ModelStatus>().clone();
    assert!(
        status.for_field("printer.layer_height").is_some(),
        "{status:?}"
    );
    assert!(
        status.for_field("printer.print_speed").is_some(),
        "{status:?}"
    );
    app.world_mut()
        .resource_mut::<DesignDoc>()
        .design
        .printer
        .print_speed = 20.0;
    // A design too wide for the bed fails after the sections were reshaped; fixing it rebuilds.
    app.world_mut()
        .resource_mut::<DesignDoc>()
        .design
        .printer
        .layer_height = 1.0;
    app.world_mut()
        .resource_mut::<DesignDoc>()
        .design
        .printer
        .bed_x = 50.0;
    app.update();
    assert!(
        app.world()
            .resource::<ModelStatus>()
            .error()
            .as_ref()
            .unwrap()
            .contains("bed")
    );
    app.world_mut()
        .resource_mut::<DesignDoc>()
        .design
        .printer
        .bed_x = 180.0;
    app.update();
    assert!(app.world().resource::<ModelStatus>().errors.is_empty());
    assert_matches_pipeline(&mut app);
}

#[test]
fn removing_a_control_line_removes_its_entities() {
    let mut app = app_with(load("pebble-spout.toml"));
    app.world_mut()
        .resource_mut::<DesignDoc>()
        .design
        .control
        .vertical
        .remove(0);
    app.update();
    app.update();
    let lines = count::<ControlLine>(&mut app);
    assert_eq!(lines, 1);
    let handles = count::<EditHandle>(&mut app);
    assert_eq!(handles, 15);
    assert_matches_pipeline(&mut app);
}

/// Distance from `p` to the closed polyline `ring` (3D).
fn distance_to_ring(p: bevy::math::DVec3, ring: &[bevy::math::DVec3]) -> f64 {
    (0..ring.len())
        .map(|j| {
            let (a, b) = (ring[j], ring[(j + 1) % ring.len()]);
            let ab = b - a;
            let f = if ab.length_squared() > 0.0 {
                ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0)
            } else {
                0.0
            };
            p.distance(a + ab * f)
        })
        .fold(f64::INFINITY, f64::min)
}

/// On every shipped design, the control-line curves the view draws and the control-line
/// handles the user drags lie on the shaped wall (the section the printer lays at that height)
/// within 0.01 mm — on stars, splines and traced pictures, where a radial push leaves the wall.
#[test]
fn control_lines_and_their_handles_lie_on_the_wall_of_every_shipped_design() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/designs");
    let mut names: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|n| n.ends_with(".toml"))
        .collect();
    names.sort();
    let mut checked = 0;
    for name in &names {
        let mut app = app_with(load(name));
        let design = app.world().resource::<DesignDoc>().design.clone();
        let engine = app.world().resource::<Engine>();
        let model = engine.0.model().unwrap().clone();
        // Handles of control-line points.
        let mut q = app.world_mut().query::<(&EditHandle, &HandlePosition)>();
        for (handle, pos) in q.iter(app.world()) {
            let HandleRole::Line { kind, line, point } = handle.0 else {
                continue;
            };
            let t = match kind {
                LineKind::Vertical => design.control.vertical[line].points[point][0],
                LineKind::Horizontal => design.control.horizontal[line].at,
            };
            let wall = model.section_at(t).points;
            let d = distance_to_ring(pos.0, &wall);
            assert!(d < 0.01, "{name}: {:?} is {d:.4} mm off the wall", handle.0);
            checked += 1;
        }
        // The drawn curves: vertical ones vertex by vertex on the section entities, horizontal
        // ones on the wall at their height.
        let mut sections: Vec<(usize, Vec<bevy::math::DVec3>)> = app
            .world_mut()
            .query::<(&SectionIndex, &ShapedSection)>()
            .iter(app.world())
            .map(|(k, s)| (k.0, s.0.points.clone()))
            .collect();
        sections.sort_by_key(|(k, _)| *k);
        let mut q = app.world_mut().query::<(&ControlLine, &ControlLineCurve)>();
        for (line, curve) in q.iter(app.world()) {
            assert!(!curve.0.is_empty(), "{name}: {line:?} drawn empty");
            for (k, p) in curve.0.iter().enumerate() {
                let d = match line.kind {
                    LineKind::Vertical => distance_to_ring(*p, &sections[k].1),
                    LineKind::Horizontal => distance_to_ring(
                        *p,
                        &model
                            .section_at(design.control.horizontal[line.index].at)
                            .points,
                    ),
                };
                assert!(
                    d < 0.01,
                    "{name}: {line:?} vertex {k} is {d:.4} mm off the wall"
                );
                checked += 1;
            }
        }
    }
    assert!(checked > 100, "only {checked} points checked");
}

/// Dragging a control-line handle moves it under the pointer: along the wall's normal, the
/// handle lands where it was dragged to (within rounding to 0.001 mm).
#[test]
fn a_dragged_line_handle_lands_where_it_was_dragged() {
    let mut app = app_with(load("pebble-spout.toml"));
    let tip = HandleRole::Line {
        kind: LineKind::Vertical,
        line: 0,
        point: 2,
    };
    let before = handle_at(&mut app, tip);
    let normal = {
        let engine = app.world().resource::<Engine>();
        let model = engine.0.model().unwrap();
        let design = &app.world().resource::<DesignDoc>().design;
        let v = &design.control.vertical[0];
        let i = model.column_at_angle(v.angle.unwrap_or(0.0).to_radians());
        model.wall_frame(i, v.points[2][0], Some(0)).1
    };
    drag(&mut app, tip, (normal * 3.0).extend(0.0));
    app.update();
    let after = handle_at(&mut app, tip);
    let moved = after - before;
    assert!(
        (moved.truncate().dot(normal.normalize()) - 3.0 * normal.length()).abs() < 0.01,
        "moved {moved}"
    );
}

fn handle_at(app: &mut App, role: HandleRole) -> bevy::math::DVec3 {
    let mut q = app.world_mut().query::<(&EditHandle, &HandlePosition)>();
    q.iter(app.world())
        .find(|(h, _)| h.0 == role)
        .map(|(_, p)| p.0)
        .unwrap()
}

#[test]
fn a_mesh_design_builds_its_vessel_without_handles_and_back() {
    let mesh = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/meshes/lobed-vase.stl");
    let from_mesh = clayloft_core::load_design(&mesh).unwrap().design;
    let mut app = app_with(from_mesh.clone());
    assert_eq!(surface(&mut app).0.layers, 90);
    assert_eq!(count::<EditHandle>(&mut app), 0, "a mesh has no handles");
    assert!(app.world().resource::<ModelStatus>().errors.is_empty());
    // A texture edit re-does the surface from the same slices.
    let passes = app.world().resource::<RecomputeLog>().passes;
    let texture = load("ellipse-ripple.toml").texture;
    assert!(texture.is_some());
    app.world_mut().resource_mut::<DesignDoc>().design.texture = texture;
    app.update();
    let log = app.world().resource::<RecomputeLog>().clone();
    assert_eq!(log.passes, passes + 1);
    assert!(
        log.update.surface && !log.update.plan && log.update.sections.is_empty(),
        "{log:?}"
    );
    // Back to a lofted design: contours, handles and sections return.
    app.world_mut().resource_mut::<DesignDoc>().design = load("pebble-spout.toml");
    app.update();
    app.update();
    assert!(count::<EditHandle>(&mut app) > 0);
    assert_matches_pipeline(&mut app);
}
