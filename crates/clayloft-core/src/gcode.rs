//! G-code (SPEC §5, §12): plain ASCII, one command per line, deterministic, in the printer's
//! own frame, between the dialect's (or the profile's) start and end G-code.
//!
//! Extrusion per segment: `V = line_width × thickness × length_xy × flow`, and
//! `E = V / (π·feed_diameter²/4) × flow_multiplier`. Thickness is the local layer height of the
//! segment's end point (its z minus the z one revolution below), so extrusion follows the
//! changing layer height of the spiral. Numbers are formatted with fixed decimals by integer
//! arithmetic: writing is I/O-bound, not formatting-bound.

use std::io::{self, Write};

use glam::DVec3;

use crate::decimal::Line;
pub use crate::decimal::put_fixed;

/// Decimals of the moves' X, Y and Z (a micrometre): what the printer is told, and what the
/// self-check measures.
pub const XYZ_DECIMALS: u32 = 3;
use crate::design::{BedShape, Design, Dialect, ExtrusionMode, Kinematics, Origin};
use crate::motion;
use crate::pipeline::PrintJob;
use crate::templates::Values;
use crate::toolpath::Toolpath;

/// Height above the first and last point for the approach and exit moves, mm.
pub const CLEARANCE: f64 = 10.0;

/// Key of the header line that carries the printer limits for `clayloft check`.
pub const LIMITS_KEY: &str = "; clayloft-limits:";

/// Where a program goes as it is written: its text and, for a reader of moves that wants them
/// (the self-check of `clayloft gcode`), each piece of the path's body with the moves its
/// lines read as, so that the reader need not read that text again.
pub(crate) trait ProgramOut {
    /// Text outside the body (header, start G-code, approach, exit, end G-code).
    fn text(&mut self, bytes: &[u8]) -> io::Result<()>;
    /// Whether the body's pieces should come with their moves.
    fn wants_moves(&self) -> bool {
        false
    }
    /// Pieces of the body in order, each with its moves where told.
    fn body(&mut self, pieces: &[crate::check::ToldPiece<'_>]) -> io::Result<()> {
        pieces.iter().try_for_each(|p| self.text(p.text))
    }

    /// Runs `body` with a sink that takes the body's pieces as they are formatted, on the
    /// threads that format them, where this output has one (`moves`: how many moves the
    /// pieces hold); none, with `body` not run, where the pieces must come in order through
    /// [`ProgramOut::body`].
    fn with_sink(
        &mut self,
        moves: usize,
        body: &mut dyn FnMut(&dyn PieceSink) -> io::Result<()>,
    ) -> Option<io::Result<()>> {
        let _ = (moves, body);
        None
    }
}

/// Where the body's pieces go as they are formatted ([`ProgramOut::with_sink`]).
pub(crate) trait PieceSink: Sync {
    /// Takes piece `k` of the body, once it waits for the pieces before it to be placed: each
    /// of 0, 1, 2 … once, from any thread, a thread that takes several taking them in order.
    fn take(&self, k: usize, piece: &crate::check::ToldPiece<'_>) -> io::Result<()>;
    /// Stops every wait for a piece: some piece will never come.
    fn abandon(&self);
}

impl<W: Write + ?Sized> ProgramOut for W {
    fn text(&mut self, bytes: &[u8]) -> io::Result<()> {
        self.write_all(bytes)
    }
}

/// Summary of a written (or writable) job.
#[derive(Debug, Clone, PartialEq)]
pub struct JobSummary {
    pub layers: usize,
    pub points: usize,
    pub path_length_mm: f64,
    /// Estimated time including approach and exit, s, planned as firmware plans the moves
    /// ([`crate::motion`]: the printer's acceleration and cornering limit).
    pub estimated_time_s: f64,
    /// Extruded volume, mm³.
    pub volume_mm3: f64,
    /// Length of "filament" the extruder advances (the sum of E), mm.
    pub e_length_mm: f64,
    /// The box of the path's points, its lowest and its highest corner, mm (the wet size of
    /// the vessel as printed; infinite for a path without points).
    pub path_bounds_mm: (DVec3, DVec3),
}

/// Approach and exit moves: (approach start height, exit height).
fn clearance_heights(design: &Design, tp: &Toolpath) -> (f64, f64) {
    let first = tp.points.first().map_or(0.0, |p| p.pos.z);
    let last = tp.points.last().map_or(0.0, |p| p.pos.z);
    let max_z = design.printer.max_z;
    (
        (first + CLEARANCE).min(max_z),
        (last + CLEARANCE).min(max_z),
    )
}

/// Extruded volume of the segment ending at point `i` (i ≥ 1), mm³.
#[inline]
fn segment_volume(design: &Design, tp: &Toolpath, i: usize) -> f64 {
    let (a, b) = (&tp.points[i - 1], &tp.points[i]);
    let len = a.pos.truncate().distance(b.pos.truncate());
    design.printer.line_width * b.thickness.max(0.0) * len * b.flow
}

/// Cross-section of the feed (the "filament" E counts), mm²: π·d²/4.
fn feed_area(p: &crate::design::Printer) -> f64 {
    std::f64::consts::PI * p.feed_diameter * p.feed_diameter / 4.0
}

/// E advanced per mm³ of clay extruded: the flow multiplier over the feed's cross-section.
fn e_per_mm3(p: &crate::design::Printer) -> f64 {
    p.flow_multiplier / feed_area(p)
}

/// Where the nozzle is when the start G-code has homed, in the bed frame: a delta at the top
/// of its column over the centre, other printers at the origin corner.
fn home_position(p: &crate::design::Printer) -> DVec3 {
    match p.kinematics {
        Kinematics::Delta => DVec3::new(p.bed_x / 2.0, p.bed_y / 2.0, p.max_z),
        _ => DVec3::ZERO,
    }
}

/// The moves of the whole job as the motion planner sees them, from the home position: the
/// approach (up, over, down), the path, the exit lift.
struct JobMoves<'a> {
    home: DVec3,
    approach: Vec<motion::Move>,
    path: &'a [crate::toolpath::PathPoint],
    exit: Option<motion::Move>,
}

impl<'a> JobMoves<'a> {
    fn new(design: &Design, tp: &'a Toolpath) -> Self {
        let p = &design.printer;
        let (z_in, z_out) = clearance_heights(design, tp);
        let home = home_position(p);
        let travel = p.travel_speed;
        let at = |to: DVec3| motion::Move { to, speed: travel };
        let (approach, exit) = match (tp.points.first(), tp.points.last()) {
            (Some(f), Some(l)) => (
                vec![
                    at(DVec3::new(home.x, home.y, z_in)),
                    at(DVec3::new(f.pos.x, f.pos.y, z_in)),
                    at(f.pos),
                ],
                Some(at(DVec3::new(l.pos.x, l.pos.y, z_out))),
            ),
            _ => (Vec::new(), None),
        };
        Self {
            home,
            approach,
            path: tp.points.get(1..).unwrap_or(&[]),
            exit,
        }
    }
}

impl motion::Moves for JobMoves<'_> {
    fn len(&self) -> usize {
        self.approach.len() + self.path.len() + usize::from(self.exit.is_some())
    }

    fn get(&self, i: usize) -> motion::Move {
        let Some(k) = i.checked_sub(self.approach.len()) else {
            return self.approach[i];
        };
        match self.path.get(k) {
            Some(q) => motion::Move {
                to: q.pos,
                speed: q.speed,
            },
            None => self.exit.expect("an index below len()"),
        }
    }
}

