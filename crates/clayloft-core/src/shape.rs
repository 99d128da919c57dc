//! The large-scale shape: loft plus control lines, section by section, on a layer plan that keeps
//! every local layer height printable (SPEC §1.5, §2).
//!
//! Section k (k = 0 ..= L) sits at height fraction t = k / L. Its points are
//! `P(i, t) + d(i, t)·nᵢ` in XY, with d the sum of the vertical control lines, and
//! `z = k·h + s·Σ_l w_l(t)·dz_l(φᵢ)` with h = height / L and s the horizontal-line scale (1 unless
//! a constraint needed it lowered). Section 0 is the bed contact at z = 0.
//!
//! Where a concave stretch is pushed out further than its radius of curvature (d > ρ, a belly
//! past a rose's cusps), `P + d·n` folds back on itself in a swallowtail; the wall there is the
//! offset's corner, the crossing of the two sides, and the tail's points are spread over that
//! corner ([`trim_swallowtails`]). The nozzle then turns the corner instead of tracing a loop
//! of clay, and the texture fades over the squeezed columns (`texture::squeeze_fade`).

use glam::{DVec2, DVec3};

use crate::control::angle_difference;
use crate::control::{HorizontalProfile, VerticalProfile};
use crate::design::{Design, VerticalLine};
use crate::geometry::{outward_normal_at, outward_normals, trim_swallowtails};
use crate::loft::LoftInput;
use crate::report::{Finding, FindingKind};
use crate::section::Section;
use crate::validate::{FieldError, MAX_PATH_POINTS};

/// Safety margin on printer limits: the pipeline aims 2 % inside them so that rounding in the
/// spiral and the G-code never tips a measurement over.
pub const LIMIT_MARGIN: f64 = 0.98;
/// Height-fraction resolution used to plan layers against horizontal control lines.
const PLAN_STEPS: usize = 512;

/// Samples on either side of a fold within which its crossing is searched
/// ([`trim_swallowtails`]): a twelfth of the ring (60 of 720 samples, 30° of a round vessel),
/// far more than the folds of a belly pushed past a rose's cusps (about 25 samples a side on
/// the benchmark vase); a fold wider than that is left for the checker to find.
fn swallowtail_reach(samples: usize) -> usize {
    (samples / 12).max(8)
}

/// What cutting off a section's folds did ([`ShapeModel::section_with_folds`]): how many of its
/// points were moved onto the folds' corners, and the farthest, mm.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Folds {
    pub points: usize,
    pub most_mm: f64,
}

/// The findings of the sections' folds (`folds[k]`: section k's), one per run of folded
/// sections: where the shape cut off the swallowtails of a push past the contour's curvature.
pub fn fold_findings(folds: &[Folds]) -> Vec<Finding> {
    let mut out: Vec<Finding> = Vec::new();
    for (k, f) in folds.iter().enumerate().filter(|(_, f)| f.points > 0) {
        match out.last_mut() {
            Some(last) if last.layers.1 + 1 == k => {
                last.layers.1 = k;
                last.points += f.points;
                last.amount_mm = last.amount_mm.max(f.most_mm);
            }
            _ => out.push(Finding {
                kind: FindingKind::Folds,
                corrected: true,
                layers: (k, k),
                points: f.points,
                amount_mm: f.most_mm,
                message: "the control lines push the wall out of the contour's hollows further \
                    than they curve, so it would fold back on itself: the folds are cut off at \
                    their corners"
                    .into(),
            }),
        }
    }
    out
}

/// Everything needed to compute any section of the shaped (uncorrected, untextured) surface.
#[derive(Debug, Clone)]
pub struct ShapeModel {
    pub loft: LoftInput,
    /// The vertical control lines ([`ShapeModel::set_vertical`]).
    vertical: Vec<VerticalProfile>,
    /// `weights[l][i]`: vertical line l's angular weight at sample i (they do not change with
    /// the height, so every section reads them instead of a cosine per point).
    weights: Vec<Vec<f64>>,
    pub horizontal: Vec<HorizontalProfile>,
    /// `hz[l][i]`: full-weight z offset of horizontal line l at sample i.
    pub hz: Vec<Vec<f64>>,
    /// Scale applied to all horizontal lines (lowered by constraint enforcement).
    pub hz_scale: f64,
    /// Number of layers L.
    pub layers: usize,
    /// Nominal layer pitch h = height / L, mm.
    pub layer_pitch: f64,
    pub height: f64,
}

