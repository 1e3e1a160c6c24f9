//! The stepping loop specialised for each stepper: the stepper (RK4, the exponential method,
//! the exact hold) is chosen once per run instead of once per step, so the loop the compiler
//! builds for each holds only that stepper's code, with the step and its bookkeeping inlined
//! together ([`Run::stream_steps`] of [`Simulation`]).
//!
//! [`Run::step`] of a [`Simulation`] (one step at a time, as an FMU steps) and this loop share
//! [`StepMethod::advance`] and [`Simulation::finish_step`], so both give the same results bit
//! for bit (this module's test checks it on every model and stepper).

use super::run::{RunState, stream};
use super::{Method, Run, Sample, SimError, Simulation};
use crate::model::{CommandPath, Model, ModelKind};
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
            Method::ExactHold(m) => {
                stream(&mut Stepping { sim, stepper: &**m }, t_end, every, record)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::model::linear::LinearModel;
    use crate::model::passive::PassiveModel;
    use crate::params::{Integrator, Params};
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
    /// [`Run::step`] at a time (the stepper dispatched at every step, as an FMU steps).
    fn one_step_at_a_time<M, const N: usize>(
        mut sim: Simulation<M, N>,
        t_end: f64,
        every: u64,
    ) -> (Vec<Sample>, crate::simulation::integrate::StepStats)
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
        (out, sim.stats())
    }

    fn assert_same_runs<M, const N: usize>(sim: Simulation<M, N>, every: u64)
    where
        M: crate::model::Model<N> + CommandPath,
    {
        let t_end = 1.5;
        let mut fast = sim.clone();
        let mut specialised = Vec::new();
        fast.run_until(t_end, every, |s| specialised.push(s))
            .expect("no divergence");
        let (reference, stats) = one_step_at_a_time(sim, t_end, every);
        assert_eq!(specialised.len(), reference.len());
        for (a, b) in specialised.iter().zip(&reference) {
            assert_eq!(bits(a), bits(b), "at t = {}", b.t);
        }
        assert_eq!(fast.stats(), stats);
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
        assert_same_runs(passive, 1);
        // RK4 on a linear model (a delay shorter than the step).
        let mut short = p;
        short.linear.tau_s = 5e-4;
        assert_same_runs(
            Simulation::new(LinearModel::new(&short), 2.5e-4, closed, ride()),
            4,
        );
    }
}
