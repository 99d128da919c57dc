//! A job's G-code written to a file, right first time: what `clayloft gcode` and the app's
//! "Export G-code" both do. Every piece the writer gives goes to a temporary file beside the
//! output and to the self-check ([`crate::check::GcodeVerifier`], which takes it in as moves as
//! it comes, so the text is never held whole). With `constraints.enforce`, the file is renamed
//! into place only when the check passes: a design that still breaks a limit on its printer is
//! refused with what broke, and no file (nor temporary) is left. Without it, the file is written
//! as designed and what the checker finds is reported with it (SPEC §2: "report violations
//! without changing the shape"), the loops of a path crossing itself among them, which only
//! the checker measures.
//!
//! The path's body (all but a few hundred lines) reaches the self-check as the moves the writer
//! formatted, each number as its text reads back to the bit (`decimal::Line::fixed_read`), not
//! as text to read again: the same moves as reading the file (tested on every printer form in
//! `check::moves`), about a tenth less time for the whole command (median 132.7 → 118.2 ms for the
//! benchmark vase, 2026-12-06). The header, start and end G-code are read as text.

use std::io::Write;
use std::path::Path;

use crate::atomic::{Replaced, WriteError};
use crate::check::{
    CROSSING, CheckReport, GcodeError, GcodeVerifier, Limits, NOT_CONTINUOUS, OUTSIDE, RETRACTION,
    Violation,
};
use crate::design::Design;
use crate::gcode::{JobSummary, PieceSink, ProgramOut, write_program_to};
use crate::pipeline::PrintJob;

/// A G-code file in place: the header's figures, and the file it replaced (see [`Replaced`]:
/// dropping it frees the old file's data, which a caller may do where it costs nothing).
pub struct Written {
    pub summary: JobSummary,
    pub replaced: Replaced,
    /// The limits the program breaks, as the checker finds them, where the design does not
    /// enforce its constraints: written as designed and reported (SPEC §2), not refused. Empty
    /// where it enforces them (the file passed the self-check) or where nothing breaks.
    pub unenforced: Vec<Violation>,
}

/// Why a job's G-code was not written.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    /// The file could not be written (the message names it).
    #[error(transparent)]
    Write(#[from] WriteError),
    /// The program written does not read back as G-code (a writer's fault, never a design's).
    #[error("{file}: the G-code written does not read back: {error}")]
    Unreadable { file: String, error: GcodeError },
    /// The program breaks a limit of its printer: the worst-reported violation.
    #[error(
        "does not print on this printer ({printer}): {what} at {count} {}{worst} ({detail}); {}",
        if *count == 1 { "point" } else { "points" },
        advice(what)
    )]
    Refused {
        printer: String,
        what: &'static str,
        count: usize,
        /// ", worst 0.19 mm short", or nothing where the limit has no measure.
        worst: String,
        detail: String,
    },
}

/// What a potter can change when the self-check finds `what` broken. A vessel's path is one
/// extruding spiral inside the machine by construction, so breaks of those rules come from the
/// printer's start or end G-code; the others from the vessel on this printer.
fn advice(what: &str) -> &'static str {
    if what == NOT_CONTINUOUS || what == RETRACTION {
        "the printer's start or end G-code travels or retracts between extruding moves (a purge line?): leave that out of it"
    } else if what == OUTSIDE {
        "the printer's start or end G-code moves outside the machine, or the vessel does not fit it"
    } else if what == CROSSING {
        // A finer bead would make it stricter (the loop is let be within half a bead), and
        // thinner layers do not change it: the shape folds the path.
        "the wall turns back on itself there: gentler control lines, a shallower texture or one of a longer period, or a rounder contour where the wall turns sharply (its corrections, in `clayloft info` or the app's Constraints panel, say where the shape had to change)"
    } else {
        "try a printer with a finer bead or thinner layers, or a simpler contour, gentler control lines or a shallower texture (its corrections, in `clayloft info` or the app's Constraints panel, say where the shape had to change)"
    }
}