impl ShapeModel {
    /// Builds the model and plans the layers; returns findings for any horizontal-line scaling.
    /// A plan with more than [`MAX_PATH_POINTS`] wall points is an error on `shape.samples`.
    pub fn new(design: &Design, loft: LoftInput) -> Result<(ShapeModel, Vec<Finding>), FieldError> {
        let horizontal: Vec<_> = design
            .control
            .horizontal
            .iter()
            .map(HorizontalProfile::new)
            .collect();
        let hz = horizontal
            .iter()
            .map(|h| loft.angles.iter().map(|&phi| h.dz_at(phi)).collect())
            .collect();
        let mut model = ShapeModel {
            loft,
            vertical: Vec::new(),
            weights: Vec::new(),
            horizontal,
            hz,
            hz_scale: 1.0,
            layers: 1,
            layer_pitch: design.shape.height,
            height: design.shape.height,
        };
        model.set_vertical(&design.control.vertical);
        let findings = model.plan_layers(design);
        let points = (model.layers as u128 + 1) * model.loft.samples() as u128;
        if points > MAX_PATH_POINTS as u128 {
            return Err(FieldError::new(
                "shape.samples",
                format!(
                    "{} samples × {} layers make {points} wall points, more than the {MAX_PATH_POINTS} a path may have (fewer samples or thicker layers)",
                    model.loft.samples(),
                    model.layers + 1
                ),
            ));
        }
        Ok((model, findings))
    }

    /// z offset of sample i at height fraction t from all horizontal lines (scaled).
    #[inline]
    fn dz(&self, i: usize, t: f64) -> f64 {
        let mut dz = 0.0;
        for (line, values) in self.horizontal.iter().zip(&self.hz) {
            let w = line.weight_at(t);
            if w != 0.0 {
                dz += w * values[i];
            }
        }
        dz * self.hz_scale
    }

    /// Puts in the vertical control lines (the layer plan does not read them, so a session
    /// changes them on a kept plan).
    pub fn set_vertical(&mut self, lines: &[VerticalLine]) {
        self.vertical = lines.iter().map(VerticalProfile::new).collect();
        self.weights = self
            .vertical
            .iter()
            .map(|v| {
                self.loft
                    .angles
                    .iter()
                    .map(|&phi| v.weight_at(phi))
                    .collect()
            })
            .collect();
    }

    /// The vertical control lines, in the design's order.
    pub fn vertical(&self) -> &[VerticalProfile] {
        &self.vertical
    }

    /// The shaped section k: loft, vertical control offsets along the normal, z with horizontal
    /// control offsets. This is the per-section entry point the app calls for dirty sections.
    pub fn section(&self, k: usize) -> Section {
        self.section_with_folds(k).0
    }

    /// [`ShapeModel::section`], with what cutting off its folds did.
    pub fn section_with_folds(&self, k: usize) -> (Section, Folds) {
        let t = k as f64 / self.layers as f64;
        let z0 = (k > 0).then_some(k as f64 * self.layer_pitch);
        self.shaped_section(t, z0)
    }

    /// The shaped wall at any height fraction `t` (between sections too): the section the
    /// printer would lay there. Control-line curves and handles are drawn on it.
    pub fn section_at(&self, t: f64) -> Section {
        let t = t.clamp(0.0, 1.0);
        self.shaped_section(t, (t > 0.0).then_some(t * self.height))
            .0
    }

    /// The shaped points at height fraction t; `z0` is the nominal height (`None` on the bed,
    /// where z = 0 whatever the horizontal lines do).
    fn shaped_section(&self, t: f64, z0: Option<f64>) -> (Section, Folds) {
        let n = self.loft.samples();
        let xy: Vec<DVec2> = (0..n).map(|i| self.loft.point(i, t)).collect();
        let active = self.active_vertical(t, None);
        let mut wall = xy.clone();
        let mut folds = Folds::default();
        if !active.is_empty() {
            let normals = outward_normals(&xy);
            for (i, p) in wall.iter_mut().enumerate() {
                for (l, d) in &active {
                    *p += normals[i] * (d * self.weights[*l][i]);
                }
            }
            (folds.points, folds.most_mm) = trim_swallowtails(&mut wall, &xy, swallowtail_reach(n));
        }
        let points = wall
            .iter()
            .enumerate()
            .map(|(i, p)| DVec3::new(p.x, p.y, z0.map_or(0.0, |z0| z0 + self.dz(i, t))))
            .collect();
        (Section { points }, folds)
    }

