//! Manufacturing constraints (SPEC §2) on the section surface: detect, correct locally, report.
//!
//! Support-free: between section k−1 and k the wall may move along the XY normal of section k−1
//! by at most `Δz·tan(max_overhang)`, with Δz the local layer height, and no point may lie
//! farther than that from the wall below (the nearest point of section k−1's segments around
//! its column, as the checker measures it: at a sharp corner the two differ). Corrections clamp
//! point by point, from the bottom up, so a section only ever depends on the corrected section
//! below it.

use glam::DVec2;

use crate::report::PointEvent;
use crate::section::Section;

/// Measured quality of a section surface.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SurfaceMetrics {
    /// Largest lean of the wall from vertical between consecutive sections, degrees.
    pub max_overhang_deg: f64,
    /// Largest z range within one section, mm.
    pub max_layer_z_range: f64,
    /// Smallest and largest local layer height, mm.
    pub min_layer_height: f64,
    pub max_layer_height: f64,
    /// The box (min, max) in XY of every point of the sections, and the highest point's z,
    /// mm: whether the wall fits the machine (measured here, in the same pass).
    pub xy_box: (DVec2, DVec2),
    pub top: f64,
}

impl SurfaceMetrics {
    /// Nothing measured yet: extremes that any measurement replaces.
    fn unmeasured() -> SurfaceMetrics {
        SurfaceMetrics {
            min_layer_height: f64::INFINITY,
            xy_box: (DVec2::INFINITY, DVec2::NEG_INFINITY),
            ..Default::default()
        }
    }

    /// A point of the first section (on the bed): its place in the box and top.
    #[inline]
    fn add_bed_point(&mut self, p: glam::DVec3) {
        self.xy_box = (
            self.xy_box.0.min(p.truncate()),
            self.xy_box.1.max(p.truncate()),
        );
        self.top = self.top.max(p.z);
    }

    /// Point `p` of a section above `q`, its column's point of the section below, where that
    /// section's outward normal is `n`: its layer height, lean, box and top; gives the tangent
    /// of its lean, `|(p − q)·n| / Δz`. `steepest` is the largest tangent whose lean was
    /// worked out exactly so far: a point clearly less steep cannot lean more (the exact lean
    /// is worked out only where it might be the largest).
    #[inline]
    fn add_point(&mut self, p: glam::DVec3, q: glam::DVec3, n: DVec2, steepest: &mut f64) -> f64 {
        self.add_bed_point(p);
        let dz = p.z - q.z;
        self.min_layer_height = self.min_layer_height.min(dz);
        self.max_layer_height = self.max_layer_height.max(dz);
        // As in [`lean_deg`].
        let off = (p.truncate() - q.truncate()).dot(n).abs();
        let tan = off / dz.max(1e-9);
        if tan >= *steepest * (1.0 - 1e-9) || tan > 1e3 {
            self.max_overhang_deg = self.max_overhang_deg.max(lean_deg(p, q, n));
            *steepest = steepest.max(tan);
        }
        tan
    }

    /// The metrics of two sets of points together (extremes: the same in any order).
    fn merge(&mut self, other: &SurfaceMetrics) {
        self.max_overhang_deg = self.max_overhang_deg.max(other.max_overhang_deg);
        self.max_layer_z_range = self.max_layer_z_range.max(other.max_layer_z_range);
        self.min_layer_height = self.min_layer_height.min(other.min_layer_height);
        self.max_layer_height = self.max_layer_height.max(other.max_layer_height);
        self.xy_box = (
            self.xy_box.0.min(other.xy_box.0),
            self.xy_box.1.max(other.xy_box.1),
        );
        self.top = self.top.max(other.top);
    }

    /// The metrics of the whole surface once every point is in (no layer: height 0).
    fn finished(mut self) -> SurfaceMetrics {
        if !self.min_layer_height.is_finite() {
            self.min_layer_height = 0.0;
        }
        self
    }
}

/// Clamps the normal offset of every point of sections `from ..` against the section below, and
/// its distance from that section's wall, to `tan_limit·Δz` (`clamp_point`). Returns the
/// points moved (or, with `enforce = false`, the points in violation,
/// unchanged). Also returns the index of the highest section changed, if any.
pub fn clamp_overhang(
    sections: &mut [Section],
    from: usize,
    tan_limit: f64,
    enforce: bool,
) -> Vec<PointEvent> {
    clamp_overhang_in(sections, from, tan_limit, enforce, false).0
}

/// [`clamp_overhang`] from the first section up, with the [`measure`] of the sections it
/// leaves (to the bit), measured as each point is clamped: the normals of the section below
/// and the points are at hand then, and a second pass over the surface is spared (on the
/// benchmark vase, about a millisecond of the two cores).
pub fn clamp_overhang_measured(
    sections: &mut [Section],
    tan_limit: f64,
    enforce: bool,
) -> (Vec<PointEvent>, SurfaceMetrics) {
    let (events, metrics) = clamp_overhang_in(sections, 1, tan_limit, enforce, true);
    // Sections of different lengths are measured as [`measure`] measures them.
    let metrics = metrics.unwrap_or_else(|| measure(sections));
    (events, metrics)
}

