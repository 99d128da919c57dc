//! Plain 2D polyline geometry shared by the pipeline stages: area, orientation, arc length,
//! resampling and self-intersection tests on closed polylines.
//!
//! A closed polyline is a `&[DVec2]` whose last point connects back to the first; the first point
//! is *not* repeated at the end.

use glam::DVec2;

/// Two points closer than this (mm) are the same point. Contours are tens of millimetres across,
/// so a micrometre is far below anything a printer resolves and far above rounding noise.
pub const POINT_EPS: f64 = 1e-6;

/// Signed area of a closed polyline by the shoelace formula, `A = ½ Σ (xᵢ yᵢ₊₁ − xᵢ₊₁ yᵢ)`.
/// Positive for counter-clockwise order.
pub fn signed_area(points: &[DVec2]) -> f64 {
    segments_closed(points)
        .map(|(a, b)| a.perp_dot(b))
        .sum::<f64>()
        * 0.5
}

/// The segments of a closed polyline in order, the closing one last (neighbours by an iterator,
/// not by index modulo n: a division per vertex costs more than the work on it).
fn segments_closed(points: &[DVec2]) -> impl Iterator<Item = (DVec2, DVec2)> + '_ {
    points
        .iter()
        .copied()
        .zip(points.iter().skip(1).chain(points.first()).copied())
}

/// Total length of a closed polyline (including the closing segment).
pub fn closed_length(points: &[DVec2]) -> f64 {
    segments_closed(points).map(|(a, b)| a.distance(b)).sum()
}

/// Cumulative arc length at each vertex of a closed polyline: `s[0] = 0`, `s[i] = Σ_{j<i} |p_{j+1} − p_j|`.
/// The returned vector has `n + 1` entries; the last one is the closed length.
pub fn cumulative_length(points: &[DVec2]) -> Vec<f64> {
    let mut s = Vec::with_capacity(points.len() + 1);
    let mut acc = 0.0;
    s.push(0.0);
    for (a, b) in segments_closed(points) {
        acc += a.distance(b);
        s.push(acc);
    }
    s
}

/// Resamples a closed polyline at `count` points equally spaced by arc length, starting at its
/// first vertex and following its order. Linear interpolation along the polyline's segments.
pub fn resample_closed(points: &[DVec2], count: usize) -> Vec<DVec2> {
    let n = points.len();
    let s = cumulative_length(points);
    let total = s[n];
    let step = total / count as f64;
    let mut out = Vec::with_capacity(count);
    let mut seg = 0;
    for k in 0..count {
        let target = k as f64 * step;
        while seg + 1 < n && s[seg + 1] <= target {
            seg += 1;
        }
        let len = s[seg + 1] - s[seg];
        let f = if len > 0.0 {
            (target - s[seg]) / len
        } else {
            0.0
        };
        out.push(points[seg].lerp(points[(seg + 1) % n], f));
    }
    out
}

/// Removes consecutive duplicates (closer than [`POINT_EPS`]), including a last point equal to the
/// first.
pub fn dedup_closed(points: &[DVec2]) -> Vec<DVec2> {
    let mut out: Vec<DVec2> = Vec::with_capacity(points.len());
    for &p in points {
        if out.last().is_none_or(|q: &DVec2| q.distance(p) > POINT_EPS) {
            out.push(p);
        }
    }
    while out.len() > 1 && out[0].distance(out[out.len() - 1]) <= POINT_EPS {
        out.pop();
    }
    out
}

