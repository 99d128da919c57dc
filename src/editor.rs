//! `clayloft-editor`: the application (SPEC §8, [`app`]) with the whole command line
//! ([`clayloft::cli`]); `clayloft` hands it the commands that open a window.

mod app;
mod screenshot;

use std::path::PathBuf;
use std::process::ExitCode;

use clayloft::cli::{self, Failure, Window, job_of};
use clayloft_core::load_design;

fn main() -> ExitCode {
    cli::main(open)
}

/// Opens the window a command asks for.
fn open(window: Window) -> Result<ExitCode, Failure> {
    match window {
        Window::Editor(design) => editor(design),
        Window::Screenshot {
            design,
            out,
            progress,
            size,
            flow,
        } => shoot(design, out, progress, size, flow),
    }
}

/// `clayloft [DESIGN]`: the editor. The design is read first, so a bad file is a one-line error
/// (exit 2) rather than an empty window.
fn editor(design: PathBuf) -> Result<ExitCode, Failure> {
    let loaded = load_design(&design)?;
    Ok(app::run(loaded.design, loaded.path, None))
}

/// `clayloft screenshot [DESIGN] -o OUT.png [--progress F]` (its arguments checked by
/// [`cli`]).
fn shoot(
    design: PathBuf,
    out: PathBuf,
    progress: Option<f64>,
    (width, height): (u32, u32),
    flow: bool,
) -> Result<ExitCode, Failure> {
    let (loaded, _job) = job_of(&design, None)?;
    let req = screenshot::ScreenshotRequest {
        out,
        progress,
        width,
        height,
        settle_frames: 60,
        settle_time: std::time::Duration::from_secs(4),
        timeout: std::time::Duration::from_secs(300),
        flow,
    };
    Ok(app::run(loaded.design, loaded.path, Some(req)))
}