/// [`clamp_overhang`], with the metrics of the sections where `measuring` (from the first
/// section: `from` ≤ 1) and they are all as long.
fn clamp_overhang_in(
    sections: &mut [Section],
    from: usize,
    tan_limit: f64,
    enforce: bool,
    measuring: bool,
) -> (Vec<PointEvent>, Option<SurfaceMetrics>) {
    let start = from.max(1);
    let n = sections.first().map_or(0, |s| s.points.len());
    let rows = sections.len();
    let same_lengths = sections.iter().all(|s| s.points.len() == n);
    let measuring = measuring && start == 1 && same_lengths;
    if start < rows && (rows - start) * n >= crate::parallel::PARALLEL_POINTS && same_lengths {
        let parts = crate::parallel::ranges(n, 2 * MIN_PART_COLUMNS);
        if parts.len() > 1
            && let Some(clamped) =
                clamp_by_columns(sections, start, &parts, tan_limit, enforce, measuring)
        {
            return clamped;
        }
    }
    clamp_by_rows(sections, from, tan_limit, enforce, measuring)
}

/// Fewest columns a core takes in [`clamp_overhang`].
const MIN_PART_COLUMNS: usize = 64;

/// One core's columns in [`clamp_by_columns`]: each section's points there, and the first and
/// last of them as each section is finished (for the cores on either side).
struct ColumnPart<'a> {
    columns: std::ops::Range<usize>,
    rows: Vec<&'a mut [glam::DVec3]>,
}

/// [`clamp_by_rows`] with the columns cut into one contiguous part per core, all running at
/// once, layer by layer: a part clamps section k once the parts on either side have finished
/// section k − 1 (the normals at its edge columns need their neighbours' points), so the parts
/// move up together, at most one section apart. Every point gets the arithmetic of the one-core
/// clamp, and the events come back in its order; with `measuring` (`start` = 1), each part
/// measures its columns as they are clamped, each section's z range merged from the parts'.
/// `None` when the cores are not free.
fn clamp_by_columns(
    sections: &mut [Section],
    start: usize,
    parts: &[std::ops::Range<usize>],
    tan_limit: f64,
    enforce: bool,
    measuring: bool,
) -> Option<(Vec<PointEvent>, Option<SurfaceMetrics>)> {
    use std::sync::OnceLock;
    use std::sync::atomic::{AtomicBool, Ordering};
    let count = parts.len();
    let rows = sections.len() - (start - 1);
    let mut split: Vec<ColumnPart> = parts
        .iter()
        .map(|r| ColumnPart {
            columns: r.clone(),
            rows: Vec::with_capacity(rows),
        })
        .collect();
    for s in &mut sections[start - 1..] {
        let mut rest: &mut [glam::DVec3] = &mut s.points;
        for part in &mut split {
            let (head, tail) = std::mem::take(&mut rest).split_at_mut(part.columns.len());
            part.rows.push(head);
            rest = tail;
        }
    }
    // edges[j][r]: part j's first and last NEAR_COLUMNS points of section start − 1 + r, once
    // finished.
    let edges: Vec<Vec<OnceLock<Edges>>> = (0..count)
        .map(|_| (0..rows).map(|_| OnceLock::new()).collect())
        .collect();
    // Set when a part ends, finished or stopped early (a panic), so that its neighbours do not
    // wait forever for a section it will not finish.
    let ended: Vec<AtomicBool> = (0..count).map(|_| AtomicBool::new(false)).collect();
    let (edges, ended) = (&edges, &ended);
    let wait = move |j: usize, r: usize| -> Edges {
        let mut spins = 0u32;
        loop {
            if let Some(e) = edges[j][r].get() {
                return *e;
            }
            if ended[j].load(Ordering::Acquire) {
                // A part that ended sets its last edges first: look once more.
                return *edges[j][r].get().expect("a neighbouring part stopped");
            }
            // A section takes about a microsecond; a neighbour that long late has lost its
            // core: let it have this one.
            spins = spins.wrapping_add(1);
            if spins.is_multiple_of(4096) {
                std::thread::yield_now();
            } else {
                std::hint::spin_loop();
            }
        }
    };
    let jobs: Vec<_> = split
        .into_iter()
        .enumerate()
        .map(|(j, part)| {
            move || {
                struct End<'a>(&'a AtomicBool);
                impl Drop for End<'_> {
                    fn drop(&mut self) {
                        self.0.store(true, Ordering::Release);
                    }
                }
                let _end = End(&ended[j]);
                let ColumnPart { columns, mut rows } = part;
                let w = columns.len();
                let (left, right) = ((j + count - 1) % count, (j + 1) % count);
                let _ = edges[j][0].set(edges_of(rows[0]));
                let mut events = Vec::new();
                // This part's metrics, the z range of its columns of each section above the
                // first, and the steepest tangent measured exactly.
                let mut metrics = SurfaceMetrics::unmeasured();
                let mut z_ranges = Vec::with_capacity(if measuring { rows.len() } else { 0 });
                let mut steepest = 0.0;
                if measuring {
                    rows[0].iter().for_each(|&p| metrics.add_bed_point(p));
                }
                let mut normals = Vec::with_capacity(w);
                // The section below, with its neighbours' NEAR_COLUMNS points on either side.
                let mut padded = Vec::with_capacity(w + 2 * NEAR_COLUMNS);
                for r in 1..rows.len() {
                    let (left_edges, right_edges) = (wait(left, r - 1), wait(right, r - 1));
                    let (below, above) = rows.split_at_mut(r);
                    let (prev, cur) = (&*below[r - 1], &mut *above[0]);
                    padded.clear();
                    padded.extend_from_slice(&left_edges.1);
                    padded.extend_from_slice(prev);
                    padded.extend_from_slice(&right_edges.0);
                    normals.clear();
                    normals.extend(padded.windows(2 * NEAR_COLUMNS + 1).map(|near| {
                        let (before, after) = (near[NEAR_COLUMNS - 1], near[NEAR_COLUMNS + 1]);
                        crate::geometry::normal_from_neighbours(before.truncate(), after.truncate())
                    }));
                    let layer = start - 1 + r;
                    let near = padded.windows(2 * NEAR_COLUMNS + 1);
                    let mut z_range = (f64::INFINITY, f64::NEG_INFINITY);
                    for (c, (p, near)) in cur.iter_mut().zip(near).enumerate() {
                        let near = near.try_into().expect("a window of the padded row");
                        if let Some(amount_mm) =
                            clamp_point(p, near, normals[c], tan_limit, enforce)
                        {
                            events.push(PointEvent {
                                layer,
                                sample: columns.start + c,
                                amount_mm,
                            });
                        }
                        if measuring {
                            metrics.add_point(*p, near[NEAR_COLUMNS], normals[c], &mut steepest);
                            z_range = (z_range.0.min(p.z), z_range.1.max(p.z));
                        }
                    }
                    if measuring {
                        z_ranges.push(z_range);
                    }
                    let _ = edges[j][r].set(edges_of(cur));
                }
                (events, metrics, z_ranges)
            }
        })
        .collect();
    let done = crate::parallel::run_together(jobs).ok()?;
    let metrics = measuring.then(|| {
        let mut m = SurfaceMetrics::unmeasured();
        for (_, part, _) in &done {
            m.merge(part);
        }
        // Each section's z range, its parts' merged.
        for r in 0..done.first().map_or(0, |(_, _, z)| z.len()) {
            let (lo, hi) = done
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |z, d| {
                    (z.0.min(d.2[r].0), z.1.max(d.2[r].1))
                });
            m.max_layer_z_range = m.max_layer_z_range.max(hi - lo);
        }
        m.finished()
    });
    let mut events: Vec<PointEvent> = done.into_iter().flat_map(|(e, _, _)| e).collect();
    events.sort_by_key(|e| (e.layer, e.sample));
    Some((events, metrics))
}

