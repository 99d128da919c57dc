//! The whole pipeline as one loop over the per-stage functions: design → loft → control lines →
//! constraints → texture → spiral toolpath. [`crate::session::Session`] runs them
//! incrementally; [`run`] is its first update.

use std::sync::Arc;

use glam::DVec2;

use crate::constraint::{
    SurfaceMetrics, clamp_overhang, clamp_overhang_measured, measure, measure_with_leans,
};
use crate::design::Design;
use crate::loft::LoftInput;
use crate::report::{Finding, FindingKind, group_events};
use crate::section::Section;
use crate::session::Session;
use crate::shape::{LIMIT_MARGIN, ShapeModel};
use crate::texture::{apply_displacements, apply_texture};
use crate::toolpath::Toolpath;
use crate::validate::FieldError;

/// The corrected, textured section surface of a design.
#[derive(Debug, Clone, PartialEq)]
pub struct Surface {
    /// Sections 0 ..= L; section 0 is the bed contact at z = 0.
    pub sections: Vec<Section>,
    pub layers: usize,
    /// Nominal layer pitch, mm.
    pub layer_pitch: f64,
    pub center: DVec2,
    pub findings: Vec<Finding>,
    pub metrics: SurfaceMetrics,
    /// Lean from vertical of every point, section-major (`k·n + i`), degrees (the view colours
    /// the wall by it): empty for a surface made without a view (the command line's; the
    /// view's mesh then measures them itself).
    pub point_leans_deg: Vec<f32>,
}

/// A design turned into a printable job. Shared, not copied: the app's view, the replay, the
/// exports and the printer read the same job the [`crate::session::Session`] computed.
#[derive(Debug, Clone)]
pub struct PrintJob {
    pub surface: Arc<Surface>,
    /// The wall's inner beads ([`crate::walls::inner_beads`]): empty for a one-bead wall.
    pub beads: Arc<crate::walls::InnerBeads>,
    pub toolpath: Arc<Toolpath>,
    /// Whether the wet wall stands while the toolpath is printed (SPEC §14); `None` for a clay
    /// body that does not resolve (validation reports it).
    pub verdict: Option<Arc<crate::printability::Printability>>,
}

impl PrintJob {
    /// Everything the stages corrected or found: the surface's first, then the inner beads',
    /// then the path's.
    pub fn findings(&self) -> impl Iterator<Item = &Finding> {
        self.surface
            .findings
            .iter()
            .chain(&self.beads.findings)
            .chain(&self.toolpath.findings)
    }
}

/// `tan(max_overhang)` with the pipeline's safety margin.
pub fn overhang_tan_limit(design: &Design) -> f64 {
    design.printer.max_overhang_deg.to_radians().tan() * LIMIT_MARGIN
}

/// Corrects the shaped sections against the overhang limit from section `from` upward and
/// reports what moved.
pub fn correct_shape(design: &Design, sections: &mut [Section], from: usize) -> Vec<Finding> {
    let enforce = design.constraints.enforce;
    let events = clamp_overhang(sections, from, overhang_tan_limit(design), enforce);
    let limit = design.printer.max_overhang_deg;
    group_events(&events, FindingKind::Overhang, enforce, 3, |mm| {
        if enforce {
            format!("wall leaned past {limit}°; offsets clamped by up to {mm:.2} mm")
        } else {
            format!("wall leans past {limit}° by up to {mm:.2} mm per layer")
        }
    })
}

/// Builds the corrected, textured surface of a design.
pub fn build_surface(design: &Design) -> Result<Surface, FieldError> {
    let loft = LoftInput::from_design(design)?;
    let (model, findings) = ShapeModel::new(design, loft)?;
    let sections: Vec<Section> = (0..=model.layers).map(|k| model.section(k)).collect();
    finish_surface(design, &model, sections, findings, None)
}

/// Stages 4–5 on the shaped sections `model.section(k)`: overhang correction, texture, metrics
/// and the fit on the machine. The session calls this after recomputing only the sections an
/// edit touched; `findings` are the layer plan's (from [`ShapeModel::new`]); `displacements`
/// the texture's for this grid if already known ([`crate::texture::displacements`]).
pub fn finish_surface(
    design: &Design,
    model: &ShapeModel,
    sections: Vec<Section>,
    findings: Vec<Finding>,
    displacements: Option<&[Vec<f64>]>,
) -> Result<Surface, FieldError> {
    let grid = SectionGrid {
        center: model.loft.center,
        layers: model.layers,
        layer_pitch: model.layer_pitch,
    };
    finish_sections(design, grid, sections, findings, displacements, true)
}

