//! Issue 22 ("the app, second round"): what a new user ran into, each as a test of the real
//! app driven headless — idle means idle, "last stable" means last committed, gain sliders
//! a person can steer, and messages that do not outlive what they were about.
#![cfg(feature = "gui")]

use super::gui::{harness, step_until};
use egui::accesskit::Role;
use egui_kittest::Harness;
use egui_kittest::kittest::{By, Queryable};
use seat_twin::gui::SeatTwinApp;
use std::time::Duration;

/// The repaint the app asked for in the last frame (`Duration::MAX`: none).
fn repaint_delay(h: &Harness<'static, SeatTwinApp>) -> Duration {
    h.output()
        .viewport_output
        .get(&egui::ViewportId::ROOT)
        .map_or(Duration::MAX, |v| v.repaint_delay)
}

fn kp(h: &Harness<'static, SeatTwinApp>) -> f64 {
    h.state().params().controller.kp_v_per_m
}

/// Types `v` into the Kp control (as Enter on the number would) and lets it settle.
fn type_kp(h: &mut Harness<'static, SeatTwinApp>, v: f64) {
    h.get_by_role_and_label(Role::Slider, "Kp")
        .set_value_accesskit(v);
    h.step();
    h.step();
}

/// Presses in the middle of the Kp rail and moves the pointer right by `steps` of `dx` px,
/// one frame each, with Shift held if `fine`; returns (Kp, unstable) after each frame. The
/// button stays down: call [`release`] after.
fn drag_kp(
    h: &mut Harness<'static, SeatTwinApp>,
    steps: usize,
    dx: f32,
    fine: bool,
) -> (egui::Pos2, Vec<(f64, bool)>) {
    let c = h.get_by_role_and_label(Role::Slider, "Kp").rect().center();
    if fine {
        h.event(egui::Event::ModifiersChanged(egui::Modifiers::SHIFT));
    }
    h.hover_at(c);
    h.step();
    h.drag_at(c);
    h.step();
    let mut seen = Vec::new();
    let mut pos = c;
    for _ in 0..steps {
        pos.x += dx;
        h.hover_at(pos);
        h.step();
        seen.push((kp(h), h.state().curves().unstable()));
    }
    (pos, seen)
}

fn release(h: &mut Harness<'static, SeatTwinApp>, at: egui::Pos2) {
    h.drop_at(at);
    h.event(egui::Event::ModifiersChanged(egui::Modifiers::NONE));
    h.step();
    h.step();
}

/// Item 3: paused, with an error notice on the toolbar (errors never expire), the app asks
/// for no repaint at all; an information notice books one repaint, when it expires. (Before:
/// any notice repainted every 100 ms, for ever.)
#[test]
fn paused_app_with_an_error_notice_asks_for_no_repaint() {
    let mut h = harness();
    h.step();
    step_until(&mut h, "the engine's first status", |a| {
        a.engine_params().is_some()
    });
    h.state_mut().toggle_running();
    step_until(&mut h, "the pause and the dwell points", |a| {
        !a.engine_view().running && a.dwell().is_current(a.params())
    });
    h.state_mut()
        .open_preset_file(std::path::Path::new("/no/such/preset.toml"));
    h.step();
    assert!(h.state().notice().is_some_and(|n| n.error));
    // egui may ask for a frame or two after a layout change; then nothing, for ever.
    let frames = h
        .try_run()
        .expect("the app settles: no repaint stream while paused");
    assert!(frames < 5, "{frames} frames to settle");
    assert_eq!(repaint_delay(&h), Duration::MAX, "paused: no repaint");

    let shipped = h.state().shipped_presets()[0].1.clone();
    h.state_mut().open_preset_file(&shipped);
    h.step();
    step_until(&mut h, "the dwell points of the preset", |a| {
        a.dwell().is_current(a.params()) && a.dwell().progress().is_none()
    });
    h.step();
    assert!(h.state().notice().is_some_and(|n| !n.error));
    let d = repaint_delay(&h);
    assert!(
        d > Duration::from_secs(5) && d <= Duration::from_secs(8),
        "one repaint when the notice expires, not a stream: {d:?}"
    );
}

