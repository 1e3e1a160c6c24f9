//! One entry point for a model's frequency response: the valve Bode `u̇/V_in` or the
//! transmissibility `ÿ/ẍ`, of any model, by any method the model has (closed form, simulated
//! sine dwells, or the twin linearised at rest). The CLI's `bode` and `transmissibility`
//! commands are this function plus a CSV file.

use super::dwell::{self, DwellOptions};
use super::frequency_response as fr;
use crate::control::ControlLaw;
use crate::format::general;
use crate::model::ModelKind;
use crate::params::Params;
use crate::simulation::SimError;
use num_complex::Complex64;

/// How a response is computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(not(target_arch = "wasm32"), derive(clap::ValueEnum))]
pub enum Method {
    /// Closed form (linear and passive models).
    Exact,
    /// Sine dwell by simulation, first harmonic.
    Simulated,
    /// Numerical linearisation at rest, evaluated on jω (twin).
    Linearised,
}

impl Method {
    /// The method used when none is asked for: simulation for the twin (it is nonlinear),
    /// the closed form for the others.
    pub fn default_for(kind: ModelKind) -> Self {
        match kind {
            ModelKind::Twin => Method::Simulated,
            ModelKind::Linear | ModelKind::Passive => Method::Exact,
        }
    }

    /// Lower-case name as on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Method::Exact => "exact",
            Method::Simulated => "simulated",
            Method::Linearised => "linearised",
        }
    }
}

/// Which response.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Response {
    /// Relative velocity over valve command `u̇/V_in` [m/(s·V)], platform still, open loop,
    /// for a command sine of `amplitude_v` \[V\] (the simulated method is amplitude dependent).
    Bode {
        /// Command amplitude \[V\].
        amplitude_v: f64,
    },
    /// Body over platform acceleration `ÿ/ẍ` [-], closed loop.
    Transmissibility,
}

impl Response {
    /// CSV columns: frequency, magnitude in display units, phase in degrees.
    pub fn columns(self) -> [&'static str; 3] {
        match self {
            Response::Bode { .. } => ["freq_hz", "mag_mm_per_s_v", "phase_deg"],
            Response::Transmissibility => ["freq_hz", "mag", "phase_deg"],
        }
    }

    /// One CSV row for the point `value` at `freq_hz`, in the units of [`Self::columns`].
    pub fn row(self, freq_hz: f64, value: Complex64) -> Vec<f64> {
        let scale = match self {
            Response::Bode { .. } => 1000.0,
            Response::Transmissibility => 1.0,
        };
        vec![freq_hz, value.norm() * scale, value.arg().to_degrees()]
    }
}

