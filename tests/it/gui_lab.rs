//! The controller lab in the app, driven headless with egui_kittest: the structure combo box
//! and its gain sliders reach the engine and the frequency plots, refused gains reach
//! nothing, seat-test classes run from the excitation list, and the A/B view runs B.
#![cfg(feature = "gui")]

use super::gui::step_until;
use egui::accesskit::Role;
use egui_kittest::Harness;
use egui_kittest::kittest::{By, Queryable};
use num_complex::Complex64;
use seat_twin::control::ControlLaw;
use seat_twin::gui::SeatTwinApp;
use seat_twin::gui::frequency::{F_RANGE_HZ, N_POINTS};
use seat_twin::model::linear::g_of;
use seat_twin::params::{ControllerKind, ControllerParams, Params};
use std::f64::consts::PI;
use std::time::Duration;

/// The app after its first frame, once the engine has answered.
fn harness() -> Harness<'static, SeatTwinApp> {
    let mut h = super::gui::harness();
    h.step();
    step_until(&mut h, "the engine's first status", |a| {
        a.engine_params().is_some()
    });
    h
}

/// Opens the combo box that shows `current` and picks `choice` in it.
fn pick(h: &mut Harness<'static, SeatTwinApp>, current: &str, choice: &str) {
    h.get(By::new().role(Role::ComboBox).value(current)).click();
    h.run_steps(2);
    h.get_by_label(choice).click();
    h.run_steps(2);
}

/// |T| [dB] of the linear model G(s) under a controller, from `ControlLaw::transmissibility`
/// with the plant's open-loop responses written out here: `u = G0/s·V_valve`,
/// `ÿ = ẍ + s·G0·V_valve` (G0: G(s) without its delay).
fn linear_t_db(p: &Params, f_hz: f64) -> f64 {
    let w = 2.0 * PI * f_hz;
    let s = Complex64::new(0.0, w);
    let mut l = p.linear;
    let tau = l.tau_s;
    l.tau_s = 0.0;
    let g0 = g_of(&l, w);
    let t = ControlLaw::new(p).transmissibility(
        w,
        tau,
        g0 / s,
        Complex64::new(0.0, 0.0),
        g0 * s,
        Complex64::new(1.0, 0.0),
    );
    20.0 * t.norm().log10()
}

#[test]
fn structure_switch_reaches_the_engine_and_the_transmissibility() {
    let mut h = harness();
    let paper_curve = h.state().curves().t_mag[0].clone();
    assert_eq!(paper_curve.len(), N_POINTS);
    pick(&mut h, "paper", "skyhook");
    let p = *h.state().params();
    assert_eq!(p.controller.kind, ControllerKind::Skyhook);
    // The skyhook's own gain sliders replace the paper's pair.
    h.get_by_role_and_label(Role::Slider, "Ksky");
    h.get_by_role_and_label(Role::Slider, "leak");
    assert!(h.query_by_label("lead").is_none());
    // The linear |T| on screen is the one ControlLaw predicts for the skyhook law.
    let curve = &h.state().curves().t_mag[0];
    let mut moved: f64 = 0.0;
    for (i, pt) in curve.iter().enumerate() {
        let f = 10f64.powf(pt.x);
        assert!(f >= F_RANGE_HZ.0 * 0.999 && f <= F_RANGE_HZ.1 * 1.001);
        let expected = linear_t_db(&p, f);
        assert!(
            (pt.y - expected).abs() < 1e-6,
            "{f} Hz: {} dB shown, {expected} dB expected",
            pt.y
        );
        moved = moved.max((pt.y - paper_curve[i].y).abs());
    }
    assert!(moved > 1.0, "the skyhook did not change |T| ({moved} dB)");
    // A gain of that kind moves it again, and reaches the engine.
    h.get_by_role_and_label(Role::Slider, "Ksky")
        .set_value_accesskit(-6.0);
    h.run_steps(2);
    assert_eq!(h.state().params().controller.sky_v_s_per_m, -6.0);
    step_until(&mut h, "the engine to run skyhook with Ksky = -6", |a| {
        a.engine_params().is_some_and(|p| {
            p.controller.kind == ControllerKind::Skyhook && p.controller.sky_v_s_per_m == -6.0
        })
    });
}

