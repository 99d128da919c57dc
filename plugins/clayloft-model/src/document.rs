//! The design being edited and what the model says about it.

use std::path::PathBuf;

use bevy::prelude::*;
use clayloft_core::Design;
use clayloft_core::validate::FieldError;

/// The design being edited: the one source of truth the derived entities follow.
#[derive(Resource, Debug, Clone)]
pub struct DesignDoc {
    pub design: Design,
    /// The file it was opened from or last saved to.
    pub path: Option<PathBuf>,
}

/// The outcome of the last recompute, shown in the status line.
#[derive(Resource, Debug, Clone, Default, PartialEq)]
pub struct ModelStatus {
    /// Why the edited design cannot be built, one line each: the problem that stopped it, then
    /// every other field the validator refuses ([`clayloft_core::validate::validate_all`]).
    /// While there are any, the derived entities keep the last good design: the view shows it
    /// as stale.
    pub errors: Vec<FieldError>,
}

impl ModelStatus {
    /// The problem that stopped the recompute, as one line.
    pub fn error(&self) -> Option<String> {
        self.errors.first().map(|e| e.to_string())
    }

    /// Whether what the view shows is not the design being edited.
    pub fn is_stale(&self) -> bool {
        !self.errors.is_empty()
    }

    /// The problem with the field at dotted `path`, if any.
    pub fn for_field(&self, path: &str) -> Option<&FieldError> {
        self.errors.iter().find(|e| e.field == path)
    }
}
