//! `clayloft`: the command line (SPEC §7). Thin: every piece of work is a call into
//! `clayloft-core`; this file only parses arguments, prints summaries and maps errors to exit
//! codes (0 = done, 1 = check found violations, 2 = bad input).

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use clayloft_core::check::{Limits, check_gcode};
use clayloft_core::gcode::{format_duration, summarize, write_gcode};
use clayloft_core::stl::{wall_mesh, write_ascii_stl, write_binary_stl};
use clayloft_core::{LoadedDesign, PrintJob, load_design};

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
    /// Design file to open (default: the petal vase).
    design: Option<PathBuf>,
}

#[derive(Subcommand)]
enum Command {
    /// Turn a design into G-code and print a summary.
    Gcode {
        design: PathBuf,
        #[arg(short, long)]
        out: PathBuf,
    },
    /// Export the printed wall (thickness = line width, with the base) as a closed STL mesh.
    Stl {
        design: PathBuf,
        #[arg(short, long)]
        out: PathBuf,
        /// Write ASCII STL instead of binary.
        #[arg(long)]
        ascii: bool,
    },
    /// Re-measure a G-code file against the printer limits (exit 0 = all hold, 1 = violations).
    Check {
        gcode: PathBuf,
        /// Take the limits from this design (default: the file's Clayloft header, else the paper's printer).
        #[arg(long)]
        design: Option<PathBuf>,
    },
}

/// A failure to report as one line, with its exit code.
struct Failure(String);

impl<E: std::fmt::Display> From<E> for Failure {
    fn from(e: E) -> Self {
        Failure(e.to_string())
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Some(Command::Gcode { design, out }) => gcode(&design, &out),
        Some(Command::Stl { design, out, ascii }) => stl(&design, &out, ascii),
        Some(Command::Check { gcode, design }) => check(&gcode, design.as_deref()),
        None => overview(&cli.design.unwrap_or_else(default_design)),
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
fn default_design() -> PathBuf {
    let local = PathBuf::from(DEFAULT_DESIGN);
    if local.exists() {
        local
    } else {
        Path::new(env!("CARGO_MANIFEST_DIR")).join(DEFAULT_DESIGN)
    }
}

/// Loads a design and runs the pipeline, with errors located in the file.
fn job_of(path: &Path) -> Result<(LoadedDesign, PrintJob), Failure> {
    let loaded = load_design(path)?;
    let job = clayloft_core::run(&loaded.design).map_err(|e| loaded.locate(e))?;
    Ok((loaded, job))
}

fn print_summary(loaded: &LoadedDesign, job: &PrintJob) {
    let d = &loaded.design;
    let s = summarize(d, job);
    let m = &job.surface.metrics;
    println!("design: {} ({})", d.name, loaded.path.display());
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
    if job.surface.findings.is_empty() {
        println!("corrections: none needed");
    } else {
        println!("corrections ({}):", job.surface.findings.len());
        for f in &job.surface.findings {
            println!("  {f}");
        }
    }
}

fn gcode(design: &Path, out: &Path) -> Result<ExitCode, Failure> {
    let (loaded, job) = job_of(design)?;
    clayloft_core::atomic::write_atomically(out, |w| write_gcode(&loaded.design, &job, w))?;
    print_summary(&loaded, &job);
    println!("wrote {}", out.display());
    Ok(ExitCode::SUCCESS)
}

fn stl(design: &Path, out: &Path, ascii: bool) -> Result<ExitCode, Failure> {
    let (loaded, job) = job_of(design)?;
    let d = &loaded.design;
    let mesh = wall_mesh(&job.surface, d.printer.line_width, d.shape.base_layers);
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
        None => match Limits::from_header(&text) {
            Some(l) => (l, "the file's header".to_string()),
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

/// `clayloft [DESIGN]`: the interactive application is not built yet (see the README); until it
/// is, show what the design would print.
fn overview(design: &Path) -> Result<ExitCode, Failure> {
    let (loaded, job) = job_of(design)?;
    print_summary(&loaded, &job);
    println!("(the interactive 3D editor is not built yet; `clayloft gcode` writes the print)");
    Ok(ExitCode::SUCCESS)
}
