//! Walls of two or three beads (SPEC §13): the outer bead on the designed (corrected, textured)
//! surface, bead `j` the surface moved inward by exactly `j · line_width`, so the outside of the
//! vessel stays where it was designed and neighbouring beads touch all the way round.
//!
//! Each bead's section `k` has the outer section's sample count, starts at the point of the
//! offset nearest the outer section's point 0 (so the path steps straight across from one bead to
//! the next) and is resampled by equal arc length from there; its point `i` takes the z of the
//! outer section's point `i` (non-planar layers stay non-planar). The true offset, not a move
//! along the vertex normals, keeps an inner bead free of loops where the wall turns sharply
//! inward (a star's notch, a deep texture groove): the offset rounds those corners instead.
//!
//! With ties (`wall_ties = true`) every inner bead weaves towards the outside by a quarter bead
//! and back, `N` times round (a triangle wave of amplitude `w/4`, about `4·w` long): at each crest
//! it presses a quarter of its width into the bead outside it, keying the two together. The
//! crest stays over the bead it was offset from (within half a bead of the layer's own line
//! below), so it is carried, not bridged: a deeper weave would put the crest over the joint of
//! two beads. `N` is the same for every layer and the wave is placed by arc fraction, so each
//! layer's crests sit on the crests below.

use glam::DVec2;

use crate::geometry::{closed_length, outward_normals, resample_closed};
use crate::pipeline::Surface;
use crate::section::Section;
use crate::validate::FieldError;

/// The inner beads of a wall as printed: `sections[j − 1][k]` is bead `j`'s section `k`
/// ([`inner_beads`], each clamped to the overhang limit against itself a layer below where the
/// outer bead's corners sharpen), and what that clamp corrected (or, with the limits not
/// enforced, found) for the report. Reads as its sections.
#[derive(Debug, Clone, Default)]
pub struct InnerBeads {
    pub sections: Vec<Vec<Section>>,
    pub findings: Vec<crate::report::Finding>,
}

impl std::ops::Deref for InnerBeads {
    type Target = Vec<Vec<Section>>;

    fn deref(&self) -> &Self::Target {
        &self.sections
    }
}

/// Most beads side by side a wall may have.
pub const MAX_WALLS: usize = 3;

/// Length of one tie (crest to crest) in bead widths.
const TIE_PERIOD_BEADS: f64 = 4.0;
/// How far a tie's crest presses into the bead outside it, in bead widths.
const TIE_DEPTH_BEADS: f64 = 0.25;

/// The sections of the inner beads: `result[j − 1][k]` is bead `j`'s section `k` (bead 0, the
/// outer one, is `surface.sections` itself). Empty for a one-bead wall. With `ties_from`
/// sections `ties_from ..` are tied (woven); the first wall layer over a base is not, so that it
/// lies on the base's rings (the weave then grows in over one revolution).
pub fn inner_beads(
    surface: &Surface,
    walls: usize,
    line_width: f64,
    ties_from: Option<usize>,
) -> Result<Vec<Vec<Section>>, FieldError> {
    let sections = &surface.sections;
    if walls <= 1 || sections.is_empty() {
        return Ok(Vec::new());
    }
    let n = sections[0].points.len();
    // The same number of ties on every layer (from the first layer's length), so they stack.
    let crests = (closed_length(&sections[sections.len().min(2) - 1].xy())
        / (TIE_PERIOD_BEADS * line_width))
        .round()
        .max(1.0);
    let mut beads = Vec::with_capacity(walls - 1);
    for j in 1..walls {
        let depth = j as f64 * line_width;
        let bead: Vec<Result<Section, usize>> =
            crate::parallel::map_ranges(sections.len(), 16, |r| {
                r.map(|k| {
                    let mut s = offset_section(&sections[k], depth, n).ok_or(k)?;
                    if ties_from.is_some_and(|from| k >= from) {
                        weave(&mut s, crests, TIE_DEPTH_BEADS * line_width);
                    }
                    Ok(s)
                })
                .collect()
            });
        let bead: Result<Vec<Section>, usize> = bead.into_iter().collect();
        beads.push(bead.map_err(|k| {
            let z = sections[k].z_range().1;
            FieldError::new(
                "shape.walls",
                format!(
                    "at layer {k} (z = {z:.1} mm) the vessel is narrower than {walls} beads of {line_width} mm side by side: use fewer walls or a wider vessel",
                ),
            )
        })?);
    }
    Ok(beads)
}

