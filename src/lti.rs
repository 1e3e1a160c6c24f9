//! Exact discretisation of the linear models (G(s) and the passive seat) for fast runs.
//!
//! The linear model and the passive reference are linear time-invariant, so instead of RK4 at
//! the twin's 0.1 ms step they are advanced at the output interval with the exact transition
//! of a first-order hold: over one step `[t_k, t_k + h]` the inputs `w = (V_valve, ẍ)` are
//! taken as linear between their sampled values, and
//!
//! ```text
//! x_{k+1} = Φ·x_k + Γa·w_k + Γb·(w_{k+1} − w_k)/h,
//! exp([[A, B, 0], [0, 0, I], [0, 0, 0]]·h) = [[Φ, Γa, Γb], [0, I, h·I], [0, 0, I]]
//! ```
//!
//! (one matrix exponential, computed once per run). The only approximation is the hold of
//! the inputs between samples, O(h²) in their curvature; `tests/it/physics.rs` checks the result
//! against the closed-form transmissibility and this module's tests against a fine RK4 run.
//! `A` and `B` are read off the model's own [`Model::derivatives`] (exact for a linear model),
//! so there is one definition of each model.
//!
//! The controller, saturation and pure delay are the same as in [`crate::simulation`]: the
//! command is sampled at each step, stored in a [`DelayLine`] and read back at `t − τ`. This
//! needs `τ ≥ h` (or no command at all); [`LtiSimulation::new`] returns `None` otherwise and
//! the caller falls back to RK4.

use crate::control::{Controller, Measurement};
use crate::delay::{DelayLine, Tap};
use crate::integrate::StepStats;
use crate::model::{Inputs, Model, ModelKind};
use crate::params::MAX_DELAY_S;
use crate::scenario::PlatformMotion;
use crate::simulation::{
    CommandPath, Drive, Run, RunState, Sample, SimError, check_bounds, closed_loop_controller,
    send_command, start_controller,
};
use nalgebra::{DMatrix, SMatrix};

/// Marker for models whose derivatives are linear in state and inputs.
pub trait LinearTimeInvariant {}

impl LinearTimeInvariant for crate::model::linear::LinearModel {}
impl LinearTimeInvariant for crate::model::passive::PassiveModel {}

/// A linear model stepped exactly (first-order hold of the inputs) at a fixed step.
#[derive(Debug, Clone)]
pub struct LtiSimulation<M, const N: usize> {
    model: M,
    /// Rows of Φ.
    phi: [[f64; N]; N],
    /// Rows of `Γa − Γb/h`, applied to the inputs at the start of a step.
    g0: [[f64; 2]; N],
    /// Rows of `Γb/h`, applied to the inputs at the end of a step.
    g1: [[f64; 2]; N],
    /// The grid, the steps taken and the contacts.
    run: RunState,
    tau: f64,
    v_max: f64,
    drive: Drive,
    platform: PlatformMotion,
    y: [f64; N],
    /// Divergence bound of each state (the model's [`Model::state_bound`]).
    bounds: [f64; N],
    /// The controller with its state, when the drive is closed loop.
    controller: Option<Controller>,
    history: DelayLine,
    /// The read of `history` at `t − τ` for grid times `t`.
    tap: Tap,
    /// Record samples per step when the platform is a record the grid lands on.
    stride: Option<usize>,
    /// Platform acceleration at the current time [m/s²] (the previous step's end value).
    xdd_now: f64,
    /// Command at the valve now [V], kept from the previous step when `reuse_valve`.
    valve_now: f64,
    /// Closed loop with a settled tap ([`Tap::is_settled`]): the end-of-step read
    /// is the next step's start read, bit for bit.
    reuse_valve: bool,
}

