//! Will the wall stand while it is printed (SPEC §14)? The wet wall is judged along the real
//! toolpath: every layer's age is the print time since it was laid, its clay stiffens with that
//! age ([`crate::clay::ClayBody`]), and as each layer j is finished every layer k below it carries
//! the weight of the wall from its own bottom to the top of layer j. Two ways to fail are
//! checked, after the published models of layer-by-layer extrusion of yield-stress pastes:
//!
//! * **Plastic collapse** (Roussel 2018, *Cem. Concr. Res.* 112:76, eq. for the "layer-by-layer"
//!   buildability; Perrot et al. 2016, *Mater. Struct.* 49:1213): layer k flows when the vertical
//!   stress ρ·g·h of the wall above it exceeds its compressive yield strength √3·τ₀(age) (von
//!   Mises: a uniaxial yield stress is √3 times the shear yield stress). Safety factor
//!   `F = √3·τ₀(age) / (ρ·g·h)`.
//! * **Elastic buckling** of the thin wall as an axially compressed cylindrical shell (the
//!   classical critical stress σ_cr = E·e / (R·√(3(1 − ν²))), Timoshenko & Gere, *Theory of
//!   Elastic Stability* §11.4; ν = ½ for an incompressible paste, so σ_cr = E·e/(1.5·R)), reduced
//!   by the NASA SP-8007 (1968) knock-down for imperfect shells,
//!   γ = 1 − 0.901·(1 − e^{−√(R/e)/16}). Layer k buckles when the stress on it exceeds γ·σ_cr
//!   with its own stiffness E(age): `F = γ·E(age)·e / (1.5·R·ρ·g·h)`. Suiker (2018, *Int. J.
//!   Mech. Sci.* 137:145) and Wolfs et al. (2018, *Cem. Concr. Res.* 106:103) treat printed walls
//!   with stiffness that grows with age the same way; this local check is their simplest form.
//!
//! Assumptions, stated so that a teacher can discuss them: the wall is a cylinder of the
//! layer's own length (R = perimeter / 2π; a star or a flat side is weaker than that) and of the
//! bead width times the beads of the wall (e); the clay stiffens linearly with age (τ₀ + A·t,
//! over the first hour or so of a print); the weight is that of a vertical wall (a wall that
//! flares carries a little more per bead); the base, a solid disc, does not buckle; the
//! youngest point of each layer (its end) stands for the layer.

use glam::DVec2;

use crate::clay::{ClayBody, GRAVITY};
use crate::design::Design;
use crate::pipeline::Surface;
use crate::toolpath::Toolpath;
use crate::validate::FieldError;

/// Layers judged at most (longer prints are judged in groups of consecutive layers): keeps the
/// pairwise check and the search for a minimum layer time bounded on any design.
const MAX_LAYERS: usize = 600;
/// Longest minimum layer time searched for, s.
const MAX_LAYER_TIME: f64 = 3600.0;

/// How the wall fails.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mechanism {
    PlasticCollapse,
    Buckling,
}

impl Mechanism {
    /// Short name for a summary line.
    pub fn name(self) -> &'static str {
        match self {
            Mechanism::PlasticCollapse => "plastic collapse",
            Mechanism::Buckling => "buckling",
        }
    }

    /// What it means, in words a student understands.
    pub fn explanation(self) -> &'static str {
        match self {
            Mechanism::PlasticCollapse => {
                "the soft clay low in the wall is squeezed out sideways by the weight of the wall above it before it has stiffened enough to carry it"
            }
            Mechanism::Buckling => {
                "the wall is too thin and soft for its height: like a sheet of paper stood on end it bends sideways under its own weight and folds"
            }
        }
    }
}