/// Length, time and volume of a job.
pub fn summarize(design: &Design, job: &PrintJob) -> JobSummary {
    summarize_beside(design, job, false, || ()).0
}

/// [`summarize`], with `beside` (the writer's thumbnails) run on a second core (when
/// `use_beside` and one is free) while this one sums the path in one pass ([`PathSums`], each
/// segment's time and volume worked out on both cores first) and runs the motion planner's
/// look-ahead passes (its entry limits use both cores first); with the path's sums. For the
/// benchmark vase the thumbnails and the estimate took 9.3 ms with the thumbnails beside the
/// whole planner, 6 ms so; the path's sums (its length, time, volume and box, and each body
/// chunk's start) were five passes, one of them after `beside`, before they were one.
fn summarize_beside<T: Send>(
    design: &Design,
    job: &PrintJob,
    use_beside: bool,
    beside: impl FnOnce() -> T + Send,
) -> (JobSummary, PathSums, T) {
    let p = &design.printer;
    let tp = &job.toolpath;
    let moves = JobMoves::new(design, tp);
    let plan = motion::Plan::new(moves.home, &moves, p.max_acceleration, p.junction_deviation);
    // The path's segments are the planner's moves after the approach.
    let a = moves.approach.len();
    let path_segments = a..a + tp.points.len().saturating_sub(1);
    // Each segment's time and volume on both cores, then what is summed in path order on
    // this one while the other draws the thumbnails.
    let steps = PathSums::steps(design, tp, plan.lengths().get(path_segments.clone()));
    let (other, (time, sums)) = crate::parallel::both(use_beside, beside, || {
        let sums = PathSums::of_steps(design, tp, plan.lengths().get(path_segments), steps);
        (plan.time(), sums)
    });
    let summary = JobSummary {
        layers: job.surface.layers,
        points: tp.points.len(),
        path_length_mm: sums.length,
        estimated_time_s: time,
        volume_mm3: sums.volume,
        e_length_mm: sums.volume * p.flow_multiplier / feed_area(p),
        path_bounds_mm: sums.bounds,
    };
    (summary, sums, other)
}

/// `1h 02m 03s` style duration.
pub fn format_duration(seconds: f64) -> String {
    let s = seconds.max(0.0).round() as u64;
    let (h, m, s) = (s / 3600, (s / 60) % 60, s % 60);
    if h > 0 {
        format!("{h}h {m:02}m {s:02}s")
    } else {
        format!("{m}m {s:02}s")
    }
}

/// PrusaSlicer's duration form (`1h 2m 3s`, `4m 5s`), which its G-code viewer reads back.
fn prusa_duration(seconds: f64) -> String {
    let s = seconds.max(0.0).round() as u64;
    let (d, h, m, s) = (s / 86_400, (s / 3600) % 24, (s / 60) % 60, s % 60);
    match (d, h, m) {
        (0, 0, 0) => format!("{s}s"),
        (0, 0, _) => format!("{m}m {s}s"),
        (0, _, _) => format!("{h}h {m}m {s}s"),
        _ => format!("{d}d {h}h {m}m {s}s"),
    }
}

/// Why a job cannot be written as G-code (a template that cannot be filled).
#[derive(Debug, thiserror::Error)]
pub enum GcodeWriteError {
    #[error("{field}: {error}")]
    Template {
        field: &'static str,
        error: crate::templates::TemplateError,
    },
    #[error(transparent)]
    Io(#[from] io::Error),
}

impl From<GcodeWriteError> for io::Error {
    fn from(e: GcodeWriteError) -> io::Error {
        match e {
            GcodeWriteError::Io(e) => e,
            other => io::Error::new(io::ErrorKind::InvalidInput, other.to_string()),
        }
    }
}

/// The placeholder values of a job's templates, in the printer's own coordinates (the top of
/// the path from the summary's box).
pub fn template_values(design: &Design, job: &PrintJob, summary: &JobSummary) -> Values {
    let p = &design.printer;
    let tp = &job.toolpath;
    let [ox, oy] = p.origin_offset();
    let (first, last) = match (tp.points.first(), tp.points.last()) {
        (Some(f), Some(l)) => (f.pos, l.pos),
        _ => (DVec3::ZERO, DVec3::ZERO),
    };
    let top = summary.path_bounds_mm.1.z.max(0.0);
    let park_z = (top + CLEARANCE).min(p.max_z);
    // Present the part: the back of the bed comes forward on a bed slinger, the head goes
    // to the back on a gantry; the back left corner suits both (the back edge of a round bed).
    let (park_x, park_y) = match p.bed_shape {
        BedShape::Rectangle => (0.0 - ox, p.bed_y - oy),
        BedShape::Circle => (p.bed_x / 2.0 - ox, p.bed_y - oy),
    };
    let f3 = |v: f64| {
        let mut b = Vec::new();
        put_fixed(&mut b, v, 3);
        String::from_utf8(b).unwrap_or_default()
    };
    vec![
        ("bed_x", f3(p.bed_x)),
        ("bed_y", f3(p.bed_y)),
        ("max_z", f3(p.max_z)),
        ("first_x", f3(first.x - ox)),
        ("first_y", f3(first.y - oy)),
        ("first_z", f3(first.z)),
        ("last_z", f3(last.z)),
        ("top_z", f3(top)),
        ("park_z", f3(park_z)),
        ("park_x", f3(park_x)),
        ("park_y", f3(park_y)),
        ("layer_height", f3(p.layer_height)),
        ("line_width", f3(p.line_width)),
        ("nozzle_diameter", f3(p.nozzle_diameter)),
        ("layers", summary.layers.to_string()),
        ("print_time_s", format!("{:.0}", summary.estimated_time_s)),
        ("print_time", format_duration(summary.estimated_time_s)),
        (
            "clay_volume_cm3",
            format!("{:.1}", summary.volume_mm3 / 1000.0),
        ),
        (
            "design_name",
            design.name.replace(['\n', '\r', '{', '}'], " "),
        ),
        ("e_mode", p.extrusion.gcode().into()),
        ("travel_feed", format!("{:.0}", p.travel_speed * 60.0)),
    ]
}

/// Writes the whole G-code program of a job: header (settings, host metadata, thumbnails),
/// start G-code, approach, the one continuous path (with progress and layer messages), exit,
/// end G-code. Coordinates are in the printer's own frame (SPEC §12).
pub fn write_gcode(design: &Design, job: &PrintJob, out: &mut dyn Write) -> io::Result<()> {
    write_gcode_summarized(design, job, out).map(|_| ())
}

/// [`write_gcode`], returning the figures of its header (the same as [`summarize`] gives): a
/// caller that reports them needs no second run of the motion planner.
pub fn write_gcode_summarized(
    design: &Design,
    job: &PrintJob,
    out: &mut dyn Write,
) -> io::Result<JobSummary> {
    write_program(design, job, out).map_err(io::Error::from)
}

/// [`write_gcode_summarized`] with its errors kept apart (a template that cannot be filled names
/// its field).
pub fn write_program(
    design: &Design,
    job: &PrintJob,
    mut out: &mut dyn Write,
) -> Result<JobSummary, GcodeWriteError> {
    write_program_indexed(design, job, &mut out, None)
}

/// [`write_program`] to a [`ProgramOut`], which may take the body's moves as told.
pub(crate) fn write_program_to(
    design: &Design,
    job: &PrintJob,
    out: &mut dyn ProgramOut,
) -> Result<JobSummary, GcodeWriteError> {
    write_program_indexed(design, job, out, None)
}

/// A whole G-code program in memory, with the path point each line belongs to: what a printer
/// host streams and shows (the nozzle at the line being printed) without reading the G-code back.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Program {
    pub text: String,
    /// `point_of_line[j]`: index (into the job's toolpath points) of the point the nozzle has
    /// reached once text line j has run: 0 up to and including the approach, the point a `G1`
    /// moves to, the last point from the exit on.
    pub point_of_line: Vec<u32>,
}