/// `section` moved inward by `depth` exactly, as `n` points from the one nearest the section's
/// point 0, each with the z of the section's point of the same index. `None` where nothing is
/// left or the offset splits (the section is narrower than `2 · depth` somewhere).
fn offset_section(section: &Section, depth: f64, n: usize) -> Option<Section> {
    let xy = section.xy();
    let mut rings = crate::base_fill::inward_offset_rings(&xy, depth)?;
    if rings.is_empty() {
        // The offsetting library (cavalier_contours 0.9) now and then finds nothing inside a ring
        // plainly wide enough: a section of a 36 mm wide vessel offset 3 mm (found by
        // `any_vessel_gives_one_printable_spiral`, tested below). The same ring resampled at
        // equal arc length (its points on the ring, within a sagitta of its corners) offsets.
        rings = crate::base_fill::inward_offset_rings(&resample_closed(&xy, xy.len()), depth)?;
    }
    if rings.len() != 1 && crate::geometry::find_self_intersection(&xy).is_some() {
        // A section that crosses itself (a deep texture folded on a tight curve): the offset of
        // the section without its small loops (which the inner bead would round away anyway).
        rings = crate::base_fill::inward_offset_rings(&crate::geometry::without_loops(&xy), depth)?;
    }
    if rings.len() != 1 {
        return None;
    }
    let ring = starting_at_step(&rings.pop()?, &xy);
    let ring = resample_closed(&ring, n);
    Some(Section {
        points: ring
            .iter()
            .zip(&section.points)
            .map(|(q, p)| q.extend(p.z))
            .collect(),
    })
}

/// Feet on the bead's ring tried, nearest first, for a step onto it that crosses nothing (see
/// [`starting_at_step`]).
const STEP_CANDIDATES: usize = 24;

/// The closed polyline `ring` (a bead's offset of the outer section `outer`) re-started where
/// the path steps onto it from the outer section's point 0: the ring's point nearest that point
/// (inserted on its segment), unless the straight step to it crosses the outer ring or the bead
/// itself. That happens where point 0 is the tip of a deep texture's crest that leans back
/// over the flank before it: the nozzle would drive back through the flank it has just laid (a
/// loop at every layer's seam, found by random designs). Then the nearest foot (of the
/// [`STEP_CANDIDATES`] nearest segments') whose step crosses neither; the nearest if none.
fn starting_at_step(ring: &[DVec2], outer: &[DVec2]) -> Vec<DVec2> {
    let (m, p) = (ring.len(), outer[0]);
    let feet: Vec<(f64, usize, DVec2)> = (0..m)
        .map(|i| {
            let (a, b) = (ring[i], ring[(i + 1) % m]);
            let (d, f) = crate::geometry::point_segment_distance(p, a, b);
            (d, i, a.lerp(b, f))
        })
        .collect();
    let nearest = feet
        .iter()
        .copied()
        .min_by(|x, y| x.0.total_cmp(&y.0))
        .expect("a ring has segments");
    let (_, at, foot) = if step_is_clear(p, nearest.2, nearest.1, ring, outer) {
        nearest
    } else {
        let mut order = feet;
        order.sort_by(|x, y| x.0.total_cmp(&y.0));
        order
            .into_iter()
            .take(STEP_CANDIDATES)
            .find(|&(_, i, f)| step_is_clear(p, f, i, ring, outer))
            .unwrap_or(nearest)
    };
    let mut out = Vec::with_capacity(m + 1);
    out.push(foot);
    out.extend((1..=m).map(|s| ring[(at + s) % m]));
    // The vertex after the foot may coincide with it; drop a zero-length first step.
    crate::geometry::dedup_closed(&out)
}

/// Whether the step from `outer[0]` to `foot` (on segment `at` of `ring`) crosses no segment of
/// the closed polylines `outer` and `ring` (touching where it starts and ends aside).
fn step_is_clear(p: DVec2, foot: DVec2, at: usize, ring: &[DVec2], outer: &[DVec2]) -> bool {
    let crosses = |a: DVec2, b: DVec2| crate::geometry::proper_crossing(p, foot, a, b).is_some();
    let n = outer.len();
    // The outer ring's segments, but the two that meet at point 0.
    let outer_clear = (1..n - 1).all(|i| !crosses(outer[i], outer[i + 1]));
    let m = ring.len();
    outer_clear
        && (0..m)
            .filter(|&i| i != at)
            .all(|i| !crosses(ring[i], ring[(i + 1) % m]))
}

