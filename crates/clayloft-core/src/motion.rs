//! The print time as firmware plans it (SPEC §12): each move accelerates and decelerates with the
//! printer's acceleration `a` (trapezoidal speed profiles), corners are taken at the speed the
//! cornering limit allows, and the planner looks ahead so that it can always stop.
//!
//! Junction speed (Marlin's junction deviation δ, `planner.cpp`): with θ the angle between the
//! reversed incoming direction and the outgoing one (180° = straight on), `sin(θ/2) =
//! √((1 − cos θ)/2)` and `v² = a·δ·sin(θ/2) / (1 − sin(θ/2))` — unlimited going straight, zero
//! reversing, and barely limited by the small turns of a finely sampled curve. Klipper's
//! square corner velocity `v₉₀` is the same rule with `δ = v₉₀²(√2 − 1)/a`.
//!
//! Look-ahead: a backward pass limits each entry speed so the rest of the path can still stop
//! (`v_entry² ≤ v_exit² + 2·a·L`), a forward pass limits what acceleration can reach
//! (`v_exit² ≤ v_entry² + 2·a·L`). Each move then takes the trapezoid (or triangle) between its
//! entry and exit speeds under its nominal speed.

use glam::DVec3;

/// One straight move at a nominal speed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Move {
    pub to: DVec3,
    /// mm/s.
    pub speed: f64,
}

/// Time of a move of length `len` entered and left at squared speeds `entry2` (feasible), at
/// top speed `v` (`inv_v` = 1/v, kept by the caller across moves of one speed): `len/v` when
/// it cruises all the way, else [`trapezoid_time`].
#[inline]
fn move_time(len: f64, (in2, out2): (f64, f64), (v, inv_v): (f64, f64), a: f64) -> f64 {
    let v2 = v * v;
    if in2 >= v2 && out2 >= v2 {
        len * inv_v
    } else {
        trapezoid_time(len, in2.sqrt(), out2.sqrt(), v, a)
    }
}

/// Time of a move of length `len` from speed `v0` to `v1` with top speed `vmax` and
/// acceleration `a` (all speeds already feasible: `|v1² − v0²| ≤ 2·a·len`).
pub fn trapezoid_time(len: f64, v0: f64, v1: f64, vmax: f64, a: f64) -> f64 {
    if len <= 0.0 {
        return 0.0;
    }
    let (v0, v1) = (v0.min(vmax), v1.min(vmax));
    let d_acc = (vmax * vmax - v0 * v0) / (2.0 * a);
    let d_dec = (vmax * vmax - v1 * v1) / (2.0 * a);
    if d_acc + d_dec <= len {
        (vmax - v0) / a + (vmax - v1) / a + (len - d_acc - d_dec) / vmax
    } else {
        // Triangle: the peak speed where acceleration and deceleration meet.
        let vp = ((2.0 * a * len + v0 * v0 + v1 * v1) / 2.0).sqrt().min(vmax);
        (vp - v0).max(0.0) / a + (vp - v1).max(0.0) / a
    }
}

/// Largest speed through the corner between directions `u` (in) and `w` (out), unit vectors.
///
/// Marlin measures θ between the reversed incoming direction and the outgoing one
/// (`cos θ = −u·w`): going straight on is θ = 180°, so `sin(θ/2) = √((1 + u·w)/2)`.
pub fn junction_speed(u: DVec3, w: DVec3, a: f64, deviation: f64) -> f64 {
    junction_speed2(u, w, a, deviation, f64::INFINITY).sqrt()
}