/// A part's first and last [`NEAR_COLUMNS`] points of a section, for the parts beside it.
type Edges = ([glam::DVec3; NEAR_COLUMNS], [glam::DVec3; NEAR_COLUMNS]);

/// The [`Edges`] of a part's row (at least `NEAR_COLUMNS` points).
fn edges_of(row: &[glam::DVec3]) -> Edges {
    let w = row.len();
    (
        std::array::from_fn(|j| row[j]),
        std::array::from_fn(|j| row[w - NEAR_COLUMNS + j]),
    )
}

/// Points of the section below that [`clamp_point`] measures a point's distance to: its own
/// column's and [`FEW_COLUMNS`] on either side, and [`NEAR_COLUMNS`] on either side where the
/// nearest of those is an end and out of reach.
const FEW_COLUMNS: usize = 2;

/// Sixteen, not two: where a wall pulled far in or out bunches the samples below at a corner,
/// two columns either side lie within a fraction of a millimetre of each other, a point beside
/// them is taken to have slid past them and is left unclamped, several millimetres out (a
/// 40 mm foot flaring to a 105 mm rose 18 mm up: `any_vessel_gives_one_printable_spiral`).
/// Looking 16 columns either side there, 14 more of 450 random designs print (8: 12 more),
/// none is refused that printed before, and the shipped designs are unchanged.
const NEAR_COLUMNS: usize = 16;

/// Clamps point `p` against `below[NEAR_COLUMNS]` under it (`n`: the outward normal of the
/// section below there; `below`: that point and its neighbours on either side); the excess when
/// it leaned past the limit (moved back onto it when `enforce`).
///
/// First the offset along the normal. Then the distance to the wall below as the checker
/// measures it, to the nearest point of the segments between `below`'s points: where the
/// samples do not sit at the same place on a sharp corner from one section to the next, a
/// point may keep its offset along its normal and still lie farther than that from the corner
/// below (the checker found a rose lofted to a seven-point star leaning 47.8° at three points).
/// Where the nearest point of the [`FEW_COLUMNS`] either side is an end and out of reach, the
/// nearest of all `below`'s; where that too is an end (the point slid along the wall past
/// them) the segments do not say, and it is left.
#[inline]
fn clamp_point(
    p: &mut glam::DVec3,
    below: &[glam::DVec3; 2 * NEAR_COLUMNS + 1],
    n: DVec2,
    tan_limit: f64,
    enforce: bool,
) -> Option<f64> {
    let q = below[NEAR_COLUMNS];
    let dz = (p.z - q.z).max(0.0);
    let limit = dz * tan_limit;
    // A point brought back along the normal onto the limit, and by how much it was past it.
    let onto_limit = |xy: DVec2| {
        let offset = (xy - q.truncate()).dot(n);
        let over = offset.abs() - limit;
        if over > 0.0 {
            (xy - n * (over * offset.signum()), Some(over))
        } else {
            (xy, None)
        }
    };
    let (mut xy, mut excess) = onto_limit(p.truncate());
    if let Some(over) = excess {
        xy = with_slide_scaled(xy, q.truncate(), n, over + limit, limit);
    }
    // Within the limit of q itself, the wall below is nearer still: most points.
    if (xy - q.truncate()).length_squared() > limit * limit {
        // The nearest point of the wall below within FEW_COLUMNS columns, then, where that is
        // an end and farther than the limit, within all of `below`.
        let few = &below[NEAR_COLUMNS - FEW_COLUMNS..=NEAR_COLUMNS + FEW_COLUMNS];
        let mut nearest = nearest_on(xy, few);
        if nearest.2 && nearest.0 > limit {
            nearest = nearest_on(xy, below);
        }
        let (d, x, at_end) = nearest;
        if !at_end && d > limit {
            excess = Some(excess.unwrap_or(0.0) + d - limit);
            // Towards a side that turns outward (a concave corner) that can lean the point
            // past the limit along the normal again: the normal's limit holds (the surface's
            // lean is measured along it).
            xy = onto_limit(x + (xy - x) * (limit / d)).0;
        }
    }
    if enforce && excess.is_some() {
        p.x = xy.x;
        p.y = xy.y;
    }
    excess
}