/// Writes the G-code of `job` (of `design`) to `path`, re-measured on its way (see the module
/// documentation): refused where the design enforces its constraints and the program breaks a
/// limit, else written, with what it breaks when the design does not enforce them.
pub fn write_checked_gcode(
    design: &Design,
    job: &PrintJob,
    path: &Path,
) -> Result<Written, ExportError> {
    let mut verifier = GcodeVerifier::with_capacity(job.toolpath.points.len() + 64);
    let (pending, summary) = crate::atomic::prepare(path, |file| {
        let mut sink = Tee {
            file,
            verifier: &mut verifier,
            written: 0,
            started: 0,
        };
        write_program_to(design, job, &mut sink).map_err(std::io::Error::from)
    })?;
    let report = verifier
        .finish(&Limits::from(&design.printer))
        .map_err(|error| ExportError::Unreadable {
            file: path.display().to_string(),
            error,
        })?;
    let mut unenforced = Vec::new();
    if design.constraints.enforce {
        if let Some(refusal) = refusal(design, report.as_ref()) {
            // Dropped, the pending file is deleted: nothing is written.
            drop(pending);
            return Err(refusal);
        }
    } else if let Some(report) = report {
        unenforced = report.violations;
    }
    let replaced = pending.commit()?;
    Ok(Written {
        summary,
        replaced,
        unenforced,
    })
}

/// Whether a program in memory (`text`, what a printer host streams) may go to the printer of
/// `design`: the self-check of [`write_checked_gcode`] when the design enforces its
/// constraints, with the same refusal.
pub fn verify_program(design: &Design, text: &str) -> Result<(), ExportError> {
    if !design.constraints.enforce {
        return Ok(());
    }
    let report =
        crate::check::verify_gcode(text, &Limits::from(&design.printer)).map_err(|error| {
            ExportError::Unreadable {
                file: "the program".into(),
                error,
            }
        })?;
    refusal(design, report.as_ref()).map_or(Ok(()), Err)
}

/// The refusal of a program whose self-check found `report` (none when it holds).
fn refusal(design: &Design, report: Option<&CheckReport>) -> Option<ExportError> {
    let v = report?.violations.first()?;
    Some(ExportError::Refused {
        printer: design
            .printer
            .profile
            .clone()
            .unwrap_or_else(|| "the paper's printer".into()),
        what: v.what,
        count: v.count,
        worst: v.worst_said(2),
        detail: v.detail.clone(),
    })
}

/// Writes to the output file and to the self-check, which takes the body's moves as the writer
/// tells them (the text they read as, tested) and reads the rest of the text. Each piece of the
/// body goes to its place in the file, and its moves to the self-check, from the core that
/// formatted it, as soon as it is formatted ([`FileSink`]); where the self-check cannot take
/// pieces so (a line cut before the body), a round of pieces goes to the file on a second
/// core while this one reads it. The text written is started for the disk a megabyte at a
/// time (see [`crate::atomic::start_writeback`]).
struct Tee<'a, 'f> {
    file: &'a mut crate::atomic::Output<'f>,
    verifier: &'a mut GcodeVerifier,
    /// Bytes given to the file so far, and those started for the disk.
    written: u64,
    started: u64,
}

impl ProgramOut for Tee<'_, '_> {
    fn text(&mut self, bytes: &[u8]) -> std::io::Result<()> {
        self.file.write_all(bytes)?;
        self.written += bytes.len() as u64;
        self.verifier.write_all(bytes)
    }

    fn wants_moves(&self) -> bool {
        true
    }

