//! Whole-body vibration metrics for the seat: RMS, peak, crest factor, the ISO 2631-1
//! frequency weighting **Wk**, the weighted RMS `a_w`, the vibration dose value (VDV), the
//! SEAT value and the daily exposure `A(8)` with the EU action and limit values.
//!
//! All quantities are SI: accelerations in m/s², time in s (except exposure durations,
//! which are in hours as in the directive), frequencies in Hz, phases in rad.
//!
//! # What is implemented
//!
//! * [`rms`], [`peak`] and [`crest_factor`] of any sampled signal.
//! * The Wk weighting (vertical, seated, ISO 2631-1:1997 Annex A) as the standard's chain of
//!   analogue filters, each a factor of the transfer function `H(s)`:
//!   * band limiting: 2nd-order Butterworth high-pass at `f1 = 0.4 Hz` and 2nd-order
//!     Butterworth low-pass at `f2 = 100 Hz` (`Q1 = Q2 = 1/√2`);
//!   * acceleration–velocity transition
//!     `Ht(s) = (1 + s/ω3) / (1 + s/(ω4·Q4) + s²/ω4²)` with `f3 = f4 = 12.5 Hz`, `Q4 = 0.63`;
//!   * upward step
//!     `Hs(s) = (1 + s/(ω5·Q5) + s²/ω5²) / (1 + s/(ω6·Q6) + s²/ω6²) · (ω5/ω6)²` with
//!     `f5 = 2.37 Hz`, `Q5 = 0.91`, `f6 = 3.35 Hz`, `Q6 = 0.91` (gain (2.37/3.35)² ≈ 0.5
//!     below the step, 1 above it); overall gain `K = 1`;
//!
//!   where `ωi = 2π·fi`. [`wk_response`] evaluates the exact magnitude and phase of this
//!   continuous filter; at the nominal band frequencies it reproduces the weighting factors
//!   of ISO 2631-1 Table 3 (e.g. 0.418 at 0.5 Hz, 0.482 at 1 Hz, 0.967 at 4 Hz, 1.054 at
//!   6.3 Hz, 0.902 at 12.5 Hz, 0.186 at 63 Hz) within 0.3 %.
//! * [`WkFilter`], the digital (IIR) version for sampled signals: four second-order sections
//!   (one per analogue factor above), each obtained by the bilinear transform after
//!   pre-warping its characteristic frequencies (`ω' = 2·fs·tan(ω/(2·fs))`), so that each
//!   section's corner, resonance or step frequencies land where the standard puts them. The
//!   sections run in transposed direct form II in `f64`. The sample rate must be at least
//!   [`MIN_SAMPLE_RATE_HZ`] (250 Hz) so that the 100 Hz band limit lies below Nyquist.
//!   The bilinear transform compresses the response towards Nyquist, so the accuracy
//!   depends on the rate; the steady-state gain relative to [`wk_response`] is, at worst:
//!
//!   | sample rate | 0.5–50 Hz | 80 Hz   | 100 Hz  |
//!   |------------:|----------:|--------:|--------:|
//!   | 250 Hz      | −10 %     | −26 %   | −59 %   |
//!   | 500 Hz      | −2.1 %    | −5.7 %  | −13 %   |
//!   | 1 kHz       | −0.5 %    | −1.4 %  | −3.3 %  |
//!   | 2 kHz       | −0.12 %   | −0.35 % | −0.8 %  |
//!
//!   Use 1 kHz or more when the content above 20 Hz matters (it rarely does for a seat,
//!   where Wk already attenuates it). [`WkFilter::gain_at`] gives the digital gain at any
//!   frequency. [`wk_weight`] filters a whole signal.
//! * [`vdv`], the fourth-power vibration dose value `VDV = (∫ a_w⁴ dt)^(1/4)` [m/s^1.75]
//!   (ISO 2631-1 §6.3.2), integrated with the rectangle rule.
//! * [`vibration_metrics`] collects everything in a [`VibrationMetrics`]; it runs the
//!   filter over the whole signal but can leave an initial settling interval (`settle_s`)
//!   out of every statistic. [`RunningMetrics`] gives the
//!   same numbers incrementally (O(1) per sample) for a live display.
//! * [`seat_percent`], the SEAT value `100 · a_w,seat / a_w,floor` [%].
//! * [`a8`], the daily exposure `A(8) = a_w·√(T / 8 h)`, the EU values
//!   [`EU_ACTION_VALUE_A8`] and [`EU_LIMIT_VALUE_A8`], [`exposure_verdict`] and
//!   [`time_to_reach`].
//!
//! Only the vertical axis (Wk, `k = 1`) is covered. For horizontal axes ISO 2631-1 uses Wd
//! and Directive 2002/44/EC multiplies `a_w` by 1.4 before forming `A(8)`.
//!
//! # References
//!
//! * ISO 2631-1:1997, *Mechanical vibration and shock — Evaluation of human exposure to
//!   whole-body vibration — Part 1: General requirements*: §6.1 (weighted RMS `a_w`),
//!   §6.2.1 (crest factor of the weighted signal), §6.3.2 (VDV), Table 3 (weighting factors),
//!   Annex A (filter definitions).
//! * ISO 8041:2005 (now ISO 8041-1:2017), *Human response to vibration — Measuring
//!   instrumentation*, which restates the Wk filter parameters (`f1 = 0.4`, `f2 = 100`, `f3 = f4 = 12.5 Hz`,
//!   `Q4 = 0.63`, `f5 = 2.37 Hz`, `Q5 = 0.91`, `f6 = 3.35 Hz`, `Q6 = 0.91`, `K = 1`).
//! * Directive 2002/44/EC of the European Parliament and of the Council (vibration),
//!   Article 3(2): whole-body daily exposure limit value 1.15 m/s² and action value
//!   0.5 m/s², both as `A(8)` (Member States may instead use VDV values of 21 and
//!   9.1 m/s^1.75); Annex, part B: `A(8)` is the 8-hour energy equivalent of the highest
//!   of `1.4·a_wx`, `1.4·a_wy`, `a_wz` evaluated per ISO 2631-1, i.e.
//!   `A(8) = a_w·√(T/T0)` with `T0 = 8 h`.
//! * M. J. Griffin, *Handbook of Human Vibration*, Academic Press, 1990: the SEAT value
//!   (Seat Effective Amplitude Transmissibility).
//! * A. V. Oppenheim, R. W. Schafer, *Discrete-Time Signal Processing*: the bilinear
//!   transform with frequency pre-warping.
//!
//! # Edge cases
//!
//! No function panics. The plain statistics return 0 for an empty signal; the functions
//! that need a sample rate or a non-empty signal return a [`MetricsError`]. NaN samples
//! propagate to the results (NaN in, NaN out).

