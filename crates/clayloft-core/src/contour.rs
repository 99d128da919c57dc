//! Contours (SPEC §1): closed curves in the XY plane built from a [`ContourSpec`], as dense
//! counter-clockwise polylines ready to be sampled. Self-intersecting or degenerate curves are
//! rejected.

use std::f64::consts::{PI, TAU};
use std::path::Path;

use glam::DVec2;

use crate::design::ContourSpec;
use crate::geometry::{dedup_closed, find_self_intersection, signed_area};
use crate::spline::closed_catmull_rom;

/// Points per curve used to approximate a contour before sampling. Far denser than any sampling
/// the user asks for, so that equal-arc-length resampling reads the true curve.
pub const DENSE_POINTS: usize = 4096;

/// A closed contour as a dense counter-clockwise polyline (first point not repeated).
#[derive(Debug, Clone, PartialEq)]
pub struct Contour {
    pub points: Vec<DVec2>,
}

/// Why a contour could not be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ContourError {
    #[error("the contour has fewer than 3 distinct points")]
    TooFewPoints,
    #[error("the contour encloses no area (its points are collinear)")]
    ZeroArea,
    #[error("the contour crosses itself (near ({x:.1}, {y:.1}) mm)")]
    SelfIntersecting { x: f64, y: f64 },
    #[error("{file}: {reason}")]
    Image {
        file: String,
        reason: crate::trace::TraceError,
    },
    #[error("{file}: {reason}")]
    Svg {
        file: String,
        reason: crate::svg::SvgError,
    },
}

impl Contour {
    /// Builds the contour described by `spec`, normalised to counter-clockwise order.
    /// `dense` is the number of points used for smooth curves (at least [`DENSE_POINTS`] is wise).
    pub fn from_spec(spec: &ContourSpec, dense: usize) -> Result<Contour, ContourError> {
        Contour::from_spec_in(spec, dense, None)
    }

    /// As [`Contour::from_spec`], with image and SVG paths relative to `base` (the design file's
    /// folder).
    pub fn from_spec_in(
        spec: &ContourSpec,
        dense: usize,
        base: Option<&Path>,
    ) -> Result<Contour, ContourError> {
        let raw = match spec {
            ContourSpec::Circle { radius } => polar(dense, |_| *radius),
            ContourSpec::Ellipse { rx, ry } => (0..dense)
                .map(|i| {
                    let th = TAU * i as f64 / dense as f64;
                    DVec2::new(rx * th.cos(), ry * th.sin())
                })
                .collect(),
            ContourSpec::Rose {
                radius,
                amplitude,
                petals,
            } => polar(dense, |th| radius + amplitude * (*petals as f64 * th).cos()),
            ContourSpec::Polygon {
                sides,
                radius,
                corner_radius,
            } => rounded_polygon(*sides, *radius, *corner_radius, dense),
            ContourSpec::Star {
                points,
                outer_radius,
                inner_radius,
            } => (0..2 * points)
                .map(|j| {
                    let r = if j % 2 == 0 {
                        *outer_radius
                    } else {
                        *inner_radius
                    };
                    DVec2::from_angle(PI * j as f64 / *points as f64) * r
                })
                .collect(),
            ContourSpec::Spline { points } => {
                let ctrl = dedup_closed(
                    &points
                        .iter()
                        .map(|&[x, y]| DVec2::new(x, y))
                        .collect::<Vec<_>>(),
                );
                if ctrl.len() < 3 {
                    return Err(ContourError::TooFewPoints);
                }
                let per_span = (dense / ctrl.len()).clamp(8, 256);
                closed_catmull_rom(&ctrl, per_span)
            }
            ContourSpec::Image { .. } | ContourSpec::Svg { .. } => {
                crate::outline::outline_of(spec, base)?
            }
        };
        Contour::from_points(raw)
    }

