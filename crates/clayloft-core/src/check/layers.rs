//! The layer search: for each point of an extruding path, the layer below (layer height,
//! overhang, support) and the printed part above the nozzle tip (holder collision).

use std::collections::HashMap;

use foldhash::fast::FixedState;

use glam::{DVec2, DVec3};

use super::Limits;
use super::crossings::{CrossingLimits, LOOP_REACH_BEADS, find_crossings};
use super::report::{
    COLLISION, CROSSING, CheckReport, NOT_MEASURED, OVERHANG, PathEvent, Tally, UNSUPPORTED,
    Violation,
};

mod tree;
use tree::ChordTree;

/// Points a chord may span. Chords stand for runs of nearly collinear path points (see
/// [`chords_and_lengths`]); the cap bounds the work of building one.
const MAX_POINTS_PER_CHORD: usize = 64;
/// How far a chord may deviate from the points it stands for, mm: below the 1 µm rounding of
/// G-code coordinates' effect on any measured angle, far below a bead.
const CHORD_TOLERANCE_MM: f64 = 0.002;
/// Grid column insertions allowed in all: a fixed allowance plus this many per chord. A clay
/// spiral's chords span one or two columns each; a file of segments hundreds of beads long (no
/// clay print) runs out of budget and is reported as not measurable rather than searched for
/// minutes.
const INSERTIONS_PER_CHORD: usize = 64;
const INSERTIONS_BASE: usize = 1 << 22;
/// Candidate chords examined in all: a fixed allowance plus this many per point. The 720 × 300
/// benchmark vase examines 96 per point on average (more at the centre of its spiral base); a file that
/// piles its whole path onto one spot, rising (no clay print), runs out of budget and is reported
/// as not measurable instead of being searched in quadratic time.
const CANDIDATES_PER_POINT: usize = 1024;
const CANDIDATES_BASE: usize = 1 << 24;

/// A grid column: (x, y) cell indices.
type ColumnKey = (i32, i32);

/// A chord as a column keeps it: its id and last point, and its ends in single precision with its
/// heights rounded outward, enough to reject most candidates without reading the path (a point's
/// box holds about a hundred chords, of which one in seven is under it).
#[derive(Clone, Copy)]
struct ColumnChord {
    id: u32,
    /// The chord's last point (it is a candidate for points from there on).
    end: u32,
    /// Lowest and highest z of the chord, rounded down and up.
    z_min: f32,
    z_max: f32,
    a: [f32; 2],
    b: [f32; 2],
}

impl ColumnChord {
    fn new(id: u32, end: usize, a: DVec3, b: DVec3) -> Self {
        Self {
            id,
            end: end as u32,
            z_min: (a.z.min(b.z) as f32).next_down(),
            z_max: (a.z.max(b.z) as f32).next_up(),
            a: [a.x as f32, a.y as f32],
            b: [b.x as f32, b.y as f32],
        }
    }

    /// False only when the chord is surely not beside point `p` along its own direction (the
    /// foot of the perpendicular more than half its length before or after it): the exact test
    /// allows −0.5 … 1.5, this one −0.6 … 1.6 in single precision, and passes chords shorter
    /// than √`short2` (see [`short_chord2`]), whose fraction single precision cannot place
    /// within 0.1.
    ///
    /// Passes too chords with an end within √`end2` of `p` (see [`end_reach2`]): a point on
    /// the bead's round end, past a sharp corner of the layer below (see
    /// [`past_corner`]).
    ///
    /// And false when the chord lies wholly above or below the heights `z` (low, high) a layer
    /// under the point may have (the bead just laid, mostly).
    fn may_be_under(&self, p: [f32; 2], z: [f32; 2], [short2, end2]: [f32; 2]) -> bool {
        let ab = [self.b[0] - self.a[0], self.b[1] - self.a[1]];
        let len2 = ab[0] * ab[0] + ab[1] * ab[1];
        let dot = (p[0] - self.a[0]) * ab[0] + (p[1] - self.a[1]) * ab[1];
        let dist2 = |q: [f32; 2]| (p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]);
        let beside = (len2 < short2)
            | ((dot >= -0.6 * len2) & (dot <= 1.6 * len2))
            | (dist2(self.a) <= end2)
            | (dist2(self.b) <= end2);
        beside & (self.z_max >= z[0]) & (self.z_min <= z[1])
    }
}

/// The squared length below which a chord's single-precision fraction along it is not trusted,
/// mm², for coordinates up to `extent` mm and spots up to `radius` mm across.
///
/// Rounding to single precision moves each coordinate by δ ≤ extent·2⁻²⁴, so the fraction
/// f = (p − a)·(b − a) / |b − a|² moves by at most about 2δ(|b − a| + |p − a|) / |b − a|²; for a
/// chord the point may rest on, |p − a| ≤ 1.5·|b − a| + radius. That stays within the 0.1 of
/// slack when |b − a| ≥ 50δ + √(20δ·radius) (twice that, for the rounding of the arithmetic),
/// and never below 0.1 mm.
fn short_chord2(extent: f64, radius: f64) -> f32 {
    let delta = extent.abs() * 2f64.powi(-24);
    let len = (2.0 * (50.0 * delta + (20.0 * delta * radius).sqrt())).max(0.1);
    (len * len) as f32
}

/// The squared distance, mm², within which [`ColumnChord::may_be_under`] passes a chord whose
/// end is that near the point, for coordinates up to `extent` mm: half a bead, and 8δ for the
/// rounding of the coordinates to single precision (δ ≤ extent·2⁻²⁴ each) and of the sum.
fn end_reach2(extent: f64, half_bead: f64) -> f32 {
    let delta = extent.abs() * 2f64.powi(-24);
    let r = half_bead * (1.0 + 1e-6) + 8.0 * delta + 1e-6;
    (r * r) as f32
}

/// The chords that pass over one XY cell, in path order, with the running extremes of their
/// heights: a point's search takes only the run of chords that can reach its layers, found by
/// bisection (or a few steps from the last point's), instead of every chord of the column.
///
/// With `top[i]` = max z_max over chords 0 ..= i and `bottom[i]` = min z_min over chords i ..,
/// both non-decreasing: the chords before the first i with `top[i]` ≥ z_lo lie wholly below z_lo,
/// and those from the first i with `bottom[i]` > z_hi on lie wholly above z_hi. On a spiral (z
/// rising with the path) that leaves just the few layers within reach, whatever the height of
/// the column; on any other path it leaves at least the chords the height test keeps.
#[derive(Default)]
struct Column {
    chords: Vec<ColumnChord>,
    top: Vec<f32>,
    bottom: Vec<f32>,
}

impl Column {
    /// Fills the running extremes (once every chord is in).
    fn finish(&mut self) {
        self.top = self
            .chords
            .iter()
            .scan(f32::NEG_INFINITY, |t, c| {
                *t = t.max(c.z_max);
                Some(*t)
            })
            .collect();
        self.bottom = self
            .chords
            .iter()
            .rev()
            .scan(f32::INFINITY, |b, c| {
                *b = b.min(c.z_min);
                Some(*b)
            })
            .collect();
        self.bottom.reverse();
    }

    /// The run of chords laid before point `j` (their last point at or before it) that may reach
    /// heights `z` (low, high): found from the run of the last search when there is one (a few
    /// steps for the next point of a path, bisection after a jump), else by bisection.
    fn run(&self, j: usize, z: [f32; 2], from: Option<Run>) -> Run {
        let laid = |c: &ColumnChord| c.end as usize <= j;
        let below = |&t: &f32| t < z[0];
        let not_above = |&b: &f32| b <= z[1];
        match from {
            Some(from) => Run {
                low: seek(&self.top, from.low, below),
                high: seek(&self.bottom, from.high, not_above),
                laid: seek(&self.chords, from.laid, laid),
            },
            None => Run {
                low: self.top.partition_point(below),
                high: self.bottom.partition_point(not_above),
                laid: self.chords.partition_point(laid),
            },
        }
    }
}

/// A column's run for one point: chords `low .. high.min(laid)`.
#[derive(Clone, Copy, Default)]
struct Run {
    low: usize,
    high: usize,
    laid: usize,
}

impl Run {
    fn range(&self) -> std::ops::Range<usize> {
        self.low..self.high.min(self.laid).max(self.low)
    }
}

/// The first index of `v` where `pred` is false (`pred` true on a prefix of `v`, false after),
/// stepping from `guess` when it is near and bisecting otherwise.
pub(super) fn seek<T>(v: &[T], guess: usize, pred: impl Fn(&T) -> bool) -> usize {
    const STEPS: usize = 8;
    let mut i = guess.min(v.len());
    for _ in 0..STEPS {
        if i < v.len() && pred(&v[i]) {
            i += 1;
        } else if i > 0 && !pred(&v[i - 1]) {
            i -= 1;
        } else {
            return i;
        }
    }
    v.partition_point(pred)
}

/// Where the search finds the chords near a point.
enum ChordIndex {
    Grid(ChordGrid),
    Tree(ChordTree),
}

/// Spatial hash of path chords in XY columns.
struct ChordGrid {
    cell: f64,
    /// Each column's place in `columns`.
    index: HashMap<ColumnKey, u32, FixedState>,
    columns: Vec<Column>,
}

impl ChordGrid {
    fn key(&self, p: DVec2) -> ColumnKey {
        column_key(self.cell, p)
    }

    /// The grid of chords `chords` of path `v` that lie inside the machine, in columns `cell`
    /// mm across; built in parts of the chords on every core (from `serial_below` chords) and
    /// joined column by column (each part's chords follow the previous part's, so every column
    /// stays in path order). None when the chords need more than `budget` column insertions in
    /// all.
    fn build(
        v: &[DVec3],
        chords: &[(usize, usize)],
        cell: f64,
        inside: &(impl Fn(DVec3) -> bool + Sync),
        budget: usize,
        serial_below: usize,
    ) -> Option<ChordGrid> {
        let parts = crate::parallel::ranges(chords.len(), serial_below);
        let built = crate::parallel::run_parts(
            parts
                .into_iter()
                .map(|range| move || GridPart::build(v, chords, range, cell, inside, budget))
                .collect(),
        );
        let mut grid = ChordGrid {
            cell,
            index: HashMap::with_hasher(FixedState::default()),
            columns: Vec::new(),
        };
        let mut used = 0usize;
        for part in built {
            let part = part?;
            used = used.saturating_add(part.used);
            if used > budget {
                return None;
            }
            for (key, chords) in part.columns {
                let at = *grid.index.entry(key).or_insert_with(|| {
                    grid.columns.push(Column::default());
                    (grid.columns.len() - 1) as u32
                });
                let column = &mut grid.columns[at as usize].chords;
                // The parts split the chords, not the columns: a column's chords from this
                // part all come after those from the parts before.
                if column.is_empty() {
                    *column = chords;
                } else {
                    column.extend_from_slice(&chords);
                }
            }
        }
        crate::parallel::for_each_part(&mut grid.columns, 64, |_, columns| {
            columns.iter_mut().for_each(Column::finish)
        });
        Some(grid)
    }
}

/// Whether the chord from `a` to `b` rises more than it runs: a step between layers that no
/// point rests on, left out of the grid.
fn steep(a: DVec3, b: DVec3) -> bool {
    let d = b - a;
    d.z * d.z > d.truncate().length_squared()
}

/// The column holding point `p`, for columns `cell` mm across.
fn column_key(cell: f64, p: DVec2) -> ColumnKey {
    (floor_i32(p.x / cell), floor_i32(p.y / cell))
}

/// `q.floor() as i32` (saturating, NaN to 0), without a call to the C library's `floor`
/// (the default x86-64 target has no rounding instruction): truncation, one less for a
/// negative fraction.
fn floor_i32(q: f64) -> i32 {
    let t = q as i32;
    if f64::from(t) > q {
        t.saturating_sub(1)
    } else {
        t
    }
}

/// The columns of one part of the chords, in the order first met.
struct GridPart {
    columns: Vec<(ColumnKey, Vec<ColumnChord>)>,
    /// Column insertions made.
    used: usize,
}

