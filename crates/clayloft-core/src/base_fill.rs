//! Base fill (SPEC §13): one continuous path that covers any flat, simple closed foot with beads
//! one line width apart — connected contour-parallel offsets.
//!
//! **Rings.** The foot's inward offsets by w, 2w, 3w, … (w the line width), each the offset by w
//! of the ring around it kept exactly with its arcs (with `cavalier_contours`, which gets
//! splits, pinches and vanishing lobes right), and one more at (j + ½)·w inside a ring at level
//! j where no ring one level in covers its middle. They form a tree: a ring's
//! children are the next level's rings inside it (an offset splits where the foot has a waist).
//! The root is the foot itself: the wall's first bead.
//!
//! **Bridges.** The path walks the tree depth first, once round each ring anticlockwise. It
//! visits a child through a bridge: from the parent ring at q_in it steps in to the child at e,
//! goes round the child to x (half a line width before e) and steps back out to q_out on the
//! parent, leaving the parent's stretch from q_in to q_out out. The outline is the exception: the
//! wall's first revolution rests on it (and, on a wall flaring at 45°, the next base layer's
//! outline, a layer's height further out), and a half-bead notch under a wall at the overhang
//! limit leans it past the limit; so a bridge from the outline steps back out to q_in itself, x
//! a whole bead before e, and the outline is laid all round. Under a wall of W beads the W − 1
//! rings inside the outline carry its inner beads and are laid all round too: each is walked
//! round through its entry e and half a bead on before the step back out to q_in.
//!
//! Every point of a ring of level j + 1 lies exactly w from the ring of level j around it (the
//! offsets are erosions of the foot by growing discs), so both steps are one bead long and lie in
//! the strip between the two rings, which no other ring enters; facing rings run in opposite
//! directions (the orientation alternates), so the parent reaches q_in first and the two steps do
//! not cross. Bridges on one ring are kept apart, and away from the ring's own bridge, by a bead.
//!
//! The layer starts and ends at the foot's point 0, so base layers stack without a travel move
//! (alternate layers run the same path backwards) and the last ends where the wall begins.
//!
//! **Several layers.** Each base layer's outline is its own foot (a flaring wall's feet grow a
//! layer's height times the lean from layer to layer); the rings inside are the first foot's on
//! every layer, so that they and their bridges stack. Under a wall of W beads on a foot that
//! moves more than a quarter bead over the base, the W − 1 rings its inner beads rest on follow
//! each layer's own foot instead (each moves as the outline does, within the overhang limit), and
//! the first foot's rings go on further in.

use cavalier_contours::polyline::{PlineCreation, PlineSource, PlineSourceMut, Polyline};
use glam::DVec2;

/// Largest deviation of the drawn offset rings from their arcs, mm (far below a bead).
const ARC_TOLERANCE_MM: f64 = 0.01;

/// Ring levels a base may have (the tree is built and walked recursively; a clay foot 1 m
/// across with 1 mm beads has 500).
pub const MAX_RING_LEVELS: usize = 1000;

/// At most how many rings deep a foot's fill goes: half its smaller extent over the bead width
/// (no ring lies deeper), plus one.
pub fn ring_levels(foot: &[DVec2], w: f64) -> usize {
    let (lo, hi) = crate::geometry::bounds(foot.iter().copied());
    let levels = ((hi - lo).min_element() / 2.0 / w).ceil();
    if levels.is_finite() {
        levels.min(1e9) as usize + 1
    } else {
        usize::MAX
    }
}

/// Why a foot cannot be filled.
#[derive(Debug, Clone, PartialEq)]
pub enum FillError {
    /// No part of the foot is as wide as one bead.
    NarrowerThanABead,
    /// The offset of the outline failed (a foot the offsetting library cannot handle).
    Offset,
    /// More ring levels than [`MAX_RING_LEVELS`].
    TooDeep { levels: usize },
}

/// A place where the foot is narrower than one bead: the beads on either side overlap there.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NarrowSpot {
    /// Foot outline points narrower than a bead.
    pub points: usize,
    /// The narrowest of them (where the foot is farthest from fitting a bead).
    pub at: DVec2,
    /// How far that point lies from the bead-wide part of the foot, mm.
    pub depth_mm: f64,
}

/// One base layer's path (XY, starting and ending at `foot[0]`) and where the foot is too narrow.
#[derive(Debug, Clone, PartialEq)]
pub struct BaseFill {
    pub path: Vec<DVec2>,
    pub narrow: Option<NarrowSpot>,
}

/// A closed ring with its arc length at each vertex (`cum[n]` = the ring's length).
#[derive(Debug, Clone)]
struct Ring {
    pts: Vec<DVec2>,
    cum: Vec<f64>,
    /// Spurs into the sharp corners the ring around leaves uncovered: (vertex, tip), by vertex.
    spurs: Vec<(usize, DVec2)>,
    /// The bounding box (min, max) of each run of [`BLOCK_SEGMENTS`] segments, in order.
    blocks: Vec<(DVec2, DVec2)>,
    /// The bounding box of each run of [`GROUP_BLOCKS`] blocks, in order.
    groups: Vec<(DVec2, DVec2)>,
}

/// Segments per bounding box in [`Ring::nearest`]'s search.
const BLOCK_SEGMENTS: usize = 8;
/// Blocks per group box in [`Ring::nearest`]'s search: a query passes over a ring's far side
/// a group at a time (on the benchmark vase's 720-point foot, 12 boxes instead of 90).
const GROUP_BLOCKS: usize = 8;

/// The box (min, max) holding `boxes`.
fn joined(boxes: &[(DVec2, DVec2)]) -> (DVec2, DVec2) {
    boxes.iter().fold(
        (DVec2::INFINITY, DVec2::NEG_INFINITY),
        |(lo, hi), &(l, h)| (lo.min(l), hi.max(h)),
    )
}

impl Ring {
    fn new(pts: Vec<DVec2>) -> Ring {
        let cum = crate::geometry::cumulative_length(&pts);
        let n = pts.len();
        let blocks = (0..n)
            .step_by(BLOCK_SEGMENTS)
            .map(|first| {
                // Segment i runs from vertex i to vertex i + 1 (the last back to vertex 0).
                (first..=(first + BLOCK_SEGMENTS).min(n))
                    .map(|i| pts[i % n])
                    .fold((DVec2::INFINITY, DVec2::NEG_INFINITY), |(lo, hi), q| {
                        (lo.min(q), hi.max(q))
                    })
            })
            .collect::<Vec<_>>();
        let groups = blocks.chunks(GROUP_BLOCKS).map(joined).collect();
        Ring {
            pts,
            cum,
            spurs: Vec::new(),
            blocks,
            groups,
        }
    }

    fn len(&self) -> f64 {
        self.cum[self.pts.len()]
    }

    /// The point at arc length `s` (taken modulo the length).
    fn at(&self, s: f64) -> DVec2 {
        let s = s.rem_euclid(self.len());
        let i = self
            .cum
            .partition_point(|&c| c <= s)
            .clamp(1, self.pts.len())
            - 1;
        let (a, b) = (self.pts[i], self.pts[(i + 1) % self.pts.len()]);
        let seg = self.cum[i + 1] - self.cum[i];
        let f = if seg > 0.0 {
            (s - self.cum[i]) / seg
        } else {
            0.0
        };
        a.lerp(b, f)
    }

    /// Arc length of the ring point nearest to `p`, and its distance (the first segment's, in
    /// order, where several are as near).
    ///
    /// The group of segments whose box lies nearest `p` is searched first, then the others in
    /// order; a run of segments whose bounding box (a block's, or a group of blocks') lies
    /// farther from `p` than the nearest point found so far is passed over: none of them can be
    /// as near. Of segments as near, the first in order is taken: the result is the plain
    /// scan's.
    fn nearest(&self, p: DVec2) -> (f64, f64) {
        let (s, d, _) = self.nearest_segment(p);
        (s, d)
    }

