//! `seat_twin::gui::schematic`: unit tests kept out of the library (see `gui_parts`).

use egui::Color32;
use seat_twin::gui::schematic::*;
use seat_twin::gui::style::rig;
use seat_twin::params::Params;

fn distance(a: Color32, b: Color32) -> i32 {
    (i32::from(a.r()) - i32::from(b.r())).abs()
        + (i32::from(a.g()) - i32::from(b.g())).abs()
        + (i32::from(a.b()) - i32::from(b.b())).abs()
}

/// ±1 bar around 55 bar (a gentle ride) spans the whole colour scale once the range seen
/// sets it; on the fixed return…supply scale the two were nearly the same white.
#[test]
fn a_one_bar_swing_is_visible() {
    let p = Params::paper();
    let range = color_range(Some((54e5, 56e5)), &p);
    let (lo, hi) = (pressure_color(54e5, range), pressure_color(56e5, range));
    assert!(distance(lo, hi) > 250, "{lo:?} vs {hi:?}");
    let fixed = color_range(None, &p);
    let (a, b) = (pressure_color(54e5, fixed), pressure_color(56e5, fixed));
    assert!(distance(a, b) < 60, "the old scale: {a:?} vs {b:?}");
}

/// A still rig (a few mbar of noise) does not sweep the whole scale.
#[test]
fn noise_stays_near_white() {
    let p = Params::paper();
    let range = color_range(Some((55e5 - 50.0, 55e5 + 50.0)), &p);
    let mid = rig::PRESSURE_MID;
    assert!(distance(pressure_color(55e5 + 50.0, range), mid) < 30);
}
