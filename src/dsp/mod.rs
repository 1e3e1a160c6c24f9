//! Signal processing shared by the vibration metrics (`analysis::metrics`) and the
//! identification (`identify::replay`): the RMS, noise estimates, band splits and spectra
//! here; second-order IIR sections (biquads), their design from analogue prototypes,
//! Butterworth low-passes and zero-phase (forward–backward) filtering of whole records in
//! [`filters`] (re-exported here).
//!
//! [`noise_rms`] estimates a channel's sensor noise from the top of its spectrum, [`spectrum`]
//! gives a Hann-windowed amplitude spectrum.
//!
//! All functions are pure; none panics on empty input.

pub mod filters;

pub use filters::*;

use num_complex::Complex64;
use realfft::RealFftPlanner;
use std::f64::consts::PI;

/// Root mean square of `x` (0 for an empty slice) [same unit as `x`].
pub fn rms(x: &[f64]) -> f64 {
    if x.is_empty() {
        return 0.0;
    }
    (x.iter().map(|v| v * v).sum::<f64>() / x.len() as f64).sqrt()
}

/// RMS gain of a linear operator on white noise of unit variance: `√Σh²` of its impulse
/// response at the middle of a record of `len` samples (at most 4096).
pub fn noise_gain(len: usize, op: impl Fn(&[f64]) -> Vec<f64>) -> f64 {
    let n = len.clamp(16, 4096);
    let mut x = vec![0.0; n];
    x[n / 2] = 1.0;
    op(&x).iter().map(|v| v * v).sum::<f64>().sqrt()
}

/// Runs `f` with this thread's FFT planner for transforms of length `n`. The planner keeps
/// the plans (and their twiddle factors) it made, since a calibration takes the spectra of
/// the same record lengths again and again; it starts afresh after [`PLANNED_LENGTHS`]
/// lengths, so that a long-running app holds a bounded number of plans.
fn with_planner<R>(n: usize, f: impl FnOnce(&mut RealFftPlanner<f64>) -> R) -> R {
    use std::cell::RefCell;
    use std::collections::BTreeSet;
    thread_local! {
        static PLANNER: RefCell<(RealFftPlanner<f64>, BTreeSet<usize>)> =
            RefCell::new((RealFftPlanner::new(), BTreeSet::new()));
    }
    PLANNER.with(|cell| {
        let mut cell = cell.borrow_mut();
        let (planner, lengths) = &mut *cell;
        if lengths.insert(n) && lengths.len() > PLANNED_LENGTHS {
            *planner = RealFftPlanner::new();
            lengths.clear();
            lengths.insert(n);
        }
        f(planner)
    })
}

/// How many transform lengths a thread's planner keeps plans for ([`with_planner`]).
const PLANNED_LENGTHS: usize = 64;

/// Noise RMS of a raw channel, estimated from the top of its spectrum: the power in
/// `[0.3, 0.5]·fs` (where the rig's motion has almost nothing) extrapolated to the whole band
/// as white noise. Includes quantisation (which is white at these levels).
pub fn noise_rms(x: &[f64], dt: f64) -> f64 {
    let _ = dt;
    let n = x.len();
    if n < 32 {
        return 0.0;
    }
    let mean = x.iter().sum::<f64>() / n as f64;
    let mut buf: Vec<f64> = x.iter().map(|v| v - mean).collect();
    let fft = with_planner(n, |p| p.plan_fft_forward(n));
    let mut spec = fft.make_output_vec();
    if fft.process(&mut buf, &mut spec).is_err() {
        return 0.0;
    }
    let m = spec.len();
    let lo = (0.6 * (m as f64)) as usize;
    let band: f64 = spec[lo..m].iter().map(|c| c.norm_sqr()).sum();
    let fraction = (m - lo) as f64 / m as f64;
    // Parseval for a real FFT: Σx² ≈ (2/n)·Σ_k |X_k|² over the half spectrum.
    let power = 2.0 * band / (n as f64 * n as f64);
    (power / fraction).sqrt()
}

