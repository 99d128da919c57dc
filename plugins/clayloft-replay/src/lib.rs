//! The nozzle replay (SPEC §8 "Simulation"): an animated nozzle — tip, tube of `nozzle_length`
//! and the holder above it — follows the spiral at the printer's speeds (times a replay speed);
//! play, pause, scrub. The printed part grows behind it, layer by layer. Every point where the
//! holder would hit the part, or the path overhangs or has nothing under it, is found by the same
//! checker as `clayloft check` ([`clayloft_core::check::check_path`]); passing one is flagged on
//! screen and listed. The checker measures every point against the layers below it (tens of
//! milliseconds to seconds): it runs on a thread of its own, and only while the replay is shown,
//! so that editing never waits for it.

pub mod timeline;

use std::sync::Arc;

use bevy::picking::Pickable;
use bevy::prelude::*;
use clayloft_core::check::{Limits, PathEvent, check_path};
use clayloft_core::view_mesh::WallBuffers;
use clayloft_model::background::Background;
use clayloft_model::coords::to_world;
use clayloft_model::preview::wall_mesh;
use clayloft_model::*;
use clayloft_view::ViewSettings;

pub use timeline::Timeline;

/// Replay state: the panels drive it, the systems follow it.
#[derive(Resource, Debug, Clone, PartialEq)]
pub struct Replay {
    /// The replay is shown (nozzle, growing part) instead of the finished wall.
    pub active: bool,
    pub playing: bool,
    /// Replay speed, times real print time.
    pub speed: f64,
    /// Position in print time, s.
    pub time_s: f64,
}

impl Default for Replay {
    fn default() -> Self {
        Replay {
            active: false,
            playing: false,
            speed: 30.0,
            time_s: 0.0,
        }
    }
}

/// What the replay knows about the current toolpath: its timeline and the checker's events.
#[derive(Resource, Debug, Clone, Default)]
pub struct ReplayPath {
    pub timeline: Timeline,
    pub events: Vec<PathEvent>,
    /// The checker has not yet measured this path (`events` is empty until it has).
    pub checking: bool,
    /// Index of the path point the nozzle is at (or just past).
    pub index: usize,
    /// Events passed so far (an index into `events`).
    pub passed: usize,
}

impl ReplayPath {
    /// The replay of a toolpath: its timeline and every point the checker flags.
    pub fn new(
        path: &clayloft_core::toolpath::Toolpath,
        printer: &clayloft_core::design::Printer,
    ) -> ReplayPath {
        ReplayPath {
            events: flagged_points(path, &Limits::from(printer)),
            checking: false,
            ..ReplayPath::unchecked(path)
        }
    }

    /// The replay of a toolpath before the checker has measured it: its timeline only.
    pub fn unchecked(path: &clayloft_core::toolpath::Toolpath) -> ReplayPath {
        ReplayPath {
            timeline: Timeline::new(path),
            events: Vec::new(),
            checking: true,
            index: 0,
            passed: 0,
        }
    }

    /// Moves the nozzle to print time `t` (s).
    pub fn seek(&mut self, t: f64) {
        self.index = self.timeline.index_at(t);
        let index = self.index;
        self.passed = self.events.partition_point(|e| e.line <= index);
    }

    /// The events the nozzle has passed, most recent last.
    pub fn passed_events(&self) -> &[PathEvent] {
        &self.events[..self.passed]
    }

    /// Whether the point the nozzle is at is flagged (a collision or overhang happening now).
    pub fn flag_now(&self) -> Option<&PathEvent> {
        self.passed
            .checked_sub(1)
            .map(|i| &self.events[i])
            .filter(|e| self.index.saturating_sub(e.line) < 40)
    }
}

/// Every point of `path` the checker flags (collisions, overhangs, unsupported points), in path
/// order.
pub fn flagged_points(path: &clayloft_core::toolpath::Toolpath, limits: &Limits) -> Vec<PathEvent> {
    let points: Vec<_> = path.points.iter().map(|p| p.pos).collect();
    check_path(&points, limits).events
}