/// Whether segments `a0–a1` and `b0–b1` cross or touch (proper or collinear overlap).
pub fn segments_intersect(a0: DVec2, a1: DVec2, b0: DVec2, b1: DVec2) -> bool {
    let d1 = (a1 - a0).perp_dot(b0 - a0);
    let d2 = (a1 - a0).perp_dot(b1 - a0);
    let d3 = (b1 - b0).perp_dot(a0 - b0);
    let d4 = (b1 - b0).perp_dot(a1 - b0);
    let eps = 1e-12;
    if ((d1 > eps && d2 < -eps) || (d1 < -eps && d2 > eps))
        && ((d3 > eps && d4 < -eps) || (d3 < -eps && d4 > eps))
    {
        return true;
    }
    let on = |p: DVec2, q0: DVec2, q1: DVec2, d: f64| {
        d.abs() <= eps
            && p.x >= q0.x.min(q1.x) - eps
            && p.x <= q0.x.max(q1.x) + eps
            && p.y >= q0.y.min(q1.y) - eps
            && p.y <= q0.y.max(q1.y) + eps
    };
    on(b0, a0, a1, d1) || on(b1, a0, a1, d2) || on(a0, b0, b1, d3) || on(a1, b0, b1, d4)
}

/// Where segments `a0–a1` and `b0–b1` cross properly (each one's ends strictly on either side
/// of the other; touching and collinear overlaps are not crossings): the fractions `(t, u)`
/// along each, the crossing being `a0 + t·(a1 − a0) = b0 + u·(b1 − b0)`. Their boxes first,
/// which rules out most pairs.
pub fn proper_crossing(a0: DVec2, a1: DVec2, b0: DVec2, b1: DVec2) -> Option<(f64, f64)> {
    if a0.max(a1).cmplt(b0.min(b1)).any() || b0.max(b1).cmplt(a0.min(a1)).any() {
        return None;
    }
    let (da, db) = (a1 - a0, b1 - b0);
    let (b0_side, b1_side) = (da.perp_dot(b0 - a0), da.perp_dot(b1 - a0));
    let (a0_side, a1_side) = (db.perp_dot(a0 - b0), db.perp_dot(a1 - b0));
    (b0_side * b1_side < 0.0 && a0_side * a1_side < 0.0)
        .then(|| (a0_side / (a0_side - a1_side), b0_side / (b0_side - b1_side)))
}

/// Finds a pair of non-adjacent segments of a closed polyline that intersect, if any.
///
/// Sweep over x: segments sorted by their left end, an active list pruned by right end. For the
/// contours of vessels only a handful of segments span any x, so this is close to `O(n log n)`.
pub fn find_self_intersection(points: &[DVec2]) -> Option<(usize, usize)> {
    let n = points.len();
    if n < 4 {
        return None;
    }
    let seg = |i: usize| (points[i], points[(i + 1) % n]);
    let mut order: Vec<usize> = (0..n).collect();
    let min_x = |i: usize| {
        let (a, b) = seg(i);
        a.x.min(b.x)
    };
    order.sort_by(|&a, &b| min_x(a).total_cmp(&min_x(b)));
    let mut active: Vec<usize> = Vec::new();
    for &i in &order {
        let (a0, a1) = seg(i);
        let left = a0.x.min(a1.x);
        active.retain(|&j| {
            let (b0, b1) = seg(j);
            b0.x.max(b1.x) >= left
        });
        for &j in &active {
            let adjacent = (i + 1) % n == j || (j + 1) % n == i;
            if adjacent {
                continue;
            }
            let (b0, b1) = seg(j);
            let (ylo, yhi) = (a0.y.min(a1.y), a0.y.max(a1.y));
            if b0.y.max(b1.y) < ylo || b0.y.min(b1.y) > yhi {
                continue;
            }
            if segments_intersect(a0, a1, b0, b1) {
                return Some((i.min(j), i.max(j)));
            }
        }
        active.push(i);
    }
    None
}

/// The closed polyline with the small loops it makes where it crosses itself cut off: for
/// crossing segments `i < j` the shorter side between them (at most an eighth of the points) is
/// replaced by the crossing point, until no crossing is left (each pass removes at least one
/// point, so at most `n` passes). A crossing of two far-apart parts is left as it is.
pub fn without_loops(points: &[DVec2]) -> Vec<DVec2> {
    let mut p = points.to_vec();
    while p.len() >= 4 {
        let Some((i, j)) = find_self_intersection(&p) else {
            break;
        };
        let n = p.len();
        let x = crossing_point(p[i], p[(i + 1) % n], p[j], p[(j + 1) % n]);
        if (j - i).min(n - (j - i)) > n / 8 {
            // Not a small loop: two parts of the outline cross; nothing to cut.
            break;
        }
        if j - i <= n / 2 {
            p.splice(i + 1..=j, [x]);
        } else {
            p = std::iter::once(x)
                .chain(p[i + 1..=j].iter().copied())
                .collect();
        }
    }
    p
}

