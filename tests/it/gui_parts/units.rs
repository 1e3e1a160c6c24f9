//! `seat_twin::gui::units`: unit tests kept out of the library (see `gui_parts`).

use seat_twin::gui::units::*;

#[test]
fn conversions_at_known_points() {
    assert_eq!(0.035 * MM_PER_M, 35.0);
    assert!((100e5 * BAR_PER_PA - 100.0).abs() < 1e-12);
    assert!((1e-3 / 60.0 * LPM_PER_M3_S - 1.0).abs() < 1e-12);
    assert!((db(10.0) - 20.0).abs() < 1e-12);
    assert!((deg(std::f64::consts::PI) - 180.0).abs() < 1e-12);
}
