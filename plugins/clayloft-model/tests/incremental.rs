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
    let first = (0.7 * layers as f64).floor() as usize;
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
    assert!(status.error.unwrap().contains("printer.layer_height"));
    assert_eq!(surface(&mut app).0.sections, before);
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
            .error
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
    assert!(app.world().resource::<ModelStatus>().error.is_none());
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
