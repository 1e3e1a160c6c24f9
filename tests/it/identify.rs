//! The identification loop against an independent "true rig".
//!
//! The rig below is written here, apart from the library: its own integration (RK4 at 50 µs),
//! its own square-root regularisation and delay interpolation, and effect laws deliberately
//! different in form from the library's (Stribeck + tanh friction where the library fits
//! Coulomb + viscous, a smooth overlap edge, a spool-position offset, a pressure-dependent
//! leakage, separate hose and chamber bulk moduli, a quadratic supply droop). Its declared
//! parameters are off from the preset (Cd −5 %, τ +1.5 ms), and its records carry sensor
//! noise (0.08 m/s² on accelerations, 0.01 mm on u plus 18.3 µm quantisation). Most
//! campaigns have no pressure channels, as the issue expects; the supply-sag case and one
//! friction case record `p1`, `p2` too (0.2 bar noise, 12-bit on 250 bar).

use rand::SeedableRng;
use rand_distr::{Distribution, Normal};
use seat_twin::dataset::Record;
use seat_twin::identify::{self, CalibrationOptions, CalibrationReport, EffectId, Verdict};
use seat_twin::params::Params;
use std::f64::consts::PI;
use std::path::PathBuf;

#[derive(Clone, Copy, Default)]
struct RigEffects {
    /// (Coulomb N, Stribeck extra N, Stribeck velocity m/s, viscous N·s/m)
    friction: Option<(f64, f64, f64, f64)>,
    /// overlap m (smooth edge)
    overlap: Option<f64>,
    /// spool null offset m
    offset: Option<f64>,
    /// leakage coefficient m³/(s·Pa), grows with |Δp|
    leakage: Option<f64>,
    /// (β hose, β chamber) Pa
    compliance: Option<(f64, f64)>,
    /// quadratic droop Pa/(m³/s)²
    sag: Option<f64>,
}

struct Rig {
    cd: f64,
    tau: f64,
    fx: RigEffects,
}

enum Test {
    Sine { f: f64, a: f64, dur: f64 },
    Ride { dur: f64 },
}

fn ssqrt(dp: f64) -> f64 {
    const D: f64 = 1.0e4;
    if dp.abs() < D {
        dp / D.sqrt()
    } else {
        dp.signum() * dp.abs().sqrt()
    }
}

/// Platform of the ride: three cosines in position, from rest in position and velocity.
fn platform(t: f64) -> (f64, f64, f64) {
    let comps = [(1.3, 0.35), (2.7, 0.3), (4.1, 0.25)];
    let (mut x, mut xd, mut xdd) = (0.0, 0.0, 0.0);
    for (f, acc) in comps {
        let w: f64 = 2.0 * PI * f;
        let a = 2.0 * acc / (w * w);
        x += 0.5 * a * (1.0 - (w * t).cos());
        xd += 0.5 * a * w * (w * t).sin();
        xdd += 0.5 * a * w * w * (w * t).cos();
    }
    (x, xd, xdd)
}