/// Item 4: "Reset to last stable gains" restores the last *committed* gains. Kp = −20 is
/// typed, then a drag passes through other stable values into the unstable region and the
/// button is released there: the reset gives −20, not a value the drag only passed through.
#[test]
fn last_stable_gains_are_the_committed_ones_not_a_dragged_through_value() {
    let mut h = harness();
    h.step();
    type_kp(&mut h, -20.0);
    assert_eq!(kp(&h), -20.0);
    assert!(!h.state().curves().unstable());
    assert_eq!(
        h.state().last_stable_gains().map(|g| g.kp_v_per_m),
        Some(-20.0)
    );

    let (end, seen) = drag_kp(&mut h, 60, 10.0, false);
    assert!(
        seen.iter().any(|&(k, unstable)| !unstable && k != -20.0),
        "the drag passed through other stable gains: {seen:?}"
    );
    assert!(
        seen.last().is_some_and(|&(_, unstable)| unstable),
        "the drag ended unstable: {seen:?}"
    );
    release(&mut h, end);
    assert!(h.state().curves().unstable());
    assert_eq!(
        h.state().last_stable_gains().map(|g| g.kp_v_per_m),
        Some(-20.0),
        "last stable = last committed"
    );
    h.state_mut().reset_to_last_stable_gains();
    h.step();
    assert_eq!(kp(&h), -20.0);
    assert!(!h.state().curves().unstable());
}

/// Item 5: a gain a person can steer. From Kp = −20, a 40 px drag moves Kp by less than half
/// a decade (it reached −2000, two decades, before), and with Shift held by less than a
/// twentieth of one. Neither drag jumps to where the pointer was pressed.
#[test]
fn a_40_px_drag_moves_kp_less_than_half_a_decade_and_shift_a_twentieth() {
    let mut h = harness();
    h.step();
    for (fine, limit) in [(false, 0.5), (true, 0.05)] {
        type_kp(&mut h, -20.0);
        let (end, seen) = drag_kp(&mut h, 4, 10.0, fine);
        release(&mut h, end);
        let after = kp(&h);
        let decades = (after / -20.0).log10().abs();
        assert!(
            after < 0.0 && decades > 0.0 && decades < limit,
            "fine = {fine}: −20 → {after} ({decades:.2} decades; frames {seen:?})"
        );
    }
}

/// Item 8: a refused value's message is about the parameters it was typed into; loading a
/// preset clears it.
#[test]
fn loading_a_preset_clears_a_refused_value_message() {
    let mut h = harness();
    h.step();
    type_kp(&mut h, 5000.0);
    assert!(h.state().field_errors().contains_key("Kp"));
    assert!(h.query_by_label_contains("refused").is_some());
    let shipped = h.state().shipped_presets()[0].1.clone();
    h.state_mut().open_preset_file(&shipped);
    h.step();
    h.step();
    assert!(h.state().field_errors().is_empty());
    assert!(h.query_by_label_contains("refused").is_none());
}

fn campaign_dir() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/demo-campaign")
}

/// Item 1: the typed path of the measured-data window takes a pattern, a folder and several
/// files separated by `;`, and the status counts what was read and what the list holds.
/// (Before: one file at a time; a folder was "is a directory", `*.csv` "No such file", and
/// ten records listed read "1 record(s) loaded".)
#[test]
fn typed_patterns_folders_and_lists_load_every_record_and_count_right() {
    let mut h = harness();
    h.step();
    let dir = campaign_dir();
    h.state_mut()
        .measured_mut()
        .load_typed(&format!("{}/sine_0*.csv", dir.display()));
    step_until(&mut h, "the sine records below 10 Hz", |a| {
        !a.measured().busy() && !a.measured().records.is_empty()
    });
    assert_eq!(h.state().measured().records.len(), 4);
    assert_eq!(h.state().measured().last_info(), Some("4 records loaded"));

    let two = format!(
        "{}; {}",
        dir.join("bump.csv").display(),
        dir.join("ride.csv").display()
    );
    h.state_mut().measured_mut().load_typed(&two);
    step_until(&mut h, "bump and ride", |a| a.measured().records.len() == 6);
    assert_eq!(
        h.state().measured().last_info(),
        Some("2 records loaded (6 in the window)")
    );

    h.state_mut()
        .measured_mut()
        .load_typed(&dir.display().to_string());
    step_until(&mut h, "the whole folder", |a| {
        a.measured().records.len() == 10 && !a.measured().busy()
    });
    assert_eq!(h.state().measured().last_info(), Some("10 records loaded"));

    h.state_mut()
        .measured_mut()
        .load_typed(&format!("{}/nothing_*.csv", dir.display()));
    let e = h
        .state()
        .measured()
        .last_error()
        .unwrap_or_default()
        .to_string();
    assert!(
        e.contains("nothing_*.csv") && e.contains("no file matches"),
        "{e}"
    );
}

