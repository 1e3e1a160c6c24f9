//! The stepping loop specialised for each stepper: the stepper (RK4, the exponential method,
//! the exact hold) is chosen once per run instead of once per step, so the loop the compiler
//! builds for each holds only that stepper's code, with the step and its bookkeeping inlined
//! together ([`Run::stream_steps`] of [`Simulation`]).
//!
//! [`Run::step`] of a [`Simulation`] (one step at a time, as an FMU steps) and this loop share
//! [`StepMethod::advance`] and [`Simulation::finish_step`], so both give the same results bit
//! for bit (this module's test checks it on every model and stepper).

use super::delay::{DelayLine, Tap};
use super::hold_paper::stream_hold_paper;
#[cfg(target_arch = "x86_64")]
use super::run::wide_simd;
use super::run::{RunState, check_bounds, stream, stream_portable};
use super::{Method, Run, Sample, SimError, Simulation};
use crate::control::{Controller, Measurement};
use crate::model::{CommandPath, Inputs, Model, ModelKind};
use crate::scenario::PlatformMotion;
use crate::simulation::integrate::{Etd4, Rk4, StepStats};
use crate::simulation::lti::ExactHold;

/// What one step of a stepper gives, before the simulation takes it
/// ([`Simulation::finish_step`]).
pub(crate) struct Advance<const N: usize> {
    /// The state at the step's end.
    pub(crate) y: [f64; N],
    /// Platform acceleration at the step's end [m/s²].
    pub(crate) xdd1: f64,
    /// The controller's `∫ẍ dt` over the step [m/s].
    pub(crate) dxd: f64,
    /// The command at the valve at the step's end [V] (the exact hold reads it).
    pub(crate) valve_end: Option<f64>,
    /// Right-hand-side evaluations of the step.
    pub(crate) evals: u64,
}

/// A stepper advancing a simulation's problem by one step.
pub(crate) trait StepMethod<M: Model<N> + CommandPath, const N: usize> {
    /// One step from the simulation's current state (which it leaves as it is).
    fn advance(&self, sim: &Simulation<M, N>) -> Advance<N>;
}

impl<M: Model<N> + CommandPath, const N: usize> StepMethod<M, N> for Rk4 {
    #[inline(always)]
    fn advance(&self, sim: &Simulation<M, N>) -> Advance<N> {
        sim.stages_step(self)
    }
}

impl<M: Model<N> + CommandPath, const N: usize> StepMethod<M, N> for Etd4<N> {
    #[inline(always)]
    fn advance(&self, sim: &Simulation<M, N>) -> Advance<N> {
        sim.stages_step(self)
    }
}

impl<M: Model<N> + CommandPath, const N: usize> StepMethod<M, N> for ExactHold<N> {
    #[inline(always)]
    fn advance(&self, sim: &Simulation<M, N>) -> Advance<N> {
        sim.hold_step(self)
    }
}

/// A simulation stepped by one stepper held apart from it, as a [`Run`]: what the
/// specialised loop steps.
struct Stepping<'a, M: Model<N>, const N: usize, S> {
    sim: &'a mut Simulation<M, N>,
    stepper: &'a S,
}

impl<M, const N: usize, S> Run for Stepping<'_, M, N, S>
where
    M: Model<N> + CommandPath,
    S: StepMethod<M, N>,
{
    const KIND: ModelKind = M::KIND;

    fn run_state(&self) -> &RunState {
        &self.sim.run
    }

    #[inline(always)]
    fn step(&mut self) -> Result<(), SimError> {
        let advance = self.stepper.advance(self.sim);
        self.sim.finish_step(advance)
    }

    #[inline(always)]
    fn sample(&self) -> Sample {
        self.sim.sample()
    }

    fn stats(&self) -> StepStats {
        self.sim.stats
    }
}

/// The simulation with its stepper taken out for a loop; the stepper goes back when this is
/// dropped, also when the recorder panics.
struct Lent<'a, M: Model<N>, const N: usize> {
    sim: &'a mut Simulation<M, N>,
    method: Method<N>,
}

impl<M: Model<N>, const N: usize> Drop for Lent<'_, M, N> {
    fn drop(&mut self) {
        std::mem::swap(&mut self.sim.method, &mut self.method);
    }
}

