//! `tune` on short runs: it lowers the objective without breaking a constraint, its claims
//! re-computed independently (the tuned gains re-simulated from `tuned.toml`, the margins from
//! the linearised loop), and its outputs have the documented shape.

use seat_twin::analysis::metrics;
use seat_twin::analysis::stability;
use seat_twin::experiments;
use seat_twin::model::ModelKind;
use seat_twin::params::{ControllerKind, Params};
use seat_twin::preset::Preset;
use seat_twin::simulation::Drive;
use seat_twin::tune::{self, Objective, TuneOptions};

fn short(kind: ControllerKind) -> TuneOptions {
    TuneOptions {
        kind,
        objective: Objective::Aw,
        input: tune::TuneInput::Ride,
        tune_seeds: vec![1],
        heldout_seeds: vec![101],
        duration_s: 12.0,
        robust: false,
        max_evaluations: 24,
    }
}

/// From the paper's gains with the predictive structure (the one the stability rules leave
/// room to improve: its lead acts outside the loop), on one short ride.
#[test]
fn tune_improves_the_paper_gains_within_every_constraint() {
    let p = Params::paper();
    let r = tune::tune(&p, &short(ControllerKind::Predictive), None).unwrap();
    assert!(r.failures.is_empty(), "{:?}", r.failures);
    assert!(r.tuned.feasible, "{:?}", r.tuned);
    assert!(
        r.tuned.objective < 0.95 * r.baseline.objective,
        "tuned {} vs start {}",
        r.tuned.objective,
        r.baseline.objective
    );
    assert!(r.evaluations <= 24, "{} evaluations", r.evaluations);
    // The constraints, recomputed here: margins of the linearised twin with the tuned law.
    let mut q = p;
    q.controller = r.tuned.controller;
    let m = stability::twin_stability(&q);
    assert!(m.stable(), "{m:?}");
    assert!(
        m.margins.gain_margin_db().abs() >= tune::MIN_GAIN_MARGIN_DB,
        "{m:?}"
    );
    assert!(
        m.margins.phase_margin_deg().abs() >= tune::MIN_PHASE_MARGIN_DEG,
        "{m:?}"
    );
    assert!(
        m.margins.delay_margin_s() >= tune::MIN_DELAY_MARGIN_S,
        "{m:?}"
    );
    // Stable at every point of the spread, as the hard constraint says.
    for s in tune::spread(&q) {
        assert!(stability::twin_stability(&s).stable(), "{s:?}");
    }
    // The objective and stroke, recomputed by an independent run of the tuned gains.
    let trace = experiments::run(
        &q,
        ModelKind::Twin,
        Drive::closed_loop(&q),
        tune::ride(1, 12.0),
        12.0,
        1000.0,
    )
    .unwrap();
    let ydd = trace.channel(|s| s.ydd);
    let aw = metrics::vibration_metrics(&ydd, 1000.0, tune::SETTLE_S)
        .unwrap()
        .aw;
    assert!(
        (aw - r.tuned.objective).abs() < 0.02 * aw,
        "re-simulated a_w {aw} vs reported {}",
        r.tuned.objective
    );
    assert!(trace.contacts.is_empty());
    let max_u = trace.samples.iter().map(|s| s.u.abs()).fold(0.0, f64::max);
    assert!(max_u <= tune::MAX_ABS_U_M, "{max_u}");
    // The Pareto front is feasible and non-dominated.
    assert!(!r.pareto.is_empty());
    for a in &r.pareto {
        assert!(a.feasible);
        for b in &r.pareto {
            assert!(
                !(b.objective < a.objective && b.max_abs_u_m < a.max_abs_u_m),
                "{a:?} dominated by {b:?}"
            );
        }
    }
    // 27 rows over Cd ±10 %, τ ±3 ms, mass ±20 %.
    assert_eq!(r.robustness.len(), 27);
    let cds: Vec<f64> = r.robustness.iter().map(|row| row.cd).collect();
    assert!(
        (cds.iter().cloned().fold(f64::INFINITY, f64::min) - 0.9 * p.plant.valve.cd).abs() < 1e-12
    );
}

