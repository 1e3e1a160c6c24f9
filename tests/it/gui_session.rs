//! Issue 22 item 12: a session file keeps the parameters, the excitation, the A/B state, the
//! view and the Tune panel's last result; opening it in a fresh app restores every piece and
//! the engine runs with it. A corrupted or newer file is refused and changes nothing.
#![cfg(feature = "gui")]

use super::gui::{harness, step_until};
use egui_kittest::kittest::Queryable;
use seat_twin::gui::controls::ExcitationKind;
use seat_twin::gui::session::{self, Session};
use seat_twin::params::{ControllerKind, ControllerParams};
use seat_twin::tune::{Evaluation, Objective, TuneResult};

fn evaluation(c: ControllerParams, objective: f64, u_m: f64) -> Evaluation {
    Evaluation {
        controller: c,
        gains: vec![
            ("kp_v_per_m".into(), c.kp_v_per_m),
            ("ki_v_s_per_m".into(), c.ki_v_s_per_m),
        ],
        objective,
        max_abs_u_m: u_m,
        contacts: 0,
        gain_margin_db: 9.0,
        phase_margin_deg: 50.0,
        delay_margin_s: 0.03,
        unstable_points: 0,
        worst_growth_rate_per_s: -1.5,
        feasible: true,
    }
}

/// A tune result with two Pareto points of different gains (a real tuning takes minutes).
fn tune_result() -> TuneResult {
    let base = ControllerParams::paper(-5.0, -7.5);
    let a = ControllerParams::paper(-3.0, -9.0);
    let b = ControllerParams::paper(-2.0, -11.0);
    TuneResult {
        kind: ControllerKind::default(),
        objective: Objective::Aw,
        input: "random rides".into(),
        baseline: evaluation(base, 0.5, 0.01),
        tuned: evaluation(a, 0.4, 0.012),
        baseline_heldout: evaluation(base, 0.52, 0.011),
        tuned_heldout: evaluation(a, 0.41, 0.013),
        robustness: Vec::new(),
        pareto: vec![evaluation(a, 0.4, 0.012), evaluation(b, 0.45, 0.009)],
        evaluations: 40,
        tune_seeds: vec![1, 2],
        heldout_seeds: vec![101, 102],
        duration_s: 20.0,
        robust: false,
        stop_reason: "budget".into(),
        failures: Vec::new(),
    }
}

#[test]
fn session_round_trip_restores_every_piece_and_reaches_the_engine() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("lesson.toml");
    let mut h = harness();
    h.run_steps(2);
    let ctx = h.ctx.clone();
    // A gain, the excitation, A/B with a reference, a hidden curve, the view, a tune result.
    let reference = ControllerParams::paper(-4.0, -6.0);
    let live = ControllerParams::paper(-6.5, -8.0);
    {
        let app = h.state_mut();
        app.apply_tuned(reference);
        app.set_current_as_reference();
        app.apply_tuned(live);
        app.set_ab(true);
        app.settings.excitation.sine_freq_hz = 3.7;
        app.settings.excitation.sine_accel_m_s2 = 1.3;
        app.set_excitation_kind(ExcitationKind::Sine);
        app.settings.phase_unwrapped = true;
        app.settings.scope_window_s = 25.0;
        app.settings.show_schematic = false;
        app.set_ui_scale(&ctx, 1.25);
        app.tune_panel_mut().restore(Some(tune_result()), Some(1));
    }
    h.get_by_label("Q1").click();
    h.step();
    assert!(h.state().hidden_curves().contains("scope_q/Q1"));
    h.state_mut().save_session_file(&file);
    let n = h.state().notice().unwrap();
    assert!(!n.error, "{}", n.text);
    drop(h);

    let mut h = harness();
    h.run_steps(2);
    let ctx = h.ctx.clone();
    assert_eq!(h.state().settings.excitation.kind, ExcitationKind::Random);
    h.state_mut().open_session_file(&file, &ctx);
    let n = h.state().notice().unwrap();
    assert!(!n.error, "{}", n.text);
    let app = h.state();
    assert_eq!(app.params().controller, live);
    assert!(!app.is_modified());
    let ex = &app.settings.excitation;
    assert_eq!(ex.kind, ExcitationKind::Sine);
    assert_eq!((ex.sine_freq_hz, ex.sine_accel_m_s2), (3.7, 1.3));
    assert!(app.ab().is_on());
    assert_eq!(app.ab().reference(), reference);
    assert!(app.hidden_curves().contains("scope_q/Q1"));
    assert!(app.settings.phase_unwrapped);
    assert_eq!(app.settings.scope_window_s, 25.0);
    assert!(!app.settings.show_schematic);
    assert_eq!(app.settings.ui_scale, 1.25);
    let t = app.tune_panel().result().expect("the tune result");
    let want = tune_result();
    assert_eq!(
        t.pareto, want.pareto,
        "Pareto points with their controllers"
    );
    assert_eq!(t.tuned_heldout, want.tuned_heldout);
    assert_eq!(t.baseline_heldout, want.baseline_heldout);
    assert_eq!(app.tune_panel().selected(), Some(1));
    h.step();
    assert_eq!(ctx.zoom_factor(), 1.25);
    assert_eq!(h.state().settings.ui_scale, 1.25);
    // The engine runs the restored gains and the reference.
    step_until(&mut h, "the engine's echo of the session", |a| {
        a.engine_params().map(|p| p.controller) == Some(live)
            && a.engine_view().reference == Some(reference)
    });
}

