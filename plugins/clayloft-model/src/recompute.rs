//! The recompute systems: the core's incremental engine ([`Session`]) brought up to date with
//! the edited design, and its outputs copied into the derived entities. What an edit
//! invalidates is the session's business; nothing here decides it.

use std::sync::Arc;

use bevy::math::DVec3;
use bevy::prelude::*;
use clayloft_core::Session;
use clayloft_core::session::Update;

use crate::components::*;
use crate::document::{DesignDoc, ModelStatus};

/// The core's incremental engine for the design being edited (keeping the wall's mesh for the
/// view too).
#[derive(Resource, Debug)]
pub struct Engine(pub Session);

impl Default for Engine {
    fn default() -> Self {
        Engine(Session::with_wall_view())
    }
}

impl Engine {
    /// The session's job for exactly this design (what exports and the printer use: nothing is
    /// recomputed), or why there is none in a sentence.
    pub fn current_job(
        &self,
        design: &clayloft_core::Design,
    ) -> Result<clayloft_core::PrintJob, String> {
        let session = &self.0;
        if let Some(e) = session.error() {
            return Err(format!("the design has an error: {e}"));
        }
        match (session.design(), session.job()) {
            (Some(d), Some(job)) if d == design => Ok(job),
            _ => Err("the design is still being computed".into()),
        }
    }
}

/// What the last recompute did, for tests, benchmarks and the status line.
#[derive(Resource, Debug, Clone, Default, PartialEq)]
pub struct RecomputeLog {
    /// Successful recompute passes so far (a pass that recomputed something).
    pub passes: u64,
    /// Contours resampled in the last pass.
    pub resampled: Vec<ContourRole>,
    /// Sections reshaped in the last pass, ascending.
    pub sections: Vec<usize>,
    /// The session's account of the last pass.
    pub update: Update,
}

/// Spawns the two contour entities, the vessel and the toolpath entity.
pub fn spawn_model_entities(mut commands: Commands) {
    for role in ContourRole::BOTH {
        commands.spawn((role, ContourSamples::default(), Name::new(role.field())));
    }
    commands.spawn((Vessel, Name::new("vessel")));
    commands.spawn((ToolpathMarker, Name::new("toolpath")));
}

/// Marker of the toolpath entity.
#[derive(Component, Debug, Clone, Copy, Default)]
pub struct ToolpathMarker;

/// Updates the session when the design changed (change detection on [`DesignDoc`]; never runs
/// otherwise) and copies what it recomputed into the entities.
#[allow(clippy::too_many_arguments)]
pub fn recompute_model(
    mut commands: Commands,
    doc: Option<Res<DesignDoc>>,
    mut engine: ResMut<Engine>,
    mut status: ResMut<ModelStatus>,
    mut log: ResMut<RecomputeLog>,
    mut contours: Query<(&ContourRole, &mut ContourSamples)>,
    mut sections: Query<(Entity, &SectionIndex, &mut ShapedSection)>,
    vessel: Single<Entity, With<Vessel>>,
    toolpath: Single<Entity, With<ToolpathMarker>>,
) {
    let Some(doc) = doc else { return };
    if !doc.is_changed() {
        return;
    }
    let update = match engine.0.update(&doc.design) {
        Ok(u) => u,
        Err(e) => {
            let mut errors = vec![e];
            for other in clayloft_core::validate::validate_all(&doc.design) {
                if !errors.contains(&other) {
                    errors.push(other);
                }
            }
            status.set_if_neq(ModelStatus { errors });
            return;
        }
    };
    if status.is_stale() {
        status.errors.clear();
    }
    if update.is_nothing() {
        return;
    }
    let session = &engine.0;
    // Contours.
    let resampled: Vec<ContourRole> = ContourRole::BOTH
        .into_iter()
        .filter(|r| update.contours.contains(&r.field()))
        .collect();
    for (role, mut samples) in &mut contours {
        if resampled.contains(role)
            && let Some(c) = session.contour(role.index())
        {
            *samples = ContourSamples {
                samples: c.samples.clone(),
                offset: c.offset,
            };
        }
    }
    // Sections: one entity per section, the reshaped ones copied.
    let count = session.model().map_or(0, |m| m.layers + 1);
    let mut present = vec![false; count];
    for (entity, index, mut section) in &mut sections {
        let k = index.0;
        if k >= count {
            commands.entity(entity).despawn();
            continue;
        }
        present[k] = true;
        if update.sections.binary_search(&k).is_ok()
            && let Some(s) = session.shaped_section_shared(k)
        {
            section.0 = s;
        }
    }
    for (k, _) in present.iter().enumerate().filter(|(_, p)| !**p) {
        if let Some(s) = session.shaped_section_shared(k) {
            commands.spawn((SectionIndex(k), ShapedSection(s)));
        }
    }
    // The corrected surface and the toolpath, shared with the session.
    if update.surface
        && let Some(surface) = session.surface()
    {
        commands
            .entity(*vessel)
            .insert(VesselSurface(Arc::clone(surface)));
    }
    if update.wall_view
        && let Some(mesh) = session.wall_view()
    {
        commands
            .entity(*vessel)
            .insert(VesselMesh(Arc::clone(mesh)));
    }
    if update.beads
        && let Some(beads) = session.beads()
    {
        commands
            .entity(*vessel)
            .insert(VesselBeads(Arc::clone(beads)));
    }
    if update.toolpath
        && let Some(path) = session.toolpath()
    {
        commands
            .entity(*toolpath)
            .insert(ToolpathPath(Arc::clone(path)));
    }
    if update.verdict {
        let mut e = commands.entity(*toolpath);
        match session.printability() {
            Some(p) => {
                e.insert(ToolpathPrintability(Arc::clone(p)));
            }
            None => {
                e.remove::<ToolpathPrintability>();
            }
        }
    }
    log.passes += 1;
    log.resampled = resampled;
    log.sections = update.sections.clone();
    log.update = update;
}

