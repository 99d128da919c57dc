//! The 3D view (SPEC §8 "View"): an orbit camera, the printer's bed and build volume, the lofted
//! wall coloured by overhang (violating regions in red), the spiral toolpath as lines and the
//! control lines on the surface. It only reads the model's entities.

use bevy::camera::visibility::Visibility;
use bevy::picking::Pickable;
use bevy::prelude::*;
use bevy_panorbit_camera::PanOrbitCamera;
use clayloft_model::coords::to_world;
use clayloft_model::preview::{toolpath_gizmo, wall_mesh};
use clayloft_model::*;

/// What the view shows; the panels toggle these.
#[derive(Resource, Debug, Clone, Copy, PartialEq)]
pub struct ViewSettings {
    pub show_wall: bool,
    pub show_toolpath: bool,
    pub show_control_lines: bool,
    pub show_build_volume: bool,
    /// Colour the wall by its safety factor while printing (SPEC §14) instead of its lean.
    pub colour_by_safety: bool,
}

impl Default for ViewSettings {
    fn default() -> Self {
        ViewSettings {
            show_wall: true,
            show_toolpath: false,
            show_control_lines: true,
            show_build_volume: true,
            colour_by_safety: false,
        }
    }
}

/// Marker of the wall mesh entity.
#[derive(Component, Debug, Clone, Copy)]
pub struct WallView;

/// Marker of the toolpath lines entity.
#[derive(Component, Debug, Clone, Copy)]
pub struct ToolpathView;

/// Marker of the bed entity.
#[derive(Component, Debug, Clone, Copy)]
pub struct BedView;

/// How often the view rebuilt its meshes and lines (tests count them over idle frames: zero).
/// Counted with atomics, so that the systems that rebuild the wall and the lines only read the
/// resource and Bevy runs them side by side.
#[derive(Resource, Debug, Default)]
pub struct ViewRebuilds {
    wall_mesh: std::sync::atomic::AtomicU64,
    toolpath_lines: std::sync::atomic::AtomicU64,
}

/// The counts of [`ViewRebuilds`] at one moment.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct RebuildCounts {
    pub wall_mesh: u64,
    pub toolpath_lines: u64,
}

impl ViewRebuilds {
    pub fn counts(&self) -> RebuildCounts {
        use std::sync::atomic::Ordering::Relaxed;
        RebuildCounts {
            wall_mesh: self.wall_mesh.load(Relaxed),
            toolpath_lines: self.toolpath_lines.load(Relaxed),
        }
    }
}

/// Number of wall points past the overhang limit (for the status line).
#[derive(Resource, Debug, Clone, Copy, Default)]
pub struct WallStats {
    pub violating_points: usize,
}

/// The 3D view.
pub struct ViewPlugin;

impl Plugin for ViewPlugin {
    fn build(&self, app: &mut App) {
        app.add_message::<FrameVessel>()
            .init_resource::<ViewSettings>()
            .init_resource::<WallStats>()
            .init_resource::<ViewRebuilds>()
            .insert_resource(ClearColor(Color::srgb(0.13, 0.14, 0.16)))
            .add_systems(Startup, spawn_scene)
            .add_systems(
                Update,
                (
                    frame_camera_on_first_surface,
                    rebuild_wall_mesh,
                    fade_stale_vessel,
                    rebuild_toolpath_lines,
                    update_bed,
                    apply_view_settings,
                    draw_build_volume,
                    draw_control_lines,
                    keep_drawing_while_the_camera_moves,
                )
                    .in_set(ModelSystems::View),
            );
    }
}