use crate::dsp::{AnalogSection, BiquadState};
use std::f64::consts::{FRAC_1_SQRT_2, PI};

/// Lowest sample rate accepted by the digital Wk filter \[Hz\].
///
/// The band-limiting low-pass of Wk sits at 100 Hz, which must lie below the Nyquist
/// frequency with some room (125 Hz at this rate). Even at this minimum the digital gain
/// is 10 % low at 50 Hz; see the module documentation for the accuracy at higher rates
/// (1 kHz or more is recommended).
pub const MIN_SAMPLE_RATE_HZ: f64 = 250.0;

/// Daily exposure action value for whole-body vibration, `A(8)` [m/s²]
/// (Directive 2002/44/EC, Art. 3(2)(b)).
pub const EU_ACTION_VALUE_A8: f64 = 0.5;

/// Daily exposure limit value for whole-body vibration, `A(8)` [m/s²]
/// (Directive 2002/44/EC, Art. 3(2)(a)).
pub const EU_LIMIT_VALUE_A8: f64 = 1.15;

/// Reference duration of the daily exposure `A(8)` \[h\].
const REFERENCE_DURATION_H: f64 = 8.0;

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

/// Errors of the vibration metrics.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MetricsError {
    /// The sample rate is NaN, infinite, zero or negative.
    #[error("sample rate must be a finite, positive number of Hz, got {sample_rate_hz} Hz")]
    InvalidSampleRate {
        /// The rejected sample rate \[Hz\].
        sample_rate_hz: f64,
    },
    /// The sample rate is too low for the Wk filter's 100 Hz band limit.
    #[error(
        "sample rate {sample_rate_hz} Hz is too low for the ISO 2631-1 Wk weighting: \
         at least {min_hz} Hz is needed to represent its 100 Hz band-limiting low-pass"
    )]
    SampleRateTooLow {
        /// The rejected sample rate \[Hz\].
        sample_rate_hz: f64,
        /// The minimum accepted sample rate \[Hz\] ([`MIN_SAMPLE_RATE_HZ`]).
        min_hz: f64,
    },
    /// The signal has no samples.
    #[error("signal is empty: at least one sample is needed to compute vibration metrics")]
    EmptySignal,
    /// The settling interval is NaN, infinite or negative.
    #[error("settling interval must be a finite, non-negative number of seconds, got {settle_s} s")]
    InvalidSettle {
        /// The rejected settling interval \[s\].
        settle_s: f64,
    },
    /// The settling interval covers the whole signal.
    #[error(
        "settling interval {settle_s} s leaves no samples to evaluate in a signal of {duration_s} s"
    )]
    SettleTooLong {
        /// The requested settling interval \[s\].
        settle_s: f64,
        /// The duration of the whole signal \[s\].
        duration_s: f64,
    },
}

