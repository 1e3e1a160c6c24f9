//! The exact hold's stepping loop for its most common run, written out with its changing
//! state in local variables: a linear model in closed loop with the paper's controller, a
//! settled delay tap, on a record that the grid lands on (the bench's and the Table 1 sweep's
//! runs of G(s)). Every other exact-hold run keeps the loop of [`super::specialised`].
//!
//! The [`HoldRun`](super::specialised) loop held the same state in a value of its own, but the
//! compiler kept that value in memory: the state `y` went through the stack at every step
//! (a store and a load on the recurrence `y ← Φ·y + …`), and so did the delay line's length,
//! the controller's `∫ẍ` and the clock. Here each is a local that nothing takes the address
//! of, and the delay line is read, once its window is full, by four masked loads without the
//! edge cases of [`DelayLine::value_at_tap`]. The arithmetic is [`Simulation::hold_step`] and
//! [`Simulation::finish_step`]'s, operation for operation (the tests of
//! [`super::specialised`] check every sample bit for bit against [`Run::step`]).

use super::delay::{DelayLine, Tap};
use super::run::{RunState, check_bounds};
use super::{Sample, SimError, Simulation};
use crate::control::{Measurement, PaperLaw};
use crate::model::{CommandPath, Inputs, Model};
use crate::scenario::{PlatformMotion, PlatformSample};
use crate::simulation::lti::ExactHold;
#[cfg(doc)]
use {super::Run, crate::scenario::SampledMotion};

/// The loop of [`Run::stream_steps`] for an exact-hold run of `sim` with the paper controller
/// and a settled tap on a record the grid lands on; `None`, with `sim` untouched, for any
/// other run. `sim` must be one that `HoldRun::fits` in [`super::specialised`] (closed loop,
/// the command at the valve kept between steps).
#[inline(always)]
pub(super) fn stream_hold_paper<M: Model<N> + CommandPath, const N: usize>(
    sim: &mut Simulation<M, N>,
    hold: &ExactHold<N>,
    t_end: f64,
    every: u64,
    record: &mut impl FnMut(Sample) -> bool,
) -> Option<Result<(u64, bool), SimError>> {
    let law = sim.controller.as_ref()?.paper_law()?;
    let (PlatformMotion::Sampled(motion), Some(stride)) = (&sim.platform, sim.stride) else {
        return None;
    };
    if motion.channels().2.is_empty() {
        return None;
    }
    let tap = *sim.taps.as_ref()?.first()?;
    let valve = sim.valve_now?;
    let interior_from = sim.history.interior_from(&tap)?;
    // One sample pushed per step since t = 0 (what a run from `Simulation::new` keeps).
    if sim.history.pushed() != sim.run.steps + 1 {
        return None;
    }
    let h = sim.run.h;
    let start = Local {
        y: sim.y,
        valve,
        xdd_now: sim.xdd_now,
        law,
        history: sim.history.take(),
        run: std::mem::replace(&mut sim.run, RunState::new(h)),
        stats_steps: sim.stats.steps,
    };
    let (x, xd, xdd) = motion.channels();
    let problem = Problem {
        model: &sim.model,
        hold,
        x,
        xd,
        xdd,
        stride,
        interior_from,
        tap,
        bounds: sim.bounds,
        v_max: sim.v_max,
    };
    let (end, result) = problem.stream(start, t_end, every, record);
    sim.y = end.y;
    sim.valve_now = Some(end.valve);
    sim.xdd_now = end.xdd_now;
    if let Some(c) = sim.controller.as_mut() {
        c.set_paper_law(&end.law);
    }
    sim.history = end.history;
    sim.run = end.run;
    sim.stats.steps = end.stats_steps;
    Some(result)
}

/// What the loop changes, moved out of the simulation for the loop and back after it.
struct Local<const N: usize> {
    y: [f64; N],
    /// The command at the valve at the current grid time [V].
    valve: f64,
    /// Platform acceleration at the current grid time [m/s²].
    xdd_now: f64,
    law: PaperLaw,
    history: DelayLine,
    run: RunState,
    stats_steps: u64,
}

/// What the loop only reads.
struct Problem<'a, M, const N: usize> {
    model: &'a M,
    hold: &'a ExactHold<N>,
    /// The record's `x` [m], `ẋ` [m/s] and `ẍ` [m/s²] (`ẍ` not empty).
    x: &'a [f64],
    xd: &'a [f64],
    xdd: &'a [f64],
    /// Record samples per step.
    stride: usize,
    /// The grid index from which the tap reads inside the delay line's window.
    interior_from: u64,
    tap: Tap,
    bounds: [f64; N],
    /// Command limit [V].
    v_max: f64,
}

