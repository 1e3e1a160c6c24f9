//! Levenberg–Marquardt fit of a set of parameters ("knobs") of the twin to prepared records.
//!
//! Each knob maps a dimensionless unknown `θ` (order 1) to an SI parameter; non-negative
//! parameters use `|θ|`, so the fit can start at 0 (effect off) and the model stays valid.
//! The Jacobian is by forward differences, its columns simulated in parallel (rayon), each
//! column's records in parallel too. The fit stops after `max_jacobians` Jacobians, at
//! convergence, or on cancel. Uncertainties come from `(JᵀJ)⁻¹·s²`, inflated by `n/n_eff`
//! because the residual samples are correlated (`n_eff` from the lag-1 autocorrelation).

use super::IdentifyError;
use super::memo::ResidualMemo;
use super::progress::{Monitor, StopReason};
use super::replay::{PreparedRecord, StepRule};
use crate::params::{ParamSpec, Params, spec};
use levenberg_marquardt::{LeastSquaresProblem, LevenbergMarquardt, MinimizationReport};
use nalgebra::{DMatrix, DVector, Dyn, Owned};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

/// A fitted parameter of the twin, seen through a dimensionless unknown θ.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Knob {
    /// `valve.cd` [-] = 0.1·θ.
    Cd,
    /// `valve.tau_s` \[s\] = 0.01·θ.
    Tau,
    /// `body.mass_kg` \[kg\] = 10·θ.
    Mass,
    /// `effects.friction.coulomb_n` \[N\] = 10·|θ|.
    FrictionCoulomb,
    /// `effects.friction.viscous_n_s_per_m` [N·s/m] = 100·|θ|.
    FrictionViscous,
    /// `effects.valve_overlap.overlap_m` \[m\] = 2e-5·|θ|.
    Overlap,
    /// `effects.valve_overlap.edge_width_m` \[m\] = 2e-5·|θ|.
    OverlapEdge,
    /// `effects.friction.stribeck_n` \[N\] = 10·|θ|.
    FrictionStribeck,
    /// `effects.friction.stribeck_velocity_m_s` [m/s] = 0.01·|θ|, at least 0.5 mm/s: how fast
    /// the static excess dies away with the velocity (a shape knob, [`Knob::is_shape`]).
    FrictionStribeckVelocity,
    /// `effects.friction.smoothing_velocity_m_s` [m/s] = 1e-3·|θ|, 0.5 ..= 10 mm/s: the
    /// velocity over which the friction force changes sign (pre-sliding; a shape knob).
    FrictionSmoothing,

    /// `effects.valve_offset.bias_v` \[V\] = 0.02·θ.
    Offset,
    /// `sensors.ydd_scale` [-] = 1 + 0.01·θ.
    SensorYddScale,
    /// `sensors.ydd_offset_m_s2` [m/s²] = 0.01·θ.
    SensorYddOffset,
    /// `sensors.u_lag_s` \[s\] = 1e-3·θ (clamped at 0).
    SensorULag,
    /// `effects.leakage.coefficient_m3_per_s_pa` [m³/(s·Pa)] = 1e-12·|θ|.
    Leakage,
    /// `effects.leakage.growth_per_pa` [1/Pa] = 1e-8·|θ|: the leakage coefficient's growth
    /// with the pressure across the piston.
    LeakageGrowth,
    /// `effects.compliance.effective_bulk_modulus_pa` \[Pa\] = β_fluid/(1 + |θ|).
    Compliance,
    /// `effects.compliance.hose_bulk_modulus_pa` \[Pa\] = β_chambers/(1 + |θ|): hoses softer
    /// than the chambers (set after [`Knob::Compliance`], whose value it divides).
    HoseCompliance,
    /// `effects.supply_sag.droop_pa_per_m3_s` [Pa/(m³/s)] = 1e10·|θ|.
    SupplySag,
    /// `corrections.cd_opening_slope` [-] = 0.1·θ.
    CdSlope,
    /// `corrections.flow_gain_direction` [-] = 0.05·θ.
    FlowDirection,
    /// `corrections.flow_gain_direction_width_m` \[m\] = 1e-4·|θ|.
    FlowDirectionWidth,
    /// `corrections.flow_gain_return_edge` [-] = 0.05·θ.
    ReturnEdge,
    /// `corrections.spring_n_per_m` [N/m] = 1000·θ, within ±90 % of the declared stiffness
    /// (a larger negative one would leave the body without a spring).
    ExtraSpring,
    /// `corrections.quadratic_damping_n_s2_per_m2` [N·s²/m²] = 1000·|θ|.
    QuadraticDamping,
    /// `corrections.turbulent_leakage_m3_per_s_sqrt_pa` [m³/(s·√Pa)] = 1e-9·|θ|.
    TurbulentLeakage,
    /// `corrections.command_lag_s` \[s\] = 1e-3·|θ|.
    CommandLag,
    /// `corrections.command_drift_v_per_s` [V/s] = 1e-3·θ.
    CommandDrift,
}

