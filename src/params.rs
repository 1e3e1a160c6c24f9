//! Parameter structs of the rig, its controller and the numerics.
//!
//! Every field is in SI units, documents its unit and valid range, and is checked by
//! [`Params::validate`]. Defaults are the paper's adjusted twin (section 3 and 4.2, with the
//! corrections listed in `docs/model.md`): `Cd = 0.1506`, `τ = 17.5 ms`, `k = 3680 N/m` in total.

use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// A parameter outside its allowed range, or an inconsistent combination.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ParamError {
    /// A value outside `[min, max]` (or not finite).
    #[error(
        "parameter `{name}` = {} is outside the allowed range [{}, {}] {unit}",
        fmt_value(*.value),
        fmt_value(*.min),
        fmt_value(*.max)
    )]
    OutOfRange {
        /// Dotted name as in the preset file, e.g. `valve.cd`.
        name: String,
        /// The offending value.
        value: f64,
        /// Smallest allowed value.
        min: f64,
        /// Largest allowed value.
        max: f64,
        /// Unit of the value.
        unit: &'static str,
    },
    /// Two parameters that are individually valid but not together.
    #[error("parameters are inconsistent: {0}")]
    Inconsistent(String),
}

/// A number for people: at most 6 significant digits, plain for 1e-4 ≤ |x| < 1e7 (`0.0005`,
/// `11.7`, `3680`), scientific otherwise (`1e-6`, `1.5e300`); never hundreds of digits.
pub fn fmt_value(x: f64) -> String {
    if !x.is_finite() {
        return format!("{x}");
    }
    let r: f64 = format!("{x:.5e}").parse().unwrap_or(x);
    let a = r.abs();
    if a == 0.0 {
        "0".into()
    } else if (1e-4..1e7).contains(&a) {
        format!("{r}")
    } else {
        format!("{r:e}")
    }
}

/// Checks `min <= value <= max` and finiteness.
pub(crate) fn check(
    name: &str,
    value: f64,
    min: f64,
    max: f64,
    unit: &'static str,
) -> Result<(), ParamError> {
    if value.is_finite() && value >= min && value <= max {
        Ok(())
    } else {
        Err(ParamError::OutOfRange {
            name: name.to_string(),
            value,
            min,
            max,
            unit,
        })
    }
}

/// The suspended body and its springs.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct BodyParams {
    /// Suspended mass incl. seat and operator [kg], 1 ..= 500. Paper: 11.7.
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
    /// Full stroke `Lc` [m], 0.005 ..= 1. Paper: 0.070. End stops sit at ±Lc/2.
    pub stroke_m: f64,
    /// Bore `D` [m], 0.005 ..= 0.3, > rod. Paper: 0.025.
    pub bore_m: f64,
    /// Rod diameter `d` [m], 0 ..= 0.3, < bore. Paper: 0.018.
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
    /// Annular piston area `A1 = A2 = π(D² − d²)/4` [m²].
    pub fn piston_area_m2(&self) -> f64 {
        PI * (self.bore_m.powi(2) - self.rod_m.powi(2)) / 4.0
    }
}

/// The two identical hoses between valve and cylinder.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct HoseParams {
    /// Length of each hose `Li` [m], 0.01 ..= 20. Paper: 0.5.
    pub length_m: f64,
    /// Inner diameter of each hose `di` [m], 0.001 ..= 0.05. Paper: 0.010.
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
    /// Feed pressure `pA` [Pa], 1e5 ..= 5e7, > return pressure. Paper: 100 bar.
    pub supply_pressure_pa: f64,
    /// Discharge (return) pressure `p0` [Pa], 0 ..= 5e7. Paper: 10 bar.
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
    /// Area gradient `ka` (opening area = ka·xv) [m], 1e-4 ..= 0.5. Paper: 0.0251.
    pub ka_m: f64,
    /// Static spool gain `kv` [m/V], 1e-7 ..= 1e-2. Paper: 8e-5.
    pub kv_m_per_v: f64,
    /// Spool natural frequency `ωn` [rad/s], 1 ..= 1e5. Paper: 691.
    pub omega_n_rad_s: f64,
    /// Spool damping ratio `ζs` [-], 0.01 ..= 10. Paper: 1.1.
    pub zeta: f64,
    /// Spool travel limit `xv,max` [m], 1e-6 ..= 0.05. Paper: 0.8 mm.
    pub xv_max_m: f64,
    /// Pure input delay `τ` of the command [s], 0 ..= 0.1. Paper: 17.5 ms.
    pub tau_s: f64,
    /// Command saturation `±Vmax` [V], 0.1 ..= 100. Paper: 10 V.
    pub v_max_v: f64,
    /// Width of the laminar core of the signed square root [Pa], 1 ..= 1e6 (docs/model.md, correction 10).
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
    /// Bulk modulus `β` [Pa], 1e6 ..= 1e10. Paper: 1200 MPa (docs/model.md, correction 2).
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

