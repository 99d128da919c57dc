//! What the panels show of the current job that takes a walk over its whole path, worked out
//! on a thread of its own once per toolpath, one toolpath at a time ([`PerToolpath`]): while a
//! drag makes a new toolpath every frame, the panels show the last result and catch up when the
//! work is done.
//!
//! - The status line's figures: the path length and the print time as the motion planner
//!   estimates it (acceleration, corners, look-ahead: the figure the G-code's header,
//!   `clayloft gcode` and the printer panel give), not the time at the points' nominal speeds,
//!   which is up to 13 % short on the shipped designs (1.3 ms for 77 000 points).
//! - The checks panel's verdict on the job's G-code: the self-check that "Export G-code" and
//!   "Print design" run ([`clayloft_core::export::verify_program`]), so that a program they would
//!   refuse is named before either is tried (24 ms for 77 000 points, 13 of them writing the
//!   program: started once the toolpath has stayed the same for [`CHECK_SETTLE`]).

use std::time::{Duration, Instant};

use clayloft_core::gcode::summarize;
use clayloft_core::{Design, PrintJob};
use clayloft_model::background::Background;

/// Path length, mm, and planned print time, s.
pub type Figures = (f64, f64);

/// The self-check's verdict on a job's program: `Err` with why it would be refused.
pub type ProgramVerdict = Result<(), String>;

/// How long a toolpath stays the same before its program is checked (not while a handle or a
/// field is dragged).
pub const CHECK_SETTLE: Duration = Duration::from_millis(400);

/// The latest result of work done once per toolpath (see the module documentation).
pub struct PerToolpath<T> {
    /// The toolpath the result is of (its address), and the result.
    shown: Option<(usize, T)>,
    /// The toolpath being worked on, and the work.
    running: Option<(usize, Background<T>)>,
}

impl<T> Default for PerToolpath<T> {
    fn default() -> Self {
        PerToolpath {
            shown: None,
            running: None,
        }
    }
}

/// What [`PerToolpath::update`] gives: the latest result, whether it is of the current
/// toolpath, and whether work is still under way (ask for another frame to show its result).
pub struct Latest<'a, T> {
    pub result: Option<&'a T>,
    pub current: bool,
    pub busy: bool,
}

impl<T: Send + 'static> PerToolpath<T> {
    /// Takes finished work in, and starts `start()`'s for the toolpath at address `key` when its
    /// result is wanted and no work runs (`start` may decline: not yet, or nothing to do).
    pub fn update(
        &mut self,
        key: usize,
        start: impl FnOnce() -> Option<Background<T>>,
    ) -> Latest<'_, T> {
        if let Some((of, work)) = &mut self.running
            && let Some(done) = work.poll()
        {
            // Work that panicked leaves the last result (and is not retried for this path).
            if let Ok(result) = done {
                self.shown = Some((*of, result));
            }
            self.running = None;
        }
        let current = self.shown.as_ref().is_some_and(|(of, _)| *of == key);
        if !current
            && self.running.is_none()
            && let Some(work) = start()
        {
            self.running = Some((key, work));
        }
        Latest {
            result: self.shown.as_ref().map(|(_, r)| r),
            current,
            busy: self.running.is_some(),
        }
    }
}

/// The panels' work on the current job: the status line's figures, the program check, and the
/// toolpath the check waits to settle on (and since when).
#[derive(Default)]
pub struct JobWork {
    figures: PerToolpath<Figures>,
    check: PerToolpath<ProgramVerdict>,
    settled: Option<(usize, Instant)>,
}

/// What the panels show of the current job this frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Shown {
    /// The latest figures (perhaps of an earlier toolpath).
    pub figures: Option<Figures>,
    /// The verdict on the current toolpath's program, once worked out.
    pub check: Option<ProgramVerdict>,
    /// Work runs or waits: ask for another frame.
    pub busy: bool,
}

impl JobWork {
    /// Takes finished work in and starts what the toolpath at address `key` needs at `now`:
    /// its figures at once, the check of its program (for a design that enforces its
    /// constraints) once it has stayed the same for [`CHECK_SETTLE`]. `job` gives the design
    /// and job to work on (none while the session is behind the document).
    pub fn update(
        &mut self,
        key: usize,
        now: Instant,
        enforce: bool,
        job: impl Fn() -> Option<(Design, PrintJob)>,
    ) -> Shown {
        let since = match self.settled {
            Some((of, t)) if of == key => t,
            _ => self.settled.insert((key, now)).1,
        };
        let settling = now.duration_since(since) < CHECK_SETTLE;
        let f = self.figures.update(key, || {
            job().map(|(design, job)| work_out_figures(design, job))
        });
        let (figures, figures_busy) = (f.result.copied(), f.busy);
        let c = self.check.update(key, || {
            if settling || !enforce {
                return None;
            }
            job().map(|(design, job)| check_program(design, job))
        });
        let waiting = enforce && settling && !c.current;
        Shown {
            figures,
            check: c.current.then(|| c.result.cloned()).flatten(),
            busy: figures_busy || c.busy || waiting,
        }
    }
}

/// The status line's figures of `job`, on a thread of their own.
pub fn work_out_figures(design: Design, job: PrintJob) -> Background<Figures> {
    Background::start(move || {
        let s = summarize(&design, &job);
        (s.path_length_mm, s.estimated_time_s)
    })
}

