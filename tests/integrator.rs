//! The integrator on the twin itself: RK4's 4th order (halving the step divides the error by
//! about 16) on a smooth open-loop valve test, and the closed-loop ride's accuracy against a
//! 10× finer step at the preset's step (the figure `seat-twin bench` reports).

use seat_twin::bench::{accuracy, bench_ride};
use seat_twin::model::twin::Twin;
use seat_twin::params::Params;
use seat_twin::scenario::{CommandSignal, PlatformMotion};
use seat_twin::simulation::{Drive, Simulation};

/// Final (u [m], p1 [Pa], q1 [m³/s]) of a 0.25 s open-loop valve sine at step `h`.
fn final_state(h: f64) -> (f64, f64, f64) {
    let params = Params::paper();
    let drive = Drive::OpenLoop(CommandSignal::Sine {
        amplitude_v: 2.1,
        freq_hz: 5.0,
    });
    let mut sim = Simulation::new(Twin::new(params), h, drive, PlatformMotion::Still);
    sim.run_until(0.25, u64::MAX, |_| {})
        .expect("no divergence");
    let s = sim.sample();
    assert!((s.t - 0.25).abs() < 1e-12);
    (s.u, s.p1, s.q1)
}

#[test]
fn rk4_is_fourth_order_on_the_twin() {
    let reference = final_state(1e-4 / 64.0);
    let err = |h: f64| {
        let (u, p1, q1) = final_state(h);
        // Relative to the scale of each channel, so no channel dominates by its unit.
        ((u - reference.0) / 1e-3)
            .abs()
            .max(((p1 - reference.1) / 1e5).abs())
            .max(((q1 - reference.2) / 1e-5).abs())
    };
    // At 0.1 ms the hose modes (5.8e3 rad/s, h·ω ≈ 0.6) are still pre-asymptotic (measured
    // ratios 22 and 27 for 0.2→0.1→0.05 ms); the asymptotic order shows from 0.05 ms down.
    let e_preset = err(1e-4);
    let (e1, e2) = (err(5e-5), err(2.5e-5));
    assert!(e_preset > e1, "error falls with the step");
    let ratio = e1 / e2;
    assert!(
        (12.0..=20.0).contains(&ratio),
        "halving the step divided the error by {ratio:.1} (errors {e1:.3e}, {e2:.3e}); RK4 gives ≈16"
    );
}

#[test]
fn preset_step_meets_the_accuracy_requirement_on_the_ride() {
    let params = Params::paper();
    let ride = bench_ride(5.0);
    let a = accuracy(&params, &ride, 5.0, params.numerics.max_step_s).expect("no divergence");
    // Issue 2: body-acceleration error ≤ 1e-4 m/s² against a 10× finer step.
    assert!(a.max_ydd_error <= 1e-4, "{a:?}");
    assert!(a.rms_ydd_error < a.max_ydd_error);
}