/// Outward unit normal in XY at each vertex of a counter-clockwise closed polyline, from the
/// central difference `pᵢ₊₁ − pᵢ₋₁` rotated by −90°.
pub fn outward_normals(points: &[DVec2]) -> Vec<DVec2> {
    (0..points.len())
        .map(|i| outward_normal_at(points, i))
        .collect()
}

/// The outward unit normal of [`outward_normals`] at vertex i alone.
#[inline]
pub fn outward_normal_at(points: &[DVec2], i: usize) -> DVec2 {
    let (before, after) = ring_neighbours(i, points.len());
    normal_from_neighbours(points[before], points[after])
}

/// The vertices before and after vertex i of a closed ring of `n` (compared, not taken modulo
/// n: a division per vertex costs more than the work done on it).
#[inline]
pub fn ring_neighbours(i: usize, n: usize) -> (usize, usize) {
    (
        if i == 0 { n - 1 } else { i - 1 },
        if i + 1 == n { 0 } else { i + 1 },
    )
}

/// The outward unit normal at a vertex of a counter-clockwise ring from its neighbours:
/// `after − before` rotated by −90°, unit length (zero where they coincide).
#[inline]
pub fn normal_from_neighbours(before: DVec2, after: DVec2) -> DVec2 {
    let d = after - before;
    DVec2::new(d.y, -d.x).normalize_or_zero()
}

/// The smallest and largest x and y of a set of points (their bounding box's corners).
pub fn bounds(points: impl IntoIterator<Item = DVec2>) -> (DVec2, DVec2) {
    points.into_iter().fold(
        (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(p), hi.max(p)),
    )
}

/// True when `p` lies inside the closed polyline (even–odd rule: a ray from p crosses it an
/// odd number of times).
pub fn contains_point(poly: &[DVec2], p: DVec2) -> bool {
    let n = poly.len();
    let mut inside = false;
    for i in 0..n {
        let (a, b) = (poly[i], poly[(i + 1) % n]);
        if (a.y > p.y) != (b.y > p.y) && p.x < a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x) {
            inside = !inside;
        }
    }
    inside
}

/// Pairs of segments [`trim_swallowtails`] may test per point of a ring. The benchmark vase's
/// sections need about 3 (six folds of some 300 tests each in 720 points: their sides cross
/// about 13 segments from their ends); this bounds the time a hostile ring takes (a 40-pointed
/// star pushed 40 mm out, 8 000 samples: its 101 sections 29 ms untrimmed, 378 ms at 64 tests
/// per point).
pub const TRIM_TESTS_PER_POINT: usize = 16;

/// The crossing point of segments `a0–a1` and `b0–b1` when they cross or touch.
fn segment_crossing(a0: DVec2, a1: DVec2, b0: DVec2, b1: DVec2) -> Option<DVec2> {
    segments_intersect(a0, a1, b0, b1).then(|| crossing_point(a0, a1, b0, b1))
}

/// Where the line through `a0–a1` meets the line through `b0–b1`, clamped to the first
/// segment; `a1` for parallel lines (a collinear overlap is cut at the shared stretch's start).
fn crossing_point(a0: DVec2, a1: DVec2, b0: DVec2, b1: DVec2) -> DVec2 {
    let (da, db) = (a1 - a0, b1 - b0);
    let denom = da.perp_dot(db);
    if denom.abs() > 1e-300 {
        a0 + da * ((b0 - a0).perp_dot(db) / denom).clamp(0.0, 1.0)
    } else {
        a1
    }
}