/// A channel's sensor noise as the raw error measure holds a residual against it
/// ([`noise_floor`]).
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
pub struct NoiseFloor {
    /// Estimated RMS of the channel's white noise, quantisation included [unit of the channel].
    pub rms: f64,
    /// Quantisation step when the samples lie on a grid (a 12-bit stroke sensor: its LSB),
    /// else 0 [unit of the channel].
    pub lsb: f64,
}

/// Estimates the white-noise RMS of a measured channel from the channel itself, three ways,
/// and keeps the smallest that the quantisation allows:
///
/// * the top 40 % of the spectrum of the linearly detrended, Hann-windowed signal (a seat
///   rig's motion lies far below it; the window and the detrend keep the record's ends and
///   its drift from leaking up there);
/// * the fourth difference `x[i] − 4x[i−1] + 6x[i−2] − 4x[i−3] + x[i−4]`, which multiplies
///   white noise power by 70 and a signal at `f` by `(2 sin(π f dt))⁸`, through its median
///   absolute deviation (robust to a start transient): `σ = 1.4826·MAD/√70`;
/// * the quantisation step `q` (the smallest change between samples, when every change is a
///   multiple of it): `σ ≥ q/√12`.
///
/// Each of the first two can only be raised by the signal, never lowered, so the smaller is
/// the better bound. Returns zeros for fewer than 32 samples.
pub fn noise_floor(x: &[f64]) -> NoiseFloor {
    let n = x.len();
    if n < 32 {
        return NoiseFloor::default();
    }
    // Spectral estimate on the detrended, windowed signal.
    let (a, b) = (x[0], x[n - 1]);
    let mut buf: Vec<f64> = x
        .iter()
        .enumerate()
        .map(|(i, v)| {
            let trend = a + (b - a) * i as f64 / (n - 1) as f64;
            let w = 0.5 - 0.5 * (2.0 * PI * i as f64 / (n - 1) as f64).cos();
            (v - trend) * w
        })
        .collect();
    let mean_w2 = 3.0 / 8.0;
    let fft = with_planner(n, |p| p.plan_fft_forward(n));
    let mut spec = fft.make_output_vec();
    let spectral = if fft.process(&mut buf, &mut spec).is_ok() {
        let m = spec.len();
        let lo = (0.6 * m as f64) as usize;
        let band: f64 = spec[lo..m].iter().map(|c| c.norm_sqr()).sum();
        let power = 2.0 * band / (n as f64 * n as f64) / mean_w2;
        (power / ((m - lo) as f64 / m as f64)).sqrt()
    } else {
        f64::INFINITY
    };
    // The spectrum's buffers go before the difference's, so that a long record's estimate
    // holds one record-length buffer at a time (the replay's memory per row).
    drop((buf, spec));
    // Fourth-difference estimate; the deviations from the median in the same buffer.
    let mut d4: Vec<f64> = x
        .windows(5)
        .map(|w| w[4] - 4.0 * w[3] + 6.0 * w[2] - 4.0 * w[1] + w[0])
        .collect();
    let med = median(&mut d4);
    for d in &mut d4 {
        *d = (*d - med).abs();
    }
    let differenced = 1.4826 * median(&mut d4) / 70f64.sqrt();
    let lsb = quantisation_step(x);
    NoiseFloor {
        rms: spectral.min(differenced).max(lsb / 12f64.sqrt()),
        lsb,
    }
}

/// Median of `v` (reordered in place; 0 when empty).
fn median(v: &mut [f64]) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    let k = v.len() / 2;
    *v.select_nth_unstable_by(k, f64::total_cmp).1
}