/// Item 1: the measured-data window opens below the toolbar and the typed-path prompt, so
/// neither is hidden behind it (before: it opened over them and "Load measured records…"
/// seemed to do nothing on a desktop without a file dialog).
#[test]
fn measured_window_opens_below_the_toolbar_and_the_path_prompt() {
    let mut h = harness();
    h.step();
    h.state_mut()
        .prompt_path(seat_twin::gui::files::Purpose::LoadMeasured, "");
    h.state_mut().measured_mut().open = true;
    h.run_steps(3);
    let toolbar = h.get_by_label("Reset").rect();
    let prompt = h.get_by_label("OK").rect();
    let title = h.get_by_label("Measured data").rect();
    assert!(
        title.top() > toolbar.bottom() && title.top() > prompt.bottom(),
        "window title at {title:?}, toolbar button {toolbar:?}, prompt button {prompt:?}"
    );
}

/// Item 10: typed save paths are full paths in the folder last used (at first the documents
/// folder), not bare names that land in the working directory.
#[test]
fn typed_save_paths_are_full_paths_in_the_last_used_folder() {
    use seat_twin::gui::files::Purpose;
    let mut h = harness();
    h.step();
    let first = h.state().suggested_path(Purpose::ExportCsv);
    assert!(
        std::path::Path::new(&first).is_absolute() && first.ends_with("traces.csv"),
        "{first}"
    );
    let dir = tempfile::tempdir().unwrap();
    let preset = dir.path().join("mine.toml");
    h.state_mut().prompt_path(Purpose::SavePreset, "");
    h.step();
    let ctx = h.ctx.clone();
    h.state_mut()
        .use_paths(Purpose::SavePreset, vec![preset.clone()], &ctx);
    h.step();
    assert!(preset.is_file());
    assert_eq!(
        std::path::PathBuf::from(h.state().suggested_path(Purpose::ExportPng)),
        dir.path().join("plots.png")
    );
    let notice = h
        .state()
        .notice()
        .map(|n| n.text.clone())
        .unwrap_or_default();
    assert!(
        notice.contains(&preset.display().to_string()),
        "the full path is shown: {notice}"
    );
}

/// Item 1: the wildcard of typed paths.
#[test]
fn wildcards_match_whole_file_names() {
    use seat_twin::gui::files::wildcard_match as m;
    assert!(m("*.csv", "ride.csv"));
    assert!(m("sine_0?hz*", "sine_05hz_0.72v.csv"));
    assert!(!m("sine_0?hz*", "sine_10hz_1.10v.csv"));
    assert!(!m("*.csv", "ride.csv.bak"));
    assert!(m("*", ""));
    assert!(m("a*b*c", "aXXbYYc") && !m("a*b*c", "aXXbYY"));
}

/// Item 2: a window remembered from a larger screen is cut to fit a smaller one, one from a
/// much smaller screen grows, one that fits is left alone.
#[test]
fn a_remembered_window_larger_than_the_screen_is_fitted() {
    use seat_twin::gui::app::fitted_window;
    let big = egui::vec2(1600.0, 1000.0);
    let fitted = fitted_window(big, egui::vec2(1280.0, 720.0)).expect("too large");
    assert!(fitted.x <= 1280.0 * 0.9 + 0.1 && fitted.y <= 720.0 * 0.9 + 0.1);
    assert_eq!(fitted_window(big, egui::vec2(2560.0, 1440.0)), None);
    // A 1280×720 window remembered from a laptop, reopened on a 2560×1440 screen, grows.
    assert_eq!(
        fitted_window(egui::vec2(1280.0, 720.0), egui::vec2(2560.0, 1440.0)),
        Some(egui::vec2(1920.0, 1080.0))
    );
}