/// The verdict on a print.
#[derive(Debug, Clone, PartialEq)]
pub struct Printability {
    pub body: ClayBody,
    /// The lowest safety factor anywhere in the print (≥ 1: it stands).
    pub factor: f64,
    pub mechanism: Mechanism,
    /// The layer that fails first (1-based, as the G-code's layer messages count) and its top, mm.
    pub layer: usize,
    pub z: f64,
    /// The layer whose laying loads it most (1-based).
    pub loaded_by: usize,
    /// Below 1: the smallest `printer.min_layer_time` that makes the print stand, s (`None`: none
    /// up to an hour does).
    pub min_layer_time_to_stand: Option<f64>,
    /// Each judged layer's top, mm, and its own lowest safety factor over the print, bottom up
    /// (for colouring the wall).
    pub layer_factors: Vec<(f64, f64)>,
    /// The layers with a stretch of bead that has nothing under it ([`droops`]), the one most
    /// past its limit first.
    pub droops: Vec<Droop>,
}

impl Printability {
    /// The lowest safety factor of the layer at height `z`, mm (the layer whose top is the first
    /// at or above it).
    pub fn factor_at(&self, z: f64) -> f64 {
        let i = self
            .layer_factors
            .partition_point(|&(top, _)| top < z - 1e-9);
        self.layer_factors
            .get(i)
            .or(self.layer_factors.last())
            .map_or(f64::INFINITY, |&(_, f)| f)
    }
}

/// One judged layer (or group of layers).
#[derive(Debug, Clone, Copy)]
struct Layer {
    /// Time it takes, s.
    duration: f64,
    /// Bottom and top, m.
    bottom: f64,
    top: f64,
    /// Equivalent shell radius, m (0 for the base).
    radius: f64,
    /// First layer (1-based) it stands for.
    first: usize,
}

/// Judges the print of `toolpath` in the design's clay body.
///
/// With it, the layers of `surface` (the toolpath's wall) that droop, found meanwhile. The
/// toolpath's layers are summed first, on every core (a pass over every point: the verdict's
/// larger part, 2.9 ms of 3.1 ms on the benchmark vase in a slow hour, when it was summed on one
/// core beside the droops); then the verdict on them is one task, the droops of runs of 32
/// layers (`DROOP_RUN`) the others, shared out as the cores get free.
pub fn assess(
    design: &Design,
    surface: &Surface,
    toolpath: &Toolpath,
) -> Result<Printability, FieldError> {
    let body = crate::clay::resolve(design.clay.as_ref())?;
    let layers = surface.sections.len();
    let (mut verdict, mut droops) = (None, Vec::new());
    if toolpath.points.len() >= crate::parallel::PARALLEL_POINTS && layers > 2 {
        let path_layers = layers_of(design, toolpath);
        let runs = (layers - 2).div_ceil(DROOP_RUN);
        let done = crate::parallel::map_shared(
            1 + runs,
            || (),
            |(), task| match task.checked_sub(1) {
                None => (Some(standing_on(design, &body, &path_layers)), Vec::new()),
                Some(r) => {
                    let from = 2 + r * DROOP_RUN;
                    let ks = from..(from + DROOP_RUN).min(layers);
                    (None, droops_in(design, &body, surface, ks))
                }
            },
        );
        for (v, d) in done {
            verdict = verdict.or(v);
            droops.extend(d);
        }
    } else {
        droops = droops_in(design, &body, surface, 2..layers.max(2));
    }
    let verdict = verdict.unwrap_or_else(|| standing(design, &body, toolpath));
    droops.sort_by(|a, b| (b.length - b.limit).total_cmp(&(a.length - a.limit)));
    Ok(Printability { droops, ..verdict })
}

/// Layers a task of [`assess`] searches for droops.
const DROOP_RUN: usize = 32;

/// The safety factor of the wet wall of `toolpath` in clay `body` (see the module
/// documentation), and the layer time that would make it stand.
fn standing(design: &Design, body: &ClayBody, toolpath: &Toolpath) -> Printability {
    standing_on(design, body, &layers_of(design, toolpath))
}

