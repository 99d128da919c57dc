//! Handles: one entity per editable point of the design, placed on the vessel, and the inverse
//! map from a dragged position back to the design value.
//!
//! Each handle has a [`HandleFrame`] taken from the current model: where its value is measured
//! from and along which direction. Placing is `frame → position`; dragging is `position → value`
//! with the frame captured when the drag started, so the handle stays under the pointer even
//! when the edit moves the frame (a spline point moves the contour's anchor).

use bevy::math::{DVec2, DVec3};
use bevy::prelude::*;
use clayloft_core::Design;
use clayloft_core::design::ContourSpec;
use std::collections::HashMap;

use crate::components::{ContourRole, ContourSamples, EditHandle, HandlePosition, LineKind};
use crate::document::DesignDoc;
use crate::recompute::Engine;
use clayloft_core::shape::ShapeModel;

/// Which value of a contour a handle edits.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ContourParam {
    /// Spline control point i.
    Point(usize),
    /// Circle radius, polygon radius (at its first vertex), rose `radius + amplitude` (at 0°).
    Radius,
    /// Ellipse semi-axis along x.
    RadiusX,
    /// Ellipse semi-axis along y.
    RadiusY,
    /// Star tip radius (at 0°).
    Outer,
    /// Star notch radius (at 180°/points).
    Inner,
}

/// The design value a handle stands for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum HandleRole {
    Contour {
        contour: ContourRole,
        param: ContourParam,
    },
    /// Point `point` (`[t, offset]`) of `control.vertical[line]` or (`[angle, dz]`)
    /// `control.horizontal[line]`.
    Line {
        kind: LineKind,
        line: usize,
        point: usize,
    },
}

/// Where a handle's value is measured from, in the current model (design space):
/// - a contour value from `origin` (the contour's alignment offset) along `dir`;
/// - a vertical line's offset from `origin` (the wall at the point's column and height without
///   this line) along `dir` (the wall's outward normal times the line's angular weight), its
///   height fraction from z / `height`;
/// - a horizontal line's dz from `origin` (the wall there without this point's value) upward,
///   `z_scale` mm per mm of dz (the horizontal-line scale the layer plan chose).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HandleFrame {
    pub origin: DVec3,
    pub dir: DVec2,
    pub height: f64,
    pub z_scale: f64,
}

/// All handle roles a design has, in a stable order.
pub fn handle_roles(design: &Design) -> Vec<HandleRole> {
    let mut roles = Vec::new();
    for contour in ContourRole::BOTH {
        let spec = contour_spec(design, contour);
        let params: Vec<ContourParam> = match spec {
            ContourSpec::Circle { .. } | ContourSpec::Polygon { .. } | ContourSpec::Rose { .. } => {
                vec![ContourParam::Radius]
            }
            ContourSpec::Ellipse { .. } => vec![ContourParam::RadiusX, ContourParam::RadiusY],
            ContourSpec::Star { .. } => vec![ContourParam::Outer, ContourParam::Inner],
            ContourSpec::Spline { points } => (0..points.len()).map(ContourParam::Point).collect(),
            ContourSpec::Image { .. } | ContourSpec::Svg { .. } => vec![],
        };
        roles.extend(
            params
                .into_iter()
                .map(|param| HandleRole::Contour { contour, param }),
        );
    }
    for (line, v) in design.control.vertical.iter().enumerate() {
        roles.extend((0..v.points.len()).map(|point| HandleRole::Line {
            kind: LineKind::Vertical,
            line,
            point,
        }));
    }
    for (line, h) in design.control.horizontal.iter().enumerate() {
        roles.extend((0..h.points.len()).map(|point| HandleRole::Line {
            kind: LineKind::Horizontal,
            line,
            point,
        }));
    }
    roles
}

pub fn contour_spec(design: &Design, role: ContourRole) -> &ContourSpec {
    match role {
        ContourRole::Lower => &design.shape.lower,
        ContourRole::Upper => &design.shape.upper,
    }
}