impl<M: Model<N> + CommandPath + LinearTimeInvariant, const N: usize> LtiSimulation<M, N> {
    /// A run from rest with step `h` [s], or `None` when the command delay is shorter than the
    /// step (then the delayed command is not yet known at the end of a step).
    pub fn new(model: M, h: f64, drive: Drive, platform: PlatformMotion) -> Option<Self> {
        let tau = model.command_delay();
        let v_max = model.command_limit();
        let has_command = v_max > 0.0;
        if has_command && tau < h {
            return None;
        }
        let (a, b) = state_space(&model);
        let (phi, gamma_a, gamma_b) = foh(&a, &b, h);
        // x_{k+1} = Φ·x_k + (Γa − Γb/h)·w_k + (Γb/h)·w_{k+1}, by rows.
        let g1 = gamma_b / h;
        let g0 = gamma_a - g1;
        let rows2 = |m: SMatrix<f64, N, 2>| std::array::from_fn(|i| [m[(i, 0)], m[(i, 1)]]);
        let bounds = std::array::from_fn(|i| model.state_bound(i));
        let mut history = DelayLine::new(h, MAX_DELAY_S + h, 0.0);
        let y = model.rest_state();
        let tap = history.tap(tau);
        let stride = platform.grid_stride(h);
        let xdd_now = platform.xdd_at_grid(0, h, stride);
        let controller = closed_loop_controller(&drive, h);
        let mut sim = Self {
            model,
            phi: std::array::from_fn(|i| std::array::from_fn(|j| phi[(i, j)])),
            g0: rows2(g0),
            g1: rows2(g1),
            run: RunState::new(h),
            tau,
            v_max,
            drive,
            platform,
            y,
            bounds,
            controller,
            history: DelayLine::new(h, 0.0, 0.0),
            tap,
            stride,
            xdd_now,
            valve_now: 0.0,
            reuse_valve: false,
        };
        let u0 = sim.model.relative_position(&sim.y);
        start_controller(&mut sim.controller, u0, xdd_now);
        let v0 = sim.command_now();
        send_command(&mut sim.controller, &mut history, v0);
        sim.history = history;
        sim.reuse_valve = matches!(sim.drive, Drive::ClosedLoop(_)) && sim.tap.is_settled();
        sim.valve_now = sim.valve_command(0, 1.0);
        Some(sim)
    }

    /// Command as sent at the current time (before the delay) [V].
    #[inline(always)]
    fn command_now(&self) -> f64 {
        let v = match (&self.drive, &self.controller) {
            (Drive::ClosedLoop(_), Some(c)) => c.output(self.model.relative_position(&self.y)),
            (Drive::OpenLoop(sig), _) => sig.at(self.time()),
            (Drive::ClosedLoop(_), None) => 0.0,
        };
        v.clamp(-self.v_max, self.v_max)
    }

    /// Command at the valve at the grid time `n·h` (after the delay) [V]; `side` = +1 reads a
    /// jump of an open-loop command as its right limit, −1 as its left limit (see
    /// `Simulation`).
    #[inline(always)]
    fn valve_command(&self, n: u64, side: f64) -> f64 {
        if self.v_max == 0.0 {
            // No valve (the passive seat): nothing to read.
            return 0.0;
        }
        match &self.drive {
            Drive::ClosedLoop(_) => self.history.value_at_tap(n, &self.tap),
            Drive::OpenLoop(sig) => sig
                .at(n as f64 * self.run.h - self.tau + side * 1e-6 * self.run.h)
                .clamp(-self.v_max, self.v_max),
        }
    }

    /// Command at the valve now [V]: kept from the previous step's end when `reuse_valve`,
    /// else read with `side` as in [`Self::valve_command`].
    #[inline(always)]
    fn valve_command_now(&self, side: f64) -> f64 {
        if self.reuse_valve {
            self.valve_now
        } else {
            self.valve_command(self.run.steps, side)
        }
    }

    /// Advances one step to a time where the platform's acceleration is `xdd1` [m/s²].
    #[inline(always)]
    fn advance(&mut self, xdd1: f64) -> Result<(), SimError> {
        let n = self.run.steps;
        let xdd0 = self.xdd_now;
        let v0 = self.valve_command_now(1.0);
        let v1 = self.valve_command(n + 1, -1.0);
        self.valve_now = v1;
        let y = self.y;
        for (i, yi) in self.y.iter_mut().enumerate() {
            let (g0, g1) = (self.g0[i], self.g1[i]);
            let mut acc = g0[0] * v0 + g0[1] * xdd0 + g1[0] * v1 + g1[1] * xdd1;
            for (p, yj) in self.phi[i].iter().zip(&y) {
                acc += p * yj;
            }
            *yi = acc;
        }
        self.run.steps += 1;
        self.xdd_now = xdd1;
        self.check_state()?;
        if let Some(c) = self.controller.as_ref() {
            // ÿ at the step's end, only for a controller that reads it.
            let ydd = if c.needs_body_acceleration() {
                let inputs = Inputs {
                    v_valve: v1,
                    xdd: xdd1,
                };
                self.model.outputs(&self.y, &inputs).ydd
            } else {
                0.0
            };
            let m = Measurement {
                u: self.model.relative_position(&self.y),
                ydd,
                xdd: xdd1,
                // The controller's ∫ẍ with the same hold as the plant's input (trapezoid).
                dxd: 0.5 * self.run.h * (xdd0 + xdd1),
            };
            if let Some(c) = self.controller.as_mut() {
                c.advance(&m);
            }
        }
        let v = self.command_now();
        send_command(&mut self.controller, &mut self.history, v);
        self.track_contact();
        Ok(())
    }