/// The program of a job, with its line → path point index (see [`Program`]).
pub fn program(design: &Design, job: &PrintJob) -> Result<Program, GcodeWriteError> {
    let mut bytes = Vec::new();
    let mut index = Vec::new();
    write_program_indexed(design, job, &mut bytes, Some(&mut index))?;
    let text = String::from_utf8(bytes).map_err(|e| {
        GcodeWriteError::Io(io::Error::new(io::ErrorKind::InvalidData, e.to_string()))
    })?;
    // The exit, the end G-code and the closing comment: the path is done.
    let last = job.toolpath.points.len().saturating_sub(1) as u32;
    index.resize(text.lines().count(), last);
    Ok(Program {
        text,
        point_of_line: index,
    })
}

/// What a printer host sends when this job is cancelled, in place of the rest of it:
/// `printer.cancel_gcode`, or else the end G-code (stop extruding, lift clear of the rim, park),
/// filled with the job's values (the park height clears the whole vessel).
pub fn cancel_gcode(design: &Design, job: &PrintJob) -> Result<String, GcodeWriteError> {
    let p = &design.printer;
    let values = template_values(design, job, &summarize(design, job));
    let (field, template) = match p.cancel_gcode.as_deref() {
        Some(t) => ("printer.cancel_gcode", t),
        None => (
            "printer.end_gcode",
            p.end_gcode
                .as_deref()
                .unwrap_or(crate::templates::default_end(p)),
        ),
    };
    crate::templates::fill(template, &values)
        .map_err(|error| GcodeWriteError::Template { field, error })
}

/// Records `lines` text lines, each at path point `point`, when an index is kept.
#[inline]
fn mark(index: &mut Option<&mut Vec<u32>>, lines: usize, point: usize) {
    if let Some(v) = index {
        v.extend(std::iter::repeat_n(point as u32, lines));
    }
}

/// [`write_program`], optionally recording each line's path point into `index`.
fn write_program_indexed(
    design: &Design,
    job: &PrintJob,
    out: &mut dyn ProgramOut,
    mut index: Option<&mut Vec<u32>>,
) -> Result<JobSummary, GcodeWriteError> {
    let p = &design.printer;
    let tp = &job.toolpath;
    // The thumbnails are drawn beside the path's sums and the motion planner's passes.
    let layers_total = tp.layer_starts.len().max(1);
    let (summary, sums, thumbnails) = summarize_beside(design, job, true, || {
        p.thumbnail.then(|| {
            // Thinned to what a thumbnail draws: no copy of the whole path.
            let step = (tp.points.len() / crate::thumbnail::MAX_DRAWN).max(1);
            let points: Vec<DVec3> = tp.points.iter().step_by(step).map(|q| q.pos).collect();
            crate::thumbnail::header_blocks(&points)
        })
    });
    let body = BodyWriter::new(design, tp, &sums, summary.estimated_time_s, layers_total);
    let starts = body.chunk_starts(&sums);
    let values = template_values(design, job, &summary);
    let fill = |field: &'static str, t: &str| {
        crate::templates::fill(t, &values)
            .map_err(|error| GcodeWriteError::Template { field, error })
    };
    let start = fill(
        "printer.start_gcode",
        p.start_gcode
            .as_deref()
            .unwrap_or(crate::templates::default_start(p)),
    )?;
    let end = fill(
        "printer.end_gcode",
        p.end_gcode
            .as_deref()
            .unwrap_or(crate::templates::default_end(p)),
    )?;
    let mut head = String::new();
    use std::fmt::Write as _;
    let _ = writeln!(
        head,
        "; Clayloft {} — one continuous spiral for clay paste extrusion",
        env!("CARGO_PKG_VERSION")
    );
    let _ = writeln!(head, "; design: {}", design.name.replace(['\n', '\r'], " "));
    let _ = writeln!(
        head,
        "; printer: {}, {} bed {}, origin {}, {} firmware",
        p.profile
            .as_deref()
            .unwrap_or("the paper's printer (defaults)"),
        match p.bed_shape {
            BedShape::Rectangle => "rectangular",
            BedShape::Circle => "round",
        },
        match p.bed_shape {
            BedShape::Rectangle => format!("{} x {} mm", p.bed_x, p.bed_y),
            BedShape::Circle => format!("{} mm across", p.bed_x),
        },
        match p.origin {
            Origin::Corner => "at the front left corner",
            Origin::Centre => "at the bed centre",
        },
        p.dialect.title()
    );
    let _ = writeln!(
        head,
        "; layers: {} (pitch {:.3} mm), points: {}, path length: {:.1} mm, clay volume: {:.1} cm3",
        summary.layers,
        job.surface.layer_pitch,
        summary.points,
        summary.path_length_mm,
        summary.volume_mm3 / 1000.0
    );
    let _ = writeln!(
        head,
        "; estimated time: {} ({:.0} s, acceleration {} mm/s2, junction deviation {} mm)",
        format_duration(summary.estimated_time_s),
        summary.estimated_time_s,
        p.max_acceleration,
        p.junction_deviation
    );
    let _ = writeln!(
        head,
        "; settings: nozzle {} mm, line width {} mm, layer height {} mm ({} .. {}), speed {} mm/s, feed diameter {} mm, flow x{}, {} E, min layer time {} s",
        p.nozzle_diameter,
        p.line_width,
        p.layer_height,
        p.min_layer_height,
        p.max_layer_height,
        p.print_speed,
        p.feed_diameter,
        p.flow_multiplier,
        match p.extrusion {
            ExtrusionMode::Relative => "relative",
            ExtrusionMode::Absolute => "absolute",
        },
        p.min_layer_time
    );
    let _ = writeln!(
        head,
        "{LIMITS_KEY} bed_x={} bed_y={} max_z={} line_width={} min_layer_height={} max_layer_height={} nozzle_length={} max_overhang_deg={} bed_shape={} origin={}",
        p.bed_x,
        p.bed_y,
        p.max_z,
        p.line_width,
        p.min_layer_height,
        p.max_layer_height,
        p.nozzle_length,
        p.max_overhang_deg,
        p.bed_shape.name(),
        p.origin.name()
    );
    for f in &job.surface.findings {
        let _ = writeln!(head, "; {f}");
    }
    if p.host_metadata {
        // The forms printer hosts read: Cura's (`;TIME:`, `;LAYER:`: OctoPrint's plugins, printer
        // screens) and PrusaSlicer's (its G-code viewer). Moonraker reads these only from the
        // slicers it identifies (metadata.py SUPPORTED_SLICERS), not from Clayloft; Mainsail and
        // Fluidd get the layers from SET_PRINT_STATS_INFO (Klipper dialect) and progress from M73.
        let _ = writeln!(
            head,
            ";FLAVOR:{}",
            match p.dialect {
                Dialect::Marlin => "Marlin",
                Dialect::Klipper => "Klipper",
                Dialect::RepRapFirmware => "RepRap",
            }
        );
        let _ = writeln!(head, ";TIME:{:.0}", summary.estimated_time_s);
        let _ = writeln!(head, ";Filament used: {:.5}m", summary.e_length_mm / 1000.0);
        let _ = writeln!(head, ";Layer height: {}", p.layer_height);
        let _ = writeln!(head, ";LAYER_COUNT:{layers_total}");
        let _ = writeln!(
            head,
            "; estimated printing time (normal mode) = {}",
            prusa_duration(summary.estimated_time_s)
        );
        let _ = writeln!(head, "; filament used [mm] = {:.2}", summary.e_length_mm);
        let _ = writeln!(
            head,
            "; filament used [cm3] = {:.2}",
            summary.volume_mm3 / 1000.0
        );
        let _ = writeln!(head, "; total layers count = {layers_total}");
    }
    if let Some(blocks) = thumbnails {
        head.push_str(&blocks);
    }
    head.push_str(&start);
    if !start.ends_with('\n') {
        head.push('\n');
    }
    // Whatever a custom start G-code does, the path needs absolute positions and its E mode.
    let _ = writeln!(
        head,
        "G90\n{}\nG92 E0 ; positions and E as the path needs them",
        p.extrusion.gcode()
    );
    out.text(head.as_bytes())?;
    mark(&mut index, head.matches('\n').count(), 0);

    let [ox, oy] = p.origin_offset();
    let mut buf: Vec<u8> = Vec::with_capacity(1 << 16);
    let put_xy = |buf: &mut Vec<u8>, q: DVec3| {
        buf.extend_from_slice(b"X");
        put_fixed(buf, q.x - ox, 3);
        buf.extend_from_slice(b" Y");
        put_fixed(buf, q.y - oy, 3);
    };
    let (z_in, z_out) = clearance_heights(design, tp);
    let travel_f = p.travel_speed * 60.0;
    if let Some(first) = tp.points.first() {
        buf.extend_from_slice(b"G0 Z");
        put_fixed(&mut buf, z_in, 3);
        buf.extend_from_slice(b" F");
        put_fixed(&mut buf, travel_f, 0);
        buf.extend_from_slice(b" ; approach\nG0 ");
        put_xy(&mut buf, first.pos);
        buf.extend_from_slice(b"\nG0 Z");
        put_fixed(&mut buf, first.pos.z, 3);
        buf.push(b'\n');
        mark(&mut index, 3, 0);
    }
    out.text(&buf)?;
    buf.clear();
    body.write(out, &mut index, &starts)?;
    if !tp.points.is_empty() {
        buf.extend_from_slice(b"G0 Z");
        put_fixed(&mut buf, z_out, 3);
        buf.extend_from_slice(b" F");
        put_fixed(&mut buf, travel_f, 0);
        buf.extend_from_slice(b" ; exit\n");
    }
    if p.progress {
        buf.extend_from_slice(b"M73 P100 R0\n");
    }
    buf.extend_from_slice(end.as_bytes());
    if !end.ends_with('\n') {
        buf.push(b'\n');
    }
    buf.extend_from_slice(b"; end\n");
    out.text(&buf)?;
    Ok(summary)
}