impl Rig {
    fn rhs(&self, y: &[f64; 10], v_valve: f64, xdd: f64) -> [f64; 10] {
        let (m, k) = (11.7, 3680.0);
        let area = PI * (0.025f64.powi(2) - 0.018f64.powi(2)) / 4.0;
        let (l, dh): (f64, f64) = (0.5, 0.010);
        let (rho, mu) = (840.0, 0.02);
        let (beta_h, beta_c) = self.fx.compliance.unwrap_or((1.2e9, 1.2e9));
        let r = 128.0 * mu * l / (PI * dh.powi(4));
        let inert = 4.0 * rho * l / (PI * dh * dh);
        let ch = PI * l * dh * dh / (4.0 * beta_h);
        let cc = area * 0.035 / beta_c;
        let (pa, p0) = (100e5, 10e5);
        let [u, du, p1, p2, q1, q2, p1v, p2v, xv, dxv] = *y;
        // Friction.
        let ff = match self.fx.friction {
            Some((fc, fs, vs, b)) => {
                (fc + fs * (-(du / vs).powi(2)).exp()) * (du / 2e-3).tanh() + b * du
            }
            None => 0.0,
        };
        let half = 0.035;
        let pen = u.abs() - half;
        let stop = if pen > 0.0 {
            -u.signum() * (5e6 * pen + 5e3 * du * u.signum()).max(0.0)
        } else {
            0.0
        };
        let ydd = (-k * u - p1 * area + p2 * area - ff + stop) / m;
        // Valve opening.
        let mut x = xv.clamp(-0.8e-3, 0.8e-3) - self.fx.offset.unwrap_or(0.0);
        if let Some(ov) = self.fx.overlap {
            let d = x.abs() - ov;
            let e = 5e-6;
            let open =
                0.5 * (d + (d * d + e * e).sqrt()) - 0.5 * (ov * ov + e * e).sqrt() + 0.5 * ov;
            x = x.signum() * open.max(0.0);
        }
        let g = self.cd * 0.0251 * (2.0 / rho).sqrt() * x;
        let supply = |p_line: f64| -> f64 {
            match self.fx.sag {
                None => pa,
                Some(r2) => {
                    let mut ps = pa;
                    for _ in 0..4 {
                        let q = g.abs() * ssqrt(ps - p_line).max(0.0);
                        ps = pa - r2 * q * q;
                    }
                    ps
                }
            }
        };
        let (q1v, q2v) = if x > 0.0 {
            (g * ssqrt(p1v - p0), g * ssqrt(supply(p2v) - p2v))
        } else {
            (g * ssqrt(supply(p1v) - p1v), g * ssqrt(p2v - p0))
        };
        let ql = match self.fx.leakage {
            Some(cl) => cl * (p1 - p2) * (1.0 + (p1 - p2).abs() / 2e7),
            None => 0.0,
        };
        let wn = 691.0;
        let target = 8e-5 * v_valve;
        [
            du,
            ydd - xdd,
            (du * area - q1 - ql) / cc,
            (q2 - du * area + ql) / cc,
            (p1 - p1v - r * q1) / inert,
            (p2v - p2 - r * q2) / inert,
            (q1 - q1v) / ch,
            (q2v - q2) / ch,
            dxv,
            wn * wn * (target - xv) - 2.0 * 1.1 * wn * dxv,
        ]
    }

    fn body_acc(&self, y: &[f64; 10], xdd: f64) -> f64 {
        self.rhs(y, 0.0, xdd)[1] + xdd
    }

