//! `seat_twin::gui::gain`: unit tests kept out of the library (see `gui_parts`).

use seat_twin::gui::gain::*;

#[test]
fn symlog_round_trips_both_signs_and_zero() {
    let sc = SymLog { resolution: 1.0 };
    for v in [-2000.0, -20.0, -0.3, 0.0, 0.5, 7.0, 200.0] {
        let back = sc.value(sc.position(v));
        assert!(
            (back - v).abs() <= 1e-12 * v.abs().max(1.0),
            "{v} -> {back}"
        );
    }
    // A decade of |K| well above r is one unit of position.
    let d = sc.position(-2000.0) - sc.position(-200.0);
    assert!((d + 1.0).abs() < 0.01, "{d}");
}

#[test]
fn significant_digits() {
    assert_eq!(round_significant(-23.4172, 3), -23.4);
    assert_eq!(round_significant(0.012345, 2), 0.012);
    assert_eq!(round_significant(1999.6, 3), 2000.0);
    assert_eq!(round_significant(0.0, 3), 0.0);
}