    /// The vertical lines (by index) with a non-zero offset at t and that offset, leaving out
    /// `skip`.
    fn active_vertical(&self, t: f64, skip: Option<usize>) -> Vec<(usize, f64)> {
        self.vertical
            .iter()
            .enumerate()
            .filter(|(l, _)| Some(*l) != skip)
            .map(|(l, v)| (l, v.offset_at(t)))
            .filter(|(_, d)| *d != 0.0)
            .collect()
    }

    /// The loft sample nearest to angle `phi` (radians, from the centre): the column a control
    /// line at that angle runs on.
    pub fn column_at_angle(&self, phi: f64) -> usize {
        (0..self.loft.samples())
            .min_by(|&a, &b| {
                let da = angle_difference(self.loft.angles[a], phi).abs();
                let db = angle_difference(self.loft.angles[b], phi).abs();
                da.total_cmp(&db)
            })
            .unwrap_or(0)
    }

    /// Where on the wall column i at height fraction t a control line's offset is measured
    /// from, and along which direction: the wall point is `base + dir · offset` with `base`
    /// the wall without the vertical line `line` and `dir` the loft's outward normal scaled by
    /// that line's angular weight (zero where the line does not reach). With `line = None`,
    /// `base` is the wall point itself.
    pub fn wall_frame(&self, i: usize, t: f64, line: Option<usize>) -> (DVec3, DVec2) {
        let t = t.clamp(0.0, 1.0);
        self.frame_at(i, t, (t > 0.0).then_some(t * self.height), line)
    }

    /// [`ShapeModel::wall_frame`] with the nominal height `z0` given (`None` on the bed).
    fn frame_at(&self, i: usize, t: f64, z0: Option<f64>, line: Option<usize>) -> (DVec3, DVec2) {
        let n = self.loft.samples();
        if n == 0 {
            return (DVec3::ZERO, DVec2::ZERO);
        }
        let i = i % n;
        let xy: Vec<DVec2> = [(i + n - 1) % n, i, (i + 1) % n]
            .iter()
            .map(|&j| self.loft.point(j, t))
            .collect();
        let normal = outward_normal_at(&xy, 1);
        let dir = line
            .and_then(|l| self.weights.get(l))
            .map_or(DVec2::ZERO, |w| normal * w[i]);
        let active = self.active_vertical(t, None);
        if active.is_empty() {
            let z = z0.map_or(0.0, |z0| z0 + self.dz(i, t));
            return (xy[1].extend(z), dir);
        }
        // Pushed out, the wall may fold back on itself here, which only the whole section
        // shows (`trim_swallowtails`): the point is the section's, and the base is that point
        // less the line's own push.
        let wall = self.shaped_section(t, z0).0.points[i];
        let own = line
            .and_then(|l| active.iter().find(|(k, _)| *k == l))
            .map_or(0.0, |(_, d)| *d);
        (wall - (dir * own).extend(0.0), dir)
    }

    /// The shaped wall point of column i at height fraction t.
    pub fn wall_point(&self, i: usize, t: f64) -> DVec3 {
        self.wall_frame(i, t, None).0
    }

    /// A horizontal control line drawn on the wall at its height fraction `at`, closed.
    pub fn horizontal_line_curve(&self, at: f64) -> Vec<DVec3> {
        let mut points = self.section_at(at).points;
        if let Some(first) = points.first().copied() {
            points.push(first);
        }
        points
    }

    /// Sections whose shape a vertical control line's span `(t0, t1)` touches.
    pub fn sections_in_span(&self, span: (f64, f64)) -> std::ops::RangeInclusive<usize> {
        let l = self.layers as f64;
        let lo = (span.0 * l).floor().max(0.0) as usize;
        let hi = ((span.1 * l).ceil() as usize).min(self.layers);
        lo..=hi
    }

