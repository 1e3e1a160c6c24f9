//! The simplified model of Eq. (15): `G(s) = u̇/V = sp²·Kg·e^(−sτ)/(s² + 2ζp·sp·s + sp²)`.
//!
//! In the time domain the delay lives in the simulation's delay line (like the twin's τ) and
//! the rational part is a state space with states `[u, u̇, ü]`. The platform does not act on
//! `u` directly: the valve-driven cylinder imposes the relative velocity (section 5), so
//! `ÿ = ẍ + ü`.

use super::{Inputs, Model, ModelKind, Outputs};
use crate::params::{LinearParams, Params};
use num_complex::Complex64;

/// G(s) in state space, with the stroke for overrun flagging.
#[derive(Debug, Clone)]
pub struct LinearModel {
    lin: LinearParams,
    half_stroke_m: f64,
    v_max_v: f64,
}

impl LinearModel {
    /// Builds the model from a full parameter set (uses `linear` and the stroke).
    pub fn new(params: &Params) -> Self {
        Self {
            lin: params.linear,
            half_stroke_m: 0.5 * params.plant.cylinder.stroke_m,
            v_max_v: params.plant.valve.v_max_v,
        }
    }

    /// The parameters of G(s).
    pub fn params(&self) -> &LinearParams {
        &self.lin
    }

    /// `G(jω)` including the delay [m/(s·V)].
    pub fn g(&self, omega_rad_s: f64) -> Complex64 {
        g_of(&self.lin, omega_rad_s)
    }
}

/// `G(jω)` of Eq. (15) including the delay [m/(s·V)].
pub fn g_of(l: &LinearParams, omega_rad_s: f64) -> Complex64 {
    let s = Complex64::new(0.0, omega_rad_s);
    let sp2 = l.sp_rad_s * l.sp_rad_s;
    sp2 * l.kg_m_per_s_v * (-s * l.tau_s).exp() / (s * s + 2.0 * l.zeta * l.sp_rad_s * s + sp2)
}

impl super::CommandPath for LinearModel {
    fn command_delay(&self) -> f64 {
        self.lin.tau_s
    }
    fn command_limit(&self) -> f64 {
        self.v_max_v
    }
}

impl Model<3> for LinearModel {
    const KIND: ModelKind = ModelKind::Linear;
    const STATE_NAMES: [&'static str; 3] = ["u [m]", "du [m/s]", "ddu [m/s2]"];

    #[inline]
    fn derivatives(&self, _t: f64, y: &[f64; 3], inputs: &Inputs) -> [f64; 3] {
        let l = &self.lin;
        let sp = l.sp_rad_s;
        [
            y[1],
            y[2],
            sp * sp * (l.kg_m_per_s_v * inputs.v_valve - y[1]) - 2.0 * l.zeta * sp * y[2],
        ]
    }

    fn rest_state(&self) -> [f64; 3] {
        [0.0; 3]
    }

    #[inline]
    fn outputs(&self, y: &[f64; 3], inputs: &Inputs) -> Outputs {
        Outputs::mechanical(y[0], y[1], inputs.xdd + y[2])
    }

    #[inline(always)]
    fn relative_position(&self, y: &[f64; 3]) -> f64 {
        y[0]
    }

    fn half_stroke(&self) -> f64 {
        self.half_stroke_m
    }

    fn state_bound(&self, index: usize) -> f64 {
        [1.0, 100.0, 1.0e5][index.min(2)]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn g_static_gain_and_resonance() {
        let l = LinearParams::default();
        let g0 = g_of(&l, 1e-6);
        assert!((g0.norm() - 0.13325).abs() < 1e-9);
        // At ω = sp: |G| = Kg/(2ζ) = 1.3325 and the rational phase is −90°.
        let gs = g_of(&l, l.sp_rad_s);
        assert!((gs.norm() - 0.13325 / 0.1).abs() < 1e-9);
        let rational_phase = gs.arg() + l.sp_rad_s * l.tau_s;
        let wrapped = (rational_phase + std::f64::consts::PI)
            .rem_euclid(2.0 * std::f64::consts::PI)
            - std::f64::consts::PI;
        assert!((wrapped + std::f64::consts::FRAC_PI_2).abs() < 1e-9);
    }
}
