//! The real app driven headless with egui_kittest: no window, no GPU. The engine thread
//! runs for real; the tests step frames until it has answered.
#![cfg(feature = "gui")]

use egui::accesskit::Role;
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use seat_twin::gui::SeatTwinApp;
use seat_twin::gui::settings::Settings;
use std::time::{Duration, Instant};

pub(crate) fn harness() -> Harness<'static, SeatTwinApp> {
    let app = SeatTwinApp::new(Settings::default(), || {});
    Harness::builder()
        .with_size([1600.0, 1000.0])
        .build_ui_state(|ui, app: &mut SeatTwinApp| app.ui(ui), app)
}

/// The app after its first frame, with the speed button "max" clicked (engine as fast as it
/// can go).
pub(crate) fn harness_at_max_speed() -> Harness<'static, SeatTwinApp> {
    let mut h = harness();
    h.step();
    h.get_by_label("max").click();
    h.step();
    h
}

/// Steps frames (with short sleeps so the engine can work) until `done` holds. The limit
/// only stops a test that would hang; it is generous because the suite runs the engine
/// threads of several app tests at once on two cores.
pub(crate) fn step_until(
    h: &mut Harness<'static, SeatTwinApp>,
    what: &str,
    done: impl Fn(&SeatTwinApp) -> bool,
) {
    let t0 = Instant::now();
    while !done(h.state()) {
        assert!(
            t0.elapsed() < Duration::from_secs(60),
            "timed out waiting for: {what}"
        );
        std::thread::sleep(Duration::from_millis(20));
        h.step();
    }
}

#[test]
fn kp_slider_reaches_the_engine_and_changes_the_response() {
    let mut h = harness();
    h.step();
    step_until(&mut h, "the engine's first status", |a| {
        a.engine_params().is_some()
    });
    assert_eq!(h.state().params().controller.kp_v_per_m, -5.0);
    let before_twin = h.state().curves().t_mag[1].clone();
    let before_linear = h.state().curves().t_mag[0].clone();
    assert!(!before_twin.is_empty());

    h.get_by_role_and_label(Role::Slider, "Kp")
        .set_value_accesskit(-40.0);
    h.step();
    // The edited value and the analytic curves change on the same frame.
    assert_eq!(h.state().params().controller.kp_v_per_m, -40.0);
    assert!(h.state().is_modified());
    let after_twin = &h.state().curves().t_mag[1];
    let after_linear = &h.state().curves().t_mag[0];
    let moved = |a: &[egui_plot::PlotPoint], b: &[egui_plot::PlotPoint]| {
        a.iter()
            .zip(b)
            .map(|(p, q)| (p.y - q.y).abs())
            .fold(0.0, f64::max)
    };
    assert!(
        moved(&before_twin, after_twin) > 1.0,
        "twin |T| did not move"
    );
    assert!(
        moved(&before_linear, after_linear) > 1.0,
        "linear |T| did not move"
    );

    // The engine echoes the gain it runs with.
    step_until(&mut h, "the engine to report Kp = -40", |a| {
        a.engine_params()
            .is_some_and(|p| p.controller.kp_v_per_m == -40.0)
    });
    // And it keeps streaming samples into the scopes.
    step_until(&mut h, "samples in the scopes", |a| {
        a.traces().rows().len() > 50
    });
}

#[test]
fn typed_tau_in_ms_is_stored_in_seconds() {
    let mut h = harness();
    h.step();
    h.get_by_role_and_label(Role::Slider, "τ")
        .set_value_accesskit(25.0);
    h.step();
    let p = h.state().params();
    assert!(
        (p.plant.valve.tau_s - 0.025).abs() < 1e-12,
        "{}",
        p.plant.valve.tau_s
    );
    assert!((p.linear.tau_s - 0.025).abs() < 1e-12);
    step_until(&mut h, "the engine to run with τ = 25 ms", |a| {
        a.engine_params()
            .is_some_and(|p| (p.plant.valve.tau_s - 0.025).abs() < 1e-12)
    });
}