    /// Chooses the number of layers L and the horizontal-line scale s.
    ///
    /// With `g(t, i) = ∂dz/∂t`, the local layer height is about `(H + s·g) / L`. L is the smallest
    /// count with `(H + s·g_max) / L ≤ max_layer_height` and at least `H / layer_height`. If then
    /// `(H + s·g_min) / L < min_layer_height`, or the z range under the nozzle holder exceeds the
    /// nozzle length, s is lowered (bisection) when enforcing, or the violation is reported.
    fn plan_layers(&mut self, design: &Design) -> Vec<Finding> {
        let p = &design.printer;
        let height = design.shape.height;
        let hmax = p.max_layer_height * LIMIT_MARGIN;
        let hmin = p.min_layer_height / LIMIT_MARGIN;
        // Whole layers of at most the layer height; fewer where those would be thinner than the
        // wall can be laid, while they fit the printer's maximum: each of W beads' turns rises at
        // least the minimum layer height (the toolpath's turns), so a layer holds W of them.
        let least = p.min_layer_height * design.shape.walls.max(1) as f64;
        let mut nominal = (height / p.layer_height - 1e-9).ceil().max(1.0) as usize;
        while nominal > 1
            && height / (nominal as f64) < least
            && height / ((nominal - 1) as f64) <= p.max_layer_height
        {
            nominal -= 1;
        }
        let (g_min, g_max) = self.dz_gradient_range();
        let layers_for = |s: f64| {
            if s * g_max > 0.0 {
                nominal.max(((height + s * g_max) / hmax - 1e-9).ceil() as usize)
            } else {
                nominal
            }
        };
        let thin_ok =
            |s: f64| s * g_min >= 0.0 || (height + s * g_min) / layers_for(s) as f64 >= hmin;
        let holder_ok = |s: f64| self.holder_clearance(s, height) <= p.nozzle_length * LIMIT_MARGIN;
        let ok = |s: f64| thin_ok(s) && holder_ok(s);
        let mut findings = Vec::new();
        let mut s = 1.0;
        if !self.horizontal.is_empty() && !ok(1.0) {
            let why = if !holder_ok(1.0) {
                format!(
                    "the z range of a layer would exceed the nozzle length ({} mm)",
                    p.nozzle_length
                )
            } else {
                format!(
                    "layers would get thinner than min_layer_height ({} mm)",
                    p.min_layer_height
                )
            };
            if design.constraints.enforce {
                let (mut lo, mut hi) = (0.0, 1.0);
                for _ in 0..40 {
                    let mid = 0.5 * (lo + hi);
                    if ok(mid) { lo = mid } else { hi = mid }
                }
                s = lo;
                findings.push(Finding {
                    kind: FindingKind::HorizontalLines,
                    corrected: true,
                    layers: (0, layers_for(s)),
                    points: self.loft.samples(),
                    amount_mm: self.max_abs_dz() * (1.0 - s),
                    message: format!(
                        "horizontal control lines scaled to {:.0} %: {why}",
                        s * 100.0
                    ),
                });
            } else {
                findings.push(Finding {
                    kind: FindingKind::HorizontalLines,
                    corrected: false,
                    layers: (0, layers_for(1.0)),
                    points: self.loft.samples(),
                    amount_mm: self.max_abs_dz(),
                    message: format!("horizontal control lines too strong: {why}"),
                });
            }
        }
        self.hz_scale = s;
        self.layers = layers_for(s);
        self.layer_pitch = height / self.layers as f64;
        findings
    }

    fn max_abs_dz(&self) -> f64 {
        self.hz
            .iter()
            .flatten()
            .fold(0.0, |m: f64, v| m.max(v.abs()))
    }

    /// Range of ∂dz/∂t over the height and all samples, at scale 1.
    fn dz_gradient_range(&self) -> (f64, f64) {
        if self.horizontal.is_empty() {
            return (0.0, 0.0);
        }
        let n = self.loft.samples();
        let (mut g_min, mut g_max) = (0.0_f64, 0.0_f64);
        let dt = 1.0 / PLAN_STEPS as f64;
        for step in 0..PLAN_STEPS {
            let (t0, t1) = (step as f64 * dt, (step + 1) as f64 * dt);
            let dw: Vec<f64> = self
                .horizontal
                .iter()
                .map(|h| (h.weight_at(t1) - h.weight_at(t0)) / dt)
                .collect();
            if dw.iter().all(|w| *w == 0.0) {
                continue;
            }
            for i in 0..n {
                let g: f64 = dw.iter().zip(&self.hz).map(|(w, v)| w * v[i]).sum();
                g_min = g_min.min(g);
                g_max = g_max.max(g);
            }
        }
        (g_min, g_max)
    }