impl Knob {
    /// Whether the knob shapes its effect's law rather than sizing it: a search starts it at
    /// the value the parameters hold (the preset's), not at zero, since at zero size its
    /// shape cannot be seen.
    pub fn is_shape(self) -> bool {
        matches!(
            self,
            Knob::FrictionStribeckVelocity | Knob::FrictionSmoothing
        )
    }

    /// The sensor properties the calibration estimates beside the declared parameters.
    pub const SENSORS: [Knob; 3] = [
        Knob::SensorYddScale,
        Knob::SensorYddOffset,
        Knob::SensorULag,
    ];

    /// For a sensor property: its channel (`ydd`, `u`), its kind (`scale`, `offset`, `lag`)
    /// and its exact value (1 for a scale, else 0).
    pub fn sensor(self) -> Option<(&'static str, &'static str, f64)> {
        match self {
            Knob::SensorYddScale => Some(("ydd", "scale", 1.0)),
            Knob::SensorYddOffset => Some(("ydd", "offset", 0.0)),
            Knob::SensorULag => Some(("u", "lag", 0.0)),
            _ => None,
        }
    }

    /// Name with unit, as in reports (`cd`, `tau_s`, `coulomb_n`, …): the last part of its
    /// preset key.
    pub fn name(self) -> &'static str {
        let key = self.spec().key;
        key.rsplit('.').next().unwrap_or(key)
    }

    /// θ of the parameter's current value in `p`.
    pub fn theta(self, p: &Params) -> f64 {
        let e = &p.plant.effects;
        let c = &p.plant.corrections;
        match self {
            Knob::Cd => p.plant.valve.cd / 0.1,
            Knob::Tau => p.plant.valve.tau_s / 0.01,
            Knob::Mass => p.plant.body.mass_kg / 10.0,
            Knob::SensorYddScale => (p.sensors.ydd_scale - 1.0) / 0.01,
            Knob::SensorYddOffset => p.sensors.ydd_offset_m_s2 / 0.01,
            Knob::SensorULag => p.sensors.u_lag_s / 1e-3,
            Knob::FrictionCoulomb if e.friction.enabled => e.friction.coulomb_n / 10.0,
            Knob::FrictionViscous if e.friction.enabled => e.friction.viscous_n_s_per_m / 100.0,
            Knob::Overlap if e.valve_overlap.enabled => e.valve_overlap.overlap_m / 2e-5,
            Knob::OverlapEdge if e.valve_overlap.enabled => e.valve_overlap.edge_width_m / 2e-5,
            Knob::FrictionStribeck if e.friction.enabled => e.friction.stribeck_n / 10.0,
            Knob::FrictionStribeckVelocity => e.friction.stribeck_velocity_m_s / 0.01,
            Knob::FrictionSmoothing => e.friction.smoothing_velocity_m_s / 1e-3,

            Knob::Offset if e.valve_offset.enabled => e.valve_offset.bias_v / 0.02,
            Knob::Leakage if e.leakage.enabled => e.leakage.coefficient_m3_per_s_pa / 1e-12,
            Knob::LeakageGrowth if e.leakage.enabled => e.leakage.growth_per_pa / 1e-8,
            Knob::Compliance if e.compliance.enabled => {
                (p.plant.fluid.bulk_modulus_pa / e.compliance.effective_bulk_modulus_pa - 1.0)
                    .max(0.0)
            }
            Knob::HoseCompliance if e.compliance.enabled => {
                (p.effective_bulk_modulus_pa() / p.hose_bulk_modulus_pa() - 1.0).max(0.0)
            }
            Knob::SupplySag if e.supply_sag.enabled => e.supply_sag.droop_pa_per_m3_s / 1e10,
            Knob::CdSlope => c.cd_opening_slope / 0.1,
            Knob::FlowDirection => c.flow_gain_direction / 0.05,
            Knob::FlowDirectionWidth => c.flow_gain_direction_width_m / 1e-4,
            Knob::ReturnEdge => c.flow_gain_return_edge / 0.05,
            Knob::ExtraSpring => c.spring_n_per_m / 1000.0,
            Knob::QuadraticDamping => c.quadratic_damping_n_s2_per_m2 / 1000.0,
            Knob::TurbulentLeakage => c.turbulent_leakage_m3_per_s_sqrt_pa / 1e-9,
            Knob::CommandLag => c.command_lag_s / 1e-3,
            Knob::CommandDrift => c.command_drift_v_per_s / 1e-3,
            _ => 0.0,
        }
    }

    /// Its entry in the parameter table.
    pub fn spec(self) -> &'static ParamSpec {
        let key = match self {
            Knob::Cd => "valve.cd",
            Knob::Tau => "valve.tau_s",
            Knob::Mass => "body.mass_kg",
            Knob::SensorYddScale => "sensors.ydd_scale",
            Knob::SensorYddOffset => "sensors.ydd_offset_m_s2",
            Knob::SensorULag => "sensors.u_lag_s",
            Knob::FrictionCoulomb => "effects.friction.coulomb_n",
            Knob::FrictionViscous => "effects.friction.viscous_n_s_per_m",
            Knob::Overlap => "effects.valve_overlap.overlap_m",
            Knob::OverlapEdge => "effects.valve_overlap.edge_width_m",
            Knob::FrictionStribeck => "effects.friction.stribeck_n",
            Knob::FrictionStribeckVelocity => "effects.friction.stribeck_velocity_m_s",
            Knob::FrictionSmoothing => "effects.friction.smoothing_velocity_m_s",

            Knob::Offset => "effects.valve_offset.bias_v",
            Knob::Leakage => "effects.leakage.coefficient_m3_per_s_pa",
            Knob::LeakageGrowth => "effects.leakage.growth_per_pa",
            Knob::Compliance => "effects.compliance.effective_bulk_modulus_pa",
            Knob::HoseCompliance => "effects.compliance.hose_bulk_modulus_pa",
            Knob::SupplySag => "effects.supply_sag.droop_pa_per_m3_s",
            Knob::CdSlope => "corrections.cd_opening_slope",
            Knob::FlowDirection => "corrections.flow_gain_direction",
            Knob::FlowDirectionWidth => "corrections.flow_gain_direction_width_m",
            Knob::ReturnEdge => "corrections.flow_gain_return_edge",
            Knob::ExtraSpring => "corrections.spring_n_per_m",
            Knob::QuadraticDamping => "corrections.quadratic_damping_n_s2_per_m2",
            Knob::TurbulentLeakage => "corrections.turbulent_leakage_m3_per_s_sqrt_pa",
            Knob::CommandLag => "corrections.command_lag_s",
            Knob::CommandDrift => "corrections.command_drift_v_per_s",
        };
        spec(key).expect("every knob is in the parameter table")
    }

    /// Sets the parameter from θ, clamped into its range in the parameter table (the overlap
    /// also below 90 % of the spool travel), and enables its effect.
    pub fn set(self, p: &mut Params, theta: f64) {
        let s = self.spec();
        let a = theta.abs();
        let value = match self {
            Knob::Cd => 0.1 * theta,
            Knob::Tau => 0.01 * theta,
            Knob::Mass => 10.0 * theta,
            Knob::SensorYddScale => 1.0 + 0.01 * theta,
            Knob::SensorYddOffset => 0.01 * theta,
            Knob::SensorULag => 1e-3 * theta,
            Knob::FrictionCoulomb => 10.0 * a,
            Knob::FrictionViscous => 100.0 * a,
            Knob::Overlap => (2e-5 * a).min(0.9 * p.plant.valve.xv_max_m),
            Knob::OverlapEdge => (2e-5 * a).min(0.9 * p.plant.valve.xv_max_m),
            Knob::FrictionStribeck => 10.0 * a,
            Knob::FrictionStribeckVelocity => (0.01 * a).max(5e-4),
            Knob::FrictionSmoothing => (1e-3 * a).clamp(5e-4, 1e-2),

            Knob::Offset => 0.02 * theta,
            Knob::Leakage => 1e-12 * a,
            Knob::LeakageGrowth => 1e-8 * a,
            Knob::Compliance => p.plant.fluid.bulk_modulus_pa / (1.0 + a),
            // 0 stands for "as the chambers" (θ = 0).
            Knob::HoseCompliance if a == 0.0 => 0.0,
            Knob::HoseCompliance => p.effective_bulk_modulus_pa() / (1.0 + a),
            Knob::SupplySag => 1e10 * a,
            Knob::CdSlope => 0.1 * theta,
            Knob::FlowDirection | Knob::ReturnEdge => 0.05 * theta,
            Knob::FlowDirectionWidth => 1e-4 * a,
            Knob::ExtraSpring => {
                let k = 0.9 * p.plant.body.stiffness_n_per_m;
                (1000.0 * theta).clamp(-k, k)
            }
            Knob::QuadraticDamping => 1000.0 * a,
            Knob::TurbulentLeakage => 1e-9 * a,
            Knob::CommandLag => 1e-3 * a,
            Knob::CommandDrift => 1e-3 * theta,
        };
        // The hoses' modulus is the chambers' divided by (1 + θ_hose): a new chambers' modulus
        // keeps that ratio, so the two knobs can be set in either order.
        let hose_ratio =
            (self == Knob::Compliance && p.plant.effects.compliance.enabled).then(|| {
                p.plant.effects.compliance.hose_bulk_modulus_pa / p.effective_bulk_modulus_pa()
            });
        s.set_unchecked(p, value.clamp(s.min, s.max));
        let e = &mut p.plant.effects;
        if let Some(r) = hose_ratio {
            e.compliance.hose_bulk_modulus_pa = r * e.compliance.effective_bulk_modulus_pa;
        }
        match self {
            Knob::Cd | Knob::Tau | Knob::Mass => {}
            Knob::SensorYddScale | Knob::SensorYddOffset | Knob::SensorULag => {}
            Knob::FrictionCoulomb
            | Knob::FrictionViscous
            | Knob::FrictionStribeck
            | Knob::FrictionStribeckVelocity
            | Knob::FrictionSmoothing => e.friction.enabled = true,
            Knob::Overlap | Knob::OverlapEdge => e.valve_overlap.enabled = true,
            Knob::Offset => e.valve_offset.enabled = true,
            Knob::Leakage | Knob::LeakageGrowth => e.leakage.enabled = true,
            Knob::Compliance | Knob::HoseCompliance => e.compliance.enabled = true,
            Knob::SupplySag => e.supply_sag.enabled = true,
            // Corrections have no switch: zero is off.
            Knob::CdSlope
            | Knob::FlowDirection
            | Knob::FlowDirectionWidth
            | Knob::ReturnEdge
            | Knob::ExtraSpring
            | Knob::QuadraticDamping
            | Knob::TurbulentLeakage
            | Knob::CommandLag
            | Knob::CommandDrift => {}
        }
    }

    /// SI value of the parameter in `p` (for compliance, the bulk modulus in use).
    pub fn value(self, p: &Params) -> f64 {
        match self {
            Knob::Compliance => p.effective_bulk_modulus_pa(),
            Knob::HoseCompliance => p.hose_bulk_modulus_pa(),
            _ => self.spec().get(p),
        }
    }
}