/// Root mean square of `x` [same unit as `x`, e.g. m/s²]. Returns 0 for an empty slice
/// (one implementation for the crate, in [`crate::dsp`]).
pub use crate::dsp::rms;

/// Peak magnitude `max |x|` [same unit as `x`]. Returns 0 for an empty slice; a NaN sample
/// makes the result NaN.
pub fn peak(x: &[f64]) -> f64 {
    x.iter().fold(0.0, |p, &v| max_abs(p, v))
}

/// Crest factor `peak(x) / rms(x)` [-]. Returns 0 for an empty or all-zero signal.
///
/// ISO 2631-1 §6.2.1 defines it on the frequency-weighted acceleration; pass the output of
/// [`wk_weight`] for that meaning (as [`VibrationMetrics::crest_factor`] does).
pub fn crest_factor(x: &[f64]) -> f64 {
    ratio_or_zero(peak(x), rms(x))
}

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
fn wk_sections(omega: impl Fn(f64) -> f64) -> [AnalogSection; 4] {
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

/// Vibration dose value `VDV = (∫ a⁴ dt)^(1/4)` [m/s^1.75] of an already weighted
/// acceleration [m/s²] sampled at `sample_rate_hz` \[Hz\] (rectangle rule, `dt = 1/fs`).
///
/// Returns 0 for an empty signal and NaN if the sample rate is not finite and positive.
pub fn vdv(weighted: &[f64], sample_rate_hz: f64) -> f64 {
    if check_sample_rate(sample_rate_hz).is_err() {
        return f64::NAN;
    }
    (weighted.iter().map(|a| (a * a) * (a * a)).sum::<f64>() / sample_rate_hz).powf(0.25)
}

/// Vibration statistics of one acceleration signal (all over the same evaluated interval).
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct VibrationMetrics {
    /// RMS of the unweighted acceleration [m/s²].
    pub rms: f64,
    /// Peak magnitude of the unweighted acceleration [m/s²].
    pub peak: f64,
    /// Wk-weighted RMS acceleration `a_w` [m/s²] (ISO 2631-1 §6.1).
    pub aw: f64,
    /// Vibration dose value of the Wk-weighted acceleration [m/s^1.75] (ISO 2631-1 §6.3.2).
    pub vdv: f64,
    /// Crest factor of the Wk-weighted acceleration, peak / `a_w` [-] (0 if `a_w` = 0).
    pub crest_factor: f64,
    /// Duration of the evaluated interval \[s\] (number of evaluated samples / sample rate).
    pub duration_s: f64,
}

/// Computes [`VibrationMetrics`] of an acceleration signal [m/s²] sampled at
/// `sample_rate_hz` \[Hz\], leaving out an initial settling interval of `settle_s` \[s\].
///
/// The Wk filter runs over every sample (so its start-up transient has died out by the end
/// of the settling interval), but all statistics — unweighted and weighted — cover only
/// the samples at `t = i/fs ≥ settle_s`, and `duration_s` is the length of that interval.
/// Pass `settle_s = 0.0` to evaluate the whole signal.
///
/// # Errors
/// [`MetricsError::EmptySignal`], [`MetricsError::InvalidSettle`],
/// [`MetricsError::SettleTooLong`] if no sample is left, or the sample-rate errors of
/// [`WkFilter::new`].
pub fn vibration_metrics(
    signal: &[f64],
    sample_rate_hz: f64,
    settle_s: f64,
) -> Result<VibrationMetrics, MetricsError> {
    let mut running = RunningMetrics::with_settle(sample_rate_hz, settle_s)?;
    if signal.is_empty() {
        return Err(MetricsError::EmptySignal);
    }
    if running.skip >= signal.len() {
        return Err(MetricsError::SettleTooLong {
            settle_s,
            duration_s: signal.len() as f64 / sample_rate_hz,
        });
    }
    for &x in signal {
        running.push(x);
    }
    Ok(running.metrics())
}

/// Streaming version of [`vibration_metrics`] for a live display: push samples
/// one at a time (O(1) each) and read the statistics of everything pushed so far.
///
/// After pushing a whole signal, [`metrics`](Self::metrics) equals the batch result for
/// that signal.
#[derive(Debug, Clone, PartialEq)]
pub struct RunningMetrics {
    filter: WkFilter,
    /// Number of initial samples left out of the statistics.
    skip: usize,
    /// Number of samples pushed since the last reset.
    pushed: usize,
    acc: Accumulator,
}

impl RunningMetrics {
    /// Starts an accumulator for a signal sampled at `sample_rate_hz` \[Hz\], counting every
    /// sample.
    ///
    /// # Errors
    /// As [`WkFilter::new`].
    pub fn new(sample_rate_hz: f64) -> Result<Self, MetricsError> {
        Self::with_settle(sample_rate_hz, 0.0)
    }

    /// Starts an accumulator that filters every sample but leaves the samples with
    /// `t = i/fs < settle_s` \[s\] out of the statistics.
    ///
    /// # Errors
    /// As [`WkFilter::new`], and [`MetricsError::InvalidSettle`] if `settle_s` is not
    /// finite and non-negative.
    pub fn with_settle(sample_rate_hz: f64, settle_s: f64) -> Result<Self, MetricsError> {
        let filter = WkFilter::new(sample_rate_hz)?;
        if !(settle_s.is_finite() && settle_s >= 0.0) {
            return Err(MetricsError::InvalidSettle { settle_s });
        }
        Ok(Self {
            filter,
            skip: settle_samples(settle_s, sample_rate_hz),
            pushed: 0,
            acc: Accumulator::default(),
        })
    }

    /// Adds one acceleration sample [m/s²].
    pub fn push(&mut self, x: f64) {
        let weighted = self.filter.filter(x);
        if self.pushed >= self.skip {
            self.acc.add(x, weighted);
        }
        self.pushed = self.pushed.saturating_add(1);
    }

    /// Statistics of the samples counted so far; all fields are 0 while none is counted.
    pub fn metrics(&self) -> VibrationMetrics {
        self.acc.metrics(self.filter.sample_rate_hz)
    }

    /// Number of samples pushed since creation or the last [`reset`](Self::reset),
    /// including those in the settling interval.
    pub fn samples_pushed(&self) -> usize {
        self.pushed
    }

    /// Clears the statistics and returns the Wk filter to rest; the settling interval
    /// applies again from the next sample.
    pub fn reset(&mut self) {
        self.filter.reset();
        self.pushed = 0;
        self.acc = Accumulator::default();
    }
}

/// Running sums behind [`RunningMetrics`] and the batch metrics.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
struct Accumulator {
    n: usize,
    sum_sq: f64,
    peak: f64,
    sum_sq_w: f64,
    sum_4_w: f64,
    peak_w: f64,
}

impl Accumulator {
    fn add(&mut self, x: f64, w: f64) {
        self.n += 1;
        self.sum_sq += x * x;
        self.peak = max_abs(self.peak, x);
        let w2 = w * w;
        self.sum_sq_w += w2;
        self.sum_4_w += w2 * w2;
        self.peak_w = max_abs(self.peak_w, w);
    }

    fn metrics(&self, sample_rate_hz: f64) -> VibrationMetrics {
        if self.n == 0 {
            return VibrationMetrics::default();
        }
        let n = self.n as f64;
        let aw = (self.sum_sq_w / n).sqrt();
        VibrationMetrics {
            rms: (self.sum_sq / n).sqrt(),
            peak: self.peak,
            aw,
            vdv: (self.sum_4_w / sample_rate_hz).powf(0.25),
            crest_factor: ratio_or_zero(self.peak_w, aw),
            duration_s: n / sample_rate_hz,
        }
    }
}

/// SEAT value [%]: `100 · a_w,body / a_w,platform`, the weighted RMS on the seat (body side)
/// over the weighted RMS on the platform (floor), both [m/s²]. Below 100 % the seat
/// isolates. A zero platform value gives a non-finite result (∞ or NaN).
pub fn seat_percent(aw_body: f64, aw_platform: f64) -> f64 {
    100.0 * aw_body / aw_platform
}

/// Daily vibration exposure `A(8) = a_w·√(T / 8 h)` [m/s²] for a weighted RMS `aw`
/// [m/s²] endured for `exposure_h` hours a day. A negative duration gives NaN.
pub fn a8(aw: f64, exposure_h: f64) -> f64 {
    aw * (exposure_h / REFERENCE_DURATION_H).sqrt()
}

/// Daily exposure `A(8)` against the values of Directive 2002/44/EC.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub enum ExposureVerdict {
    /// `A(8)` ≤ the action value (0.5 m/s²).
    BelowAction,
    /// The action value is exceeded but not the limit value (0.5 < `A(8)` ≤ 1.15 m/s²):
    /// the employer must act to reduce exposure.
    AboveAction,
    /// The limit value is exceeded (`A(8)` > 1.15 m/s²): workers must not be exposed.
    AboveLimit,
}

