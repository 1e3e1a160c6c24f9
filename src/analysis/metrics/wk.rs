//! The ISO 2631-1 Wk frequency weighting: the standard's analogue filter ([`wk_response`])
//! and its digital version ([`WkFilter`], [`wk_weight`]); see the [metrics module](super)
//! for the definitions, accuracy and references.

use super::{MIN_SAMPLE_RATE_HZ, MetricsError, check_sample_rate};
use crate::dsp::{AnalogSection, BiquadState};
use std::f64::consts::{FRAC_1_SQRT_2, PI};

// ISO 2631-1:1997 Annex A / ISO 8041-1, weighting Wk.
/// Band-limiting high-pass corner \[Hz\].
const F1: f64 = 0.4;
/// Band-limiting low-pass corner \[Hz\].
const F2: f64 = 100.0;
/// Quality factor of both Butterworth band-limiting sections [-].
const Q12: f64 = FRAC_1_SQRT_2;
/// a–v transition, numerator corner \[Hz\].
const F3: f64 = 12.5;
/// a–v transition, denominator resonance \[Hz\].
const F4: f64 = 12.5;
/// a–v transition quality factor [-].
const Q4: f64 = 0.63;
/// Upward step, numerator frequency \[Hz\].
const F5: f64 = 2.37;
/// Upward step, numerator quality factor [-].
const Q5: f64 = 0.91;
/// Upward step, denominator frequency \[Hz\].
const F6: f64 = 3.35;
/// Upward step, denominator quality factor [-].
const Q6: f64 = 0.91;

/// Exact response of the continuous ISO 2631-1 Wk weighting at `freq_hz` \[Hz\]:
/// `(magnitude, phase)`, the magnitude as a factor [-] and the phase in rad.
///
/// The magnitude is the weighting factor (1 = unweighted; 0.482 at 1 Hz, 1.054 at 6.3 Hz).
/// The phase is continuous in frequency (not wrapped to ±π): it tends to +π as `f → 0`
/// (second-order high-pass) and to −3π/2 as `f → ∞`. At 0 Hz the magnitude is 0. A
/// non-finite frequency gives NaN.
pub fn wk_response(freq_hz: f64) -> (f64, f64) {
    let w = 2.0 * PI * freq_hz;
    wk_sections(|omega| omega)
        .iter()
        .fold((1.0, 0.0), |(mag, phase), section| {
            let (m, p) = section.response(w);
            (mag * m, phase + p)
        })
}

/// The four analogue factors of Wk, with every characteristic angular frequency passed
/// through `omega` (identity for the analogue filter, pre-warping for the digital one).
pub(super) fn wk_sections(omega: impl Fn(f64) -> f64) -> [AnalogSection; 4] {
    let w = |f: f64| omega(2.0 * PI * f);
    let (w1, w2, w3, w4, w5, w6) = (w(F1), w(F2), w(F3), w(F4), w(F5), w(F6));
    // The step's gain is that of the standard, (f5/f6)², not of the warped frequencies, so
    // the digital filter keeps the exact low-frequency weighting.
    let step_gain = (F5 / F6).powi(2);
    [
        // Band limiting, high-pass: (s/ω1)² / (1 + s/(ω1·Q1) + (s/ω1)²).
        AnalogSection {
            num: [0.0, 0.0, 1.0 / (w1 * w1)],
            den: [1.0, 1.0 / (w1 * Q12), 1.0 / (w1 * w1)],
        },
        // Band limiting, low-pass: 1 / (1 + s/(ω2·Q2) + (s/ω2)²).
        AnalogSection {
            num: [1.0, 0.0, 0.0],
            den: [1.0, 1.0 / (w2 * Q12), 1.0 / (w2 * w2)],
        },
        // a–v transition.
        AnalogSection {
            num: [1.0, 1.0 / w3, 0.0],
            den: [1.0, 1.0 / (w4 * Q4), 1.0 / (w4 * w4)],
        },
        // Upward step.
        AnalogSection {
            num: [step_gain, step_gain / (w5 * Q5), step_gain / (w5 * w5)],
            den: [1.0, 1.0 / (w6 * Q6), 1.0 / (w6 * w6)],
        },
    ]
}

/// Digital ISO 2631-1 Wk weighting filter for a signal sampled at a fixed rate.
///
/// A cascade of four second-order sections (band-limiting high-pass and low-pass,
/// a–v transition, upward step), each the bilinear transform of the corresponding
/// analogue factor with its characteristic frequencies pre-warped. Input and output are
/// accelerations [m/s²]. It starts at rest; feed it samples one at a time with
/// [`filter`](Self::filter).
#[derive(Debug, Clone, PartialEq)]
pub struct WkFilter {
    sections: [BiquadState; 4],
    sample_rate_hz: f64,
}

impl WkFilter {
    /// Designs the filter for `sample_rate_hz` \[Hz\].
    ///
    /// # Errors
    /// [`MetricsError::InvalidSampleRate`] if the rate is not finite and positive,
    /// [`MetricsError::SampleRateTooLow`] if it is below [`MIN_SAMPLE_RATE_HZ`].
    pub fn new(sample_rate_hz: f64) -> Result<Self, MetricsError> {
        check_sample_rate(sample_rate_hz)?;
        if sample_rate_hz < MIN_SAMPLE_RATE_HZ {
            return Err(MetricsError::SampleRateTooLow {
                sample_rate_hz,
                min_hz: MIN_SAMPLE_RATE_HZ,
            });
        }
        let k = 2.0 * sample_rate_hz;
        let sections = wk_sections(|omega| k * (omega / k).tan())
            .map(|section| BiquadState::new(section.bilinear(k)));
        Ok(Self {
            sections,
            sample_rate_hz,
        })
    }

    /// Filters one sample [m/s²] and returns the weighted sample [m/s²].
    pub fn filter(&mut self, x: f64) -> f64 {
        self.sections.iter_mut().fold(x, |v, s| s.step(v))
    }

    /// Returns the filter to rest (zero state), as after [`new`](Self::new).
    pub fn reset(&mut self) {
        for section in &mut self.sections {
            section.reset();
        }
    }

    /// The sample rate the filter was designed for \[Hz\].
    pub fn sample_rate_hz(&self) -> f64 {
        self.sample_rate_hz
    }

    /// Steady-state gain of the digital filter at `freq_hz` \[Hz\] (from its transfer function
    /// on the unit circle) [-]; compare with the magnitude of [`wk_response`].
    pub fn gain_at(&self, freq_hz: f64) -> f64 {
        let theta = 2.0 * PI * freq_hz / self.sample_rate_hz;
        self.sections.iter().map(|s| s.coeffs.gain(theta)).product()
    }
}

/// Applies the digital Wk weighting to a whole signal sampled at `sample_rate_hz` \[Hz\];
/// returns the weighted acceleration [m/s²], one sample per input sample. The filter starts
/// at rest. An empty signal gives an empty result.
///
/// # Errors
/// As [`WkFilter::new`].
pub fn wk_weight(signal: &[f64], sample_rate_hz: f64) -> Result<Vec<f64>, MetricsError> {
    let mut filter = WkFilter::new(sample_rate_hz)?;
    Ok(signal.iter().map(|&x| filter.filter(x)).collect())
}