#[test]
fn space_bar_and_button_toggle_run_and_pause() {
    let mut h = harness();
    h.step();
    step_until(&mut h, "running", |a| a.engine_view().running);
    h.key_press(egui::Key::Space);
    h.step();
    assert!(!h.state().wants_running());
    step_until(&mut h, "the engine to pause", |a| !a.engine_view().running);
    let t_paused = h.state().engine_view().t;
    std::thread::sleep(Duration::from_millis(200));
    h.step();
    assert_eq!(
        h.state().engine_view().t,
        t_paused,
        "time moved while paused"
    );

    h.get_by_label("Run").click();
    h.step();
    assert!(h.state().wants_running());
    step_until(&mut h, "the engine to run again", |a| {
        a.engine_view().running && a.engine_view().t > t_paused
    });
}

#[test]
fn shipped_preset_opens_from_the_menu_after_the_discard_prompt() {
    let mut h = harness();
    h.step();
    assert!(
        h.state()
            .shipped_presets()
            .iter()
            .any(|(n, _)| n == "paper-initial"),
        "presets/paper-initial.toml is shipped"
    );
    // An unsaved change first: opening a preset must ask.
    h.get_by_role_and_label(Role::Slider, "Ki")
        .set_value_accesskit(-20.0);
    h.step();
    assert!(h.state().is_modified());

    h.get_by_label("Presets").click();
    h.run_steps(3);
    h.get_by_label("paper-initial").click();
    h.step();
    assert!(h.state().is_confirm_open(), "no discard prompt");
    assert_eq!(h.state().params().controller.ki_v_s_per_m, -20.0);
    h.run_steps(2);
    h.get_by_label("Discard changes").click();
    h.step();
    assert!(!h.state().is_confirm_open());
    let app = h.state();
    assert_eq!(app.preset().name, "paper-initial");
    assert_eq!(app.params().plant.valve.cd, 0.1074);
    assert!(!app.is_modified());
    step_until(&mut h, "the engine to run the preset", |a| {
        a.engine_params()
            .is_some_and(|p| p.plant.valve.cd == 0.1074)
    });
}

#[test]
fn bad_preset_file_leaves_the_parameters_and_says_where() {
    let mut h = harness();
    h.step();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("broken.toml");
    std::fs::write(&path, "[valve]\ncd = \"fast\"\n").unwrap();
    let before = *h.state().params();
    h.state_mut().open_preset_file(&path);
    h.step();
    let app = h.state();
    assert_eq!(*app.params(), before);
    let n = app.notice().expect("a message");
    assert!(n.error);
    assert!(n.text.contains("broken.toml"), "{}", n.text);
    assert!(n.text.contains('2'), "line number missing: {}", n.text);
    // The message is on screen.
    h.get_by_label_contains("preset not loaded");
}

#[test]
fn saved_preset_reads_back_and_clears_the_modified_marker() {
    let mut h = harness();
    h.step();
    h.get_by_role_and_label(Role::Slider, "Cd")
        .set_value_accesskit(0.2);
    h.step();
    assert!(h.state().is_modified());
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("mine.toml");
    h.state_mut().save_preset_file(&path);
    h.step();
    assert!(!h.state().is_modified());
    let back = seat_twin::preset::Preset::load(&path).unwrap();
    assert_eq!(back.params, *h.state().params());
    assert_eq!(
        h.state().settings.last_preset.as_deref(),
        Some(path.as_path())
    );
}

/// The banner says which mode grows and how fast (the eigenvalue verdict), and the remedy.
#[test]
fn positive_kp_shows_the_unstable_banner_with_the_growing_mode() {
    let mut h = harness();
    h.step();
    assert!(h.query_by_label_contains("UNSTABLE").is_none());
    h.get_by_role_and_label(Role::Slider, "Kp")
        .set_value_accesskit(20.0);
    h.step();
    assert!(h.state().curves().unstable());
    h.step();
    let banner = h.get_by_label_contains("UNSTABLE");
    let text = format!("{banner:?}");
    assert!(
        text.contains("grows at") && text.contains("use a negative Kp"),
        "{text}"
    );
}