/// Points formatted per chunk: [`ROUND_CHUNKS`] chunks at a time go to the cores, then to the
/// output. About 150 kB of text each, so that the text in memory stays small whatever the path
/// length (`clayloft gcode` never holds a whole program: it goes to the file and the self-check
/// piece by piece); with 128 Ki points a chunk, a whole process took 6 000 more page faults.
const BODY_CHUNK: usize = 4 * 1024;

/// Chunks formatted at a time, shared out over the cores as they get free (a core slowed by
/// another thread on it takes fewer), for an output that takes the body in rounds (an output
/// with a [`PieceSink`], `clayloft gcode`'s, takes each chunk as it is formatted): four a core
/// of this machine. A round's last chunks leave
/// a core idle while the other finishes; rounds of eight chunks of 4 Ki points left the helper
/// idle beside the formatting a quarter as long as rounds of four of 8 Ki points (0.4 against
/// 1.6 ms a run of the benchmark vase, `perf record`, 30 runs, 2026-12-06).
const ROUND_CHUNKS: usize = 8;

/// The path's sums, in one pass in path order: its length and its time at its own speeds (the
/// planner's moves' sums, to the bit), the clay's volume, its box, and where the
/// body's running sums stand at each chunk's start.
struct PathSums {
    /// Σ |p_i − p_{i−1}|, mm.
    length: f64,
    /// Σ |p_i − p_{i−1}| / v_i, s ([`Toolpath::print_time`]).
    nominal_s: f64,
    /// Σ of each segment's volume, mm³.
    volume: f64,
    /// The box of the path's points: its lowest and its highest corner.
    bounds: (DVec3, DVec3),
    /// The state before each chunk of [`BODY_CHUNK`] points (the first at point 1), without
    /// its progress percent, which needs the whole time: ...
    starts: Vec<BodyState>,
    /// ... the time done before the chunk's last point was written, whose percent it is.
    percent_times: Vec<Option<f64>>,
    /// Each segment's time at its point's speed, s, and E (relative), as the body's writer
    /// adds them: `steps[i − 1]` for the segment to point i.
    steps: Vec<(f64, f64)>,
}

impl PathSums {
    /// [`PathSums::of_steps`] of [`PathSums::steps`]: the whole sums in one call (the tests').
    #[cfg(test)]
    fn of(design: &Design, tp: &Toolpath, segments: Option<&[f64]>) -> PathSums {
        let steps = Self::steps(design, tp, segments);
        Self::of_steps(design, tp, segments, steps)
    }

    /// Each segment's time at its point's speed and its volume, `(dt, volume)` for the
    /// segment to point i at i − 1: what [`PathSums::of_steps`] sums, on every core for a long
    /// path (each value depends on its segment alone, so the sums in path order stay the same
    /// to the bit). For the benchmark vase a third of the sums' time, which the thumbnails'
    /// core then waited for.
    fn steps(design: &Design, tp: &Toolpath, segments: Option<&[f64]>) -> Vec<(f64, f64)> {
        let points = &tp.points;
        let count = points.len().saturating_sub(1);
        let mut steps = Vec::with_capacity(count);
        crate::parallel::for_each_part(
            &mut steps.spare_capacity_mut()[..count],
            crate::parallel::PARALLEL_POINTS,
            |offset, part| {
                for (i, step) in (offset + 1..).zip(part) {
                    let d = match segments {
                        Some(lengths) => lengths[i - 1],
                        None => points[i - 1].pos.distance(points[i].pos),
                    };
                    step.write((d / points[i].speed, segment_volume(design, tp, i)));
                }
            },
        );
        // SAFETY: the parts cover the room's `count` places, and each part writes each of its
        // places above.
        unsafe { steps.set_len(count) };
        steps
    }