/// The app draws only on input (reactive rendering); the orbit camera eases towards its target
/// after the input stopped, so it asks for frames until it arrives.
fn keep_drawing_while_the_camera_moves(
    cams: Query<&PanOrbitCamera>,
    redraw: Option<ResMut<Messages<bevy::window::RequestRedraw>>>,
) {
    let moving = cams.iter().any(|c| {
        let off = |a: Option<f32>, b: f32| a.is_none_or(|a| (a - b).abs() > 1e-4);
        off(c.yaw, c.target_yaw)
            || off(c.pitch, c.target_pitch)
            || off(c.radius, c.target_radius)
            || c.focus.distance(c.target_focus) > 1e-3
    });
    if moving && let Some(mut redraw) = redraw {
        redraw.write(bevy::window::RequestRedraw);
    }
}

fn spawn_scene(
    mut commands: Commands,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<StandardMaterial>>,
    mut gizmo_assets: ResMut<Assets<GizmoAsset>>,
) {
    commands.spawn((
        PanOrbitCamera {
            focus: Vec3::new(90.0, 60.0, -95.0),
            radius: Some(380.0),
            yaw: Some(0.5),
            pitch: Some(0.45),
            ..default()
        },
        Transform::from_xyz(200.0, 200.0, 200.0),
    ));
    commands.insert_resource(GlobalAmbientLight {
        color: Color::WHITE,
        brightness: 180.0,
        ..default()
    });
    commands.spawn((
        DirectionalLight {
            illuminance: 9000.0,
            shadow_maps_enabled: false,
            ..default()
        },
        Transform::from_xyz(150.0, 300.0, 200.0).looking_at(Vec3::ZERO, Vec3::Y),
    ));
    commands.spawn((
        DirectionalLight {
            illuminance: 2500.0,
            shadow_maps_enabled: false,
            ..default()
        },
        Transform::from_xyz(-200.0, 100.0, -150.0).looking_at(Vec3::ZERO, Vec3::Y),
    ));
    // The wall: vertex colours carry the overhang; both faces lit (the inside shows at the rim).
    commands.spawn((
        WallView,
        wall_mesh_bundle(&mut meshes, &mut materials),
        Name::new("wall view"),
    ));
    let bed_meshes = BedMeshes {
        rectangle: meshes.add(Cuboid::new(1.0, 1.0, 1.0)),
        circle: meshes.add(Cylinder::new(0.5, 1.0).mesh().resolution(96)),
    };
    commands.spawn((
        BedView,
        Mesh3d(bed_meshes.rectangle.clone()),
        bed_meshes,
        MeshMaterial3d(materials.add(StandardMaterial {
            base_color: Color::srgb(0.32, 0.34, 0.38),
            perceptual_roughness: 0.95,
            ..default()
        })),
        Transform::default(),
        Pickable::IGNORE,
        Name::new("bed"),
    ));
    commands.spawn((
        ToolpathView,
        Gizmo {
            handle: gizmo_assets.add(GizmoAsset::new()),
            line_config: GizmoLineConfig {
                width: 1.5,
                ..default()
            },
            depth_bias: -0.001,
        },
        Name::new("toolpath view"),
    ));
}

/// An empty, unpickable wall mesh whose vertex colours carry the overhang, lit on both faces
/// (the inside shows at the rim). The replay's printed part uses the same.
pub fn wall_mesh_bundle(
    meshes: &mut Assets<Mesh>,
    materials: &mut Assets<StandardMaterial>,
) -> impl Bundle {
    (
        Mesh3d(meshes.add(Mesh::from(Cuboid::new(0.0, 0.0, 0.0)))),
        MeshMaterial3d(materials.add(StandardMaterial {
            base_color: Color::WHITE,
            perceptual_roughness: 0.85,
            double_sided: true,
            cull_mode: None,
            ..default()
        })),
        Pickable::IGNORE,
    )
}

/// Asks the view to point the camera at the whole vessel (the panels' button, the F key).
#[derive(Message, Debug, Clone, Copy, Default)]
pub struct FrameVessel;

/// Where the camera looks at a vessel from, and how near and far it may zoom (world units, mm).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraFrame {
    pub focus: Vec3,
    pub radius: f32,
    /// Nearest the camera may come to the focus: outside the sphere around the focus that holds
    /// the whole vessel, so no zoom puts it inside the wall.
    pub min_radius: f32,
    pub max_radius: f32,
}

