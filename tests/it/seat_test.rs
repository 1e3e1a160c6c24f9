//! Standard seat-test inputs (issue 14, part 3): the class generator meets each class's target
//! PSD within ±10 % of its peak, the estimator that says so is itself right, the SEAT formula
//! agrees with a hand-computed case, the seat test agrees with a frequency-domain prediction,
//! and the CLI writes what it promises.

use seat_twin::analysis::frequency_response as fr;
use seat_twin::analysis::metrics;
use seat_twin::model::ModelKind;
use seat_twin::params::Params;
use seat_twin::scenario::class_motion::{self as signal, CLASS_RATE_HZ, ClassMotion};
use seat_twin::scenario::classes::{self, CLASSES, PSD_TOLERANCE_OF_PEAK};
use seat_twin::seat_test::{SeatTestOptions, run_seat_test};
use std::f64::consts::PI;
use std::process::Command;

/// The steady (fade-free) part of a generated class record's acceleration.
fn steady_xdd(m: &ClassMotion) -> Vec<f64> {
    let rec = m.generate().expect("valid settings");
    m.steady_range().map(|i| rec.at_sample(i).xdd).collect()
}

#[test]
fn every_class_meets_its_target_psd_within_10_percent_of_the_peak() {
    for class in &CLASSES {
        for seed in [1, 2] {
            let m = ClassMotion {
                seed,
                ..ClassMotion::new(class, 180.0)
            };
            let xdd = steady_xdd(&m);
            let c = signal::check_psd(class, &xdd, CLASS_RATE_HZ).expect("long enough");
            assert!(
                c.max_error_of_peak <= PSD_TOLERANCE_OF_PEAK,
                "{} seed {seed}: {:.1} % of the peak at {:.2} Hz",
                class.name,
                100.0 * c.max_error_of_peak,
                c.at_hz
            );
            // The estimate reaches the target's peak (a flat, too-low PSD would fail here).
            assert!(
                (c.estimate_peak / c.target_peak - 1.0).abs() < PSD_TOLERANCE_OF_PEAK,
                "{}: peak {} vs {}",
                class.name,
                c.estimate_peak,
                c.target_peak
            );
            // The band rms is the target's within 3 %.
            assert!(
                (c.band_rms / c.target_band_rms - 1.0).abs() < 0.03,
                "{}: band rms {} vs {}",
                class.name,
                c.band_rms,
                c.target_band_rms
            );
        }
    }
}

#[test]
fn a_wrong_class_fails_the_psd_check() {
    // The check can fail: AG2's record against AG1's target is far outside the tolerance,
    // and so is a record 20 % too strong.
    let ag1 = classes::find("AG1").expect("AG1");
    let ag2 = classes::find("AG2").expect("AG2");
    let xdd = steady_xdd(&ClassMotion::new(ag2, 120.0));
    let c = signal::check_psd(ag1, &xdd, CLASS_RATE_HZ).expect("long enough");
    assert!(c.max_error_of_peak > 0.5, "{}", c.max_error_of_peak);
    let strong: Vec<f64> = steady_xdd(&ClassMotion::new(ag1, 120.0))
        .iter()
        .map(|a| a * 1.2f64.sqrt())
        .collect();
    let c = signal::check_psd(ag1, &strong, CLASS_RATE_HZ).expect("long enough");
    assert!(c.max_error_of_peak > 0.15, "{}", c.max_error_of_peak);
}

#[test]
fn stated_rms_agrees_with_the_target_psd_except_em7() {
    // The toolbox states the rms (hvtestsignal.m) and the PSD (hvtestspectrum.m) in two
    // files; integrating the PSD through the rms band must give the stated rms.
    for class in &CLASSES {
        let implied = class.target_band_rms();
        let rel = implied / class.rms_m_s2 - 1.0;
        if class.name == "EM7" {
            // Same PSD as AG1 (2.26 m/s²) but stated as 2.36 m/s²: the known discrepancy.
            assert!((rel + 0.045).abs() < 0.01, "EM7: {implied}");
            assert!((implied - 2.255).abs() < 0.01, "EM7: {implied}");
        } else {
            assert!(
                rel.abs() < 0.006,
                "{}: {implied} vs {}",
                class.name,
                class.rms_m_s2
            );
        }
    }
}