fn contour_spec_mut(design: &mut Design, role: ContourRole) -> &mut ContourSpec {
    match role {
        ContourRole::Lower => &mut design.shape.lower,
        ContourRole::Upper => &mut design.shape.upper,
    }
}

/// Direction (unit, spec coordinates) of a radial contour parameter.
fn param_dir(spec: &ContourSpec, param: ContourParam) -> DVec2 {
    match (spec, param) {
        (ContourSpec::Star { points, .. }, ContourParam::Inner) => {
            DVec2::from_angle(std::f64::consts::PI / (*points).max(1) as f64)
        }
        (_, ContourParam::RadiusY) => DVec2::Y,
        _ => DVec2::X,
    }
}

/// The frame of a handle in the current model; `None` if the role does not exist (any more).
pub fn handle_frame(
    role: HandleRole,
    design: &Design,
    model: &ShapeModel,
    offsets: &HashMap<ContourRole, DVec2>,
) -> Option<HandleFrame> {
    // The model is the vessel as printed: enlarged where the clay's shrinkage is compensated.
    let (_, kz) = clayloft_core::clay::wet_factors(design);
    let height = design.shape.height * kz;
    match role {
        HandleRole::Contour { contour, param } => {
            let z = if contour == ContourRole::Lower {
                0.0
            } else {
                height
            };
            let offset = offsets.get(&contour).copied().unwrap_or_default();
            Some(HandleFrame {
                origin: offset.extend(z),
                dir: param_dir(contour_spec(design, contour), param),
                height,
                z_scale: 0.0,
            })
        }
        HandleRole::Line {
            kind: LineKind::Vertical,
            line,
            point,
        } => {
            let v = design.control.vertical.get(line)?;
            let [t, _] = *v.points.get(point)?;
            let column = model.column_at_angle(v.angle.unwrap_or(0.0).to_radians());
            let (origin, dir) = model.wall_frame(column, t, Some(line));
            Some(HandleFrame {
                origin,
                dir,
                height,
                z_scale: 0.0,
            })
        }
        HandleRole::Line {
            kind: LineKind::Horizontal,
            line,
            point,
        } => {
            let h = design.control.horizontal.get(line)?;
            let [angle, dz] = *h.points.get(point)?;
            let column = model.column_at_angle(angle.to_radians());
            let on_wall = model.wall_point(column, h.at);
            let z_scale = model.hz_scale * model.horizontal.get(line)?.weight_at(h.at);
            Some(HandleFrame {
                origin: on_wall - DVec3::Z * (z_scale * dz * kz),
                dir: DVec2::ZERO,
                height,
                z_scale,
            })
        }
    }
}

/// The name of a contour for people: the foot stands on the bed, the rim is the top.
fn contour_name(role: ContourRole) -> &'static str {
    match role {
        ContourRole::Lower => "foot",
        ContourRole::Upper => "rim",
    }
}

/// What a handle stands for, in words (points counted from 1, as people count):
/// "rim radius", "foot star notch radius", "rim point 3",
/// "vertical control line 1, point 3: height and offset".
pub fn describe(role: HandleRole, design: &Design) -> String {
    match role {
        HandleRole::Contour { contour, param } => {
            let name = contour_name(contour);
            match (contour_spec(design, contour), param) {
                (_, ContourParam::Point(i)) => format!("{name} point {}", i + 1),
                (ContourSpec::Polygon { .. }, _) => format!("{name} polygon radius (to a corner)"),
                (ContourSpec::Rose { .. }, _) => format!("{name} rose radius (at 0°)"),
                (_, ContourParam::Radius) => format!("{name} radius"),
                (_, ContourParam::RadiusX) => format!("{name} ellipse half-width along x"),
                (_, ContourParam::RadiusY) => format!("{name} ellipse half-width along y"),
                (_, ContourParam::Outer) => format!("{name} star tip radius"),
                (_, ContourParam::Inner) => format!("{name} star notch radius"),
            }
        }
        HandleRole::Line { kind, line, point } => {
            let what = match kind {
                LineKind::Vertical => "vertical",
                LineKind::Horizontal => "horizontal",
            };
            format!(
                "{what} control line {}, point {}: {}",
                line + 1,
                point + 1,
                freedom(role, design).moves
            )
        }
    }
}