    /// [`Ring::nearest`], with the segment the nearest point lies on (`usize::MAX` for a ring
    /// with none).
    fn nearest_segment(&self, p: DVec2) -> (f64, f64, usize) {
        let n = self.pts.len();
        let gap = |(lo, hi): (DVec2, DVec2)| (lo - p).max(p - hi).max(DVec2::ZERO).length();
        // Rounding in either distance is far below this margin.
        let beyond = |bx, reach: f64| gap(bx) > reach + 1e-9 * (1.0 + reach);
        // (arc length, distance, segment) of the nearest point so far.
        let mut best = (0.0, f64::INFINITY, usize::MAX);
        let search_group = |g: usize, best: &mut (f64, f64, usize)| {
            let blocks = g * GROUP_BLOCKS..((g + 1) * GROUP_BLOCKS).min(self.blocks.len());
            for b in blocks {
                if beyond(self.blocks[b], best.1) {
                    continue;
                }
                let first = b * BLOCK_SEGMENTS;
                for i in first..(first + BLOCK_SEGMENTS).min(n) {
                    let (d, f) = crate::geometry::point_segment_distance(
                        p,
                        self.pts[i],
                        self.pts[(i + 1) % n],
                    );
                    if d < best.1 || (d == best.1 && i < best.2) {
                        *best = (self.cum[i] + f * (self.cum[i + 1] - self.cum[i]), d, i);
                    }
                }
            }
        };
        let Some(closest) = (0..self.groups.len())
            .min_by(|&a, &b| gap(self.groups[a]).total_cmp(&gap(self.groups[b])))
        else {
            return (0.0, f64::INFINITY, usize::MAX);
        };
        search_group(closest, &mut best);
        for g in (0..self.groups.len()).filter(|&g| g != closest) {
            if !beyond(self.groups[g], best.1) {
                search_group(g, &mut best);
            }
        }
        best
    }

    /// A segment among those from `around − 2` to `around + 8` (wrapping round) within
    /// `reach` of `p`, if one is: where the point before `p` found its nearest, the next point
    /// along a similar outline mostly finds one too.
    fn segment_within(&self, p: DVec2, around: usize, reach: f64) -> Option<usize> {
        let n = self.pts.len();
        (0..11).map(|k| (around + n + k - 2) % n).find(|&i| {
            crate::geometry::point_segment_distance(p, self.pts[i], self.pts[(i + 1) % n]).0
                <= reach
        })
    }

    /// Appends the vertices strictly after arc length `from` and before `to` (going forward,
    /// `from ≤ to ≤ from + len`), then the point at `to`.
    fn walk(&self, from: f64, to: f64, out: &mut Vec<DVec2>) {
        let (n, len) = (self.pts.len(), self.len());
        let turns = (from / len).floor();
        let mut i = self.cum.partition_point(|&c| c <= from.rem_euclid(len));
        let mut base = turns * len;
        loop {
            if i >= n {
                i = 0;
                base += len;
            }
            let s = base + self.cum[i];
            if s >= to - 1e-9 {
                break;
            }
            if s > from + 1e-9 {
                out.push(self.pts[i]);
                if let Ok(k) = self.spurs.binary_search_by_key(&i, |sp| sp.0) {
                    out.push(self.spurs[k].1);
                    out.push(self.pts[i]);
                }
            }
            i += 1;
        }
        out.push(self.at(to));
    }
}

/// A ring and the rings one level in that lie inside it.
#[derive(Debug, Clone)]
struct Node {
    ring: Ring,
    /// How far inside the ring around it this ring lies, mm (w, or w/2 for a middle ring; 0
    /// for the foot).
    step: f64,
    children: Vec<Node>,
}

/// The foot as a closed polyline for the offsetting library (anticlockwise, no repeated points).
fn polyline(foot: &[DVec2]) -> Polyline<f64> {
    let mut pl = Polyline::with_capacity(foot.len(), true);
    for p in crate::geometry::dedup_closed(foot) {
        pl.add(p.x, p.y, 0.0);
    }
    pl
}

/// The foot's inward offset by `d`: its rings, drawn with straight segments, anticlockwise.
fn offset(foot: &Polyline<f64>, d: f64) -> Result<Vec<Vec<DVec2>>, FillError> {
    Ok(offset_exact(foot, d)?
        .into_iter()
        .map(|(_, pts)| pts)
        .collect())
}

/// The closed outline `outline` (counter-clockwise) moved inward by `d` exactly — each point `d`
/// from the outline, corners rounded where the outline turns outward — as its largest ring
/// (where the outline is narrower than 2·d somewhere the offset splits; the narrow part cannot
/// hold the path anyway). `None` when nothing is left.
pub fn inward_offset(outline: &[DVec2], d: f64) -> Option<Vec<DVec2>> {
    inward_offset_rings(outline, d)?
        .into_iter()
        .max_by(|a, b| crate::geometry::signed_area(a).total_cmp(&crate::geometry::signed_area(b)))
}

/// Every ring of the closed outline's inward offset by `d` (more than one where the outline is
/// narrower than 2·d somewhere), anticlockwise; `None` when the offset fails.
pub fn inward_offset_rings(outline: &[DVec2], d: f64) -> Option<Vec<Vec<DVec2>>> {
    offset(&polyline(outline), d).ok()
}

/// A ring as the offsetting library has it (with arcs) and as the path draws it.
type ExactRing = (Polyline<f64>, Vec<DVec2>);

/// [`offset`], each ring also kept exactly (with its arcs) for offsetting further.
fn offset_exact(foot: &Polyline<f64>, d: f64) -> Result<Vec<ExactRing>, FillError> {
    let loops = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        foot.parallel_offset(d)
            .into_iter()
            .map(|pl| {
                let flat = pl
                    .arcs_to_approx_lines(ARC_TOLERANCE_MM)
                    .unwrap_or(pl.clone());
                (pl, flat)
            })
            .collect::<Vec<_>>()
    }))
    .map_err(|_| FillError::Offset)?;
    Ok(loops
        .into_iter()
        .filter(|(_, flat)| flat.is_closed() && flat.vertex_count() >= 3)
        .map(|(pl, flat)| {
            let mut pts: Vec<DVec2> = (0..flat.vertex_count())
                .map(|i| {
                    let v = flat.at(i);
                    DVec2::new(v.x, v.y)
                })
                .collect();
            if crate::geometry::signed_area(&pts) < 0.0 {
                pts.reverse();
            }
            (pl, without_spikes(pts))
        })
        .filter(|(_, pts)| pts.len() >= 3 && crate::geometry::signed_area(pts) > 1e-9)
        .collect())
}

/// A ring without repeated points and without spikes (a vertex where the ring turns straight
/// back: the offsetting library can close a ring by going back over its first segment).
fn without_spikes(mut pts: Vec<DVec2>) -> Vec<DVec2> {
    loop {
        pts = crate::geometry::dedup_closed(&pts);
        let n = pts.len();
        if n < 3 {
            return pts;
        }
        let spike = (0..n).find(|&i| {
            let (a, b, c) = (pts[(i + n - 1) % n], pts[i], pts[(i + 1) % n]);
            let (u, v) = (b - a, c - b);
            u.dot(v) < 0.0 && u.perp_dot(v).abs() <= 1e-9 * u.length() * v.length()
        });
        match spike {
            Some(i) => {
                pts.remove(i);
            }
            None => return pts,
        }
    }
}

/// The ring tree of a foot (module documentation): each ring the offset by w of the ring around
/// it, kept exactly with its arcs (erosion by w after erosion by d is erosion by d + w, and the
/// offset of an arc is an arc: nothing is lost from level to level), and the offset by w/2
/// where that middle ring is not covered by a deeper one.
///
/// `beside` runs on the second core before it makes the middle rings, while this one makes the
/// rings (here after them, with no second core; not at all when the foot is too deep);
/// `rings_made` once both are done.
fn ring_tree(
    foot: &[DVec2],
    w: f64,
    rings_made: impl FnOnce(),
    beside: impl FnOnce() + Send,
) -> Result<Node, FillError> {
    let max_levels = ring_levels(foot, w);
    if max_levels > MAX_RING_LEVELS {
        return Err(FillError::TooDeep { levels: max_levels });
    }
    let mut root = Node {
        ring: Ring::new(foot.to_vec()),
        step: 0.0,
        children: Vec::new(),
    };
    grow(&mut root, &polyline(foot), w, max_levels, beside)?;
    rings_made();
    orient(&mut root, true, w);
    prune_spurs(&mut root);
    Ok(root)
}

/// Adds the rings one level inside `node` (exactly `exact`), and theirs, `levels` deep, and the
/// middle rings where no deeper ring reaches.
///
/// The middle rings (offsets by w/2) do not depend on the rings inside them, so a second core
/// offsets them while this one goes down the rings: [`grow_rings`] hands each ring's exact
/// outline over as it is made, this core takes those still waiting once the rings are made,
/// and [`add_middles`] puts their offsets in afterwards, in the order they were handed over.
/// The tree is the one made on one core.
fn grow(
    root: &mut Node,
    exact: &Polyline<f64>,
    w: f64,
    levels: usize,
    beside: impl FnOnce() + Send,
) -> Result<(), FillError> {
    grow_on(root, exact, w, levels, crate::parallel::cores() > 1, beside)
}