/// A fitted parameter with its 1-σ uncertainty (SI).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FittedValue {
    /// Which parameter.
    pub knob: Knob,
    /// Name with unit.
    pub name: String,
    /// Value \[SI\].
    pub value: f64,
    /// Standard uncertainty \[SI\] (NaN when the fit cannot tell).
    pub std: f64,
}

impl FittedValue {
    /// Whether the records determine it: a finite 1-σ of at most half its size.
    pub fn is_determined(&self) -> bool {
        self.std.is_finite() && self.std <= 0.5 * self.value.abs()
    }
}

/// Outcome of one Levenberg–Marquardt fit.
#[derive(Debug, Clone)]
pub struct FitResult {
    /// The parameters with the fitted values set.
    pub params: Params,
    /// The fitted values and uncertainties, in knob order.
    pub values: Vec<FittedValue>,
    /// Sum of squared weighted residuals at the result.
    pub rss: f64,
    /// Number of residuals.
    pub n: usize,
    /// Why the optimiser stopped.
    pub termination: StopReason,
    /// Residual evaluations (each one replays every record).
    pub evaluations: usize,
    /// Correlation matrix of the fitted values (row-major, knob order).
    pub correlation: Vec<Vec<f64>>,
}

/// Shared evaluation context: the records and the calibration's [`Monitor`] (cancel flag,
/// observer, replay count).
pub struct Evaluator<'a> {
    /// The prepared records.
    pub records: &'a [PreparedRecord],
    /// Progress, cancel and the count of evaluations.
    pub monitor: &'a Monitor<'a>,
    /// How short the replays' step is.
    pub step: StepRule,
}