/// Where the sections of a surface stand: the vessel's centre on the bed, the layer count and
/// the nominal pitch (from the layer plan of a lofted design, or the slicing of a mesh).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SectionGrid {
    pub center: DVec2,
    pub layers: usize,
    pub layer_pitch: f64,
}

/// [`finish_surface`] for sections from anywhere (a lofted design's or a mesh's slices), keeping
/// each point's lean ([`Surface::point_leans_deg`]) only when `keep_leans` (for a view).
pub fn finish_sections(
    design: &Design,
    grid: SectionGrid,
    mut sections: Vec<Section>,
    mut findings: Vec<Finding>,
    displacements: Option<&[Vec<f64>]>,
    keep_leans: bool,
) -> Result<Surface, FieldError> {
    let center = grid.center;
    findings.extend(correct_shape(design, &mut sections, 1));
    // The metrics, where taken as the texture's last correction is made; a wall of several
    // beads is turned to its seam after it (below), and measured then.
    let mut measured = None;
    let seam_after = design.shape.walls > 1;
    if let Some(tex) = &design.texture {
        let enforce = design.constraints.enforce;
        // The overhang limit, and never a bead wholly beside the one below it (half a bead out
        // per layer: beyond that a texture's stretch of bead has nothing under it and droops,
        // SPEC §14; only a printer set steeper than about 56° reaches it).
        let tan = overhang_tan_limit(design)
            .min(0.5 * design.printer.line_width / grid.layer_pitch.max(1e-9));
        let lowered = match displacements {
            Some(disp) => apply_displacements(&mut sections, disp, tan, enforce),
            None => apply_texture(&mut sections, tex, tan, enforce),
        };
        // Made whether or not the limits are enforced: a fold is not a shape the design asks
        // for but the texture's offset turning the wall back on itself (as the shape's folds).
        findings.extend(group_events(
            &lowered.folds,
            FindingKind::Texture,
            true,
            usize::MAX,
            |mm| {
                format!(
                    "texture amplitude lowered by up to {mm:.2} mm where the wall turns more sharply than the texture is deep, so that it does not fold back on itself"
                )
            },
        ));
        let events = lowered.overhang;
        if !events.is_empty() {
            let columns = events.len();
            let mut f = group_events(&events, FindingKind::Texture, enforce, usize::MAX, |mm| {
                if enforce {
                    format!(
                        "texture amplitude lowered by up to {mm:.2} mm on {columns} of the columns to keep the overhang limit"
                    )
                } else {
                    format!(
                        "texture breaks the overhang limit on {columns} columns (up to {mm:.2} mm too deep)"
                    )
                }
            });
            findings.append(&mut f);
        }
        // Safety net: whatever the column scaling missed (normals turn with the texture). The
        // wall is measured as it is clamped where nothing moves it after and no point's lean
        // is kept.
        let tan = overhang_tan_limit(design) / LIMIT_MARGIN;
        let residual = if seam_after || keep_leans {
            clamp_overhang(&mut sections, 1, tan, enforce)
        } else {
            let (events, metrics) = clamp_overhang_measured(&mut sections, tan, enforce);
            measured = Some(metrics);
            events
        };
        findings.extend(group_events(
            &residual,
            FindingKind::Texture,
            enforce,
            3,
            |mm| format!("textured wall clamped by up to {mm:.2} mm at the overhang limit"),
        ));
    }
    // A wall of several beads steps across where the layers are level (see `seam`).
    if seam_after {
        let seam = crate::seam::flattest_sample(
            &sections,
            design.printer.line_width,
            design.shape.walls,
            design.printer.min_layer_height,
        );
        crate::seam::start_at(&mut sections, seam);
    }
    let (metrics, point_leans_deg) = match measured {
        Some(metrics) => (metrics, Vec::new()),
        None if keep_leans => measure_with_leans(&sections),
        None => (measure(&sections), Vec::new()),
    };
    let surface = Surface {
        sections,
        layers: grid.layers,
        layer_pitch: grid.layer_pitch,
        center,
        findings,
        metrics,
        point_leans_deg,
    };
    check_fits_machine(design, &surface)?;
    Ok(surface)
}