impl<M: Model<N> + CommandPath, const N: usize> Simulation<M, N> {
    /// The stepping loop of [`Run::stream_steps`] with the stepper chosen once.
    #[inline(always)]
    pub(crate) fn stream_specialised(
        &mut self,
        t_end: f64,
        every: u64,
        record: impl FnMut(Sample) -> bool,
    ) -> Result<(u64, bool), SimError> {
        // A stand-in while the stepper is lent to the loop (nothing in the loop reads it).
        let stand_in = Method::Rk4(Rk4 { h: self.run.h });
        let method = std::mem::replace(&mut self.method, stand_in);
        let mut lent = Lent { sim: self, method };
        let Lent { sim, method } = &mut lent;
        match method {
            Method::Rk4(m) => stream(&mut Stepping { sim, stepper: m }, t_end, every, record),
            Method::Exponential(m) => {
                stream(&mut Stepping { sim, stepper: &**m }, t_end, every, record)
            }
            Method::ExactHold(m) if HoldRun::fits(&**sim) => {
                stream_hold(&mut **sim, &**m, t_end, every, record)
            }
            Method::ExactHold(m) => {
                stream(&mut Stepping { sim, stepper: &**m }, t_end, every, record)
            }
        }
    }
}

/// An exact-hold run whose changing state (the model's state, the clock, the controller, the
/// delay line, the command at the valve) is held by the loop itself while it steps, the
/// simulation (the problem: model, platform, step, taps) only read: the usual run of the
/// linear model G(s) (closed loop with a settled tap, [`Simulation::settled_valve`]).
///
/// Stepped in place, the simulation's fields were stored and loaded at every step, since the
/// recorder's writes might have reached them: about 15 stores a step beside the sample's 14.
/// Held here, in a value the loop owns, they can stay in registers (measured: 14.0–15.2 ns a
/// step of G(s) against 15.7–16.9 in the general loop, README "Speed"). The step is [`Simulation::hold_step`] followed by
/// [`Simulation::finish_step`] for these runs, operation for operation (the test below checks
/// every sample bit for bit against [`Run::step`]).
struct HoldRun<'a, M: Model<N>, const N: usize> {
    /// The problem (its own changing fields are stale while this runs).
    sim: &'a Simulation<M, N>,
    hold: &'a ExactHold<N>,
    /// The valve's read of the delay line at a step's end (`None` without a command, which
    /// [`Self::fits`] leaves to the general loop).
    tap: Option<Tap>,
    y: [f64; N],
    run: RunState,
    controller: Option<Controller>,
    history: DelayLine,
    /// The command at the valve at the current grid time [V] (0 without a valve).
    valve: f64,
    /// Platform acceleration at the current grid time [m/s²].
    xdd_now: f64,
    stats: StepStats,
}

impl<'a, M: Model<N> + CommandPath, const N: usize> HoldRun<'a, M, N> {
    /// Whether `sim`'s exact hold runs as a [`HoldRun`]: a model with a command in closed loop
    /// whose command at the valve is kept between steps. (The passive seat, without a command,
    /// was measured slower in this loop than in the general one: 11–12 ns a step against 8.)
    fn fits(sim: &Simulation<M, N>) -> bool {
        M::KIND.has_command() && sim.valve_now.is_some() && sim.controller.is_some()
    }

    /// The run of `sim` (for which [`Self::fits`]) with copies of its changing state.
    fn new(sim: &'a Simulation<M, N>, hold: &'a ExactHold<N>) -> Self {
        let tap = match (M::KIND.has_command(), &sim.taps) {
            (true, Some([tap, ..])) => Some(*tap),
            _ => None,
        };
        Self {
            sim,
            hold,
            tap,
            y: sim.y,
            run: sim.run.clone(),
            controller: sim.controller.clone(),
            history: sim.history.clone(),
            valve: sim.valve_now.unwrap_or(0.0),
            xdd_now: sim.xdd_now,
            stats: sim.stats,
        }
    }

    /// Inputs at the current time ([`Simulation::inputs_now`]).
    #[inline(always)]
    fn inputs_now(&self) -> Inputs {
        Inputs {
            v_valve: self.valve,
            xdd: self.xdd_now,
        }
    }
}

