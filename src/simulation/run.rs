//! What every run shares, however it steps: the grid and its clock, the end-stop contacts,
//! the divergence check, and the stepping loop that records samples into a trace or passes
//! them on as they are made. [`Run`] is implemented by [`Simulation`](super::Simulation),
//! whatever its stepper (RK4, the exponential integrator, the exact hold): it gives its step
//! and its sample, the rest is written once, here.

use super::{ContactEvent, RunSummary, Sample, SimError, Trace, record_every, sample_count};
use crate::model::{Model, ModelKind};
use crate::simulation::integrate::StepStats;

/// What every run keeps besides its model's state: the grid step, the steps taken and the
/// end-stop contacts met so far.
#[derive(Debug, Clone)]
pub struct RunState {
    /// Internal step [s].
    pub(crate) h: f64,
    /// Steps taken.
    pub(crate) steps: u64,
    contacts: Vec<ContactEvent>,
    in_contact: bool,
}

impl RunState {
    /// A run at t = 0 on a grid of step `h` [s].
    pub(crate) fn new(h: f64) -> Self {
        Self {
            h,
            steps: 0,
            contacts: Vec::new(),
            in_contact: false,
        }
    }

    /// Current time \[s\]: the steps taken times the step.
    #[inline(always)]
    pub fn time(&self) -> f64 {
        self.steps as f64 * self.h
    }

    /// Internal step \[s\].
    pub fn step_size(&self) -> f64 {
        self.h
    }

    /// Steps taken.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// End-stop contacts (twin) or stroke overruns so far.
    pub fn contacts(&self) -> &[ContactEvent] {
        &self.contacts
    }

    /// Whether the body is in an end-stop contact (an event still open).
    #[inline(always)]
    pub(crate) fn in_contact(&self) -> bool {
        self.in_contact
    }

    /// Opens, extends or closes the end-stop contact event at the current time for stroke
    /// `u` [m]. Called every step: the usual step (no contact before or after) writes nothing.
    #[inline(always)]
    pub(crate) fn track_contact(&mut self, u: f64, half_stroke: f64) {
        let pen = u.abs() - half_stroke;
        if pen > 0.0 {
            let t = self.time();
            if !self.in_contact {
                self.contacts.push(ContactEvent {
                    t_start: t,
                    t_end: t,
                    side: if u > 0.0 { 1 } else { -1 },
                    max_penetration_m: pen,
                });
                self.in_contact = true;
            } else if let Some(c) = self.contacts.last_mut() {
                c.t_end = t;
                c.max_penetration_m = c.max_penetration_m.max(pen);
            }
        } else if self.in_contact {
            self.in_contact = false;
        }
    }
}

/// What of a [`RunState`] changes while stepping, without the closed contacts (the run's
/// record, not its state): the steps taken and the contact still open, which the next steps
/// may extend ([`RunState::snapshot`]).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RunStateSnapshot {
    /// Steps taken.
    pub steps: u64,
    /// The end-stop contact the body is in, if any.
    pub open_contact: Option<ContactEvent>,
}

impl RunState {
    /// The steps taken and the open contact.
    pub fn snapshot(&self) -> RunStateSnapshot {
        RunStateSnapshot {
            steps: self.steps,
            open_contact: self.contacts.last().copied().filter(|_| self.in_contact),
        }
    }

    /// Takes the steps and open contact of a snapshot (the closed contacts are forgotten).
    pub(crate) fn restore(&mut self, s: &RunStateSnapshot) {
        self.steps = s.steps;
        self.in_contact = s.open_contact.is_some();
        self.contacts = s.open_contact.into_iter().collect();
    }
}

/// The first state of `y` that is not finite or beyond its bound `bound(i)`, as the divergence
/// of model `M` at time `t`.
#[inline(always)]
pub(crate) fn check_bounds<M: Model<N>, const N: usize>(
    y: &[f64; N],
    t: f64,
    bound: impl Fn(usize) -> f64,
) -> Result<(), SimError> {
    for (i, v) in y.iter().enumerate() {
        let bound = bound(i);
        if !v.is_finite() || v.abs() > bound {
            return Err(SimError::Diverged {
                model: M::KIND.name(),
                t,
                state: M::STATE_NAMES[i],
                value: *v,
                bound,
            });
        }
    }
    Ok(())
}

/// A run advanced on a fixed grid and sampled. An implementation gives its step, its sample
/// and its [`RunState`]; the clock, the contacts, the stepping loop, the traces and the
/// summaries come from here.
pub trait Run {
    /// Which model runs.
    const KIND: ModelKind;

    /// The grid, the steps taken and the contacts so far.
    fn run_state(&self) -> &RunState;

    /// Advances one internal step.
    fn step(&mut self) -> Result<(), SimError>;

    /// The current instant as a recorded sample.
    fn sample(&self) -> Sample;

    /// Integrator work so far.
    fn stats(&self) -> StepStats;

    /// Advances one step whose end is recorded and returns that sample (a run may share work
    /// between the two).
    #[inline(always)]
    fn step_sampled(&mut self) -> Result<Sample, SimError> {
        self.step()?;
        Ok(self.sample())
    }

    /// Current time \[s\].
    fn time(&self) -> f64 {
        self.run_state().time()
    }

    /// Internal step \[s\].
    fn step_size(&self) -> f64 {
        self.run_state().step_size()
    }

    /// Contacts so far.
    fn contacts(&self) -> &[ContactEvent] {
        self.run_state().contacts()
    }

