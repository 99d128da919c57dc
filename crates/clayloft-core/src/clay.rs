//! Clay bodies (SPEC §14): what the wet clay of a print weighs, how much stress it carries when
//! it leaves the nozzle and how fast it stiffens at rest, how stiff it is against buckling, and
//! how much it shrinks in the kiln.
//!
//! A design's `[clay]` table names a preset (`body = "stoneware"`) and may override any field;
//! without the table the vessel is judged as the default body, stoneware.
//!
//! Where the numbers come from, and how far to trust them:
//! * **Wet density** is that of a saturated paste of clay particles (2600 kg/m³: kaolinite
//!   2.61–2.68 g/cm³, quartz 2.65, the bulk of every body — Deer, Howie & Zussman, *An
//!   Introduction to the Rock-Forming Minerals*, 2nd ed. 1992) in water, at the water content of
//!   a printing paste: ρ = 1 / ((1 − w)/ρₛ + w/ρ_w). Printing pastes are throwing clay (20–24 %
//!   water, wet basis) softened by a few percent of water, as the extruder makers' mixing guides
//!   advise (e.g. Vormvrij's LUTUM clay guide); finer bodies (porcelain) hold more.
//! * **Yield stress at deposition** is the undrained shear strength of the paste. The fall-cone
//!   test calibrates it: a 30°, 80 g cone sinking d mm means τ₀ = 0.8·m·g/d² (Hansbo 1957, the
//!   constant of BS 1377-2), and a clay at its liquid limit (20 mm) has τ₀ ≈ 1.7 kPa (Wroth &
//!   Wood 1978, *Can. Geotech. J.* 15:137). A paste that extrudes through a 3 mm nozzle and holds
//!   its bead sits a little stiffer than that: the presets take 2–4 kPa. These are orders of
//!   magnitude, not measurements of a brand: measure your own paste (`fall_cone_mm`).
//! * **Structuration rate** A (Pa/s): the yield stress grows at rest as τ₀(t) = τ₀ + A·t, the
//!   linear model of Roussel (2006, *Cem. Concr. Res.* 36:1797) that Roussel (2018, *Cem. Concr.
//!   Res.* 112:76) and Perrot et al. (2016, *Mater. Struct.* 49:1213) use for layer-by-layer
//!   building, valid over the first hour or so. A wet clay gains its strength mostly by losing
//!   water to the air rather than by thixotropy; the presets assume 0.3–0.8 Pa/s (1–3 kPa an
//!   hour), the low end of Roussel's range for printable cement pastes.
//! * **Elastic modulus** E at deposition, growing in proportion to the yield stress (Roussel
//!   2018: the critical strain γ_c = τ₀/G of a paste stays constant as it structures, and
//!   E = 2(1 + ν)G = 3G for an incompressible paste). The presets take γ_c = 5 %: E = 60·τ₀.
//! * **Firing shrinkage** (linear, wet to fired, which is what a printed wet vessel goes
//!   through): stoneware 12 % (11–15 % total for stoneware, Laguna B-Mix 12–14 %: craftcalc.com
//!   clay shrinkage table), porcelain 15 % (Plainsman Polar Ice, "the highest firing shrinkage
//!   you should ever normally encounter", 14–15 %: Digitalfire/Insight-live 2015), earthenware
//!   9 % (8–12 %, craftcalc.com), terracotta 8 % (red earthenware 8–10 %, craftcalc.com); the
//!   paper itself expects 10–20 % (§5).

use serde::{Deserialize, Serialize};

use crate::design::{ContourSpec, Design};
use crate::validate::FieldError;

/// Standard gravity, m/s².
pub const GRAVITY: f64 = 9.806_65;

/// The `[clay]` table of a design: a preset and the fields it overrides.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ClayTable {
    /// Preset name ([`PRESETS`]); stoneware when not given.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub body: Option<String>,
    /// kg/m³.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub wet_density: Option<f64>,
    /// Pa, at deposition.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub yield_stress: Option<f64>,
    /// Depth an 80 g, 30° fall cone sinks into the paste, mm: sets the yield stress (Hansbo).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fall_cone_mm: Option<f64>,
    /// Pa/s: growth of the yield stress at rest.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub structuration_rate: Option<f64>,
    /// Pa, at deposition.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub elastic_modulus: Option<f64>,
    /// Linear shrinkage from wet to fired, % (XY, and Z unless `firing_shrinkage_z_percent`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub firing_shrinkage_percent: Option<f64>,
    /// Linear shrinkage in height, % (defaults to `firing_shrinkage_percent`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub firing_shrinkage_z_percent: Option<f64>,
    /// Print the vessel enlarged so that the fired piece has the designed size.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub compensate_shrinkage: bool,
}