/// The step of the grid the samples lie on: the smallest non-zero change between successive
/// samples, if every change is a whole multiple of it (to 2 % of the step) and it is not
/// below 1e-12 of the signal's range; else 0.
pub fn quantisation_step(x: &[f64]) -> f64 {
    let range = x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let changes: Vec<f64> = x
        .windows(2)
        .map(|w| (w[1] - w[0]).abs())
        .filter(|d| *d > 1e-12 * range.max(1e-300))
        .collect();
    let Some(q) = changes.iter().copied().reduce(f64::min) else {
        return 0.0;
    };
    let on_grid = changes.iter().all(|d| {
        let k = d / q;
        (k - k.round()).abs() < 0.02
    });
    if on_grid && changes.len() >= 16 {
        q
    } else {
        0.0
    }
}

/// Splits `x` into frequency bands: for each `[lo, hi)` of `bands_hz` the part of `x` whose
/// Fourier components lie in it (brick-wall masks on the record's DFT, so the parts add up to
/// `x` exactly when the bands tile 0 … Nyquist). The straight line through the means of the
/// first and the last 5 % of the record is taken out first and given whole to the band that holds 0 Hz, with the mean:
/// the DFT sees the record as periodic, and the jump between a drifting record's ends would
/// otherwise leak into every band.
pub fn band_parts(x: &[f64], dt: f64, bands_hz: &[[f64; 2]]) -> Vec<Vec<f64>> {
    let n = x.len();
    if n < 2 {
        return bands_hz
            .iter()
            .map(|b| {
                if b[0] <= 0.0 {
                    x.to_vec()
                } else {
                    vec![0.0; n]
                }
            })
            .collect();
    }
    // The line through the means of the first and last 5 % (so that the noise of two single
    // samples does not tilt it).
    let m = (n / 20).max(1);
    let mean = |s: &[f64]| s.iter().sum::<f64>() / s.len() as f64;
    let (a, b) = (mean(&x[..m]), mean(&x[n - m..]));
    let (ia, ib) = ((m - 1) as f64 / 2.0, (n - 1) as f64 - (m - 1) as f64 / 2.0);
    let slope = if ib > ia { (b - a) / (ib - ia) } else { 0.0 };
    let ramp = |i: usize| a + slope * (i as f64 - ia);
    let (fwd, inv) = with_planner(n, |p| (p.plan_fft_forward(n), p.plan_fft_inverse(n)));
    let mut buf: Vec<f64> = x.iter().enumerate().map(|(i, v)| v - ramp(i)).collect();
    let mut spec = fwd.make_output_vec();
    if fwd.process(&mut buf, &mut spec).is_err() {
        return bands_hz.iter().map(|_| vec![0.0; n]).collect();
    }
    let df = 1.0 / (n as f64 * dt);
    bands_hz
        .iter()
        .map(|b| {
            let mut s: Vec<Complex64> = spec
                .iter()
                .enumerate()
                .map(|(k, c)| {
                    let f = k as f64 * df;
                    if f >= b[0] && f < b[1] {
                        *c
                    } else {
                        Complex64::new(0.0, 0.0)
                    }
                })
                .collect();
            // The inverse of a real signal's spectrum needs real DC and Nyquist bins.
            s[0].im = 0.0;
            if n.is_multiple_of(2) {
                let last = s.len() - 1;
                s[last].im = 0.0;
            }
            let mut out = inv.make_output_vec();
            if inv.process(&mut s, &mut out).is_err() {
                return vec![0.0; n];
            }
            let with_dc = b[0] <= 0.0 && b[1] > 0.0;
            out.iter()
                .enumerate()
                .map(|(i, v)| v / n as f64 + if with_dc { ramp(i) } else { 0.0 })
                .collect()
        })
        .collect()
}

