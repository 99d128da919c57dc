//! The command line (SPEC §7) of both programs (see the crate's documentation). Thin: every
//! piece of work is a call into `clayloft-core` or a plugin; this file only parses arguments,
//! prints summaries and maps errors to exit codes (0 = done, 1 = check found violations,
//! 2 = bad input).

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use clayloft_core::atomic::FreeingThread;
use clayloft_core::check::{Limits, check_gcode};
use clayloft_core::export::{ExportError, write_checked_gcode};
use clayloft_core::gcode::{JobSummary, format_duration, summarize};
// The batch commands keep the helper threads spinning from start to end: their stages follow
// each other closely (see `clayloft_core::parallel`).
use clayloft_core::parallel::awake;
use clayloft_core::stl::{job_mesh, write_ascii_stl, write_binary_stl};
use clayloft_core::{Design, LoadedDesign, PrintJob, load_design};

/// The design opened when none is given.
const DEFAULT_DESIGN: &str = "assets/designs/petal-vase.toml";

#[derive(Parser)]
#[command(
    name = "clayloft",
    version,
    about = "Design clay vessels and print them as one continuous spiral"
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
    /// Design file to open in the editor (default: the petal vase).
    design: Option<PathBuf>,
}

#[derive(Subcommand)]
enum Command {
    /// Turn a design into G-code and print a summary.
    Gcode {
        design: PathBuf,
        #[arg(short, long)]
        out: PathBuf,
        /// Printer profile: a shipped name (`clayloft printers`) or a profile file; replaces the
        /// design's `printer.profile` (fields the design sets itself still win).
        #[arg(long)]
        printer: Option<String>,
    },
    /// Export the printed wall (thickness = line width, with the base) as a closed STL mesh.
    Stl {
        design: PathBuf,
        #[arg(short, long)]
        out: PathBuf,
        /// Write ASCII STL instead of binary.
        #[arg(long)]
        ascii: bool,
        /// Printer profile, as for `gcode`.
        #[arg(long)]
        printer: Option<String>,
    },
    /// Print what a design makes (layers, path, time, corrections) without opening a window.
    Info {
        design: Option<PathBuf>,
        /// Printer profile, as for `gcode`.
        #[arg(long)]
        printer: Option<String>,
    },
    /// List the shipped printer profiles (name, bed shape and size, origin, firmware dialect).
    Printers,
    /// List the clay-body presets of `[clay] body = …` (density, yield stress, stiffening,
    /// stiffness, firing shrinkage).
    ClayBodies,
    /// Render the editor's view of a design to a PNG and exit (works under xvfb-run with Mesa).
    Screenshot {
        design: Option<PathBuf>,
        #[arg(short, long)]
        out: PathBuf,
        /// Put the replayed nozzle at this fraction (0–1) of the print.
        #[arg(long)]
        progress: Option<f64>,
        #[arg(long, default_value_t = 1280)]
        width: u32,
        #[arg(long, default_value_t = 720)]
        height: u32,
        /// Open the extruder-flow window and show its converged simulation.
        #[arg(long)]
        flow: bool,
    },
    /// Stream a G-code file to a printer (Marlin protocol) with a progress bar.
    Print {
        gcode: PathBuf,
        /// Serial port, e.g. /dev/ttyUSB0 (or the path `clayloft fake-printer` prints).
        #[arg(long)]
        port: String,
        #[arg(long, default_value_t = 115_200)]
        baud: u32,
        /// Seconds of silence before the printer is probed with M105.
        #[arg(long, default_value_t = 10.0)]
        timeout: f64,
    },
    /// Play a Marlin printer on a pseudo-terminal (prints its path), with injected faults.
    FakePrinter {
        /// Fraction of lines with a fault (0–0.5), spread over resends, corrupted bytes, lost oks,
        /// busy periods, slow replies and resends without ok.
        #[arg(long, default_value_t = 0.0)]
        faults: f64,
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Reboot (print `start`) after this many accepted commands.
        #[arg(long)]
        reset_after: Option<u64>,
        /// Make the port disappear after this many accepted commands.
        #[arg(long)]
        vanish_after: Option<u64>,
        /// Write every accepted command to this file when the host disconnects.
        #[arg(long)]
        log: Option<PathBuf>,
    },
    /// Simulate the clay in the extruder's screw groove (lattice Boltzmann) and write CSV + PNG.
    Flow(crate::flow::FlowOptions),
    /// Re-measure a G-code file against the printer limits (exit 0 = all hold, 1 = violations).
    Check {
        gcode: PathBuf,
        /// Take the limits from this design (default: the file's Clayloft header, else the paper's printer).
        #[arg(long)]
        design: Option<PathBuf>,
    },
}

