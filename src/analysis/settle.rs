//! The settle test at rest: the nonlinear twin in closed loop after a cycloidal bump (the
//! paper's Fig. 13 input: 30 mm in 0.5 s), then left alone. A loop whose linearisation at rest
//! is barely damped or unstable (the oil column near 77 Hz) rings or grows here, while a
//! random ride, whose moving valve damps that mode, hides it.
//!
//! Verdict: the RMS of `ÿ` over the last 2 s of a 10 s run is below [`SETTLE_RMS_M_S2`] and
//! the RMS of the last second is not above the one before (no growth, no limit cycle).

use crate::experiments;
use crate::model::ModelKind;
use crate::params::Params;
use crate::scenario::Cycloid;
use crate::simulation::SimError;

/// Length of the run \[s\].
pub const SETTLE_RUN_S: f64 = 10.0;
/// Largest RMS of ÿ over the last 2 s of a settled run [m/s²].
pub const SETTLE_RMS_M_S2: f64 = 0.02;
/// Recording rate [Hz] (resolves the oil-column and valve modes, 70–90 Hz).
const RATE_HZ: f64 = 1000.0;
/// Below this RMS [m/s²] the last two seconds are at rest whatever their ratio.
const AT_REST_M_S2: f64 = 1e-6;

/// The outcome of one settle test.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Settle {
    /// RMS of ÿ over the last 2 s [m/s²].
    pub rms_last_2s_m_s2: f64,
    /// RMS of ÿ over the last second over that of the second before [-].
    pub growth_ratio: f64,
    /// Frequency of the strongest oscillation in the last 2 s \[Hz\] (zero crossings of ÿ).
    pub freq_hz: f64,
}

impl Settle {
    /// Settled: small and not growing.
    pub fn settled(&self) -> bool {
        self.rms_last_2s_m_s2 < SETTLE_RMS_M_S2
            && (self.growth_ratio <= 1.0 || self.rms_last_2s_m_s2 < AT_REST_M_S2)
    }
}

fn rms(x: &[f64]) -> f64 {
    (x.iter().map(|v| v * v).sum::<f64>() / x.len().max(1) as f64).sqrt()
}

/// Runs the twin of `params` (its own controller) over the bump and reads the last 2 s.
/// A run that diverges is an error ([`SimError`]), and not settled.
pub fn settle_after_bump(params: &Params) -> Result<Settle, SimError> {
    let trace = experiments::cycloid(
        params,
        ModelKind::Twin,
        &Cycloid::default(),
        SETTLE_RUN_S,
        RATE_HZ,
    )?;
    let ydd = trace.channel(|s| s.ydd);
    let per_s = RATE_HZ as usize;
    let n = ydd.len();
    let last2 = &ydd[n.saturating_sub(2 * per_s)..];
    let (prev, last) = last2.split_at(last2.len() / 2);
    let mean = last2.iter().sum::<f64>() / last2.len().max(1) as f64;
    let crossings = last2
        .windows(2)
        .filter(|w| (w[0] - mean) * (w[1] - mean) < 0.0)
        .count();
    Ok(Settle {
        rms_last_2s_m_s2: rms(last2),
        growth_ratio: rms(last) / rms(prev).max(f64::MIN_POSITIVE),
        freq_hz: crossings as f64 / 2.0 / (last2.len() as f64 / RATE_HZ),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The paper's gains settle at the nominal plant: the bump's transient has decayed by 8 s.
    #[test]
    fn paper_gains_settle() {
        let s = settle_after_bump(&Params::paper()).expect("runs");
        assert!(s.settled(), "{s:?}");
    }
}