    fn body(&mut self, pieces: &[crate::check::ToldPiece<'_>]) -> std::io::Result<()> {
        // What was given before this round is in the file (a piece at least as long as the
        // writer's buffer is written through, after what the buffer held).
        let before = self.started..self.written;
        let disk = self.file.file();
        let (file, verifier) = (&mut *self.file, &mut *self.verifier);
        let (written, ()) = crate::parallel::both(
            true,
            move || pieces.iter().try_for_each(|p| file.write_all(p.text)),
            || {
                crate::atomic::start_writeback(disk, before);
                verifier.feed_told(pieces);
            },
        );
        self.started = self.written;
        self.written += pieces.iter().map(|p| p.text.len() as u64).sum::<u64>();
        written
    }

    fn with_sink(
        &mut self,
        moves: usize,
        body: &mut dyn FnMut(&dyn PieceSink) -> std::io::Result<()>,
    ) -> Option<std::io::Result<()>> {
        // The text before the body is in the file; each piece goes after it, at its place.
        if let Err(e) = self.file.flush() {
            return Some(Err(e));
        }
        let file = self.file.file();
        let started = std::sync::atomic::AtomicU64::new(self.started);
        let mut outcome = Ok(());
        let end = self.verifier.stream_told(self.written, moves, |stream| {
            let sink = FileSink {
                stream,
                file,
                started: &started,
            };
            outcome = body(&sink);
        })?;
        let outcome = outcome.and_then(|()| self.file.continue_at(end));
        self.started = started.into_inner();
        self.written = end;
        Some(outcome)
    }
}

/// The body's pieces, each written to its place in the file and resolved by the self-check on
/// the core that formatted it ([`crate::check::ToldStream`]).
struct FileSink<'s, 'r> {
    stream: &'s crate::check::ToldStream<'r>,
    file: &'s std::fs::File,
    /// Where the text not yet started for the disk begins.
    started: &'s std::sync::atomic::AtomicU64,
}

/// Bytes of the body started for the disk at a time ([`crate::atomic::start_writeback`]):
/// about a round of the writer's pieces, so that little is left to write at the rename.
const WRITEBACK_BYTES: u64 = 1 << 20;

impl PieceSink for FileSink<'_, '_> {
    fn take(&self, k: usize, piece: &crate::check::ToldPiece<'_>) -> std::io::Result<()> {
        let mut result = Ok(());
        self.stream.take(k, piece, |offset| {
            result = crate::atomic::write_at(self.file, piece.text, offset);
            // The text before this piece is placed (and mostly written): started for the disk
            // once a megabyte of it waits.
            use std::sync::atomic::Ordering;
            let from = self.started.load(Ordering::Relaxed);
            if offset >= from + WRITEBACK_BYTES
                && self
                    .started
                    .compare_exchange(from, offset, Ordering::Relaxed, Ordering::Relaxed)
                    .is_ok()
            {
                crate::atomic::start_writeback(self.file, from..offset);
            }
        });
        result
    }

