//! `seat_twin::gui::plotkit`: unit tests kept out of the library (see `gui_parts`).

use egui_plot::GridInput;
use seat_twin::gui::plotkit::*;

#[test]
fn small_amplitudes_get_several_labelled_ticks() {
    // ±0.004 on a 110 px scope: several marks, each more than 20 px apart and labelled.
    let marks = y_marks(
        GridInput {
            bounds: (-0.0045, 0.0045),
            base_step_size: 1e-5,
        },
        110.0,
    );
    assert!(marks.len() >= 3, "{marks:?}");
    let px = marks[0].step_size / 0.009 * 110.0;
    assert!(px >= 16.0, "{px} px between ticks");
    let labels: Vec<String> = marks.iter().map(|m| y_tick(*m, &(0.0..=1.0))).collect();
    assert!(labels.contains(&"0.002".to_string()), "{labels:?}");
    assert!(labels.contains(&"−0.002".to_string()), "{labels:?}");
}

#[test]
fn wrapped_phase_stays_within_half_a_turn() {
    assert_eq!(wrap_deg(-1000.0), 80.0);
    assert_eq!(wrap_deg(-180.0), 180.0);
    assert_eq!(wrap_deg(190.0), -170.0);
    assert_eq!(wrap_deg(45.0), 45.0);
}

#[test]
fn nice_steps() {
    assert_eq!(nice_step(0.0013), 0.002);
    assert_eq!(nice_step(2.1), 2.5);
    assert_eq!(nice_step(3.0), 5.0);
    assert_eq!(nice_step(7.0), 10.0);
    assert_eq!(nice_step(20.0), 20.0);
}
