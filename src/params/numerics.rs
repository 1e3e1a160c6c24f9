//! How the twin is integrated.

use serde::{Deserialize, Serialize};

/// How the twin is integrated (the linear and passive models are stepped exactly either way).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Integrator {
    /// Exponential RK4 (ETDRK4, [`crate::simulation::integrate::Etd4`]): the twin's Jacobian at rest is
    /// integrated exactly, the nonlinear remainder explicitly. The default: it resolves the
    /// lightly damped 912 Hz hose modes at any step, so 0.5 ms meets the 1e-4 m/s² accuracy.
    #[default]
    Exponential,
    /// Classical RK4 ([`crate::simulation::integrate::rk4_step`]); needs ≈ 0.1 ms for the same accuracy.
    Rk4,
}

impl Integrator {
    /// Name as in presets.
    pub fn name(self) -> &'static str {
        match self {
            Integrator::Exponential => "exponential",
            Integrator::Rk4 => "rk4",
        }
    }
}

/// Numerical options of the fixed-step integrator.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct NumericsParams {
    /// Integration method of the twin, `"exponential"` (default) or `"rk4"`.
    pub integrator: Integrator,
    /// Largest internal step \[s\], 1e-6 ..= 1e-3; must also respect the method's stability limit
    /// ([`Params::step_limit_s`](super::Params::step_limit_s): RK4's from the hose modes, the
    /// exponential method's from the end-stop contact and friction, which it treats
    /// explicitly).
    pub max_step_s: f64,
}

impl Default for NumericsParams {
    fn default() -> Self {
        Self {
            integrator: Integrator::Exponential,
            max_step_s: 5.0e-4,
        }
    }
}
