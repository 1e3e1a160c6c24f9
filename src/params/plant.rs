//! The physical rig: body and springs, cylinder and end stops, hoses, supply, valve, oil.

use super::{CorrectionParams, EffectsParams};
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// The physical rig: what the twin is built from. A change here rebuilds the model (its
/// linearisation, its exponential integrator); gains and numerics do not.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields, default)]
pub struct PlantParams {
    /// Suspended body and springs.
    pub body: BodyParams,
    /// Cylinder and end stops.
    pub cylinder: CylinderParams,
    /// Hoses.
    pub hose: HoseParams,
    /// Supply.
    pub supply: SupplyParams,
    /// Valve.
    pub valve: ValveParams,
    /// Oil.
    pub fluid: FluidParams,
    /// Optional physical effects (off by default).
    pub effects: EffectsParams,
    /// Terms beyond the effect library, proposed by a calibration (zero by default).
    pub corrections: CorrectionParams,
}

/// The suspended body and its springs.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct BodyParams {
    /// Suspended mass incl. seat and operator \[kg\], 1 ..= 500. Paper: 11.7.
    pub mass_kg: f64,
    /// Equivalent stiffness of all springs together [N/m], 1 ..= 1e6. Paper: 3680 (docs/model.md, correction 3).
    pub stiffness_n_per_m: f64,
}

impl Default for BodyParams {
    fn default() -> Self {
        Self {
            mass_kg: 11.7,
            stiffness_n_per_m: 3680.0,
        }
    }
}

/// The double-rod cylinder and its end stops.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CylinderParams {
    /// Full stroke `Lc` \[m\], 0.005 ..= 1. Paper: 0.070. End stops sit at ±Lc/2.
    pub stroke_m: f64,
    /// Bore `D` \[m\], 0.005 ..= 0.3, > rod. Paper: 0.025.
    pub bore_m: f64,
    /// Rod diameter `d` \[m\], 0 ..= 0.3, < bore. Paper: 0.018.
    pub rod_m: f64,
    /// Contact stiffness of the end stops [N/m], 1e3 ..= 1e8.
    pub end_stop_stiffness_n_per_m: f64,
    /// Contact damping of the end stops [N·s/m], 0 ..= 1e6.
    pub end_stop_damping_n_s_per_m: f64,
}

impl Default for CylinderParams {
    fn default() -> Self {
        Self {
            stroke_m: 0.070,
            bore_m: 0.025,
            rod_m: 0.018,
            end_stop_stiffness_n_per_m: 5.0e6,
            end_stop_damping_n_s_per_m: 5.0e3,
        }
    }
}

impl CylinderParams {
    /// Annular piston area `A1 = A2 = π(D² − d²)/4` \[m²\].
    pub fn piston_area_m2(&self) -> f64 {
        PI * (self.bore_m.powi(2) - self.rod_m.powi(2)) / 4.0
    }
}

/// The two identical hoses between valve and cylinder.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct HoseParams {
    /// Length of each hose `Li` \[m\], 0.01 ..= 20. Paper: 0.5.
    pub length_m: f64,
    /// Inner diameter of each hose `di` \[m\], 0.001 ..= 0.05. Paper: 0.010.
    pub diameter_m: f64,
}

impl Default for HoseParams {
    fn default() -> Self {
        Self {
            length_m: 0.5,
            diameter_m: 0.010,
        }
    }
}

/// Hydraulic supply.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SupplyParams {
    /// Feed pressure `pA` \[Pa\], 1e5 ..= 5e7, > return pressure. Paper: 100 bar.
    pub supply_pressure_pa: f64,
    /// Discharge (return) pressure `p0` \[Pa\], 0 ..= 5e7. Paper: 10 bar.
    pub return_pressure_pa: f64,
}

impl Default for SupplyParams {
    fn default() -> Self {
        Self {
            supply_pressure_pa: 100.0e5,
            return_pressure_pa: 10.0e5,
        }
    }
}

/// The proportional flow-control valve (orifice law and spool dynamics).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ValveParams {
    /// Flow coefficient `Cd` [-], 1e-3 ..= 1. Paper: 0.1074 initial, 0.1506 adjusted.
    pub cd: f64,
    /// Area gradient `ka` (opening area = ka·xv) \[m\], 1e-4 ..= 0.5. Paper: 0.0251.
    pub ka_m: f64,
    /// Static spool gain `kv` [m/V], 1e-7 ..= 1e-2. Paper: 8e-5.
    pub kv_m_per_v: f64,
    /// Spool natural frequency `ωn` [rad/s], 1 ..= 1e5. Paper: 691.
    pub omega_n_rad_s: f64,
    /// Spool damping ratio `ζs` [-], 0.01 ..= 10. Paper: 1.1.
    pub zeta: f64,
    /// Spool travel limit `xv,max` \[m\], 1e-6 ..= 0.05. Paper: 0.8 mm.
    pub xv_max_m: f64,
    /// Pure input delay `τ` of the command \[s\], 0 ..= 0.1. Paper: 17.5 ms.
    pub tau_s: f64,
    /// Command saturation `±Vmax` \[V\], 0.1 ..= 100. Paper: 10 V.
    pub v_max_v: f64,
    /// Width of the laminar core of the signed square root \[Pa\], 1 ..= 1e6 (docs/model.md, correction 10).
    pub laminar_core_pa: f64,
}

impl Default for ValveParams {
    fn default() -> Self {
        Self {
            cd: 0.1506,
            ka_m: 0.0251,
            kv_m_per_v: 8.0e-5,
            omega_n_rad_s: 691.0,
            zeta: 1.1,
            xv_max_m: 0.8e-3,
            tau_s: 0.0175,
            v_max_v: 10.0,
            laminar_core_pa: 1.0e4,
        }
    }
}

/// The mineral oil.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FluidParams {
    /// Density `ρ` [kg/m³], 500 ..= 2000. Paper: 840.
    pub density_kg_m3: f64,
    /// Dynamic viscosity `μ` [Pa·s], 1e-4 ..= 10. Paper: 0.02 (docs/model.md, correction 2).
    pub viscosity_pa_s: f64,
    /// Bulk modulus `β` \[Pa\], 1e6 ..= 1e10. Paper: 1200 MPa (docs/model.md, correction 2).
    pub bulk_modulus_pa: f64,
}

impl Default for FluidParams {
    fn default() -> Self {
        Self {
            density_kg_m3: 840.0,
            viscosity_pa_s: 0.02,
            bulk_modulus_pa: 1.2e9,
        }
    }
}
