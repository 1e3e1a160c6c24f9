//! The passive reference suspension: the same mass and springs with a viscous damper in
//! parallel, `c = 2ζ·√(k·m)`. Linear, with exact transmissibility
//! `T(s) = (2ζωn·s + ωn²)/(s² + 2ζωn·s + ωn²)`. It has no end stops; a stroke overrun is
//! flagged by the simulation instead.

use super::{Inputs, Model, ModelKind, Outputs};
use crate::params::Params;
use num_complex::Complex64;

/// Mass–spring–damper with base excitation, states `[u, u̇]`.
#[derive(Debug, Clone)]
pub struct PassiveModel {
    mass_kg: f64,
    stiffness_n_per_m: f64,
    damping_n_s_per_m: f64,
    half_stroke_m: f64,
}

impl PassiveModel {
    /// Builds the passive reference from the body parameters and `passive.zeta`.
    pub fn new(params: &Params) -> Self {
        let m = params.plant.body.mass_kg;
        let k = params.plant.body.stiffness_n_per_m;
        Self {
            mass_kg: m,
            stiffness_n_per_m: k,
            damping_n_s_per_m: 2.0 * params.passive.zeta * (k * m).sqrt(),
            half_stroke_m: 0.5 * params.plant.cylinder.stroke_m,
        }
    }

    /// Damper coefficient [N·s/m].
    pub fn damping_n_s_per_m(&self) -> f64 {
        self.damping_n_s_per_m
    }

    /// Exact transmissibility `ÿ/ẍ` at `ω` [-].
    pub fn transmissibility(&self, omega_rad_s: f64) -> Complex64 {
        let s = Complex64::new(0.0, omega_rad_s);
        let (m, k, c) = (self.mass_kg, self.stiffness_n_per_m, self.damping_n_s_per_m);
        (c * s + k) / (m * s * s + c * s + k)
    }

    fn body_acceleration(&self, y: &[f64; 2]) -> f64 {
        -(self.stiffness_n_per_m * y[0] + self.damping_n_s_per_m * y[1]) / self.mass_kg
    }
}

impl super::CommandPath for PassiveModel {
    fn command_delay(&self) -> f64 {
        0.0
    }
    fn command_limit(&self) -> f64 {
        0.0
    }
}

impl Model<2> for PassiveModel {
    const KIND: ModelKind = ModelKind::Passive;
    const STATE_NAMES: [&'static str; 2] = ["u [m]", "du [m/s]"];

    #[inline]
    fn derivatives(&self, _t: f64, y: &[f64; 2], inputs: &Inputs) -> [f64; 2] {
        [y[1], self.body_acceleration(y) - inputs.xdd]
    }

    fn rest_state(&self) -> [f64; 2] {
        [0.0; 2]
    }

    #[inline]
    fn outputs(&self, y: &[f64; 2], _inputs: &Inputs) -> Outputs {
        Outputs::mechanical(y[0], y[1], self.body_acceleration(y))
    }

    #[inline(always)]
    fn relative_position(&self, y: &[f64; 2]) -> f64 {
        y[0]
    }

    fn half_stroke(&self) -> f64 {
        self.half_stroke_m
    }

    fn state_bound(&self, index: usize) -> f64 {
        [1.0, 100.0][index.min(1)]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn passive_crossing_is_sqrt2_fn() {
        let params = Params::paper();
        let p = PassiveModel::new(&params);
        let wn = (params.plant.body.stiffness_n_per_m / params.plant.body.mass_kg).sqrt();
        // |T| = 1 exactly at ω = √2·ωn for any damping (the closed form).
        assert!((p.transmissibility(2f64.sqrt() * wn).norm() - 1.0).abs() < 1e-12);
    }
}
