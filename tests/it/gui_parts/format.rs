//! `seat_twin::gui::format`: unit tests kept out of the library (see `gui_parts`).

use seat_twin::gui::format::*;
use seat_twin::params::Params;

#[test]
fn refinements_are_said_only_when_set() {
    let mut p = Params::paper();
    p.plant.effects.compliance.enabled = true;
    p.plant.effects.compliance.effective_bulk_modulus_pa = 9e8;
    assert_eq!(active_effects(&p), ["compliance (β = 0.9000 GPa)"]);
    p.plant.effects.compliance.hose_bulk_modulus_pa = 6e8;
    assert_eq!(
        active_effects(&p),
        ["compliance (β = 0.9000 GPa, β_hose = 0.6000 GPa)"]
    );
}

#[test]
fn fitted_values_read_as_in_a_paper() {
    assert_eq!(fitted("tau_s", 0.017497, 7.96e-6), "τ = 17.50 ± 0.01 ms");
    assert_eq!(fitted("mass_kg", 11.66, 0.1), "m = 11.66 ± 0.10 kg");
    assert_eq!(
        fitted("effective_bulk_modulus_pa", 5.9483e8, f64::NAN),
        "β = 0.5948 GPa"
    );
    assert_eq!(fitted("cd", 0.15061, 2e-4), "Cd = 0.1506 ± 0.0002");
    assert_eq!(
        fitted("bias_v", -0.0123, 1e-9),
        "V_bias = −12.30 ± <0.01 mV"
    );
}

#[test]
fn long_numbers_in_messages_are_shortened() {
    assert_eq!(
        shorten_numbers(
            "linear model diverged at t = 80.871000 s: state u [m] = 1.000365001548847e0 (bound ±1e0); p1 2"
        ),
        "linear model diverged at t = 80.87 s: state u [m] = 1.000 (bound ±1); p1 2"
    );
    assert_eq!(
        shorten_numbers("max_step_s = 0.5, x2"),
        "max_step_s = 0.5, x2"
    );
    assert_eq!(compact(200.0), "200");
    assert_eq!(compact(-5.0), "−5");
    assert_eq!(compact(0.1506), "0.1506");
}
