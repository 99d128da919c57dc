//! The G-code checker (SPEC §2, §7): re-measures a G-code file alone against the printer's limits.
//!
//! * Single continuous path: between the first and the last extruding move every move extrudes;
//!   no retraction anywhere.
//! * Inside the machine: every move's end point on the bed and within 0 ..= max_z.
//! * Layer height and overhang: for each path vertex p, the layer below is the topmost earlier
//!   path (more than a few line widths back along the path, or a whole minimum layer lower, and
//!   at least a quarter of the minimum layer height lower) within half a bead in XY. Local
//!   layer height = p.z − z below; the lean is the least `atan(d / Δz)` over the earlier paths
//!   within the search radius and two layers down (d their XY distance, Δz how far below p): a
//!   leaning wall leans alike from every layer under it, while a bead beside a thinner one (the
//!   beads of a wall of several, SPEC §13) but resting on a layer beneath does not lean. Points
//!   low enough rest on the bed.
//! * Collision: the highest earlier printed point may rise at most `nozzle_length` above the
//!   nozzle tip (the holder is treated as a plane `nozzle_length` above the tip).
//!
//! [`check_gcode`] measures every point (the report's figures); [`verify_gcode`] only asks
//! whether the limits hold, and shows most points' layers by a witness instead;
//! [`GcodeVerifier`] is `verify_gcode` of a program read as it is written.

mod crossings;
mod layers;
pub(crate) use layers::{
    ChordFoot, chord_foot, chords_beside, chords_of, just_laid_gap, on_bead_just_laid, past_corner,
    same_layer_tolerance, thinnest_layer_accepted, within_window,
};
mod limits;
mod moves;
mod report;

use glam::DVec3;

pub use limits::{Limits, LimitsError};
use moves::MoveReader;
pub use moves::{GcodeError, Move, parse_moves};
pub(crate) use moves::{ToldPiece, ToldStream};
use report::Tally;
pub use report::{
    COLLISION, CROSSING, CheckReport, NOT_CONTINUOUS, NOT_MEASURED, OUTSIDE, OVERHANG, PathEvent,
    RETRACTION, UNSUPPORTED, Violation,
};

/// Re-measures a G-code program against `limits`. Errors only when the text is not G-code.
pub fn check_gcode(text: &str, limits: &Limits) -> Result<CheckReport, GcodeError> {
    validate(limits)?;
    let (moves, start) = parse_moves(text)?;
    check_moves(moves, start, limits, false).map(Option::unwrap_or_default)
}

/// Whether a G-code program keeps `limits`: `Ok(None)` when it does, shown without measuring
/// every point's layers in full where a witness shows them (about a fifth of the time on a clay
/// vessel; see `layers::layers_hold`), else `Ok(Some(report))` with [`check_gcode`]'s
/// report of what breaks. What `clayloft gcode` asks of its own file before writing it. The
/// verdict is [`check_gcode`]'s (tested), but for a file whose layers the full search would give
/// up on (its candidate budget spent or its grid too large to build, "not measurable") while a
/// witness shows every point: that file passes here.
pub fn verify_gcode(text: &str, limits: &Limits) -> Result<Option<CheckReport>, GcodeError> {
    validate(limits)?;
    let (moves, start) = parse_moves(text)?;
    check_moves(moves, start, limits, true)
}

/// [`verify_gcode`] of a program as it is written: the text goes in through
/// [`std::io::Write`] in pieces of any size and is read into moves as it comes
/// (a move reader), so that it need not be kept whole; [`GcodeVerifier::finish`] gives the
/// verdict. What `clayloft gcode` writes its file through.
pub struct GcodeVerifier {
    reader: MoveReader,
}

impl GcodeVerifier {
    /// A verifier with room for about `moves` moves.
    pub fn with_capacity(moves: usize) -> Self {
        GcodeVerifier {
            reader: MoveReader::with_capacity(moves),
        }
    }

