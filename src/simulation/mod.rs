//! A model, its command path (controller or open-loop signal, saturation, pure delay) and an
//! excitation stepped together on one fixed grid, with recorded traces.
//!
//! ```text
//!  platform ẍ(t) ──────────────┬──────────────────────────────► model ──► u, ÿ, p, Q …
//!                              │ ∫                                ▲
//!  u ─► V = Kp·u + Ki·∫ẍ ─► sat(±Vmax) ─► delay τ ─► V(t − τ) ────┘
//!       (or an open-loop V_in(t))
//! ```

use crate::control::{ControlLaw, Controller, Measurement};
pub use crate::model::CommandPath;
use crate::model::{Inputs, Model, ModelKind, Outputs};
use crate::params::MAX_DELAY_S;
use crate::scenario::{CommandSignal, PlatformMotion, PlatformSample};
use crate::simulation::delay::{DelayLine, Tap};
use crate::simulation::integrate::{Etd4, Method, Rk4, StepStats, Stepper, rk4_step};
use crate::simulation::lti::{ExactHold, LinearTimeInvariant};

mod csv;
pub mod delay;
mod hold_paper;
pub mod integrate;
pub mod lti;
mod memo;
mod run;
mod sample;
mod specialised;
mod state;
pub use csv::{CsvRunError, SAMPLE_UNITS, SampleColumns, write_csv_streamed};
pub use delay::RestoreError;
pub use run::{Run, RunState, RunStateSnapshot, wide_simd};
pub(crate) use run::{check_bounds, trace_buffer};
pub use sample::{ContactEvent, RunSummary, Sample, Trace, record_every, sample_count};
use specialised::{Advance, StepMethod};
pub use state::SimulationState;

/// Where the valve command comes from.
#[derive(Debug, Clone, PartialEq)]
pub enum Drive {
    /// A controller ([`crate::control`]) in closed loop.
    ClosedLoop(ControlLaw),
    /// An open-loop command (sine tests, replay).
    OpenLoop(CommandSignal),
}

impl Drive {
    /// Closed loop with the preset's controller (the passive model ignores it).
    pub fn closed_loop(params: &crate::params::Params) -> Self {
        Drive::ClosedLoop(ControlLaw::new(params))
    }
}

/// A numerical failure of a run.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SimError {
    /// A state became non-finite or left its physical bound: the run diverged.
    #[error(
        "{model} model diverged at t = {t:.6} s: state {state} = {} (bound ±{}); \
         check the gains (an unstable loop) or reduce numerics.max_step_s",
        crate::format::general(*.value),
        crate::format::general(*.bound)
    )]
    Diverged {
        /// Which model.
        model: &'static str,
        /// Time of detection \[s\].
        t: f64,
        /// Name of the offending state.
        state: &'static str,
        /// Its value.
        value: f64,
        /// Its bound.
        bound: f64,
    },
}

/// A model stepped with its command path and excitation.
#[derive(Debug, Clone)]
pub struct Simulation<M: Model<N>, const N: usize> {
    model: M,
    y: [f64; N],
    /// The grid, the steps taken and the contacts.
    run: RunState,
    tau: f64,
    v_max: f64,
    drive: Drive,
    platform: PlatformMotion,
    /// The controller with its state, when the drive is closed loop.
    controller: Option<Controller>,
    history: DelayLine,
    /// Reads of `history` at `t − τ`, `t + h/2 − τ`, `t + h − τ` for grid times `t`, when
    /// τ ≥ h (then the three are stored before the step).
    taps: Option<[Tap; 3]>,
    /// Record samples per step when the platform is a record the grid lands on.
    stride: Option<usize>,
    /// The exact hold's command at the valve at the current grid time [V], kept from the
    /// previous step's end when that read is, bit for bit, the same (closed loop, a settled
    /// tap: [`Tap::is_settled`]); `None` otherwise.
    valve_now: Option<f64>,
    /// Divergence bound of each state (the model's [`Model::state_bound`]).
    bounds: [f64; N],
    /// Platform acceleration at the current time [m/s²] (the previous step's end value).
    xdd_now: f64,
    stats: StepStats,
    /// The stepper (the solver; everything above is the problem it solves): RK4, the
    /// exponential integrator for
    /// [`Integrator::Exponential`](crate::params::Integrator::Exponential), or the exact hold
    /// of a linear model ([`Self::exact_hold`]).
    method: Method<N>,
}

