//! Texture (SPEC §3): small-scale shaping by periodic curve embedding. In the parameter space
//! x = sample index, y = layer index, each point moves along the outward normal by
//! `d = f_x(x)·f_y(y)` (product) or `f_x(x) + f_y(y)` (sum).
//!
//! Waves of amplitude A and period T, with phase u = frac(t / T):
//! * sine: `A sin(2πu)`
//! * triangle: the symmetric (even) triangle wave, `A (1 − 4 min(u, 1 − u))`: +A at u = 0, −A at
//!   u = ½ — so the paper's period-2 y wave alternates layers in and out (a woven look)
//! * square: `A sign(sin(2πu))`, exactly 0 at u = 0 and u = ½

use crate::design::{Combine, Texture, Wave, WaveKind};

/// Value of a wave at parameter `t` (samples or layers).
pub fn wave_value(w: &Wave, t: f64) -> f64 {
    let u = (t / w.period).rem_euclid(1.0);
    let a = w.amplitude;
    match w.wave {
        WaveKind::Sine => a * (std::f64::consts::TAU * u).sin(),
        WaveKind::Triangle => a * (1.0 - 4.0 * u.min(1.0 - u)),
        WaveKind::Square => {
            const EDGE: f64 = 1e-9;
            if u < EDGE || (u - 0.5).abs() < EDGE || u > 1.0 - EDGE {
                0.0
            } else if u < 0.5 {
                a
            } else {
                -a
            }
        }
    }
}

/// Texture displacement (mm, along the outward normal) at sample `i` of layer `k` of `layers`.
/// Zero outside the texture's height range.
pub fn displacement(tex: &Texture, i: usize, k: usize, layers: usize) -> f64 {
    let t = k as f64 / layers.max(1) as f64;
    if t < tex.start - 1e-12 || t > tex.end + 1e-12 {
        return 0.0;
    }
    let x = i as f64 + tex.phase_drift * k as f64;
    let fx = tex.x.as_ref().map(|w| wave_value(w, x));
    let fy = tex.y.as_ref().map(|w| wave_value(w, k as f64));
    match (tex.combine, fx, fy) {
        (_, None, None) => 0.0,
        (_, Some(a), None) | (_, None, Some(a)) => a,
        (Combine::Product, Some(a), Some(b)) => a * b,
        (Combine::Sum, Some(a), Some(b)) => a + b,
    }
}

/// Displaces every section along its outward normal by the texture, keeping the overhang limit.
///
/// For each column (sample index i) the amplitude is lowered by the largest factor `sᵢ ∈ [0, 1]`
/// such that between any two consecutive sections `|b + sᵢ·Δd| ≤ Δz·tan_limit`, where b is the
/// normal offset of the untextured wall and Δd the change of displacement. Returns one event
/// per lowered column (amount = amplitude removed, mm), at the layer where the limit binds.
pub fn apply_texture(
    sections: &mut [crate::section::Section],
    tex: &Texture,
    tan_limit: f64,
    enforce: bool,
) -> Vec<crate::report::PointEvent> {
    let n = sections.first().map_or(0, |s| s.points.len());
    let disp = displacements(tex, n, sections.len());
    apply_displacements(sections, &disp, tan_limit, enforce)
}

/// The texture's displacement `disp[k][i]` of sample i on section k, for `count` sections of
/// `n` samples: it depends on the texture and the grid only, not on the wall's shape, so the
/// incremental engine keeps it while the shape is edited.
pub fn displacements(tex: &Texture, n: usize, count: usize) -> Vec<Vec<f64>> {
    let layers = count.saturating_sub(1);
    // Without phase drift every textured section has the same x wave: computed once.
    let row0: Option<Vec<f64>> =
        (tex.phase_drift == 0.0).then(|| (0..n).map(|i| displacement(tex, i, 0, 0)).collect());
    crate::parallel::map_ranges(count, 64, |ks| {
        ks.map(|k| {
            let t = k as f64 / layers.max(1) as f64;
            if t < tex.start - 1e-12 || t > tex.end + 1e-12 {
                return vec![0.0; n];
            }
            match (&row0, tex.y.is_some()) {
                // x wave only: the same row on every section.
                (Some(row), false) => row.clone(),
                _ => (0..n).map(|i| displacement(tex, i, k, layers)).collect(),
            }
        })
        .collect()
    })
}