/// Which controller structure drives the valve. The equations, signals and units of each are in
/// [`crate::control`]; every kind runs on the twin and on the linear models.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ControllerKind {
    /// The paper's Eq. (16): `V = Kp·u + Ki·∫ẍ dt` (position feedback, platform-velocity
    /// feed-forward).
    #[default]
    Paper,
    /// The paper's structure with the platform velocity predicted `lead_s` ahead:
    /// `V = Kp·u + Ki·(∫ẍ dt + lead_s·LP(ẍ))`.
    Predictive,
    /// The paper's structure plus feedback of the absolute body velocity, estimated from a body
    /// accelerometer by a leaky integrator and band-limited:
    /// `V = Kp·u + Ki·∫ẍ dt + Ksky·ωs/(s + ωs)·ÿ/(s + ωl)`.
    Skyhook,
    /// A Smith predictor on G(s) with its delay around the position loop, plus the paper's
    /// feed-forward.
    Smith,
}

impl ControllerKind {
    /// Every kind, in menu order.
    pub const ALL: [ControllerKind; 4] = [
        ControllerKind::Paper,
        ControllerKind::Predictive,
        ControllerKind::Skyhook,
        ControllerKind::Smith,
    ];

    /// The name used in presets and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            ControllerKind::Paper => "paper",
            ControllerKind::Predictive => "predictive",
            ControllerKind::Skyhook => "skyhook",
            ControllerKind::Smith => "smith",
        }
    }

    /// The preset keys (gains) this kind reads, besides `kind`.
    pub fn keys(self) -> &'static [&'static str] {
        match self {
            ControllerKind::Paper | ControllerKind::Smith => &["kp_v_per_m", "ki_v_s_per_m"],
            ControllerKind::Predictive => {
                &["kp_v_per_m", "ki_v_s_per_m", "lead_s", "lead_cutoff_hz"]
            }
            ControllerKind::Skyhook => &[
                "kp_v_per_m",
                "ki_v_s_per_m",
                "sky_v_s_per_m",
                "leak_hz",
                "sky_cutoff_hz",
            ],
        }
    }
}

impl std::fmt::Display for ControllerKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for ControllerKind {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Self::ALL
            .into_iter()
            .find(|k| k.name() == s)
            .ok_or_else(|| {
                format!("unknown controller kind `{s}` (one of: paper, predictive, skyhook, smith)")
            })
    }
}

/// The controller: its structure and gains. In a preset, `[controller]` holds `kind` (default
/// `"paper"`) and that kind's keys only ([`ControllerKind::keys`]); a key of another kind is an
/// error, as is an unknown key. Gains a kind does not use keep their defaults.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "ControllerTable", into = "ControllerTable")]
pub struct ControllerParams {
    /// Structure.
    pub kind: ControllerKind,
    /// Position gain `Kp` [V/m], -1e4 ..= 1e4. Paper: -5. All kinds.
    pub kp_v_per_m: f64,
    /// Gain on the integral of the platform acceleration `Ki` [V·s/m], -1e3 ..= 1e3. Paper: -7.5.
    /// All kinds.
    pub ki_v_s_per_m: f64,
    /// Prediction horizon of the platform velocity [s], 0 ..= 0.1. Default 0.0207 (the valve's
    /// 17.5 ms delay plus the spool's ≈ 3.2 ms lag). `predictive` only.
    pub lead_s: f64,
    /// Corner of the first-order low-pass on the predicted term [Hz], 0.5 ..= 200. Default 12.
    /// `predictive` only.
    pub lead_cutoff_hz: f64,
    /// Gain on the estimated absolute body velocity `Ksky` [V·s/m], -1e3 ..= 1e3. Default -3.
    /// `skyhook` only.
    pub sky_v_s_per_m: f64,
    /// Corner of the leaky integrator `ωl/2π` [Hz], 0.01 ..= 10. Default 0.3. `skyhook` only.
    pub leak_hz: f64,
    /// Corner of the first-order low-pass on the body-velocity estimate `ωs/2π` [Hz],
    /// 0.5 ..= 200. Default 6: keeps the feedback off the valve's lightly damped resonance
    /// (≈ 80 Hz), where the delay turns it positive. `skyhook` only.
    pub sky_cutoff_hz: f64,
}

