//! The path crossing itself within its layer: two stretches of the extruding path at the same
//! height whose XY segments cross. The nozzle drives through the bead it has just laid and
//! leaves a knot of clay where the wall should run once (a texture or a control line folding a
//! sharp turn of the wall back on itself). A loop that reaches no farther than half a bead from
//! its crossing stays within the bead and is let be.
//!
//! "The same height" is within a quarter of the minimum layer height (what the layer search
//! does not take as a layer below), and "its layer" is the stretch of path since it was last
//! that much lower, at most [`LOOP_REACH_BEADS`] bead widths long: on a spiral, a part of one
//! revolution.
//!
//! **The search.** A chord's window is the stretch of earlier chords it may cross. Testing
//! every pair would cost the window's length per chord; two facts of plane curves leave most
//! chords untested, and most of the rest tested against a few:
//!
//! * the innermost loop of a crossing is a simple closed polygon: its turns add up to a whole
//!   turn, of which the turn at the crossing is less than a half-turn, so **the chords from
//!   one crossing chord to the other turn through more than a half-turn** (the range of their
//!   unwrapped direction, in [`pseudo_angle`]'s units);
//! * **a stretch that goes on round a point, less than once round, cannot cross itself**: its
//!   chords lie in sectors round the point that do not overlap. Round the middle of the path
//!   (a vessel's axis, roughly) a wall goes on round except where its texture or its outline
//!   turns back.
//!
//! So chord c is tested only where its window turns through more than a half-turn, and then
//! only against the earlier chords i such that the chords i ..= c go both ways round (or all
//! the way round); a group of 16 chords' box is tested before theirs. On the benchmark vase a
//! quarter of the windows pass the first test (its textured belly, its base's rings), and
//! about one pair in a chord is tested.
//!
//! A block whose wall goes on round but steps back here and there (a texture on a petalled
//! wall: the benchmark vase's belly) is settled by the chords' angles round its middle instead
//! ([`Work::judge_by_angles`]): two chords of a window that goes round less than once cross
//! only where the angles they sweep overlap, which near a step back alone they do.
//!
//! The chords are judged in blocks on every core; each block reads the path back as far as its
//! first chord's window reaches, so the loops found do not depend on the number of cores.

use glam::{DVec2, DVec3};

use super::report::{CROSSING, PathEvent, Tally};

/// Path, in bead widths, within which a crossing is searched for behind each chord: the
/// layer's stretch on a spiral is mostly shorter (a loop longer than it rises a quarter
/// layer, and its crossing is a layer too thin, the layer search's); on a file of flat layers
/// it bounds the search.
pub(super) const LOOP_REACH_BEADS: f64 = 50.0;

/// Exact pair tests allowed (with the chords read again before each block): a fixed allowance
/// shared by the blocks plus this many per chord. A clay spiral tests a few per chord; a file
/// that piles its path up in one spot runs out, and says so rather than testing for minutes.
const TESTS_PER_CHORD: usize = 1024;
const TESTS_BASE: usize = 1 << 22;

/// Chords judged in a block (see the module's documentation).
const BLOCK: usize = 8192;

/// Chords whose boxes are joined, a pair's very first test.
const GROUP: usize = 16;

/// The loops found: their tally (for each move that closes one or more, the widest one's reach
/// from its crossing, mm, at that move's G-code line), one event per such move in path order,
/// whether the search ran to the end, and how many pairs of chords it tested.
pub(super) struct Crossings {
    pub(super) tally: Tally,
    pub(super) events: Vec<PathEvent>,
    pub(super) complete: bool,
    pub(super) tested: usize,
}

/// What [`find_crossings`] measures against.
#[derive(Clone, Copy)]
pub(super) struct CrossingLimits {
    /// Heights closer than this are the same layer, mm.
    pub(super) same_layer: f64,
    /// Loops reaching farther than this from their crossing count, mm.
    pub(super) half_bead: f64,
    /// How far back along the path a crossing is searched for, mm.
    pub(super) reach: f64,
}

