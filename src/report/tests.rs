//! Unit tests of the report's numbers.

use super::*;
use crate::model::ModelKind;
use crate::simulation::Sample;
use crate::simulation::integrate::StepStats;
use std::f64::consts::PI;

/// A trace at `fs` with ÿ = a·sin(2π·f·t), ẍ = 2·ÿ and u = 3 mm·cos(2π·f·t).
fn sine_trace(fs: f64, f: f64, a: f64, seconds: f64) -> Trace {
    let n = (seconds * fs) as usize;
    let samples = (0..n)
        .map(|i| {
            let t = i as f64 / fs;
            let s = (2.0 * PI * f * t).sin();
            Sample {
                t,
                x: 0.0,
                xd: 0.0,
                xdd: 2.0 * a * s,
                u: 3e-3 * (2.0 * PI * f * t).cos(),
                du: 0.0,
                ydd: a * s,
                v_in: f64::NAN,
                xv: 0.0,
                p1: 0.0,
                p2: 0.0,
                q1: 0.0,
                q2: 0.0,
                contact: false,
            }
        })
        .collect();
    Trace {
        model: ModelKind::Passive,
        samples,
        contacts: Vec::new(),
        stats: StepStats::default(),
    }
}

/// The ride metrics of a pure sine: RMS a/√2, stroke RMS 3 mm/√2 and peak 3 mm, and the
/// body/platform ratio of 1/2 (frequency weighting is the same for both, so it cancels).
#[test]
fn ride_metrics_of_a_sine_match_the_closed_form() {
    let (a, f) = (0.8, 4.0);
    let m = ride_metrics(&sine_trace(1000.0, f, a, 20.0), 2.0).unwrap();
    assert!(
        (m.rms_ydd - a / 2f64.sqrt()).abs() < 1e-3 * a,
        "{}",
        m.rms_ydd
    );
    assert!((m.rms_u - 3e-3 / 2f64.sqrt()).abs() < 1e-6, "{}", m.rms_u);
    assert!((m.max_abs_u - 3e-3).abs() < 1e-6, "{}", m.max_abs_u);
    assert!((m.seat_percent - 50.0).abs() < 0.5, "{}", m.seat_percent);
    assert_eq!(m.contacts, 0);
}

/// Eq. (12) solved for Cd gives back the nominal 20 L/min through the orifice equation
/// Q = Cd·Ka·xv·√(2Δp/ρ), and Cd scales as 1/√Δp.
#[test]
fn cd_of_eq12_returns_the_nominal_flow() {
    let p = Params::paper();
    for dp in [70e5, 100e5] {
        let cd = cd_eq12(&p, dp);
        let q = cd
            * p.plant.valve.ka_m
            * p.plant.valve.xv_max_m
            * (2.0 * dp / p.plant.fluid.density_kg_m3).sqrt();
        assert!((q * 60_000.0 - 20.0).abs() < 1e-9, "{} L/min", q * 60_000.0);
    }
    let ratio = cd_eq12(&p, 70e5) / cd_eq12(&p, 100e5);
    assert!((ratio - (100.0f64 / 70.0).sqrt()).abs() < 1e-12);
}

/// The passive curve of the crossing sets is 1 at √2·√(k/m)/2π (the damping-free
/// crossing) and follows |(cs + k)/(ms² + cs + k)| elsewhere; one value per frequency.
#[test]
fn crossing_sets_cross_unity_where_the_passive_closed_form_does() {
    let p = Params::paper();
    let f_x =
        2f64.sqrt() * (p.plant.body.stiffness_n_per_m / p.plant.body.mass_kg).sqrt() / (2.0 * PI);
    let (passive, linear, twin) = crossing_sets(&p, &[f_x, 20.0]);
    assert!((passive[0] - 1.0).abs() < 1e-9, "{}", passive[0]);
    let (k, m) = (p.plant.body.stiffness_n_per_m, p.plant.body.mass_kg);
    let c = 2.0 * p.passive.zeta * (k * m).sqrt();
    let s = Complex64::new(0.0, 2.0 * PI * 20.0);
    let exact = ((c * s + k) / (m * s * s + c * s + k)).norm();
    assert!(
        (passive[1] - exact).abs() < 1e-12 * exact,
        "{} vs {exact}",
        passive[1]
    );
    assert_eq!((linear.len(), twin.len()), (2, 2));
}
