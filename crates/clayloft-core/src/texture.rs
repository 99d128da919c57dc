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
) -> TextureLowered {
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
/// In two passes over the sections, each shared out in runs of sections as the cores get
/// free:
/// 1. each section's normals and shifts, faded where the texture would fold the ring
///    (`fold_fade`), and the least admissible scale of each column over the run's sections
///    (`least_scales`), while the normals and shifts just made are at hand: a column's scale
///    is its least over all layers, the lowest layer where it binds on a tie, so the runs'
///    least are merged in order of their layers;
/// 2. the points moved by their shifts, scaled down (`move_points`).
///
/// Each section is read and written by one core at a time. Cut by columns instead (as it was),
/// both cores wrote every section, and where the host places the two cores apart a core
/// writing lines the other holds waits for each to cross: `clayloft gcode` of the benchmark
/// vase 59.6 → 57.6 ms with the cores apart, 49.8 → 49.3 ms together (medians of 134 and 805
/// alternating rounds, 2026-12-07).
pub fn apply_displacements(
    sections: &mut [crate::section::Section],
    disp: &[Vec<f64>],
    tan_limit: f64,
    enforce: bool,
) -> TextureLowered {
    let n = sections.first().map_or(0, |s| s.points.len());
    if n == 0 {
        return TextureLowered::default();
    }
    // A section that folds costs many times one that does not, and they come in bands of
    // layers: runs shared out as the cores get free, not halves.
    let serial_below = crate::parallel::PARALLEL_POINTS / n;
    let runs = crate::parallel::runs(sections.len(), serial_below, FOLD_FADE_RUN);
    apply_in_runs(sections, disp, tan_limit, enforce, &runs)
}

/// [`apply_displacements`] with the sections cut into `runs` (consecutive, from the first
/// section to the last): the same points and events whatever the runs.
fn apply_in_runs(
    sections: &mut [crate::section::Section],
    disp: &[Vec<f64>],
    tan_limit: f64,
    enforce: bool,
    runs: &[std::ops::Range<usize>],
) -> TextureLowered {
    let (n, count) = (sections[0].points.len(), sections.len());
    let typical: Vec<f64> = sections.iter().map(typical_chord).collect();
    let faded_runs: Vec<(Vec<FoldFade>, Vec<Least>)> = {
        let sections = &*sections;
        let run = |ks: std::ops::Range<usize>| {
            let faded: Vec<FoldFade> = ks
                .clone()
                .map(|k| fold_fade(&sections[k].points, &disp[k], typical[k]))
                .collect();
            let least = least_scales(sections, ks.start, &faded, tan_limit);
            (faded, least)
        };
        if runs.len() == 1 {
            vec![run(0..count)]
        } else {
            crate::parallel::map_shared(runs.len(), || (), |(), r| run(runs[r].clone()))
        }
    };
    // The runs' least in order of their layers, each run's first section (over the last of the
    // run before) in its place.
    let mut scale: Vec<Least> = vec![(1.0, 0); n];
    for (r, (faded, least)) in faded_runs.iter().enumerate() {
        if r > 0 {
            let k = runs[r].start;
            let below = faded_runs[r - 1].0.last().expect("a run has sections");
            let pair = (&sections[k].points[..], &sections[k - 1].points[..]);
            lessen(&mut scale, pair, (&faded[0], below), k, tan_limit);
        }
        for (s, &candidate) in scale.iter_mut().zip(least) {
            keep_least(s, candidate);
        }
    }
    let folds = faded_runs
        .iter()
        .flat_map(|(faded, _)| faded)
        .enumerate()
        .flat_map(|(layer, f)| {
            f.lowered
                .iter()
                .map(move |&(sample, amount_mm)| crate::report::PointEvent {
                    layer,
                    sample,
                    amount_mm,
                })
        })
        .collect();
    let overhang = scale
        .iter()
        .enumerate()
        .filter(|(_, (s, _))| *s < 1.0 - 1e-9)
        .map(|(i, &(s, k))| {
            let amp = disp.iter().map(|d| d[i].abs()).fold(0.0, f64::max);
            crate::report::PointEvent {
                layer: k,
                sample: i,
                amount_mm: amp * (1.0 - s),
            }
        })
        .collect();
    let scale: Vec<f64> = scale
        .iter()
        .map(|&(s, _)| if enforce { s } else { 1.0 })
        .collect();
    // Each run's sections moved by the core that takes the run.
    let mut moves: Vec<_> = Vec::with_capacity(runs.len());
    let (mut rest, scale) = (&mut *sections, &scale);
    for (range, (faded, _)) in runs.iter().zip(&faded_runs) {
        let (run, tail) = std::mem::take(&mut rest).split_at_mut(range.len());
        rest = tail;
        moves.push(move || move_points(run, faded, scale));
    }
    if moves.len() == 1 {
        moves.into_iter().for_each(|mut move_run| move_run());
    } else {
        crate::parallel::run_shared(moves);
    }
    TextureLowered { overhang, folds }
}

/// A column's least admissible share of the texture, and the layer where it binds.
type Least = (f64, usize);

/// The least admissible scale of each column over sections `first + 1 ..` of a run (`faded`:
/// the run's sections' [`FoldFade`], from section `first` on), the lowest layer on a tie;
/// (1, 0) for a column that none lessens.
fn least_scales(
    sections: &[crate::section::Section],
    first: usize,
    faded: &[FoldFade],
    tan_limit: f64,
) -> Vec<Least> {
    let n = sections[first].points.len();
    let mut least = vec![(1.0, 0); n];
    for (j, pair) in faded.windows(2).enumerate() {
        let k = first + j + 1;
        let points = (&sections[k].points[..], &sections[k - 1].points[..]);
        lessen(&mut least, points, (&pair[1], &pair[0]), k, tan_limit);
    }
    least
}

/// Lowers each column's `least` to its admissible scale at section k (`points`, `faded`: of
/// section k and the one below), where that is less.
fn lessen(
    least: &mut [Least],
    (above, below): (&[glam::DVec3], &[glam::DVec3]),
    (faded, faded_below): (&FoldFade, &FoldFade),
    k: usize,
    tan_limit: f64,
) {
    for (c, l) in least.iter_mut().enumerate() {
        let allowed = admissible_scale(
            (above[c], below[c]),
            (faded.normals[c], faded_below.normals[c]),
            (faded.shifts[c], faded_below.shifts[c]),
            tan_limit,
        );
        keep_least(l, (allowed, k));
    }
}

/// `least` lowered to `candidate` where that is strictly less: of two equal scales the one
/// met first, from a lower layer, stays.
fn keep_least(least: &mut Least, candidate: Least) {
    if candidate.0 < least.0 {
        *least = candidate;
    }
}

/// Moves the points of `sections` along their normals by their shifts (`faded`, one per
/// section), each column's scaled by `scale`.
fn move_points(sections: &mut [crate::section::Section], faded: &[FoldFade], scale: &[f64]) {
    for (s, f) in sections.iter_mut().zip(faded) {
        for (c, p) in s.points.iter_mut().enumerate() {
            let shift = f.normals[c] * (f.shifts[c] * scale[c]);
            p.x += shift.x;
            p.y += shift.y;
        }
    }
}

/// Where [`apply_displacements`] lowered the texture: one event per column lowered to keep the
/// overhang limit (at the layer where it binds), and one per point faded so as not to fold the
/// wall (`fold_fade`); amounts in mm of texture removed.
#[derive(Debug, Default)]
pub struct TextureLowered {
    pub overhang: Vec<crate::report::PointEvent>,
    pub folds: Vec<crate::report::PointEvent>,
}

/// How far, in samples, [`fold_fade`] looks on either side of a point where the wall turns
/// more sharply than the texture is deep: a fold whose loop spans up to twice this is seen.
const FOLD_REACH: usize = 16;

/// Sections a core fades at a time ([`apply_displacements`]).
const FOLD_FADE_RUN: usize = 8;

/// Rounds of [`fold_fade`] that halve a fold's texture; the next ones take all of it, and after
/// [`FOLD_ROUNDS`] what still folds is left as it is.
const FOLD_HALVINGS: usize = 6;
const FOLD_ROUNDS: usize = FOLD_HALVINGS + 4;

/// One section's texture as its points take it: along their outward normals before the
/// texture, faded where it would fold the wall back on itself.
#[derive(Debug)]
struct FoldFade {
    /// Every point's outward unit normal in XY before the texture ([`Section::normals`]'s).
    ///
    /// [`Section::normals`]: crate::section::Section::normals
    normals: Vec<glam::DVec2>,
    /// Every point's shift along it, mm (the squeeze's fade included).
    shifts: Vec<f64>,
    /// The points faded, and by how much, mm.
    lowered: Vec<(usize, f64)>,
}

/// The texture's shifts on one section (`points`, untextured; `disp`, its displacements;
/// `typical`, its typical chord) and the normals they move the points along, faded where they
/// would fold the ring back on itself (where nothing folds, the shifts are
/// `disp · squeeze_fade`). Made once a section, the texture's scale and move read them
/// ([`least_scales`], [`move_points`]).
///
/// Displacing along the normals by `s` offsets the wall, and an offset folds where it is deeper
/// than the wall's radius of curvature there (`s κ > 1`): at a sharp tip pushed in, a sharp
/// valley pushed out, the corner of a cut fold. The points beside it change places and the
/// nozzle traces an X or a loop. So only around the points where the ring turns more sharply
/// than twice the deepest shift allows (`|nᵢ₊₁ − nᵢ| · 2 max|s| > |pᵢ₊₁ − pᵢ|`), within
/// [`FOLD_REACH`] points, the displaced ring `q = p + s n` is searched for segments that cross
/// another and for chords `qᵢ → qᵢ₊ₘ` that point against `pᵢ → pᵢ₊ₘ` (a stretch run
/// backwards). The ends of each have their texture halved, round by round, then taken away:
/// the untextured ring (s = 0) has neither. The fade comes before the overhang's scale,
/// which is worked out on the faded shifts.
fn fold_fade(points: &[glam::DVec3], disp: &[f64], typical: f64) -> FoldFade {
    use glam::DVec2;
    let n = points.len();
    let p = |i: usize| points[i].truncate();
    let (normals, given): (Vec<DVec2>, Vec<f64>) = (0..n)
        .map(|i| {
            let (b, a) = crate::geometry::ring_neighbours(i, n);
            let shift = disp[i] * squeeze_fade(p(b), p(a), typical);
            (crate::geometry::normal_from_neighbours(p(b), p(a)), shift)
        })
        .unzip();
    match faded_where_folding(points, &normals, &given) {
        Some((shifts, lowered)) => FoldFade {
            normals,
            shifts,
            lowered,
        },
        None => FoldFade {
            normals,
            shifts: given,
            lowered: Vec::new(),
        },
    }
}

/// Shifts faded where they would fold a ring, and the points faded, by how much (mm).
type Faded = (Vec<f64>, Vec<(usize, f64)>);

/// [`fold_fade`]'s shifts `given` (along `normals`) of the ring `points` faded where they fold
/// it, and the points faded by how much; none where nothing folds.
fn faded_where_folding(
    points: &[glam::DVec3],
    normals: &[glam::DVec2],
    given: &[f64],
) -> Option<Faded> {
    use glam::DVec2;
    let n = points.len();
    if n < 4 || given.iter().all(|&s| s == 0.0) {
        return None;
    }
    let at = |i: usize| if i < n { i } else { i - n };
    let p: Vec<DVec2> = points.iter().map(|q| q.truncate()).collect();
    // Twice the deepest shift: the normals from neighbours spread a corner's turn over two
    // points, so a corner looks half as sharp as it is.
    let deepest = 2.0 * given.iter().fold(0.0_f64, |m, s| m.max(s.abs()));
    // The stretches around the sharp turns, as (first point, points), wrapping, apart.
    let mut stretches: Vec<(usize, usize)> = Vec::new();
    let reach = FOLD_REACH.min(n / 2 - 1);
    let mut covered = 0; // points of the ring up to which the last stretch reaches
    for i in 0..n {
        let j = at(i + 1);
        let sharp = (normals[j] - normals[i]).length_squared() * deepest * deepest
            > (p[j] - p[i]).length_squared();
        if !sharp {
            continue;
        }
        let (from, to) = (i + n - reach, i + n + 1 + reach); // in 0..3n, `to` exclusive
        match stretches.last_mut() {
            Some((first, len)) if from <= covered => {
                *len = (to - *first).min(n);
                covered = to;
            }
            _ => {
                stretches.push((from, to - from));
                covered = to;
            }
        }
    }
    if stretches.is_empty() {
        return None;
    }
    // A last stretch reaching round to the first one: the whole ring, once.
    if let (Some(&(first, _)), Some(&(last, len))) = (stretches.first(), stretches.last())
        && stretches.len() > 1
        && last + len >= first + n
    {
        stretches = vec![(first, n)];
    }
    let mut q: Vec<DVec2> = (0..n).map(|i| p[i] + normals[i] * given[i]).collect();
    let mut shifts = given.to_vec();
    let mut folded = vec![false; n];
    // A stretch found clean stays clean: only its own points move. After the first round, a
    // stretch is searched only where its points moved (the points marked the round before).
    let mut active = vec![true; stretches.len()];
    let mut marked: Vec<Vec<usize>> = vec![Vec::new(); stretches.len()];
    let (mut ps, mut qs) = (Vec::new(), Vec::new());
    for round in 0..FOLD_ROUNDS {
        let mut found = false;
        for ((&(first, len), active), marked) in stretches.iter().zip(&mut active).zip(&mut marked)
        {
            if !*active {
                continue;
            }
            ps.clear();
            qs.clear();
            ps.extend((first..first + len).map(|i| p[i % n]));
            qs.extend((first..first + len).map(|i| q[i % n]));
            let moved = (round > 0).then(|| touching(len, marked));
            marked.clear();
            *active = mark_folds(&ps, &qs, reach, moved.as_deref(), |k| {
                folded[(first + k) % n] = true;
                marked.push(k);
            });
            found |= *active;
        }
        if !found {
            break;
        }
        let factor = if round < FOLD_HALVINGS { 0.5 } else { 0.0 };
        for i in 0..n {
            if std::mem::take(&mut folded[i]) {
                shifts[i] *= factor;
                q[i] = p[i] + normals[i] * shifts[i];
            }
        }
    }
    let lowered: Vec<(usize, f64)> = (0..n)
        .filter(|&i| shifts[i] != given[i])
        .map(|i| (i, (given[i] - shifts[i]).abs()))
        .collect();
    (!lowered.is_empty()).then_some((shifts, lowered))
}

/// Which of a stretch's `len` points touch a point of `marked`: the point itself, or the one
/// after it (the segment from it ends there).
fn touching(len: usize, marked: &[usize]) -> Vec<bool> {
    let mut touches = vec![false; len];
    for &k in marked {
        touches[k] = true;
        if k > 0 {
            touches[k - 1] = true;
        }
    }
    touches
}

/// Marks (by `mark(k)`) the ends of the chords `qₖ → qₖ₊ₘ` (m ≤ `reach`) of a stretch that
/// point against `pₖ → pₖ₊ₘ`, and of the segments that cross one `m ≥ 2` further on; whether
/// any.
///
/// With `moved` (see [`touching`]: the points that touch a point moved since the stretch was
/// last searched), only the pairs with an end that touches one are tested. The others are as
/// they were: none folded then (a pair that folds marks its ends, which then move), and none
/// folds now.
fn mark_folds(
    p: &[glam::DVec2],
    q: &[glam::DVec2],
    reach: usize,
    moved: Option<&[bool]>,
    mut mark: impl FnMut(usize),
) -> bool {
    let len = q.len();
    let mut folds = 0;
    // Tests pair (a, b), marking its ends where it folds (a macro: a closure here is not
    // inlined, and the search costs a third more).
    macro_rules! test {
        ($a:expr, $b:expr) => {{
            let (a, b) = ($a, $b);
            let pair = pair_folds(p, q, a, b);
            if pair != 0 {
                folds |= pair;
                mark(a);
                mark(b);
                if pair & CROSSES != 0 {
                    mark(a + 1);
                    mark(b + 1);
                }
            }
        }};
    }
    match moved {
        None => {
            for a in 0..len {
                for b in a + 1..=(a + reach).min(len - 1) {
                    test!(a, b);
                }
            }
        }
        Some(moved) => {
            // Each pair with a moved end once: from its first end, else from its second.
            for a in (0..len).filter(|&a| moved[a]) {
                for b in a + 1..=(a + reach).min(len - 1) {
                    test!(a, b);
                }
            }
            for b in (0..len).filter(|&b| moved[b]) {
                for a in (b.saturating_sub(reach)..b).filter(|&a| !moved[a]) {
                    test!(a, b);
                }
            }
        }
    }
    folds != 0
}

/// [`pair_folds`]: the chord from a to b runs backwards (its ends are marked).
const RUNS_BACK: u8 = 1;
/// [`pair_folds`]: segment a crosses segment b (the ends of both are marked).
const CROSSES: u8 = 2;

/// How points a < b of a stretch fold ([`mark_folds`]): [`RUNS_BACK`] where `q[a] → q[b]`
/// points against `p[a] → p[b]`, [`CROSSES`] where segment a (a → a + 1) crosses segment b
/// (b → b + 1) and they are not neighbours.
#[inline(always)]
fn pair_folds(p: &[glam::DVec2], q: &[glam::DVec2], a: usize, b: usize) -> u8 {
    let mut folds = 0;
    if (q[b] - q[a]).dot(p[b] - p[a]) < 0.0 {
        folds |= RUNS_BACK;
    }
    if b >= a + 2 && b + 1 < q.len() {
        let (a0, a1, b0, b1) = (q[a], q[a + 1], q[b], q[b + 1]);
        let apart = a0.max(a1).cmplt(b0.min(b1)).any() || b0.max(b1).cmplt(a0.min(a1)).any();
        if !apart && crate::geometry::segments_intersect(a0, a1, b0, b1) {
            folds |= CROSSES;
        }
    }
    folds
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

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The points [`mark_folds`] marks, in order, each once.
    fn folds_marked(p: &[glam::DVec2], q: &[glam::DVec2], moved: Option<&[bool]>) -> Vec<usize> {
        let mut marked = std::collections::BTreeSet::new();
        let any = mark_folds(p, q, FOLD_REACH, moved, |k| {
            marked.insert(k);
        });
        assert_eq!(any, !marked.is_empty());
        marked.into_iter().collect()
    }

    proptest! {
        /// A stretch searched again only where its marked points moved finds what a whole search
        /// finds, whatever the marked points are moved to.
        #[test]
        fn folds_searched_where_points_moved_are_the_whole_search(
            radius in proptest::collection::vec(20.0..21.0f64, 40..90),
            wiggle in proptest::collection::vec(-3.0..3.0f64, 90),
            moves in proptest::collection::vec((-4.0..4.0f64, -4.0..4.0f64), 90),
        ) {
            let n = radius.len();
            let at = |k: usize, r: f64| {
                let t = k as f64 * 0.05;
                glam::DVec2::new(r * t.cos(), r * t.sin())
            };
            let p: Vec<glam::DVec2> = (0..n).map(|k| at(k, radius[k])).collect();
            let q: Vec<glam::DVec2> = (0..n).map(|k| at(k, radius[k] + wiggle[k])).collect();
            let first = folds_marked(&p, &q, None);
            let mut moved_q = q.clone();
            for &k in &first {
                moved_q[k] += glam::DVec2::from(moves[k]);
            }
            let touches = touching(n, &first);
            prop_assert_eq!(
                folds_marked(&p, &moved_q, Some(&touches)),
                folds_marked(&p, &moved_q, None)
            );
        }
    }

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

    /// In runs of sections, merged, gives the whole-surface passes' points and events to the
    /// bit, for one to several hundred samples, scaled and not, and whatever the runs: one
    /// run, runs of one section (every run's least over its own sections empty: all comes from
    /// the merge), runs of 3 and 7 (the last shorter), and as `apply_displacements` cuts them.
    #[test]
    fn texture_in_runs_of_sections_is_the_whole_surface_pass() {
        let cut = |count: usize, run: usize| -> Vec<std::ops::Range<usize>> {
            (0..count)
                .step_by(run)
                .map(|s| s..(s + run).min(count))
                .collect()
        };
        for n in [1usize, 2, 3, 130, 301, 720] {
            for (enforce, run) in [true, false]
                .into_iter()
                .flat_map(|e| [0, 1, 3, 7, 40].map(|r| (e, r)))
            {
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
                let lowered = if run == 0 {
                    apply_displacements(&mut ours, &disp, 1.0, enforce)
                } else {
                    apply_in_runs(&mut ours, &disp, 1.0, enforce, &cut(40, run))
                };
                let events: Vec<(usize, usize, u64)> = lowered
                    .overhang
                    .iter()
                    .map(|e| (e.layer, e.sample, e.amount_mm.to_bits()))
                    .collect();
                assert_eq!(
                    events,
                    apply_by_passes(&mut reference, &disp, 1.0, enforce),
                    "{n} {run}"
                );
                assert!(!events.is_empty(), "{n}: the test must scale some columns");
                for (a, b) in ours.iter().zip(&reference) {
                    for (p, q) in a.points.iter().zip(&b.points) {
                        assert_eq!(
                            p.to_array().map(f64::to_bits),
                            q.to_array().map(f64::to_bits),
                            "{n} {run}"
                        );
                    }
                }
            }
        }
    }

    /// A four-pointed star's ring (outer radius 26.75, inner 13.23: tips of about 50°), `n`
    /// points spaced evenly along it, at height `z`.
    fn star(n: usize, z: f64) -> crate::section::Section {
        let corners: Vec<glam::DVec2> = (0..8)
            .map(|c| {
                let r = if c % 2 == 0 { 26.75 } else { 13.23 };
                glam::DVec2::from_angle(std::f64::consts::TAU * c as f64 / 8.0) * r
            })
            .collect();
        let ring = crate::geometry::resample_closed(&corners, n);
        crate::section::Section {
            points: ring.iter().map(|p| p.extend(z)).collect(),
        }
    }

    /// A texture deeper than a sharp tip is wide (1.8 mm inward, or a zig-zag of ±1.4 mm every
    /// other point, on the tips of a four-pointed star 60 or 200 points round) makes the
    /// points beside each tip change places: the ring crosses itself there. Faded where it
    /// would cross or run back, it does not, the tips lose only part of their texture, and the
    /// flanks keep all of it.
    #[test]
    fn a_texture_deeper_than_a_tip_is_wide_does_not_fold_it() {
        type ShiftAt = fn(usize) -> f64;
        let textures: [(usize, ShiftAt); 2] = [
            (60, |_| -1.8),
            (200, |i| 1.41 * [1.0, 0.0, -1.0, 0.0][i % 4]),
        ];
        for (n, texture) in textures {
            let before = vec![star(n, 0.0), star(n, 0.5)];
            let disp = vec![(0..n).map(texture).collect::<Vec<f64>>(); 2];
            let ring = |s: &crate::section::Section| -> Vec<glam::DVec2> {
                s.points.iter().map(|p| p.truncate()).collect()
            };
            // Displaced along the normals as given, it crosses itself.
            let normals = before[1].normals();
            let raw: Vec<glam::DVec2> = (0..n)
                .map(|i| before[1].points[i].truncate() + normals[i] * disp[1][i])
                .collect();
            let crossing = crate::geometry::find_self_intersection;
            assert!(crossing(&raw).is_some(), "{n}: the test needs a fold");
            let mut after = before.clone();
            let lowered = apply_displacements(&mut after, &disp, 1e9, true);
            assert!(lowered.overhang.is_empty(), "{n}");
            assert_eq!(crossing(&ring(&after[1])), None, "{n}");
            assert!(!lowered.folds.is_empty(), "{n}");
            assert!(
                lowered.folds.len() < n / 2,
                "{n}: {} faded",
                lowered.folds.len()
            );
            // The flanks, a tenth of the ring away from each tip, keep their texture.
            let pairs = after[1].points.iter().zip(&before[1].points);
            for (i, ((moved_to, was), d)) in pairs.zip(&disp[1]).enumerate() {
                let from_tip = (0..4)
                    .map(|t| (i as i64 - (t * n / 4) as i64).rem_euclid(n as i64))
                    .map(|d| d.min(n as i64 - d))
                    .min()
                    .unwrap();
                if from_tip as usize > n / 10 {
                    let moved = moved_to.distance(*was);
                    assert!((moved - d.abs()).abs() < 1e-9, "{n}: point {i}");
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
        let lowered = apply_displacements(&mut after, &vec![vec![1.0; n]; 2], 1e9, true);
        assert!(lowered.overhang.is_empty() && lowered.folds.is_empty());
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