/// The loops of path `v`, given as chords (`chords[c]` = points `i ..= k`, nearly straight;
/// `usable(c)`: the chord is measured, inside the machine and not steep) with each point's
/// G-code line in `lines` and the path's length up to each point in `cum`; and `beside()`, work
/// that needs the cores while the blocks are judged (the layer search's index), run as one more
/// task among the blocks: the core that takes it goes on with the blocks once it is done.
pub(super) fn find_crossings<T: Send>(
    v: &[DVec3],
    chords: &[(usize, usize)],
    lines: &[usize],
    cum: &[f64],
    limits: CrossingLimits,
    usable: &(impl Fn(usize) -> bool + Sync),
    beside: impl FnOnce() -> T + Send,
) -> (Crossings, T) {
    let n = chords.len();
    let blocks = n.div_ceil(BLOCK);
    let path = Path {
        v,
        chords,
        cum,
        limits,
        usable,
    };
    let beside = std::sync::Mutex::new(Some(beside));
    let beside_done = std::sync::Mutex::new(None);
    // Task 0 is `beside`, first so that it starts at once; task b + 1 judges block b. A block's
    // cost varies tenfold (the belly's turns back), so the blocks are shared out as they go.
    let judged = crate::parallel::map_shared(blocks + 1, Work::default, |work, task| {
        let Some(b) = task.checked_sub(1) else {
            let f = beside.lock().unwrap_or_else(|e| e.into_inner()).take();
            let out = f.map(|f| f());
            *beside_done.lock().unwrap_or_else(|e| e.into_inner()) = out;
            return None;
        };
        let budget =
            TESTS_BASE.div_ceil(blocks.max(1)) + TESTS_PER_CHORD * (BLOCK.min(n - b * BLOCK));
        Some(work.judge(&path, b * BLOCK..((b + 1) * BLOCK).min(n), budget))
    });
    let beside = beside_done
        .into_inner()
        .unwrap_or_else(|e| e.into_inner())
        .expect("the task beside the blocks ran");
    let mut found = Crossings {
        tally: Tally::default(),
        events: Vec::new(),
        complete: true,
        tested: 0,
    };
    for block in judged.into_iter().flatten() {
        found.tested += block.tested;
        found.complete &= block.complete;
        for (value, c) in block.loops {
            let line = lines[chords[c].1];
            found.tally.add(value, line);
            found.events.push(PathEvent {
                line,
                what: CROSSING,
                value,
            });
        }
    }
    (found, beside)
}

/// What the blocks read.
struct Path<'a, U> {
    v: &'a [DVec3],
    chords: &'a [(usize, usize)],
    cum: &'a [f64],
    limits: CrossingLimits,
    usable: &'a U,
}

impl<U> Path<'_, U> {
    /// The first of a block's chords (counted from chord `first`) that ends within
    /// `limits.reach` of path before chord `c` starts, stepping on from `from` (the answer for
    /// an earlier chord; the chords' ends only move on).
    fn length_start(&self, first: usize, c: usize, from: &mut usize) -> usize {
        let reach = self.cum[self.chords[first + c].0] - self.limits.reach;
        while *from < c && self.cum[self.chords[first + *from].1] < reach {
            *from += 1;
        }
        *from
    }

    /// Chord `c`'s window where the heights rise along the block (chords counted from chord
    /// `first`, `boxes` theirs so far): from the chord after the last one lying wholly a
    /// layer's tolerance below it, and no farther back than `limits.reach` of path. `from`
    /// holds the two answers for an earlier chord (both only move on).
    fn rising_start(
        &self,
        first: usize,
        c: usize,
        boxes: &[ChordBox],
        (height_from, length_from): &mut (usize, usize),
    ) -> usize {
        let below = boxes[c].lo.z - self.limits.same_layer;
        while *height_from < c && boxes[*height_from].hi.z < below {
            *height_from += 1;
        }
        (*height_from).max(self.length_start(first, c, length_from))
    }
}

/// One block's loops (for each chord that closes one or more, the widest one's reach, mm),
/// its tests, and whether it was judged within its budget.
struct Judged {
    loops: Vec<(f64, usize)>,
    tested: usize,
    complete: bool,
}

/// A thread's buffers for its blocks, kept from one to the next: each block's chords from the
/// first its windows reach, indexed from there.
#[derive(Default)]
struct Work {
    boxes: Vec<ChordBox>,
    /// The boxes of the chords `GROUP` by `GROUP` (the last group's so far).
    groups: Vec<ChordBox>,
    /// Unwrapped direction.
    turn: Vec<f64>,
    /// The least and greatest unwrapped angle round the block's middle of each chord's points
    /// ([`Work::judge_by_angles`]).
    sweeps: Vec<(f64, f64)>,
    /// Times the path has crossed the ray from the block's middle towards +x, anticlockwise
    /// less clockwise, by each chord's end: with the angle there, the unwrapped angle round
    /// the middle.
    winding: Vec<i32>,
    /// The first chord of each one's window, and the least start from each chord on, where
    /// the heights do not rise along the block (else found as the chords are read).
    starts: Vec<usize>,
    flag_starts: Vec<usize>,
    minima: Vec<u32>,
    highs: MonotoneQueue,
    lows: MonotoneQueue,
}

