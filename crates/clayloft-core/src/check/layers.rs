//! The layer search: for each point of an extruding path, the layer below (layer height,
//! overhang, support) and the printed part above the nozzle tip (holder collision).

use std::collections::HashMap;

use foldhash::fast::FixedState;

use glam::{DVec2, DVec3};

use super::Limits;
use super::report::{
    COLLISION, CheckReport, NOT_MEASURED, OVERHANG, PathEvent, Tally, UNSUPPORTED, Violation,
};
use crate::geometry::point_segment_distance;

/// Points a chord may span. Chords stand for runs of nearly collinear path points (see
/// [`chords`]); the cap bounds the work of building one.
const MAX_POINTS_PER_CHORD: usize = 64;
/// How far a chord may deviate from the points it stands for, mm: below the 1 µm rounding of
/// G-code coordinates' effect on any measured angle, far below a bead.
const CHORD_TOLERANCE_MM: f64 = 0.002;
/// Grid cell insertions allowed in all: a fixed allowance plus this many per chord. A clay
/// spiral's chords span one or two cells each; a file of segments hundreds of beads long (no
/// clay print) runs out of budget and is reported as not measurable rather than searched for
/// minutes.
const INSERTIONS_PER_CHORD: usize = 64;
const INSERTIONS_BASE: usize = 1 << 22;
/// Candidate chords examined in all: a fixed allowance plus this many per point. The shipped
/// designs examine 48 … 234 per point on average (most at the centre of spiral bases); a file that
/// piles its whole path onto one spot (no clay print) runs out of budget and is reported as not
/// measurable instead of being searched in quadratic time.
const CANDIDATES_PER_POINT: usize = 1024;
const CANDIDATES_BASE: usize = 1 << 24;

/// A grid cell: (x, y, z-band) indices.
type CellKey = (i32, i32, i32);

/// Spatial hash of path chords in (x, y, z-band) cells.
struct ChordGrid {
    cell: f64,
    band: f64,
    /// Chord ids per cell, ascending (chords are inserted in path order).
    cells: HashMap<CellKey, Vec<u32>, FixedState>,
    /// Insertions left before the grid gives up (see [`INSERTIONS_PER_CHORD`]).
    budget: usize,
}

impl ChordGrid {
    fn key(&self, p: DVec2, z: f64) -> CellKey {
        (
            (p.x / self.cell).floor() as i32,
            (p.y / self.cell).floor() as i32,
            (z / self.band).floor() as i32,
        )
    }

    /// Registers chord `id` from `a` to `b` in every cell it passes: the chord is cut into pieces
    /// no longer than a cell (and a band) and each piece's box of cells is marked. False when the
    /// insertion budget is spent.
    fn insert(&mut self, id: u32, a: DVec3, b: DVec3) -> bool {
        let d = b - a;
        let steps = (d.truncate().abs().max_element() / self.cell)
            .max(d.z.abs() / self.band)
            .ceil()
            .max(1.0);
        if steps > self.budget as f64 {
            self.budget = 0;
            return false;
        }
        let steps = steps as usize;
        for s in 0..steps {
            let (p, q) = (
                a + d * (s as f64 / steps as f64),
                a + d * ((s + 1) as f64 / steps as f64),
            );
            let (k0, k1) = (
                self.key(p.truncate().min(q.truncate()), p.z.min(q.z)),
                self.key(p.truncate().max(q.truncate()), p.z.max(q.z)),
            );
            for x in k0.0..=k1.0 {
                for y in k0.1..=k1.1 {
                    for z in k0.2..=k1.2 {
                        if self.budget == 0 {
                            return false;
                        }
                        self.budget -= 1;
                        self.cells.entry((x, y, z)).or_default().push(id);
                    }
                }
            }
        }
        true
    }
}

/// The path as chords `(i, k)`: each stands for path points `i ..= k`, all within
/// [`CHORD_TOLERANCE_MM`] of the straight line from point `i` to point `k` (at most
/// [`MAX_POINTS_PER_CHORD`] points). A finely sampled curve becomes chords about a millimetre
/// long, whatever its sampling; a hostile file that zig-zags in one spot stays one chord per
/// point but its cells are capped.
pub(super) fn chords(v: &[DVec3]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut i = 0;
    while i + 1 < v.len() {
        let mut k = i + 1;
        while k + 1 < v.len() && k + 1 - i < MAX_POINTS_PER_CHORD {
            let (a, b) = (v[i], v[k + 1]);
            let ab = b - a;
            let len2 = ab.length_squared();
            let fits = len2 > 0.0
                && (i + 1..=k).all(|m| {
                    let f = ((v[m] - a).dot(ab) / len2).clamp(0.0, 1.0);
                    (a + ab * f).distance_squared(v[m]) <= CHORD_TOLERANCE_MM * CHORD_TOLERANCE_MM
                });
            if !fits {
                break;
            }
            k += 1;
        }
        out.push((i, k));
        i = k;
    }
    out
}

