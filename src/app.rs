//! The interactive application (SPEC §8): assembles the plugins under `plugins/`. Nothing here
//! computes; every feature lives in its plugin crate.

use std::path::PathBuf;
use std::process::ExitCode;

use bevy::prelude::*;
use bevy::window::{PresentMode, WindowResolution};
use clayloft_core::Design;
use clayloft_model::{DesignDoc, ModelPlugin};

use crate::screenshot::{ScreenshotPlugin, ScreenshotRequest};

/// Runs the editor on `design` (opened from `path`) until the window is closed, or, with a
/// screenshot request, until the picture is saved.
pub fn run(design: Design, path: PathBuf, screenshot: Option<ScreenshotRequest>) -> ExitCode {
    let title = format!("Clayloft — {}", design.name);
    let (w, h) = screenshot
        .as_ref()
        .map_or((1600, 900), |s| (s.width, s.height));
    let mut app = App::new();
    app.add_plugins(DefaultPlugins.set(WindowPlugin {
        primary_window: Some(Window {
            title,
            resolution: WindowResolution::new(w, h),
            present_mode: PresentMode::AutoVsync,
            ..default()
        }),
        ..default()
    }))
    .insert_resource(DesignDoc {
        design,
        path: Some(path),
    })
    .add_plugins((
        ModelPlugin,
        clayloft_view::ViewPlugin,
        clayloft_edit::EditPlugin,
        clayloft_files::FilesPlugin,
        clayloft_replay::ReplayPlugin,
        clayloft_panels::PanelsPlugin,
        clayloft_printer::PrinterPlugin,
        clayloft_flowview::FlowViewPlugin,
    ));
    let screenshot_mode = screenshot.is_some();
    if let Some(req) = screenshot {
        // A screenshot shows the design file as it is, not an autosave.
        app.insert_resource(clayloft_files::Autosave::new(
            std::env::temp_dir().join(format!("clayloft-screenshot-{}", std::process::id())),
        ));
        if req.flow {
            app.insert_resource(clayloft_flowview::FlowView::opened());
        }
        app.add_plugins(ScreenshotPlugin(req));
    }
    match app.run() {
        AppExit::Success => ExitCode::SUCCESS,
        AppExit::Error(code) if screenshot_mode => ExitCode::from(code.get()),
        AppExit::Error(_) => ExitCode::from(1),
    }
}