/// Penalty residual for a diverged replay (per element).
const DIVERGED_PENALTY: f64 = 1.0e3;

impl Evaluator<'_> {
    /// Number of residuals of the records.
    pub fn residual_len(&self) -> usize {
        self.records.iter().map(|r| r.residual_len()).sum()
    }

    /// Weighted residual vector of all records at `params` (diverged replays give a large
    /// constant penalty, so the optimiser steps back). `None` once cancelled.
    pub fn residuals(&self, params: &Params) -> Option<Vec<f64>> {
        if self.monitor.is_cancelled() {
            return None;
        }
        let key = ResidualMemo::key(params, self.records, self.step);
        if let Some(r) = self.monitor.residuals.get(&key) {
            return Some(r);
        }
        let parts: Vec<Vec<f64>> = self
            .records
            .par_iter()
            .map(|rec| {
                let mut v = Vec::with_capacity(rec.residual_len());
                match rec.simulate_with(params, self.step) {
                    Ok(sim) => rec.weighted_residuals(&sim, &mut v),
                    Err(_) => v.resize(rec.residual_len(), DIVERGED_PENALTY),
                }
                v
            })
            .collect();
        self.monitor.evaluated();
        if self.monitor.is_cancelled() {
            return None;
        }
        let r = parts.concat();
        self.monitor.residuals.put(key, &r);
        Some(r)
    }
}

