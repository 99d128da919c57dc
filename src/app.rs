//! The interactive application (SPEC §8): [`ClayloftPlugins`] assembles the plugins under
//! `plugins/`, [`ThirdPartyPlugins`] sets up egui, the orbit camera and picking (once each, here
//! only). Nothing here computes; every feature lives in its plugin crate.
//!
//! Rendering is reactive, like a desktop application: a frame is drawn on input, and otherwise
//! only while something moves — the replay plays (`clayloft-replay`), the camera eases to its
//! target (`clayloft-view`), a flow simulation or a print streams (their windows ask egui for a
//! repaint), an export or the autosave is pending (`clayloft-files`) — or once a minute. Left
//! alone, the app sleeps.

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
    if std::env::var_os("CLAYLOFT_FRAME_LOG").is_some() {
        app.add_systems(Last, log_frames);
    }
    let screenshot_mode = screenshot.is_some();
    // A screenshot waits for frames to settle: it runs continuously until the picture is saved.
    app.insert_resource(if screenshot_mode {
        WinitSettings::continuous()
    } else {
        // Woken by input and by what moves (see the module documentation); the timeouts only
        // bound how stale a forgotten case could get. Under software rendering one frame of
        // the default design costs ~0.8 s of processor time, so a 5 s wake-up would be 16 %.
        WinitSettings {
            focused_mode: bevy::winit::UpdateMode::reactive(std::time::Duration::from_secs(60)),
            unfocused_mode: bevy::winit::UpdateMode::reactive_low_power(
                std::time::Duration::from_secs(60),
            ),
        }
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

/// bevy_egui 0.42 hands egui a `ModifiersChanged` event every frame (`write_egui_input_system`,
/// input.rs:1517), changed or not; egui takes any event as a reason to repaint at once, so the
/// app would never sleep (measured: 193 % CPU idle under software rendering). The event is
/// dropped when the modifiers are what they were.
fn drop_unchanged_egui_modifiers(
    mut inputs: Query<&mut bevy_egui::EguiInput>,
    mut last: Local<Option<bevy_egui::egui::Modifiers>>,
) {
    for mut input in &mut inputs {
        let before = *last;
        input.0.events.retain(|e| match e {
            bevy_egui::egui::Event::ModifiersChanged(m) => {
                let changed = before != Some(*m);
                *last = Some(*m);
                changed
            }
            _ => true,
        });
    }
}

/// With `CLAYLOFT_FRAME_LOG` set: frames drawn and redraws asked for, every two seconds (to see
/// that an idle app sleeps, and what keeps it awake when it does not).
fn log_frames(
    time: Res<Time<Real>>,
    mut redraws: MessageReader<bevy::window::RequestRedraw>,
    mut egui: bevy_egui::EguiContexts,
    mut counts: Local<(u64, u64, u64, f64)>,
) {
    counts.0 += 1;
    counts.1 += redraws.read().count() as u64;
    if let Ok(ctx) = egui.ctx_mut()
        && ctx.has_requested_repaint()
    {
        counts.2 += 1;
        if counts.2 == 1 {
            let events =
                ctx.input(|i| format!("{:?} pointer {:?}", i.raw.events, i.pointer.latest_pos()));
            info!(
                "egui repaint causes: {:?}; input: {events}",
                ctx.repaint_causes()
            );
        }
    }
    let now = time.elapsed_secs_f64();
    if now - counts.3 >= 2.0 {
        info!(
            "frames: {} in {:.1} s, redraw requests: {}, egui repaint requests: {}",
            counts.0,
            now - counts.3,
            counts.1,
            counts.2
        );
        *counts = (0, 0, 0, now);
    }
}

/// Every Clayloft plugin, in the order they build on each other: the third-party set-up, the
/// model (the core's incremental engine), then the views and tools that read it.
pub struct ClayloftPlugins;

impl PluginGroup for ClayloftPlugins {
    fn build(self) -> PluginGroupBuilder {
        PluginGroupBuilder::start::<Self>()
            .add(ThirdPartyPlugins)
            .add(clayloft_ui::UiPlugin)
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
        ))
        .add_systems(
            PreUpdate,
            drop_unchanged_egui_modifiers
                .after(bevy_egui::EguiPreUpdateSet::ProcessInput)
                .before(bevy_egui::EguiPreUpdateSet::BeginPass),
        );
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

    /// [`headless`] on the default design.
    fn headless_default_design() -> App {
        let path =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/designs/petal-vase.toml");
        headless(clayloft_core::load_design(&path).unwrap().design)
    }

    /// Idle frames rebuild nothing: no recompute, no wall mesh, no toolpath lines, no control
    /// lines, and the design, the engine and the view settings are never marked changed.
    #[test]
    fn idle_frames_rebuild_nothing() {
        let mut app = headless_default_design();
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
        let passes = app
            .world()
            .resource::<clayloft_model::RecomputeLog>()
            .passes;
        let rebuilds = app
            .world()
            .resource::<clayloft_view::ViewRebuilds>()
            .counts();
        assert_eq!(passes, 1);
        assert_eq!(rebuilds.wall_mesh, 1);
        app.world_mut().resource_mut::<Changes>().0 = 0;
        for _ in 0..100 {
            app.update();
        }
        assert_eq!(
            app.world()
                .resource::<clayloft_model::RecomputeLog>()
                .passes,
            passes,
            "recomputed while idle"
        );
        assert_eq!(
            app.world()
                .resource::<clayloft_view::ViewRebuilds>()
                .counts(),
            rebuilds,
            "rebuilt while idle"
        );
        assert_eq!(app.world().resource::<Changes>().0, 0, "changes while idle");
        // The camera cannot zoom into the wall, and "frame the vessel" brings it back.
        let frame = {
            let mut q = app.world_mut().query::<&clayloft_model::VesselSurface>();
            let surface = q.single(app.world()).unwrap().0.clone();
            let h = app.world().resource::<DesignDoc>().design.shape.height;
            clayloft_view::camera_frame(&surface, h)
        };
        let mut q = app
            .world_mut()
            .query::<&mut bevy_panorbit_camera::PanOrbitCamera>();
        {
            let mut cam = q.single_mut(app.world_mut()).unwrap();
            assert_eq!(cam.zoom_lower_limit, frame.min_radius);
            cam.target_radius = frame.min_radius * 3.0;
        }
        app.world_mut()
            .resource_mut::<Messages<clayloft_view::FrameVessel>>()
            .write(clayloft_view::FrameVessel);
        app.update();
        let cam = q.single(app.world()).unwrap();
        assert_eq!(cam.target_radius, frame.radius);
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
            app.world()
                .resource::<clayloft_model::RecomputeLog>()
                .passes,
            passes + 1
        );
    }

    /// The replay's checker runs on a thread of its own and only while the replay is shown:
    /// editing a design with the replay hidden never waits for it, and once shown the replay
    /// flags what the checker flags.
    #[test]
    fn the_replay_checks_the_path_in_the_background_while_shown() {
        let mut app = headless_default_design();
        for _ in 0..5 {
            app.update();
        }
        // Hidden: the path is not checked.
        assert!(
            app.world()
                .resource::<clayloft_replay::ReplayPath>()
                .checking
        );
        // A steeper wall than the printer allows (enforcement off), so that there is something
        // to flag, then the replay shown.
        {
            let mut doc = app.world_mut().resource_mut::<DesignDoc>();
            doc.design.constraints.enforce = false;
            doc.design.printer.max_overhang_deg = 5.0;
        }
        app.update();
        assert!(
            app.world()
                .resource::<clayloft_replay::ReplayPath>()
                .checking
        );
        app.world_mut()
            .resource_mut::<clayloft_replay::Replay>()
            .active = true;
        let start = std::time::Instant::now();
        while app
            .world()
            .resource::<clayloft_replay::ReplayPath>()
            .checking
        {
            assert!(start.elapsed().as_secs() < 60, "the check never finished");
            std::thread::sleep(std::time::Duration::from_millis(5));
            app.update();
        }
        let design = app.world().resource::<DesignDoc>().design.clone();
        let mut q = app.world_mut().query::<&clayloft_model::ToolpathPath>();
        let toolpath = q.single(app.world()).unwrap().0.clone();
        let expected = clayloft_replay::ReplayPath::new(&toolpath, &design.printer).events;
        assert!(!expected.is_empty());
        assert_eq!(
            app.world().resource::<clayloft_replay::ReplayPath>().events,
            expected
        );
    }
}