#[test]
fn a_refused_gain_reaches_neither_the_params_nor_the_engine() {
    let mut h = harness();
    pick(&mut h, "paper", "predictive");
    step_until(&mut h, "the engine to run predictive", |a| {
        a.engine_params()
            .is_some_and(|p| p.controller.kind == ControllerKind::Predictive)
    });
    let p0 = *h.state().params();
    // 150 ms of lead is outside 0 … 100 ms.
    h.get_by_role_and_label(Role::Slider, "lead")
        .set_value_accesskit(150.0);
    h.run_steps(2);
    assert_eq!(*h.state().params(), p0);
    let e = h
        .state()
        .field_errors()
        .get("lead")
        .expect("a message next to the slider")
        .clone();
    assert!(e.contains("refused") && e.contains("100"), "{e}");
    std::thread::sleep(Duration::from_millis(100));
    h.step();
    assert_eq!(h.state().engine_params(), Some(&p0));
    // An accepted value goes through, in seconds.
    h.get_by_role_and_label(Role::Slider, "lead")
        .set_value_accesskit(30.0);
    h.run_steps(2);
    assert!((h.state().params().controller.lead_s - 0.030).abs() < 1e-12);
    assert!(h.state().field_errors().is_empty());
}

#[test]
fn seat_test_class_runs_from_the_excitation_list() {
    let mut h = harness();
    h.get_by_label("max").click();
    h.step();
    pick(&mut h, "random ride", "seat-test class");
    pick(&mut h, "EM6", "AG2");
    assert_eq!(h.state().settings.excitation.class_name, "AG2");
    h.get_by_label_contains("ISO 5007:2003");
    h.get_by_label_contains("this twin carries 11.7 kg");
    step_until(&mut h, "3 s of the class on the scopes", |a| {
        a.traces().t_now() > 3.0
    });
    assert!(h.state().engine_error().is_none());
    let rows = h.state().traces().rows();
    let rms = (rows.iter().map(|r| r.twin.xdd.powi(2)).sum::<f64>() / rows.len() as f64).sqrt();
    assert!(rms > 0.3, "platform rms {rms}");
}

#[test]
fn ab_switch_runs_the_reference_and_set_current_pins_it() {
    let mut h = harness();
    h.get_by_label("max").click();
    h.step();
    h.get_by_label("A/B: compare with a reference twin").click();
    h.step();
    assert!(h.state().ab().is_on());
    step_until(&mut h, "the engine to run B with the paper's gains", |a| {
        a.engine_view().reference == Some(ControllerParams::default())
    });
    step_until(&mut h, "B on the scopes", |a| a.traces().t_now() > 2.5);
    // Same controller on both: B is A, sample for sample.
    let m = h.state().traces().metrics.ab().expect("A/B metrics");
    assert_eq!(m.a.aw, m.b.aw);
    h.get_by_label("A vs B");
    // A new live controller, then pin it as B.
    h.get_by_role_and_label(Role::Slider, "Kp")
        .set_value_accesskit(-40.0);
    h.run_steps(2);
    h.get_by_label("Set current as reference").click();
    h.run_steps(2);
    assert_eq!(h.state().ab().reference().kp_v_per_m, -40.0);
    step_until(&mut h, "the engine to run B with Kp = -40", |a| {
        a.engine_view()
            .reference
            .is_some_and(|c| c.kp_v_per_m == -40.0)
    });
    // Paper's gains back as B: A (Kp = −40) and B now differ.
    h.get_by_label("Paper's gains").click();
    h.run_steps(2);
    step_until(&mut h, "B = paper again and 3 s counted", |a| {
        a.engine_view().reference == Some(ControllerParams::default())
            && a.traces()
                .metrics
                .ab()
                .is_some_and(|m| m.b.duration_s > 2.0)
    });
    let m = h.state().traces().metrics.ab().expect("A/B metrics");
    assert!(m.a.aw != m.b.aw, "A and B identical with different gains");
    // Off: B stops.
    h.get_by_label("A/B: compare with a reference twin").click();
    h.step();
    step_until(&mut h, "B off", |a| a.engine_view().reference.is_none());
}

