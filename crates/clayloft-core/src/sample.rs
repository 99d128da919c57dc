//! Sampling and correspondence (SPEC §1.3): both contours are sampled at N points equally spaced
//! by arc length, starting where the ray from the anchor towards +x meets the contour, so point i
//! of one corresponds to point i of the other. A cyclic offset of the upper samples then minimises
//! the total twist Σ |lowerᵢ − upper₍ᵢ₊ₒ₎|².

use glam::DVec2;

use crate::contour::Contour;
use crate::geometry::resample_closed;

/// `count` points equally spaced by arc length along the contour, counter-clockwise, starting on
/// the ray from `anchor` in the +x direction (the outermost crossing if there are several).
pub fn sample_from_anchor(contour: &Contour, anchor: DVec2, count: usize) -> Vec<DVec2> {
    let pts = &contour.points;
    let n = pts.len();
    // Find the crossing of the ray y = anchor.y, x > anchor.x with the largest x.
    let mut best: Option<(f64, usize, DVec2)> = None;
    for i in 0..n {
        let (a, b) = (pts[i], pts[(i + 1) % n]);
        let (da, db) = (a.y - anchor.y, b.y - anchor.y);
        if (da <= 0.0 && db > 0.0) || (da > 0.0 && db <= 0.0) {
            let f = da / (da - db);
            let p = a.lerp(b, f);
            if p.x > anchor.x && best.is_none_or(|(x, _, _)| p.x > x) {
                best = Some((p.x, i, p));
            }
        }
    }
    let rotated: Vec<DVec2> = match best {
        Some((_, i, p)) => {
            let mut v = Vec::with_capacity(n + 1);
            v.push(p);
            v.extend((1..=n).map(|k| pts[(i + k) % n]));
            v
        }
        // The anchor sees no crossing (cannot happen for a closed curve around it); keep order.
        None => pts.clone(),
    };
    resample_closed(&rotated, count)
}

/// Total twist `Σ |aᵢ − b₍ᵢ₊ₒ₎|²` for offset `o` (summed in the order of i, without a division
/// per term: b's indices wrap once, at i = n − o).
fn twist(a: &[DVec2], b: &[DVec2], o: usize) -> f64 {
    twist_within(a, b, o, f64::INFINITY).unwrap_or(f64::INFINITY)
}

/// [`twist`] for offset `o` where it is at most `bound`, summed alike; `None` as soon as the sum
/// passes `bound`. Its terms are never negative, so the sum never falls as terms are added (a
/// rounded sum of a non-negative term is never less than the sum before it): a sum past the
/// bound part way is past it at the end.
fn twist_within(a: &[DVec2], b: &[DVec2], o: usize, bound: f64) -> Option<f64> {
    let o = o % a.len().max(1);
    let (a_head, a_tail) = a.split_at(a.len() - o);
    let (b_head, b_tail) = b.split_at(o);
    let mut sum = 0.0;
    for (k, (p, q)) in a_head
        .iter()
        .zip(b_tail)
        .chain(a_tail.iter().zip(b_head))
        .enumerate()
    {
        sum += p.distance_squared(*q);
        // Tested every few terms: a comparison a term costs more than it saves.
        if k.is_multiple_of(TWIST_TEST_EVERY) && sum > bound {
            return None;
        }
    }
    (sum <= bound || sum.is_nan() || bound.is_nan()).then_some(sum)
}

/// Terms of [`twist_within`] between its tests against the bound.
const TWIST_TEST_EVERY: usize = 16;

