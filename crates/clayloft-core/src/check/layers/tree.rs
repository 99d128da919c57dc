//! The chords of a path in path order under a hierarchy of boxes: what the self-check searches
//! instead of the chord grid ([`super::ChordGrid`]).
//!
//! A path is laid in order, so a run of consecutive chords stays in a small box: the chords
//! are cut into leaves of [`LEAF`] and each level joins two boxes of the level below, each box
//! bounding its chords in x, y and z. A search for the chords near a point and within a band of
//! heights descends from the top, leaving out every box farther than the search radius or
//! outside the band. On a rising wall that leaves the layers just under the point and the
//! stretch of them nearest it: the boxes of older layers lie below the band, those of the bead
//! just laid above it, and those across the vessel too far. Built in one pass over the chords
//! on both cores (2 ms for the 720 × 300 vase, against 13 ms for the grid), and never too large
//! to build: a search's cost is bounded by its budget instead.

use glam::{DVec2, DVec3};

/// Chords in a leaf box (at most 8: a byte says which of them the tree holds).
const LEAF: usize = 8;
const _: () = assert!(LEAF <= 8);

/// A box around chords: x, y, z from `lo` to `hi`, in single precision rounded outward (it
/// holds every point of its chords exactly); empty when `lo > hi`.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Bounds {
    lo: [f32; 3],
    hi: [f32; 3],
}

impl Bounds {
    const EMPTY: Bounds = Bounds {
        lo: [f32::INFINITY; 3],
        hi: [f32::NEG_INFINITY; 3],
    };

    /// The box of the chord from `a` to `b`.
    fn of(a: DVec3, b: DVec3) -> Bounds {
        let (lo, hi) = (a.min(b), a.max(b));
        Bounds {
            lo: [lo.x, lo.y, lo.z].map(|x| (x as f32).next_down()),
            hi: [hi.x, hi.y, hi.z].map(|x| (x as f32).next_up()),
        }
    }

    fn join(self, o: Bounds) -> Bounds {
        Bounds {
            lo: [0, 1, 2].map(|k| self.lo[k].min(o.lo[k])),
            hi: [0, 1, 2].map(|k| self.hi[k].max(o.hi[k])),
        }
    }

    /// Whether no point of the box is within `r` of `p` in XY at heights `z` (low, high).
    fn misses(&self, p: DVec2, r: f64, z: [f32; 2]) -> bool {
        if self.hi[2] < z[0] || self.lo[2] > z[1] {
            return true;
        }
        // Exact in double precision but for the last rounding: 1 nm to spare.
        let dx = (f64::from(self.lo[0]) - p.x).max(p.x - f64::from(self.hi[0]));
        let dy = (f64::from(self.lo[1]) - p.y).max(p.y - f64::from(self.hi[1]));
        let (dx, dy) = (dx.max(0.0), dy.max(0.0));
        dx * dx + dy * dy > (r + 1e-6) * (r + 1e-6)
    }
}

/// The chords of a path under boxes (see the module documentation).
pub(super) struct ChordTree {
    /// `levels[0]`: a box per [`LEAF`] chords (of those the search holds); `levels[k]`: a box
    /// per two of level k − 1; the last level has one box.
    levels: Vec<Vec<Bounds>>,
    /// The highest z of leaves `0 ..= i` (non-decreasing): the leaves before the first at or
    /// above a band lie wholly below it (on a rising wall, every leaf but the last few layers').
    top: Vec<f32>,
    /// Which chords of each leaf the search holds, one bit each.
    held: Vec<u8>,
}