    /// Makes a contour from a closed polyline: removes repeats, checks area and simplicity, and
    /// orders it counter-clockwise.
    pub fn from_points(points: Vec<DVec2>) -> Result<Contour, ContourError> {
        let mut points = dedup_closed(&points);
        if points.len() < 3 {
            return Err(ContourError::TooFewPoints);
        }
        let area = signed_area(&points);
        let scale = points
            .iter()
            .map(|p| p.length_squared())
            .fold(0.0, f64::max);
        let far = points.iter().copied().max_by(|a, b| {
            a.distance_squared(points[0])
                .total_cmp(&b.distance_squared(points[0]))
        });
        let dir = (far.unwrap_or(points[0]) - points[0]).normalize_or_zero();
        let collinear = points
            .iter()
            .all(|p| dir.perp_dot(*p - points[0]).abs() <= 1e-9 * scale.sqrt().max(1.0));
        let flat = collinear || area.abs() <= 1e-12 * scale.max(1e-9);
        let crossing = if winds_once_around_origin(&points) {
            None
        } else {
            find_self_intersection(&points)
        };
        if let Some((i, _)) = crossing {
            if collinear {
                return Err(ContourError::ZeroArea);
            }
            let p = points[i];
            return Err(ContourError::SelfIntersecting { x: p.x, y: p.y });
        }
        if flat {
            return Err(ContourError::ZeroArea);
        }
        if area < 0.0 {
            points.reverse();
        }
        Ok(Contour { points })
    }

    /// Translates every point by `offset`.
    pub fn translated(&self, offset: DVec2) -> Contour {
        Contour {
            points: self.points.iter().map(|p| *p + offset).collect(),
        }
    }
}

/// Whether the closed polyline goes once around the origin with every segment turning
/// anticlockwise about it (each `pᵢ × pᵢ₊₁` clearly positive, and one upward crossing of the
/// +x axis): a star-shaped polygon, which cannot cross or touch itself, since each segment keeps
/// to its own angular sector. Circles, ellipses, roses and polygons about their centre pass, and
/// need no sweep for crossings ([`find_self_intersection`]).
fn winds_once_around_origin(points: &[DVec2]) -> bool {
    let n = points.len();
    let mut upward = 0;
    for (i, &p) in points.iter().enumerate() {
        let q = points[(i + 1) % n];
        // A margin far above rounding: a sign the arithmetic could flip fails the test.
        if p.perp_dot(q) <= 1e-9 * p.length() * q.length() {
            return false;
        }
        if p.y < 0.0 && q.y >= 0.0 {
            upward += 1;
        }
    }
    upward == 1
}

/// `n` points of the polar curve `r(θ)`, θ from 0 in equal steps.
pub(crate) fn polar(n: usize, r: impl Fn(f64) -> f64) -> Vec<DVec2> {
    (0..n)
        .map(|i| {
            let th = TAU * i as f64 / n as f64;
            DVec2::from_angle(th) * r(th)
        })
        .collect()
}