/// [`standing`], of the toolpath's `layers` ([`layers_of`]).
fn standing_on(design: &Design, body: &ClayBody, layers: &[Layer]) -> Printability {
    let thickness = design.shape.walls.max(1) as f64 * design.printer.line_width * 1e-3;
    let mut verdict = weakest(body, layers, thickness, 0.0);
    verdict.min_layer_time_to_stand =
        if verdict.factor >= 1.0 || weakest(body, layers, thickness, MAX_LAYER_TIME).factor < 1.0 {
            // It stands already, or no layer time up to an hour saves it.
            None
        } else {
            // The factor grows with every layer's duration: bisect the minimum layer time.
            let (mut lo, mut hi) = (0.0, MAX_LAYER_TIME);
            for _ in 0..40 {
                let mid = 0.5 * (lo + hi);
                if weakest(body, layers, thickness, mid).factor >= 1.0 {
                    hi = mid;
                } else {
                    lo = mid;
                }
            }
            Some(hi)
        };
    verdict
}

/// The toolpath's layers (base layers and wall revolutions), grouped to at most [`MAX_LAYERS`].
fn layers_of(design: &Design, tp: &Toolpath) -> Vec<Layer> {
    let pts = &tp.points;
    let walls = design.shape.walls.max(1) as f64;
    let starts = &tp.layer_starts;
    // Each layer's time, length and top (a sum along its points), the layers in parts on the
    // machine's cores: the same sums in the same order as on one.
    let sums = crate::parallel::map_ranges(starts.len(), 64, |r| {
        r.map(|i| {
            let (start, end) = (starts[i], starts.get(i + 1).copied().unwrap_or(pts.len()));
            if end <= start {
                return None;
            }
            let (mut duration, mut length, mut top) = (0.0, 0.0, f64::MIN);
            for k in start.max(1)..end {
                let seg = pts[k - 1].pos.distance(pts[k].pos);
                duration += seg / pts[k].speed.max(1e-9);
                length += seg;
            }
            for p in &pts[start..end] {
                top = top.max(p.pos.z);
            }
            Some((duration, length, top))
        })
        .collect()
    });
    let mut out = Vec::with_capacity(starts.len());
    let mut bottom = 0.0;
    for (i, sum) in sums.into_iter().enumerate() {
        let Some((duration, length, top)) = sum else {
            continue;
        };
        let base = starts[i] < tp.base_points;
        out.push(Layer {
            duration,
            bottom,
            top: top * 1e-3,
            radius: if base {
                0.0
            } else {
                length / walls / std::f64::consts::TAU * 1e-3
            },
            first: i + 1,
        });
        bottom = top * 1e-3;
    }
    let group = out.len().div_ceil(MAX_LAYERS).max(1);
    if group == 1 {
        return out;
    }
    out.chunks(group)
        .map(|c| Layer {
            duration: c.iter().map(|l| l.duration).sum(),
            bottom: c[0].bottom,
            top: c[c.len() - 1].top,
            radius: c.iter().map(|l| l.radius).fold(f64::INFINITY, f64::min),
            first: c[0].first,
        })
        .collect()
}

/// The NASA SP-8007 knock-down factor of a cylinder of radius `r` and wall `e`.
pub fn knock_down(r: f64, e: f64) -> f64 {
    1.0 - 0.901 * (1.0 - (-(r / e).sqrt() / 16.0).exp())
}

