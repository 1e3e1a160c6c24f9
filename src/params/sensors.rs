//! How the records' sensors read the twin's channels: properties of the measurement, not of
//! the plant. `seat-twin calibrate` estimates them beside the declared parameters and writes
//! them into `calibrated.toml`; the replay applies them to the twin's channels before they
//! are compared with (or written beside) a record.

use serde::{Deserialize, Serialize};

/// Sensor properties: `ÿ_read = scale·ÿ + offset`; `u_read` is `u` through a first-order
/// low-pass of time constant `lag` run on the record's samples (a data-acquisition filter):
/// `u_read[n] = a·u_read[n−1] + (1 − a)·u[n]` with `a = e^(−Δt/lag)`, Δt the record's
/// sample interval. At low frequency it delays `u` by `Δt·a/(1 − a) ≈ lag − Δt/2`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SensorParams {
    /// Scale of the body accelerometer [-], 0.5 ..= 2 (1: exact).
    pub ydd_scale: f64,
    /// Offset of the body accelerometer [m/s^2], -50 ..= 50.
    pub ydd_offset_m_s2: f64,
    /// Time constant of the stroke sensor's first-order filter on the samples \[s\], 0 ..= 0.05.
    pub u_lag_s: f64,
}

impl Default for SensorParams {
    fn default() -> Self {
        Self {
            ydd_scale: 1.0,
            ydd_offset_m_s2: 0.0,
            u_lag_s: 0.0,
        }
    }
}

impl SensorParams {
    /// Whether every property is exact (nothing to apply).
    pub fn is_exact(&self) -> bool {
        *self == Self::default()
    }

    /// The accelerometer's reading of `ydd` [m/s²], in place.
    pub fn read_ydd(&self, ydd: &mut [f64]) {
        for v in ydd {
            *v = self.read_ydd_sample(*v);
        }
    }

    /// The accelerometer's reading of one sample of `ydd` [m/s²].
    pub fn read_ydd_sample(&self, ydd: f64) -> f64 {
        self.ydd_scale * ydd + self.ydd_offset_m_s2
    }

    /// The stroke sensor as a running filter, for samples `dt` \[s\] apart that arrive one at a
    /// time (a streamed replay); [`Self::read_u`] is it over a whole channel.
    pub fn u_reader(&self, dt: f64) -> StrokeReader {
        StrokeReader {
            a: if self.u_lag_s > 0.0 && dt > 0.0 {
                (-dt / self.u_lag_s).exp()
            } else {
                0.0
            },
            state: None,
        }
    }

    /// The stroke sensor's reading of `u` sampled every `dt` \[s\], in place: the samples
    /// through a first-order low-pass of time constant `u_lag_s`, `y[n] = a·y[n−1] +
    /// (1 − a)·u[n]`, `a = e^(−dt/u_lag_s)`, started settled at the first sample. Why this
    /// form and not a continuous-time lag: a rig's stroke filter runs in its data
    /// acquisition, on the samples, and the two read differently by half a sample at low
    /// frequency (the sampled filter delays by `dt·a/(1 − a) ≈ u_lag_s − dt/2`), which at
    /// 200 Hz is more than a small lag itself.
    pub fn read_u(&self, u: &mut [f64], dt: f64) {
        let mut reader = self.u_reader(dt);
        for v in u {
            *v = reader.read(*v);
        }
    }
}

/// The stroke sensor's first-order filter, sample by sample ([`SensorParams::u_reader`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StrokeReader {
    /// `e^(−dt/u_lag_s)`; 0 without a lag (the reading is then the sample itself).
    a: f64,
    /// Last output; `None` before the first sample (settled there).
    state: Option<f64>,
}

impl StrokeReader {
    /// The reading of the next sample of `u` \[m\].
    pub fn read(&mut self, u: f64) -> f64 {
        if self.a == 0.0 {
            return u;
        }
        let y = match self.state {
            None => u,
            Some(y) => self.a * y + (1.0 - self.a) * u,
        };
        self.state = Some(y);
        y
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A sampled first-order filter of 2.5 ms at 1 ms samples: a ramp comes out
    /// `a/(1 − a)` samples late once settled (a = e^(−0.4): 2.03 ms, about 2.5 − ½ ms), and
    /// a step rises by `1 − aⁿ` after n samples; scale and offset are affine.
    #[test]
    fn sensors_read_as_documented() {
        let s = SensorParams {
            ydd_scale: 0.96,
            ydd_offset_m_s2: 0.1,
            u_lag_s: 2.5e-3,
        };
        let mut u: Vec<f64> = (0..200).map(|i| i as f64).collect();
        s.read_u(&mut u, 1e-3);
        let a = (-0.4f64).exp();
        let late = a / (1.0 - a);
        assert!((late - 2.0332).abs() < 1e-4, "{late}");
        for (i, v) in u.iter().enumerate().skip(60) {
            assert!((v - (i as f64 - late)).abs() < 1e-9, "{i} {v}");
        }
        let mut step = vec![0.0, 1.0, 1.0, 1.0, 1.0, 1.0];
        let lag = SensorParams {
            u_lag_s: 2e-3,
            ..Default::default()
        };
        lag.read_u(&mut step, 1e-3);
        let a = (-0.5f64).exp();
        for (n, v) in step.iter().enumerate().skip(1) {
            assert!((v - (1.0 - a.powi(n as i32))).abs() < 1e-12, "{step:?}");
        }
        let mut y = vec![10.0, -5.0];
        s.read_ydd(&mut y);
        assert!((y[0] - 9.7).abs() < 1e-12 && (y[1] + 4.7).abs() < 1e-12);
        assert!(SensorParams::default().is_exact() && !s.is_exact());
    }
}