    #[inline(always)]
    fn check_state(&self) -> Result<(), SimError> {
        // `|v| ≤ bound` is false for NaN as well.
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

    /// The current instant as a recorded sample, the platform's motion now being `p`.
    #[inline(always)]
    fn sample_with(&self, p: crate::scenario::PlatformSample) -> Sample {
        let v_valve = self.valve_command_now(0.0);
        let inputs = Inputs {
            v_valve,
            xdd: p.xdd,
        };
        let o = self.model.outputs(&self.y, &inputs);
        let v_in = if M::KIND.has_command() {
            self.history.last_value()
        } else {
            f64::NAN
        };
        Sample::assemble(self.time(), p, &o, v_in, self.model.half_stroke())
    }
}

impl<M: Model<N> + CommandPath + LinearTimeInvariant, const N: usize> Run for LtiSimulation<M, N> {
    const KIND: ModelKind = M::KIND;

    fn run_state(&self) -> &RunState {
        &self.run
    }

    #[inline]
    fn step(&mut self) -> Result<(), SimError> {
        let xdd1 = self
            .platform
            .xdd_at_grid(self.run.steps + 1, self.run.h, self.stride);
        self.advance(xdd1)
    }

    fn sample(&self) -> Sample {
        self.sample_with(
            self.platform
                .at_grid(self.run.steps, self.run.h, self.stride),
        )
    }

    fn stats(&self) -> StepStats {
        StepStats {
            steps: self.run.steps,
            rhs_evals: 0,
        }
    }

