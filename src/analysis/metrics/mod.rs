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
//! The Wk weighting (design, analogue response, digital filter) is in `wk`, the tests in
//! `tests`; everything public is re-exported here.
//!
//! # Edge cases
//!
//! No function panics. The plain statistics return 0 for an empty signal; the functions
//! that need a sample rate or a non-empty signal return a [`MetricsError`]. NaN samples
//! propagate to the results (NaN in, NaN out).

mod wk;

pub use wk::{WkFilter, wk_response, wk_weight};

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
        self.acc.metrics(self.filter.sample_rate_hz())
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
mod tests;