impl std::fmt::Display for ExposureVerdict {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::BelowAction => "below the action value",
            Self::AboveAction => "above the action value",
            Self::AboveLimit => "above the limit value",
        })
    }
}

/// Classifies a daily exposure `A(8)` [m/s²] against [`EU_ACTION_VALUE_A8`] and
/// [`EU_LIMIT_VALUE_A8`]. A value is "above" only when it exceeds the threshold (the
/// directive's wording); NaN is classified, conservatively, as
/// [`ExposureVerdict::AboveLimit`].
pub fn exposure_verdict(a8: f64) -> ExposureVerdict {
    if a8.is_nan() || a8 > EU_LIMIT_VALUE_A8 {
        ExposureVerdict::AboveLimit
    } else if a8 > EU_ACTION_VALUE_A8 {
        ExposureVerdict::AboveAction
    } else {
        ExposureVerdict::BelowAction
    }
}

/// Daily exposure time \[h\] after which a weighted RMS `aw` [m/s²] reaches the daily
/// exposure `a8_value` [m/s²]: `T = 8 h · (a8_value / aw)²`. For example
/// `time_to_reach(aw, EU_ACTION_VALUE_A8)`. A zero `aw` gives ∞ (never reached).
pub fn time_to_reach(aw: f64, a8_value: f64) -> f64 {
    REFERENCE_DURATION_H * (a8_value / aw).powi(2)
}