impl GridPart {
    /// Chords `range` of path `v` (those with both ends inside the machine) in their columns;
    /// None past `budget` insertions.
    fn build(
        v: &[DVec3],
        chords: &[(usize, usize)],
        range: std::ops::Range<usize>,
        cell: f64,
        inside: &impl Fn(DVec3) -> bool,
        budget: usize,
    ) -> Option<GridPart> {
        let mut index: HashMap<ColumnKey, usize, FixedState> =
            HashMap::with_hasher(FixedState::default());
        let mut part = GridPart {
            columns: Vec::new(),
            used: 0,
        };
        // Consecutive chords mostly fall in the column of the one before.
        let mut last: Option<(ColumnKey, usize)> = None;
        for id in range {
            let (ia, ib) = chords[id];
            let (a, b) = (v[ia], v[ib]);
            if !(inside(a) && inside(b)) {
                continue;
            }
            part.insert(id as u32, ib, a, b, cell, budget, &mut index, &mut last)?;
        }
        Some(part)
    }

    /// Registers chord `id` from `a` to `b` in every column it passes: the chord is cut into
    /// pieces no longer than a cell and each piece's box of columns is marked. A steep chord
    /// (rising more than it runs) is a step between layers that no point rests on, and is left
    /// out. None when the insertion budget is spent.
    #[allow(clippy::too_many_arguments)]
    fn insert(
        &mut self,
        id: u32,
        end: usize,
        a: DVec3,
        b: DVec3,
        cell: f64,
        budget: usize,
        index: &mut HashMap<ColumnKey, usize, FixedState>,
        last: &mut Option<(ColumnKey, usize)>,
    ) -> Option<()> {
        if steep(a, b) {
            return Some(());
        }
        let d = b - a;
        let chord = ColumnChord::new(id, end, a, b);
        let steps = (d.truncate().abs().max_element() / cell).ceil().max(1.0);
        if steps > budget.saturating_sub(self.used) as f64 {
            return None;
        }
        let steps = steps as usize;
        for s in 0..steps {
            let (p, q) = (
                a.truncate() + d.truncate() * (s as f64 / steps as f64),
                a.truncate() + d.truncate() * ((s + 1) as f64 / steps as f64),
            );
            let (k0, k1) = (column_key(cell, p.min(q)), column_key(cell, p.max(q)));
            for x in k0.0..=k1.0 {
                for y in k0.1..=k1.1 {
                    if self.used >= budget {
                        return None;
                    }
                    self.used += 1;
                    let at = match *last {
                        Some((key, at)) if key == (x, y) => at,
                        _ => {
                            let at = *index.entry((x, y)).or_insert_with(|| {
                                self.columns.push(((x, y), Vec::new()));
                                self.columns.len() - 1
                            });
                            *last = Some(((x, y), at));
                            at
                        }
                    };
                    let column = &mut self.columns[at].1;
                    // Neighbouring pieces share columns: each column holds a chord once.
                    if column.last().is_none_or(|c| c.id != id) {
                        column.push(chord);
                    }
                }
            }
        }
        Some(())
    }
}

/// Points whose thin-layer bands are searched at once, at most (see
/// [`LayerSearch::band_clear`]).
const BAND_RUN: usize = 128;

/// How far, in bead widths, a run's points may lie from its first in XY (see
/// [`LayerSearch::band_clear`]): a few dozen points of a finely sampled wall. Runs of half a
/// bead searched the tree every 3.4 points of the benchmark vase; two beads' runs, every 14,
/// about as cheaply each (the band a fifth of a layer deep holds no chord near a wall going
/// round), so the proof takes 27 % fewer instructions (callgrind, 161 M → 118 M, 2026-12-06).
/// Four beads' runs (of up to 128 points) take 4 % fewer again (119 M → 115 M, 2026-12-06);
/// eight, no fewer.
const BAND_REACH_BEADS: f64 = 4.0;

/// Points searched alone after a run that met a chord in its band, before a run is tried
/// again.
const BAND_RETRY: usize = 16;

/// Path points in a block of [`chords_and_lengths`]: no chord crosses a block's end, so that
/// the blocks are found on every core and the chords are the same whatever their number.
const CHORD_BLOCK: usize = 1 << 15;

/// The chords of path `v` (see [`chords_and_lengths`]), for the tests.
#[cfg(test)]
pub(super) fn chords(v: &[DVec3]) -> Vec<(usize, usize)> {
    chords_and_lengths(v).0
}

/// The path `v` as chords `(i, k)`, and its length up to each point, mm: block by block on
/// every core.
///
/// A chord stands for path points `i ..= k`, all within [`CHORD_TOLERANCE_MM`] of the straight
/// line from point `i` to point `k` (at most [`MAX_POINTS_PER_CHORD`] points, and never across
/// a multiple of [`CHORD_BLOCK`]). A finely sampled curve becomes chords about a millimetre
/// long, whatever its sampling; a hostile file that zig-zags in one spot stays one chord per
/// point but its cells are capped.
///
/// The running length is summed within each block and the blocks' totals are added after, in
/// path order: the same sums whatever the number of cores.
fn chords_and_lengths(v: &[DVec3]) -> (Vec<(usize, usize)>, Vec<f64>) {
    let segments = v.len().saturating_sub(1);
    // Both buffers are written block by block, never cleared first (clearing them was a
    // memset of 5 MB on one core for the benchmark vase, 0.9 ms in a slow hour).
    let mut cum: Vec<f64> = Vec::with_capacity(v.len());
    // A block has at most a chord a segment: each is found into a room of that size, and the
    // rooms are closed up after (no second buffer to copy them into).
    let mut chords: Vec<(usize, usize)> = Vec::with_capacity(segments);
    let (lengths, rooms) = (
        &mut cum.spare_capacity_mut()[..v.len()],
        &mut chords.spare_capacity_mut()[..segments],
    );
    if let Some(start) = lengths.first_mut() {
        start.write(0.0);
    }
    // Per block: its lengths (from its first point) and its chords in its room, how many; the
    // blocks shared out as the cores get free (halves of whole blocks left one core waiting
    // for the other's extra block, 0.4 ms on the benchmark vase's seven).
    let blocks = lengths
        .get_mut(1..)
        .unwrap_or_default()
        .chunks_mut(CHORD_BLOCK)
        .zip(rooms.chunks_mut(CHORD_BLOCK))
        .enumerate()
        .map(|(b, (lengths, room))| {
            move || {
                let first = b * CHORD_BLOCK;
                let count = chords_in(v, first, first + lengths.len(), room);
                let mut sum = 0.0;
                for (m, c) in lengths.iter_mut().enumerate() {
                    sum += v[first + m].distance(v[first + m + 1]);
                    c.write(sum);
                }
                count
            }
        })
        .collect();
    let counts: Vec<usize> = crate::parallel::run_shared(blocks);
    // SAFETY: every length was written: the first above, each block's in its task (the blocks
    // cover the rest).
    unsafe { cum.set_len(v.len()) };
    // The blocks' totals carried on, in path order.
    let mut carried = 0.0;
    for lengths in cum.get_mut(1..).unwrap_or_default().chunks_mut(CHORD_BLOCK) {
        let total = lengths.last().copied().unwrap_or(0.0);
        if carried != 0.0 {
            lengths.iter_mut().for_each(|c| *c += carried);
        }
        carried += total;
    }
    // Each block's chords, written at the start of its room, moved down after the blocks
    // before it.
    let rooms = chords.spare_capacity_mut();
    let mut end = 0;
    for (b, count) in counts.into_iter().enumerate() {
        let at = b * CHORD_BLOCK;
        rooms.copy_within(at..at + count, end);
        end += count;
    }
    // SAFETY: places 0 .. end hold the blocks' chords, each written by `chords_in` and moved
    // down in path order.
    unsafe { chords.set_len(end) };
    (chords, cum)
}

/// The chords of path `v` (see [`chords_and_lengths`]), on this core: for a short path.
pub(crate) fn chords_of(v: &[DVec3]) -> Vec<(usize, usize)> {
    let segments = v.len().saturating_sub(1);
    let mut room = vec![std::mem::MaybeUninit::uninit(); segments];
    let count = chords_in(v, 0, segments, &mut room);
    room[..count]
        .iter()
        // SAFETY: `chords_in` wrote the first `count` places.
        .map(|c| unsafe { c.assume_init() })
        .collect()
}

/// Writes the chords of path points `first ..= last` (see [`chords_and_lengths`]) to the
/// start of `room` (one place a segment); how many there are.
fn chords_in(
    v: &[DVec3],
    first: usize,
    last: usize,
    room: &mut [std::mem::MaybeUninit<(usize, usize)>],
) -> usize {
    let mut count = 0;
    let mut i = first;
    while i < last {
        let k = chord_end(v, i, last, f64::INFINITY);
        room[count].write((i, k));
        count += 1;
        i = k;
    }
    count
}