impl Simulation<crate::model::twin::Twin, 10> {
    /// The twin from rest, stepped with `params.numerics.integrator` at step `h` \[s\].
    ///
    /// The exponential integrator's coefficients always build for validated parameters (its
    /// step ≤ 1 ms keeps `h·A` moderate; the twin has four nonlinear rows); should they not,
    /// RK4 is used and the run is checked for divergence as always.
    pub fn twin(
        params: &crate::params::Params,
        h: f64,
        drive: Drive,
        platform: PlatformMotion,
    ) -> Self {
        let mut sim = Self::new(crate::model::twin::Twin::new(*params), h, drive, platform);
        if params.numerics.integrator == crate::params::Integrator::Exponential {
            let _ = sim.use_exponential();
        }
        sim
    }
}

impl<M: Model<N> + CommandPath + LinearTimeInvariant, const N: usize> Simulation<M, N> {
    /// A linear model from rest stepped exactly at step `h` \[s\] ([`crate::simulation::lti`]), or
    /// `None` when the command delay is shorter than the step (then the delayed command at a
    /// step's end is not yet known at its start; use [`Self::new`], RK4).
    pub fn exact_hold(model: M, h: f64, drive: Drive, platform: PlatformMotion) -> Option<Self> {
        hold_fits(&model, h).then(|| Self::exact_or_rk4(model, h, h, drive, platform))
    }

    /// The linear model stepped as `seat-twin simulate` steps it: exactly at `h_exact` \[s\]
    /// ([`Self::exact_hold`]), or by RK4 at `h_rk4` \[s\] when the delay is shorter than
    /// `h_exact`.
    pub fn exact_or_rk4(
        model: M,
        h_exact: f64,
        h_rk4: f64,
        drive: Drive,
        platform: PlatformMotion,
    ) -> Self {
        if hold_fits(&model, h_exact) {
            let hold = ExactHold::new(&model, h_exact);
            let mut sim = Self::new(model, h_exact, drive, platform);
            sim.method = Method::ExactHold(Box::new(hold));
            sim.refresh_valve_now();
            sim
        } else {
            Self::new(model, h_rk4, drive, platform)
        }
    }
}

/// Whether the exact hold can step `model` at `h` [s]: no command, or one delayed by ≥ h.
fn hold_fits<M: CommandPath>(model: &M, h: f64) -> bool {
    model.command_limit() == 0.0 || model.command_delay() >= h
}

impl<M: Model<N> + CommandPath, const N: usize> Simulation<M, N> {
    /// A run from rest at t = 0 with internal step `h` \[s\].
    pub fn new(model: M, h: f64, drive: Drive, platform: PlatformMotion) -> Self {
        let y = model.rest_state();
        let tau = model.command_delay();
        let v_max = model.command_limit();
        let mut history = DelayLine::new(h, MAX_DELAY_S + h, 0.0);
        let taps = stage_taps(&history, tau, h);
        let stride = platform.grid_stride(h);
        let xdd_now = platform.xdd_at_grid(0, h, stride);
        let bounds = std::array::from_fn(|i| model.state_bound(i));
        let mut sim = Self {
            model,
            y,
            run: RunState::new(h),
            tau,
            v_max,
            controller: closed_loop_controller(&drive, h),
            drive,
            platform,
            history: DelayLine::new(h, 0.0, 0.0),
            taps,
            stride,
            valve_now: None,
            bounds,
            xdd_now,
            stats: StepStats::default(),
            method: Method::Rk4(Rk4 { h }),
        };
        let u0 = sim.model.relative_position(&sim.y);
        start_controller(&mut sim.controller, u0, xdd_now);
        let v0 = sim.command_now();
        send_command(&mut sim.controller, &mut history, v0);
        sim.history = history;
        sim
    }

    /// The model.
    pub fn model(&self) -> &M {
        &self.model
    }

    /// The raw state array (for linearisation and tests).
    pub fn state(&self) -> &[f64; N] {
        &self.y
    }