/// Item 6: Pareto points never read the same a_w (one would look dominated), and the
/// controller is named by symbols and display units, not preset keys.
#[test]
fn pareto_digits_separate_points_and_gains_have_names_and_units() {
    use seat_twin::gui::tune::separating_decimals;
    assert_eq!(separating_decimals([0.0951, 0.0949, 0.12].into_iter()), 4);
    assert_eq!(separating_decimals([0.095, 0.12].into_iter()), 3);
    let mut c = seat_twin::params::Params::paper().controller;
    c.kp_v_per_m = -37.47;
    let t = seat_twin::gui::format::controller_text(&c);
    assert!(t.contains("Kp = −37.47 V/m"), "{t}");
    assert!(!t.contains("kp_v_per_m"), "{t}");
}

/// Item 9: the CSV header carries every parameter that made the traces (τ and the plant as
/// well as the gains), and the scopes figure keeps the view's line styles (the linear model
/// dashed, the passive seat dotted → dashed in the figure, the twin solid) and names τ.
#[test]
fn exports_carry_every_parameter_and_the_line_styles() {
    use seat_twin::plot::SeriesStyle;
    let mut h = harness();
    h.step();
    let table = h.state().traces_table();
    let keys: Vec<&str> = table.comments.iter().map(|(k, _)| k.as_str()).collect();
    for k in [
        "valve.tau_s",
        "valve.cd",
        "body.mass_kg",
        "supply.supply_pressure_pa",
    ] {
        assert!(keys.contains(&k), "{k} missing from {keys:?}");
    }
    let tau = &table.comments[keys.iter().position(|k| *k == "valve.tau_s").unwrap()].1;
    assert_eq!(tau, "0.0175 s");
    let figs = h.state().plot_figures();
    let scopes = &figs.iter().find(|(n, _)| *n == "scopes").unwrap().1;
    assert!(scopes.title.contains("τ = 17.5 ms"), "{}", scopes.title);
    let dashed = |label: &str| {
        scopes.panels[0]
            .series
            .iter()
            .find(|s| s.label == label)
            .map(|s| matches!(s.style, SeriesStyle::Line { dashed: true, .. }))
    };
    assert_eq!(dashed("linear"), Some(true));
    assert_eq!(dashed("passive"), Some(true));
    assert_eq!(dashed("twin"), Some(false));
}

/// Item 6: a tune result belongs to the structure it tuned. After switching the structure
/// the panel says so and offers no Apply (before: the old front stayed under the new
/// structure's heading, and Apply silently switched the structure back).
#[test]
fn a_tune_result_for_another_structure_is_not_offered() {
    let mut h = harness();
    h.step();
    let mut opts = seat_twin::gui::tune::interactive_options(h.state().params());
    opts.max_evaluations = 10;
    opts.duration_s = 5.0;
    opts.tune_seeds = vec![1];
    opts.heldout_seeds = vec![2];
    h.state_mut().start_tune(opts);
    step_until(&mut h, "the tune result", |a| {
        a.tune_panel().result().is_some() || a.tune_panel().message().is_some()
    });
    let front = h
        .state()
        .tune_panel()
        .result()
        .map_or(0, |r| r.pareto.len());
    assert!(
        front > 0,
        "a front to offer: {:?}",
        h.state().tune_panel().message()
    );
    h.get_by_label("Tune").click();
    h.run_steps(2);
    assert!(
        h.query_by_label("Apply").is_some(),
        "the paper front is offered"
    );

    h.get(By::new().role(Role::ComboBox).value("paper")).click();
    h.run_steps(2);
    h.get_by_label("skyhook").click();
    h.run_steps(2);
    assert_eq!(
        h.state().params().controller.kind,
        seat_twin::params::ControllerKind::Skyhook
    );
    assert!(
        h.query_by_label("Apply").is_none(),
        "no Apply of paper gains"
    );
    assert!(h.query_by_label_contains("tuned the paper gains").is_some());
}