#[test]
fn class_motion_is_consistent_drift_free_and_reproducible() {
    let class = classes::find("EM1").expect("EM1");
    let m = ClassMotion::new(class, 40.0);
    let rec = m.generate().expect("valid");
    let n = (rec.duration_s() * CLASS_RATE_HZ).round() as usize;
    // At rest at both ends, at the same place.
    for i in [0, n] {
        let s = rec.at_sample(i);
        assert!(
            s.x.abs() < 1e-9 && s.xd.abs() < 1e-9 && s.xdd.abs() < 1e-9,
            "{i}: {s:?}"
        );
    }
    // ẋ is the derivative of x and ẍ that of ẋ (central differences, 1 ms).
    let h = 1.0 / CLASS_RATE_HZ;
    let (mut ev, mut ea, mut amax): (f64, f64, f64) = (0.0, 0.0, 0.0);
    for i in 1..n {
        let (a, b, c) = (rec.at_sample(i - 1), rec.at_sample(i), rec.at_sample(i + 1));
        ev = ev.max(((c.x - a.x) / (2.0 * h) - b.xd).abs());
        ea = ea.max(((c.xd - a.xd) / (2.0 * h) - b.xdd).abs());
        amax = amax.max(b.xdd.abs());
    }
    assert!(ev < 1e-4, "velocity mismatch {ev} m/s");
    assert!(
        ea < 2e-3 * amax,
        "acceleration mismatch {ea} of {amax} m/s²"
    );
    // Zero mean acceleration and velocity.
    let mean = |f: &dyn Fn(usize) -> f64| (0..=n).map(f).sum::<f64>() / (n + 1) as f64;
    assert!(mean(&|i| rec.at_sample(i).xdd).abs() < 1e-3);
    assert!(mean(&|i| rec.at_sample(i).xd).abs() < 1e-4);
    // Seeded: the same seed gives the same record, another seed another one.
    assert_eq!(rec, m.generate().expect("valid"));
    let other = ClassMotion { seed: 2, ..m }.generate().expect("valid");
    assert_ne!(rec, other);
    // Out-of-range settings are errors, not panics.
    assert!(ClassMotion::new(class, 5.0).generate().is_err());
    assert!(ClassMotion { fade_s: 30.0, ..m }.generate().is_err());
}

#[test]
fn welch_psd_of_a_sine_and_of_white_noise() {
    let fs = 1000.0;
    let n = 200_000;
    // A sine of amplitude 2 at 3 Hz: the PSD integrates to A²/2 = 2 around 3 Hz.
    let x: Vec<f64> = (0..n)
        .map(|i| 2.0 * (2.0 * PI * 3.0 * i as f64 / fs).sin())
        .collect();
    let p = signal::welch_psd(&x, fs, 16_384).expect("long enough");
    let df = p.freq_hz[1];
    let power: f64 = p
        .freq_hz
        .iter()
        .zip(&p.psd)
        .filter(|(f, _)| (**f - 3.0).abs() < 0.5)
        .map(|(_, v)| v * df)
        .sum();
    assert!((power - 2.0).abs() < 0.01, "{power}");
    // Uniform white noise of variance 1/3: level 2σ²/fs, averaged over 0.5–400 Hz.
    let mut state = 0x2545_f491_4f6c_dd1d_u64;
    let noise: Vec<f64> = (0..n)
        .map(|_| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            2.0 * (state as f64 / u64::MAX as f64) - 1.0
        })
        .collect();
    let p = signal::welch_psd(&noise, fs, 1024).expect("long enough");
    let band: Vec<f64> = p
        .freq_hz
        .iter()
        .zip(&p.psd)
        .filter(|(f, _)| **f > 0.5 && **f < 400.0)
        .map(|(_, v)| *v)
        .collect();
    let level = band.iter().sum::<f64>() / band.len() as f64;
    let expected = 2.0 * (1.0 / 3.0) / fs;
    assert!(
        (level / expected - 1.0).abs() < 0.02,
        "{level} vs {expected}"
    );
    assert!(signal::welch_psd(&noise[..100], fs, 1024).is_err());
}

#[test]
fn band_rms_of_sines_in_and_out_of_the_band() {
    let fs = 1000.0;
    let sine = |a: f64, f: f64| -> Vec<f64> {
        (0..100_000)
            .map(|i| a * (2.0 * PI * f * i as f64 / fs).sin())
            .collect()
    };
    // 3 Hz is deep inside 0.89–11.22 Hz: |B|² = 1/((1+(0.89/3)^16)(1+(3/11.22)^16)) ≈ 1.
    let r = signal::band_rms(&sine(2.0, 3.0), fs, (0.89, 11.22));
    assert!((r - 2f64.sqrt()).abs() < 1e-6, "{r}");
    // At the upper edge the 8-pole band passes half the power: rms/√2.
    let r = signal::band_rms(&sine(2.0, 11.22), fs, (0.89, 11.22));
    assert!((r - 1.0).abs() < 0.01, "{r}");
    // At 40 Hz the 8-pole low-pass leaves 1/√(1 + (40/11.22)^16) = 3.8e-5 of the amplitude.
    let r = signal::band_rms(&sine(2.0, 40.0), fs, (0.89, 11.22));
    let expected = 2f64.sqrt() / (1.0 + (40.0f64 / 11.22).powi(16)).sqrt();
    assert!((r / expected - 1.0).abs() < 0.01, "{r} vs {expected}");
}