/// The nearest point of the polyline `points` to `xy`: its distance, the point, and whether it
/// is an end of the polyline.
#[inline]
fn nearest_on(xy: DVec2, points: &[glam::DVec3]) -> (f64, DVec2, bool) {
    let mut nearest = (f64::INFINITY, DVec2::ZERO, true);
    for (s, pair) in points.windows(2).enumerate() {
        let (a, b) = (pair[0].truncate(), pair[1].truncate());
        let (d, f) = crate::geometry::point_segment_distance(xy, a, b);
        if d < nearest.0 {
            let at_end = (s == 0 && f <= 0.0) || (s + 2 == points.len() && f >= 1.0);
            nearest = (d, a.lerp(b, f), at_end);
        }
    }
    nearest
}

/// How far, in layer limits (`tan_limit · Δz`), a point's offset along the normal may reach
/// before [`clamp_point`] scales its slide along the wall back with it: three limits. Of the 450
/// random designs, with one or two limits one that printed before was refused (a layer 0.02 mm
/// too thin at one point) and 19–20 more printed; with three none was refused and 11 more
/// printed.
const SLIDE_REACH_LIMITS: f64 = 3.0;

/// `xy`, a point brought back along the normal `n` from an offset `offset` (> `limit`) off `q`
/// onto the limit, with its slide along the wall (the part of `xy − q` across `n`) kept in
/// full while the offset was within [`SLIDE_REACH_LIMITS`] limits and scaled by
/// `reach / offset` beyond: the step from `q` then keeps the direction the design gave it.
///
/// A design whose wall comes in or out tens of millimetres too far in a layer (a 100 mm foot
/// under a 40 mm rim 10 mm up) would otherwise keep each point's slide of several millimetres
/// while its offset is cut to a fraction of a millimetre: the points pass their neighbours,
/// the section zigzags, and its normals, and so the layers above, go wrong (found by
/// `any_vessel_gives_one_printable_spiral`: a seam step of 43 mm). A wall moved back by less,
/// or sliding along itself (a twist), keeps its slide.
#[inline]
fn with_slide_scaled(xy: DVec2, q: DVec2, n: DVec2, offset: f64, limit: f64) -> DVec2 {
    let reach = SLIDE_REACH_LIMITS * limit;
    if offset <= reach {
        return xy;
    }
    let across = DVec2::new(-n.y, n.x);
    let slide = (xy - q).dot(across);
    xy - across * (slide * (1.0 - reach / offset))
}

/// [`clamp_overhang`] section by section on one core.
fn clamp_by_rows(
    sections: &mut [Section],
    from: usize,
    tan_limit: f64,
    enforce: bool,
    measuring: bool,
) -> (Vec<PointEvent>, Option<SurfaceMetrics>) {
    let mut events = Vec::new();
    let mut padded = Vec::new();
    let (mut metrics, mut steepest) = (SurfaceMetrics::unmeasured(), 0.0);
    if measuring && let Some(first) = sections.first() {
        first.points.iter().for_each(|&p| metrics.add_bed_point(p));
    }
    for k in from.max(1)..sections.len() {
        let (below, above) = sections.split_at_mut(k);
        let prev = &below[k - 1];
        let cur = &mut above[0];
        let normals = prev.normals();
        let n = prev.points.len();
        // The section below with NEAR_COLUMNS points of the other end on either side (around
        // again, for a section of fewer points).
        padded.clear();
        padded.extend(
            (0..n + 2 * NEAR_COLUMNS)
                .map(|m| prev.points[(m + n * NEAR_COLUMNS - NEAR_COLUMNS) % n]),
        );
        let near = padded.windows(2 * NEAR_COLUMNS + 1);
        for (i, (p, below)) in cur.points.iter_mut().zip(near).enumerate() {
            let below = below.try_into().expect("a window of the padded section");
            if let Some(amount_mm) = clamp_point(p, below, normals[i], tan_limit, enforce) {
                events.push(PointEvent {
                    layer: k,
                    sample: i,
                    amount_mm,
                });
            }
            if measuring {
                metrics.add_point(*p, below[NEAR_COLUMNS], normals[i], &mut steepest);
            }
        }
        if measuring {
            let (lo, hi) = cur.z_range();
            metrics.max_layer_z_range = metrics.max_layer_z_range.max(hi - lo);
        }
    }
    (events, measuring.then(|| metrics.finished()))
}

