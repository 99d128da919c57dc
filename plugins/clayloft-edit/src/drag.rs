//! Handle entities made visible and draggable: a small sphere per [`EditHandle`], picked with the
//! mouse or a finger; dragging moves it in the plane its value lives in and writes the value into
//! the design.
//!
//! Handles drawn on the same spot (at 0° the rim radius and the ends of the control lines meet)
//! form a stack: a click on it picks one, the next click the next one ([`next_pick`]), and a drag
//! starting there moves the picked one. A drag that cannot move the handle (across its free
//! directions, [`freedom`]) says why in [`DragHint`].

use std::collections::HashMap;

use bevy::math::DVec2;
use bevy::picking::Pickable;
use bevy::picking::mesh_picking::{MeshPickingCamera, MeshPickingPlugin, MeshPickingSettings};
use bevy::prelude::*;
use bevy_panorbit_camera::PanOrbitCamera;
use clayloft_model::coords::{from_world, to_world};
use clayloft_model::handles::{
    HandleFrame, HandleRole, describe, freedom, handle_frame, handle_roles, next_pick, set_handle,
};
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
    /// How far the pointer has moved since the drag started, logical pixels (a press that
    /// barely moves is a click).
    pub moved_px: f32,
    /// Whether the drag changed the design yet.
    pub changed: bool,
    /// The selection before the press (a press that stays a click picks from it).
    pub selection_before: Option<HandleRole>,
}

/// Why the last drag did not move its handle, or which handle a click picked: shown in the
/// status line; replaced by the next pick or drag.
#[derive(Resource, Debug, Clone, Default, PartialEq)]
pub struct DragHint(pub Option<String>);

/// Screen distance, logical pixels, within which handles count as drawn on the same spot.
pub const STACK_PX: f32 = 10.0;

/// Pointer travel, logical pixels, past which a press is a drag and no longer a click.
const CLICK_SLOP_PX: f32 = 4.0;

/// Pointer travel, logical pixels, past which a drag that changed nothing is told why.
const LOCKED_PX: f32 = 25.0;

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
        .init_resource::<DragHint>()
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

/// The handles drawn on the same spot as `entity`'s handle (itself included), in the design's
/// handle order: within [`STACK_PX`] of it on screen, or — where the camera cannot project, as
/// in a headless app — whose spheres overlap in space.
fn stack_at(
    entity: Entity,
    handles: &Query<(Entity, &EditHandle, &GlobalTransform)>,
    cams: &Query<(&Camera, &GlobalTransform), With<Camera3d>>,
    design: &clayloft_core::Design,
) -> Vec<HandleRole> {
    let Ok((_, _, hit)) = handles.get(entity) else {
        return vec![];
    };
    let on_screen = |g: &GlobalTransform| {
        let (cam, eye) = cams.iter().next()?;
        cam.world_to_viewport(eye, g.translation()).ok()
    };
    let same_spot = |g: &GlobalTransform| match (on_screen(hit), on_screen(g)) {
        (Some(a), Some(b)) => a.distance(b) <= STACK_PX,
        _ => hit.translation().distance(g.translation()) <= 2.0 * HANDLE_RADIUS,
    };
    let near: Vec<HandleRole> = handles
        .iter()
        .filter(|(_, _, g)| same_spot(g))
        .map(|(_, h, _)| h.0)
        .collect();
    handle_roles(design)
        .into_iter()
        .filter(|r| near.contains(r))
        .collect()
}

