//! `seat_twin::gui::frequency::curves`: unit tests kept out of the library (see `gui_parts`).

use seat_twin::analysis::frequency_response as fr;
use seat_twin::analysis::stability::Stability;
use seat_twin::control::ControlLaw;
use seat_twin::gui::frequency::PlantCache;
use seat_twin::params::Params;

/// The cached plant responses reproduce the engine's linearised-twin responses for any
/// gains and delay (the fast path used while dragging Kp, Ki, τ).
#[test]
fn cached_plant_matches_the_linearised_twin() {
    let mut p = Params::paper();
    p.controller.kp_v_per_m = -37.0;
    p.controller.ki_v_s_per_m = -3.0;
    p.plant.valve.tau_s = 0.021;
    let freqs = fr::log_space(0.2, 50.0, 9);
    let cache = PlantCache::new(&p, &freqs);
    let lin = fr::linearise_twin(&p);
    for (pt, &f) in cache.points.iter().zip(&freqs) {
        let (a, b) = (
            pt.transmissibility(&ControlLaw::new(&p), 0.021),
            lin.transmissibility(&ControlLaw::new(&p), f),
        );
        assert!(
            (a - b).norm() <= 1e-6 * b.norm().max(1e-3),
            "T at {f} Hz: {a} vs {b}"
        );
        let (a, b) = (pt.bode(0.021), lin.bode(f));
        assert!(
            (a - b).norm() <= 1e-6 * b.norm(),
            "bode at {f} Hz: {a} vs {b}"
        );
    }
    let law = ControlLaw::new(&p);
    let (a, b) = (
        cache.stability(&law, 0.021),
        Stability::of(&lin, &law, 0.021),
    );
    assert_eq!(a.stable(), b.stable());
    assert_eq!(
        a.margins.gain_crossovers.len(),
        b.margins.gain_crossovers.len()
    );
    assert!(
        (a.margins.delay_margin_s() - b.margins.delay_margin_s()).abs() < 1e-9,
        "{a:?} {b:?}"
    );
}