    /// The sums of `tp`'s points from their `steps` ([`PathSums::steps`]), each added in path
    /// order as the body's writer adds them; `segments[i − 1]` is `|p_i − p_{i−1}|` where given
    /// (the planner's, the same to the bit: the difference's coordinates are the same up to
    /// their signs), else measured here.
    fn of_steps(
        design: &Design,
        tp: &Toolpath,
        segments: Option<&[f64]>,
        mut steps: Vec<(f64, f64)>,
    ) -> PathSums {
        let p = &design.printer;
        let e_per_mm3 = e_per_mm3(p);
        let absolute = p.extrusion == ExtrusionMode::Absolute;
        let points = &tp.points;
        let n = points.len();
        let mut st = BodyState::START;
        let (mut length, mut volume) = (0.0, 0.0);
        let (mut lo, mut hi) = points
            .first()
            .map_or((DVec3::INFINITY, DVec3::NEG_INFINITY), |q| (q.pos, q.pos));
        let mut starts = vec![BodyState::START];
        let mut percent_times = vec![None];
        let mut percent_before = None;
        for i in 1..n {
            let q = &points[i];
            if (i - 1) % BODY_CHUNK == 0 && i > 1 {
                starts.push(st);
                percent_times.push(percent_before);
            }
            percent_before = Some(st.t_done);
            let d = match segments {
                Some(lengths) => lengths[i - 1],
                None => points[i - 1].pos.distance(q.pos),
            };
            length += d;
            let (dt, v) = steps[i - 1];
            st.t_done += dt;
            volume += v;
            let e = v * e_per_mm3;
            if absolute {
                st.e_total += e;
            }
            // The segment's E in place of its volume.
            steps[i - 1].1 = e;
            (lo, hi) = (lo.min(q.pos), hi.max(q.pos));
            st.last_speed = q.speed;
            while st.next_layer < tp.layer_starts.len() && tp.layer_starts[st.next_layer] <= i {
                st.next_layer += 1;
            }
        }
        PathSums {
            length,
            nominal_s: st.t_done,
            volume,
            bounds: (lo, hi),
            starts,
            percent_times,
            steps,
        }
    }
}

/// Where the body's running sums stand just before path point `i` is written.
#[derive(Debug, Clone, Copy)]
struct BodyState {
    /// Print time at nominal speeds up to point i − 1, s.
    t_done: f64,
    /// Cumulative E up to point i − 1 (absolute mode).
    e_total: f64,
    /// Feed rate last written (NaN before the first).
    last_speed: f64,
    /// Progress percent last written (`u64::MAX` before the first).
    last_percent: u64,
    /// Next entry of `layer_starts` to announce.
    next_layer: usize,
}

impl BodyState {
    /// Before the first point.
    const START: BodyState = BodyState {
        t_done: 0.0,
        e_total: 0.0,
        last_speed: f64::NAN,
        last_percent: u64::MAX,
        next_layer: 0,
    };
}

/// The path part of the program: one `G1` per point with its E and, where they change, the
/// feed rate, the layer messages and the M73 progress. Chunks of points are formatted on both
/// cores; the running sums are carried from chunk to chunk in the order the sequential loop adds
/// them, so the text is byte for byte the same as written on one core.
struct BodyWriter<'a> {
    design: &'a Design,
    tp: &'a Toolpath,
    origin: [f64; 2],
    /// Print time at nominal speeds (the M73 percentages are of it), s.
    nominal: f64,
    /// Planned over nominal time: M73's minutes left count down to the planned end.
    scale: f64,
    layers_total: usize,
    /// Each segment's time and E ([`PathSums::steps`]).
    steps: &'a [(f64, f64)],
}

impl<'a> BodyWriter<'a> {
    /// The writer of `tp`'s body from its `sums` (its print time at the points' speeds,
    /// [`Toolpath::print_time`], and each segment's time and E), planned to take `planned_s`.
    fn new(
        design: &'a Design,
        tp: &'a Toolpath,
        sums: &'a PathSums,
        planned_s: f64,
        layers_total: usize,
    ) -> Self {
        let p = &design.printer;
        let nominal = sums.nominal_s.max(1e-9);
        BodyWriter {
            design,
            tp,
            origin: p.origin_offset(),
            nominal,
            scale: planned_s / nominal,
            layers_total,
            steps: &sums.steps,
        }
    }

    /// The whole percent of the nominal time done by `t_done`, 0 … 100.
    fn percent(&self, t_done: f64) -> u64 {
        percent_done(t_done, self.nominal)
    }

    /// See [`time_below_next_percent`].
    fn percent_below(&self, percent: u64) -> f64 {
        time_below_next_percent(percent, self.nominal)
    }

    /// Where each chunk of [`BODY_CHUNK`] points starts (the first at point 1): the states
    /// `sums` reached, each with the progress percent last written before it.
    fn chunk_starts(&self, sums: &PathSums) -> Vec<BodyState> {
        let progress = self.design.printer.progress;
        sums.starts
            .iter()
            .zip(&sums.percent_times)
            .map(|(&st, &t)| BodyState {
                last_percent: match t {
                    Some(t) if progress => self.percent(t),
                    _ => st.last_percent,
                },
                ..st
            })
            .collect()
    }

