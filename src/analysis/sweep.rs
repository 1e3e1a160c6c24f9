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

/// Which frequency response [`response`] computes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Response {
    /// `u̇/V_in`, open loop, platform still; a simulated dwell drives the valve with this
    /// command amplitude [V].
    Bode {
        /// Command amplitude of a simulated dwell [V].
        amplitude_v: f64,
    },
    /// `ÿ/ẍ` with the controller in the loop.
    Transmissibility,
}

/// How [`response`] computes it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ResponseMethod {
    /// Closed form (linear and passive models).
    Exact,
    /// Sine dwell by simulation, first harmonic.
    Simulated,
    /// Numerical linearisation at rest, evaluated on jω (twin).
    Linearised,
}

impl ResponseMethod {
    /// The usual method for a model: simulated for the twin, exact for the others.
    pub fn default_for(kind: ModelKind) -> Self {
        match kind {
            ModelKind::Twin => ResponseMethod::Simulated,
            _ => ResponseMethod::Exact,
        }
    }
}

/// Why [`response`] gave no response.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ResponseError {
    /// The passive seat has no valve, so no `u̇/V_in`.
    #[error("the passive model has no valve: no Bode of u̇/V_in")]
    NoValve,
    /// The method does not apply to the model.
    #[error("method {method:?} not available for the {model} model")]
    Unavailable {
        /// The model's name.
        model: &'static str,
        /// The method asked for.
        method: ResponseMethod,
    },
    /// A simulated dwell failed.
    #[error(transparent)]
    Sim(#[from] SimError),
}

/// One entry point for a model's frequency response at `freqs_hz`, by `method` (closed form,
/// linearisation or simulated dwells run in parallel).
pub fn response(
    params: &Params,
    kind: ModelKind,
    what: Response,
    method: ResponseMethod,
    freqs_hz: &[f64],
) -> Result<Vec<Complex64>, ResponseError> {
    use super::frequency_response as fr;
    use ResponseMethod::{Exact, Linearised, Simulated};
    let opt = DwellOptions::default();
    let closed =
        |g: fn(&Params, f64) -> Complex64| freqs_hz.iter().map(|&f| g(params, f)).collect();
    Ok(match (what, kind, method) {
        (Response::Bode { .. }, ModelKind::Passive, _) => return Err(ResponseError::NoValve),
        (Response::Bode { .. }, ModelKind::Linear, Exact) => closed(fr::linear_bode),
        (Response::Transmissibility, ModelKind::Linear, Exact) => {
            closed(fr::linear_transmissibility)
        }
        (Response::Transmissibility, ModelKind::Passive, Exact) => {
            closed(fr::passive_transmissibility)
        }
        (_, ModelKind::Twin, Linearised) => {
            let lin = fr::linearise_twin(params);
            let law = crate::control::ControlLaw::new(params);
            freqs_hz
                .iter()
                .map(|&f| match what {
                    Response::Bode { .. } => lin.bode(f),
                    Response::Transmissibility => lin.transmissibility(&law, f),
                })
                .collect()
        }
        (Response::Bode { amplitude_v }, _, Simulated) => sweep(freqs_hz, |&f| {
            simulated_bode(params, kind, f, amplitude_v, &opt)
        })
        .into_iter()
        .collect::<Result<_, _>>()?,
        (Response::Transmissibility, _, Simulated) => sweep(freqs_hz, |&f| {
            simulated_transmissibility(params, kind, f, &opt)
        })
        .into_iter()
        .collect::<Result<_, _>>()?,
        (_, k, m) => {
            return Err(ResponseError::Unavailable {
                model: k.name(),
                method: m,
            });
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The entry point's exact and linearised answers are the closed forms they name, and it
    /// refuses what does not exist.
    #[test]
    fn response_dispatches_to_the_named_method() {
        let p = Params::paper();
        let f = [1.0, 7.0];
        let t = response(
            &p,
            ModelKind::Linear,
            Response::Transmissibility,
            ResponseMethod::Exact,
            &f,
        )
        .unwrap();
        for (v, &fi) in t.iter().zip(&f) {
            assert_eq!(
                *v,
                super::super::frequency_response::linear_transmissibility(&p, fi)
            );
        }
        let t = response(
            &p,
            ModelKind::Passive,
            Response::Transmissibility,
            ResponseMethod::Exact,
            &f,
        )
        .unwrap();
        let (k, m) = (p.plant.body.stiffness_n_per_m, p.plant.body.mass_kg);
        let c = 2.0 * p.passive.zeta * (k * m).sqrt();
        for (v, &fi) in t.iter().zip(&f) {
            let s = Complex64::new(0.0, 2.0 * PI * fi);
            let exact = (c * s + k) / (m * s * s + c * s + k);
            assert!((*v - exact).norm() < 1e-12 * exact.norm(), "{v} vs {exact}");
        }
        assert_eq!(
            response(
                &p,
                ModelKind::Passive,
                Response::Bode { amplitude_v: 1.0 },
                ResponseMethod::Exact,
                &f
            ),
            Err(ResponseError::NoValve)
        );
        assert!(matches!(
            response(
                &p,
                ModelKind::Twin,
                Response::Transmissibility,
                ResponseMethod::Exact,
                &f
            ),
            Err(ResponseError::Unavailable { .. })
        ));
    }
}
