//! The reference models beside the twin: the passive suspension and the simplified G(s).

use serde::{Deserialize, Serialize};

/// The passive reference suspension: same mass and springs plus a viscous damper.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PassiveParams {
    /// Damping ratio `ζ` of the viscous damper [-], 0 ..= 5. Paper: 0.3.
    pub zeta: f64,
}

impl Default for PassiveParams {
    fn default() -> Self {
        Self { zeta: 0.3 }
    }
}

/// The simplified model, Eq. (15): `G(s) = sp²·Kg·e^(−sτ) / (s² + 2ζp·sp·s + sp²)`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LinearParams {
    /// Pole location `sp` [rad/s], 1 ..= 1e5. Paper: 500.
    pub sp_rad_s: f64,
    /// Static gain `Kg` [m/(s·V)], 1e-4 ..= 10. Paper: 133.25 mm/(s·V).
    pub kg_m_per_s_v: f64,
    /// Damping factor `ζp` [-], 0 ..= 10. Paper: 0.05.
    pub zeta: f64,
    /// Pure delay of G(s) `τ` \[s\], 0 ..= 0.1. Paper: 17.5 ms.
    pub tau_s: f64,
}

impl Default for LinearParams {
    fn default() -> Self {
        Self {
            sp_rad_s: 500.0,
            kg_m_per_s_v: 0.13325,
            zeta: 0.05,
            tau_s: 0.0175,
        }
    }
}