    /// Writes points 1 .. n, [`ROUND_CHUNKS`] chunks a round: a round's chunks are formatted
    /// by whichever core is free (each from its start, `starts[k]` for chunk k, see
    /// [`BodyWriter::chunk_starts`]), then handed over in order.
    fn write(
        &self,
        out: &mut dyn ProgramOut,
        index: &mut Option<&mut Vec<u32>>,
        starts: &[BodyState],
    ) -> io::Result<()> {
        let n = self.tp.points.len();
        if n < 2 {
            return Ok(());
        }
        let want = Wanted {
            index: index.is_some(),
            moves: out.wants_moves(),
        };
        let chunk = |k: usize| 1 + k * BODY_CHUNK..(1 + (k + 1) * BODY_CHUNK).min(n);
        // Each chunk goes from the core that formats it to its place, where the output can
        // take it so (and no line index is kept): no rounds, no core reading another's text.
        if !want.index {
            let streamed = out.with_sink(n - 1, &mut |sink| {
                let written =
                    crate::parallel::map_shared(starts.len(), Piece::default, |piece, k| {
                        // A panic here leaves piece k untaken: the other cores stop waiting for it.
                        struct Abandon<'s>(&'s dyn PieceSink);
                        impl Drop for Abandon<'_> {
                            fn drop(&mut self) {
                                if std::thread::panicking() {
                                    self.0.abandon();
                                }
                            }
                        }
                        let _abandon = Abandon(sink);
                        self.format(chunk(k), starts[k], want, piece);
                        sink.take(k, &piece.told())
                    });
                written.into_iter().collect()
            });
            if let Some(result) = streamed {
                return result;
            }
        }
        // A round's pieces, reused round after round.
        let mut pieces: Vec<std::sync::Mutex<Piece>> = (0..ROUND_CHUNKS)
            .map(|_| std::sync::Mutex::new(Piece::default()))
            .collect();
        for round in (0..starts.len()).step_by(ROUND_CHUNKS) {
            let count = ROUND_CHUNKS.min(starts.len() - round);
            crate::parallel::map_shared(
                count,
                || (),
                |(), j| {
                    let mut piece = pieces[j].lock().unwrap_or_else(|e| e.into_inner());
                    self.format(chunk(round + j), starts[round + j], want, &mut piece);
                },
            );
            let used: Vec<&Piece> = pieces[..count]
                .iter_mut()
                .map(|p| &*p.get_mut().unwrap_or_else(|e| e.into_inner()))
                .collect();
            let told: Vec<_> = used.iter().map(|p| p.told()).collect();
            out.body(&told)?;
            if let Some(v) = index.as_deref_mut() {
                used.iter().for_each(|p| v.extend_from_slice(&p.points));
            }
        }
        Ok(())
    }

    /// Formats points `range` starting from `st` into `piece` (emptied first), with what is
    /// wanted besides the text.
    fn format(
        &self,
        range: std::ops::Range<usize>,
        st: BodyState,
        want: Wanted,
        piece: &mut Piece,
    ) {
        // Whether the moves are read back is decided once a chunk: each way has its own loop.
        if want.moves {
            self.format_reading::<true>(range, st, want, piece);
        } else {
            self.format_reading::<false>(range, st, want, piece);
        }
    }

    /// [`BodyWriter::format`] with `want.moves` as `MOVES`, a constant in the loop.
    fn format_reading<const MOVES: bool>(
        &self,
        range: std::ops::Range<usize>,
        mut st: BodyState,
        want: Wanted,
        piece: &mut Piece,
    ) {
        let (p, tp) = (&self.design.printer, self.tp);
        let [ox, oy] = self.origin;
        piece.clear(range.len());
        if MOVES {
            piece.moves.reserve(range.len());
        }
        let Piece {
            text: buf,
            lines,
            points,
            moves,
            told,
        } = piece;
        // Each number written, and read back where the moves are wanted (the decimals a
        // constant: no dispatch on them at each number).
        #[inline(always)]
        fn number<const D: u32>(line: &mut Line<'_>, v: f64, read: bool) -> Option<f64> {
            if read {
                line.fixed_const::<D, true>(v)
            } else {
                line.fixed_const::<D, false>(v)
            }
        }
        // Counts `count` lines at path point `point`.
        let mark = |lines: &mut usize, points: &mut Vec<u32>, count: usize, point: usize| {
            *lines += count;
            if want.index {
                points.extend(std::iter::repeat_n(point as u32, count));
            }
        };
        // The next layer's first point (none past the last layer): one comparison a point.
        let layer_at = |next: usize| tp.layer_starts.get(next).copied().unwrap_or(usize::MAX);
        let mut next_layer_at = layer_at(st.next_layer);
        // The times between which the percent is known to stay `st.last_percent` (see
        // [`BodyWriter::percent_below`]): none known at the chunk's start.
        let (mut percent_from, mut percent_below) = (f64::INFINITY, f64::NEG_INFINITY);
        for i in range {
            let q = &tp.points[i];
            if i >= next_layer_at {
                // The layer that starts at this point (or at the point before it: the first
                // point of the path is where the approach ends).
                while st.next_layer < tp.layer_starts.len() && tp.layer_starts[st.next_layer] <= i {
                    let n = st.next_layer + 1;
                    if p.host_metadata {
                        mark(lines, points, 2, i - 1);
                        buf.extend_from_slice(format!(";LAYER:{}\n", n - 1).as_bytes());
                        match p.dialect {
                            Dialect::Klipper => buf.extend_from_slice(
                                format!("SET_PRINT_STATS_INFO CURRENT_LAYER={n}\n").as_bytes(),
                            ),
                            _ => buf.extend_from_slice(
                                format!("M117 Layer {n}/{}\n", self.layers_total).as_bytes(),
                            ),
                        }
                    }
                    st.next_layer += 1;
                }
                next_layer_at = layer_at(st.next_layer);
            }
            // The percent is computed where it may have changed: not between the time it was
            // last computed at and the time below which it cannot reach the next whole percent
            // (it never falls as the time grows).
            if p.progress && !(percent_from <= st.t_done && st.t_done < percent_below) {
                let percent = self.percent(st.t_done);
                (percent_from, percent_below) = (st.t_done, self.percent_below(percent));
                if percent != st.last_percent {
                    mark(lines, points, 1, i - 1);
                    let left_min = ((self.nominal - st.t_done) * self.scale / 60.0)
                        .ceil()
                        .max(0.0);
                    buf.extend_from_slice(format!("M73 P{percent} R{left_min:.0}\n").as_bytes());
                    st.last_percent = percent;
                }
            }
            let (dt, e) = self.steps[i - 1];
            st.t_done += dt;
            let (x, y, z, e) = Line::append(buf, |line| {
                line.text(b"G1 X");
                let x = number::<XYZ_DECIMALS>(line, q.pos.x - ox, MOVES);
                line.text(b" Y");
                let y = number::<XYZ_DECIMALS>(line, q.pos.y - oy, MOVES);
                line.text(b" Z");
                let z = number::<XYZ_DECIMALS>(line, q.pos.z, MOVES);
                line.text(b" E");
                let e = match p.extrusion {
                    ExtrusionMode::Relative => number::<5>(line, e, MOVES),
                    ExtrusionMode::Absolute => {
                        st.e_total += e;
                        number::<5>(line, st.e_total, MOVES)
                    }
                };
                if q.speed != st.last_speed {
                    line.text(b" F");
                    number::<1>(line, q.speed * 60.0, false);
                    st.last_speed = q.speed;
                }
                line.text(b"\n");
                (x, y, z, e)
            });
            mark(lines, points, 1, i);
            if MOVES {
                // What the checker's reader makes of the line: X Y Z E as written.
                match (x, y, z, e) {
                    (Some(x), Some(y), Some(z), Some(e)) => moves.push(crate::check::Move {
                        to: DVec3::new(x, y, z),
                        de: e,
                        line: *lines,
                    }),
                    _ => *told = false,
                }
            }
        }
        *told &= MOVES;
    }
}

/// The whole percent of `nominal` seconds done by `t_done`, 0 … 100: never less for a later
/// time (a division and a product, each rounded monotonically, then [`whole_percent`]).
fn percent_done(t_done: f64, nominal: f64) -> u64 {
    whole_percent((t_done / nominal) * 100.0)
}

/// A time below which [`percent_done`] is at most `percent`: the time of the next whole
/// percent less a millionth of it, far more than the two roundings of [`percent_done`] (each
/// under 2⁻⁵² of its value) can move it; never past 100. Between a time whose percent is
/// `percent` and this one, the percent is `percent` without computing it.
fn time_below_next_percent(percent: u64, nominal: f64) -> f64 {
    if percent >= 100 {
        f64::INFINITY
    } else {
        (percent + 1) as f64 / 100.0 * nominal * (1.0 - 1e-6)
    }
}

/// `⌊percent⌋` clamped to 0 … 100 (0 for NaN): the truncation of the clamped value, which is
/// its floor there, with no call to the C library's `floor` (what the baseline x86-64 target
/// makes of `f64::floor`), once a line.
#[inline]
fn whole_percent(percent: f64) -> u64 {
    percent.clamp(0.0, 100.0) as u64
}

/// What the body's writer gives besides the text.
#[derive(Clone, Copy)]
struct Wanted {
    /// Each line's path point (the program's index).
    index: bool,
    /// Each line's move as the checker's reader reads it.
    moves: bool,
}

/// A chunk of the body as formatted: its text, its lines, and what was wanted besides.
#[derive(Default)]
struct Piece {
    text: Vec<u8>,
    /// Lines in the text.
    lines: usize,
    /// The path point of each line (when the index is wanted).
    points: Vec<u32>,
    /// Each `G1` line's move as read before the modal state, its line counted from 1 in the
    /// piece (when wanted): `crate::check::ToldPiece`'s.
    moves: Vec<crate::check::Move>,
    /// Whether `moves` are the piece's (wanted, and every number written as a plain decimal).
    told: bool,
}

