//! Where a wall of several beads steps across from bead to bead (SPEC §13): the seam.
//!
//! Each revolution of a wall of W beads steps straight across between its beads at one sample,
//! the seam ([`crate::toolpath::build_toolpath_on`]). A turn rises 1/W of a layer, so the next
//! revolution's turn passes over that step's bead only Δ/W higher (Δ the layer) at the seam
//! itself; on a layer that slopes there (a rim cut on a slope, a control line that tilts the
//! top) the turn's last and first points, within half a bead of the step, lie lower or higher
//! than the seam by the slope times their distance, and the layer over the step's bead gets
//! thinner than the printer lays (the tilted rim with two beads: 0.236 mm for 0.25 mm, at 41
//! points). A seam where every layer is level across half a bead either side has none of that.
//!
//! [`flattest_sample`] finds that sample where sample 0 lacks the room: the one that the ring
//! within half a bead either side lies least below on any layer that slopes — a valley of the
//! layers, where they all lie higher and the turns pass over the step with more than Δ/W, else
//! where the layers are most level. On walls whose layers are all planar, or that leave the
//! turns room over a step at sample 0, it is sample 0, where the contours start: the seam
//! moves only where it must (a seam moved also moves where each revolution blends from one
//! section to the next, which changes the lean where the layers bunch up).

use crate::section::Section;

/// Heights within this of the least are as flat, mm (far below any layer's tolerance): the
/// sample nearer the contours' start is kept.
const AS_FLAT_MM: f64 = 1e-6;

/// How far either side of the seam the next turn passes over its step, in beads: a point on the
/// turn lies as far from the step as it lies along the ring from the seam, and rests on the
/// step within half a bead (a tenth more for the turns' own curve).
const SEAM_WINDOW_BEADS: f64 = 0.55;

/// The sample at which a wall of beads `w` wide on `sections` (all of one length) is best
/// stepped across: the first of those that the ring within 0.55·`w` either side lies least
/// below, on the sections that are not planar. 0 where the ring there lies at most `room` mm
/// below sample 0 (the turns pass over its step a layer thick enough: Δ/W less the minimum
/// layer), where sample 0 is as good as any, where every section is planar, and for sections
/// of fewer than 3 points.
pub fn flattest_sample(sections: &[Section], w: f64, room: f64) -> usize {
    let n = sections.first().map_or(0, |s| s.points.len());
    if n < 3 || sections.iter().any(|s| s.points.len() != n) {
        return 0;
    }
    // Only sections that are not level anywhere count; planar ones score 0 at every sample.
    let sloped: Vec<&Section> = sections
        .iter()
        .filter(|s| {
            let (lo, hi) = s
                .points
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
                    (lo.min(p.z), hi.max(p.z))
                });
            hi - lo > AS_FLAT_MM
        })
        .collect();
    if sloped.is_empty() {
        return 0;
    }
    // score[j]: how far the ring lies below sample j within SEAM_WINDOW_BEADS·w of it either
    // way along the ring (interpolated along the segment that leaves the window), on the
    // sloped sections: negative in a valley, where it lies higher all round.
    let window = SEAM_WINDOW_BEADS * w;
    let mut score = vec![f64::NEG_INFINITY; n];
    for s in &sloped {
        let p = |i: usize| s.points[i % n];
        for (j, worst) in score.iter_mut().enumerate() {
            let here = p(j);
            for forward in [true, false] {
                let next = |i: usize| if forward { i + 1 } else { i + n - 1 };
                let (mut at, mut walked) = (j + n, 0.0);
                for _ in 0..n / 2 {
                    let to = next(at);
                    let step = p(at).truncate().distance(p(to).truncate());
                    let z = if walked + step >= window && step > 0.0 {
                        p(at).z + (p(to).z - p(at).z) * ((window - walked) / step)
                    } else {
                        p(to).z
                    };
                    *worst = worst.max(here.z - z);
                    walked += step;
                    at = to;
                    if walked >= window {
                        break;
                    }
                }
            }
        }
    }
    let least = score.iter().copied().fold(f64::INFINITY, f64::min);
    if !least.is_finite() || score[0] <= room || score[0] <= least + AS_FLAT_MM {
        return 0;
    }
    score
        .iter()
        .position(|&s| s <= least + AS_FLAT_MM)
        .unwrap_or(0)
}