/// [`grow`], with `beside` and the middle rings on a second thread or not.
fn grow_on(
    root: &mut Node,
    exact: &Polyline<f64>,
    w: f64,
    levels: usize,
    two_threads: bool,
    beside: impl FnOnce() + Send,
) -> Result<(), FillError> {
    let middles = Middles::default();
    // On a helper this waits for each ring by spinning (a ring takes tens of microseconds, a
    // sleeping thread as long to wake); run after the rings, it finds them all made. `beside`
    // first: the rings it finds waiting then are offset one after another.
    let offset_all = || {
        beside();
        let mut spins = 0u32;
        loop {
            match middles.offset_next(w) {
                Next::Made => {}
                Next::Waiting => {
                    // Let the ring maker have the core should it have lost its own.
                    spins = spins.wrapping_add(1);
                    if spins.is_multiple_of(65_536) {
                        std::thread::yield_now();
                    } else {
                        std::hint::spin_loop();
                    }
                }
                Next::AllMade => return,
            }
        }
    };
    let ((), grown) = crate::parallel::both(two_threads && levels > 1, offset_all, || {
        let grown = {
            // Every ring is made once this is dropped, on unwinding too: the second core, waiting
            // for more, never waits for rings that will not come.
            let _made = RingsMade(&middles);
            grow_rings(root, exact, w, levels, &middles)
        };
        // The middle rings still waiting, shared with the second core (which measured the
        // foot's narrow spot first).
        while let Next::Made = middles.offset_next(w) {}
        grown
    });
    grown?;
    add_middles(root, &mut middles.in_order().into_iter(), w, levels)
}

/// The middle rings of [`grow_on`]: the exact outlines of the rings made so far that wait for
/// their offset by half a bead, numbered in the order they were made, and the offsets made by
/// whichever core took them.
#[derive(Default)]
struct Middles {
    waiting: std::sync::Mutex<Waiting>,
    /// The middle rings made, each with its outline's number.
    made: std::sync::Mutex<Vec<(usize, MiddleRing)>>,
}

/// A ring's offset by half a bead (one ring or several, where it splits).
type MiddleRing = Result<Vec<Vec<DVec2>>, FillError>;

/// The outlines waiting in [`Middles`], numbered; how many were given; whether every ring is
/// made.
#[derive(Default)]
struct Waiting {
    outlines: std::collections::VecDeque<(usize, Polyline<f64>)>,
    given: usize,
    all_made: bool,
}

/// Says every ring is made ([`Middles::all_rings_made`]) when dropped.
struct RingsMade<'a>(&'a Middles);

impl Drop for RingsMade<'_> {
    fn drop(&mut self) {
        self.0.all_rings_made();
    }
}

/// What [`Middles::offset_next`] did.
enum Next {
    /// Offset a waiting outline.
    Made,
    /// Found none waiting: more rings are being made.
    Waiting,
    /// Found none waiting, and every ring is made.
    AllMade,
}

impl Middles {
    /// A ring's exact outline, to wait for its middle ring.
    fn give(&self, outline: Polyline<f64>) {
        let mut waiting = self.waiting.lock().unwrap_or_else(|e| e.into_inner());
        let k = waiting.given;
        waiting.outlines.push_back((k, outline));
        waiting.given += 1;
    }

    /// Every ring is made: no outline comes after those given.
    fn all_rings_made(&self) {
        self.waiting
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .all_made = true;
    }

    /// Offsets the first waiting outline by half of `w` (outside the lock).
    fn offset_next(&self, w: f64) -> Next {
        let next = {
            let mut waiting = self.waiting.lock().unwrap_or_else(|e| e.into_inner());
            match waiting.outlines.pop_front() {
                Some(next) => next,
                None if waiting.all_made => return Next::AllMade,
                None => return Next::Waiting,
            }
        };
        let middle = offset(&next.1, 0.5 * w);
        let mut made = self.made.lock().unwrap_or_else(|e| e.into_inner());
        made.push((next.0, middle));
        Next::Made
    }

    /// The middle rings in the order their outlines were given.
    fn in_order(self) -> Vec<MiddleRing> {
        let mut made = self.made.into_inner().unwrap_or_else(|e| e.into_inner());
        made.sort_unstable_by_key(|m| m.0);
        made.into_iter().map(|m| m.1).collect()
    }
}

/// The rings one level inside `node` (exactly `exact`), and theirs, `levels` deep; the exact
/// outline of each ring inside the foot goes to `middles` (depth first, a ring before those
/// inside it).
fn grow_rings(
    node: &mut Node,
    exact: &Polyline<f64>,
    w: f64,
    levels: usize,
    middles: &Middles,
) -> Result<(), FillError> {
    if levels == 0 {
        return Ok(());
    }
    if node.step > 0.0 {
        middles.give(exact.clone());
    }
    for (inner, ring) in offset_exact(exact, w)? {
        let mut child = Node {
            ring: Ring::new(ring),
            step: w,
            children: Vec::new(),
        };
        grow_rings(&mut child, &inner, w, levels - 1, middles)?;
        node.children.push(child);
    }
    Ok(())
}

/// Puts in the middle rings (`middles`: the offsets by w/2 in [`grow_rings`]' order) of each ring
/// still wider than a bead where no deeper ring reaches (not inside the foot itself: there the
/// outline's own bead covers the first half bead).
fn add_middles(
    node: &mut Node,
    middles: &mut impl Iterator<Item = Result<Vec<Vec<DVec2>>, FillError>>,
    w: f64,
    levels: usize,
) -> Result<(), FillError> {
    if levels == 0 {
        return Ok(());
    }
    let mine = if node.step > 0.0 {
        middles.next().ok_or(FillError::Offset)??
    } else {
        Vec::new()
    };
    for child in &mut node.children {
        add_middles(child, middles, w, levels - 1)?;
    }
    for half in mine {
        let covered = node
            .children
            .iter()
            .any(|c| c.step == w && crate::geometry::contains_point(&half, c.ring.pts[0]));
        if !covered {
            node.children.push(Node {
                ring: Ring::new(half),
                step: 0.5 * w,
                children: Vec::new(),
            });
        }
    }
    Ok(())
}

/// Turns the rings so that each runs opposite to its parent (the foot anticlockwise): where two
/// rings face each other across a bridge they then run in opposite directions.
fn orient(node: &mut Node, anticlockwise: bool, w: f64) {
    if (crate::geometry::signed_area(&node.ring.pts) > 0.0) != anticlockwise {
        node.ring = Ring::new(facing(std::mem::take(&mut node.ring.pts), anticlockwise));
    }
    if node.step > 0.0 {
        node.ring.spurs = corner_spurs(&node.ring, anticlockwise, node.step, w);
    }
    for child in &mut node.children {
        orient(child, !anticlockwise, w);
    }
}

/// The ring `pts` running anticlockwise or clockwise as asked, from the same first point.
fn facing(mut pts: Vec<DVec2>, anticlockwise: bool) -> Vec<DVec2> {
    if (crate::geometry::signed_area(&pts) > 0.0) != anticlockwise {
        pts.reverse();
        pts.rotate_right(1);
    }
    pts
}

/// Leaves out the spurs that would cross a ring (on a jagged foot a corner's bisector can run
/// into the ring's own next corner, or into a ring around or inside it).
fn prune_spurs(root: &mut Node) {
    fn segments(node: &Node, out: &mut Vec<(DVec2, DVec2)>) {
        let (pts, n) = (&node.ring.pts, node.ring.pts.len());
        out.extend((0..n).map(|k| (pts[k], pts[(k + 1) % n])));
        for c in &node.children {
            segments(c, out);
        }
    }
    fn prune(node: &mut Node, all: &[(DVec2, DVec2)]) {
        let pts = &node.ring.pts;
        node.ring.spurs.retain(|&(i, tip)| {
            let base = pts[i];
            // A segment whose box stays clear of the spur's (with a margin far above the
            // test's rounding) cannot touch it: most are passed over without the test.
            let (lo, hi) = (base.min(tip) - 1e-6, base.max(tip) + 1e-6);
            all.iter().all(|&(a, b)| {
                a == base
                    || b == base
                    || a.max(b).cmplt(lo).any()
                    || a.min(b).cmpgt(hi).any()
                    || !crate::geometry::segments_intersect(base, tip, a, b)
            })
        });
        for c in &mut node.children {
            prune(c, all);
        }
    }
    let mut all = Vec::new();
    segments(root, &mut all);
    prune(root, &all);
}

/// Turns of at least this much within half a bead of ring make a sharp corner (radians; an
/// interior angle under 100°).
const SHARP_TURN: f64 = 80.0 * std::f64::consts::PI / 180.0;

/// The share of a corner's gap a spur reaches into (see [`corner_spurs`]): with 0.6, a deep
/// star's points are neither left bare nor doubled past the bounds.
const SPUR_REACH: f64 = 0.6;

