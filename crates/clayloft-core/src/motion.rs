//! The print time as firmware plans it (SPEC §12): each move accelerates and decelerates with the
//! printer's acceleration `a` (trapezoidal speed profiles), corners are taken at the speed the
//! cornering limit allows, and the planner looks ahead so that it can always stop.
//!
//! Junction speed (Marlin's junction deviation δ, `planner.cpp`): with θ the angle between the two
//! moves' directions (0 = straight on), `sin(θ/2) = √((1 − cos θ)/2)` and
//! `v² = a·δ·sin(θ/2) / (1 − sin(θ/2))` — unlimited going straight, zero reversing. Klipper's
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
pub fn junction_speed(u: DVec3, w: DVec3, a: f64, deviation: f64) -> f64 {
    let cos_theta = u.dot(w).clamp(-1.0, 1.0);
    let sin_half = ((1.0 - cos_theta) / 2.0).max(0.0).sqrt();
    if sin_half < 1e-9 {
        return f64::INFINITY; // straight on
    }
    if sin_half > 1.0 - 1e-9 {
        return 0.0; // reversing
    }
    (a * deviation * sin_half / (1.0 - sin_half)).sqrt()
}

/// Total time of `moves` starting at rest at `start` and ending at rest, s.
pub fn plan_time(start: DVec3, moves: &[Move], a: f64, deviation: f64) -> f64 {
    let n = moves.len();
    if n == 0 || !(a > 0.0) {
        return 0.0;
    }
    let mut len = Vec::with_capacity(n);
    let mut dir = Vec::with_capacity(n);
    let mut prev = start;
    for m in moves {
        let d = m.to - prev;
        let l = d.length();
        len.push(l);
        dir.push(if l > 0.0 { d / l } else { DVec3::ZERO });
        prev = m.to;
    }
    // Entry speed limits: the junction with the previous (non-empty) move and both moves' speeds.
    let mut entry = vec![0.0_f64; n + 1]; // entry[i] = speed entering move i; entry[n] = 0 (stop)
    let mut last_dir: Option<DVec3> = None;
    for i in 0..n {
        if len[i] == 0.0 {
            entry[i] = last_dir.map_or(0.0, |_| f64::INFINITY);
            continue;
        }
        entry[i] = match last_dir {
            None => 0.0,
            Some(u) => junction_speed(u, dir[i], a, deviation)
                .min(moves[i].speed)
                .min(moves[i - 1].speed.max(0.0)),
        };
        last_dir = Some(dir[i]);
    }
    for i in 0..n {
        entry[i] = entry[i].min(moves[i].speed);
    }
    entry[n] = 0.0;
    // Backward pass: every move can still slow down to the next entry speed.
    for i in (0..n).rev() {
        entry[i] = entry[i].min((entry[i + 1] * entry[i + 1] + 2.0 * a * len[i]).sqrt());
    }
    // Forward pass: acceleration from the previous entry limits this one.
    for i in 0..n {
        entry[i + 1] = entry[i + 1].min((entry[i] * entry[i] + 2.0 * a * len[i]).sqrt());
    }
    (0..n)
        .map(|i| trapezoid_time(len[i], entry[i], entry[i + 1], moves[i].speed, a))
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;

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
    fn lower_acceleration_takes_longer() {
        let circle: Vec<Move> = (1..=400)
            .map(|k| {
                let a = std::f64::consts::TAU * k as f64 / 100.0;
                Move {
                    to: DVec3::new(40.0 * a.cos(), 40.0 * a.sin(), k as f64 * 0.01),
                    speed: 20.0,
                }
            })
            .collect();
        let start = DVec3::new(40.0, 0.0, 0.0);
        let fast = plan_time(start, &circle, 3000.0, 0.013);
        let slow = plan_time(start, &circle, 50.0, 0.013);
        let length: f64 = 4.0 * std::f64::consts::TAU * 40.0;
        assert!(fast > length / 20.0, "{fast}");
        assert!(slow > fast * 1.05, "{slow} vs {fast}");
    }
}
