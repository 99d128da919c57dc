//! The recompute systems: from the edited design to the derived entities, doing only the work
//! [`plan_recompute`] says an edit needs.

use std::collections::BTreeSet;
use std::sync::Arc;

use bevy::math::{DVec2, DVec3};
use bevy::prelude::*;
use clayloft_core::Design;
use clayloft_core::loft::{LoftInput, sample_contour};
use clayloft_core::pipeline::finish_surface;
use clayloft_core::report::Finding;
use clayloft_core::section::Section;
use clayloft_core::shape::ShapeModel;
use clayloft_core::toolpath::build_toolpath;
use clayloft_core::validate::validate;

use crate::components::*;
use crate::document::{DesignDoc, ModelStatus};
use crate::plan::{Recompute, plan_recompute};

/// What the last successful recompute was computed from.
#[derive(Resource, Debug, Clone, Default)]
pub struct ModelCache {
    /// The design the derived entities show.
    pub design: Option<Design>,
    /// Its shape model (loft, control profiles, layer plan).
    pub model: Option<ShapeModel>,
    /// The layer plan's findings.
    pub plan_findings: Vec<Finding>,
}

/// What the last recompute did, for tests, benchmarks and the status line.
#[derive(Resource, Debug, Clone, Default, PartialEq)]
pub struct RecomputeLog {
    /// Recompute passes so far.
    pub passes: u64,
    /// Contours resampled in the last pass.
    pub resampled: Vec<ContourRole>,
    /// Sections reshaped in the last pass, ascending.
    pub sections: Vec<usize>,
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

/// Recomputes the derived entities when the design changed (change detection on
/// [`DesignDoc`]); never runs otherwise.
pub fn recompute_model(
    mut commands: Commands,
    doc: Option<Res<DesignDoc>>,
    mut cache: ResMut<ModelCache>,
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
    let design = &doc.design;
    if let Err(e) = validate(design) {
        status.error = Some(e.to_string());
        return;
    }
    let plan = plan_recompute(cache.design.as_ref(), design, cache.model.as_ref());
    if plan == Recompute::Nothing {
        status.error = None;
        return;
    }
    // Stage 1: contours.
    let resample: Vec<ContourRole> = match &plan {
        Recompute::Everything => ContourRole::BOTH.to_vec(),
        Recompute::Contours(roles) => roles.clone(),
        _ => Vec::new(),
    };
    let [cx, cy] = design.center();
    let center = DVec2::new(cx, cy);
    let mut new_samples = Vec::new();
    for role in &resample {
        let spec = crate::handles::contour_spec(design, *role);
        match sample_contour(
            spec,
            role.field(),
            center,
            design.shape.samples,
            design.base_dir.as_deref(),
        ) {
            Ok(c) => new_samples.push((*role, c)),
            Err(e) => {
                status.error = Some(e.to_string());
                return;
            }
        }
    }
    // Stage 2: the shape model (loft + control lines + layer plan).
    let (model, plan_findings, dirty): (ShapeModel, Vec<Finding>, Option<BTreeSet<usize>>) =
        match (&plan, cache.model.as_ref()) {
            (Recompute::Sections(dirty), Some(old)) => {
                let mut m = old.clone();
                m.vertical = design
                    .control
                    .vertical
                    .iter()
                    .map(clayloft_core::control::VerticalProfile::new)
                    .collect();
                (m, cache.plan_findings.clone(), Some(dirty.clone()))
            }
            (Recompute::Finish, Some(old)) => (
                old.clone(),
                cache.plan_findings.clone(),
                Some(BTreeSet::new()),
            ),
            _ => {
                let sample_of = |role: ContourRole| -> Vec<DVec2> {
                    if let Some((_, c)) = new_samples.iter().find(|(r, _)| *r == role) {
                        return c.samples.clone();
                    }
                    contours
                        .iter()
                        .find(|(r, _)| **r == role)
                        .map(|(_, s)| s.samples.clone())
                        .unwrap_or_default()
                };
                let loft = LoftInput::from_samples(
                    sample_of(ContourRole::Lower),
                    sample_of(ContourRole::Upper),
                    center,
                );
                match ShapeModel::new(design, loft) {
                    Ok((m, f)) => (m, f, None),
                    Err(e) => {
                        status.error = Some(e.to_string());
                        return;
                    }
                }
            }
        };
    // Stage 3: sections, one entity per section; only the dirty ones are reshaped.
    let count = model.layers + 1;
    let mut shaped: Vec<Option<Section>> = vec![None; count];
    let mut reshaped = Vec::new();
    for (entity, index, mut section) in &mut sections {
        let k = index.0;
        if k >= count {
            commands.entity(entity).despawn();
            continue;
        }
        let needed = dirty.as_ref().is_none_or(|d| d.contains(&k));
        if needed {
            section.0 = model.section(k);
            reshaped.push(k);
        }
        shaped[k] = Some(section.0.clone());
    }
    for (k, slot) in shaped.iter_mut().enumerate() {
        if slot.is_none() {
            let s = model.section(k);
            commands.spawn((SectionIndex(k), ShapedSection(s.clone())));
            reshaped.push(k);
            *slot = Some(s);
        }
    }
    reshaped.sort_unstable();
    let shaped: Vec<Section> = shaped.into_iter().map(Option::unwrap_or_default).collect();
    // Stages 4–6: constraints, texture, toolpath (whole surface).
    let built = finish_surface(design, &model, shaped, plan_findings.clone())
        .and_then(|surface| build_toolpath(design, &surface).map(|path| (surface, path)));
    let (surface, path) = match built {
        Ok(b) => b,
        Err(e) => {
            status.error = Some(e.to_string());
            // Section entities now hold this design's shapes: the next pass starts afresh.
            cache.design = None;
            cache.model = None;
            return;
        }
    };
    for (role, c) in new_samples {
        if let Some((_, mut s)) = contours.iter_mut().find(|(r, _)| **r == role) {
            *s = ContourSamples {
                samples: c.samples,
                offset: c.offset,
            };
        }
    }
    commands
        .entity(*vessel)
        .insert(VesselSurface(Arc::new(surface)));
    commands
        .entity(*toolpath)
        .insert(ToolpathPath(Arc::new(path)));
    status.error = None;
    log.passes += 1;
    log.resampled = resample;
    log.sections = reshaped;
    cache.design = Some(design.clone());
    cache.model = Some(model);
    cache.plan_findings = plan_findings;
}

/// Keeps one entity per control line with its curve drawn on the loft (design space).
pub fn derive_control_lines(
    mut commands: Commands,
    cache: Res<ModelCache>,
    mut lines: Query<(Entity, &ControlLine, &mut ControlLineCurve)>,
) {
    if !cache.is_changed() {
        return;
    }
    let (Some(design), Some(model)) = (&cache.design, &cache.model) else {
        return;
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
    for (entity, line, mut curve) in &mut lines {
        if wanted.contains(line) {
            curve.0 = line_curve(*line, design, model);
            seen.push(*line);
        } else {
            commands.entity(entity).despawn();
        }
    }
    for line in wanted.into_iter().filter(|l| !seen.contains(l)) {
        commands.spawn((line, ControlLineCurve(line_curve(line, design, model))));
    }
}

/// A vertical line runs up the loft at its angle, offset by its profile; a horizontal line runs
/// around the loft at its height, raised by its profile.
fn line_curve(line: ControlLine, design: &Design, model: &ShapeModel) -> Vec<DVec3> {
    let loft = &model.loft;
    let n = loft.samples();
    if n == 0 {
        return Vec::new();
    }
    let h = design.shape.height;
    match line.kind {
        LineKind::Vertical => {
            let Some(v) = design.control.vertical.get(line.index) else {
                return Vec::new();
            };
            let profile = &model.vertical[line.index];
            let phi = v.angle.unwrap_or(0.0).to_radians();
            let i = crate::handles::nearest_sample(&loft.angles, phi).unwrap_or(0);
            (0..=64)
                .map(|j| {
                    let t = j as f64 / 64.0;
                    let p = loft.point(i, t);
                    let dir = (p - loft.center).normalize_or(DVec2::X);
                    (p + dir * profile.offset_at(t)).extend(t * h)
                })
                .collect()
        }
        LineKind::Horizontal => {
            let Some(hl) = design.control.horizontal.get(line.index) else {
                return Vec::new();
            };
            let profile = &model.horizontal[line.index];
            (0..=n)
                .map(|j| {
                    let i = j % n;
                    let p = loft.point(i, hl.at);
                    p.extend(hl.at * h + profile.dz_at(loft.angles[i]) * model.hz_scale)
                })
                .collect()
        }
    }
}