impl Default for ControllerParams {
    fn default() -> Self {
        Self {
            kind: ControllerKind::Paper,
            kp_v_per_m: -5.0,
            ki_v_s_per_m: -7.5,
            lead_s: 0.0207,
            lead_cutoff_hz: 12.0,
            sky_v_s_per_m: -3.0,
            leak_hz: 0.3,
            sky_cutoff_hz: 6.0,
        }
    }
}

impl ControllerParams {
    /// The paper's controller with gains `kp` [V/m] and `ki` [V·s/m].
    pub fn paper(kp_v_per_m: f64, ki_v_s_per_m: f64) -> Self {
        Self {
            kp_v_per_m,
            ki_v_s_per_m,
            ..Self::default()
        }
    }

    /// Value of a gain by its preset key, `None` for an unknown key.
    pub fn get(&self, key: &str) -> Option<f64> {
        Some(match key {
            "kp_v_per_m" => self.kp_v_per_m,
            "ki_v_s_per_m" => self.ki_v_s_per_m,
            "lead_s" => self.lead_s,
            "lead_cutoff_hz" => self.lead_cutoff_hz,
            "sky_v_s_per_m" => self.sky_v_s_per_m,
            "leak_hz" => self.leak_hz,
            "sky_cutoff_hz" => self.sky_cutoff_hz,
            _ => return None,
        })
    }

    /// Sets a gain by its preset key; `false` for an unknown key.
    pub fn set(&mut self, key: &str, value: f64) -> bool {
        let slot = match key {
            "kp_v_per_m" => &mut self.kp_v_per_m,
            "ki_v_s_per_m" => &mut self.ki_v_s_per_m,
            "lead_s" => &mut self.lead_s,
            "lead_cutoff_hz" => &mut self.lead_cutoff_hz,
            "sky_v_s_per_m" => &mut self.sky_v_s_per_m,
            "leak_hz" => &mut self.leak_hz,
            "sky_cutoff_hz" => &mut self.sky_cutoff_hz,
            _ => return false,
        };
        *slot = value;
        true
    }

    /// Allowed range `(min, max, unit)` of a gain by its preset key.
    pub fn range(key: &str) -> Option<(f64, f64, &'static str)> {
        Some(match key {
            "kp_v_per_m" => (-1e4, 1e4, "V/m"),
            "ki_v_s_per_m" => (-1e3, 1e3, "V·s/m"),
            "lead_s" => (0.0, 0.1, "s"),
            "lead_cutoff_hz" => (0.5, 200.0, "Hz"),
            "sky_v_s_per_m" => (-1e3, 1e3, "V·s/m"),
            "leak_hz" => (0.01, 10.0, "Hz"),
            "sky_cutoff_hz" => (0.5, 200.0, "Hz"),
            _ => return None,
        })
    }

    /// Checks every gain of this kind against its range.
    pub fn validate(&self) -> Result<(), ParamError> {
        for key in self.kind.keys() {
            let (min, max, unit) = Self::range(key).expect("every kind's key has a range");
            let value = self.get(key).expect("every kind's key is a field");
            check(&format!("controller.{key}"), value, min, max, unit)?;
        }
        Ok(())
    }
}

/// `[controller]` as written in a preset: `kind` and the gains that kind reads.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct ControllerTable {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    kind: Option<ControllerKind>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    kp_v_per_m: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    ki_v_s_per_m: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    lead_s: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    lead_cutoff_hz: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    sky_v_s_per_m: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    leak_hz: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    sky_cutoff_hz: Option<f64>,
}

impl TryFrom<ControllerTable> for ControllerParams {
    type Error = String;
    fn try_from(t: ControllerTable) -> Result<Self, String> {
        let kind = t.kind.unwrap_or_default();
        let mut c = ControllerParams {
            kind,
            ..ControllerParams::default()
        };
        let given = [
            ("kp_v_per_m", t.kp_v_per_m),
            ("ki_v_s_per_m", t.ki_v_s_per_m),
            ("lead_s", t.lead_s),
            ("lead_cutoff_hz", t.lead_cutoff_hz),
            ("sky_v_s_per_m", t.sky_v_s_per_m),
            ("leak_hz", t.leak_hz),
            ("sky_cutoff_hz", t.sky_cutoff_hz),
        ];
        for (key, value) in given {
            let Some(value) = value else { continue };
            if !kind.keys().contains(&key) {
                return Err(format!(
                    "`{key}` is not a gain of controller kind `{kind}` (its keys: kind, {})",
                    kind.keys().join(", ")
                ));
            }
            c.set(key, value);
        }
        Ok(c)
    }
}