struct Problem<'a, 'b> {
    ev: &'a Evaluator<'b>,
    /// Where the optimiser's Jacobians are taken, if not on `ev` ([`fit_steered`]).
    steer: Option<&'a Evaluator<'b>>,
    base: Params,
    knobs: &'a [Knob],
    theta: DVector<f64>,
    cache: Mutex<Option<(DVector<f64>, DVector<f64>)>>,
    best: Mutex<Option<(f64, DVector<f64>)>>,
    jacobians: AtomicUsize,
    max_jacobians: usize,
    last_jacobian: Mutex<Option<(DVector<f64>, DMatrix<f64>)>>,
}

fn params_at(base: &Params, knobs: &[Knob], theta: &DVector<f64>) -> Params {
    let mut p = *base;
    for (k, t) in knobs.iter().zip(theta.iter()) {
        k.set(&mut p, *t);
    }
    p
}

impl Problem<'_, '_> {
    fn eval(&self, theta: &DVector<f64>) -> Option<DVector<f64>> {
        if let Some((t, r)) = self.cache.lock().ok()?.as_ref()
            && t == theta
        {
            return Some(r.clone());
        }
        let r = DVector::from_vec(
            self.ev
                .residuals(&params_at(&self.base, self.knobs, theta))?,
        );
        let cost = r.norm_squared();
        if let Ok(mut b) = self.best.lock()
            && b.as_ref().is_none_or(|(c, _)| cost < *c)
        {
            *b = Some((cost, theta.clone()));
        }
        if let Ok(mut c) = self.cache.lock() {
            *c = Some((theta.clone(), r.clone()));
        }
        Some(r)
    }

    /// The Jacobian of the residual at `theta`, by forward differences.
    fn jacobian_at(&self, theta: &DVector<f64>) -> Option<DMatrix<f64>> {
        self.columns(self.ev, &self.eval(theta)?, theta)
    }

    /// The Jacobian the optimiser steps with: on `steer` where given, else [`jacobian_at`].
    fn steering_jacobian(&self, theta: &DVector<f64>) -> Option<DMatrix<f64>> {
        match self.steer {
            Some(steer) => {
                let r0 = steer.residuals(&params_at(&self.base, self.knobs, theta))?;
                self.columns(steer, &DVector::from_vec(r0), theta)
            }
            None => self.jacobian_at(theta),
        }
    }