/// A job's moves by index: the planner reads them in parts, one per core.
pub trait Moves: Sync {
    fn len(&self) -> usize;
    fn get(&self, i: usize) -> Move;
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

impl Moves for [Move] {
    fn len(&self) -> usize {
        <[Move]>::len(self)
    }
    fn get(&self, i: usize) -> Move {
        self[i]
    }
}

/// Moves below which the planner stays on one core (starting a thread costs more).
const SERIAL_BELOW: usize = crate::parallel::PARALLEL_POINTS;

/// Total time of `moves` starting at rest at `start` and ending at rest, s.
///
/// Works on squared speeds (no square root where a limit does not bind: on a smooth spiral at
/// constant speed almost every junction and every pass leaves the speed at its nominal value, and
/// such moves take `len / v` directly). Each move's length and entry limit are found on every
/// core; the two look-ahead passes, and the sum, in path order on one.
pub fn plan_time(start: DVec3, moves: &[Move], a: f64, deviation: f64) -> f64 {
    plan_time_in(start, moves, a, deviation, SERIAL_BELOW)
}

/// [`plan_time`], on one core below `serial_below` moves.
fn plan_time_in(
    start: DVec3,
    moves: &(impl Moves + ?Sized),
    a: f64,
    deviation: f64,
    serial_below: usize,
) -> f64 {
    Plan::new_in(start, moves, a, deviation, serial_below).time()
}

/// A plan half done: each move's length, speed and entry limit, found on every core;
/// [`Plan::time`] makes the look-ahead passes on one. Apart, so that a caller can use the second
/// core for other work during the passes.
pub struct Plan {
    a: f64,
    len: Vec<f64>,
    speed: Vec<f64>,
    /// `entry2[i]`: squared speed entering move i; `entry2[n]` = 0 (the job ends at rest).
    /// Each part's own backward pass is made (see [`backward_within`]).
    entry2: Vec<f64>,
    /// The parts the moves were planned in, in order.
    parts: Vec<std::ops::Range<usize>>,
}

impl Plan {
    /// The entry limits of `moves` starting at rest at `start` (see [`plan_time`]).
    pub fn new(start: DVec3, moves: &(impl Moves + ?Sized), a: f64, deviation: f64) -> Plan {
        Self::new_in(start, moves, a, deviation, SERIAL_BELOW)
    }

    fn new_in(
        start: DVec3,
        moves: &(impl Moves + ?Sized),
        a: f64,
        deviation: f64,
        serial_below: usize,
    ) -> Plan {
        if a.is_nan() || a <= 0.0 {
            return Plan {
                a,
                len: Vec::new(),
                speed: Vec::new(),
                entry2: Vec::new(),
                parts: Vec::new(),
            };
        }
        let n = moves.len();
        // Written part by part, never cleared first (clearing them was a memset of 5 MB on one
        // core for the benchmark vase).
        let (mut len, mut speed) = (Vec::with_capacity(n), Vec::with_capacity(n));
        let mut entry2 = Vec::with_capacity(n + 1);
        // Parts of PLAN_PART moves shared out as the cores get free: a textured wall's corners
        // bind (and cost more) in bands of layers, which halves fixed in advance left to one
        // core.
        let parts = crate::parallel::runs(n, serial_below, PLAN_PART);
        {
            let (mut len, mut speed, mut entry2) = (
                &mut len.spare_capacity_mut()[..n],
                &mut speed.spare_capacity_mut()[..n],
                &mut entry2.spare_capacity_mut()[..n],
            );
            let mut jobs = Vec::with_capacity(parts.len());
            for range in &parts {
                let (l, rest_l) = std::mem::take(&mut len).split_at_mut(range.len());
                let (s, rest_s) = std::mem::take(&mut speed).split_at_mut(range.len());
                let (e, rest_e) = std::mem::take(&mut entry2).split_at_mut(range.len());
                (len, speed, entry2) = (rest_l, rest_s, rest_e);
                let legs = Legs {
                    len: l,
                    speed: s,
                    entry2: e,
                };
                let range = range.clone();
                jobs.push(move || entry_limits(start, moves, range, legs, a, deviation));
            }
            crate::parallel::run_shared(jobs);
        }
        // SAFETY: the parts cover 0 .. n, and `entry_limits` writes each move's three values.
        unsafe {
            len.set_len(n);
            speed.set_len(n);
            entry2.set_len(n);
        }
        // The job ends at rest.
        entry2.push(0.0);
        // The backward pass within each part, on every core; [`Plan::time`] carries it across
        // the parts' ends.
        {
            let two_a = 2.0 * a;
            let mut jobs = Vec::with_capacity(parts.len());
            let (mut rest, last) = (&mut entry2[..], parts.len().saturating_sub(1));
            for (p, range) in parts.iter().enumerate() {
                let (e, after) = std::mem::take(&mut rest).split_at_mut(range.len());
                rest = after;
                let l = &len[range.clone()];
                // The last part ends at rest; every other is carried across later.
                let end = (p == last).then_some(0.0);
                jobs.push(move || backward_within(e, l, end, two_a));
            }
            crate::parallel::run_shared(jobs);
        }
        Plan {
            a,
            len,
            speed,
            entry2,
            parts,
        }
    }