/// Amplitude spectrum of a signal: `(frequency [Hz], RMS amplitude density)` on a Hann window.
pub fn spectrum(x: &[f64], dt: f64) -> (Vec<f64>, Vec<f64>) {
    let n = x.len();
    if n < 8 {
        return (Vec::new(), Vec::new());
    }
    let mean = x.iter().sum::<f64>() / n as f64;
    let mut buf: Vec<f64> = x
        .iter()
        .enumerate()
        .map(|(i, v)| {
            let w = 0.5 - 0.5 * (2.0 * std::f64::consts::PI * i as f64 / (n - 1) as f64).cos();
            (v - mean) * w
        })
        .collect();
    let fft = with_planner(n, |p| p.plan_fft_forward(n));
    let mut spec = fft.make_output_vec();
    if fft.process(&mut buf, &mut spec).is_err() {
        return (Vec::new(), Vec::new());
    }
    let df = 1.0 / (n as f64 * dt);
    let scale = (2.0 * dt / (0.375 * n as f64)).sqrt();
    let f = (0..spec.len()).map(|k| k as f64 * df).collect();
    let a = spec.iter().map(|c| c.norm() * scale).collect();
    (f, a)
}

#[cfg(test)]
mod tests {
    use super::*;

    pub(super) fn sine(a: f64, f: f64, dt: f64, n: usize, phase: f64) -> Vec<f64> {
        (0..n)
            .map(|i| a * (2.0 * PI * f * i as f64 * dt + phase).sin())
            .collect()
    }

    /// RMS of a sine of amplitude A over whole periods is A/√2; of a constant, its magnitude.
    #[test]
    fn rms_of_a_sine_is_amplitude_over_root_two() {
        let (a, f, dt) = (3.7, 5.0, 1e-3);
        // 2 s = 10 whole periods.
        let x = sine(a, f, dt, 2000, 0.3);
        assert!((rms(&x) - a / 2f64.sqrt()).abs() < 1e-12 * a, "{}", rms(&x));
        assert_eq!(rms(&[-2.0; 7]), 2.0);
        assert_eq!(rms(&[]), 0.0);
    }

    /// White-noise gain: 1 for the identity; for a moving average of m samples, 1/√m.
    #[test]
    fn noise_gain_of_known_operators() {
        assert!((noise_gain(100, |x| x.to_vec()) - 1.0).abs() < 1e-12);
        let avg4 = |x: &[f64]| -> Vec<f64> {
            (0..x.len())
                .map(|i| x[i.saturating_sub(3)..=i].iter().sum::<f64>() / 4.0)
                .collect()
        };
        assert!((noise_gain(100, avg4) - 0.5).abs() < 1e-12);
    }

    /// The spectrum of a sine peaks at its frequency; the noise estimate of white noise of
    /// σ under a slow sine is σ (the sine's power lies far below the band it looks at).
    #[test]
    fn spectrum_peak_and_noise_estimate() {
        let (dt, n) = (1e-3, 4000);
        let x = sine(2.0, 50.0, dt, n, 0.0);
        let (f, a) = spectrum(&x, dt);
        let k = (0..a.len()).max_by(|&i, &j| a[i].total_cmp(&a[j])).unwrap();
        assert!((f[k] - 50.0).abs() < 0.5, "{}", f[k]);
        // A deterministic white sequence (xorshift), σ = 0.1, over a 2 Hz sine of amplitude 5.
        let mut s: u64 = 0x9e37_79b9_7f4a_7c15;
        let noise: Vec<f64> = (0..n)
            .map(|_| {
                s ^= s << 13;
                s ^= s >> 7;
                s ^= s << 17;
                // Uniform on [−√3, √3]·σ has standard deviation σ.
                0.1 * 3f64.sqrt() * (2.0 * (s >> 11) as f64 / (1u64 << 53) as f64 - 1.0)
            })
            .collect();
        let y: Vec<f64> = sine(5.0, 2.0, dt, n, 0.0)
            .iter()
            .zip(&noise)
            .map(|(a, b)| a + b)
            .collect();
        let est = noise_rms(&y, dt);
        assert!(
            (est / rms(&noise) - 1.0).abs() < 0.1,
            "{est} vs {}",
            rms(&noise)
        );
        assert_eq!(noise_rms(&[1.0; 10], dt), 0.0);
    }
}