    /// Forward differences of `ev`'s residual (`r0` at `theta`), one replay per knob.
    fn columns(
        &self,
        ev: &Evaluator<'_>,
        r0: &DVector<f64>,
        theta: &DVector<f64>,
    ) -> Option<DMatrix<f64>> {
        let cols: Vec<Option<DVector<f64>>> = (0..self.knobs.len())
            .into_par_iter()
            .map(|j| {
                let h = 1e-2 * theta[j].abs().max(1.0);
                let mut t = theta.clone();
                t[j] += h;
                let r = ev.residuals(&params_at(&self.base, self.knobs, &t))?;
                Some((DVector::from_vec(r) - r0) / h)
            })
            .collect();
        let mut jac = DMatrix::zeros(r0.len(), self.knobs.len());
        for (j, c) in cols.into_iter().enumerate() {
            jac.set_column(j, &c?);
        }
        Some(jac)
    }
}

impl LeastSquaresProblem<f64, Dyn, Dyn> for Problem<'_, '_> {
    type ResidualStorage = Owned<f64, Dyn>;
    type JacobianStorage = Owned<f64, Dyn, Dyn>;
    type ParameterStorage = Owned<f64, Dyn>;

    fn set_params(&mut self, x: &DVector<f64>) {
        self.theta.copy_from(x);
    }

    fn params(&self) -> DVector<f64> {
        self.theta.clone()
    }

    fn residuals(&self) -> Option<DVector<f64>> {
        self.eval(&self.theta)
    }

    fn jacobian(&self) -> Option<DMatrix<f64>> {
        if self.jacobians.fetch_add(1, Ordering::Relaxed) >= self.max_jacobians {
            return None;
        }
        let j = self.steering_jacobian(&self.theta)?;
        self.ev.monitor.jacobian();
        // Only a Jacobian of `ev` itself serves the covariance.
        if self.steer.is_none()
            && let Ok(mut l) = self.last_jacobian.lock()
        {
            *l = Some((self.theta.clone(), j.clone()));
        }
        Some(j)
    }
}

/// Effective number of independent residuals: `n·(1 − ρ)/(1 + ρ)` with ρ the lag-1
/// autocorrelation (AR(1) approximation), at least 1 % of `n`.
pub fn effective_count(r: &[f64]) -> f64 {
    let n = r.len() as f64;
    if r.len() < 3 {
        return n.max(1.0);
    }
    let c0: f64 = r.iter().map(|v| v * v).sum();
    let c1: f64 = r.windows(2).map(|w| w[0] * w[1]).sum();
    let rho = if c0 > 0.0 {
        (c1 / c0).clamp(0.0, 0.999)
    } else {
        0.0
    };
    (n * (1.0 - rho) / (1.0 + rho)).max(0.01 * n).max(1.0)
}

/// The Bayesian information criterion on the fit records, with the residual count corrected
/// for autocorrelation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bic {
    /// Residual count.
    pub n: usize,
    /// Effective (decorrelated) count ([`effective_count`]).
    pub n_eff: f64,
}

impl Bic {
    /// The criterion at the residual of `fit` (one more replay).
    pub fn at(ev: &Evaluator<'_>, fit: &FitResult) -> Result<Self, IdentifyError> {
        let r = ev.residuals(&fit.params).ok_or(IdentifyError::Cancelled)?;
        Ok(Self {
            n: ev.residual_len(),
            n_eff: effective_count(&r),
        })
    }

    /// `n_eff·ln(RSS/n) + k·ln(n_eff)` for a model of `k` parameters.
    pub fn value(&self, rss: f64, k: usize) -> f64 {
        self.n_eff * (rss / self.n as f64).ln() + k as f64 * self.n_eff.ln()
    }

    /// `n_eff/n`, for the fits' uncertainties.
    pub fn ratio(&self) -> f64 {
        self.n_eff / self.n as f64
    }
}

/// The residual's variance per independent residual, `s2 = RSS/(n − p)/(n_eff/n)`, of a
/// fit of `p` parameters to `n` residuals with `n_eff_ratio` = n_eff/n: the scale of the
/// covariance ([`fit`]) and of a profile's Δχ² ([`super::profile`]).
pub fn residual_variance(rss: f64, n: usize, p: usize, n_eff_ratio: f64) -> f64 {
    rss / (n.saturating_sub(p).max(1)) as f64 / n_eff_ratio.clamp(1e-6, 1.0)
}

