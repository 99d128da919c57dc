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
//! [`flattest_sample`] finds that sample where sample 0 lacks the room: the one where the
//! turns pass over the step most thickly on every layer that slopes — a valley of the layers,
//! where they all lie higher and the turns pass over the step with more than Δ/W, else where
//! the layers are most level or thickest. On walls whose layers are all planar, or that leave
//! the turns a minimum layer over a step at sample 0 on every layer, it is sample 0, where the
//! contours start: the seam moves only where it must (a seam moved also moves where each
//! revolution blends from one section to the next, which changes the lean where the layers
//! bunch up).

use crate::section::Section;

/// Heights within this of the least are as flat, mm (far below any layer's tolerance): the
/// sample nearer the contours' start is kept.
const AS_FLAT_MM: f64 = 1e-6;

/// How far either side of the seam the next turn passes over its step, in beads: a point on the
/// turn lies as far from the step as it lies along the ring from the seam, and rests on the
/// step within half a bead (a tenth more for the turns' own curve).
const SEAM_WINDOW_BEADS: f64 = 0.55;

/// The sample at which a wall of `walls` beads `w` wide on `sections` (all of one length) is
/// best stepped across. A step at sample j is laid on each revolution's section k at its
/// height; the next turn passes within 0.55·`w` of it either side up to the drop of the ring
/// there below it, Δ/W higher (Δ the layer at j, from section k − 1 to k): that is the layer
/// over the step, which must be at least `min_layer`. Sample 0, where the contours start, where
/// every section keeps that (or every section is planar, or the sections have fewer than 3
/// points); else the first of the samples where the worst shortfall over the sections that are
/// not planar is least.
pub fn flattest_sample(sections: &[Section], w: f64, walls: usize, min_layer: f64) -> usize {
    let n = sections.first().map_or(0, |s| s.points.len());
    if n < 3 || sections.iter().any(|s| s.points.len() != n) {
        return 0;
    }
    let level = |s: &Section| {
        let (lo, hi) = s
            .points
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
                (lo.min(p.z), hi.max(p.z))
            });
        hi - lo <= AS_FLAT_MM
    };
    let window = SEAM_WINDOW_BEADS * w;
    let share = 1.0 / walls.max(1) as f64;
    // score[j]: how much thinner than the minimum layer the turns pass over a step at j, at
    // worst over the sections that are not planar (negative: room to spare).
    let mut score = vec![f64::NEG_INFINITY; n];
    let mut any = false;
    for k in 1..sections.len() {
        let s = &sections[k];
        if level(s) {
            continue;
        }
        any = true;
        let below = &sections[k - 1];
        let p = |i: usize| s.points[i % n];
        for (j, worst) in score.iter_mut().enumerate() {
            let here = p(j);
            let room = (here.z - below.points[j].z) * share - min_layer;
            let mut drop = f64::NEG_INFINITY;
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
                    drop = drop.max(here.z - z);
                    walked += step;
                    at = to;
                    if walked >= window {
                        break;
                    }
                }
            }
            *worst = worst.max(drop - room);
        }
    }
    if !any {
        return 0;
    }
    let least = score.iter().copied().fold(f64::INFINITY, f64::min);
    if !least.is_finite() || score[0] <= 0.0 || score[0] <= least + AS_FLAT_MM {
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
        assert_eq!(
            flattest_sample(&rings(180, 40, 0, |_| 0.0), 3.0, 2, 0.25),
            0
        );
        assert_eq!(flattest_sample(&[], 3.0, 2, 0.25), 0);
    }

    #[test]
    fn a_tilted_top_moves_the_seam_where_its_layers_are_level_and_thickest() {
        // Sine tilt, highest at 90° (sample 45 of 180), lowest at 270°: level at both, its
        // layers 0.7 + 0.5 mm thick at the top of the high side, 0.7 − 0.5 at the low side.
        let sections = rings(180, 60, 20, |a| 10.0 * a.sin());
        assert_eq!(flattest_sample(&sections, 3.0, 2, 0.25), 45);
        // Turned: highest at 180° (sample 90).
        let sections = rings(180, 60, 20, |a| -10.0 * a.cos());
        assert_eq!(flattest_sample(&sections, 3.0, 2, 0.25), 90);
    }

    #[test]
    fn a_seam_with_room_for_its_slope_stays_where_the_contours_start() {
        // Half a bead and a tenth (1.65 mm, 2.7° on a 35 mm ring) before 0°, the top ring
        // (lifted 0.95 of the way) lies 0.95·10·sin 2.7° ≈ 0.45 mm below it; at 0° the layers
        // are 0.7 mm. Two beads leave the turns 0.35 − 0.45 mm over the step there, one bead
        // 0.7 − 0.45 = 0.25 mm: room for a 0.2 mm layer, not for 0.3 mm.
        let sections = rings(180, 60, 20, |a| 10.0 * a.sin());
        assert_eq!(flattest_sample(&sections, 3.0, 2, 0.25), 45);
        assert_eq!(flattest_sample(&sections, 3.0, 1, 0.2), 0);
        assert_eq!(flattest_sample(&sections, 3.0, 1, 0.3), 45);
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