    /// Simulates one test and returns a measured record (1 kHz, noisy, quantised); with
    /// `pressures`, the chamber pressures too (Pa gauge, 0.2 bar noise, 12-bit on 250 bar).
    fn record(&self, test: &Test, seed: u64, pressures: bool) -> Record {
        let h = 5e-5;
        let per_sample = 20;
        let dur = match test {
            Test::Sine { dur, .. } | Test::Ride { dur } => *dur,
        };
        let n = (dur * 1000.0).round() as usize + 1;
        let mut y = [0.0; 10];
        for i in [2, 3, 6, 7] {
            y[i] = 55e5;
        }
        let mut hist: Vec<f64> = Vec::with_capacity(n * per_sample + 1);
        let (kp, ki) = (-5.0, -7.5);
        let cmd = |t: f64, y: &[f64; 10]| -> f64 {
            match test {
                Test::Sine { f, a, .. } => a * (2.0 * PI * f * t).cos(),
                Test::Ride { .. } => (kp * y[0] + ki * platform(t).1).clamp(-10.0, 10.0),
            }
        };
        let plat = |t: f64| match test {
            Test::Sine { .. } => (0.0, 0.0, 0.0),
            Test::Ride { .. } => platform(t),
        };
        let delayed = |hist: &[f64], t: f64| -> f64 {
            let s = (t - self.tau) / h;
            if s < 0.0 {
                return 0.0;
            }
            let i = s.floor() as usize;
            let f = s - i as f64;
            match (hist.get(i), hist.get(i + 1)) {
                (Some(a), Some(b)) => a + f * (b - a),
                (Some(a), None) => *a,
                _ => *hist.last().unwrap_or(&0.0),
            }
        };
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let acc_noise = Normal::new(0.0, 0.08).unwrap();
        let pos_noise = Normal::new(0.0, 1e-5).unwrap();
        let lsb = 0.075 / 4096.0;
        let p_noise = Normal::new(0.0, 2e4).unwrap();
        let p_lsb = 250e5 / 4096.0;
        let (mut t_col, mut v_col, mut u_col, mut x_col, mut xdd_col, mut ydd_col) =
            (vec![], vec![], vec![], vec![], vec![], vec![]);
        let (mut p1_col, mut p2_col) = (vec![], vec![]);
        let mut t = 0.0;
        hist.push(cmd(0.0, &y));
        for s in 0..n {
            let (x, _, xdd) = plat(t);
            t_col.push(s as f64 * 1e-3);
            v_col.push(hist[hist.len() - 1]);
            let un = y[0] + pos_noise.sample(&mut rng);
            u_col.push(lsb * ((un + 0.0375) / lsb).round() - 0.0375);
            x_col.push(x + pos_noise.sample(&mut rng));
            xdd_col.push(xdd + acc_noise.sample(&mut rng));
            ydd_col.push(self.body_acc(&y, xdd) + acc_noise.sample(&mut rng));
            if pressures {
                for (col, p) in [(&mut p1_col, y[2]), (&mut p2_col, y[3])] {
                    col.push(p_lsb * ((p + p_noise.sample(&mut rng)) / p_lsb).round());
                }
            }
            if s + 1 == n {
                break;
            }
            for _ in 0..per_sample {
                let f = |tt: f64, yy: &[f64; 10]| self.rhs(yy, delayed(&hist, tt), plat(tt).2);
                let k1 = f(t, &y);
                let mut tmp = [0.0; 10];
                for i in 0..10 {
                    tmp[i] = y[i] + 0.5 * h * k1[i];
                }
                let k2 = f(t + 0.5 * h, &tmp);
                for i in 0..10 {
                    tmp[i] = y[i] + 0.5 * h * k2[i];
                }
                let k3 = f(t + 0.5 * h, &tmp);
                for i in 0..10 {
                    tmp[i] = y[i] + h * k3[i];
                }
                let k4 = f(t + h, &tmp);
                for i in 0..10 {
                    y[i] += h / 6.0 * (k1[i] + 2.0 * (k2[i] + k3[i]) + k4[i]);
                }
                y[8] = y[8].clamp(-0.8e-3, 0.8e-3);
                t += h;
                hist.push(cmd(t, &y));
            }
        }
        let ride = matches!(test, Test::Ride { .. });
        Record {
            path: PathBuf::from(match test {
                Test::Sine { f, a, .. } => format!("sine_{f}hz_{a}v.csv"),
                Test::Ride { .. } => "ride.csv".into(),
            }),
            metadata: vec![],
            dt: 1e-3,
            t: t_col,
            v_in: Some(v_col),
            u: Some(u_col),
            x: ride.then_some(x_col),
            xdd: ride.then_some(xdd_col),
            ydd: Some(ydd_col),
            p1: pressures.then_some(p1_col),
            p2: pressures.then_some(p2_col),
            warnings: vec![],
        }
    }
}