/// [`apply_texture`] with the displacements given (from [`displacements`] for these sections).
///
/// Each column's scale depends on that column alone (and its neighbours' points, for the
/// normals), so the columns are cut into one contiguous part per core and each part does all
/// of it (normals, scale, shifts) in one go: one hand-over to the other core instead of three.
/// A part reads its neighbours' edge columns from copies taken before any point moves.
pub fn apply_displacements(
    sections: &mut [crate::section::Section],
    disp: &[Vec<f64>],
    tan_limit: f64,
    enforce: bool,
) -> Vec<crate::report::PointEvent> {
    let n = sections.first().map_or(0, |s| s.points.len());
    if n == 0 {
        return Vec::new();
    }
    let parts = crate::parallel::ranges(n, 128);
    let typical: Vec<f64> = sections.iter().map(typical_chord).collect();
    let typical = &typical;
    // The columns just outside each part, as they are before the texture.
    let column = |i: usize| -> Vec<glam::DVec2> {
        sections.iter().map(|s| s.points[i].truncate()).collect()
    };
    let edges: Vec<(Vec<glam::DVec2>, Vec<glam::DVec2>)> = parts
        .iter()
        .map(|r| (column((r.start + n - 1) % n), column(r.end % n)))
        .collect();
    // Each part's columns of every section, to be moved by that part alone.
    let mut columns: Vec<Vec<&mut [glam::DVec3]>> = parts
        .iter()
        .map(|_| Vec::with_capacity(sections.len()))
        .collect();
    for s in sections.iter_mut() {
        let mut rest: &mut [glam::DVec3] = &mut s.points;
        for (part, r) in columns.iter_mut().zip(&parts) {
            let (head, tail) = std::mem::take(&mut rest).split_at_mut(r.len());
            part.push(head);
            rest = tail;
        }
    }
    let work = parts.into_iter().zip(columns).zip(edges);
    // One part's work (a copy of it for each part: it holds only references).
    let part_work = move |((cols, part), (left, right)): ((_, _), (Vec<_>, Vec<_>))| {
        texture_columns(
            cols,
            part,
            (&left, &right),
            typical,
            disp,
            tan_limit,
            enforce,
        )
    };
    let mut events = Vec::new();
    if work.len() == 1 {
        for item in work {
            events = part_work(item);
        }
        return events;
    }
    for part in crate::parallel::run_parts(work.map(|item| move || part_work(item)).collect()) {
        events.extend(part);
    }
    events
}

/// Columns closer together than this share of their section's typical spacing are squeezed
/// (see [`squeeze_fade`]). A loft's own spacing varies far less: 0.67–1.87 of the typical on
/// the shipped designs' shaped sections outside their folds; a fold's tail spread over its
/// corner comes down to a thousandth of it (measured 2026-12-05).
const SQUEEZE: f64 = 0.25;

/// The share (0 … 1) of the texture a point takes whose neighbours lie `before` and `after` it
/// on a section of typical chord `typical` ([`typical_chord`]): all of it, but where the
/// columns are squeezed together below [`SQUEEZE`] (a concave stretch pushed past its radius of
/// curvature, its fold cut off by the shape, `geometry::trim_swallowtails`), in proportion to
/// the squeeze. The wave there is compressed along the wall; fading it with the squeeze keeps its
/// slope within 1 / SQUEEZE of the design's instead of zig-zagging across the corner.
#[inline]
fn squeeze_fade(before: glam::DVec2, after: glam::DVec2, typical: f64) -> f64 {
    let threshold = SQUEEZE * typical;
    let chord2 = (after - before).length_squared();
    if chord2 >= threshold * threshold {
        1.0
    } else {
        chord2.sqrt() / threshold
    }
}

/// The typical chord `|pᵢ₊₁ − pᵢ₋₁|` of a section: twice its length over its point count, the
/// length measured on every `n / 64`-th point (a fold's corner is short either way).
fn typical_chord(section: &crate::section::Section) -> f64 {
    let p = &section.points;
    let n = p.len();
    if n < 3 {
        // No ring to squeeze: a threshold of nothing fades nothing.
        return 0.0;
    }
    let step = (n / 64).max(1);
    let ring: Vec<glam::DVec2> = p.iter().step_by(step).map(|q| q.truncate()).collect();
    2.0 * crate::geometry::closed_length(&ring) / n as f64
}