impl From<ControllerParams> for ControllerTable {
    fn from(c: ControllerParams) -> Self {
        let mut t = ControllerTable {
            kind: Some(c.kind),
            ..Default::default()
        };
        for key in c.kind.keys() {
            let value = c.get(key);
            match *key {
                "kp_v_per_m" => t.kp_v_per_m = value,
                "ki_v_s_per_m" => t.ki_v_s_per_m = value,
                "lead_s" => t.lead_s = value,
                "lead_cutoff_hz" => t.lead_cutoff_hz = value,
                "sky_v_s_per_m" => t.sky_v_s_per_m = value,
                "leak_hz" => t.leak_hz = value,
                "sky_cutoff_hz" => t.sky_cutoff_hz = value,
                _ => {}
            }
        }
        t
    }
}

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
    /// Pure delay of G(s) `τ` [s], 0 ..= 0.1. Paper: 17.5 ms.
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

/// How the twin is integrated (the linear and passive models are stepped exactly either way).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Integrator {
    /// Exponential RK4 (ETDRK4, [`crate::integrate::Etd4`]): the twin's Jacobian at rest is
    /// integrated exactly, the nonlinear remainder explicitly. The default: it resolves the
    /// lightly damped 912 Hz hose modes at any step, so 0.5 ms meets the 1e-4 m/s² accuracy.
    #[default]
    Exponential,
    /// Classical RK4 ([`crate::integrate::rk4_step`]); needs ≈ 0.1 ms for the same accuracy.
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
    /// Largest internal step [s], 1e-6 ..= 1e-3; must also respect the method's stability limit
    /// ([`Params::step_limit_s`]: RK4's from the hose modes, the exponential method's from the
    /// end-stop contact and friction, which it treats explicitly).
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

/// Physical effects that the paper's model lacks (issue 4). All off by default; each is a real
/// part of the twin, usable in simulation, the app and presets.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields, default)]
pub struct EffectsParams {
    /// Seal and slide friction.
    pub friction: FrictionEffect,
    /// Spool overlap (dead band) around null.
    pub valve_overlap: OverlapEffect,
    /// Valve null offset, expressed as a command bias.
    pub valve_offset: OffsetEffect,
    /// Internal leakage across the piston.
    pub leakage: LeakageEffect,
    /// Reduced effective bulk modulus (air, hose walls).
    pub compliance: ComplianceEffect,
    /// Supply pressure falling with drawn flow.
    pub supply_sag: SupplySagEffect,
}

/// Coulomb + viscous friction with an optional Stribeck peak, smoothed at zero velocity:
/// `F = (Fc + Fs·exp(−(v/vs)²))·tanh(v/v_eps) + b·v`, opposing the relative velocity `u̇`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FrictionEffect {
    /// Effect active.
    pub enabled: bool,
    /// Coulomb force `Fc` [N], 0 ..= 5000.
    pub coulomb_n: f64,
    /// Viscous coefficient `b` [N·s/m], 0 ..= 1e5.
    pub viscous_n_s_per_m: f64,
    /// Extra static (Stribeck) force `Fs` above Coulomb [N], 0 ..= 5000.
    pub stribeck_n: f64,
    /// Stribeck velocity `vs` [m/s], 1e-5 ..= 1.
    pub stribeck_velocity_m_s: f64,
    /// Smoothing velocity `v_eps` of the sign function [m/s], 1e-5 ..= 0.1.
    pub smoothing_velocity_m_s: f64,
}

impl Default for FrictionEffect {
    fn default() -> Self {
        Self {
            enabled: false,
            coulomb_n: 0.0,
            viscous_n_s_per_m: 0.0,
            stribeck_n: 0.0,
            stribeck_velocity_m_s: 0.005,
            smoothing_velocity_m_s: 1.0e-3,
        }
    }
}

/// Symmetric spool overlap: the orifices open only once `|xv|` exceeds the overlap.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct OverlapEffect {
    /// Effect active.
    pub enabled: bool,
    /// Overlap on each side of null [m], 0 ..= 0.01.
    pub overlap_m: f64,
}