/// A failure to report as one line, with its exit code.
pub struct Failure(pub String);

impl<E: std::fmt::Display> From<E> for Failure {
    fn from(e: E) -> Self {
        Failure(e.to_string())
    }
}

/// Output piped into a program that stops reading (`clayloft info | head`) ends the program
/// quietly, as command-line tools do, instead of a panic about a broken pipe.
fn quiet_on_broken_pipe() {
    let default = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let text = info
            .payload()
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| info.payload().downcast_ref::<&str>().copied())
            .unwrap_or("");
        if text.contains("failed printing to stdout") && text.contains("Broken pipe") {
            std::process::exit(0);
        }
        default(info)
    }));
}

/// A command that opens a window: the editor on a design, or a picture of its view (read by
/// `clayloft-editor`; `clayloft` passes its arguments on as they came).
pub enum Window {
    Editor(PathBuf),
    Screenshot {
        design: PathBuf,
        out: PathBuf,
        progress: Option<f64>,
        size: (u32, u32),
        flow: bool,
    },
}

/// Runs the command line; `open` runs the commands that open a window (their arguments
/// checked first).
pub fn main(open: fn(Window) -> Result<ExitCode, Failure>) -> ExitCode {
    quiet_on_broken_pipe();
    let cli = Cli::parse();
    if matches!(
        cli.command,
        Some(Command::Gcode { .. } | Command::Stl { .. } | Command::Check { .. })
    ) {
        clayloft_core::heap::tune_for_batch_command();
    }
    let result = match cli.command {
        Some(Command::Gcode {
            design,
            out,
            printer,
        }) => awake(|| gcode(&design, &out, printer.as_deref())),
        Some(Command::Stl {
            design,
            out,
            ascii,
            printer,
        }) => awake(|| stl(&design, &out, ascii, printer.as_deref())),
        Some(Command::Printers) => printers(),
        Some(Command::ClayBodies) => clay_bodies(),
        Some(Command::Check { gcode, design }) => awake(|| check(&gcode, design.as_deref())),
        Some(Command::Print {
            gcode,
            port,
            baud,
            timeout,
        }) => crate::printer::print(&gcode, &port, baud, timeout),
        Some(Command::FakePrinter {
            faults,
            seed,
            reset_after,
            vanish_after,
            log,
        }) => crate::printer::fake_printer(crate::printer::FakeOptions {
            faults,
            seed,
            reset_after,
            vanish_after,
            log,
        }),
        Some(Command::Flow(options)) => crate::flow::flow(options),
        Some(Command::Info { design, printer }) => {
            overview(&design.unwrap_or_else(default_design), printer.as_deref())
        }
        Some(Command::Screenshot {
            design,
            out,
            progress,
            width,
            height,
            flow,
        }) => screenshot_size(progress, (width, height)).and_then(|size| {
            open(Window::Screenshot {
                design: design.unwrap_or_else(default_design),
                out,
                progress,
                size,
                flow,
            })
        }),
        None => open(Window::Editor(cli.design.unwrap_or_else(default_design))),
    };
    match result {
        Ok(code) => code,
        Err(Failure(message)) => {
            eprintln!("error: {message}");
            ExitCode::from(2)
        }
    }
}

/// The default design: from the current folder when run in the repository, else from the source
/// tree this binary was built from.
pub fn default_design() -> PathBuf {
    let local = PathBuf::from(DEFAULT_DESIGN);
    if local.exists() {
        local
    } else {
        Path::new(env!("CARGO_MANIFEST_DIR")).join(DEFAULT_DESIGN)
    }
}

/// Loads a design and runs the pipeline, with errors located in the file.
pub fn job_of(path: &Path, printer: Option<&str>) -> Result<(LoadedDesign, PrintJob), Failure> {
    job_by(clayloft_core::run, path, printer)
}

/// The design at `path` (on `printer`, if named) and its job, computed by `run` (the whole
/// pipeline, or all of it but the verdict).
fn job_by(
    run: fn(&Design) -> Result<PrintJob, clayloft_core::validate::FieldError>,
    path: &Path,
    printer: Option<&str>,
) -> Result<(LoadedDesign, PrintJob), Failure> {
    let loaded = clayloft_core::load::load_design_using(path, printer)?;
    clayloft_core::heap::fault_ahead_for(&loaded.design);
    let job = run(&loaded.design).map_err(|e| loaded.locate(e))?;
    Ok((loaded, job))
}