/// The largest share (0 … 1) of the texture a column may take at the point `above` over `below`
/// (their untextured normals, their displacements) without leaning past `tan_limit`: the
/// textured offset `b + s·(d n·n_below − d_below)` along the normal below stays within
/// `Δz·tan_limit`.
fn admissible_scale(
    (above, below): (glam::DVec3, glam::DVec3),
    (normal, normal_below): (glam::DVec2, glam::DVec2),
    (d, d_below): (f64, f64),
    tan_limit: f64,
) -> f64 {
    let b = (above.truncate() - below.truncate()).dot(normal_below);
    let dd = d * normal.dot(normal_below) - d_below;
    let limit = (above.z - below.z).max(0.0) * tan_limit;
    let allowed = if dd > 1e-12 {
        (limit - b) / dd
    } else if dd < -1e-12 {
        (limit + b) / -dd
    } else {
        1.0
    };
    allowed.clamp(0.0, 1.0)
}

/// [`apply_displacements`] on the columns `cols` (`part[k]`: section k's points there; `left`,
/// `right`: each section's point just before and after them; `typical`: each section's typical
/// chord): the normals before the texture and the displacements faded where the columns are
/// squeezed, the largest admissible scale of each column and the layer where it binds, the
/// shifts; the columns scaled down, in order.
fn texture_columns(
    cols: std::ops::Range<usize>,
    mut part: Vec<&mut [glam::DVec3]>,
    (left, right): (&[glam::DVec2], &[glam::DVec2]),
    typical: &[f64],
    disp: &[Vec<f64>],
    tan_limit: f64,
    enforce: bool,
) -> Vec<crate::report::PointEvent> {
    let (w, count) = (cols.len(), part.len());
    // Outward normals in XY, section-major, as `Section::normals` has them, and each point's
    // displacement faded by its squeeze.
    let mut normals = Vec::with_capacity(count * w);
    let mut shifts = Vec::with_capacity(count * w);
    for (k, row) in part.iter().enumerate() {
        for c in 0..w {
            let before = if c == 0 {
                left[k]
            } else {
                row[c - 1].truncate()
            };
            let after = if c + 1 == w {
                right[k]
            } else {
                row[c + 1].truncate()
            };
            normals.push(crate::geometry::normal_from_neighbours(before, after));
            shifts.push(disp[k][cols.start + c] * squeeze_fade(before, after, typical[k]));
        }
    }
    // Largest admissible scale per column, and the layer where it binds.
    let mut scale = vec![(1.0_f64, 0_usize); w];
    for k in 1..count {
        let (above, below) = (&part[k], &part[k - 1]);
        for c in 0..w {
            let allowed = admissible_scale(
                (above[c], below[c]),
                (normals[k * w + c], normals[(k - 1) * w + c]),
                (shifts[k * w + c], shifts[(k - 1) * w + c]),
                tan_limit,
            );
            if allowed < scale[c].0 {
                scale[c] = (allowed, k);
            }
        }
    }
    let mut events = Vec::new();
    for (c, &(s, k)) in scale.iter().enumerate() {
        if s < 1.0 - 1e-9 {
            let i = cols.start + c;
            let amp = disp.iter().map(|d| d[i].abs()).fold(0.0, f64::max);
            events.push(crate::report::PointEvent {
                layer: k,
                sample: i,
                amount_mm: amp * (1.0 - s),
            });
        }
    }
    for (k, row) in part.iter_mut().enumerate() {
        for (c, p) in row.iter_mut().enumerate() {
            let s = if enforce { scale[c].0 } else { 1.0 };
            let shift = normals[k * w + c] * (shifts[k * w + c] * s);
            p.x += shift.x;
            p.y += shift.y;
        }
    }
    events
}

#[cfg(test)]
mod tests {
    use super::*;

