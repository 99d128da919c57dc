//! The incremental engine (SPEC §8): a [`Session`] keeps the output of every pipeline stage
//! together with the inputs it was computed from, and [`Session::update`] recomputes only the
//! stages whose inputs changed.
//!
//! Each stage declares its inputs as a small value ([`ContourKey`], [`PlanKey`], [`SectionKey`],
//! [`SurfaceKey`], [`ToolpathKey`]) built from the design and from the revisions of the stages
//! before it; a stage runs again exactly when its key differs from the one it was last computed
//! with. There is no hand-written list of what an edit invalidates: a field a stage does not put
//! in its key cannot make it run, and a field it reads but forgets is caught by the test that
//! edits designs at random and compares every update with a fresh batch run.
//!
//! The stages, in order:
//! 1. each contour: built, aligned on the centre, sampled (`loft::sample_contour`);
//! 2. the plan: loft, horizontal control lines and the layer count (`ShapeModel::new`);
//! 3. each section k: loft plus the vertical control lines active at its height
//!    (`ShapeModel::section`), in parallel on the machine's cores;
//! 4. the surface: overhang correction, texture, metrics, fit on the machine
//!    (`pipeline::finish_surface`);
//! 5. the base fill of the feet (`toolpath::base_fills`), kept while the feet do not change;
//! 6. the toolpath: the one continuous spiral (`toolpath::build_toolpath_on`);
//! 7. the verdict: whether the wet wall stands while it is printed (`printability::assess`),
//!    but in a session made [`Session::for_one_unjudged_update`];
//! 8. for a session made [`Session::with_wall_view`], the wall's mesh for a 3D view
//!    (`view_mesh::wall_buffers`), so that an application's view and replay share one; it is
//!    built on a second core from the moment the base fill's rings are made (beside the
//!    bridges and the toolpath), or beside the toolpath when the base is kept.
//!
//! The batch [`crate::run`] is a fresh session's first update.

use std::path::PathBuf;
use std::sync::Arc;

use glam::{DVec2, DVec3};

use crate::design::{BedShape, ContourSpec, Design, HorizontalLine, Origin, Texture, VerticalLine};
use crate::loft::{LoftInput, SampledContour, sample_contour};
use crate::pipeline::{PrintJob, Surface, finish_sections};
use crate::printability::Printability;
use crate::report::Finding;
use crate::section::Section;
use crate::shape::ShapeModel;
use crate::toolpath::{Toolpath, build_toolpath_on};
use crate::validate::{FieldError, validate};
use crate::view_mesh::WallBuffers;

/// The two contours, in the order of [`Session::contour`].
pub const CONTOUR_FIELDS: [&str; 2] = ["shape.lower", "shape.upper"];

/// One stage's output and the key it was computed from. `revision` counts the recomputations,
/// so that later stages can put "the output of stage X as of now" in their own keys.
#[derive(Debug, Clone)]
struct Stage<K, V> {
    key: Option<K>,
    value: Option<V>,
    revision: u64,
}

impl<K, V> Default for Stage<K, V> {
    fn default() -> Self {
        Stage {
            key: None,
            value: None,
            revision: 0,
        }
    }
}

impl<K: PartialEq, V> Stage<K, V> {
    /// Recomputes the value when `key` differs from the last one; returns whether it ran. On an
    /// error the stage is left empty, so the next update computes it again.
    fn refresh(
        &mut self,
        key: K,
        compute: impl FnOnce() -> Result<V, FieldError>,
    ) -> Result<bool, FieldError> {
        if self.is_current(&key) {
            return Ok(false);
        }
        self.key = None;
        self.value = None;
        self.revision += 1;
        let value = compute()?;
        self.key = Some(key);
        self.value = Some(value);
        Ok(true)
    }

    /// Whether the value was computed from `key` (a [`Stage::refresh`] would not run).
    fn is_current(&self, key: &K) -> bool {
        self.value.is_some() && self.key.as_ref() == Some(key)
    }

    fn get(&self) -> Option<&V> {
        self.value.as_ref()
    }
}

/// Inputs of a contour: its specification and where and how finely it is sampled.
#[derive(Debug, Clone, PartialEq)]
pub struct ContourKey {
    pub spec: ContourSpec,
    pub center: DVec2,
    pub samples: usize,
    /// The folder image and SVG paths are relative to.
    pub base_dir: Option<PathBuf>,
}

/// Inputs of the layer plan: the sampled contours (by revision), the height, the horizontal
/// control lines and the printer's layer and nozzle limits.
#[derive(Debug, Clone, PartialEq)]
pub struct PlanKey {
    pub contours: [u64; 2],
    pub center: DVec2,
    pub height: f64,
    pub horizontal: Vec<HorizontalLine>,
    pub layer_height: f64,
    pub min_layer_height: f64,
    pub max_layer_height: f64,
    pub nozzle_length: f64,
    pub enforce: bool,
}

/// Inputs of one shaped section: the plan (by revision) and the vertical control lines whose
/// offset is not zero at the section's height (a line that adds nothing there is not an input).
#[derive(Debug, Clone, PartialEq)]
pub struct SectionKey {
    pub plan: u64,
    pub lines: Vec<VerticalLine>,
}

/// Inputs of the corrected, textured surface.
#[derive(Debug, Clone, PartialEq)]
pub struct SurfaceKey {
    pub plan: u64,
    /// Revision of the shaped sections as a whole (any section recomputed bumps it).
    pub sections: u64,
    pub texture: Option<Texture>,
    pub enforce: bool,
    pub max_overhang_deg: f64,
    /// The fit on the machine.
    pub line_width: f64,
    pub bed: (BedShape, f64, f64, Origin),
    pub max_z: f64,
    pub center_given: bool,
    /// The wall's beads: a wall of several starts its sections at its seam, found for that many
    /// beads ([`crate::seam`]).
    pub beads: usize,
}

/// Inputs of the texture's displacement table: the texture and the section grid.
#[derive(Debug, Clone, PartialEq)]
pub struct TextureKey {
    pub texture: Texture,
    pub samples: usize,
    pub sections: usize,
}

/// Inputs of the base fill: the feet it fills, the bead width, the beads of the wall on it
/// (the rings under them are laid all round) and the wall's length, which bounds the path.
#[derive(Debug, Clone, PartialEq)]
pub struct BaseKey {
    pub feet: Vec<Vec<DVec2>>,
    pub line_width: f64,
    pub walls: usize,
    pub wall: (usize, usize),
}