/// How a handle may move: the directions (design space, unit or zero-length when they depend
/// on the frame: see [`Freedom::directions`]), in words, and why the other directions are fixed.
#[derive(Debug, Clone, PartialEq)]
pub struct Freedom {
    pub moves: &'static str,
    pub directions: Vec<Direction>,
    /// Why a drag across the free directions does nothing.
    pub locked: &'static str,
}

/// One direction a handle moves in, resolved against its [`HandleFrame`] by [`Direction::world`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Direction {
    /// Along the frame's direction in the bed plane (a radius, a control-line offset).
    Frame,
    X,
    Y,
    /// Up.
    Z,
}

impl Direction {
    /// The unit direction in design space.
    pub fn design(self, frame: &HandleFrame) -> DVec3 {
        match self {
            Direction::Frame => frame.dir.normalize_or_zero().extend(0.0),
            Direction::X => DVec3::X,
            Direction::Y => DVec3::Y,
            Direction::Z => DVec3::Z,
        }
    }
}

/// The directions a handle of `role` moves in (what the move gizmo shows) and why the rest are
/// fixed (what a drag across them says).
pub fn freedom(role: HandleRole, design: &Design) -> Freedom {
    match role {
        HandleRole::Contour {
            param: ContourParam::Point(_),
            ..
        } => Freedom {
            moves: "anywhere in the contour's plane",
            directions: vec![Direction::X, Direction::Y],
            locked: "a contour point stays in its contour's plane: the contour's height is the vessel's foot or rim",
        },
        HandleRole::Contour { .. } => Freedom {
            moves: "in and out along its radius",
            directions: vec![Direction::Frame],
            locked: "a radius handle moves only along its radius: the shape's other values are in the panel",
        },
        HandleRole::Line {
            kind: LineKind::Vertical,
            line,
            point,
        } => {
            let n = design
                .control
                .vertical
                .get(line)
                .map_or(0, |v| v.points.len());
            if point == 0 || point + 1 >= n {
                Freedom {
                    moves: "offset (in and out); an end point stays at the line's end",
                    directions: vec![Direction::Frame],
                    locked: "the end points of a vertical control line keep their height (the foot and the rim): drag it in or out",
                }
            } else {
                Freedom {
                    moves: "height and offset",
                    directions: vec![Direction::Z, Direction::Frame],
                    locked: "a vertical control line stays at its angle around the vessel: change the angle in the panel",
                }
            }
        }
        HandleRole::Line {
            kind: LineKind::Horizontal,
            ..
        } => Freedom {
            moves: "up and down",
            directions: vec![Direction::Z],
            locked: "a horizontal control line's point moves only up and down: its angle around the vessel is set in the panel",
        },
    }
}

/// The handle a click picks among those drawn on the same spot (`stack`, in a stable order): the
/// one after the current selection if that is in the stack (click again, the next one), else the
/// one clicked.
pub fn next_pick(
    stack: &[HandleRole],
    clicked: HandleRole,
    current: Option<HandleRole>,
) -> HandleRole {
    match current.and_then(|c| stack.iter().position(|r| *r == c)) {
        Some(i) if stack.len() > 1 => stack[(i + 1) % stack.len()],
        _ => clicked,
    }
}

