//! Parameter structs of the rig, its controller and the numerics.
//!
//! Every field is in SI units, documents its unit and valid range, and is checked by
//! [`Params::validate`]. Defaults are the paper's adjusted twin (section 3 and 4.2, with the
//! corrections listed in `docs/model.md`): `Cd = 0.1506`, `τ = 17.5 ms`, `k = 3680 N/m` in total.

use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

mod controller;
mod corrections;
mod effects;
mod models;
mod numerics;
mod plant;
mod sensors;
mod table;

pub use controller::{ControllerKind, ControllerParams};
pub use corrections::CorrectionParams;
pub use effects::{
    ComplianceEffect, EffectsParams, FrictionEffect, LeakageEffect, OffsetEffect, OverlapEffect,
    SupplySagEffect,
};
pub use models::{LinearParams, PassiveParams};
pub use numerics::{Integrator, NumericsParams};
pub use plant::{
    BodyParams, CylinderParams, FluidParams, HoseParams, PlantParams, SupplyParams, ValveParams,
};
pub use sensors::{SensorParams, StrokeReader};
pub use table::{Display, PARAMS, ParamSpec, describe, spec};

/// A parameter outside its allowed range, or an inconsistent combination.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ParamError {
    /// A value outside `[min, max]` (or not finite).
    #[error(
        "parameter `{name}` = {} is outside the allowed range [{}, {}]{}",
        crate::format::general(*.value),
        crate::format::general(*.min),
        crate::format::general(*.max),
        unit_suffix(unit)
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

