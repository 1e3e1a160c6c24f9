//! Synthetic records made by the twin itself with known parameters, so that a calibration
//! stage has a known answer: for the tests, and for trying the calibration without a rig.

use super::IdentifyError;
use super::replay::{MetricOptions, PreparedRecord};
use crate::dataset::Record;
use crate::params::Params;
use std::f64::consts::PI;

/// A measured record of `secs` at 1 kHz made by the twin with `params`: the valve driven in
/// open loop by `0.6·sin(2π·3t) + 0.4·sin(2π·9t)` V, the platform still, `u` and `ÿ` as the
/// twin gives them (noise-free). An error when `params` do not validate or the twin cannot
/// replay them.
pub fn twin_record(params: &Params, secs: f64, name: &str) -> Result<Record, IdentifyError> {
    params.validate()?;
    let dt = 1e-3;
    let n = (secs / dt).round() as usize + 1;
    let t: Vec<f64> = (0..n).map(|i| i as f64 * dt).collect();
    let v_in = t
        .iter()
        .map(|t| 0.6 * (2.0 * PI * 3.0 * t).sin() + 0.4 * (2.0 * PI * 9.0 * t).sin())
        .collect();
    let mut rec = Record {
        path: name.into(),
        metadata: vec![],
        dt,
        t,
        v_in: Some(v_in),
        u: Some(vec![0.0; n]),
        x: None,
        xdd: None,
        ydd: Some(vec![0.0; n]),
        p1: None,
        p2: None,
        warnings: vec![],
    };
    let sim = PreparedRecord::new(&rec, &MetricOptions::default())?.simulate(params)?;
    rec.u = Some(sim.u);
    rec.ydd = Some(sim.ydd);
    Ok(rec)
}

/// The paper preset with Cd 10 % low and τ 2 ms longer: "the rig" of the tests.
pub fn true_params() -> Params {
    let mut p = Params::paper();
    p.plant.valve.cd *= 0.9;
    p.plant.valve.tau_s += 2e-3;
    p
}
