//! The move gizmo on the selected handle: an arrow along each direction the handle can move in
//! ([`freedom`]: a radius along itself, a control-line point up and down and in and out, a contour
//! point across the bed plane — upright arrows blue, the others red and green) and, for points
//! free in the bed plane, a square that moves them parallel to the bed. Dragging an arrow moves
//! the handle only along it. Built on picking like the handles (the transform-gizmo crate needs
//! a newer compiler than ours).

use bevy::picking::Pickable;
use bevy::prelude::*;
use clayloft_model::coords::to_world;
use clayloft_model::handles::{Direction, HandleFrame, HandleRole, freedom, handle_frame};
use clayloft_model::*;

use crate::drag::{Selection, contour_offsets, move_handle_to, pointer_ray};
use crate::history::EditInProgress;
use crate::ray::{ray_axis, ray_plane};

/// Length of an arrow, mm.
const ARROW: f32 = 22.0;

/// The gizmo's root entity, placed on the selected handle.
#[derive(Component, Debug, Clone, Copy)]
pub struct MoveGizmo;

/// Arrow `0`, `1` or `2` of the gizmo: the handle's free directions in order.
#[derive(Component, Debug, Clone, Copy, PartialEq, Eq)]
pub struct GizmoArrow(pub usize);

/// The arrows' colours: upright, first and second bed-plane direction.
#[derive(Resource)]
struct GizmoLook {
    upright: Handle<StandardMaterial>,
    first: Handle<StandardMaterial>,
    second: Handle<StandardMaterial>,
}

/// One grabbable part of the gizmo.
#[derive(Component, Debug, Clone, Copy, PartialEq)]
pub enum GizmoPart {
    /// Move along this world direction.
    Axis(Vec3),
    /// Move in the horizontal (bed) plane.
    BedPlane,
}

/// A gizmo drag under way.
#[derive(Resource, Debug, Clone, Copy, Default)]
pub struct GizmoDrag(Option<GizmoDragState>);

#[derive(Debug, Clone, Copy)]
struct GizmoDragState {
    part: GizmoPart,
    role: HandleRole,
    frame: HandleFrame,
    /// Handle position at the start (world).
    start: Vec3,
    /// Axis parameter or plane point where the pointer grabbed.
    grab_s: f32,
    grab_point: Vec3,
}

pub(crate) fn plugin(app: &mut App) {
    app.init_resource::<GizmoDrag>()
        .add_systems(Startup, spawn_gizmo)
        .add_systems(Update, follow_selection.in_set(ModelSystems::View));
}

fn spawn_gizmo(
    mut commands: Commands,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<StandardMaterial>>,
) {
    let mut mat = |c: Color| {
        materials.add(StandardMaterial {
            base_color: c,
            unlit: true,
            ..default()
        })
    };
    let look = GizmoLook {
        first: mat(Color::srgb(0.95, 0.2, 0.2)),
        second: mat(Color::srgb(0.2, 0.9, 0.3)),
        upright: mat(Color::srgb(0.25, 0.45, 1.0)),
    };
    let plane = mat(Color::srgba(0.95, 0.9, 0.3, 0.8));
    let shaft = meshes.add(Cuboid::new(1.2, 1.2, ARROW));
    let square = meshes.add(Cuboid::new(7.0, 0.6, 7.0));
    commands
        .spawn((
            MoveGizmo,
            Transform::default(),
            Visibility::Hidden,
            Name::new("move gizmo"),
        ))
        .with_children(|root| {
            for i in 0..3 {
                root.spawn((
                    GizmoArrow(i),
                    GizmoPart::Axis(Vec3::Y),
                    Mesh3d(shaft.clone()),
                    MeshMaterial3d(look.upright.clone()),
                    Transform::default(),
                    Visibility::Hidden,
                    Pickable::default(),
                ))
                .observe(start_gizmo_drag)
                .observe(gizmo_drag)
                .observe(end_gizmo_drag);
            }
            root.spawn((
                GizmoPart::BedPlane,
                Mesh3d(square),
                MeshMaterial3d(plane),
                Transform::from_xyz(8.0, 0.0, -8.0),
                Visibility::Hidden,
                Pickable::default(),
            ))
            .observe(start_gizmo_drag)
            .observe(gizmo_drag)
            .observe(end_gizmo_drag);
        });
    commands.insert_resource(look);
}

/// The arrow along world direction `a`, its shaft starting a little off the handle.
fn arrow_transform(a: Vec3) -> Transform {
    Transform::from_translation(a * (ARROW / 2.0 + 3.0))
        .looking_to(a, if a.y.abs() > 0.9 { Vec3::X } else { Vec3::Y })
}