/// Measures the layers of an extruding path `v` (see the module documentation of
/// [`crate::check`]); `lines` gives each point's G-code line (or index) for the report. Points
/// outside the machine (already a violation of their own) are neither searched nor searched for.
pub(super) fn measure_layers(
    v: &[DVec3],
    lines: &[usize],
    limits: &Limits,
    report: &mut CheckReport,
) {
    let tan_max = limits.max_overhang_deg.to_radians().tan();
    let radius = limits.line_width + 2.0 * limits.max_layer_height * tan_max;
    let gap = 3.0 * radius;
    let below_tol = 0.25 * limits.min_layer_height;
    let reach = 2.0 * limits.max_layer_height + below_tol;
    let margin = 2.0 * radius + 10.0;
    let inside = |p: DVec3| {
        p.x >= -margin
            && p.y >= -margin
            && p.z >= -margin
            && p.x <= limits.bed_x + margin
            && p.y <= limits.bed_y + margin
            && p.z <= limits.max_z + margin
    };
    let chords = chords(v);
    let mut grid = ChordGrid {
        cell: radius,
        band: limits.max_layer_height,
        cells: HashMap::with_hasher(FixedState::default()),
        budget: INSERTIONS_BASE.saturating_add(INSERTIONS_PER_CHORD.saturating_mul(chords.len())),
    };
    // Every chord goes into the grid first; a point's candidates are the chords that end at or
    // before it (a prefix of each cell's ascending list), so the points can be searched in any
    // order, on every core.
    let mut measurable = true;
    let mut ends = Vec::with_capacity(chords.len());
    for (id, &(ia, ib)) in chords.iter().enumerate() {
        let (a, b) = (v[ia], v[ib]);
        if measurable && inside(a) && inside(b) {
            measurable = grid.insert(id as u32, a, b);
        }
        ends.push(ib);
    }
    let mut cum = vec![0.0; v.len()];
    for j in 1..v.len() {
        cum[j] = cum[j - 1] + v[j - 1].distance(v[j]);
    }
    report.path_length_mm = cum[v.len() - 1];
    let search = LayerSearch {
        v,
        chords: &chords,
        ends: &ends,
        cum: &cum,
        grid: &grid,
        radius,
        gap,
        below_tol,
        reach,
        half_bead: 0.5 * limits.line_width,
        bed_layer: limits.max_layer_height + 0.01 * limits.max_layer_height + 0.002,
        inside: &inside,
    };
    let below: Vec<Below> = if measurable {
        search.all(CANDIDATES_BASE.saturating_add(CANDIDATES_PER_POINT.saturating_mul(v.len())))
    } else {
        Vec::new()
    };
    let (mut thin, mut thick, mut lean, mut unsupported, mut collide) = (
        Tally::default(),
        Tally::default(),
        Tally::default(),
        Tally::default(),
        Tally::default(),
    );
    report.min_layer_height = f64::INFINITY;
    let mut running_max_z = f64::NEG_INFINITY;
    let layer_tol = 0.01 * limits.max_layer_height + 0.002;
    // Degrees: G-code coordinates are rounded to 1 µm and the lean is measured against polyline
    // segments; the seam step where the helix leaves the flat revolution leans up to ~2° more
    // than the sections around it for one point.
    let angle_tol = 2.0;
    for j in 0..v.len() {
        let p = v[j];
        if running_max_z - p.z > report.max_rise_above_tip {
            report.max_rise_above_tip = running_max_z - p.z;
        }
        if running_max_z - p.z > limits.nozzle_length + 1e-6 {
            collide.add(running_max_z - p.z, lines[j]);
            report.events.push(PathEvent {
                line: lines[j],
                what: COLLISION,
                value: running_max_z - p.z,
            });
        }
        running_max_z = running_max_z.max(p.z);
        if !measurable {
            continue;
        }
        let (height, angle) = match below[j] {
            Below::Skipped => continue,
            Below::Unmeasurable => {
                measurable = false;
                continue;
            }
            Below::Unsupported => {
                unsupported.add(p.z, lines[j]);
                report.events.push(PathEvent {
                    line: lines[j],
                    what: UNSUPPORTED,
                    value: p.z,
                });
                continue;
            }
            Below::Layer { height, lean_deg } => (height, lean_deg),
        };
        report.min_layer_height = report.min_layer_height.min(height);
        report.max_layer_height = report.max_layer_height.max(height);
        if height < limits.min_layer_height - layer_tol {
            thin.add(limits.min_layer_height - height, lines[j]);
        }
        if height > limits.max_layer_height + layer_tol {
            thick.add(height - limits.max_layer_height, lines[j]);
        }
        report.max_overhang_deg = report.max_overhang_deg.max(angle);
        if angle > limits.max_overhang_deg + angle_tol {
            lean.add(angle, lines[j]);
            report.events.push(PathEvent {
                line: lines[j],
                what: OVERHANG,
                value: angle,
            });
        }
    }
    if !report.min_layer_height.is_finite() {
        report.min_layer_height = 0.0;
    }
    if !measurable {
        report.violations.push(Violation {
            what: NOT_MEASURED,
            count: 1,
            worst: report.path_length_mm,
            first_line: lines[0],
            detail: format!(
                "segments hundreds of bead widths long ({:.0} mm of path in {} chords): layers, overhang and support were not measured",
                report.path_length_mm,
                chords.len()
            ),
        });
    }
    let mut push = |t: Tally, what: &'static str, detail: String| {
        report.violations.extend(t.into_violation(what, detail))
    };
    push(
        thin,
        "layer too thin",
        format!(
            "below min_layer_height {} mm (worst = mm short)",
            limits.min_layer_height
        ),
    );
    push(
        thick,
        "layer too thick",
        format!(
            "above max_layer_height {} mm (worst = mm over)",
            limits.max_layer_height
        ),
    );
    push(
        lean,
        OVERHANG,
        format!(
            "wall leans past {}° (worst = degrees)",
            limits.max_overhang_deg
        ),
    );
    push(
        unsupported,
        UNSUPPORTED,
        format!("no printed layer within {radius:.1} mm below (worst = z, mm)"),
    );
    push(
        collide,
        COLLISION,
        format!(
            "printed part rises above the holder, nozzle_length {} mm (worst = mm)",
            limits.nozzle_length
        ),
    );
}