/// Folds the swallowtails out of a closed polyline moved point by point from `reference` (the
/// same number of points, the same order), in place; returns how many points it moved and the
/// farthest it moved one.
///
/// A concave stretch pushed outward further than its radius of curvature (an offset `d > ρ`)
/// turns back on itself: its segments run against the reference's, between two cusps, and the
/// stretches before and after cross (a swallowtail). The wall there is a corner at the
/// crossing: the tail's points are spread over it, in order and apart, so the ring keeps
/// its point count (one point per column) and the nozzle turns the corner once instead of
/// tracing the loop.
///
/// Each run of reversed segments is looked at on its own, in the points as given: its crossing
/// is searched within `reach` segments before and after it (nearest first); a longer run, or
/// one whose sides do not cross within reach, is left as it is. The search tests at most
/// [`TRIM_TESTS_PER_POINT`] pairs of segments per point of the ring, whatever the ring: runs
/// past that budget are left as they are too (for the checker to judge).
pub fn trim_swallowtails(points: &mut [DVec2], reference: &[DVec2], reach: usize) -> (usize, f64) {
    let n = points.len();
    if n < 4 || reference.len() != n || reach == 0 {
        return (0, 0.0);
    }
    let next = |i: usize| if i + 1 == n { 0 } else { i + 1 };
    let reversed =
        |p: &[DVec2], j: usize| (p[next(j)] - p[j]).dot(reference[next(j)] - reference[j]) < 0.0;
    if !(0..n).any(|j| reversed(points, j)) {
        return (0, 0.0);
    }
    // The first segment that is not reversed: runs are found from there on, so none wraps past
    // the start of the search.
    let Some(first) = (0..n).find(|&j| !reversed(points, j)) else {
        return (0, 0.0);
    };
    let given = points.to_vec();
    let mut trimmed = false;
    let mut budget = TRIM_TESTS_PER_POINT * n;
    let mut s = 0;
    while s < n && budget > 0 {
        let a = (first + s) % n;
        if !reversed(&given, a) {
            s += 1;
            continue;
        }
        // The run a ..= b of reversed segments.
        let mut len = 1;
        while len < n && reversed(&given, (a + len) % n) {
            len += 1;
        }
        s += len;
        if len > reach || 2 * reach + len >= n {
            continue;
        }
        let b = (a + len - 1) % n;
        // The crossing of segment j (before the run) and k (after it) nearest to the run.
        let mut crossing = None;
        'search: for sum in 2..=2 * reach {
            for back in sum.saturating_sub(reach).max(1)..=(sum - 1).min(reach) {
                if budget == 0 {
                    break 'search;
                }
                budget -= 1;
                let j = (a + n - back) % n;
                let k = (b + sum - back) % n;
                if let Some(x) =
                    segment_crossing(given[j], given[next(j)], given[k], given[next(k)])
                {
                    crossing = Some((j, k, x));
                    break 'search;
                }
            }
        }
        if let Some((j, k, x)) = crossing {
            spread_over_corner(points, &given, j, k, x);
            trimmed = true;
        }
    }
    if !trimmed {
        return (0, 0.0);
    }
    // Counted at the end: folds close together may move the same point twice.
    points
        .iter()
        .zip(&given)
        .map(|(p, q)| p.distance(*q))
        .filter(|&d| d > 0.0)
        .fold((0, 0.0), |(count, most), d| (count + 1, d.max(most)))
}

