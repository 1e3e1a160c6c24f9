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

use crate::analysis::watch::{Finding, Watch};
use crate::control::ControlLaw;
use crate::experiments::LTI_MAX_STEP_S;
use crate::model::linear::LinearModel;
use crate::model::passive::PassiveModel;
use crate::model::twin::Twin;
use crate::params::ControllerParams;
use crate::params::Params;
use crate::scenario::{ClassMotion, InputClass};
use crate::scenario::{CommandSignal, Cycloid, PlatformMotion, RandomRide, SampledMotion};
use crate::simulation::{ContactEvent, Drive, Run, Sample, SimError, Simulation, step_for_rate};
use serde::{Deserialize, Serialize};
use std::panic::AssertUnwindSafe;
use std::sync::mpsc::{Receiver, Sender, channel};
use std::time::Duration;
use web_time::Instant;

/// Rate at which samples are streamed to the UI [Hz].
pub const STREAM_RATE_HZ: f64 = 500.0;

/// How fast simulated time runs against wall-clock time.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum Speed {
    /// 0.1× real time.
    Slow,
    /// Real time.
    RealTime,
    /// 10× real time.
    Fast,
    /// As fast as the machine allows.
    Max,
}

impl Speed {
    /// Factor of simulated over wall-clock time (∞ for `Max`).
    pub fn factor(self) -> f64 {
        match self {
            Speed::Slow => 0.1,
            Speed::RealTime => 1.0,
            Speed::Fast => 10.0,
            Speed::Max => f64::INFINITY,
        }
    }

    /// Label for the UI.
    pub fn label(self) -> &'static str {
        match self {
            Speed::Slow => "0.1×",
            Speed::RealTime => "1×",
            Speed::Fast => "10×",
            Speed::Max => "max",
        }
    }
}

/// What the platform does in the live simulation.
#[derive(Debug, Clone, PartialEq)]
pub enum Excitation {
    /// Band-limited random ride; a new seed starts when the record ends.
    Random(RandomRide),
    /// A cycloidal bump (repeated every `period_s`, alternating up and down).
    Cycloid {
        /// The bump.
        bump: Cycloid,
        /// Repeat period [s].
        period_s: f64,
    },
    /// Platform sine: acceleration amplitude [m/s²] and frequency [Hz].
    Sine {
        /// Acceleration amplitude [m/s²].
        accel_m_s2: f64,
        /// Frequency [Hz].
        freq_hz: f64,
    },
    /// A loaded platform record (replayed from the start when it ends).
    Record(SampledMotion),
    /// A seat-test input class (ISO 7096 / ISO 5007 / EN 13490) generated as the CLI's
    /// `simulate --scenario class` does; a new seed starts when the record ends.
    Class {
        /// The class.
        class: &'static InputClass,
        /// Record length [s], 20 ..= 3600.
        duration_s: f64,
        /// Seed of the phases.
        seed: u64,
    },
    /// Platform still; open-loop valve sine `A·cos(2πft)` on the active models.
    ValveSine {
        /// Amplitude [V].
        amplitude_v: f64,
        /// Frequency [Hz].
        freq_hz: f64,
    },
}

impl Default for Excitation {
    fn default() -> Self {
        Excitation::Random(RandomRide {
            duration_s: 300.0,
            ..Default::default()
        })
    }
}

