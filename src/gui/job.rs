//! One background job: progress, cancel, streamed partial results and a final result, polled
//! each frame. A panic inside the work is caught and reported as the job's error, never
//! taking the UI down. Every background task of the app runs on it: the sine dwell (streams
//! its points), the file dialogs and writers, the measured-record loader, replays and
//! calibration, and Tune.
//!
//! Where the work runs is the job's [`Runner`], not the caller's business: on the desktop a
//! thread of its own; in a browser tab (no threads) in slices inside the frame loop, under a
//! time budget ([`pump`], called once per frame by the app). Work given as steps
//! ([`Job::spawn_steps`]: each call does a bounded piece and says whether it is done) is cut
//! there; work given as one call ([`Job::spawn`]) is one slice.
//!
//! ```text
//!   Job::spawn_steps(step) ──► Thread: loop step(&ctx)           ──► Result<T, String> ──► poll()
//!        │                     Frames: pump(budget) each frame:
//!        │                             step(&ctx) until the budget is spent
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

/// What one step of a job's work gives: more to do, or the end.
#[derive(Debug, PartialEq)]
pub enum Step<T> {
    /// Not finished: call again.
    More,
    /// Finished with this result.
    Done(Result<T, String>),
}

/// Where a job's work runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Runner {
    /// A thread of its own (the desktop).
    Thread,
    /// In slices inside the frames, run by [`pump`] on the thread that started the job (a
    /// browser tab, which has no threads).
    Frames,
}

impl Runner {
    /// The runner of this build: [`Runner::Frames`] on wasm32, else [`Runner::Thread`].
    pub fn here() -> Self {
        if cfg!(target_arch = "wasm32") {
            Runner::Frames
        } else {
            Runner::Thread
        }
    }
}

/// A job run in the frames, as [`pump`] sees it.
trait Sliced {
    /// One step; true when the work has ended (its result is sent).
    fn slice(&mut self) -> bool;
}

/// The work of a [`Runner::Frames`] job, its context and where its result goes.
struct InFrames<T, P, F> {
    ctx: JobCtx<P>,
    step: F,
    result: Sender<Result<T, String>>,
}

impl<T, P, F: FnMut(&JobCtx<P>) -> Step<T>> Sliced for InFrames<T, P, F> {
    fn slice(&mut self) -> bool {
        let out = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| (self.step)(&self.ctx)))
            .unwrap_or_else(|panic| Step::Done(Err(panic_text(panic))));
        match out {
            Step::More => false,
            Step::Done(r) => {
                let _ = self.result.send(r);
                (self.ctx.waker)();
                true
            }
        }
    }
}

thread_local! {
    /// The [`Runner::Frames`] jobs started on this thread and not ended, in start order.
    static IN_FRAMES: std::cell::RefCell<Vec<Box<dyn Sliced>>> =
        const { std::cell::RefCell::new(Vec::new()) };
}

/// Runs the [`Runner::Frames`] jobs of this thread for about `budget` of wall time: one step
/// of each in turn, at least one step in all, until they end or the budget is spent (a step
/// is not interrupted, so a long step overruns it). Returns whether work is left (the caller
/// asks for another frame). Without such jobs (the desktop) it returns false at once.
pub fn pump(budget: std::time::Duration) -> bool {
    // Taken out while they run, so a step may start another job.
    let mut jobs = IN_FRAMES.with(|j| std::mem::take(&mut *j.borrow_mut()));
    if jobs.is_empty() {
        return false;
    }
    let t0 = web_time::Instant::now();
    while !jobs.is_empty() {
        jobs.retain_mut(|job| !job.slice());
        if t0.elapsed() >= budget {
            break;
        }
    }
    IN_FRAMES.with(|j| {
        let mut j = j.borrow_mut();
        let started_meanwhile = std::mem::take(&mut *j);
        *j = jobs;
        j.extend(started_meanwhile);
        !j.is_empty()
    })
}

/// A panic's message, as the job's error.
fn panic_text(panic: Box<dyn std::any::Any + Send>) -> String {
    let msg = panic
        .downcast_ref::<String>()
        .cloned()
        .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
        .unwrap_or_else(|| "unknown panic".into());
    format!("the job stopped on an internal error: {msg}")
}

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
    /// Starts `work`, one call, on this build's [`Runner`] (named `name` as a thread). Its
    /// `Err` (or a panic, as text) is the job's error. In the frames it is one slice.
    pub fn spawn(
        name: &str,
        waker: Waker,
        work: impl FnOnce(&JobCtx<P>) -> Result<T, String> + Send + 'static,
    ) -> Self {
        let mut work = Some(work);
        Self::spawn_steps(name, waker, move |ctx| match work.take() {
            Some(w) => Step::Done(w(ctx)),
            None => Step::Done(Err("the job was run twice".into())),
        })
    }

    /// Starts work given as steps on this build's [`Runner`]: `step` is called until it
    /// returns [`Step::Done`]; each call should do a bounded piece (in a browser it runs
    /// inside a frame).
    pub fn spawn_steps(
        name: &str,
        waker: Waker,
        step: impl FnMut(&JobCtx<P>) -> Step<T> + Send + 'static,
    ) -> Self {
        Self::spawn_steps_on(Runner::here(), name, waker, step)
    }

    /// [`Self::spawn_steps`] on a given runner (tests run [`Runner::Frames`] natively).
    pub fn spawn_steps_on(
        runner: Runner,
        name: &str,
        waker: Waker,
        mut step: impl FnMut(&JobCtx<P>) -> Step<T> + Send + 'static,
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
        let result = match runner {
            Runner::Frames => {
                let job = InFrames {
                    ctx: worker,
                    step,
                    result: tx,
                };
                IN_FRAMES.with(|j| j.borrow_mut().push(Box::new(job)));
                // The next frame runs it.
                (ctx.waker)();
                rx
            }
            Runner::Thread => {
                let spawned = std::thread::Builder::new()
                    .name(name.to_string())
                    .spawn(move || {
                        let out = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                            loop {
                                if let Step::Done(r) = step(&worker) {
                                    break r;
                                }
                            }
                        }))
                        .unwrap_or_else(|panic| Err(panic_text(panic)));
                        let _ = tx.send(out);
                        (worker.waker)();
                    });
                match spawned {
                    Ok(_) => rx,
                    Err(e) => {
                        let (tx, rx) = channel();
                        let _ = tx.send(Err(format!("could not start a thread: {e}")));
                        rx
                    }
                }
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
