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
//! [`flattest_sample`] finds that sample: the one whose neighbours within half a bead (and a
//! half more, for the turns' own rise) lie least below it on any layer that slopes — a valley
//! of the layers, where they all lie higher and the turns pass over the step with more than
//! Δ/W, else where the layers are most level. On walls whose layers are all planar it is
//! sample 0, where the contours start: the seam moves only where it must.

use crate::section::Section;

/// Heights within this of the least are as flat, mm (far below any layer's tolerance): the
/// sample nearer the contours' start is kept.
const AS_FLAT_MM: f64 = 1e-6;

/// The sample at which a wall of beads `w` wide on `sections` (all of one length) is best
/// stepped across: the first of those that the samples within 0.75·`w` along the section (at
/// least one either side) lie least below, on the sections that are not planar. 0 where sample
/// 0 is as good as any, where every section is planar, and for sections of fewer than 3
/// points.
pub fn flattest_sample(sections: &[Section], w: f64) -> usize {
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
    let reach = neighbours_within(&sloped, 0.75 * w).clamp(1, n / 4).max(1);
    // score[j]: how far any sample within reach lies below sample j, on the sloped sections
    // (negative in a valley, where all of them lie higher).
    let mut score = vec![f64::NEG_INFINITY; n];
    for s in &sloped {
        let z = |i: usize| s.points[i % n].z;
        for (j, worst) in score.iter_mut().enumerate() {
            let here = z(j);
            for i in 1..=reach {
                let drop = (here - z(j + i)).max(here - z(j + n - i));
                *worst = worst.max(drop);
            }
        }
    }
    let least = score.iter().copied().fold(f64::INFINITY, f64::min);
    if !least.is_finite() || score[0] <= least + AS_FLAT_MM {
        return 0;
    }
    score
        .iter()
        .position(|&s| s <= least + AS_FLAT_MM)
        .unwrap_or(0)
}

/// How many samples lie within `reach` mm along the sections on average: `reach` over the
/// mean spacing of their points (rounded up).
fn neighbours_within(sections: &[&Section], reach: f64) -> usize {
    let (mut length, mut count) = (0.0, 0usize);
    for s in sections {
        let n = s.points.len();
        for i in 0..n {
            length += s.points[i]
                .truncate()
                .distance(s.points[(i + 1) % n].truncate());
        }
        count += n;
    }
    let spacing = length / count.max(1) as f64;
    if spacing > 0.0 && (reach / spacing).is_finite() {
        (reach / spacing).ceil().min(1e9) as usize
    } else {
        1
    }
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
        assert_eq!(flattest_sample(&rings(180, 40, 0, |_| 0.0), 3.0), 0);
        assert_eq!(flattest_sample(&[], 3.0), 0);
    }

    #[test]
    fn a_tilted_top_moves_the_seam_to_its_lowest_side() {
        // Sine tilt, highest at 90° and lowest at 270° (sample 135 of 180).
        let sections = rings(180, 60, 20, |a| 10.0 * a.sin());
        assert_eq!(flattest_sample(&sections, 3.0), 135);
        // A tilt whose valley is at the contours' start keeps it there.
        let sections = rings(180, 60, 20, |a| -10.0 * a.cos());
        assert_eq!(flattest_sample(&sections, 3.0), 0);
        // Two peaks and two valleys, straight between them (a control line's corners): the
        // first valley, though the lower peak is flatter across.
        let zigzag = |a: f64| {
            let t = (a / std::f64::consts::FRAC_PI_2).rem_euclid(4.0);
            let up = [6.0, 1.8][usize::from(t >= 2.0)];
            up * (1.0 - ((t % 2.0) - 1.0).abs())
        };
        let sections = rings(60, 30, 10, zigzag);
        assert_eq!(flattest_sample(&sections, 3.0), 0);
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
