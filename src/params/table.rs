//! The one table of parameters: for every number in a preset, its key, symbol, SI unit, valid
//! range, paper value and display unit. [`Params::validate`](super::Params::validate), the
//! app's sliders, the calibration's fitted knobs and the reports all read it from here, so a
//! range or a unit is written once.

use super::{ControllerKind, ParamError, Params, check};

/// How a parameter is shown to people: `display = SI value · scale`, in `unit`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Display {
    /// Factor from the SI value to the displayed one.
    pub scale: f64,
    /// Display unit (`""` for dimensionless).
    pub unit: &'static str,
}

/// One parameter of [`Params`].
#[derive(Clone, Copy)]
pub struct ParamSpec {
    /// Dotted key as in the preset file, e.g. `valve.cd`.
    pub key: &'static str,
    /// Short symbol for labels and reports (`Cd`, `τ`, `Kp`).
    pub symbol: &'static str,
    /// What it is, in a few words, with the paper's value where there is one.
    pub doc: &'static str,
    /// SI unit (`"-"` for dimensionless).
    pub unit: &'static str,
    /// Smallest valid value \[SI\].
    pub min: f64,
    /// Largest valid value \[SI\].
    pub max: f64,
    /// The paper's value \[SI\], if the paper gives one (its adjusted twin where it has two).
    pub paper: Option<f64>,
    /// Display unit and scale.
    pub display: Display,
    get: fn(&Params) -> f64,
    set: fn(&mut Params, f64),
}

impl std::fmt::Debug for ParamSpec {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ParamSpec")
            .field("key", &self.key)
            .field("unit", &self.unit)
            .field("min", &self.min)
            .field("max", &self.max)
            .finish_non_exhaustive()
    }
}

impl ParamSpec {
    /// The value in `p` \[SI\].
    pub fn get(&self, p: &Params) -> f64 {
        (self.get)(p)
    }

    /// Writes `value` \[SI\] into `p`, unchecked (see [`Params::set`] for the checked form).
    pub fn set_unchecked(&self, p: &mut Params, value: f64) {
        (self.set)(p, value)
    }

    /// `min ≤ value ≤ max` and finite, else the out-of-range error naming key, range and unit.
    pub fn check(&self, value: f64) -> Result<(), ParamError> {
        check(self.key, value, self.min, self.max, self.unit)
    }

    /// The value in display units.
    pub fn to_display(&self, si: f64) -> f64 {
        si * self.display.scale
    }

    /// The SI value of a displayed one.
    pub fn from_display(&self, shown: f64) -> f64 {
        shown / self.display.scale
    }

    /// The valid range in display units, low end first (the scale is positive for every
    /// entry; a test holds the table to it).
    pub fn display_range(&self) -> (f64, f64) {
        (self.to_display(self.min), self.to_display(self.max))
    }

    /// The controller gain this entry is (`kp_v_per_m`, …), if it is one.
    pub fn controller_key(&self) -> Option<&'static str> {
        self.key.strip_prefix("controller.")
    }

    /// Whether [`Params::validate`] checks this entry for `p`: every entry, except the gains
    /// of controller kinds other than `p`'s (they keep their defaults and are not used).
    pub fn applies_to(&self, kind: ControllerKind) -> bool {
        self.controller_key()
            .is_none_or(|k| kind.keys().contains(&k))
    }
}

macro_rules! entry {
    ($key:literal, $($field:ident).+, $sym:literal, $unit:literal, [$min:expr, $max:expr],
     $paper:expr, ($scale:expr, $dunit:literal), $doc:literal) => {
        ParamSpec {
            key: $key,
            symbol: $sym,
            doc: $doc,
            unit: $unit,
            min: $min,
            max: $max,
            paper: $paper,
            display: Display {
                scale: $scale,
                unit: $dunit,
            },
            get: |p| p.$($field).+,
            set: |p, v| p.$($field).+ = v,
        }
    };
}

/// Pascal per bar, litre per cubic metre and seconds per minute, for display scales.
const BAR: f64 = 1e5;
const L_PER_MIN: f64 = 1e-3 / 60.0;

