//! The stability verdict against independent checks (issue 19): the nonlinear twin itself at
//! rest, the delay margin against the eigenvalues, and crossings a fixed grid misses.

use seat_twin::analysis::frequency_response as fr;
use seat_twin::analysis::settle::settle_after_bump;
use seat_twin::analysis::stability::{
    ClosedLoopModes, LoopPlant, MarginGrid, Stability, linear_stability, twin_stability,
};
use seat_twin::control::ControlLaw;
use seat_twin::experiments;
use seat_twin::model::ModelKind;
use seat_twin::params::Params;
use seat_twin::preset::resolve;
use seat_twin::scenario::Cycloid;
use seat_twin::tune;

/// The spread's corner where the oil column is least damped: Cd +10 %, τ + 3 ms, mass −20 %.
fn worst_corner() -> Params {
    let mut p = Params::paper();
    p.plant.valve.cd *= 1.1;
    p.plant.valve.tau_s += 0.003;
    p.plant.body.mass_kg *= 0.8;
    p
}

/// The verdict agrees with the nonlinear twin on both sides of the limit (the twin is a
/// different program from the eigenvalue solve: the exponential integrator on the nonlinear
/// equations). For position gains from −2 to −20 V/m at the worst corner (the limit is near
/// −4 V/m there): stable by the eigenvalues is settled after a bump on the twin, unstable
/// rings at the mode's frequency; and where the growing mode stays small, its growth rate on
/// the twin is the rightmost eigenvalue's real part.
#[test]
fn verdict_matches_the_twins_own_growth_on_both_sides_of_the_limit() {
    let base = worst_corner();
    let plant = LoopPlant::new(&fr::linearise_twin(&base));
    let mut seen = (false, false);
    for kp in [-2.0, -3.0, -8.0, -12.0, -20.0] {
        let mut p = base;
        p.controller.kp_v_per_m = kp;
        let m = ClosedLoopModes::of(&plant, &ControlLaw::new(&p), p.plant.valve.tau_s).unwrap();
        let s = settle_after_bump(&p).unwrap();
        if m.stable() {
            seen.0 = true;
        } else {
            seen.1 = true;
        }
        assert_eq!(
            m.stable(),
            s.settled(),
            "Kp {kp}: eigenvalues {m:?}, twin {s:?}"
        );
        if !m.stable() {
            // Growing: the twin rings at the unstable mode's frequency (a limit cycle once
            // the valve saturates the growth).
            assert!(
                (s.freq_hz - m.freq_hz).abs() < 0.05 * m.freq_hz,
                "Kp {kp}: {m:?} vs {s:?}"
            );
        }
    }
    // The growth rate itself, where the mode stays small for the whole run (Kp −8 at this
    // corner: ≈ 0.16 1/s on the eigenvalues): the twin's RMS of ÿ from 15 s to 20 s after
    // the start rises at the same rate.
    let mut p = base;
    p.controller.kp_v_per_m = -8.0;
    let m = ClosedLoopModes::of(&plant, &ControlLaw::new(&p), p.plant.valve.tau_s).unwrap();
    let trace =
        experiments::cycloid(&p, ModelKind::Twin, &Cycloid::default(), 20.0, 1000.0).unwrap();
    let ydd = trace.channel(|s| s.ydd);
    let rms = |x: &[f64]| (x.iter().map(|v| v * v).sum::<f64>() / x.len() as f64).sqrt();
    let per_s: Vec<f64> = ydd.chunks(1000).map(rms).collect();
    let simulated = (per_s[19] / per_s[14]).ln() / 5.0;
    assert!(
        (simulated - m.growth_rate_per_s).abs() < 0.02 + 0.1 * m.growth_rate_per_s,
        "eigenvalues {:.4} 1/s, twin {simulated:.4} 1/s ({per_s:?})",
        m.growth_rate_per_s
    );
    assert!(seen.0 && seen.1, "gains on both sides of the limit");
}