/// A clay body with every number resolved (SI units but shrinkage, in %).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClayBody {
    pub name: &'static str,
    /// kg/m³.
    pub wet_density: f64,
    /// Pa.
    pub yield_stress: f64,
    /// Pa/s.
    pub structuration_rate: f64,
    /// Pa.
    pub elastic_modulus: f64,
    /// %.
    pub firing_shrinkage_percent: f64,
    /// %.
    pub firing_shrinkage_z_percent: f64,
}

/// Wet density of a saturated paste with water fraction `w` (wet basis), kg/m³ (see the module
/// documentation for ρₛ).
const fn paste_density(w: f64) -> f64 {
    1.0 / ((1.0 - w) / 2600.0 + w / 1000.0)
}

/// Modulus of a paste of yield stress `tau` with a 5 % critical strain: E = 3·τ/γ_c.
const fn modulus(tau: f64) -> f64 {
    3.0 * tau / 0.05
}

const fn body(name: &'static str, water: f64, tau: f64, rate: f64, shrink: f64) -> ClayBody {
    ClayBody {
        name,
        wet_density: paste_density(water),
        yield_stress: tau,
        structuration_rate: rate,
        elastic_modulus: modulus(tau),
        firing_shrinkage_percent: shrink,
        firing_shrinkage_z_percent: shrink,
    }
}

/// The shipped bodies at printing consistency (sources in the module documentation): water
/// content (wet basis), yield stress, structuration rate, firing shrinkage.
pub const PRESETS: &[ClayBody] = &[
    // Grogged or plain buff stoneware, softened from throwing consistency (22 %) to 24 %.
    body("stoneware", 0.24, 3000.0, 0.5, 12.0),
    // Fine porcelain holds more water at the same feel and is weaker: 26 %.
    body("porcelain", 0.26, 2500.0, 0.3, 15.0),
    // White or buff earthenware, 25 %.
    body("earthenware", 0.25, 3000.0, 0.5, 9.0),
    // Coarse red terracotta with grog: stiffer at less water (22 %), dries faster.
    body("terracotta", 0.22, 4000.0, 0.8, 8.0),
];

/// The default body of a design without `[clay]`.
pub const DEFAULT_BODY: &str = "stoneware";

/// Yield stress from a fall-cone depth, Pa: τ₀ = K·m·g/d² with K = 0.8, m = 80 g (Hansbo 1957).
pub fn fall_cone_yield_stress(depth_mm: f64) -> f64 {
    0.8 * 0.080 * GRAVITY / (depth_mm * 1e-3).powi(2)
}

/// The preset called `name`.
pub fn preset(name: &str) -> Option<&'static ClayBody> {
    PRESETS.iter().find(|b| b.name == name)
}

/// The clay body of a `[clay]` table (or the default body without one), every field checked.
pub fn resolve(table: Option<&ClayTable>) -> Result<ClayBody, FieldError> {
    let empty = ClayTable::default();
    let t = table.unwrap_or(&empty);
    let name = t.body.as_deref().unwrap_or(DEFAULT_BODY);
    let mut b = *preset(name).ok_or_else(|| {
        let names: Vec<&str> = PRESETS.iter().map(|b| b.name).collect();
        FieldError::new(
            "clay.body",
            format!(
                "no clay body `{name}`: the presets are {}",
                names.join(", ")
            ),
        )
    })?;
    let set = |path: &str, v: Option<f64>, slot: &mut f64| -> Result<(), FieldError> {
        if let Some(v) = v {
            crate::fields::check(path, v)?;
            *slot = v;
        }
        Ok(())
    };
    set("clay.wet_density", t.wet_density, &mut b.wet_density)?;
    if t.yield_stress.is_some() && t.fall_cone_mm.is_some() {
        return Err(FieldError::new(
            "clay.fall_cone_mm",
            "give the yield stress or the fall-cone depth, not both",
        ));
    }
    let from_preset = b.yield_stress;
    set("clay.yield_stress", t.yield_stress, &mut b.yield_stress)?;
    if let Some(d) = t.fall_cone_mm {
        crate::fields::check("clay.fall_cone_mm", d)?;
        b.yield_stress = fall_cone_yield_stress(d);
    }
    // The modulus follows a measured yield stress unless it is given too (constant γ_c).
    b.elastic_modulus *= b.yield_stress / from_preset;
    set(
        "clay.structuration_rate",
        t.structuration_rate,
        &mut b.structuration_rate,
    )?;
    set(
        "clay.elastic_modulus",
        t.elastic_modulus,
        &mut b.elastic_modulus,
    )?;
    set(
        "clay.firing_shrinkage_percent",
        t.firing_shrinkage_percent,
        &mut b.firing_shrinkage_percent,
    )?;
    b.firing_shrinkage_z_percent = b.firing_shrinkage_percent;
    set(
        "clay.firing_shrinkage_z_percent",
        t.firing_shrinkage_z_percent,
        &mut b.firing_shrinkage_z_percent,
    )?;
    Ok(b)
}