    /// A recorded step reads the platform's whole motion once, for both.
    #[inline(always)]
    fn step_sampled(&mut self) -> Result<Sample, SimError> {
        let p = self
            .platform
            .at_grid(self.run.steps + 1, self.run.h, self.stride);
        self.advance(p.xdd)?;
        Ok(self.sample_with(p))
    }
}

/// `A` and `B = [b_v, b_ẍ]` of a linear model, read off its derivatives at rest.
fn state_space<M: Model<N>, const N: usize>(model: &M) -> (SMatrix<f64, N, N>, SMatrix<f64, N, 2>) {
    let zero = [0.0; N];
    let f = |y: &[f64; N], v: f64, xdd: f64| model.derivatives(0.0, y, &Inputs { v_valve: v, xdd });
    let f0 = f(&zero, 0.0, 0.0);
    let mut a = SMatrix::<f64, N, N>::zeros();
    for j in 0..N {
        let mut e = zero;
        e[j] = 1.0;
        let fj = f(&e, 0.0, 0.0);
        for i in 0..N {
            a[(i, j)] = fj[i] - f0[i];
        }
    }
    let mut b = SMatrix::<f64, N, 2>::zeros();
    let (fv, fx) = (f(&zero, 1.0, 0.0), f(&zero, 0.0, 1.0));
    for i in 0..N {
        b[(i, 0)] = fv[i] - f0[i];
        b[(i, 1)] = fx[i] - f0[i];
    }
    (a, b)
}

/// First-order-hold transition matrices `(Φ, Γa, Γb)` for step `h`.
#[allow(clippy::type_complexity)]
fn foh<const N: usize>(
    a: &SMatrix<f64, N, N>,
    b: &SMatrix<f64, N, 2>,
    h: f64,
) -> (SMatrix<f64, N, N>, SMatrix<f64, N, 2>, SMatrix<f64, N, 2>) {
    let size = N + 4;
    let mut m = DMatrix::<f64>::zeros(size, size);
    for i in 0..N {
        for j in 0..N {
            m[(i, j)] = a[(i, j)] * h;
        }
        for j in 0..2 {
            m[(i, N + j)] = b[(i, j)] * h;
        }
    }
    for j in 0..2 {
        m[(N + j, N + 2 + j)] = h;
    }
    let e = m.exp();
    let phi = SMatrix::<f64, N, N>::from_fn(|i, j| e[(i, j)]);
    let gamma_a = SMatrix::<f64, N, 2>::from_fn(|i, j| e[(i, N + j)]);
    let gamma_b = SMatrix::<f64, N, 2>::from_fn(|i, j| e[(i, N + 2 + j)]);
    (phi, gamma_a, gamma_b)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::linear::LinearModel;
    use crate::model::passive::PassiveModel;
    use crate::params::Params;
    use crate::scenario::{CommandSignal, RandomRide};
    use crate::simulation::Simulation;

    /// Largest difference of ÿ and u between the exact-hold run at 1 ms and RK4 at 10 µs.
    fn compare<M: Model<N> + CommandPath + LinearTimeInvariant + Clone, const N: usize>(
        model: M,
        drive: Drive,
        platform: PlatformMotion,
        t_from: f64,
    ) -> (f64, f64, f64) {
        let fast = LtiSimulation::new(model.clone(), 1e-3, drive.clone(), platform.clone())
            .expect("τ ≥ h")
            .run_trace(4.0, 1000.0)
            .unwrap();
        let fine = Simulation::new(model, 1e-5, drive, platform)
            .run_trace(4.0, 1000.0)
            .unwrap();
        assert_eq!(fast.samples.len(), fine.samples.len());
        let mut e_ydd: f64 = 0.0;
        let mut e_u: f64 = 0.0;
        let mut peak: f64 = 0.0;
        for (a, b) in fast.samples.iter().zip(&fine.samples) {
            assert!((a.t - b.t).abs() < 1e-9);
            if a.t < t_from {
                continue;
            }
            e_ydd = e_ydd.max((a.ydd - b.ydd).abs());
            e_u = e_u.max((a.u - b.u).abs());
            peak = peak.max(b.ydd.abs());
        }
        (e_ydd, e_u, peak)
    }

    fn ride() -> PlatformMotion {
        PlatformMotion::Sampled(
            RandomRide {
                duration_s: 4.0,
                fade_in_s: 1.0,
                seed: 3,
                ..Default::default()
            }
            .generate(),
        )
    }

    /// On the closed-loop ride the exact hold is within 0.2 % of the peak ÿ and 1 µm of u of
    /// fine RK4.
    fn assert_exact_on_the_ride<M, const N: usize>(model: M)
    where
        M: Model<N> + CommandPath + LinearTimeInvariant + Clone,
    {
        let p = Params::paper();
        let (e_ydd, e_u, peak) = compare(model, Drive::closed_loop(&p), ride(), 0.0);
        assert!(e_ydd < 2e-3 * peak, "ÿ error {e_ydd} of peak {peak}");
        assert!(e_u < 1e-6, "u error {e_u}");
    }

    #[test]
    fn exact_hold_matches_fine_rk4_on_the_closed_loop_ride() {
        assert_exact_on_the_ride(LinearModel::new(&Params::paper()));
    }

    #[test]
    fn exact_hold_matches_fine_rk4_on_an_open_loop_sine_and_the_passive_seat() {
        let p = Params::paper();
        let drive = Drive::OpenLoop(CommandSignal::Sine {
            amplitude_v: 1.1,
            freq_hz: 10.0,
        });
        // The sine test's command jumps to A at t = τ (17.5 ms, between grid points of 1 ms):
        // the hold smears that jump, so compare once its 80 Hz ring has died out.
        let (e_ydd, _, peak) = compare(LinearModel::new(&p), drive, PlatformMotion::Still, 0.5);
        assert!(e_ydd < 5e-3 * peak, "ÿ error {e_ydd} of peak {peak}");
        assert_exact_on_the_ride(PassiveModel::new(&p));
    }

    #[test]
    fn a_delay_shorter_than_the_step_is_refused() {
        let mut p = Params::paper();
        p.linear.tau_s = 5e-4;
        let sim = LtiSimulation::new(
            LinearModel::new(&p),
            1e-3,
            Drive::closed_loop(&p),
            PlatformMotion::Still,
        );
        assert!(sim.is_none());
    }
}