/// Inputs of the wall's inner beads: the surface (by revision), how many beads, their width and
/// where their ties begin.
#[derive(Debug, Clone, PartialEq)]
pub struct BeadKey {
    pub surface: u64,
    pub walls: usize,
    pub line_width: f64,
    /// From which section the inner beads are tied (none: untied).
    pub ties_from: Option<usize>,
    /// The overhang limit they are held to (its tangent, margin included), and whether it is
    /// enforced or only reported.
    pub tan_limit: f64,
    pub enforce: bool,
}

/// Inputs of the spiral toolpath.
#[derive(Debug, Clone, PartialEq)]
pub struct ToolpathKey {
    pub surface: u64,
    /// The base fill (by revision).
    pub base: u64,
    /// The inner beads (by revision).
    pub beads: u64,
    pub base_layers: usize,
    pub line_width: f64,
    pub min_layer_height: f64,
    pub max_layer_height: f64,
    pub min_layer_time: f64,
    pub print_speed: f64,
    pub flow_ramp: (f64, f64),
}

/// What one [`Session::update`] recomputed.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Update {
    /// The contours resampled, as their design fields (`shape.lower`, `shape.upper`).
    pub contours: Vec<&'static str>,
    /// The loft and layer plan (for a design from a mesh: the mesh or its slices) were rebuilt.
    pub plan: bool,
    /// The sections reshaped, ascending.
    pub sections: Vec<usize>,
    /// Overhang correction, texture, metrics and the fit on the machine were redone.
    pub surface: bool,
    /// The wall's inner beads were rebuilt (SPEC §13; empty for a one-bead wall).
    pub beads: bool,
    /// The spiral toolpath was rebuilt.
    pub toolpath: bool,
    /// The printability verdict was redone (a new toolpath, or another clay body).
    pub verdict: bool,
    /// The view's mesh of the wall was rebuilt ([`Session::with_wall_view`]).
    pub wall_view: bool,
}

impl Update {
    /// True when nothing was recomputed.
    pub fn is_nothing(&self) -> bool {
        *self == Update::default()
    }
}

/// The stages after the shape: the texture's displacement table, the corrected surface, the base
/// fill, the beads, the toolpath, its verdict and the wall's mesh for a view.
#[derive(Debug, Clone, Default)]
struct LaterStages {
    /// The texture's displacements on the section grid (no shape input: kept while shaping).
    texture: Stage<TextureKey, Vec<Vec<f64>>>,
    surface: Stage<SurfaceKey, Arc<Surface>>,
    base: Stage<BaseKey, Vec<crate::base_fill::BaseFill>>,
    beads: Stage<BeadKey, Arc<crate::walls::InnerBeads>>,
    toolpath: Stage<ToolpathKey, Arc<Toolpath>>,
    /// Whether the wet wall stands while the toolpath is printed (`None` for a clay body that
    /// does not resolve: validation reports it).
    verdict: Stage<VerdictKey, Option<Arc<Printability>>>,
    /// The wall's mesh for a view (kept only by a session made [`Session::with_wall_view`]).
    view: Stage<WallViewKey, Arc<WallBuffers>>,
}

/// Inputs of the printability verdict: the toolpath (by revision; a new surface, whose droops
/// the verdict lists, makes a new toolpath), the clay body and the wall's thickness.
#[derive(Debug, Clone, PartialEq)]
pub struct VerdictKey {
    pub toolpath: u64,
    pub clay: Option<crate::clay::ClayTable>,
    pub walls: usize,
    pub line_width: f64,
}

/// Inputs of the view's mesh: the surface and the beads (by revision) and the overhang limit
/// its colours mark.
#[derive(Debug, Clone, PartialEq)]
pub struct WallViewKey {
    pub surface: u64,
    pub beads: u64,
    pub limit_deg: f64,
}

/// Inputs of a mesh: the file (and when it last changed, so an edited file is read again) and
/// how it is placed.
#[derive(Debug, Clone, PartialEq)]
pub struct MeshKey {
    pub path: PathBuf,
    pub stamp: Option<(std::time::SystemTime, u64)>,
    pub scale: f64,
    pub rotate_x: f64,
}

/// Inputs of a mesh's slices: the mesh (by revision) and the layer height.
#[derive(Debug, Clone, PartialEq)]
pub struct SliceKey {
    pub mesh: u64,
    pub layer_height: f64,
}

/// Inputs of the wall sections of a mesh: its slices (by revision), the samples, the inset and
/// the centre on the bed.
#[derive(Debug, Clone, PartialEq)]
pub struct MeshWallKey {
    pub slices: u64,
    pub samples: usize,
    pub line_width: f64,
    pub center: DVec2,
}

/// The incremental engine: the cached stages of one design being edited.
#[derive(Debug, Clone, Default)]
pub struct Session {
    contours: [Stage<ContourKey, SampledContour>; 2],
    plan: Stage<PlanKey, (ShapeModel, Vec<Finding>)>,
    sections: Vec<Stage<SectionKey, Arc<Section>>>,
    /// What cutting off each shaped section's folds did, beside `sections`.
    section_folds: Vec<crate::shape::Folds>,
    /// Bumped whenever any section is recomputed or the section count changes.
    sections_revision: u64,
    /// The stages after the shape, lofted or sliced: texture, surface, base, beads, toolpath,
    /// verdict, view mesh.
    later: LaterStages,
    /// A design from a mesh: the mesh read and placed, its slices, the wall sections from them.
    mesh: Stage<MeshKey, Arc<crate::stl::Mesh>>,
    slices: Stage<SliceKey, Arc<crate::mesh::MeshSlices>>,
    mesh_wall: Stage<MeshWallKey, Vec<Section>>,
    /// Whether the current design takes its shape from a mesh (the loft stages then say
    /// nothing: no contours, model or shaped sections).
    from_mesh: bool,
    /// The design and job of the last successful update.
    design: Option<Design>,
    job: Option<PrintJob>,
    /// The error of the last update, if it failed.
    error: Option<FieldError>,
    updates: u64,
    /// Whether the wall's mesh for a view is kept ([`Session::with_wall_view`]).
    wall_view: bool,
    /// Whether this session serves a single update ([`Session::for_one_update`]).
    one_update: bool,
    /// Whether the verdict stage is left to the caller ([`Session::for_one_unjudged_update`]).
    unjudged: bool,
}

impl Session {
    pub fn new() -> Session {
        Session::default()
    }