fn campaign(fx: RigEffects, seed: u64, pressures: bool) -> Vec<Record> {
    let rig = Rig {
        cd: 0.95 * 0.1506,
        tau: 0.0175 + 0.0015,
        fx,
    };
    let tests = [
        Test::Sine {
            f: 2.0,
            a: 2.1,
            dur: 2.5,
        },
        Test::Sine {
            f: 5.0,
            a: 0.72,
            dur: 2.0,
        },
        Test::Sine {
            f: 10.0,
            a: 4.0,
            dur: 2.0,
        },
        Test::Sine {
            f: 20.0,
            a: 0.72,
            dur: 1.5,
        },
        Test::Ride { dur: 5.0 },
    ];
    tests
        .iter()
        .enumerate()
        .map(|(i, t)| rig.record(t, seed * 100 + i as u64, pressures))
        .collect()
}

fn run(fx: RigEffects, seed: u64) -> CalibrationReport {
    run_with(fx, seed, false)
}

fn run_with(fx: RigEffects, seed: u64, pressures: bool) -> CalibrationReport {
    let recs = campaign(fx, seed, pressures);
    identify::calibrate(
        &Params::paper(),
        &recs,
        &CalibrationOptions::default(),
        &|_| true,
    )
    .expect("calibration runs")
}

fn first_ranked(r: &CalibrationReport) -> EffectId {
    r.candidates
        .iter()
        .filter(|c| c.round == 1)
        .min_by(|a, b| a.score.total_cmp(&b.score))
        .expect("candidates scored")
        .effect
}

fn summary(r: &CalibrationReport) -> String {
    let c: Vec<String> = r
        .candidates
        .iter()
        .map(|c| {
            format!(
                "r{} {} {:.1} ({:.1} %)",
                c.round,
                c.effect.name(),
                c.score,
                100.0 * c.relative_gain
            )
        })
        .collect();
    format!(
        "verdict {:?}, effects {:?}, errors nominal {:.3} before {:.3} after {:.3}, cd {:.5} tau {:.5}; {}",
        r.verdict,
        r.effects
            .iter()
            .map(|e| e.effect.name())
            .collect::<Vec<_>>(),
        r.error_nominal.value,
        r.error_before.value,
        r.error_after.value,
        r.params.valve.cd,
        r.params.valve.tau_s,
        c.join("; ")
    )
}

/// Weighted error of a correct model on these records: the null case (no hidden effect) ends
/// at 0.715, i.e. the sensor noise and quantisation alone.
const NOISE_FLOOR: f64 = 0.70;

/// The effect removes at least 30 % of the error, or — for a weak effect whose error before is
/// already within 50 % of the noise floor (leakage: 0.985) — brings it down to that floor.
fn assert_reduced_to_noise(r: &CalibrationReport, s: &str) {
    let (before, after) = (r.error_before.value, r.error_after.value);
    assert!(
        after < 0.7 * before || (before < 1.5 * NOISE_FLOOR && after < 1.02 * NOISE_FLOOR),
        "{s}"
    );
}

fn check_single(fx: RigEffects, expected: EffectId, seed: u64) -> CalibrationReport {
    check_single_with(fx, expected, seed, false)
}

fn check_single_with(
    fx: RigEffects,
    expected: EffectId,
    seed: u64,
    pressures: bool,
) -> CalibrationReport {
    let r = run_with(fx, seed, pressures);
    let s = summary(&r);
    eprintln!("{}: {s}", expected.name());
    assert_eq!(first_ranked(&r), expected, "{s}");
    assert_eq!(r.verdict, Verdict::Explained, "{s}");
    assert_eq!(r.effects[0].effect, expected, "{s}");
    assert_reduced_to_noise(&r, &s);
    // The declared mismatch is found: Cd −5 %, τ +1.5 ms.
    assert!(
        (r.params.valve.cd / (0.95 * 0.1506) - 1.0).abs() < 0.03,
        "{s}"
    );
    assert!((r.params.valve.tau_s - 0.019).abs() < 1.0e-3, "{s}");
    r
}