    /// Replaces the model (e.g. new parameters from a slider) keeping the state and time.
    pub fn set_model(&mut self, model: M) {
        self.tau = model.command_delay();
        self.v_max = model.command_limit();
        self.taps = stage_taps(&self.history, self.tau, self.run.h);
        self.bounds = std::array::from_fn(|i| model.state_bound(i));
        self.model = model;
        match &self.method {
            Method::Rk4(_) => {}
            Method::Exponential(_) => {
                if self.use_exponential().is_err() {
                    self.method = Method::Rk4(Rk4 { h: self.run.h });
                }
            }
            // The model is of the same (linear) type: its new transition, while τ ≥ h.
            Method::ExactHold(_) => {
                self.method = if hold_fits(&self.model, self.run.h) {
                    Method::ExactHold(Box::new(ExactHold::new(&self.model, self.run.h)))
                } else {
                    Method::Rk4(Rk4 { h: self.run.h })
                };
            }
        }
        self.refresh_valve_now();
    }

    /// Steps with the exponential integrator [`Etd4`], its matrix the model's Jacobian at rest
    /// (central differences at the model's state scales). On error RK4 stays in use.
    pub fn use_exponential(&mut self) -> Result<(), crate::simulation::integrate::Etd4Error> {
        let rest = self.model.rest_state();
        let scales = self.model.state_scales();
        let a = crate::model::jacobian(&self.model, &rest, &scales);
        // Unit inputs in the probe make the rows the inputs enter count as nonlinear.
        let inputs = Inputs {
            v_valve: 1.0,
            xdd: 1.0,
        };
        let etd = Etd4::new(self.run.h, &a, rest, &scales, |y| {
            self.model.derivatives(0.0, y, &inputs)
        })?;
        self.method = Method::Exponential(Box::new(etd));
        Ok(())
    }

    /// Rows of the right-hand side the exponential integrator treats explicitly, if in use.
    pub fn exponential_rows(&self) -> Option<&[usize]> {
        self.method.exponential().map(|e| e.nonlinear_rows())
    }

    /// Whether the exponential integrator is in use.
    pub fn is_exponential(&self) -> bool {
        self.method.exponential().is_some()
    }

    /// Replaces the platform motion from the current time on (an FMU's inputs at a
    /// communication point), keeping the state and time. The step that starts now reads the
    /// new motion at its start too: a motion that jumps now is taken at its right limit.
    pub fn set_platform(&mut self, platform: PlatformMotion) {
        self.stride = platform.grid_stride(self.run.h);
        self.xdd_now = platform.xdd_at_grid(self.run.steps, self.run.h, self.stride);
        self.platform = platform;
    }

    /// The drive in use.
    pub fn drive(&self) -> &Drive {
        &self.drive
    }

    /// Replaces the drive (e.g. new gains) keeping the state and time; a controller keeps its
    /// signal states ([`Controller::retune`]).
    pub fn set_drive(&mut self, drive: Drive) {
        match (&drive, self.controller.as_mut()) {
            (Drive::ClosedLoop(law), Some(c)) => c.retune(law),
            _ => {
                self.controller = closed_loop_controller(&drive, self.run.h);
                let u = self.model.relative_position(&self.y);
                start_controller(&mut self.controller, u, self.xdd_now);
            }
        }
        self.drive = drive;
        self.refresh_valve_now();
    }

    /// Reads the exact hold's command at the valve now, when it can be kept between steps
    /// ([`Self::settled_valve`]); forgets it otherwise.
    fn refresh_valve_now(&mut self) {
        let keep = matches!(self.method, Method::ExactHold(_)) && self.settled_valve();
        self.valve_now = keep.then(|| self.valve_at_grid(self.run.steps, 1.0));
    }

    #[inline(always)]
    fn saturate(&self, v: f64) -> f64 {
        v.clamp(-self.v_max, self.v_max)
    }

    /// Command as sent at the current time (before the delay) \[V\].
    #[inline(always)]
    pub fn command_now(&self) -> f64 {
        self.command_for(self.time(), &self.y, 0.0)
    }