    fn abandon(&self) {
        self.stream.abandon();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A refusal says what a potter can change: the printer's G-code for a break of the one
    /// path or of the machine's bounds (a vessel's path keeps those by construction), else the
    /// printer, the contour, the control lines or the texture.
    #[test]
    fn a_refusal_advises_by_what_broke() {
        for what in [NOT_CONTINUOUS, RETRACTION, OUTSIDE] {
            assert!(advice(what).contains("start or end G-code"), "{what}");
        }
        for what in [
            crate::check::OVERHANG,
            crate::check::UNSUPPORTED,
            "layer too thin",
        ] {
            assert!(advice(what).contains("finer bead"), "{what}");
            assert!(advice(what).contains("gentler control lines"), "{what}");
        }
        // A loop: the shape, not the printer.
        let loops = advice(CROSSING);
        assert!(!loops.contains("finer bead") && loops.contains("shallower texture"));
    }

    /// A refusal at one point says "1 point" (it said "1 points").
    #[test]
    fn a_refusal_counts_its_points_in_words() {
        let refused = |count| ExportError::Refused {
            printer: "the paper's printer".into(),
            what: "layer too thin",
            count,
            worst: ", worst 0.02 mm short".into(),
            detail: "below min_layer_height 0.25 mm".into(),
        };
        let said = refused(1).to_string();
        assert!(
            said.contains("layer too thin at 1 point, worst 0.02 mm short"),
            "{said}"
        );
        let said = refused(3).to_string();
        assert!(said.contains("layer too thin at 3 points, worst"), "{said}");
    }

    /// A refusal says how far the worst point is past the limit, in the limit's own unit: a
    /// vessel of 1 mm layers (thinner where the spiral leaves the flat first revolution) on a
    /// printer that now lays them no thinner than 1.05 mm.
    #[test]
    fn a_refusal_says_the_worst_in_its_unit() {
        let (mut d, job) = vessel("");
        d.printer.min_layer_height = 1.05;
        d.printer.max_layer_height = 1.2;
        let program = crate::gcode::program(&d, &job).unwrap();
        let e = verify_program(&d, &program.text).expect_err("refused");
        let said = e.to_string();
        let worst = said
            .split_once(" points, worst ")
            .and_then(|(_, rest)| rest.split_once(" mm short (below min_layer_height 1.05 mm); "))
            .and_then(|(number, _)| number.parse::<f64>().ok());
        assert!(
            said.contains("layer too thin at ") && worst.is_some_and(|w| (0.05..1.05).contains(&w)),
            "{said}"
        );
    }

    /// A program the self-check cannot read (a start G-code moving past any finite number):
    /// its body goes to the file in rounds, as the self-check takes pieces only in order after
    /// an error, and the export fails naming the line; the old file stays, with nothing beside.
    #[test]
    fn a_program_the_checker_cannot_read_is_not_written() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("v.gcode");
        std::fs::write(&out, "old").unwrap();
        let (mut d, job) = vessel("");
        d.printer.start_gcode = Some("G28\nG1 X1e999\n".into());
        let e = write_checked_gcode(&d, &job, &out)
            .err()
            .expect("unreadable");
        assert!(
            matches!(&e, ExportError::Unreadable { error, .. } if error.message.contains("finite")),
            "{e}"
        );
        assert_eq!(std::fs::read_to_string(&out).unwrap(), "old");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    fn vessel(extra: &str) -> (Design, PrintJob) {
        let d = crate::load::parse_design(&format!(
            "version = 1\n[shape]\nheight = 20.0\nsamples = 120\nlower = {{ type = \"circle\", radius = 30.0 }}\nupper = {{ type = \"circle\", radius = 32.0 }}\n{extra}"
        ))
        .unwrap();
        let job = crate::run(&d).unwrap();
        (d, job)
    }

    /// A design that keeps its limits: the file is the writer's program, byte for byte, and
    /// replaces what was there.
    #[test]
    fn a_design_that_keeps_its_limits_is_written() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("v.gcode");
        std::fs::write(&out, "old").unwrap();
        let (d, job) = vessel("");
        let written = write_checked_gcode(&d, &job, &out).unwrap();
        let mut want = Vec::new();
        let summary = crate::gcode::write_gcode_summarized(&d, &job, &mut want).unwrap();
        assert_eq!(std::fs::read(&out).unwrap(), want);
        assert_eq!(written.summary, summary);
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    /// A program that breaks a limit of its printer (a bed narrower than the vessel's path,
    /// found by the checker alone: the design is given a wide bed, its printer limits a narrow
    /// one): refused with what broke, and the old file stays, with no temporary beside it.
    /// Without enforcement the same program is written.
    #[test]
    fn a_program_past_its_printers_limits_is_refused_and_nothing_is_written() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("v.gcode");
        std::fs::write(&out, "old").unwrap();
        let (mut d, job) = vessel("");
        // The job was made for the default bed; the printer now ends just short of the vessel's
        // far side.
        let far = job
            .toolpath
            .points
            .iter()
            .map(|q| q.pos.x)
            .fold(0.0, f64::max);
        d.printer.bed_x = far - 5.0;
        let e = write_checked_gcode(&d, &job, &out).err().expect("refused");
        assert!(
            matches!(e, ExportError::Refused { count, .. } if count > 0),
            "{e}"
        );
        assert!(
            e.to_string()
                .starts_with("does not print on this printer (the paper's printer): "),
            "{e}"
        );
        // Off the bed has no measure: no "worst" is said.
        assert!(!e.to_string().contains("worst"), "{e}");
        assert_eq!(std::fs::read_to_string(&out).unwrap(), "old");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
        // A printer host's program in memory: the same refusal.
        let program = crate::gcode::program(&d, &job).unwrap();
        let again = verify_program(&d, &program.text).expect_err("refused");
        assert_eq!(again.to_string(), e.to_string());
        d.constraints.enforce = false;
        assert!(verify_program(&d, &program.text).is_ok());
        assert!(write_checked_gcode(&d, &job, &out).is_ok());
        assert_ne!(std::fs::read_to_string(&out).unwrap(), "old");
    }
}