/// The checker's run for the replay, on a thread of its own: one at a time; a path edited
/// while one runs waits for it (its result then is dropped) and is checked next.
#[derive(Resource, Default)]
struct ReplayCheck {
    /// The path to check next (it changed since the running check started).
    wanted: Option<(Arc<clayloft_core::toolpath::Toolpath>, Limits)>,
    /// The running check, and whether it is of the current path.
    running: Option<(Background<Vec<PathEvent>>, bool)>,
}

/// Marker of the nozzle's root entity (at the tip).
#[derive(Component, Debug, Clone, Copy)]
pub struct Nozzle;

/// Marker of the holder part of the nozzle (turns red on a collision).
#[derive(Component, Debug, Clone, Copy)]
pub struct NozzleHolder;

/// Marker of the printed-part mesh.
#[derive(Component, Debug, Clone, Copy)]
pub struct PrintedPart;

/// The full wall buffers the printed part is cut from, and the rows shown.
#[derive(Resource, Debug, Clone, Default)]
struct PrintedSource {
    /// The session's mesh of the wall (shared with the view).
    buffers: Arc<WallBuffers>,
    samples: usize,
    rows_shown: usize,
}

#[derive(Resource)]
struct NozzleLook {
    holder_ok: Handle<StandardMaterial>,
    holder_hit: Handle<StandardMaterial>,
}

pub struct ReplayPlugin;

impl Plugin for ReplayPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<Replay>()
            .init_resource::<ReplayPath>()
            .init_resource::<PrintedSource>()
            .init_resource::<ReplayCheck>()
            .add_systems(Startup, spawn_nozzle)
            .add_systems(
                Update,
                (
                    prepare_replay_path,
                    check_replay_path,
                    advance_replay,
                    follow_path,
                    grow_printed_part,
                    swap_wall_for_printed_part,
                    draw_flags,
                    keep_drawing_while_playing,
                )
                    .chain()
                    .in_set(ModelSystems::View),
            );
    }
}

/// The app draws only on input (reactive rendering): a playing replay asks for the next frame.
fn keep_drawing_while_playing(
    replay: Res<Replay>,
    redraw: Option<ResMut<Messages<bevy::window::RequestRedraw>>>,
) {
    if replay.playing
        && let Some(mut redraw) = redraw
    {
        redraw.write(bevy::window::RequestRedraw);
    }
}

fn spawn_nozzle(
    mut commands: Commands,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<StandardMaterial>>,
) {
    let steel = materials.add(StandardMaterial {
        base_color: Color::srgb(0.75, 0.77, 0.8),
        metallic: 0.7,
        perceptual_roughness: 0.35,
        ..default()
    });
    let holder_ok = materials.add(StandardMaterial {
        base_color: Color::srgba(0.35, 0.5, 0.75, 0.8),
        alpha_mode: AlphaMode::Blend,
        ..default()
    });
    let holder_hit = materials.add(StandardMaterial {
        base_color: Color::srgba(0.95, 0.1, 0.1, 0.85),
        emissive: LinearRgba::rgb(2.0, 0.0, 0.0),
        alpha_mode: AlphaMode::Blend,
        ..default()
    });
    commands.insert_resource(NozzleLook {
        holder_ok: holder_ok.clone(),
        holder_hit,
    });
    commands
        .spawn((
            Nozzle,
            Transform::default(),
            Visibility::Hidden,
            Name::new("nozzle"),
        ))
        .with_children(|n| {
            // Unit-height parts, scaled to the printer's nozzle in `follow_path`.
            n.spawn((
                Mesh3d(meshes.add(Cone::new(1.0, 1.0))),
                MeshMaterial3d(steel.clone()),
                Transform::default(),
                NozzlePart::Tip,
                Pickable::IGNORE,
            ));
            n.spawn((
                Mesh3d(meshes.add(Cylinder::new(1.0, 1.0))),
                MeshMaterial3d(steel),
                Transform::default(),
                NozzlePart::Tube,
                Pickable::IGNORE,
            ));
            n.spawn((
                Mesh3d(meshes.add(Cylinder::new(1.0, 1.0))),
                MeshMaterial3d(holder_ok),
                Transform::default(),
                NozzlePart::Holder,
                NozzleHolder,
                Pickable::IGNORE,
            ));
        });
    commands.spawn((
        PrintedPart,
        clayloft_view::wall_mesh_bundle(&mut meshes, &mut materials),
        Visibility::Hidden,
        Name::new("printed part"),
    ));
}

