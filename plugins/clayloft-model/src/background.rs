//! Work on a thread of its own, for the systems that must not wait for it (an export, the
//! replay's check): started once, then polled each frame until its result is there. The app
//! draws on input only, so a system with work running asks for the next frame itself.

use std::sync::Mutex;
use std::sync::mpsc::{Receiver, TryRecvError};

/// One piece of work running on its own thread.
pub struct Background<T> {
    /// In a mutex only so that a resource holding it is `Sync`; only its owner polls it.
    result: Mutex<Receiver<T>>,
}

/// The work stopped without a result (it panicked).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Stopped;

impl<T: Send + 'static> Background<T> {
    /// Starts `work` on a new thread.
    pub fn start(work: impl FnOnce() -> T + Send + 'static) -> Self {
        let (tx, rx) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            // The receiver may be gone (its owner gave up on it): the result is dropped.
            let _ = tx.send(work());
        });
        Background {
            result: Mutex::new(rx),
        }
    }

    /// The result once the work is done (`Err` if it stopped without one), `None` while it runs.
    pub fn poll(&mut self) -> Option<Result<T, Stopped>> {
        let received = self
            .result
            .get_mut()
            .map_or(Err(TryRecvError::Disconnected), |r| r.try_recv());
        match received {
            Ok(t) => Some(Ok(t)),
            Err(TryRecvError::Empty) => None,
            Err(TryRecvError::Disconnected) => Some(Err(Stopped)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn wait<T: Send + 'static>(job: &mut Background<T>) -> Result<T, Stopped> {
        loop {
            if let Some(r) = job.poll() {
                return r;
            }
            std::thread::sleep(std::time::Duration::from_millis(1));
        }
    }

    #[test]
    fn the_result_comes_once_the_work_is_done_and_a_panic_is_a_stop() {
        let (go, gate) = std::sync::mpsc::channel::<()>();
        let mut job = Background::start(move || {
            gate.recv().unwrap();
            42
        });
        assert_eq!(job.poll(), None, "still running");
        go.send(()).unwrap();
        assert_eq!(wait(&mut job), Ok(42));
        let mut failing = Background::start(|| -> u32 { panic!("a bug in the work") });
        assert_eq!(wait(&mut failing), Err(Stopped));
    }
}
