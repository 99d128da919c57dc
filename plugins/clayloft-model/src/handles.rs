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
    let height = design.shape.height;
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
                origin: on_wall - DVec3::Z * (z_scale * dz),
                dir: DVec2::ZERO,
                height,
                z_scale,
            })
        }
    }
}

/// Where the handle of `role` sits (design space), given its frame.
pub fn handle_position(role: HandleRole, design: &Design, f: &HandleFrame) -> Option<DVec3> {
    match role {
        HandleRole::Contour { contour, param } => {
            let spec = contour_spec(design, contour);
            let local = match (spec, param) {
                (ContourSpec::Spline { points }, ContourParam::Point(i)) => {
                    let [x, y] = *points.get(i)?;
                    DVec2::new(x, y)
                }
                _ => f.dir * radial_value(spec, param)?,
            };
            Some(f.origin + local.extend(0.0))
        }
        HandleRole::Line { kind, line, point } => match kind {
            LineKind::Vertical => {
                let [_, offset] = *design.control.vertical.get(line)?.points.get(point)?;
                Some(f.origin + (f.dir * offset).extend(0.0))
            }
            LineKind::Horizontal => {
                let [_, dz] = *design.control.horizontal.get(line)?.points.get(point)?;
                Some(f.origin + DVec3::Z * (f.z_scale * dz))
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
    match role {
        HandleRole::Contour { contour, param } => {
            let local = target.truncate() - f.origin.truncate();
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
                    (target.truncate() - f.origin.truncate()).dot(f.dir) / along
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
                    p[1] = round3((target.z - f.origin.z) / f.z_scale);
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
