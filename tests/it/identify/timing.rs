//! A ten-record campaign of the independent rig, written to disk, for timing the CLI's
//! `calibrate` (issue 20: a 10-record campaign in at most 30 s on 2 cores) at any sample rate:
//! the eight open-loop sine tests of the demo campaign (same frequencies, amplitudes and
//! lengths: the longer of 3 s and six periods) and two closed-loop rides of 15 s, 60 s in all.
//!
//! ```sh
//! CAMPAIGN_OUT=/tmp/c10k CAMPAIGN_RATE_HZ=10000 CAMPAIGN_EFFECT=friction \
//!   cargo test --no-default-features --test it identify::timing -- --ignored
//! time target/release/seat-twin calibrate --data /tmp/c10k/*.csv --out /tmp/c10k-out
//! ```
//!
//! `CAMPAIGN_EFFECT` is `null` (the default), `friction` (Coulomb 40 N, Stribeck 15 N at
//! 10 mm/s, viscous 80 N·s/m), `overlap` (40 µm), `compliance` (hoses 0.6 GPa, chambers
//! 1.2 GPa), `leakage_compliance` (3.5·10⁻¹² m³/(s·Pa) beside hoses at 0.68 GPa), or one
//! outside the library: `quadratic_damping` (2250 N·s²/m²) or `null_drift` (the valve's null
//! drifting 2 mV/s), or `friction_null_drift` (that friction beside that drift); the rig's
//! declared mismatch is the campaign tests' (Cd −5 %, τ +1.5 ms).
//! `CAMPAIGN_ACC_NOISE` sets the accelerometers' noise RMS [m/s²] (default the rig's 0.08).

use super::rig::{Rig, RigEffects, Test};
use std::path::PathBuf;

/// The demo campaign's eight sine tests (f Hz, A V).
const SINES: [(f64, f64); 8] = [
    (1.0, 0.72),
    (2.0, 2.1),
    (5.0, 0.72),
    (5.0, 4.5),
    (10.0, 1.1),
    (10.0, 6.4),
    (15.0, 3.0),
    (20.0, 0.72),
];

/// The timing campaigns' friction: Coulomb 40 N, Stribeck 15 N at 10 mm/s, viscous 80 N·s/m.
const FRICTION: (f64, f64, f64, f64) = (40.0, 15.0, 0.01, 80.0);
/// The timing campaigns' drift of the valve's null [V/s].
const NULL_DRIFT_V_PER_S: f64 = 2e-3;

fn effects(name: &str) -> RigEffects {
    let mut fx = RigEffects::default();
    match name {
        "null" => {}
        "friction" => fx.friction = Some(FRICTION),
        "overlap" => fx.overlap = Some(40e-6),
        "compliance" => fx.compliance = Some((0.6e9, 1.2e9)),
        "leakage_compliance" => {
            fx.leakage = Some(3.5e-12);
            fx.compliance = Some((0.68e9, 1.2e9));
        }
        // Outside the library (the survey's middle magnitudes).
        "quadratic_damping" => fx.quadratic_damping = Some(2250.0),
        "null_drift" => fx.null_drift_v_per_s = Some(NULL_DRIFT_V_PER_S),
        // A library effect beside one outside it (the survey never draws the two together).
        "friction_null_drift" => {
            fx.friction = Some(FRICTION);
            fx.null_drift_v_per_s = Some(NULL_DRIFT_V_PER_S);
        }
        other => panic!(
            "CAMPAIGN_EFFECT={other}: one of null, friction, overlap, compliance, \
             leakage_compliance, quadratic_damping, null_drift, friction_null_drift"
        ),
    }
    fx
}

#[test]
#[ignore = "a tool: writes a campaign to CAMPAIGN_OUT for timing the CLI"]
fn a_ten_record_campaign_for_timing() {
    let Ok(out) = std::env::var("CAMPAIGN_OUT") else {
        panic!("set CAMPAIGN_OUT to the directory to write the campaign into");
    };
    let rate_hz: f64 = std::env::var("CAMPAIGN_RATE_HZ")
        .ok()
        .and_then(|v| v.trim().parse().ok())
        .unwrap_or(1000.0);
    let name = std::env::var("CAMPAIGN_EFFECT").unwrap_or_else(|_| "null".into());
    let mut fx = effects(&name);
    fx.acc_noise = std::env::var("CAMPAIGN_ACC_NOISE")
        .ok()
        .and_then(|v| v.trim().parse().ok());
    let rig = Rig {
        cd: 0.95 * 0.1506,
        tau: 0.0175 + 0.0015,
        fx,
    };
    let mut tests: Vec<Test> = SINES
        .iter()
        .map(|&(f, a)| Test::Sine {
            f,
            a,
            dur: (6.0 / f).max(3.0),
        })
        .collect();
    tests.extend([Test::Ride { dur: 15.0 }, Test::Ride { dur: 15.0 }]);
    let mut records = Vec::new();
    for (i, t) in tests.iter().enumerate() {
        let mut rec = rig.record_at(t, 7000 + i as u64, false, rate_hz);
        if matches!(t, Test::Ride { .. }) {
            rec.path = PathBuf::from(format!("ride_{}.csv", i - SINES.len() + 1));
        }
        records.push(rec);
    }
    super::survey::write_records(&records, std::path::Path::new(&out));
}
