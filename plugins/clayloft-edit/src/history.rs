//! Undo and redo of settled edits: a drag counts once when it ends, a number typed or dragged in
//! a panel once when the widget is let go. Any edit — handle, panel, file — goes through the
//! design document, so this one watcher records them all.

use bevy::input::keyboard::KeyCode;
use bevy::prelude::*;
use clayloft_core::Design;
use clayloft_model::{DesignDoc, ModelSystems};

/// Largest number of undo steps kept.
pub const MAX_UNDO: usize = 200;

/// True while a handle or gizmo drag is under way: the design changes every frame but the edit
/// is not settled yet.
#[derive(Resource, Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct EditInProgress(pub bool);

/// True while the pointer is over the panels or one of their widgets is held (set by the panels):
/// the camera ignores the pointer, and a value being dragged in a panel is not settled yet.
#[derive(Resource, Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct PanelInUse {
    pub hovered: bool,
    pub editing: bool,
    /// A text field has the keyboard: Ctrl+Z belongs to it, not to the design's history.
    pub typing: bool,
}

/// Settled designs before and after the current one.
#[derive(Resource, Debug, Clone, Default)]
pub struct History {
    undo: Vec<Design>,
    redo: Vec<Design>,
    /// The last settled design.
    settled: Option<Design>,
}

impl History {
    /// Starts a history at `design` (a newly opened file): nothing to undo.
    pub fn reset(&mut self, design: &Design) {
        self.undo.clear();
        self.redo.clear();
        self.settled = Some(design.clone());
    }

    /// Records `current` if it differs from the last settled design; returns whether it did.
    pub fn settle(&mut self, current: &Design) -> bool {
        match &self.settled {
            Some(s) if s == current => false,
            Some(s) => {
                self.undo.push(s.clone());
                if self.undo.len() > MAX_UNDO {
                    self.undo.remove(0);
                }
                self.redo.clear();
                self.settled = Some(current.clone());
                true
            }
            None => {
                self.settled = Some(current.clone());
                false
            }
        }
    }

    /// The design to go back to, if any.
    pub fn undo(&mut self) -> Option<Design> {
        let prev = self.undo.pop()?;
        if let Some(s) = self.settled.replace(prev.clone()) {
            self.redo.push(s);
        }
        Some(prev)
    }

    /// The design to go forward to, if any.
    pub fn redo(&mut self) -> Option<Design> {
        let next = self.redo.pop()?;
        if let Some(s) = self.settled.replace(next.clone()) {
            self.undo.push(s);
        }
        Some(next)
    }

    pub fn can_undo(&self) -> bool {
        !self.undo.is_empty()
    }

    pub fn can_redo(&self) -> bool {
        !self.redo.is_empty()
    }
}

/// An undo or redo asked for by a button (the panels) rather than the keyboard.
#[derive(Message, Debug, Clone, Copy, PartialEq, Eq)]
pub enum HistoryCommand {
    Undo,
    Redo,
}

pub(crate) fn plugin(app: &mut App) {
    app.init_resource::<History>()
        .init_resource::<EditInProgress>()
        .init_resource::<PanelInUse>()
        .add_message::<HistoryCommand>()
        .add_systems(
            Update,
            (read_history_keys, apply_history_commands, settle_edits)
                .chain()
                .in_set(ModelSystems::Edit),
        );
}

/// Ctrl+Z undoes, Ctrl+Shift+Z (or Ctrl+Y) redoes.
fn read_history_keys(
    keys: Option<Res<ButtonInput<KeyCode>>>,
    panel: Res<PanelInUse>,
    mut out: MessageWriter<HistoryCommand>,
) {
    let Some(keys) = keys else { return };
    if panel.typing {
        return;
    }
    let ctrl = keys.any_pressed([
        KeyCode::ControlLeft,
        KeyCode::ControlRight,
        KeyCode::SuperLeft,
    ]);
    let shift = keys.any_pressed([KeyCode::ShiftLeft, KeyCode::ShiftRight]);
    if ctrl && keys.just_pressed(KeyCode::KeyZ) {
        out.write(if shift {
            HistoryCommand::Redo
        } else {
            HistoryCommand::Undo
        });
    } else if ctrl && keys.just_pressed(KeyCode::KeyY) {
        out.write(HistoryCommand::Redo);
    }
}