impl Default for OverlapEffect {
    fn default() -> Self {
        Self {
            enabled: false,
            overlap_m: 0.0,
        }
    }
}

/// Valve null offset, as a constant bias added to the delayed command at the valve.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct OffsetEffect {
    /// Effect active.
    pub enabled: bool,
    /// Command bias [V], -5 ..= 5.
    pub bias_v: f64,
}

impl Default for OffsetEffect {
    fn default() -> Self {
        Self {
            enabled: false,
            bias_v: 0.0,
        }
    }
}

/// Laminar internal leakage from the upper to the lower chamber: `Ql = Cl·(p1 − p2)`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LeakageEffect {
    /// Effect active.
    pub enabled: bool,
    /// Leakage coefficient `Cl` [m³/(s·Pa)], 0 ..= 1e-9.
    pub coefficient_m3_per_s_pa: f64,
}

impl Default for LeakageEffect {
    fn default() -> Self {
        Self {
            enabled: false,
            coefficient_m3_per_s_pa: 0.0,
        }
    }
}

/// Reduced effective bulk modulus of the oil in chambers and hoses.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ComplianceEffect {
    /// Effect active.
    pub enabled: bool,
    /// Effective bulk modulus [Pa], 1e6 ..= 1e10 (replaces `fluid.bulk_modulus_pa`).
    pub effective_bulk_modulus_pa: f64,
}

impl Default for ComplianceEffect {
    fn default() -> Self {
        Self {
            enabled: false,
            effective_bulk_modulus_pa: 1.2e9,
        }
    }
}

/// Supply pressure drooping linearly with the flow drawn from it: `pA,eff = pA − r·Q`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SupplySagEffect {
    /// Effect active.
    pub enabled: bool,
    /// Droop `r` [Pa/(m³/s)], 0 ..= 1e12 (1e10 ≈ 1.7 bar per L/min).
    pub droop_pa_per_m3_s: f64,
}

impl Default for SupplySagEffect {
    fn default() -> Self {
        Self {
            enabled: false,
            droop_pa_per_m3_s: 0.0,
        }
    }
}

/// Everything that defines the rig, its controller and the numerics. The content of a preset.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields, default)]
pub struct Params {
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
    /// Controller: the paper's Eq. (16) or another structure ([`ControllerKind`]).
    pub controller: ControllerParams,
    /// Passive reference.
    pub passive: PassiveParams,
    /// Simplified model G(s).
    pub linear: LinearParams,
    /// Integrator options.
    pub numerics: NumericsParams,
    /// Optional physical effects (off by default).
    pub effects: EffectsParams,
}

impl Params {
    /// The paper's adjusted digital twin (Cd = 0.1506, τ = 17.5 ms).
    pub fn paper() -> Self {
        Self::default()
    }