/// Spurs into sharp corners. At a convex corner of interior angle θ a ring lying `step` inside
/// the ring around it has its corner `step / s` from the outer corner along the bisector
/// (s = sin(θ/2)); the outer bead covers `(w/2) / s` of that and this ring's bead `w/2`, so a
/// spur of length `(step − w/2)/s − w/2` out along the bisector (and back) closes the gap.
fn corner_spurs(ring: &Ring, anticlockwise: bool, step: f64, w: f64) -> Vec<(usize, DVec2)> {
    let (pts, n) = (&ring.pts, ring.pts.len());
    let sign = if anticlockwise { 1.0 } else { -1.0 };
    let dir = |i: usize| (pts[(i + 1) % n] - pts[i]).normalize_or_zero();
    // Convex turn at each vertex (positive toward the ring's inside).
    let turn: Vec<f64> = (0..n)
        .map(|i| {
            let (a, b) = (dir((i + n - 1) % n), dir(i));
            sign * a.perp_dot(b).atan2(a.dot(b))
        })
        .collect();
    let mut spurs = Vec::new();
    for i in 0..n {
        if turn[i] <= 0.0 {
            continue;
        }
        // The vertices within half a bead on either side that turn the same way.
        let (mut lo, mut hi, mut total) = (i, i, turn[i]);
        let mut is_peak = true;
        for k in 1..n / 2 {
            let j = (i + n - k) % n;
            if ring.pts[j].distance(pts[i]) > 0.5 * w || turn[j] <= 0.0 {
                break;
            }
            is_peak &= turn[j] < turn[i];
            total += turn[j];
            lo = j;
        }
        for k in 1..n / 2 {
            let j = (i + k) % n;
            if ring.pts[j].distance(pts[i]) > 0.5 * w || turn[j] <= 0.0 {
                break;
            }
            is_peak &= turn[j] <= turn[i];
            total += turn[j];
            hi = j;
        }
        // Past 150° the ring turns back on itself (the end of a thin ring), not into a corner.
        if !is_peak || !(SHARP_TURN..=150f64.to_radians()).contains(&total) {
            continue;
        }
        let s = (0.5 * total).cos();
        // Part of the gap only: near its far end the outer bead's sides close in, and a spur
        // all the way would lay a second bead over them. At most a bead long.
        let length = (SPUR_REACH * ((step - 0.5 * w) / s - 0.5 * w)).min(w);
        if length <= 0.1 * w {
            continue;
        }
        let (u_in, u_out) = (dir((lo + n - 1) % n), dir(hi));
        let out = (u_in - u_out).normalize_or_zero();
        if out != DVec2::ZERO {
            spurs.push((i, pts[i] + out * length));
        }
    }
    spurs
}

/// The part of a child ring a bridge leaves out, in beads: half a bead, so that the parent's
/// gap is short enough for the layer above to rest on the bridge's two steps (a point over the
/// middle of the gap lies a quarter bead from them).
const BRIDGE_GAP_BEADS: f64 = 0.5;
/// The part of a ring inside the outline a bridge from the outline leaves out, in beads. That
/// bridge steps back out to where it stepped in (the outline is laid all round: the wall rests
/// on it), so its two steps meet on the outline; a whole bead apart on the ring inside, they
/// spread rather than lie on each other (on the six-point star of the tests: 4.95 % of the foot
/// laid twice, against 5.06 % with half a bead; 4.98 % with the outline's gap of before).
const OUTLINE_BRIDGE_GAP_BEADS: f64 = 1.0;

/// Where a child is entered and left: arc lengths on the parent (`s_in < s_out`, relative to
/// where the parent's walk starts) and the entry on the child.
#[derive(Debug, Clone, Copy)]
struct Bridge {
    s_in: f64,
    s_out: f64,
    child_entry: f64,
}

/// The bridge into `child` entered at `e` (arc length on the child), seen from `parent`'s walk
/// that starts at `start`: `None` when the two steps land in the wrong order.
fn bridge_at(parent: &Ring, child: &Ring, start: f64, e: f64, w: f64) -> Option<Bridge> {
    let len = parent.len();
    let (s_e, _) = parent.nearest(child.at(e));
    let (s_x, _) = parent.nearest(child.at(e - BRIDGE_GAP_BEADS * w));
    let s_in = (s_e - start).rem_euclid(len);
    let mut s_out = (s_x - start).rem_euclid(len);
    if s_out < s_in && s_in - s_out > 0.5 * len {
        s_out += len;
    }
    (s_out > s_in).then_some(Bridge {
        s_in,
        s_out,
        child_entry: e,
    })
}

/// Places the bridges of `node`'s children on its walk of `span` (arc lengths `0 ..= span`
/// after `start`): a bead apart and a bead from the walk's ends, each where the parent's gap is
/// closest to the child's (candidate entries every half bead round the child). With
/// `late`, among gaps within a quarter bead of the best the one latest on the walk is taken: on
/// the outline, the wall's first revolution rises from the minimum layer height to a full layer,
/// and rests on the bridge's steps best where it is thickest.
fn bridges(node: &Node, start: f64, span: f64, w: f64, late: bool) -> Vec<(Bridge, usize)> {
    let mut taken: Vec<(f64, f64)> = Vec::new();
    let mut out = Vec::new();
    let want = BRIDGE_GAP_BEADS * w;
    for (c, child) in node.children.iter().enumerate() {
        let clen = child.ring.len();
        let steps = ((clen / (0.5 * w)).ceil() as usize).max(1);
        let mut fits: Vec<(f64, Bridge)> = Vec::new();
        for k in 0..steps {
            let e = k as f64 * clen / steps as f64;
            let Some(b) = bridge_at(&node.ring, &child.ring, start, e, w) else {
                continue;
            };
            let (lo, hi) = (b.s_in - 0.5 * w, b.s_out + 0.5 * w);
            if lo < w || hi > span - w || !taken.iter().all(|&(x, y)| hi < x || lo > y) {
                continue;
            }
            let misfit = ((b.s_out - b.s_in) - want).abs();
            fits.push((misfit, b));
            // Inside, the first close fit will do (each candidate costs two nearest-point
            // searches round the parent).
            if !late && misfit <= 0.1 * w {
                break;
            }
        }
        let least = fits.iter().map(|f| f.0).fold(f64::INFINITY, f64::min);
        let pick = if late {
            fits.iter()
                .filter(|f| f.0 <= least + 0.25 * w)
                .max_by(|a, b| a.1.s_in.total_cmp(&b.1.s_in))
        } else {
            fits.iter().find(|f| f.0 <= least + 1e-9)
        };
        // No room anywhere (a ring crowded by its siblings' bridges): it is left out.
        let Some(&(_, b)) = pick else { continue };
        taken.push((b.s_in - 0.5 * w, b.s_out + 0.5 * w));
        out.push((b, c));
    }
    out.sort_by(|a, b| a.0.s_in.total_cmp(&b.0.s_in));
    out
}

/// Where a ring's children are entered ([`bridges`]), and, as far as planned, where theirs
/// are (by child): chosen once on the first base layer's rings so that every layer's bridges
/// stack.
#[derive(Debug, Clone, Default)]
struct Entries {
    here: Vec<(Bridge, usize)>,
    below: Vec<Option<Entries>>,
}

/// The bridges of `node`'s walk from `start` over `span` ([`bridges`]; `late` on the outline),
/// and those of its children's walks `depth` levels further down, as [`walk_node`] walks them
/// under `whole_levels` rings laid all round.
fn plan_entries(
    node: &Node,
    start: f64,
    span: f64,
    w: f64,
    late: bool,
    depth: usize,
    whole_levels: usize,
) -> Entries {
    let here = bridges(node, start, span, w, late);
    let mut below = vec![None; node.children.len()];
    if depth > 0 {
        for &(bridge, c) in &here {
            let child = &node.children[c];
            below[c] = Some(plan_entries(
                child,
                bridge.child_entry,
                child_span(&child.ring, w, whole_levels),
                w,
                false,
                depth - 1,
                whole_levels.saturating_sub(1),
            ));
        }
    }
    Entries { here, below }
}

/// `entries` (planned on `old`'s rings) for `new`, whose rings `depth` levels down are its own
/// (the rest `old`'s): each entry on a ring of its own moved to the point of that ring nearest
/// the planned one.
fn remap_entries(entries: &Entries, old: &Node, new: &Node, depth: usize) -> Entries {
    let here = entries
        .here
        .iter()
        .map(|&(b, c)| {
            let entry = if depth > 0 {
                new.children[c]
                    .ring
                    .nearest(old.children[c].ring.at(b.child_entry))
                    .0
            } else {
                b.child_entry
            };
            (
                Bridge {
                    child_entry: entry,
                    ..b
                },
                c,
            )
        })
        .collect();
    let below = entries
        .below
        .iter()
        .enumerate()
        .map(|(c, e)| {
            let e = e.as_ref()?;
            Some(if depth > 1 {
                remap_entries(e, &old.children[c], &new.children[c], depth - 1)
            } else {
                e.clone()
            })
        })
        .collect();
    Entries { here, below }
}

