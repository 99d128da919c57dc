//! Handle entities made visible and draggable: a small sphere per [`EditHandle`], picked with the
//! mouse or a finger; dragging moves it in the plane its value lives in and writes the value into
//! the design.

use std::collections::HashMap;

use bevy::math::DVec2;
use bevy::picking::Pickable;
use bevy::picking::mesh_picking::{MeshPickingCamera, MeshPickingPlugin, MeshPickingSettings};
use bevy::prelude::*;
use bevy_panorbit_camera::PanOrbitCamera;
use clayloft_model::coords::{from_world, to_world};
use clayloft_model::handles::{HandleFrame, HandleRole, handle_frame, set_handle};
use clayloft_model::*;

use crate::history::{EditInProgress, PanelInUse};
use crate::ray::ray_plane;

/// The handle chosen for precise moves (the gizmo sits on it; the panels show its value).
#[derive(Resource, Debug, Clone, Copy, Default, PartialEq)]
pub struct Selection(pub Option<HandleRole>);

/// A drag under way: which handle, its frame when the drag started, the plane it moves in (world)
/// and where on the handle it was grabbed.
#[derive(Resource, Debug, Clone, Copy, Default)]
pub struct ActiveDrag(pub Option<DragState>);

#[derive(Debug, Clone, Copy)]
pub struct DragState {
    pub role: HandleRole,
    pub frame: HandleFrame,
    pub plane_point: Vec3,
    pub plane_normal: Vec3,
    /// Grab point minus handle centre (world).
    pub grab: Vec3,
}

/// Radius of a handle sphere, mm.
pub const HANDLE_RADIUS: f32 = 2.6;

#[derive(Resource)]
struct HandleLook {
    mesh: Handle<Mesh>,
    lower: Handle<StandardMaterial>,
    upper: Handle<StandardMaterial>,
    vertical: Handle<StandardMaterial>,
    horizontal: Handle<StandardMaterial>,
    selected: Handle<StandardMaterial>,
}

/// Mesh picking as the handles need it (only cameras and entities that opt in are picked); the
/// app adds it once in its third-party set-up.
pub fn picking_setup(app: &mut App) {
    app.add_plugins(MeshPickingPlugin)
        .insert_resource(MeshPickingSettings {
            require_markers: true,
            ..default()
        });
}

pub(crate) fn plugin(app: &mut App) {
    app.init_resource::<Selection>()
        .init_resource::<ActiveDrag>()
        .add_systems(Startup, make_handle_look)
        .add_systems(
            Update,
            (
                mark_picking_camera,
                show_new_handles,
                place_handles,
                colour_selected_handle,
                gate_camera,
            )
                .in_set(ModelSystems::View),
        );
}

fn make_handle_look(
    mut commands: Commands,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<StandardMaterial>>,
) {
    let mut mat = |c: Color| {
        materials.add(StandardMaterial {
            base_color: c,
            emissive: LinearRgba::from(c) * 0.4,
            unlit: false,
            ..default()
        })
    };
    commands.insert_resource(HandleLook {
        mesh: meshes.add(Sphere::new(HANDLE_RADIUS)),
        lower: mat(Color::srgb(1.0, 0.55, 0.1)),
        upper: mat(Color::srgb(1.0, 0.85, 0.2)),
        vertical: mat(Color::srgb(0.2, 0.85, 0.95)),
        horizontal: mat(Color::srgb(0.95, 0.4, 0.9)),
        selected: mat(Color::WHITE),
    });
}

fn mark_picking_camera(
    mut commands: Commands,
    cams: Query<Entity, (With<Camera3d>, Without<MeshPickingCamera>)>,
) {
    for c in &cams {
        commands.entity(c).insert(MeshPickingCamera);
    }
}

fn material_for(look: &HandleLook, role: HandleRole) -> Handle<StandardMaterial> {
    match role {
        HandleRole::Contour {
            contour: ContourRole::Lower,
            ..
        } => look.lower.clone(),
        HandleRole::Contour {
            contour: ContourRole::Upper,
            ..
        } => look.upper.clone(),
        HandleRole::Line {
            kind: LineKind::Vertical,
            ..
        } => look.vertical.clone(),
        HandleRole::Line {
            kind: LineKind::Horizontal,
            ..
        } => look.horizontal.clone(),
    }
}

fn show_new_handles(
    mut commands: Commands,
    look: Option<Res<HandleLook>>,
    new: Query<(Entity, &EditHandle, &HandlePosition), Added<EditHandle>>,
) {
    let Some(look) = look else { return };
    for (e, handle, pos) in &new {
        commands
            .entity(e)
            .insert((
                Mesh3d(look.mesh.clone()),
                MeshMaterial3d(material_for(&look, handle.0)),
                Transform::from_translation(to_world(pos.0)),
                Pickable::default(),
            ))
            .observe(start_drag)
            .observe(drag_handle)
            .observe(end_drag)
            .observe(select_on_click);
    }
}

fn place_handles(mut handles: Query<(&HandlePosition, &mut Transform), Changed<HandlePosition>>) {
    for (pos, mut t) in &mut handles {
        t.translation = to_world(pos.0);
    }
}

