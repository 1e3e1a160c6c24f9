//! The paper's own calibration (section 4): Cd from the gain and τ from the phase slope of
//! the open-loop sine tests. The baseline to beat and the declared fit's start.

use super::replay::{PreparedRecord, Replay, rms};
use super::result::PaperBaseline;
use crate::analysis::frequency_response::first_harmonic;
use crate::params::Params;

/// The paper's section-4 method on the open-loop sine tests (platform still, sinusoidal
/// `v_in`): `u̇/V_in` at each test's frequency, measured vs nominal twin; Cd scales with the
/// mean gain ratio, τ shifts by the slope of the phase difference.
pub(super) fn paper_baseline(
    params: &Params,
    recs: &[PreparedRecord],
    nominal: &[Replay],
) -> Option<PaperBaseline> {
    let mut files = Vec::new();
    let (mut ratio_sum, mut wsum) = (0.0, 0.0);
    let (mut sxy, mut sxx) = (0.0, 0.0);
    for (p, r) in recs.iter().zip(nominal) {
        if p.platform_moves {
            continue;
        }
        let Some(f) = sine_frequency(&p.v_in, p.dt) else {
            continue;
        };
        let periods = ((p.duration_s() - 0.5) * f).floor() as usize;
        if periods < 1 {
            continue;
        }
        let v = first_harmonic(&p.v_in, p.dt, 0.0, f, periods);
        // Is v_in a sine? Its first harmonic must carry (almost) all its power.
        let v_rms = rms(&p.v_in[p.len - (periods as f64 / f / p.dt) as usize..]);
        if !(v.norm() > 0.0 && (v.norm() / (v_rms * 2f64.sqrt()) - 1.0).abs() < 0.05) {
            continue;
        }
        let gm = first_harmonic(&p.du_meas_f, p.dt, 0.0, f, periods) / v;
        let gs = first_harmonic(&r.twin_du, p.dt, 0.0, f, periods) / v;
        if !(gm.norm().is_finite() && gs.norm() > 0.0) {
            continue;
        }
        let w = 1.0;
        ratio_sum += w * gm.norm() / gs.norm();
        wsum += w;
        let dphi = (gm / gs).arg();
        let x = 2.0 * std::f64::consts::PI * f;
        sxy += x * (-dphi);
        sxx += x * x;
        files.push(p.name.clone());
    }
    if files.is_empty() || wsum == 0.0 {
        return None;
    }
    let cd = (params.plant.valve.cd * ratio_sum / wsum).clamp(1e-3, 1.0);
    let tau = (params.plant.valve.tau_s + sxy / sxx).clamp(0.0, 0.1);
    Some(PaperBaseline {
        files,
        cd,
        tau_s: tau,
    })
}

/// Frequency of a sinusoidal command from its upward zero crossings [Hz].
fn sine_frequency(v: &[f64], dt: f64) -> Option<f64> {
    let mut crossings = Vec::new();
    for i in 1..v.len() {
        if v[i - 1] < 0.0 && v[i] >= 0.0 {
            let frac = -v[i - 1] / (v[i] - v[i - 1]);
            crossings.push((i - 1) as f64 + frac);
        }
    }
    if crossings.len() < 2 {
        return None;
    }
    let span = (crossings[crossings.len() - 1] - crossings[0]) * dt;
    (span > 0.0).then(|| (crossings.len() - 1) as f64 / span)
}