/// Lean of the wall from vertical at point i of section k (k ≥ 1), degrees:
/// `atan(|(pₖ − pₖ₋₁)·n| / Δz)` with n the XY normal of section k − 1.
#[inline]
fn lean_deg(p: glam::DVec3, q: glam::DVec3, n: DVec2) -> f64 {
    let dz = p.z - q.z;
    let off = (p.truncate() - q.truncate()).dot(n).abs();
    off.atan2(dz.max(1e-9)).to_degrees()
}

/// Lean from vertical of every point, section-major (`k·n + i`), degrees; section 0 (on the bed)
/// leans 0. The preview colours the wall by these.
pub fn point_leans_deg(sections: &[Section]) -> Vec<f32> {
    measure_with_leans(sections).1
}

/// Largest lean, z ranges and layer heights of a surface (without each point's lean: what
/// the command line needs).
pub fn measure(sections: &[Section]) -> SurfaceMetrics {
    measure_in_parts(sections, false).0
}

/// Sections a core measures at a time ([`measure_in_parts`]): halves fixed in advance left this
/// core waiting about half a millisecond for the other's on the benchmark vase, whose helper
/// may be finishing other work when its half is handed over.
const MEASURE_RUN: usize = 16;

/// [`measure`] and [`point_leans_deg`] in one pass (the surface of a session with a view keeps
/// both).
pub fn measure_with_leans(sections: &[Section]) -> (SurfaceMetrics, Vec<f32>) {
    measure_in_parts(sections, true)
}

/// [`measure`], with each point's lean when `keep_leans`: the sections are measured in runs
/// of [`MEASURE_RUN`] shared out over the machine's cores as they get free, and the runs merged
/// (maxima and minima, the same whatever the runs).
fn measure_in_parts(sections: &[Section], keep_leans: bool) -> (SurfaceMetrics, Vec<f32>) {
    let parts = crate::parallel::map_runs(sections.len(), 64, MEASURE_RUN, |r| {
        vec![measure_part(sections, r, keep_leans)]
    });
    let mut m = SurfaceMetrics::unmeasured();
    let mut leans = Vec::with_capacity(if keep_leans {
        sections.iter().map(|s| s.points.len()).sum()
    } else {
        0
    });
    for (part, part_leans) in parts {
        m.merge(&part);
        leans.extend_from_slice(&part_leans);
    }
    (m.finished(), leans)
}

/// `atan(x)` for `x ≥ 0` by the Cephes library's rational approximation (S. L. Moshier,
/// `atan.c`: `x` reduced to `|x| ≤ 0.66` by `atan x = π/4 + atan((x−1)/(x+1))` or
/// `π/2 − atan(1/x)`, then `x + x³·P(x²)/Q(x²)`), within a few units in the last place of
/// double precision: several times cheaper than the library's `atan2`, and used where the
/// result is kept in single precision only (the preview's colours).
fn atan_nonnegative(x: f64) -> f64 {
    const P: [f64; 5] = [
        -8.750_608_600_031_904e-1,
        -1.615_753_718_733_365e1,
        -7.500_855_792_314_705e1,
        -1.228_866_684_490_136e2,
        -6.485_021_904_942_025e1,
    ];
    const Q: [f64; 5] = [
        2.485_846_490_142_306e1,
        1.650_270_098_316_988_5e2,
        4.328_810_604_912_903e2,
        4.853_903_996_359_137e2,
        1.945_506_571_482_614e2,
    ];
    const MORE_BITS: f64 = 6.123_233_995_736_766e-17;
    let (base, x, extra) = if x > 2.414_213_562_373_095 {
        (std::f64::consts::FRAC_PI_2, -1.0 / x, MORE_BITS)
    } else if x > 0.66 {
        (
            std::f64::consts::FRAC_PI_4,
            (x - 1.0) / (x + 1.0),
            0.5 * MORE_BITS,
        )
    } else {
        (0.0, x, 0.0)
    };
    let z = x * x;
    let p = (((P[0] * z + P[1]) * z + P[2]) * z + P[3]) * z + P[4];
    let q = ((((z + Q[0]) * z + Q[1]) * z + Q[2]) * z + Q[3]) * z + Q[4];
    base + (x * (z * p / q) + x + extra)
}