/// The grid cells around the last point searched (reused while the next point's box of cells
/// is the same).
#[derive(Default)]
struct NearCells<'g> {
    bounds: Option<(CellKey, CellKey)>,
    cells: Vec<&'g Vec<u32>>,
}

/// What lies below one path point.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Below {
    /// The first point, or a point outside the machine: not searched.
    Skipped,
    /// The candidate budget ran out here.
    Unmeasurable,
    /// Nothing printed within reach and not on the bed.
    Unsupported,
    /// The layer it rests on: its height above it, mm, and how far p leans out from the layers
    /// below, degrees from vertical.
    Layer { height: f64, lean_deg: f64 },
}

/// The search for the layer below each point (read-only: shared by the threads).
struct LayerSearch<'a, F: Fn(DVec3) -> bool + Sync> {
    v: &'a [DVec3],
    chords: &'a [(usize, usize)],
    /// Last point of each chord: chord c is a candidate for point j when `ends[c] <= j`.
    ends: &'a [usize],
    /// Path length up to each point, mm.
    cum: &'a [f64],
    grid: &'a ChordGrid,
    radius: f64,
    gap: f64,
    below_tol: f64,
    reach: f64,
    half_bead: f64,
    /// Highest a point may be and still rest on the bed, mm.
    bed_layer: f64,
    inside: &'a F,
}