/// A very short tune of `kind` from the paper's plant, its outputs written into a temporary
/// folder, and their report.json.
fn short_tune_written(
    kind: ControllerKind,
) -> (tune::TuneResult, tempfile::TempDir, serde_json::Value) {
    let p = Params::paper();
    let mut o = short(kind);
    o.max_evaluations = 12;
    o.duration_s = 8.0;
    let r = tune::tune(&p, &o, None).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let mut start = p;
    start.controller.kind = kind;
    tune::report::write_outputs(&r, &start, dir.path(), 1.0).unwrap();
    let json =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("report.json")).unwrap())
            .unwrap();
    (r, dir, json)
}

/// A skyhook tuned from its default gains cannot keep the oil column stable at rest over the
/// spread (issue 19): the run says why and writes its report, but no tuned.toml.
#[test]
fn a_claim_that_fails_writes_no_tuned_preset() {
    let (r, dir, json) = short_tune_written(ControllerKind::Skyhook);
    assert!(!r.failures.is_empty());
    assert!(
        r.failures.iter().any(|f| f.contains("unstable")),
        "{:?}",
        r.failures
    );
    assert!(!dir.path().join("tuned.toml").exists());
    assert_eq!(json["claim_holds"], false);
    assert!(!json["failures"].as_array().unwrap().is_empty());
    let md = std::fs::read_to_string(dir.path().join("report.md")).unwrap();
    assert!(md.contains("The claim fails"), "{md}");
    assert!(!md.contains("NaN") && !md.contains(" inf"), "{md}");
}

#[test]
fn tune_outputs_load_and_carry_the_interface_keys() {
    let (r, dir, json) = short_tune_written(ControllerKind::Predictive);
    assert!(r.failures.is_empty(), "{:?}", r.failures);
    let preset = Preset::load(&dir.path().join("tuned.toml")).unwrap();
    assert_eq!(preset.params.controller, r.tuned.controller);
    assert_eq!(preset.params.controller.kind, ControllerKind::Predictive);
    assert_eq!(json["controller"]["kind"], "predictive");
    assert!(json["controller"]["gains"]["lead_s"].is_number());
    assert_eq!(json["claim_holds"], true);
    for row in json["robustness"].as_array().unwrap() {
        assert_eq!(row["stable"], true);
        assert_eq!(row["passes"], true);
        assert!(row["settle"]["rms_last_2s_m_s2"].as_f64().unwrap() < 0.02);
    }
    for key in ["baseline", "tuned", "baseline_heldout", "tuned_heldout"] {
        assert!(json["objective"][key].is_number(), "objective.{key}");
    }
    for key in [
        "gain_margin_db",
        "phase_margin_deg",
        "delay_margin_s",
        "max_abs_u_mm",
        "contacts",
    ] {
        assert!(json["constraints"][key].is_number(), "constraints.{key}");
    }
    assert_eq!(json["robustness"].as_array().unwrap().len(), 27);
    assert!(json["evaluations"].as_u64().unwrap() >= 1);
    assert!(json["wall_s"].is_number());
    let md = std::fs::read_to_string(dir.path().join("report.md")).unwrap();
    assert!(!md.contains("NaN"), "{md}");
    for f in [
        "pareto.png",
        "pareto.svg",
        "transmissibility.png",
        "transmissibility.svg",
    ] {
        assert!(dir.path().join(f).metadata().unwrap().len() > 1000, "{f}");
    }
}

#[test]
fn tune_runs_on_a_seat_test_class() {
    let p = Params::paper();
    let class = seat_twin::seat_test::find("AG1").unwrap();
    let o = TuneOptions {
        input: tune::TuneInput::Class(class),
        duration_s: 20.0,
        max_evaluations: 10,
        ..short(ControllerKind::Paper)
    };
    let r = tune::tune(&p, &o, None).unwrap();
    assert!(r.input.contains("AG1"), "{}", r.input);
    assert!(r.baseline.objective.is_finite() && r.tuned.objective.is_finite());
    // The paper's gains are not feasible whatever the ride: the closed loop is unstable at
    // points of the parameter spread. So the result must be a feasible set (stable at every
    // point, no contact, within the stroke), not merely "no worse". (Before, `||
    // !baseline.feasible` let any result pass here.)
    assert!(
        !r.baseline.feasible && r.baseline.unstable_points > 0,
        "{:?}",
        r.baseline
    );
    assert!(r.tuned.feasible, "{:?}", r.tuned);
    assert_eq!(r.tuned.unstable_points, 0, "{:?}", r.tuned);
    assert_eq!(r.tuned.contacts, 0, "{:?}", r.tuned);
    assert!(r.tuned.max_abs_u_m <= 0.030, "{:?}", r.tuned);
    // The class is far stronger than the paper's ride (AG1: 2.26 m/s² rms against 0.47).
    assert!(r.baseline.objective > 0.3, "{}", r.baseline.objective);
}