/// Where the handle of `role` sits (design space, on the vessel as printed: the design's
/// lengths times [`clayloft_core::clay::wet_factors`]), given its frame.
pub fn handle_position(role: HandleRole, design: &Design, f: &HandleFrame) -> Option<DVec3> {
    let (kxy, kz) = clayloft_core::clay::wet_factors(design);
    match role {
        HandleRole::Contour { contour, param } => {
            let spec = contour_spec(design, contour);
            let local = match (spec, param) {
                (ContourSpec::Spline { points }, ContourParam::Point(i)) => {
                    let [x, y] = *points.get(i)?;
                    DVec2::new(x, y) * kxy
                }
                _ => f.dir * radial_value(spec, param)? * kxy,
            };
            Some(f.origin + local.extend(0.0))
        }
        HandleRole::Line { kind, line, point } => match kind {
            LineKind::Vertical => {
                let [_, offset] = *design.control.vertical.get(line)?.points.get(point)?;
                Some(f.origin + (f.dir * offset * kxy).extend(0.0))
            }
            LineKind::Horizontal => {
                let [_, dz] = *design.control.horizontal.get(line)?.points.get(point)?;
                Some(f.origin + DVec3::Z * (f.z_scale * dz * kz))
            }
        },
    }
}

fn radial_value(spec: &ContourSpec, param: ContourParam) -> Option<f64> {
    Some(match (spec, param) {
        (ContourSpec::Circle { radius }, ContourParam::Radius)
        | (ContourSpec::Polygon { radius, .. }, ContourParam::Radius) => *radius,
        (
            ContourSpec::Rose {
                radius, amplitude, ..
            },
            ContourParam::Radius,
        ) => radius + amplitude,
        (ContourSpec::Ellipse { rx, .. }, ContourParam::RadiusX) => *rx,
        (ContourSpec::Ellipse { ry, .. }, ContourParam::RadiusY) => *ry,
        (ContourSpec::Star { outer_radius, .. }, ContourParam::Outer) => *outer_radius,
        (ContourSpec::Star { inner_radius, .. }, ContourParam::Inner) => *inner_radius,
        _ => return None,
    })
}

/// Smallest radius or offset-free value a drag can set, mm (validation reports anything worse).
const MIN_RADIUS: f64 = 1.0;

/// Writes the value that puts the handle of `role` at `target` (design space) into the design,
/// measured in the frame captured when the drag started. Returns false if nothing changed.
pub fn set_handle(role: HandleRole, design: &mut Design, f: &HandleFrame, target: DVec3) -> bool {
    let before = design.clone();
    // The target is on the vessel as printed; the design holds the fired size.
    let (kxy, kz) = clayloft_core::clay::wet_factors(design);
    match role {
        HandleRole::Contour { contour, param } => {
            let local = (target.truncate() - f.origin.truncate()) / kxy;
            let spec = contour_spec_mut(design, contour);
            let r = local.dot(f.dir).max(MIN_RADIUS);
            match (spec, param) {
                (ContourSpec::Spline { points }, ContourParam::Point(i)) => {
                    if let Some(p) = points.get_mut(i) {
                        *p = [round3(local.x), round3(local.y)];
                    }
                }
                (ContourSpec::Circle { radius }, ContourParam::Radius)
                | (ContourSpec::Polygon { radius, .. }, ContourParam::Radius) => {
                    *radius = round3(r)
                }
                (
                    ContourSpec::Rose {
                        radius, amplitude, ..
                    },
                    ContourParam::Radius,
                ) => *radius = round3((r - *amplitude).max(MIN_RADIUS)),
                (ContourSpec::Ellipse { rx, .. }, ContourParam::RadiusX) => *rx = round3(r),
                (ContourSpec::Ellipse { ry, .. }, ContourParam::RadiusY) => *ry = round3(r),
                (
                    ContourSpec::Star {
                        outer_radius,
                        inner_radius,
                        ..
                    },
                    param,
                ) => match param {
                    ContourParam::Outer => *outer_radius = round3(r.max(*inner_radius + 0.5)),
                    _ => *inner_radius = round3(r.min(*outer_radius - 0.5)),
                },
                _ => {}
            }
        }
        HandleRole::Line { kind, line, point } => match kind {
            LineKind::Vertical => {
                let Some(v) = design.control.vertical.get_mut(line) else {
                    return false;
                };
                let n = v.points.len();
                // Keep the points in height order and the end points where they are.
                let lo = if point == 0 {
                    0.0
                } else {
                    v.points[point - 1][0] + 0.01
                };
                let hi = if point + 1 == n {
                    1.0
                } else {
                    v.points[point + 1][0] - 0.01
                };
                let t = if point == 0 || point + 1 == n {
                    v.points[point][0]
                } else {
                    (target.z / f.height).clamp(lo, hi.max(lo))
                };
                // Along the wall's normal, per mm of offset as weighted at this column; where
                // the line does not reach (zero weight) the offset cannot be dragged.
                let along = f.dir.length_squared();
                let offset = if along > 1e-12 {
                    (target.truncate() - f.origin.truncate()).dot(f.dir) / along / kxy
                } else {
                    v.points[point][1]
                };
                v.points[point] = [round3(t), round3(offset)];
            }
            LineKind::Horizontal => {
                let Some(h) = design.control.horizontal.get_mut(line) else {
                    return false;
                };
                if let Some(p) = h.points.get_mut(point)
                    && f.z_scale > 1e-12
                {
                    p[1] = round3((target.z - f.origin.z) / f.z_scale / kz);
                }
            }
        },
    }
    *design != before
}

