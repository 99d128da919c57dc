//! The interactive application (SPEC §8): [`ClayloftPlugins`] assembles the plugins under
//! `plugins/`, [`ThirdPartyPlugins`] sets up egui, the orbit camera and picking (once each, here
//! only). Nothing here computes; every feature lives in its plugin crate.
//!
//! Rendering is reactive, like a desktop application: a frame is drawn on input, and otherwise
//! only while something moves — the replay plays (`clayloft-replay`), the camera eases to its
//! target (`clayloft-view`), a flow simulation or a print streams (their windows ask egui for a
//! repaint) — or every 5 s. Left alone, the app sleeps.

use std::path::PathBuf;
use std::process::ExitCode;

use bevy::app::PluginGroupBuilder;
use bevy::prelude::*;
use bevy::window::{PresentMode, WindowResolution};
use bevy::winit::WinitSettings;
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
    .add_plugins(ClayloftPlugins);
    let screenshot_mode = screenshot.is_some();
    // A screenshot waits for frames to settle: it runs continuously until the picture is saved.
    app.insert_resource(if screenshot_mode {
        WinitSettings::continuous()
    } else {
        WinitSettings::desktop_app()
    });
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

/// Every Clayloft plugin, in the order they build on each other: the third-party set-up, the
/// model (the core's incremental engine), then the views and tools that read it.
pub struct ClayloftPlugins;

impl PluginGroup for ClayloftPlugins {
    fn build(self) -> PluginGroupBuilder {
        PluginGroupBuilder::start::<Self>()
            .add(ThirdPartyPlugins)
            .add(ModelPlugin)
            .add(clayloft_view::ViewPlugin)
            .add(clayloft_edit::EditPlugin)
            .add(clayloft_files::FilesPlugin)
            .add(clayloft_replay::ReplayPlugin)
            .add(clayloft_panels::PanelsPlugin)
            .add(clayloft_printer::PrinterPlugin)
            .add(clayloft_flowview::FlowViewPlugin)
    }
}

/// The third-party plugins, set up in this one place: egui (the panels and windows), the orbit
/// camera (the 3D view) and mesh picking (the handles).
pub struct ThirdPartyPlugins;

impl Plugin for ThirdPartyPlugins {
    fn build(&self, app: &mut App) {
        app.add_plugins((
            bevy_egui::EguiPlugin::default(),
            bevy_panorbit_camera::PanOrbitCameraPlugin,
        ));
        clayloft_edit::drag::picking_setup(app);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use bevy::render::RenderPlugin;
    use bevy::render::settings::WgpuSettings;

    /// The whole app without a window or a GPU: every plugin's main-world systems run.
    fn headless(design: Design) -> App {
        let mut app = App::new();
        app.add_plugins(
            DefaultPlugins
                .set(WindowPlugin {
                    primary_window: None,
                    exit_condition: bevy::window::ExitCondition::DontExit,
                    ..default()
                })
                .set(RenderPlugin {
                    render_creation: WgpuSettings {
                        backends: None,
                        ..default()
                    }
                    .into(),
                    ..default()
                })
                .disable::<bevy::winit::WinitPlugin>(),
        )
        .insert_resource(DesignDoc { design, path: None })
        .insert_resource(clayloft_files::Autosave::new(
            std::env::temp_dir().join(format!("clayloft-idle-test-{}", std::process::id())),
        ))
        .add_plugins(ClayloftPlugins);
        app
    }

    /// Idle frames rebuild nothing: no recompute, no wall mesh, no toolpath lines, no control
    /// lines, and the design, the engine and the view settings are never marked changed.
    #[test]
    fn idle_frames_rebuild_nothing() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("assets/designs/petal-vase.toml");
        let design = clayloft_core::load_design(&path).unwrap().design;
        let mut app = headless(design);
        #[derive(Resource, Default, Debug)]
        struct Changes(u64);
        app.init_resource::<Changes>().add_systems(
            Last,
            |doc: Res<DesignDoc>,
             engine: Res<clayloft_model::Engine>,
             settings: Res<clayloft_view::ViewSettings>,
             replay: Res<clayloft_replay::Replay>,
             lines: Query<(), Changed<clayloft_model::ControlLineCurve>>,
             handles: Query<(), Changed<clayloft_model::HandlePosition>>,
             mut changes: ResMut<Changes>| {
                let flags = [
                    doc.is_changed(),
                    engine.is_changed(),
                    settings.is_changed(),
                    replay.is_changed(),
                    !lines.is_empty(),
                    !handles.is_empty(),
                ];
                changes.0 += flags.iter().filter(|f| **f).count() as u64;
            },
        );
        // The first frames build everything.
        for _ in 0..5 {
            app.update();
        }
        let passes = app.world().resource::<clayloft_model::RecomputeLog>().passes;
        let rebuilds = *app.world().resource::<clayloft_view::ViewRebuilds>();
        assert_eq!(passes, 1);
        assert_eq!(rebuilds.wall_mesh, 1);
        app.world_mut().resource_mut::<Changes>().0 = 0;
        for _ in 0..100 {
            app.update();
        }
        assert_eq!(
            app.world().resource::<clayloft_model::RecomputeLog>().passes,
            passes,
            "recomputed while idle"
        );
        assert_eq!(
            *app.world().resource::<clayloft_view::ViewRebuilds>(),
            rebuilds,
            "rebuilt while idle"
        );
        assert_eq!(app.world().resource::<Changes>().0, 0, "changes while idle");
        // One edit: exactly one recompute and one wall rebuild.
        app.world_mut()
            .resource_mut::<DesignDoc>()
            .design
            .printer
            .print_speed += 1.0;
        for _ in 0..3 {
            app.update();
        }
        assert_eq!(
            app.world().resource::<clayloft_model::RecomputeLog>().passes,
            passes + 1
        );
    }
}