fn tiny_tune(p: &Params, evaluations: usize, duration_s: f64) -> seat_twin::tune::TuneOptions {
    seat_twin::tune::TuneOptions {
        kind: p.controller.kind,
        tune_seeds: vec![1],
        heldout_seeds: vec![101],
        duration_s,
        max_evaluations: evaluations,
        ..Default::default()
    }
}

#[test]
fn tune_job_reports_progress_completes_and_apply_sets_the_gains() {
    let mut h = harness();
    let p0 = *h.state().params();
    h.get_by_label("Tune").click();
    h.run_steps(2);
    let opts = tiny_tune(&p0, 10, 5.0);
    h.state_mut().start_tune(opts);
    step_until(&mut h, "the tuning result", |a| {
        a.tune_panel().result().is_some()
    });
    let (done, budget) = h.state().tune_panel().last_progress().expect("a job");
    assert_eq!(budget, 10);
    assert!(done >= 1, "{done} evaluations reported");
    let r = h.state().tune_panel().result().expect("a result").clone();
    assert!(
        !r.pareto.is_empty(),
        "no feasible point on the paper's start"
    );
    // Every point on the front keeps the constraints.
    for e in &r.pareto {
        assert!(e.feasible && e.contacts == 0 && e.max_abs_u_m <= 0.030);
        assert!(e.gain_margin_db >= 6.0 && e.phase_margin_deg >= 45.0);
    }
    h.run_steps(2);
    h.get_by_label_contains("Held-out a_w");
    let chosen = r.pareto[h.state().tune_panel().selected().expect("a chosen point")].controller;
    h.get_by_label("Apply").click();
    h.run_steps(2);
    assert_eq!(h.state().params().controller, chosen);
    assert!(h.state().is_modified() || chosen == p0.controller);
    step_until(&mut h, "the engine to run the tuned gains", |a| {
        a.engine_params().is_some_and(|p| p.controller == chosen)
    });
}

#[test]
fn tune_job_can_be_cancelled_from_the_panel() {
    let mut h = harness();
    h.get_by_label("Tune").click();
    h.run_steps(2);
    let p0 = *h.state().params();
    h.state_mut().start_tune(tiny_tune(&p0, 10_000, 60.0));
    h.run_steps(2);
    assert!(h.state().tune_panel().is_running());
    h.get_by_label("Cancel tuning").click();
    h.run_steps(1);
    step_until(&mut h, "the job to stop", |a| !a.tune_panel().is_running());
    let (m, error) = h.state().tune_panel().message().expect("a message").clone();
    assert!(m.contains("cancelled") && !error, "{m}");
    assert!(h.state().tune_panel().result().is_none());
    assert_eq!(*h.state().params(), p0);
}

#[test]
fn a_saved_preset_keeps_the_structure_and_its_gains() {
    let mut h = harness();
    pick(&mut h, "paper", "predictive");
    h.get_by_role_and_label(Role::Slider, "lead")
        .set_value_accesskit(25.0);
    h.run_steps(2);
    let c = h.state().params().controller;
    assert_eq!(c.kind, ControllerKind::Predictive);
    let dir = tempfile::tempdir().expect("a temp dir");
    let path = dir.path().join("lab.toml");
    h.state_mut().save_preset_file(&path);
    let text = std::fs::read_to_string(&path).expect("the preset file");
    assert!(text.contains("kind = \"predictive\""), "{text}");
    // Back to paper, then the file brings the structure and gains back.
    pick(&mut h, "predictive", "paper");
    assert_eq!(h.state().params().controller.kind, ControllerKind::Paper);
    h.state_mut().open_preset_file(&path);
    h.run_steps(2);
    assert_eq!(h.state().params().controller, c);
    h.get_by_role_and_label(Role::Slider, "lead");
    step_until(&mut h, "the engine to run the loaded controller", |a| {
        a.engine_params().is_some_and(|p| p.controller == c)
    });
}