impl Work {
    /// The loops closed by the chords `block`.
    fn judge<U: Fn(usize) -> bool>(
        &mut self,
        path: &Path<U>,
        block: std::ops::Range<usize>,
        mut budget: usize,
    ) -> Judged {
        let Path {
            v,
            chords,
            cum,
            limits,
            usable,
        } = *path;
        let mut judged = Judged {
            loops: Vec::new(),
            tested: 0,
            complete: true,
        };
        // The first chord any window of the block may reach.
        let reach_from = cum[chords[block.start].0] - limits.reach;
        let first = chords[..block.start].partition_point(|&(_, k)| cum[k] < reach_from);
        let all = first..block.end;
        if all.len() - block.len() > budget {
            judged.complete = false;
            return judged;
        }
        budget -= all.len() - block.len();
        let centre = centre_of(&v[chords[first].0..=chords[block.end - 1].1]);
        if self.goes_round_less_than_once(path, first, block.clone(), centre) {
            return judged;
        }
        if let Some(by_angles) = self.judge_by_angles(path, first, block.clone(), centre, budget) {
            return by_angles;
        }
        let chord = |c: usize| (v[chords[first + c].0], v[chords[first + c].1]);
        let count = all.len();
        let head = block.start - first;
        // Windows: found as the chords are read where the heights rise (a spiral, flat
        // layers), else all first.
        let rising = (1..count).all(|c| {
            let ((a0, b0), (a1, b1)) = (chord(c - 1), chord(c));
            a0.z.min(b0.z) <= a1.z.min(b1.z) && a0.z.max(b0.z) <= a1.z.max(b1.z)
        });
        if !rising {
            self.window_starts(path, all.clone());
        }
        self.boxes.clear();
        self.groups.clear();
        self.turn.clear();
        self.winding.clear();
        self.highs.clear();
        self.lows.clear();
        let (mut heading, mut last_heading) = (0.0, None);
        let mut winding = 0;
        // The last chords that do not go round the middle anticlockwise, and clockwise.
        let (mut not_ccw, mut not_cw) = (None, None);
        // The last chord's window starts (by height, by length).
        let mut starts_from = (0, 0);
        for c in 0..count {
            // The chord read: its box, direction, winding and way round.
            let (a, b) = chord(c);
            let d = (b - a).truncate();
            if d != DVec2::ZERO {
                let p = pseudo_angle(d);
                if let Some(q) = last_heading {
                    heading += wrapped(p - q);
                }
                last_heading = Some(p);
            }
            self.turn.push(heading);
            let (ra, rb) = (a.truncate() - centre, b.truncate() - centre);
            // Crossing the ray y = 0, x > 0 (the ends on either side, or leaving it).
            if (ra.y < 0.0) != (rb.y < 0.0) && ra.x.max(rb.x) > 0.0 {
                let x = ra.x + (rb.x - ra.x) * (-ra.y / (rb.y - ra.y));
                if x > 0.0 {
                    winding += if rb.y >= 0.0 { 1 } else { -1 };
                }
            }
            self.winding.push(winding);
            let cross = ra.perp_dot(rb);
            if cross <= 0.0 {
                not_ccw = Some(c);
            }
            if cross >= 0.0 {
                not_cw = Some(c);
            }
            let bx = ChordBox::of(a, b);
            self.boxes.push(bx);
            if c % GROUP == 0 {
                self.groups.push(bx);
            } else if let Some(g) = self.groups.last_mut() {
                *g = g.joined(&bx);
            }
            let turn = &self.turn;
            self.highs.push(c, |k| turn[k] <= turn[c]);
            self.lows.push(c, |k| turn[k] >= turn[c]);
            // The window.
            let (start, flag_start) = if rising {
                let start = path.rising_start(first, c, &self.boxes, &mut starts_from);
                (start, start)
            } else {
                (self.starts[c], self.flag_starts[c])
            };
            if c < head {
                continue;
            }
            self.highs.drop_before(flag_start);
            self.lows.drop_before(flag_start);
            if c < start + 2 {
                continue;
            }
            // Turning through no more than a half-turn (2 in pseudo-angle units): no loop.
            if turn[self.highs.first()] - turn[self.lows.first()] <= 2.0 || !usable(first + c) {
                continue;
            }
            // After the last chord that does not go round one way, the chords go round that
            // way: no loop among them closes at c, unless they go all round.
            let mut end = c - 1;
            for last_other in [not_ccw, not_cw] {
                let after = last_other.map_or(start, |k| (k + 1).max(start));
                if !self.all_round(chord, centre, after, c) {
                    end = end.min(last_other.map_or(0, |k| (k + 1).max(start)));
                }
            }
            if end <= start {
                continue;
            }
            if end - start > budget {
                judged.complete = false;
                return judged;
            }
            let near = bx.widened(limits.same_layer);
            // A group's box first, then its chords'. The widest loop c closes, if any.
            let mut widest: Option<f64> = None;
            let mut i = start;
            while i < end {
                let group_end = ((i / GROUP + 1) * GROUP).min(end);
                budget = budget.saturating_sub(1);
                judged.tested += 1;
                if self.groups[i / GROUP].meets(&near) {
                    for (i, b) in (i..group_end).zip(&self.boxes[i..group_end]) {
                        budget = budget.saturating_sub(1);
                        judged.tested += 1;
                        if !b.meets(&near) || !usable(first + i) {
                            continue;
                        }
                        let (ci, cc) = (chords[first + i], chords[first + c]);
                        if let Some(reach) = loop_reach(v, ci, cc, limits, &mut budget) {
                            widest = Some(widest.map_or(reach, |w| w.max(reach)));
                        }
                    }
                }
                i = group_end;
            }
            if let Some(reach) = widest {
                judged.loops.push((reach, first + c));
            }
        }
        judged
    }

