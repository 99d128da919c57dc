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

use crate::design::{BedShape, Design, Dialect, ExtrusionMode, Kinematics, Origin};
use crate::motion;
use crate::pipeline::PrintJob;
use crate::templates::Values;
use crate::toolpath::Toolpath;

/// Height above the first and last point for the approach and exit moves, mm.
pub const CLEARANCE: f64 = 10.0;

/// Key of the header line that carries the printer limits for `clayloft check`.
pub const LIMITS_KEY: &str = "; clayloft-limits:";

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
fn planned_moves<'a>(
    design: &Design,
    tp: &'a Toolpath,
) -> (DVec3, impl Iterator<Item = motion::Move> + 'a) {
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
    let path = tp.points.get(1..).unwrap_or(&[]);
    let moves = approach
        .into_iter()
        .chain(path.iter().map(|q| motion::Move {
            to: q.pos,
            speed: q.speed,
        }))
        .chain(exit);
    (home, moves)
}

/// Length, time and volume of a job.
pub fn summarize(design: &Design, job: &PrintJob) -> JobSummary {
    let p = &design.printer;
    let tp = &job.toolpath;
    let volume: f64 = (1..tp.points.len())
        .map(|i| segment_volume(design, tp, i))
        .sum();
    let (home, moves) = planned_moves(design, tp);
    let feed_area = std::f64::consts::PI * p.feed_diameter * p.feed_diameter / 4.0;
    JobSummary {
        layers: job.surface.layers,
        points: tp.points.len(),
        path_length_mm: tp.length(),
        estimated_time_s: motion::plan_time_of(
            home,
            moves,
            p.max_acceleration,
            p.junction_deviation,
        ),
        volume_mm3: volume,
        e_length_mm: volume * p.flow_multiplier / feed_area,
    }
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

/// The placeholder values of a job's templates, in the printer's own coordinates.
pub fn template_values(design: &Design, job: &PrintJob, summary: &JobSummary) -> Values {
    let p = &design.printer;
    let tp = &job.toolpath;
    let [ox, oy] = p.origin_offset();
    let (first, last) = match (tp.points.first(), tp.points.last()) {
        (Some(f), Some(l)) => (f.pos, l.pos),
        _ => (DVec3::ZERO, DVec3::ZERO),
    };
    let top = tp.points.iter().map(|q| q.pos.z).fold(0.0, f64::max);
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
    write_program(design, job, out).map_err(io::Error::from)
}

/// [`write_gcode`] with its errors kept apart (a template that cannot be filled names its field).
pub fn write_program(
    design: &Design,
    job: &PrintJob,
    out: &mut dyn Write,
) -> Result<(), GcodeWriteError> {
    let p = &design.printer;
    let tp = &job.toolpath;
    let summary = summarize(design, job);
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
    let layers_total = tp.layer_starts.len().max(1);
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
    if p.thumbnail {
        let points: Vec<DVec3> = tp.points.iter().map(|q| q.pos).collect();
        head.push_str(&crate::thumbnail::header_blocks(&points));
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
    out.write_all(head.as_bytes())?;

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
    }
    let feed_area = std::f64::consts::PI * p.feed_diameter * p.feed_diameter / 4.0;
    let e_per_mm3 = p.flow_multiplier / feed_area;
    let mut e_total = 0.0;
    let mut last_speed = f64::NAN;
    // Progress: time into the print at each point (the nominal-speed estimate scaled to the
    // planned total, so M73 counts down to the planned end).
    let nominal: f64 = tp.print_time().max(1e-9);
    let scale = summary.estimated_time_s / nominal;
    let mut t_done = 0.0;
    let mut last_percent = u64::MAX;
    let mut next_layer = 0usize;
    for i in 1..tp.points.len() {
        let q = &tp.points[i];
        if p.host_metadata || p.progress {
            // The layer that starts at this point (or at the point before it: the first point
            // of the path is where the approach ends).
            while next_layer < tp.layer_starts.len() && tp.layer_starts[next_layer] <= i {
                let n = next_layer + 1;
                if p.host_metadata {
                    buf.extend_from_slice(format!(";LAYER:{}\n", n - 1).as_bytes());
                    match p.dialect {
                        Dialect::Klipper => buf.extend_from_slice(
                            format!("SET_PRINT_STATS_INFO CURRENT_LAYER={n}\n").as_bytes(),
                        ),
                        _ => buf.extend_from_slice(
                            format!("M117 Layer {n}/{layers_total}\n").as_bytes(),
                        ),
                    }
                }
                next_layer += 1;
            }
            if p.progress {
                let percent = ((t_done / nominal) * 100.0).floor().clamp(0.0, 100.0) as u64;
                if percent != last_percent {
                    let left_min = ((nominal - t_done) * scale / 60.0).ceil().max(0.0);
                    buf.extend_from_slice(format!("M73 P{percent} R{left_min:.0}\n").as_bytes());
                    last_percent = percent;
                }
            }
        }
        let prev = &tp.points[i - 1];
        t_done += prev.pos.distance(q.pos) / q.speed;
        let e = segment_volume(design, tp, i) * e_per_mm3;
        buf.extend_from_slice(b"G1 ");
        put_xy(&mut buf, q.pos);
        buf.extend_from_slice(b" Z");
        put_fixed(&mut buf, q.pos.z, 3);
        buf.extend_from_slice(b" E");
        match p.extrusion {
            ExtrusionMode::Relative => put_fixed(&mut buf, e, 5),
            ExtrusionMode::Absolute => {
                e_total += e;
                put_fixed(&mut buf, e_total, 5)
            }
        }
        if q.speed != last_speed {
            buf.extend_from_slice(b" F");
            put_fixed(&mut buf, q.speed * 60.0, 1);
            last_speed = q.speed;
        }
        buf.push(b'\n');
        if buf.len() > (1 << 16) - 256 {
            out.write_all(&buf)?;
            buf.clear();
        }
    }
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
    out.write_all(&buf)?;
    Ok(())
}

/// Two-digit pairs "00" … "99", for writing integers two digits per division.
const DIGIT_PAIRS: &[u8; 200] = b"0001020304050607080910111213141516171819\
2021222324252627282930313233343536373839\
4041424344454647484950515253545556575859\
6061626364656667686970717273747576777879\
8081828384858687888990919293949596979899";

/// Appends the decimal digits of `n`, at least `min_digits` of them (zero-padded).
#[inline]
fn put_digits(buf: &mut Vec<u8>, mut n: u64, min_digits: usize) {
    let mut tmp = [b'0'; 24];
    let mut pos = tmp.len();
    while n >= 100 {
        let pair = (n % 100) as usize * 2;
        n /= 100;
        pos -= 2;
        tmp[pos..pos + 2].copy_from_slice(&DIGIT_PAIRS[pair..pair + 2]);
    }
    if n >= 10 {
        pos -= 2;
        tmp[pos..pos + 2].copy_from_slice(&DIGIT_PAIRS[n as usize * 2..n as usize * 2 + 2]);
    } else {
        pos -= 1;
        tmp[pos] = b'0' + n as u8;
    }
    let start = pos.min(tmp.len() - min_digits.min(tmp.len()));
    buf.extend_from_slice(&tmp[start..]);
}

/// Appends `v` with exactly `decimals` digits after the point (none and no point for 0),
/// rounded half away from zero; `-0` is written as `0`.
#[inline]
pub fn put_fixed(buf: &mut Vec<u8>, v: f64, decimals: u32) {
    let pow = 10u64.pow(decimals);
    let scaled = (v.abs() * pow as f64).round();
    if !scaled.is_finite() || scaled >= 9.0e18 {
        // Out of range for integer formatting (never for a real printer); fall back.
        buf.extend_from_slice(format!("{v:.*}", decimals as usize).as_bytes());
        return;
    }
    let n = scaled as u64;
    if v < 0.0 && n != 0 {
        buf.push(b'-');
    }
    put_digits(buf, n / pow, 1);
    if decimals > 0 {
        buf.push(b'.');
        put_digits(buf, n % pow, decimals as usize);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fixed(v: f64, d: u32) -> String {
        let mut b = Vec::new();
        put_fixed(&mut b, v, d);
        String::from_utf8(b).unwrap()
    }

    #[test]
    fn fixed_formatting() {
        assert_eq!(fixed(12.3456, 3), "12.346");
        assert_eq!(fixed(0.0004, 3), "0.000");
        assert_eq!(fixed(-0.0004, 3), "0.000");
        assert_eq!(fixed(-1.5, 3), "-1.500");
        assert_eq!(fixed(0.05, 5), "0.05000");
        assert_eq!(fixed(3000.0, 0), "3000");
        assert_eq!(fixed(7.0, 1), "7.0");
        assert_eq!(fixed(1e300, 2).len(), format!("{:.2}", 1e300).len());
        assert_eq!(fixed(123456.789, 3), "123456.789");
        assert_eq!(fixed(0.00123, 5), "0.00123");
        assert_eq!(fixed(99.9996, 3), "100.000");
        for k in 0..2000 {
            let v = (k as f64 - 1000.0) * 0.7391;
            let written: f64 = fixed(v, 3).parse().unwrap();
            assert!((written - v).abs() <= 0.0005 + 1e-9, "{v} -> {written}");
        }
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