/// Every number of a preset, in preset order.
#[rustfmt::skip]
pub static PARAMS: [ParamSpec; 63] = [
    entry!("body.mass_kg", plant.body.mass_kg, "m", "kg", [1.0, 500.0], Some(11.7), (1.0, "kg"),
        "suspended mass incl. seat, operator and payload"),
    entry!("body.stiffness_n_per_m", plant.body.stiffness_n_per_m, "k", "N/m", [1.0, 1e6], Some(3680.0),
        (1e-3, "kN/m"), "equivalent stiffness of all springs together"),
    entry!("cylinder.stroke_m", plant.cylinder.stroke_m, "Lc", "m", [0.005, 1.0], Some(0.070),
        (1e3, "mm"), "full stroke; the end stops sit at ±Lc/2"),
    entry!("cylinder.bore_m", plant.cylinder.bore_m, "D", "m", [0.005, 0.3], Some(0.025), (1e3, "mm"),
        "bore (larger than the rod)"),
    entry!("cylinder.rod_m", plant.cylinder.rod_m, "d", "m", [0.0, 0.3], Some(0.018), (1e3, "mm"),
        "rod diameter (smaller than the bore)"),
    entry!("cylinder.end_stop_stiffness_n_per_m", plant.cylinder.end_stop_stiffness_n_per_m, "k_stop",
        "N/m", [1e3, 1e8], None, (1e-6, "MN/m"), "contact stiffness of the end stops"),
    entry!("cylinder.end_stop_damping_n_s_per_m", plant.cylinder.end_stop_damping_n_s_per_m, "c_stop",
        "N·s/m", [0.0, 1e6], None, (1.0, "N·s/m"), "contact damping of the end stops"),
    entry!("hose.length_m", plant.hose.length_m, "Li", "m", [0.01, 20.0], Some(0.5), (1.0, "m"),
        "length of each hose"),
    entry!("hose.diameter_m", plant.hose.diameter_m, "di", "m", [1e-3, 0.05], Some(0.010), (1e3, "mm"),
        "inner diameter of each hose"),
    entry!("supply.supply_pressure_pa", plant.supply.supply_pressure_pa, "pA", "Pa", [1e5, 5e7],
        Some(100.0 * BAR), (1.0 / BAR, "bar"), "feed pressure (above the return pressure)"),
    entry!("supply.return_pressure_pa", plant.supply.return_pressure_pa, "p0", "Pa", [0.0, 5e7],
        Some(10.0 * BAR), (1.0 / BAR, "bar"), "discharge pressure (below the supply)"),
    entry!("valve.cd", plant.valve.cd, "Cd", "-", [1e-3, 1.0], Some(0.1506), (1.0, ""),
        "flow coefficient (paper: 0.1074 initial, 0.1506 adjusted)"),
    entry!("valve.ka_m", plant.valve.ka_m, "ka", "m", [1e-4, 0.5], Some(0.0251), (1e3, "mm"),
        "area gradient: opening area = ka·xv"),
    entry!("valve.kv_m_per_v", plant.valve.kv_m_per_v, "kv", "m/V", [1e-7, 1e-2], Some(8e-5),
        (1e3, "mm/V"), "static spool gain"),
    entry!("valve.omega_n_rad_s", plant.valve.omega_n_rad_s, "ωn", "rad/s", [1.0, 1e5], Some(691.0),
        (1.0, "rad/s"), "spool natural frequency"),
    entry!("valve.zeta", plant.valve.zeta, "ζs", "-", [0.01, 10.0], Some(1.1), (1.0, ""),
        "spool damping ratio"),
    entry!("valve.xv_max_m", plant.valve.xv_max_m, "xv,max", "m", [1e-6, 0.05], Some(0.8e-3), (1e3, "mm"),
        "spool travel limit"),
    entry!("valve.tau_s", plant.valve.tau_s, "τ", "s", [0.0, super::MAX_DELAY_S], Some(0.0175),
        (1e3, "ms"), "pure input delay of the valve command (paper: 17.5 ms adjusted)"),
    entry!("valve.v_max_v", plant.valve.v_max_v, "Vmax", "V", [0.1, 100.0], Some(10.0), (1.0, "V"),
        "command saturation ±Vmax"),
    entry!("valve.laminar_core_pa", plant.valve.laminar_core_pa, "p_lam", "Pa", [1.0, 1e6], None,
        (1.0 / BAR, "bar"), "width of the laminar core of the orifice's signed square root"),
    entry!("fluid.density_kg_m3", plant.fluid.density_kg_m3, "ρ", "kg/m³", [500.0, 2000.0], Some(840.0),
        (1.0, "kg/m³"), "oil density"),
    entry!("fluid.viscosity_pa_s", plant.fluid.viscosity_pa_s, "μ", "Pa·s", [1e-4, 10.0], Some(0.02),
        (1e3, "mPa·s"), "dynamic viscosity of the oil"),
    entry!("fluid.bulk_modulus_pa", plant.fluid.bulk_modulus_pa, "β", "Pa", [1e6, 1e10], Some(1.2e9),
        (1e-9, "GPa"), "bulk modulus of the oil"),
    entry!("controller.kp_v_per_m", controller.kp_v_per_m, "Kp", "V/m", [-1e4, 1e4], Some(-5.0),
        (1.0, "V/m"), "position gain on the stroke u (all kinds)"),
    entry!("controller.ki_v_s_per_m", controller.ki_v_s_per_m, "Ki", "V·s/m", [-1e3, 1e3],
        Some(-7.5), (1.0, "V·s/m"),
        "gain on the integral of the platform acceleration (all kinds)"),
    entry!("controller.lead_s", controller.lead_s, "lead", "s", [0.0, 0.1], None, (1e3, "ms"),
        "prediction horizon of the platform velocity (predictive)"),
    entry!("controller.lead_cutoff_hz", controller.lead_cutoff_hz, "f_lead", "Hz", [0.5, 200.0],
        None, (1.0, "Hz"), "corner of the low-pass on the predicted term (predictive)"),
    entry!("controller.sky_v_s_per_m", controller.sky_v_s_per_m, "Ksky", "V·s/m", [-1e3, 1e3], None,
        (1.0, "V·s/m"), "gain on the estimated absolute body velocity (skyhook)"),
    entry!("controller.leak_hz", controller.leak_hz, "f_leak", "Hz", [0.01, 10.0], None,
        (1.0, "Hz"), "corner of the leaky integrator of the body acceleration (skyhook)"),
    entry!("controller.sky_cutoff_hz", controller.sky_cutoff_hz, "f_sky", "Hz", [0.5, 200.0], None,
        (1.0, "Hz"), "corner of the low-pass on the body-velocity estimate (skyhook)"),
    entry!("passive.zeta", passive.zeta, "ζ", "-", [0.0, 5.0], Some(0.3), (1.0, ""),
        "damping ratio of the passive reference suspension"),
    entry!("linear.sp_rad_s", linear.sp_rad_s, "sp", "rad/s", [1.0, 1e5], Some(500.0),
        (1.0, "rad/s"), "pole location of G(s)"),
    entry!("linear.kg_m_per_s_v", linear.kg_m_per_s_v, "Kg", "m/(s·V)", [1e-4, 10.0], Some(0.13325),
        (1e3, "mm/(s·V)"), "static gain of G(s)"),
    entry!("linear.zeta", linear.zeta, "ζp", "-", [0.0, 10.0], Some(0.05), (1.0, ""),
        "damping factor of G(s)"),
    entry!("linear.tau_s", linear.tau_s, "τ_G", "s", [0.0, super::MAX_DELAY_S], Some(0.0175),
        (1e3, "ms"), "pure delay of G(s)"),
    entry!("numerics.max_step_s", numerics.max_step_s, "h_max", "s", [1e-6, 1e-3], None,
        (1e3, "ms"), "largest internal step of the twin's integrator"),
    entry!("sensors.ydd_scale", sensors.ydd_scale, "k_ÿ", "-", [0.5, 2.0], None, (1.0, ""),
        "scale of the body accelerometer (1: exact)"),
    entry!("sensors.ydd_offset_m_s2", sensors.ydd_offset_m_s2, "ÿ_0", "m/s^2", [-50.0, 50.0], None,
        (1.0, "m/s²"), "offset of the body accelerometer"),
    entry!("sensors.u_lag_s", sensors.u_lag_s, "τ_u", "s", [0.0, 0.05], None, (1e3, "ms"),
        "lag of the stroke sensor"),
    entry!("effects.friction.coulomb_n", plant.effects.friction.coulomb_n, "F_c", "N", [0.0, 5000.0],
        None, (1.0, "N"), "Coulomb friction force"),
    entry!("effects.friction.viscous_n_s_per_m", plant.effects.friction.viscous_n_s_per_m, "b", "N·s/m",
        [0.0, 1e5], None, (1.0, "N·s/m"), "viscous friction coefficient"),
    entry!("effects.friction.stribeck_n", plant.effects.friction.stribeck_n, "F_s", "N", [0.0, 5000.0],
        None, (1.0, "N"), "static (Stribeck) force above Coulomb"),
    entry!("effects.friction.stribeck_velocity_m_s", plant.effects.friction.stribeck_velocity_m_s, "v_s",
        "m/s", [1e-5, 1.0], None, (1e3, "mm/s"), "Stribeck velocity"),
    entry!("effects.friction.smoothing_velocity_m_s", plant.effects.friction.smoothing_velocity_m_s,
        "v_eps", "m/s", [1e-5, 0.1], None, (1e3, "mm/s"),
        "smoothing velocity of the friction's sign function"),
    entry!("effects.valve_overlap.overlap_m", plant.effects.valve_overlap.overlap_m, "overlap", "m",
        [0.0, 0.01], None, (1e6, "µm"), "spool overlap on each side of null"),
    entry!("effects.valve_overlap.edge_width_m", plant.effects.valve_overlap.edge_width_m, "w_edge",
        "m", [0.0, 0.01], None, (1e6, "µm"),
        "width over which the overlap's rounded edges open (0: sharp)"),
    entry!("effects.valve_offset.bias_v", plant.effects.valve_offset.bias_v, "V_bias", "V", [-5.0, 5.0],
        None, (1e3, "mV"), "valve null offset as a command bias"),
    entry!("effects.leakage.coefficient_m3_per_s_pa", plant.effects.leakage.coefficient_m3_per_s_pa,
        "C_leak", "m³/(s·Pa)", [0.0, 1e-9], None, (BAR / L_PER_MIN, "(L/min)/bar"),
        "internal leakage coefficient across the piston"),
    entry!("effects.leakage.growth_per_pa", plant.effects.leakage.growth_per_pa, "g_leak", "1/Pa",
        [0.0, 1e-6], None, (1e9, "% per 100 bar"),
        "growth of the leakage coefficient with the pressure across the piston"),
    entry!("effects.compliance.effective_bulk_modulus_pa",
        plant.effects.compliance.effective_bulk_modulus_pa, "β", "Pa", [1e6, 1e10], None, (1e-9, "GPa"),
        "effective bulk modulus with air and hose walls"),
    entry!("effects.compliance.hose_bulk_modulus_pa", plant.effects.compliance.hose_bulk_modulus_pa,
        "β_hose", "Pa", [0.0, 1e10], None, (1e-9, "GPa"),
        "effective bulk modulus of the hoses (0: as the chambers)"),
    entry!("effects.supply_sag.droop_pa_per_m3_s", plant.effects.supply_sag.droop_pa_per_m3_s, "droop",
        "Pa/(m³/s)", [0.0, 1e12], None, (L_PER_MIN / BAR, "bar/(L/min)"),
        "supply pressure droop per drawn flow"),
    entry!("corrections.cd_opening_slope", plant.corrections.cd_opening_slope, "s_Cd", "-",
        [-0.5, 0.5], None, (100.0, "%"), "relative change of Cd from small to full spool opening"),
    entry!("corrections.flow_gain_direction", plant.corrections.flow_gain_direction, "a_dir", "-",
        [-0.5, 0.5], None, (100.0, "%"), "flow-gain difference between the spool directions"),
    entry!("corrections.flow_gain_direction_width_m", plant.corrections.flow_gain_direction_width_m,
        "w_dir", "m", [0.0, 0.01], None, (1e6, "µm"),
        "spool travel over which the direction difference builds up"),
    entry!("corrections.flow_gain_return_edge", plant.corrections.flow_gain_return_edge, "e_edge", "-",
        [-0.5, 0.5], None, (100.0, "%"), "flow-gain difference between tank and supply edges"),
    entry!("corrections.spring_n_per_m", plant.corrections.spring_n_per_m, "k_c", "N/m",
        [-1e5, 1e5], None, (1.0, "N/m"), "spring on the body beyond the declared stiffness"),
    entry!("corrections.quadratic_damping_n_s2_per_m2", plant.corrections.quadratic_damping_n_s2_per_m2,
        "c_q", "N·s²/m²", [0.0, 1e6], None, (1.0, "N·s²/m²"), "damping quadratic in the velocity"),
    entry!("corrections.turbulent_leakage_m3_per_s_sqrt_pa",
        plant.corrections.turbulent_leakage_m3_per_s_sqrt_pa, "c_t", "m³/(s·√Pa)", [0.0, 1e-7], None,
        (1.0, "m³/(s·√Pa)"), "leakage across the piston growing with √|Δp|"),
    entry!("corrections.command_lag_s", plant.corrections.command_lag_s, "T_cmd", "s", [0.0, 0.05],
        None, (1e3, "ms"), "first-order lag of the valve command"),
    entry!("corrections.command_drift_v_per_s", plant.corrections.command_drift_v_per_s, "r_null",
        "V/s", [-0.1, 0.1], None, (1e3, "mV/s"), "drift of the valve's null during each record"),
    // Added last, so that the exported FMU's value references of the entries above stay as
    // they were.
    entry!("sensors.antialias_hz", sensors.antialias_hz, "f_aa", "Hz", [0.0, 1e5], None, (1.0, "Hz"),
        "corner of the data acquisition's anti-alias filter (0: none)"),
    entry!("sensors.antialias_order", sensors.antialias_order, "n_aa", "-", [1.0, 8.0], None,
        (1.0, ""), "order of the anti-alias filter (Butterworth)"),
];