    /// Brings every stage up to date with `design`, recomputing only the stages whose inputs
    /// changed, and says what it recomputed. On an error (an invalid value, a vessel off the
    /// bed) the stages that did succeed keep their new outputs, [`Session::job`] keeps the last
    /// complete job, and [`Session::is_current`] is false until an update succeeds.
    pub fn update(&mut self, design: &Design) -> Result<Update, FieldError> {
        self.updates += 1;
        // The vessel is built at its wet size (SPEC §14: enlarged to fire to the designed size);
        // the session keeps the design as given (what the job is asked for by).
        let given = design;
        let wet = crate::clay::wet_design(design);
        let design = match &wet {
            Ok(d) => d.as_ref(),
            Err(_) => design,
        };
        let result = match &wet {
            Ok(_) => crate::parallel::awake(|| self.update_stages(design)),
            Err(e) => Err(e.clone()),
        };
        match &result {
            Ok(_) => {
                self.error = None;
                self.job = Some(PrintJob {
                    surface: self.later.surface.get().expect("updated").clone(),
                    beads: self.later.beads.get().expect("updated").clone(),
                    toolpath: self.later.toolpath.get().expect("updated").clone(),
                    verdict: self.later.verdict.get().expect("updated").clone(),
                });
                if self.design.as_ref() != Some(given)
                    || self.design.as_ref().map(|d| &d.base_dir) != Some(&given.base_dir)
                {
                    self.design = Some(given.clone());
                }
            }
            Err(e) => self.error = Some(e.clone()),
        }
        result
    }

    fn update_stages(&mut self, design: &Design) -> Result<Update, FieldError> {
        validate(design)?;
        let mut done = Update::default();
        let [cx, cy] = design.center();
        let center = DVec2::new(cx, cy);
        self.from_mesh = design.shape.mesh.is_some();
        if let Some(source) = &design.shape.mesh {
            self.update_mesh_stages(design, source, center, &mut done)?;
            return Ok(done);
        }

        // 1. Contours: the upper on a helper while this thread samples the lower (a quarter of
        // a millisecond each for the benchmark vase, with the helper otherwise idle).
        let specs = [&design.shape.lower, &design.shape.upper];
        let refresh = |role: usize, stage: &mut Stage<ContourKey, SampledContour>| {
            let key = ContourKey {
                spec: specs[role].clone(),
                center,
                samples: design.shape.samples,
                base_dir: design.base_dir.clone(),
            };
            let base = design.base_dir.as_deref();
            stage.refresh(key, || {
                let field = CONTOUR_FIELDS[role];
                sample_contour(specs[role], field, center, design.shape.samples, base)
            })
        };
        let [lower_stage, upper_stage] = &mut self.contours;
        let (upper_ran, lower_ran) =
            crate::parallel::both(true, || refresh(1, upper_stage), || refresh(0, lower_stage));
        // The lower contour's error first, as when they ran in turn.
        for (role, ran) in [lower_ran, upper_ran].into_iter().enumerate() {
            if ran? {
                done.contours.push(CONTOUR_FIELDS[role]);
            }
        }

        // 2. Loft and layer plan.
        let (lower, upper) = (&self.contours[0], &self.contours[1]);
        let key = PlanKey {
            contours: [lower.revision, upper.revision],
            center,
            height: design.shape.height,
            horizontal: design.control.horizontal.clone(),
            layer_height: design.printer.layer_height,
            min_layer_height: design.printer.min_layer_height,
            max_layer_height: design.printer.max_layer_height,
            nozzle_length: design.printer.nozzle_length,
            enforce: design.constraints.enforce,
        };
        done.plan = self.plan.refresh(key, || {
            let (Some(lo), Some(up)) = (lower.get(), upper.get()) else {
                unreachable!("the contour stages ran above")
            };
            let loft = LoftInput::from_samples(lo.samples.clone(), up.samples.clone(), center);
            // The vertical lines are the sections' inputs: the plan does not read them.
            let mut plan_only = design.clone();
            plan_only.control.vertical.clear();
            ShapeModel::new(&plan_only, loft)
        })?;
        let plan_revision = self.plan.revision;
        let Some((model, plan_findings)) = self.plan.value.as_mut() else {
            unreachable!("the plan stage ran above")
        };
        model.set_vertical(&design.control.vertical);
        let model = &*model;

        // 3. Sections, each keyed by the lines active at its height; the dirty ones in parallel.
        let count = model.layers + 1;
        if self.sections.len() != count {
            self.sections.resize_with(count, Stage::default);
            self.section_folds.resize(count, Default::default());
            self.sections_revision += 1;
        }
        let mut dirty = Vec::new();
        for (k, stage) in self.sections.iter_mut().enumerate() {
            let t = k as f64 / model.layers as f64;
            let lines: Vec<VerticalLine> = design
                .control
                .vertical
                .iter()
                .zip(model.vertical())
                .filter(|(_, profile)| profile.offset_at(t) != 0.0)
                .map(|(line, _)| line.clone())
                .collect();
            let key = SectionKey {
                plan: plan_revision,
                lines,
            };
            if stage.value.is_none() || stage.key.as_ref() != Some(&key) {
                stage.key = Some(key);
                stage.revision += 1;
                dirty.push(k);
            }
        }
        if !dirty.is_empty() {
            let shaped = shape_sections(model, &dirty);
            for (&k, (section, folds)) in dirty.iter().zip(shaped) {
                self.sections[k].value = Some(Arc::new(section));
                self.section_folds[k] = folds;
            }
            self.sections_revision += 1;
        }
        done.sections = dirty;

        let grid = crate::pipeline::SectionGrid {
            center: model.loft.center,
            layers: model.layers,
            layer_pitch: model.layer_pitch,
        };
        let (sections, one_update) = (&mut self.sections, self.one_update);
        let surface_inputs = (plan_revision, self.sections_revision);
        let mut findings = plan_findings.clone();
        findings.extend(crate::shape::fold_findings(&self.section_folds));
        finish_stages(
            &mut self.later,
            Kept {
                wall_view: self.wall_view,
                verdict: !self.unjudged,
            },
            design,
            &mut done,
            grid,
            surface_inputs,
            || {
                if one_update {
                    // Taken, not copied: no later update looks at them.
                    return sections
                        .iter_mut()
                        .map(|s| s.value.take().map(Arc::unwrap_or_clone).unwrap_or_default())
                        .collect();
                }
                // Copied on both cores: the surface stage corrects its own copy.
                crate::parallel::map_ranges(sections.len(), 64, |r| {
                    sections[r]
                        .iter()
                        .map(|s| s.value.as_deref().cloned().unwrap_or_default())
                        .collect()
                })
            },
            &findings,
        )?;
        Ok(done)
    }