/// Moves the handle of `role` by `delta` (design space, mm) as a drag would: measured in its
/// current frame, written into the design document of `world`. Returns false if the handle does
/// not exist or the value did not change. (Tests, benchmarks and scripted edits use this.)
pub fn nudge_handle(world: &mut World, role: HandleRole, delta: DVec3) -> bool {
    let offsets: HashMap<ContourRole, DVec2> = world
        .query::<(&ContourRole, &ContourSamples)>()
        .iter(world)
        .map(|(r, s)| (*r, s.offset))
        .collect();
    let (Some(engine), Some(doc)) = (
        world.get_resource::<Engine>(),
        world.get_resource::<DesignDoc>(),
    ) else {
        return false;
    };
    let Some(model) = engine.0.model() else {
        return false;
    };
    let Some(frame) = handle_frame(role, &doc.design, model, &offsets) else {
        return false;
    };
    let Some(at) = handle_position(role, &doc.design, &frame) else {
        return false;
    };
    let mut doc = world.resource_mut::<DesignDoc>();
    set_handle(role, &mut doc.design, &frame, at + delta)
}

/// Rounds to 0.001 mm so saved files stay readable.
fn round3(v: f64) -> f64 {
    (v * 1000.0).round() / 1000.0
}

/// Keeps one handle entity per role of the design, at its position; runs when the design or
/// the model changed. Unchanged positions are not written (no false change detection).
pub fn sync_handles(
    mut commands: Commands,
    doc: Option<Res<DesignDoc>>,
    engine: Res<Engine>,
    contours: Query<(&ContourRole, &ContourSamples)>,
    mut handles: Query<(Entity, &EditHandle, &mut HandlePosition)>,
) {
    let Some(doc) = doc else { return };
    if !doc.is_changed() && !engine.is_changed() {
        return;
    }
    let Some(model) = engine.0.model() else {
        return;
    };
    let offsets: HashMap<ContourRole, DVec2> =
        contours.iter().map(|(r, s)| (*r, s.offset)).collect();
    let roles = handle_roles(&doc.design);
    let mut seen = std::collections::HashSet::new();
    for (entity, handle, mut pos) in &mut handles {
        let placed = roles
            .contains(&handle.0)
            .then(|| handle_frame(handle.0, &doc.design, model, &offsets))
            .flatten()
            .and_then(|f| handle_position(handle.0, &doc.design, &f));
        match placed {
            Some(p) => {
                pos.set_if_neq(HandlePosition(p));
                seen.insert(handle.0);
            }
            None => commands.entity(entity).despawn(),
        }
    }
    for role in roles.into_iter().filter(|r| !seen.contains(r)) {
        let placed = handle_frame(role, &doc.design, model, &offsets)
            .and_then(|f| handle_position(role, &doc.design, &f));
        if let Some(p) = placed {
            commands.spawn((
                EditHandle(role),
                HandlePosition(p),
                Name::new(format!("{role:?}")),
            ));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(origin: DVec3, dir: DVec2) -> HandleFrame {
        HandleFrame {
            origin,
            dir,
            height: 100.0,
            z_scale: 1.0,
        }
    }

    fn design() -> Design {
        clayloft_core::load::parse_design(
            r#"
version = 1
[shape]
height = 100.0
lower = { type = "star", points = 5, outer_radius = 40.0, inner_radius = 30.0 }
upper = { type = "spline", points = [[40.0, 0.0], [0.0, 35.0], [-40.0, 0.0], [0.0, -35.0]] }
[[control.vertical]]
points = [[0.0, 0.0], [0.5, 5.0], [1.0, 0.0]]
"#,
        )
        .unwrap()
    }

    #[test]
    fn handles_are_described_in_words() {
        let d = design();
        let words: Vec<String> = handle_roles(&d).iter().map(|r| describe(*r, &d)).collect();
        assert_eq!(words[0], "foot star tip radius");
        assert_eq!(words[1], "foot star notch radius");
        assert_eq!(words[3], "rim point 2");
        assert_eq!(
            words[6],
            "vertical control line 1, point 1: offset (in and out); an end point stays at the line's end"
        );
        assert_eq!(
            words[7],
            "vertical control line 1, point 2: height and offset"
        );
        assert!(
            words
                .iter()
                .all(|w| !w.contains('{') && !w.contains("Line"))
        );
    }

    #[test]
    fn clicking_a_stack_again_picks_the_next() {
        let roles = handle_roles(&design());
        let stack = [roles[0], roles[6], roles[7]];
        // First click: the one hit; again: the next, round and round.
        assert_eq!(next_pick(&stack, roles[6], None), roles[6]);
        assert_eq!(next_pick(&stack, roles[6], Some(roles[6])), roles[7]);
        assert_eq!(next_pick(&stack, roles[6], Some(roles[7])), roles[0]);
        // A selection elsewhere does not cycle; a lone handle stays picked.
        assert_eq!(next_pick(&stack, roles[0], Some(roles[3])), roles[0]);
        assert_eq!(next_pick(&[roles[3]], roles[3], Some(roles[3])), roles[3]);
    }

    #[test]
    fn each_handle_moves_in_the_directions_its_value_has() {
        let d = design();
        for role in handle_roles(&d) {
            // A vertical line's frame stands at its point's height, as the model gives it.
            let z = match role {
                HandleRole::Line {
                    kind: LineKind::Vertical,
                    line,
                    point,
                } => d.control.vertical[line].points[point][0] * 100.0,
                _ => 0.0,
            };
            let f = frame(DVec3::new(0.0, 0.0, z), DVec2::new(0.6, 0.8));
            let free = freedom(role, &d);
            // Moving along each free direction changes the design; across them it does not.
            let at = handle_position(role, &d, &f).unwrap();
            for dir in &free.directions {
                let mut moved = d.clone();
                assert!(
                    set_handle(role, &mut moved, &f, at + dir.design(&f) * 3.0),
                    "{}: {dir:?} does nothing",
                    describe(role, &d)
                );
            }
            let dirs: Vec<DVec3> = free.directions.iter().map(|x| x.design(&f)).collect();
            let across = [DVec3::X, DVec3::Y, DVec3::Z, DVec3::new(-0.8, 0.6, 0.0)]
                .into_iter()
                .find(|c| dirs.iter().all(|d| d.dot(*c).abs() < 1e-9));
            if let Some(c) = across {
                let mut moved = d.clone();
                assert!(
                    !set_handle(role, &mut moved, &f, at + c * 3.0),
                    "{}: moved across its free directions ({c:?})",
                    describe(role, &d)
                );
            }
        }
    }

    #[test]
    fn roles_cover_every_point() {
        let roles = handle_roles(&design());
        // star: outer + inner; spline: 4 points; vertical line: 3 points.
        assert_eq!(roles.len(), 2 + 4 + 3);
    }

    #[test]
    fn place_then_drag_round_trips() {
        let mut d = design();
        let f = frame(DVec3::new(90.0, 95.0, 0.0), DVec2::X);
        let star_outer = HandleRole::Contour {
            contour: ContourRole::Lower,
            param: ContourParam::Outer,
        };
        assert_eq!(
            handle_position(star_outer, &d, &f),
            Some(DVec3::new(130.0, 95.0, 0.0))
        );
        assert!(set_handle(
            star_outer,
            &mut d,
            &f,
            DVec3::new(135.0, 97.0, 0.0)
        ));
        assert!(
            matches!(d.shape.lower, ContourSpec::Star { outer_radius, .. } if outer_radius == 45.0)
        );
        // The notch handle sits at 36° and cannot pass the tip radius.
        let inner = HandleRole::Contour {
            contour: ContourRole::Lower,
            param: ContourParam::Inner,
        };
        let fi = frame(f.origin, param_dir(&d.shape.lower, ContourParam::Inner));
        let p = handle_position(inner, &d, &fi).unwrap();
        assert!(((p.truncate() - f.origin.truncate()).to_angle().to_degrees() - 36.0).abs() < 1e-9);
        set_handle(inner, &mut d, &fi, f.origin + (fi.dir * 80.0).extend(0.0));
        assert!(
            matches!(d.shape.lower, ContourSpec::Star { inner_radius, .. } if inner_radius == 44.5)
        );
        // A spline point follows the pointer exactly in its frame.
        let sp = HandleRole::Contour {
            contour: ContourRole::Upper,
            param: ContourParam::Point(1),
        };
        let fu = frame(DVec3::new(90.0, 95.0, 100.0), DVec2::X);
        set_handle(sp, &mut d, &fu, DVec3::new(92.5, 135.0, 100.0));
        assert_eq!(
            handle_position(sp, &d, &fu),
            Some(DVec3::new(92.5, 135.0, 100.0))
        );
    }

    #[test]
    fn vertical_line_point_drags_in_height_and_offset() {
        let mut d = design();
        // The wall without this line at the point's column and height, and its normal there.
        let f = frame(DVec3::new(110.0, 90.0, 50.0), DVec2::X);
        let mid = HandleRole::Line {
            kind: LineKind::Vertical,
            line: 0,
            point: 1,
        };
        // Offset 5 mm along the normal.
        assert_eq!(
            handle_position(mid, &d, &f),
            Some(DVec3::new(115.0, 90.0, 50.0))
        );
        set_handle(mid, &mut d, &f, DVec3::new(122.0, 90.0, 60.0));
        assert_eq!(d.control.vertical[0].points[1], [0.6, 12.0]);
        // End points keep their height; only the offset changes.
        let end = HandleRole::Line {
            kind: LineKind::Vertical,
            line: 0,
            point: 2,
        };
        set_handle(end, &mut d, &f, DVec3::new(123.0, 90.0, 40.0));
        assert_eq!(d.control.vertical[0].points[2], [1.0, 13.0]);
        // A half weight (the edge of a local line) doubles the offset a drag makes.
        let half = frame(f.origin, DVec2::X * 0.5);
        set_handle(mid, &mut d, &half, DVec3::new(112.0, 90.0, 60.0));
        assert_eq!(d.control.vertical[0].points[1], [0.6, 4.0]);
    }
}