/// The parameters' covariance `s2·(JᵀJ)⁻¹` from the Jacobian `jac`, with each parameter the
/// residual does not respond to at all (a zero column: a knob held at its bound, as a sensor
/// lag at 0 or a Stribeck velocity at its floor, where the one-sided difference moves
/// nothing) left out: its row and column are NaN (undetermined), and the others are the
/// covariance with it held where it is. Without that, one such column made `JᵀJ` singular
/// and every parameter of the fit read "undetermined" (a campaign whose fit was at its floor
/// then came out `insufficient_data`). `None` when the rest is singular too.
fn covariance(jac: &DMatrix<f64>, s2: f64) -> Option<DMatrix<f64>> {
    let p = jac.ncols();
    let norms: Vec<f64> = (0..p).map(|j| jac.column(j).norm()).collect();
    let largest = norms.iter().copied().fold(0.0, f64::max);
    let kept: Vec<usize> = (0..p)
        .filter(|&j| norms[j].is_finite() && norms[j] > 1e-12 * largest)
        .collect();
    if kept.is_empty() {
        return None;
    }
    let sub = jac.select_columns(kept.iter());
    let inv = (sub.transpose() * &sub).try_inverse()?;
    let mut cov = DMatrix::from_element(p, p, f64::NAN);
    for (a, &i) in kept.iter().enumerate() {
        for (b, &j) in kept.iter().enumerate() {
            cov[(i, j)] = inv[(a, b)] * s2;
        }
    }
    Some(cov)
}

/// A screening fit's outcome: where the fit ended and its residual, without uncertainties
/// (see [`screen`]).
#[derive(Debug, Clone)]
pub struct Screened {
    /// The parameters with the fitted values set.
    pub params: Params,
    /// Sum of squared weighted residuals at the result.
    pub rss: f64,
}

/// The Levenberg–Marquardt minimum of `knobs` from their values in `start`, with at most
/// `max_jacobians` Jacobians: the optimiser's state, its report, and the best residual sum of
/// squares with its θ.
fn minimise<'a, 'b>(
    ev: &'a Evaluator<'b>,
    steer: Option<&'a Evaluator<'b>>,
    start: &Params,
    knobs: &'a [Knob],
    max_jacobians: usize,
) -> Result<(Problem<'a, 'b>, MinimizationReport<f64>, f64, DVector<f64>), IdentifyError> {
    let theta0 = DVector::from_iterator(knobs.len(), knobs.iter().map(|k| k.theta(start)));
    let problem = Problem {
        ev,
        steer,
        base: *start,
        knobs,
        theta: theta0.clone(),
        cache: Mutex::new(None),
        best: Mutex::new(None),
        jacobians: AtomicUsize::new(0),
        max_jacobians,
        last_jacobian: Mutex::new(None),
    };
    let lm = LevenbergMarquardt::new()
        .with_ftol(1e-4)
        .with_xtol(1e-4)
        .with_patience(20)
        .with_stepbound(1.0);
    let (problem, report) = lm.minimize(problem);
    ev.monitor.check()?;
    let (rss, theta) = match problem.best.lock().ok().and_then(|b| b.clone()) {
        Some(b) => b,
        None => {
            let r = problem.eval(&theta0).ok_or(IdentifyError::Cancelled)?;
            (r.norm_squared(), theta0)
        }
    };
    Ok((problem, report, rss, theta))
}

/// A screening fit: [`fit`]'s minimum without its uncertainties, which cost one more
/// Jacobian wherever the fit ended on a step (a screening fit's are never read: the search
/// ranks candidates by their residual and re-fits the best with [`fit`]).
pub fn screen(
    ev: &Evaluator<'_>,
    start: &Params,
    knobs: &[Knob],
    max_jacobians: usize,
) -> Result<Screened, IdentifyError> {
    screen_steered(ev, None, start, knobs, max_jacobians)
}

/// [`screen`], with the optimiser's Jacobians taken on `steer` where given (see
/// [`fit_steered`]).
pub fn screen_steered(
    ev: &Evaluator<'_>,
    steer: Option<&Evaluator<'_>>,
    start: &Params,
    knobs: &[Knob],
    max_jacobians: usize,
) -> Result<Screened, IdentifyError> {
    let steer = steer.filter(|s| s.residual_len() == ev.residual_len());
    let (_, _, rss, theta) = minimise(ev, steer, start, knobs, max_jacobians)?;
    Ok(Screened {
        params: params_at(start, knobs, &theta),
        rss,
    })
}

/// Fits `knobs` starting from their values in `start`, with at most `max_jacobians`
/// Jacobians. `n_eff_ratio` = n_eff/n of the residual, for the uncertainties.
pub fn fit(
    ev: &Evaluator<'_>,
    start: &Params,
    knobs: &[Knob],
    max_jacobians: usize,
    n_eff_ratio: f64,
) -> Result<FitResult, IdentifyError> {
    fit_steered(ev, None, start, knobs, max_jacobians, n_eff_ratio)
}