    /// Whether no chord of `block` can close a loop, shown for the whole block at once: every
    /// chord from `first` (the first any of its windows reaches) to its end goes round `centre`
    /// the same way, and from the first chord within `limits.reach` of path of each chord of
    /// the block to its end, less than once round. Such a stretch cannot cross itself (see the
    /// module documentation), and each chord's window lies within it. A wall that goes on round
    /// its axis, textured or not, is shown a block at a time, with one division a chord; a
    /// base's small rings and a wall that turns back are judged chord by chord.
    ///
    /// Unwrapped angles: a chord that goes round one way turns through less than a half-turn,
    /// its ends' [`pseudo_angle`]s 0 … 2 apart that way (`wrapped`); added up chord by chord
    /// they give the angle turned since `first` in units of 4 a turn, to within a few ulps a
    /// chord, so the test allows a millionth of a unit.
    fn goes_round_less_than_once<U>(
        &mut self,
        path: &Path<U>,
        first: usize,
        block: std::ops::Range<usize>,
        centre: DVec2,
    ) -> bool {
        let (v, chords) = (path.v, path.chords);
        let around = |i: usize| v[i].truncate() - centre;
        let way = {
            let (a, b) = chords[first];
            around(a).perp_dot(around(b)).signum()
        };
        // The angle turned by each chord's end since the start of chord `first`.
        self.turn.clear();
        let (mut turned, mut last) = (0.0, pseudo_angle_or_zero(around(chords[first].0)));
        for &(a, b) in &chords[first..block.end] {
            // Strictly one way round (not through the centre, not along a ray; no NaN).
            let onward = around(a).perp_dot(around(b)) * way;
            if onward.is_nan() || onward <= 0.0 {
                return false;
            }
            let angle = pseudo_angle(around(b));
            turned += wrapped(angle - last);
            last = angle;
            self.turn.push(turned);
        }
        let mut from = 0;
        (block.start - first..block.end - first).all(|c| {
            let start = path.length_start(first, c, &mut from);
            let before = start.checked_sub(1).map_or(0.0, |k| self.turn[k]);
            (self.turn[c] - before).abs() < 4.0 - 1e-6
        })
    }

    /// [`Work::judge`]'s loops of `block` (windows from chord `first`, `budget` left), where
    /// the chords' angles round `centre` settle most pairs; `None` where they cannot (the
    /// block is then judged chord by chord).
    ///
    /// A chord that does not pass within a half-turn of the centre's far side sweeps the angles
    /// between its ends' (less than a half-turn), and two chords that cross share the angle of
    /// their crossing. Unwrapped along the path (its chords' sweeps added up), the angles of a
    /// stretch that goes round less than once stand for their directions one to one: two chords
    /// of one window cross only where their sweeps overlap. A wall that goes on round its axis
    /// but steps back here and there (a texture on a fluted or petalled wall, which makes
    /// [`Work::goes_round_less_than_once`] fail on a block) has a few such pairs at each step
    /// back, tested as [`Work::judge`] tests them; every other chord is settled by comparing its
    /// sweep with the extremes of its window's (two sliding extremes). About a third of the
    /// cost of judging the chords one by one, with the same loops.
    ///
    /// `None` where the heights do not rise along the block (the windows are not the rising
    /// ones), a chord sweeps nearly a half-turn or has no direction from the centre, a window
    /// spans a whole turn, or the budget runs out.
    fn judge_by_angles<U: Fn(usize) -> bool>(
        &mut self,
        path: &Path<U>,
        first: usize,
        block: std::ops::Range<usize>,
        centre: DVec2,
        mut budget: usize,
    ) -> Option<Judged> {
        let (v, chords, limits, usable) = (path.v, path.chords, path.limits, path.usable);
        let count = block.end - first;
        let head = block.start - first;
        let chord = |c: usize| (v[chords[first + c].0], v[chords[first + c].1]);
        // Rounding of the pseudo-angles and their sums, far below this.
        const SLACK: f64 = 1e-9;
        let mut judged = Judged {
            loops: Vec::new(),
            tested: 0,
            complete: true,
        };
        // Each chord read in turn: its box and sweep (the least and greatest of its ends'
        // unwrapped angles), then its window and the pairs it may close, so that a block that
        // cannot be settled this way (a base's rings, which go round within a window) is given
        // up at its first such window.
        self.boxes.clear();
        self.sweeps.clear();
        self.highs.clear();
        self.lows.clear();
        // The last chord's end: its point and its pseudo-angle.
        let mut last: Option<(usize, f64)> = None;
        let mut angle = 0.0;
        // The last chord's window starts (by height, by length).
        let mut starts_from = (0, 0);
        for c in 0..count {
            let (a, b) = chord(c);
            let bx = ChordBox::of(a, b);
            if let Some(prev) = self.boxes.last()
                && !(prev.lo.z <= bx.lo.z && prev.hi.z <= bx.hi.z)
            {
                return None;
            }
            self.boxes.push(bx);
            // A chord mostly starts where the last one ended: its pseudo-angle is known.
            let qa = match last {
                Some((end, q)) if end == chords[first + c].0 => q,
                _ => pseudo_angle(a.truncate() - centre),
            };
            if let Some((_, q)) = last {
                // The path's step from the last chord's end to this one's start (none where
                // the chords share their point).
                angle += wrapped(qa - q);
            }
            let qb = pseudo_angle(b.truncate() - centre);
            let sweep = wrapped(qb - qa);
            // Not a number for a chord end at the centre; a half-turn through it.
            if sweep.is_nan() || sweep.abs() >= 1.9 || !angle.is_finite() {
                return None;
            }
            let from = angle;
            angle += sweep;
            self.sweeps.push((from.min(angle), from.max(angle)));
            last = Some((chords[first + c].1, qb));
            // The window, as [`Work::judge`] finds it where the heights rise.
            let start = path.rising_start(first, c, &self.boxes, &mut starts_from);
            // The chords up to c − 2 in the sliding extremes.
            if let Some(k) = c.checked_sub(2) {
                let sweeps = &self.sweeps;
                self.highs.push(k, |i| sweeps[i].1 <= sweeps[k].1);
                self.lows.push(k, |i| sweeps[i].0 >= sweeps[k].0);
            }
            if c < head || c < start + 2 {
                continue;
            }
            self.highs.drop_before(start);
            self.lows.drop_before(start);
            let sweeps = &self.sweeps;
            let (high, low) = (sweeps[self.highs.first()].1, sweeps[self.lows.first()].0);
            let (lo, hi) = sweeps[c];
            // The window's angles within less than a whole turn.
            let span = high.max(sweeps[c - 1].1).max(hi) - low.min(sweeps[c - 1].0).min(lo);
            if span.is_nan() || span >= 4.0 - 1e-6 {
                return None;
            }
            // No earlier chord of the window sweeps an angle of this one's.
            if high < lo - SLACK || low > hi + SLACK || !usable(first + c) {
                continue;
            }
            let near = bx.widened(limits.same_layer);
            let mut widest: Option<f64> = None;
            for i in start..c - 1 {
                let (l, h) = sweeps[i];
                if h < lo - SLACK || l > hi + SLACK {
                    continue;
                }
                judged.tested += 1;
                budget = budget.checked_sub(1)?;
                if !self.boxes[i].meets(&near) || !usable(first + i) {
                    continue;
                }
                let (ci, cc) = (chords[first + i], chords[first + c]);
                if let Some(reach) = loop_reach(v, ci, cc, limits, &mut budget) {
                    widest = Some(widest.map_or(reach, |w| w.max(reach)));
                }
                if budget == 0 {
                    return None;
                }
            }
            if let Some(reach) = widest {
                judged.loops.push((reach, first + c));
            }
        }
        Some(judged)
    }