    /// Command at time `t` for state `y`, `dxd` [m/s] of `∫ẍ` beyond the last grid time.
    #[inline(always)]
    fn command_for(&self, t: f64, y: &[f64; N], dxd: f64) -> f64 {
        match (&self.drive, &self.controller) {
            (Drive::ClosedLoop(_), Some(c)) => {
                self.saturate(c.output_with(self.model.relative_position(y), dxd))
            }
            (Drive::OpenLoop(sig), _) => self.saturate(sig.at(t)),
            (Drive::ClosedLoop(_), None) => 0.0,
        }
    }

    /// Command at the valve at stage time `ts` with stage state `ys` [V].
    ///
    /// `side` is +1 for the first stage of a step, −1 for the last and 0 in between: an
    /// open-loop command that jumps on a grid point (a sine test starting at t = τ) is read
    /// as its right limit at the start of a step and its left limit at the end, whatever the
    /// rounding of `t − τ`. Without this, RK4 drops to first order on such tests
    /// (`tests/it/integrator.rs`).
    #[inline(always)]
    fn valve_command(&self, ts: f64, side: f64, ys: &[f64; N], xdd0: f64, xdds: f64) -> f64 {
        let tq = ts - self.tau;
        match &self.drive {
            Drive::OpenLoop(sig) => self.saturate(sig.at(tq + side * 1e-6 * self.run.h)),
            Drive::ClosedLoop(_) => {
                let t_last = self.history.last_time();
                if tq <= t_last + 1e-12 * self.run.h {
                    self.history.value_at(tq)
                } else {
                    // τ shorter than the stage offset: blend the newest stored command with
                    // the command of the stage state itself (exact for τ = 0).
                    let dz = 0.5 * (ts - self.time()) * (xdd0 + xdds);
                    let v_now = self.command_for(ts, ys, dz);
                    let span = ts - t_last;
                    let w = if span > 0.0 {
                        (tq - t_last) / span
                    } else {
                        1.0
                    };
                    self.history.last_value() + w * (v_now - self.history.last_value())
                }
            }
        }
    }

    /// Steps the controller to the current grid time; `dxd` is `∫ẍ dt` over the step.
    #[inline(always)]
    fn advance_controller(&mut self, dxd: f64) {
        let Some(c) = self.controller.as_ref() else {
            return;
        };
        let ydd = if c.needs_body_acceleration() {
            self.outputs().ydd
        } else {
            0.0
        };
        let m = Measurement {
            u: self.model.relative_position(&self.y),
            ydd,
            xdd: self.xdd_now,
            dxd,
        };
        if let Some(c) = self.controller.as_mut() {
            c.advance(&m);
        }
    }

    #[inline(always)]
    fn check_state(&self) -> Result<(), SimError> {
        // `|v| ≤ bound` is false for NaN as well: one pass of comparisons in the usual case.
        if self.y.iter().zip(&self.bounds).all(|(v, b)| v.abs() <= *b) {
            return Ok(());
        }
        check_bounds::<M, N>(&self.y, self.time(), |i| self.bounds[i])
    }

    #[inline(always)]
    fn track_contact(&mut self) {
        let u = self.model.relative_position(&self.y);
        self.run.track_contact(u, self.model.half_stroke());
    }