    /// Each move's length, mm, `|to − from|` (none where the acceleration is not a positive
    /// number: nothing was planned).
    pub fn lengths(&self) -> &[f64] {
        &self.len
    }

    /// The total time, s: the look-ahead passes and the sum, in path order.
    pub fn time(self) -> f64 {
        let Plan {
            a,
            len,
            speed,
            mut entry2,
            parts,
        } = self;
        if a.is_nan() || a <= 0.0 {
            return 0.0;
        }
        let n = len.len();
        let two_a = 2.0 * a;
        // Backward pass: every move can still slow down to the next entry speed. Each part made
        // its own; carried across the parts' ends here.
        carry_backward(&mut entry2, &len, &parts, two_a);
        // Forward pass: acceleration from the previous entry limits this one. Once it has limited
        // move i's exit (the next entry), both ends of move i are final: its time is added then.
        let mut total = 0.0;
        let (mut v_last, mut inv_v) = (f64::NAN, 0.0);
        for i in 0..n {
            let reach = entry2[i] + two_a * len[i];
            if entry2[i + 1] > reach {
                entry2[i + 1] = reach;
            }
            let v = speed[i];
            if v != v_last {
                (v_last, inv_v) = (v, 1.0 / v);
            }
            total += move_time(len[i], (entry2[i], entry2[i + 1]), (v, inv_v), a);
        }
        total
    }
}

/// Moves a part of the planner's passes takes (see [`Plan::new`]).
const PLAN_PART: usize = 16 * 1024;

/// The backward pass over one part of the moves (`entry2` and `len` of its moves): each entry
/// lowered to what decelerating at `two_a`/2 from the next entry allows, the part's last from
/// `end` (the entry after the part), or not at all where that is not known yet.
///
/// Carried across the part's end later, from the final entry after it, the pass gives what one
/// pass over all moves gives, to the bit: with E the one pass's entries and L these
/// (L ≥ E, as L starts from no limit), min(L_i, E_{i+1} + c_i) = min(e_i, E_{i+1} + c_i) = E_i
/// (rounding is monotone, so E_{i+1} + c_i ≤ L_{i+1} + c_i); and once an entry is left as it
/// is, so is every one before it.
fn backward_within(entry2: &mut [f64], len: &[f64], end: Option<f64>, two_a: f64) {
    let Some(last) = entry2.len().checked_sub(1) else {
        return;
    };
    if let Some(end) = end {
        let reach = end + two_a * len[last];
        if entry2[last] > reach {
            entry2[last] = reach;
        }
    }
    for i in (0..last).rev() {
        let reach = entry2[i + 1] + two_a * len[i];
        if entry2[i] > reach {
            entry2[i] = reach;
        }
    }
}

/// The backward pass that each of `parts` made on its own ([`backward_within`], every part but
/// the last without the entry after it) carried across the parts' ends, from the last: each
/// part's entries lowered from its end back only as far as they change.
fn carry_backward(entry2: &mut [f64], len: &[f64], parts: &[std::ops::Range<usize>], two_a: f64) {
    for range in parts.iter().rev().skip(1) {
        for i in range.clone().rev() {
            let reach = entry2[i + 1] + two_a * len[i];
            if entry2[i] > reach {
                entry2[i] = reach;
            } else {
                break;
            }
        }
    }
}

/// One part of the planner's per-move values.
struct Legs<'a> {
    len: &'a mut [std::mem::MaybeUninit<f64>],
    speed: &'a mut [std::mem::MaybeUninit<f64>],
    entry2: &'a mut [std::mem::MaybeUninit<f64>],
}

/// Each move's length, speed and the squared speed it may enter at (its own speed, the speed
/// before it and the corner allow), for moves `range`.
fn entry_limits(
    start: DVec3,
    moves: &(impl Moves + ?Sized),
    range: std::ops::Range<usize>,
    legs: Legs,
    a: f64,
    deviation: f64,
) {
    let from = |i: usize| if i == 0 { start } else { moves.get(i - 1).to };
    // What the moves before this part leave: the direction and squared speed of the last one
    // that goes somewhere.
    let (mut last_dir, mut last_speed2) = (None, 0.0);
    for i in (0..range.start).rev() {
        let m = moves.get(i);
        let d = m.to - from(i);
        let l = d.length();
        if l != 0.0 {
            last_dir = Some(d * (1.0 / l));
            last_speed2 = m.speed * m.speed;
            break;
        }
    }
    let mut prev = from(range.start);
    let mut corners = Corners::new(a, deviation, last_dir, last_speed2);
    for (k, i) in range.enumerate() {
        let m = moves.get(i);
        let d = m.to - prev;
        let l = d.length();
        legs.entry2[k].write(corners.entry2(d, l, m.speed * m.speed));
        legs.len[k].write(l);
        legs.speed[k].write(m.speed);
        prev = m.to;
    }
}