impl ClayBody {
    /// Yield stress after `age` seconds at rest, Pa: τ₀ + A·age (Roussel 2006).
    pub fn yield_stress_at(&self, age: f64) -> f64 {
        self.yield_stress + self.structuration_rate * age.max(0.0)
    }

    /// Elastic modulus after `age` seconds at rest, Pa, in proportion to the yield stress.
    pub fn elastic_modulus_at(&self, age: f64) -> f64 {
        self.elastic_modulus * self.yield_stress_at(age) / self.yield_stress
    }

    /// Wet size over fired size in XY and in Z: the factors that make a fired piece the designed
    /// size, 1 / (1 − s).
    pub fn compensation(&self) -> (f64, f64) {
        (
            1.0 / (1.0 - self.firing_shrinkage_percent / 100.0),
            1.0 / (1.0 - self.firing_shrinkage_z_percent / 100.0),
        )
    }
}

/// The vessel as it must be printed wet so that it fires to the design's size: with
/// `[clay] compensate_shrinkage = true` every length across (contours, control-line offsets,
/// texture amplitudes, a mesh's scale) grows by 1/(1 − s_xy) and every height (the vessel's,
/// horizontal control lines' rises) by 1/(1 − s_z); otherwise the design itself. Layer heights
/// stay the printer's: a taller vessel gets more layers.
pub fn wet_design(design: &Design) -> Result<std::borrow::Cow<'_, Design>, FieldError> {
    let Some(table) = design.clay.as_ref().filter(|t| t.compensate_shrinkage) else {
        return Ok(std::borrow::Cow::Borrowed(design));
    };
    let body = resolve(Some(table))?;
    let (kxy, kz) = body.compensation();
    let mut d = design.clone();
    let s = &mut d.shape;
    s.height *= kz;
    if let Some(m) = &mut s.mesh {
        if kxy != kz {
            return Err(FieldError::new(
                "clay.firing_shrinkage_z_percent",
                "a vessel from a mesh is enlarged alike in every direction: give one firing_shrinkage_percent",
            ));
        }
        m.scale *= kxy;
    }
    for c in [&mut s.lower, &mut s.upper] {
        scale_contour(c, kxy);
    }
    for line in &mut d.control.vertical {
        for p in &mut line.points {
            p[1] *= kxy;
        }
    }
    for line in &mut d.control.horizontal {
        for p in &mut line.points {
            p[1] *= kz;
        }
    }
    if let Some(t) = &mut d.texture {
        for w in [&mut t.x, &mut t.y].into_iter().flatten() {
            w.amplitude *= kxy;
        }
    }
    Ok(std::borrow::Cow::Owned(d))
}

/// The factors [`wet_design`] enlarges the design by, across and in height: (1, 1) without
/// compensation (or with a clay table that does not resolve: the validator reports it).
pub fn wet_factors(design: &Design) -> (f64, f64) {
    design
        .clay
        .as_ref()
        .filter(|t| t.compensate_shrinkage)
        .and_then(|t| resolve(Some(t)).ok())
        .map_or((1.0, 1.0), |b| b.compensation())
}