impl ChordTree {
    /// The tree of chords `chords` of path `v`, holding those that `held` says the search
    /// holds (on both cores for a long path).
    pub(super) fn build(
        v: &[DVec3],
        chords: &[(usize, usize)],
        held: &(impl Fn(usize) -> bool + Sync),
    ) -> ChordTree {
        let built = crate::parallel::map_ranges(chords.len().div_ceil(LEAF), 4096, |range| {
            range
                .map(|leaf| {
                    // The box of the leaf's held chords' ends, rounded outwards once: the join of
                    // each chord's box (the rounding to f32 and the step out are monotone).
                    let ids = leaf * LEAF..(leaf * LEAF + LEAF).min(chords.len());
                    let (lo, hi, bits) = ids.filter(|&id| held(id)).fold(
                        (DVec3::INFINITY, DVec3::NEG_INFINITY, 0u8),
                        |(lo, hi, bits), id| {
                            let (a, c) = (v[chords[id].0], v[chords[id].1]);
                            (lo.min(a.min(c)), hi.max(a.max(c)), bits | 1 << (id % LEAF))
                        },
                    );
                    let b = if bits == 0 {
                        Bounds::EMPTY
                    } else {
                        Bounds::of(lo, hi)
                    };
                    (b, bits)
                })
                .collect()
        });
        let (leaves, held): (Vec<Bounds>, Vec<u8>) = built.into_iter().unzip();
        let top = leaves
            .iter()
            .scan(f32::NEG_INFINITY, |t, b: &Bounds| {
                *t = t.max(b.hi[2]);
                Some(*t)
            })
            .collect();
        let mut levels = vec![leaves];
        while let Some(below) = levels.last().filter(|l| l.len() > 1) {
            let joined = below
                .chunks(2)
                .map(|pair| pair.iter().fold(Bounds::EMPTY, |b, &c| b.join(c)))
                .collect();
            levels.push(joined);
        }
        ChordTree { levels, top, held }
    }

    /// Whether the tree holds chord `id` (the `held` it was built with).
    #[inline]
    pub(super) fn holds(&self, id: usize) -> bool {
        self.held[id / LEAF] >> (id % LEAF) & 1 == 1
    }