/// The children of a ring whose own outline is now `exact` (a base layer's foot): `old`'s
/// children with each ring a bead in replaced by the same ring of `exact`'s offset, and so on
/// `levels` deep (below that, `old`'s rings, and `old`'s middle rings throughout). `None` where
/// the offsets do not pair one to one with `old`'s rings (a waist the layer's foot splits at
/// differently).
fn own_children(
    old: &Node,
    exact: &Polyline<f64>,
    w: f64,
    levels: usize,
    anticlockwise: bool,
) -> Option<Vec<Node>> {
    let own = offset_exact(exact, w).ok()?;
    let olds: Vec<usize> = (0..old.children.len())
        .filter(|&c| old.children[c].step == w)
        .collect();
    if own.len() != olds.len() {
        return None;
    }
    let centre = |pts: &[DVec2]| pts.iter().copied().sum::<DVec2>() / pts.len().max(1) as f64;
    let mut children = old.children.clone();
    let mut used = vec![false; own.len()];
    for &c in &olds {
        let at = centre(&old.children[c].ring.pts);
        let k = (0..own.len()).filter(|&k| !used[k]).min_by(|&a, &b| {
            centre(&own[a].1)
                .distance(at)
                .total_cmp(&centre(&own[b].1).distance(at))
        })?;
        used[k] = true;
        let (inner, pts) = own[k].clone();
        // Each ring runs opposite to the ring around it (see [`orient`]).
        let mut ring = Ring::new(facing(pts, !anticlockwise));
        ring.spurs = corner_spurs(&ring, !anticlockwise, w, w);
        let grandchildren = if levels > 1 {
            own_children(&old.children[c], &inner, w, levels - 1, !anticlockwise)?
        } else {
            old.children[c].children.clone()
        };
        children[c] = Node {
            ring,
            step: w,
            children: grandchildren,
        };
    }
    Some(children)
}

/// How far, in beads, a base layer's foot may lie from the first's before the rings under the
/// wall's inner beads follow each layer's own foot (see [`fill_feet_then`]).
const OWN_RINGS_DRIFT_BEADS: f64 = 0.25;

/// How much of `child` the walk of its parent lays (in arc length from its entry), the parent
/// under `whole_levels` rings laid all round: all of it where the child is laid all round too (a
/// ring under a bead of the wall is walked all the way round, back through the point it was
/// entered at, and half a bead on, so that the step back out does not run back down the step
/// in); else all but the gap its bridge leaves, a bead from the outline, half a bead inside.
fn child_span(child: &Ring, w: f64, whole_levels: usize) -> f64 {
    let clen = child.len();
    let gap = if whole_levels > 0 {
        OUTLINE_BRIDGE_GAP_BEADS
    } else {
        BRIDGE_GAP_BEADS
    };
    if whole_levels > 1 {
        clen
    } else {
        clen - (gap * w).min(0.5 * clen)
    }
}

/// Walks `node` from arc length `start` for `span`, visiting its children by their bridges
/// (`entries`: where to enter each child, and as far as planned each child's children, if
/// already chosen; else chosen here, level by level). While `whole_levels > 0`, each
/// bridge steps back out to where it stepped in, so that the ring is laid all round: the
/// outline's, on which the wall's first revolution (or the next base layer's outline, a
/// layer's height out on a wall flaring at 45°) rests, and the rings in under a wall's inner
/// beads. The two steps then meet there (a bead's sliver laid twice). The children are walked
/// with one level fewer.
fn walk_node(
    node: &Node,
    start: f64,
    span: f64,
    w: f64,
    entries: Option<&Entries>,
    whole_levels: usize,
    out: &mut Vec<DVec2>,
) {
    let whole = whole_levels > 0;
    out.push(node.ring.at(start));
    let mut at = 0.0;
    let placed = match entries {
        Some(e) => e
            .here
            .iter()
            .filter_map(|(b, c)| {
                bridge_at(&node.ring, &node.children[*c].ring, start, b.child_entry, w)
                    .map(|b| (b, *c))
            })
            .collect(),
        None => bridges(node, start, span, w, false),
    };
    for (bridge, c) in placed {
        if bridge.s_in < at {
            continue;
        }
        node.ring.walk(start + at, start + bridge.s_in, out);
        let child = &node.children[c];
        let clen = child.ring.len();
        walk_node(
            child,
            bridge.child_entry,
            child_span(&child.ring, w, whole_levels),
            w,
            entries.and_then(|e| e.below.get(c)?.as_ref()),
            whole_levels.saturating_sub(1),
            out,
        );
        if whole_levels > 1 {
            // Back at the entry: the very point the step in ended at (not its rounding once
            // round), so that the two meet there.
            if let Some(last) = out.last_mut() {
                *last = child.ring.at(bridge.child_entry);
            }
            let on = bridge.child_entry + clen;
            child
                .ring
                .walk(on, on + (BRIDGE_GAP_BEADS * w).min(0.5 * clen), out);
        }
        let back = if whole { bridge.s_in } else { bridge.s_out };
        out.push(node.ring.at(start + back));
        at = back;
    }
    node.ring.walk(start + at, start + span, out);
}

/// Foot outline points farther than a bead from the part of the foot a bead fits in (the foot
/// eroded by half a bead): there the foot is narrower than a bead.
///
/// A point with a segment of the eroded foot within the limit is not narrow, whichever segment
/// is nearest: the segments beside the one that settled the point before are tried first, and
/// only a point they do not settle is searched in full (on the benchmark vase's 720-point
/// foot, 0.85 → 0.05 ms; the same spot and count).
fn narrow_spot(foot: &[DVec2], eroded: &[Vec<DVec2>], w: f64) -> Option<NarrowSpot> {
    let rings: Vec<Ring> = eroded.iter().map(|l| Ring::new(l.clone())).collect();
    // A straight or gently curved wall lies w/2 from the eroded foot; a corner of angle θ
    // lies (w/2)/sin(θ/2): more than w only for corners sharper than about 60°, or where a
    // whole arm is missing from the eroded foot.
    let limit = w * 1.01;
    let mut spot: Option<NarrowSpot> = None;
    let mut count = 0;
    // The ring and segment that settled the point before.
    let mut settled: Option<(usize, usize)> = None;
    for &p in foot {
        if let Some((r, i)) = settled
            && let Some(i) = rings[r].segment_within(p, i, limit)
        {
            settled = Some((r, i));
            continue;
        }
        let (d, nearest) = rings
            .iter()
            .enumerate()
            .map(|(r, ring)| {
                let (_, d, i) = ring.nearest_segment(p);
                (d, (r, i))
            })
            .fold((f64::INFINITY, None), |best, (d, at)| {
                if d < best.0 { (d, Some(at)) } else { best }
            });
        settled = nearest.filter(|_| d <= limit);
        if d > limit {
            count += 1;
            if spot.is_none_or(|s| d > s.depth_mm) {
                spot = Some(NarrowSpot {
                    points: 0,
                    at: p,
                    depth_mm: d,
                });
            }
        }
    }
    spot.map(|s| NarrowSpot { points: count, ..s })
}

/// The base layer path of a foot (its outline anticlockwise, point 0 where the wall starts) for
/// beads `w` wide: starts and ends at `foot[0]` (see the module documentation).
pub fn fill_foot(foot: &[DVec2], w: f64) -> Result<BaseFill, FillError> {
    let mut fills = fill_feet(&[foot.to_vec()], w)?;
    Ok(fills.remove(0))
}

/// The paths of several base layers, one per foot (bottom up): the rings inside are those of the
/// first foot on every layer, so that each layer's beads lie on the beads below; only the
/// outline (and the bridge from it) follows each layer's own foot (and, under a wall of several
/// beads, the rings under its inner beads: see [`fill_feet_then`]).
pub fn fill_feet(feet: &[Vec<DVec2>], w: f64) -> Result<Vec<BaseFill>, FillError> {
    fill_feet_then(feet, w, 1, || ())
}

