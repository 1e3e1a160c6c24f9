//! How the records' sensors read the twin's channels: properties of the measurement, not of
//! the plant. `seat-twin calibrate` estimates them beside the declared parameters and writes
//! them into `calibrated.toml`; the replay applies them to the twin's channels before they
//! are compared with (or written beside) a record.

use serde::{Deserialize, Serialize};

/// Sensor properties: `ÿ_read = scale·ÿ + offset`; `u_read` is `u` through a first-order
/// low-pass of time constant `lag` run on the record's samples (a data-acquisition filter):
/// `u_read[n] = a·u_read[n−1] + (1 − a)·u[n]` with `a = e^(−Δt/lag)`, Δt the record's
/// sample interval. At low frequency it delays `u` by `Δt·a/(1 − a) ≈ lag − Δt/2`.
///
/// The data acquisition's anti-alias filter (`antialias_hz`, `antialias_order`) is declared,
/// not fitted: it acts on every measured channel alike (u, x, ẍ, ÿ, p1, p2), and in the
/// tests a rig's controller drives (the command, sent and recorded as sent) it delays them
/// all against the command by its group delay, which the records cannot tell from the valve's
/// delay τ (a second-order filter at 80 Hz delays by 2.8 ms; undeclared, τ reads that much
/// long). Declared, the replay reads the twin's measured channels through the same filter at
/// every step and advances the measured platform motion that drives it by the filter's
/// delay (see `identify::replay`), so τ stays the valve's own.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SensorParams {
    /// Scale of the body accelerometer [-], 0.5 ..= 2 (1: exact).
    pub ydd_scale: f64,
    /// Offset of the body accelerometer [m/s^2], -50 ..= 50.
    pub ydd_offset_m_s2: f64,
    /// Time constant of the stroke sensor's first-order filter on the samples \[s\], 0 ..= 0.05.
    pub u_lag_s: f64,
    /// Corner (−3 dB) of the data acquisition's anti-alias filter on every measured channel
    /// \[Hz\], 0 ..= 100000 (0: none, the channels sampled as they are). Declared from the
    /// acquisition's settings, not fitted.
    pub antialias_hz: f64,
    /// Order of that filter, a Butterworth low-pass [-], 1 ..= 8, a whole number.
    pub antialias_order: f64,
}

impl Default for SensorParams {
    fn default() -> Self {
        Self {
            ydd_scale: 1.0,
            ydd_offset_m_s2: 0.0,
            u_lag_s: 0.0,
            antialias_hz: 0.0,
            antialias_order: 2.0,
        }
    }
}

impl SensorParams {
    /// Whether every property is exact (nothing to apply).
    pub fn is_exact(&self) -> bool {
        *self == Self::default()
    }

    /// The declared anti-alias filter's order as a count of poles, 1 ..= 8.
    fn antialias_poles(&self) -> usize {
        self.antialias_order.round().clamp(1.0, 8.0) as usize
    }

    /// The declared anti-alias filter's sections for the sample step `dt` \[s\]
    /// ([`crate::dsp::butterworth_sections`]), or `None` without one.
    pub fn antialias_sections(&self, dt: f64) -> Option<Vec<crate::dsp::Biquad>> {
        (self.antialias_hz > 0.0).then(|| {
            crate::dsp::butterworth_sections(dt, self.antialias_hz, self.antialias_poles())
        })
    }

    /// The declared anti-alias filter's delay at low frequency \[s\], `(1/ωc)·Σ 1/Qₖ` over its
    /// sections (√2/ωc for the second order, 2.613/ωc for the fourth); 0 without one.
    pub fn antialias_delay_s(&self) -> f64 {
        if self.antialias_hz <= 0.0 {
            return 0.0;
        }
        crate::dsp::butterworth_delay_s(self.antialias_hz, self.antialias_poles())
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

    /// The declared filter's delay is the slope of its sections' phase at low frequency
    /// (1 Hz against an 80 Hz corner), for every order; none without a corner.
    #[test]
    fn antialias_delay_is_the_sections_low_frequency_delay() {
        assert_eq!(SensorParams::default().antialias_delay_s(), 0.0);
        assert!(SensorParams::default().antialias_sections(1e-4).is_none());
        for n in 1..=8 {
            let s = SensorParams {
                antialias_hz: 80.0,
                antialias_order: n as f64,
                ..Default::default()
            };
            let dt = 1e-5;
            let sections = s.antialias_sections(dt).expect("declared");
            let theta = 2.0 * std::f64::consts::PI * 1.0 * dt;
            let phase: f64 = sections.iter().map(|c| c.response(theta).arg()).sum();
            let delay = -phase / (2.0 * std::f64::consts::PI);
            let want = s.antialias_delay_s();
            assert!(
                (delay - want).abs() < 2e-3 * want,
                "order {n}: {delay} vs {want}"
            );
        }
        // The second order at 80 Hz: √2/(2π·80 Hz) = 2.81 ms.
        let two = SensorParams {
            antialias_hz: 80.0,
            ..Default::default()
        };
        assert!((two.antialias_delay_s() - 2.8135e-3).abs() < 1e-6);
    }

    /// A sampled first-order filter of 2.5 ms at 1 ms samples: a ramp comes out
    /// `a/(1 − a)` samples late once settled (a = e^(−0.4): 2.03 ms, about 2.5 − ½ ms), and
    /// a step rises by `1 − aⁿ` after n samples; scale and offset are affine.
    #[test]
    fn sensors_read_as_documented() {
        let s = SensorParams {
            ydd_scale: 0.96,
            ydd_offset_m_s2: 0.1,
            u_lag_s: 2.5e-3,
            ..Default::default()
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