    /// A session that also keeps the wall's mesh for a 3D view ([`crate::view_mesh`]), rebuilt
    /// with the surface, and each point's lean on the surface: what an interactive application
    /// shows (the command line does without).
    pub fn with_wall_view() -> Session {
        Session {
            wall_view: true,
            ..Session::default()
        }
    }

    /// A session for one update, the batch run of [`crate::run`]: the surface stage takes the
    /// shaped sections instead of copying them (5 MB and 2 ms on the benchmark vase), so an
    /// update after the first shapes every section again. Its jobs are a [`Session::new`]'s.
    pub fn for_one_update() -> Session {
        Session {
            one_update: true,
            ..Session::default()
        }
    }

    /// [`Session::for_one_update`] without the verdict stage: its job's `verdict` is `None`, for
    /// a caller that judges the job later, beside other work ([`crate::pipeline::run_unjudged`]).
    pub fn for_one_unjudged_update() -> Session {
        Session {
            unjudged: true,
            ..Session::for_one_update()
        }
    }

    /// The wall's mesh for a view as of the last successful update (a session made
    /// [`Session::with_wall_view`]; `None` otherwise).
    pub fn wall_view(&self) -> Option<&Arc<WallBuffers>> {
        self.later.view.get()
    }

    /// Whether the wet wall of the current toolpath stands while it is printed (SPEC §14), as of
    /// the last successful update; `None` before one, or for a clay body that does not resolve.
    pub fn printability(&self) -> Option<&Arc<Printability>> {
        self.later.verdict.get().and_then(Option::as_ref)
    }

    /// The current job (the last complete one if the last update failed).
    pub fn job(&self) -> Option<PrintJob> {
        self.job.clone()
    }

    /// The design the current job was computed from, as given to [`Session::update`] (a
    /// design printed enlarged to fire to its size is computed at its wet size, but this is
    /// the design as drawn).
    pub fn design(&self) -> Option<&Design> {
        self.design.as_ref()
    }

    /// True when the last update succeeded: the outputs are the current design's.
    pub fn is_current(&self) -> bool {
        self.error.is_none() && self.design.is_some()
    }

    /// The last update's error.
    pub fn error(&self) -> Option<&FieldError> {
        self.error.as_ref()
    }

    /// Updates so far.
    pub fn updates(&self) -> u64 {
        self.updates
    }

    /// The sampled contour `role` (0 lower, 1 upper; see [`CONTOUR_FIELDS`]); none for a design
    /// from a mesh.
    pub fn contour(&self, role: usize) -> Option<&SampledContour> {
        if self.from_mesh {
            return None;
        }
        self.contours.get(role)?.get()
    }

    /// The shape model (loft, control profiles, layer plan) of the current design; none for a
    /// design from a mesh.
    pub fn model(&self) -> Option<&ShapeModel> {
        if self.from_mesh {
            return None;
        }
        self.plan.get().map(|(m, _)| m)
    }

    /// Shaped section k (loft and control lines, or the mesh's slice, before correction and
    /// texture).
    pub fn shaped_section(&self, k: usize) -> Option<&Section> {
        if self.from_mesh {
            return self.mesh_wall.get()?.get(k);
        }
        self.sections.get(k)?.get().map(|s| &**s)
    }

    /// Vertical control line `l` drawn on the wall: the column at `angle_deg` of every shaped
    /// section, so each vertex is the point the printer lays there (a fold trimmed out of a
    /// section is trimmed out of the line too). Empty for a line the design does not have.
    pub fn vertical_line_curve(&self, l: usize, angle_deg: f64) -> Vec<DVec3> {
        let Some(model) = self.model() else {
            return Vec::new();
        };
        if l >= model.vertical().len() || model.loft.samples() == 0 {
            return Vec::new();
        }
        let i = model.column_at_angle(angle_deg.to_radians());
        (0..self.sections.len())
            .filter_map(|k| Some(self.shaped_section(k)?.points[i]))
            .collect()
    }

    /// [`Session::shaped_section`], shared: a lofted design's sections are kept behind an `Arc`,
    /// so that an application can hold them without copying their points on every edit (a
    /// mesh's wall sections are copied).
    pub fn shaped_section_shared(&self, k: usize) -> Option<Arc<Section>> {
        if self.from_mesh {
            return self.mesh_wall.get()?.get(k).cloned().map(Arc::new);
        }
        self.sections.get(k)?.get().cloned()
    }

    /// The corrected, textured surface.
    pub fn surface(&self) -> Option<&Arc<Surface>> {
        self.later.surface.get()
    }

    /// The wall's inner beads, `[j − 1][k]` bead `j`'s section `k` (empty for a one-bead wall).
    pub fn beads(&self) -> Option<&Arc<crate::walls::InnerBeads>> {
        self.later.beads.get()
    }

    /// The spiral toolpath.
    pub fn toolpath(&self) -> Option<&Arc<Toolpath>> {
        self.later.toolpath.get()
    }

    /// The stages of a design from a mesh: read and place the mesh, slice it at the layer
    /// heights, make the wall sections, then the stages every design shares.
    fn update_mesh_stages(
        &mut self,
        design: &Design,
        source: &crate::design::MeshSource,
        center: DVec2,
        done: &mut Update,
    ) -> Result<(), FieldError> {
        let path = crate::mesh::resolve(source, design.base_dir.as_deref());
        let stamp = std::fs::metadata(&path)
            .ok()
            .and_then(|m| Some((m.modified().ok()?, m.len())));
        let key = MeshKey {
            path: path.clone(),
            stamp,
            scale: source.scale,
            rotate_x: source.rotate_x,
        };
        done.plan |= self.mesh.refresh(key, || {
            crate::mesh::load_placed(&path, source).map(Arc::new)
        })?;
        let mesh = self.mesh.get().expect("the mesh stage ran above").clone();
        let key = SliceKey {
            mesh: self.mesh.revision,
            layer_height: design.printer.layer_height,
        };
        done.plan |= self.slices.refresh(key, || {
            crate::mesh::slices(&mesh, design.printer.layer_height, &path).map(Arc::new)
        })?;
        let slices = self
            .slices
            .get()
            .expect("the slice stage ran above")
            .clone();
        let p = &design.printer;
        let key = MeshWallKey {
            slices: self.slices.revision,
            samples: design.shape.samples,
            line_width: p.line_width,
            center,
        };
        if self.mesh_wall.refresh(key, || {
            Ok(crate::mesh::wall_sections(
                &slices.outlines,
                &slices.heights,
                design.shape.samples,
                p.line_width / 2.0,
            )
            .map_err(|e| crate::mesh::mesh_field_error(&path, e))?
            .into_iter()
            .map(|s| Section {
                points: s.points.iter().map(|q| *q + center.extend(0.0)).collect(),
            })
            .collect())
        })? {
            done.sections = (0..slices.heights.len()).collect();
        }
        let grid = crate::pipeline::SectionGrid {
            center,
            layers: slices.heights.len() - 1,
            layer_pitch: slices.pitch,
        };
        let wall = self.mesh_wall.get().expect("the wall stage ran above");
        finish_stages(
            &mut self.later,
            Kept {
                wall_view: self.wall_view,
                verdict: !self.unjudged,
            },
            design,
            done,
            grid,
            (self.slices.revision, self.mesh_wall.revision),
            || wall.clone(),
            &[],
        )
    }
}