/// The lowest safety factor when every layer takes at least `min_layer_time` seconds.
fn weakest(body: &ClayBody, layers: &[Layer], e: f64, min_layer_time: f64) -> Printability {
    let rho_g = body.wet_density * GRAVITY;
    // Time at which each layer is finished.
    let mut done = Vec::with_capacity(layers.len());
    let mut t = 0.0;
    for l in layers {
        t += l.duration.max(min_layer_time);
        done.push(t);
    }
    let mut worst = Printability {
        body: *body,
        factor: f64::INFINITY,
        mechanism: Mechanism::PlasticCollapse,
        layer: 1,
        z: 0.0,
        loaded_by: 1,
        min_layer_time_to_stand: None,
        layer_factors: layers
            .iter()
            .map(|l| (l.top * 1e3, f64::INFINITY))
            .collect(),
        droops: Vec::new(),
    };
    // Both factors are τ₀(age)/(ρ·g·h) times a constant of the loaded layer: √3 for plastic
    // collapse, γ·E₀·e/(1.5·R·τ₀) for buckling (γ the layer's knock-down factor, E(age) =
    // E₀·τ₀(age)/τ₀). So each layer fails by one mechanism whatever loads it, its constant is
    // computed once, and a pair of layers costs one division.
    let by_layer: Vec<(f64, Mechanism)> = layers
        .iter()
        .map(|l| {
            let buckling = if l.radius > 0.0 {
                knock_down(l.radius, e) * body.elastic_modulus * e
                    / (1.5 * l.radius * body.yield_stress)
            } else {
                f64::INFINITY
            };
            if buckling < 3f64.sqrt() {
                (buckling, Mechanism::Buckling)
            } else {
                (3f64.sqrt(), Mechanism::PlasticCollapse)
            }
        })
        .collect();
    for (j, top) in layers.iter().enumerate() {
        for (k, l) in layers[..=j].iter().enumerate() {
            let h = top.top - l.bottom;
            if h <= 0.0 {
                continue;
            }
            let age = done[j] - done[k];
            let (c, m) = by_layer[k];
            let f = c * body.yield_stress_at(age) / (rho_g * h);
            let own = &mut worst.layer_factors[k].1;
            *own = own.min(f);
            if f < worst.factor {
                worst.factor = f;
                worst.mechanism = m;
                worst.layer = l.first;
                worst.z = l.top * 1e3;
                worst.loaded_by = top.first;
            }
        }
    }
    worst
}

impl Printability {
    /// The summary line: `printability: safety factor F (mechanism) at layer N, z mm`.
    pub fn summary(&self) -> String {
        format!(
            "printability: safety factor {:.2} ({}) at layer {}, z {:.1} mm, when layer {} is laid ({})",
            self.factor,
            self.mechanism.name(),
            self.layer,
            self.z,
            self.loaded_by,
            self.body.name
        )
    }

    /// Below a factor of 1: the warning, what happens and what would help.
    pub fn warning(&self, design: &Design) -> Option<String> {
        if self.factor >= 1.0 {
            return None;
        }
        let time = match self.min_layer_time_to_stand {
            Some(t) => format!(
                "print slower or let each layer stiffen longer (printer.min_layer_time = {:.0} s makes it stand; now {} s)",
                t.ceil(),
                design.printer.min_layer_time
            ),
            None => "no minimum layer time up to an hour makes it stand".into(),
        };
        let walls = if design.shape.walls < crate::walls::MAX_WALLS {
            format!(
                "; a thicker wall (shape.walls = {})",
                design.shape.walls + 1
            )
        } else {
            String::new()
        };
        Some(format!(
            "warning: the wall will not stand: {}. What would help: {time}{walls}; a stiffer paste (less water: a higher clay.yield_stress); or a lower vessel",
            self.mechanism.explanation()
        ))
    }
}

/// A stretch of one layer whose bead has nothing under it for longer than the clay can span
/// (SPEC §14, the paper's §5 "drooping of the print path" under large texture amplitudes).
#[derive(Debug, Clone, PartialEq)]
pub struct Droop {
    /// The section (layer) it is on and its height, mm.
    pub layer: usize,
    pub z: f64,
    /// Length of the longest unsupported stretch there, mm, and the longest the body spans.
    pub length: f64,
    pub limit: f64,
}

/// Longest stretch of fresh bead, mm, that spans a gap with nothing under it: a beam of the
/// bead's own weight supported at both ends (the bead on either side rests on the layer below),
/// bending stress at its middle 6·q·L²/(8·w·h²) = ¾·ρ·g·L²/h against the compressive yield
/// strength √3·τ₀ at deposition: L = √(4·√3·τ₀·h / (3·ρ·g)). A 1 mm layer of stoneware (3 kPa)
/// spans about 19 mm.
pub fn span_limit(body: &ClayBody, layer_height_mm: f64) -> f64 {
    let h = layer_height_mm * 1e-3;
    (4.0 * 3f64.sqrt() * body.yield_stress * h / (3.0 * body.wet_density * GRAVITY)).sqrt() * 1e3
}