    /// Largest height of already-printed surface above the current layer's lowest point, at
    /// horizontal-line scale s: `max_t (max_{t' ≤ t} max_i z(t', i) − min_i z(t, i))`.
    fn holder_clearance(&self, s: f64, height: f64) -> f64 {
        if self.horizontal.is_empty() {
            return 0.0;
        }
        let n = self.loft.samples();
        let mut running_max = f64::NEG_INFINITY;
        let mut worst: f64 = 0.0;
        for step in 0..=PLAN_STEPS {
            let t = step as f64 / PLAN_STEPS as f64;
            let w: Vec<f64> = self.horizontal.iter().map(|h| h.weight_at(t) * s).collect();
            let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
            for i in 0..n {
                let z = t * height + w.iter().zip(&self.hz).map(|(w, v)| w * v[i]).sum::<f64>();
                lo = lo.min(z);
                hi = hi.max(z);
            }
            running_max = running_max.max(hi);
            worst = worst.max(running_max - lo);
        }
        worst
    }
}

#[cfg(test)]
mod tests {
    use crate::load::parse_design;
    use crate::pipeline::build_surface;

    fn tilted(dz: f64, enforce: bool) -> crate::design::Design {
        parse_design(&format!(
            "version = 1\n[shape]\nheight = 80.0\nsamples = 120\nbase_layers = 0\n[shape.lower]\ntype = \"circle\"\nradius = 35.0\n\
             [shape.upper]\ntype = \"circle\"\nradius = 35.0\n[[control.horizontal]]\nat = 1.0\nreach = 0.5\n\
             points = [[90.0, {dz}], [270.0, -{dz}]]\n[constraints]\nenforce = {enforce}\n"
        ))
        .unwrap()
    }

    /// A height that is no whole number of layers gets one layer more, a little thinner, unless
    /// that is thinner than the wall can be laid (the printer's minimum, W of it for W beads):
    /// then one fewer, a little thicker.
    #[test]
    fn layers_stay_within_the_printers_range_when_the_height_does_not_divide() {
        let layers = |min: f64| {
            let d = parse_design(&format!(
                "version = 1\n[printer]\nlayer_height = 0.5\nmin_layer_height = {min}\n[shape]\nheight = 35.3\n[shape.lower]\ntype = \"circle\"\nradius = 30.0\n[shape.upper]\ntype = \"circle\"\nradius = 30.0\n"
            ))
            .unwrap();
            let s = build_surface(&d).unwrap();
            (s.layers, s.layer_pitch)
        };
        let (n, pitch) = layers(0.25);
        assert_eq!(n, 71);
        assert!((pitch - 35.3 / 71.0).abs() < 1e-12);
        // 35.3 / 71 = 0.497 mm is under a 0.499 mm minimum: 70 layers of 0.504 mm.
        let (n, pitch) = layers(0.499);
        assert_eq!(n, 70);
        assert!((0.499..=1.0).contains(&pitch), "{pitch}");
        // Two beads of 0.25 mm turns at the least: 71 layers of 0.497 mm would not hold two.
        let d = parse_design(
            "version = 1\n[printer]\nlayer_height = 0.5\nmin_layer_height = 0.25\n[shape]\nheight = 35.3\nwalls = 2\n[shape.lower]\ntype = \"circle\"\nradius = 30.0\n[shape.upper]\ntype = \"circle\"\nradius = 30.0\n",
        )
        .unwrap();
        let s = build_surface(&d).unwrap();
        assert_eq!(s.layers, 70);
    }

    #[test]
    fn tilted_layers_get_more_layers_not_thicker_ones() {
        let s = build_surface(&tilted(10.0, true)).unwrap();
        assert!(s.layers > 80, "{}", s.layers);
        assert!(
            s.metrics.max_layer_height <= 1.0 + 1e-9,
            "{}",
            s.metrics.max_layer_height
        );
        assert!(
            s.metrics.min_layer_height >= 0.25 - 1e-9,
            "{}",
            s.metrics.min_layer_height
        );
        assert!(
            (s.metrics.max_layer_z_range - 20.0).abs() < 0.1,
            "{}",
            s.metrics.max_layer_z_range
        );
        assert!(s.findings.is_empty());
    }

    #[test]
    fn a_tilt_taller_than_the_nozzle_is_scaled_down_and_reported() {
        // ±20 mm: a 40 mm z range in the top layer, more than the 30 mm nozzle.
        let s = build_surface(&tilted(20.0, true)).unwrap();
        assert!(
            s.metrics.max_layer_z_range <= 30.0,
            "{}",
            s.metrics.max_layer_z_range
        );
        assert_eq!(s.findings.len(), 1);
        assert!(
            s.findings[0].corrected && s.findings[0].message.contains("nozzle length"),
            "{}",
            s.findings[0]
        );
        let reported = build_surface(&tilted(20.0, false)).unwrap();
        assert!(!reported.findings[0].corrected);
        assert!((reported.metrics.max_layer_z_range - 40.0).abs() < 0.1);
    }