    /// Takes pieces of the program whose moves the writer tells (see `ToldPiece`), reading only
    /// the text of those it does not: what the G-code writer gives for the path's body.
    pub(crate) fn feed_told(&mut self, pieces: &[ToldPiece<'_>]) {
        self.reader.feed_told(pieces);
    }

    /// The reader's `MoveReader::stream_told`: the body's pieces taken on the threads that
    /// write them (none, `run` not run, where they must come through `feed_told`).
    pub(crate) fn stream_told(
        &mut self,
        text_at: u64,
        moves: usize,
        run: impl FnOnce(&ToldStream<'_>),
    ) -> Option<u64> {
        self.reader.stream_told(text_at, moves, run)
    }

    /// [`verify_gcode`]'s verdict on the text written.
    pub fn finish(self, limits: &Limits) -> Result<Option<CheckReport>, GcodeError> {
        validate(limits)?;
        let (moves, start) = self.reader.finish()?;
        check_moves(moves, start, limits, true)
    }
}

impl std::io::Write for GcodeVerifier {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.reader.feed(buf);
        Ok(buf.len())
    }

    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

/// The limits, or why they cannot be checked against (as an error of the program's first line).
fn validate(limits: &Limits) -> Result<(), GcodeError> {
    limits.validate().map_err(|e| GcodeError {
        line: e.line.unwrap_or(1),
        message: format!("limits: {e}"),
    })
}

/// [`check_gcode`] of moves read already (`start`: where the first begins), in the file's
/// coordinates, always a report; with `show`, [`verify_gcode`]'s verdict: the layers first
/// shown to hold by witnesses, and no report where they are and nothing else breaks. The moves
/// are let go once the path is copied from them (the layer search's buffers reuse their 9 MB
/// on the benchmark vase, whose `clayloft gcode` then fills two huge pages fewer).
fn check_moves(
    moves: Vec<Move>,
    start: DVec3,
    limits: &Limits,
    show: bool,
) -> Result<Option<CheckReport>, GcodeError> {
    // Into the bed frame: the file's coordinates are the printer's own.
    let [ox, oy] = limits.origin_offset();
    let shift = DVec3::new(ox, oy, 0.0);
    let start = start + shift;
    if moves.is_empty() {
        return Err(GcodeError {
            line: 1,
            message: "there are no moves to check".into(),
        });
    }
    let mut report = CheckReport {
        moves: moves.len(),
        ..Default::default()
    };
    let first_ext = moves.iter().position(|m| m.de > 0.0);
    let last_ext = moves.iter().rposition(|m| m.de > 0.0);
    let extruding = first_ext.zip(last_ext);
    let tally = |range| MoveTally::of(&moves, range, start, limits, extruding);
    let (path, tallied) = extruding_path(&moves, start, shift, extruding, limits, tally);
    drop(moves);
    tallied.into_report(limits, &mut report);
    let Some(((vertices, lines), clearance)) = path else {
        return Ok((!show || !report.violations.is_empty()).then_some(report));
    };
    if show {
        let before = report.clone();
        match layers::layers_hold(&vertices, &lines, limits, &mut report, clearance) {
            true if report.violations.is_empty() => return Ok(None),
            // Not shown: the layers were measured in full after all, and this is the report.
            false => return Ok(Some(report)),
            // The layers shown, another limit broken (the bed, the holder): measured in full
            // for the layers' figures of the report.
            true => report = before,
        }
    }
    layers::measure_layers(&vertices, &lines, limits, &mut report);
    Ok(Some(report))
}

/// The points of an extruding path in the bed frame, and each one's G-code line.
type PathPoints = (Vec<DVec3>, Vec<usize>);

/// [`PathPoints`], with the holder's clearance along them where their two halves tell it
/// ([`layers::ClearanceRun::then`]).
type MeasuredPath = (PathPoints, Option<layers::ClearanceRun>);

/// The extruding path `moves[a..=b]` (`extruding`: a and b) for the layer search: the point it
/// starts from and each move's end, in the bed frame (`shift` added), with each point's line
/// and the holder's clearance along them (for a nozzle of `limits`); and the moves' tally
/// (`tally` of a range of moves: see [`MoveTally`]). In two halves, one on a second core and
/// one on this one, each copying its half of the path, measuring its clearance and tallying its
/// half of the moves: the copy was mostly the new buffers' page faults (3.2 ms on one core for
/// the benchmark vase's 7 MB, before batch commands took huge pages), the tally a pass over
/// every move, the clearance a pass of its own at the end of the self-check (1.5 ms on one core
/// in a slow hour).
fn extruding_path(
    moves: &[Move],
    start: DVec3,
    shift: DVec3,
    extruding: Option<(usize, usize)>,
    limits: &Limits,
    tally: impl Fn(std::ops::Range<usize>) -> MoveTally + Sync,
) -> (Option<MeasuredPath>, MoveTally) {
    let halves = |count: usize| [0..count / 2, count / 2..count];
    let two_cores = moves.len() >= crate::parallel::PARALLEL_POINTS;
    let Some((a, b)) = extruding else {
        let [first, second] = halves(moves.len());
        let (t0, t1) = crate::parallel::both(two_cores, || tally(first), || tally(second));
        return (None, t0.then(t1));
    };
    // Point k of the path is where move a + k − 1 ends (point 0: where move a starts); its
    // line is that move's (point 0: move a's).
    let count = b - a + 2;
    let (mut vertices, mut lines) = (Vec::with_capacity(count), Vec::with_capacity(count));
    let fill = |from: usize,
                points: &mut [std::mem::MaybeUninit<DVec3>],
                at: &mut [std::mem::MaybeUninit<usize>]| {
        let mut clearance = layers::ClearanceRun::new(limits);
        for (k, (p, l)) in (from..).zip(points.iter_mut().zip(at.iter_mut())) {
            let (to, line) = match k {
                0 if a == 0 => (start, moves[a].line),
                0 => (moves[a - 1].to + shift, moves[a].line),
                _ => (moves[a + k - 1].to + shift, moves[a + k - 1].line),
            };
            p.write(to);
            l.write(line);
            clearance.add(to.z, line);
        }
        clearance
    };
    let half = count / 2;
    let (p0, p1) = vertices.spare_capacity_mut()[..count].split_at_mut(half);
    let (l0, l1) = lines.spare_capacity_mut()[..count].split_at_mut(half);
    let [first, second] = halves(moves.len());
    let ((c0, t0), (c1, t1)) = crate::parallel::both(
        two_cores,
        || (fill(0, p0, l0), tally(first)),
        || (fill(half, p1, l1), tally(second)),
    );
    // SAFETY: the two halves wrote every one of the first `count` slots of both buffers.
    unsafe {
        vertices.set_len(count);
        lines.set_len(count);
    }
    (Some(((vertices, lines), c0.then(c1))), t0.then(t1))
}

/// What single moves show, tallied over a range of them: the bounds of the extruding moves,
/// those outside the machine, moves without extrusion within the extruding path, retractions,
/// and how many moves extrude within it. Ranges tallied apart join in path order
/// ([`MoveTally::then`]) to the tally of the whole.
#[derive(Debug, PartialEq)]
struct MoveTally {
    lo: DVec3,
    hi: DVec3,
    outside: Tally,
    travel: Tally,
    retract: Tally,
    extruding: usize,
}

impl MoveTally {
    /// The tally of `moves[range]` (the move before the range ends where its first starts;
    /// the first move starts at `start`), `extruding` the first and last extruding move.
    fn of(
        moves: &[Move],
        range: std::ops::Range<usize>,
        start: DVec3,
        limits: &Limits,
        extruding: Option<(usize, usize)>,
    ) -> MoveTally {
        let [ox, oy] = limits.origin_offset();
        let shift = DVec3::new(ox, oy, 0.0);
        let mut t = MoveTally {
            lo: DVec3::splat(f64::INFINITY),
            hi: DVec3::splat(f64::NEG_INFINITY),
            outside: Tally::default(),
            travel: Tally::default(),
            retract: Tally::default(),
            extruding: 0,
        };
        let mut prev = match range.start {
            0 => start,
            k => moves[k - 1].to + shift,
        };
        for (k, m) in range.clone().zip(&moves[range]) {
            let to = m.to + shift;
            if m.de > 0.0 {
                t.lo = t.lo.min(to);
                t.hi = t.hi.max(to);
            }
            let eps = 1e-6;
            if !limits.on_bed(to.x, to.y, eps) || to.z < -eps || to.z > limits.max_z + eps {
                t.outside.add(0.0, m.line);
            }
            if m.de < 0.0 {
                t.retract.add(-m.de, m.line);
            }
            if let Some((a, b)) = extruding
                && k >= a
                && k <= b
            {
                if m.de > 0.0 {
                    t.extruding += 1;
                } else if k > a && to != prev {
                    t.travel.add(to.distance(prev), m.line);
                }
            }
            prev = to;
        }
        t
    }

    /// This tally followed by `later`'s (of the moves after this one's).
    fn then(self, later: MoveTally) -> MoveTally {
        MoveTally {
            lo: self.lo.min(later.lo),
            hi: self.hi.max(later.hi),
            outside: self.outside.then(later.outside),
            travel: self.travel.then(later.travel),
            retract: self.retract.then(later.retract),
            extruding: self.extruding + later.extruding,
        }
    }

    /// The bounds, the extruding moves' count and the violations of single moves (outside
    /// the machine, a move without extrusion within the extruding path, a retraction), into
    /// `report`.
    fn into_report(self, limits: &Limits, report: &mut CheckReport) {
        let [ox, oy] = limits.origin_offset();
        if self.lo.is_finite() {
            report.bounds_min = self.lo;
            report.bounds_max = self.hi;
        }
        report.extruding_moves = self.extruding;
        report.violations.extend(
            [
                self.outside.into_violation(
                    OUTSIDE,
                    "",
                    match limits.bed_shape {
                        crate::design::BedShape::Rectangle => format!(
                            "bed {} … {} × {} … {} mm, height 0 … {} mm",
                            -ox,
                            limits.bed_x - ox,
                            -oy,
                            limits.bed_y - oy,
                            limits.max_z
                        ),
                        crate::design::BedShape::Circle => format!(
                            "round bed {} mm across, height 0 … {} mm",
                            limits.bed_x, limits.max_z
                        ),
                    },
                ),
                self.travel.into_violation(
                    NOT_CONTINUOUS,
                    " mm (the longest)",
                    "moves without extrusion between the first and last extruding move".into(),
                ),
                self.retract.into_violation(
                    RETRACTION,
                    " mm of E",
                    "clay printing allows no retraction".into(),
                ),
            ]
            .into_iter()
            .flatten(),
        );
    }
}

/// Measures an extruding path (layer heights, overhang, support, holder collision) given as
/// points; the `line` of each event and violation is the point index. The app's nozzle replay
/// uses this on the toolpath so that it flags exactly what `clayloft check` would.
pub fn check_path(points: &[DVec3], limits: &Limits) -> CheckReport {
    let mut report = CheckReport {
        moves: points.len(),
        extruding_moves: points.len().saturating_sub(1),
        ..Default::default()
    };
    if let Err(e) = limits.validate() {
        report.violations.push(Violation {
            what: NOT_MEASURED,
            count: 1,
            worst: 0.0,
            unit: "",
            first_line: 0,
            detail: format!("limits: {e}"),
        });
        return report;
    }
    if points.len() >= 2 {
        let lines: Vec<usize> = (0..points.len()).collect();
        layers::measure_layers(points, &lines, limits, &mut report);
    }
    report
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::design::Printer;

    fn limits() -> Limits {
        Limits::from(&Printer::default())
    }

    proptest::proptest! {
        /// Moves tallied in two parts and joined give the tally of all of them, wherever the
        /// parts meet: moves on and off the bed, extruding, travelling and retracting, on a
        /// printer with its origin in the middle (so that the parts' first moves start from a
        /// shifted end).
        #[test]
        fn moves_tallied_in_parts_are_tallied_whole(
            steps in proptest::collection::vec(
                (-20.0..320.0f64, -20.0..320.0f64, -1.0..5.0f64, -2i32..4),
                1..60,
            ),
            cut in 0.0..=1.0f64,
        ) {
            let mut limits = limits();
            limits.origin = crate::design::Origin::Centre;
            let moves: Vec<Move> = steps
                .iter()
                .enumerate()
                .map(|(k, &(x, y, z, e))| Move {
                    to: DVec3::new(x - 150.0, y - 150.0, z),
                    de: f64::from(e.clamp(-1, 2)) * 0.5,
                    line: k + 10,
                })
                .collect();
            let start = DVec3::new(150.0, 150.0, 0.2);
            let extruding = moves
                .iter()
                .position(|m| m.de > 0.0)
                .zip(moves.iter().rposition(|m| m.de > 0.0));
            let tally = |r| MoveTally::of(&moves, r, start, &limits, extruding);
            let m = (cut * moves.len() as f64) as usize;
            proptest::prop_assert_eq!(
                tally(0..m).then(tally(m..moves.len())),
                tally(0..moves.len())
            );
        }
    }

    fn helix(radius_per_layer: f64, layers: usize, h: f64) -> String {
        let mut s = String::from("G21\nG90\nM83\nG0 X120 Y95 Z1\n");
        let n = 100;
        for k in 0..layers * n {
            let t = (k + 1) as f64 / n as f64;
            let a = std::f64::consts::TAU * t;
            let r = 30.0 + radius_per_layer * t;
            // Flat first revolution, then a helix that leaves it by the minimum layer height.
            let z = if k < n {
                h
            } else if t <= 2.0 {
                h + 0.25 + (h - 0.25) * (t - 1.0)
            } else {
                h * t
            };
            s += &format!(
                "G1 X{:.3} Y{:.3} Z{:.3} E0.5\n",
                90.0 + r * a.cos(),
                95.0 + r * a.sin(),
                z
            );
        }
        s
    }

    #[test]
    fn check_path_flags_each_point_like_the_gcode_checker() {
        let text = helix(1.5, 10, 1.0);
        let from_gcode = check_gcode(&text, &limits()).unwrap();
        let (moves, start) = parse_moves(&text).unwrap();
        let points: Vec<DVec3> = std::iter::once(start)
            .chain(moves.iter().map(|m| m.to))
            .collect();
        let r = check_path(&points[1..], &limits());
        let lean = |r: &CheckReport| {
            r.violations
                .iter()
                .find(|v| v.what == OVERHANG)
                .map(|v| v.count)
        };
        assert!(lean(&r).unwrap() > 0);
        assert_eq!(lean(&r), lean(&from_gcode));
        let overhangs: Vec<&PathEvent> = r.events.iter().filter(|e| e.what == OVERHANG).collect();
        assert_eq!(overhangs.len(), lean(&r).unwrap());
        assert!(overhangs.windows(2).all(|w| w[0].line < w[1].line));
        assert!(overhangs.iter().all(|e| e.value > 45.0));
        // A point far below a tall printed part is a holder collision at that index.
        let mut tower: Vec<DVec3> = (0..200)
            .map(|k| {
                DVec3::new(
                    90.0 + 30.0 * (k as f64 * 0.1).cos(),
                    95.0 + 30.0 * (k as f64 * 0.1).sin(),
                    1.0 + k as f64 * 0.2,
                )
            })
            .collect();
        tower.push(DVec3::new(90.0, 95.0, 1.0));
        let r = check_path(&tower, &limits());
        let hit: Vec<&PathEvent> = r.events.iter().filter(|e| e.what == COLLISION).collect();
        assert_eq!(hit.len(), 1);
        assert_eq!(hit[0].line, 200);
        assert!((hit[0].value - 39.8).abs() < 1e-9);
    }

    /// `verify_gcode` passes what the checker passes, and for what it does not gives the
    /// checker's own report.
    #[test]
    fn verifying_agrees_with_checking() {
        for text in [
            helix(0.0, 10, 1.0),
            helix(0.4, 10, 1.0),
            helix(1.5, 10, 1.0),
        ] {
            let checked = check_gcode(&text, &limits()).unwrap();
            // Written to the verifier in pieces cut anywhere: the same verdict.
            for piece in [1, 7, 4096] {
                let mut verifier = GcodeVerifier::with_capacity(0);
                for bytes in text.as_bytes().chunks(piece) {
                    std::io::Write::write_all(&mut verifier, bytes).unwrap();
                }
                assert_eq!(
                    verifier.finish(&limits()),
                    verify_gcode(&text, &limits()),
                    "pieces of {piece}"
                );
            }
            // A bed too small for it: the layers shown, the bed broken, the full report.
            let small = Limits {
                bed_x: 100.0,
                ..limits()
            };
            let mut verifier = GcodeVerifier::with_capacity(0);
            std::io::Write::write_all(&mut verifier, text.as_bytes()).unwrap();
            let report = verifier.finish(&small).unwrap().expect("off the bed");
            assert_eq!(report, check_gcode(&text, &small).unwrap());
            assert!(
                report
                    .violations
                    .iter()
                    .any(|v| v.what == "outside the machine")
            );
            match verify_gcode(&text, &limits()).unwrap() {
                None => assert!(checked.ok(), "{checked}"),
                Some(report) => {
                    assert!(!checked.ok());
                    assert_eq!(report, checked);
                }
            }
        }
        assert!(
            verify_gcode(&helix(0.0, 10, 1.0), &limits())
                .unwrap()
                .is_none()
        );
        assert!(
            verify_gcode(&helix(1.5, 10, 1.0), &limits())
                .unwrap()
                .is_some()
        );
    }

    #[test]
    fn vertical_spiral_passes() {
        let r = check_gcode(&helix(0.0, 10, 1.0), &limits()).unwrap();
        assert!(r.ok(), "{r}");
        assert!(r.max_overhang_deg < 1.0, "{}", r.max_overhang_deg);
        assert!((r.max_layer_height - 1.0).abs() < 0.01);
    }

    #[test]
    fn flare_past_45_is_an_overhang() {
        let r = check_gcode(&helix(1.5, 10, 1.0), &limits()).unwrap();
        let v = r
            .violations
            .iter()
            .find(|v| v.what == "overhang")
            .expect("overhang found");
        // 1.5 mm outward per 1 mm layer is 56°; steeper where the helix leaves the flat revolution.
        assert!(v.worst >= 56.0, "{}", v.worst);
        assert!(v.count > 500, "{}", v.count);
        // Said with its unit, once: "worst 56.310°, first at line … (wall leans past 45°)".
        let said = r.to_string();
        let line = said
            .lines()
            .find(|l| l.starts_with("VIOLATION overhang:"))
            .unwrap();
        assert!(
            line.contains(&format!("worst {:.3}°, first at line", v.worst))
                && line.ends_with("(wall leans past 45°)"),
            "{line}"
        );
        // 0.8 mm per layer in the steady helix is 38.7°: only the thin helix start breaks 45°.
        let mild = check_gcode(&helix(0.8, 10, 1.0), &limits()).unwrap();
        assert!(mild.violations.iter().all(|v| v.count < 200), "{mild}");
    }

    #[test]
    fn travel_and_retraction_break_continuity() {
        let g = "M83\nG1 X10 Y10 Z1 E1\nG1 X20 Y10 Z1 E1\nG0 X30 Y10\nG1 X40 Y10 Z1 E-1\nG1 X50 Y10 Z1 E1\n";
        let r = check_gcode(g, &limits()).unwrap();
        let kinds: Vec<_> = r.violations.iter().map(|v| v.what).collect();
        assert!(kinds.contains(&"not one continuous path"), "{kinds:?}");
        assert!(kinds.contains(&"retraction"), "{kinds:?}");
    }

    #[test]
    fn off_the_bed_and_too_high() {
        let r = check_gcode("G1 X500 Y10 Z1 E1\nG1 X10 Y10 Z900 E1\n", &limits()).unwrap();
        assert_eq!(r.violations[0].what, "outside the machine");
        assert_eq!(r.violations[0].count, 2);
    }

    #[test]
    fn absolute_extrusion_and_header_limits() {
        let g = "; clayloft-limits: bed_x=50 bed_y=50 max_z=20\nM82\nG1 X10 Y10 Z1 E1\nG1 X20 Y10 Z1 E2\nG1 X30 Y10 Z1 E3\n";
        let (l, _) = Limits::from_header(g).unwrap().unwrap();
        assert_eq!((l.bed_x, l.max_z, l.line_width), (50.0, 20.0, 3.0));
        let r = check_gcode(g, &l).unwrap();
        assert!(r.ok(), "{r}");
        assert_eq!(r.extruding_moves, 3);
    }

    #[test]
    fn line_numbers_and_checksums_are_understood() {
        let (moves, _) = parse_moves("N1 G1 X10 Y10 Z1 E1*37\nN2 G1 X20 Y10 Z1 E1*38\n").unwrap();
        assert_eq!(moves.len(), 2);
        assert_eq!(moves[1].to, DVec3::new(20.0, 10.0, 1.0));
    }

    #[test]
    fn garbage_is_an_error_with_a_line() {
        let e = check_gcode("G1 X10\nhello world\n", &limits()).unwrap_err();
        assert_eq!(e.line, 2);
        let e = check_gcode("G1 Xabc\n", &limits()).unwrap_err();
        assert!(e.message.contains("Xabc"));
        assert!(check_gcode("; nothing\n", &limits()).is_err());
    }

    /// Hostile files end quickly with violations or an error, whatever their numbers.
    #[test]
    fn hostile_numbers_are_violations_or_errors_never_a_hang() {
        // The four-line file that once ran for minutes: a coordinate of 1e9.
        let r = check_gcode(
            "M83\nG1 X10 Y10 Z1 E1\nG1 X1000000000 Y10 Z1 E1\nG1 X10 Y20 Z1 E1\n",
            &limits(),
        )
        .unwrap();
        assert!(
            r.violations.iter().any(|v| v.what == "outside the machine"),
            "{r}"
        );
        // Diagonals across a 10 m bed with the finest bead: too many cells for the budget.
        let mut big = String::from(
            "; clayloft-limits: bed_x=10000 bed_y=10000 max_z=10000 line_width=0.1 min_layer_height=0.01 max_layer_height=0.01\nM83\n",
        );
        for k in 0..2000 {
            let (x, y) = if k % 2 == 0 { (0, 0) } else { (10000, 10000) };
            big += &format!("G1 X{x} Y{y} Z{:.2} E1\n", 0.01 * (k / 2) as f64);
        }
        let (l, _) = Limits::from_header(&big).unwrap().unwrap();
        let r = check_gcode(&big, &l).unwrap();
        assert!(r.violations.iter().any(|v| v.what == NOT_MEASURED), "{r}");
        // A file that zig-zags on one spot, slowly rising: every chord in the same few cells,
        // every point searching all of them.
        let mut spot = String::from("M83\n");
        let n = 100_000;
        for k in 0..n {
            spot += &format!(
                "G1 X{:.3} Y90 Z{:.5} E0.01\n",
                90.0 + 0.5 * (k % 2) as f64,
                1.0 + k as f64 / n as f64
            );
        }
        let r = check_gcode(&spot, &limits()).unwrap();
        assert!(r.violations.iter().any(|v| v.what == NOT_MEASURED), "{r}");
        // The same zig-zag at one height on the bed: no chord is within a layer's reach below
        // any point, so none is a candidate and every point rests on the bed (the search by
        // 3-D cells spent its budget on them and called the file not measurable).
        let flat = spot
            .lines()
            .map(|l| match l.find(" Z") {
                Some(at) => format!("{} Z0.5 E0.01\n", &l[..at]),
                None => format!("{l}\n"),
            })
            .collect::<String>();
        let r = check_gcode(&flat, &limits()).unwrap();
        assert!(r.ok(), "{r}");
        assert_eq!((r.min_layer_height, r.max_layer_height), (0.5, 0.5));
        // Relative moves that run past every finite number.
        let e = check_gcode("G91\nG1 X1e308 E1\nG1 X1e308 E1\n", &limits()).unwrap_err();
        assert!(e.message.contains("finite"), "{e}");
        // An absurd line: its word is quoted short.
        let long = format!("G1 X{}abc\n", "9".repeat(1_000_000));
        let e = check_gcode(&long, &limits()).unwrap_err();
        assert!(e.message.len() < 200, "{}", e.message.len());
        // Microscopic or absurd limits are refused, never used.
        let tiny = Limits {
            line_width: 1e-9,
            ..limits()
        };
        assert!(
            check_gcode("G1 X1 E1\n", &tiny)
                .unwrap_err()
                .message
                .contains("line_width")
        );
        let r = check_path(&[DVec3::ZERO, DVec3::X], &tiny);
        assert_eq!(r.violations[0].what, NOT_MEASURED);
    }

    #[test]
    fn chords_stand_for_nearly_collinear_runs() {
        // A finely sampled circle: chords about a millimetre long, whatever the sampling.
        let n = 20_000;
        let circle: Vec<DVec3> = (0..=n)
            .map(|k| {
                let a = std::f64::consts::TAU * k as f64 / n as f64;
                DVec3::new(50.0 * a.cos(), 50.0 * a.sin(), 1.0)
            })
            .collect();
        let c = layers::chords(&circle);
        assert!(c.len() < n / 10, "{}", c.len());
        assert_eq!(c.first().unwrap().0, 0);
        assert_eq!(c.last().unwrap().1, n);
        assert!(c.windows(2).all(|w| w[0].1 == w[1].0));
        // A square's corners are kept.
        let square = [
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(5.0, 0.0, 0.0),
            DVec3::new(10.0, 0.0, 0.0),
            DVec3::new(10.0, 10.0, 0.0),
        ];
        assert_eq!(layers::chords(&square), vec![(0, 2), (2, 3)]);
    }
}