/// Regular polygon with circumradius `radius`, first vertex on +x, each corner replaced by a
/// circular arc of `corner_radius` tangent to both edges.
///
/// With interior angle α = π − 2π/n, the arc's tangent points lie `rc / tan(α/2)` from the
/// vertex and its centre lies on the bisector `rc / sin(α/2)` from the vertex.
fn rounded_polygon(sides: usize, radius: f64, rc: f64, dense: usize) -> Vec<DVec2> {
    let vertex = |j: usize| DVec2::from_angle(TAU * j as f64 / sides as f64) * radius;
    if rc <= 0.0 {
        return (0..sides).map(vertex).collect();
    }
    let half_interior = (PI - TAU / sides as f64) / 2.0;
    let arc_points = (dense / sides).clamp(4, 512);
    let mut out = Vec::with_capacity(sides * (arc_points + 1));
    for j in 0..sides {
        let v = vertex(j);
        let to_centre = -v.normalize();
        let centre = v + to_centre * (rc / half_interior.sin());
        // The arc spans the exterior angle 2π/n, symmetric about the vertex direction.
        let mid = (v - centre).to_angle();
        let half_span = PI / sides as f64;
        for k in 0..=arc_points {
            let a = mid - half_span + 2.0 * half_span * k as f64 / arc_points as f64;
            out.push(centre + DVec2::from_angle(a) * rc);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::closed_length;

    #[test]
    fn circle_area_and_length() {
        let c = Contour::from_spec(&ContourSpec::Circle { radius: 40.0 }, DENSE_POINTS).unwrap();
        assert!((signed_area(&c.points) - PI * 1600.0).abs() / (PI * 1600.0) < 1e-5);
        assert!((closed_length(&c.points) - TAU * 40.0).abs() < 1e-3);
    }

    #[test]
    fn clockwise_spline_is_normalised_to_ccw() {
        let cw = ContourSpec::Spline {
            points: vec![[40.0, 0.0], [0.0, -35.0], [-40.0, 0.0], [0.0, 35.0]],
        };
        let c = Contour::from_spec(&cw, 1024).unwrap();
        assert!(signed_area(&c.points) > 0.0);
    }

    #[test]
    /// The star test never passes an outline the sweep finds crossing: random polygons about
    /// the origin (some star-shaped, some winding twice, some folding back, some off centre),
    /// and the pentagram {5/2} and a bow tie are refused.
    fn outlines_passing_the_star_test_never_cross() {
        let mut next = crate::test_rng::uniform(0x2545_f491_4f6c_dd1d);
        let mut passed = 0;
        for _ in 0..2000 {
            let n = 3 + (next() * 30.0) as usize;
            let turns = if next() < 0.2 { 2.0 } else { 1.0 };
            let shift = if next() < 0.2 { 30.0 * next() } else { 0.0 };
            let pts: Vec<DVec2> = (0..n)
                .map(|i| {
                    let jitter = if next() < 0.1 {
                        3.0 * next()
                    } else {
                        0.5 * next()
                    };
                    let th = turns * TAU * (i as f64 + jitter) / n as f64;
                    DVec2::from_angle(th) * (5.0 + 40.0 * next()) + DVec2::new(shift, 0.0)
                })
                .collect();
            if winds_once_around_origin(&pts) {
                passed += 1;
                assert_eq!(find_self_intersection(&pts), None, "{pts:?}");
            }
        }
        assert!(passed > 500, "{passed}");
        let pentagram: Vec<DVec2> = (0..5)
            .map(|j| DVec2::from_angle(TAU * (2 * j) as f64 / 5.0) * 10.0)
            .collect();
        assert!(!winds_once_around_origin(&pentagram));
        assert!(matches!(
            Contour::from_points(pentagram),
            Err(ContourError::SelfIntersecting { .. })
        ));
        let bow_tie =
            [(-1.0, -1.0), (1.0, 1.0), (1.0, -1.0), (-1.0, 1.0)].map(|(x, y)| DVec2::new(x, y));
        assert!(!winds_once_around_origin(&bow_tie));
    }

    #[test]
    fn self_intersecting_spline_is_rejected() {
        let bow = ContourSpec::Spline {
            points: vec![[0.0, 0.0], [20.0, 20.0], [20.0, 0.0], [0.0, 20.0]],
        };
        assert!(matches!(
            Contour::from_spec(&bow, 1024),
            Err(ContourError::SelfIntersecting { .. })
        ));
    }

    #[test]
    fn collinear_and_repeated_points_are_rejected() {
        let line = ContourSpec::Spline {
            points: vec![[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]],
        };
        assert!(Contour::from_spec(&line, 64).is_err());
        let same = ContourSpec::Spline {
            points: vec![[1.0, 1.0], [1.0, 1.0], [1.0, 1.0]],
        };
        assert_eq!(
            Contour::from_spec(&same, 64),
            Err(ContourError::TooFewPoints)
        );
    }

    #[test]
    fn rounded_square_has_the_analytic_perimeter() {
        // Square of circumradius R: side a = R√2; rounding corners of radius r removes 8r of
        // straight edge and adds a full circle 2πr.
        let (r_circ, rc) = (40.0_f64, 5.0);
        let c = Contour::from_spec(
            &ContourSpec::Polygon {
                sides: 4,
                radius: r_circ,
                corner_radius: rc,
            },
            DENSE_POINTS,
        )
        .unwrap();
        let a = r_circ * 2f64.sqrt();
        let expected = 4.0 * a - 8.0 * rc + TAU * rc;
        assert!(
            (closed_length(&c.points) - expected).abs() < 0.01,
            "{}",
            closed_length(&c.points)
        );
    }

    #[test]
    fn star_and_rose_extremes() {
        let s = Contour::from_spec(
            &ContourSpec::Star {
                points: 5,
                outer_radius: 45.0,
                inner_radius: 30.0,
            },
            DENSE_POINTS,
        )
        .unwrap();
        assert_eq!(s.points.len(), 10);
        let r = Contour::from_spec(
            &ContourSpec::Rose {
                radius: 45.0,
                amplitude: 8.0,
                petals: 6,
            },
            DENSE_POINTS,
        )
        .unwrap();
        let max = r.points.iter().map(|p| p.length()).fold(0.0, f64::max);
        let min = r.points.iter().map(|p| p.length()).fold(f64::MAX, f64::min);
        assert!((max - 53.0).abs() < 1e-9 && (min - 37.0).abs() < 1e-3);
    }
}