impl<M: Model<N> + CommandPath, const N: usize> Run for HoldRun<'_, M, N> {
    const KIND: ModelKind = M::KIND;

    fn run_state(&self) -> &RunState {
        &self.run
    }

    #[inline(always)]
    fn step(&mut self) -> Result<(), SimError> {
        let sim = self.sim;
        let (h, n) = (sim.run.h, self.run.steps);
        // Simulation::hold_step.
        let xdd0 = self.xdd_now;
        let xdd1 = sim.platform.xdd_at_grid(n + 1, h, sim.stride);
        let v0 = self.valve;
        let v1 = match &self.tap {
            Some(tap) => self.history.value_at_tap(n + 1, tap),
            None => 0.0,
        };
        let mut y = self.y;
        self.hold.step(&mut y, [v0, xdd0], [v1, xdd1]);
        let dxd = 0.5 * h * (xdd0 + xdd1);
        // Simulation::finish_step.
        self.valve = v1;
        self.y = y;
        sim.model.project(&mut self.y);
        self.stats.steps += 1;
        self.run.steps += 1;
        self.xdd_now = xdd1;
        if !self.y.iter().zip(&sim.bounds).all(|(v, b)| v.abs() <= *b) {
            check_bounds::<M, N>(&self.y, self.run.time(), |i| sim.bounds[i])?;
        }
        let u = sim.model.relative_position(&self.y);
        let inputs = self.inputs_now();
        if M::KIND.has_command()
            && let Some(c) = self.controller.as_mut()
        {
            let ydd = if c.needs_body_acceleration() {
                sim.model.outputs(&self.y, &inputs).ydd
            } else {
                0.0
            };
            c.advance(&Measurement {
                u,
                ydd,
                xdd: self.xdd_now,
                dxd,
            });
            let v = sim.saturate(c.output_with(u, 0.0));
            c.sent(v);
            self.history.push(v);
        }
        self.run.track_contact(u, sim.model.half_stroke());
        Ok(())
    }

    #[inline(always)]
    fn sample(&self) -> Sample {
        let sim = self.sim;
        let n = self.run.steps;
        let v_in = if M::KIND.has_command() {
            self.history.last_value()
        } else {
            f64::NAN
        };
        let at = |p| {
            let outputs = sim.model.outputs(&self.y, &self.inputs_now());
            Sample::assemble(self.run.time(), p, &outputs, v_in, sim.model.half_stroke())
        };
        // As in `Run::sample` of the simulation: the sample assembled in the branch that reads
        // a record on the grid.
        match (&sim.platform, sim.stride) {
            (PlatformMotion::Sampled(s), Some(k)) => at(s.at_sample(n as usize * k)),
            _ => at(sim.platform.at_grid(n, sim.run.h, sim.stride)),
        }
    }

    fn stats(&self) -> StepStats {
        self.stats
    }
}

/// The stepping loop of [`Run::stream_steps`] for a [`HoldRun`] of `sim`: its changing state
/// is copied into the loop and back after it (also after a divergence, as a step leaves it).
#[inline(always)]
fn stream_hold<M: Model<N> + CommandPath, const N: usize>(
    sim: &mut Simulation<M, N>,
    hold: &ExactHold<N>,
    t_end: f64,
    every: u64,
    record: impl FnMut(Sample) -> bool,
) -> Result<(u64, bool), SimError> {
    #[cfg(target_arch = "x86_64")]
    if wide_simd() {
        // SAFETY: the processor has AVX (checked by `wide_simd`).
        return unsafe { stream_hold_avx(sim, hold, t_end, every, record) };
    }
    stream_hold_portable(sim, hold, t_end, every, record)
}

/// [`stream_hold_portable`] compiled for AVX (see [`super::run::stream`]).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
fn stream_hold_avx<M: Model<N> + CommandPath, const N: usize>(
    sim: &mut Simulation<M, N>,
    hold: &ExactHold<N>,
    t_end: f64,
    every: u64,
    record: impl FnMut(Sample) -> bool,
) -> Result<(u64, bool), SimError> {
    stream_hold_portable(sim, hold, t_end, every, record)
}