#[test]
fn a_corrupted_or_newer_session_is_refused_and_changes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("s.toml");
    let mut h = harness();
    h.run_steps(2);
    let ctx = h.ctx.clone();
    h.state_mut().save_session_file(&file);
    let good = std::fs::read_to_string(&file).unwrap();
    // Unsaved work: a changed gain.
    let work = ControllerParams::paper(-6.0, -8.5);
    h.state_mut().apply_tuned(work);
    let before = *h.state().params();
    let v = session::FORMAT_VERSION;
    let cases = [
        (
            good.replace(
                &format!("format_version = {v}"),
                &format!("format_version = {}", v + 1),
            ),
            format!("format_version {}", v + 1),
        ),
        (
            good.replace("sine_freq_hz = ", "sine_freq_hz = \"x\" #"),
            "sine_freq_hz".into(),
        ),
        (
            good.replace("mass_kg = ", "mass_kg = -1.0 #"),
            "mass_kg".into(),
        ),
        (good[..good.len() / 2].to_string(), "s.toml".into()),
    ];
    for (text, field) in cases {
        std::fs::write(&file, &text).unwrap();
        h.state_mut().open_session_file(&file, &ctx);
        let n = h.state().notice().unwrap();
        assert!(n.error, "accepted: {}", n.text);
        assert!(n.text.contains("s.toml"), "{}", n.text);
        assert!(n.text.contains(&field), "{field} not named: {}", n.text);
        assert_eq!(*h.state().params(), before);
        assert!(h.state().is_modified());
    }
    // A preset is not a session.
    let preset = dir.path().join("p.toml");
    h.state_mut().save_preset_file(&preset);
    assert!(Session::load(&preset).is_err());
}

/// report.json's evaluation keys stay as they were: the controllers travel beside them.
#[test]
fn tune_controllers_live_beside_the_report_fields() {
    let v = serde_json::to_value(tune_result().pareto[0].clone()).unwrap();
    assert!(v.get("controller").is_none());
    assert!(v.get("gains").is_some());
}

/// File → Open session… asks first when there is unsaved work, as Open preset… does.
#[test]
fn open_session_asks_before_discarding_unsaved_work() {
    let mut h = harness();
    h.run_steps(2);
    h.state_mut()
        .apply_tuned(ControllerParams::paper(-6.0, -8.5));
    assert!(h.state().is_modified());
    h.get_by_label("File").click();
    h.run_steps(2);
    h.get_by_label("Open session…").click();
    h.run_steps(2);
    assert!(h.state().is_confirm_open());
}

/// A loaded platform record is kept by its path and read again on opening; a session whose
/// record has gone is refused naming `record_path`, and the excitation stays as it was.
#[test]
fn a_session_keeps_the_record_by_its_path() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("rec-session.toml");
    let rec = super::gui_edges::short_record(dir.path(), 2.0);
    let mut h = harness();
    h.run_steps(2);
    let ctx = h.ctx.clone();
    h.state_mut().load_record_file(&rec);
    assert_eq!(h.state().settings.excitation.kind, ExcitationKind::Record);
    h.state_mut().save_session_file(&file);

    let mut h = harness();
    h.run_steps(2);
    h.state_mut().open_session_file(&file, &ctx);
    let n = h.state().notice().unwrap();
    assert!(!n.error, "{}", n.text);
    let ex = &h.state().settings.excitation;
    assert_eq!(ex.kind, ExcitationKind::Record);
    let loaded = ex.record.as_ref().expect("the record read again");
    assert_eq!(loaded.path, rec);
    assert_eq!(loaded.name, "short.csv");

    std::fs::remove_file(&rec).unwrap();
    let mut h = harness();
    h.run_steps(2);
    h.state_mut().open_session_file(&file, &ctx);
    let n = h.state().notice().unwrap();
    assert!(n.error && n.text.contains("record_path"), "{}", n.text);
    assert_eq!(h.state().settings.excitation.kind, ExcitationKind::Random);
}