    #[test]
    fn local_vertical_line_moves_only_its_angles_and_span() {
        let d = parse_design(
            "version = 1\n[shape]\nheight = 50.0\nsamples = 360\n[shape.lower]\ntype = \"circle\"\nradius = 30.0\n\
             [shape.upper]\ntype = \"circle\"\nradius = 30.0\n[[control.vertical]]\n\
             points = [[0.0, 0.0], [0.4, 0.0], [0.6, 5.0], [0.8, 0.0], [1.0, 0.0]]\nangle = 90.0\nwidth = 60.0\n",
        )
        .unwrap();
        let s = build_surface(&d).unwrap();
        let c = s.center;
        let r = |k: usize, deg: usize| (s.sections[k].points[deg].truncate() - c).length();
        assert!((r(30, 90) - 35.0).abs() < 1e-6, "{}", r(30, 90));
        assert!((r(30, 105) - 32.5).abs() < 1e-4, "{}", r(30, 105));
        assert!((r(30, 270) - 30.0).abs() < 1e-6);
        assert!((r(10, 90) - 30.0).abs() < 1e-6);
    }
}

#[cfg(test)]
mod wall_tests {
    use super::*;
    use crate::load::parse_design;

    /// A non-circular loft (a star foot under an ellipse) with two overlapping vertical lines
    /// and a horizontal line: where a radial push would leave the wall.
    fn model() -> ShapeModel {
        let d = parse_design(
            "version = 1\n[shape]\nheight = 60.0\nsamples = 180\n\
             [shape.lower]\ntype = \"star\"\npoints = 6\nouter_radius = 40.0\ninner_radius = 25.0\n\
             [shape.upper]\ntype = \"ellipse\"\nrx = 35.0\nry = 20.0\n\
             [[control.vertical]]\npoints = [[0.0, 0.0], [0.5, 6.0], [1.0, 0.0]]\n\
             [[control.vertical]]\npoints = [[0.0, 0.0], [0.2, 0.0], [0.45, 4.0], [0.7, 0.0], [1.0, 0.0]]\nangle = 30.0\nwidth = 90.0\n\
             [[control.horizontal]]\nat = 0.8\nreach = 0.2\npoints = [[0.0, 3.0], [180.0, -2.0]]\n",
        )
        .unwrap();
        ShapeModel::new(&d, LoftInput::from_design(&d).unwrap())
            .unwrap()
            .0
    }

    #[test]
    fn wall_points_are_the_printed_sections() {
        let m = model();
        for k in [0, 1, m.layers / 3, m.layers / 2, m.layers] {
            let s = m.section(k);
            let at = m.section_at(k as f64 / m.layers as f64);
            for i in (0..m.loft.samples()).step_by(7) {
                assert!(s.points[i].distance(at.points[i]) < 1e-9, "k {k} i {i}");
                let w = m.wall_point(i, k as f64 / m.layers as f64);
                assert!(
                    s.points[i].distance(w) < 1e-9,
                    "k {k} i {i}: {w} vs {}",
                    s.points[i]
                );
            }
        }
    }

    #[test]
    fn a_frame_moves_the_wall_point_along_the_normal_by_the_weighted_offset() {
        let m = model();
        let t = 0.45;
        let i = m.column_at_angle(30f64.to_radians());
        let (base, dir) = m.wall_frame(i, t, Some(1));
        let offset = m.vertical()[1].offset_at(t);
        assert!((offset - 4.0).abs() < 1e-12);
        let on_wall = m.wall_point(i, t);
        assert!((base.truncate() + dir * offset).distance(on_wall.truncate()) < 1e-9);
        assert_eq!(base.z, on_wall.z);
        // Near its own angle the weight is about 1: the direction is the normal, not the radius.
        assert!((dir.length() - 1.0).abs() < 0.01, "{}", dir.length());
        let radial = (on_wall.truncate() - m.loft.center).normalize();
        assert!(
            dir.normalize().dot(radial) < 0.9999,
            "the star's normal is not radial here"
        );
    }
}
