//! The error metric of a replay: the weighted residuals the fit minimises, the filtered
//! channel errors and the raw-channel errors.

use super::{DRIFT_LOWPASS_HZ, PreparedRecord, SimChannels};
use crate::dsp::{butterworth_zero_phase, filtered_derivative, lowpass, rms};

impl PreparedRecord {
    /// Weighted residuals (twin − measured) of a replay, appended to `out`:
    /// decimated velocity channel, then decimated acceleration channel, then the pressure
    /// channels the record has, then the stroke-drift channel (`u` through the zero-phase
    /// [`DRIFT_LOWPASS_HZ`] low-pass, kept at [`super::DRIFT_EVAL_RATE_HZ`], divided by
    /// [`Self::scale_u_drift`]): the velocity channel is blind to a drift of the stroke that
    /// the raw error measure, and a user, sees.
    pub fn weighted_residuals(&self, sim: &SimChannels, out: &mut Vec<f64>) {
        let du_sim_f = filtered_derivative(&sim.u, self.dt, self.lowpass_hz);
        for i in self.eval_indices() {
            out.push((du_sim_f[i] - self.du_meas_f[i]) / self.scale_du);
        }
        if let Some(ym) = &self.ydd_meas_f {
            let ys = lowpass(&sim.ydd, self.dt, self.lowpass_hz);
            for i in self.eval_indices() {
                out.push((ys[i] - ym[i]) / self.scale_ydd);
            }
        }
        for (k, sim_p) in [&sim.p1, &sim.p2].into_iter().enumerate() {
            if let Some(pm) = &self.p_meas_f[k] {
                let ps = lowpass(sim_p, self.dt, self.lowpass_hz);
                for i in self.eval_indices() {
                    out.push((ps[i] - pm[i]) / self.scale_p[k]);
                }
            }
        }
        let fc = DRIFT_LOWPASS_HZ.min(0.3 / self.dt);
        let us = butterworth_zero_phase(&sim.u, self.dt, fc, 2);
        for i in self.window.clone().step_by(self.drift_decimate.max(1)) {
            out.push((us[i] - self.u_drift_meas[i]) / self.scale_u_drift);
        }
    }

    /// Raw-signal errors of a replay on the window: every written channel the record also
    /// has (`u`, `ÿ`, `p1`, `p2`), unfiltered, sample by sample on the record's own grid.
    pub fn raw_errors(&self, sim: &SimChannels) -> RawErrors {
        let w = self.window.clone();
        let ch = |twin: &[f64], meas: &[f64]| RawChannel::of(&twin[w.clone()], &meas[w.clone()]);
        RawErrors {
            u: ch(&sim.u, &self.u),
            ydd: self.ydd.as_ref().map(|m| ch(&sim.ydd, m)),
            p1: self.p_raw[0].as_ref().map(|m| ch(&sim.p1, m)),
            p2: self.p_raw[1].as_ref().map(|m| ch(&sim.p2, m)),
        }
    }

    /// Unweighted channel errors of a replay.
    pub fn channel_errors(&self, sim: &SimChannels) -> ChannelErrors {
        let w = self.window.clone();
        let du_sim_f = filtered_derivative(&sim.u, self.dt, self.lowpass_hz);
        let e_du: Vec<f64> = du_sim_f[w.clone()]
            .iter()
            .zip(&self.du_meas_f[w.clone()])
            .map(|(a, b)| a - b)
            .collect();
        let e_u: Vec<f64> = sim.u[w.clone()]
            .iter()
            .zip(&self.u[w.clone()])
            .map(|(a, b)| a - b)
            .collect();
        let (ydd, ydd_nrmse) = match &self.ydd_meas_f {
            Some(ym) => {
                let ys = lowpass(&sim.ydd, self.dt, self.lowpass_hz);
                let e: Vec<f64> = ys[w.clone()]
                    .iter()
                    .zip(&ym[w.clone()])
                    .map(|(a, b)| a - b)
                    .collect();
                let r = rms(&e);
                (Some(r), Some(r / rms(&ym[w.clone()]).max(1e-12)))
            }
            None => (None, None),
        };
        let p_err = |k: usize, sim_p: &[f64]| {
            self.p_meas_f[k].as_ref().map(|pm| {
                let ps = lowpass(sim_p, self.dt, self.lowpass_hz);
                rms(&ps[w.clone()]
                    .iter()
                    .zip(&pm[w.clone()])
                    .map(|(a, b)| a - b)
                    .collect::<Vec<_>>())
            })
        };
        // Weighted RMS per channel, in the order of `weighted_residuals`.
        let mut wres = Vec::new();
        self.weighted_residuals(sim, &mut wres);
        let k = self.window.len().div_ceil(self.decimate.max(1));
        let mut chunks = wres.chunks(k.max(1));
        let w_du = chunks.next().map(rms).unwrap_or(0.0);
        let w_ydd = self
            .ydd_meas_f
            .as_ref()
            .and_then(|_| chunks.next().map(rms));
        let mut w_p = [None, None];
        for (j, slot) in w_p.iter_mut().enumerate() {
            if self.p_meas_f[j].is_some() {
                *slot = chunks.next().map(rms);
            }
        }
        ChannelErrors {
            p1: p_err(0, &sim.p1),
            p2: p_err(1, &sim.p2),
            du: rms(&e_du),
            du_nrmse: rms(&e_du) / rms(&self.du_meas_f[w.clone()]).max(1e-12),
            ydd,
            ydd_nrmse,
            u: rms(&e_u),
            samples: w.len(),
            weighted: rms(&wres),
            weighted_du: w_du,
            weighted_ydd: w_ydd,
            weighted_p1: w_p[0],
            weighted_p2: w_p[1],
            raw: self.raw_errors(sim),
        }
    }
}

