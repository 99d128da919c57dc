//! Editing (SPEC §8 "Editing"): every handle can be dragged with the mouse or a finger (Bevy's
//! picking), the selected handle gets a move gizmo for precise axis-constrained moves, and every
//! settled edit can be undone and redone (Ctrl+Z / Ctrl+Shift+Z).

pub mod drag;
pub mod gizmo;
pub mod history;
pub mod ray;

use bevy::prelude::*;

pub use drag::{ActiveDrag, DragHint, Selection};
pub use history::{EditInProgress, History, HistoryCommand, PanelInUse};

/// Handles, the move gizmo and undo/redo.
pub struct EditPlugin;

impl Plugin for EditPlugin {
    fn build(&self, app: &mut App) {
        app.add_plugins((drag::plugin, gizmo::plugin, history::plugin));
    }
}