/// The SEAT value through the whole pipeline (digital Wk filter, weighted rms, ratio) against
/// a case computed by hand from the Wk definition of ISO 2631-1 Annex A
/// (f1 = 0.4, f2 = 100, f3 = f4 = 12.5 Hz, Q4 = 0.63, f5 = 2.37 Hz, Q5 = 0.91, f6 = 3.35 Hz,
/// Q6 = 0.91; the upward step has gain (f5/f6)² below it, 1 above).
///
/// Floor: 1.5 m/s² at 3 Hz. Seat: 0.6 m/s² at 7 Hz.
///
/// |Wk(3 Hz)|: high-pass r = 3/0.4 = 7.5, r²/√((1−r²)² + 2r²) = 56.25/√(3080.6 + 112.5)
/// = 0.999842; low-pass 1/√((1−0.0009)² + 2·0.0009) = 1.000000; a–v transition
/// √(1 + 0.24²)/√((1 − 0.0576)² + (0.24/0.63)²) = 1.028397/1.016500 = 1.011718; upward step
/// 0.500512 · |1 − 1.602307 + j·1.391011| / |1 − 0.801960 + j·0.984090|
/// = 0.500512 · 1.515812/1.003819 = 0.755784. Product: 0.764519.
///
/// |Wk(7 Hz)|: high-pass 0.999995; low-pass 0.999988; transition
/// √(1 + 0.56²)/√((1 − 0.3136)² + (0.56/0.63)²) = 1.146124/1.123062 = 1.020535; upward step
/// 0.500512 · |1 − 8.723664 + j·3.245666| / |1 − 4.366228 + j·2.296146|
/// = 0.500512 · 8.377630/4.074649 = 1.029050. Product: 1.050163.
///
/// a_w,floor = 1.5/√2 · 0.764519 = 0.810895 m/s²; a_w,seat = 0.6/√2 · 1.050163 = 0.445546 m/s²;
/// SEAT = 100 · 0.445546/0.810895 = 54.945 %.
#[test]
fn seat_formula_matches_a_hand_computed_case() {
    let fs = 4000.0; // the digital Wk is within 0.1 % of the analogue filter below 20 Hz here
    let n = (120.0 * fs) as usize;
    let floor: Vec<f64> = (0..n)
        .map(|i| 1.5 * (2.0 * PI * 3.0 * i as f64 / fs).sin())
        .collect();
    let seat: Vec<f64> = (0..n)
        .map(|i| 0.6 * (2.0 * PI * 7.0 * i as f64 / fs).sin())
        .collect();
    // Leave out 20 s while the 0.4 Hz high-pass settles; 100 s of whole periods remain.
    let f = metrics::vibration_metrics(&floor, fs, 20.0).expect("valid");
    let s = metrics::vibration_metrics(&seat, fs, 20.0).expect("valid");
    assert!((f.aw / 0.810895 - 1.0).abs() < 2e-3, "a_w floor {}", f.aw);
    assert!((s.aw / 0.445546 - 1.0).abs() < 2e-3, "a_w seat {}", s.aw);
    let seat_percent = metrics::seat_percent(s.aw, f.aw);
    assert!((seat_percent - 54.945).abs() < 0.15, "SEAT {seat_percent}");
}