/// Puts points `j + 1 ..= k` (of a ring, wrapping) on the corner `pⱼ → x → pₖ₊₁` that cuts off
/// their tail, evenly by length and in order, the one nearest the corner on it. Kept apart (none on `pⱼ`, `pₖ₊₁` or another), every point keeps a
/// direction to its neighbours, so normals, offsets and the toolpath see a corner, not a stack
/// of coincident points. A corner of no length is left alone.
fn spread_over_corner(points: &mut [DVec2], given: &[DVec2], j: usize, k: usize, x: DVec2) {
    let n = points.len();
    let (start, end) = (given[j], given[(k + 1) % n]);
    let (to_x, from_x) = (start.distance(x), x.distance(end));
    let length = to_x + from_x;
    if length <= POINT_EPS {
        return;
    }
    let count = (k + n - j) % n;
    let step = length / (count + 1) as f64;
    // The point nearest the corner goes onto it, unless that would put it on an end.
    let at_corner = ((to_x / step).round() as usize).clamp(1, count);
    let corner_inside = to_x > POINT_EPS && from_x > POINT_EPS;
    for r in 1..=count {
        let s = r as f64 * step;
        points[(j + r) % n] = if corner_inside && r == at_corner {
            x
        } else if s <= to_x {
            start.lerp(x, s / to_x)
        } else {
            x.lerp(end, (s - to_x) / from_x)
        };
    }
}