    /// Checks every parameter against its range and the relations between them.
    pub fn validate(&self) -> Result<(), ParamError> {
        let b = &self.body;
        check("body.mass_kg", b.mass_kg, 1.0, 500.0, "kg")?;
        check(
            "body.stiffness_n_per_m",
            b.stiffness_n_per_m,
            1.0,
            1e6,
            "N/m",
        )?;
        let c = &self.cylinder;
        check("cylinder.stroke_m", c.stroke_m, 0.005, 1.0, "m")?;
        check("cylinder.bore_m", c.bore_m, 0.005, 0.3, "m")?;
        check("cylinder.rod_m", c.rod_m, 0.0, 0.3, "m")?;
        if c.rod_m >= c.bore_m {
            return Err(ParamError::OutOfRange {
                name: "cylinder.rod_m".into(),
                value: c.rod_m,
                min: 0.0,
                max: c.bore_m,
                unit: "m (must be smaller than cylinder.bore_m)",
            });
        }
        check(
            "cylinder.end_stop_stiffness_n_per_m",
            c.end_stop_stiffness_n_per_m,
            1e3,
            1e8,
            "N/m",
        )?;
        check(
            "cylinder.end_stop_damping_n_s_per_m",
            c.end_stop_damping_n_s_per_m,
            0.0,
            1e6,
            "N·s/m",
        )?;
        check("hose.length_m", self.hose.length_m, 0.01, 20.0, "m")?;
        check("hose.diameter_m", self.hose.diameter_m, 1e-3, 0.05, "m")?;
        let s = &self.supply;
        check(
            "supply.supply_pressure_pa",
            s.supply_pressure_pa,
            1e5,
            5e7,
            "Pa",
        )?;
        check(
            "supply.return_pressure_pa",
            s.return_pressure_pa,
            0.0,
            5e7,
            "Pa",
        )?;
        if s.return_pressure_pa >= s.supply_pressure_pa {
            return Err(ParamError::OutOfRange {
                name: "supply.return_pressure_pa".into(),
                value: s.return_pressure_pa,
                min: 0.0,
                max: s.supply_pressure_pa,
                unit: "Pa (must be below supply.supply_pressure_pa)",
            });
        }
        let v = &self.valve;
        check("valve.cd", v.cd, 1e-3, 1.0, "-")?;
        check("valve.ka_m", v.ka_m, 1e-4, 0.5, "m")?;
        check("valve.kv_m_per_v", v.kv_m_per_v, 1e-7, 1e-2, "m/V")?;
        check("valve.omega_n_rad_s", v.omega_n_rad_s, 1.0, 1e5, "rad/s")?;
        check("valve.zeta", v.zeta, 0.01, 10.0, "-")?;
        check("valve.xv_max_m", v.xv_max_m, 1e-6, 0.05, "m")?;
        check("valve.tau_s", v.tau_s, 0.0, MAX_DELAY_S, "s")?;
        check("valve.v_max_v", v.v_max_v, 0.1, 100.0, "V")?;
        check("valve.laminar_core_pa", v.laminar_core_pa, 1.0, 1e6, "Pa")?;
        let f = &self.fluid;
        check(
            "fluid.density_kg_m3",
            f.density_kg_m3,
            500.0,
            2000.0,
            "kg/m³",
        )?;
        check("fluid.viscosity_pa_s", f.viscosity_pa_s, 1e-4, 10.0, "Pa·s")?;
        check("fluid.bulk_modulus_pa", f.bulk_modulus_pa, 1e6, 1e10, "Pa")?;
        self.controller.validate()?;
        check("passive.zeta", self.passive.zeta, 0.0, 5.0, "-")?;
        let l = &self.linear;
        check("linear.sp_rad_s", l.sp_rad_s, 1.0, 1e5, "rad/s")?;
        check("linear.kg_m_per_s_v", l.kg_m_per_s_v, 1e-4, 10.0, "m/(s·V)")?;
        check("linear.zeta", l.zeta, 0.0, 10.0, "-")?;
        check("linear.tau_s", l.tau_s, 0.0, MAX_DELAY_S, "s")?;
        check(
            "numerics.max_step_s",
            self.numerics.max_step_s,
            1e-6,
            1e-3,
            "s",
        )?;
        self.validate_effects()?;
        let limit = self.step_limit_s();
        if self.numerics.max_step_s > limit {
            return Err(ParamError::OutOfRange {
                name: "numerics.max_step_s".into(),
                value: self.numerics.max_step_s,
                min: 1e-6,
                max: limit,
                unit: match self.numerics.integrator {
                    Integrator::Rk4 => "s (RK4 stability limit from the hose and oil-column modes)",
                    Integrator::Exponential => {
                        "s (stability limit of the explicit part: end-stop contact, friction)"
                    }
                },
            });
        }
        Ok(())
    }

    fn validate_effects(&self) -> Result<(), ParamError> {
        let e = &self.effects;
        let fr = &e.friction;
        check("effects.friction.coulomb_n", fr.coulomb_n, 0.0, 5000.0, "N")?;
        check(
            "effects.friction.viscous_n_s_per_m",
            fr.viscous_n_s_per_m,
            0.0,
            1e5,
            "N·s/m",
        )?;
        check(
            "effects.friction.stribeck_n",
            fr.stribeck_n,
            0.0,
            5000.0,
            "N",
        )?;
        check(
            "effects.friction.stribeck_velocity_m_s",
            fr.stribeck_velocity_m_s,
            1e-5,
            1.0,
            "m/s",
        )?;
        check(
            "effects.friction.smoothing_velocity_m_s",
            fr.smoothing_velocity_m_s,
            1e-5,
            0.1,
            "m/s",
        )?;
        check(
            "effects.valve_overlap.overlap_m",
            e.valve_overlap.overlap_m,
            0.0,
            0.01,
            "m",
        )?;
        check(
            "effects.valve_offset.bias_v",
            e.valve_offset.bias_v,
            -5.0,
            5.0,
            "V",
        )?;
        check(
            "effects.leakage.coefficient_m3_per_s_pa",
            e.leakage.coefficient_m3_per_s_pa,
            0.0,
            1e-9,
            "m³/(s·Pa)",
        )?;
        check(
            "effects.compliance.effective_bulk_modulus_pa",
            e.compliance.effective_bulk_modulus_pa,
            1e6,
            1e10,
            "Pa",
        )?;
        check(
            "effects.supply_sag.droop_pa_per_m3_s",
            e.supply_sag.droop_pa_per_m3_s,
            0.0,
            1e12,
            "Pa/(m³/s)",
        )?;
        Ok(())
    }