/// The stages every design shares once its shaped sections are known: the texture's
/// displacements, the corrected surface (its key holds the revisions `inputs` of what the
/// sections came from), the base fill, the beads, the toolpath, and as `kept` says its verdict
/// and the wall's mesh for a view.
#[allow(clippy::too_many_arguments)]
fn finish_stages(
    later: &mut LaterStages,
    Kept { wall_view, verdict }: Kept,
    design: &Design,
    done: &mut Update,
    grid: crate::pipeline::SectionGrid,
    inputs: (u64, u64),
    shaped: impl FnOnce() -> Vec<Section>,
    plan_findings: &[Finding],
) -> Result<(), FieldError> {
    let count = grid.layers + 1;
    // 4. Surface (with the texture's displacements, kept while only the shape changes).
    let samples = design.shape.samples;
    if let Some(tex) = &design.texture {
        let key = TextureKey {
            texture: tex.clone(),
            samples,
            sections: count,
        };
        later.texture.refresh(key, || {
            Ok(crate::texture::displacements(tex, samples, count))
        })?;
    }
    let p = &design.printer;
    let key = SurfaceKey {
        plan: inputs.0,
        sections: inputs.1,
        texture: design.texture.clone(),
        enforce: design.constraints.enforce,
        max_overhang_deg: p.max_overhang_deg,
        line_width: p.line_width,
        bed: (p.bed_shape, p.bed_x, p.bed_y, p.origin),
        max_z: p.max_z,
        center_given: design.shape.center.is_some(),
        beads: design.shape.walls.max(1),
    };
    let disp = design
        .texture
        .as_ref()
        .and(later.texture.get())
        .map(Vec::as_slice);
    done.surface = later.surface.refresh(key, || {
        finish_sections(
            design,
            grid,
            shaped(),
            plan_findings.to_vec(),
            disp,
            wall_view,
        )
        .map(Arc::new)
    })?;

    // 5.–6. Base fill, beads and toolpath.
    let surface = later
        .surface
        .get()
        .cloned()
        .expect("the surface stage ran above");
    let key = BeadKey {
        surface: later.surface.revision,
        walls: design.shape.walls,
        line_width: p.line_width,
        ties_from: crate::toolpath::ties_from(design, &surface),
        tan_limit: crate::pipeline::overhang_tan_limit(design),
        enforce: design.constraints.enforce,
    };
    done.beads = later.beads.refresh(key, || {
        crate::toolpath::inner_beads(design, &surface).map(Arc::new)
    })?;
    let beads = Arc::clone(later.beads.get().expect("the bead stage ran above"));

    // 8. The wall's mesh for a view (after the beads: a wall of several shows its inner bead)
    // needs neither the base nor the toolpath, which use one core once the base fill's rings
    // are made: it is built on a second core from then on (or beside the toolpath when the
    // base is kept).
    let view_key = wall_view.then_some(WallViewKey {
        surface: later.surface.revision,
        beads: later.beads.revision,
        limit_deg: p.max_overhang_deg,
    });
    let points: usize = surface.sections.iter().map(|s| s.points.len()).sum();
    let view_beside = crate::parallel::cores() > 1
        && points >= crate::parallel::PARALLEL_POINTS
        && view_key.as_ref().is_some_and(|k| !later.view.is_current(k));
    let mut build_view = Some({
        let (surface, beads, limit) =
            (Arc::clone(&surface), Arc::clone(&beads), p.max_overhang_deg);
        move || crate::view_mesh::wall_buffers(&surface, beads.last().map(Vec::as_slice), limit)
    });
    let mut view_started = None;

    // The base fill is kept while the feet are the same (an edit higher up the wall).
    let key = BaseKey {
        feet: crate::toolpath::base_feet(design, &surface),
        line_width: p.line_width,
        walls: design.shape.walls,
        wall: (surface.layers, surface.sections[0].points.len()),
    };
    later.base.refresh(key, || {
        crate::toolpath::base_fills_then(design, &surface, || {
            if view_beside && let Some(build) = build_view.take() {
                view_started = Some(crate::parallel::beside(build));
            }
        })
    })?;
    let key = ToolpathKey {
        surface: later.surface.revision,
        base: later.base.revision,
        beads: later.beads.revision,
        base_layers: design.shape.base_layers,
        line_width: p.line_width,
        min_layer_height: p.min_layer_height,
        max_layer_height: p.max_layer_height,
        min_layer_time: p.min_layer_time,
        print_speed: p.print_speed,
        flow_ramp: (p.flow_ramp_start, p.flow_ramp_end),
    };
    let fills = later.base.get().expect("the base stage ran above");
    let toolpath = &mut later.toolpath;
    let make_toolpath = || {
        toolpath.refresh(key, || {
            build_toolpath_on(design, &surface, fills, &beads).map(Arc::new)
        })
    };
    let view = &mut later.view;
    let (view, toolpath) = match view_started {
        Some(started) => {
            let toolpath = make_toolpath();
            let buffers = started.join();
            let view = view_key.map(|key| view.refresh(key, || Ok(Arc::new(buffers))));
            (view, toolpath)
        }
        None => crate::parallel::both(
            view_beside,
            || {
                let build = build_view.expect("the view was not started");
                view_key.map(|key| view.refresh(key, || Ok(Arc::new(build()))))
            },
            make_toolpath,
        ),
    };
    done.toolpath = toolpath?;
    done.wall_view = view.transpose()?.unwrap_or(false);

    // 7. Whether the wet wall stands while it is printed.
    let toolpath = later.toolpath.get().expect("the toolpath stage ran above");
    let verdict_key = VerdictKey {
        toolpath: later.toolpath.revision,
        clay: design.clay.clone(),
        walls: design.shape.walls,
        line_width: p.line_width,
    };
    done.verdict = later.verdict.refresh(verdict_key, || {
        Ok(verdict
            .then(|| crate::pipeline::verdict(design, &surface, toolpath))
            .flatten())
    })?;
    Ok(())
}