/// The cyclic offset `o` minimising total twist between `lower` and `upper` (same length).
///
/// Exhaustive for up to 2048 samples; above that, a coarse search with stride `n / 1024` refined
/// around the best coarse offset.
pub fn min_twist_offset(lower: &[DVec2], upper: &[DVec2]) -> usize {
    let n = lower.len();
    let best_in = |cands: &mut dyn Iterator<Item = usize>| {
        cands
            .map(|o| (twist(lower, upper, o), o))
            .min_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)))
            .map(|(_, o)| o)
            .unwrap_or(0)
    };
    if n <= 2048 {
        // The offsets in parts on the machine's cores; the least (twist, offset) of the parts'
        // is the least of all.
        let parts = crate::parallel::map_ranges(n, 256, |r| vec![(twist_min(lower, upper, r))]);
        return parts
            .into_iter()
            .min_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)))
            .map_or(0, |(_, o)| o);
    }
    let stride = n / 1024;
    let coarse = best_in(&mut (0..n).step_by(stride));
    best_in(&mut (0..=2 * stride).map(|d| (coarse + n + d - stride) % n))
}

/// The least (twist, offset) over the offsets `range` (the first of equal twists).
///
/// Every 32nd offset first, then the others, each summed only until it passes the least twist
/// found so far (it cannot be the least then: see [`twist_within`]): most offsets of smooth
/// contours are passed over after a small part of their terms (the benchmark vase's 720
/// samples: its layer plan 0.42 → 0.14 ms, `clayloft gcode` 0.984 of the wall, alternating,
/// 556 rounds, 2026-12-07). The same offset as summing every offset in full, to the bit.
fn twist_min(lower: &[DVec2], upper: &[DVec2], range: std::ops::Range<usize>) -> (f64, usize) {
    let mut best = (f64::INFINITY, 0);
    let mut seen = false;
    let first = range.clone().step_by(TWIST_COARSE);
    let rest = range
        .clone()
        .filter(|o| !(o - range.start).is_multiple_of(TWIST_COARSE));
    for o in first.chain(rest) {
        if let Some(t) = twist_within(lower, upper, o, best.0) {
            let candidate = (t, o);
            if !seen || candidate.0.total_cmp(&best.0).then(o.cmp(&best.1)).is_lt() {
                best = candidate;
                seen = true;
            }
        }
    }
    best
}

/// Stride of [`twist_min`]'s first offsets.
const TWIST_COARSE: usize = 32;