/// Every length of a contour times `k`.
fn scale_contour(c: &mut ContourSpec, k: f64) {
    match c {
        ContourSpec::Circle { radius } => *radius *= k,
        ContourSpec::Ellipse { rx, ry } => {
            *rx *= k;
            *ry *= k;
        }
        ContourSpec::Polygon {
            radius,
            corner_radius,
            ..
        } => {
            *radius *= k;
            *corner_radius *= k;
        }
        ContourSpec::Star {
            outer_radius,
            inner_radius,
            ..
        } => {
            *outer_radius *= k;
            *inner_radius *= k;
        }
        ContourSpec::Rose {
            radius, amplitude, ..
        } => {
            *radius *= k;
            *amplitude *= k;
        }
        ContourSpec::Spline { points } => {
            for p in points {
                p[0] *= k;
                p[1] *= k;
            }
        }
        ContourSpec::Image { size, .. } | ContourSpec::Svg { size, .. } => *size *= k,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_have_the_densities_of_their_pastes() {
        // ρ = 1 / (0.76/2600 + 0.24/1000) = 1878.6 kg/m³.
        let s = preset("stoneware").unwrap();
        assert!((s.wet_density - 1878.6).abs() < 0.1, "{}", s.wet_density);
        for b in PRESETS {
            assert!((1700.0..2100.0).contains(&b.wet_density), "{}", b.name);
            assert_eq!(b.elastic_modulus, 60.0 * b.yield_stress);
        }
        assert_eq!(PRESETS.len(), 4);
    }

    #[test]
    fn the_fall_cone_gives_the_liquid_limit_strength_at_20_mm() {
        // Wroth & Wood: about 1.7 kPa at the liquid limit (20 mm).
        let tau = fall_cone_yield_stress(20.0);
        assert!((tau - 1569.1).abs() < 1.0, "{tau}");
    }

    #[test]
    fn fields_override_the_preset_and_bad_values_name_the_field() {
        let t = ClayTable {
            body: Some("porcelain".into()),
            yield_stress: Some(5000.0),
            firing_shrinkage_percent: Some(13.0),
            ..Default::default()
        };
        let b = resolve(Some(&t)).unwrap();
        assert_eq!(b.name, "porcelain");
        assert_eq!(b.yield_stress, 5000.0);
        // The modulus follows the measured yield stress.
        assert_eq!(b.elastic_modulus, 60.0 * 5000.0);
        assert_eq!(b.firing_shrinkage_z_percent, 13.0);
        assert_eq!(resolve(None).unwrap().name, "stoneware");
        let bad = |t: ClayTable| resolve(Some(&t)).unwrap_err().field;
        assert_eq!(
            bad(ClayTable {
                body: Some("plasticine".into()),
                ..Default::default()
            }),
            "clay.body"
        );
        assert_eq!(
            bad(ClayTable {
                wet_density: Some(-3.0),
                ..Default::default()
            }),
            "clay.wet_density"
        );
        assert_eq!(
            bad(ClayTable {
                firing_shrinkage_percent: Some(60.0),
                ..Default::default()
            }),
            "clay.firing_shrinkage_percent"
        );
        assert_eq!(
            bad(ClayTable {
                yield_stress: Some(f64::NAN),
                ..Default::default()
            }),
            "clay.yield_stress"
        );
        assert_eq!(
            bad(ClayTable {
                yield_stress: Some(3000.0),
                fall_cone_mm: Some(12.0),
                ..Default::default()
            }),
            "clay.fall_cone_mm"
        );
    }

    #[test]
    fn the_wet_vessel_is_the_designed_one_enlarged_to_fire_to_size() {
        let d = crate::load::parse_design(
            "version = 1\n[shape]\nheight = 88.0\n[shape.lower]\ntype = \"circle\"\nradius = 44.0\n[shape.upper]\ntype = \"star\"\npoints = 5\nouter_radius = 44.0\ninner_radius = 22.0\n[[control.vertical]]\npoints = [[0.0, 0.0], [0.5, 8.8], [1.0, 0.0]]\n[clay]\nbody = \"stoneware\"\ncompensate_shrinkage = true\nfiring_shrinkage_z_percent = 10.0\n",
        )
        .unwrap();
        let wet = wet_design(&d).unwrap();
        // 12 % across: 44 / 0.88 = 50; 10 % in height: 88 / 0.9 = 97.8.
        assert!((wet.shape.height - 88.0 / 0.9).abs() < 1e-9);
        assert!(
            matches!(wet.shape.lower, ContourSpec::Circle { radius } if (radius - 50.0).abs() < 1e-9)
        );
        assert!(
            matches!(wet.shape.upper, ContourSpec::Star { outer_radius, inner_radius, .. }
            if (outer_radius - 50.0).abs() < 1e-9 && (inner_radius - 25.0).abs() < 1e-9)
        );
        assert!((wet.control.vertical[0].points[1][1] - 10.0).abs() < 1e-9);
        // Without compensation the design itself.
        let mut plain = d.clone();
        plain.clay.as_mut().unwrap().compensate_shrinkage = false;
        assert!(matches!(
            wet_design(&plain).unwrap(),
            std::borrow::Cow::Borrowed(_)
        ));
    }

    #[test]
    fn compensation_makes_the_fired_piece_the_designed_size() {
        let b = preset("stoneware").unwrap();
        let (kxy, kz) = b.compensation();
        assert!((100.0 * kxy * (1.0 - 0.12) - 100.0).abs() < 1e-9);
        assert_eq!(kxy, kz);
    }
}