/// The corner limits along a run of moves, move after move: the direction and squared speed of
/// the last move that goes somewhere, and the threshold of the last cap (consecutive moves mostly
/// share their speeds, so it is rarely computed again).
struct Corners {
    a: f64,
    deviation: f64,
    last_dir: Option<DVec3>,
    last_speed2: f64,
    cached_cap2: f64,
    cached_threshold: f64,
}

impl Corners {
    fn new(a: f64, deviation: f64, last_dir: Option<DVec3>, last_speed2: f64) -> Self {
        Self {
            a,
            deviation,
            last_dir,
            last_speed2,
            cached_cap2: f64::NAN,
            cached_threshold: f64::INFINITY,
        }
    }

    /// The squared speed the next move (`d`, `l` = |d| long, squared speed `v2`) may enter at:
    /// its own speed, the speed before it and the corner allow. It then becomes the last move.
    #[inline]
    fn entry2(&mut self, d: DVec3, l: f64, v2: f64) -> f64 {
        let limit2 = if l == 0.0 {
            // A move that goes nowhere passes the speed on unchanged.
            if self.last_dir.is_some() {
                f64::INFINITY
            } else {
                0.0
            }
        } else {
            let w = d * (1.0 / l);
            let j2 = match self.last_dir {
                None => 0.0,
                Some(u) => {
                    let cap2 = v2.min(self.last_speed2);
                    if cap2 != self.cached_cap2 {
                        self.cached_cap2 = cap2;
                        self.cached_threshold = cap_threshold(cap2, self.a, self.deviation);
                    }
                    // Most junctions of a smooth path turn too little for the limit to bind.
                    let sin_half2 = (1.0 + u.dot(w).clamp(-1.0, 1.0)) / 2.0;
                    if sin_half2 >= self.cached_threshold {
                        cap2
                    } else {
                        junction_speed2(u, w, self.a, self.deviation, cap2)
                    }
                }
            };
            self.last_dir = Some(w);
            j2
        };
        let entry = limit2.min(v2).min(if l == 0.0 {
            f64::INFINITY
        } else {
            self.last_speed2.max(v2)
        });
        if l > 0.0 {
            self.last_speed2 = v2;
        }
        entry
    }
}

/// The `sin²(θ/2)` above which a junction's speed limit reaches `cap2`: `v² = a·δ·s/(1 − s)`
/// grows with `s = sin(θ/2)`, and `v² ≥ cap²` ⟺ `s ≥ k/(1 + k)` with `k = cap²/(a·δ)`.
fn cap_threshold(cap2: f64, a: f64, deviation: f64) -> f64 {
    let k = cap2 / (a * deviation);
    if k.is_finite() {
        let s_cap = k / (1.0 + k);
        s_cap * s_cap
    } else {
        f64::INFINITY
    }
}