#[test]
fn csv_export_table_holds_ten_seconds_of_finite_rows() {
    let mut h = harness();
    h.step();
    step_until(&mut h, "a second of samples", |a| {
        a.traces().rows().len() >= 500
    });
    let table = h.state().traces_table();
    assert_eq!(table.header.len(), table.rows[0].len());
    assert!(table.rows.len() >= 500);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("traces.csv");
    seat_twin::dataset::write_csv_atomic(
        &path,
        &table.header,
        &table.comments,
        table.rows.into_iter(),
    )
    .unwrap();
    // It reads back as a measured record (t, v_in, u in SI).
    let rec =
        seat_twin::dataset::read_record(&path, seat_twin::dataset::RecordKind::Measured).unwrap();
    assert!((rec.sample_rate_hz() - 500.0).abs() < 1.0);
}

/// Headless per-frame cost of the UI with 10 s of history in all scopes: the app's `ui`
/// (layout, plots, analytic curves cache) plus egui's tessellation of the frame. Prints the
/// figures (run with `--nocapture` to see them); what it asserts is that the scopes hold 10 s,
/// the frame tessellates and a Kp change reaches the curves within the frame.
/// Issue 13.7: this test used to time frames and end in an assertion that was always true.
/// Speed is not asserted by tests (a busy CI machine would fail them; the app's debug overlay
/// shows the frame cost). What it checks now can fail: with a full 10 s window every twin
/// channel holds the whole window, every scope is laid out, the frame tessellates, and a
/// slider frame recomputes the analytic curves for the new value.
#[test]
fn full_scopes_paint_the_whole_window_and_sliders_recompute_in_frame() {
    let mut h = harness_at_max_speed();
    step_until(&mut h, "10 s of history", |a| a.traces().t_now() > 10.5);
    h.key_press(egui::Key::Space);
    h.step();
    step_until(&mut h, "pause", |a| !a.engine_view().running);
    h.step();
    let rows = h.state().traces().rows().len();
    assert!(rows >= 4900, "{rows} rows in the window");
    // Every scope is laid out, and every twin channel holds the whole window (no sample
    // dropped between the engine and the plots).
    assert_eq!(
        h.state().scope_frames().len(),
        seat_twin::gui::scopes::N_SCOPES
    );
    for f in h.state().scope_frames() {
        assert!(f.width() > 100.0 && f.height() > 50.0, "scope frame {f:?}");
    }
    use seat_twin::gui::traces::Ch;
    for ch in [
        Ch::TwinAcc,
        Ch::TwinU,
        Ch::P1,
        Ch::Q1,
        Ch::TwinVin,
        Ch::TwinXv,
    ] {
        let n = h.state().traces().channel(ch).points().len();
        assert!(
            n as f64 >= 0.98 * rows as f64,
            "{ch:?}: {n} of {rows} points"
        );
    }
    let shapes = h.output().shapes.clone();
    let ppp = h.output().pixels_per_point;
    assert!(!h.ctx.tessellate(shapes, ppp).is_empty());
    // A slider move: the analytic curves (and margins) are recomputed within that frame.
    // The curves themselves, not only the parameters they were computed for: the linear
    // model's |T| against the closed form G(s) gives at the new gain, point for point.
    let mut before = h.state().curves().t_mag[0].clone();
    for kp in [-6.0, -7.0, -8.0] {
        h.get_by_role_and_label(Role::Slider, "Kp")
            .set_value_accesskit(kp);
        h.step();
        let curves = h.state().curves();
        assert_eq!(curves.params.unwrap().controller.kp_v_per_m, kp);
        let p = *h.state().params();
        let t_lin = &curves.t_mag[0];
        assert!(t_lin.len() > 100);
        for pt in t_lin {
            // The plot's x is log10 of the frequency.
            let f_hz = 10f64.powf(pt.x);
            let t = seat_twin::analysis::frequency_response::linear_transmissibility(&p, f_hz);
            let want = 20.0 * t.norm().log10();
            assert!(
                (pt.y - want).abs() < 1e-6,
                "|T| at {f_hz} Hz: {} dB, want {want} dB",
                pt.y
            );
        }
        assert!(
            t_lin
                .iter()
                .zip(&before)
                .any(|(a, b)| (a.y - b.y).abs() > 1e-3),
            "Kp = {kp}: the curve did not change"
        );
        before = t_lin.clone();
    }
    // A plant parameter: the twin is re-linearised and its responses re-evaluated in-frame.
    for cd in [0.14, 0.15] {
        h.get_by_role_and_label(Role::Slider, "Cd")
            .set_value_accesskit(cd);
        h.step();
        assert_eq!(h.state().curves().params.unwrap().plant.valve.cd, cd);
    }
}