/// RMS errors of one replay, per channel (SI).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct ChannelErrors {
    /// RMS error of the filtered relative velocity [m/s].
    pub du: f64,
    /// The same divided by the RMS of the measured filtered velocity [-].
    pub du_nrmse: f64,
    /// RMS error of the filtered body acceleration [m/s²], if measured.
    pub ydd: Option<f64>,
    /// The same divided by the RMS of the measured filtered acceleration [-].
    pub ydd_nrmse: Option<f64>,
    /// RMS error of the filtered upper chamber pressure \[Pa\], if measured.
    pub p1: Option<f64>,
    /// RMS error of the filtered lower chamber pressure \[Pa\], if measured.
    pub p2: Option<f64>,
    /// RMS error of the relative displacement \[m\] (open loop: includes drift; not fitted).
    pub u: f64,
    /// Samples counted (the record's, or its window's).
    pub samples: usize,
    /// RMS of the noise-weighted residual of this record (1 = sensor-noise level).
    pub weighted: f64,
    /// The same for the velocity channel alone.
    pub weighted_du: f64,
    /// The same for the acceleration channel, if measured.
    pub weighted_ydd: Option<f64>,
    /// The same for `p1`, if measured.
    pub weighted_p1: Option<f64>,
    /// The same for `p2`, if measured.
    pub weighted_p2: Option<f64>,
    /// Errors of the raw (unfiltered) channels, as `seat-twin replay` writes them.
    pub raw: RawErrors,
}

/// Error of one raw channel of a replay against the record.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
pub struct RawChannel {
    /// RMS of twin − measured \[SI\].
    pub rms_error: f64,
    /// Standard deviation of the measured channel about its mean \[SI\].
    pub measured_std: f64,
    /// `rms_error / measured_std` [-] (0 when the channel does not vary).
    pub nrmse: f64,
}

impl RawChannel {
    fn of(twin: &[f64], meas: &[f64]) -> Self {
        let e: Vec<f64> = twin.iter().zip(meas).map(|(a, b)| a - b).collect();
        let n = meas.len().max(1) as f64;
        let mean = meas.iter().sum::<f64>() / n;
        let dev: Vec<f64> = meas.iter().map(|v| v - mean).collect();
        let (rms_error, measured_std) = (rms(&e), rms(&dev));
        Self {
            rms_error,
            measured_std,
            nrmse: if measured_std > 0.0 {
                rms_error / measured_std
            } else {
                0.0
            },
        }
    }
}

/// Raw-channel errors of a replay (`None`: the record lacks the channel).
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
pub struct RawErrors {
    /// Relative displacement \[m\].
    pub u: RawChannel,
    /// Body acceleration [m/s²].
    pub ydd: Option<RawChannel>,
    /// Upper chamber pressure \[Pa\].
    pub p1: Option<RawChannel>,
    /// Lower chamber pressure \[Pa\].
    pub p2: Option<RawChannel>,
}

#[cfg(test)]
mod tests {
    use super::super::*;
    use crate::dataset::Record;

    #[test]
    fn pressure_channels_enter_the_metric_only_when_recorded() {
        let n = 2000;
        let dt = 1e-3;
        let t: Vec<f64> = (0..n).map(|i| i as f64 * dt).collect();
        let p: Vec<f64> = t.iter().map(|t| 55e5 + 2e5 * (6.0 * t).sin()).collect();
        let mut rec = Record {
            path: "p.csv".into(),
            metadata: vec![],
            dt,
            t: t.clone(),
            v_in: Some(vec![0.0; n]),
            u: Some(vec![0.0; n]),
            x: None,
            xdd: None,
            ydd: None,
            p1: None,
            p2: None,
            warnings: vec![],
        };
        let opt = MetricOptions::default();
        let k = n.div_ceil(4);
        // The stroke-drift channel: 5 Hz over 2 s.
        let drift = n.div_ceil(200);
        assert_eq!(
            PreparedRecord::new(&rec, &opt).unwrap().residual_len(),
            k + drift
        );
        rec.p1 = Some(p.clone());
        let prep = PreparedRecord::new(&rec, &opt).unwrap();
        assert_eq!(prep.residual_len(), 2 * k + drift);
        // Floor: 1 % of the swing (2 bar sine → 0.014 bar), not of the 55 bar mean.
        assert!((prep.scale_p[0] - 0.01 * 2e5 / 2f64.sqrt()).abs() < 100.0);
        // A twin 1 bar too low on p1 gives a weighted pressure residual of −1 bar / scale.
        let sim = SimChannels {
            u: vec![0.0; n],
            ydd: vec![0.0; n],
            p1: p.iter().map(|v| v - 1e5).collect(),
            p2: vec![0.0; n],
            ..Default::default()
        };
        let mut w = Vec::new();
        prep.weighted_residuals(&sim, &mut w);
        assert_eq!(w.len(), 2 * k + drift);
        let mid = w[k + k / 2];
        assert!(
            (mid + 1e5 / prep.scale_p[0]).abs() < 1e-3 * mid.abs(),
            "{mid}"
        );
        assert!((prep.channel_errors(&sim).p1.unwrap() - 1e5).abs() < 1.0);
    }
}