#[test]
fn null_case_adds_nothing() {
    let r = run(RigEffects::default(), 1);
    let s = summary(&r);
    eprintln!("null: {s}");
    assert!(r.effects.is_empty(), "{s}");
    assert_eq!(r.verdict, Verdict::NoMissingEffect, "{s}");
    // The declared parameters are still re-fitted.
    assert!(r.error_before.value < r.error_nominal.value, "{s}");
    assert!(
        (r.params.valve.cd / (0.95 * 0.1506) - 1.0).abs() < 0.02,
        "{s}"
    );
}

#[test]
fn friction_is_found() {
    let fx = RigEffects {
        friction: Some((40.0, 20.0, 0.01, 80.0)),
        ..Default::default()
    };
    let r = check_single(fx, EffectId::Friction, 2);
    // Coulomb friction acts at reversals, which sag cannot mimic: no ambiguity note.
    assert!(
        !r.notes.iter().any(|n| n.contains("about equally")),
        "{:?}",
        r.notes
    );
}

#[test]
fn valve_overlap_is_found() {
    let fx = RigEffects {
        overlap: Some(40e-6),
        ..Default::default()
    };
    check_single(fx, EffectId::ValveOverlap, 3);
}

#[test]
fn valve_offset_is_found() {
    let fx = RigEffects {
        offset: Some(3e-6),
        ..Default::default()
    };
    check_single(fx, EffectId::ValveOffset, 4);
}

#[test]
fn leakage_is_found() {
    let fx = RigEffects {
        leakage: Some(2e-12),
        ..Default::default()
    };
    check_single(fx, EffectId::Leakage, 5);
}

#[test]
fn compliance_is_found() {
    let fx = RigEffects {
        compliance: Some((0.5e9, 0.9e9)),
        ..Default::default()
    };
    check_single(fx, EffectId::Compliance, 6);
}

/// Supply sag with chamber pressures recorded. Without them the case cannot be decided (see
/// `supply_sag_without_pressures_is_reported_ambiguous`): at steady flow a supply droop and a
/// viscous friction lower the velocity alike, since both take pressure from the metering
/// edges in proportion to the flow (r ≈ b/A²), so u̇ and ÿ carry almost the same signature.
/// The pressures do not: sag lowers the common-mode pressure (p1 + p2)/2 with the drawn
/// flow, friction shifts the load pressure p1 − p2. Fitting pressure transducers is the
/// physically justified experiment when sag is suspected (the record format has `p1`, `p2`),
/// so this campaign records them; the tests and the rig's effect law are unchanged.
#[test]
fn supply_sag_is_found() {
    let fx = RigEffects {
        sag: Some(1.5e14),
        ..Default::default()
    };
    check_single_with(fx, EffectId::SupplySag, 7, true);
}

/// Without pressure channels, the pipeline must not claim it told supply sag from friction:
/// it adds one of them and says, in the notes, that the other explains the data as well.
#[test]
fn supply_sag_without_pressures_is_reported_ambiguous() {
    let fx = RigEffects {
        sag: Some(1.5e14),
        ..Default::default()
    };
    let r = run(fx, 7);
    let s = summary(&r);
    let params: Vec<String> = r
        .candidates
        .iter()
        .filter(|c| c.round == 1 && c.score < 0.0)
        .map(|c| format!("{} {:?}", c.effect.name(), c.params))
        .collect();
    eprintln!(
        "supply_sag without pressures: {s}; round-1 fits {params:?}; notes {:?}",
        r.notes
    );
    assert_eq!(r.verdict, Verdict::Explained, "{s}");
    assert!(
        [EffectId::Friction, EffectId::SupplySag].contains(&r.effects[0].effect),
        "{s}"
    );
    assert!(
        r.notes
            .iter()
            .any(|n| n.contains("`friction`") && n.contains("`supply_sag`")),
        "{s}; notes {:?}",
        r.notes
    );
    assert!(r.error_after.value < 0.7 * r.error_before.value, "{s}");
}