/// " m" after a range for a unit, " (dimensionless)" for the table's "-".
fn unit_suffix(unit: &str) -> String {
    match unit {
        "" => String::new(),
        "-" => " (dimensionless)".into(),
        u => format!(" {u}"),
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

/// Everything that defines the rig, its controller and the numerics: the content of a preset.
/// Three parts that change for different reasons: the [`PlantParams`] (what the twin is built
/// from; a change rebuilds it), the [`ControllerParams`] (gains change while it runs) and the
/// [`NumericsParams`] (how it is integrated); beside them the two reference models.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields, default)]
pub struct Params {
    /// The physical rig: body, cylinder, hoses, supply, valve, oil and optional effects.
    pub plant: PlantParams,
    /// Controller: the paper's Eq. (16) or another structure ([`ControllerKind`]).
    pub controller: ControllerParams,
    /// Passive reference.
    pub passive: PassiveParams,
    /// Simplified model G(s).
    pub linear: LinearParams,
    /// Integrator options.
    pub numerics: NumericsParams,
    /// How the records' sensors read the twin (calibrated; applied by the replay).
    pub sensors: SensorParams,
}

impl Params {
    /// The paper's adjusted digital twin (Cd = 0.1506, τ = 17.5 ms).
    pub fn paper() -> Self {
        Self::default()
    }

    /// Checks every parameter against its range in [`PARAMS`] and the relations between them:
    /// rod thinner than bore, return pressure below supply, step within the method's
    /// stability limit.
    pub fn validate(&self) -> Result<(), ParamError> {
        self.check_ranges()?;
        let (c, s) = (&self.plant.cylinder, &self.plant.supply);
        let step_unit = match self.numerics.integrator {
            Integrator::Rk4 => "s (RK4 stability limit from the hose and oil-column modes)",
            Integrator::Exponential => {
                "s (stability limit of the explicit part: end-stop contact, friction)"
            }
        };
        // (key, value, lowest, must stay below/at, unit with the reason, strictly below)
        let relations = [
            (
                "cylinder.rod_m",
                c.rod_m,
                0.0,
                c.bore_m,
                "m (must be smaller than cylinder.bore_m)",
                true,
            ),
            (
                "supply.return_pressure_pa",
                s.return_pressure_pa,
                0.0,
                s.supply_pressure_pa,
                "Pa (must be below supply.supply_pressure_pa)",
                true,
            ),
            (
                "numerics.max_step_s",
                self.numerics.max_step_s,
                1e-6,
                self.step_limit_s(),
                step_unit,
                false,
            ),
        ];
        // The hoses' modulus: 0 stands for "as the chambers"; a modulus of its own is a real one.
        let hose = self.plant.effects.compliance.hose_bulk_modulus_pa;
        if hose > 0.0 && hose < 1e6 {
            return Err(ParamError::OutOfRange {
                name: "effects.compliance.hose_bulk_modulus_pa".into(),
                value: hose,
                min: 1e6,
                max: 1e10,
                unit: "Pa (or 0: as the chambers)",
            });
        }
        // The anti-alias filter's order counts sections: a whole number.
        let order = self.sensors.antialias_order;
        if order.fract() != 0.0 {
            return Err(ParamError::OutOfRange {
                name: "sensors.antialias_order".into(),
                value: order,
                min: 1.0,
                max: 8.0,
                unit: "- (a whole number: the Butterworth filter's order)",
            });
        }
        for (name, value, min, max, unit, strict) in relations {
            if max < min {
                // No value can pass: say why, not an empty range `[min, max]`.
                return Err(ParamError::Inconsistent(format!(
                    "`{name}` has no allowed value with these parameters: the largest it may \
                     be is {} {unit}, below its smallest allowed value {}",
                    crate::format::general(max),
                    crate::format::general(min)
                )));
            }
            if value > max || (strict && value == max) {
                return Err(ParamError::OutOfRange {
                    name: name.into(),
                    value,
                    min,
                    max,
                    unit,
                });
            }
        }
        Ok(())
    }

    /// Bulk modulus in use \[Pa\]: the compliance effect's, if enabled, else the fluid's.
    pub fn effective_bulk_modulus_pa(&self) -> f64 {
        if self.plant.effects.compliance.enabled {
            self.plant.effects.compliance.effective_bulk_modulus_pa
        } else {
            self.plant.fluid.bulk_modulus_pa
        }
    }

    /// Bulk modulus in use in the hoses \[Pa\]: the compliance effect's hose modulus if
    /// enabled and set, else [`Self::effective_bulk_modulus_pa`].
    pub fn hose_bulk_modulus_pa(&self) -> f64 {
        let c = &self.plant.effects.compliance;
        if c.enabled && c.hose_bulk_modulus_pa > 0.0 {
            c.hose_bulk_modulus_pa
        } else {
            self.effective_bulk_modulus_pa()
        }
    }

    /// Largest stable step of the configured integrator \[s\].
    pub fn step_limit_s(&self) -> f64 {
        match self.numerics.integrator {
            Integrator::Rk4 => self.rk4_step_limit_s(),
            Integrator::Exponential => self.exponential_step_limit_s(),
        }
    }

    /// Rate of the smoothed friction seen as a viscous damper of slope (Fc + Fs)/v_eps + b, per
    /// unit mass [1/s] (a real eigenvalue); 0 with friction off.
    fn friction_rate_rad_s(&self) -> f64 {
        let fr = &self.plant.effects.friction;
        if fr.enabled {
            ((fr.coulomb_n + fr.stribeck_n) / fr.smoothing_velocity_m_s + fr.viscous_n_s_per_m)
                / self.plant.body.mass_kg
        } else {
            0.0
        }
    }

    /// Largest step \[s\] at which the exponential integrator resolves the smoothed friction it
    /// treats explicitly: one friction time constant, `1/rate` of
    /// `friction_rate_rad_s` (∞ with friction off). Below its stability limit
    /// ([`Self::exponential_step_limit_s`], 2.4/rate) a step is stable but smears the force's
    /// sign change at a reversal over too few steps: replayed against a 1 kHz record of a rig
    /// with a 2 mm/s smoothing (rate 2600 /s), the step of 0.5 ms left a start transient at
    /// 2.8× the sensor's noise floor that 0.33 ms (and anything finer) took to 1.35×.
    pub fn friction_resolving_step_s(&self) -> f64 {
        let rate = self.friction_rate_rad_s();
        if rate > 0.0 {
            1.0 / rate
        } else {
            f64::INFINITY
        }
    }

    /// Largest stable step of the exponential integrator \[s\], capped at 1 ms. Its linear part
    /// (hoses, oil column, spool) is exact; what it treats explicitly and could destabilise is
    /// the end-stop contact (spring on the body while in contact) and smoothed friction.
    pub fn exponential_step_limit_s(&self) -> f64 {
        let w_contact =
            (self.plant.cylinder.end_stop_stiffness_n_per_m / self.plant.body.mass_kg).sqrt();
        let w_friction = self.friction_rate_rad_s();
        (0.85 * 2.83 / w_contact.max(w_friction)).min(1e-3)
    }

    /// Largest stable RK4 step \[s\], from the fastest oscillatory modes: the hose L–C mode
    /// (`1/√(I·C_eq)`) and the body on the oil column; RK4's stability boundary on the imaginary
    /// axis is `|hλ| ≈ 2.83`, and we keep a 15 % margin.
    pub fn rk4_step_limit_s(&self) -> f64 {
        let d = derived(self);
        // Hose inertance between the hose capacitance and the chamber capacitance in series.
        let c_series = d.c_hose * d.c_chamber / (d.c_hose + d.c_chamber);
        let w_hose = 1.0 / (d.inertance * c_series).sqrt();
        // Body on two oil columns (chamber + hose capacitance per side), plus end-stop contact.
        let k_oil = 2.0 * d.area.powi(2) / (d.c_chamber + d.c_hose);
        let w_body = ((k_oil + self.plant.cylinder.end_stop_stiffness_n_per_m)
            / self.plant.body.mass_kg)
            .sqrt();
        let w_spool = self.plant.valve.omega_n_rad_s
            * (self.plant.valve.zeta + (self.plant.valve.zeta.powi(2) + 1.0).sqrt());
        let w_friction = self.friction_rate_rad_s();
        let w_max = w_hose.max(w_body).max(w_spool).max(w_friction);
        0.85 * 2.83 / w_max
    }
}

/// Largest pure delay accepted anywhere \[s\].
pub const MAX_DELAY_S: f64 = 0.1;

/// Lumped hydraulic quantities derived from the parameters, Eqs. (8)–(11).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Derived {
    /// Piston area A1 = A2 \[m²\].
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
/// moduli (compliance effect) of the hoses and the chambers.
pub fn derived(p: &Params) -> Derived {
    let beta = p.effective_bulk_modulus_pa();
    let beta_hose = p.hose_bulk_modulus_pa();
    let (l, d) = (p.plant.hose.length_m, p.plant.hose.diameter_m);
    let area = p.plant.cylinder.piston_area_m2();
    Derived {
        area,
        resistance: 128.0 * p.plant.fluid.viscosity_pa_s * l / (PI * d.powi(4)),
        inertance: 4.0 * p.plant.fluid.density_kg_m3 * l / (PI * d * d),
        c_hose: PI * l * d * d / (4.0 * beta_hose),
        c_chamber: PI
            * p.plant.cylinder.stroke_m
            * (p.plant.cylinder.bore_m.powi(2) - p.plant.cylinder.rod_m.powi(2))
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
    fn a_hose_modulus_is_zero_or_a_real_modulus() {
        let mut p = Params::paper();
        p.plant.effects.compliance.hose_bulk_modulus_pa = 5e8;
        p.validate().unwrap();
        p.plant.effects.compliance.hose_bulk_modulus_pa = 10.0;
        let e = p.validate().unwrap_err().to_string();
        assert!(
            e.contains("effects.compliance.hose_bulk_modulus_pa") && e.contains("as the chambers"),
            "{e}"
        );
    }

    #[test]
    fn friction_resolving_step_is_its_time_constant() {
        let mut p = Params::paper();
        assert_eq!(p.friction_resolving_step_s(), f64::INFINITY);
        let f = &mut p.plant.effects.friction;
        f.enabled = true;
        f.coulomb_n = 40.0;
        f.stribeck_n = 20.0;
        f.smoothing_velocity_m_s = 2e-3;
        f.viscous_n_s_per_m = 80.0;
        // (40 + 20)/0.002 + 80 = 30 080 N·s/m on 11.7 kg: 2571 /s.
        let rate = 30_080.0 / p.plant.body.mass_kg;
        assert!((p.friction_resolving_step_s() * rate - 1.0).abs() < 1e-12);
        assert!(p.friction_resolving_step_s() < p.exponential_step_limit_s());
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
        p.plant.body.mass_kg = f64::NAN;
        let e = p.validate().unwrap_err();
        assert!(e.to_string().contains("body.mass_kg"), "{e}");
        let mut p = Params::paper();
        p.plant.body.mass_kg = -1.0;
        assert!(p.validate().is_err());
        let mut p = Params::paper();
        p.plant.cylinder.rod_m = 0.025;
        let e = p.validate().unwrap_err();
        assert!(e.to_string().contains("cylinder.rod_m"), "{e}");
        let mut p = Params::paper();
        p.plant.supply.return_pressure_pa = 120e5;
        assert!(p.validate().is_err());
        // The anti-alias filter's order counts sections: 2.5 is refused by name, 9 by range.
        for (order, says) in [(2.5, "whole number"), (9.0, "8")] {
            let mut p = Params::paper();
            p.sensors.antialias_hz = 80.0;
            p.sensors.antialias_order = order;
            let e = p.validate().unwrap_err().to_string();
            assert!(
                e.contains("sensors.antialias_order") && e.contains(says),
                "{e}"
            );
        }
        let mut p = Params::paper();
        p.sensors.antialias_hz = -1.0;
        let e = p.validate().unwrap_err().to_string();
        assert!(e.contains("sensors.antialias_hz"), "{e}");
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
        p.plant.cylinder.end_stop_stiffness_n_per_m = 1e8;
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
            assert_eq!(crate::format::general(x), text, "{x:e}");
        }
        let mut p = Params::paper();
        p.plant.body.mass_kg = 1e300;
        let e = p.validate().unwrap_err().to_string();
        assert_eq!(
            e,
            "parameter `body.mass_kg` = 1e300 is outside the allowed range [1, 500] kg"
        );
    }
}