impl<F: Fn(DVec3) -> bool + Sync> LayerSearch<'_, F> {
    /// Every point, split over the machine's cores; each part gets its share of the budget.
    fn all(&self, budget: usize) -> Vec<Below> {
        let n = self.v.len();
        let threads = crate::parallel::cores().clamp(1, 8);
        if threads < 2 || n < 20_000 {
            return self.range(0..n, budget);
        }
        let chunk = n.div_ceil(threads);
        let share = budget / threads;
        std::thread::scope(|scope| {
            let parts: Vec<_> = (0..n)
                .step_by(chunk)
                .map(|start| scope.spawn(move || self.range(start..(start + chunk).min(n), share)))
                .collect();
            parts
                .into_iter()
                .flat_map(|h| crate::parallel::join(h))
                .collect()
        })
    }

    /// Points `range`, with `budget` candidate chords to examine in all; once it is spent the
    /// rest are unmeasurable.
    fn range(&self, range: std::ops::Range<usize>, mut budget: usize) -> Vec<Below> {
        let mut out = Vec::with_capacity(range.len());
        let mut found: Vec<(f64, f64)> = Vec::new();
        let mut near = NearCells::default();
        let mut spent = false;
        for j in range {
            if spent {
                out.push(Below::Unmeasurable);
                continue;
            }
            let b = self.point(j, &mut found, &mut near, &mut budget);
            spent = b == Below::Unmeasurable;
            out.push(b);
        }
        out
    }

    /// The topmost earlier layer below point j within the search radius.
    fn point<'g>(
        &'g self,
        j: usize,
        found: &mut Vec<(f64, f64)>,
        near: &mut NearCells<'g>,
        budget: &mut usize,
    ) -> Below {
        let p = self.v[j];
        if j == 0 || !(self.inside)(p) {
            return Below::Skipped;
        }
        let (radius, below_tol, reach) = (self.radius, self.below_tol, self.reach);
        let grid = self.grid;
        let pxy = p.truncate();
        let (k_lo, k_hi) = (
            grid.key(pxy - radius, p.z - reach),
            grid.key(pxy + radius, p.z - below_tol),
        );
        found.clear();
        // Consecutive points mostly share their box of cells: look the cells up once per box.
        if near.bounds != Some((k_lo, k_hi)) {
            near.bounds = Some((k_lo, k_hi));
            near.cells.clear();
            for x in k_lo.0..=k_hi.0 {
                for y in k_lo.1..=k_hi.1 {
                    for z in k_lo.2..=k_hi.2 {
                        if let Some(cell) = grid.cells.get(&(x, y, z)) {
                            near.cells.push(cell);
                        }
                    }
                }
            }
        }
        let (z_lo, z_hi) = (p.z - reach, p.z - below_tol);
        {
            {
                for cell in &near.cells {
                    // The chords laid before p: a prefix of the ascending ids.
                    let earlier = cell.partition_point(|&id| self.ends[id as usize] <= j);
                    let cell = &cell[..earlier];
                    if cell.len() > *budget {
                        return Below::Unmeasurable;
                    }
                    *budget -= cell.len();
                    for &id in cell {
                        let (ia, ib) = self.chords[id as usize];
                        let (a, b) = (self.v[ia], self.v[ib]);
                        // Entirely above or below the heights a layer under p may have (the
                        // bead just laid, mostly): no distance needed.
                        if a.z.max(b.z) < z_lo || a.z.min(b.z) > z_hi {
                            continue;
                        }
                        // Distance across the segment's line, for feet of the perpendicular on
                        // the segment or just past its ends; a segment entirely ahead of or
                        // behind p along its own direction is beside p, not under it.
                        let (a2, b2) = (a.truncate(), b.truncate());
                        let ab = b2 - a2;
                        let len2 = ab.length_squared();
                        // A steep segment (rising more than it runs) is a step between layers,
                        // not a layer to rest on.
                        if (b.z - a.z).powi(2) > len2 {
                            continue;
                        }
                        let f_line = if len2 > 0.0 {
                            (pxy - a2).dot(ab) / len2
                        } else {
                            0.0
                        };
                        if !(-0.5..=1.5).contains(&f_line) {
                            continue;
                        }
                        let (d, f) = point_segment_distance(pxy, a2, b2);
                        let zq = a.z + (b.z - a.z) * f;
                        // The bead just laid: reached from p along an almost straight stretch of
                        // path. Where the path has come back over itself (the next revolution,
                        // the centre of a spiral base) the layer below is much nearer in XY than
                        // along the path.
                        let cum = self.cum;
                        let along = cum[j] - (cum[ia] + f * (cum[ib] - cum[ia]));
                        if along < self.gap && d >= 0.5 * along {
                            continue;
                        }
                        if d <= radius && zq <= z_hi && zq >= z_lo {
                            found.push((zq, d));
                        }
                    }
                }
            }
        }
        // Support: the topmost layer within half a bead of p; failing that, the nearest layer.
        let top_under = found
            .iter()
            .filter(|(_, d)| *d <= self.half_bead)
            .map(|(z, _)| *z)
            .fold(f64::NEG_INFINITY, f64::max);
        let lean = |d: f64, z: f64| d.atan2((p.z - z).max(1e-9)).to_degrees();
        if top_under.is_finite() {
            // The lean: the least of the layers below within reach. A wall that leans leans
            // alike from each layer under it; a bead laid beside an earlier, thinner one (the
            // step between the beads of a wall of several, a tie, a base bead crossing under)
            // while resting on a layer beneath does not lean.
            let lean_deg = found
                .iter()
                .map(|&(z, d)| lean(d, z))
                .fold(f64::INFINITY, f64::min);
            Below::Layer {
                height: p.z - top_under,
                lean_deg,
            }
        } else if let Some(&(z, d)) = found.iter().min_by(|a, b| a.1.total_cmp(&b.1)) {
            Below::Layer {
                height: p.z - z,
                lean_deg: lean(d, z),
            }
        } else if p.z <= self.bed_layer {
            Below::Layer {
                height: p.z,
                lean_deg: 0.0,
            } // on the bed
        } else {
            Below::Unsupported
        }
    }
}