impl Piece {
    /// The piece as the self-check takes it.
    fn told(&self) -> crate::check::ToldPiece<'_> {
        crate::check::ToldPiece {
            text: &self.text,
            moves: self.told.then_some(&self.moves[..]),
            lines: self.lines,
        }
    }

    /// Emptied for a chunk of `points` path points.
    fn clear(&mut self, points: usize) {
        self.text.clear();
        self.text.reserve(points * 48);
        self.lines = 0;
        self.points.clear();
        self.moves.clear();
        self.told = true;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    proptest::proptest! {
        /// The whole percent is the floor of the percent, clamped, for any number.
        #[test]
        fn the_whole_percent_is_the_floor_clamped(
            x in proptest::num::f64::ANY,
            near in -2i32..103,
            tiny in -1e-9..1e-9f64,
        ) {
            for x in [x, f64::from(near) + tiny, f64::from(near)] {
                proptest::prop_assert_eq!(whole_percent(x), x.floor().clamp(0.0, 100.0) as u64);
            }
        }
    }

    proptest::proptest! {
        /// From a time whose percent is P up to the time below the next percent, every time's
        /// percent is P: right at that bound, past a percent's exact time, at any nominal time.
        #[test]
        fn the_percent_stays_until_the_time_below_the_next(
            nominal in proptest::prop_oneof![1e-6..1e-3f64, 1e-3..1e7f64],
            from in 0.0..1.02f64,
            ahead in 0.0..1.0f64,
            whole in 0u64..101,
        ) {
            for t0 in [from * nominal, whole as f64 / 100.0 * nominal] {
                let p = percent_done(t0, nominal);
                let below = time_below_next_percent(p, nominal);
                let last = below.next_down().min(1e300);
                for t in [t0, t0 + (last - t0).max(0.0) * ahead, last] {
                    if t0 <= t && t < below {
                        proptest::prop_assert_eq!(percent_done(t, nominal), p, "{} .. {}", t0, t);
                    }
                }
                // The bound is close: the next percent is reached within a thousandth of it.
                if p < 100 {
                    let next = (p + 1) as f64 / 100.0 * nominal * (1.0 + 1e-12);
                    proptest::prop_assert!(percent_done(next, nominal) > p);
                    proptest::prop_assert!(next - below < 1e-5 * nominal);
                }
            }
        }
    }

    /// The path's sums in one pass are the toolpath's own to the last bit: its length, its time
    /// at its own speeds, the clay's volume and its box (a spiral whose speeds change: its upper
    /// layers slowed to the minimum layer time; on a base, whose first point is the lowest).
    /// Long enough for each segment's time and volume to be worked out on every core.
    #[test]
    fn the_path_sums_are_the_paths_own() {
        let mut d = crate::load::parse_design(
            "version = 1\n[shape]\nheight = 60.0\nsamples = 720\nbase_layers = 2\nlower = { type = \"circle\", radius = 30.0 }\nupper = { type = \"circle\", radius = 36.0 }\n[printer]\nmin_layer_time = 30.0\n",
        )
        .unwrap();
        for a in [500.0, 5.0] {
            d.printer.max_acceleration = a;
            let job = crate::run(&d).unwrap();
            let tp = &job.toolpath;
            assert!(tp.points.len() > 2 * crate::parallel::PARALLEL_POINTS);
            assert!(tp.points.windows(2).any(|w| w[0].speed != w[1].speed));
            let (summary, sums, ()) = summarize_beside(&d, &job, true, || ());
            assert_eq!(summary.path_length_mm.to_bits(), tp.length().to_bits());
            assert_eq!(sums.nominal_s.to_bits(), tp.print_time().to_bits());
            // The planner's segments, or the path's measured here: the same sums.
            let measured = PathSums::of(&d, tp, None);
            assert_eq!(sums.length.to_bits(), measured.length.to_bits());
            let times = |s: &PathSums| s.starts.iter().map(|b| b.t_done.to_bits()).collect();
            let times: [Vec<u64>; 2] = [times(&sums), times(&measured)];
            assert_eq!(times[0], times[1]);
            let volume: f64 = (1..tp.points.len())
                .map(|i| segment_volume(&d, tp, i))
                .sum();
            assert_eq!(summary.volume_mm3.to_bits(), volume.to_bits());
            // Each segment's time and E, as the body's writer adds them up.
            for (i, &(dt, e)) in (1..).zip(&sums.steps) {
                let (a, b) = (&tp.points[i - 1], &tp.points[i]);
                assert_eq!(dt.to_bits(), (a.pos.distance(b.pos) / b.speed).to_bits());
                let e_of = segment_volume(&d, tp, i) * e_per_mm3(&d.printer);
                assert_eq!(e.to_bits(), e_of.to_bits());
            }
            assert_eq!(sums.steps.len(), tp.points.len() - 1);
            let z = |q: &crate::toolpath::PathPoint| q.pos.z;
            let top = tp.points.iter().map(z).fold(f64::MIN, f64::max);
            let bottom = tp.points.iter().map(z).fold(f64::MAX, f64::min);
            let x = tp.points.iter().map(|q| q.pos.x);
            let (left, right) = (
                x.clone().fold(f64::MAX, f64::min),
                x.fold(f64::MIN, f64::max),
            );
            let (lo, hi) = summary.path_bounds_mm;
            assert_eq!((lo.z, hi.z, lo.x, hi.x), (bottom, top, left, right));
            assert!(lo.y < hi.y);
        }
    }

    /// The body written in rounds of chunks, on both cores, each from the state its chunk's
    /// sums reach, is the body formatted in one piece on one: a path of more than a round of
    /// chunks (the last short) whose speeds change, with and without host metadata and
    /// progress, in either E mode.
    #[test]
    fn chunks_write_the_body_in_one_piece() {
        let mut d = crate::load::parse_design(
            "version = 1\n[shape]\nheight = 20.0\nlower = { type = \"circle\", radius = 30.0 }\nupper = { type = \"circle\", radius = 30.0 }\n",
        )
        .unwrap();
        // More than a round of chunks, the last one short.
        let n = (ROUND_CHUNKS + 1) * BODY_CHUNK + BODY_CHUNK / 3;
        let points: Vec<crate::toolpath::PathPoint> = (0..n)
            .map(|i| {
                let a = i as f64 * 0.01;
                crate::toolpath::PathPoint {
                    pos: DVec3::new(
                        90.0 + 40.0 * a.cos(),
                        95.0 + 40.0 * a.sin(),
                        0.5 + i as f64 * 1e-4,
                    ),
                    thickness: 0.5,
                    flow: 1.0,
                    speed: if (i / 5000) % 3 == 0 { 15.0 } else { 20.0 },
                }
            })
            .collect();
        let tp = Toolpath {
            layer_starts: (0..n).step_by(628).collect(),
            points,
            base_points: 0,
            revolutions: 1,
            findings: Vec::new(),
        };
        for (metadata, progress, extrusion) in [
            (true, true, ExtrusionMode::Absolute),
            (false, false, ExtrusionMode::Absolute),
            (false, true, ExtrusionMode::Relative),
            (true, false, ExtrusionMode::Relative),
        ] {
            (d.printer.host_metadata, d.printer.progress) = (metadata, progress);
            d.printer.extrusion = extrusion;
            let sums = PathSums::of(&d, &tp, None);
            let body = BodyWriter::new(&d, &tp, &sums, 12_345.0, tp.layer_starts.len());
            let (mut text, mut index) = (Vec::new(), Vec::new());
            crate::parallel::awake(|| {
                body.write(&mut text, &mut Some(&mut index), &body.chunk_starts(&sums))
            })
            .unwrap();
            let mut whole = Piece::default();
            let want = Wanted {
                index: true,
                moves: true,
            };
            body.format(1..n, BodyState::START, want, &mut whole);
            assert!(text == whole.text, "the texts differ");
            assert_eq!(index, whole.points);
            assert_eq!(whole.lines, index.len());
            assert_eq!(text.windows(4).any(|w| w == b"M73 "), progress);
            assert_eq!(text.windows(7).any(|w| w == b";LAYER:"), metadata);
        }
    }

    /// The program's line index names, for every line that moves the nozzle along the path, the
    /// point that line moves to (read back from the text); the text is the file's, byte for byte.
    #[test]
    fn every_path_line_carries_its_point() {
        for profile in ["", "profile = \"klipper-paste-delta\"\n"] {
            let d = crate::load::parse_design(&format!(
                "version = 1\n[printer]\n{profile}[shape]\nheight = 20.0\nsamples = 60\nbase_layers = 1\n\
                 lower = {{ type = \"circle\", radius = 30.0 }}\nupper = {{ type = \"circle\", radius = 30.0 }}\n"
            ))
            .unwrap();
            let job = crate::run(&d).unwrap();
            let prog = program(&d, &job).unwrap();
            let mut file = Vec::new();
            write_gcode(&d, &job, &mut file).unwrap();
            assert_eq!(prog.text.as_bytes(), &file[..]);
            assert_eq!(prog.point_of_line.len(), prog.text.lines().count());
            let [ox, oy] = d.printer.origin_offset();
            let mut moves = 0;
            let mut last = 0;
            for (line, &point) in prog.text.lines().zip(&prog.point_of_line) {
                assert!(point >= last, "the index never goes back");
                last = point;
                let Some(rest) = line.strip_prefix("G1 X") else {
                    continue;
                };
                let words: Vec<&str> = rest.split(' ').collect();
                let x: f64 = words[0].parse().unwrap();
                let y: f64 = words[1].trim_start_matches('Y').parse().unwrap();
                let q = job.toolpath.points[point as usize].pos;
                assert!(
                    (q.x - ox - x).abs() < 1e-3 && (q.y - oy - y).abs() < 1e-3,
                    "{line}"
                );
                moves += 1;
            }
            assert_eq!(moves, job.toolpath.points.len() - 1);
            assert_eq!(last as usize, job.toolpath.points.len() - 1);
        }
    }

    #[test]
    fn the_cancel_sequence_lifts_clear_of_the_vessel_and_parks() {
        let (d, j) = job("");
        let text = cancel_gcode(&d, &j).unwrap();
        let lines: Vec<&str> = text.lines().filter(|l| !l.starts_with(';')).collect();
        // No extrusion; the lift clears the rim (10 mm tall vessel) before any XY move.
        assert!(lines.iter().all(|l| !l.contains(" E")), "{text}");
        let lift = lines.iter().position(|l| l.starts_with("G0 Z")).unwrap();
        let park = lines.iter().position(|l| l.starts_with("G0 X")).unwrap();
        assert!(lift < park, "{text}");
        let z: f64 = lines[lift][4..].split(' ').next().unwrap().parse().unwrap();
        assert!(z > 10.0, "{z}");
        let (d, j) = job("[printer]\ncancel_gcode = \"M104 S0\\nG91\\nG0 Z{park_z}\\n\"\n");
        assert!(
            cancel_gcode(&d, &j)
                .unwrap()
                .starts_with("M104 S0\nG91\nG0 Z")
        );
    }

    #[test]
    fn durations() {
        assert_eq!(format_duration(3723.0), "1h 02m 03s");
        assert_eq!(format_duration(59.6), "1m 00s");
    }

    fn job(extra: &str) -> (Design, PrintJob) {
        let d = crate::load::parse_design(&format!(
            "version = 1\nname = \"t\"\n[shape]\nheight = 10.0\nsamples = 60\nbase_layers = 0\n[shape.lower]\ntype = \"circle\"\nradius = 30.0\n[shape.upper]\ntype = \"circle\"\nradius = 30.0\n{extra}"
        ))
        .unwrap();
        let j = crate::pipeline::run(&d).unwrap();
        (d, j)
    }

    #[test]
    fn the_writer_returns_the_summary_it_wrote() {
        let (d, j) = job("[texture]\n[texture.x]\nwave = \"sine\"\nperiod = 6\namplitude = 1.0\n");
        let mut v = Vec::new();
        let s = write_gcode_summarized(&d, &j, &mut v).unwrap();
        assert_eq!(s, summarize(&d, &j));
        let text = String::from_utf8(v).unwrap();
        assert!(text.contains(&format!("({:.0} s,", s.estimated_time_s)));
    }

    fn gcode(d: &Design, j: &PrintJob) -> String {
        let mut v = Vec::new();
        write_gcode(d, j, &mut v).unwrap();
        String::from_utf8(v).unwrap()
    }

    #[test]
    fn extrusion_follows_the_volume_formula() {
        let (d, j) = job("");
        let text = gcode(&d, &j);
        // Wall segment in the steady helix: E = w·h·len / (π·3²/4), len = chord of a 30 mm circle in 60 steps.
        let chord = 2.0 * 30.0 * (std::f64::consts::PI / 60.0).sin();
        let e_expected = 3.0 * 1.0 * chord / (std::f64::consts::PI * 9.0 / 4.0);
        let line = text
            .lines()
            .filter(|l| l.starts_with("G1"))
            .nth(300)
            .unwrap();
        let e: f64 = line.split(' ').find(|w| w.starts_with('E')).unwrap()[1..]
            .parse()
            .unwrap();
        assert!(
            (e - e_expected).abs() < 2e-3 * e_expected,
            "{e} vs {e_expected}: {line}"
        );
        assert!(text.contains("M83"));
        assert!(text.contains("; estimated time:"));
        assert!(text.contains(LIMITS_KEY));
    }

    #[test]
    fn absolute_mode_accumulates_to_the_same_total() {
        let (d, j) = job("");
        let (da, ja) = job("[printer]\nextrusion = \"absolute\"\n");
        let rel: f64 = gcode(&d, &j)
            .lines()
            .filter(|l| l.starts_with("G1"))
            .map(|l| {
                l.split(' ').find(|w| w.starts_with('E')).unwrap()[1..]
                    .parse::<f64>()
                    .unwrap()
            })
            .sum();
        let abs_text = gcode(&da, &ja);
        assert!(abs_text.contains("M82"));
        let last_e: f64 = abs_text
            .lines()
            .rfind(|l| l.starts_with("G1"))
            .map(|l| {
                l.split(' ').find(|w| w.starts_with('E')).unwrap()[1..]
                    .parse()
                    .unwrap()
            })
            .unwrap();
        assert!((rel - last_e).abs() < 1e-3 * rel, "{rel} {last_e}");
    }

    #[test]
    fn output_is_deterministic_and_textured_prints_longer() {
        let (d, j) = job("");
        assert_eq!(gcode(&d, &j), gcode(&d, &crate::pipeline::run(&d).unwrap()));
        let (dt, jt) =
            job("[texture]\n[texture.x]\nwave = \"sine\"\nperiod = 6\namplitude = 1.0\n");
        assert!(summarize(&dt, &jt).estimated_time_s > summarize(&d, &j).estimated_time_s);
    }
}