/// The pressure channels must not turn friction into sag: friction still wins with them.
#[test]
fn friction_is_found_with_pressures() {
    let fx = RigEffects {
        friction: Some((40.0, 20.0, 0.01, 80.0)),
        ..Default::default()
    };
    check_single_with(fx, EffectId::Friction, 2, true);
}

#[test]
fn two_effects_are_both_found() {
    let fx = RigEffects {
        friction: Some((40.0, 20.0, 0.01, 80.0)),
        offset: Some(3e-6),
        ..Default::default()
    };
    let r = run(fx, 8);
    let s = summary(&r);
    eprintln!("two effects: {s}");
    let found: Vec<EffectId> = r.effects.iter().map(|e| e.effect).collect();
    assert!(
        [EffectId::Friction, EffectId::ValveOffset].contains(&first_ranked(&r)),
        "{s}"
    );
    assert!(
        found.contains(&EffectId::Friction) && found.contains(&EffectId::ValveOffset),
        "{s}"
    );
    assert!(r.error_after.value < 0.6 * r.error_before.value, "{s}");
}

/// The demo campaign (a rig model no one here wrote, one hidden effect). The calibration runs
/// first, on the files alone; only then is the truth read, to check what it found.
#[test]
fn demo_campaign_finds_its_hidden_effect() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/demo-campaign");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .expect("assets/demo-campaign exists")
        .map(|e| e.expect("dir entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "csv"))
        .collect();
    files.sort();
    assert_eq!(files.len(), 10);
    let recs: Vec<Record> = files
        .iter()
        .map(|p| {
            seat_twin::dataset::read_record(p, seat_twin::dataset::RecordKind::Measured)
                .expect("demo file reads")
        })
        .collect();
    let r = identify::calibrate(
        &Params::paper(),
        &recs,
        &CalibrationOptions::default(),
        &|_| true,
    )
    .expect("calibration runs");
    let s = summary(&r);
    eprintln!("demo: {s}");

    // Only now: the truth.
    let truth: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(
            std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("tests/data/demo-campaign-truth.json"),
        )
        .expect("truth file"),
    )
    .expect("truth JSON");
    let hidden: Vec<&str> = truth["effect_ids"]
        .as_array()
        .expect("effect_ids")
        .iter()
        .filter_map(|v| v.as_str())
        .collect();
    assert_eq!(r.verdict, Verdict::Explained, "{s}");
    let found: Vec<&str> = r.effects.iter().map(|e| e.effect.name()).collect();
    assert_eq!(found, hidden, "{s}");
    assert_eq!(first_ranked(&r).name(), hidden[0], "{s}");
    let decl = &truth["true_declared_parameters"];
    let cd = decl["Cd"].as_f64().expect("Cd");
    let tau = decl["tau_s"].as_f64().expect("tau_s");
    let m = decl["m_kg"].as_f64().expect("m_kg");
    assert!((r.params.valve.cd / cd - 1.0).abs() < 0.02, "{s}");
    assert!((r.params.valve.tau_s - tau).abs() < 0.5e-3, "{s}");
    assert!((r.params.body.mass_kg / m - 1.0).abs() < 0.05, "{s}");
    if hidden[0] == "compliance" {
        // The rig has separate hose and chamber moduli; the library fits one effective value,
        // which must lie between them.
        let c = &truth["effects"]["compliance"];
        let (bh, bc) = (
            c["beta_hose_Pa"].as_f64().expect("beta_hose_Pa"),
            c["beta_chamber_Pa"].as_f64().expect("beta_chamber_Pa"),
        );
        let beta = r.params.effective_bulk_modulus_pa();
        assert!(
            beta >= bh.min(bc) * 0.9 && beta <= bh.max(bc) * 1.1,
            "β = {beta}; {s}"
        );
    }
    assert!(r.error_after.value < 0.6 * r.error_before.value, "{s}");
    assert!(r.error_before.value < r.error_nominal.value, "{s}");
}