/// The stages after the toolpath that a session keeps: the wall's mesh for a view
/// ([`Session::with_wall_view`]) and the verdict (all but [`Session::for_one_unjudged_update`]).
#[derive(Clone, Copy)]
struct Kept {
    wall_view: bool,
    verdict: bool,
}

/// Shapes the sections `ks` of `model`, shared out over the machine's cores in runs of
/// [`SHAPE_RUN`] when there is enough work (a section whose folds are cut off costs several
/// times one without).
fn shape_sections(model: &ShapeModel, ks: &[usize]) -> Vec<(Section, crate::shape::Folds)> {
    let per_section = model.loft.samples().max(1);
    crate::parallel::map_runs(
        ks.len(),
        crate::parallel::PARALLEL_POINTS / per_section,
        SHAPE_RUN,
        |r| ks[r].iter().map(|&k| model.section_with_folds(k)).collect(),
    )
}

/// Sections a core shapes at a time ([`shape_sections`]).
const SHAPE_RUN: usize = 8;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::design::{ContourSpec, VerticalLine};
    use crate::load::parse_design;
    use proptest::prelude::*;

    /// A small design with every kind of input: two contours, a global and a local vertical
    /// line, a horizontal line, a texture and a base.
    fn design() -> Design {
        parse_design(
            r#"
version = 1
[shape]
height = 30.0
samples = 48
base_layers = 2
lower = { type = "circle", radius = 25.0 }
upper = { type = "ellipse", rx = 30.0, ry = 22.0 }
[[control.vertical]]
points = [[0.0, 0.0], [0.5, 3.0], [1.0, 0.0]]
[[control.vertical]]
points = [[0.0, 0.0], [0.3, 0.0], [0.5, 4.0], [0.7, 0.0], [1.0, 0.0]]
angle = 90.0
width = 60.0
[[control.horizontal]]
at = 1.0
reach = 0.3
points = [[0.0, 1.0], [180.0, -1.0]]
[texture]
x = { wave = "sine", period = 10.0, amplitude = 0.8 }
"#,
        )
        .unwrap()
    }

    /// The edits a user makes, one per case; some make the design invalid or unprintable.
    fn edit(d: &mut Design, which: u8, amount: f64) {
        let a = amount; // in [0, 1)
        match which % 25 {
            0 => {
                d.shape.lower = ContourSpec::Circle {
                    radius: 20.0 + 10.0 * a,
                }
            }
            1 => {
                d.shape.upper = ContourSpec::Star {
                    points: 5,
                    outer_radius: 30.0,
                    inner_radius: 20.0 + 5.0 * a,
                }
            }
            2 => d.shape.samples = 24 + (a * 48.0) as usize,
            3 => d.shape.height = 20.0 + 20.0 * a,
            4 => {
                if let Some(v) = d.control.vertical.last_mut() {
                    let mid = v.points.len() / 2;
                    v.points[mid][1] = 6.0 * a - 1.0;
                }
            }
            5 => d.control.vertical.push(VerticalLine {
                points: vec![[0.0, 0.0], [0.1 + 0.5 * a, 2.0], [0.9, 0.0], [1.0, 0.0]],
                angle: Some(360.0 * a),
                width: Some(40.0),
            }),
            6 => {
                if !d.control.vertical.is_empty() {
                    d.control.vertical.remove(0);
                }
            }
            7 => {
                if let Some(h) = d.control.horizontal.first_mut() {
                    h.points[0][1] = 3.0 * a;
                } else {
                    d.control.horizontal = design().control.horizontal;
                }
            }
            8 => {
                if let Some(t) = &mut d.texture
                    && let Some(x) = &mut t.x
                {
                    x.amplitude = 2.0 * a;
                }
            }
            9 => d.texture = if a < 0.5 { None } else { design().texture },
            10 => d.printer.print_speed = 10.0 + 20.0 * a,
            11 => d.printer.max_overhang_deg = 30.0 + 20.0 * a,
            12 => d.constraints.enforce = a < 0.5,
            13 => d.shape.base_layers = (a * 4.0) as usize,
            14 => d.printer.line_width = 2.0 + 3.0 * a,
            15 => d.printer.layer_height = 0.8 + 0.8 * a,
            16 => d.printer.min_layer_time = 20.0 * a,
            // A bed too small for the vessel (an error from the surface stage), then back.
            17 => d.printer.bed_x = if a < 0.5 { 40.0 } else { 180.0 },
            // An invalid value (an error from validation).
            18 => d.printer.line_width = if a < 0.5 { -1.0 } else { 3.5 },
            19 => d.shape.center = Some([80.0 + 20.0 * a, 95.0]),
            20 => d.printer.nozzle_length = 5.0 + 30.0 * a,
            21 => d.shape.walls = 1 + (a * 3.0) as usize,
            22 => d.shape.wall_ties = a < 0.5 && d.shape.walls > 1,
            // The clay stiffening faster or slower: only the verdict.
            23 => {
                d.clay = Some(crate::clay::ClayTable {
                    structuration_rate: Some(0.05 + 2.0 * a),
                    ..Default::default()
                })
            }
            _ => d.printer.max_layer_height = 1.2 + a,
        }
    }

    fn assert_same_as_batch(session: &Session, d: &Design, result: &Result<Update, FieldError>) {
        // A fresh session with a view (the surface keeps each point's lean), and the command
        // line's batch run (a session for one update, which takes the shaped sections).
        let batch = {
            let mut fresh = Session::with_wall_view();
            fresh.update(d).map(|_| fresh.job().unwrap())
        };
        let once = crate::run(d);
        // `clayloft gcode`'s run, judged once its program is written.
        let unjudged = crate::pipeline::run_unjudged(d);
        match (result, batch) {
            (Ok(_), Ok(b)) => {
                let job = session.job().unwrap();
                assert_eq!(*job.surface, *b.surface, "surface differs from a batch run");
                let once = once.expect("the batch run fails where a fresh session does not");
                let unjudged = unjudged.expect("the unjudged run fails where a fresh one does not");
                assert!(unjudged.verdict.is_none());
                assert_eq!(*unjudged.toolpath, *once.toolpath);
                assert_eq!(
                    crate::pipeline::judge(d, &unjudged),
                    once.verdict,
                    "the verdict judged after the run differs"
                );
                assert!(once.surface.point_leans_deg.is_empty());
                assert_eq!(
                    *once.surface,
                    Surface {
                        point_leans_deg: Vec::new(),
                        ..(*b.surface).clone()
                    },
                    "the batch run's surface differs"
                );
                assert_eq!(
                    *once.toolpath, *b.toolpath,
                    "the batch run's toolpath differs"
                );
                assert_eq!(
                    *job.toolpath, *b.toolpath,
                    "toolpath differs from a batch run"
                );
                // The session works on the wet design (SPEC §14).
                let wet = crate::clay::wet_design(d).unwrap();
                assert_eq!(
                    session.printability().map(|p| &**p),
                    crate::printability::assess(&wet, &b.surface, &b.toolpath)
                        .ok()
                        .as_ref(),
                    "verdict differs from a batch run"
                );
                let mesh = crate::view_mesh::wall_buffers(
                    &b.surface,
                    b.beads.last().map(Vec::as_slice),
                    wet.printer.max_overhang_deg,
                );
                assert_eq!(
                    session.wall_view().map(|m| &**m),
                    Some(&mesh),
                    "view mesh differs from a batch run"
                );
                assert!(session.is_current());
            }
            (Err(e), Err(b)) => {
                assert_eq!(e.to_string(), b.to_string());
                assert_eq!(once.map(|_| ()).unwrap_err().to_string(), b.to_string());
                assert_eq!(unjudged.map(|_| ()).unwrap_err().to_string(), b.to_string());
                assert!(!session.is_current());
            }
            (a, b) => panic!("incremental {a:?} but batch {:?}", b.map(|_| ())),
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]
        /// Incremental equals batch: after every edit of a random sequence, the session's job,
        /// verdict and view mesh are exactly (bit for bit) what a fresh run computes, and both
        /// fail alike.
        #[test]
        fn incremental_updates_equal_a_batch_run(
            edits in proptest::collection::vec((0u8..25, 0.0f64..1.0), 1..12)
        ) {
            let mut d = design();
            let mut session = Session::with_wall_view();
            let first = session.update(&d);
            assert_same_as_batch(&session, &d, &first);
            for (which, amount) in edits {
                edit(&mut d, which, amount);
                let r = session.update(&d);
                assert_same_as_batch(&session, &d, &r);
            }
        }
    }

    /// A design printed enlarged to fire to its size: the job is of the wet design, and the
    /// session says it is the design as given (what the app asks the job for by).
    #[test]
    fn the_session_keeps_the_design_as_given() {
        let mut d = design();
        d.clay = Some(crate::clay::ClayTable {
            compensate_shrinkage: true,
            ..Default::default()
        });
        let wet = crate::clay::wet_design(&d).unwrap().into_owned();
        assert_ne!(wet, d);
        let mut s = Session::new();
        s.update(&d).unwrap();
        assert_eq!(s.design(), Some(&d));
        assert_eq!(
            *s.job().unwrap().toolpath,
            *crate::run(&d).unwrap().toolpath
        );
    }

    #[test]
    fn each_edit_recomputes_only_its_stages() {
        let d = design();
        let mut s = Session::new();
        let first = s.update(&d).unwrap();
        assert_eq!(first.contours, CONTOUR_FIELDS.to_vec());
        assert!(first.plan && first.surface && first.toolpath);
        let layers = s.model().unwrap().layers;
        assert_eq!(first.sections, (0..=layers).collect::<Vec<_>>());
        // No change: nothing.
        assert!(s.update(&d).unwrap().is_nothing());
        // A local line's point: only the sections in its span (0.3 … 0.7), then the rest.
        let mut e = d.clone();
        e.control.vertical[1].points[2][1] = 5.0;
        let u = s.update(&e).unwrap();
        assert!(u.contours.is_empty() && !u.plan && u.surface && u.toolpath);
        let (lo, hi) = (u.sections[0], *u.sections.last().unwrap());
        assert!(
            lo as f64 >= 0.3 * layers as f64 - 1.0 && hi as f64 <= 0.7 * layers as f64 + 1.0,
            "{:?} of {layers}",
            u.sections
        );
        // The overhang limit: correction again, but no replanning and no section.
        e.printer.max_overhang_deg = 40.0;
        let u = s.update(&e).unwrap();
        assert!(!u.plan && u.sections.is_empty() && u.surface && u.toolpath);
        // The speed: only the toolpath and its verdict.
        e.printer.print_speed = 25.0;
        let u = s.update(&e).unwrap();
        assert_eq!(
            u,
            Update {
                toolpath: true,
                verdict: true,
                ..Update::default()
            }
        );
        // The clay stiffening faster: only the verdict.
        e.clay = Some(crate::clay::ClayTable {
            structuration_rate: Some(1.5),
            ..Default::default()
        });
        let u = s.update(&e).unwrap();
        assert_eq!(
            u,
            Update {
                verdict: true,
                ..Update::default()
            }
        );
        // Two beads: the surface (it starts at the beads' seam, see `seam`), the beads and the
        // toolpath; a third bead, the same (the seam is found for the beads' number: each turn
        // rises a third of a layer, not a half).
        e.shape.walls = 2;
        let u = s.update(&e).unwrap();
        assert_eq!(
            u,
            Update {
                surface: true,
                beads: true,
                toolpath: true,
                verdict: true,
                ..Update::default()
            }
        );
        assert_eq!(s.beads().unwrap().len(), 1);
        e.shape.walls = 3;
        let u = s.update(&e).unwrap();
        assert_eq!(
            u,
            Update {
                surface: true,
                beads: true,
                toolpath: true,
                verdict: true,
                ..Update::default()
            }
        );
        assert_eq!(s.beads().unwrap().len(), 2);
        e.shape.walls = 1;
        s.update(&e).unwrap();
        assert!(s.beads().unwrap().is_empty());
        // The G-code-only settings: nothing at all.
        e.printer.flow_multiplier = 1.1;
        e.printer.thumbnail = false;
        e.name = "renamed".into();
        assert!(s.update(&e).unwrap().is_nothing());
        // The upper contour: that contour, the plan and every section.
        e.shape.upper = ContourSpec::Circle { radius: 28.0 };
        let u = s.update(&e).unwrap();
        assert_eq!(u.contours, vec!["shape.upper"]);
        assert!(u.plan && u.sections.len() == s.model().unwrap().layers + 1);
        // A session without a view keeps no mesh.
        assert!(!u.wall_view && s.wall_view().is_none());
    }

    #[test]
    fn the_view_mesh_follows_the_surface_the_beads_and_the_limit() {
        let d = design();
        let mut s = Session::with_wall_view();
        assert!(s.update(&d).unwrap().wall_view);
        let first = s.wall_view().unwrap().clone();
        // The speed: a new toolpath, the same mesh (shared, not rebuilt).
        let mut e = d.clone();
        e.printer.print_speed = 25.0;
        assert!(!s.update(&e).unwrap().wall_view);
        assert!(Arc::ptr_eq(&first, s.wall_view().unwrap()));
        // The limit the colours mark: a new mesh (and a corrected surface).
        e.printer.max_overhang_deg = 40.0;
        assert!(s.update(&e).unwrap().wall_view);
        // A second bead: the mesh shows its inner sheet (the surface is made again, started at
        // the beads' seam); a third, the same (the seam is found for the beads' number).
        e.shape.walls = 2;
        let u = s.update(&e).unwrap();
        assert!(u.wall_view && u.surface);
        let two = s.wall_view().unwrap().positions.len();
        assert!(two > first.positions.len());
        e.shape.walls = 3;
        let u = s.update(&e).unwrap();
        assert!(u.wall_view && u.surface);
        assert_eq!(s.wall_view().unwrap().positions.len(), two);
    }

    #[test]
    fn a_failed_update_keeps_the_last_job_and_recovers() {
        let mut d = design();
        d.shape.center = Some([90.0, 95.0]);
        let mut s = Session::new();
        s.update(&d).unwrap();
        let good = s.job().unwrap();
        // A bed too narrow: the fit on the machine (the surface stage) fails.
        let mut e = d.clone();
        e.printer.bed_x = 100.0;
        let err = s.update(&e).unwrap_err();
        assert!(err.to_string().contains("printer.bed_x"), "{err}");
        assert!(!s.is_current());
        assert_eq!(s.error().map(|e| e.to_string()), Some(err.to_string()));
        assert_eq!(*s.job().unwrap().toolpath, *good.toolpath);
        assert_eq!(s.design(), Some(&d));
        // Back to the good design: the surface is recomputed (it failed), nothing before it.
        let u = s.update(&d).unwrap();
        assert!(u.contours.is_empty() && !u.plan && u.sections.is_empty() && u.surface);
        assert!(s.is_current());
    }

    /// A vertical line's curve is its column of the shaped sections, exactly; on the shipped
    /// petal vase (the app's first design), whose belly is pushed past the rose's cusps, those
    /// sections have no fold left: no segment runs against its loft section's.
    #[test]
    fn a_vertical_line_is_drawn_on_its_column_of_the_folded_out_sections() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../assets/designs/petal-vase.toml");
        let d = crate::load::load_design(&path).unwrap().design;
        let mut s = Session::new();
        s.update(&d).unwrap();
        let model = s.model().unwrap().clone();
        let angle = d.control.vertical[0].angle.unwrap_or(0.0);
        let curve = s.vertical_line_curve(0, angle);
        let i = model.column_at_angle(angle.to_radians());
        assert_eq!(curve.len(), model.layers + 1);
        let mut trimmed = 0;
        for (k, p) in curve.iter().enumerate() {
            let section = s.shaped_section(k).unwrap();
            assert_eq!(*p, section.points[i]);
            let t = k as f64 / model.layers as f64;
            let loft: Vec<DVec2> = (0..model.loft.samples())
                .map(|j| model.loft.point(j, t))
                .collect();
            let n = loft.len();
            for j in 0..n {
                let wall = section.points[(j + 1) % n].truncate() - section.points[j].truncate();
                let along = loft[(j + 1) % n] - loft[j];
                assert!(
                    wall.dot(along) >= 0.0,
                    "section {k} segment {j} runs backwards"
                );
                // A fold's columns spread over the short corner that cuts its tail off.
                trimmed += usize::from(wall.length() < 0.1 * along.length());
            }
        }
        assert!(trimmed > 100, "only {trimmed} columns on a fold's corner");
        assert!(s.vertical_line_curve(1, angle).is_empty());
        // Said among the corrections: one run of folded sections, every column moved counted.
        let job = s.job().unwrap();
        let folds: Vec<_> = job
            .surface
            .findings
            .iter()
            .filter(|f| f.kind == crate::report::FindingKind::Folds)
            .collect();
        assert_eq!(folds.len(), 1, "{folds:?}");
        assert!(
            folds[0].corrected && folds[0].points >= trimmed,
            "{:?}",
            folds[0]
        );
        assert!(
            folds[0].amount_mm > 0.1 && folds[0].amount_mm < 10.0,
            "{:?}",
            folds[0]
        );
        // Without the belly, no fold and nothing said.
        let mut plain = d.clone();
        plain.control.vertical.clear();
        s.update(&plain).unwrap();
        let job = s.job().unwrap();
        assert!(
            !job.surface
                .findings
                .iter()
                .any(|f| f.kind == crate::report::FindingKind::Folds)
        );
    }

    /// The two contours are sampled at once: where both are broken the lower one's error is
    /// reported (as when they were sampled in turn), and where only the upper one is, the lower
    /// one is kept and not sampled again when the upper one is mended.
    #[test]
    fn a_broken_contour_is_named_lower_first_and_the_other_is_kept() {
        let missing = |name: &str| ContourSpec::Image {
            path: format!("/nonexistent/clayloft/{name}.png"),
            size: 60.0,
            threshold: None,
        };
        let good = design();
        let mut both_broken = good.clone();
        both_broken.shape.lower = missing("lower");
        both_broken.shape.upper = missing("upper");
        let mut session = Session::new();
        let e = session.update(&both_broken).unwrap_err();
        assert_eq!(e.field, "shape.lower", "{e:?}");
        assert!(e.message.contains("lower.png"), "{e:?}");

        let mut upper_broken = good.clone();
        upper_broken.shape.upper = missing("upper");
        let mut session = Session::new();
        let e = session.update(&upper_broken).unwrap_err();
        assert_eq!(e.field, "shape.upper", "{e:?}");
        let mended = session.update(&good).unwrap();
        assert_eq!(mended.contours, ["shape.upper"]);
        let mut fresh = Session::new();
        fresh.update(&good).unwrap();
        assert_eq!(
            session.job().unwrap().toolpath.points,
            fresh.job().unwrap().toolpath.points
        );
    }
}
