//! Frequency responses by simulation: open-loop valve sine dwells (`u̇/V_in`), closed-loop
//! platform sine dwells (`ÿ/ẍ`), both read by the first harmonic over whole periods, and the
//! valve chirp. The analytic and linearised responses these are checked against live in
//! [`super::frequency_response`].

use super::frequency_response::first_harmonic;
use crate::experiments;
use crate::model::ModelKind;
use crate::params::Params;
use crate::scenario::{CommandSignal, PlatformMotion, PlatformSine};
use crate::simulation::{Drive, SimError, step_for_rate};
use num_complex::Complex64;
use rayon::prelude::*;
use std::f64::consts::PI;

/// Options of a simulated sine dwell.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DwellOptions {
    /// Settling time before the analysis window \[s\].
    pub settle_s: f64,
    /// Minimum analysis window \[s\] (rounded up to whole periods, at least 2).
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

/// Simulated time of one [`simulated_bode`] dwell \[s\]: the settling time and the whole
/// periods of the analysis window (for cost estimates as well as the run).
pub fn bode_dwell_s(freq_hz: f64, opt: &DwellOptions) -> f64 {
    opt.settle_s + dwell_periods(freq_hz, opt) as f64 / freq_hz
}

/// Fade-in of a transmissibility dwell's platform sine [s].
const TRANSMISSIBILITY_FADE_S: f64 = 1.0;

fn transmissibility_periods(freq_hz: f64, opt: &DwellOptions) -> usize {
    dwell_periods(freq_hz, opt).max(freq_hz.ceil() as usize)
}

/// Simulated time of one [`simulated_transmissibility`] dwell \[s\]: the fade-in, 2 s, the
/// settling time and the analysis window.
pub fn transmissibility_dwell_s(freq_hz: f64, opt: &DwellOptions) -> f64 {
    TRANSMISSIBILITY_FADE_S
        + 2.0
        + opt.settle_s
        + transmissibility_periods(freq_hz, opt) as f64 / freq_hz
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
    let t_end = bode_dwell_s(freq_hz, opt);
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
    let periods = transmissibility_periods(freq_hz, opt);
    let fade = TRANSMISSIBILITY_FADE_S;
    let t_end = transmissibility_dwell_s(freq_hz, opt);
    let h = step_for_rate(params.numerics.max_step_s, 1000.0);
    let platform = PlatformMotion::Sine(PlatformSine {
        amplitude_m: amp,
        freq_hz,
        fade_in_s: fade,
    });
    let trace = experiments::run(
        params,
        kind,
        Drive::closed_loop(params),
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The passive seat, excited by platform sine dwells in simulation, crosses |T| = 1 at
    /// √2 times its natural frequency √(k/m)/2π whatever its damping (|T|² = 1 ⇔
    /// (k − mω²)² = k²), computed here from the body's k and m, not from the model; and that
    /// crossing is the paper's ≈ 4 Hz.
    #[test]
    fn simulated_passive_seat_crosses_unity_at_sqrt2_times_its_natural_frequency() {
        let params = Params::paper();
        let (k, m) = (
            params.plant.body.stiffness_n_per_m,
            params.plant.body.mass_kg,
        );
        let f_n = (k / m).sqrt() / (2.0 * std::f64::consts::PI);
        let opt = DwellOptions::default();
        let gain = |f: f64| {
            simulated_transmissibility(&params, ModelKind::Passive, f, &opt)
                .expect("the passive seat runs")
                .norm()
        };
        // Bisect the simulated |T| − 1 between 3 and 5 Hz (above 1 below the crossing).
        let (mut lo, mut hi) = (3.0, 5.0);
        assert!(gain(lo) > 1.0 && gain(hi) < 1.0);
        for _ in 0..14 {
            let mid = 0.5 * (lo + hi);
            if gain(mid) > 1.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let crossing = 0.5 * (lo + hi);
        let expected = 2f64.sqrt() * f_n;
        assert!(
            (crossing - expected).abs() < 2e-3 * expected,
            "simulated crossing {crossing:.4} Hz, √2·√(k/m)/2π = {expected:.4} Hz"
        );
        assert!((crossing - 3.99).abs() < 0.01, "crossing {crossing:.4} Hz");
    }
}