/// Keeps one entity per control line with its curve on the wall, from the core's shape model.
pub fn derive_control_lines(
    mut commands: Commands,
    engine: Res<Engine>,
    mut lines: Query<(Entity, &ControlLine, &mut ControlLineCurve)>,
) {
    if !engine.is_changed() {
        return;
    }
    let (Some(design), Some(model)) = (engine.0.design(), engine.0.model()) else {
        return;
    };
    let curve = |line: ControlLine| -> Vec<DVec3> {
        match line.kind {
            LineKind::Vertical => {
                design
                    .control
                    .vertical
                    .get(line.index)
                    .map_or_else(Vec::new, |v| {
                        engine
                            .0
                            .vertical_line_curve(line.index, v.angle.unwrap_or(0.0))
                    })
            }
            LineKind::Horizontal => design
                .control
                .horizontal
                .get(line.index)
                .map_or_else(Vec::new, |h| model.horizontal_line_curve(h.at)),
        }
    };
    let wanted: Vec<ControlLine> = (0..design.control.vertical.len())
        .map(|index| ControlLine {
            kind: LineKind::Vertical,
            index,
        })
        .chain(
            (0..design.control.horizontal.len()).map(|index| ControlLine {
                kind: LineKind::Horizontal,
                index,
            }),
        )
        .collect();
    let mut seen = Vec::new();
    for (entity, line, mut drawn) in &mut lines {
        if wanted.contains(line) {
            drawn.0 = curve(*line);
            seen.push(*line);
        } else {
            commands.entity(entity).despawn();
        }
    }
    for line in wanted.into_iter().filter(|l| !seen.contains(l)) {
        commands.spawn((line, ControlLineCurve(curve(line))));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The job is the document's whatever the session builds it at: a design that is printed
    /// enlarged to fire to its size (the session works on the enlarged, wet design) is exported
    /// and printed from its own job, and an edit makes it not current until it is recomputed.
    #[test]
    fn the_current_job_is_the_documents_even_when_printed_enlarged() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../assets/designs/porcelain-beaker.toml");
        let design = clayloft_core::load_design(&path).unwrap().design;
        assert!(design.clay.as_ref().is_some_and(|c| c.compensate_shrinkage));
        let mut engine = Engine::default();
        engine.0.update(&design).unwrap();
        let job = engine
            .current_job(&design)
            .expect("the job of the design just computed");
        assert_eq!(
            job.toolpath.points,
            clayloft_core::run(&design).unwrap().toolpath.points
        );
        let mut edited = design.clone();
        edited.shape.height += 5.0;
        assert!(engine.current_job(&edited).is_err());
    }
}