/// Rotates `upper` by the minimal-twist offset so that `upper[i]` corresponds to `lower[i]`.
pub fn correspond(lower: &[DVec2], upper: &[DVec2]) -> Vec<DVec2> {
    let o = min_twist_offset(lower, upper);
    let n = upper.len();
    (0..n).map(|i| upper[(i + o) % n]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contour::DENSE_POINTS;
    use crate::design::ContourSpec;
    use proptest::prelude::*;

    fn contour(spec: ContourSpec) -> Contour {
        Contour::from_spec(&spec, DENSE_POINTS).unwrap()
    }

    #[test]
    fn circle_samples_start_on_plus_x_and_are_equally_spaced() {
        let c = contour(ContourSpec::Circle { radius: 40.0 });
        let s = sample_from_anchor(&c, DVec2::ZERO, 200);
        assert!(s[0].distance(DVec2::new(40.0, 0.0)) < 1e-9);
        assert!(s[50].distance(DVec2::new(0.0, 40.0)) < 1e-2);
        let d0 = s[0].distance(s[1]);
        for i in 0..200 {
            let d = s[i].distance(s[(i + 1) % 200]);
            assert!((d - d0).abs() / d0 < 0.01);
        }
    }

    #[test]
    fn twist_offset_undoes_a_rotation() {
        let c = contour(ContourSpec::Ellipse { rx: 50.0, ry: 30.0 });
        let a = sample_from_anchor(&c, DVec2::ZERO, 120);
        let rotated: Vec<DVec2> = (0..120).map(|i| a[(i + 7) % 120]).collect();
        assert_eq!(min_twist_offset(&a, &rotated), 113);
        assert_eq!(correspond(&a, &rotated), a);
    }

    /// Of two offsets with the same least twist, the first: here offset 5, met only after
    /// offset 32 (every 32nd offset is summed first), which is as twisted (the upper ring
    /// repeats itself every 27 samples).
    #[test]
    fn equal_least_twists_give_the_first_offset() {
        let b: Vec<DVec2> = (0..54)
            .map(|j| DVec2::from_angle(std::f64::consts::TAU * (j % 27) as f64 / 27.0) * 30.0)
            .collect();
        let a: Vec<DVec2> = (0..54).map(|i| b[(i + 5) % 54]).collect();
        assert_eq!(twist(&a, &b, 5).to_bits(), twist(&a, &b, 32).to_bits());
        assert_eq!(twist_min(&a, &b, 0..54), (0.0, 5));
    }

    #[test]
    fn large_sample_counts_use_the_refined_search() {
        let c = contour(ContourSpec::Circle { radius: 30.0 });
        let a = sample_from_anchor(&c, DVec2::ZERO, 5000);
        let b: Vec<DVec2> = (0..5000).map(|i| a[(i + 1234) % 5000]).collect();
        assert_eq!(min_twist_offset(&a, &b), 5000 - 1234);
    }

    /// Arc-length position of `p` along the closed polyline `poly` (p must lie on it).
    fn arc_position(poly: &[DVec2], p: DVec2) -> f64 {
        let s = crate::geometry::cumulative_length(poly);
        let n = poly.len();
        (0..n)
            .map(|i| {
                let (d, f) = crate::geometry::point_segment_distance(p, poly[i], poly[(i + 1) % n]);
                (d, s[i] + f * (s[i + 1] - s[i]))
            })
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .map(|(_, s)| s)
            .unwrap()
    }

    proptest! {
        /// The least twist with the offsets passed over once past the least so far is the
        /// least of every offset summed in full (offset and twist, to the bit), on roses turned
        /// by any offset and on jagged rings, with ties (a ring against itself turned by half
        /// of a two-fold symmetry).
        #[test]
        fn the_least_twist_is_the_exhaustive_searchs(
            r in 20.0..80.0f64, amp in 0.0..0.5f64, k in 1usize..12, n in 3usize..900,
            turn in 0usize..900, jitter in proptest::collection::vec(-5.0..5.0f64, 900),
            jagged in proptest::bool::ANY,
        ) {
            let c = contour(ContourSpec::Rose { radius: r, amplitude: amp * r, petals: k });
            let a = sample_from_anchor(&c, DVec2::ZERO, n);
            let b: Vec<DVec2> = (0..n)
                .map(|i| {
                    let q = a[(i + turn) % n];
                    if jagged { q + DVec2::splat(jitter[i]) } else { q }
                })
                .collect();
            for range in [0..n, 0..n / 2, n / 3..n] {
                let exhaustive = range
                    .clone()
                    .map(|o| (twist(&a, &b, o), o))
                    .min_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)))
                    .unwrap_or((f64::INFINITY, 0));
                let found = twist_min(&a, &b, range);
                prop_assert_eq!((found.0.to_bits(), found.1), (exhaustive.0.to_bits(), exhaustive.1));
            }
        }

        /// Equal arc-length sampling of any rose curve: the arc between consecutive samples,
        /// measured along the curve, is within 1 % of the mean.
        #[test]
        fn sampling_is_equal_arc_length(r in 20.0..80.0f64, amp in 0.0..0.5f64, k in 1usize..12, n in 30usize..400) {
            let c = contour(ContourSpec::Rose { radius: r, amplitude: amp * r, petals: k });
            let s = sample_from_anchor(&c, DVec2::ZERO, n);
            let pos: Vec<f64> = s.iter().map(|&p| arc_position(&c.points, p)).collect();
            let total = crate::geometry::closed_length(&c.points);
            for i in 0..n {
                let gap = (pos[(i + 1) % n] - pos[i]).rem_euclid(total);
                prop_assert!((gap - total / n as f64).abs() / (total / n as f64) < 0.01, "gap {gap}");
            }
        }
    }
}