#[test]
fn simulated_bode_points_follow_the_paper_gain_and_the_linearised_phase() {
    let mut h = harness();
    h.step();
    super::gui_measured::step_until_long(
        &mut h,
        "the background sine dwells",
        Duration::from_secs(120),
        |a| a.dwell().is_current(a.params()),
    );
    let d = h.state().dwell();
    let n_expected = seat_twin::analysis::frequency_response::log_space(0.3, 30.0, 14)
        .into_iter()
        .filter(|&f| f <= 20.0)
        .count();
    assert_eq!(
        d.bode_mag.len(),
        n_expected,
        "one u̇/V point per dwell ≤ 20 Hz"
    );
    // Low frequency: the paper's measured valve-cylinder gain Kg = 133.25 mm/(s·V)
    // (42.49 dB), independent of this code.
    let low = d.bode_mag[0];
    let kg_db = 20.0 * 133.25f64.log10();
    assert!((low.y - kg_db).abs() < 0.2, "{} dB vs {kg_db} dB", low.y);
    // Phase lag grows with frequency as a delay of ≈ 20 ms (17.5 ms + the spool's lag).
    let last = d.bode_phase[d.bode_phase.len() - 1];
    let f = 10f64.powf(last.x);
    let delay_s = -last.y / 360.0 / f;
    assert!(
        (0.016..0.025).contains(&delay_s),
        "phase {} deg at {f} Hz: {delay_s} s",
        last.y
    );
}

/// Gains that make the loop unstable: the linear model diverges in the engine thread. The app
/// shows the engine's error in the red banner (naming the model), keeps drawing frames, and
/// Reset, with stable gains set again, clears the banner and restarts the stream.
#[test]
fn a_divergence_shows_the_engine_banner_and_reset_recovers() {
    let mut h = harness_at_max_speed();
    h.get_by_role_and_label(Role::Slider, "Kp")
        .set_value_accesskit(20.0);
    h.step();
    step_until(&mut h, "the engine's error", |a| a.engine_error().is_some());
    h.step();
    let msg = h.state().engine_error().unwrap_or_default().to_string();
    assert!(msg.contains("linear model diverged"), "{msg}");
    let banner = format!("{:?}", h.get_by_label_contains("Engine stopped"));
    assert!(banner.contains("diverged"), "{banner}");

    let kp = seat_twin::params::Params::paper().controller.kp_v_per_m;
    h.get_by_role_and_label(Role::Slider, "Kp")
        .set_value_accesskit(kp);
    h.step();
    let reset = h.query_all_by_label("Reset").next();
    reset.expect("a Reset button").click();
    h.step();
    assert!(h.state().engine_error().is_none());
    assert!(h.query_by_label_contains("Engine stopped").is_none());
    step_until(&mut h, "the stream to resume", |a| {
        a.engine_view().running && a.traces().t_now() > 1.0
    });
    assert!(h.state().engine_error().is_none(), "stable gains stay up");
}
