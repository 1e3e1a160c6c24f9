//! Every controller structure against an independent reference: the time-domain controller
//! (discrete states, stepped with the plant) against its closed-form transfer functions in
//! the loop, on the linear model G(s) (exact) and on the twin (its linearisation, at small
//! amplitude); the structures' own claims (the predictor advances the feed-forward, the Smith
//! predictor removes the delay from the position loop, skyhook feedback damps the body); and
//! the preset syntax.

use seat_twin::analysis::dwell;
use seat_twin::analysis::frequency_response as fr;
use seat_twin::analysis::stability;
use seat_twin::control::ControlLaw;
use seat_twin::model::ModelKind;
use seat_twin::params::{ControllerKind, Params};
use seat_twin::preset::Preset;
use std::f64::consts::PI;

fn with_kind(kind: ControllerKind) -> Params {
    let mut p = Params::paper();
    p.controller.kind = kind;
    p
}

/// The simulated closed loop of the linear model (exact-hold stepper, controller stepped on
/// the grid) against `T(jω)` from the controller's transfer functions and G(s) in closed form.
#[test]
fn each_controller_on_the_linear_model_matches_its_transfer_function() {
    let opt = dwell::DwellOptions::default();
    for kind in ControllerKind::ALL {
        let p = with_kind(kind);
        for f in [0.7, 2.5, 6.0, 11.0] {
            let sim = dwell::simulated_transmissibility(&p, ModelKind::Linear, f, &opt).unwrap();
            let exact = fr::linear_transmissibility(&p, f);
            assert!(
                (sim - exact).norm() < 0.01 * exact.norm().max(0.05),
                "{kind} at {f} Hz: simulated {sim} vs closed form {exact}"
            );
        }
    }
}

/// The same controllers on the nonlinear twin at small amplitude, against the twin's
/// linearisation closed with the same transfer functions.
#[test]
fn each_controller_on_the_twin_matches_the_linearised_loop() {
    let opt = dwell::DwellOptions::default();
    for kind in ControllerKind::ALL {
        let p = with_kind(kind);
        let lin = fr::linearise_twin(&p);
        let law = ControlLaw::new(&p);
        for f in [1.0, 5.0] {
            let sim = dwell::simulated_transmissibility(&p, ModelKind::Twin, f, &opt).unwrap();
            let l = lin.transmissibility(&law, f);
            assert!(
                (sim - l).norm() < 0.03 * l.norm().max(0.1),
                "{kind} at {f} Hz: simulated {sim} vs linearised {l}"
            );
        }
    }
}

/// The predictor's feed-forward leads the paper's by the designed horizon at low frequency:
/// `Ki·(1/s + L·ωc/(s + ωc)) ≈ Ki·e^(sL)/s` for ω ≪ ωc, so its phase lead over the paper's
/// `Ki/s`, read as a time advance, is ≈ L.
#[test]
fn predictive_feed_forward_leads_by_its_horizon() {
    let p = with_kind(ControllerKind::Predictive);
    let law = ControlLaw::new(&p);
    let paper = ControlLaw::new(&Params::paper());
    let l = p.controller.lead_s;
    for f in [0.25, 0.5, 1.0] {
        let w = 2.0 * PI * f;
        let advance = (law.response(w).c_x / paper.response(w).c_x).arg() / w;
        assert!(
            (advance - l).abs() < 0.05 * l,
            "{f} Hz: advance {advance} s vs horizon {l} s"
        );
    }
}

/// The Smith predictor's defining property, on the linear model with a perfect internal
/// model: the closed loop from the platform to the seat is the delay-free loop, delayed.
/// With `M = G0/s`, `u/ẍ = e^(−sτ)·M·(Ki/s)/(1 − Kp·M)`, so `T = 1 + s²·u/ẍ`. The
/// simulated dwell (Smith model stepped with a held command, read τ back from a delay line)
/// is checked against that formula, written here from G(s)'s parameters.
#[test]
fn smith_predictor_closed_loop_is_the_delay_free_loop_delayed() {
    let mut p = with_kind(ControllerKind::Smith);
    p.controller.kp_v_per_m = -40.0;
    let l = p.linear;
    let opt = dwell::DwellOptions::default();
    for f in [1.0, 3.0, 8.0] {
        let w = 2.0 * PI * f;
        let s = num_complex::Complex64::new(0.0, w);
        let sp2 = l.sp_rad_s * l.sp_rad_s;
        let m = l.kg_m_per_s_v * sp2 / (s * s + 2.0 * l.zeta * l.sp_rad_s * s + sp2) / s;
        let u_x = (-s * l.tau_s).exp() * m * (p.controller.ki_v_s_per_m / s)
            / (1.0 - p.controller.kp_v_per_m * m);
        let expected = 1.0 + s * s * u_x;
        let sim = dwell::simulated_transmissibility(&p, ModelKind::Linear, f, &opt).unwrap();
        assert!(
            (sim - expected).norm() < 0.01 * expected.norm().max(0.05),
            "{f} Hz: simulated {sim} vs delay-free loop delayed {expected}"
        );
    }
}

