//! Clayloft's design as ECS entities, recomputed incrementally on change detection (SPEC §8).
//!
//! The [`DesignDoc`] resource is the one source of truth: handles, panels, undo and file loading
//! all edit it. Everything else is derived from it by the systems in [`ModelSystems`]:
//!
//! - two contour entities ([`ContourRole`]) with their [`ContourSamples`];
//! - one section entity per layer boundary ([`SectionIndex`], [`ShapedSection`]);
//! - one entity per editable point ([`EditHandle`]): contour points and radii, control-line points;
//! - one entity per control line ([`ControlLine`]) with its drawn curve;
//! - the vessel ([`Vessel`]) holding the corrected, textured [`VesselSurface`] and its mesh for
//!   the view ([`VesselMesh`]);
//! - the toolpath ([`ToolpathPath`]) and whether the wall stands ([`ToolpathPrintability`]).
//!
//! The core's incremental engine ([`clayloft_core::Session`], held in [`Engine`]) decides what an
//! edit must redo: a local vertical control line recomputes only the sections in its span, a
//! contour that contour's samples and then the sections, a speed only the toolpath. The systems
//! here copy its outputs into components; the math, the control-line curves and the handle
//! positions are the core library's ([`clayloft_core`]); nothing here repeats it.

pub mod background;
pub mod components;
pub mod coords;
pub mod document;
pub mod handles;
pub mod preview;
pub mod recompute;

use bevy::prelude::*;

pub use components::*;
pub use document::{DesignDoc, ModelStatus};
pub use recompute::{Engine, RecomputeLog};

/// Order of the model's systems within `Update`.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ModelSystems {
    /// Edits are written into [`DesignDoc`] (handles, panels, undo, files).
    Edit,
    /// The derived entities are recomputed from the design.
    Recompute,
    /// Views read the derived entities.
    View,
}

/// Adds the design document and the recompute systems.
pub struct ModelPlugin;

impl Plugin for ModelPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<ModelStatus>()
            .init_resource::<Engine>()
            .init_resource::<RecomputeLog>()
            .configure_sets(
                Update,
                (
                    ModelSystems::Edit,
                    ModelSystems::Recompute,
                    ModelSystems::View,
                )
                    .chain(),
            )
            .add_systems(Startup, recompute::spawn_model_entities)
            .add_systems(
                Update,
                (
                    recompute::recompute_model,
                    handles::sync_handles,
                    recompute::derive_control_lines,
                )
                    .chain()
                    .in_set(ModelSystems::Recompute),
            );
    }
}