/// The loop of [`stream_hold`], for the baseline instruction set. The [`HoldRun`] is a local
/// of this function, so that its fields can live in registers.
#[inline(always)]
fn stream_hold_portable<M: Model<N> + CommandPath, const N: usize>(
    sim: &mut Simulation<M, N>,
    hold: &ExactHold<N>,
    t_end: f64,
    every: u64,
    mut record: impl FnMut(Sample) -> bool,
) -> Result<(u64, bool), SimError> {
    if let Some(result) = stream_hold_paper(sim, hold, t_end, every, &mut record) {
        return result;
    }
    let mut run = HoldRun::new(sim, hold);
    let result = stream_portable(&mut run, t_end, every, record);
    let HoldRun {
        y,
        run,
        controller,
        history,
        valve,
        xdd_now,
        stats,
        ..
    } = run;
    sim.y = y;
    sim.run = run;
    sim.controller = controller;
    sim.history = history;
    if sim.valve_now.is_some() {
        sim.valve_now = Some(valve);
    }
    sim.xdd_now = xdd_now;
    sim.stats = stats;
    result
}

#[cfg(test)]
mod tests {
    use crate::model::linear::LinearModel;
    use crate::model::passive::PassiveModel;
    use crate::params::{ControllerKind, Integrator, Params};
    use crate::scenario::{CommandSignal, PlatformMotion, RandomRide};
    use crate::simulation::{CommandPath, Drive, Run, Sample, Simulation};

    /// Every field's bits (NaN-safe, and −0 told from 0).
    fn bits(s: &Sample) -> [u64; 14] {
        [
            s.t, s.x, s.xd, s.xdd, s.u, s.du, s.ydd, s.v_in, s.xv, s.p1, s.p2, s.q1, s.q2,
        ]
        .map(f64::to_bits)
        .into_iter()
        .chain([s.contact as u64])
        .collect::<Vec<_>>()
        .try_into()
        .expect("14 fields")
    }

    /// The samples of `sim` to `t_end` [s] every `every` steps, stepped one call of
    /// [`Run::step`] at a time (the stepper dispatched at every step, as an FMU steps), and the
    /// simulation at the end.
    fn one_step_at_a_time<M, const N: usize>(
        mut sim: Simulation<M, N>,
        t_end: f64,
        every: u64,
    ) -> (Vec<Sample>, Simulation<M, N>)
    where
        M: crate::model::Model<N> + CommandPath,
    {
        let mut out = vec![sim.sample()];
        let n_end = (t_end / sim.step_size() - 1e-9).ceil() as u64;
        while sim.run_state().steps() < n_end {
            sim.step().expect("no divergence");
            if sim.run_state().steps().is_multiple_of(every) {
                out.push(sim.sample());
            }
        }
        (out, sim)
    }

    /// The specialised loop, run in two calls (the second goes on from the state the first
    /// left), gives the samples of [`one_step_at_a_time`] bit for bit and leaves the same
    /// state, from which the next step is the same too.
    fn assert_same_runs<M, const N: usize>(sim: Simulation<M, N>, every: u64)
    where
        M: crate::model::Model<N> + CommandPath,
    {
        let t_end = 1.5;
        let mut fast = sim.clone();
        let mut specialised = Vec::new();
        for t in [0.6, t_end] {
            fast.run_until(t, every, |s| specialised.push(s))
                .expect("no divergence");
        }
        let (reference, mut slow) = one_step_at_a_time(sim, t_end, every);
        assert_eq!(specialised.len(), reference.len());
        for (a, b) in specialised.iter().zip(&reference) {
            assert_eq!(bits(a), bits(b), "at t = {}", b.t);
        }
        assert_eq!(fast.stats(), slow.stats());
        assert_eq!(fast.snapshot(), slow.snapshot());
        assert_eq!(fast.contacts(), slow.contacts());
        fast.step().expect("no divergence");
        slow.step().expect("no divergence");
        assert_eq!(bits(&fast.sample()), bits(&slow.sample()));
    }