/// The camera frame of a surface: focus at 40 % of the height over the centre, the whole vessel
/// in view, zoom kept outside the vessel's bounding sphere and within ten times it.
pub fn camera_frame(surface: &clayloft_core::pipeline::Surface, height: f64) -> CameraFrame {
    let focus = surface.center.extend(height * 0.4);
    let (mut lo, mut hi) = (
        bevy::math::DVec2::splat(f64::MAX),
        bevy::math::DVec2::splat(f64::MIN),
    );
    let mut reach: f64 = 1.0;
    for q in surface.sections.iter().flat_map(|s| &s.points) {
        lo = lo.min(q.truncate());
        hi = hi.max(q.truncate());
        reach = reach.max(q.distance(focus));
    }
    let extent = (hi - lo).max_element().max(height).max(1.0);
    let min_radius = (reach * 1.1 + 10.0) as f32;
    let radius = ((extent * 2.4).max(200.0) as f32).max(min_radius * 1.5);
    CameraFrame {
        focus: to_world(focus),
        radius,
        min_radius,
        max_radius: (radius * 10.0).max(min_radius * 10.0),
    }
}

/// Frames the camera on the vessel the first time there is one and whenever asked (the F key
/// outside text fields, the panels' button); the zoom limits follow every new surface.
fn frame_camera_on_first_surface(
    vessel: Query<Ref<VesselSurface>>,
    doc: Option<Res<DesignDoc>>,
    mut camera: Query<&mut PanOrbitCamera>,
    mut asked: MessageReader<FrameVessel>,
    keys: Option<Res<ButtonInput<KeyCode>>>,
    panel: Option<Res<clayloft_edit::PanelInUse>>,
    mut done: Local<bool>,
) {
    let (Some(surface), Some(doc)) = (vessel.iter().next(), doc) else {
        asked.clear();
        return;
    };
    let typing = panel.is_some_and(|p| p.typing);
    let key = !typing && keys.is_some_and(|k| k.just_pressed(KeyCode::KeyF));
    let asked = asked.read().count() > 0 || key;
    if !asked && *done && !surface.is_changed() {
        return;
    }
    let frame = camera_frame(&surface.0, doc.design.shape.height);
    for mut cam in &mut camera {
        cam.zoom_lower_limit = frame.min_radius;
        cam.zoom_upper_limit = Some(frame.max_radius);
        if asked || !*done {
            cam.target_focus = frame.focus;
            cam.focus = frame.focus;
            cam.target_radius = frame.radius;
            cam.radius = Some(frame.radius);
        } else {
            cam.target_radius = cam.target_radius.clamp(frame.min_radius, frame.max_radius);
        }
        cam.force_update = true;
    }
    *done = true;
}

/// The vessel's wall: its surface and beads, with change ticks.
fn rebuild_wall_mesh(
    vessel: Query<Ref<VesselMesh>>,
    verdict: Query<Ref<ToolpathPrintability>>,
    settings: Res<ViewSettings>,
    wall: Single<&Mesh3d, With<WallView>>,
    mut meshes: ResMut<Assets<Mesh>>,
    mut stats: ResMut<WallStats>,
    rebuilds: Res<ViewRebuilds>,
    mut coloured_by_safety: Local<bool>,
) {
    let Some(mesh) = vessel.iter().next() else {
        return;
    };
    let verdict = verdict.iter().next();
    let by_safety = settings.colour_by_safety && verdict.is_some();
    let changed = mesh.is_changed()
        || (by_safety && verdict.as_ref().is_some_and(|v| v.is_changed()))
        || by_safety != *coloured_by_safety;
    if !changed {
        return;
    }
    *coloured_by_safety = by_safety;
    rebuilds
        .wall_mesh
        .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    // The session's buffers are shared with the replay: the asset gets its own copy.
    let mut buffers = (*mesh.0).clone();
    stats.violating_points = buffers.violating;
    if by_safety && let Some(v) = verdict {
        buffers.colour_by_safety(&v.0);
    }
    let _ = meshes.insert(wall.0.id(), wall_mesh(buffers));
}

