//! The paper's experiments as one-call functions, shared by the CLI, the report, the app and
//! the tests.

use crate::model::ModelKind;
use crate::model::linear::LinearModel;
use crate::model::passive::PassiveModel;
use crate::params::Params;
use crate::scenario::{CommandSignal, Cycloid, PlatformMotion};
use crate::simulation::{
    CsvRunError, Drive, Run, RunSummary, Sample, SimError, Simulation, Trace, step_for_rate,
    trace_buffer, write_csv_streamed,
};
use std::path::Path;

/// Largest step of the exact (first-order-hold) runs of the linear and passive models \[s\].
/// Their inputs are smooth at this scale (ride ≤ 5 Hz, loop resonance 80 Hz): the hold error
/// is below 0.2 % of the peak body acceleration (tests in [`crate::simulation::lti`]).
pub const LTI_MAX_STEP_S: f64 = 1e-3;

/// One run of a model from rest: its drive and platform motion, for `duration_s` \[s\] recorded
/// at `rate_hz` \[Hz\] (what `seat-twin simulate` runs). The twin is stepped at the preset's
/// `numerics.max_step_s`, the linear models exactly at up to [`LTI_MAX_STEP_S`].
#[derive(Debug, Clone)]
pub struct RunSpec<'a> {
    /// The parameters.
    pub params: &'a Params,
    /// Which model.
    pub kind: ModelKind,
    /// Where the valve command comes from.
    pub drive: Drive,
    /// The platform's motion.
    pub platform: PlatformMotion,
    /// Duration \[s\].
    pub duration_s: f64,
    /// Output sample rate \[Hz\].
    pub rate_hz: f64,
}

impl RunSpec<'_> {
    /// Runs it and returns the recorded trace.
    pub fn run(self) -> Result<Trace, SimError> {
        let h_max = step_for_rate(LTI_MAX_STEP_S, self.rate_hz);
        let mut samples = trace_buffer(self.duration_s, self.rate_hz, h_max);
        let summary = self.run_streaming(|s| {
            samples.push(s);
            true
        })?;
        Ok(summary.into_trace(samples))
    }

    /// Runs it passing each sample to `record` as it is made instead of keeping it (memory
    /// does not grow with the duration); `record` returns `false` to stop the run early.
    pub fn run_streaming(self, record: impl FnMut(Sample) -> bool) -> Result<RunSummary, SimError> {
        let (params, drive, platform) = (self.params, self.drive, self.platform);
        let (duration_s, rate_hz) = (self.duration_s, self.rate_hz);
        let h = step_for_rate(params.numerics.max_step_s, rate_hz);
        match self.kind {
            ModelKind::Twin => Simulation::twin(params, h, drive, platform)
                .run_streaming(duration_s, rate_hz, record),
            // The linear models are stepped exactly (crate::simulation::lti) at up to 1 ms,
            // unless the delay is shorter than that step; then RK4 at the twin's step.
            ModelKind::Linear => {
                let model = LinearModel::new(params);
                let h_lti = step_for_rate(LTI_MAX_STEP_S, rate_hz);
                let mut sim =
                    Simulation::exact_hold(model.clone(), h_lti, drive.clone(), platform.clone())
                        .unwrap_or_else(|| Simulation::new(model, h, drive, platform));
                sim.run_streaming(duration_s, rate_hz, record)
            }
            ModelKind::Passive => {
                let model = PassiveModel::new(params);
                let h_lti = step_for_rate(LTI_MAX_STEP_S, rate_hz);
                let mut sim =
                    Simulation::exact_hold(model.clone(), h_lti, drive.clone(), platform.clone())
                        .unwrap_or_else(|| Simulation::new(model, h, drive, platform));
                sim.run_streaming(duration_s, rate_hz, record)
            }
        }
    }

    /// Runs it writing each sample to `path` as it is made, with `comments`, in the columns
    /// the model has ([`crate::simulation::SampleColumns`]), atomically: memory does not grow
    /// with the duration, and a divergence or a write error leaves `path` as it was.
    pub fn write_csv(
        self,
        path: &Path,
        comments: &[(String, String)],
    ) -> Result<RunSummary, CsvRunError> {
        write_csv_streamed(path, self.kind, comments, |record| {
            self.run_streaming(record)
        })
    }
}

/// Runs `kind` from rest under `drive` and `platform` until `duration_s`, recording at
/// `rate_hz` ([`RunSpec::run`]).
pub fn run(
    params: &Params,
    kind: ModelKind,
    drive: Drive,
    platform: PlatformMotion,
    duration_s: f64,
    rate_hz: f64,
) -> Result<Trace, SimError> {
    RunSpec {
        params,
        kind,
        drive,
        platform,
        duration_s,
        rate_hz,
    }
    .run()
}

/// The cycloidal bump of Figs. 13–14 in closed loop.
pub fn cycloid(
    params: &Params,
    kind: ModelKind,
    bump: &Cycloid,
    duration_s: f64,
    rate_hz: f64,
) -> Result<Trace, SimError> {
    let (drive, platform) = (Drive::closed_loop(params), PlatformMotion::Cycloid(*bump));
    run(params, kind, drive, platform, duration_s, rate_hz)
}

/// A valve sine test (platform still, open loop): `V_in = A·cos(2πft)`.
pub fn valve_sine(
    params: &Params,
    kind: ModelKind,
    freq_hz: f64,
    amplitude_v: f64,
    duration_s: f64,
    rate_hz: f64,
) -> Result<Trace, SimError> {
    let sine = CommandSignal::Sine {
        amplitude_v,
        freq_hz,
    };
    let (drive, platform) = (Drive::OpenLoop(sine), PlatformMotion::Still);
    run(params, kind, drive, platform, duration_s, rate_hz)
}

/// Table 1 of the paper: the 69 (frequency \[Hz\], amplitude \[V\]) valve sine tests.
pub fn table1() -> Vec<(f64, f64)> {
    const AMPS: [f64; 7] = [0.72, 1.10, 2.10, 3.00, 4.50, 6.40, 8.00];
    let rows: [(f64, usize); 13] = [
        (0.5, 1),
        (1.0, 2),
        (2.0, 3),
        (3.0, 4),
        (4.0, 5),
        (5.0, 6),
        (6.0, 7),
        (7.0, 7),
        (8.0, 7),
        (9.0, 7),
        (10.0, 7),
        (15.0, 7),
        (20.0, 6),
    ];
    rows.iter()
        .flat_map(|&(f, n)| AMPS[..n].iter().map(move |&a| (f, a)))
        .collect()
}

#[cfg(test)]
mod tests {
    #[test]
    fn table1_has_69_tests_and_no_8v_at_20hz() {
        let t = super::table1();
        assert_eq!(t.len(), 69);
        assert!(!t.contains(&(20.0, 8.0)));
        assert!(t.contains(&(15.0, 8.0)));
    }
}