impl Excitation {
    /// The platform motion and the drive of the active models, and how long it lasts [s];
    /// an error for a seat-test class whose record cannot be generated (bad duration).
    fn build(&self, params: &Params) -> Result<(PlatformMotion, Drive, f64), String> {
        let closed = Drive::ClosedLoop(ControlLaw::new(params));
        Ok(match self {
            Excitation::Random(r) => (PlatformMotion::Sampled(r.generate()), closed, r.duration_s),
            Excitation::Class {
                class,
                duration_s,
                seed,
            } => {
                let motion = ClassMotion {
                    seed: *seed,
                    ..ClassMotion::new(class, *duration_s)
                }
                .generate()
                .map_err(|e| format!("seat-test class {}: {e}", class.name))?;
                let d = motion.duration_s();
                (PlatformMotion::Sampled(motion), closed, d)
            }
            Excitation::Cycloid { bump, period_s } => {
                // Build one up-and-down cycle as a sampled record so it can repeat.
                let period = period_s.max(2.0 * (bump.start_s + bump.rise_time_s));
                let dt = 1e-3;
                let n = (2.0 * period / dt) as usize + 1;
                let down = Cycloid {
                    height_m: -bump.height_m,
                    start_s: bump.start_s + period,
                    ..*bump
                };
                let (mut x, mut xd, mut xdd) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
                for i in 0..n {
                    let t = i as f64 * dt;
                    let (a, b) = (bump.at(t), down.at(t));
                    x[i] = a.x + b.x;
                    xd[i] = a.xd + b.xd;
                    xdd[i] = a.xdd + b.xdd;
                }
                (
                    PlatformMotion::Sampled(SampledMotion::new(dt, x, xd, xdd)),
                    closed,
                    2.0 * period,
                )
            }
            Excitation::Sine {
                accel_m_s2,
                freq_hz,
            } => {
                let w = 2.0 * std::f64::consts::PI * freq_hz;
                (
                    PlatformMotion::Sine(crate::scenario::PlatformSine {
                        amplitude_m: accel_m_s2 / (w * w),
                        freq_hz: *freq_hz,
                        fade_in_s: 1.0,
                    }),
                    closed,
                    f64::INFINITY,
                )
            }
            Excitation::Record(m) => (PlatformMotion::Sampled(m.clone()), closed, m.duration_s()),
            Excitation::ValveSine {
                amplitude_v,
                freq_hz,
            } => (
                PlatformMotion::Still,
                Drive::OpenLoop(CommandSignal::Sine {
                    amplitude_v: *amplitude_v,
                    freq_hz: *freq_hz,
                }),
                f64::INFINITY,
            ),
        })
    }

    /// The same excitation with the next seed (random ride and seat-test class), or as it is.
    fn reseeded(&self, bump: u64) -> Excitation {
        match self {
            Excitation::Random(r) => Excitation::Random(RandomRide {
                seed: r.seed.wrapping_add(bump),
                ..*r
            }),
            Excitation::Class {
                class,
                duration_s,
                seed,
            } => Excitation::Class {
                class,
                duration_s: *duration_s,
                seed: seed.wrapping_add(bump),
            },
            other => other.clone(),
        }
    }
}

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
        /// Simulated time [s] since the last reset or new excitation. It keeps increasing
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

/// The engine loop kept in the handle and stepped by [`EngineHandle::pump`] (web).
#[cfg(target_arch = "wasm32")]
struct Local {
    l: Loop<Box<dyn Fn()>>,
    commands: Receiver<Command>,
}

#[cfg(target_arch = "wasm32")]
impl Local {
    /// One frame's work: the wall time spent stepping, `None` once a
    /// [`Command::Shutdown`] arrived.
    fn pump(&mut self, budget: Duration) -> Option<Duration> {
        let pending: Vec<Command> = self.commands.try_iter().collect();
        for c in pending {
            if !self.l.handle(c) {
                return None;
            }
        }
        // Frames come far less often than the thread's 10 ms ticks (and a slow page draws
        // fewer of them): step on, a quarter second at a time, while behind the wall clock.
        let t0 = Instant::now();
        while self.l.running && !self.l.failed {
            self.l.step_paced();
            if self.l.lag_s() < 1.0 / STREAM_RATE_HZ || t0.elapsed() >= budget {
                break;
            }
        }
        Some(t0.elapsed())
    }
}

struct Sims {
    twin: Simulation<Twin, 10>,
    /// The linear models stepped as `seat-twin simulate` steps them: exactly at up to
    /// [`LTI_MAX_STEP_S`] (new parameters rebuild the exact hold, the state kept), or by RK4
    /// at the twin's step when the delay is shorter than that.
    linear: Simulation<LinearModel, 3>,
    passive: Simulation<PassiveModel, 2>,
    /// The A/B reference twin and its controller.
    reference: Option<(Simulation<Twin, 10>, ControllerParams)>,
    every: u64,
    duration: f64,
    contacts_seen: usize,
}

/// The parameters of the reference twin: the live plant with the reference controller.
fn with_controller(params: &Params, c: ControllerParams) -> Params {
    Params {
        controller: c,
        ..*params
    }
}