/// While the design being edited cannot be built, the wall shown is the last one that could: it
/// is drawn faded (grey and see-through) so that nobody takes it for the edit.
fn fade_stale_vessel(
    status: Res<ModelStatus>,
    wall: Single<&MeshMaterial3d<StandardMaterial>, With<WallView>>,
    mut materials: ResMut<Assets<StandardMaterial>>,
) {
    if !status.is_changed() {
        return;
    }
    let (colour, alpha) = if status.is_stale() {
        (Color::srgba(0.6, 0.6, 0.65, 0.35), AlphaMode::Blend)
    } else {
        (Color::WHITE, AlphaMode::Opaque)
    };
    if let Some(m) = materials.get(&wall.0)
        && (m.base_color != colour || m.alpha_mode != alpha)
        && let Some(mut m) = materials.get_mut(&wall.0)
    {
        m.base_color = colour;
        m.alpha_mode = alpha;
    }
}

/// Retained gizmos ignore `Visibility`: a hidden toolpath is an empty line set.
fn rebuild_toolpath_lines(
    path: Query<Ref<ToolpathPath>>,
    settings: Res<ViewSettings>,
    view: Single<&Gizmo, With<ToolpathView>>,
    mut assets: ResMut<Assets<GizmoAsset>>,
    rebuilds: Res<ViewRebuilds>,
) {
    let Some(path) = path.iter().next() else {
        return;
    };
    if !path.is_changed() && !settings.is_changed() {
        return;
    }
    rebuilds
        .toolpath_lines
        .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let asset = if settings.show_toolpath {
        toolpath_gizmo(&path.0)
    } else {
        GizmoAsset::new()
    };
    let _ = assets.insert(view.handle.id(), asset);
}

/// The bed's two shapes: a box for a rectangular bed, a disc for a round one.
#[derive(Component)]
pub struct BedMeshes {
    rectangle: Handle<Mesh>,
    circle: Handle<Mesh>,
}

fn update_bed(
    doc: Option<Res<DesignDoc>>,
    bed: Single<(&mut Transform, &mut Mesh3d, &BedMeshes), With<BedView>>,
) {
    let Some(doc) = doc else { return };
    if !doc.is_changed() {
        return;
    }
    let (mut transform, mut mesh, shapes) = bed.into_inner();
    let p = &doc.design.printer;
    let (x, y) = (p.bed_x as f32, p.bed_y as f32);
    // The bed's top face at z = 0; world (x, z, −y).
    transform.translation = Vec3::new(x / 2.0, -1.0, -y / 2.0);
    transform.scale = Vec3::new(x, 2.0, y);
    let want = match p.bed_shape {
        clayloft_core::design::BedShape::Rectangle => &shapes.rectangle,
        clayloft_core::design::BedShape::Circle => &shapes.circle,
    };
    if mesh.0 != *want {
        mesh.0 = want.clone();
    }
}

fn apply_view_settings(
    settings: Res<ViewSettings>,
    mut wall: Query<&mut Visibility, With<WallView>>,
) {
    if !settings.is_changed() {
        return;
    }
    let vis = |on: bool| {
        if on {
            Visibility::Inherited
        } else {
            Visibility::Hidden
        }
    };
    for mut v in &mut wall {
        *v = vis(settings.show_wall);
    }
}