/// [`junction_speed`] squared, at most `cap2` (the square of the speeds on either side).
fn junction_speed2(u: DVec3, w: DVec3, a: f64, deviation: f64, cap2: f64) -> f64 {
    let sin_half2 = (1.0 + u.dot(w).clamp(-1.0, 1.0)) / 2.0;
    if sin_half2 >= cap_threshold(cap2, a, deviation) {
        return cap2;
    }
    let sin_half = sin_half2.sqrt();
    if sin_half > 1.0 - 1e-9 {
        return cap2; // straight on
    }
    (a * deviation * sin_half / (1.0 - sin_half)).min(cap2)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The planner as it was written before it ran in parts, in one pass over an iterator: the
    /// reference the parts must match to the bit.
    fn plan_time_reference(
        start: DVec3,
        moves: impl IntoIterator<Item = Move>,
        a: f64,
        deviation: f64,
    ) -> f64 {
        if a.is_nan() || a <= 0.0 {
            return 0.0;
        }
        let moves = moves.into_iter();
        let hint = moves.size_hint().0;
        let two_a = 2.0 * a;
        let mut len = Vec::with_capacity(hint);
        let mut speed = Vec::with_capacity(hint);
        // entry2[i]: squared speed entering move i; entry2[n] = 0 (the job ends at rest).
        let mut entry2 = Vec::with_capacity(hint + 1);
        let mut prev = start;
        let mut corners = Corners::new(a, deviation, None, 0.0);
        for m in moves {
            let d = m.to - prev;
            let l = d.length();
            entry2.push(corners.entry2(d, l, m.speed * m.speed));
            len.push(l);
            speed.push(m.speed);
            prev = m.to;
        }
        let n = len.len();
        entry2.push(0.0);
        // Backward pass: every move can still slow down to the next entry speed.
        for i in (0..n).rev() {
            let reach = entry2[i + 1] + two_a * len[i];
            if entry2[i] > reach {
                entry2[i] = reach;
            }
        }
        // Forward pass: acceleration from the previous entry limits this one.
        for i in 0..n {
            let reach = entry2[i] + two_a * len[i];
            if entry2[i + 1] > reach {
                entry2[i + 1] = reach;
            }
        }
        let mut total = 0.0;
        let (mut v_last, mut inv_v) = (f64::NAN, 0.0);
        for i in 0..n {
            let v = speed[i];
            if v != v_last {
                (v_last, inv_v) = (v, 1.0 / v);
            }
            total += move_time(len[i], (entry2[i], entry2[i + 1]), (v, inv_v), a);
        }
        total
    }

    proptest::proptest! {
        /// In parts (as many as the points allow) the planner gives the one-pass planner's time
        /// to the bit: corners from straight on to reversing, moves that go nowhere (first, in a
        /// run, at a part's start), and speeds that change.
        #[test]
        fn parts_give_the_one_pass_time(
            steps in proptest::collection::vec((0u8..6, -3.0f64..3.0, -3.0f64..3.0, 0.0f64..0.5, 1.0f64..80.0), 0..400),
            serial_below in 1usize..50,
            a in 50.0f64..5000.0,
        ) {
            let mut at = DVec3::ZERO;
            let moves: Vec<Move> = steps
                .iter()
                .map(|&(kind, dx, dy, dz, speed)| {
                    if kind > 1 {
                        at += DVec3::new(dx, dy, dz);
                    }
                    Move { to: at, speed: if kind == 5 { 20.0 } else { speed } }
                })
                .collect();
            let start = DVec3::new(1.0, 2.0, 0.0);
            let parts = plan_time_in(start, &moves[..], a, 0.013, serial_below);
            let reference = plan_time_reference(start, moves.iter().copied(), a, 0.013);
            proptest::prop_assert_eq!(parts.to_bits(), reference.to_bits(), "{} vs {}", parts, reference);
        }
    }

    proptest::proptest! {
        /// The backward pass made part by part and carried across the parts' ends is the one
        /// pass over every move, to the bit, however many parts: entries that brake over many
        /// moves, across several parts' ends (a stop a few moves on, after long fast runs).
        #[test]
        fn the_backward_pass_in_parts_is_the_one_pass(
            moves in proptest::collection::vec((0.0f64..3.0, 0u8..8), 1..300),
            cuts in proptest::collection::vec(0.0f64..1.0, 0..8),
            two_a in 1.0f64..400.0,
        ) {
            let len: Vec<f64> = moves.iter().map(|m| m.0).collect();
            let mut entry2: Vec<f64> = moves.iter().map(|m| if m.1 == 0 { 0.0 } else { 2500.0 }).collect();
            entry2.push(0.0);
            let n = len.len();
            let mut one = entry2.clone();
            for i in (0..n).rev() {
                let reach = one[i + 1] + two_a * len[i];
                if one[i] > reach {
                    one[i] = reach;
                }
            }
            let mut ends: Vec<usize> = cuts.iter().map(|c| (c * n as f64) as usize).collect();
            ends.push(n);
            ends.sort_unstable();
            ends.dedup();
            let parts: Vec<_> = std::iter::once(0).chain(ends.iter().copied()).zip(ends.iter().copied()).filter(|(s, e)| e > s).map(|(s, e)| s..e).collect();
            let last = parts.len() - 1;
            for (p, r) in parts.iter().enumerate() {
                backward_within(&mut entry2[r.clone()], &len[r.clone()], (p == last).then_some(0.0), two_a);
            }
            carry_backward(&mut entry2, &len, &parts, two_a);
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            proptest::prop_assert_eq!(bits(&entry2), bits(&one));
        }
    }

    #[test]
    fn one_move_is_the_hand_computed_trapezoid() {
        // 100 mm at 50 mm/s with a = 500 mm/s²: 0.1 s and 2.5 mm to reach 50 mm/s, the same to
        // stop, 95 mm cruising for 1.9 s: 2.1 s.
        let t = plan_time(
            DVec3::ZERO,
            &[Move {
                to: DVec3::X * 100.0,
                speed: 50.0,
            }],
            500.0,
            0.013,
        );
        assert!((t - 2.1).abs() < 1e-12, "{t}");
        // Too short to reach the speed: a triangle, 2·√(L/a).
        let t = plan_time(
            DVec3::ZERO,
            &[Move {
                to: DVec3::X * 2.0,
                speed: 50.0,
            }],
            500.0,
            0.013,
        );
        assert!((t - 2.0 * (2.0_f64 / 500.0).sqrt()).abs() < 1e-12, "{t}");
    }

    #[test]
    fn straight_runs_do_not_stop_and_reversals_do() {
        let straight = [
            Move {
                to: DVec3::X * 50.0,
                speed: 50.0,
            },
            Move {
                to: DVec3::X * 100.0,
                speed: 50.0,
            },
        ];
        let t = plan_time(DVec3::ZERO, &straight, 500.0, 0.013);
        assert!((t - 2.1).abs() < 1e-12, "{t}");
        let back = [
            Move {
                to: DVec3::X * 50.0,
                speed: 50.0,
            },
            Move {
                to: DVec3::ZERO,
                speed: 50.0,
            },
        ];
        let t = plan_time(DVec3::ZERO, &back, 500.0, 0.013);
        assert!((t - 2.0 * (0.2 + 45.0 / 50.0)).abs() < 1e-12, "{t}");
    }

    #[test]
    fn junction_deviation_formula() {
        // A right angle: sin 45° = 0.7071; v² = 500·0.013·0.7071/0.2929 = 15.69.
        let v = junction_speed(DVec3::X, DVec3::Y, 500.0, 0.013);
        assert!((v * v - 500.0 * 0.013 * 0.5_f64.sqrt() / (1.0 - 0.5_f64.sqrt())).abs() < 1e-9);
        // Klipper's square corner velocity 5 mm/s is δ = 25(√2 − 1)/a: 5 mm/s at 90°.
        let d = 25.0 * (2.0_f64.sqrt() - 1.0) / 500.0;
        assert!((junction_speed(DVec3::X, DVec3::Y, 500.0, d) - 5.0).abs() < 1e-9);
    }

    #[test]
    fn a_smooth_curve_runs_at_full_speed() {
        // 4000 points round a 40 mm circle at 20 mm/s: every junction turns 0.09°, far inside
        // the cornering limit, so only the start and the stop cost time: L/v + v/a.
        let n = 4000;
        let path: Vec<Move> = (1..=n)
            .map(|k| {
                let a = std::f64::consts::TAU * k as f64 / n as f64;
                Move {
                    to: DVec3::new(40.0 * a.cos(), 40.0 * a.sin(), 0.0),
                    speed: 20.0,
                }
            })
            .collect();
        let t = plan_time(DVec3::new(40.0, 0.0, 0.0), &path, 300.0, 0.013);
        let length = n as f64 * 2.0 * 40.0 * (std::f64::consts::PI / n as f64).sin();
        let want = length / 20.0 + 20.0 / 300.0;
        assert!((t - want).abs() < 1e-6 * want, "{t} vs {want}");
    }

    #[test]
    fn lower_acceleration_takes_longer() {
        // An octagonal spiral: 45° corners every 31 mm.
        let path: Vec<Move> = (1..=80)
            .map(|k| {
                let a = std::f64::consts::TAU * k as f64 / 8.0;
                Move {
                    to: DVec3::new(40.0 * a.cos(), 40.0 * a.sin(), k as f64 * 0.1),
                    speed: 40.0,
                }
            })
            .collect();
        let start = DVec3::new(40.0, 0.0, 0.0);
        let fast = plan_time(start, &path, 3000.0, 0.013);
        let slow = plan_time(start, &path, 50.0, 0.013);
        let length: f64 = path
            .iter()
            .scan(start, |p, m| {
                let d = p.distance(m.to);
                *p = m.to;
                Some(d)
            })
            .sum();
        assert!(fast > length / 40.0, "{fast}");
        assert!(slow > fast * 1.5, "{slow} vs {fast}");
    }
}