/// The table entry of a dotted key (`valve.cd`), `None` for an unknown key.
pub fn spec(key: &str) -> Option<&'static ParamSpec> {
    PARAMS.iter().find(|s| s.key == key)
}

impl Params {
    /// The value \[SI\] of a parameter by its dotted key, `None` for an unknown key.
    pub fn get(&self, key: &str) -> Option<f64> {
        spec(key).map(|s| s.get(self))
    }

    /// Sets a parameter \[SI\] by its dotted key, after checking its range; the whole set is
    /// not re-validated (relations between parameters are [`Params::validate`]'s job).
    pub fn set(&mut self, key: &str, value: f64) -> Result<(), ParamError> {
        let s = spec(key).ok_or_else(|| {
            ParamError::Inconsistent(format!("`{key}` is not a parameter of a preset"))
        })?;
        s.check(value)?;
        s.set_unchecked(self, value);
        Ok(())
    }

    /// Checks every entry of [`PARAMS`] that applies (see [`ParamSpec::applies_to`]).
    pub(super) fn check_ranges(&self) -> Result<(), ParamError> {
        let kind = self.controller.kind;
        PARAMS
            .iter()
            .filter(|s| s.applies_to(kind))
            .try_for_each(|s| s.check(s.get(self)))
    }
}