    /// One step of a stage method (RK4, exponential) from the current state: the new state,
    /// the platform's acceleration at the step's end [m/s²] and the controller's `∫ẍ dt` over
    /// the step [m/s] (Simpson's rule, as the stages see ẍ).
    #[inline(always)]
    fn stages_step<S: Stepper<N>>(&self, method: &S) -> Advance<N> {
        let (t, h, n) = (self.time(), self.run.h, self.run.steps);
        if let Some(at) = self.open_loop_start_inside(t, h) {
            return self.split_at_start(at);
        }
        let xdd0 = self.xdd_now;
        let xdd_mid = self.platform.xdd_at(t + 0.5 * h);
        let xdd1 = self.platform.xdd_at_grid(n + 1, h, self.stride);
        let mut y = self.y;
        // Closed loop with τ ≥ h (the usual case): the delayed command at the three distinct
        // stage times is already in the history, so read it once per step, not per stage.
        let pre = match (&self.drive, &self.taps) {
            (Drive::ClosedLoop(_), Some([t0, t1, t2])) => Some([
                self.history.value_at_tap(n, t0),
                self.history.value_at_tap(n, t1),
                self.history.value_at_tap(n, t2),
            ]),
            _ => None,
        };
        let rhs = |ts: f64, ys: &[f64; N]| {
            // The stage's place in the step: its start, its middle or its end (the index of
            // its read in `pre`: an integer, not converted from `side` at every stage).
            let (xdds, side, read) = if ts == t {
                (xdd0, 1.0, 0)
            } else if ts == t + h {
                (xdd1, -1.0, 2)
            } else {
                (xdd_mid, 0.0, 1)
            };
            let v_valve = match pre {
                Some(v) => v[read],
                None => self.valve_command(ts, side, ys, xdd0, xdds),
            };
            let inputs = Inputs { v_valve, xdd: xdds };
            self.model.derivatives(ts, ys, &inputs)
        };
        method.step(t, &mut y, rhs);
        Advance {
            y,
            xdd1,
            dxd: h / 6.0 * (xdd0 + 4.0 * xdd_mid + xdd1),
            valve_end: None,
            evals: 4,
        }
    }

    /// The time the valve first sees an open-loop command that starts away from zero (a sine
    /// test's cosine: the command jumps at the valve at `t = τ`), when that jump lies inside
    /// the step from `t` by `h` [s] rather than on one of its ends.
    ///
    /// A stage method samples its input at `t`, `t + h/2` and `t + h` only, so a jump inside a
    /// step is taken as if it happened at one of those times: the valve opens up to h/2 early
    /// or late (0.25 ms at the replay's 0.5 ms step). At full opening that is a volume the
    /// stroke keeps as an offset for the whole record (0.5 m/s × 0.1 ms = 50 µm, four times a
    /// 12-bit stroke sensor's noise), and it jumps with the fractional part of τ/h rather than
    /// following τ smoothly.
    #[inline(always)]
    fn open_loop_start_inside(&self, t: f64, h: f64) -> Option<f64> {
        let tol = 1e-6 * h;
        if !(self.tau > t + tol && self.tau < t + h - tol) {
            return None;
        }
        match &self.drive {
            Drive::OpenLoop(sig) if self.saturate(sig.at(0.0)) != 0.0 => Some(self.tau),
            _ => None,
        }
    }

    /// The step from the current time over which the open-loop command jumps at the valve at
    /// `at` [s] (see [`Self::open_loop_start_inside`]), integrated by RK4 in sub-steps of at
    /// most [`SPLIT_SUBSTEPS`]-th of the step on each side of the jump, so that the valve sees
    /// the command from exactly `at`: before it the command's left limit (zero), from it on its
    /// right limit. Happens once per run.
    #[cold]
    fn split_at_start(&self, at: f64) -> Advance<N> {
        let (t, h, n) = (self.time(), self.run.h, self.run.steps);
        let Drive::OpenLoop(sig) = &self.drive else {
            unreachable!("only an open-loop command jumps at the valve");
        };
        let xdd0 = self.xdd_now;
        let xdd1 = self.platform.xdd_at_grid(n + 1, h, self.stride);
        let mut y = self.y;
        let mut evals = 0;
        for (a, b, opened) in [(t, at, false), (at, t + h, true)] {
            let m = ((b - a) / h * SPLIT_SUBSTEPS as f64).ceil().max(1.0) as usize;
            let hs = (b - a) / m as f64;
            for k in 0..m {
                let ts0 = a + k as f64 * hs;
                rk4_step(ts0, hs, &mut y, |ts, ys| {
                    let v_valve = if opened {
                        self.saturate(sig.at((ts - at).max(0.0)))
                    } else {
                        0.0
                    };
                    let xdd = if ts <= t {
                        xdd0
                    } else if ts >= t + h {
                        xdd1
                    } else {
                        self.platform.xdd_at(ts)
                    };
                    self.model.derivatives(ts, ys, &Inputs { v_valve, xdd })
                });
                evals += 4;
            }
        }
        Advance {
            y,
            xdd1,
            dxd: h / 6.0 * (xdd0 + 4.0 * self.platform.xdd_at(t + 0.5 * h) + xdd1),
            valve_end: None,
            evals,
        }
    }