    /// Calls `f` with the id of each of the first `laid` chords whose leaf box comes within
    /// `r` of `p` in XY at heights `z` (low, high), in path order: every held chord with a
    /// point there, and some without (the caller tests each). Each box looked at, and each
    /// chord given, costs one of `budget`; false, with the search cut short, once it is spent.
    ///
    /// The leaves searched are those from the first that reaches `z` up to the last laid, as
    /// the fewest aligned boxes that cover them, each searched from the top down. The first
    /// leaf is sought from `first` (where the last search of this thread began: a few steps
    /// along a path) and left there for the next.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn visit(
        &self,
        p: DVec2,
        r: f64,
        z: [f32; 2],
        laid: usize,
        first: &mut usize,
        budget: &mut usize,
        mut f: impl FnMut(usize),
    ) -> bool {
        let leaves = &self.levels[0];
        *first = super::seek(&self.top, *first, |&t| t < z[0]);
        let first = *first;
        let end = laid.div_ceil(LEAF).min(leaves.len());
        if first >= end {
            return true;
        }
        // The covering boxes: the fewest aligned ones (box i of level k covers leaves
        // i·2^k .. (i + 1)·2^k). At level k the range is ⌈first / 2^k⌉ .. end / 2^k; its
        // first box is taken when odd (in path order, climbing), the box before its end when
        // the end is odd (in path order, coming back down).
        let mut lo = first;
        let mut level = 0;
        while lo < end >> level {
            if lo % 2 == 1 {
                if !self.descend(level, lo, p, r, z, laid, budget, &mut f) {
                    return false;
                }
                lo += 1;
            }
            (lo, level) = (lo / 2, level + 1);
        }
        for level in (0..level).rev() {
            let hi = end >> level;
            if hi % 2 == 1 && !self.descend(level, hi - 1, p, r, z, laid, budget, &mut f) {
                return false;
            }
        }
        true
    }

    /// [`ChordTree::visit`] in box `i` of `level`.
    #[allow(clippy::too_many_arguments)]
    fn descend(
        &self,
        level: usize,
        i: usize,
        p: DVec2,
        r: f64,
        z: [f32; 2],
        laid: usize,
        budget: &mut usize,
        f: &mut impl FnMut(usize),
    ) -> bool {
        if (i * LEAF) << level >= laid {
            return true;
        }
        if *budget == 0 {
            return false;
        }
        *budget -= 1;
        if self.levels[level][i].misses(p, r, z) {
            return true;
        }
        if level == 0 {
            let ids = i * LEAF..(i * LEAF + LEAF).min(laid);
            if ids.len() > *budget {
                return false;
            }
            *budget -= ids.len();
            ids.for_each(f);
            return true;
        }
        let below = self.levels[level - 1].len();
        (2 * i >= below || self.descend(level - 1, 2 * i, p, r, z, laid, budget, f))
            && (2 * i + 1 >= below || self.descend(level - 1, 2 * i + 1, p, r, z, laid, budget, f))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A wall of rings climbing 0.5 mm a revolution, 90 chords each.
    fn rings() -> (Vec<DVec3>, Vec<(usize, usize)>) {
        let v: Vec<DVec3> = (0..90 * 40)
            .map(|i| {
                let t = i as f64 / 90.0;
                let a = t * std::f64::consts::TAU;
                DVec3::new(
                    100.0 + 30.0 * a.cos(),
                    100.0 + 30.0 * a.sin(),
                    0.5 + 0.5 * t,
                )
            })
            .collect();
        let chords = (0..v.len() - 1).map(|i| (i, i + 1)).collect();
        (v, chords)
    }

    /// The chords visited are all those among the laid that come within reach (tested on
    /// their exact boxes), in path order; far fewer than all.
    #[test]
    fn visits_every_chord_within_reach_in_path_order() {
        let (v, chords) = rings();
        let held = |id: usize| v[chords[id].0].x < 128.0 && v[chords[id].1].x < 128.0;
        let tree = ChordTree::build(&v, &chords, &held);
        for (j, r, z) in [
            (3000usize, 2.0, [14.0f32, 15.9]),
            (3000, 30.0, [0.0, 100.0]),
            (100, 1.0, [0.0, 1.0]),
            (3599, 0.1, [19.0, 20.0]),
        ] {
            let p = v[j].truncate();
            let laid = chords.partition_point(|&(_, e)| e <= j);
            let mut seen = Vec::new();
            let mut budget = usize::MAX;
            assert!(tree.visit(p, r, z, laid, &mut 0, &mut budget, |id| seen.push(id)));
            assert!(seen.windows(2).all(|w| w[0] < w[1]));
            assert!(seen.iter().all(|&id| id < laid));
            let want: Vec<usize> = (0..laid)
                .filter(|&id| {
                    let (a, b) = (v[chords[id].0], v[chords[id].1]);
                    a.x < 128.0 && b.x < 128.0 && !Bounds::of(a, b).misses(p, r, z)
                })
                .collect();
            assert!(want.iter().all(|id| seen.contains(id)), "{j} {r}");
            assert!((0..chords.len()).all(|id| tree.holds(id) == held(id)));
            if r < 5.0 {
                assert!(seen.len() < laid / 10, "{j}: {} of {laid}", seen.len());
            }
        }
    }

    /// A spent budget cuts the search short and says so.
    #[test]
    fn a_spent_budget_says_so() {
        let (v, chords) = rings();
        let tree = ChordTree::build(&v, &chords, &|_| true);
        let p = v[3000].truncate();
        let mut budget = usize::MAX;
        assert!(tree.visit(p, 30.0, [0.0, 100.0], 2990, &mut 0, &mut budget, |_| {}));
        let spent = usize::MAX - budget;
        let mut short = spent - 1;
        assert!(!tree.visit(p, 30.0, [0.0, 100.0], 2990, &mut 0, &mut short, |_| {}));
    }

    /// Every box holds its chords: the boxes of the levels join the leaves'.
    #[test]
    fn each_box_holds_the_boxes_under_it() {
        let (v, chords) = rings();
        let tree = ChordTree::build(&v, &chords, &|_| true);
        assert_eq!(tree.levels.last().map(Vec::len), Some(1));
        for k in 1..tree.levels.len() {
            for (i, b) in tree.levels[k].iter().enumerate() {
                let under = tree.levels[k - 1][2 * i..(2 * i + 2).min(tree.levels[k - 1].len())]
                    .iter()
                    .fold(Bounds::EMPTY, |x, &y| x.join(y));
                assert_eq!(*b, under);
            }
        }
        for (id, &(a, b)) in chords.iter().enumerate() {
            let leaf = tree.levels[0][id / LEAF];
            assert_eq!(leaf.join(Bounds::of(v[a], v[b])), leaf);
        }
        // A leaf's box is exactly the join of its held chords' boxes (one chord in three held
        // here, some leaves none).
        let held = |id: usize| id.is_multiple_of(3) && id % 40 < 20;
        let tree = ChordTree::build(&v, &chords, &held);
        for (leaf, &b) in tree.levels[0].iter().enumerate() {
            let joined = (leaf * LEAF..((leaf + 1) * LEAF).min(chords.len()))
                .filter(|&id| held(id))
                .fold(Bounds::EMPTY, |x, id| {
                    x.join(Bounds::of(v[chords[id].0], v[chords[id].1]))
                });
            assert_eq!(b, joined, "leaf {leaf}");
        }
    }
}