/// Puts the gizmo on the selected handle with an arrow per direction it moves in.
#[allow(clippy::type_complexity)]
fn follow_selection(
    selection: Res<Selection>,
    doc: Option<Res<DesignDoc>>,
    engine: Res<Engine>,
    look: Option<Res<GizmoLook>>,
    contours: Query<(&ContourRole, &ContourSamples)>,
    handles: Query<(&EditHandle, &Transform), (Without<MoveGizmo>, Without<GizmoPart>)>,
    mut gizmo: Single<(&mut Transform, &mut Visibility), With<MoveGizmo>>,
    mut parts: Query<
        (
            &mut GizmoPart,
            Option<&GizmoArrow>,
            &mut Transform,
            &mut Visibility,
            &mut MeshMaterial3d<StandardMaterial>,
        ),
        Without<MoveGizmo>,
    >,
    drag: Res<GizmoDrag>,
) {
    let placed = selection
        .0
        .and_then(|role| handles.iter().find(|(h, _)| h.0 == role))
        .map(|(h, t)| (h.0, t.translation));
    let (t, v) = &mut *gizmo;
    let (Some((role, at)), Some(doc), Some(look)) = (placed, doc, look) else {
        v.set_if_neq(Visibility::Hidden);
        return;
    };
    t.translation = at;
    v.set_if_neq(Visibility::Inherited);
    // The arrows are re-aimed between drags (a drag keeps the frame it started with).
    if drag.0.is_some() {
        return;
    }
    let Some(model) = engine.0.model() else {
        return;
    };
    let Some(frame) = handle_frame(role, &doc.design, model, &contour_offsets(&contours)) else {
        return;
    };
    let free = freedom(role, &doc.design);
    let dirs: Vec<(Direction, Vec3)> = free
        .directions
        .iter()
        .map(|d| (*d, to_world(d.design(&frame))))
        .filter(|(_, w)| w.length_squared() > 1e-6)
        .collect();
    let in_plane =
        free.directions.contains(&Direction::X) && free.directions.contains(&Direction::Y);
    let mut flat = 0;
    for (mut part, arrow, mut transform, mut vis, mut material) in &mut parts {
        let shown = match arrow {
            Some(GizmoArrow(i)) => match dirs.get(*i) {
                Some(&(kind, w)) => {
                    part.set_if_neq(GizmoPart::Axis(w.normalize()));
                    transform.set_if_neq(arrow_transform(w.normalize()));
                    let m = if kind == Direction::Z {
                        look.upright.clone()
                    } else {
                        flat += 1;
                        if flat == 1 {
                            look.first.clone()
                        } else {
                            look.second.clone()
                        }
                    };
                    if material.0 != m {
                        material.0 = m;
                    }
                    true
                }
                None => false,
            },
            None => in_plane,
        };
        vis.set_if_neq(if shown {
            Visibility::Inherited
        } else {
            Visibility::Hidden
        });
    }
}

fn start_gizmo_drag(
    ev: On<Pointer<DragStart>>,
    parts: Query<&GizmoPart>,
    selection: Res<Selection>,
    handles: Query<(&EditHandle, &Transform)>,
    doc: Option<Res<DesignDoc>>,
    engine: Res<Engine>,
    contours: Query<(&ContourRole, &ContourSamples)>,
    cams: Query<(&Camera, &GlobalTransform), With<Camera3d>>,
    mut drag: ResMut<GizmoDrag>,
    mut busy: ResMut<EditInProgress>,
) {
    let (Ok(part), Some(role), Some(doc)) = (parts.get(ev.entity), selection.0, doc) else {
        return;
    };
    let Some((_, t)) = handles.iter().find(|(h, _)| h.0 == role) else {
        return;
    };
    let Some(model) = engine.0.model() else {
        return;
    };
    let Some(frame) = handle_frame(role, &doc.design, model, &contour_offsets(&contours)) else {
        return;
    };
    let Some((o, d)) = pointer_ray(&cams, ev.pointer_location.position) else {
        return;
    };
    let start = t.translation;
    let (grab_s, grab_point) = match part {
        GizmoPart::Axis(a) => (ray_axis(o, d, start, *a).unwrap_or(0.0), start),
        GizmoPart::BedPlane => (
            0.0,
            ray_plane(o, d, start, Vec3::Y).map_or(start, |t| o + d * t),
        ),
    };
    drag.0 = Some(GizmoDragState {
        part: *part,
        role,
        frame,
        start,
        grab_s,
        grab_point,
    });
    busy.0 = true;
}

fn gizmo_drag(
    ev: On<Pointer<Drag>>,
    drag: Res<GizmoDrag>,
    cams: Query<(&Camera, &GlobalTransform), With<Camera3d>>,
    doc: Option<ResMut<DesignDoc>>,
) {
    let (Some(s), Some(mut doc)) = (drag.0, doc) else {
        return;
    };
    let Some((o, d)) = pointer_ray(&cams, ev.pointer_location.position) else {
        return;
    };
    let target = match s.part {
        GizmoPart::Axis(a) => match ray_axis(o, d, s.start, a) {
            Some(sv) => s.start + a * (sv - s.grab_s),
            None => return,
        },
        GizmoPart::BedPlane => match ray_plane(o, d, s.grab_point, Vec3::Y) {
            Some(t) => s.start + (o + d * t - s.grab_point),
            None => return,
        },
    };
    move_handle_to(&mut doc, s.role, &s.frame, target);
}

fn end_gizmo_drag(
    _ev: On<Pointer<DragEnd>>,
    mut drag: ResMut<GizmoDrag>,
    mut busy: ResMut<EditInProgress>,
) {
    drag.0 = None;
    busy.0 = false;
}