/// [`fit`], with the optimiser's Jacobians taken on `steer` where given: the same records
/// read on fewer samples and weighted as `ev`'s, so that its residual has `ev`'s rows
/// ([`Evaluator::residual_len`]; the fits on every sample of fast records,
/// [`super::search_rate`]). The residual minimised, the step accepted and the Jacobian of
/// the uncertainties are `ev`'s.
pub fn fit_steered(
    ev: &Evaluator<'_>,
    steer: Option<&Evaluator<'_>>,
    start: &Params,
    knobs: &[Knob],
    max_jacobians: usize,
    n_eff_ratio: f64,
) -> Result<FitResult, IdentifyError> {
    let steer = steer.filter(|s| s.residual_len() == ev.residual_len());
    let evals_before = ev.monitor.evaluations();
    let (problem, report, rss, theta) = minimise(ev, steer, start, knobs, max_jacobians)?;
    let jac = match problem.last_jacobian.lock().ok().and_then(|l| l.clone()) {
        Some((t, j)) if t == theta => Some(j),
        _ => None,
    };
    let jac = match jac {
        Some(j) => j,
        None => problem
            .jacobian_at(&theta)
            .ok_or(IdentifyError::Cancelled)?,
    };
    let n = jac.nrows();
    let p = knobs.len();
    let s2 = residual_variance(rss, n, p, n_eff_ratio);
    let cov = covariance(&jac, s2);
    let params = params_at(start, knobs, &theta);
    let mut values = Vec::with_capacity(p);
    for (j, k) in knobs.iter().enumerate() {
        // NaN (a parameter left out of the covariance) stays NaN: `f64::max` would make it 0.
        let std_theta = cov
            .as_ref()
            .map(|c| c[(j, j)])
            .filter(|d| !d.is_nan())
            .map_or(f64::NAN, |d| d.max(0.0).sqrt());
        // SI uncertainty through the local slope of the θ → SI map.
        let mut q = params;
        let eps = 1e-3 * theta[j].abs().max(1.0);
        let t1 = if theta[j] < 0.0 {
            theta[j] - eps
        } else {
            theta[j] + eps
        };
        k.set(&mut q, t1);
        let slope = ((k.value(&q) - k.value(&params)) / eps).abs();
        values.push(FittedValue {
            knob: *k,
            name: k.name().to_string(),
            value: k.value(&params),
            std: std_theta * slope,
        });
    }
    let correlation = match &cov {
        Some(c) => (0..p)
            .map(|i| {
                (0..p)
                    .map(|j| c[(i, j)] / (c[(i, i)] * c[(j, j)]).sqrt().max(1e-300))
                    .collect()
            })
            .collect(),
        None => vec![vec![f64::NAN; p]; p],
    };
    Ok(FitResult {
        params,
        values,
        rss,
        n,
        termination: StopReason::from(&report.termination),
        evaluations: ev.monitor.evaluations() - evals_before,
        correlation,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A parameter the residual does not respond to (a zero column) is undetermined on its
    /// own: its variance is NaN, and the others' covariance is `s2·(JᵀJ)⁻¹` of the rest.
    #[test]
    fn a_zero_column_leaves_only_its_own_parameter_undetermined() {
        // Two independent parameters with slopes 2 and 4 over four residuals, and a third
        // the residual does not see.
        let jac = DMatrix::from_row_slice(
            4,
            3,
            &[2.0, 0.0, 0.0, 2.0, 0.0, 0.0, 0.0, 4.0, 0.0, 0.0, 4.0, 0.0],
        );
        let cov = covariance(&jac, 0.5).expect("the rest is regular");
        // (JᵀJ)⁻¹ = diag(1/8, 1/32), times s2 = 0.5.
        assert!((cov[(0, 0)] - 0.5 / 8.0).abs() < 1e-15);
        assert!((cov[(1, 1)] - 0.5 / 32.0).abs() < 1e-15);
        assert_eq!(cov[(0, 1)], 0.0);
        assert!(cov[(2, 2)].is_nan() && cov[(0, 2)].is_nan() && cov[(2, 1)].is_nan());
        // Two columns that are the same: singular, no covariance.
        let twins = DMatrix::from_row_slice(2, 2, &[1.0, 1.0, 2.0, 2.0]);
        assert!(covariance(&twins, 1.0).is_none());
    }
}
