//! The paper's section 5–6 figures within statistically honest bands: a 60 s realisation of
//! band-limited noise has a few % spread, so each figure is checked as the mean of several
//! seeds against the paper's value with a stated tolerance, never as a single point.

use seat_twin::analysis::metrics::rms;
use seat_twin::experiments;
use seat_twin::model::ModelKind;
use seat_twin::params::Params;
use seat_twin::scenario::{PlatformMotion, RandomRide};
use seat_twin::simulation::Drive;

const SEEDS: [u64; 5] = [1, 2, 3, 4, 5];

/// Mean over the seeds of (RMS ẍ, RMS ÿ) after the 2 s fade-in, for `kind`.
fn ride_rms(kind: ModelKind) -> (f64, f64) {
    let params = Params::paper();
    let mut sx = 0.0;
    let mut sy = 0.0;
    for seed in SEEDS {
        let ride = RandomRide {
            seed,
            ..Default::default()
        };
        let trace = experiments::run(
            &params,
            kind,
            Drive::closed_loop(&params),
            PlatformMotion::Sampled(ride.generate()),
            60.0,
            500.0,
        )
        .expect("the paper's ride does not diverge");
        let settled: Vec<_> = trace.samples.iter().filter(|s| s.t >= 2.0).collect();
        sx += rms(&settled.iter().map(|s| s.xdd).collect::<Vec<_>>());
        sy += rms(&settled.iter().map(|s| s.ydd).collect::<Vec<_>>());
    }
    let n = SEEDS.len() as f64;
    (sx / n, sy / n)
}

fn within(value: f64, paper: f64, tol: f64) -> bool {
    (value / paper - 1.0).abs() <= tol
}

#[test]
fn random_ride_rms_values_match_section_6() {
    let (x_lin, y_lin) = ride_rms(ModelKind::Linear);
    let (_, y_twin) = ride_rms(ModelKind::Twin);
    let (x_pas, y_pas) = ride_rms(ModelKind::Passive);
    // The same platform record drives every model.
    assert_eq!(x_lin, x_pas);
    // S0 = 0.05 (m/s²)²/Hz over 0.5–5 Hz gives √(0.05·4.5) = 0.474 m/s²; the paper reads 0.48.
    assert!(within(x_lin, 0.48, 0.06), "platform {x_lin}");
    // Passive ζ = 0.3: paper 0.67 m/s².
    assert!(within(y_pas, 0.67, 0.08), "passive {y_pas}");
    // Equivalent model G(s): paper 0.15 m/s².
    assert!(within(y_lin, 0.15, 0.10), "linear {y_lin}");
    // Multi-physics twin: paper 0.16 m/s². This twin is up to ~20 % higher on some seeds
    // (an occasional end-stop touch, which the paper's figure does not show): band 30 %.
    assert!(within(y_twin, 0.16, 0.30), "twin {y_twin}");
    // And the ranking the paper draws: active ≪ passive, twin ≥ linear model.
    assert!(y_twin < 0.4 * y_pas && y_lin < 0.4 * y_pas);
    assert!(y_twin >= y_lin * 0.98);
}

#[test]
fn cycloid_body_acceleration_is_far_below_the_passive_seat() {
    let params = Params::paper();
    let bump = Default::default();
    let peak = |kind| {
        experiments::cycloid(&params, kind, &bump, 3.0, 1000.0)
            .unwrap()
            .samples
            .iter()
            .map(|s| s.ydd.abs())
            .fold(0.0, f64::max)
    };
    // Platform peak of a 30 mm / 0.5 s cycloid: 2π·h/T² = 0.754 m/s².
    let (twin, linear, passive) = (
        peak(ModelKind::Twin),
        peak(ModelKind::Linear),
        peak(ModelKind::Passive),
    );
    assert!(
        passive > 0.754,
        "the passive seat amplifies the bump: {passive}"
    );
    assert!(
        twin < 0.4 * 0.754 && linear < 0.4 * 0.754,
        "{twin} {linear}"
    );
}
