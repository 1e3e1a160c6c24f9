//! The calibration on records the twin made itself (noise-free, `identify::testdata`): the
//! fits have a known answer, and the reports must carry the result's own numbers.
//!
//! These run a whole calibration or a declared-parameter fit. They were unit tests; they are
//! here so that the library's unit tests stay cheap enough to compile unoptimised (see the
//! README's "Tests").

use seat_twin::identify::fit::{Evaluator, Knob};
use seat_twin::identify::progress::Monitor;
use seat_twin::identify::replay::StepRule;
use seat_twin::identify::report::{report_json, report_markdown};
use seat_twin::identify::stages::{declared_fit, fit_params};
use seat_twin::identify::testdata::{true_params, twin_record};
use seat_twin::identify::units::format_parameter;
use seat_twin::identify::{CalibrationOptions, Progress, Stage, Verdict, calibrate, data};
use seat_twin::params::Params;
use std::sync::atomic::AtomicBool;

/// The declared fit, on records the twin made with Cd 10 % low and τ 2 ms long, starts from
/// the paper's values and recovers both (the data are noise-free, so to a fraction of a per
/// cent), with uncertainties that cover the truth and nothing undetermined.
#[test]
fn declared_fit_recovers_known_cd_and_tau() {
    let truth = true_params();
    let records = [
        twin_record(&truth, 3.0, "a.csv").unwrap(),
        twin_record(&truth, 3.0, "b.csv").unwrap(),
    ];
    let options = CalibrationOptions::default();
    let checked = data::check(&records, &options).unwrap();
    assert!(checked.missing.is_empty(), "{:?}", checked.missing);
    let campaign = data::split(checked.records);
    let cancel = AtomicBool::new(false);
    let stages = std::sync::Mutex::new(Vec::new());
    let observer = |p: &Progress| stages.lock().unwrap().push(p.stage);
    let monitor = Monitor::new(&cancel, &observer);
    let ev = Evaluator {
        records: &campaign.fit,
        monitor: &monitor,
        step: StepRule::Resolving,
    };
    let start = fit_params(&Params::paper(), &options);
    let d = declared_fit(&ev, &start, start.plant.body.mass_kg, &options).unwrap();
    assert!(d.undetermined.is_empty(), "{:?}", d.undetermined);
    let value = |k: Knob| d.fit.values.iter().find(|v| v.knob == k).unwrap();
    let (cd, tau) = (value(Knob::Cd), value(Knob::Tau));
    assert!(
        (cd.value / truth.plant.valve.cd - 1.0).abs() < 2e-3,
        "Cd {} ± {} vs {}",
        cd.value,
        cd.std,
        truth.plant.valve.cd
    );
    assert!(
        (tau.value - truth.plant.valve.tau_s).abs() < 5e-5,
        "τ {} ± {} vs {}",
        tau.value,
        tau.std,
        truth.plant.valve.tau_s
    );
    // The starting point was far off: the fit moved, by the whole error.
    assert!((start.plant.valve.cd - truth.plant.valve.cd).abs() > 0.05 * truth.plant.valve.cd);
    assert!(d.notes.iter().any(|n| n.starts_with(&format!(
        "declared-parameter fit stopped: {} after",
        d.fit.termination
    ))));
    // The observer saw the stage, and Jacobians as its work.
    assert!(stages.lock().unwrap().contains(&Stage::DeclaredFit));
    assert!(monitor.evaluations() > 0);
}

/// The numbers of `report.json` are the result's own, and `report.md` shows the calibrated
/// parameters, the verdict and the optimiser's stop reason in words. The calibrated
/// parameters validate and keep the preset's step (nothing in them needs a shorter one).
#[test]
fn report_numbers_are_the_results() {
    let truth = true_params();
    let records = [
        twin_record(&truth, 3.0, "a.csv").unwrap(),
        twin_record(&truth, 3.0, "b.csv").unwrap(),
    ];
    let r = calibrate(&Params::paper(), &records, &Default::default(), &|_| true).unwrap();
    assert_ne!(r.verdict, Verdict::InsufficientData);
    r.params.validate().expect("the calibrated parameters load");
    assert_eq!(
        r.params.numerics.max_step_s,
        Params::paper().numerics.max_step_s
    );
    assert!(!r.notes.iter().any(|n| n.contains("calibrated twin's step")));
    let j = report_json(&r);
    assert_eq!(j["verdict"], r.verdict.name());
    for v in &r.calibrated {
        assert_eq!(j["calibrated_parameters"][&v.name].as_f64(), Some(v.value));
        assert_eq!(j["calibrated_uncertainties"][&v.name].as_f64(), Some(v.std));
    }
    // The twin made the data: the calibration finds its Cd.
    let cd = j["calibrated_parameters"]["cd"].as_f64().unwrap();
    assert!((cd / truth.plant.valve.cd - 1.0).abs() < 5e-3, "{cd}");
    for (key, e) in [
        ("error_nominal", &r.error_nominal),
        ("error_before", &r.error_before),
        ("error_after", &r.error_after),
    ] {
        assert_eq!(j[key]["value"].as_f64(), Some(e.value), "{key}");
    }
    let v = r.error_validation.as_ref().unwrap();
    assert_eq!(j["error_validation"]["before"].as_f64(), Some(v.before));
    assert_eq!(j["error_validation"]["after"].as_f64(), Some(v.after));
    assert_eq!(j["replays"].as_u64(), Some(r.evaluations as u64));
    // Nominal (Cd 10 % off) is far worse than calibrated.
    assert!(r.error_nominal.value > 3.0 * r.error_before.value);
    let md = report_markdown(&r, Some(1.5));
    assert!(md.contains(&format!("**Verdict: `{}`**", r.verdict.name())));
    for v in &r.calibrated {
        assert!(
            md.contains(&format_parameter(&v.name, v.value, v.std)),
            "{md}"
        );
    }
    let stopped = r
        .notes
        .iter()
        .find(|n| n.starts_with("declared-parameter fit stopped: "))
        .unwrap();
    assert!(
        !stopped.contains('{') && !stopped.contains('"'),
        "{stopped}"
    );
    assert!(md.contains(stopped.as_str()));
}