/// `Ok` if the sample rate is finite and positive.
fn check_sample_rate(sample_rate_hz: f64) -> Result<(), MetricsError> {
    if sample_rate_hz.is_finite() && sample_rate_hz > 0.0 {
        Ok(())
    } else {
        Err(MetricsError::InvalidSampleRate { sample_rate_hz })
    }
}

/// Number of samples with `t = i/fs < settle_s`, robust to rounding in `settle_s·fs`.
fn settle_samples(settle_s: f64, sample_rate_hz: f64) -> usize {
    let x = settle_s * sample_rate_hz;
    let nearest = x.round();
    let count = if (x - nearest).abs() <= 1e-9 * nearest.max(1.0) {
        nearest
    } else {
        x.ceil()
    };
    // Float-to-int `as` saturates; the caller has checked that settle_s is finite.
    count as usize
}

/// `max(p, |v|)` that propagates NaN.
fn max_abs(p: f64, v: f64) -> f64 {
    let a = v.abs();
    if a > p || a.is_nan() { a } else { p }
}

/// `num / den`, or 0 if `den` is 0.
fn ratio_or_zero(num: f64, den: f64) -> f64 {
    if den == 0.0 { 0.0 } else { num / den }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sine(amplitude: f64, freq_hz: f64, fs: f64, n: usize) -> Vec<f64> {
        (0..n)
            .map(|i| amplitude * (2.0 * PI * freq_hz * i as f64 / fs).sin())
            .collect()
    }

    fn rel(a: f64, b: f64) -> f64 {
        ((a - b) / b).abs()
    }

    #[test]
    fn rms_peak_crest_of_simple_signals() {
        let x = [3.0, -4.0];
        assert!((rms(&x) - (12.5_f64).sqrt()).abs() < 1e-15);
        assert_eq!(peak(&x), 4.0);
        assert!((crest_factor(&x) - 4.0 / 12.5_f64.sqrt()).abs() < 1e-15);

        // A sine over whole periods: RMS = A/√2, crest = √2.
        let s = sine(2.0, 5.0, 1000.0, 1000);
        assert!(rel(rms(&s), 2.0 / 2f64.sqrt()) < 1e-12);
        assert!(rel(peak(&s), 2.0) < 1e-12);
        assert!(rel(crest_factor(&s), 2f64.sqrt()) < 1e-12);
    }

    #[test]
    fn empty_and_zero_signals_give_zero() {
        assert_eq!(rms(&[]), 0.0);
        assert_eq!(peak(&[]), 0.0);
        assert_eq!(crest_factor(&[]), 0.0);
        assert_eq!(crest_factor(&[0.0, 0.0]), 0.0);
        assert_eq!(vdv(&[], 1000.0), 0.0);
        assert_eq!(wk_weight(&[], 1000.0), Ok(Vec::new()));
        assert_eq!(
            vibration_metrics(&[], 1000.0, 0.0),
            Err(MetricsError::EmptySignal)
        );
        let running = RunningMetrics::new(1000.0).expect("valid rate");
        assert_eq!(running.metrics(), VibrationMetrics::default());
    }

    #[test]
    fn nan_propagates() {
        assert!(peak(&[1.0, f64::NAN, 2.0]).is_nan());
        assert!(rms(&[1.0, f64::NAN]).is_nan());
    }

    /// ISO 2631-1:1997 Table 3, weighting Wk, as factors (the table prints factor × 1000).
    const ISO_TABLE_3_WK: [(f64, f64); 16] = [
        (0.1, 0.0312),
        (0.5, 0.418),
        (1.0, 0.482),
        (2.0, 0.531),
        (4.0, 0.967),
        (5.0, 1.039),
        (6.3, 1.054),
        (8.0, 1.036),
        (10.0, 0.988),
        (12.5, 0.902),
        (16.0, 0.768),
        (20.0, 0.636),
        (31.5, 0.405),
        (63.0, 0.186),
        (80.0, 0.132),
        (100.0, 0.0887),
    ];

    #[test]
    fn wk_response_matches_iso_2631_table_3() {
        // The table is evaluated at the nominal band frequencies and printed to three
        // significant figures; the analytic filter reproduces it to 0.3 %.
        for (f, expected) in ISO_TABLE_3_WK {
            let (mag, _) = wk_response(f);
            assert!(
                rel(mag, expected) < 0.005,
                "Wk at {f} Hz: {mag:.4}, table {expected}"
            );
        }
    }

    #[test]
    fn wk_response_limits_and_phase() {
        // Flat region shapes: gain → 0 at DC and at high frequency.
        assert_eq!(wk_response(0.0).0, 0.0);
        assert!(wk_response(0.01).0 < 1e-3);
        assert!(wk_response(1000.0).0 < 0.01);
        // Low-frequency phase → +π (second-order high-pass), high → −3π/2.
        assert!((wk_response(1e-4).1 - PI).abs() < 1e-3);
        assert!((wk_response(1e6).1 + 1.5 * PI).abs() < 1e-2);
        // The continuous phase agrees, modulo 2π, with the argument of the product H(jω).
        for f in [0.3, 1.0, 3.0, 8.0, 12.5, 40.0, 150.0] {
            let (_, phase) = wk_response(f);
            let w = 2.0 * PI * f;
            let (re, im) = wk_sections(|o| o).iter().fold((1.0, 0.0), |(r, i), s| {
                let (m, p) = s.response(w);
                let (sr, si) = (m * p.cos(), m * p.sin());
                (r * sr - i * si, r * si + i * sr)
            });
            let diff = (phase - im.atan2(re)).rem_euclid(2.0 * PI);
            assert!(diff < 1e-9 || 2.0 * PI - diff < 1e-9, "f = {f}");
        }
        assert!(wk_response(f64::NAN).0.is_nan());
    }

    /// Steady-state gain of the digital filter, measured as the RMS ratio of a sine over
    /// whole periods after the transient.
    fn measured_gain(fs: f64, f: f64) -> f64 {
        let settle = (30.0 * fs) as usize; // HP at 0.4 Hz: transient ≪ 30 s
        let cycles = (20.0 * f).ceil().max(10.0);
        let window = (cycles * fs / f).round() as usize;
        let x = sine(1.0, f, fs, settle + window);
        let y = wk_weight(&x, fs).expect("valid rate");
        rms(&y[settle..]) / rms(&x[settle..])
    }

    #[test]
    fn digital_filter_gain_matches_analogue_within_1_percent() {
        let fs = 1000.0;
        let filter = WkFilter::new(fs).expect("valid rate");
        // Third-octave centres from 0.5 Hz to 50 Hz.
        let freqs = [
            0.5, 0.63, 0.8, 1.0, 1.25, 1.6, 2.0, 2.5, 3.15, 4.0, 5.0, 6.3, 8.0, 10.0, 12.5, 16.0,
            20.0, 25.0, 31.5, 40.0, 50.0,
        ];
        for f in freqs {
            let (exact, _) = wk_response(f);
            let measured = measured_gain(fs, f);
            assert!(
                rel(measured, exact) < 0.01,
                "{f} Hz: digital {measured:.5}, analogue {exact:.5}"
            );
            // The transfer-function gain agrees with the measured one.
            assert!(rel(filter.gain_at(f), measured) < 1e-3, "{f} Hz");
        }
    }

    #[test]
    fn digital_filter_is_accurate_at_the_characteristic_frequencies() {
        // Pre-warping puts each section's characteristic frequencies where the standard
        // has them, so the cascade follows the analogue filter there even at 250 Hz.
        for fs in [250.0, 500.0, 1000.0, 5000.0] {
            let filter = WkFilter::new(fs).expect("valid rate");
            for f in [0.4, 2.37, 3.35, 12.5] {
                assert!(
                    rel(filter.gain_at(f), wk_response(f).0) < 0.01,
                    "fs {fs}, f {f}: {} vs {}",
                    filter.gain_at(f),
                    wk_response(f).0
                );
            }
        }
    }

    #[test]
    fn filter_streaming_reset_and_dc_rejection() {
        let fs = 500.0;
        let x = sine(1.0, 3.0, fs, 2000);
        let batch = wk_weight(&x, fs).expect("valid rate");
        let mut filter = WkFilter::new(fs).expect("valid rate");
        let streamed: Vec<f64> = x.iter().map(|&v| filter.filter(v)).collect();
        assert_eq!(batch, streamed);
        filter.reset();
        let again: Vec<f64> = x.iter().map(|&v| filter.filter(v)).collect();
        assert_eq!(batch, again);
        assert_eq!(filter.sample_rate_hz(), fs);

        // A constant input (gravity offset) is removed by the 0.4 Hz high-pass.
        filter.reset();
        let last = (0..(60.0 * fs) as usize).fold(0.0, |_, _| filter.filter(9.81));
        assert!(last.abs() < 1e-6, "DC residue {last}");
    }

    #[test]
    fn sample_rate_errors() {
        let err = WkFilter::new(200.0).expect_err("too slow");
        assert_eq!(
            err,
            MetricsError::SampleRateTooLow {
                sample_rate_hz: 200.0,
                min_hz: MIN_SAMPLE_RATE_HZ
            }
        );
        let msg = err.to_string();
        assert!(
            msg.contains("200") && msg.contains("250") && msg.contains("100 Hz"),
            "{msg}"
        );
        for bad in [0.0, -1000.0, f64::NAN, f64::INFINITY] {
            assert!(matches!(
                WkFilter::new(bad),
                Err(MetricsError::InvalidSampleRate { .. })
            ));
            assert!(vdv(&[1.0], bad).is_nan());
        }
        assert!(WkFilter::new(MIN_SAMPLE_RATE_HZ).is_ok());
        assert!(wk_weight(&[1.0], 100.0).is_err());
        assert!(vibration_metrics(&[1.0], 100.0, 0.0).is_err());
        assert!(RunningMetrics::new(100.0).is_err());
    }

    #[test]
    fn vdv_of_a_sine_matches_the_analytic_integral() {
        // ∫₀ᵀ (A sin ωt)⁴ dt = 3A⁴T/8 over whole periods.
        let (amplitude, f, fs, duration) = (1.7, 4.0, 1000.0, 10.0);
        let x = sine(amplitude, f, fs, (duration * fs) as usize);
        let expected = (3.0 * amplitude.powi(4) * duration / 8.0).powf(0.25);
        assert!(rel(vdv(&x, fs), expected) < 1e-12);
        // A constant: VDV = a·T^(1/4).
        let c = vec![2.0; 4000];
        assert!(rel(vdv(&c, 1000.0), 2.0 * 4f64.powf(0.25)) < 1e-12);
    }

    #[test]
    fn vibration_metrics_of_a_sine() {
        let (amplitude, f, fs): (f64, f64, f64) = (1.0, 6.3, 1000.0);
        let settle: f64 = 20.0;
        let window_s = 100.0 / f; // 100 whole periods
        let n = ((settle + window_s) * fs).round() as usize;
        let x = sine(amplitude, f, fs, n);
        let m = vibration_metrics(&x, fs, settle).expect("valid input");
        let w = wk_response(f).0;
        assert!(rel(m.rms, amplitude / 2f64.sqrt()) < 1e-3);
        assert!(rel(m.peak, amplitude) < 1e-3);
        assert!(rel(m.aw, w * amplitude / 2f64.sqrt()) < 0.01);
        assert!(rel(m.crest_factor, 2f64.sqrt()) < 0.01);
        let expected_vdv = (3.0 * (w * amplitude).powi(4) * window_s / 8.0).powf(0.25);
        assert!(rel(m.vdv, expected_vdv) < 0.01);
        assert!((m.duration_s - (n - (settle * fs) as usize) as f64 / fs).abs() < 1e-12);

        // Without settling, the whole signal is counted.
        let whole = vibration_metrics(&x, fs, 0.0).expect("valid input");
        assert!((whole.duration_s - n as f64 / fs).abs() < 1e-12);
    }

    #[test]
    fn settling_interval_excludes_initial_samples() {
        let fs = 1000.0;
        // A large initial shock then a quiet sine: settling hides the shock from the
        // unweighted statistics.
        let mut x = sine(0.1, 5.0, fs, 5000);
        x[10] = 50.0;
        let m = vibration_metrics(&x, fs, 1.0).expect("valid input");
        assert!(m.peak < 0.11);
        assert!((m.duration_s - 4.0).abs() < 1e-12);
        let all = vibration_metrics(&x, fs, 0.0).expect("valid input");
        assert_eq!(all.peak, 50.0);

        // 0.3 s at 1 kHz skips exactly 300 samples despite 0.3·1000 = 300.00000000000006.
        assert_eq!(settle_samples(0.3, 1000.0), 300);
        assert_eq!(settle_samples(0.0, 1000.0), 0);
        assert_eq!(settle_samples(0.0015, 1000.0), 2);

        assert_eq!(
            vibration_metrics(&x, fs, 5.0),
            Err(MetricsError::SettleTooLong {
                settle_s: 5.0,
                duration_s: 5.0
            })
        );
        for bad in [-1.0, f64::NAN, f64::INFINITY] {
            assert!(matches!(
                vibration_metrics(&x, fs, bad),
                Err(MetricsError::InvalidSettle { .. })
            ));
        }
    }

    fn pseudo_random_ride(n: usize, fs: f64) -> Vec<f64> {
        // Deterministic broadband-ish signal: a few sines plus an LCG noise.
        let mut state: u64 = 0x2545_f491_4f6c_dd1d;
        (0..n)
            .map(|i| {
                state = state
                    .wrapping_mul(6_364_136_223_846_793_005)
                    .wrapping_add(1_442_695_040_888_963_407);
                let noise = (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
                let t = i as f64 / fs;
                0.8 * (2.0 * PI * 1.3 * t).sin() + 0.5 * (2.0 * PI * 4.7 * t).sin() + noise
            })
            .collect()
    }

    #[test]
    fn running_metrics_equal_batch_metrics() {
        let fs = 1000.0;
        let x = pseudo_random_ride(12_345, fs);
        let batch = vibration_metrics(&x, fs, 0.0).expect("valid input");
        let mut running = RunningMetrics::new(fs).expect("valid rate");
        for &v in &x {
            running.push(v);
        }
        let live = running.metrics();
        for (a, b) in [
            (live.rms, batch.rms),
            (live.peak, batch.peak),
            (live.aw, batch.aw),
            (live.vdv, batch.vdv),
            (live.crest_factor, batch.crest_factor),
            (live.duration_s, batch.duration_s),
        ] {
            assert!(rel(a, b) < 1e-9, "{a} vs {b}");
        }
        assert_eq!(running.samples_pushed(), x.len());

        // Batch statistics agree with the free functions.
        let y = wk_weight(&x, fs).expect("valid rate");
        assert!(rel(batch.rms, rms(&x)) < 1e-9);
        assert!(rel(batch.peak, peak(&x)) < 1e-12);
        assert!(rel(batch.aw, rms(&y)) < 1e-9);
        assert!(rel(batch.vdv, vdv(&y, fs)) < 1e-9);
        assert!(rel(batch.crest_factor, crest_factor(&y)) < 1e-9);

        // With a settling interval too.
        let settled = vibration_metrics(&x, fs, 2.5).expect("valid input");
        let mut running = RunningMetrics::with_settle(fs, 2.5).expect("valid input");
        x.iter().for_each(|&v| running.push(v));
        assert_eq!(running.metrics(), settled);

        // Reset starts over.
        running.reset();
        assert_eq!(running.metrics(), VibrationMetrics::default());
        assert_eq!(running.samples_pushed(), 0);
        x.iter().for_each(|&v| running.push(v));
        assert_eq!(running.metrics(), settled);
    }

    #[test]
    fn seat_value() {
        assert!((seat_percent(0.4, 0.8) - 50.0).abs() < 1e-12);
        assert!((seat_percent(1.0, 1.0) - 100.0).abs() < 1e-12);
        assert!(!seat_percent(1.0, 0.0).is_finite());
    }

    #[test]
    fn daily_exposure() {
        assert!((a8(1.0, 8.0) - 1.0).abs() < 1e-15);
        assert!((a8(1.0, 2.0) - 0.5).abs() < 1e-15);
        assert!((a8(0.6, 4.5) - 0.6 * (4.5f64 / 8.0).sqrt()).abs() < 1e-15);
        assert!(a8(1.0, -1.0).is_nan());

        assert_eq!(exposure_verdict(0.3), ExposureVerdict::BelowAction);
        assert_eq!(exposure_verdict(0.5), ExposureVerdict::BelowAction);
        assert_eq!(exposure_verdict(0.51), ExposureVerdict::AboveAction);
        assert_eq!(exposure_verdict(1.15), ExposureVerdict::AboveAction);
        assert_eq!(exposure_verdict(1.2), ExposureVerdict::AboveLimit);
        assert_eq!(exposure_verdict(f64::NAN), ExposureVerdict::AboveLimit);
        assert_eq!(
            ExposureVerdict::AboveAction.to_string(),
            "above the action value"
        );

        // time_to_reach inverts a8.
        let aw = 0.7;
        let t_action = time_to_reach(aw, EU_ACTION_VALUE_A8);
        assert!((a8(aw, t_action) - EU_ACTION_VALUE_A8).abs() < 1e-12);
        let t_limit = time_to_reach(aw, EU_LIMIT_VALUE_A8);
        assert!((a8(aw, t_limit) - EU_LIMIT_VALUE_A8).abs() < 1e-12);
        assert!((time_to_reach(0.5, 0.5) - 8.0).abs() < 1e-12);
        assert_eq!(time_to_reach(0.0, 0.5), f64::INFINITY);
    }
}