/// Item 2: in a small window the scopes are not squeezed: the centre stacks them above the
/// frequency plots at a readable height and scrolls (before: six scopes shared 700 px with
/// the window's furniture, and the last one lost its time axis).
#[test]
fn a_small_window_stacks_and_scrolls_instead_of_squeezing() {
    let app = SeatTwinApp::new(seat_twin::gui::settings::Settings::default(), || {});
    let mut h = egui_kittest::Harness::builder()
        .with_size([1100.0, 700.0])
        .build_ui_state(|ui, app: &mut SeatTwinApp| app.ui(ui), app);
    h.run_steps(3);
    let frames = h.state().scope_frames().to_vec();
    assert_eq!(frames.len(), 6);
    for f in &frames {
        assert!(f.height() >= 60.0, "a squeezed scope: {f:?}");
    }
    let last = frames.last().unwrap();
    assert!(
        last.bottom() > 700.0,
        "the scopes run below the window (the centre scrolls): {last:?}"
    );
}

/// Issue 25, item 4: File ▸ Export FMU… and Export controller code… write what the CLI's
/// `export` commands write, from the parameters on screen, on the writer's background job.
#[test]
fn the_file_menu_exports_the_fmu_and_the_controller_code() {
    use seat_twin::export::fmu::ControllerPlacement;
    use seat_twin::gui::files::Purpose;
    let mut h = harness();
    h.step();
    type_kp(&mut h, -7.5);
    let dir = tempfile::tempdir().unwrap();
    let ctx = h.ctx.clone();

    // The FMU packs the shared library built beside the executable: `cargo build` makes it,
    // `cargo test` alone does not. Without it the app must say so (and write nothing).
    let library = seat_twin::export::fmu::library_beside_executable();
    let fmu = dir.path().join("seat.fmu");
    h.state_mut().use_paths(
        Purpose::ExportFmu(ControllerPlacement::Internal),
        vec![fmu.clone()],
        &ctx,
    );
    if library.is_file() {
        step_until(&mut h, "the FMU written", |_| fmu.is_file());
        // A ZIP with the model description and the shared library; the on-screen Kp is its
        // start value.
        let bytes = std::fs::read(&fmu).unwrap();
        assert_eq!(&bytes[..2], b"PK");
        let text = String::from_utf8_lossy(&bytes);
        assert!(text.contains("binaries/linux64/seat_twin.so"));
        let md_start = text
            .find("<fmiModelDescription")
            .expect("modelDescription.xml");
        let md = &text[md_start..];
        let kp = md
            .find("name=\"controller.kp_v_per_m\"")
            .expect("Kp is a parameter");
        let start = md[kp..].find("start=\"").unwrap() + kp + 7;
        let value: f64 = md[start..start + md[start..].find('"').unwrap()]
            .parse()
            .unwrap();
        assert_eq!(value, -7.5, "the FMU carries the gain on screen");
    } else {
        step_until(&mut h, "the missing library named", |a| {
            a.notice().is_some_and(|n| {
                n.text.contains("FMU not written") && n.text.contains("libseat_twin.so")
            })
        });
        assert!(!fmu.exists(), "nothing written without the library");
    }

    let code = dir.path().join("ctl");
    h.state_mut()
        .use_paths(Purpose::ExportController, vec![code.clone()], &ctx);
    step_until(&mut h, "the controller code written", |a| {
        code.join("seat_controller.c").is_file()
            && a.notice()
                .is_some_and(|n| n.text.contains("controller code at"))
    });

    // The controller code: header, source and coefficients, with the gain on screen.
    let header = std::fs::read_to_string(code.join("seat_controller.h")).unwrap();
    let source = std::fs::read_to_string(code.join("seat_controller.c")).unwrap();
    assert!(header.contains("seat_ctrl_step"));
    assert!(
        header.contains("-7.5") || source.contains("-7.5"),
        "the comment header names the gain on screen"
    );
    assert!(code.join("seat_controller.json").is_file());
}