    /// The stepping loop: steps until `t_end` \[s\], passing a sample to `record` every `every`
    /// steps (and at the start when no step has been taken yet), and stops early when `record`
    /// returns `false`; returns the samples passed and whether it stopped. A run may override
    /// it with a loop of its own (a [`Simulation`](super::Simulation) chooses its stepper once,
    /// not at every step) that gives the same samples.
    #[inline(always)]
    fn stream_steps(
        &mut self,
        t_end: f64,
        every: u64,
        record: impl FnMut(Sample) -> bool,
    ) -> Result<(u64, bool), SimError> {
        stream(self, t_end, every, record)
    }

    /// Runs until `t_end` \[s\], calling `record` every `every` steps (and at the start if
    /// t = 0).
    fn run_until(
        &mut self,
        t_end: f64,
        every: u64,
        mut record: impl FnMut(Sample),
    ) -> Result<(), SimError> {
        self.stream_steps(t_end, every, |s| {
            record(s);
            true
        })
        .map(|_| ())
    }

    /// Runs from the current state to `t_end` \[s\] and returns the trace recorded at
    /// `rate_hz` (a whole number of steps per sample, [`record_every`]).
    fn run_trace(&mut self, t_end: f64, rate_hz: f64) -> Result<Trace, SimError> {
        let mut samples = trace_buffer(t_end, rate_hz, self.step_size());
        let summary = self.run_streaming(t_end, rate_hz, |s| {
            samples.push(s);
            true
        })?;
        Ok(summary.into_trace(samples))
    }

    /// Runs from the current state to `t_end` \[s\], passing each sample at `rate_hz` to
    /// `record` as it is made (the samples of [`Self::run_trace`], without keeping them:
    /// memory does not grow with the duration). `record` returns `false` to stop the run
    /// early.
    fn run_streaming(
        &mut self,
        t_end: f64,
        rate_hz: f64,
        record: impl FnMut(Sample) -> bool,
    ) -> Result<RunSummary, SimError> {
        let every = record_every(self.step_size(), rate_hz);
        let (samples, stopped) = self.stream_steps(t_end, every, record)?;
        Ok(RunSummary {
            model: Self::KIND,
            samples,
            stopped,
            contacts: self.contacts().to_vec(),
            stats: self.stats(),
        })
    }
}

/// An empty sample buffer sized for a run to `t_end` [s] at `rate_hz` with step `h` [s].
pub(crate) fn trace_buffer(t_end: f64, rate_hz: f64, h: f64) -> Vec<Sample> {
    let n = sample_count(t_end, rate_hz, h);
    Vec::with_capacity(usize::try_from(n).unwrap_or(0).min(1 << 24))
}

/// The stepping loop of every run: steps `run` until `t_end` [s], passing a sample to
/// `record` every `every` steps (and at the start when no step has been taken yet), and stops
/// early when `record` returns `false`. Returns the samples passed and whether it stopped.
///
/// On x86-64 processors with AVX (checked at run time, so the binary stays portable) the loop,
/// with the step and the integrator inlined into it, is compiled a second time for AVX: the
/// integrator's matrix–vector products then run four lanes wide instead of SSE2's two. Without
/// fused multiply–add the arithmetic is the same operations in the same order, so both forms
/// give the same results bit for bit (`tests/it/engine.rs` checks a run against the SSE2 form).
#[inline(always)]
pub(super) fn stream<R: Run + ?Sized>(
    run: &mut R,
    t_end: f64,
    every: u64,
    record: impl FnMut(Sample) -> bool,
) -> Result<(u64, bool), SimError> {
    #[cfg(target_arch = "x86_64")]
    if wide_simd() {
        // SAFETY: the processor has AVX (checked by `wide_simd`).
        return unsafe { stream_avx(run, t_end, every, record) };
    }
    stream_portable(run, t_end, every, record)
}

/// Whether runs use the AVX form of the stepping loop: the processor has AVX and the
/// environment variable `SEAT_TWIN_PORTABLE_SIMD` is not set (set it to compare with the
/// SSE2 form).
#[cfg(target_arch = "x86_64")]
pub fn wide_simd() -> bool {
    use std::sync::OnceLock;
    static WIDE: OnceLock<bool> = OnceLock::new();
    *WIDE.get_or_init(|| {
        std::is_x86_feature_detected!("avx")
            && std::env::var_os("SEAT_TWIN_PORTABLE_SIMD").is_none()
    })
}

/// Whether runs use a wider SIMD form of the stepping loop (never, off x86-64).
#[cfg(not(target_arch = "x86_64"))]
pub fn wide_simd() -> bool {
    false
}

/// [`stream_portable`] compiled for AVX.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
fn stream_avx<R: Run + ?Sized>(
    run: &mut R,
    t_end: f64,
    every: u64,
    record: impl FnMut(Sample) -> bool,
) -> Result<(u64, bool), SimError> {
    stream_portable(run, t_end, every, record)
}

/// The loop of [`stream`], for the baseline instruction set.
#[inline(always)]
pub(super) fn stream_portable<R: Run + ?Sized>(
    run: &mut R,
    t_end: f64,
    every: u64,
    mut record: impl FnMut(Sample) -> bool,
) -> Result<(u64, bool), SimError> {
    let every = every.max(1);
    let mut samples = 0u64;
    if run.run_state().steps == 0 {
        samples += 1;
        if !record(run.sample()) {
            return Ok((samples, true));
        }
    }
    let n_end = (t_end / run.step_size() - 1e-9).ceil() as u64;
    // Steps until the next multiple of `every`: a countdown rather than a division per step,
    // which is a fair share of a step as cheap as the exact hold's.
    let mut to_record = every - run.run_state().steps % every;
    while run.run_state().steps < n_end {
        to_record -= 1;
        if to_record == 0 {
            to_record = every;
            let s = run.step_sampled()?;
            samples += 1;
            if !record(s) {
                return Ok((samples, true));
            }
        } else {
            run.step()?;
        }
    }
    Ok((samples, false))
}