    /// Whether chords `from ..= to` go all round `centre` (their ends' unwrapped angles a
    /// whole turn apart, or more): never where the winding is the same at both ends.
    fn all_round(
        &self,
        chord: impl Fn(usize) -> (DVec3, DVec3),
        centre: DVec2,
        from: usize,
        to: usize,
    ) -> bool {
        let winding_before = from.checked_sub(1).map_or(0, |k| self.winding[k]);
        if self.winding[to] == winding_before {
            return false;
        }
        let angle = |p: DVec3| pseudo_angle_or_zero(p.truncate() - centre);
        let turns = f64::from(self.winding[to] - winding_before);
        (angle(chord(to).1) - angle(chord(from).0) + 4.0 * turns).abs() >= 4.0
    }

    /// Each chord's window (see [`find_crossings`]) as indices into the block's chords `all`,
    /// where the heights do not rise along them: the chord after the last one lying wholly a
    /// layer's tolerance below it (found on the running minima of the chords' tops, stepping
    /// from the last chord's answer), and no farther back than `limits.reach` of path; and
    /// the least start from each chord on.
    fn window_starts<U>(&mut self, path: &Path<U>, all: std::ops::Range<usize>) {
        let (v, chords, limits) = (path.v, path.chords, path.limits);
        let first = all.start;
        let heights = |c: usize| {
            let (a, b) = (v[chords[first + c].0].z, v[chords[first + c].1].z);
            (a.min(b), a.max(b))
        };
        self.starts.clear();
        self.minima.clear();
        // Chords whose tops are lower than every later one's, in path order (so rising in
        // height): the last chord below any height is among them.
        let (mut guess, mut length_from) = (0, 0);
        for c in 0..all.len() {
            let (low, top) = heights(c);
            let below = low - limits.same_layer;
            guess = super::layers::seek(&self.minima, guess, |&k| heights(k as usize).1 < below);
            let by_height = guess
                .checked_sub(1)
                .map_or(0, |m| self.minima[m] as usize + 1);
            self.starts
                .push(by_height.max(path.length_start(first, c, &mut length_from)));
            while self
                .minima
                .last()
                .is_some_and(|&k| heights(k as usize).1 >= top)
            {
                self.minima.pop();
            }
            self.minima.push(c as u32);
            guess = guess.min(self.minima.len());
        }
        self.flag_starts.clear();
        self.flag_starts.extend_from_slice(&self.starts);
        for c in (0..all.len().saturating_sub(1)).rev() {
            self.flag_starts[c] = self.flag_starts[c].min(self.flag_starts[c + 1]);
        }
    }
}

/// A chord's box: a pair's first test, on a compact array.
#[derive(Clone, Copy)]
struct ChordBox {
    lo: DVec3,
    hi: DVec3,
}

