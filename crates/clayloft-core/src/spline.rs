//! Closed centripetal Catmull–Rom splines: the curve passes through every control point, and the
//! centripetal parametrisation (α = ½) never forms cusps or loops within a span.
//!
//! For a span P₁→P₂ with neighbours P₀, P₃, knots tᵢ₊₁ = tᵢ + |Pᵢ₊₁ − Pᵢ|^α and the point at
//! t ∈ [t₁, t₂] follows the Barry–Goldman pyramid of linear interpolations.

use glam::DVec2;

const ALPHA: f64 = 0.5;

/// Points along the closed spline through `control`, `per_span` points per span (the control
/// points themselves included, each once). `control` must hold at least 3 distinct points with no
/// two consecutive points equal.
pub fn closed_catmull_rom(control: &[DVec2], per_span: usize) -> Vec<DVec2> {
    let n = control.len();
    let mut out = Vec::with_capacity(n * per_span);
    for i in 0..n {
        let p0 = control[(i + n - 1) % n];
        let p1 = control[i];
        let p2 = control[(i + 1) % n];
        let p3 = control[(i + 2) % n];
        for k in 0..per_span {
            out.push(span_point(p0, p1, p2, p3, k as f64 / per_span as f64));
        }
    }
    out
}

/// Point at fraction `u ∈ [0, 1)` of the span P₁→P₂.
fn span_point(p0: DVec2, p1: DVec2, p2: DVec2, p3: DVec2, u: f64) -> DVec2 {
    let knot = |a: DVec2, b: DVec2| a.distance(b).powf(ALPHA).max(1e-9);
    let t0 = 0.0;
    let t1 = t0 + knot(p0, p1);
    let t2 = t1 + knot(p1, p2);
    let t3 = t2 + knot(p2, p3);
    let t = t1 + (t2 - t1) * u;
    let lerp = |a: DVec2, b: DVec2, ta: f64, tb: f64| {
        a * ((tb - t) / (tb - ta)) + b * ((t - ta) / (tb - ta))
    };
    let a1 = lerp(p0, p1, t0, t1);
    let a2 = lerp(p1, p2, t1, t2);
    let a3 = lerp(p2, p3, t2, t3);
    let b1 = lerp(a1, a2, t0, t2);
    let b2 = lerp(a2, a3, t1, t3);
    lerp(b1, b2, t1, t2)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn passes_through_every_control_point() {
        let c = [
            DVec2::new(40.0, 0.0),
            DVec2::new(0.0, 35.0),
            DVec2::new(-40.0, 0.0),
            DVec2::new(0.0, -35.0),
        ];
        let pts = closed_catmull_rom(&c, 16);
        assert_eq!(pts.len(), 64);
        for (i, p) in c.iter().enumerate() {
            assert!(pts[i * 16].distance(*p) < 1e-12);
        }
    }

    #[test]
    fn regular_polygon_controls_give_a_near_circle() {
        let n = 12;
        let c: Vec<DVec2> = (0..n)
            .map(|i| DVec2::from_angle(std::f64::consts::TAU * i as f64 / n as f64) * 10.0)
            .collect();
        for p in closed_catmull_rom(&c, 32) {
            assert!((p.length() - 10.0).abs() < 0.02, "{}", p.length());
        }
    }
}