/// The passive seat's SEAT on a class, simulated, against the frequency-domain prediction
/// `a_w,seat² = ∫ G(f)·|T(f)|²·|Wk(f)|² df` with the closed-form passive transmissibility:
/// checks generator, simulation and metrics together against an independent calculation.
#[test]
fn passive_seat_value_matches_the_frequency_domain_prediction() {
    let params = Params::paper();
    for name in ["AG1", "EM6"] {
        let class = classes::find(name).expect("class");
        let opts = SeatTestOptions {
            duration_s: 120.0,
            ..SeatTestOptions::new(class, ModelKind::Passive)
        };
        let r = run_seat_test(&params, &opts).expect("runs");
        // Integrate over the generated band (0.2–50 Hz) on a fine grid.
        let (mut floor, mut seat) = (0.0, 0.0);
        let df = 1e-3;
        let mut fq = signal::GEN_BAND_HZ.0;
        while fq <= signal::GEN_BAND_HZ.1 {
            let g = class.target_psd(fq) * metrics::wk_response(fq).0.powi(2) * df;
            floor += g;
            seat += g * fr::passive_transmissibility(&params, fq).norm_sqr();
            fq += df;
        }
        let predicted = 100.0 * (seat / floor).sqrt();
        let n = &r.numbers;
        assert!(
            (n.seat_percent / predicted - 1.0).abs() < 0.03,
            "{name}: simulated SEAT {} vs predicted {predicted}",
            n.seat_percent
        );
        assert!(
            (n.aw_floor / floor.sqrt() - 1.0).abs() < 0.03,
            "{name}: a_w floor {} vs {}",
            n.aw_floor,
            floor.sqrt()
        );
        assert!(n.psd_within_tolerance, "{name}: {}", n.psd_error_percent);
    }
}

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_seat-twin"))
}

#[test]
fn seat_test_cli_writes_report_numbers_and_plots() {
    let dir = tempfile::tempdir().expect("tmp");
    let out = dir.path().join("ag1");
    let o = bin()
        .args(["seat-test", "--class", "ag1", "--duration", "40", "--out"])
        .arg(&out)
        .output()
        .expect("runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(out.join("numbers.json")).expect("numbers.json");
    let v: serde_json::Value = serde_json::from_str(&text).expect("json");
    for key in [
        "class",
        "model",
        "mass_kg",
        "aw_floor",
        "aw_seat",
        "seat_percent",
        "vdv_seat",
        "max_abs_u_mm",
        "contacts",
        "psd_error_percent",
    ] {
        assert!(v.get(key).is_some(), "numbers.json lacks {key}");
    }
    assert_eq!(v["class"], "AG1");
    assert_eq!(v["model"], "twin");
    assert_eq!(v["mass_kg"], 11.7);
    let seat = v["seat_percent"].as_f64().expect("a number");
    let ratio =
        100.0 * v["aw_seat"].as_f64().unwrap_or(0.0) / v["aw_floor"].as_f64().unwrap_or(1.0);
    assert!((seat - ratio).abs() < 1e-9 && seat > 0.0);
    let md = std::fs::read_to_string(out.join("report.md")).expect("report.md");
    assert!(md.contains("SEAT") && md.contains("11.7 kg"), "{md}");
    for f in [
        "platform_psd.png",
        "platform_psd.svg",
        "seat_response.png",
        "seat_response.svg",
    ] {
        let len = std::fs::metadata(out.join(f)).map(|m| m.len()).unwrap_or(0);
        assert!(len > 1000, "{f}: {len} bytes");
    }

    // A heavier mass and another model are accepted and reported.
    let out2 = dir.path().join("em6");
    let o = bin()
        .args([
            "seat-test",
            "--class",
            "EM6",
            "--model",
            "passive",
            "--mass",
            "75",
            "--duration",
            "30",
            "--out",
        ])
        .arg(&out2)
        .output()
        .expect("runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(out2.join("numbers.json")).expect("numbers.json"),
    )
    .expect("json");
    assert_eq!(v["mass_kg"], 75.0);
    assert_eq!(v["model"], "passive");

    // An unknown class is an error that lists the classes; nothing is written.
    let out3 = dir.path().join("bad");
    let o = bin()
        .args(["seat-test", "--class", "EM10", "--out"])
        .arg(&out3)
        .output()
        .expect("runs");
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("EM10") && err.contains("AG3"), "{err}");
    assert!(!out3.exists());
}

#[test]
fn simulate_runs_a_class_scenario() {
    let dir = tempfile::tempdir().expect("tmp");
    let out = dir.path().join("em6.csv");
    let o = bin()
        .args([
            "simulate",
            "--model",
            "linear",
            "--scenario",
            "class",
            "--class",
            "EM6",
            "--duration",
            "25",
            "--out",
        ])
        .arg(&out)
        .output()
        .expect("runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(&out).expect("csv");
    assert!(
        text.contains("class EM6"),
        "the scenario is named in the header"
    );
    let rows = text.lines().filter(|l| !l.starts_with('#')).count();
    assert!(rows > 20_000, "{rows}");
    // `--scenario class` without `--class` is an error.
    let o = bin()
        .args([
            "simulate",
            "--model",
            "linear",
            "--scenario",
            "class",
            "--out",
        ])
        .arg(dir.path().join("x.csv"))
        .output()
        .expect("runs");
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("--class"));
}
