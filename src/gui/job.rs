//! One background job: a worker thread with progress, cancel, streamed partial results and a
//! final result, polled each frame. A panic inside the work is caught and reported as the
//! job's error, never taking the UI down. Every background task of the app runs on it: the
//! sine dwell (streams its points), the file dialogs and writers, the measured-record loader,
//! replays and calibration, and Tune.
//!
//! ```text
//!   Job::spawn(work) ──► thread: work(&ctx) ──► Result<T, String> ──► poll() (once)
//!        │                 ctx.report(done, total) ──► progress()
//!        │                 ctx.send(part)          ──► drain() (each frame)
//!        └── cancel() / drop ──► ctx.cancelled() / ctx.cancel_flag() (the work stops itself)
//! ```

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::mpsc::{Receiver, Sender, TryRecvError, channel};

/// Called when the job reported progress or finished (the app repaints).
pub type Waker = Arc<dyn Fn() + Send + Sync>;

/// What the work sees of its job: the cancel flag, the progress counters and the channel of
/// partial results `P` (none by default).
pub struct JobCtx<P = ()> {
    cancel: Arc<AtomicBool>,
    done: Arc<AtomicUsize>,
    total: Arc<AtomicUsize>,
    parts: Sender<P>,
    waker: Waker,
}

impl<P> Clone for JobCtx<P> {
    fn clone(&self) -> Self {
        Self {
            cancel: self.cancel.clone(),
            done: self.done.clone(),
            total: self.total.clone(),
            parts: self.parts.clone(),
            waker: self.waker.clone(),
        }
    }
}

impl<P> JobCtx<P> {
    /// Reports `done` of `total` steps.
    pub fn report(&self, done: usize, total: usize) {
        self.done.store(done, Ordering::Relaxed);
        self.total.store(total, Ordering::Relaxed);
        (self.waker)();
    }

    /// Hands a partial result to the UI (read with [`Job::drain`]). Returns false when nobody
    /// will read it any more (the job was dropped): the work should stop.
    pub fn send(&self, part: P) -> bool {
        let sent = self.parts.send(part).is_ok();
        (self.waker)();
        sent
    }

    /// Whether the UI asked the job to stop (or dropped it).
    pub fn cancelled(&self) -> bool {
        self.cancel.load(Ordering::Relaxed)
    }

    /// The cancel flag itself, for library calls that take one.
    pub fn cancel_flag(&self) -> Arc<AtomicBool> {
        self.cancel.clone()
    }
}

/// The error of every background job in the web build (sine dwells, Tune, calibration,
/// file dialogs): they need a thread, which a browser tab does not have.
pub const NO_THREADS_ON_THE_WEB: &str = "not available in the web build (a browser tab has no background threads): use the \
     desktop app";

/// A job running (or finished) on its own thread, producing partial results `P` and then a
/// `T`. Dropping it cancels the work (nobody will read its result).
pub struct Job<T, P = ()> {
    ctx: JobCtx<P>,
    result: Receiver<Result<T, String>>,
    parts: Receiver<P>,
    finished: std::cell::Cell<bool>,
}

impl<T, P> Drop for Job<T, P> {
    fn drop(&mut self) {
        self.ctx.cancel.store(true, Ordering::Relaxed);
    }
}

impl<T: Send + 'static, P: Send + 'static> Job<T, P> {
    /// Starts `work` on a thread named `name`. Its `Err` (or a panic, as text) is the job's
    /// error.
    pub fn spawn(
        name: &str,
        waker: Waker,
        work: impl FnOnce(&JobCtx<P>) -> Result<T, String> + Send + 'static,
    ) -> Self {
        let (parts_tx, parts) = channel();
        let ctx = JobCtx {
            cancel: Arc::new(AtomicBool::new(false)),
            done: Arc::new(AtomicUsize::new(0)),
            total: Arc::new(AtomicUsize::new(0)),
            parts: parts_tx,
            waker,
        };
        let (tx, rx) = channel();
        let worker = ctx.clone();
        #[cfg(target_arch = "wasm32")]
        let spawned: std::io::Result<()> = {
            // A browser tab has no threads: the job says so instead of freezing the page.
            let _ = (work, worker, tx, name);
            Err(std::io::Error::other(NO_THREADS_ON_THE_WEB))
        };
        #[cfg(not(target_arch = "wasm32"))]
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
            #[cfg(target_arch = "wasm32")]
            Err(e) => {
                let (tx, rx) = channel();
                let _ = tx.send(Err(e.to_string()));
                rx
            }
            #[cfg(not(target_arch = "wasm32"))]
            Err(e) => {
                let (tx, rx) = channel();
                let _ = tx.send(Err(format!("could not start a thread: {e}")));
                rx
            }
        };
        Self {
            ctx,
            result,
            parts,
            finished: std::cell::Cell::new(false),
        }
    }
}

impl<T, P> Job<T, P> {
    /// `(done, total)` as last reported.
    pub fn progress(&self) -> (usize, usize) {
        (
            self.ctx.done.load(Ordering::Relaxed),
            self.ctx.total.load(Ordering::Relaxed),
        )
    }

    /// The partial results sent since the last call, in order.
    pub fn drain(&self) -> impl Iterator<Item = P> + '_ {
        self.parts.try_iter()
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

    /// The result, once, when the work has ended; `None` while it runs (or after). Partial
    /// results sent before the end are still there for [`Job::drain`].
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

    fn wait<T, P>(job: &Job<T, P>) -> Result<T, String> {
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
        let ok: Job<i32> = Job::spawn("t", noop.clone(), |ctx| {
            ctx.report(3, 4);
            Ok(7)
        });
        assert_eq!(wait(&ok), Ok(7));
        assert_eq!(ok.progress(), (3, 4));
        assert!(ok.poll().is_none(), "the result comes once");

        let stop: Job<()> = Job::spawn("t", noop.clone(), |ctx| {
            while !ctx.cancelled() {
                std::thread::sleep(Duration::from_millis(1));
            }
            Err::<(), _>("cancelled".into())
        });
        stop.cancel();
        assert_eq!(wait(&stop), Err("cancelled".into()));

        let boom: Job<()> = Job::spawn("t", noop, |_| panic!("kaboom"));
        let e = wait(&boom).unwrap_err();
        assert!(e.contains("kaboom"), "{e}");
    }

    #[test]
    fn partial_results_arrive_in_order_and_a_dropped_job_is_cancelled() {
        let noop: Waker = Arc::new(|| {});
        let job: Job<usize, usize> = Job::spawn("t", noop.clone(), |ctx| {
            for i in 0..5 {
                ctx.send(i * i);
            }
            Ok(5)
        });
        assert_eq!(wait(&job), Ok(5));
        assert_eq!(job.drain().collect::<Vec<_>>(), vec![0, 1, 4, 9, 16]);
        assert_eq!(job.drain().count(), 0, "each part comes once");

        // A job nobody holds stops: its work sees the cancel flag.
        let (tx, rx) = std::sync::mpsc::channel();
        let dropped: Job<(), ()> = Job::spawn("t", noop, move |ctx| {
            let t0 = Instant::now();
            while !ctx.cancelled() {
                if t0.elapsed() > Duration::from_secs(10) {
                    let _ = tx.send(false);
                    return Ok(());
                }
                std::thread::sleep(Duration::from_millis(1));
            }
            let _ = tx.send(true);
            Ok(())
        });
        drop(dropped);
        assert_eq!(rx.recv_timeout(Duration::from_secs(20)), Ok(true));
    }
}
