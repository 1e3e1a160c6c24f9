//! The engine loop: commands handled, the simulations stepped against the wall clock, batches and events sent (a thread on the desktop, [`Local`] pumped by the app's frames on the web).

use super::sims::Sims;
use super::*;
use crate::analysis::watch::Watch;
use crate::params::ControllerParams;
use crate::params::Params;
use crate::simulation::Run;
use std::panic::AssertUnwindSafe;
use std::sync::mpsc::{Receiver, Sender};
use std::time::Duration;
use web_time::Instant;

/// The engine loop kept in the handle and stepped by [`EngineHandle::pump`] (web).
#[cfg(target_arch = "wasm32")]
pub(super) struct Local {
    pub(super) l: Loop<Box<dyn Fn()>>,
    pub(super) commands: Receiver<Command>,
}

#[cfg(target_arch = "wasm32")]
impl Local {
    /// One frame's work: the wall time spent stepping, `None` once a
    /// [`Command::Shutdown`] arrived.
    pub(super) fn pump(&mut self, budget: Duration) -> Option<Duration> {
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

pub(super) struct Loop<W: Fn()> {
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
pub(super) fn engine_loop<W: Fn()>(
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
    pub(super) fn start(params: Params, events: Sender<Event>, waker: W) -> Option<Self> {
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
