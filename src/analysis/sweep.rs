//! Simulated frequency responses: open-loop valve sine dwells (Bode), closed-loop platform
//! sine dwells (transmissibility), a valve chirp, and the parallel sweep over frequencies that
//! runs them. These run the models in time ([`crate::experiments`]); the analytic and
//! linearised responses they are checked against are in [`super::frequency_response`].

use crate::experiments;
use crate::model::ModelKind;
use crate::params::Params;
use crate::scenario::{CommandSignal, PlatformMotion, PlatformSine};
use crate::simulation::{Drive, SimError, step_for_rate};
use num_complex::Complex64;
use rayon::prelude::*;
use std::f64::consts::PI;

/// First harmonic `(2/T)·∫ s(t)·e^(−jωt) dt` of uniformly sampled data over an integer number
/// of periods ending at the last sample (trapezoidal rule).
pub fn first_harmonic(values: &[f64], dt: f64, t0: f64, freq_hz: f64, periods: usize) -> Complex64 {
    let w = 2.0 * PI * freq_hz;
    let t_window = periods as f64 / freq_hz;
    let n_window = (t_window / dt).round() as usize;
    if values.len() < n_window + 1 || n_window == 0 {
        return Complex64::new(f64::NAN, f64::NAN);
    }
    let start = values.len() - 1 - n_window;
    let mut acc = Complex64::new(0.0, 0.0);
    for (k, v) in values[start..].iter().enumerate() {
        let t = t0 + (start + k) as f64 * dt;
        let weight = if k == 0 || k == n_window { 0.5 } else { 1.0 };
        acc += weight * v * Complex64::new(0.0, -w * t).exp();
    }
    acc * 2.0 * dt / (n_window as f64 * dt)
}

/// Options of a simulated sine dwell.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DwellOptions {
    /// Settling time before the analysis window [s].
    pub settle_s: f64,
    /// Minimum analysis window [s] (rounded up to whole periods, at least 2).
    pub min_window_s: f64,
}

impl Default for DwellOptions {
    fn default() -> Self {
        Self {
            settle_s: 0.25,
            min_window_s: 0.5,
        }
    }
}

fn dwell_periods(freq_hz: f64, opt: &DwellOptions) -> usize {
    ((opt.min_window_s * freq_hz).ceil() as usize).max(2)
}

/// `u̇/V_in` of a model by an open-loop sine dwell `V = A·cos(2πft)`, platform still.
pub fn simulated_bode(
    params: &Params,
    kind: ModelKind,
    freq_hz: f64,
    amplitude_v: f64,
    opt: &DwellOptions,
) -> Result<Complex64, SimError> {
    let periods = dwell_periods(freq_hz, opt);
    let t_end = opt.settle_s + periods as f64 / freq_hz;
    let rate = 1.0 / step_for_rate(params.numerics.max_step_s, 1.0 / params.numerics.max_step_s);
    let trace = experiments::valve_sine(params, kind, freq_hz, amplitude_v, t_end, rate)?;
    let dt = 1.0 / rate;
    let du = trace.channel(|s| s.du);
    let v = trace.channel(|s| s.v_in);
    let du1 = first_harmonic(&du, dt, 0.0, freq_hz, periods);
    let v1 = first_harmonic(&v, dt, 0.0, freq_hz, periods);
    Ok(du1 / v1)
}

/// Platform acceleration amplitude of a transmissibility dwell [m/s²]: 0.5 m/s², reduced at
/// low frequency so the platform moves at most 5 mm (keeps the stroke far from its stops).
pub fn dwell_platform_acceleration(freq_hz: f64) -> f64 {
    let w = 2.0 * PI * freq_hz;
    0.5_f64.min(w * w * 0.005)
}

/// `ÿ/ẍ` of a model by a closed-loop platform sine dwell (fade-in 1 s, then settle).
pub fn simulated_transmissibility(
    params: &Params,
    kind: ModelKind,
    freq_hz: f64,
    opt: &DwellOptions,
) -> Result<Complex64, SimError> {
    let w = 2.0 * PI * freq_hz;
    let amp = dwell_platform_acceleration(freq_hz) / (w * w);
    let periods = dwell_periods(freq_hz, opt).max((1.0 * freq_hz).ceil() as usize);
    let fade = 1.0;
    let t_end = fade + 2.0 + opt.settle_s + periods as f64 / freq_hz;
    let h = step_for_rate(params.numerics.max_step_s, 1000.0);
    let platform = PlatformMotion::Sine(PlatformSine {
        amplitude_m: amp,
        freq_hz,
        fade_in_s: fade,
    });
    let trace = experiments::run(
        params,
        kind,
        experiments::closed_loop(params),
        platform,
        t_end,
        1.0 / h,
    )?;
    let ydd = trace.channel(|s| s.ydd);
    let xdd = trace.channel(|s| s.xdd);
    Ok(first_harmonic(&ydd, h, 0.0, freq_hz, periods)
        / first_harmonic(&xdd, h, 0.0, freq_hz, periods))
}

/// Runs `f` on every item in parallel (rayon), keeping the order.
pub fn sweep<T: Sync, R: Send>(items: &[T], f: impl Fn(&T) -> R + Sync + Send) -> Vec<R> {
    items.par_iter().map(f).collect()
}

/// A valve chirp on the twin (platform still): useful for a quick Bode by FFT.
pub fn chirp_drive(amplitude_v: f64, f0_hz: f64, f1_hz: f64, duration_s: f64) -> Drive {
    Drive::OpenLoop(CommandSignal::Chirp {
        amplitude_v,
        f0_hz,
        f1_hz,
        duration_s,
    })
}
