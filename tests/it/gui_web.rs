//! What the web page claims, checked natively: the live engine's seeded random ride is
//! `seat-twin simulate`'s run sample for sample (all three models), a parameter change keeps
//! the linear models' state, and in the real app (egui_kittest) a setup link restores a
//! setup, a bad one keeps the defaults with a message, a lesson step completes through the
//! sliders' path, and presentation mode enlarges the UI. The browser itself is tested by
//! `.ci/checks/web.sh`.
#![cfg(feature = "gui")]

use super::gui::{harness, step_until};
use seat_twin::engine::{self, Command, EngineHandle, Event, Excitation, Speed};
use seat_twin::experiments::RunSpec;
use seat_twin::model::ModelKind;
use seat_twin::params::Params;
use seat_twin::scenario::{PlatformMotion, RandomRide};
use seat_twin::simulation::{Drive, Sample};
use std::time::{Duration, Instant};

/// The ride `simulate --scenario random --seed 3 --duration 4` builds.
fn ride() -> RandomRide {
    RandomRide {
        seed: 3,
        duration_s: 4.0,
        fade_in_s: 1.0,
        ..Default::default()
    }
}

/// `simulate --model kind` on [`ride`] at the engine's stream rate.
fn simulate(kind: ModelKind) -> Vec<Sample> {
    let p = Params::paper();
    RunSpec {
        params: &p,
        kind,
        drive: Drive::closed_loop(&p),
        platform: PlatformMotion::Sampled(ride().generate()),
        duration_s: 4.0,
        rate_hz: engine::STREAM_RATE_HZ,
    }
    .run()
    .expect("the paper's loop is stable on the ride")
    .samples
}

/// The seeded ride in the engine at full speed, paused at its end; `mid` is sent once the
/// twin passed 2 s. Returns the three models' samples from the ride's start.
fn engine_ride(mid: Option<Command>) -> [Vec<Sample>; 3] {
    let h: EngineHandle = engine::spawn(Params::paper(), || {});
    h.send(Command::SetRepeat(false));
    h.send(Command::SetSpeed(Speed::Max));
    h.send(Command::SetExcitation(Box::new(Excitation::Random(ride()))));
    let mut mid = mid;
    let (mut twin, mut linear, mut passive) = (Vec::new(), Vec::new(), Vec::new());
    let t0 = Instant::now();
    loop {
        assert!(
            t0.elapsed() < Duration::from_secs(60),
            "the ride did not end"
        );
        let Ok(e) = h.events.recv_timeout(Duration::from_millis(50)) else {
            continue;
        };
        match e {
            Event::Samples(b) => {
                // The engine may have stepped its default ride before the commands arrived:
                // the seeded ride is what follows its last start from rest.
                if b.twin.first().is_some_and(|s| s.t == 0.0) {
                    twin.clear();
                    linear.clear();
                    passive.clear();
                }
                twin.extend(b.twin);
                linear.extend(b.linear);
                passive.extend(b.passive);
                if twin.last().is_some_and(|s: &Sample| s.t > 2.0)
                    && let Some(c) = mid.take()
                {
                    h.send(c);
                }
            }
            Event::Status { t, running, .. } if !running && t >= 4.0 - 1e-9 => break,
            Event::Error(e) => panic!("engine error: {e}"),
            _ => {}
        }
    }
    [twin, linear, passive]
}

#[test]
fn the_engines_seeded_ride_is_simulates_run_sample_for_sample() {
    let [twin, linear, passive] = engine_ride(None);
    for (kind, live) in [
        (ModelKind::Twin, &twin),
        (ModelKind::Linear, &linear),
        (ModelKind::Passive, &passive),
    ] {
        let cli = simulate(kind);
        assert_eq!(live.len(), cli.len(), "{kind:?}: sample count");
        for (a, b) in live.iter().zip(&cli) {
            // The same steppers on the same grid: bit for bit, not merely close (the
            // linear models used to run RK4 in the engine and the exact hold in the CLI).
            assert_eq!(
                (a.t, a.ydd.to_bits(), a.u.to_bits()),
                (b.t, b.ydd.to_bits(), b.u.to_bits()),
                "{kind:?} at t = {}",
                a.t
            );
        }
    }
}