    /// One exact-hold step (see [`Self::stages_step`]), and the command at the valve at its
    /// end [V]; the controller's `∫ẍ dt` is the trapezoid, the same hold as the plant's input.
    #[inline(always)]
    fn hold_step(&self, hold: &ExactHold<N>) -> Advance<N> {
        let (h, n) = (self.run.h, self.run.steps);
        let xdd0 = self.xdd_now;
        let xdd1 = self.platform.xdd_at_grid(n + 1, h, self.stride);
        let v0 = self.valve_now.unwrap_or_else(|| self.valve_at_grid(n, 1.0));
        let v1 = self.valve_at_grid(n + 1, -1.0);
        let mut y = self.y;
        hold.step(&mut y, [v0, xdd0], [v1, xdd1]);
        Advance {
            y,
            xdd1,
            dxd: 0.5 * h * (xdd0 + xdd1),
            valve_end: Some(v1),
            evals: 0,
        }
    }

    /// Whether the command at the valve read for a step's end is, bit for bit, the one read
    /// at the next step's start: closed loop with a settled tap.
    fn settled_valve(&self) -> bool {
        matches!(
            (&self.drive, &self.taps),
            (Drive::ClosedLoop(_), Some([tap, ..])) if tap.is_settled() && self.v_max > 0.0
        )
    }

    /// Command at the valve at grid time `n·h` [V] when τ ≥ h (it is then in the history); an
    /// open-loop command's jump there is read as its right limit for `side` = +1 and its left
    /// limit for −1 (see [`Self::valve_command`]).
    #[inline(always)]
    fn valve_at_grid(&self, n: u64, side: f64) -> f64 {
        if self.v_max == 0.0 {
            // No valve (the passive seat): nothing to read.
            return 0.0;
        }
        match (&self.drive, &self.taps) {
            (Drive::ClosedLoop(_), Some([tap, ..])) => self.history.value_at_tap(n, tap),
            (Drive::ClosedLoop(_), None) => self.history.value_at(n as f64 * self.run.h - self.tau),
            (Drive::OpenLoop(sig), _) => {
                self.saturate(sig.at(n as f64 * self.run.h - self.tau + side * 1e-6 * self.run.h))
            }
        }
    }

    /// Inputs at the current time (for outputs).
    #[inline(always)]
    fn inputs_now(&self) -> Inputs {
        Inputs {
            v_valve: match (&self.drive, self.valve_now) {
                // No valve (the passive seat): nothing to read.
                _ if self.v_max == 0.0 => 0.0,
                (_, Some(v)) => v,
                (Drive::OpenLoop(sig), None) => self.saturate(sig.at(self.time() - self.tau)),
                (Drive::ClosedLoop(_), None) => match &self.taps {
                    Some([tap, ..]) => self.history.value_at_tap(self.run.steps, tap),
                    None => self.history.value_at(self.time() - self.tau),
                },
            },
            xdd: self.xdd_now,
        }
    }

    /// Model outputs at the current time.
    #[inline(always)]
    pub fn outputs(&self) -> Outputs {
        self.model.outputs(&self.y, &self.inputs_now())
    }
}

impl<M: Model<N> + CommandPath, const N: usize> Simulation<M, N> {
    /// The sample now, the platform's motion now being `platform`.
    #[inline(always)]
    fn sample_with(&self, platform: PlatformSample) -> Sample {
        let v_in = if M::KIND.has_command() {
            self.history.last_value()
        } else {
            f64::NAN
        };
        Sample::assemble(
            self.time(),
            platform,
            &self.outputs(),
            v_in,
            self.model.half_stroke(),
        )
    }