/// Issue 21, item 4: the budget is a maximum. Before, `--evaluations 10` ran 11–29 search
/// evaluations (the iteration limit was half the budget, and an iteration of Nelder–Mead
/// makes one to n + 2 evaluations).
#[test]
fn the_evaluation_budget_is_a_hard_maximum() {
    for kind in [ControllerKind::Paper, ControllerKind::Skyhook] {
        let opts = TuneOptions {
            duration_s: 5.0,
            max_evaluations: 10,
            ..short(kind)
        };
        let most = std::sync::Arc::new(std::sync::atomic::AtomicUsize::new(0));
        let seen = most.clone();
        let progress: tune::Progress = std::sync::Arc::new(move |done, budget| {
            assert_eq!(budget, 10);
            seen.fetch_max(done, std::sync::atomic::Ordering::Relaxed);
        });
        let r = tune::tune_observed(&Params::paper(), &opts, None, Some(progress)).unwrap();
        assert!(
            r.evaluations <= 10,
            "{kind:?}: {} evaluations",
            r.evaluations
        );
        assert_eq!(
            most.load(std::sync::atomic::Ordering::Relaxed),
            r.evaluations
        );
        // Nelder–Mead does not stop on its tolerance within 10 evaluations here: the budget
        // is used whole, and the report says so.
        assert_eq!(r.evaluations, 10, "{kind:?}");
        assert_eq!(r.stop_reason, "budget of evaluations used", "{kind:?}");
    }
}

/// Issue 23, item 5: a cancel is a typed stop reason, not an error text to match. A cancel
/// set from the progress observer after the third search evaluation stops the search at the
/// next one with `TuneError::Cancelled`, and no evaluation runs after it.
#[test]
fn a_cancel_during_the_search_stops_it_with_the_cancelled_error() {
    use std::sync::Arc;
    use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
    let opts = TuneOptions {
        duration_s: 5.0,
        max_evaluations: 10,
        ..short(ControllerKind::Paper)
    };
    let cancel = Arc::new(AtomicBool::new(false));
    let done = Arc::new(AtomicUsize::new(0));
    let (flag, seen) = (cancel.clone(), done.clone());
    let progress: tune::Progress = Arc::new(move |n, _| {
        seen.store(n, Ordering::Relaxed);
        if n == 3 {
            flag.store(true, Ordering::Relaxed);
        }
    });
    let r = tune::tune_observed(&Params::paper(), &opts, Some(cancel), Some(progress));
    assert!(
        matches!(r, Err(tune::TuneError::Cancelled)),
        "{:?}",
        r.map(|r| r.stop_reason)
    );
    assert_eq!(done.load(Ordering::Relaxed), 3);
}

/// The stepped search (one optimiser iteration per step, for the web app's frames) gives what
/// argmin's `Executor` gives in one call: the same evaluations in the same order, the same
/// stop reason and result, bit for bit.
#[test]
fn stepped_tune_equals_the_executor_run() {
    let opts = TuneOptions {
        kind: ControllerKind::Predictive,
        tune_seeds: vec![1],
        heldout_seeds: vec![101],
        duration_s: 6.0,
        max_evaluations: 14,
        ..TuneOptions::default()
    };
    let p = Params::paper();
    let mut steps = 0;
    let mut run = tune::TuneRun::new(&p, &opts, None, None).unwrap();
    let stepped = loop {
        steps += 1;
        if let Some(r) = run.step() {
            break r.unwrap();
        }
    };
    let reference = tune::TuneRun::new(&p, &opts, None, None)
        .unwrap()
        .finish_with_executor()
        .unwrap();
    let json = |r: &tune::TuneResult| serde_json::to_string(r).unwrap();
    assert_eq!(json(&stepped), json(&reference));
    assert_eq!(stepped.stop_reason, reference.stop_reason);
    // Cut into pieces: at least the baseline, the start simplex and an iteration.
    assert!(steps >= 4, "{steps} steps");
}