    fn ride() -> PlatformMotion {
        PlatformMotion::Sampled(
            RandomRide {
                duration_s: 1.5,
                fade_in_s: 0.3,
                seed: 5,
                ..Default::default()
            }
            .generate(),
        )
    }

    #[test]
    fn the_specialised_loop_steps_bit_for_bit_as_the_step_by_step_dispatch() {
        let p = Params::paper();
        let closed = Drive::closed_loop(&p);
        let sine = Drive::OpenLoop(CommandSignal::Sine {
            amplitude_v: 1.1,
            freq_hz: 10.0,
        });
        // The twin with both stage methods, closed loop on the ride.
        let twin = Simulation::twin(&p, 5e-4, closed.clone(), ride());
        assert!(twin.is_exponential());
        assert_same_runs(twin, 2);
        let mut rk4 = p;
        rk4.numerics.integrator = Integrator::Rk4;
        assert_same_runs(Simulation::twin(&rk4, 1e-4, closed.clone(), ride()), 10);
        // The exact hold of both linear models, closed and open loop.
        let hold = |drive: &Drive| {
            Simulation::exact_hold(LinearModel::new(&p), 1e-3, drive.clone(), ride())
                .expect("τ ≥ h")
        };
        assert_same_runs(hold(&closed), 1);
        assert_same_runs(hold(&sine), 1);
        let passive = Simulation::exact_hold(PassiveModel::new(&p), 1e-3, closed.clone(), ride())
            .expect("no command");
        assert_same_runs(passive.clone(), 1);
        assert_same_runs(passive, 3);
        // The exact hold's own loop with every controller structure (the skyhook reads the body
        // acceleration, the Smith predictor its model's delay line), recording every 2 steps.
        for kind in ControllerKind::ALL {
            let mut q = p;
            q.controller.kind = kind;
            let drive = Drive::closed_loop(&q);
            let sim =
                Simulation::exact_hold(LinearModel::new(&q), 1e-3, drive, ride()).expect("τ ≥ h");
            assert_same_runs(sim, 2);
        }
        // End-stop overruns opening and closing (a stroke far shorter than the ride's), which
        // the paper controller's own loop tracks as the general one does.
        let mut tight = p;
        tight.plant.cylinder.stroke_m = 2e-5;
        let sim = Simulation::exact_hold(LinearModel::new(&tight), 1e-3, closed.clone(), ride())
            .expect("τ ≥ h");
        let mut probe = sim.clone();
        probe.run_until(1.5, 1, |_| {}).expect("no divergence");
        assert!(
            probe.contacts().len() > 2,
            "{} overruns",
            probe.contacts().len()
        );
        assert_same_runs(sim, 1);
        // A delay of between one and two steps: its tap is not settled, so the general loop.
        let mut near = p;
        near.linear.tau_s = 1.5e-3;
        let sim = Simulation::exact_hold(LinearModel::new(&near), 1e-3, closed.clone(), ride())
            .expect("τ ≥ h");
        assert_same_runs(sim, 1);
        // RK4 on a linear model (a delay shorter than the step).
        let mut short = p;
        short.linear.tau_s = 5e-4;
        assert_same_runs(
            Simulation::new(LinearModel::new(&short), 2.5e-4, closed, ride()),
            4,
        );
    }

    #[test]
    fn the_exact_hold_loop_stops_on_a_divergence_as_one_step_at_a_time_stops() {
        // Position feedback of the wrong sign pushes the seat away until u leaves its bound.
        let mut p = Params::paper();
        p.controller.kp_v_per_m = 2000.0;
        let sim =
            Simulation::exact_hold(LinearModel::new(&p), 1e-3, Drive::closed_loop(&p), ride())
                .expect("τ ≥ h");
        let mut fast = sim.clone();
        let fast_err = fast
            .run_until(1.5, 1, |_| {})
            .expect_err("a pushing position loop diverges");
        let mut slow = sim;
        let slow_err = loop {
            assert!(slow.time() < 1.5, "no divergence one step at a time");
            if let Err(e) = slow.step() {
                break e;
            }
        };
        assert_eq!(fast_err, slow_err);
        assert_eq!(fast.snapshot(), slow.snapshot());
        assert_eq!(fast.contacts(), slow.contacts());
    }
}