/// Moves the points of a bead's section outward along its normal by `amplitude · tri(N·i/n)`,
/// `tri` the unit triangle wave (0 at whole numbers, 1 half-way).
fn weave(section: &mut Section, crests: f64, amplitude: f64) {
    let n = section.points.len();
    let normals = outward_normals(&section.xy());
    for (i, (p, nrm)) in section.points.iter_mut().zip(normals).enumerate() {
        let x = crests * i as f64 / n as f64;
        let tri = 1.0 - (2.0 * x.fract() - 1.0).abs();
        p.x += nrm.x * amplitude * tri;
        p.y += nrm.y * amplitude * tri;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::load::parse_design;
    use crate::pipeline::build_surface;

    fn surface(lower: &str, upper: &str) -> Surface {
        build_surface(
            &parse_design(&format!(
                "version = 1\n[shape]\nheight = 10.0\nsamples = 360\nbase_layers = 0\n[shape.lower]\n{lower}\n[shape.upper]\n{upper}\n"
            ))
            .unwrap(),
        )
        .unwrap()
    }

    /// Distance from `p` to the closed polyline `ring`.
    fn distance_to(ring: &[DVec2], p: DVec2) -> f64 {
        (0..ring.len())
            .map(|i| {
                crate::geometry::point_segment_distance(p, ring[i], ring[(i + 1) % ring.len()]).0
            })
            .fold(f64::INFINITY, f64::min)
    }

    #[test]
    fn a_cylinder_gets_concentric_beads_a_line_width_apart() {
        let s = surface(
            "type = \"circle\"\nradius = 30.0",
            "type = \"circle\"\nradius = 30.0",
        );
        let beads = inner_beads(&s, 3, 3.0, None).unwrap();
        assert_eq!(beads.len(), 2);
        let c = s.center;
        for (j, bead) in beads.iter().enumerate() {
            assert_eq!(bead.len(), s.sections.len());
            let r = 30.0 - 3.0 * (j + 1) as f64;
            for (sec, outer) in bead.iter().zip(&s.sections) {
                assert_eq!(sec.points.len(), 360);
                for (q, o) in sec.points.iter().zip(&outer.points) {
                    // The sampled circle is a polygon: its offset lies within the chord's sagitta.
                    assert!((q.truncate().distance(c) - r).abs() < 0.01, "{q}");
                    assert_eq!(q.z, o.z);
                }
                // Point 0 straight inward of the outer point 0.
                let (o0, q0) = (outer.points[0].truncate(), sec.points[0].truncate());
                assert!((o0.distance(q0) - 3.0 * (j + 1) as f64).abs() < 0.01);
            }
        }
    }

    #[test]
    fn a_star_s_inner_bead_is_a_line_width_inside_everywhere_and_never_loops() {
        let star = "type = \"star\"\npoints = 6\nouter_radius = 50.0\ninner_radius = 30.0";
        let s = surface(star, star);
        let w = 3.0;
        let bead = &inner_beads(&s, 2, w, None).unwrap()[0];
        let outer = s.sections[3].xy();
        let inner = bead[3].xy();
        for q in &inner {
            assert!((distance_to(&outer, *q) - w).abs() < 0.02, "{q}");
        }
        // Along the sides every outer point has the inner bead a width away (touching, no gap);
        // only at the star's sharp tips is the inner bead's rounded corner further, w/sin(α/2)
        // for a tip angle α.
        let touching = outer
            .iter()
            .filter(|p| distance_to(&inner, **p) < w + 0.02)
            .count();
        // (Measured: 306 of 360 samples, the rest next to the six tips.)
        assert!(touching as f64 > 0.8 * outer.len() as f64, "{touching}");
        assert!(outer.iter().all(|p| distance_to(&inner, *p) < 2.0 * w));
        // …and the inner bead is a simple ring.
        assert!(crate::geometry::find_self_intersection(&inner).is_none());
    }

    #[test]
    fn folded_sections_still_get_a_clean_inner_bead() {
        // The benchmark vase with its wall replaced by a rose pushed out three times the radius
        // of curvature between its petals, folds and all (what a fold wider than the shape's
        // reach or a texture deeper than a corner leaves): small loops in every section.
        let d = parse_design(include_str!("../../../assets/benchmarks/vase-720x300.toml")).unwrap();
        let mut s = build_surface(&d).unwrap();
        let rose: Vec<DVec2> = (0..720)
            .map(|i| {
                let t = std::f64::consts::TAU * i as f64 / 720.0;
                s.center + DVec2::from_angle(t) * (40.0 + 8.0 * (6.0 * t).cos())
            })
            .collect();
        let folded: Vec<DVec2> = rose
            .iter()
            .zip(crate::geometry::outward_normals(&rose))
            .map(|(p, n)| *p + n * 12.0)
            .collect();
        for section in &mut s.sections {
            let z = section.points[0].z;
            section.points = folded.iter().map(|p| p.extend(z)).collect();
        }
        assert!(crate::geometry::find_self_intersection(&s.sections[150].xy()).is_some());
        let bead = &inner_beads(&s, 2, 3.0, None).unwrap()[0];
        for k in [1, 150, 299] {
            let inner = bead[k].xy();
            assert!(
                crate::geometry::find_self_intersection(&inner).is_none(),
                "layer {k}"
            );
            // A width from the outer bead with its loops cut off (the tails reach 4 mm in).
            let outer = crate::geometry::without_loops(&s.sections[k].xy());
            for q in inner.iter().step_by(7) {
                let d = distance_to(&outer, *q);
                assert!(d > 3.0 - 0.05, "layer {k}: {q} {d}");
            }
        }
    }

    /// A vessel 36 mm across whose section 35 the offsetting library leaves empty when offset
    /// 3 mm inward as it is (the case `any_vessel_gives_one_printable_spiral` found): the bead
    /// is offset from the section resampled, 3 mm inside it.
    #[test]
    fn a_wide_section_the_library_cannot_offset_gets_its_inner_bead() {
        let d = parse_design(
            "version = 1\n[printer]\nlayer_height = 0.5\nmin_layer_height = 0.125\n\
             [shape]\nheight = 38.23433352529929\nsamples = 241\nbase_layers = 0\nwalls = 2\n\
             [shape.lower]\ntype = \"circle\"\nradius = 20.42491727500761\n\
             [shape.upper]\ntype = \"rose\"\nradius = 28.850951106383206\n\
             amplitude = 4.130341755074595\npetals = 6\n\
             [[control.vertical]]\npoints = [[0.0, 0.0], [0.5, -4.359722931641384], [1.0, 0.0]]\n",
        )
        .unwrap();
        let s = build_surface(&d).unwrap();
        let xy = s.sections[35].xy();
        assert_eq!(
            crate::base_fill::inward_offset_rings(&xy, 3.0).map(|r| r.len()),
            Some(0),
            "the library offsets this section now: the workaround may go"
        );
        let bead = &inner_beads(&s, 2, 3.0, None).unwrap()[0];
        for q in bead[35].xy().iter().step_by(5) {
            let d = distance_to(&xy, *q);
            assert!((d - 3.0).abs() < 0.05, "{q}: {d} mm inside");
        }
    }

    #[test]
    fn a_vessel_narrower_than_its_beads_is_refused_with_the_layer() {
        let s = surface(
            "type = \"ellipse\"\nrx = 40.0\nry = 5.0",
            "type = \"ellipse\"\nrx = 40.0\nry = 5.0",
        );
        let e = inner_beads(&s, 3, 3.0, None).unwrap_err();
        assert_eq!(e.field, "shape.walls");
        assert!(
            e.message.contains("layer 0") && e.message.contains("3 beads"),
            "{e}"
        );
    }

    #[test]
    fn ties_weave_a_quarter_bead_outward_on_the_same_crests_every_layer() {
        let s = surface(
            "type = \"circle\"\nradius = 30.0",
            "type = \"circle\"\nradius = 30.0",
        );
        let bead = &inner_beads(&s, 2, 3.0, Some(0)).unwrap()[0];
        let c = s.center;
        let radii = |k: usize| -> Vec<f64> {
            bead[k]
                .points
                .iter()
                .map(|q| q.truncate().distance(c))
                .collect()
        };
        let r = radii(2);
        let (lo, hi) = r
            .iter()
            .fold((f64::MAX, f64::MIN), |(a, b), &x| (a.min(x), b.max(x)));
        // The crests fall between samples (22.5 samples a tie): the highest sample is within a
        // sample's share of the wave below 27.75.
        assert!(
            (lo - 27.0).abs() < 0.01 && hi > 27.7 && hi < 27.75 + 1e-9,
            "{lo} {hi}"
        );
        // 2π·30 / 12 ≈ 15.7 → 16 ties round, the same on the next layer.
        let crests = r
            .iter()
            .enumerate()
            .filter(|&(i, &x)| x > r[(i + 359) % 360] && x >= r[(i + 1) % 360])
            .count();
        assert_eq!(crests, 16);
        for (a, b) in radii(2).iter().zip(radii(7)) {
            assert!((a - b).abs() < 1e-9);
        }
    }
}
