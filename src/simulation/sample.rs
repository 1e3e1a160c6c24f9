//! What a run records: its samples, its end-stop contacts and its traces, and the grid of
//! recorded samples.

use super::*;

/// One recorded instant (SI). Fields a model lacks are NaN.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Time \[s\].
    pub t: f64,
    /// Platform position \[m\].
    pub x: f64,
    /// Platform velocity [m/s].
    pub xd: f64,
    /// Platform acceleration [m/s²].
    pub xdd: f64,
    /// Relative displacement \[m\].
    pub u: f64,
    /// Relative velocity [m/s].
    pub du: f64,
    /// Body acceleration [m/s²].
    pub ydd: f64,
    /// Command as sent (before the delay), saturated \[V\]. NaN for the passive model.
    pub v_in: f64,
    /// Spool position \[m\].
    pub xv: f64,
    /// Upper chamber pressure \[Pa\].
    pub p1: f64,
    /// Lower chamber pressure \[Pa\].
    pub p2: f64,
    /// Hose-1 flow [m³/s].
    pub q1: f64,
    /// Hose-2 flow [m³/s].
    pub q2: f64,
    /// Body beyond ±Lc/2 (end-stop contact for the twin, stroke overrun for the others).
    pub contact: bool,
}

impl Sample {
    /// The sample at `t` from the platform's motion, the model's outputs and the command as
    /// sent (NaN without a valve); `half_stroke` \[m\] decides `contact`.
    pub fn assemble(t: f64, p: PlatformSample, o: &Outputs, v_in: f64, half_stroke: f64) -> Self {
        Sample {
            t,
            x: p.x,
            xd: p.xd,
            xdd: p.xdd,
            u: o.u,
            du: o.du,
            ydd: o.ydd,
            v_in,
            xv: o.xv,
            p1: o.p1,
            p2: o.p2,
            q1: o.q1,
            q2: o.q2,
            contact: o.u.abs() > half_stroke,
        }
    }
}

/// One end-stop contact (twin) or stroke overrun (linear, passive models).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ContactEvent {
    /// Start \[s\].
    pub t_start: f64,
    /// End \[s\] (the run's end if still in contact).
    pub t_end: f64,
    /// +1 upper stop (u > 0), −1 lower stop.
    pub side: i8,
    /// Largest penetration beyond ±Lc/2 \[m\].
    pub max_penetration_m: f64,
}

/// A recorded run.
#[derive(Debug, Clone, PartialEq)]
pub struct Trace {
    /// Which model produced it.
    pub model: ModelKind,
    /// Samples at the output rate.
    pub samples: Vec<Sample>,
    /// End-stop contacts / stroke overruns.
    pub contacts: Vec<ContactEvent>,
    /// Integrator work.
    pub stats: StepStats,
}

/// What a streamed run leaves besides its samples ([`Run::run_streaming`]).
#[derive(Debug, Clone, PartialEq)]
pub struct RunSummary {
    /// Which model produced it.
    pub model: ModelKind,
    /// Samples passed to the recorder.
    pub samples: u64,
    /// Whether the recorder stopped the run before its end.
    pub stopped: bool,
    /// End-stop contacts / stroke overruns.
    pub contacts: Vec<ContactEvent>,
    /// Integrator work.
    pub stats: StepStats,
}

impl RunSummary {
    /// The trace of these samples.
    pub fn into_trace(self, samples: Vec<Sample>) -> Trace {
        Trace {
            model: self.model,
            samples,
            contacts: self.contacts,
            stats: self.stats,
        }
    }
}

/// Steps between recorded samples at `rate_hz` for an internal step `h` \[s\] (at least 1).
pub fn record_every(h: f64, rate_hz: f64) -> u64 {
    ((1.0 / rate_hz) / h).round().max(1.0) as u64
}

/// Samples a run to `t_end` \[s\] recorded at `rate_hz` with internal step `h` gives, both
/// ends included (what [`Run::run_trace`] returns); saturates for absurd inputs.
pub fn sample_count(t_end: f64, rate_hz: f64, h: f64) -> u64 {
    let every = record_every(h, rate_hz);
    let n_end = (t_end / h - 1e-9).ceil().max(0.0) as u64;
    (n_end / every).saturating_add(1)
}

impl Trace {
    /// One channel as a vector.
    pub fn channel(&self, f: impl Fn(&Sample) -> f64) -> Vec<f64> {
        self.samples.iter().map(f).collect()
    }
}