/// The table as Markdown for people writing presets: each key with its symbol, the value in
/// `p` (SI and in display units), the valid range, the paper's value and what it is. The
/// other controller kinds' gains are listed as unused.
pub fn describe(p: &Params) -> String {
    use crate::format::general;
    let mut out = String::from(
        "| key | symbol | value | unit | shown as | valid range | paper | what |\n\
         |---|---|---|---|---|---|---|---|\n",
    );
    for s in &PARAMS {
        let v = s.get(p);
        let shown = if s.display.scale == 1.0 && s.display.unit == s.unit.trim_matches('-') {
            String::new()
        } else {
            format!("{} {}", general(s.to_display(v)), s.display.unit)
        };
        let what = if s.applies_to(p.controller.kind) {
            s.doc.to_string()
        } else {
            format!("{} (not used by `{}`)", s.doc, p.controller.kind)
        };
        out.push_str(&format!(
            "| `{}` | {} | {} | {} | {} | {} … {} | {} | {} |\n",
            s.key,
            s.symbol,
            general(v),
            s.unit,
            shown,
            general(s.min),
            general(s.max),
            s.paper.map_or("–".into(), general),
            what
        ));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every number in a preset has an entry: the TOML of the paper's parameters has as many
    /// numeric leaves as the table has entries, once the other kinds' gains are added.
    #[test]
    fn every_number_has_an_entry() {
        fn count(v: &toml::Value) -> usize {
            match v {
                toml::Value::Table(t) => t.values().map(count).sum(),
                toml::Value::Float(_) | toml::Value::Integer(_) => 1,
                _ => 0,
            }
        }
        let p = Params::paper();
        let doc: toml::Value = toml::Value::try_from(p).unwrap();
        let other_gains = PARAMS
            .iter()
            .filter(|s| !s.applies_to(p.controller.kind))
            .count();
        assert_eq!(count(&doc) + other_gains, PARAMS.len());
        let mut keys: Vec<_> = PARAMS.iter().map(|s| s.key).collect();
        keys.sort();
        keys.dedup();
        assert_eq!(keys.len(), PARAMS.len(), "a key is listed twice");
    }

    #[test]
    fn paper_values_are_the_defaults_and_lie_in_range() {
        let p = Params::paper();
        for s in &PARAMS {
            assert!(s.min < s.max && s.display.scale > 0.0, "{}", s.key);
            s.check(s.get(&p)).unwrap();
            if let Some(v) = s.paper {
                assert_eq!(s.get(&p), v, "{}", s.key);
            }
        }
    }

    #[test]
    fn set_checks_the_range_and_names_the_key() {
        let mut p = Params::paper();
        p.set("valve.cd", 0.12).unwrap();
        assert_eq!(p.plant.valve.cd, 0.12);
        let e = p.set("valve.cd", 2.0).unwrap_err().to_string();
        assert!(e.contains("valve.cd") && e.contains("[0.001, 1]"), "{e}");
        assert_eq!(p.plant.valve.cd, 0.12, "a refused value is not written");
        assert!(p.set("valve.nothing", 1.0).is_err());
        assert_eq!(p.get("supply.supply_pressure_pa"), Some(1e7));
        let s = spec("supply.supply_pressure_pa").unwrap();
        assert!((s.to_display(1e7) - 100.0).abs() < 1e-12);
        // 1 (L/min)/bar = 1.667e-5 m³/s per 1e5 Pa.
        let leak = spec("effects.leakage.coefficient_m3_per_s_pa").unwrap();
        assert!((leak.to_display(1e-3 / 60.0 / 1e5) - 1.0).abs() < 1e-12);
    }

    #[test]
    fn other_kinds_gains_are_not_checked() {
        let mut p = Params::paper();
        p.controller.lead_s = 5.0; // out of range, but a paper controller does not read it
        p.validate().unwrap();
        p.controller.kind = ControllerKind::Predictive;
        let e = p.validate().unwrap_err().to_string();
        assert!(e.contains("controller.lead_s"), "{e}");
    }

    /// The field docs of the parameter structs state unit and range in words
    /// (`[kg], 1 ..= 500`); they must say what the table says, for every entry.
    #[test]
    fn field_docs_agree_with_the_table() {
        let sources = [
            include_str!("plant.rs"),
            include_str!("controller.rs"),
            include_str!("models.rs"),
            include_str!("numerics.rs"),
            include_str!("effects.rs"),
            include_str!("sensors.rs"),
            include_str!("corrections.rs"),
        ];
        let section = |ty: &str| -> Option<&str> {
            Some(match ty {
                "BodyParams" => "body",
                "CylinderParams" => "cylinder",
                "HoseParams" => "hose",
                "SupplyParams" => "supply",
                "ValveParams" => "valve",
                "FluidParams" => "fluid",
                "ControllerParams" => "controller",
                "PassiveParams" => "passive",
                "LinearParams" => "linear",
                "NumericsParams" => "numerics",
                "SensorParams" => "sensors",
                "CorrectionParams" => "corrections",
                "FrictionEffect" => "effects.friction",
                "OverlapEffect" => "effects.valve_overlap",
                "OffsetEffect" => "effects.valve_offset",
                "LeakageEffect" => "effects.leakage",
                "ComplianceEffect" => "effects.compliance",
                "SupplySagEffect" => "effects.supply_sag",
                _ => return None,
            })
        };
        let mut seen = Vec::new();
        for src in sources {
            let (mut current, mut doc) = (None, String::new());
            for line in src.lines().map(str::trim) {
                if let Some(rest) = line.strip_prefix("pub struct ") {
                    current = section(rest.split_whitespace().next().unwrap_or(""));
                } else if let Some(d) = line.strip_prefix("///") {
                    doc.push_str(d);
                    doc.push(' ');
                    continue;
                } else if let (Some(sec), Some(field)) = (
                    current,
                    line.strip_prefix("pub ")
                        .and_then(|l| l.strip_suffix(": f64,")),
                ) {
                    let key = format!("{sec}.{field}");
                    let s = spec(&key).unwrap_or_else(|| panic!("{key} has no table entry"));
                    // The unit in brackets, escaped (`\[kg\]`, which rustdoc would otherwise
                    // read as a link) or not (`[m/s]`).
                    let plain = doc.replace("\\[", "[").replace("\\]", "]");
                    let unit = plain.split('[').nth(1).and_then(|u| u.split(']').next());
                    assert_eq!(unit, Some(s.unit), "{key}: unit in its doc: {doc}");
                    let words: Vec<&str> = doc.split_whitespace().collect();
                    let at = words.iter().position(|w| *w == "..=");
                    let at = at.unwrap_or_else(|| panic!("{key}: no range in its doc"));
                    let num = |w: &str| w.trim_end_matches([',', '.', ';']).parse::<f64>().ok();
                    assert_eq!(num(words[at - 1]), Some(s.min), "{key}: min in {doc}");
                    assert_eq!(num(words[at + 1]), Some(s.max), "{key}: max in {doc}");
                    seen.push(key);
                }
                doc.clear();
            }
        }
        assert_eq!(seen.len(), PARAMS.len(), "documented: {seen:?}");
    }

    #[test]
    fn describe_lists_every_key_with_its_value() {
        let mut p = Params::paper();
        p.plant.supply.supply_pressure_pa = 1.5e7;
        let text = describe(&p);
        assert_eq!(text.lines().count(), PARAMS.len() + 2);
        let row = text
            .lines()
            .find(|l| l.contains("`supply.supply_pressure_pa`"))
            .unwrap();
        assert!(
            row.contains("| 1.5e7 | Pa | 150 bar | 100000 … 5e7 | 1e7 |"),
            "{row}"
        );
        let lead = text
            .lines()
            .find(|l| l.contains("`controller.lead_s`"))
            .unwrap();
        assert!(lead.contains("not used by `paper`"), "{lead}");
    }

    /// docs/model.md (section 9) lists every parameter with its unit and range; each row must
    /// say what the table says, and every entry must have a row.
    #[test]
    fn model_docs_agree_with_the_table() {
        let doc = include_str!("../../docs/model.md");
        let plain = |t: &str| t.trim().replace(['−', '–'], "-");
        let mut seen = Vec::new();
        for line in doc.lines().filter(|l| l.starts_with("| `")) {
            let cells: Vec<String> = line.split('|').map(plain).collect();
            let key = cells[1].trim_matches('`');
            let key = key.split('`').next().unwrap_or(key);
            let Some(s) = spec(key) else { continue };
            // Plant, controller and reference tables: key | symbol | unit | range | …;
            // the effects table: key (symbol) | unit | range | default.
            let (unit, range) = if cells.len() == 6 {
                (&cells[2], &cells[3])
            } else {
                (&cells[3], &cells[4])
            };
            assert_eq!(unit, s.unit, "{key}: unit in docs/model.md");
            let (lo, hi) = range
                .split_once('…')
                .unwrap_or_else(|| panic!("{key}: {range}"));
            let num = |t: &str| t.trim_end_matches([',', '.']).parse::<f64>().ok();
            assert_eq!(
                num(lo.split_whitespace().last().unwrap_or("")),
                Some(s.min),
                "{key}"
            );
            assert_eq!(
                num(hi.split_whitespace().next().unwrap_or("")),
                Some(s.max),
                "{key}"
            );
            seen.push(key.to_string());
        }
        let missing: Vec<_> = PARAMS
            .iter()
            .filter(|s| !seen.iter().any(|k| k == s.key))
            .collect();
        assert!(missing.is_empty(), "not in docs/model.md: {missing:?}");
    }
}
