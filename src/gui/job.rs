//! One background job: a worker thread with progress, cancel and a result polled each frame.
//! A panic inside the work is caught and reported as the job's error, never taking the UI
//! down.
//!
//! ```text
//!   Job::spawn(work) ──► thread: work(&ctx) ──► Result<T, String> ──► poll() (once)
//!        │                 ctx.report(done, total) ──► progress()
//!        └── cancel() ──► ctx.cancelled() / ctx.cancel_flag() (the work stops itself)
//! ```

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::mpsc::{Receiver, TryRecvError, channel};

/// Called when the job reported progress or finished (the app repaints).
pub type Waker = Arc<dyn Fn() + Send + Sync>;

/// What the work sees of its job: the cancel flag and the progress counters.
#[derive(Clone)]
pub struct JobCtx {
    cancel: Arc<AtomicBool>,
    done: Arc<AtomicUsize>,
    total: Arc<AtomicUsize>,
    waker: Waker,
}

impl JobCtx {
    /// Reports `done` of `total` steps.
    pub fn report(&self, done: usize, total: usize) {
        self.done.store(done, Ordering::Relaxed);
        self.total.store(total, Ordering::Relaxed);
        (self.waker)();
    }

    /// Whether the UI asked the job to stop.
    pub fn cancelled(&self) -> bool {
        self.cancel.load(Ordering::Relaxed)
    }

    /// The cancel flag itself, for library calls that take one.
    pub fn cancel_flag(&self) -> Arc<AtomicBool> {
        self.cancel.clone()
    }
}

/// A job running (or finished) on its own thread, producing a `T`.
pub struct Job<T> {
    ctx: JobCtx,
    result: Receiver<Result<T, String>>,
    finished: std::cell::Cell<bool>,
}

impl<T: Send + 'static> Job<T> {
    /// Starts `work` on a thread named `name`. Its `Err` (or a panic, as text) is the job's
    /// error.
    pub fn spawn(
        name: &str,
        waker: Waker,
        work: impl FnOnce(&JobCtx) -> Result<T, String> + Send + 'static,
    ) -> Self {
        let ctx = JobCtx {
            cancel: Arc::new(AtomicBool::new(false)),
            done: Arc::new(AtomicUsize::new(0)),
            total: Arc::new(AtomicUsize::new(0)),
            waker,
        };
        let (tx, rx) = channel();
        let worker = ctx.clone();
        let spawned = std::thread::Builder::new()
            .name(name.to_string())
            .spawn(move || {
                let out = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| work(&worker)))
                    .unwrap_or_else(|panic| {
                        let msg = panic
                            .downcast_ref::<String>()
                            .cloned()
                            .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
                            .unwrap_or_else(|| "unknown panic".into());
                        Err(format!("the job stopped on an internal error: {msg}"))
                    });
                let _ = tx.send(out);
                (worker.waker)();
            });
        let result = match spawned {
            Ok(_) => rx,
            Err(e) => {
                let (tx, rx) = channel();
                let _ = tx.send(Err(format!("could not start a thread: {e}")));
                rx
            }
        };
        Self {
            ctx,
            result,
            finished: std::cell::Cell::new(false),
        }
    }

    /// `(done, total)` as last reported.
    pub fn progress(&self) -> (usize, usize) {
        (
            self.ctx.done.load(Ordering::Relaxed),
            self.ctx.total.load(Ordering::Relaxed),
        )
    }

    /// Asks the work to stop (it checks the flag itself).
    pub fn cancel(&self) {
        self.ctx.cancel.store(true, Ordering::Relaxed);
    }

    /// Whether cancel was asked.
    pub fn is_cancelled(&self) -> bool {
        self.ctx.cancelled()
    }

    /// Whether the result has been taken.
    pub fn is_finished(&self) -> bool {
        self.finished.get()
    }

    /// The result, once, when the work has ended; `None` while it runs (or after).
    pub fn poll(&self) -> Option<Result<T, String>> {
        if self.finished.get() {
            return None;
        }
        match self.result.try_recv() {
            Ok(r) => {
                self.finished.set(true);
                Some(r)
            }
            Err(TryRecvError::Empty) => None,
            Err(TryRecvError::Disconnected) => {
                self.finished.set(true);
                Some(Err("the job's thread ended without a result".into()))
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::{Duration, Instant};

    fn wait<T: Send + 'static>(job: &Job<T>) -> Result<T, String> {
        let t0 = Instant::now();
        loop {
            if let Some(r) = job.poll() {
                return r;
            }
            assert!(t0.elapsed() < Duration::from_secs(10), "job never ended");
            std::thread::sleep(Duration::from_millis(5));
        }
    }

    #[test]
    fn result_progress_cancel_and_panic() {
        let noop: Waker = Arc::new(|| {});
        let ok = Job::spawn("t", noop.clone(), |ctx| {
            ctx.report(3, 4);
            Ok(7)
        });
        assert_eq!(wait(&ok), Ok(7));
        assert_eq!(ok.progress(), (3, 4));
        assert!(ok.poll().is_none(), "the result comes once");

        let stop = Job::spawn("t", noop.clone(), |ctx| {
            while !ctx.cancelled() {
                std::thread::sleep(Duration::from_millis(1));
            }
            Err::<(), _>("cancelled".into())
        });
        stop.cancel();
        assert_eq!(wait(&stop), Err("cancelled".into()));

        let boom = Job::spawn("t", noop, |_| -> Result<(), String> { panic!("kaboom") });
        let e = wait(&boom).unwrap_err();
        assert!(e.contains("kaboom"), "{e}");
    }
}
