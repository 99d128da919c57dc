//! Loft (SPEC §1.2–1.4): the two contours aligned, sampled and put in correspondence, then
//! linearly interpolated: `P(i, t) = (1 − t)·lowerᵢ + t·upperᵢ`.

use glam::DVec2;

use crate::align::anchor_for;
use crate::contour::{Contour, ContourError, DENSE_POINTS};
use crate::design::{ContourSpec, Design};
use crate::sample::{correspond, sample_from_anchor};
use crate::validate::FieldError;

/// The two sampled, corresponding contours of a design and what is derived from them alone.
#[derive(Debug, Clone, PartialEq)]
pub struct LoftInput {
    /// Lower contour samples, on the bed at the design centre.
    pub lower: Vec<DVec2>,
    /// Upper contour samples, `upper[i]` corresponding to `lower[i]`.
    pub upper: Vec<DVec2>,
    /// Design centre on the bed (both anchors sit here), mm.
    pub center: DVec2,
    /// Angle (radians, counter-clockwise from +x) of sample i seen from the centre, taken at the
    /// midpoint of the two contours; the angular position that local control lines refer to.
    pub angles: Vec<f64>,
}

/// One contour of the design, aligned and sampled.
#[derive(Debug, Clone, PartialEq)]
pub struct SampledContour {
    /// Samples by equal arc length from the anchor, on the bed coordinates.
    pub samples: Vec<DVec2>,
    /// Translation that alignment applied to the contour as specified (spec → bed coordinates).
    pub offset: DVec2,
}

/// Builds, aligns and samples one contour of the design.
/// Image and SVG paths are relative to `base` (the design file's folder).
pub fn sample_contour(
    spec: &ContourSpec,
    field: &str,
    center: DVec2,
    samples: usize,
    base: Option<&std::path::Path>,
) -> Result<SampledContour, FieldError> {
    let contour = Contour::from_spec_in(spec, DENSE_POINTS.max(4 * samples), base)
        .map_err(|e: ContourError| FieldError::new(field, e.to_string()))?;
    let offset = center - anchor_for(spec, &contour);
    let aligned = contour.translated(offset);
    Ok(SampledContour {
        samples: sample_from_anchor(&aligned, center, samples),
        offset,
    })
}

/// The samples of one contour of the design (see [`sample_contour`]).
pub fn sampled_contour(
    spec: &ContourSpec,
    field: &str,
    center: DVec2,
    samples: usize,
) -> Result<Vec<DVec2>, FieldError> {
    sample_contour(spec, field, center, samples, None).map(|c| c.samples)
}

impl LoftInput {
    /// Samples both contours of `design` and puts them in correspondence.
    pub fn from_design(design: &Design) -> Result<LoftInput, FieldError> {
        let [cx, cy] = design.center();
        let center = DVec2::new(cx, cy);
        let n = design.shape.samples;
        let base = design.base_dir.as_deref();
        let lower = sample_contour(&design.shape.lower, "shape.lower", center, n, base)?.samples;
        let upper = sample_contour(&design.shape.upper, "shape.upper", center, n, base)?.samples;
        Ok(LoftInput::from_samples(lower, upper, center))
    }

    /// From already sampled contours (same length): corresponds them and derives the angles.
    pub fn from_samples(lower: Vec<DVec2>, upper: Vec<DVec2>, center: DVec2) -> LoftInput {
        let upper = correspond(&lower, &upper);
        let angles = lower
            .iter()
            .zip(&upper)
            .map(|(a, b)| ((*a + *b) * 0.5 - center).to_angle())
            .collect();
        LoftInput {
            lower,
            upper,
            center,
            angles,
        }
    }

    pub fn samples(&self) -> usize {
        self.lower.len()
    }

    /// The lofted point i at height fraction t.
    #[inline]
    pub fn point(&self, i: usize, t: f64) -> DVec2 {
        self.lower[i].lerp(self.upper[i], t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn loft_between_two_circles_is_a_cone() {
        let d = crate::load::parse_design(
            "version = 1\n[shape.lower]\ntype = \"circle\"\nradius = 40.0\n[shape.upper]\ntype = \"circle\"\nradius = 20.0\n",
        )
        .unwrap();
        let l = LoftInput::from_design(&d).unwrap();
        let c = DVec2::new(90.0, 95.0);
        for i in 0..l.samples() {
            assert!(((l.point(i, 0.5) - c).length() - 30.0).abs() < 1e-3);
            assert!((l.point(i, 0.0) - c).angle_to(l.point(i, 1.0) - c).abs() < 1e-3);
        }
        assert!((l.angles[0]).abs() < 1e-9);
    }
}