    /// [`apply_displacements`] as it was written, a whole-surface pass at a time: the reference.
    fn apply_by_passes(
        sections: &mut [crate::section::Section],
        disp: &[Vec<f64>],
        tan_limit: f64,
        enforce: bool,
    ) -> Vec<(usize, usize, u64)> {
        let n = sections[0].points.len();
        let normals: Vec<Vec<glam::DVec2>> = sections.iter().map(|s| s.normals()).collect();
        let shifts: Vec<Vec<f64>> = sections
            .iter()
            .enumerate()
            .map(|(k, s)| {
                let typical = typical_chord(s);
                (0..n)
                    .map(|i| {
                        let (b, a) = crate::geometry::ring_neighbours(i, n);
                        let (b, a) = (s.points[b].truncate(), s.points[a].truncate());
                        disp[k][i] * squeeze_fade(b, a, typical)
                    })
                    .collect()
            })
            .collect();
        let mut scale = vec![(1.0_f64, 0_usize); n];
        for k in 1..sections.len() {
            for i in 0..n {
                let allowed = admissible_scale(
                    (sections[k].points[i], sections[k - 1].points[i]),
                    (normals[k][i], normals[k - 1][i]),
                    (shifts[k][i], shifts[k - 1][i]),
                    tan_limit,
                );
                if allowed < scale[i].0 {
                    scale[i] = (allowed, k);
                }
            }
        }
        let mut events = Vec::new();
        for (i, &(s, k)) in scale.iter().enumerate() {
            if s < 1.0 - 1e-9 {
                let amp = disp.iter().map(|d| d[i].abs()).fold(0.0, f64::max);
                events.push((k, i, (amp * (1.0 - s)).to_bits()));
            }
        }
        for (k, section) in sections.iter_mut().enumerate() {
            for (i, p) in section.points.iter_mut().enumerate() {
                let s = if enforce { scale[i].0 } else { 1.0 };
                let shift = normals[k][i] * (shifts[k][i] * s);
                p.x += shift.x;
                p.y += shift.y;
            }
        }
        events
    }

    /// Column by column in parts gives the whole-surface passes' points and events to the bit,
    /// for one to several hundred samples (one part, and one per core), scaled and not.
    #[test]
    fn texture_in_column_parts_is_the_whole_surface_pass() {
        for n in [1usize, 2, 3, 130, 301, 720] {
            for enforce in [true, false] {
                let sections: Vec<crate::section::Section> = (0..40)
                    .map(|k| crate::section::Section {
                        points: (0..n)
                            .map(|i| {
                                // A tenth of the columns squeezed into a hundredth of the ring,
                                // as a fold's are: their texture fades.
                                let (from, to) = (n / 3, n / 3 + n / 10);
                                let at = if (from..to).contains(&i) {
                                    from as f64 + 0.1 * (i - from) as f64
                                } else if i >= to {
                                    i as f64 - 0.9 * (to - from) as f64
                                } else {
                                    i as f64
                                };
                                let a = std::f64::consts::TAU * at / n as f64;
                                let r = 30.0 + 0.3 * k as f64 + 2.0 * (5.0 * a).sin();
                                glam::DVec3::new(r * a.cos(), r * a.sin(), 0.5 * k as f64)
                            })
                            .collect(),
                    })
                    .collect();
                let disp: Vec<Vec<f64>> = (0..40)
                    .map(|k| {
                        (0..n)
                            .map(|i| 1.5 * ((i * 7 + k * 3) as f64).sin())
                            .collect()
                    })
                    .collect();
                let (mut ours, mut reference) = (sections.clone(), sections);
                let events: Vec<(usize, usize, u64)> =
                    apply_displacements(&mut ours, &disp, 1.0, enforce)
                        .iter()
                        .map(|e| (e.layer, e.sample, e.amount_mm.to_bits()))
                        .collect();
                assert_eq!(
                    events,
                    apply_by_passes(&mut reference, &disp, 1.0, enforce),
                    "{n}"
                );
                assert!(!events.is_empty(), "{n}: the test must scale some columns");
                for (a, b) in ours.iter().zip(&reference) {
                    for (p, q) in a.points.iter().zip(&b.points) {
                        assert_eq!(
                            p.to_array().map(f64::to_bits),
                            q.to_array().map(f64::to_bits),
                            "{n}"
                        );
                    }
                }
            }
        }
    }

