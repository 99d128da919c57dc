//! What an edit invalidates: the last computed design against the edited one.
//!
//! The dependency graph of the pipeline, coarsest first:
//! - the layer plan (number of layers, horizontal-line scale) depends on the height, the sampling,
//!   the centre, the horizontal control lines and the printer's layer and nozzle limits;
//! - each contour's samples depend on that contour and on the centre and sampling;
//! - section k depends on the loft and on the vertical control lines whose span contains k;
//! - constraints, texture and the toolpath depend on the whole surface and are always redone
//!   (they are the cheap, linear stages).

use std::collections::BTreeSet;

use clayloft_core::Design;
use clayloft_core::control::VerticalProfile;
use clayloft_core::shape::ShapeModel;

use crate::components::ContourRole;

/// The work an edit needs, from most to least.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Recompute {
    /// Resample both contours, plan the layers anew, recompute every section.
    Everything,
    /// Resample these contours, rebuild the loft, recompute every section.
    Contours(Vec<ContourRole>),
    /// Recompute only these sections (vertical control lines changed).
    Sections(BTreeSet<usize>),
    /// Only the finishing stages (constraints, texture, toolpath): no section is reshaped.
    Finish,
    /// Nothing changed.
    Nothing,
}

/// Compares the last computed design (`None` before the first) with the edited one.
/// `model` is the shape model of `old`, used to map control-line spans to sections.
pub fn plan_recompute(old: Option<&Design>, new: &Design, model: Option<&ShapeModel>) -> Recompute {
    let (Some(old), Some(model)) = (old, model) else {
        return Recompute::Everything;
    };
    if old == new {
        return Recompute::Nothing;
    }
    let (po, pn) = (&old.printer, &new.printer);
    let plan_changed = old.shape.height != new.shape.height
        || old.shape.samples != new.shape.samples
        || old.center() != new.center()
        || old.control.horizontal != new.control.horizontal
        || old.constraints != new.constraints
        || po.layer_height != pn.layer_height
        || po.min_layer_height != pn.min_layer_height
        || po.max_layer_height != pn.max_layer_height
        || po.nozzle_length != pn.nozzle_length
        || po.max_overhang_deg != pn.max_overhang_deg;
    if plan_changed {
        return Recompute::Everything;
    }
    let contours: Vec<ContourRole> = ContourRole::BOTH
        .into_iter()
        .filter(|role| match role {
            ContourRole::Lower => old.shape.lower != new.shape.lower,
            ContourRole::Upper => old.shape.upper != new.shape.upper,
        })
        .collect();
    if !contours.is_empty() {
        return Recompute::Contours(contours);
    }
    let (vo, vn) = (&old.control.vertical, &new.control.vertical);
    if vo != vn {
        let mut dirty = BTreeSet::new();
        for l in 0..vo.len().max(vn.len()) {
            let (a, b) = (vo.get(l), vn.get(l));
            if a == b {
                continue;
            }
            // Both the old and the new span change: where the line was and where it is now.
            for line in [a, b].into_iter().flatten() {
                let (t0, t1) = VerticalProfile::new(line).span();
                if t0 <= t1 {
                    dirty.extend(model.sections_in_span((t0, t1)));
                }
            }
        }
        return Recompute::Sections(dirty);
    }
    Recompute::Finish
}

#[cfg(test)]
mod tests {
    use super::*;
    use clayloft_core::design::{ContourSpec, VerticalLine};
    use clayloft_core::loft::LoftInput;

    fn design() -> Design {
        clayloft_core::load::parse_design(
            r#"
version = 1
[shape]
height = 100.0
lower = { type = "circle", radius = 40.0 }
upper = { type = "circle", radius = 30.0 }
[[control.vertical]]
points = [[0.0, 0.0], [0.4, 0.0], [0.5, 5.0], [0.6, 0.0], [1.0, 0.0]]
angle = 90.0
width = 60.0
"#,
        )
        .unwrap()
    }

    fn model(d: &Design) -> ShapeModel {
        ShapeModel::new(d, LoftInput::from_design(d).unwrap())
            .unwrap()
            .0
    }

    #[test]
    fn first_build_and_no_change() {
        let d = design();
        let m = model(&d);
        assert_eq!(plan_recompute(None, &d, None), Recompute::Everything);
        assert_eq!(plan_recompute(Some(&d), &d, Some(&m)), Recompute::Nothing);
    }

    #[test]
    fn local_line_point_dirties_only_its_span() {
        let d = design();
        let m = model(&d);
        assert_eq!(m.layers, 100);
        let mut e = d.clone();
        e.control.vertical[0].points[2][1] = 8.0;
        // Span (0.4, 0.6) at 100 layers: sections 40 ..= 60.
        let expected: BTreeSet<usize> = (40..=60).collect();
        assert_eq!(
            plan_recompute(Some(&d), &e, Some(&m)),
            Recompute::Sections(expected)
        );
        // Moving the peak up widens the span to (0.4, 0.8): the union of old and new.
        e.control.vertical[0].points[3][0] = 0.8;
        e.control.vertical[0].points[3][1] = 1.0;
        e.control.vertical[0].points[4] = [1.0, 0.0];
        let Recompute::Sections(s) = plan_recompute(Some(&d), &e, Some(&m)) else {
            panic!("expected sections");
        };
        assert_eq!(s, (40..=100).collect());
    }

    #[test]
    fn added_line_dirties_its_span() {
        let d = design();
        let m = model(&d);
        let mut e = d.clone();
        e.control.vertical.push(VerticalLine {
            points: vec![[0.0, 0.0], [0.1, 2.0], [0.2, 0.0], [1.0, 0.0]],
            angle: None,
            width: None,
        });
        assert_eq!(
            plan_recompute(Some(&d), &e, Some(&m)),
            Recompute::Sections((0..=20).collect())
        );
    }

    #[test]
    fn contour_texture_and_plan_edits() {
        let d = design();
        let m = model(&d);
        let mut e = d.clone();
        e.shape.upper = ContourSpec::Circle { radius: 31.0 };
        assert_eq!(
            plan_recompute(Some(&d), &e, Some(&m)),
            Recompute::Contours(vec![ContourRole::Upper])
        );
        let mut e = d.clone();
        e.printer.print_speed = 25.0;
        assert_eq!(plan_recompute(Some(&d), &e, Some(&m)), Recompute::Finish);
        let mut e = d.clone();
        e.shape.height = 90.0;
        assert_eq!(
            plan_recompute(Some(&d), &e, Some(&m)),
            Recompute::Everything
        );
    }
}