/// Rotates every section to start at sample `seam` (before anything is measured per point).
pub fn start_at(sections: &mut [Section], seam: usize) {
    for s in sections.iter_mut() {
        let n = s.points.len();
        if n > 0 {
            s.points.rotate_left(seam % n);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    /// Rings of radius 35 with `n` samples, `layers` of them 0.7 mm apart, the top `tilted` of
    /// them raised by `lift(angle)`·(how far up the tilt they are).
    fn rings(n: usize, layers: usize, tilted: usize, lift: impl Fn(f64) -> f64) -> Vec<Section> {
        (0..layers)
            .map(|k| {
                let share = (k + tilted).saturating_sub(layers) as f64 / tilted.max(1) as f64;
                Section {
                    points: (0..n)
                        .map(|i| {
                            let a = i as f64 / n as f64 * std::f64::consts::TAU;
                            DVec3::new(
                                35.0 * a.cos(),
                                35.0 * a.sin(),
                                0.7 * k as f64 + share * lift(a),
                            )
                        })
                        .collect(),
                }
            })
            .collect()
    }

    #[test]
    fn level_layers_keep_the_seam_where_the_contours_start() {
        assert_eq!(flattest_sample(&rings(180, 40, 0, |_| 0.0), 3.0, 0.0), 0);
        assert_eq!(flattest_sample(&[], 3.0, 0.0), 0);
    }

    #[test]
    fn a_tilted_top_moves_the_seam_to_its_lowest_side() {
        // Sine tilt, highest at 90° and lowest at 270° (sample 135 of 180).
        let sections = rings(180, 60, 20, |a| 10.0 * a.sin());
        assert_eq!(flattest_sample(&sections, 3.0, 0.0), 135);
        // A tilt whose valley is at the contours' start keeps it there (searched for however
        // little room there is).
        let sections = rings(180, 60, 20, |a| -10.0 * a.cos());
        assert_eq!(flattest_sample(&sections, 3.0, -1.0), 0);
        // Two peaks and two valleys, straight between them (a control line's corners): the
        // first valley, though the lower peak is flatter across.
        let zigzag = |a: f64| {
            let t = (a / std::f64::consts::FRAC_PI_2).rem_euclid(4.0);
            let up = [6.0, 1.8][usize::from(t >= 2.0)];
            up * (1.0 - ((t % 2.0) - 1.0).abs())
        };
        let sections = rings(60, 30, 10, zigzag);
        assert_eq!(flattest_sample(&sections, 3.0, -1.0), 0);
    }

    #[test]
    fn a_seam_with_room_for_its_slope_stays_where_the_contours_start() {
        // Half a bead and a tenth (1.65 mm, 2.7° on a 35 mm ring) before 0°, the top ring lies
        // 10·sin 2.7° ≈ 0.47 mm below it.
        let sections = rings(180, 60, 20, |a| 10.0 * a.sin());
        assert_eq!(flattest_sample(&sections, 3.0, 0.4), 135);
        assert_eq!(flattest_sample(&sections, 3.0, 0.5), 0);
    }

    #[test]
    fn the_seam_turns_every_section_alike() {
        let mut sections = rings(4, 2, 0, |_| 0.0);
        let (first, second) = (sections[0].points[2], sections[1].points[2]);
        start_at(&mut sections, 2);
        assert_eq!(
            [sections[0].points[0], sections[1].points[0]],
            [first, second]
        );
        assert_eq!(sections[1].points.len(), 4);
    }
}