#[test]
fn a_parameter_change_keeps_the_linear_models_state() {
    // The same parameters sent again at t ≈ 2 s: the linear models leave the exact stepper
    // for RK4 there, from the state they had, so the run goes on as it was (to RK4's
    // accuracy), with no restart from rest.
    let [_, linear, passive] = engine_ride(Some(Command::SetParams(Box::new(Params::paper()))));
    for (name, live, cli) in [
        ("linear", linear, simulate(ModelKind::Linear)),
        ("passive", passive, simulate(ModelKind::Passive)),
    ] {
        assert_eq!(live.len(), cli.len(), "{name}: sample count");
        let peak = cli.iter().map(|s| s.ydd.abs()).fold(0.0, f64::max);
        let worst = live
            .iter()
            .zip(&cli)
            .map(|(a, b)| (a.ydd - b.ydd).abs())
            .fold(0.0, f64::max);
        assert!(
            worst < 1e-3 * peak,
            "{name}: |Δÿ| up to {worst:e} m/s² against a peak of {peak} m/s²"
        );
    }
}

#[test]
fn a_setup_link_restores_the_setup_and_a_bad_one_keeps_the_defaults() {
    let mut h = harness();
    h.step();
    h.state_mut()
        .apply_link("1;preset=tuned-predictive;controller.kp_v_per_m=-33.25;exc=sine,0.5,6")
        .expect("a good link");
    h.step();
    let app = h.state();
    assert_eq!(app.preset().name, "tuned-predictive");
    assert_eq!(app.params().controller.kp_v_per_m, -33.25);
    assert!(app.is_modified(), "Kp differs from the preset");
    let link = app.link();
    assert!(link.contains("exc=sine,0.5,6"), "{link}");
    step_until(&mut h, "the engine runs the link's gain", |a| {
        a.engine_params()
            .is_some_and(|p| p.controller.kp_v_per_m == -33.25)
    });
    // A bad link: an error naming the field; nothing changes.
    let before = *h.state().params();
    let err = h
        .state_mut()
        .apply_link("1;preset=paper;valve.cd=7")
        .unwrap_err();
    assert!(err.contains("valve.cd"), "{err}");
    h.step();
    assert_eq!(*h.state().params(), before);
    let notice = h.state().notice().expect("the bad link is reported");
    assert!(
        notice.error && notice.text.contains("valve.cd"),
        "{}",
        notice.text
    );
}

#[test]
fn lesson_three_completes_when_the_loop_goes_unstable() {
    let mut h = harness();
    h.step();
    h.state_mut().start_lesson(2);
    h.step();
    let app = h.state();
    assert_eq!(app.preset().name, "paper");
    assert!(!app.state_json().contains("\"lesson_done\":true"));
    // Through the sliders' own path: a value outside the slider's span is refused.
    assert!(h.state_mut().set_slider("Kp", 5000.0).is_err());
    h.state_mut()
        .set_slider("Kp", -2000.0)
        .expect("in the span");
    h.step();
    h.step();
    let state: serde_json::Value = serde_json::from_str(&h.state().state_json()).unwrap();
    assert_eq!(state["stable"], false, "{state}");
    assert_eq!(state["lesson"], 3, "{state}");
    assert_eq!(state["lesson_done"], true, "{state}");
}

#[test]
fn every_lesson_step_draws_in_presentation_mode() {
    // Every glyph of the texts and equations is in the app's fonts (egui refuses to draw a
    // missing one under kittest), and each step sets its preset up.
    let mut h = harness();
    h.step();
    h.state_mut().set_presentation(true);
    for n in 0..seat_twin::gui::lessons::LESSONS.len() {
        h.state_mut().start_lesson(n);
        h.step();
        h.step();
        let state: serde_json::Value = serde_json::from_str(&h.state().state_json()).unwrap();
        assert_eq!(state["lesson"], n + 1);
        assert_eq!(
            state["preset"],
            seat_twin::gui::lessons::LESSONS[n].preset,
            "{state}"
        );
    }
}

#[test]
fn presentation_mode_enlarges_the_ui_and_gives_it_back() {
    let mut h = harness();
    h.step();
    let before = h.ctx.zoom_factor();
    h.state_mut().set_presentation(true);
    h.step();
    assert_eq!(h.ctx.zoom_factor(), seat_twin::gui::app::PRESENTATION_SCALE);
    assert!(h.state().link().contains("present=1"));
    h.state_mut().set_presentation(false);
    h.step();
    assert_eq!(h.ctx.zoom_factor(), before);
}
