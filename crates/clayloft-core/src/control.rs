//! Control lines (SPEC §1.5): large-scale shaping of the loft.
//!
//! * A vertical line gives an outward offset `d(t)` along the section normal as a smooth function
//!   of the height fraction `t`, on the whole section or locally around an angle with a raised
//!   cosine fall-off `w(φ) = ½(1 + cos(2π Δφ / width))` for `|Δφ| < width / 2`.
//! * A horizontal line gives a z offset `dz(φ)`, periodic in the angle φ, weighted by
//!   `w(t) = ½(1 + cos(π |t − at| / reach))` for `|t − at| < reach`.

use crate::design::{HorizontalLine, VerticalLine};
use crate::interp::Pchip;

/// Default angular width of a local vertical line, degrees.
pub const DEFAULT_LOCAL_WIDTH_DEG: f64 = 60.0;

/// A vertical control line ready to evaluate.
#[derive(Debug, Clone)]
pub struct VerticalProfile {
    profile: Pchip,
    /// Centre angle and full width, radians, for a local line.
    local: Option<(f64, f64)>,
    /// Height-fraction span where the offset is non-zero (inclusive).
    span: (f64, f64),
}

impl VerticalProfile {
    pub fn new(line: &VerticalLine) -> VerticalProfile {
        let xs: Vec<f64> = line.points.iter().map(|p| p[0]).collect();
        let ys: Vec<f64> = line.points.iter().map(|p| p[1]).collect();
        let first_nonzero = ys.iter().position(|y| *y != 0.0);
        let last_nonzero = ys.iter().rposition(|y| *y != 0.0);
        let span = match (first_nonzero, last_nonzero) {
            (Some(a), Some(b)) => (
                if a == 0 { 0.0 } else { xs[a - 1] },
                if b + 1 == xs.len() { 1.0 } else { xs[b + 1] },
            ),
            _ => (1.0, 0.0), // all zero: empty span
        };
        VerticalProfile {
            profile: Pchip::new(xs, ys),
            local: line.angle.map(|a| {
                (
                    a.to_radians(),
                    line.width.unwrap_or(DEFAULT_LOCAL_WIDTH_DEG).to_radians(),
                )
            }),
            span,
        }
    }

    /// Offset (mm) at height fraction `t`, before the angular weight.
    pub fn offset_at(&self, t: f64) -> f64 {
        self.profile.eval(t)
    }

    /// Angular weight at angle `phi` (radians): 1 everywhere for a global line.
    pub fn weight_at(&self, phi: f64) -> f64 {
        match self.local {
            None => 1.0,
            Some((centre, width)) => {
                let d = angle_difference(phi, centre).abs();
                if d >= width / 2.0 {
                    0.0
                } else {
                    0.5 * (1.0 + (std::f64::consts::TAU * d / width).cos())
                }
            }
        }
    }

    /// Height fractions where this line moves the surface: sections outside are untouched by it.
    pub fn span(&self) -> (f64, f64) {
        self.span
    }
}

/// A horizontal control line ready to evaluate.
#[derive(Debug, Clone)]
pub struct HorizontalProfile {
    dz: Pchip,
    at: f64,
    reach: f64,
}

impl HorizontalProfile {
    pub fn new(line: &HorizontalLine) -> HorizontalProfile {
        let xs: Vec<f64> = line.points.iter().map(|p| p[0]).collect();
        let ys: Vec<f64> = line.points.iter().map(|p| p[1]).collect();
        HorizontalProfile {
            dz: Pchip::periodic(&xs, &ys, 360.0),
            at: line.at,
            reach: line.reach,
        }
    }

    /// z offset (mm) at angle `phi` (radians) at full weight.
    pub fn dz_at(&self, phi: f64) -> f64 {
        self.dz.eval(phi.to_degrees().rem_euclid(360.0))
    }

    /// Weight at height fraction `t`.
    pub fn weight_at(&self, t: f64) -> f64 {
        let s = (t - self.at).abs() / self.reach;
        if s >= 1.0 {
            0.0
        } else {
            0.5 * (1.0 + (std::f64::consts::PI * s).cos())
        }
    }
}

/// Signed difference `a − b` of two angles (radians), in (−π, π].
pub fn angle_difference(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(std::f64::consts::TAU);
    if d > std::f64::consts::PI {
        d - std::f64::consts::TAU
    } else {
        d
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn global_belly_profile() {
        let v = VerticalProfile::new(&VerticalLine {
            points: vec![[0.0, 0.0], [0.5, 15.0], [1.0, 0.0]],
            angle: None,
            width: None,
        });
        assert_eq!(v.offset_at(0.5), 15.0);
        assert_eq!(v.offset_at(0.0), 0.0);
        assert_eq!(v.weight_at(2.0), 1.0);
        assert_eq!(v.span(), (0.0, 1.0));
    }

    #[test]
    fn local_line_falls_off_with_angle() {
        let v = VerticalProfile::new(&VerticalLine {
            points: vec![[0.0, 0.0], [0.3, 0.0], [0.5, 10.0], [0.7, 0.0], [1.0, 0.0]],
            angle: Some(90.0),
            width: Some(60.0),
        });
        assert!((v.weight_at(90f64.to_radians()) - 1.0).abs() < 1e-12);
        assert!((v.weight_at(105f64.to_radians()) - 0.5).abs() < 1e-12);
        assert_eq!(v.weight_at(120f64.to_radians()), 0.0);
        assert_eq!(v.weight_at(270f64.to_radians()), 0.0);
        assert_eq!(v.span(), (0.3, 0.7));
        assert_eq!(v.offset_at(0.2), 0.0);
    }

    #[test]
    fn horizontal_weight_and_periodic_dz() {
        let h = HorizontalProfile::new(&HorizontalLine {
            at: 1.0,
            reach: 0.2,
            points: vec![[0.0, 0.0], [90.0, 8.0], [180.0, 0.0], [270.0, 8.0]],
        });
        assert_eq!(h.weight_at(1.0), 1.0);
        assert!((h.weight_at(0.9) - 0.5).abs() < 1e-12);
        assert_eq!(h.weight_at(0.8), 0.0);
        assert!((h.dz_at(std::f64::consts::FRAC_PI_2) - 8.0).abs() < 1e-12);
        assert!((h.dz_at(-std::f64::consts::FRAC_PI_2) - 8.0).abs() < 1e-12);
    }

    #[test]
    fn angle_difference_wraps() {
        assert!((angle_difference(0.1, std::f64::consts::TAU - 0.1) - 0.2).abs() < 1e-12);
    }
}
