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
//! edge cases of [`DelayLine::value_at_tap`], from a copy of its newest samples in a ring of
//! the loop's own ([`LocalRing`]: a constant mask, no bounds checks). The paper law's `∫ẍ` is a
//! local too, and its last measurement is set once after the loop instead of stored at every
//! step; a run recorded at every step records without the countdown. The arithmetic is
//! [`Simulation::hold_step`] and [`Simulation::finish_step`]'s, operation for operation (the
//! tests of [`super::specialised`] check every sample bit for bit against [`Run::step`]).

use super::delay::{DelayLine, LocalRing, Tap};
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

/// The loop's changing values between its phases ([`Problem::steps`]).
struct Carry<const N: usize> {
    y: [f64; N],
    valve: f64,
    xdd_now: f64,
    law: PaperLaw,
    run: RunState,
    /// Steps taken (the grid index of the current time).
    n: u64,
    /// Steps until the next sample.
    to_record: u64,
    /// Samples passed to the recorder.
    samples: u64,
    /// Whether the recorder stopped the run.
    stopped: bool,
}

impl<const N: usize> Carry<N> {
    /// A value to leave in a `Carry` while its values are held as locals.
    fn stand_in() -> Self {
        Self {
            y: [0.0; N],
            valve: 0.0,
            xdd_now: 0.0,
            law: PaperLaw::default(),
            run: RunState::new(1.0),
            n: 0,
            to_record: 0,
            samples: 0,
            stopped: false,
        }
    }
}

/// Samples in the loop's own ring of the command's history ([`LocalRing`]): the size of the
/// line's own ring at a 1 ms step (room for the longest delay, 0.1 s, and 8 spare, rounded up
/// to a power of two). A line of a shorter step keeps its own ring.
const LOCAL_RING: usize = 128;

/// The command's history as the loop reads and writes it.
trait CommandLine {
    /// The delayed command at the end of step `n1 - 1` (grid index `n1`), read through `tap`.
    fn read_end(&self, n1: u64, tap: &Tap) -> f64;
    /// Appends the command sent at the current grid time.
    fn push(&mut self, v: f64);
    /// The newest command (what the last [`Self::push`] appended).
    fn newest(&self) -> f64;
}

/// A delay line read at its edge ([`DelayLine::value_at_tap`]).
struct Edge<'a>(&'a mut DelayLine);

impl CommandLine for Edge<'_> {
    #[inline(always)]
    fn read_end(&self, n1: u64, tap: &Tap) -> f64 {
        self.0.value_at_tap(n1, tap)
    }
    #[inline(always)]
    fn push(&mut self, v: f64) {
        self.0.push(v);
    }
    fn newest(&self) -> f64 {
        self.0.last_value()
    }
}

/// A delay line read inside its window ([`DelayLine::value_at_interior_tap`]).
struct Interior<'a>(&'a mut DelayLine);

impl CommandLine for Interior<'_> {
    #[inline(always)]
    fn read_end(&self, n1: u64, tap: &Tap) -> f64 {
        self.0.value_at_interior_tap(n1, tap)
    }
    #[inline(always)]
    fn push(&mut self, v: f64) {
        self.0.push(v);
    }
    fn newest(&self) -> f64 {
        self.0.last_value()
    }
}