/// The parts of the nozzle model, sized from the printer.
#[derive(Component, Debug, Clone, Copy, PartialEq, Eq)]
enum NozzlePart {
    Tip,
    Tube,
    Holder,
}

/// Holder size drawn above the tube, mm (the collision test uses the plane at its bottom).
const HOLDER_RADIUS: f32 = 14.0;
const HOLDER_HEIGHT: f32 = 35.0;

fn prepare_replay_path(
    path: Query<&ToolpathPath, Changed<ToolpathPath>>,
    vessel: Query<(&VesselSurface, &VesselMesh)>,
    doc: Option<Res<DesignDoc>>,
    mut replay_path: ResMut<ReplayPath>,
    mut source: ResMut<PrintedSource>,
    mut replay: ResMut<Replay>,
    mut check: ResMut<ReplayCheck>,
) {
    let (Some(path), Some(doc)) = (path.iter().next(), doc) else {
        return;
    };
    *replay_path = ReplayPath::unchecked(&path.0);
    check.wanted = Some((Arc::clone(&path.0), Limits::from(&doc.design.printer)));
    if let Some((_, current)) = &mut check.running {
        *current = false;
    }
    replay.time_s = replay.time_s.min(replay_path.timeline.total_s());
    if let Some((surface, mesh)) = vessel.iter().next() {
        *source = PrintedSource {
            buffers: Arc::clone(&mesh.0),
            samples: surface.0.sections.first().map_or(0, |s| s.points.len()),
            rows_shown: usize::MAX,
        };
    }
}

/// Takes the finished check of the current path, and starts the next one while the replay is
/// shown; while one runs, asks for frames so that it is polled (the app draws on input only).
fn check_replay_path(
    replay: Res<Replay>,
    mut path: ResMut<ReplayPath>,
    mut check: ResMut<ReplayCheck>,
    redraw: Option<ResMut<Messages<bevy::window::RequestRedraw>>>,
) {
    if let Some((job, current)) = &mut check.running
        && let Some(result) = job.poll()
    {
        if result.is_err() {
            // A panic in the checker (a bug: its input is a path the core made).
            error!("the replay's check of the path stopped without a result");
        }
        if *current {
            path.events = result.unwrap_or_default();
            path.checking = false;
            path.passed = path.events.partition_point(|e| e.line <= path.index);
        }
        check.running = None;
    }
    if check.running.is_none()
        && replay.active
        && let Some((toolpath, limits)) = check.wanted.take()
    {
        let job = Background::start(move || flagged_points(&toolpath, &limits));
        check.running = Some((job, true));
    }
    if check.running.is_some()
        && let Some(mut redraw) = redraw
    {
        redraw.write(bevy::window::RequestRedraw);
    }
}

fn advance_replay(time: Res<Time>, mut replay: ResMut<Replay>, mut path: ResMut<ReplayPath>) {
    let total = path.timeline.total_s();
    if replay.playing && replay.active {
        replay.time_s += time.delta_secs_f64() * replay.speed;
        if replay.time_s >= total {
            replay.time_s = total;
            replay.playing = false;
        }
    }
    path.seek(replay.time_s);
}

/// A nozzle part, where it sits, and its material (the holder's turns red on a collision).
type NozzlePartItem = (
    &'static NozzlePart,
    &'static mut Transform,
    Option<&'static mut MeshMaterial3d<StandardMaterial>>,
);