/// [`fill_feet`] under a wall of `walls` beads, calling `rings_made` once the rings are made,
/// before the bridges are laid: from there on the fill uses one core, so a caller can start
/// other work beside it.
///
/// The outline and the `walls − 1` rings inside it are laid all round (their bridges step back
/// out where they stepped in): the wall's first revolution rests its beads on them. The ring
/// inside the outline, left open a bead where the path comes back out of it, had nothing under
/// the inner bead there but the two steps, which leaned it past the limit (found by the checker
/// on 14 of 450 random designs with two beads on one base layer, 47–57°).
pub fn fill_feet_then(
    feet: &[Vec<DVec2>],
    w: f64,
    walls: usize,
    rings_made: impl FnOnce(),
) -> Result<Vec<BaseFill>, FillError> {
    let Some(first) = feet.first() else {
        return Ok(Vec::new());
    };
    if feet.iter().any(|f| f.len() < 3) || w.is_nan() || w <= 0.0 {
        return Err(FillError::NarrowerThanABead);
    }
    // Where the foot is narrower than a bead: measured on the second core while this one makes
    // the rings (its error comes first, as if run first).
    let narrowness = || -> Result<Option<NarrowSpot>, FillError> {
        let eroded = offset(&polyline(first), 0.5 * w)?;
        if eroded.is_empty() {
            return Err(FillError::NarrowerThanABead);
        }
        Ok(narrow_spot(first, &eroded, w))
    };
    let mut measured = None;
    let tree = ring_tree(first, w, rings_made, || measured = Some(narrowness()));
    let narrow = measured.unwrap_or_else(narrowness)?;
    let inner = tree?;
    // The bridges from the outline are placed on the first foot and entered at the same points
    // of the inner rings on every layer, so that the layers' bridges stack.
    let first_root = Node {
        ring: Ring::new(first.clone()),
        step: 0.0,
        children: inner.children.clone(),
    };
    // Under a wall of several beads on a foot that flares (or draws in) over the base, the rings
    // its inner beads rest on follow each layer's own foot: the first foot's lay up to a bead
    // inside the top layer's outline, and the first revolution's inner bead crossed the gap
    // (random designs; the flared bowl with two beads on three base layers: 351 points a layer
    // too thick). A layer's own ring moves from the one below as its outline does, by at most
    // the overhang limit; the rings further in are the first foot's on every layer.
    // Only where the feet grow: where one draws in by half a bead, its own rings would crowd
    // the first foot's further in (the first foot's rings then carry the beads anyway).
    let levels = walls.max(1) - 1;
    let drifts = levels > 0 && {
        let drift = |p: DVec2| {
            let d = first_root.ring.nearest(p).1;
            if d > 0.5 * w && crate::geometry::contains_point(first, p) {
                -d
            } else {
                d
            }
        };
        let (mut out, mut inward) = (false, false);
        for &p in feet[1..].iter().flatten() {
            let d = drift(p);
            out |= d > OWN_RINGS_DRIFT_BEADS * w;
            inward |= d < -0.5 * w;
        }
        out && !inward
    };
    let own_levels = if drifts { levels } else { 0 };
    let entries = plan_entries(
        &first_root,
        0.0,
        first_root.ring.len(),
        w,
        true,
        own_levels,
        walls.max(1),
    );
    // Each layer's walk (0.3 ms for the benchmark vase's foot), one layer per core.
    Ok(crate::parallel::map_ranges(feet.len(), 2, |layers| {
        layers
            .map(|m| {
                let foot = &feet[m];
                let own = (own_levels > 0 && m > 0)
                    .then(|| own_children(&first_root, &polyline(foot), w, own_levels, true))
                    .flatten();
                let mut root = Node {
                    ring: Ring::new(foot.clone()),
                    step: 0.0,
                    children: Vec::new(),
                };
                let plan = match own {
                    Some(children) => {
                        root.children = children;
                        prune_spurs(&mut root);
                        remap_entries(&entries, &first_root, &root, own_levels)
                    }
                    None => {
                        root.children = inner.children.clone();
                        entries.clone()
                    }
                };
                let mut path = Vec::new();
                walk_node(
                    &root,
                    0.0,
                    root.ring.len(),
                    w,
                    Some(&plan),
                    walls.max(1),
                    &mut path,
                );
                path.dedup_by(|a, b| a.distance(*b) < 1e-9);
                BaseFill { path, narrow }
            })
            .collect()
    }))
}

/// How evenly a base layer covers its foot, measured on a raster (cells `cell` mm wide): the
/// number of passes of a bead `w` wide over each cell inside the foot (a pass: the path coming
/// within w/2 of the cell centre; running on along the path within 1.5 w counts as the same
/// pass). With one layer's thickness per pass, a cell with no pass is under half the layer
/// height and one with two or more is over 1.6 times it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Coverage {
    /// Share of the foot's area with no bead.
    pub uncovered: f64,
    /// Share of the foot's area with two or more beads.
    pub doubled: f64,
}