impl Sims {
    fn new(
        params: &Params,
        excitation: &Excitation,
        reference: Option<ControllerParams>,
    ) -> Result<Self, String> {
        let (platform, drive, duration) = excitation.build(params)?;
        let h = step_for_rate(params.numerics.max_step_s, STREAM_RATE_HZ);
        let h_lti = step_for_rate(LTI_MAX_STEP_S, STREAM_RATE_HZ);
        let every = ((1.0 / STREAM_RATE_HZ) / h).round() as u64;
        let reference = reference.map(|c| {
            let rp = with_controller(params, c);
            let rdrive = match &drive {
                Drive::ClosedLoop(_) => Drive::ClosedLoop(ControlLaw::new(&rp)),
                open => open.clone(),
            };
            (Simulation::twin(&rp, h, rdrive, platform.clone()), c)
        });
        Ok(Self {
            reference,
            twin: Simulation::twin(params, h, drive.clone(), platform.clone()),
            linear: Simulation::exact_or_rk4(
                LinearModel::new(params),
                h_lti,
                h,
                drive.clone(),
                platform.clone(),
            ),
            passive: Simulation::exact_or_rk4(PassiveModel::new(params), h_lti, h, drive, platform),
            every,
            duration,
            contacts_seen: 0,
        })
    }

    fn set_params(&mut self, params: &Params) {
        if let Some((sim, c)) = self.reference.as_mut() {
            let rp = with_controller(params, *c);
            sim.set_model(Twin::new(rp));
            sim.update_gains(&rp);
        }
        self.twin.set_model(Twin::new(*params));
        self.twin.update_gains(params);
        self.linear.set_model(LinearModel::new(params));
        self.linear.update_gains(params);
        self.passive.set_model(PassiveModel::new(params));
        self.passive.update_gains(params);
    }

    fn time(&self) -> f64 {
        self.twin.time()
    }

    /// Advances all three until `t_end`, appending streamed samples.
    fn advance(&mut self, t_end: f64, batch: &mut Batch) -> Result<(), SimError> {
        let every = self.every;
        self.twin.run_until(t_end, every, |s| batch.twin.push(s))?;
        let every_of = |h: f64| ((1.0 / STREAM_RATE_HZ) / h).round() as u64;
        let linear_every = every_of(self.linear.step_size());
        self.linear
            .run_until(t_end, linear_every, |s| batch.linear.push(s))?;
        let passive_every = every_of(self.passive.step_size());
        self.passive
            .run_until(t_end, passive_every, |s| batch.passive.push(s))?;
        if let Some((sim, _)) = self.reference.as_mut() {
            sim.run_until(t_end, every, |s| batch.reference.push(s))?;
        }
        Ok(())
    }
}

trait DriveTarget {
    fn update_gains(&mut self, params: &Params);
}