/// The end of the chord of path `v` that starts at point `i` (before `last`): the furthest
/// point up to `last` (and [`MAX_POINTS_PER_CHORD`] points) with every point between within
/// [`CHORD_TOLERANCE_MM`] of the straight line from `i` to it; or the first that lies `long` or
/// further from `i` in XY.
#[inline]
fn chord_end(v: &[DVec3], i: usize, last: usize, long: f64) -> usize {
    let mut k = i + 1;
    while k < last
        && k + 1 - i < MAX_POINTS_PER_CHORD
        && (long == f64::INFINITY || v[k].truncate().distance(v[i].truncate()) < long)
    {
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
    k
}

/// The chords the checker could cut from path `v` (a stretch of a longer path), as far as a
/// point within `reach` of one of their ends can tell: the checker cuts the whole path into
/// chords from its start, so those of a stretch start wherever the ones before them ended.
/// From each point, the chord forward as [`chords_of`] would make it were one to start there,
/// and backward to each point the same way round; each stopped once it is `2 · reach` long in XY
/// (a point within reach of such a chord's end lies within half its length of it, in its
/// window ([`within_window`]), however much longer it is).
pub(crate) fn chords_beside(v: &[DVec3], reach: f64) -> Vec<(usize, usize)> {
    let last = v.len().saturating_sub(1);
    let long = 2.0 * reach;
    let mut chords: Vec<(usize, usize)> = (0..last)
        .map(|i| (i, chord_end(v, i, last, long)))
        .collect();
    let back: Vec<DVec3> = v.iter().rev().copied().collect();
    chords.extend((0..last).map(|i| (last - chord_end(&back, i, last, long), last - i)));
    chords.sort_unstable();
    chords.dedup();
    chords
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
    measure_layers_in(v, lines, limits, report, Search::NearFirst, false, None);
}

/// Whether the layers of `v` keep `limits`, shown point by point without measuring each in full
/// where a witness shows it (see [`LayerSearch::proves`]): true when shown for every point, and
/// then `report` holds the path's length and the holder's clearance only, not the layers'
/// figures; false when not (a limit broken, or the search's budget spent), and then `report` is
/// [`measure_layers`]'s. The clearance is `clearance` where it was measured already (as the
/// path was copied), else measured here.
pub(super) fn layers_hold(
    v: &[DVec3],
    lines: &[usize],
    limits: &Limits,
    report: &mut CheckReport,
    clearance: Option<ClearanceRun>,
) -> bool {
    let before = report.clone();
    let shown = measure_layers_in(v, lines, limits, report, Search::Tree, true, clearance);
    if !shown {
        // Not shown: the checker's own report (its grid gives the figures).
        *report = before;
        measure_layers(v, lines, limits, report);
    }
    shown
}

/// How [`measure_layers_in`] searches: all four give the same report (tested; the checker
/// uses the first, the self-check the last).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(not(test), allow(dead_code))]
enum Search {
    /// The near box first, the whole box where it does not settle the point (the checker's).
    NearFirst,
    /// The whole box always.
    WholeBox,
    /// Every earlier chord, without the grid or its prefilters, for every point (the path's
    /// first layer too, see [`nothing_under_until`]): the reference.
    EveryChord,
    /// The near box first, as `NearFirst`, with the chords found under their boxes
    /// ([`ChordTree`]) instead of in the grid's columns (the self-check's).
    Tree,
}

/// [`measure_layers`], searched as `search` says; with `first_show`, [`layers_hold`]. Where no
/// point's layers are tallied, the holder's clearance is `measured`'s, if given.
fn measure_layers_in(
    v: &[DVec3],
    lines: &[usize],
    limits: &Limits,
    report: &mut CheckReport,
    search: Search,
    first_show: bool,
    measured: Option<ClearanceRun>,
) -> bool {
    let tan_max = limits.max_overhang_deg.to_radians().tan();
    let radius = search_radius(limits);
    let gap = just_laid_gap(limits);
    let below_tol = same_layer_tolerance(limits);
    let layer_limits = LayerLimits::of(limits);
    let stepped_up = limits.min_layer_height - layer_limits.height_tol;
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
    // The near box (see [`LayerSearch::point`]): the support within half a bead, and every lean
    // up to the limit from the lowest layer within reach.
    let near_radius = if matches!(search, Search::NearFirst | Search::Tree) {
        (0.5 * limits.line_width).max(reach * tan_max).min(radius)
    } else {
        radius
    };
    let (chords, cum) = chords_and_lengths(v);
    let usable = |id: usize| {
        let (a, b) = (v[chords[id].0], v[chords[id].1]);
        inside(a) && inside(b) && !steep(a, b)
    };
    // The loops, and beside them the index of the chords the layer search reads.
    let (crossings, index) = find_crossings(
        v,
        &chords,
        lines,
        &cum,
        CrossingLimits {
            same_layer: below_tol,
            half_bead: 0.5 * limits.line_width,
            reach: LOOP_REACH_BEADS * limits.line_width,
        },
        &usable,
        || match search {
            // The tree holds what the grid holds, and is never too large to build.
            Search::Tree => Some(ChordIndex::Tree(ChordTree::build(v, &chords, &usable))),
            // Columns twice the near box's half-width across: a point's near box spans 2 × 2
            // of them mostly. Every chord goes into the grid first; a point's candidates are
            // the chords that end at or before it (a prefix of each column's ascending list),
            // so the points can be searched in any order, on every core.
            _ => ChordGrid::build(
                v,
                &chords,
                2.0 * near_radius,
                &inside,
                INSERTIONS_BASE.saturating_add(INSERTIONS_PER_CHORD.saturating_mul(chords.len())),
                crate::parallel::PARALLEL_POINTS,
            )
            .map(ChordIndex::Grid),
        },
    );
    let mut measurable = index.is_some();
    let index = index.unwrap_or_else(|| {
        ChordIndex::Grid(ChordGrid {
            cell: 2.0 * near_radius,
            index: HashMap::with_hasher(FixedState::default()),
            columns: Vec::new(),
        })
    });
    report.path_length_mm = cum[v.len() - 1];
    let extent = limits.bed_x.max(limits.bed_y).max(limits.max_z) + margin;
    let search = LayerSearch {
        v,
        chords: &chords,
        cum: &cum,
        index: &index,
        radius,
        near_radius,
        prefilter: [
            short_chord2(extent, radius),
            end_reach2(extent, 0.5 * limits.line_width),
        ],
        gap,
        stepped_up,
        below_tol,
        reach,
        half_bead: 0.5 * limits.line_width,
        bed_layer: limits.max_layer_height + 0.01 * limits.max_layer_height + 0.002,
        inside: &inside,
        every_chord: search == Search::EveryChord,
        // The reference searches every point.
        nothing_under_until: match search {
            Search::EveryChord => 0,
            _ => nothing_under_until(v, below_tol),
        },
    };
    let budget = CANDIDATES_BASE.saturating_add(CANDIDATES_PER_POINT.saturating_mul(v.len()));
    let shown = first_show && measurable && search.proves_all(budget, layer_limits);
    // Shown or not measurable: no point's layers to tally (the holder's clearance only).
    let below: Vec<Below> = if measurable && !shown {
        search.all(budget)
    } else {
        Vec::new()
    };
    let (mut thin, mut thick, mut lean, mut unsupported) = (
        Tally::default(),
        Tally::default(),
        Tally::default(),
        Tally::default(),
    );
    let mut clearance = Clearance {
        highest: f64::NEG_INFINITY,
        max_rise: report.max_rise_above_tip,
        limit: limits.nozzle_length + 1e-6,
        collide: Tally::default(),
    };
    report.min_layer_height = f64::INFINITY;
    // With no layers to tally, the clearance alone: as measured beside the path's copy, or in
    // one tight pass; else point by point.
    let tallied = if below.is_empty() {
        match measured {
            Some(run) => {
                clearance.max_rise = clearance.max_rise.max(run.clearance.max_rise);
                clearance.collide = run.clearance.collide;
                report.events.extend(run.events);
            }
            None => {
                for (p, &line) in v.iter().zip(lines) {
                    clearance.add(p.z, line, &mut report.events);
                }
            }
        }
        0
    } else {
        v.len()
    };
    for j in 0..tallied {
        let p = v[j];
        clearance.add(p.z, lines[j], &mut report.events);
        let Some(&below) = below.get(j).filter(|_| measurable) else {
            continue;
        };
        let (height, angle) = match below {
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
        if layer_limits.too_thin(height) {
            thin.add(limits.min_layer_height - height, lines[j]);
        }
        if layer_limits.too_thick(height) {
            thick.add(height - limits.max_layer_height, lines[j]);
        }
        report.max_overhang_deg = report.max_overhang_deg.max(angle);
        if layer_limits.leans_too_far(angle) {
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
    // A search that gave up, and what it left unmeasured.
    let not_measured = |report: &mut CheckReport, detail: String| {
        report.violations.push(Violation {
            what: NOT_MEASURED,
            count: 1,
            worst: report.path_length_mm,
            unit: " mm of path",
            first_line: lines[0],
            detail,
        })
    };
    if !measurable {
        not_measured(
            report,
            format!(
                "segments hundreds of bead widths long ({:.0} mm of path in {} chords): layers, overhang and support were not measured",
                report.path_length_mm,
                chords.len()
            ),
        );
    }
    let mut push = |t: Tally, what: &'static str, unit: &'static str, detail: String| {
        report
            .violations
            .extend(t.into_violation(what, unit, detail))
    };
    push(
        thin,
        "layer too thin",
        " mm short",
        format!("below min_layer_height {} mm", limits.min_layer_height),
    );
    push(
        thick,
        "layer too thick",
        " mm over",
        format!("above max_layer_height {} mm", limits.max_layer_height),
    );
    push(
        lean,
        OVERHANG,
        "°",
        format!("wall leans past {}°", limits.max_overhang_deg),
    );
    push(
        unsupported,
        UNSUPPORTED,
        " mm high (z of the highest such point)",
        format!("no printed layer within {radius:.1} mm below"),
    );
    push(
        crossings.tally,
        CROSSING,
        " mm out from the crossing",
        format!(
            "the nozzle runs through the bead it laid in the same layer, in loops reaching more than half a bead ({} mm) from where the path crosses itself",
            0.5 * limits.line_width
        ),
    );
    report.max_rise_above_tip = clearance.max_rise;
    push(
        clearance.collide,
        COLLISION,
        " mm above the nozzle tip",
        format!(
            "printed part rises above the holder, nozzle_length {} mm",
            limits.nozzle_length
        ),
    );
    if !crossings.complete {
        not_measured(
            report,
            "the path turns back on itself too often in too small a space: where it crosses itself was not searched in full".into(),
        );
    }
    report.events.extend(crossings.events);
    report.events.sort_by_key(|e| e.line);
    shown
}

/// The holder's clearance along the path: how far the part printed rises above the point
/// printing (the highest point so far, over it), and where that is more than the nozzle's
/// length (the holder hits the part).
#[derive(Debug, PartialEq)]
struct Clearance {
    highest: f64,
    max_rise: f64,
    /// The nozzle's length, with a tolerance.
    limit: f64,
    collide: Tally,
}

impl Clearance {
    /// The next point of the path, at height `z` on `line`.
    #[inline]
    fn add(&mut self, z: f64, line: usize, events: &mut Vec<PathEvent>) {
        let rise = self.highest - z;
        if rise > self.max_rise {
            self.max_rise = rise;
        }
        if rise > self.limit {
            self.collide.add(rise, line);
            events.push(PathEvent {
                line,
                what: COLLISION,
                value: rise,
            });
        }
        self.highest = self.highest.max(z);
    }
}

/// The holder's clearance along one run of the path, measured as if the path began there, with
/// the run's lowest point: two runs in path order join into the clearance of both
/// ([`ClearanceRun::then`]). The self-check measures the two halves of the path as it copies
/// them, on two cores, rather than in a pass of its own at the end (on one).
#[derive(Debug, PartialEq)]
pub(super) struct ClearanceRun {
    clearance: Clearance,
    lowest: f64,
    events: Vec<PathEvent>,
}

impl ClearanceRun {
    /// A run not yet begun, for a nozzle of `limits`.
    pub(super) fn new(limits: &Limits) -> ClearanceRun {
        ClearanceRun {
            clearance: Clearance {
                highest: f64::NEG_INFINITY,
                max_rise: f64::NEG_INFINITY,
                limit: limits.nozzle_length + 1e-6,
                collide: Tally::default(),
            },
            lowest: f64::INFINITY,
            events: Vec::new(),
        }
    }

    /// The next point of the run, at height `z` on `line`.
    #[inline]
    pub(super) fn add(&mut self, z: f64, line: usize) {
        self.clearance.add(z, line, &mut self.events);
        self.lowest = self.lowest.min(z);
    }

    /// This run followed by `later`: as if every point had been added to one, or `None` where
    /// that cannot be told from the two (a point of `later` lower than this run's highest by
    /// more than the nozzle's length: its rise was measured from `later`'s own points only).
    ///
    /// Otherwise every rise in `later` is the larger of its own and this run's highest over the
    /// point, and the second is within the limit: the collisions are `later`'s own, and the
    /// largest rise this run makes in it is its highest over `later`'s lowest.
    pub(super) fn then(self, later: ClearanceRun) -> Option<ClearanceRun> {
        let (a, b) = (self.clearance, later.clearance);
        let over_later = a.highest - later.lowest;
        if over_later > a.limit {
            return None;
        }
        let mut events = self.events;
        events.extend(later.events);
        Some(ClearanceRun {
            clearance: Clearance {
                highest: a.highest.max(b.highest),
                max_rise: a.max_rise.max(b.max_rise).max(over_later),
                limit: a.limit,
                collide: a.collide.then(b.collide),
            },
            lowest: self.lowest.min(later.lowest),
            events,
        })
    }
}

/// The grid columns around the last point searched, each with its run for that point (the
/// columns are looked up again only when the box moves; the runs move a few chords a point).
/// A column's run is also kept after the box leaves it: the path comes back to the column a
/// layer higher, and the run has moved by the chords of one layer, a few steps from it.
#[derive(Default)]
struct NearColumns<'g> {
    bounds: Option<(ColumnKey, ColumnKey)>,
    /// The box's columns: each with its run and its place in the grid.
    columns: Vec<(&'g Column, Run, u32)>,
    /// Each grid column's last run, by its place in the grid (empty until first needed).
    last: Vec<Option<Run>>,
    /// For a search of the [`ChordTree`]: the chords laid before the last point, and the first
    /// leaf its search looked at.
    laid: usize,
    first_leaf: usize,
}

impl<'g> NearColumns<'g> {
    /// The columns of the box `lo ..= hi` with their runs for point `j` and heights `z`.
    fn update(
        &mut self,
        grid: &'g ChordGrid,
        lo: ColumnKey,
        hi: ColumnKey,
        j: usize,
        z: [f32; 2],
    ) -> &[(&'g Column, Run, u32)] {
        if self.bounds != Some((lo, hi)) {
            self.bounds = Some((lo, hi));
            if self.last.len() != grid.columns.len() {
                self.last = vec![None; grid.columns.len()];
            }
            for &(_, run, at) in &self.columns {
                self.last[at as usize] = Some(run);
            }
            self.columns.clear();
            for x in lo.0..=hi.0 {
                for y in lo.1..=hi.1 {
                    if let Some(&at) = grid.index.get(&(x, y)) {
                        let column = &grid.columns[at as usize];
                        let run = column.run(j, z, self.last[at as usize]);
                        self.columns.push((column, run, at));
                    }
                }
            }
            return &self.columns;
        }
        for (column, run, _) in &mut self.columns {
            *run = column.run(j, z, Some(*run));
        }
        &self.columns
    }
}

/// The limits a point's layer keeps, with the tolerances the checker allows them.
#[derive(Debug, Clone, Copy)]
struct LayerLimits {
    min_height: f64,
    max_height: f64,
    /// mm either way: the 1 µm rounding of G-code coordinates, and 1 % of the range.
    height_tol: f64,
    /// Degrees from vertical, tolerance included: G-code coordinates are rounded to 1 µm and
    /// the lean is measured against polyline segments; the seam step where the helix leaves
    /// the flat revolution leans up to ~2° more than the sections around it for one point.
    max_lean_deg: f64,
    /// A lean whose tangent is below this is surely within `max_lean_deg` (a millionth of a
    /// degree to spare for the rounding of the tangent): the witness's test, without an
    /// arctangent per point.
    surely_within_tan: f64,
}

impl LayerLimits {
    fn of(limits: &Limits) -> Self {
        LayerLimits {
            min_height: limits.min_layer_height,
            max_height: limits.max_layer_height,
            height_tol: 0.01 * limits.max_layer_height + 0.002,
            max_lean_deg: limits.max_overhang_deg + 2.0,
            surely_within_tan: Self::tan_below(limits.max_overhang_deg + 2.0),
        }
    }

    /// The tangent of a millionth of a degree less than `lean_deg` (infinite from 90°: every
    /// lean of a spot below a point is less).
    fn tan_below(lean_deg: f64) -> f64 {
        let deg = lean_deg - 1e-6;
        if deg >= 90.0 {
            f64::INFINITY
        } else {
            deg.max(0.0).to_radians().tan()
        }
    }

    fn too_thin(&self, height: f64) -> bool {
        height < self.min_height - self.height_tol
    }

    fn too_thick(&self, height: f64) -> bool {
        height > self.max_height + self.height_tol
    }

    fn leans_too_far(&self, lean_deg: f64) -> bool {
        lean_deg > self.max_lean_deg
    }

    /// Whether what lies below a point breaks a limit (or was not measured).
    fn broken_by(&self, below: Below) -> bool {
        match below {
            Below::Skipped => false,
            Below::Unmeasurable | Below::Unsupported => true,
            Below::Layer { height, lean_deg } => {
                self.too_thin(height) || self.too_thick(height) || self.leans_too_far(lean_deg)
            }
        }
    }
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

/// The layers found under one point so far: each is a spot `(zq, d)` of an earlier chord at
/// height `zq`, `d` across from the point in XY. Kept as running extremes, not a list.
#[derive(Clone, Copy)]
struct Found {
    /// Highest spot within half a bead (the layer the point rests on), and its chord.
    top_under: f64,
    top_chord: usize,
    /// The spot of least lean, as d / (p.z − zq) (the tangent of the lean, which is monotone in
    /// it: one arctangent per point, not per spot), with d and zq: of spots leaning as little,
    /// the highest.
    least_lean: Option<(f64, f64, f64)>,
    /// The nearest spot in XY, (d, zq): of spots as near, the highest.
    nearest: Option<(f64, f64)>,
}

impl Found {
    const NONE: Found = Found {
        top_under: f64::NEG_INFINITY,
        top_chord: usize::MAX,
        least_lean: None,
        nearest: None,
    };

    fn add(&mut self, pz: f64, zq: f64, d: f64, half_bead: f64, chord: usize) {
        if d <= half_bead && zq > self.top_under {
            (self.top_under, self.top_chord) = (zq, chord);
        }
        // Ties go to the higher spot, so that the answer does not depend on the order the
        // chords are met in (the grid meets them column by column, the tree box by box).
        let tan = d / (pz - zq).max(1e-9);
        if self
            .least_lean
            .is_none_or(|(t, _, z)| tan < t || (tan == t && zq > z))
        {
            self.least_lean = Some((tan, d, zq));
        }
        if self
            .nearest
            .is_none_or(|(dn, z)| d < dn || (d == dn && zq > z))
        {
            self.nearest = Some((d, zq));
        }
    }
}

/// The search for the layer below each point (read-only: shared by the threads).
struct LayerSearch<'a, F: Fn(DVec3) -> bool + Sync> {
    v: &'a [DVec3],
    chords: &'a [(usize, usize)],
    /// Path length up to each point, mm.
    cum: &'a [f64],
    index: &'a ChordIndex,
    radius: f64,
    /// The first, smaller search box's half-width, mm (see [`LayerSearch::point`]).
    near_radius: f64,
    /// The prefilter's two squared lengths, see [`short_chord2`] and [`end_reach2`].
    prefilter: [f32; 2],
    gap: f64,
    /// A spot at least this far below the point (a minimum layer, less the tolerance) is a layer
    /// the path has stepped up from within a few beads (a base's next layer starting a layer up
    /// and out at a 45° flare, a wall leaving its base), never the bead just laid.
    stepped_up: f64,
    below_tol: f64,
    reach: f64,
    half_bead: f64,
    /// Highest a point may be and still rest on the bed, mm.
    bed_layer: f64,
    inside: &'a F,
    /// Search every earlier chord instead of the grid (see [`Search::EveryChord`]).
    every_chord: bool,
    /// Points before this one have no point before them low enough to lie under them
    /// ([`nothing_under_until`]): the path's first layer, on the bed.
    nothing_under_until: usize,
}

/// How far across from a point the layer search looks for what lies below it, mm: a bead, and
/// the lean of two of the thickest layers at the overhang limit.
fn search_radius(limits: &Limits) -> f64 {
    let tan_max = limits.max_overhang_deg.to_radians().tan();
    limits.line_width + 2.0 * limits.max_layer_height * tan_max
}

/// Whether `p`, at `f_line` along chord `id` of path `v` (more than half its length past one of
/// its ends), lies more than half a length past that end of the chord beyond it too: outside
/// the tip of a sharp corner of the path, which neither chord at the corner has beside it.
/// There the corner is the spot under `p` (within half a bead: on the bead's round end).
pub(crate) fn past_corner(
    v: &[DVec3],
    chords: &[(usize, usize)],
    id: usize,
    f_line: f64,
    p: DVec2,
) -> bool {
    let other = if f_line > 1.5 {
        id.checked_add(1)
    } else {
        id.checked_sub(1)
    };
    let Some(&(ia, ib)) = other.and_then(|k| chords.get(k)) else {
        return false;
    };
    let (a, b) = (v[ia].truncate(), v[ib].truncate());
    let len2 = (b - a).length_squared();
    if len2 == 0.0 {
        return false;
    }
    let g = (p - a).dot(b - a) / len2;
    if f_line > 1.5 { g < -0.5 } else { g > 1.5 }
}

/// Where chord `id` of path `v` lies under the point `p` (in XY), as the layer search measures
/// it: the foot of the perpendicular at `f` along the chord (clamped to it), `d` across from
/// `p`, at height `z` there; `None` where the chord is more than `radius` across, or where the
/// foot lies more than half the chord's length past its ends (a chord ahead of or behind `p`
/// along its own direction is beside `p`, not under it) unless `p` is within `half_bead` and
/// outside the tip of a sharp corner there ([`past_corner`]).
#[inline]
fn foot_under(
    v: &[DVec3],
    chords: &[(usize, usize)],
    id: usize,
    p: DVec2,
    radius: f64,
    half_bead: f64,
) -> Option<ChordFoot> {
    let (ia, ib) = chords[id];
    let (f_line, foot) = chord_foot(v[ia], v[ib], p);
    if foot.d > radius
        || !(within_window(f_line) || foot.d <= half_bead && past_corner(v, chords, id, f_line, p))
    {
        return None;
    }
    Some(foot)
}

/// Whether a point at `f_line` along a chord's line lies beside the chord rather than ahead
/// of it or behind it: within half the chord's length past either end.
#[inline]
pub(crate) fn within_window(f_line: f64) -> bool {
    (-0.5..=1.5).contains(&f_line)
}

/// The foot of the perpendicular from `p` on the chord `a`–`b` (in XY): its fraction along
/// the chord's line, and the foot clamped to the chord ([`ChordFoot`]).
#[inline]
pub(crate) fn chord_foot(a: DVec3, b: DVec3, p: DVec2) -> (f64, ChordFoot) {
    let (a2, b2) = (a.truncate(), b.truncate());
    let ab = b2 - a2;
    let len2 = ab.length_squared();
    let f_line = if len2 > 0.0 {
        (p - a2).dot(ab) / len2
    } else {
        0.0
    };
    // `point_segment_distance` with the fraction along the line above.
    let f = f_line.clamp(0.0, 1.0);
    let foot = ChordFoot {
        f,
        d: p.distance(a2 + ab * f),
        z: a.z + (b.z - a.z) * f,
    };
    (f_line, foot)
}

/// The foot of the perpendicular on a chord under a point ([`foot_under`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct ChordFoot {
    /// Fraction along the chord, 0 … 1.
    pub f: f64,
    /// Distance across from the point, mm.
    pub d: f64,
    /// Height of the chord there, mm.
    pub z: f64,
}

/// Whether a spot `behind` mm back along the path from a point, `d` across from it and `rise`
/// under it, is the bead just laid rather than the layer below (see [`LayerSearch::spot`]): it
/// is within `gap` along an almost straight stretch of path (at least half as far across as
/// along) and less than a thin layer (`stepped_up`) under the point. Where the path has come
/// back over itself the layer below is much nearer in XY than along the path; where it has
/// stepped up a whole layer on the way, what it left is the layer below.
#[inline]
pub(crate) fn on_bead_just_laid(behind: f64, d: f64, rise: f64, gap: f64, stepped_up: f64) -> bool {
    behind < gap && d >= 0.5 * behind && rise < stepped_up
}

/// The thinnest layer the search accepts, mm: the printer's thinnest, less the tolerance of a
/// measure between chords that stand for the path within [`CHORD_TOLERANCE_MM`].
pub(crate) fn thinnest_layer_accepted(limits: &Limits) -> f64 {
    let layer = LayerLimits::of(limits);
    layer.min_height - layer.height_tol
}

/// A spot less than this under a point is at its own height, not a layer below it, mm: a
/// quarter of the thinnest layer.
pub(crate) fn same_layer_tolerance(limits: &Limits) -> f64 {
    0.25 * limits.min_layer_height
}

/// Path length, mm, within which a spot behind a point along an almost straight stretch of path
/// is the bead just laid, not the layer below (see [`LayerSearch::spot`]): three search radii.
/// The spot is passed over when it also lies at least half its length along the path across
/// from the point and less than a thin layer under it.
pub(crate) fn just_laid_gap(limits: &Limits) -> f64 {
    3.0 * search_radius(limits)
}

/// The first point of path `v` that some point up to it lies at least `below_tol` under (less
/// 10⁻⁹ mm, for the rounding of a spot's height between a chord's ends, which lies between
/// them): every point before it has no chord laid before it with a spot in its search's
/// heights (`below_tol` or more under it), so nothing lies under it but, maybe, the bed. The
/// path's first layer: the benchmark vase's first 2 878 points, each of which the search
/// found nothing under after searching the whole box around it (0.7 µs a point, 2 ms of
/// processor time in its proof).
fn nothing_under_until(v: &[DVec3], below_tol: f64) -> usize {
    let mut lowest = f64::INFINITY;
    v.iter()
        .position(|p| {
            lowest = lowest.min(p.z);
            lowest <= p.z - below_tol + 1e-9
        })
        .unwrap_or(v.len())
}

/// Points a task of the layer search takes ([`LayerSearch::all`], [`LayerSearch::proves_all`]):
/// the cost of a point varies along the path (the base, the belly's turns), so the points are
/// shared out in runs as the cores get free, not in halves. A run's first point has no chord
/// under the point before to start from: it is searched in full, one point in 4 096.
const SEARCH_RUN: usize = 4096;

/// Runs of the points of a path of `n` for the cores to share out: of [`SEARCH_RUN`] points,
/// and the last two runs' points in runs an eighth as long, so that the core that takes the
/// last run does not keep the other waiting for most of a run (about 0.3 ms of the benchmark
/// vase's proof).
fn search_runs(n: usize) -> Vec<std::ops::Range<usize>> {
    const TAIL_RUN: usize = SEARCH_RUN / 8;
    let tail_from = n.saturating_sub(2 * SEARCH_RUN);
    let body = (0..tail_from)
        .step_by(SEARCH_RUN)
        .map(|s| s..(s + SEARCH_RUN).min(tail_from));
    let tail = (tail_from..n)
        .step_by(TAIL_RUN)
        .map(|s| s..(s + TAIL_RUN).min(n));
    body.chain(tail).collect()
}

impl<F: Fn(DVec3) -> bool + Sync> LayerSearch<'_, F> {
    /// Every point, in runs of [`SEARCH_RUN`] shared out over the machine's cores as they go;
    /// each run gets its share of the budget.
    fn all(&self, budget: usize) -> Vec<Below> {
        let n = self.v.len();
        if crate::parallel::cores() < 2 || n < crate::parallel::PARALLEL_POINTS {
            return self.range(0..n, budget);
        }
        let runs = search_runs(n);
        let share = budget / runs.len().max(1);
        crate::parallel::map_shared(
            runs.len(),
            || (),
            |(), k| self.range(runs[k].clone(), share),
        )
        .into_iter()
        .flatten()
        .collect()
    }

    /// Points `range`, with `budget` candidate chords to examine in all; once it is spent the
    /// rest are unmeasurable.
    fn range(&self, range: std::ops::Range<usize>, mut budget: usize) -> Vec<Below> {
        let mut out = Vec::with_capacity(range.len());
        let (mut near, mut wide) = (NearColumns::default(), NearColumns::default());
        let mut spent = false;
        for j in range {
            if spent {
                out.push(Below::Unmeasurable);
                continue;
            }
            let (b, _) = self.point(j, &mut near, &mut wide, &mut budget);
            spent = b == Below::Unmeasurable;
            out.push(b);
        }
        out
    }

    /// Whether every point keeps `limits`, shown without measuring every point in full (see
    /// [`LayerSearch::proves`]); on every core, each part with its share of `budget`.
    fn proves_all(&self, budget: usize, limits: LayerLimits) -> bool {
        let n = self.v.len();
        if crate::parallel::cores() < 2 || n < crate::parallel::PARALLEL_POINTS {
            return self.proves(0..n, budget, limits);
        }
        let runs = search_runs(n);
        let share = budget / runs.len().max(1);
        // Once a run is not shown, the others need not be tried.
        let failed = std::sync::atomic::AtomicBool::new(false);
        let shown = |k: usize| {
            use std::sync::atomic::Ordering::Relaxed;
            let shown = !failed.load(Relaxed) && self.proves(runs[k].clone(), share, limits);
            if !shown {
                failed.store(true, Relaxed);
            }
            shown
        };
        crate::parallel::map_shared(runs.len(), || (), |(), k| shown(k))
            .into_iter()
            .all(|holds| holds)
    }

    /// Whether points `range` keep `limits` (the layer they rest on neither too thin nor too
    /// thick, a lean within the limit, support): true only when shown for each; false at the
    /// first point where it is not (a point that breaks a limit, or one this way cannot show).
    ///
    /// A point is shown by a witness: a spot within half a bead under it (so the layer it
    /// rests on is at least that high, and the layer not too thick) leaning within the limit (so
    /// the least lean is too), sought on the chords from the one under the point before; and by
    /// the absence of any spot within half a bead higher than the thinnest layer allows (a
    /// search of a band of heights a fifth of a layer deep, which on a rising wall holds no
    /// chord). Where no witness is near, the point is measured in full and judged.
    fn proves(
        &self,
        range: std::ops::Range<usize>,
        mut budget: usize,
        limits: LayerLimits,
    ) -> bool {
        let (mut near, mut wide, mut thin) = (
            NearColumns::default(),
            NearColumns::default(),
            NearColumns::default(),
        );
        let mut under: Option<usize> = None;
        // Points before `clear_to` are shown free of thin layers by their run's search (see
        // [`LayerSearch::band_clear`]); from `tried_to` on, a run is tried again.
        let (mut clear_to, mut tried_to) = (0, 0);
        let end = range.end;
        for j in range {
            let p = self.v[j];
            if j == 0 || !(self.inside)(p) {
                continue;
            }
            // The path moves on about a chord a point: the next chord first (the witness of
            // nine points in ten on the benchmark vase), then the same, the ones after, the one
            // before.
            let witness = under.and_then(|k| {
                [k + 1, k, k + 2, k + 3, k.wrapping_sub(1)]
                    .into_iter()
                    .find(|&id| self.witnesses(j, id, limits))
            });
            if witness.is_none() {
                let (below, top) = self.point(j, &mut near, &mut wide, &mut budget);
                if limits.broken_by(below) {
                    return false;
                }
                under = top;
                continue;
            }
            under = witness;
            if j < clear_to {
                continue;
            }
            if j >= tried_to {
                match self.band_clear(j, end, limits, &mut thin, &mut budget) {
                    None => return false,
                    Some(k) if k > j => {
                        clear_to = k;
                        continue;
                    }
                    Some(_) => tried_to = j + BAND_RETRY,
                }
            }
            let heights = [
                p.z - limits.min_height + limits.height_tol,
                p.z - self.below_tol,
            ];
            match self.scan_heights(j, self.half_bead, heights, &mut thin, &mut budget) {
                Some(found) if !found.top_under.is_finite() => {}
                Some(_) => {
                    // A spot as high as a thin layer: measured in full and judged.
                    let (below, _) = self.point(j, &mut near, &mut wide, &mut budget);
                    if limits.broken_by(below) {
                        return false;
                    }
                }
                None => return false,
            }
        }
        true
    }

    /// The end of a short run of points from j (before `end`) shown to have no spot in any of
    /// their thin-layer bands (see [`LayerSearch::proves`]) by one search of the tree around
    /// the whole run; `Some(j)` when that search meets a chord that might hold one (each point
    /// is then searched alone), or the index is not a tree; `None` once the budget is spent.
    ///
    /// The run: up to [`BAND_RUN`] points inside the machine, within [`BAND_REACH_BEADS`] of
    /// its first in XY and rising less than the height tolerance from it (so that the run's
    /// band stays a point's). Its search holds each point's: the chords laid before its last
    /// point, a circle around the run's box holding each point's half-bead circle, and every
    /// point's heights. A longer run's circle is wider, and more often meets a chord in its band
    /// (then each point is searched alone): a run stays where that is rare.
    fn band_clear(
        &self,
        j: usize,
        end: usize,
        limits: LayerLimits,
        cache: &mut NearColumns,
        budget: &mut usize,
    ) -> Option<usize> {
        let ChordIndex::Tree(tree) = self.index else {
            return Some(j);
        };
        let first = self.v[j];
        let run_end = (j..end.min(j + BAND_RUN))
            .find(|&k| {
                let q = self.v[k];
                !(self.inside)(q)
                    || q.truncate().distance(first.truncate())
                        > 2.0 * BAND_REACH_BEADS * self.half_bead
                    || q.z - first.z >= limits.height_tol
                    || q.z < first.z
            })
            .unwrap_or(end.min(j + BAND_RUN));
        if run_end < j + 2 {
            return Some(j);
        }
        let run = &self.v[j..run_end];
        let (lo, hi) = run.iter().fold(
            (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
            |(lo, hi), q| (lo.min(q.truncate()), hi.max(q.truncate())),
        );
        let z_lo = run.iter().map(|q| q.z).fold(f64::INFINITY, f64::min);
        let z_hi = run.iter().map(|q| q.z).fold(f64::NEG_INFINITY, f64::max);
        let z32 = [
            ((z_lo - limits.min_height + limits.height_tol) as f32).next_down(),
            ((z_hi - self.below_tol) as f32).next_up(),
        ];
        let centre = 0.5 * (lo + hi);
        let r = self.half_bead + 0.5 * (hi - lo).length() + 1e-6;
        let last = run_end - 1;
        cache.laid = seek(self.chords, cache.laid, |&(_, e)| e <= last);
        let mut met = false;
        let visited = tree.visit(
            centre,
            r,
            z32,
            cache.laid,
            &mut cache.first_leaf,
            budget,
            |id| met |= self.held(id),
        );
        if !visited {
            return None;
        }
        Some(if met { j } else { run_end })
    }

    /// Whether chord `id`'s spot under point j is a witness that j keeps `limits` (see
    /// [`LayerSearch::proves`]): a spot as the search would find it, within half a bead, at
    /// most the thickest layer below and leaning within the limit.
    fn witnesses(&self, j: usize, id: usize, limits: LayerLimits) -> bool {
        // Only chords the search would meet: laid before j, held by the grid.
        if self.chords.get(id).is_none_or(|&(_, end)| end > j) || !self.held(id) {
            return false;
        }
        let p = self.v[j];
        let Some((z, d)) = self.spot(j, id, [p.z - self.reach, p.z - self.below_tol]) else {
            return false;
        };
        // Within half a bead: the layer the point rests on is at least this high.
        d <= self.half_bead
            && !limits.too_thick(p.z - z)
            // The least lean is at most this one's (its tangent is).
            && d < (p.z - z).max(1e-9) * limits.surely_within_tan
    }

    /// The topmost earlier layer below point j within the search radius, and the least lean
    /// from the layers below within reach.
    ///
    /// Searched in two boxes. The near box (half-width `near_radius` ≥ half a bead) holds every
    /// spot the point can rest on, so it settles the support. A spot outside it, at d >
    /// near_radius and at most `reach` below, leans more than near_radius / reach; when the
    /// least lean found in the near box is already below that, nothing outside can lessen it
    /// and the answer is the one the whole box would give. Otherwise (no support near, or a
    /// lean past the limit) the whole box of half-width `radius` is searched.
    ///
    /// With it, the chord of the layer the point rests on (if it rests on one).
    fn point<'g>(
        &'g self,
        j: usize,
        near: &mut NearColumns<'g>,
        wide: &mut NearColumns<'g>,
        budget: &mut usize,
    ) -> (Below, Option<usize>) {
        let p = self.v[j];
        if j == 0 || !(self.inside)(p) {
            return (Below::Skipped, None);
        }
        if j < self.nothing_under_until {
            return (self.below(p, Found::NONE), None);
        }
        let found = if self.every_chord {
            self.every_chord(j)
        } else {
            match self.point_scans(j, near, wide, budget) {
                Some(found) => found,
                None => return (Below::Unmeasurable, None),
            }
        };
        let top = found.top_under.is_finite().then_some(found.top_chord);
        (self.below(p, found), top)
    }

    /// The near box's spots, or the whole box's where the near box does not settle the point.
    fn point_scans<'g>(
        &'g self,
        j: usize,
        near: &mut NearColumns<'g>,
        wide: &mut NearColumns<'g>,
        budget: &mut usize,
    ) -> Option<Found> {
        let mut found = self.scan(j, self.near_radius, near, budget)?;
        let settled = found.top_under.is_finite()
            && found
                .least_lean
                .is_some_and(|(t, _, _)| t * self.reach < self.near_radius);
        if !settled && self.near_radius < self.radius {
            found = self.scan(j, self.radius, wide, budget)?;
        }
        Some(found)
    }

    /// What lies below point `p`, given the spots found under it.
    fn below(&self, p: DVec3, found: Found) -> Below {
        let lean = |d: f64, z: f64| d.atan2((p.z - z).max(1e-9)).to_degrees();
        // Support: the topmost layer within half a bead of p; failing that, the nearest layer.
        // The lean: the least of the layers below within reach. A wall that leans leans alike
        // from each layer under it; a bead laid beside an earlier, thinner one (the step between
        // the beads of a wall of several, a tie, a base bead crossing under) while resting on a
        // layer beneath does not lean.
        match (found.top_under.is_finite(), found.least_lean, found.nearest) {
            (true, Some((_, d, z)), _) => Below::Layer {
                height: p.z - found.top_under,
                lean_deg: lean(d, z),
            },
            (_, _, Some((d, z))) => Below::Layer {
                height: p.z - z,
                lean_deg: lean(d, z),
            },
            _ if p.z <= self.bed_layer => Below::Layer {
                height: p.z,
                lean_deg: 0.0,
            }, // on the bed
            _ => Below::Unsupported,
        }
    }

    /// The spots of the chords laid before point j, in the columns of the box of half-width
    /// `box_radius` around it, within `radius` across and between `reach` and `below_tol` below
    /// it. None when the candidate budget is spent.
    fn scan<'g>(
        &'g self,
        j: usize,
        box_radius: f64,
        cache: &mut NearColumns<'g>,
        budget: &mut usize,
    ) -> Option<Found> {
        let z = self.v[j].z;
        self.scan_heights(
            j,
            box_radius,
            [z - self.reach, z - self.below_tol],
            cache,
            budget,
        )
    }

    /// [`LayerSearch::scan`] for the spots at heights `z_lo ..= z_hi` only.
    fn scan_heights<'g>(
        &'g self,
        j: usize,
        box_radius: f64,
        [z_lo, z_hi]: [f64; 2],
        cache: &mut NearColumns<'g>,
        budget: &mut usize,
    ) -> Option<Found> {
        let p = self.v[j];
        let pxy = p.truncate();
        let z32 = [(z_lo as f32).next_down(), (z_hi as f32).next_up()];
        let p32 = [pxy.x as f32, pxy.y as f32];
        let grid = match self.index {
            ChordIndex::Grid(grid) => grid,
            ChordIndex::Tree(tree) => {
                // The chords laid before j: a few steps from the last point's.
                cache.laid = seek(self.chords, cache.laid, |&(_, end)| end <= j);
                let mut found = Found::NONE;
                let (laid, first) = (cache.laid, &mut cache.first_leaf);
                let visited = tree.visit(pxy, box_radius, z32, laid, first, budget, |id| {
                    if self.held(id) {
                        self.add_spot(j, id, [z_lo, z_hi], &mut found);
                    }
                });
                return visited.then_some(found);
            }
        };
        // Consecutive points mostly share their box of columns: look them up once per box.
        let columns = cache.update(
            grid,
            grid.key(pxy - box_radius),
            grid.key(pxy + box_radius),
            j,
            z32,
        );
        let mut found = Found::NONE;
        for (column, run, _) in columns {
            // The chords laid before p that may reach its layers.
            let cell = &column.chords[run.range()];
            if cell.len() > *budget {
                return None;
            }
            *budget -= cell.len();
            for c in cell {
                // Most candidates are rejected on their single-precision copy, without reading
                // the path.
                if !c.may_be_under(p32, z32, self.prefilter) {
                    continue;
                }
                self.add_spot(j, c.id as usize, [z_lo, z_hi], &mut found);
            }
        }
        Some(found)
    }

    /// The spots of every chord laid before point j that the grid holds, by the exact test
    /// alone.
    fn every_chord(&self, j: usize) -> Found {
        let p = self.v[j];
        let z = [p.z - self.reach, p.z - self.below_tol];
        let mut found = Found::NONE;
        for id in (0..self.chords.len()).take_while(|&id| self.chords[id].1 <= j) {
            if self.held(id) {
                self.add_spot(j, id, z, &mut found);
            }
        }
        found
    }

    /// Whether the search holds chord `id`: both ends inside the machine, and not steep (as
    /// the tree, when searched, has it already).
    #[inline]
    fn held(&self, id: usize) -> bool {
        if let ChordIndex::Tree(tree) = self.index {
            return tree.holds(id);
        }
        let (a, b) = (self.v[self.chords[id].0], self.v[self.chords[id].1]);
        (self.inside)(a) && (self.inside)(b) && !steep(a, b)
    }

    /// Adds to `found` the spot of chord `id` under point j, when it is one (see
    /// [`LayerSearch::spot`]).
    fn add_spot(&self, j: usize, id: usize, z: [f64; 2], found: &mut Found) {
        if let Some((zq, d)) = self.spot(j, id, z) {
            found.add(self.v[j].z, zq, d, self.half_bead, id);
        }
    }

    /// The spot of chord `id` under point j, its height and distance across, when it is one:
    /// the foot of the perpendicular on or near the chord, within `radius` across
    /// ([`foot_under`]), at a height within `z` (low, high), and not on the bead just laid
    /// ([`on_bead_just_laid`]).
    #[inline]
    fn spot(&self, j: usize, id: usize, z: [f64; 2]) -> Option<(f64, f64)> {
        let p = self.v[j];
        let ChordFoot { f, d, z: zq } = foot_under(
            self.v,
            self.chords,
            id,
            p.truncate(),
            self.radius,
            self.half_bead,
        )?;
        let (ia, ib) = self.chords[id];
        let cum = self.cum;
        let along = cum[j] - (cum[ia] + f * (cum[ib] - cum[ia]));
        if on_bead_just_laid(along, d, p.z - zq, self.gap, self.stepped_up) {
            return None;
        }
        (zq <= z[1] && zq >= z[0]).then_some((zq, d))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::design::Printer;
    use proptest::prelude::*;

    /// The first layer ends at the first point a tolerance above the lowest before it: a flat
    /// ring at 0.5 mm, then a rise. A path that only comes down never rises above what it
    /// laid before, nor does one that rises less than the tolerance.
    #[test]
    fn nothing_lies_under_the_points_before_the_first_a_tolerance_up() {
        let at = |zs: &[f64]| -> Vec<DVec3> {
            zs.iter()
                .enumerate()
                .map(|(i, &z)| DVec3::new(i as f64, 0.0, z))
                .collect()
        };
        let tol = 0.1;
        assert_eq!(
            nothing_under_until(&at(&[0.5, 0.5, 0.55, 0.59, 0.61, 0.5]), tol),
            4
        );
        assert_eq!(nothing_under_until(&at(&[2.0, 1.95, 1.9, 1.8]), tol), 4);
        assert_eq!(nothing_under_until(&at(&[2.0, 1.8, 1.85, 1.91]), tol), 3);
        assert_eq!(nothing_under_until(&at(&[0.5, 0.58, 0.52]), tol), 3);
        assert_eq!(nothing_under_until(&[], tol), 0);
    }

    /// A spiral wall whose radius follows `r(z)` with a wobble: leans from vertical to past the
    /// limit, steps between revolutions, a few points off the wall.
    fn wobbly_spiral(flare: f64, wobble: f64, lobes: f64, jitter: &[f64]) -> Vec<DVec3> {
        wall(flare, wobble, lobes, jitter, 40, false)
    }

    /// Rings stacked 0.8 mm apart, each at one height (a vertical step between them), the
    /// first on the bed: a wall whose every point rests on the ring below, leaning as the
    /// spiral's does.
    fn stacked_rings(flare: f64, wobble: f64, lobes: f64, jitter: &[f64]) -> Vec<DVec3> {
        wall(flare, wobble, lobes, jitter, 30, true)
    }

    /// `revolutions` of a wall 0.8 mm a revolution, as a helix or as `stacked` rings.
    fn wall(
        flare: f64,
        wobble: f64,
        lobes: f64,
        jitter: &[f64],
        revolutions: usize,
        stacked: bool,
    ) -> Vec<DVec3> {
        let (per_rev, h) = (180, 0.8);
        (0..per_rev * revolutions)
            .map(|i| {
                let t = i as f64 / per_rev as f64;
                let a = t * std::f64::consts::TAU;
                let z = 0.5 + h * if stacked { t.floor() } else { t };
                let r = 40.0
                    + flare * z * z / 30.0
                    + wobble * (lobes * a + 0.3 * z).sin()
                    + jitter[i % jitter.len()];
                DVec3::new(150.0 + r * a.cos(), 150.0 + r * a.sin(), z)
            })
            .collect()
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(12))]
        /// The near box is a shortcut, not an approximation: the same report as the whole box,
        /// on walls that lean from 0° to well past 45°.
        #[test]
        fn near_box_reports_what_the_whole_box_reports(
            flare in 0.0f64..4.0,
            wobble in 0.0f64..3.0,
            lobes in 1.0f64..9.0,
            jitter in proptest::collection::vec(-0.6f64..0.6, 1..7),
        ) {
            let v = wobbly_spiral(flare, wobble, lobes, &jitter);
            let lines: Vec<usize> = (0..v.len()).collect();
            let limits = Limits::from(&Printer::default());
            let (mut near, mut whole) = (CheckReport::default(), CheckReport::default());
            measure_layers_in(&v, &lines, &limits, &mut near, Search::NearFirst, false, None);
            measure_layers_in(&v, &lines, &limits, &mut whole, Search::WholeBox, false, None);
            prop_assert_eq!(&near, &whole);
        }
    }

    /// Three points in a line but the middle, 3 µm off it (more than the chords' tolerance):
    /// each point starts a chord and ends one. In a line, the first point's chord takes in the
    /// next, which still starts one of its own, and the last's backward chord reaches the first;
    /// a chord stops once it is twice the reach long.
    #[test]
    fn chords_beside_start_and_end_at_every_point() {
        let v = [
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.003, 0.0),
            DVec3::new(2.0, 0.0, 0.0),
        ];
        assert_eq!(chords_of(&v), vec![(0, 1), (1, 2)]);
        assert_eq!(chords_beside(&v, 1.5), vec![(0, 1), (1, 2)]);
        let line: Vec<DVec3> = (0..5).map(|i| DVec3::new(i as f64, 0.0, 0.0)).collect();
        assert_eq!(chords_of(&line), vec![(0, 4)]);
        assert_eq!(
            chords_beside(&line, 1.5),
            vec![(0, 1), (0, 2), (0, 3), (1, 4), (2, 4), (3, 4)]
        );
    }

    /// A flat spiral base from the centre out, then a wall that climbs, steps back down to
    /// print a second, lower ring inside the first (z falls along the path), and climbs again:
    /// chords that come back over earlier ones at every height order.
    /// Spots as near in XY at different heights (a ring laid again over the same points, a
    /// layer lower than the ring beside it: found by the proptest below): the grid meets the
    /// chords column by column, the tree box by box, and every search takes the higher.
    #[test]
    fn spots_equally_near_are_taken_alike_by_every_search() {
        let limits = Limits::from(&Printer::default());
        let v = base_and_rings(
            1.8457174072058156,
            1.7088817164686907,
            &[-0.0389837374335059, -0.3909880239543382],
        );
        let lines: Vec<usize> = (0..v.len()).collect();
        let report = |search| {
            let mut report = CheckReport::default();
            measure_layers_in(&v, &lines, &limits, &mut report, search, false, None);
            report
        };
        let every = report(Search::EveryChord);
        assert!(!every.ok(), "the path breaks limits: {every}");
        for search in [Search::NearFirst, Search::WholeBox, Search::Tree] {
            assert_eq!(report(search), every, "{search:?}");
        }
    }

    fn base_and_rings(turns: f64, drop: f64, jitter: &[f64]) -> Vec<DVec3> {
        let mut v = Vec::new();
        let per_turn = 90.0;
        for i in 0..(turns * per_turn) as usize {
            let t = i as f64 / per_turn;
            let (r, a) = (1.0 + 3.0 * t, t * std::f64::consts::TAU);
            v.push(DVec3::new(100.0 + r * a.cos(), 100.0 + r * a.sin(), 0.5));
        }
        let r0 = 1.0 + 3.0 * turns;
        for (ring, (r, z0)) in [(r0, 0.5), (r0 - 4.0, 0.5 + drop), (r0 + 1.0, 3.0)]
            .into_iter()
            .enumerate()
        {
            for i in 0..(6.0 * per_turn) as usize {
                let t = i as f64 / per_turn;
                let a = t * std::f64::consts::TAU + ring as f64;
                let r = r + jitter[i % jitter.len()];
                v.push(DVec3::new(
                    100.0 + r * a.cos(),
                    100.0 + r * a.sin(),
                    z0 + 0.5 * t,
                ));
            }
        }
        v
    }

    prop_compose! {
        /// A leaning wobbly spiral, stacked rings leaning alike, and a spiral base with rings
        /// that come back lower down.
        fn paths()(
            flare in 0.0f64..4.0,
            wobble in 0.0f64..3.0,
            lobes in 1.0f64..9.0,
            turns in 1.0f64..8.0,
            drop in -0.5f64..2.0,
            jitter in proptest::collection::vec(-0.6f64..0.6, 1..7),
        ) -> [Vec<DVec3>; 3] {
            [
                wobbly_spiral(flare, wobble, lobes, &jitter),
                stacked_rings(flare, wobble, lobes, &jitter),
                base_and_rings(turns, drop, &jitter),
            ]
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(8))]
        /// The grid, its columns' runs, the chord tree's boxes and the single-precision
        /// prefilters only skip chords the exact test would reject: the report is the one of a
        /// search of every earlier chord, on leaning walls and on paths that come back over
        /// themselves at lower heights.
        #[test]
        fn the_grid_search_is_the_search_of_every_chord(paths in paths()) {
            let limits = Limits::from(&Printer::default());
            let [spiral, rings, base] = &paths;
            for v in [&spiral[..180 * 12], &rings[..180 * 12], &base[..]] {
                let lines: Vec<usize> = (0..v.len()).collect();
                let (mut grid, mut every) = (CheckReport::default(), CheckReport::default());
                let mut tree = CheckReport::default();
                measure_layers_in(v, &lines, &limits, &mut grid, Search::NearFirst, false, None);
                measure_layers_in(v, &lines, &limits, &mut every, Search::EveryChord, false, None);
                measure_layers_in(v, &lines, &limits, &mut tree, Search::Tree, false, None);
                prop_assert_eq!(&grid, &every);
                prop_assert_eq!(&tree, &every);
            }
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(16))]
        /// Shown by witnesses only where the full measurement finds no layer broken, with the
        /// same holder clearance; and shown on walls within the limits (not a shortcut that
        /// never fires): walls from upright to past 45°, paths that come back over themselves.
        #[test]
        fn the_layers_are_shown_to_hold_only_where_measuring_finds_them_holding(paths in paths()) {
            let limits = Limits::from(&Printer::default());
            for v in &paths {
                let lines: Vec<usize> = (0..v.len()).collect();
                let (mut full, mut quick) = (CheckReport::default(), CheckReport::default());
                measure_layers_in(v, &lines, &limits, &mut full, Search::NearFirst, false, None);
                let measured = clearance_in_halves(v, &lines, &limits, v.len() / 2);
                let shown = layers_hold(v, &lines, &limits, &mut quick, measured);
                let broken = full.violations.iter().any(|x| x.what != COLLISION);
                prop_assert!(!(shown && broken), "shown, but {}", full);
                if shown {
                    prop_assert_eq!(&quick.violations, &full.violations);
                    prop_assert_eq!(&quick.events, &full.events);
                    prop_assert_eq!(quick.max_rise_above_tip, full.max_rise_above_tip);
                } else {
                    prop_assert_eq!(&quick, &full);
                }
            }
        }
    }

    /// The clearance of `v` measured in two runs split at `at`, joined (see
    /// [`ClearanceRun::then`]).
    fn clearance_in_halves(
        v: &[DVec3],
        lines: &[usize],
        limits: &Limits,
        at: usize,
    ) -> Option<ClearanceRun> {
        let run = |range: std::ops::Range<usize>| {
            let mut run = ClearanceRun::new(limits);
            range.for_each(|j| run.add(v[j].z, lines[j]));
            run
        };
        run(0..at).then(run(at..v.len()))
    }

    proptest! {
        /// Two runs of a path joined are the clearance measured in one pass, wherever the path
        /// is split, or none where they cannot tell: heights that rise and fall by up to twice
        /// the nozzle's length (collisions in either run, and across the split).
        #[test]
        fn two_runs_of_clearance_join_into_the_whole(
            z in proptest::collection::vec(0.0..60.0f64, 0..40),
            split in 0.0..1.0f64,
        ) {
            let limits = Limits::from(&Printer::default());
            let v: Vec<DVec3> = z.iter().map(|&z| DVec3::new(0.0, 0.0, z)).collect();
            let lines: Vec<usize> = (0..v.len()).map(|j| 10 + j).collect();
            let at = (split * v.len() as f64) as usize;
            let mut whole = ClearanceRun::new(&limits);
            v.iter().zip(&lines).for_each(|(p, &line)| whole.add(p.z, line));
            match clearance_in_halves(&v, &lines, &limits, at) {
                Some(joined) => prop_assert_eq!(joined, whole),
                None => {
                    // Only where a point after the split lies more than the nozzle below one
                    // before it.
                    let highest = z[..at].iter().copied().fold(f64::NEG_INFINITY, f64::max);
                    prop_assert!(z[at..].iter().any(|&z| highest - z > limits.nozzle_length));
                }
            }
        }
    }

    /// The search's runs cover the path's points in order, each once, the last ones shorter.
    #[test]
    fn search_runs_cover_the_points_in_order() {
        for n in [0, 1, 100, SEARCH_RUN, 2 * SEARCH_RUN + 1, 220_012] {
            let runs = search_runs(n);
            let all: Vec<usize> = runs.iter().cloned().flatten().collect();
            assert_eq!(all, (0..n).collect::<Vec<_>>(), "{n}");
            assert!(runs.iter().all(|r| !r.is_empty() && r.len() <= SEARCH_RUN));
            if n > 3 * SEARCH_RUN {
                assert!(runs.last().unwrap().len() <= SEARCH_RUN / 8);
            }
        }
    }

    #[test]
    fn floor_without_the_library() {
        for q in [
            0.0,
            -0.0,
            0.5,
            -0.5,
            1.0,
            -1.0,
            2.999,
            -2.999,
            1e9,
            -1e9,
            3e9,
            -3e9,
            -2147483648.5,
            2147483647.5,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
            1e-300,
            -1e-300,
        ] {
            assert_eq!(floor_i32(q), q.floor() as i32, "{q}");
        }
    }

    /// Cones of stacked rings leaning a steady angle: within the limit they are shown to hold;
    /// past it (up to the steepest a spot within half a bead can witness, 62° at 0.8 mm
    /// layers and a 3 mm bead) they are not, and the full measurement finds the overhang.
    /// Flat rings of 5 mm beads 2.5 mm apart, each 2.45 mm further out (leaning 44.4°), each
    /// run the other way round from the one below and joined to it by one step up and out, as
    /// a big bead's base flares under a 45° wall: each ring rests on the one below all round.
    /// The first points after each step used to find the ring just left to be "the bead just
    /// laid" (a few bead widths back along an almost straight path) and so nothing, or only the
    /// ring two down, under them: a layer too thick, or leaning 71°.
    #[test]
    fn a_ring_stepped_up_a_layer_rests_on_the_ring_it_left() {
        let printer = Printer {
            line_width: 5.0,
            layer_height: 2.5,
            min_layer_height: 1.25,
            max_layer_height: 2.5,
            ..Printer::default()
        };
        let limits = Limits::from(&printer);
        let per_ring = 400;
        let mut v = Vec::new();
        for k in 0..5 {
            let (z, r) = (2.5 * (k + 1) as f64, 40.0 + 2.45 * k as f64);
            let sign = if k % 2 == 0 { 1.0 } else { -1.0 };
            for i in 0..=per_ring {
                let a = sign * i as f64 / per_ring as f64 * std::f64::consts::TAU;
                v.push(DVec3::new(100.0 + r * a.cos(), 100.0 + r * a.sin(), z));
            }
        }
        let lines: Vec<usize> = (0..v.len()).collect();
        let mut report = CheckReport::default();
        measure_layers(&v, &lines, &limits, &mut report);
        assert!(report.ok(), "{report}");
        assert!(
            (report.max_layer_height - 2.5).abs() < 1e-6 && report.max_overhang_deg < 45.0,
            "{report}"
        );
    }

    /// A helix of 0.5 mm layers on a flat first revolution, with a bump: a few points of one
    /// revolution raised up to 0.4 mm (0.9 mm over the layer below: not too thick), so that the
    /// revolution above rests as little as 0.1 mm over them (thinner than the printer's
    /// 0.25 mm). Each point over the bump has a witness (the bump under it, not too thick);
    /// only the search of its thin-layer band finds the bump, also where a run of points is
    /// searched at once and the bump lies under a few of them, at either end of the run.
    #[test]
    fn a_bump_under_a_run_of_points_is_a_layer_too_thin() {
        let limits = Limits::from(&Printer::default());
        let per_rev = 720;
        // Up and down over a quarter of it each (no chord steeper than 45°: each point rests
        // on one).
        let ramp = |i: usize, bump: &std::ops::Range<usize>| {
            let inside = (i as f64 - bump.start as f64).min(bump.end as f64 - 1.0 - i as f64);
            (inside / (bump.len() / 4).max(2) as f64).clamp(0.0, 1.0)
        };
        let helix = |bump: std::ops::Range<usize>| -> Vec<DVec3> {
            (0..per_rev * 14)
                .map(|i| {
                    let t = i as f64 / per_rev as f64;
                    let a = t * std::f64::consts::TAU;
                    let z = match t {
                        t if t < 1.0 => 0.5,
                        t if t < 2.0 => 0.75 + 0.25 * (t - 1.0),
                        t => 0.5 + 0.5 * (t - 1.0),
                    } + 0.4 * ramp(i, &bump);
                    DVec3::new(100.0 + 40.0 * a.cos(), 100.0 + 40.0 * a.sin(), z)
                })
                .collect()
        };
        let lines: Vec<usize> = (0..per_rev * 14).collect();
        let mut plain = CheckReport::default();
        assert!(
            layers_hold(&helix(0..0), &lines, &limits, &mut plain, None),
            "{plain}"
        );
        // Long bumps, and bumps thin under one point only (wherever a run of points starts).
        let short = (300..300 + BAND_RUN).map(|start| (start, 5));
        for (start, len) in [(300, 10), (301, 13), (307, 16), (310, 24)]
            .into_iter()
            .chain(short)
        {
            let v = helix(10 * per_rev + start..10 * per_rev + start + len);
            let (mut quick, mut full) = (CheckReport::default(), CheckReport::default());
            measure_layers(&v, &lines, &limits, &mut full);
            let thin = full.violations.iter().find(|x| x.what == "layer too thin");
            assert!(thin.is_some_and(|x| x.count <= 2 * len), "{start}: {full}");
            assert!(
                !layers_hold(&v, &lines, &limits, &mut quick, None),
                "{start}"
            );
            assert_eq!(quick, full);
        }
    }

    /// A spiral of rhombi rising 0.5 mm a revolution (on a flat first one) and, from the third
    /// on, moving out 0.15 mm a revolution (17°), with corners of 60° at their ends: each
    /// corner's tip lies 0.3 mm past the one below, past the end of both 0.35 mm segments that meet there, which so have no
    /// point beside it. The tip
    /// below is what it rests on: the layers hold, leaning no more than the tips do (31°).
    #[test]
    fn a_sharp_corner_rests_on_the_corner_below() {
        let limits = Limits::from(&Printer::default());
        let (along, across) = (30.0, 30.0 * 30f64.to_radians().tan());
        let corners = [
            (along, 0.0),
            (0.0, across),
            (-along, 0.0),
            (0.0, -across),
            (along, 0.0),
        ]
        .map(|(x, y)| DVec2::new(x, y));
        // One revolution: the rhombus's outline in steps of at most 0.35 mm, each point but the
        // corners 10 µm to one side or the other (so that no chord stands for more than one
        // segment, as on a curved wall).
        let outline: Vec<DVec2> = corners
            .windows(2)
            .flat_map(|w| {
                let steps = (w[0].distance(w[1]) / 0.35).ceil() as usize;
                let side = (w[1] - w[0]).normalize().perp() * 0.01;
                (0..steps).map(move |i| {
                    let wobble = if i == 0 {
                        0.0
                    } else if i % 2 == 0 {
                        1.0
                    } else {
                        -1.0
                    };
                    w[0].lerp(w[1], i as f64 / steps as f64) + side * wobble
                })
            })
            .collect();
        // The edges move out 0.15 mm a revolution: the rhombus scales about its inradius.
        let inradius = along * across / (along * along + across * across).sqrt();
        let per_rev = outline.len();
        let v: Vec<DVec3> = (0..per_rev * 12)
            .map(|i| {
                let t = i as f64 / per_rev as f64;
                let q = outline[i % per_rev] * (1.0 + 0.15 * (t - 2.0).max(0.0) / inradius);
                // A flat first revolution, then the helix (leaving it by the thinnest layer).
                let z = match t {
                    t if t < 1.0 => 0.5,
                    t if t < 2.0 => 0.75 + 0.25 * (t - 1.0),
                    t => 0.5 + 0.5 * (t - 1.0),
                };
                DVec3::new(100.0 + q.x, 100.0 + q.y, z)
            })
            .collect();
        let lines: Vec<usize> = (0..v.len()).collect();
        let mut report = CheckReport::default();
        measure_layers(&v, &lines, &limits, &mut report);
        assert!(report.ok(), "{report}");
        assert!(report.max_overhang_deg < 32.0, "{report}");
        let mut quick = CheckReport::default();
        assert!(layers_hold(&v, &lines, &limits, &mut quick, None));
    }

    #[test]
    fn witnesses_do_not_show_a_lean_past_the_limit() {
        let limits = Limits::from(&Printer::default());
        for lean_deg in [0.0, 30.0, 44.0, 48.0, 52.0, 56.0, 60.0] {
            let (per_rev, h) = (180, 0.8);
            let v: Vec<DVec3> = (0..per_rev * 20)
                .map(|i| {
                    let z = 0.5 + h * (i / per_rev) as f64;
                    let a = (i % per_rev) as f64 / per_rev as f64 * std::f64::consts::TAU;
                    let r = 40.0 + (z - 0.5) * f64::to_radians(lean_deg).tan();
                    DVec3::new(150.0 + r * a.cos(), 150.0 + r * a.sin(), z)
                })
                .collect();
            let lines: Vec<usize> = (0..v.len()).collect();
            let (mut quick, mut full) = (CheckReport::default(), CheckReport::default());
            measure_layers(&v, &lines, &limits, &mut full);
            let within = lean_deg < limits.max_overhang_deg;
            assert_eq!(full.ok(), within, "{lean_deg}°: {full}");
            assert_eq!(
                layers_hold(&v, &lines, &limits, &mut quick, None),
                within,
                "{lean_deg}°"
            );
        }
    }

    /// A helix standing on a flat first revolution (leaving it by the thinnest layer), with a
    /// bulge in one sector between 6 and 11 mm up leaning out and back at `lean_deg`, and the
    /// path raised by `step` mm over a few points halfway up (the layer above it that much
    /// thicker): the points that break a limit are all met by the witness walk.
    fn standing_helix(lean_deg: f64, step: f64) -> Vec<DVec3> {
        let (per_rev, h) = (180, 0.8);
        let k = lean_deg.to_radians().tan();
        (0..per_rev * 25)
            .map(|i| {
                let t = i as f64 / per_rev as f64;
                let a = t * std::f64::consts::TAU;
                let mut z = match t {
                    t if t < 1.0 => 0.5,
                    t if t < 2.0 => 0.75 + (h - 0.25) * (t - 1.0),
                    t => 0.5 + h * (t - 1.0),
                };
                z += step * ((t - 12.0) * 180.0 / 5.0).clamp(0.0, 1.0);
                // Out at k mm per mm from 6 to 8.5 mm, back in to 11 mm; a smooth sector.
                let rise = (z - 6.0).clamp(0.0, 2.5) - (z - 8.5).clamp(0.0, 2.5);
                let sector = (a.sin().max(0.0)).powi(4);
                let r = 30.0 + k * rise * sector;
                DVec3::new(100.0 + r * a.cos(), 100.0 + r * a.sin(), z)
            })
            .collect()
    }

    /// The witness's own tests decide: a lean past the limit or a layer too thick met only
    /// by the witness walk (no point measured in full to catch it) is not shown to hold.
    #[test]
    fn witnesses_alone_do_not_pass_a_lean_or_a_thick_layer() {
        let limits = Limits::from(&Printer::default());
        for (lean_deg, step, within) in [
            (0.0, 0.0, true),
            (40.0, 0.0, true),
            (55.0, 0.0, false),
            (0.0, 0.4, false),
        ] {
            let v = standing_helix(lean_deg, step);
            let lines: Vec<usize> = (0..v.len()).collect();
            let (mut quick, mut full) = (CheckReport::default(), CheckReport::default());
            measure_layers(&v, &lines, &limits, &mut full);
            assert_eq!(full.ok(), within, "{lean_deg}° {step} mm: {full}");
            assert_eq!(
                layers_hold(&v, &lines, &limits, &mut quick, None),
                within,
                "{lean_deg}° {step} mm"
            );
        }
    }

    /// An upright and a gently leaning textured wall are shown to hold (the witnesses carry the
    /// whole wall), and one past the limit is not.
    #[test]
    fn witnesses_show_walls_within_the_limits() {
        let limits = Limits::from(&Printer::default());
        for (flare, wobble, holds) in [(0.0, 0.0, true), (0.5, 1.0, true), (4.0, 3.0, false)] {
            let v = stacked_rings(flare, wobble, 7.0, &[0.0, 0.2]);
            let lines: Vec<usize> = (0..v.len()).collect();
            let mut report = CheckReport::default();
            let mut full = CheckReport::default();
            measure_layers(&v, &lines, &limits, &mut full);
            assert_eq!(
                layers_hold(&v, &lines, &limits, &mut report, None),
                holds,
                "{flare} {wobble} {full}"
            );
        }
    }

    proptest! {
        /// The single-precision prefilter never rejects a chord the exact test keeps: chords
        /// 0.01 … 20 mm long anywhere on a 2 m machine, points up to `radius` across with the
        /// foot of the perpendicular anywhere in −0.5 … 1.5 along it.
        #[test]
        fn prefilter_keeps_every_chord_the_exact_test_keeps(
            ax in 0.0f64..2000.0, ay in 0.0f64..2000.0, az in 0.0f64..2000.0,
            log_len in -2.0f64..1.3, angle in 0.0f64..std::f64::consts::TAU,
            f in prop_oneof![Just(-0.5), Just(1.5), -0.5f64..=1.5],
            across in -1.0f64..=1.0, radius in 1.0f64..60.0,
        ) {
            let len = 10f64.powf(log_len);
            let dir = DVec2::from_angle(angle);
            let a = DVec3::new(ax, ay, az);
            let b = a + (dir * len).extend(0.3);
            let p = a.truncate() + dir * (f * len) + dir.perp() * (across * radius);
            let exact = (p - a.truncate()).dot(b.truncate() - a.truncate()) / (len * len);
            // At the ends of the range the exact fraction may round just outside it: skipped.
            prop_assume!((-0.5..=1.5).contains(&exact));
            let c = ColumnChord::new(0, 1, a, b);
            let z = [(az - 1.0) as f32, (az + 1.0) as f32];
            let extent = 2000.0 + 2.0 * radius + 10.0;
            let prefilter = [short_chord2(extent, radius), end_reach2(extent, 0.5 * radius)];
            prop_assert!(c.may_be_under([p.x as f32, p.y as f32], z, prefilter));
        }

        /// Nor a chord with an end within half a bead of the point (up to the exact test's
        /// last bit), wherever the point lies along it.
        #[test]
        fn prefilter_keeps_every_chord_with_an_end_within_half_a_bead(
            ax in 0.0f64..2000.0, ay in 0.0f64..2000.0, az in 0.0f64..2000.0,
            log_len in -2.0f64..1.3, angle in 0.0f64..std::f64::consts::TAU,
            at_b in proptest::bool::ANY, away in 0.0f64..std::f64::consts::TAU,
            reach in prop_oneof![Just(1.0), 0.0f64..=1.0], half_bead in 0.2f64..30.0,
        ) {
            let len = 10f64.powf(log_len);
            let a = DVec3::new(ax, ay, az);
            let b = a + (DVec2::from_angle(angle) * len).extend(0.3);
            let end = if at_b { b } else { a }.truncate();
            let p = end + DVec2::from_angle(away) * (reach * half_bead);
            prop_assume!(p.distance(end) <= half_bead);
            let c = ColumnChord::new(0, 1, a, b);
            let z = [(az - 1.0) as f32, (az + 1.0) as f32];
            let extent = 2000.0 + 4.0 * half_bead + 10.0;
            let prefilter = [short_chord2(extent, 2.0 * half_bead), end_reach2(extent, half_bead)];
            prop_assert!(c.may_be_under([p.x as f32, p.y as f32], z, prefilter));
        }
    }

    /// The grid built in parts on both cores is the grid built on one: the same columns, each
    /// with the same chords in path order and the same height bounds; and past its budget
    /// (counted over all parts) it gives up alike.
    #[test]
    fn the_grid_in_parts_is_the_grid_in_one() {
        let v = wobbly_spiral(2.0, 1.5, 5.0, &[0.0, 0.3, -0.2]);
        let chords = chords(&v);
        let inside = |p: DVec3| p.x > 120.0; // some chords outside the machine
        let columns = |g: &ChordGrid| {
            let mut c: Vec<_> = g
                .index
                .iter()
                .map(|(k, &at)| {
                    let col = &g.columns[at as usize];
                    let ids: Vec<u32> = col.chords.iter().map(|c| c.id).collect();
                    (*k, ids, col.top.clone(), col.bottom.clone())
                })
                .collect();
            c.sort_by_key(|x| x.0);
            c
        };
        let one = ChordGrid::build(&v, &chords, 2.5, &inside, usize::MAX, usize::MAX).unwrap();
        let parts = ChordGrid::build(&v, &chords, 2.5, &inside, usize::MAX, 100).unwrap();
        assert!(one.columns.len() > 20);
        assert_eq!(columns(&one), columns(&parts));
        // The least budget that one part needs is the least that two need.
        let build = |budget, serial_below| {
            ChordGrid::build(&v, &chords, 2.5, &inside, budget, serial_below).is_some()
        };
        let (mut lo, mut hi) = (0, 64 * chords.len());
        while lo + 1 < hi {
            let mid = (lo + hi) / 2;
            if build(mid, usize::MAX) {
                hi = mid
            } else {
                lo = mid
            }
        }
        assert!(hi > one.columns.iter().map(|c| c.chords.len()).sum::<usize>() / 2);
        assert!(build(hi, 100) && !build(hi - 1, 100));
    }

    #[test]
    fn the_wobbly_spiral_leans_past_the_limit() {
        let v = wobbly_spiral(4.0, 3.0, 7.0, &[0.0, 0.5]);
        let lines: Vec<usize> = (0..v.len()).collect();
        let mut report = CheckReport::default();
        measure_layers_in(
            &v,
            &lines,
            &Limits::from(&Printer::default()),
            &mut report,
            Search::NearFirst,
            false,
            None,
        );
        assert!(
            report.max_overhang_deg > 50.0,
            "{}",
            report.max_overhang_deg
        );
        assert!(report.violations.iter().any(|x| x.what == OVERHANG));
    }
}