impl<const R: usize> CommandLine for LocalRing<R> {
    #[inline(always)]
    fn read_end(&self, n1: u64, tap: &Tap) -> f64 {
        self.value_at_interior_tap(n1, tap)
    }
    #[inline(always)]
    fn push(&mut self, v: f64) {
        LocalRing::push(self, v);
    }
    fn newest(&self) -> f64 {
        LocalRing::newest(self)
    }
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
    ///
    /// The steps whose end read is at the delay line's edge (the first `τ/h` or so) go through
    /// [`DelayLine::value_at_tap`]; the rest read the settled tap inside the window, from a
    /// [`LocalRing`] of the line's newest samples when the line fits one (it is given back to
    /// the line at the end), and recording every step without the countdown when `every` is 1
    /// (the bench's and the usual 1 kHz runs at 1 ms).
    #[inline(always)]
    fn stream(
        &self,
        start: Local<N>,
        t_end: f64,
        every: u64,
        record: &mut impl FnMut(Sample) -> bool,
    ) -> (Local<N>, Result<(u64, bool), SimError>) {
        let Local {
            y,
            valve,
            xdd_now,
            law,
            mut history,
            run,
            mut stats_steps,
        } = start;
        let h = run.h;
        let n = run.steps;
        let n_start = n;
        let every = every.max(1);
        let mut carry = Carry {
            y,
            valve,
            xdd_now,
            law,
            run,
            n,
            to_record: every - n % every,
            samples: 0,
            stopped: false,
        };
        if n == 0 {
            carry.samples += 1;
            let first = self.sample(h, n, &y, valve, self.xdd_at(n), history.last_value());
            carry.stopped = !record(first);
        }
        let n_end = (t_end / h - 1e-9).ceil() as u64;
        // Steps n with n + 1 < interior_from read at the line's edge.
        let edge_end = n_end.min(self.interior_from.saturating_sub(1));
        let mut diverged =
            self.steps::<_, false>(&mut carry, &mut Edge(&mut history), edge_end, every, record);
        if diverged.is_none() && !carry.stopped && carry.n < n_end {
            let from = history.pushed();
            if let Some(mut ring) = history.local_ring::<LOCAL_RING>() {
                diverged = if every == 1 {
                    self.steps::<_, true>(&mut carry, &mut ring, n_end, every, record)
                } else {
                    self.steps::<_, false>(&mut carry, &mut ring, n_end, every, record)
                };
                history.put_back(&ring, from);
            } else {
                diverged = self.steps::<_, false>(
                    &mut carry,
                    &mut Interior(&mut history),
                    n_end,
                    every,
                    record,
                );
            }
        }
        let Carry {
            y,
            valve,
            xdd_now,
            law,
            mut run,
            n,
            samples,
            stopped,
            ..
        } = carry;
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

    /// The steps from `carry` until step `n_stop`, a stop by the recorder or a divergence
    /// (returned), the command's history read and written through `line`; `EVERY_STEP` when
    /// `every` is 1 (a sample after every step, without the countdown).
    #[inline(always)]
    fn steps<L: CommandLine, const EVERY_STEP: bool>(
        &self,
        carry: &mut Carry<N>,
        line: &mut L,
        n_stop: u64,
        every: u64,
        record: &mut impl FnMut(Sample) -> bool,
    ) -> Option<SimError> {
        // The changing values as locals, so that they can live in registers.
        let Carry {
            mut y,
            mut valve,
            mut xdd_now,
            mut law,
            mut run,
            mut n,
            mut to_record,
            mut samples,
            mut stopped,
        } = std::mem::replace(carry, Carry::stand_in());
        let (h, model, half_stroke) = (run.h, self.model, self.model.half_stroke());
        let mut diverged = None;
        let n_enter = n;
        // The law's `∫ẍ`, and the last step's `∫ẍ dt` for its last measurement at the end.
        let mut xd = law.platform_velocity();
        let mut dxd_last = 0.0;
        // On a divergence: the measurement of the step before it, if in this phase.
        let mut last_before_divergence = None;
        while !stopped && n < n_stop {
            // Simulation::hold_step.
            let xdd0 = xdd_now;
            let xdd1 = self.xdd_at(n + 1);
            let v0 = valve;
            let v1 = line.read_end(n + 1, &self.tap);
            let y_prev = y;
            let mut y1 = y;
            self.hold.step(&mut y1, [v0, xdd0], [v1, xdd1]);
            let dxd = 0.5 * h * (xdd0 + xdd1);
            // Simulation::finish_step.
            valve = v1;
            y = y1;
            model.project(&mut y);
            n += 1;
            xdd_now = xdd1;
            // Every state checked without a branch per state (a NaN fails as in `all`).
            let within = y
                .iter()
                .zip(&self.bounds)
                .fold(true, |ok, (v, b)| ok & (v.abs() <= *b));
            if !within && let Err(e) = check_bounds::<M, N>(&y, n as f64 * h, |i| self.bounds[i]) {
                diverged = Some(e);
                // The law was last advanced by the step before (none in this phase when this
                // was its first step).
                if n - 1 > n_enter {
                    last_before_divergence = Some(Measurement {
                        u: model.relative_position(&y_prev),
                        ydd: 0.0,
                        xdd: xdd0,
                        dxd: dxd_last,
                    });
                }
                break;
            }
            let u = model.relative_position(&y);
            // PaperLaw::advance (its measurement is set once, after the loop).
            xd += dxd;
            dxd_last = dxd;
            // `f64::clamp` without its check of the limits' order, done once (v_max > 0).
            let v = law.output_at(u, xd);
            let v = if v < -self.v_max {
                -self.v_max
            } else if v > self.v_max {
                self.v_max
            } else {
                v
            };
            line.push(v);
            // `RunState::track_contact` writes nothing without a contact before or after.
            if u.abs() - half_stroke > 0.0 || run.in_contact() {
                run.steps = n;
                run.track_contact(u, half_stroke);
            }
            if EVERY_STEP {
                samples += 1;
                stopped = !record(self.sample(h, n, &y, valve, xdd_now, v));
            } else {
                to_record -= 1;
                if to_record == 0 {
                    to_record = every;
                    samples += 1;
                    stopped = !record(self.sample(h, n, &y, valve, xdd_now, v));
                }
            }
        }
        // What Controller::advance and Controller::sent left after the last step that
        // advanced the law: its measurement (`u` of the state as it is, ẍ now, unless the
        // run diverged) and the command it pushed.
        let last = if diverged.is_some() {
            last_before_divergence
        } else {
            (n > n_enter).then(|| Measurement {
                u: model.relative_position(&y),
                ydd: 0.0,
                xdd: xdd_now,
                dxd: dxd_last,
            })
        };
        if let Some(last) = last {
            law = law.stepped(xd, last, line.newest());
        }
        *carry = Carry {
            y,
            valve,
            xdd_now,
            law,
            run,
            n,
            to_record,
            samples,
            stopped,
        };
        diverged
    }
}