/// The layers of `surface` where a bead lies wholly beside the one below it (its centre more
/// than half a bead width from the layer below) along a stretch longer than [`span_limit`]: a
/// texture or a lean the printer's overhang limit lets through but the clay does not hold.
/// With enforcement the texture is lowered where it would put a bead half a width out (see
/// [`crate::pipeline::finish_sections`]), and within the default 45° limit no lean does; a design
/// printed without enforcement, or a printer set steeper than about 56° with a steep shape, can
/// still droop.
pub fn droops(
    design: &Design,
    surface: &crate::pipeline::Surface,
) -> Result<Vec<Droop>, FieldError> {
    let body = crate::clay::resolve(design.clay.as_ref())?;
    Ok(droops_in(design, &body, surface, 2..surface.sections.len()))
}

/// [`droops`] of the layers `ks` (each from 2 on), in their order.
fn droops_in(
    design: &Design,
    body: &ClayBody,
    surface: &crate::pipeline::Surface,
    ks: std::ops::Range<usize>,
) -> Vec<Droop> {
    let half = 0.5 * design.printer.line_width;
    let limit = span_limit(body, surface.layer_pitch);
    let sections = &surface.sections;
    let mut out = Vec::new();
    for k in ks {
        // The rings' points read in XY where they lie (no copies of the rings).
        let (below, here) = (&sections[k - 1].points, &sections[k].points);
        let n = here.len();
        if n < 3 || below.len() != n {
            continue;
        }
        // A point is supported when some chord of the layer below comes within half a bead;
        // searched near the same column (a texture moves a point along the normal, never far
        // round the vessel): the chords from below[j] to below[j + 1] for j from i − reach to
        // i + reach − 1, the nearest first (almost every point is supported there).
        let window = (n / 16).clamp(4, 64);
        let chord_within = |i: usize, o: isize| {
            let mut j = i as isize + o;
            while j < 0 {
                j += n as isize;
            }
            let j = if (j as usize) < n {
                j as usize
            } else {
                j as usize % n
            };
            let k = if j + 1 == n { 0 } else { j + 1 };
            within(
                here[i].truncate(),
                below[j].truncate(),
                below[k].truncate(),
                half,
            )
        };
        let supported_within = |i: usize, reach: usize| {
            (0..reach as isize).any(|m| chord_within(i, m) || chord_within(i, -m - 1))
        };
        let free: Vec<bool> = (0..n)
            .map(|i| !supported_within(i, 2) && !supported_within(i, window))
            .collect();
        if free.iter().all(|&f| f) || !free.iter().any(|&f| f) {
            // Everywhere (a whole layer out: an overhang, the checker's business) or nowhere.
            continue;
        }
        // The longest run of free points, round the ring from a supported one.
        let start = free.iter().position(|&f| !f).unwrap_or(0);
        let (mut run, mut longest) = (0.0, 0.0f64);
        for s in 1..=n {
            let (a, b) = ((start + s - 1) % n, (start + s) % n);
            if free[b] {
                run += here[a].truncate().distance(here[b].truncate());
            } else {
                if run > 0.0 {
                    // The gap reaches to the supported point on either side.
                    run += here[a].truncate().distance(here[b].truncate());
                }
                longest = longest.max(run);
                run = 0.0;
            }
        }
        if longest > limit {
            out.push(Droop {
                layer: k,
                z: sections[k].z_range().1,
                length: longest,
                limit,
            });
        }
    }
    out
}

/// Whether point `p` is within `r` of the segment from `a` to `b`: exactly
/// `point_segment_distance(p, a, b).0 <= r`, decided on squared lengths without a division or
/// square root unless the point is within a relative 10⁻⁹ of the edge (the squares' rounding
/// is far smaller), where the exact distance decides.
fn within(p: DVec2, a: DVec2, b: DVec2, r: f64) -> bool {
    const SLACK: f64 = 1e-9;
    let (ab, ap) = (b - a, p - a);
    let (len2, dot) = (ab.length_squared(), ap.dot(ab));
    let r2 = r * r;
    // d², and the r² it is compared with scaled alike: beside an end, |p − end|² against r²;
    // beside the inside of the segment, cross(ab, ap)² = d²·|ab|² against r²·|ab|².
    let (d2, limit) = if dot <= 0.0 || len2 <= 0.0 {
        (ap.length_squared(), r2)
    } else if dot >= len2 {
        ((p - b).length_squared(), r2)
    } else {
        let cross = ab.perp_dot(ap);
        (cross * cross, r2 * len2)
    };
    if d2 < limit * (1.0 - SLACK) {
        true
    } else if d2 > limit * (1.0 + SLACK) {
        false
    } else {
        crate::geometry::point_segment_distance(p, a, b).0 <= r
    }
}