fn draw_build_volume(settings: Res<ViewSettings>, doc: Option<Res<DesignDoc>>, mut gizmos: Gizmos) {
    let Some(doc) = doc else { return };
    if !settings.show_build_volume {
        return;
    }
    let p = &doc.design.printer;
    let (x, y, z) = (p.bed_x as f32, p.bed_y as f32, p.max_z as f32);
    let center = Vec3::new(x / 2.0, z / 2.0, -y / 2.0);
    let volume = Color::srgba(0.6, 0.7, 0.9, 0.35);
    let grid = Color::srgba(0.55, 0.58, 0.62, 0.5);
    match p.bed_shape {
        clayloft_core::design::BedShape::Rectangle => {
            gizmos.cube(
                Transform::from_translation(center).with_scale(Vec3::new(x, z, y)),
                volume,
            );
            // A 10 mm grid on the bed.
            let mut gx = 0.0;
            while gx <= x {
                gizmos.line(Vec3::new(gx, 0.05, 0.0), Vec3::new(gx, 0.05, -y), grid);
                gx += 10.0;
            }
            let mut gy = 0.0;
            while gy <= y {
                gizmos.line(Vec3::new(0.0, 0.05, -gy), Vec3::new(x, 0.05, -gy), grid);
                gy += 10.0;
            }
        }
        clayloft_core::design::BedShape::Circle => {
            // The round build volume: its floor and ceiling circles and four edges.
            let r = x / 2.0;
            let c = Vec3::new(r, 0.0, -r);
            let flat = Isometry3d::new(c, Quat::from_rotation_x(std::f32::consts::FRAC_PI_2));
            gizmos.circle(flat, r, volume).resolution(96);
            let top = Isometry3d::new(
                c + Vec3::Y * z,
                Quat::from_rotation_x(std::f32::consts::FRAC_PI_2),
            );
            gizmos.circle(top, r, volume).resolution(96);
            for k in 0..4 {
                let a = k as f32 * std::f32::consts::FRAC_PI_2;
                let at = c + Vec3::new(r * a.cos(), 0.0, r * a.sin());
                gizmos.line(at, at + Vec3::Y * z, volume);
            }
            // A 10 mm grid clipped to the disc.
            let mut g = -r + (r % 10.0);
            while g <= r {
                let half = (r * r - g * g).max(0.0).sqrt();
                gizmos.line(
                    c + Vec3::new(g, 0.05, -half),
                    c + Vec3::new(g, 0.05, half),
                    grid,
                );
                gizmos.line(
                    c + Vec3::new(-half, 0.05, g),
                    c + Vec3::new(half, 0.05, g),
                    grid,
                );
                g += 10.0;
            }
        }
    }
}

fn draw_control_lines(
    settings: Res<ViewSettings>,
    lines: Query<(&ControlLine, &ControlLineCurve)>,
    mut gizmos: Gizmos,
) {
    if !settings.show_control_lines {
        return;
    }
    for (line, curve) in &lines {
        let color = match line.kind {
            LineKind::Vertical => Color::srgb(0.2, 0.85, 0.95),
            LineKind::Horizontal => Color::srgb(0.95, 0.4, 0.9),
        };
        gizmos.linestrip(curve.0.iter().map(|p| to_world(*p)), color);
    }
}

#[cfg(test)]
mod camera_tests {
    use super::*;

    /// The nearest zoom keeps the camera outside every wall point (seen from the focus), and the
    /// framed distance lies between the limits.
    #[test]
    fn zoom_stops_outside_the_vessel() {
        for name in ["petal-vase.toml", "flared-bowl.toml", "tilted-rim.toml"] {
            let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("../../assets/designs")
                .join(name);
            let d = clayloft_core::load_design(&path).unwrap().design;
            let job = clayloft_core::run(&d).unwrap();
            let f = camera_frame(&job.surface, d.shape.height);
            for q in job.surface.sections.iter().flat_map(|s| &s.points) {
                assert!(to_world(*q).distance(f.focus) < f.min_radius, "{name}");
            }
            assert!(
                f.min_radius < f.radius && f.radius < f.max_radius,
                "{name}: {f:?}"
            );
        }
    }
}