/// A crossing between two points of a fixed grid is found: the paper's loop pokes above
/// |L| = 1 inside the oil-column resonance (≈ 77 Hz, 0.04 Hz wide), where a 2000-point log
/// grid from 0.01 to 200 Hz is 0.38 Hz apart. Every crossover's delay margin is checked against
/// the eigenvalues: with that much more delay a closed-loop pole sits on the axis at the
/// crossover's frequency.
#[test]
fn crossings_inside_a_narrow_resonance_are_found() {
    let q = resolve("paper").unwrap().params;
    let lin = fr::linearise_twin(&q);
    let law = ControlLaw::new(&q);
    let s = Stability::of(&lin, &law, q.plant.valve.tau_s);
    let near: Vec<_> = s
        .margins
        .gain_crossovers
        .iter()
        .filter(|c| (c.freq_hz - 77.0).abs() < 2.0)
        .collect();
    assert!(near.len() >= 2, "{:?}", s.margins);
    let spacing = 77.0 * ((200.0f64 / 0.01).ln() / 1999.0).exp_m1();
    assert!(
        (near[1].freq_hz - near[0].freq_hz) < spacing,
        "{near:?} vs grid spacing {spacing}"
    );
    let grid = MarginGrid::new(&lin);
    for c in &s.margins.gain_crossovers {
        if c.delay_margin_s > 0.05 {
            continue;
        }
        let m = ClosedLoopModes::of(
            &grid.loop_plant,
            &law,
            q.plant.valve.tau_s + c.delay_margin_s,
        )
        .unwrap();
        assert!(
            m.growth_rate_per_s > -1e-3,
            "τ + {:.3} ms: {m:?}",
            c.delay_margin_s * 1e3
        );
    }
    // The delay margin is exact: just under it the loop is stable, just over it unstable
    // (only crossovers where |L| falls destabilise; a rising one moves a pole leftwards).
    let dm = s.margins.delay_margin_s();
    assert!(dm.is_finite() && s.stable(), "{:?}", s.margins);
    for (factor, stable) in [(0.98, true), (1.02, false)] {
        let mut r = q;
        r.plant.valve.tau_s += factor * dm;
        assert_eq!(twin_stability(&r).stable(), stable, "τ + {factor}·{dm}");
    }
}

/// Raising the delay blocks' order does not change the verdict: the rightmost eigenvalue of
/// every shipped preset's loop moves by less than 1e-8 1/s between the two orders.
#[test]
fn the_eigenvalues_do_not_change_with_the_delay_order() {
    for (name, _) in seat_twin::preset::shipped_presets() {
        let p = resolve(&name).unwrap().params;
        let s = twin_stability(&p);
        let m = s.modes.expect("solves");
        assert!(m.order_change < 1e-8, "{name}: {m:?}");
        assert_eq!(m.neutral_modes, 1, "{name}: the chambers' pressure level");
        let g = linear_stability(&p).modes.expect("solves");
        assert!(g.order_change < 1e-8, "{name}: {g:?}");
    }
}

/// Every shipped tuned preset holds its claim where instability shows: at each of the 27
/// points of the spread, stable by the eigenvalues and settled on the nonlinear twin after a
/// bump (ÿ RMS over the last 2 s below 0.02 m/s², not growing).
#[test]
fn every_tuned_preset_settles_at_every_point_of_its_spread() {
    for (name, _) in seat_twin::preset::shipped_presets() {
        if !name.starts_with("tuned") {
            continue;
        }
        let p = resolve(&name).unwrap().params;
        for q in tune::spread(&p) {
            let at = format!(
                "{name} at Cd {:.4}, τ {:.1} ms, m {:.1} kg",
                q.plant.valve.cd,
                q.plant.valve.tau_s * 1e3,
                q.plant.body.mass_kg
            );
            assert!(twin_stability(&q).stable(), "{at}: unstable");
            let s = settle_after_bump(&q).unwrap_or_else(|e| panic!("{at}: {e}"));
            assert!(s.settled(), "{at}: {s:?}");
        }
    }
}