/// Skyhook feedback (`Ksky·Kg < 0`) lowers the body's response around the passive seat's
/// resonance relative to the paper's law with the same Kp and Ki.
#[test]
fn skyhook_feedback_reduces_body_motion_where_the_feed_forward_leaves_it() {
    let sky = with_kind(ControllerKind::Skyhook);
    let paper = Params::paper();
    for f in [2.0, 4.0, 6.0] {
        let t_sky = fr::linear_transmissibility(&sky, f).norm();
        let t_paper = fr::linear_transmissibility(&paper, f).norm();
        assert!(
            t_sky < t_paper,
            "{f} Hz: skyhook {t_sky} vs paper {t_paper}"
        );
    }
    // And the loop keeps margins (gain ≥ 6 dB, phase ≥ 45°), on G(s) and on the twin.
    let m = stability::linear_stability(&sky);
    assert!(
        m.stable() && m.margins.gain_margin_db() >= 6.0 && m.margins.phase_margin_deg() >= 45.0,
        "{m:?}"
    );
    let t = stability::twin_stability(&sky);
    assert!(t.margins.gain_margin_db() >= 6.0, "{t:?}");
}

/// Positive position feedback is reported unstable for every structure.
#[test]
fn positive_position_feedback_is_unstable_for_every_kind() {
    for kind in ControllerKind::ALL {
        let mut p = with_kind(kind);
        p.controller.kp_v_per_m = 20.0;
        assert!(!stability::linear_stability(&p).stable(), "{kind}");
        assert!(!stability::twin_stability(&p).stable(), "{kind}");
    }
}

#[test]
fn preset_controller_table_by_kind() {
    let text = "[controller]\nkind = \"skyhook\"\nkp_v_per_m = -10.0\nsky_v_s_per_m = -4.0\n";
    let p = Preset::from_toml(text, "x.toml".as_ref()).unwrap();
    assert_eq!(p.params.controller.kind, ControllerKind::Skyhook);
    assert_eq!(p.params.controller.kp_v_per_m, -10.0);
    assert_eq!(p.params.controller.sky_v_s_per_m, -4.0);
    // No kind: the paper's, as presets always were.
    let p = Preset::from_toml("[controller]\nkp_v_per_m = -7.0\n", "y.toml".as_ref()).unwrap();
    assert_eq!(p.params.controller.kind, ControllerKind::Paper);
    // A key of another kind is an error that names it and the kind's keys.
    let err = Preset::from_toml(
        "[controller]\nkind = \"paper\"\nlead_s = 0.02\n",
        "z.toml".as_ref(),
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("lead_s") && err.contains("paper"), "{err}");
    assert!(err.contains("z.toml") && err.contains("line"), "{err}");
    // An unknown kind names the allowed ones.
    let err = Preset::from_toml("[controller]\nkind = \"pid\"\n", "k.toml".as_ref())
        .unwrap_err()
        .to_string();
    assert!(err.contains("pid") && err.contains("smith"), "{err}");
    // A gain out of range names its key and range.
    let err = Preset::from_toml(
        "[controller]\nkind = \"predictive\"\nlead_s = 0.5\n",
        "r.toml".as_ref(),
    )
    .unwrap_err()
    .to_string();
    assert!(
        err.contains("controller.lead_s") && err.contains("0.1"),
        "{err}"
    );
    // Round trip: every kind writes only its keys and reads back equal.
    for kind in ControllerKind::ALL {
        let mut q = Preset {
            meta: Default::default(),
            params: with_kind(kind),
            per_record: Default::default(),
        };
        q.params.controller.kp_v_per_m = -12.5;
        let text = q.to_toml();
        let back = Preset::from_toml(&text, "rt.toml".as_ref()).unwrap();
        assert_eq!(
            back.params.controller, q.params.controller,
            "{kind}:\n{text}"
        );
        for key in ["lead_s", "sky_v_s_per_m"] {
            assert_eq!(
                text.contains(key),
                kind.keys().contains(&key),
                "{kind} writes {key}?\n{text}"
            );
        }
    }
}