impl<M: Model<N> + CommandPath, const N: usize> Problem<'_, M, N> {
    /// The record's sample index at grid index `n` ([`SampledMotion::at_sample`]'s, held at
    /// the last sample after the end).
    #[inline(always)]
    fn index(&self, n: u64) -> usize {
        (n as usize * self.stride).min(self.xdd.len() - 1)
    }

    /// [`SampledMotion::xdd_at_sample`] at grid index `n` [m/s²].
    #[inline(always)]
    fn xdd_at(&self, n: u64) -> f64 {
        self.xdd.get(self.index(n)).copied().unwrap_or(0.0)
    }

    /// `HoldRun::sample`: the sample at grid index `n` for the state `y`, the command at the
    /// valve `valve` [V], the platform acceleration there `xdd` [m/s²] (the record's, as
    /// [`Self::xdd_at`] reads it) and the command last sent `v_in` [V].
    #[inline(always)]
    fn sample(&self, h: f64, n: u64, y: &[f64; N], valve: f64, xdd: f64, v_in: f64) -> Sample {
        let outputs = self.model.outputs(
            y,
            &Inputs {
                v_valve: valve,
                xdd,
            },
        );
        let i = self.index(n);
        let p = PlatformSample {
            x: self.x.get(i).copied().unwrap_or(0.0),
            xd: self.xd.get(i).copied().unwrap_or(0.0),
            xdd,
        };
        // `n as f64` through i64: one conversion instruction instead of the unsigned
        // sequence, the same value for any step count below 2⁶³.
        let t = (n as i64) as f64 * h;
        Sample::assemble(t, p, &outputs, v_in, self.model.half_stroke())
    }

    /// [`super::run::stream_portable`]'s countdown with the step and the sample of `HoldRun`
    /// written out, from the state `start` (returned as the loop leaves it, also after a
    /// divergence, as a step leaves it).
    #[inline(always)]
    fn stream(
        &self,
        start: Local<N>,
        t_end: f64,
        every: u64,
        record: &mut impl FnMut(Sample) -> bool,
    ) -> (Local<N>, Result<(u64, bool), SimError>) {
        let Local {
            mut y,
            mut valve,
            mut xdd_now,
            mut law,
            mut history,
            mut run,
            mut stats_steps,
        } = start;
        let (h, model, half_stroke) = (run.h, self.model, self.model.half_stroke());
        let mut n = run.steps;
        let n_start = n;
        let every = every.max(1);
        let mut samples = 0u64;
        let mut stopped = false;
        let mut diverged = None;
        if n == 0 {
            samples += 1;
            let first = self.sample(h, n, &y, valve, self.xdd_at(n), history.last_value());
            stopped = !record(first);
        }
        let n_end = (t_end / h - 1e-9).ceil() as u64;
        let mut to_record = every - n % every;
        while !stopped && n < n_end {
            // Simulation::hold_step.
            let xdd0 = xdd_now;
            let xdd1 = self.xdd_at(n + 1);
            let v0 = valve;
            let v1 = if n + 1 >= self.interior_from {
                history.value_at_interior_tap(n + 1, &self.tap)
            } else {
                history.value_at_tap(n + 1, &self.tap)
            };
            let mut y1 = y;
            self.hold.step(&mut y1, [v0, xdd0], [v1, xdd1]);
            let dxd = 0.5 * h * (xdd0 + xdd1);
            // Simulation::finish_step.
            valve = v1;
            y = y1;
            model.project(&mut y);
            n += 1;
            xdd_now = xdd1;
            if !y.iter().zip(&self.bounds).all(|(v, b)| v.abs() <= *b)
                && let Err(e) = check_bounds::<M, N>(&y, n as f64 * h, |i| self.bounds[i])
            {
                diverged = Some(e);
                break;
            }
            let u = model.relative_position(&y);
            law.advance(Measurement {
                u,
                ydd: 0.0,
                xdd: xdd_now,
                dxd,
            });
            // `f64::clamp` without its check of the limits' order, done once (v_max > 0).
            let v = law.output(u);
            let v = if v < -self.v_max {
                -self.v_max
            } else if v > self.v_max {
                self.v_max
            } else {
                v
            };
            law.sent(v);
            history.push(v);
            // `RunState::track_contact` writes nothing without a contact before or after.
            if u.abs() - half_stroke > 0.0 || run.in_contact() {
                run.steps = n;
                run.track_contact(u, half_stroke);
            }
            to_record -= 1;
            if to_record == 0 {
                to_record = every;
                samples += 1;
                stopped = !record(self.sample(h, n, &y, valve, xdd_now, v));
            }
        }
        run.steps = n;
        stats_steps += n - n_start;
        let end = Local {
            y,
            valve,
            xdd_now,
            law,
            history,
            run,
            stats_steps,
        };
        let result = match diverged {
            Some(e) => Err(e),
            None => Ok((samples, stopped)),
        };
        (end, result)
    }
}
