//! Manufacturing constraints (SPEC §2) on the section surface: detect, correct locally, report.
//!
//! Support-free: between section k−1 and k the wall may move along the XY normal of section k−1
//! by at most `Δz·tan(max_overhang)`, with Δz the local layer height. Corrections clamp that
//! normal component point by point, from the bottom up, so a section only ever depends on the
//! corrected section below it.

use glam::DVec2;

use crate::report::PointEvent;
use crate::section::Section;

/// Measured quality of a section surface.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SurfaceMetrics {
    /// Largest lean of the wall from vertical between consecutive sections, degrees.
    pub max_overhang_deg: f64,
    /// Largest z range within one section, mm.
    pub max_layer_z_range: f64,
    /// Smallest and largest local layer height, mm.
    pub min_layer_height: f64,
    pub max_layer_height: f64,
}

/// Clamps the normal offset of every point of sections `from ..` against the section below to
/// `tan_limit·Δz`. Returns the points moved (or, with `enforce = false`, the points in violation,
/// unchanged). Also returns the index of the highest section changed, if any.
pub fn clamp_overhang(
    sections: &mut [Section],
    from: usize,
    tan_limit: f64,
    enforce: bool,
) -> Vec<PointEvent> {
    let mut events = Vec::new();
    for k in from.max(1)..sections.len() {
        let (below, above) = sections.split_at_mut(k);
        let prev = &below[k - 1];
        let cur = &mut above[0];
        let normals = prev.normals();
        for (i, p) in cur.points.iter_mut().enumerate() {
            let q = prev.points[i];
            let dz = (p.z - q.z).max(0.0);
            let limit = dz * tan_limit;
            let n = normals[i];
            let offset = (p.truncate() - q.truncate()).dot(n);
            if offset.abs() > limit {
                let excess = offset.abs() - limit;
                if enforce {
                    let shift: DVec2 = n * (excess * offset.signum());
                    p.x -= shift.x;
                    p.y -= shift.y;
                }
                events.push(PointEvent {
                    layer: k,
                    sample: i,
                    amount_mm: excess,
                });
            }
        }
    }
    events
}

/// Lean of the wall from vertical at point i of section k (k ≥ 1), degrees:
/// `atan(|(pₖ − pₖ₋₁)·n| / Δz)` with n the XY normal of section k − 1.
#[inline]
fn lean_deg(p: glam::DVec3, q: glam::DVec3, n: DVec2) -> f64 {
    let dz = p.z - q.z;
    let off = (p.truncate() - q.truncate()).dot(n).abs();
    off.atan2(dz.max(1e-9)).to_degrees()
}

/// Lean from vertical of every point, section-major (`k·n + i`), degrees; section 0 (on the bed)
/// leans 0. The preview colours the wall by these.
pub fn point_leans_deg(sections: &[Section]) -> Vec<f32> {
    measure_with_leans(sections).1
}

/// Largest lean, z ranges and layer heights of a surface.
pub fn measure(sections: &[Section]) -> SurfaceMetrics {
    measure_with_leans(sections).0
}

/// [`measure`] and [`point_leans_deg`] in one pass (the surface keeps both); the sections are
/// measured in parts on the machine's cores and the parts merged (maxima and minima).
pub fn measure_with_leans(sections: &[Section]) -> (SurfaceMetrics, Vec<f32>) {
    let parts =
        crate::parallel::map_ranges(sections.len(), 64, |r| vec![measure_part(sections, r)]);
    let mut m = SurfaceMetrics {
        min_layer_height: f64::INFINITY,
        ..Default::default()
    };
    let mut leans = Vec::with_capacity(sections.iter().map(|s| s.points.len()).sum());
    for (part, part_leans) in parts {
        m.max_overhang_deg = m.max_overhang_deg.max(part.max_overhang_deg);
        m.max_layer_z_range = m.max_layer_z_range.max(part.max_layer_z_range);
        m.min_layer_height = m.min_layer_height.min(part.min_layer_height);
        m.max_layer_height = m.max_layer_height.max(part.max_layer_height);
        leans.extend_from_slice(&part_leans);
    }
    if !m.min_layer_height.is_finite() {
        m.min_layer_height = 0.0;
    }
    (m, leans)
}