fn follow_path(
    replay: Res<Replay>,
    path: Res<ReplayPath>,
    toolpath: Query<&ToolpathPath>,
    doc: Option<Res<DesignDoc>>,
    look: Option<Res<NozzleLook>>,
    mut nozzle: Single<(&mut Transform, &mut Visibility), With<Nozzle>>,
    mut parts: Query<NozzlePartItem, Without<Nozzle>>,
) {
    let (Some(tp), Some(doc), Some(look)) = (toolpath.iter().next(), doc, look) else {
        return;
    };
    let (t, v) = &mut *nozzle;
    *v.as_mut() = if replay.active {
        Visibility::Inherited
    } else {
        Visibility::Hidden
    };
    if !replay.active {
        return;
    }
    if let Some(p) = path.timeline.position_at(&tp.0, replay.time_s) {
        t.translation = to_world(p);
    }
    let p = &doc.design.printer;
    let r = (p.nozzle_diameter as f32 / 2.0).max(0.5);
    let len = p.nozzle_length as f32;
    let colliding = path
        .flag_now()
        .is_some_and(|e| e.what == clayloft_core::check::COLLISION);
    for (part, mut tr, mat) in &mut parts {
        match part {
            NozzlePart::Tip => {
                *tr = Transform::from_xyz(0.0, r * 1.5, 0.0)
                    .with_rotation(Quat::from_rotation_x(std::f32::consts::PI))
                    .with_scale(Vec3::new(r * 1.6, r * 3.0, r * 1.6));
            }
            NozzlePart::Tube => {
                *tr = Transform::from_xyz(0.0, len / 2.0 + r * 1.5, 0.0).with_scale(Vec3::new(
                    r * 1.6,
                    len,
                    r * 1.6,
                ));
            }
            NozzlePart::Holder => {
                *tr = Transform::from_xyz(0.0, len + HOLDER_HEIGHT / 2.0, 0.0)
                    .with_scale(Vec3::new(HOLDER_RADIUS, HOLDER_HEIGHT, HOLDER_RADIUS));
                if let Some(mut m) = mat {
                    let want = if colliding {
                        &look.holder_hit
                    } else {
                        &look.holder_ok
                    };
                    if m.0 != *want {
                        m.0 = want.clone();
                    }
                }
            }
        }
    }
}

/// The printed part: the wall up to the section the nozzle has reached.
fn grow_printed_part(
    replay: Res<Replay>,
    path: Res<ReplayPath>,
    toolpath: Query<&ToolpathPath>,
    vessel: Query<&VesselSurface>,
    mut source: ResMut<PrintedSource>,
    part: Single<&Mesh3d, With<PrintedPart>>,
    mut meshes: ResMut<Assets<Mesh>>,
) {
    if !replay.active || source.samples == 0 {
        return;
    }
    let (Some(tp), Some(surface)) = (toolpath.iter().next(), vessel.iter().next()) else {
        return;
    };
    let z = tp.0.points.get(path.index).map_or(0.0, |p| p.pos.z);
    let rows_total = surface.0.sections.len();
    // Rows whose sections lie wholly below the nozzle are printed.
    let rows = surface
        .0
        .sections
        .partition_point(|s| s.z_range().1 <= z + 1e-6)
        .min(rows_total);
    if rows == source.rows_shown {
        return;
    }
    source.rows_shown = rows;
    // Every vertex (the sheets' rows interleave in the index list, not in the vertex list) and
    // the triangles of the rows printed.
    let wall = &*source.buffers;
    let quads = (rows.saturating_sub(1) * wall.indices_per_row).min(wall.indices.len());
    let printed = WallBuffers {
        positions: wall.positions.clone(),
        normals: wall.normals.clone(),
        colors: wall.colors.clone(),
        indices: wall.indices[..quads].to_vec(),
        ..WallBuffers::default()
    };
    let _ = meshes.insert(part.0.id(), wall_mesh(printed));
}

