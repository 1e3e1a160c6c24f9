//! `seat_twin::gui::lessons`: unit tests kept out of the library (see `gui_parts`).

use seat_twin::gui::controls::ExcitationEditor;
use seat_twin::gui::lessons::*;
use seat_twin::params::Params;

fn view<'a>(p: &'a Params, e: &'a ExcitationEditor) -> LessonView<'a> {
    LessonView {
        params: p,
        excitation: e,
        unstable: false,
        counted_s: 10.0,
        seat_twin_percent: 40.0,
        seat_passive_percent: 110.0,
        aw_platform: 0.5,
    }
}

#[test]
fn every_lesson_starts_from_a_compiled_in_preset() {
    for l in &LESSONS {
        assert!(
            seat_twin::gui::share::shipped_preset(l.preset).is_ok(),
            "{}",
            l.title
        );
    }
}

#[test]
fn the_resonance_step_needs_the_sine_at_the_passive_natural_frequency() {
    let mut panel = LessonsPanel::default();
    let mut p = Params::paper();
    let mut e = ExcitationEditor::default();
    LessonsPanel::set_up(0, &mut p, &mut e);
    panel.started(0, p);
    // At the step's own 2 Hz start it is not done…
    assert!(!panel.check(&view(&p, &e)));
    // …at the resonance it is.
    e.sine_freq_hz = passive_natural_hz(&p);
    assert!(panel.check(&view(&p, &e)));
    assert!(panel.is_done(0));
}

#[test]
fn the_feed_forward_step_needs_ki_off_then_back_on() {
    let mut panel = LessonsPanel::default();
    let mut p = Params::paper();
    let mut e = ExcitationEditor::default();
    LessonsPanel::set_up(3, &mut p, &mut e);
    panel.started(3, p);
    assert!(!panel.check(&view(&p, &e)), "untouched: not done");
    let ki = p.controller.ki_v_s_per_m;
    p.controller.ki_v_s_per_m = 0.0;
    assert!(!panel.check(&view(&p, &e)), "off: not done yet");
    p.controller.ki_v_s_per_m = ki;
    assert!(panel.check(&view(&p, &e)));
}

#[test]
fn the_delay_step_is_done_when_the_loop_goes_unstable() {
    let mut panel = LessonsPanel::default();
    let p = Params::paper();
    let e = ExcitationEditor::default();
    panel.started(2, p);
    assert!(!panel.check(&view(&p, &e)));
    let mut v = view(&p, &e);
    v.unstable = true;
    assert!(panel.check(&v));
}