impl Droop {
    /// One line for the summary.
    pub fn summary(&self, body: &str) -> String {
        format!(
            "droop: layer {} (z {:.1} mm): {:.1} mm of bead with nothing under it, longer than the {:.1} mm fresh {body} spans; it will sag. Lower the texture amplitude there or keep the overhang limit at 45°",
            self.layer, self.z, self.length, self.limit
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::load::parse_design;

    /// The verdict on a design's job, judged as the design says (not at its wet size).
    fn judged(d: &Design) -> Printability {
        let job = crate::run(d).unwrap();
        assess(d, &job.surface, &job.toolpath).unwrap()
    }

    fn cylinder(height: f64, radius: f64, extra: &str) -> Design {
        parse_design(&format!(
            "version = 1\n[printer]\nmax_z = 1000.0\nbed_x = 400.0\nbed_y = 400.0\n[shape]\nheight = {height}\nsamples = 120\nbase_layers = 1\n[shape.lower]\ntype = \"circle\"\nradius = {radius}\n[shape.upper]\ntype = \"circle\"\nradius = {radius}\n{extra}"
        ))
        .unwrap()
    }

    #[test]
    fn the_collapse_factor_is_roussel_s_ratio_for_a_wall_printed_at_once() {
        // No stiffening, a stiff modulus: only collapse, F = √3·τ₀ / (ρ g H) at the bottom.
        let d = cylinder(
            100.0,
            40.0,
            "[clay]\nstructuration_rate = 0.0\nelastic_modulus = 1e8\nwet_density = 1900.0\nyield_stress = 2000.0\n",
        );
        let job = crate::run(&d).unwrap();
        let p = assess(&d, &job.surface, &job.toolpath).unwrap();
        let expected = 3f64.sqrt() * 2000.0 / (1900.0 * GRAVITY * 0.100);
        assert!(
            (p.factor - expected).abs() / expected < 1e-6,
            "{} {expected}",
            p.factor
        );
        assert_eq!(p.mechanism, Mechanism::PlasticCollapse);
        assert_eq!(p.layer, 1);
        // Loaded most by the last revolution (the rim reaches the same height).
        assert!(p.loaded_by + 1 >= job.toolpath.layer_starts.len());
        // 1.86: it stands.
        assert!(p.factor > 1.8 && p.warning(&d).is_none());
        // The foot carries the most: its factor is the print's, the rim's is far higher.
        assert_eq!(p.factor_at(0.5), p.factor);
        assert!(p.factor_at(99.0) > 10.0 * p.factor);
        let f: Vec<f64> = p.layer_factors.iter().map(|l| l.1).collect();
        assert!(f.windows(2).all(|w| w[1] >= w[0]), "bottom up, rising");
    }

    #[test]
    fn a_tall_soft_vessel_collapses_and_a_minimum_layer_time_saves_it() {
        let d = cylinder(
            400.0,
            60.0,
            "[clay]\nyield_stress = 2500.0\nstructuration_rate = 0.05\nelastic_modulus = 1e8\n",
        );
        let job = crate::run(&d).unwrap();
        let p = assess(&d, &job.surface, &job.toolpath).unwrap();
        assert!(p.factor < 1.0, "{}", p.factor);
        assert_eq!(p.mechanism, Mechanism::PlasticCollapse);
        let t = p.min_layer_time_to_stand.expect("a layer time saves it");
        let w = p.warning(&d).unwrap();
        assert!(
            w.contains("min_layer_time") && w.contains("squeezed out"),
            "{w}"
        );
        // With that minimum layer time it stands, and just under it it does not.
        let mut slow = d.clone();
        slow.printer.min_layer_time = t.ceil();
        let p2 = judged(&slow);
        assert!(p2.factor >= 1.0, "{}", p2.factor);
        slow.printer.min_layer_time = (t * 0.9).floor();
        let p3 = judged(&slow);
        assert!(p3.factor < 1.0, "{}", p3.factor);
    }

    #[test]
    fn a_thin_wide_soft_wall_buckles_and_a_second_bead_more_than_doubles_its_factor() {
        let clay =
            "[clay]\nyield_stress = 3000.0\nelastic_modulus = 60000.0\nstructuration_rate = 0.0\n";
        let d = cylinder(150.0, 90.0, clay);
        let p = judged(&d);
        assert_eq!(p.mechanism, Mechanism::Buckling);
        // F = γ E e / (1.5 R ρ g h) with R = 90 mm, e = 3 mm at the wall's foot.
        let (r, e, h) = (0.090, 0.003, 0.150 - 0.001);
        let rho_g = preset_density() * GRAVITY;
        let expected = knock_down(r, e) * 60000.0 * e / (1.5 * r * rho_g * h);
        assert!(
            (p.factor - expected).abs() / expected < 0.02,
            "{} {expected}",
            p.factor
        );
        let mut two = d.clone();
        two.shape.walls = 2;
        let p2 = judged(&two);
        // Twice the thickness, a shorter inner bead (smaller mean radius): more than twice.
        assert!(p2.factor > 2.0 * p.factor, "{} {}", p2.factor, p.factor);
    }

    /// On a path long enough for both cores, the verdict's droops are those of every layer,
    /// found in runs of layers beside the verdict: the same as one pass over them, with the
    /// verdict of the path itself.
    #[test]
    fn droops_found_in_runs_beside_the_verdict_are_every_layer_s() {
        let d = parse_design(
            "version = 1\n[printer]\nmax_overhang_deg = 70.0\n[shape]\nheight = 60.0\nsamples = 720\nbase_layers = 0\n[shape.lower]\ntype = \"circle\"\nradius = 40.0\n[shape.upper]\ntype = \"circle\"\nradius = 40.0\n[texture]\ncombine = \"sum\"\nphase_drift = 40.0\n[texture.x]\nwave = \"square\"\nperiod = 90\namplitude = 4.0\n[constraints]\nenforce = false\n",
        )
        .unwrap();
        let job = crate::run(&d).unwrap();
        assert!(job.toolpath.points.len() >= crate::parallel::PARALLEL_POINTS);
        let found = droops(&d, &job.surface).unwrap();
        // Droops in more than one run of layers.
        assert!(
            found.first().unwrap().layer / DROOP_RUN != found.last().unwrap().layer / DROOP_RUN
        );
        let p = crate::parallel::awake(|| assess(&d, &job.surface, &job.toolpath).unwrap());
        let mut by_layer = p.droops.clone();
        by_layer.sort_by_key(|x| x.layer);
        assert_eq!(by_layer, found);
        let body = crate::clay::resolve(d.clay.as_ref()).unwrap();
        let alone = standing(&d, &body, &job.toolpath);
        assert_eq!(
            (p.factor.to_bits(), p.min_layer_time_to_stand),
            (alone.factor.to_bits(), alone.min_layer_time_to_stand)
        );
    }

    fn preset_density() -> f64 {
        crate::clay::preset("stoneware").unwrap().wet_density
    }

    #[test]
    fn the_span_limit_is_the_bead_beam_s_and_deep_steep_textures_droop() {
        let b = crate::clay::preset("stoneware").unwrap();
        // √(4·√3·3000·0.001 / (3·1878.6·9.80665)) = 19.4 mm.
        assert!(
            (span_limit(b, 1.0) - 19.4).abs() < 0.05,
            "{}",
            span_limit(b, 1.0)
        );
        // A vertical texture 4 mm deep every 6 layers, printed without enforcement on a printer
        // that allows 70°: whole stretches of bead step more than half a bead out.
        let texture = "[texture]\ncombine = \"sum\"\nphase_drift = 40.0\n[texture.x]\nwave = \"square\"\nperiod = 90\namplitude = 4.0\n";
        let steep = |enforce: bool| {
            let d = parse_design(&format!(
                "version = 1\n[printer]\nmax_overhang_deg = 70.0\n[shape]\nheight = 30.0\nsamples = 360\nbase_layers = 0\n[shape.lower]\ntype = \"circle\"\nradius = 40.0\n[shape.upper]\ntype = \"circle\"\nradius = 40.0\n{texture}[constraints]\nenforce = {enforce}\n"
            ))
            .unwrap();
            let job = crate::run(&d).unwrap();
            let found = droops(&d, &job.surface).unwrap();
            // The verdict names the same layers, the one most past its limit first.
            let listed = assess(&d, &job.surface, &job.toolpath).unwrap().droops;
            let excess = |x: &Droop| x.length - x.limit;
            assert!(listed.windows(2).all(|w| excess(&w[0]) >= excess(&w[1])));
            let mut by_layer = listed.clone();
            by_layer.sort_by_key(|x| x.layer);
            assert_eq!(by_layer, found);
            found
        };
        let found = steep(false);
        assert!(!found.is_empty());
        assert!(found.iter().all(|d| d.length > d.limit));
        assert!(found[0].summary("stoneware").contains("droop: layer"));
        // Enforced, the texture is lowered so that no bead lies wholly beside the one below.
        assert!(steep(true).is_empty());
        // The plain cylinder has none.
        let d = cylinder(30.0, 40.0, "");
        assert!(
            droops(&d, &crate::run(&d).unwrap().surface)
                .unwrap()
                .is_empty()
        );
    }

    proptest::proptest! {
        /// The squared test of a point near a segment is the exact distance's, on points far,
        /// near and exactly at the edge (at each end, beside the inside, on a segment of no
        /// length).
        #[test]
        fn within_is_the_exact_distance_test(
            a in proptest::array::uniform2(-50.0..50.0f64),
            b in proptest::array::uniform2(-50.0..50.0f64),
            p in proptest::array::uniform2(-50.0..50.0f64),
            r in 0.0..30.0f64,
            f in -0.5..1.5f64,
            zero in proptest::bool::ANY,
        ) {
            let (a, p) = (DVec2::from(a), DVec2::from(p));
            let b = if zero { a } else { DVec2::from(b) };
            let exact = |p: DVec2, r: f64| crate::geometry::point_segment_distance(p, a, b).0 <= r;
            proptest::prop_assert_eq!(within(p, a, b, r), exact(p, r));
            // At the edge: r is the distance itself, and the floats next to it.
            let q = a + (b - a) * f + (p - a) * 0.1;
            let d = crate::geometry::point_segment_distance(q, a, b).0;
            for r in [d, d.next_up(), d.next_down()] {
                proptest::prop_assert_eq!(within(q, a, b, r), exact(q, r), "{} {}", d, r);
            }
        }
    }

    #[test]
    fn the_knock_down_follows_sp_8007() {
        // R/e = 256: √256/16 = 1 → 1 − 0.901·(1 − 1/e) = 0.4305.
        assert!((knock_down(256.0, 1.0) - 0.4305).abs() < 1e-4);
        assert!(knock_down(1.0, 1.0) > 0.9);
    }

    #[test]
    fn a_long_print_is_judged_in_bounded_time() {
        // 0.1 mm layers, 3000 of them: grouped to 600.
        let d = parse_design(
            "version = 1\n[printer]\nmax_z = 1000.0\nlayer_height = 0.1\nmin_layer_height = 0.05\nmax_layer_height = 0.2\nline_width = 1.0\nnozzle_diameter = 1.0\n[shape]\nheight = 300.0\nsamples = 60\n[shape.lower]\ntype = \"circle\"\nradius = 30.0\n[shape.upper]\ntype = \"circle\"\nradius = 30.0\n",
        )
        .unwrap();
        let job = crate::run(&d).unwrap();
        assert!(job.toolpath.layer_starts.len() > 2900);
        let start = std::time::Instant::now();
        let p = assess(&d, &job.surface, &job.toolpath).unwrap();
        assert!(p.factor.is_finite());
        assert!(start.elapsed().as_secs() < 20);
    }
}