    /// Bulk modulus in use [Pa]: the compliance effect's, if enabled, else the fluid's.
    pub fn effective_bulk_modulus_pa(&self) -> f64 {
        if self.effects.compliance.enabled {
            self.effects.compliance.effective_bulk_modulus_pa
        } else {
            self.fluid.bulk_modulus_pa
        }
    }

    /// Largest stable step of the configured integrator [s].
    pub fn step_limit_s(&self) -> f64 {
        match self.numerics.integrator {
            Integrator::Rk4 => self.rk4_step_limit_s(),
            Integrator::Exponential => self.exponential_step_limit_s(),
        }
    }

    /// Rate of the smoothed friction seen as a viscous damper of slope (Fc + Fs)/v_eps + b, per
    /// unit mass [1/s] (a real eigenvalue); 0 with friction off.
    fn friction_rate_rad_s(&self) -> f64 {
        let fr = &self.effects.friction;
        if fr.enabled {
            ((fr.coulomb_n + fr.stribeck_n) / fr.smoothing_velocity_m_s + fr.viscous_n_s_per_m)
                / self.body.mass_kg
        } else {
            0.0
        }
    }

    /// Largest stable step of the exponential integrator [s], capped at 1 ms. Its linear part
    /// (hoses, oil column, spool) is exact; what it treats explicitly and could destabilise is
    /// the end-stop contact (spring on the body while in contact) and smoothed friction.
    pub fn exponential_step_limit_s(&self) -> f64 {
        let w_contact = (self.cylinder.end_stop_stiffness_n_per_m / self.body.mass_kg).sqrt();
        let w_friction = self.friction_rate_rad_s();
        (0.85 * 2.83 / w_contact.max(w_friction)).min(1e-3)
    }

    /// Largest stable RK4 step [s], from the fastest oscillatory modes: the hose L–C mode
    /// (`1/√(I·C_eq)`) and the body on the oil column; RK4's stability boundary on the imaginary
    /// axis is `|hλ| ≈ 2.83`, and we keep a 15 % margin.
    pub fn rk4_step_limit_s(&self) -> f64 {
        let d = derived(self);
        // Hose inertance between the hose capacitance and the chamber capacitance in series.
        let c_series = d.c_hose * d.c_chamber / (d.c_hose + d.c_chamber);
        let w_hose = 1.0 / (d.inertance * c_series).sqrt();
        // Body on two oil columns (chamber + hose capacitance per side), plus end-stop contact.
        let k_oil = 2.0 * d.area.powi(2) / (d.c_chamber + d.c_hose);
        let w_body =
            ((k_oil + self.cylinder.end_stop_stiffness_n_per_m) / self.body.mass_kg).sqrt();
        let w_spool =
            self.valve.omega_n_rad_s * (self.valve.zeta + (self.valve.zeta.powi(2) + 1.0).sqrt());
        let w_friction = self.friction_rate_rad_s();
        let w_max = w_hose.max(w_body).max(w_spool).max(w_friction);
        0.85 * 2.83 / w_max
    }
}

/// Largest pure delay accepted anywhere [s].
pub const MAX_DELAY_S: f64 = 0.1;

/// Lumped hydraulic quantities derived from the parameters, Eqs. (8)–(11).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Derived {
    /// Piston area A1 = A2 [m²].
    pub area: f64,
    /// Hose resistance R, Eq. (8) [Pa·s/m³].
    pub resistance: f64,
    /// Hose inertance I, Eq. (9) [kg/m⁴].
    pub inertance: f64,
    /// Hose capacitance C, Eq. (10) [m³/Pa].
    pub c_hose: f64,
    /// Chamber capacitance C_c, Eq. (11) [m³/Pa].
    pub c_chamber: f64,
}