/// The self-check of `job`'s program, on a thread of its own (see the module documentation).
pub fn check_program(design: Design, job: PrintJob) -> Background<ProgramVerdict> {
    Background::start(move || {
        let program = clayloft_core::gcode::program(&design, &job).map_err(|e| e.to_string())?;
        clayloft_core::export::verify_program(&design, &program.text).map_err(|e| e.to_string())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn job(height: f64) -> (Design, PrintJob) {
        let d = clayloft_core::load::parse_design(&format!(
            "version = 1\n[shape]\nheight = {height}\nsamples = 90\nlower = {{ type = \"rose\", radius = 40.0, amplitude = 6.0, petals = 5 }}\nupper = {{ type = \"circle\", radius = 35.0 }}\n"
        ))
        .unwrap();
        let job = clayloft_core::run(&d).unwrap();
        (d, job)
    }

    /// Polls until the work for `key` is in.
    fn settle<T: Send + Clone + 'static>(w: &mut PerToolpath<T>, key: usize) -> T {
        loop {
            let latest = w.update(key, || None);
            if latest.current {
                return latest.result.cloned().expect("a result");
            }
            assert!(latest.busy, "no work for the current toolpath");
            std::thread::sleep(std::time::Duration::from_millis(1));
        }
    }

    /// The figures are the G-code header's (the planner's time, longer than at nominal speeds
    /// on a path of short segments), worked out once per toolpath; a new toolpath shows the
    /// last figures until its own are in, and one work runs at a time.
    #[test]
    fn the_figures_are_the_planners_once_per_toolpath() {
        let (d, j) = job(30.0);
        let mut f = PerToolpath::default();
        let first = f.update(1, || {
            let (d, j) = job(30.0);
            Some(work_out_figures(d, j))
        });
        assert!(first.result.is_none() && !first.current && first.busy);
        let first = settle(&mut f, 1);
        let s = summarize(&d, &j);
        assert_eq!(first, (s.path_length_mm, s.estimated_time_s));
        assert!(s.estimated_time_s > j.toolpath.print_time());
        // The same toolpath: no new work.
        let again = f.update(1, || panic!("worked out twice"));
        assert_eq!(
            (again.result, again.current, again.busy),
            (Some(&first), true, false)
        );
        // A taller vessel: the old figures until the new ones are in. Its work waits for a
        // word from here, so that it surely still runs below.
        let (go, wait) = std::sync::mpsc::channel::<()>();
        let taller = f.update(2, || {
            let (d, j) = job(60.0);
            Some(Background::start(move || {
                let _ = wait.recv();
                let s = summarize(&d, &j);
                (s.path_length_mm, s.estimated_time_s)
            }))
        });
        assert_eq!(
            (taller.result, taller.current, taller.busy),
            (Some(&first), false, true)
        );
        // While it runs, another toolpath waits its turn (no second thread).
        let third = f.update(3, || panic!("started beside the running work"));
        assert!(third.busy && !third.current);
        go.send(()).unwrap();
        let taller = settle(&mut f, 2);
        assert!(taller.0 > 1.5 * first.0 && taller.1 > 1.5 * first.1);
    }

    /// The program is checked only once its toolpath has settled, the figures at once; while
    /// the check waits or runs the panels ask for frames, and once both are in they do not.
    #[test]
    fn the_program_is_checked_once_the_toolpath_settles() {
        let mut w = JobWork::default();
        let t0 = Instant::now();
        let started = std::cell::Cell::new(0);
        let make = || {
            started.set(started.get() + 1);
            Some(job(20.0))
        };
        let first = w.update(1, t0, true, make);
        assert_eq!((first.check.clone(), first.busy), (None, true));
        assert_eq!(
            started.get(),
            1,
            "the figures start at once, the check waits"
        );
        // Still settling: no check started.
        let soon = w.update(1, t0 + CHECK_SETTLE / 2, true, make);
        assert!(soon.busy && soon.check.is_none());
        assert_eq!(started.get(), 1);
        // Settled: the check starts, and its verdict comes in.
        let mut shown = w.update(1, t0 + CHECK_SETTLE, true, make);
        assert_eq!(started.get(), 2);
        while shown.busy {
            std::thread::sleep(Duration::from_millis(1));
            shown = w.update(1, t0 + 2 * CHECK_SETTLE, true, make);
        }
        assert_eq!(shown.check, Some(Ok(())));
        assert!(shown.figures.is_some());
        // A design that does not enforce its constraints is not checked.
        let mut free = JobWork::default();
        let s = free.update(1, t0 + CHECK_SETTLE, false, || Some(job(20.0)));
        assert!(s.check.is_none());
        let mut s = s;
        while s.busy {
            std::thread::sleep(Duration::from_millis(1));
            s = free.update(1, t0 + 2 * CHECK_SETTLE, false, || Some(job(20.0)));
        }
        assert!(s.check.is_none() && s.figures.is_some());
    }

    /// The self-check's verdict is the export's: the flared bowl on the WASP (refused by
    /// `clayloft gcode`) does not pass, with the same words; on the default printer it does.
    #[test]
    fn the_program_check_is_the_exports() {
        let bowl = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../assets/designs/flared-bowl.toml");
        for (printer, passes) in [(Some("wasp-2040-clay"), false), (None, true)] {
            let design = clayloft_core::load::load_design_using(&bowl, printer)
                .unwrap()
                .design;
            let job = clayloft_core::run(&design).unwrap();
            let mut c = PerToolpath::default();
            c.update(7, || Some(check_program(design.clone(), job.clone())));
            let verdict = settle(&mut c, 7);
            assert_eq!(verdict.is_ok(), passes, "{printer:?}: {verdict:?}");
            if let Err(why) = verdict {
                assert!(
                    why.starts_with("does not print on this printer (wasp-2040-clay)"),
                    "{why}"
                );
                let dir = tempfile::tempdir().unwrap();
                let refused = clayloft_core::export::write_checked_gcode(
                    &design,
                    &job,
                    &dir.path().join("b.gcode"),
                )
                .err()
                .expect("the export refuses it too");
                assert_eq!(refused.to_string(), why);
            }
        }
    }
}