/// The printed wall (path ± line_width / 2) must lie on the bed and under the build height.
fn check_fits_machine(design: &Design, surface: &Surface) -> Result<(), FieldError> {
    let p = &design.printer;
    let half = p.line_width / 2.0;
    // The wall's box and top, measured with the rest of its metrics.
    let ((lo, hi), top) = (surface.metrics.xy_box, surface.metrics.top);
    let (lo, hi) = (lo - half, hi + half);
    let field = if design.shape.center.is_some() {
        "shape.center"
    } else if design.shape.mesh.is_some() {
        "shape.mesh.scale"
    } else {
        "shape"
    };
    let [ox, oy] = p.origin_offset();
    match p.bed_shape {
        crate::design::BedShape::Rectangle => {
            for (axis, lo, hi, size, o) in [
                ("x", lo.x, hi.x, p.bed_x, ox),
                ("y", lo.y, hi.y, p.bed_y, oy),
            ] {
                if lo < 0.0 || hi > size {
                    return Err(FieldError::new(
                        field,
                        format!(
                            "the vessel spans {axis} = {:.1} … {:.1} mm but the bed is {} … {} mm (printer.bed_{axis}); make it smaller or move it",
                            lo - o,
                            hi - o,
                            -o,
                            size - o
                        ),
                    ));
                }
            }
        }
        crate::design::BedShape::Circle => {
            let c = DVec2::new(p.bed_x / 2.0, p.bed_y / 2.0);
            let reach = surface
                .sections
                .iter()
                .flat_map(|s| s.points.iter())
                .map(|q| q.truncate().distance(c))
                .fold(0.0, f64::max)
                + half;
            if reach > p.bed_x / 2.0 {
                return Err(FieldError::new(
                    field,
                    format!(
                        "the vessel reaches {reach:.1} mm from the bed centre but the round bed's radius is {} mm (printer.bed_diameter); make it smaller or move it",
                        p.bed_x / 2.0
                    ),
                ));
            }
        }
    }
    if top > p.max_z {
        let (field, hint) = match design.shape.mesh {
            Some(_) => (
                "shape.mesh.scale",
                " (scale the mesh down with shape.mesh.scale)",
            ),
            None => ("shape.height", ""),
        };
        return Err(FieldError::new(
            field,
            format!(
                "the rim reaches z = {top:.1} mm, above the build height printer.max_z = {} mm{hint}",
                p.max_z
            ),
        ));
    }
    Ok(())
}

/// Runs the whole pipeline (a fresh [`Session`]'s first update): the design validated, the
/// surface, then the single spiral toolpath.
pub fn run(design: &Design) -> Result<PrintJob, FieldError> {
    let mut session = Session::for_one_update();
    session.update(design)?;
    Ok(session.job().expect("a successful update has a job"))
}

/// [`run`] without the printability verdict (`verdict` is `None`), for a caller with other
/// work to set it beside: [`judge`] gives it. (`clayloft gcode` judges the job once its
/// program is in place, while the system frees the file it replaced: a wait on the disk of
/// 2–3 ms here, which the verdict's 2–4 ms of work now fills.)
pub fn run_unjudged(design: &Design) -> Result<PrintJob, FieldError> {
    let mut session = Session::for_one_unjudged_update();
    session.update(design)?;
    Ok(session.job().expect("a successful update has a job"))
}

/// The printability verdict [`run`] gives `job`, a job of `design` (judged at its wet size:
/// see [`crate::clay::wet_design`]).
pub fn judge(design: &Design, job: &PrintJob) -> Option<Arc<crate::printability::Printability>> {
    let wet = crate::clay::wet_design(design).ok()?;
    verdict(&wet, &job.surface, &job.toolpath)
}

/// The verdict on `toolpath` over `surface`, made for `wet` (a design at its wet size): `None`
/// for a clay body that does not resolve. A session's verdict stage and [`judge`] both.
pub(crate) fn verdict(
    wet: &Design,
    surface: &Surface,
    toolpath: &Toolpath,
) -> Option<Arc<crate::printability::Printability>> {
    crate::printability::assess(wet, surface, toolpath)
        .ok()
        .map(Arc::new)
}
