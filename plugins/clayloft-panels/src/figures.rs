//! The status line's figures of the current job: its path length and its print time as the
//! motion planner estimates it (acceleration, corners, look-ahead: the figure the G-code's
//! header, `clayloft gcode` and the printer panel give), not the time at the points' nominal
//! speeds, which is up to 13 % short on the shipped designs. The planner walks the whole path
//! (1.3 ms for 77 000 points), so it runs on a thread of its own, one toolpath at a time: while
//! a drag makes a new toolpath every frame, the line shows the last figures worked out and
//! catches up when the work is done.

use clayloft_core::PrintJob;
use clayloft_core::gcode::summarize;
use clayloft_model::background::Background;

/// Path length, mm, and planned print time, s.
pub type Figures = (f64, f64);

/// The figures shown and the work under way (see the module documentation).
#[derive(Default)]
pub struct JobFigures {
    /// The toolpath the figures are of (its address), and the figures.
    shown: Option<(usize, Figures)>,
    /// The toolpath being worked out, and the work.
    running: Option<(usize, Background<Figures>)>,
}

impl JobFigures {
    /// The latest figures for the toolpath at address `key` (the figures of an earlier toolpath
    /// until its own are worked out), and whether work is still under way (ask for another
    /// frame to show its result). `job` gives the job to work out when its figures are needed
    /// and no work runs.
    pub fn update(
        &mut self,
        key: usize,
        job: impl FnOnce() -> Option<(clayloft_core::Design, PrintJob)>,
    ) -> (Option<Figures>, bool) {
        if let Some((of, work)) = &mut self.running
            && let Some(done) = work.poll()
        {
            // A planner that panicked leaves the last figures (and is not retried for this path).
            self.shown = Some((*of, done.unwrap_or(self.shown.map_or((0.0, 0.0), |s| s.1))));
            self.running = None;
        }
        let current = self.shown.is_some_and(|(of, _)| of == key);
        if !current
            && self.running.is_none()
            && let Some((design, job)) = job()
        {
            self.running = Some((
                key,
                Background::start(move || {
                    let s = summarize(&design, &job);
                    (s.path_length_mm, s.estimated_time_s)
                }),
            ));
        }
        (self.shown.map(|(_, f)| f), self.running.is_some())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn job(height: f64) -> (clayloft_core::Design, PrintJob) {
        let d = clayloft_core::load::parse_design(&format!(
            "version = 1\n[shape]\nheight = {height}\nsamples = 90\nlower = {{ type = \"rose\", radius = 40.0, amplitude = 6.0, petals = 5 }}\nupper = {{ type = \"circle\", radius = 35.0 }}\n"
        ))
        .unwrap();
        let job = clayloft_core::run(&d).unwrap();
        (d, job)
    }

    /// Polls until the work is done.
    fn settle(f: &mut JobFigures, key: usize) -> Figures {
        loop {
            match f.update(key, || None) {
                (Some(figures), false) => return figures,
                _ => std::thread::sleep(std::time::Duration::from_millis(1)),
            }
        }
    }

    /// The figures are the G-code header's (the planner's time, longer than at nominal speeds
    /// on a path of short segments), worked out once per toolpath; a new toolpath shows the
    /// last figures until its own are in.
    #[test]
    fn the_figures_are_the_planners_once_per_toolpath() {
        let (d, j) = job(30.0);
        let mut f = JobFigures::default();
        assert_eq!(f.update(1, || Some(job(30.0))), (None, true));
        let first = settle(&mut f, 1);
        let s = summarize(&d, &j);
        assert_eq!(first, (s.path_length_mm, s.estimated_time_s));
        assert!(s.estimated_time_s > j.toolpath.print_time());
        // The same toolpath: no new work.
        assert_eq!(
            f.update(1, || panic!("worked out twice")),
            (Some(first), false)
        );
        // A taller vessel: the old figures until the new ones are in.
        assert_eq!(f.update(2, || Some(job(60.0))), (Some(first), true));
        // While it runs, another toolpath waits its turn (no second thread).
        let (shown, busy) = f.update(3, || panic!("started beside the running work"));
        assert!(busy && shown.is_some());
        let taller = settle(&mut f, 2);
        assert!(taller.0 > 1.5 * first.0 && taller.1 > 1.5 * first.1);
    }
}