#[allow(clippy::too_many_arguments)]
fn start_drag(
    ev: On<Pointer<DragStart>>,
    handles: Query<(Entity, &EditHandle, &GlobalTransform)>,
    doc: Option<Res<DesignDoc>>,
    engine: Res<Engine>,
    contours: Query<(&ContourRole, &ContourSamples)>,
    cams: Query<(&Camera, &GlobalTransform), With<Camera3d>>,
    mut drag: ResMut<ActiveDrag>,
    mut selection: ResMut<Selection>,
    mut busy: ResMut<EditInProgress>,
) {
    let (Ok((_, hit, _)), Some(doc)) = (handles.get(ev.entity), doc) else {
        return;
    };
    let Some(model) = engine.0.model() else {
        return;
    };
    // On a stack, the handle picked by clicking is the one dragged.
    let stack = stack_at(ev.entity, &handles, &cams, &doc.design);
    let role = selection.0.filter(|s| stack.contains(s)).unwrap_or(hit.0);
    let Some(translation) = handles
        .iter()
        .find(|(_, h, _)| h.0 == role)
        .map(|(_, _, g)| g.translation())
    else {
        return;
    };
    let Some(frame) = handle_frame(role, &doc.design, model, &contour_offsets(&contours)) else {
        return;
    };
    let eye = cams
        .iter()
        .next()
        .map_or(Vec3::NEG_Z, |(_, g)| g.forward().as_vec3());
    let normal = drag_plane_normal(role, &frame, eye);
    let grab = ev.hit.position.map_or(Vec3::ZERO, |p| p - translation);
    drag.0 = Some(DragState {
        role,
        frame,
        plane_point: translation,
        plane_normal: normal,
        grab,
        moved_px: 0.0,
        changed: false,
        selection_before: selection.0,
    });
    selection.set_if_neq(Selection(Some(role)));
    busy.0 = true;
}

fn drag_handle(
    ev: On<Pointer<Drag>>,
    mut drag: ResMut<ActiveDrag>,
    cams: Query<(&Camera, &GlobalTransform), With<Camera3d>>,
    doc: Option<ResMut<DesignDoc>>,
    mut hint: ResMut<DragHint>,
) {
    let (Some(state), Some(mut doc)) = (drag.0.as_mut(), doc) else {
        return;
    };
    state.moved_px = state.moved_px.max(ev.distance.length());
    let Some((o, d)) = pointer_ray(&cams, ev.pointer_location.position) else {
        return;
    };
    let Some(t) = ray_plane(o, d, state.plane_point + state.grab, state.plane_normal) else {
        return;
    };
    state.changed |= move_handle_to(&mut doc, state.role, &state.frame, o + d * t - state.grab);
    if !state.changed && state.moved_px > LOCKED_PX {
        hint.set_if_neq(DragHint(Some(locked_hint(state.role, &doc.design))));
    }
}

/// What a drag that cannot move its handle says: which handle, and why that way is fixed.
pub fn locked_hint(role: HandleRole, design: &clayloft_core::Design) -> String {
    format!(
        "{} — {}",
        describe(role, design),
        freedom(role, design).locked
    )
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
/// changes, so change detection stays quiet while the pointer rests. Returns whether it did.
pub(crate) fn move_handle_to(
    doc: &mut ResMut<DesignDoc>,
    role: HandleRole,
    frame: &HandleFrame,
    target: Vec3,
) -> bool {
    let mut edited = doc.design.clone();
    let changed = set_handle(role, &mut edited, frame, from_world(target));
    if changed {
        doc.design = edited;
    }
    changed
}

fn end_drag(
    _ev: On<Pointer<DragEnd>>,
    mut drag: ResMut<ActiveDrag>,
    mut busy: ResMut<EditInProgress>,
) {
    drag.0 = None;
    busy.0 = false;
}

/// A click picks the handle under the pointer, or on a stack the next one ([`next_pick`]); a
/// press that turned into a drag is not a click.
fn select_on_click(
    ev: On<Pointer<Click>>,
    handles: Query<(Entity, &EditHandle, &GlobalTransform)>,
    cams: Query<(&Camera, &GlobalTransform), With<Camera3d>>,
    doc: Option<Res<DesignDoc>>,
    drag: Res<ActiveDrag>,
    mut selection: ResMut<Selection>,
    mut hint: ResMut<DragHint>,
) {
    if drag.0.is_some_and(|d| d.moved_px > CLICK_SLOP_PX) {
        return;
    }
    // A press that moved a little started a drag, which selected already: pick from before it.
    let current = drag.0.map_or(selection.0, |d| d.selection_before);
    let (Ok((_, h, _)), Some(doc)) = (handles.get(ev.entity), doc) else {
        return;
    };
    let stack = stack_at(ev.entity, &handles, &cams, &doc.design);
    let picked = next_pick(&stack, h.0, current);
    selection.set_if_neq(Selection(Some(picked)));
    let mut said = describe(picked, &doc.design);
    if stack.len() > 1 {
        let at = stack.iter().position(|r| *r == picked).unwrap_or(0);
        said += &format!(
            " ({} of {} handles here: click again for the next)",
            at + 1,
            stack.len()
        );
    }
    hint.set_if_neq(DragHint(Some(said)));
}