    /// Where a tenth of a ring's columns are squeezed into a hundredth of it (chords about a
    /// tenth of the typical), they take about 0.1 / SQUEEZE = 0.4 of the texture; the rest all
    /// of it.
    #[test]
    fn a_squeezed_stretch_takes_its_texture_in_proportion() {
        let n = 360;
        let at = |i: usize| {
            let (from, to) = (100, 136);
            if (from..to).contains(&i) {
                from as f64 + 0.1 * (i - from) as f64
            } else if i >= to {
                i as f64 - 0.9 * (to - from) as f64
            } else {
                i as f64
            }
        };
        let ring = |z: f64| crate::section::Section {
            points: (0..n)
                .map(|i| {
                    let a = std::f64::consts::TAU * at(i) / (n as f64 - 32.4);
                    glam::DVec3::new(30.0 * a.cos(), 30.0 * a.sin(), z)
                })
                .collect(),
        };
        let before = vec![ring(0.0), ring(0.5)];
        let mut after = before.clone();
        let events = apply_displacements(&mut after, &vec![vec![1.0; n]; 2], 1e9, true);
        assert!(events.is_empty());
        for i in 0..n {
            let moved = after[1].points[i].distance(before[1].points[i]);
            // The squeezed chords against the typical (the ring's mean, a little longer than
            // the unsqueezed ones' spacing over the whole ring): 0.1 · 360 / 327.6.
            let squeezed = 0.1 * n as f64 / (n as f64 - 32.4);
            let expected = if (101..=135).contains(&i) {
                squeezed / SQUEEZE
            } else {
                1.0
            };
            assert!((moved - expected).abs() < 0.02, "column {i}: moved {moved}");
        }
    }

    fn w(wave: WaveKind, period: f64, amplitude: f64) -> Wave {
        Wave {
            wave,
            period,
            amplitude,
        }
    }

    #[test]
    fn sine_known_values() {
        let s = w(WaveKind::Sine, 8.0, 2.0);
        assert!(wave_value(&s, 0.0).abs() < 1e-12);
        assert!((wave_value(&s, 2.0) - 2.0).abs() < 1e-12);
        assert!((wave_value(&s, 6.0) + 2.0).abs() < 1e-12);
        assert!((wave_value(&s, 1.0) - 2.0 * (std::f64::consts::PI / 4.0).sin()).abs() < 1e-12);
    }

    #[test]
    fn triangle_known_values() {
        let t = w(WaveKind::Triangle, 10.0, 2.0);
        let expected = [2.0, 1.2, 0.4, -0.4, -1.2, -2.0, -1.2, -0.4, 0.4, 1.2, 2.0];
        for (x, e) in expected.iter().enumerate() {
            assert!((wave_value(&t, x as f64) - e).abs() < 1e-12, "x={x}");
        }
        let y = w(WaveKind::Triangle, 2.0, 2.0);
        assert_eq!(
            [0.0, 1.0, 2.0, 3.0].map(|k| wave_value(&y, k)),
            [2.0, -2.0, 2.0, -2.0]
        );
    }

    #[test]
    fn square_known_values() {
        let q = w(WaveKind::Square, 4.0, 1.5);
        assert_eq!(
            [0.0, 1.0, 2.0, 3.0, 4.0, 5.0].map(|x| wave_value(&q, x)),
            [0.0, 1.5, 0.0, -1.5, 0.0, 1.5]
        );
    }

    #[test]
    fn paper_example_product_and_sum() {
        let mut tex = Texture {
            combine: Combine::Product,
            x: Some(w(WaveKind::Triangle, 10.0, 2.0)),
            y: Some(w(WaveKind::Triangle, 2.0, 2.0)),
            phase_drift: 0.0,
            start: 0.0,
            end: 1.0,
        };
        assert_eq!(displacement(&tex, 0, 0, 100), 4.0);
        assert_eq!(displacement(&tex, 0, 1, 100), -4.0);
        assert!((displacement(&tex, 1, 1, 100) + 2.4).abs() < 1e-12);
        tex.combine = Combine::Sum;
        assert!((displacement(&tex, 1, 1, 100) - (1.2 - 2.0)).abs() < 1e-12);
    }

    #[test]
    fn height_range_and_phase_drift() {
        let tex = Texture {
            combine: Combine::Product,
            x: Some(w(WaveKind::Sine, 8.0, 1.0)),
            y: None,
            phase_drift: 2.0,
            start: 0.5,
            end: 1.0,
        };
        assert_eq!(displacement(&tex, 2, 10, 100), 0.0);
        // Layer 60, sample 0: x = 0 + 2·60 = 120 = 15 periods → 0; sample 2 → x = 122 → sin(π/2).
        assert!(displacement(&tex, 0, 60, 100).abs() < 1e-9);
        assert!((displacement(&tex, 2, 60, 100) - 1.0).abs() < 1e-9);
    }
}