/// Why a response could not be computed.
#[derive(Debug, thiserror::Error)]
pub enum ResponseError {
    /// The passive seat has no valve.
    #[error("the passive model has no valve: no Bode of u̇/V_in")]
    NoValve,
    /// A method the model does not have (e.g. a closed form of the twin).
    #[error("method {} not available for the {} model", .method.name(), .kind.name())]
    NotAvailable {
        /// The model.
        kind: ModelKind,
        /// The method asked for.
        method: Method,
    },
    /// A simulated dwell diverged.
    #[error(transparent)]
    Simulation(#[from] SimError),
    /// A point came out as NaN or infinite.
    #[error("the response at {} Hz is not a finite number ({value})", general(*.freq_hz))]
    NotFinite {
        /// Frequency of the first such point \[Hz\].
        freq_hz: f64,
        /// Its value.
        value: Complex64,
    },
}

/// The response of `kind` at every frequency of `freqs_hz` \[Hz\] by `method`. Simulated dwells
/// run in parallel (rayon). Every point is finite, or the error names the first that is not.
pub fn response(
    params: &Params,
    kind: ModelKind,
    what: Response,
    method: Method,
    freqs_hz: &[f64],
) -> Result<Vec<Complex64>, ResponseError> {
    let opt = DwellOptions::default();
    let values: Vec<Complex64> = match (what, kind, method) {
        (Response::Bode { .. }, ModelKind::Passive, _) => return Err(ResponseError::NoValve),
        (Response::Bode { .. }, ModelKind::Linear, Method::Exact) => freqs_hz
            .iter()
            .map(|&f| fr::linear_bode(params, f))
            .collect(),
        (Response::Transmissibility, ModelKind::Linear, Method::Exact) => freqs_hz
            .iter()
            .map(|&f| fr::linear_transmissibility(params, f))
            .collect(),
        (Response::Transmissibility, ModelKind::Passive, Method::Exact) => freqs_hz
            .iter()
            .map(|&f| fr::passive_transmissibility(params, f))
            .collect(),
        (_, ModelKind::Twin, Method::Linearised) => {
            let lin = fr::linearise_twin(params);
            let law = ControlLaw::new(params);
            freqs_hz
                .iter()
                .map(|&f| match what {
                    Response::Bode { .. } => lin.bode(f),
                    Response::Transmissibility => lin.transmissibility(&law, f),
                })
                .collect()
        }
        (Response::Bode { amplitude_v }, _, Method::Simulated) => dwell::sweep(freqs_hz, |&f| {
            dwell::simulated_bode(params, kind, f, amplitude_v, &opt)
        })
        .into_iter()
        .collect::<Result<_, _>>()?,
        (Response::Transmissibility, _, Method::Simulated) => dwell::sweep(freqs_hz, |&f| {
            dwell::simulated_transmissibility(params, kind, f, &opt)
        })
        .into_iter()
        .collect::<Result<_, _>>()?,
        (_, kind, method) => return Err(ResponseError::NotAvailable { kind, method }),
    };
    if let Some((&freq_hz, &value)) = freqs_hz.iter().zip(&values).find(|(_, v)| !v.is_finite()) {
        return Err(ResponseError::NotFinite { freq_hz, value });
    }
    Ok(values)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    /// The passive seat's transmissibility from the entry point equals the textbook
    /// base-excitation formula `(k + jωc)/(k − mω² + jωc)`, written here from m, k and ζ.
    #[test]
    fn passive_transmissibility_is_the_textbook_formula() {
        let p = Params::paper();
        let (m, k) = (p.plant.body.mass_kg, p.plant.body.stiffness_n_per_m);
        let c = 2.0 * p.passive.zeta * (k * m).sqrt();
        let freqs = [0.5, 2.0, 3.99, 8.0];
        let t = response(
            &p,
            ModelKind::Passive,
            Response::Transmissibility,
            Method::Exact,
            &freqs,
        )
        .unwrap();
        for (f, t) in freqs.iter().zip(t) {
            let w = 2.0 * PI * f;
            let want = Complex64::new(k, w * c) / Complex64::new(k - m * w * w, w * c);
            assert!(
                (t - want).norm() < 1e-9 * want.norm(),
                "{f} Hz: {t} vs {want}"
            );
        }
    }

    #[test]
    fn methods_a_model_lacks_are_refused_by_name() {
        let p = Params::paper();
        let bode = Response::Bode { amplitude_v: 1.0 };
        let e = response(&p, ModelKind::Passive, bode, Method::Exact, &[1.0]).unwrap_err();
        assert!(matches!(e, ResponseError::NoValve), "{e}");
        let e = response(&p, ModelKind::Twin, bode, Method::Exact, &[1.0]).unwrap_err();
        assert_eq!(
            e.to_string(),
            "method exact not available for the twin model"
        );
        let e = response(&p, ModelKind::Linear, bode, Method::Linearised, &[1.0]).unwrap_err();
        assert_eq!(
            e.to_string(),
            "method linearised not available for the linear model"
        );
    }

    #[test]
    fn rows_are_in_display_units() {
        let v = Complex64::from_polar(0.13325, -PI / 2.0);
        let row = Response::Bode { amplitude_v: 1.0 }.row(2.0, v);
        assert!((row[1] - 133.25).abs() < 1e-9 && (row[2] + 90.0).abs() < 1e-9);
        assert_eq!(Response::Transmissibility.row(2.0, v)[1], 0.13325);
    }
}