impl ChordBox {
    fn of(a: DVec3, b: DVec3) -> Self {
        ChordBox {
            lo: a.min(b),
            hi: a.max(b),
        }
    }

    fn joined(&self, o: &ChordBox) -> Self {
        ChordBox {
            lo: self.lo.min(o.lo),
            hi: self.hi.max(o.hi),
        }
    }

    /// The box with `dz` more room above and below.
    fn widened(&self, dz: f64) -> Self {
        ChordBox {
            lo: self.lo - DVec3::Z * dz,
            hi: self.hi + DVec3::Z * dz,
        }
    }

    /// Whether the boxes overlap (or touch).
    fn meets(&self, o: &ChordBox) -> bool {
        (self.lo.x <= o.hi.x)
            & (self.hi.x >= o.lo.x)
            & (self.lo.y <= o.hi.y)
            & (self.hi.y >= o.lo.y)
            & (self.lo.z <= o.hi.z)
            & (self.hi.z >= o.lo.z)
    }
}

/// `step` (a difference of [`pseudo_angle`]s) as the turn of less than a half-turn each way
/// it stands for: within −2 … 2.
fn wrapped(step: f64) -> f64 {
    if step > 2.0 {
        step - 4.0
    } else if step <= -2.0 {
        step + 4.0
    } else {
        step
    }
}

/// The middle of the extent in XY of points `v`: a vessel's axis, roughly (nothing depends on
/// it but how much is tested).
fn centre_of(v: &[DVec3]) -> DVec2 {
    let (lo, hi) = crate::geometry::bounds(v.iter().map(|p| p.truncate()));
    let c = 0.5 * (lo + hi);
    if c.is_finite() { c } else { DVec2::ZERO }
}

/// Whether chords `a` and `b` (`a` earlier) of path `v` cross at the same height, and if so how
/// far the loop between them reaches from the crossing (its points' greatest XY distance
/// from it): that reach where it is more than half a bead, else none. The loop's points are
/// counted against `budget`.
fn loop_reach(
    v: &[DVec3],
    (a0, a1): (usize, usize),
    (b0, b1): (usize, usize),
    limits: CrossingLimits,
    budget: &mut usize,
) -> Option<f64> {
    let (p, q) = (v[a0], v[a1]);
    let (r, s) = (v[b0], v[b1]);
    let (t, u) =
        crate::geometry::proper_crossing(p.truncate(), q.truncate(), r.truncate(), s.truncate())?;
    let (za, zb) = (p.z + (q.z - p.z) * t, r.z + (s.z - r.z) * u);
    if (za - zb).abs() >= limits.same_layer {
        return None;
    }
    let at = p.truncate().lerp(q.truncate(), t);
    let between = &v[a1..=b0];
    *budget = budget.saturating_sub(between.len());
    let reach = between
        .iter()
        .map(|m| m.truncate().distance_squared(at))
        .fold(0.0, f64::max)
        .sqrt();
    (reach > limits.half_bead).then_some(reach)
}

/// The direction of `d` (not zero) as a number in 0 … 4 that grows with its angle from +x,
/// a quarter-turn for each 1 and d's opposite exactly 2 more (mod 4): so a direction turned by
/// more than a half-turn from another is more than 2 from it, unwrapped. A division instead
/// of an arctangent.
fn pseudo_angle(d: DVec2) -> f64 {
    // y / (|x| + |y|) runs −1 … 1 over the right half-plane; the left half-plane's runs on
    // from 1 to 3. Written to select, not branch: a textured wall's directions change
    // quadrant at random.
    let t = d.y / (d.x.abs() + d.y.abs());
    let p = if d.x >= 0.0 { t } else { 2.0 - t };
    if p < 0.0 { p + 4.0 } else { p }
}

/// [`pseudo_angle`] of `d`, or 0 for the zero vector.
fn pseudo_angle_or_zero(d: DVec2) -> f64 {
    if d == DVec2::ZERO {
        0.0
    } else {
        pseudo_angle(d)
    }
}

/// Chord indices in path order, the window's running extreme first: a sliding window's
/// maximum or minimum in constant time per chord.
#[derive(Default)]
struct MonotoneQueue {
    items: Vec<u32>,
    /// Where the queue begins in `items`.
    head: usize,
}

impl MonotoneQueue {
    fn clear(&mut self) {
        self.items.clear();
        self.head = 0;
    }

    /// Adds chord `c`, dropping the chords behind it that `beaten` says it outdoes.
    fn push(&mut self, c: usize, beaten: impl Fn(usize) -> bool) {
        while self.items.len() > self.head && self.items.last().is_some_and(|&k| beaten(k as usize))
        {
            self.items.pop();
        }
        self.items.push(c as u32);
    }

    /// Drops the chords before `start` (keeping the last).
    fn drop_before(&mut self, start: usize) {
        while self.head + 1 < self.items.len() && (self.items[self.head] as usize) < start {
            self.head += 1;
        }
    }

