//! The worker thread behind the app: it steps the twin, the linear model and the passive
//! reference side by side on the same platform excitation, paced to wall-clock time, and
//! streams batches of samples back. Commands in, events out; parameters travel by value.
//!
//! ```text
//!   UI ──Command──► engine thread ──Event──► UI   (the waker asks the UI to repaint)
//! ```
//!
//! A numerical blow-up or a panic inside a step is caught, reported as
//! [`Event::Error`] and leaves the thread alive, waiting for [`Command::Reset`].
//!
//! In a browser (wasm32) there is no thread: [`spawn`] keeps the same loop inside the
//! handle, and [`EngineHandle::pump`], called once per frame by the app, handles the
//! commands and steps it under a time budget. The protocol and the app code are the same on
//! both (on the desktop `pump` does nothing); a panic there is not caught (wasm aborts).

use crate::analysis::watch::Finding;
use crate::params::ControllerParams;
use crate::params::Params;
use crate::simulation::{ContactEvent, Sample};
use std::sync::mpsc::{Receiver, Sender, channel};
use std::time::Duration;

mod excitation;
mod sims;
mod worker;
pub use excitation::{Excitation, Speed};
#[cfg(not(target_arch = "wasm32"))]
use worker::engine_loop;
#[cfg(target_arch = "wasm32")]
use worker::{Local, Loop};

/// Rate at which samples are streamed to the UI \[Hz\].
pub const STREAM_RATE_HZ: f64 = 500.0;

/// Commands to the engine.
#[derive(Debug, Clone)]
pub enum Command {
    /// New parameters (gains, Cd, τ, mass, …) take effect at once, keeping the state.
    SetParams(Box<Params>),
    /// New excitation: restarts from rest.
    SetExcitation(Box<Excitation>),
    /// Pacing.
    SetSpeed(Speed),
    /// The A/B reference: a second twin with the same plant and excitation running this
    /// controller (`None` switches it off). Restarts both from rest, so A and B start
    /// together.
    SetReference(Option<ControllerParams>),
    /// Run.
    Run,
    /// Pause.
    Pause,
    /// Back to rest at t = 0 (also clears an error).
    Reset,
    /// What happens when a finite excitation (random ride, record, class, bump) ends:
    /// `true` (the default) restarts it from rest (with the next seed); `false` pauses at
    /// its end, so its whole record can be read (the web page's `?seed=` ride does this).
    SetRepeat(bool),
    /// End the thread.
    Shutdown,
    /// TEST HOOK, never sent by the app: the next engine step panics inside the
    /// simulation, as an internal error would. It exercises the fault path (the step is
    /// caught, [`Event::Error`] is sent, the thread waits for [`Command::Reset`]). Harmless
    /// in production: it changes nothing but that one step, and nothing in the app sends it.
    #[doc(hidden)]
    InjectFault,
}

/// A batch of samples of the three models at the same instants.
#[derive(Debug, Clone, Default)]
pub struct Batch {
    /// Twin samples.
    pub twin: Vec<Sample>,
    /// Linear-model samples.
    pub linear: Vec<Sample>,
    /// Passive samples.
    pub passive: Vec<Sample>,
    /// Samples of the A/B reference twin (empty while A/B is off).
    pub reference: Vec<Sample>,
}

/// Events from the engine.
#[derive(Debug, Clone)]
pub enum Event {
    /// New samples.
    Samples(Batch),
    /// Progress and pacing.
    Status {
        /// Simulated time \[s\] since the last reset or new excitation. It keeps increasing
        /// when the excitation ends and restarts by itself, like the scopes' time axis.
        t: f64,
        /// Achieved simulated/wall time over the last second while running (never negative;
        /// 0 while paused or stopped).
        realtime_factor: f64,
        /// Running or paused.
        running: bool,
        /// The parameters in use (echo, so the UI and tests can see what was applied).
        params: Box<Params>,
        /// The A/B reference controller in use (`None`: A/B off).
        reference: Option<ControllerParams>,
        /// End-stop contacts so far since the last restart: live twin, reference twin.
        contacts: (usize, usize),
    },
    /// A new end-stop contact of the twin.
    Contact(ContactEvent),
    /// The run stopped: a divergence or a panic. The engine waits for `Reset`.
    Error(String),
    /// The excitation ended and restarted from rest (new seed for the random ride).
    Restarted,
    /// The running twin watches itself ([`crate::analysis::watch`]): a self-excited
    /// oscillation or growth (whatever the linear verdict says), or a pressure below zero.
    /// Each is sent once until the next reset, parameter or excitation change.
    Watch(Finding),
}

/// The handle the UI holds.
pub struct EngineHandle {
    /// Send commands here.
    pub commands: Sender<Command>,
    /// Receive events here (drain without blocking each frame).
    pub events: Receiver<Event>,
    #[cfg(not(target_arch = "wasm32"))]
    join: Option<std::thread::JoinHandle<()>>,
    /// The engine stepped in the app's frames (web).
    #[cfg(target_arch = "wasm32")]
    local: Option<Local>,
}

impl EngineHandle {
    /// Sends a command; returns false if the engine is gone.
    pub fn send(&self, c: Command) -> bool {
        self.commands.send(c).is_ok()
    }

    /// Lets the engine work for one frame of the app: on the web, handles the commands sent
    /// since the last frame and steps the models, paced to wall-clock time as the thread
    /// does, for at most about `budget` of wall time (at [`Speed::Max`] it steps in chunks
    /// until the budget is spent). On the desktop the thread does this and `pump` returns
    /// at once. Returns the wall time spent stepping (not handling commands), zero on the
    /// desktop.
    pub fn pump(&mut self, budget: Duration) -> Duration {
        #[cfg(target_arch = "wasm32")]
        if let Some(local) = self.local.as_mut() {
            match local.pump(budget) {
                Some(stepping) => return stepping,
                // Shutdown: the loop and its event sender go, so the app sees it
                // disconnected.
                None => self.local = None,
            }
        }
        let _ = budget;
        Duration::ZERO
    }
}

impl Drop for EngineHandle {
    fn drop(&mut self) {
        let _ = self.commands.send(Command::Shutdown);
        #[cfg(not(target_arch = "wasm32"))]
        if let Some(j) = self.join.take() {
            let _ = j.join();
        }
    }
}

/// Starts the engine thread. `waker` is called after events are sent (the app passes
/// `ctx.request_repaint()`; tests pass a no-op).
/// On the web the loop lives in the handle instead and runs in [`EngineHandle::pump`].
pub fn spawn(params: Params, waker: impl Fn() + Send + 'static) -> EngineHandle {
    let (cmd_tx, cmd_rx) = channel::<Command>();
    let (ev_tx, ev_rx) = channel::<Event>();
    #[cfg(not(target_arch = "wasm32"))]
    {
        let join = std::thread::Builder::new()
            .name("seat-twin-engine".into())
            .spawn(move || engine_loop(params, cmd_rx, ev_tx, waker))
            .ok();
        EngineHandle {
            commands: cmd_tx,
            events: ev_rx,
            join,
        }
    }
    #[cfg(target_arch = "wasm32")]
    {
        let waker: Box<dyn Fn()> = Box::new(waker);
        let local = Loop::start(params, ev_tx, waker).map(|l| Local {
            l,
            commands: cmd_rx,
        });
        EngineHandle {
            commands: cmd_tx,
            events: ev_rx,
            local,
        }
    }
}
