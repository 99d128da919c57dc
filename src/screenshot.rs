//! `clayloft screenshot`: renders the view (with the nozzle replay at a given fraction of the
//! print), saves it as PNG (atomically) and exits. Software renderers compile their pipelines
//! during the first frames, so the capture waits for the model and then for some frames and
//! seconds of rendering.

use std::path::PathBuf;
use std::time::Duration;

use bevy::prelude::*;
use bevy::render::view::screenshot::{Screenshot, ScreenshotCaptured};
use clayloft_model::VesselSurface;
use clayloft_replay::{Replay, ReplayPath};

/// What to capture and where.
#[derive(Resource, Debug, Clone)]
pub struct ScreenshotRequest {
    pub out: PathBuf,
    /// Fraction of the print time to put the nozzle at; `None` shows the finished design.
    pub progress: Option<f64>,
    pub width: u32,
    pub height: u32,
    /// Frames to render after the model is ready, before capturing.
    pub settle_frames: u32,
    /// Real time to render after the model is ready, before capturing.
    pub settle_time: Duration,
    /// Give up (exit 2) if nothing was captured by then.
    pub timeout: Duration,
    /// Open the extruder-flow window and wait for its simulation to converge.
    pub flow: bool,
}

pub struct ScreenshotPlugin(pub ScreenshotRequest);

impl Plugin for ScreenshotPlugin {
    fn build(&self, app: &mut App) {
        app.insert_resource(self.0.clone())
            .add_systems(Update, drive_screenshot);
    }
}

#[derive(Default)]
struct Progress {
    ready_at: Option<(u32, Duration)>,
    requested: bool,
}

fn drive_screenshot(
    mut commands: Commands,
    req: Res<ScreenshotRequest>,
    time: Res<Time<Real>>,
    vessel: Query<&VesselSurface>,
    path: Res<ReplayPath>,
    mut replay: ResMut<Replay>,
    mut state: Local<Progress>,
    mut frames: Local<u32>,
    mut exit: MessageWriter<AppExit>,
    status: Res<clayloft_model::ModelStatus>,
    flow: Res<clayloft_flowview::FlowView>,
) {
    *frames += 1;
    let now = time.elapsed();
    if now > req.timeout {
        eprintln!(
            "error: {}: no picture after {:?} (is a GPU or Mesa's lavapipe available?)",
            req.out.display(),
            req.timeout
        );
        exit.write(AppExit::from_code(2));
        return;
    }
    if state.requested {
        return;
    }
    if vessel.is_empty() {
        if let Some(e) = status.error() {
            eprintln!("error: {e}");
            exit.write(AppExit::from_code(2));
        }
        return;
    }
    if let Some(f) = req.progress
        && path.timeline.total_s() > 0.0
    {
        replay.active = true;
        replay.playing = false;
        replay.time_s = f.clamp(0.0, 1.0) * path.timeline.total_s();
        // The flags the replay shows come from the checker, on a thread of its own.
        if path.checking {
            return;
        }
    }
    // The flow window's simulation: wait until it has converged (or run long enough to show
    // its vortex).
    if req.flow
        && !flow
            .last
            .as_ref()
            .is_some_and(|s| s.change < 1e-6 || s.steps >= 60_000)
    {
        return;
    }
    let (frame0, t0) = *state.ready_at.get_or_insert((*frames, now));
    if *frames - frame0 < req.settle_frames || now - t0 < req.settle_time {
        return;
    }
    state.requested = true;
    let out = req.out.clone();
    commands.spawn(Screenshot::primary_window()).observe(
        move |ev: On<ScreenshotCaptured>, mut exit: MessageWriter<AppExit>| match save_png(
            &ev.image, &out,
        ) {
            Ok((w, h)) => {
                println!("wrote {} ({w} × {h})", out.display());
                exit.write(AppExit::Success);
            }
            Err(e) => {
                eprintln!("error: {e}");
                exit.write(AppExit::from_code(2));
            }
        },
    );
}

/// Saves a captured frame as an RGB PNG, atomically.
fn save_png(image: &Image, out: &std::path::Path) -> Result<(u32, u32), String> {
    let rgb = image
        .clone()
        .try_into_dynamic()
        .map_err(|e| format!("{}: cannot convert the frame: {e}", out.display()))?
        .to_rgb8();
    let size = rgb.dimensions();
    let mut bytes = Vec::new();
    rgb.write_to(
        &mut std::io::Cursor::new(&mut bytes),
        image::ImageFormat::Png,
    )
    .map_err(|e| format!("{}: cannot encode PNG: {e}", out.display()))?;
    clayloft_core::atomic::write_atomically(out, |w| w.write_all(&bytes))
        .map_err(|e| e.to_string())?;
    Ok(size)
}