fn apply_history_commands(
    mut commands: MessageReader<HistoryCommand>,
    mut history: ResMut<History>,
    doc: Option<ResMut<DesignDoc>>,
    busy: Res<EditInProgress>,
) {
    let Some(mut doc) = doc else { return };
    for c in commands.read() {
        if busy.0 {
            continue;
        }
        // An unsettled change (typed this frame) is settled first so it can be undone too.
        history.settle(&doc.design);
        let target = match c {
            HistoryCommand::Undo => history.undo(),
            HistoryCommand::Redo => history.redo(),
        };
        if let Some(d) = target {
            doc.design = d;
        }
    }
}

fn settle_edits(
    doc: Option<Res<DesignDoc>>,
    busy: Res<EditInProgress>,
    panel: Res<PanelInUse>,
    mut history: ResMut<History>,
) {
    let Some(doc) = doc else { return };
    if !busy.0 && !panel.editing {
        history.settle(&doc.design);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn design(h: f64) -> Design {
        let mut d = clayloft_core::load::parse_design(
            "version = 1\n[shape]\nlower = { type = \"circle\", radius = 40.0 }\nupper = { type = \"circle\", radius = 30.0 }\n",
        )
        .unwrap();
        d.shape.height = h;
        d
    }

    #[test]
    fn undo_redo_walks_settled_designs() {
        let mut h = History::default();
        h.reset(&design(100.0));
        assert!(!h.settle(&design(100.0)));
        assert!(h.settle(&design(110.0)));
        assert!(h.settle(&design(120.0)));
        assert_eq!(h.undo().unwrap().shape.height, 110.0);
        assert_eq!(h.undo().unwrap().shape.height, 100.0);
        assert!(h.undo().is_none());
        assert_eq!(h.redo().unwrap().shape.height, 110.0);
        // A new edit drops the redo branch.
        assert!(h.settle(&design(90.0)));
        assert!(!h.can_redo());
        assert_eq!(h.undo().unwrap().shape.height, 110.0);
    }

    fn app() -> App {
        let mut app = App::new();
        app.add_plugins((MinimalPlugins, clayloft_model::ModelPlugin, plugin));
        app.insert_resource(ButtonInput::<KeyCode>::default());
        app.insert_resource(DesignDoc {
            design: design(100.0),
            path: None,
        });
        app.update();
        app
    }

    fn press(app: &mut App, keys: &[KeyCode]) {
        let mut input = app.world_mut().resource_mut::<ButtonInput<KeyCode>>();
        input.reset_all();
        for k in keys {
            input.press(*k);
        }
        app.update();
        app.world_mut()
            .resource_mut::<ButtonInput<KeyCode>>()
            .release_all();
        app.update();
    }

    #[test]
    fn ctrl_z_and_ctrl_shift_z_in_a_headless_app() {
        let mut app = app();
        app.world_mut()
            .resource_mut::<DesignDoc>()
            .design
            .shape
            .height = 80.0;
        app.update();
        // A drag in progress does not settle until it ends.
        app.world_mut().resource_mut::<EditInProgress>().0 = true;
        app.world_mut()
            .resource_mut::<DesignDoc>()
            .design
            .shape
            .height = 70.0;
        app.update();
        app.world_mut()
            .resource_mut::<DesignDoc>()
            .design
            .shape
            .height = 60.0;
        app.update();
        app.world_mut().resource_mut::<EditInProgress>().0 = false;
        app.update();
        press(&mut app, &[KeyCode::ControlLeft, KeyCode::KeyZ]);
        assert_eq!(
            app.world().resource::<DesignDoc>().design.shape.height,
            80.0
        );
        press(&mut app, &[KeyCode::ControlLeft, KeyCode::KeyZ]);
        assert_eq!(
            app.world().resource::<DesignDoc>().design.shape.height,
            100.0
        );
        press(
            &mut app,
            &[KeyCode::ControlLeft, KeyCode::ShiftLeft, KeyCode::KeyZ],
        );
        assert_eq!(
            app.world().resource::<DesignDoc>().design.shape.height,
            80.0
        );
        press(&mut app, &[KeyCode::ControlLeft, KeyCode::KeyY]);
        assert_eq!(
            app.world().resource::<DesignDoc>().design.shape.height,
            60.0
        );
    }
}
