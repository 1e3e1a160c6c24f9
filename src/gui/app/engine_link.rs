//! The app's link to the engine: the handle (commands out, events in), the waker the engine
//! and the jobs call, what the engine last reported, its error and its watch, and whether the
//! user wants it running. A dead engine thread is noticed here and restarted on Reset.

use super::super::job::Waker;
use super::super::traces::Traces;
use crate::analysis::watch::Finding;
use crate::engine::{self, Command, EngineHandle, Event};
use crate::params::{ControllerParams, Params};
use std::sync::mpsc::TryRecvError;
use std::time::Duration;

/// What the engine last reported.
#[derive(Debug, Clone, Default)]
pub struct EngineView {
    /// Simulated time \[s\].
    pub t: f64,
    /// Real-time factor.
    pub realtime_factor: f64,
    /// Running (not paused, not failed).
    pub running: bool,
    /// Parameters the engine runs with (echo).
    pub params: Option<Params>,
    /// The A/B reference controller the engine runs (`None`: A/B off).
    pub reference: Option<ControllerParams>,
    /// End-stop contacts since the last restart: live twin, reference twin.
    pub contacts: (usize, usize),
}

/// The engine thread (or, on the web, the engine stepped in the frames) as the app sees it.
pub struct EngineLink {
    handle: EngineHandle,
    waker: Waker,
    /// Whether the engine thread still answers (a send or a receive failed: it is gone).
    alive: bool,
    /// What the engine last reported.
    pub view: EngineView,
    /// The engine's error, once it stopped (cleared by a restart from rest).
    pub error: Option<String>,
    /// What the running twin's watch found since the last reset or change (it can ring
    /// while the linear verdict at rest says stable).
    pub watch: Option<Finding>,
    /// Whether the user wants the simulation running (space bar / Run button).
    pub want_running: bool,
}

impl EngineLink {
    /// Starts the engine with `params`; it calls `waker` when something arrived.
    pub fn spawn(params: &Params, waker: Waker) -> Self {
        Self {
            handle: spawn_engine(params, &waker),
            waker,
            alive: true,
            view: EngineView::default(),
            error: None,
            watch: None,
            want_running: true,
        }
    }

    /// The waker that the engine and the background jobs call.
    pub fn waker(&self) -> &Waker {
        &self.waker
    }

    /// Sends a command; a failed send marks the engine as gone.
    pub fn send(&mut self, c: Command) {
        if !self.handle.send(c) {
            self.alive = false;
        }
    }

    /// Run or Pause, as the user wants it.
    pub fn run_command(&self) -> Command {
        if self.want_running {
            Command::Run
        } else {
            Command::Pause
        }
    }

    /// Toggles run/pause.
    pub fn toggle_running(&mut self) {
        self.want_running = !self.want_running;
        let c = self.run_command();
        self.send(c);
    }

    /// Starts a new engine with `params` if the old one is gone; `true` if it did (the
    /// caller sends the new engine its setup).
    pub fn respawn_if_gone(&mut self, params: &Params) -> bool {
        if self.alive {
            return false;
        }
        self.handle = spawn_engine(params, &self.waker);
        self.alive = true;
        true
    }

    /// A restart from rest or a new setup: the error and the watch's finding are about the
    /// run before.
    pub fn forget_run(&mut self) {
        self.error = None;
        self.watch = None;
    }

    /// Steps the engine for up to `budget` of wall time (on the web; on the desktop it runs
    /// in its thread and this returns at once): the wall time it took.
    pub fn pump(&mut self, budget: Duration) -> Duration {
        self.handle.pump(budget)
    }

    /// Takes every event that arrived, without blocking: samples and contacts go to
    /// `traces`, the status, error and watch are kept here.
    pub fn drain(&mut self, traces: &mut Traces) {
        loop {
            match self.handle.events.try_recv() {
                Ok(ev) => self.handle_event(ev, traces),
                Err(TryRecvError::Empty) => break,
                Err(TryRecvError::Disconnected) => {
                    if self.alive {
                        self.alive = false;
                        self.error = Some(
                            "the engine thread has stopped. Press Reset to restart it.".into(),
                        );
                    }
                    break;
                }
            }
        }
    }

    fn handle_event(&mut self, ev: Event, traces: &mut Traces) {
        match ev {
            Event::Samples(b) => traces.push_batch(&b),
            Event::Status {
                t,
                realtime_factor,
                running,
                params,
                reference,
                contacts,
            } => {
                self.view = EngineView {
                    t,
                    realtime_factor,
                    running,
                    params: Some(*params),
                    reference,
                    contacts,
                }
            }
            Event::Contact(_) => traces.contact_count += 1,
            Event::Error(msg) => self.error = Some(msg),
            Event::Restarted => traces.mark_restart(),
            Event::Watch(f) => self.watch = Some(f),
        }
    }

    /// The text of the toolbar clock (simulated time and real-time factor).
    pub fn clock_text(&self) -> String {
        let v = &self.view;
        if self.error.is_some() {
            format!("t = {:8.2} s   stopped", v.t)
        } else if !v.running {
            format!("t = {:8.2} s   paused", v.t)
        } else {
            format!(
                "t = {:8.2} s   ×{:.2} real time",
                v.t,
                v.realtime_factor.max(0.0)
            )
        }
    }
}

fn spawn_engine(params: &Params, waker: &Waker) -> EngineHandle {
    let w = waker.clone();
    engine::spawn(*params, move || w())
}
