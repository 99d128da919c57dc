//! The design being edited and what the model says about it.

use std::path::PathBuf;

use bevy::prelude::*;
use clayloft_core::Design;

/// The design being edited: the one source of truth the derived entities follow.
#[derive(Resource, Debug, Clone)]
pub struct DesignDoc {
    pub design: Design,
    /// The file it was opened from or last saved to.
    pub path: Option<PathBuf>,
}

/// The outcome of the last recompute, shown in the status line.
#[derive(Resource, Debug, Clone, Default)]
pub struct ModelStatus {
    /// Why the edited design cannot be built (the derived entities keep the last good state).
    pub error: Option<String>,
}