fn colour_selected_handle(
    selection: Res<Selection>,
    look: Option<Res<HandleLook>>,
    mut handles: Query<(
        &EditHandle,
        &mut MeshMaterial3d<StandardMaterial>,
        &mut Transform,
    )>,
) {
    let Some(look) = look else { return };
    if !selection.is_changed() {
        return;
    }
    for (h, mut m, mut t) in &mut handles {
        let selected = selection.0 == Some(h.0);
        m.0 = if selected {
            look.selected.clone()
        } else {
            material_for(&look, h.0)
        };
        t.scale = Vec3::splat(if selected { 1.4 } else { 1.0 });
    }
}

/// The camera orbits only when nothing is dragged and the pointer is not over the panels.
fn gate_camera(
    busy: Res<EditInProgress>,
    panel: Res<PanelInUse>,
    mut cams: Query<&mut PanOrbitCamera>,
) {
    // `busy` is set by handle and gizmo drags alike.
    let enabled = !busy.0 && !panel.hovered && !panel.editing;
    for mut c in &mut cams {
        if c.enabled != enabled {
            c.enabled = enabled;
        }
    }
}

/// The plane a handle moves in (world): contour values lie in their contour's horizontal plane;
/// vertical control-line points in the upright plane through the vessel's axis at the line's
/// angle; horizontal control-line points move up and down in an upright plane facing the eye.
pub fn drag_plane_normal(role: HandleRole, frame: &HandleFrame, eye_dir: Vec3) -> Vec3 {
    match role {
        HandleRole::Contour { .. } => Vec3::Y,
        HandleRole::Line {
            kind: LineKind::Vertical,
            ..
        } => {
            let across = DVec2::new(-frame.dir.y, frame.dir.x);
            to_world(across.extend(0.0)).normalize_or(Vec3::X)
        }
        HandleRole::Line {
            kind: LineKind::Horizontal,
            ..
        } => Vec3::new(eye_dir.x, 0.0, eye_dir.z).normalize_or(Vec3::X),
    }
}

/// The current frames of every contour's alignment offset, for [`handle_frame`].
pub fn contour_offsets(
    contours: &Query<(&ContourRole, &ContourSamples)>,
) -> HashMap<ContourRole, DVec2> {
    contours.iter().map(|(r, s)| (*r, s.offset)).collect()
}

fn start_drag(
    ev: On<Pointer<DragStart>>,
    handles: Query<(&EditHandle, &Transform)>,
    doc: Option<Res<DesignDoc>>,
    engine: Res<Engine>,
    contours: Query<(&ContourRole, &ContourSamples)>,
    cams: Query<&GlobalTransform, With<Camera3d>>,
    mut drag: ResMut<ActiveDrag>,
    mut selection: ResMut<Selection>,
    mut busy: ResMut<EditInProgress>,
) {
    let (Ok((handle, t)), Some(doc)) = (handles.get(ev.entity), doc) else {
        return;
    };
    let Some(model) = engine.0.model() else {
        return;
    };
    let Some(frame) = handle_frame(handle.0, &doc.design, model, &contour_offsets(&contours))
    else {
        return;
    };
    let eye = cams
        .iter()
        .next()
        .map_or(Vec3::NEG_Z, |g| g.forward().as_vec3());
    let normal = drag_plane_normal(handle.0, &frame, eye);
    let grab = ev.hit.position.map_or(Vec3::ZERO, |p| p - t.translation);
    drag.0 = Some(DragState {
        role: handle.0,
        frame,
        plane_point: t.translation,
        plane_normal: normal,
        grab,
    });
    selection.0 = Some(handle.0);
    busy.0 = true;
}

fn drag_handle(
    ev: On<Pointer<Drag>>,
    drag: Res<ActiveDrag>,
    cams: Query<(&Camera, &GlobalTransform), With<Camera3d>>,
    doc: Option<ResMut<DesignDoc>>,
) {
    let (Some(state), Some(mut doc)) = (drag.0, doc) else {
        return;
    };
    let Some((o, d)) = pointer_ray(&cams, ev.pointer_location.position) else {
        return;
    };
    let Some(t) = ray_plane(o, d, state.plane_point + state.grab, state.plane_normal) else {
        return;
    };
    move_handle_to(&mut doc, state.role, &state.frame, o + d * t - state.grab);
}

/// The world ray under the pointer: origin and unit direction.
pub(crate) fn pointer_ray(
    cams: &Query<(&Camera, &GlobalTransform), With<Camera3d>>,
    at: Vec2,
) -> Option<(Vec3, Vec3)> {
    let (cam, t) = cams.iter().next()?;
    let ray = cam.viewport_to_world(t, at).ok()?;
    Some((ray.origin, *ray.direction))
}

/// Writes the value that puts the handle at `target` (world) into the design — only if it
/// changes, so change detection stays quiet while the pointer rests.
pub(crate) fn move_handle_to(
    doc: &mut DesignDoc,
    role: HandleRole,
    frame: &HandleFrame,
    target: Vec3,
) {
    let mut edited = doc.design.clone();
    if set_handle(role, &mut edited, frame, from_world(target)) {
        doc.design = edited;
    }
}

fn end_drag(
    _ev: On<Pointer<DragEnd>>,
    mut drag: ResMut<ActiveDrag>,
    mut busy: ResMut<EditInProgress>,
) {
    drag.0 = None;
    busy.0 = false;
}

fn select_on_click(
    ev: On<Pointer<Click>>,
    handles: Query<&EditHandle>,
    mut selection: ResMut<Selection>,
) {
    if let Ok(h) = handles.get(ev.entity) {
        selection.0 = Some(h.0);
    }
}