/// `clayloft printers`: the shipped profiles, one line each.
fn printers() -> Result<ExitCode, Failure> {
    use clayloft_core::design::BedShape;
    println!(
        "{:<22} {:<40} {:<22} {:<7} {:<15} kinematics",
        "profile", "printer", "bed", "origin", "firmware"
    );
    for (name, text) in clayloft_core::profile::SHIPPED {
        let file = clayloft_core::profile::parse_shipped(name, text).map_err(Failure)?;
        let p = file.printer;
        let bed = match p.bed_shape {
            BedShape::Rectangle => format!("{} x {} x {} mm", p.bed_x, p.bed_y, p.max_z),
            BedShape::Circle => format!("round {} x {} mm", p.bed_x, p.max_z),
        };
        println!(
            "{name:<22} {:<40} {bed:<22} {:<7} {:<15} {}",
            file.name,
            p.origin.name(),
            p.dialect.title(),
            p.kinematics.name()
        );
    }
    Ok(ExitCode::SUCCESS)
}

fn clay_bodies() -> Result<ExitCode, Failure> {
    println!(
        "{:<12} {:>12} {:>12} {:>15} {:>12} {:>17}",
        "body", "wet density", "yield stress", "stiffening", "stiffness", "firing shrinkage"
    );
    for b in clayloft_core::clay::PRESETS {
        println!(
            "{:<12} {:>7.0} kg/m³ {:>9.1} kPa {:>10.2} Pa/s {:>8.0} kPa {:>16.1} %",
            b.name,
            b.wet_density,
            b.yield_stress / 1000.0,
            b.structuration_rate,
            b.elastic_modulus / 1000.0,
            b.firing_shrinkage_percent
        );
    }
    println!(
        "(printing consistency; where the numbers come from: crates/clayloft-core/src/clay.rs. Measure your paste with a fall cone: [clay] fall_cone_mm = depth)"
    );
    Ok(ExitCode::SUCCESS)
}

/// What `info` and `gcode` print about a job; `summary` is the writer's when it has run (the
/// same figures, without a second run of the motion planner).
fn print_summary(loaded: &LoadedDesign, job: &PrintJob, summary: Option<JobSummary>) {
    let d = &loaded.design;
    let s = summary.unwrap_or_else(|| summarize(d, job));
    let m = &job.surface.metrics;
    println!("design: {} ({})", d.name, loaded.path.display());
    if let Some(profile) = &d.printer.profile {
        println!("printer: {profile}");
    }
    println!(
        "layers: {} (pitch {:.3} mm), points: {}, path length: {:.1} mm",
        s.layers, job.surface.layer_pitch, s.points, s.path_length_mm
    );
    println!(
        "estimated time: {}, clay: {:.1} cm³",
        format_duration(s.estimated_time_s),
        s.volume_mm3 / 1000.0
    );
    println!(
        "max overhang: {:.1}° (limit {}°), max z range per layer: {:.2} mm (nozzle length {} mm), layer height {:.3} … {:.3} mm",
        m.max_overhang_deg,
        d.printer.max_overhang_deg,
        m.max_layer_z_range,
        d.printer.nozzle_length,
        m.min_layer_height,
        m.max_layer_height
    );
    if let Ok(body) = clayloft_core::clay::resolve(d.clay.as_ref()) {
        // The printed (wet) size: the path's, which may end above the design (a wall that
        // cannot come back onto its layers), and what the kiln makes of it.
        let (lo, hi) = s.path_bounds_mm;
        let wet = hi - lo;
        let wet = [wet.x, wet.y].map(|extent| extent + d.printer.line_width);
        let (sxy, sz) = (
            1.0 - body.firing_shrinkage_percent / 100.0,
            1.0 - body.firing_shrinkage_z_percent / 100.0,
        );
        let compensated = d.clay.as_ref().is_some_and(|c| c.compensate_shrinkage);
        println!(
            "size: {:.1} x {:.1} x {:.1} mm wet, {:.1} x {:.1} x {:.1} mm fired ({}, {} % shrinkage{})",
            wet[0],
            wet[1],
            hi.z,
            wet[0] * sxy,
            wet[1] * sxy,
            hi.z * sz,
            body.name,
            body.firing_shrinkage_percent,
            if compensated {
                ", printed enlarged to fire to the designed size"
            } else {
                ""
            }
        );
    }
    if let Some(p) = &job.verdict {
        println!("{}", p.summary());
        if let Some(w) = p.warning(d) {
            println!("{w}");
        }
        // Stretches of bead with nothing under them (at most a few lines: the worst first).
        for x in p.droops.iter().take(3) {
            println!("{}", x.summary(p.body.name));
        }
        if p.droops.len() > 3 {
            println!("droop: {} more layers", p.droops.len() - 3);
        }
    }
    let findings: Vec<_> = job.findings().collect();
    if findings.is_empty() {
        println!("corrections: none needed");
    } else {
        println!("corrections ({}):", findings.len());
        for f in findings {
            println!("  {f}");
        }
    }
}