fn swap_wall_for_printed_part(
    replay: Res<Replay>,
    mut settings: ResMut<ViewSettings>,
    mut part: Single<&mut Visibility, With<PrintedPart>>,
    mut was_active: Local<Option<bool>>,
) {
    if *was_active == Some(replay.active) {
        return;
    }
    // Entering the replay hides the finished wall; leaving it shows it again.
    if was_active.is_some() || replay.active {
        settings.show_wall = !replay.active;
    }
    *was_active = Some(replay.active);
    **part = if replay.active {
        Visibility::Inherited
    } else {
        Visibility::Hidden
    };
}

fn draw_flags(
    replay: Res<Replay>,
    path: Res<ReplayPath>,
    toolpath: Query<&ToolpathPath>,
    mut gizmos: Gizmos,
) {
    let Some(tp) = toolpath.iter().next() else {
        return;
    };
    if !replay.active {
        return;
    }
    for e in path.passed_events() {
        let Some(p) = tp.0.points.get(e.line) else {
            continue;
        };
        let color = if e.what == clayloft_core::check::COLLISION {
            Color::srgb(1.0, 0.1, 0.1)
        } else {
            Color::srgb(1.0, 0.6, 0.0)
        };
        gizmos.sphere(Isometry3d::from_translation(to_world(p.pos)), 1.2, color);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clayloft_core::check::{COLLISION, OVERHANG};

    fn design(text: &str) -> clayloft_core::Design {
        clayloft_core::load::parse_design(text).unwrap()
    }

    #[test]
    fn a_clean_design_has_nothing_to_flag() {
        let d = design(
            "version = 1\n[shape]\nheight = 40.0\nlower = { type = \"circle\", radius = 30.0 }\nupper = { type = \"circle\", radius = 35.0 }\n",
        );
        let job = clayloft_core::run(&d).unwrap();
        let mut r = ReplayPath::new(&job.toolpath, &d.printer);
        assert!(r.events.is_empty());
        r.seek(r.timeline.total_s());
        assert_eq!(r.index, job.toolpath.points.len() - 1);
        assert!(r.flag_now().is_none());
    }

    #[test]
    fn overhangs_and_holder_collisions_are_flagged_as_the_nozzle_passes_them() {
        // A bowl flaring at 53° with enforcement off, under a short nozzle and a wavy rim that
        // rises 12 mm within a layer: overhangs, and the holder hits the rim's crests.
        let d = design(
            "version = 1\n[printer]\nnozzle_length = 8.0\n[shape]\nheight = 30.0\n\
             lower = { type = \"circle\", radius = 30.0 }\nupper = { type = \"circle\", radius = 70.0 }\n\
             [[control.horizontal]]\nat = 1.0\nreach = 0.5\npoints = [[0.0, 0.0], [90.0, 12.0], [180.0, 0.0], [270.0, 12.0]]\n\
             [constraints]\nenforce = false\n",
        );
        let job = clayloft_core::run(&d).unwrap();
        let mut r = ReplayPath::new(&job.toolpath, &d.printer);
        let overhangs = r.events.iter().filter(|e| e.what == OVERHANG).count();
        assert!(overhangs > 100, "{overhangs}");
        assert!(r.events.iter().any(|e| e.what == COLLISION));
        assert!(r.events.windows(2).all(|w| w[0].line <= w[1].line));
        // Before the first flagged point nothing is passed; just after it, it is flagged now.
        let first = r.events[0];
        r.seek(0.0);
        assert_eq!(r.passed, 0);
        let t_first = r.timeline.time_of(first.line);
        r.seek(t_first);
        assert!(r.passed >= 1);
        assert_eq!(
            r.flag_now().map(|e| e.line),
            Some(r.events[r.passed - 1].line)
        );
        r.seek(r.timeline.total_s());
        assert_eq!(r.passed, r.events.len());
    }
}