    /// Takes a step's result: the new state, the clock, the divergence check, the controller
    /// and the command it sends, the end-stop contacts.
    #[inline(always)]
    fn finish_step(&mut self, advance: Advance<N>) -> Result<(), SimError> {
        let Advance {
            y,
            xdd1,
            dxd,
            valve_end,
            evals,
        } = advance;
        if let (Some(_), Some(v1)) = (self.valve_now, valve_end) {
            self.valve_now = Some(v1);
        }
        self.y = y;
        self.model.project(&mut self.y);
        self.stats.steps += 1;
        self.stats.rhs_evals += evals;
        self.run.steps += 1;
        self.xdd_now = xdd1;
        self.check_state()?;
        // A model without a valve (the passive seat) takes no command: its controller and
        // delay line would compute what nothing reads (its valve input is 0, its `v_in` NaN).
        if M::KIND.has_command() {
            self.advance_controller(dxd);
            let v = self.command_now();
            send_command(&mut self.controller, &mut self.history, v);
        }
        self.track_contact();
        Ok(())
    }
}

impl<M: Model<N> + CommandPath, const N: usize> Run for Simulation<M, N> {
    const KIND: ModelKind = M::KIND;

    fn run_state(&self) -> &RunState {
        &self.run
    }

    #[inline(always)]
    fn step(&mut self) -> Result<(), SimError> {
        let advance = match &self.method {
            Method::Rk4(m) => m.advance(self),
            Method::Exponential(m) => (**m).advance(self),
            Method::ExactHold(m) => (**m).advance(self),
        };
        self.finish_step(advance)
    }

    fn stream_steps(
        &mut self,
        t_end: f64,
        every: u64,
        record: impl FnMut(Sample) -> bool,
    ) -> Result<(u64, bool), SimError> {
        self.stream_specialised(t_end, every, record)
    }

    #[inline(always)]
    fn sample(&self) -> Sample {
        let n = self.run.steps;
        // A record on the grid is read in place, and the sample assembled in that branch: with
        // one assembly after both branches, the platform's values went through a stack slot
        // (the interpolating branch is a call), and reading them back as a pair stalled on
        // the store of each (a quarter of the linear model's run). Same values either way.
        match (&self.platform, self.stride) {
            (PlatformMotion::Sampled(s), Some(k)) => self.sample_with(s.at_sample(n as usize * k)),
            _ => self.sample_with(self.platform.at_grid(n, self.run.h, self.stride)),
        }
    }

    fn stats(&self) -> StepStats {
        self.stats
    }
}

/// The controller a drive runs, if it is closed loop.
pub(crate) fn closed_loop_controller(drive: &Drive, h: f64) -> Option<Controller> {
    match drive {
        Drive::ClosedLoop(law) => Some(Controller::new(law, h)),
        Drive::OpenLoop(_) => None,
    }
}

/// Gives a closed loop's controller its first measurement: stroke `u` [m] and platform
/// acceleration `xdd` [m/s²] (no body acceleration and no `∫ẍ` yet).
pub(crate) fn start_controller(controller: &mut Option<Controller>, u: f64, xdd: f64) {
    if let Some(c) = controller.as_mut() {
        c.start(&Measurement {
            u,
            ydd: 0.0,
            xdd,
            dxd: 0.0,
        });
    }
}

/// Records `v` [V] as the command sent at the current grid time: the controller is told, and
/// the delay line stores it for the valve to read `τ` later.
#[inline(always)]
pub(crate) fn send_command(controller: &mut Option<Controller>, history: &mut DelayLine, v: f64) {
    if let Some(c) = controller.as_mut() {
        c.sent(v);
    }
    history.push(v);
}

/// Sub-steps per step of the RK4 run over the step in which an open-loop command jumps at the
/// valve ([`Simulation::split_at_start`]): at 1/32 of the replay's 0.5 ms step RK4 is stable on
/// the twin's fastest mode (the true rig of the tests steps it at 50 µs).
const SPLIT_SUBSTEPS: usize = 32;

/// The reads of the delayed command at a step's three stage times, when τ ≥ h.
fn stage_taps(history: &DelayLine, tau: f64, h: f64) -> Option<[Tap; 3]> {
    (tau >= h).then(|| [tau, tau - 0.5 * h, tau - h].map(|d| history.tap(d)))
}

/// Largest step ≤ `max_step` \[s\] that divides the output interval `1/rate_hz` exactly.
pub fn step_for_rate(max_step: f64, rate_hz: f64) -> f64 {
    let dt_out = 1.0 / rate_hz;
    let n = (dt_out / max_step - 1e-9).ceil().max(1.0);
    dt_out / n
}