/// The metrics and leans of sections `range` (section 0, on the bed, leans 0 and bounds no
/// layer).
fn measure_part(sections: &[Section], range: std::ops::Range<usize>) -> (SurfaceMetrics, Vec<f32>) {
    let mut m = SurfaceMetrics {
        min_layer_height: f64::INFINITY,
        ..Default::default()
    };
    let mut leans =
        Vec::with_capacity(sections[range.clone()].iter().map(|s| s.points.len()).sum());
    for k in range {
        let s = &sections[k];
        if k == 0 {
            leans.resize(s.points.len(), 0.0);
            continue;
        }
        let (lo, hi) = s.z_range();
        m.max_layer_z_range = m.max_layer_z_range.max(hi - lo);
        let prev = &sections[k - 1];
        let normals = prev.normals();
        for (i, p) in s.points.iter().enumerate() {
            let q = prev.points[i];
            let dz = p.z - q.z;
            m.min_layer_height = m.min_layer_height.min(dz);
            m.max_layer_height = m.max_layer_height.max(dz);
            let lean = lean_deg(*p, q, normals[i]);
            m.max_overhang_deg = m.max_overhang_deg.max(lean);
            leans.push(lean as f32);
        }
    }
    (m, leans)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    fn ring(r: f64, z: f64, n: usize) -> Section {
        Section {
            points: (0..n)
                .map(|i| {
                    let a = std::f64::consts::TAU * i as f64 / n as f64;
                    DVec3::new(r * a.cos(), r * a.sin(), z)
                })
                .collect(),
        }
    }

    #[test]
    fn flare_past_45_degrees_is_clamped_to_45() {
        // Radius grows 2 mm per 1 mm layer: 63.4°. Clamped to 1 mm per layer.
        let mut s: Vec<Section> = (0..5)
            .map(|k| ring(30.0 + 2.0 * k as f64, k as f64, 360))
            .collect();
        let before = measure(&s);
        assert!((before.max_overhang_deg - 2f64.atan().to_degrees()).abs() < 0.1);
        let ev = clamp_overhang(&mut s, 1, 1.0, true);
        assert_eq!(ev.len(), 4 * 360);
        // First correction removes 1 mm; later ones more as the design runs away.
        assert!((ev[0].amount_mm - 1.0).abs() < 1e-3);
        let after = measure(&s);
        let leans = point_leans_deg(&s);
        assert_eq!(leans.len(), 5 * 360);
        assert!(leans[..360].iter().all(|a| *a == 0.0));
        let max = leans.iter().cloned().fold(0.0f32, f32::max) as f64;
        assert!((max - after.max_overhang_deg).abs() < 1e-3);
        assert!(
            after.max_overhang_deg <= 45.0 + 1e-6,
            "{}",
            after.max_overhang_deg
        );
        let r_top = s[4].points[0].truncate().length();
        assert!((r_top - 34.0).abs() < 1e-3, "{r_top}");
    }

    #[test]
    fn report_only_leaves_the_surface_alone() {
        let mut s: Vec<Section> = (0..3)
            .map(|k| ring(30.0 + 2.0 * k as f64, k as f64, 90))
            .collect();
        let copy = s.clone();
        let ev = clamp_overhang(&mut s, 1, 1.0, false);
        assert_eq!(ev.len(), 2 * 90);
        assert_eq!(s, copy);
    }

    #[test]
    fn vertical_cylinder_has_no_overhang() {
        let s: Vec<Section> = (0..4).map(|k| ring(30.0, k as f64 * 0.5, 100)).collect();
        let m = measure(&s);
        assert!(m.max_overhang_deg < 1e-6);
        assert!(
            (m.min_layer_height - 0.5).abs() < 1e-12 && (m.max_layer_height - 0.5).abs() < 1e-12
        );
    }
}