/// The [`Coverage`] of `path` over `foot` (see there).
pub fn coverage(path: &[DVec2], foot: &[DVec2], w: f64, cell: f64) -> Coverage {
    let (lo, hi) = crate::geometry::bounds(foot.iter().copied());
    let (lo, hi) = (lo - w, hi + w);
    let nx = ((hi.x - lo.x) / cell).ceil() as usize;
    let ny = ((hi.y - lo.y) / cell).ceil() as usize;
    let mut passes = vec![0u16; nx * ny];
    let mut last = vec![f64::NEG_INFINITY; nx * ny];
    let r = 0.5 * w;
    let mut s = 0.0;
    for seg in path.windows(2) {
        let (a, b) = (seg[0], seg[1]);
        let len = a.distance(b);
        let (x0, x1) = (
            ((a.x.min(b.x) - r - lo.x) / cell).floor().max(0.0) as usize,
            (((a.x.max(b.x) + r - lo.x) / cell).ceil() as usize).min(nx),
        );
        let (y0, y1) = (
            ((a.y.min(b.y) - r - lo.y) / cell).floor().max(0.0) as usize,
            (((a.y.max(b.y) + r - lo.y) / cell).ceil() as usize).min(ny),
        );
        for y in y0..y1 {
            for x in x0..x1 {
                let c = lo + DVec2::new((x as f64 + 0.5) * cell, (y as f64 + 0.5) * cell);
                let (d, f) = crate::geometry::point_segment_distance(c, a, b);
                if d <= r {
                    let at = s + f * len;
                    let k = y * nx + x;
                    if at - last[k] > 1.5 * w {
                        passes[k] = passes[k].saturating_add(1);
                    }
                    last[k] = at;
                }
            }
        }
        s += len;
    }
    let (mut inside, mut none, mut two) = (0usize, 0usize, 0usize);
    for y in 0..ny {
        for x in 0..nx {
            let c = lo + DVec2::new((x as f64 + 0.5) * cell, (y as f64 + 0.5) * cell);
            if crate::geometry::contains_point(foot, c) {
                inside += 1;
                match passes[y * nx + x] {
                    0 => none += 1,
                    1 => {}
                    _ => two += 1,
                }
            }
        }
    }
    let inside = inside.max(1) as f64;
    Coverage {
        uncovered: none as f64 / inside,
        doubled: two as f64 / inside,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::TAU;

    const W: f64 = 1.2;

    use crate::contour::polar;

    /// The closed polygon with corners `c`, resampled at `n` points (point 0 at the first).
    fn polygon(c: &[(f64, f64)], n: usize) -> Vec<DVec2> {
        let pts: Vec<DVec2> = c.iter().map(|&(x, y)| DVec2::new(x, y)).collect();
        crate::geometry::resample_closed(&pts, n)
    }

    /// The first two non-adjacent segments of a path that cross (touching at a shared point,
    /// a spur's foot, does not count).
    pub(super) fn first_crossing(p: &[DVec2]) -> Option<(usize, usize)> {
        let segs: Vec<(DVec2, DVec2)> = p.windows(2).map(|s| (s[0], s[1])).collect();
        let mut grid: std::collections::HashMap<(i64, i64), Vec<usize>> = Default::default();
        for (i, (a, b)) in segs.iter().enumerate() {
            let key = |q: DVec2| ((q.x / 3.0).floor() as i64, (q.y / 3.0).floor() as i64);
            let (ka, kb) = (key(a.min(*b)), key(a.max(*b)));
            for x in ka.0..=kb.0 {
                for y in ka.1..=kb.1 {
                    grid.entry((x, y)).or_default().push(i);
                }
            }
        }
        for ids in grid.values() {
            for (m, &i) in ids.iter().enumerate() {
                for &j in &ids[m + 1..] {
                    let (a, b) = segs[i];
                    let (c, d) = segs[j];
                    let touch = [a, b].iter().any(|p| *p == c || *p == d);
                    if j > i + 1
                        && !(i == 0 && j == segs.len() - 1)
                        && !touch
                        && crate::geometry::segments_intersect(a, b, c, d)
                    {
                        return Some((i, j));
                    }
                }
            }
        }
        None
    }

    /// Fills a foot and checks the path: continuous (no step longer than two beads), from and
    /// to point 0, never crossing itself, covering the foot within the bounds.
    fn check(name: &str, foot: &[DVec2]) -> BaseFill {
        let fill = fill_foot(foot, W).unwrap();
        let p = &fill.path;
        assert!(
            p[0].distance(foot[0]) < 1e-9 && p[p.len() - 1].distance(foot[0]) < 1e-9,
            "{name}"
        );
        let longest = p
            .windows(2)
            .map(|s| s[0].distance(s[1]))
            .fold(0.0, f64::max);
        let outline_step = foot
            .windows(2)
            .map(|s| s[0].distance(s[1]))
            .fold(0.0, f64::max);
        assert!(
            longest < (2.0 * W).max(outline_step * 1.01),
            "{name}: a jump of {longest} mm"
        );
        // No two non-adjacent segments cross (the bridges step between rings, never over one).
        if let Some((i, j)) = first_crossing(p) {
            panic!("{name}: segments {i} and {j} cross");
        }
        // The outline is laid all round (the wall rests on it): no bridge's notch in it. With
        // the notch of before, a point in its middle lay a quarter bead from the path.
        let along = crate::geometry::cumulative_length(foot);
        for (k, q) in foot.iter().enumerate() {
            let next = foot[(k + 1) % foot.len()];
            for f in [0.0, 0.25, 0.5, 0.75] {
                let spot = q.lerp(next, f);
                let off = p
                    .windows(2)
                    .map(|s| crate::geometry::point_segment_distance(spot, s[0], s[1]).0)
                    .fold(f64::INFINITY, f64::min);
                assert!(
                    off < W / 8.0,
                    "{name}: the outline is not laid {off} mm from {spot} ({} mm along it)",
                    along[k]
                );
            }
        }
        let cov = coverage(p, foot, W, W / 8.0);
        eprintln!(
            "{name}: {} points, uncovered {:.2} %, doubled {:.2} %",
            p.len(),
            cov.uncovered * 100.0,
            cov.doubled * 100.0
        );
        assert!(
            cov.uncovered < 0.02,
            "{name}: {:.2} % uncovered",
            cov.uncovered * 100.0
        );
        assert!(
            cov.doubled < 0.05,
            "{name}: {:.2} % doubled",
            cov.doubled * 100.0
        );
        fill
    }

    #[test]
    fn circle_and_ellipse() {
        let f = check("circle", &polar(360, |_| 30.0));
        assert!(f.narrow.is_none());
        let e: Vec<DVec2> = polar(360, |_| 1.0)
            .iter()
            .map(|p| DVec2::new(40.0 * p.x, 22.0 * p.y))
            .collect();
        check("ellipse", &e);
    }

    /// The ring tree grown with the middle rings on a second thread is the one grown on one.
    #[test]
    fn the_ring_tree_does_not_depend_on_the_threads() {
        let rose: Vec<DVec2> = (0..360)
            .map(|i| {
                let t = std::f64::consts::TAU * i as f64 / 360.0;
                DVec2::from_angle(t) * (40.0 + 4.0 * (6.0 * t).cos())
            })
            .collect();
        let waist = polygon(
            &[
                (0.0, 0.0),
                (40.0, 0.0),
                (40.0, 30.0),
                (22.0, 30.0),
                (22.0, 8.0),
                (18.0, 8.0),
                (18.0, 30.0),
                (0.0, 30.0),
            ],
            240,
        );
        for foot in [rose, waist] {
            let levels = ring_levels(&foot, 3.0);
            // `beside` held for a while, the middle rings are mostly taken by this core, once
            // its rings are made: in between, by both.
            let grown = |two, hold_us: u64| {
                let mut root = Node {
                    ring: Ring::new(foot.clone()),
                    step: 0.0,
                    children: Vec::new(),
                };
                let hold = || {
                    let start = std::time::Instant::now();
                    while start.elapsed() < std::time::Duration::from_micros(hold_us) {
                        std::hint::spin_loop();
                    }
                };
                grow_on(&mut root, &polyline(&foot), 3.0, levels, two, hold).unwrap();
                format!("{root:?}")
            };
            let one = grown(false, 0);
            for hold_us in [0, 200, 2_000, 20_000] {
                assert_eq!(grown(true, hold_us), one, "{hold_us} µs");
            }
        }
    }

    /// A six-point star of outer radius 50 mm and inner radius `inner`, as `n` points.
    fn six_point_star(inner: f64, n: usize) -> Vec<DVec2> {
        let corners: Vec<DVec2> = (0..12)
            .map(|i| {
                DVec2::from_angle(TAU * i as f64 / 12.0) * if i % 2 == 0 { 50.0 } else { inner }
            })
            .collect();
        crate::geometry::resample_closed(&corners, n)
    }

    #[test]
    fn deep_star() {
        // Six points, outer radius 50, inner 22 (the star): not scaled copies.
        check("star", &six_point_star(22.0, 720));
    }

    /// Under a wall of two beads the ring a bead in is laid all the way round, like the
    /// outline: the inner bead rests on it (a ring left open a bead where its bridge leaves it
    /// leaned the inner bead 48° at the gap). Under one bead it is left open there.
    #[test]
    fn the_rings_under_a_wall_s_beads_are_laid_all_round() {
        let star = six_point_star(30.0, 360);
        let ring = inward_offset(&star, W).expect("one ring a bead in");
        let ring = crate::geometry::resample_closed(&ring, 4000); // every 0.06 bead
        // How far the ring's points lie from the path at most.
        let farthest = |path: &[DVec2]| {
            ring.iter()
                .map(|&q| {
                    path.windows(2)
                        .map(|s| crate::geometry::point_segment_distance(q, s[0], s[1]).0)
                        .fold(f64::INFINITY, f64::min)
                })
                .fold(0.0, f64::max)
        };
        let fill = |walls| fill_feet_then(&[star.clone(), star.clone()], W, walls, || ()).unwrap();
        // The steps onto the ring and back off it meet on it, touching, not crossing (the
        // ring is laid twice from its entry for half a bead).
        let crosses = |p: &[DVec2]| {
            let segs: Vec<(DVec2, DVec2)> = p.windows(2).map(|s| (s[0], s[1])).collect();
            segs.iter().enumerate().any(|(i, &(a, b))| {
                segs[(i + 2).min(segs.len())..]
                    .iter()
                    .any(|&(c, d)| crate::geometry::proper_crossing(a, b, c, d).is_some())
            })
        };
        for layer in fill(2) {
            assert!(
                farthest(&layer.path) < 0.01 * W,
                "{}",
                farthest(&layer.path)
            );
            assert!(!crosses(&layer.path));
        }
        // One bead: the ring's gap is a bead long, its middle half a bead from the steps.
        let gap = farthest(&fill(1)[0].path);
        assert!(gap > 0.3 * W, "{gap}");
    }

    /// Under a wall of two beads on a star foot that flares 0.3 bead a layer over three base
    /// layers, each layer lays the ring a bead inside its own outline all round (where the
    /// wall's inner bead will rest), not the first foot's, which lies 0.6 bead further in on the
    /// top layer; the rings further in are the first foot's on every layer, so they stack. Under
    /// one bead, or on a foot that does not move or draws in, every layer's rings are the first
    /// foot's.
    #[test]
    fn under_two_beads_the_ring_a_bead_in_follows_each_layer_s_foot() {
        let feet: Vec<Vec<DVec2>> = (0..3)
            .map(|m| six_point_star(30.0 + 0.3 * W * m as f64, 360))
            .collect();
        // How far the points of `ring` (resampled every 0.06 bead) lie from `path` at most.
        let farthest = |ring: &[DVec2], path: &[DVec2]| {
            crate::geometry::resample_closed(ring, 4000)
                .iter()
                .map(|&q| {
                    path.windows(2)
                        .map(|s| crate::geometry::point_segment_distance(q, s[0], s[1]).0)
                        .fold(f64::INFINITY, f64::min)
                })
                .fold(0.0, f64::max)
        };
        let a_bead_in = |foot: &[DVec2]| inward_offset(foot, W).expect("a ring a bead in");
        let two_in = inward_offset(&feet[0], 2.0 * W).expect("a ring two beads in");
        let two = fill_feet_then(&feet, W, 2, || ()).unwrap();
        for (m, layer) in two.iter().enumerate() {
            let own = farthest(&a_bead_in(&feet[m]), &layer.path);
            assert!(
                own < 0.01 * W,
                "layer {m}: its own ring {own} mm from the path"
            );
            let deeper = farthest(&two_in, &layer.path);
            // (Left open for half a bead where its bridge leaves it.)
            assert!(
                deeper < 0.5 * W,
                "layer {m}: the ring two in {deeper} mm off"
            );
        }
        let first = farthest(&a_bead_in(&feet[0]), &two[2].path);
        assert!(
            first > 0.3 * W,
            "the first foot's ring is laid on the top layer: {first}"
        );
        // A foot drawing in (0.3 bead a layer: the first foot's ring a bead in still carries
        // the inner bead) keeps the first foot's rings too.
        let drawing_in: Vec<Vec<DVec2>> = (0..3)
            .map(|m| six_point_star(30.0 - 0.3 * W * m as f64, 360))
            .collect();
        for layers in [
            fill_feet_then(&feet, W, 1, || ()).unwrap(),
            fill_feet_then(&vec![feet[0].clone(); 3], W, 2, || ()).unwrap(),
            fill_feet_then(&drawing_in, W, 2, || ()).unwrap(),
        ] {
            let first = farthest(&a_bead_in(&feet[0]), &layers[2].path);
            assert!(first < 0.6 * W, "{first}");
        }
    }

    #[test]
    fn l_shape_and_kidney() {
        let l = polygon(
            &[
                (0.0, 0.0),
                (80.0, 0.0),
                (80.0, 30.0),
                (30.0, 30.0),
                (30.0, 70.0),
                (0.0, 70.0),
            ],
            720,
        );
        check("L", &l);
        // A kidney: a circle pushed in on one side (not star-shaped around its x-extremes midpoint).
        let kidney = polar(720, |a| {
            30.0 * (1.0 - 0.55 * (-(a - TAU / 4.0).powi(2) / 0.18).exp()) + 8.0 * a.cos().powi(2)
        });
        check("kidney", &kidney);
    }

    #[test]
    fn a_waist_splits_the_rings_and_both_lobes_are_filled() {
        // Two discs joined by a neck 6 mm wide: the offsets split into two lobes.
        let mut pts = Vec::new();
        for i in 0..720 {
            let a = TAU * i as f64 / 720.0;
            let r = 25.0;
            let (x, y) = (
                45.0 * a.cos(),
                r * a.sin() * (0.12 + 0.88 * (1.0 - (-(a.cos() * 3.0).powi(2)).exp())),
            );
            pts.push(DVec2::new(x, y));
        }
        let tree = ring_tree(&pts, W, || (), || ()).unwrap();
        fn splits(n: &Node) -> bool {
            n.children.len() >= 2 || n.children.iter().any(splits)
        }
        assert!(splits(&tree), "the dumbbell's rings split into two lobes");
        check("dumbbell", &pts);
    }

    #[test]
    fn a_foot_narrower_than_a_bead_is_refused_and_a_thin_arm_is_reported() {
        let sliver = polygon(&[(0.0, 0.0), (50.0, 0.0), (50.0, 0.8), (0.0, 0.8)], 200);
        assert_eq!(fill_foot(&sliver, W), Err(FillError::NarrowerThanABead));
        // A disc with a 0.8 mm wide arm sticking out 15 mm.
        let arm = polygon(
            &[
                (0.0, 0.0),
                (20.0, 0.0),
                (20.0, 0.4),
                (35.0, 0.4),
                (35.0, 1.2),
                (20.0, 1.2),
                (20.0, 20.0),
                (0.0, 20.0),
            ],
            720,
        );
        let f = fill_foot(&arm, W).unwrap();
        let spot = f.narrow.expect("the arm is narrower than a bead");
        assert!(spot.at.x > 22.0 && spot.at.y < 2.0, "{spot:?}");
    }
}

#[cfg(test)]
mod properties {
    use super::*;
    use proptest::prelude::*;

    /// A foot with radius `radii[i]` at the i-th of as many equal angles.
    fn jagged(radii: &[f64]) -> Vec<DVec2> {
        let n = radii.len();
        radii
            .iter()
            .enumerate()
            .map(|(i, r)| DVec2::from_angle(std::f64::consts::TAU * i as f64 / n as f64) * *r)
            .collect()
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(40))]

        /// The pruned search finds what the plain scan of every segment finds, to the bit,
        /// on jagged rings (with repeated points) and points inside, outside and on them; rings
        /// of up to ten groups of boxes.
        #[test]
        fn the_nearest_ring_point_is_the_plain_scans(
            radii in proptest::collection::vec(0.0..50.0f64, 3..640),
            probes in proptest::collection::vec((-60.0..60.0f64, -60.0..60.0f64), 1..40),
            on in 0usize..200,
        ) {
            let n = radii.len();
            let mut pts: Vec<DVec2> = radii
                .iter()
                .enumerate()
                .map(|(i, r)| DVec2::from_angle(std::f64::consts::TAU * i as f64 / n as f64) * *r)
                .collect();
            if n > 4 {
                pts[n / 2] = pts[n / 2 - 1];
            }
            let ring = Ring::new(pts.clone());
            let scan = |p: DVec2| {
                let mut best = (0.0, f64::INFINITY);
                for i in 0..n {
                    let (d, f) =
                        crate::geometry::point_segment_distance(p, pts[i], pts[(i + 1) % n]);
                    if d < best.1 {
                        best = (ring.cum[i] + f * (ring.cum[i + 1] - ring.cum[i]), d);
                    }
                }
                best
            };
            let mut points: Vec<DVec2> = probes.iter().map(|&(x, y)| DVec2::new(x, y)).collect();
            points.push(pts[on % n]);
            points.push(pts[on % n].lerp(pts[(on + 1) % n], 0.5));
            for p in points {
                let (a, b) = (ring.nearest(p), scan(p));
                prop_assert!(a.0.to_bits() == b.0.to_bits() && a.1.to_bits() == b.1.to_bits(), "{p}: {a:?} against {b:?}");
            }
        }
        /// The narrow spot found with the segments beside the last point's tried first is the
        /// one every point searched in full gives (its place, depth and count, to the bit), on
        /// jagged feet with narrow arms and the feet eroded to one ring or several.
        #[test]
        fn the_narrow_spot_is_the_full_searchs(
            radii in proptest::collection::vec(1.0..40.0f64, 12..400),
            w in 0.8..6.0f64,
        ) {
            let foot = jagged(&radii);
            let Ok(eroded) = offset(&polyline(&foot), 0.5 * w) else {
                return Ok(());
            };
            let full = |foot: &[DVec2]| {
                let rings: Vec<Ring> = eroded.iter().map(|l| Ring::new(l.clone())).collect();
                let (mut spot, mut count): (Option<NarrowSpot>, usize) = (None, 0);
                for &p in foot {
                    let d = rings.iter().map(|r| r.nearest(p).1).fold(f64::INFINITY, f64::min);
                    if d > w * 1.01 {
                        count += 1;
                        if spot.is_none_or(|s| d > s.depth_mm) {
                            spot = Some(NarrowSpot { points: 0, at: p, depth_mm: d });
                        }
                    }
                }
                spot.map(|s| NarrowSpot { points: count, ..s })
            };
            let (a, b) = (narrow_spot(&foot, &eroded, w), full(&foot));
            prop_assert_eq!(a.map(|s| (s.points, s.at.to_array().map(f64::to_bits), s.depth_mm.to_bits())),
                b.map(|s| (s.points, s.at.to_array().map(f64::to_bits), s.depth_mm.to_bits())));
        }

        /// Jagged feet (random radius at every vertex, like a noisy tracing or a hand-drawn
        /// splodge) and bead widths: never a panic; either a refusal or one path from and to
        /// point 0 with no step longer than a bridge.
        #[test]
        fn any_jagged_foot_fills_in_one_path_or_is_refused(
            radii in proptest::collection::vec(5.0..50.0f64, 12..240),
            w in 0.8..5.0f64,
        ) {
            let foot = jagged(&radii);
            if let Ok(fill) = fill_foot(&foot, w) {
                let p = &fill.path;
                prop_assert!(p[0].distance(foot[0]) < 1e-9);
                prop_assert!(p[p.len() - 1].distance(foot[0]) < 1e-9);
                let outline = foot
                    .iter()
                    .zip(foot.iter().cycle().skip(1))
                    .map(|(a, b)| a.distance(*b))
                    .fold(0.0, f64::max);
                for s in p.windows(2) {
                    let step = s[0].distance(s[1]);
                    prop_assert!(step <= (3.0 * w).max(outline * 1.01), "step {step} with w {w}");
                }
                // Not asserted: that no two steps cross. On such feet a bridge into a ring
                // only a few beads round can cross the ring's own walk (found by this test,
                // open; the shipped designs and the tests above have none).
            }
        }
    }
}