impl<M, const N: usize> DriveTarget for Simulation<M, N>
where
    M: crate::model::Model<N> + crate::simulation::CommandPath,
{
    fn update_gains(&mut self, params: &Params) {
        if let Drive::ClosedLoop(_) = self.drive() {
            self.set_drive(Drive::ClosedLoop(ControlLaw::new(params)));
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

struct Loop<W: Fn()> {
    params: Params,
    excitation: Excitation,
    reference: Option<ControllerParams>,
    speed: Speed,
    running: bool,
    failed: bool,
    /// Restart a finite excitation when it ends ([`Command::SetRepeat`]).
    repeat: bool,
    sims: Sims,
    events: Sender<Event>,
    waker: W,
    wall_anchor: Instant,
    sim_anchor: f64,
    rtf_window: (Instant, f64),
    rtf: f64,
    seed_bump: u64,
    /// Simulated time of the runs before the last automatic restart [s].
    epoch: f64,
    /// Simulated time stepped since the thread started [s] (monotonic; the real-time
    /// factor is measured on it, so restarts cannot make it negative).
    stepped: f64,
    /// A fault injected by [`Command::InjectFault`] waits for the next step.
    fault_armed: bool,
    /// The live twin's watch over its own samples.
    watch: Watch,
}

#[cfg(not(target_arch = "wasm32"))]
fn engine_loop<W: Fn()>(
    params: Params,
    commands: Receiver<Command>,
    events: Sender<Event>,
    waker: W,
) {
    use std::sync::mpsc::RecvTimeoutError;
    let Some(mut l) = Loop::start(params, events, waker) else {
        return;
    };
    let tick = Duration::from_millis(10);
    loop {
        // Commands: block while idle, poll while running.
        let first = if l.running && !l.failed {
            commands.try_recv().ok()
        } else {
            match commands.recv_timeout(Duration::from_millis(100)) {
                Ok(c) => Some(c),
                Err(RecvTimeoutError::Timeout) => None,
                Err(RecvTimeoutError::Disconnected) => return,
            }
        };
        let mut pending: Vec<Command> = first.into_iter().collect();
        pending.extend(commands.try_iter());
        for c in pending {
            if !l.handle(c) {
                return;
            }
        }
        // Paused or stopped, nothing changes between commands, and each command already
        // sent its status: no event, so the app is not woken (idle means idle).
        if l.running && !l.failed {
            l.step_paced();
            if l.speed != Speed::Max {
                std::thread::sleep(tick);
            }
        }
    }
}

impl<W: Fn()> Loop<W> {
    /// The loop at rest on the default excitation, running at real time (`None` only if
    /// the default random ride could not be built, which it always can).
    fn start(params: Params, events: Sender<Event>, waker: W) -> Option<Self> {
        let excitation = Excitation::default();
        let sims = Sims::new(&params, &excitation, None).ok()?;
        Some(Loop {
            params,
            excitation,
            reference: None,
            speed: Speed::RealTime,
            running: true,
            failed: false,
            repeat: true,
            sims,
            events,
            waker,
            wall_anchor: Instant::now(),
            sim_anchor: 0.0,
            rtf_window: (Instant::now(), 0.0),
            rtf: 0.0,
            seed_bump: 0,
            epoch: 0.0,
            stepped: 0.0,
            fault_armed: false,
            watch: Watch::new(1.0 / STREAM_RATE_HZ),
        })
    }

    fn send(&self, e: Event) {
        let _ = self.events.send(e);
    }

    /// How far the simulation is behind where the pacing wants it [s] (∞ at
    /// [`Speed::Max`]).
    #[cfg(target_arch = "wasm32")]
    fn lag_s(&self) -> f64 {
        if self.speed == Speed::Max {
            return f64::INFINITY;
        }
        let wall = self.wall_anchor.elapsed().as_secs_f64();
        self.sim_anchor + wall * self.speed.factor() - self.sims.time()
    }

    fn reanchor(&mut self) {
        self.wall_anchor = Instant::now();
        self.sim_anchor = self.sims.time();
    }

    /// A new measuring window for the real-time factor (the pacing changed).
    fn new_rtf_window(&mut self) {
        self.rtf_window = (Instant::now(), self.stepped);
    }

    fn restart(&mut self) {
        self.watch.reset();
        let excitation = self.excitation.reseeded(self.seed_bump);
        match Sims::new(&self.params, &excitation, self.reference) {
            Ok(sims) => {
                self.sims = sims;
                self.failed = false;
            }
            Err(e) => {
                self.failed = true;
                self.send(Event::Error(format!("excitation refused: {e}")));
            }
        }
        self.reanchor();
    }

    /// Handles one command; false ends the thread.
    fn handle(&mut self, c: Command) -> bool {
        match c {
            Command::SetParams(p) => {
                if p.validate().is_ok() {
                    self.params = *p;
                    self.sims.set_params(&self.params);
                    self.watch.reset();
                } else if let Err(e) = p.validate() {
                    self.send(Event::Error(format!("parameters refused: {e}")));
                }
            }
            Command::SetExcitation(e) => {
                self.excitation = *e;
                self.seed_bump = 0;
                self.epoch = 0.0;
                self.restart();
            }
            Command::SetReference(r) => {
                if r.is_none_or(|c| c.validate().is_ok()) {
                    self.reference = r;
                    self.epoch = 0.0;
                    self.seed_bump = 0;
                    self.restart();
                } else {
                    self.send(Event::Error("reference controller refused".into()));
                }
            }
            Command::SetSpeed(s) => {
                self.speed = s;
                self.reanchor();
                self.new_rtf_window();
            }
            Command::Run => {
                self.running = true;
                self.reanchor();
                self.new_rtf_window();
            }
            Command::Pause => {
                self.running = false;
                self.rtf = 0.0;
            }
            Command::Reset => {
                self.seed_bump = 0;
                self.epoch = 0.0;
                self.rtf = 0.0;
                self.restart();
            }
            Command::SetRepeat(r) => self.repeat = r,
            Command::Shutdown => return false,
            Command::InjectFault => self.fault_armed = true,
        }
        self.status();
        true
    }

    fn status(&self) {
        let running = self.running && !self.failed;
        self.send(Event::Status {
            t: self.epoch + self.sims.time(),
            realtime_factor: if running { self.rtf.max(0.0) } else { 0.0 },
            running,
            params: Box::new(self.params),
            reference: self.reference,
            contacts: (
                self.sims.twin.contacts().len(),
                self.sims
                    .reference
                    .as_ref()
                    .map_or(0, |(r, _)| r.contacts().len()),
            ),
        });
        (self.waker)();
    }

    fn step_paced(&mut self) {
        let now = Instant::now();
        let target = if self.speed == Speed::Max {
            self.sims.time() + 0.05
        } else {
            let wall = now.duration_since(self.wall_anchor).as_secs_f64();
            let t = self.sim_anchor + wall * self.speed.factor();
            // Never try to catch up more than 0.25 s of simulated time in one tick.
            t.min(self.sims.time() + 0.25)
        };
        // On the stream's sample grid, where the twin's and the linear models' steps meet,
        // so that every batch holds the same instants of all three.
        let dt_out = 1.0 / STREAM_RATE_HZ;
        let end = (self.sims.duration / dt_out - 1e-9).ceil() * dt_out;
        let t_end = ((target / dt_out + 1e-9).floor() * dt_out).min(end);
        let mut batch = Batch::default();
        let sims = &mut self.sims;
        let t_before = sims.time();
        let fault = std::mem::take(&mut self.fault_armed);
        // Not a whole sample interval to go (a short tick): nothing to step or send yet. (A
        // run that has not stepped yet would send its sample at rest twice.)
        let nothing_new = t_end < t_before + 0.5 * dt_out;
        let result = if nothing_new && !fault {
            Ok(Ok(()))
        } else {
            std::panic::catch_unwind(AssertUnwindSafe(|| {
                if fault {
                    panic!("fault injected by Command::InjectFault (test hook)");
                }
                sims.advance(t_end, &mut batch)
            }))
        };
        self.stepped += (self.sims.time() - t_before).max(0.0);
        for smp in &batch.twin {
            if let Some(f) = self
                .watch
                .push(self.epoch + smp.t, smp.xdd, smp.ydd, smp.p1, smp.p2)
            {
                self.send(Event::Watch(f));
            }
        }
        if !batch.twin.is_empty() {
            self.send(Event::Samples(batch));
        }
        match result {
            Ok(Ok(())) => {}
            Ok(Err(e)) => {
                self.failed = true;
                self.send(Event::Error(format!("{e}. Press Reset to start again.")));
            }
            Err(panic) => {
                let msg = panic
                    .downcast_ref::<String>()
                    .cloned()
                    .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
                    .unwrap_or_else(|| "unknown panic".into());
                self.failed = true;
                self.send(Event::Error(format!(
                    "the engine stopped on an internal error: {msg}. Press Reset to start again."
                )));
            }
        }
        let contacts = self.sims.twin.contacts();
        for c in &contacts[self.sims.contacts_seen..] {
            self.send(Event::Contact(*c));
        }
        self.sims.contacts_seen = contacts.len();
        // Real-time factor over ~1 s windows.
        let (w0, s0) = self.rtf_window;
        let dt_wall = now.duration_since(w0).as_secs_f64();
        if dt_wall > 1.0 {
            self.rtf = (self.stepped - s0) / dt_wall;
            self.rtf_window = (now, self.stepped);
        }
        let ended = self.sims.time() >= self.sims.duration - 1e-9 && self.sims.duration.is_finite();
        if ended && !self.repeat {
            self.running = false;
            self.rtf = 0.0;
        } else if ended {
            self.seed_bump += 1;
            self.epoch += self.sims.time();
            self.restart();
            self.send(Event::Restarted);
        }
        self.status();
    }
}