    /// The window's extreme (the last chord pushed when empty).
    fn first(&self) -> usize {
        self.items.get(self.head).map_or(0, |&k| k as usize)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::TAU;

    const LIMITS: CrossingLimits = CrossingLimits {
        same_layer: 0.0625,
        half_bead: 0.6,
        reach: 240.0,
    };

    /// Every point its own chord, every chord measured.
    fn search(v: &[DVec3]) -> Crossings {
        let chords: Vec<(usize, usize)> = (0..v.len() - 1).map(|i| (i, i + 1)).collect();
        let lines: Vec<usize> = (0..v.len()).collect();
        let mut cum = vec![0.0];
        for w in v.windows(2) {
            cum.push(cum.last().unwrap() + w[0].distance(w[1]));
        }
        find_crossings(v, &chords, &lines, &cum, LIMITS, &|_| true, || ()).0
    }

    /// A spiral of `turns` revolutions of radius 40 mm, 0.5 mm a revolution, `n` points each,
    /// with `curl(t)` added to each point (t in revolutions).
    fn spiral(turns: f64, n: usize, curl: impl Fn(f64) -> DVec2) -> Vec<DVec3> {
        let count = (turns * n as f64) as usize;
        (0..=count)
            .map(|k| {
                let t = k as f64 / n as f64;
                let a = TAU * t;
                let p = DVec2::new(100.0 + 40.0 * a.cos(), 100.0 + 40.0 * a.sin()) + curl(t);
                p.extend(0.5 + 0.5 * t)
            })
            .collect()
    }

    /// A loop tied into the spiral at revolution `at` of each, `width` revolutions long: the
    /// wall swings `2 r` mm out and `back` mm back along itself and on (a prolate cycloid's
    /// arch, which crosses itself where the swing back outruns the ring's way forward).
    fn curl(at: f64, width: f64, r: f64, back: f64) -> impl Fn(f64) -> DVec2 {
        move |t| {
            let f = (t - at).rem_euclid(1.0) / width;
            if f >= 1.0 {
                return DVec2::ZERO;
            }
            let a = TAU * t;
            let (radial, tangent) = (DVec2::new(a.cos(), a.sin()), DVec2::new(-a.sin(), a.cos()));
            let phase = TAU * f;
            radial * (r * (1.0 - phase.cos())) + tangent * (back * phase.sin())
        }
    }

    #[test]
    fn a_spiral_that_only_turns_one_way_has_no_loop_and_tests_no_pair() {
        let v = spiral(6.0, 720, |_| DVec2::ZERO);
        let found = search(&v);
        assert!(found.events.is_empty());
        assert!(found.complete);
        assert_eq!(found.tested, 0);
        // A wavy wall (a texture: its direction swings ±60° about the ring's) has none either.
        let v = spiral(6.0, 720, |t| {
            let a = TAU * t;
            DVec2::new(a.cos(), a.sin()) * (1.5 * (TAU * 40.0 * t).sin())
        });
        let found = search(&v);
        assert!(found.events.is_empty());
        assert_eq!(found.tested, 0);
    }

    /// A flat path that goes round twice in one layer, its radius swinging so that the second
    /// round crosses the first: every chord goes round the same way, but a window goes round
    /// more than once, so it is judged chord by chord and its crossings are found.
    #[test]
    fn going_round_twice_in_one_layer_is_judged_chord_by_chord() {
        let v: Vec<DVec3> = (0..=1440)
            .map(|k| {
                let a = TAU * k as f64 / 720.0;
                let r = 10.0 + 2.0 * (1.5 * a).sin();
                DVec3::new(100.0 + r * a.cos(), 100.0 + r * a.sin(), 0.5)
            })
            .collect();
        let found = search(&v);
        assert!(found.complete);
        assert!(!found.events.is_empty());
        assert_eq!(found.events.len(), every_pair(&v));
    }

    #[test]
    fn a_loop_in_every_revolution_is_found_once_each_with_its_reach() {
        // A 3 mm loop, a fortieth of a revolution long (6 mm of the 250 mm ring), every turn.
        let v = spiral(4.0, 720, curl(0.3, 0.05, 3.0, 4.5));
        let found = search(&v);
        assert_eq!(found.events.len(), 4, "one loop a revolution");
        assert!(found.events.iter().all(|e| e.what == CROSSING));
        // The loop swings 6 mm out; it crosses itself about 1.7 mm out.
        let worst = found.events.iter().map(|e| e.value).fold(0.0, f64::max);
        assert!(worst > 3.5 && worst < 6.0, "{worst}");
        assert_eq!(every_pair(&v), 4);
    }

    #[test]
    fn loops_of_any_size_anywhere_are_found_as_testing_every_pair_finds_them() {
        // Loops of 0.2 … 5 mm, some swinging back too little to cross.
        let mut next = crate::test_rng::uniform(0x2545_f491_4f6c_dd1d);
        let mut looped = 0;
        for _ in 0..12 {
            let (at, width) = (next(), 0.02 + 0.06 * next());
            let (r, back) = (0.1 + 2.4 * next(), 0.5 + 8.0 * next());
            let v = spiral(3.0, 720, curl(at, width, r, back));
            let expected = every_pair(&v);
            looped += usize::from(expected > 0);
            assert_eq!(search(&v).events.len(), expected, "{at} {width} {r} {back}");
        }
        assert!(looped >= 4, "only {looped} of the spirals loop");
        // Textures that swing the wall back along itself and out (trochoids), some enough to
        // loop at every wave, some short of it: windows of both ways round and of sharp turns.
        let mut looped = 0;
        for _ in 0..12 {
            let waves = (10.0 + 50.0 * next()).round();
            let (out, along) = (0.3 + 2.0 * next(), 0.5 + 1.5 * next());
            let v = spiral(3.0, 720, move |t| {
                let (a, w) = (TAU * t, TAU * waves * t);
                DVec2::new(a.cos(), a.sin()) * (out * w.cos())
                    + DVec2::new(-a.sin(), a.cos()) * (along * w.sin())
            });
            let expected = every_pair(&v);
            looped += usize::from(expected > 0);
            assert_eq!(search(&v).events.len(), expected, "{waves} {out} {along}");
        }
        assert!((2..12).contains(&looped), "{looped} of the textures loop");
    }

    /// A petalled wall whose texture steps it back round its axis at every wave (as the
    /// benchmark vase's does on its petals' flanks), some waves far enough to loop: its windows
    /// go both ways round, the chords' angles settle all but the pairs at the steps back, and
    /// the loops are those testing every pair finds.
    #[test]
    fn a_wall_stepping_back_at_every_wave_is_settled_by_its_angles() {
        for (along, loops) in [(0.6, false), (0.9, true), (6.0, true)] {
            let v = spiral(3.0, 720, move |t| {
                let a = TAU * t;
                let (radial, tangent) =
                    (DVec2::new(a.cos(), a.sin()), DVec2::new(-a.sin(), a.cos()));
                let w = TAU * 60.0 * t;
                radial * (8.0 * (6.0 * a).cos() + 0.8 * w.cos()) + tangent * (along * w.sin())
            });
            let steps_back = v
                .windows(2)
                .filter(|s| {
                    let c = DVec2::new(100.0, 100.0);
                    (s[0].truncate() - c).perp_dot(s[1].truncate() - c) <= 0.0
                })
                .count();
            assert!(steps_back > 20, "{along}: {steps_back} steps back");
            let found = search(&v);
            assert!(found.complete);
            assert_eq!(found.events.len(), every_pair(&v), "{along}");
            assert_eq!(!found.events.is_empty(), loops, "{along}");
            if !loops {
                // A few pairs a step back, not every chord's window.
                assert!(
                    found.tested < v.len() / 4,
                    "{along}: {} pairs tested",
                    found.tested
                );
            }
        }
    }

    #[test]
    fn a_loop_within_half_a_bead_is_let_be() {
        let v = spiral(3.0, 7200, curl(0.3, 0.01, 0.15, 0.8));
        assert!(every_pair_raw(&v) > 0, "the path does cross itself");
        assert!(search(&v).events.is_empty());
    }

    #[test]
    fn crossing_the_layer_below_is_not_a_loop() {
        // A ring that wanders in and out a bead from revolution to revolution crosses the one
        // below it over and over, a layer lower.
        let v = spiral(5.0, 360, |t| {
            let a = TAU * t;
            DVec2::new(a.cos(), a.sin()) * (1.2 * (TAU * (t * 1.37)).sin())
        });
        assert!(search(&v).events.is_empty());
    }

    #[test]
    fn the_pseudo_angle_grows_with_the_angle_and_its_opposite_is_two_more() {
        let mut last = -1.0;
        for k in 0..3600 {
            let a = TAU * k as f64 / 3600.0;
            let d = DVec2::new(a.cos(), a.sin()) * 3.7;
            let p = pseudo_angle(d);
            assert!(p > last && (0.0..4.0).contains(&p), "{k}: {p}");
            last = p;
            let opposite = (pseudo_angle(-d) - p).rem_euclid(4.0);
            assert!((opposite - 2.0).abs() < 1e-9, "{k}: {opposite}");
        }
    }

    /// Segments that close a loop, found by testing every pair of segments in the same layer
    /// with the same rules.
    fn every_pair(v: &[DVec3]) -> usize {
        let mut budget = usize::MAX;
        (2..v.len() - 1)
            .filter(|&j| {
                (0..j - 1).any(|i| {
                    (v[i].z - v[j].z).abs() < 0.5
                        && loop_reach(v, (i, i + 1), (j, j + 1), LIMITS, &mut budget).is_some()
                })
            })
            .count()
    }

    /// Proper crossings of segments at the same height, however small their loops.
    fn every_pair_raw(v: &[DVec3]) -> usize {
        let mut budget = usize::MAX;
        let tiny = CrossingLimits {
            half_bead: 0.0,
            ..LIMITS
        };
        let mut count = 0;
        for j in 2..v.len() - 1 {
            for i in j.saturating_sub(60)..j - 1 {
                if loop_reach(v, (i, i + 1), (j, j + 1), tiny, &mut budget).is_some() {
                    count += 1;
                }
            }
        }
        count
    }
}