fn gcode(design: &Path, out: &Path, printer: Option<&str>) -> Result<ExitCode, Failure> {
    // Started now, it waits for the file replaced (see `FreeingThread`).
    let freeing = FreeingThread::start();
    // The verdict on the print is left for the end (below).
    let (loaded, mut job) = job_by(clayloft_core::pipeline::run_unjudged, design, printer)?;
    // Right first time: the program is re-measured by the checker on its way to the disk, and
    // a design that still breaks a limit on this printer is refused with what broke.
    let written = write_checked_gcode(&loaded.design, &job, out).map_err(|e| match e {
        ExportError::Refused { .. } => Failure(format!("{}: {e}", loaded.path.display())),
        other => Failure(other.to_string()),
    })?;
    // The system frees the file replaced on a thread of its own, mostly waiting for the disk,
    // while the cores judge the print (or here, where no thread can be started).
    freeing.free(written.replaced);
    job.verdict = clayloft_core::pipeline::judge(&loaded.design, &job);
    print_summary(&loaded, &job, Some(written.summary));
    freeing.finish();
    if !written.unenforced.is_empty() {
        println!(
            "the checker finds in this G-code (constraints not enforced: written as designed):"
        );
        for v in &written.unenforced {
            println!("  {v}");
        }
    }
    println!("wrote {}", out.display());
    Ok(ExitCode::SUCCESS)
}

fn stl(design: &Path, out: &Path, ascii: bool, printer: Option<&str>) -> Result<ExitCode, Failure> {
    let (loaded, job) = job_of(design, printer)?;
    let d = &loaded.design;
    let mesh = job_mesh(d, &job);
    clayloft_core::atomic::write_atomically(out, |w| {
        if ascii {
            write_ascii_stl(&mesh, &d.name, w)
        } else {
            write_binary_stl(&mesh, &d.name, w)
        }
    })?;
    println!(
        "wrote {} ({} triangles, wall {} mm thick, {} base layers)",
        out.display(),
        mesh.triangles.len(),
        d.printer.line_width,
        d.shape.base_layers
    );
    Ok(ExitCode::SUCCESS)
}

fn check(path: &Path, design: Option<&Path>) -> Result<ExitCode, Failure> {
    let file = path.display();
    let bytes = std::fs::read(path).map_err(|e| {
        let reason = if e.kind() == std::io::ErrorKind::NotFound {
            "no such file".to_string()
        } else {
            e.to_string()
        };
        Failure(format!("{file}: cannot read: {reason}"))
    })?;
    let text =
        String::from_utf8(bytes).map_err(|_| Failure(format!("{file}: not a text G-code file")))?;
    let (limits, source) = match design {
        Some(d) => (
            Limits::from(&load_design(d)?.design.printer),
            format!("design {}", d.display()),
        ),
        None => match Limits::from_header(&text).map_err(|e| {
            Failure(format!(
                "{file}:{}: clayloft-limits header: {e}",
                e.line.unwrap_or(1)
            ))
        })? {
            Some((l, _)) => (l, "the file's header".to_string()),
            None => (
                Limits::from(&clayloft_core::design::Printer::default()),
                "the paper's printer (defaults)".to_string(),
            ),
        },
    };
    let report = check_gcode(&text, &limits).map_err(|e| Failure(format!("{file}: {e}")))?;
    println!("checking {file} against the limits of {source}");
    println!("{report}");
    Ok(if report.ok() {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    })
}

/// `clayloft info [DESIGN]`: what the design would print.
fn overview(design: &Path, printer: Option<&str>) -> Result<ExitCode, Failure> {
    let (loaded, job) = job_of(design, printer)?;
    print_summary(&loaded, &job, None);
    Ok(ExitCode::SUCCESS)
}

/// The picture's size for `clayloft screenshot`, once its arguments are known to be sound: the
/// replay's fraction within 0 … 1, each side 64 … 8192 pixels.
fn screenshot_size(
    progress: Option<f64>,
    (width, height): (u32, u32),
) -> Result<(u32, u32), Failure> {
    if let Some(f) = progress
        && !(0.0..=1.0).contains(&f)
    {
        return Err(Failure(format!("--progress {f}: must lie in 0 … 1")));
    }
    if !(64..=8192).contains(&width) || !(64..=8192).contains(&height) {
        return Err(Failure(format!(
            "{width} × {height}: the picture must be 64 … 8192 pixels each way"
        )));
    }
    Ok((width, height))
}