/// Distance from `p` to segment `a–b`, and the parameter `f ∈ [0, 1]` of the closest point.
pub fn point_segment_distance(p: DVec2, a: DVec2, b: DVec2) -> (f64, f64) {
    let ab = b - a;
    let len2 = ab.length_squared();
    let f = if len2 > 0.0 {
        ((p - a).dot(ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p.distance(a + ab * f), f)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::TAU;

    fn circle(r: f64, n: usize) -> Vec<DVec2> {
        (0..n)
            .map(|i| DVec2::from_angle(TAU * i as f64 / n as f64) * r)
            .collect()
    }

    /// A proper crossing gives where along each segment; touching at an end, running along
    /// the other or missing it is no crossing.
    #[test]
    fn a_proper_crossing_and_where_it_lies() {
        let v = |x, y| DVec2::new(x, y);
        let (t, u) = proper_crossing(v(0.0, 0.0), v(4.0, 0.0), v(1.0, -1.0), v(1.0, 3.0)).unwrap();
        assert!(
            (t - 0.25).abs() < 1e-12 && (u - 0.25).abs() < 1e-12,
            "{t} {u}"
        );
        assert!(proper_crossing(v(0.0, 0.0), v(4.0, 0.0), v(4.0, 0.0), v(5.0, 1.0)).is_none());
        assert!(proper_crossing(v(0.0, 0.0), v(4.0, 0.0), v(1.0, 0.0), v(3.0, 0.0)).is_none());
        assert!(proper_crossing(v(0.0, 0.0), v(4.0, 0.0), v(5.0, -1.0), v(5.0, 1.0)).is_none());
        assert!(proper_crossing(v(0.0, 0.0), v(4.0, 0.0), v(2.0, 0.0), v(2.0, 1.0)).is_none());
    }

    #[test]
    fn unit_square_area_and_orientation() {
        let sq = [
            DVec2::new(0.0, 0.0),
            DVec2::new(1.0, 0.0),
            DVec2::new(1.0, 1.0),
            DVec2::new(0.0, 1.0),
        ];
        assert!((signed_area(&sq) - 1.0).abs() < 1e-12);
        let rev: Vec<_> = sq.iter().rev().copied().collect();
        assert!((signed_area(&rev) + 1.0).abs() < 1e-12);
        assert!((closed_length(&sq) - 4.0).abs() < 1e-12);
    }

    #[test]
    fn resampling_is_equally_spaced() {
        let sq = [
            DVec2::new(0.0, 0.0),
            DVec2::new(4.0, 0.0),
            DVec2::new(4.0, 4.0),
            DVec2::new(0.0, 4.0),
        ];
        let r = resample_closed(&sq, 8);
        assert_eq!(r.len(), 8);
        assert!(r[1].distance(DVec2::new(2.0, 0.0)) < 1e-12);
        assert!(r[3].distance(DVec2::new(4.0, 2.0)) < 1e-12);
        assert!(r[7].distance(DVec2::new(0.0, 2.0)) < 1e-12);
    }

    #[test]
    fn circle_has_no_self_intersection_but_figure_eight_has() {
        assert_eq!(find_self_intersection(&circle(10.0, 500)), None);
        let eight: Vec<DVec2> = (0..400)
            .map(|i| {
                let t = TAU * i as f64 / 400.0;
                DVec2::new(t.sin(), (2.0 * t).sin() * 0.5)
            })
            .collect();
        assert!(find_self_intersection(&eight).is_some());
    }

    #[test]
    fn small_loops_are_cut_off_and_a_figure_eight_is_left_alone() {
        // A circle of 100 points with a small kink that crosses back over itself (a loop of 4
        // points near point 30).
        let mut c = circle(10.0, 100);
        let (a, b) = (c[30], c[33]);
        c[31] = b + (b - a) * 0.3;
        c[32] = a - (b - a) * 0.3;
        assert!(find_self_intersection(&c).is_some());
        let clean = without_loops(&c);
        assert_eq!(find_self_intersection(&clean), None);
        assert!(clean.len() >= 97 && clean.len() < 100, "{}", clean.len());
        // Everywhere else the outline is unchanged.
        assert!(
            clean
                .iter()
                .all(|p| (p.length() - 10.0).abs() < 0.1 || p.length() < 10.0)
        );
        assert_eq!(clean[0], c[0]);
        assert_eq!(clean[clean.len() - 1], c[99]);
        // A figure eight's crossing joins halves: no loop to cut.
        let eight: Vec<DVec2> = (0..400)
            .map(|i| {
                let t = TAU * i as f64 / 400.0;
                DVec2::new(t.sin(), (2.0 * t).sin() * 0.5)
            })
            .collect();
        assert_eq!(without_loops(&eight), eight);
    }

    /// A rose r = 40 + 8·cos 6θ (concave between the petals, radius of curvature 4 mm there).
    fn rose(n: usize) -> Vec<DVec2> {
        (0..n)
            .map(|i| {
                let t = TAU * i as f64 / n as f64;
                DVec2::from_angle(t) * (40.0 + 8.0 * (6.0 * t).cos())
            })
            .collect()
    }

    /// The ring pushed out along its normals by `d`.
    fn pushed(points: &[DVec2], d: f64) -> Vec<DVec2> {
        points
            .iter()
            .zip(outward_normals(points))
            .map(|(p, n)| *p + n * d)
            .collect()
    }

    fn reversed_segments(points: &[DVec2], reference: &[DVec2]) -> usize {
        let n = points.len();
        (0..n)
            .filter(|&j| {
                let k = (j + 1) % n;
                (points[k] - points[j]).dot(reference[k] - reference[j]) < 0.0
            })
            .count()
    }

    /// Distance from `p` to the closed polyline `ring`.
    fn distance_to(p: DVec2, ring: &[DVec2]) -> f64 {
        (0..ring.len())
            .map(|j| point_segment_distance(p, ring[j], ring[(j + 1) % ring.len()]).0)
            .fold(f64::INFINITY, f64::min)
    }

    /// Pushed 12 mm out, three times the radius of curvature between the petals, the rose
    /// folds over itself there (the tail's points come closer than 12 mm to the rose). Trimmed,
    /// nothing runs backwards, nothing crosses, every point is its column's (the count is kept)
    /// and the whole wall is 12 mm from the rose: the true offset. Without the trim the test
    /// fails on all three.
    #[test]
    fn a_concave_stretch_pushed_past_its_curvature_loses_its_swallowtail() {
        let reference = rose(720);
        let mut wall = pushed(&reference, 12.0);
        let folded = reversed_segments(&wall, &reference);
        assert!(folded >= 12, "{folded} reversed segments before the trim");
        let closest = wall
            .iter()
            .map(|p| distance_to(*p, &reference))
            .fold(f64::INFINITY, f64::min);
        assert!(closest < 11.0, "closest {closest}");
        let (moved, most) = trim_swallowtails(&mut wall, &reference, 32);
        assert!(moved > folded, "{moved} points moved");
        // The tails reached to 7.9 mm from the rose: moved out to 12 mm and along the wall.
        assert!(most > 4.0 && most < 30.0, "moved up to {most} mm");
        assert_eq!(wall.len(), 720);
        assert_eq!(reversed_segments(&wall, &reference), 0);
        assert_eq!(find_self_intersection(&wall), None);
        // Spread over the corner, no two points coincide: every point has a normal.
        for j in 0..720 {
            assert!(
                wall[j].distance(wall[(j + 1) % 720]) > 1e-4,
                "points {j} and after coincide"
            );
        }
        assert!(
            outward_normals(&wall)
                .iter()
                .all(|n| (n.length() - 1.0).abs() < 1e-9)
        );
        for p in &wall {
            let d = distance_to(*p, &reference);
            assert!(d > 12.0 - 0.05, "a point {d:.3} mm from the rose");
        }
    }

    /// Where the push stays within the radius of curvature (or the ring is convex) nothing is
    /// moved; a fold whose sides do not cross within reach is left as it is.
    #[test]
    fn a_wall_without_folds_is_left_as_it_is() {
        let reference = rose(720);
        for (ring, d) in [(rose(720), 3.0), (circle(30.0, 360), 12.0)] {
            let reference = if ring.len() == 720 {
                reference.clone()
            } else {
                ring.clone()
            };
            let mut wall = pushed(&ring, d);
            let before = wall.clone();
            assert_eq!(trim_swallowtails(&mut wall, &reference, 32), (0, 0.0));
            assert_eq!(wall, before);
        }
        let mut wall = pushed(&reference, 12.0);
        let before = wall.clone();
        assert_eq!(trim_swallowtails(&mut wall, &reference, 1), (0, 0.0));
        assert_eq!(wall, before);
    }

    #[test]
    fn normals_of_ccw_circle_point_outward() {
        let c = circle(5.0, 64);
        for (p, n) in c.iter().zip(outward_normals(&c)) {
            assert!((n - p.normalize()).length() < 1e-9);
        }
    }

    #[test]
    fn dedup_drops_repeats_and_closing_point() {
        let pts = [DVec2::ZERO, DVec2::ZERO, DVec2::X, DVec2::ONE, DVec2::ZERO];
        assert_eq!(dedup_closed(&pts).len(), 3);
    }
}

#[cfg(test)]
mod properties {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(200))]

        /// On any ring pushed any way from any reference (jagged, with repeated points),
        /// trimming keeps the point count, moves no more than it has, and only ever moves a
        /// point onto the ring as given (a fold's corner lies on its two sides).
        #[test]
        fn trimming_keeps_the_count_and_stays_on_the_ring(
            radii in proptest::collection::vec(5.0..50.0f64, 4..150),
            push in -30.0..30.0f64,
            reach in 1usize..40,
            repeat in 0usize..150,
        ) {
            let n = radii.len();
            let mut reference: Vec<DVec2> = radii
                .iter()
                .enumerate()
                .map(|(i, r)| DVec2::from_angle(std::f64::consts::TAU * i as f64 / n as f64) * *r)
                .collect();
            reference[repeat % n] = reference[(repeat + 1) % n];
            let given: Vec<DVec2> = reference
                .iter()
                .zip(outward_normals(&reference))
                .map(|(p, nrm)| *p + nrm * push)
                .collect();
            let mut wall = given.clone();
            let (moved, most) = trim_swallowtails(&mut wall, &reference, reach);
            prop_assert_eq!(wall.len(), n);
            prop_assert!(moved <= n);
            let changed = wall.iter().zip(&given).filter(|(a, b)| a != b).count();
            let farthest = wall.iter().zip(&given).map(|(a, b)| a.distance(*b)).fold(0.0, f64::max);
            prop_assert_eq!((moved, most), (changed, farthest));
            for p in &wall {
                let d = (0..n)
                    .map(|j| point_segment_distance(*p, given[j], given[(j + 1) % n]).0)
                    .fold(f64::INFINITY, f64::min);
                prop_assert!(d < 1e-6, "{} off the ring", d);
            }
        }
    }
}