/// Computes the lumped hose and chamber quantities of Eqs. (8)–(11), with the effective bulk
/// modulus (compliance effect) applied to hoses and chambers alike.
pub fn derived(p: &Params) -> Derived {
    let beta = p.effective_bulk_modulus_pa();
    let (l, d) = (p.hose.length_m, p.hose.diameter_m);
    let area = p.cylinder.piston_area_m2();
    Derived {
        area,
        resistance: 128.0 * p.fluid.viscosity_pa_s * l / (PI * d.powi(4)),
        inertance: 4.0 * p.fluid.density_kg_m3 * l / (PI * d * d),
        c_hose: PI * l * d * d / (4.0 * beta),
        c_chamber: PI
            * p.cylinder.stroke_m
            * (p.cylinder.bore_m.powi(2) - p.cylinder.rod_m.powi(2))
            / (8.0 * beta),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paper_defaults_validate() {
        Params::paper().validate().unwrap();
    }

    #[test]
    fn derived_quantities_match_hand_calculation() {
        let d = derived(&Params::paper());
        // A = π/4·(25² − 18²) mm² = 236.4 mm²
        assert!((d.area - 2.3640e-4).abs() < 1e-7);
        // R = 128·0.02·0.5/(π·1e-8) = 4.074e7 Pa·s/m³
        assert!((d.resistance / 4.0744e7 - 1.0).abs() < 1e-3);
        // I = 4·840·0.5/(π·1e-4) = 5.348e6 kg/m⁴
        assert!((d.inertance / 5.3476e6 - 1.0).abs() < 1e-3);
        // C = π·0.5·1e-4/(4·1.2e9) = 3.272e-14 m³/Pa
        assert!((d.c_hose / 3.2725e-14 - 1.0).abs() < 1e-3);
        // Cc = half-stroke chamber volume / β = 236.4e-6·0.035/1.2e9 = 6.895e-15 m³/Pa
        assert!((d.c_chamber / 6.8950e-15 - 1.0).abs() < 1e-3);
    }

    #[test]
    fn invalid_values_are_refused_with_their_name() {
        let mut p = Params::paper();
        p.body.mass_kg = f64::NAN;
        let e = p.validate().unwrap_err();
        assert!(e.to_string().contains("body.mass_kg"), "{e}");
        let mut p = Params::paper();
        p.body.mass_kg = -1.0;
        assert!(p.validate().is_err());
        let mut p = Params::paper();
        p.cylinder.rod_m = 0.025;
        let e = p.validate().unwrap_err();
        assert!(e.to_string().contains("cylinder.rod_m"), "{e}");
        let mut p = Params::paper();
        p.supply.return_pressure_pa = 120e5;
        assert!(p.validate().is_err());
    }

    #[test]
    fn too_large_step_is_refused() {
        let mut p = Params::paper();
        p.numerics.integrator = Integrator::Rk4;
        p.numerics.max_step_s = 9e-4;
        let e = p.validate().unwrap_err();
        assert!(e.to_string().contains("numerics.max_step_s"), "{e}");
        assert!(e.to_string().contains("RK4"), "{e}");
        // The exponential method takes 0.9 ms, until a stiff end stop makes contact too fast.
        p.numerics.integrator = Integrator::Exponential;
        p.validate().unwrap();
        p.cylinder.end_stop_stiffness_n_per_m = 1e8;
        let e = p.validate().unwrap_err();
        assert!(e.to_string().contains("end-stop"), "{e}");
    }

    #[test]
    fn numbers_in_messages_are_short() {
        for (x, text) in [
            (0.0, "0"),
            (-0.0, "0"),
            (11.7, "11.7"),
            (3680.0, "3680"),
            (5e-4, "0.0005"),
            (1e-4, "0.0001"),
            (1e-6, "1e-6"),
            (1e7, "1e7"),
            (999_999.0, "999999"),
            (9_999_999.0, "1e7"),
            (1e300, "1e300"),
            (-2.5e-300, "-2.5e-300"),
            (0.1 + 0.2, "0.3"),
            (123.456789, "123.457"),
            (f64::NAN, "NaN"),
            (f64::NEG_INFINITY, "-inf"),
        ] {
            assert_eq!(fmt_value(x), text, "{x:e}");
        }
        let mut p = Params::paper();
        p.body.mass_kg = 1e300;
        let e = p.validate().unwrap_err().to_string();
        assert_eq!(
            e,
            "parameter `body.mass_kg` = 1e300 is outside the allowed range [1, 500] kg"
        );
    }
}