/// The metrics of sections `range` and, when `keep_leans`, their points' leans (section 0, on
/// the bed, leans 0 and bounds no layer).
///
/// Each point's lean is kept in single precision from [`atan_nonnegative`]; the largest lean is
/// [`lean_deg`] exactly, evaluated only at points whose `tan` of the lean comes within 10⁻⁹ of
/// the largest so far (or past 1000, 89.94°, where the arctangent flattens): a point further
/// below cannot lean more, whatever the rounding of either arctangent.
fn measure_part(
    sections: &[Section],
    range: std::ops::Range<usize>,
    keep_leans: bool,
) -> (SurfaceMetrics, Vec<f32>) {
    let mut m = SurfaceMetrics::unmeasured();
    let mut leans = Vec::with_capacity(if keep_leans {
        sections[range.clone()].iter().map(|s| s.points.len()).sum()
    } else {
        0
    });
    // The largest tan of a lean measured exactly so far.
    let mut steepest = 0.0_f64;
    for k in range {
        let s = &sections[k];
        if k == 0 {
            for p in &s.points {
                m.add_bed_point(*p);
            }
            if keep_leans {
                leans.resize(s.points.len(), 0.0);
            }
            continue;
        }
        let (lo, hi) = s.z_range();
        m.max_layer_z_range = m.max_layer_z_range.max(hi - lo);
        let prev = &sections[k - 1];
        let normals = prev.normals();
        for (i, p) in s.points.iter().enumerate() {
            let tan = m.add_point(*p, prev.points[i], normals[i], &mut steepest);
            if keep_leans {
                leans.push(atan_nonnegative(tan).to_degrees() as f32);
            }
        }
    }
    (m, leans)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    /// The window [`clamp_point`] reads, `below[NEAR_COLUMNS + j] = at(j)`.
    fn window(at: impl Fn(f64) -> DVec3) -> [DVec3; 2 * NEAR_COLUMNS + 1] {
        std::array::from_fn(|m| at(m as f64 - NEAR_COLUMNS as f64))
    }

    /// A sharp tip (90°, at (0, 10)) whose samples do not sit on the tip from one section to
    /// the next: the section above has its tip point 1.3 mm out of one side, 1 mm up. Along
    /// the bisector (the normal the clamp moves against) that is 0.42 mm, within tan 45° · 1 mm;
    /// from the side below it is 1.3 mm, as the checker measures. The clamp brings it to 1 mm
    /// (the limit) from the wall below; a point sliding along a straight side, as far from it
    /// as the limit allows, stays where it is.
    #[test]
    fn a_point_past_a_sharp_corner_is_clamped_by_its_distance_to_the_wall_below() {
        let side = |t: f64| DVec3::new(-10.0 + 10.0 * t, 10.0 * t, 0.0); // the left side
        let other = |t: f64| DVec3::new(10.0 * t, 10.0 - 10.0 * t, 0.0); // the right side
        // Every 0.2 of a side from the tip, both ways.
        let below = window(|j| {
            if j <= 0.0 {
                side(1.0 + 0.2 * j)
            } else {
                other(0.2 * j)
            }
        });
        let n = DVec2::new(0.0, 1.0); // the bisector at the tip
        // Up the left side's outward normal (−1, 1)/√2 by 1.3 mm from a point beside the tip.
        let out = DVec2::new(-1.0, 1.0).normalize();
        let from = side(0.95).truncate() + out * 1.3;
        let mut p = from.extend(1.0);
        let excess = clamp_point(&mut p, &below, n, 1.0, true).expect("clamped");
        let distance = |p: DVec3| {
            below
                .windows(2)
                .map(|w| {
                    let (d, _) = crate::geometry::point_segment_distance(
                        p.truncate(),
                        w[0].truncate(),
                        w[1].truncate(),
                    );
                    d
                })
                .fold(f64::INFINITY, f64::min)
        };
        assert!((distance(from.extend(1.0)) - 1.3).abs() < 1e-9);
        assert!((distance(p) - 1.0).abs() < 1e-9, "{}", distance(p));
        assert!((excess - 0.3).abs() < 1e-9, "{excess}");
        // Without the distance rule it passed: its offset along the bisector.
        let offset = (from - below[NEAR_COLUMNS].truncate()).dot(n);
        assert!(offset < 1.0, "{offset}");
        // The wall beside the tip just inside the limit, sliding along the side: 0.99 mm out
        // of the left side and 1.5 mm along it from its column's point below.
        let along = DVec2::new(1.0, 1.0).normalize();
        let beside = (side(0.5).truncate() + along * 1.5 + out * 0.99).extend(1.0);
        let near = window(|j| side(0.5 + 0.1 * j));
        let mut q = beside;
        assert_eq!(clamp_point(&mut q, &near, out, 1.0, true), None);
        assert_eq!(q, beside);
    }

    /// A point 9 mm inside the wall below and 4 mm along it, with a limit of 1 mm: brought onto
    /// the limit with its slide scaled by 3/9 (the step keeps its direction past three limits);
    /// 2.5 mm inside and 4 mm along, it keeps the whole slide.
    #[test]
    fn a_point_far_past_the_limit_keeps_the_direction_of_its_step() {
        let straight = |x: f64| DVec3::new(x, 0.0, 0.0); // the wall below along x, outward +y
        let below = window(straight);
        let n = DVec2::new(0.0, 1.0);
        let mut far = DVec3::new(4.0, -9.0, 1.0);
        let excess = clamp_point(&mut far, &below, n, 1.0, true).expect("clamped");
        assert!((excess - 8.0).abs() < 1e-9, "{excess}");
        assert!(
            (far.y + 1.0).abs() < 1e-9 && (far.x - 4.0 / 3.0).abs() < 1e-9,
            "{far}"
        );
        let mut near = DVec3::new(4.0, -2.5, 1.0);
        clamp_point(&mut near, &below, n, 1.0, true).expect("clamped");
        assert!(
            (near.y + 1.0).abs() < 1e-9 && (near.x - 4.0).abs() < 1e-9,
            "{near}"
        );
    }

    /// The clamp by columns on all cores moves every point exactly as the clamp section by
    /// section, and reports the same events in the same order: a wavy, leaning wall with many
    /// points past the limit, enforced and not, from the bottom and from half way up.
    #[test]
    fn the_clamp_by_columns_is_the_clamp_by_rows() {
        if crate::parallel::cores() < 2 {
            return; // No helper to run a second part at the same time.
        }
        let (rows, n) = (120, 300);
        let wall: Vec<Section> = (0..rows)
            .map(|k| Section {
                points: (0..n)
                    .map(|i| {
                        let th = std::f64::consts::TAU * i as f64 / n as f64;
                        let r = 40.0 + 0.3 * k as f64 + 2.5 * ((7 * i + 3 * k) as f64 * 0.37).sin();
                        DVec3::new(r * th.cos(), r * th.sin(), k as f64)
                    })
                    .collect(),
            })
            .collect();
        for enforce in [true, false] {
            for from in [1, 60] {
                let mut by_rows = wall.clone();
                let expected = clamp_by_rows(&mut by_rows, from, 1.0, enforce, false).0;
                assert!(expected.len() > 1000, "{}", expected.len());
                let parts = crate::parallel::ranges(n, 2);
                let parts = if parts.len() > 1 {
                    parts
                } else {
                    vec![0..150, 150..300]
                };
                // Retried until the helpers are free (other tests use them too).
                let (by_columns, events) = loop {
                    let mut by_columns = wall.clone();
                    if let Some(e) =
                        clamp_by_columns(&mut by_columns, from, &parts, 1.0, enforce, false)
                    {
                        break (by_columns, e.0);
                    }
                    std::thread::yield_now();
                };
                assert_eq!(by_columns, by_rows);
                assert_eq!(events, expected);
            }
        }
        // A part that finishes while its neighbour, preempted, has yet to read its last
        // section (the first version took the finished part for a stopped one and panicked,
        // once in a while under a loaded machine): many short runs on an oversubscribed machine.
        let short = &wall[..2];
        let mut by_rows = short.to_vec();
        let expected = clamp_by_rows(&mut by_rows, 1, 1.0, true, false).0;
        let parts = vec![0..150, 150..300];
        let stop = std::sync::atomic::AtomicBool::new(false);
        std::thread::scope(|s| {
            for _ in 0..crate::parallel::cores() {
                s.spawn(|| {
                    while !stop.load(std::sync::atomic::Ordering::Relaxed) {
                        std::hint::spin_loop();
                    }
                });
            }
            for _ in 0..20_000 {
                let mut by_columns = short.to_vec();
                if let Some(e) = clamp_by_columns(&mut by_columns, 1, &parts, 1.0, true, false) {
                    assert_eq!((by_columns, e.0), (by_rows.clone(), expected.clone()));
                }
            }
            stop.store(true, std::sync::atomic::Ordering::Relaxed);
        });
    }

    /// The Cephes arctangent agrees with the library's to a few units in the last place, from
    /// 0 through tiny, reduction boundaries and huge arguments to infinity.
    #[test]
    fn the_cheap_arctangent_is_the_librarys() {
        let mut xs = vec![
            0.0,
            0.66,
            0.66f64.next_up(),
            2.414_213_562_373_095,
            1.0,
            f64::INFINITY,
        ];
        xs.extend((-300..300).map(|e| 10f64.powf(e as f64 / 20.0)));
        xs.extend((0..10_000).map(|i| i as f64 * 0.0007));
        for x in xs {
            let (ours, std) = (atan_nonnegative(x), x.atan());
            assert!(
                (ours - std).abs() <= 4.0 * f64::EPSILON * std,
                "atan {x}: {ours} against {std}"
            );
        }
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(64))]

        /// Clamped and measured in one pass, the sections, the events and the metrics are
        /// those of clamping and then measuring, to the bit: by columns on both cores (walls of
        /// 720 points) and by rows (8 points), enforced or only reported.
        #[test]
        fn measured_as_clamped_is_clamped_then_measured(
            rows in 2usize..40,
            wide in proptest::bool::ANY,
            enforce in proptest::bool::ANY,
            wobble in 0.0..3.0f64,
            lobes in 1u32..9,
            seed in 0u64..1000,
        ) {
            let n = if wide { 720 } else { 8 };
            let sections: Vec<Section> = (0..rows)
                .map(|k| Section {
                    points: (0..n)
                        .map(|i| {
                            let a = std::f64::consts::TAU * i as f64 / n as f64;
                            let jitter = ((seed as f64 + 0.37 * (k * n + i) as f64).sin() * 1e4).fract();
                            let r = 30.0 + wobble * (k as f64) * (lobes as f64 * a).sin() + 0.3 * jitter;
                            DVec3::new(r * a.cos(), r * a.sin(), 0.5 * k as f64 + 0.01 * jitter)
                        })
                        .collect(),
                })
                .collect();
            let (mut a, mut b) = (sections.clone(), sections);
            let plain = clamp_overhang(&mut a, 1, 1.0, enforce);
            let (events, metrics) = clamp_overhang_measured(&mut b, 1.0, enforce);
            let bits = |s: &[Section]| -> Vec<[u64; 3]> {
                s.iter().flat_map(|s| s.points.iter().map(|p| p.to_array().map(f64::to_bits))).collect()
            };
            proptest::prop_assert_eq!(bits(&a), bits(&b));
            proptest::prop_assert_eq!(plain, events);
            let m = measure(&a);
            let exact = |m: SurfaceMetrics| {
                [m.max_overhang_deg, m.max_layer_z_range, m.min_layer_height, m.max_layer_height,
                 m.xy_box.0.x, m.xy_box.0.y, m.xy_box.1.x, m.xy_box.1.y, m.top].map(f64::to_bits)
            };
            proptest::prop_assert_eq!(exact(metrics), exact(m));
        }

        /// The largest lean is the exact one of the point-by-point scan, to the bit, and every
        /// kept lean is that point's within single precision, on walls from plumb to
        /// near-horizontal, with repeated heights; measured without the leans, the same metrics.
        #[test]
        fn the_largest_lean_is_the_exact_scans(
            radii in proptest::collection::vec(proptest::collection::vec(10.0..40.0f64, 8), 2..12),
            heights in proptest::collection::vec(proptest::prop_oneof![proptest::strategy::Just(0.0), proptest::strategy::Just(1e-12), 0.0..2.0f64], 12),
            plumb in proptest::bool::ANY,
        ) {
            let sections: Vec<Section> = radii
                .iter()
                .enumerate()
                .map(|(k, rs)| Section {
                    points: rs
                        .iter()
                        .enumerate()
                        .map(|(i, r)| {
                            let a = std::f64::consts::TAU * i as f64 / rs.len() as f64;
                            let r = if plumb { 20.0 + 1e-13 * *r } else { *r };
                            DVec3::new(r * a.cos(), r * a.sin(), heights[..=k].iter().sum())
                        })
                        .collect(),
                })
                .collect();
            let (m, leans) = measure_with_leans(&sections);
            let mut exact = 0.0_f64;
            let n = 8;
            for k in 1..sections.len() {
                let normals = sections[k - 1].normals();
                for i in 0..n {
                    let lean = lean_deg(sections[k].points[i], sections[k - 1].points[i], normals[i]);
                    exact = exact.max(lean);
                    let kept = leans[k * n + i];
                    proptest::prop_assert!((kept as f64 - lean).abs() <= 1e-5 * lean.max(1.0), "{kept} against {lean}");
                }
            }
            proptest::prop_assert_eq!(m.max_overhang_deg.to_bits(), exact.to_bits());
            // Without the leans kept (the command line's surface), the same metrics.
            proptest::prop_assert_eq!(measure(&sections), m);
            // The box and top of every point, the first section's included.
            let all = sections.iter().flat_map(|s| &s.points);
            let lo = all.clone().fold(DVec2::INFINITY, |b, p| b.min(p.truncate()));
            let hi = all.clone().fold(DVec2::NEG_INFINITY, |b, p| b.max(p.truncate()));
            let top = all.map(|p| p.z).fold(0.0, f64::max);
            proptest::prop_assert_eq!((m.xy_box, m.top), ((lo, hi), top));
        }
    }

    fn ring(r: f64, z: f64, n: usize) -> Section {
        Section {
            points: (0..n)
                .map(|i| {
                    let a = std::f64::consts::TAU * i as f64 / n as f64;
                    DVec3::new(r * a.cos(), r * a.sin(), z)
                })
                .collect(),
        }
    }

    #[test]
    fn flare_past_45_degrees_is_clamped_to_45() {
        // Radius grows 2 mm per 1 mm layer: 63.4°. Clamped to 1 mm per layer.
        let mut s: Vec<Section> = (0..5)
            .map(|k| ring(30.0 + 2.0 * k as f64, k as f64, 360))
            .collect();
        let before = measure(&s);
        assert!((before.max_overhang_deg - 2f64.atan().to_degrees()).abs() < 0.1);
        let ev = clamp_overhang(&mut s, 1, 1.0, true);
        assert_eq!(ev.len(), 4 * 360);
        // First correction removes 1 mm; later ones more as the design runs away.
        assert!((ev[0].amount_mm - 1.0).abs() < 1e-3);
        let after = measure(&s);
        let leans = point_leans_deg(&s);
        assert_eq!(leans.len(), 5 * 360);
        assert!(leans[..360].iter().all(|a| *a == 0.0));
        let max = leans.iter().cloned().fold(0.0f32, f32::max) as f64;
        assert!((max - after.max_overhang_deg).abs() < 1e-3);
        assert!(
            after.max_overhang_deg <= 45.0 + 1e-6,
            "{}",
            after.max_overhang_deg
        );
        let r_top = s[4].points[0].truncate().length();
        assert!((r_top - 34.0).abs() < 1e-3, "{r_top}");
    }

    #[test]
    fn report_only_leaves_the_surface_alone() {
        let mut s: Vec<Section> = (0..3)
            .map(|k| ring(30.0 + 2.0 * k as f64, k as f64, 90))
            .collect();
        let copy = s.clone();
        let ev = clamp_overhang(&mut s, 1, 1.0, false);
        assert_eq!(ev.len(), 2 * 90);
        assert_eq!(s, copy);
    }

    #[test]
    fn vertical_cylinder_has_no_overhang() {
        let s: Vec<Section> = (0..4).map(|k| ring(30.0, k as f64 * 0.5, 100)).collect();
        let m = measure(&s);
        assert!(m.max_overhang_deg < 1e-6);
        assert!(
            (m.min_layer_height - 0.5).abs() < 1e-12 && (m.max_layer_height - 0.5).abs() < 1e-12
        );
    }
}
