//! Effects outside the library: a Cd that depends on the spool position, a drifting valve
//! null, three effects at once and a lag of the valve command. The verdict stays
//! `unexplained` (by the library), and the search beyond it proposes what the rig has.

use super::rig::*;
use seat_twin::identify::{self, CalibrationReport, Verdict};

/// An effect the library cannot imitate (Cd depending on the spool position): the verdict is
/// `unexplained`, never `explained`; effects that helped keep their evidence, and the report
/// says what is left — which records and channels, which band, what it correlates with.
/// Beyond the library the direction difference is proposed, with no library effect beside it.
#[test]
fn effect_outside_the_library_is_unexplained() {
    let fx = RigEffects {
        cd_spool: Some(0.25),
        ..Default::default()
    };
    let r = run(fx, 24);
    let s = summary(&r);
    let left = r.residual_left.as_ref().map(|l| l.summary.clone());
    eprintln!("out of library: {s}; left: {left:?}; notes {:?}", r.notes);
    assert_eq!(r.verdict, Verdict::Unexplained, "{s}");
    let left = r.residual_left.as_ref().expect("what is left is reported");
    assert!(!left.channels.is_empty(), "{s}");
    assert!(left.channels.iter().all(|c| c.weighted_rms > 1.0), "{s}");
    assert!(left.main_band_hz[1] > left.main_band_hz[0]);
    assert!(!left.correlations.is_empty());
    for e in &r.effects {
        assert!(
            e.evidence.contains("ΔBIC") && e.evidence.contains("validation"),
            "{s}"
        );
    }
    let json = identify::report::report_json(&r);
    assert_eq!(json["verdict"], "unexplained");
    assert!(
        json["residual_left"]["summary"]
            .as_str()
            .is_some_and(|t| t.contains(".csv"))
    );
    let md = identify::report::report_markdown(&r, None);
    assert!(md.contains("## What is left"), "{md}");
    // Beyond the library, the direction difference is proposed, and the twin with it
    // carries no library effect: the valve offset the library's twin needs (15.7 mV) comes
    // out at 0.12 mV beside the term, and does not earn its parameter there (ΔBIC +2.4 for
    // keeping it, the raw error at its floor without it).
    assert!(
        r.proposed.iter().any(|t| t.name == "flow_direction"),
        "{:?}",
        r.proposed
    );
    assert_eq!(
        identify::report::proposed_twin_effects(&r),
        Vec::<&str>::new(),
        "{:?}",
        r.proposed_leaves_out
    );
    assert!(!r.params.plant.effects.valve_offset.enabled);
}

/// Issue 20: an effect outside the library that makes the stroke drift slowly (the valve's
/// null drifting during each test) is `unexplained`, however well a valve offset follows
/// the drift's mean; the report names the record, `u`, the band and the window where the raw
/// residual stays above the noise floor. The old verdict, which judged a low-passed velocity
/// weighted by 1 % of its own RMS, could not see this drift. Beyond the library the drift is
/// proposed as what it is, the valve's null drifting, at the rig's rate within 3σ, and with
/// it every raw band is at its floor.
#[test]
fn a_slow_stroke_drift_outside_the_library_is_unexplained() {
    let fx = RigEffects {
        null_drift_v_per_s: Some(2e-3),
        ..Default::default()
    };
    let r = run(fx, 25);
    let s = summary(&r);
    eprintln!(
        "null drift: {s}; raw: {}; proposed {:?}; candidates {:?}; with them {}",
        r.raw_error_after.summary(),
        r.proposed,
        r.proposed_candidates,
        r.raw_error_proposed
            .as_ref()
            .map(|e| e.summary())
            .unwrap_or_default()
    );
    assert_eq!(r.verdict, Verdict::Unexplained, "{s}");
    let worst = r
        .raw_error_after
        .above
        .first()
        .expect("a band above the floor");
    assert_eq!(worst.channel, "u", "{s}");
    assert!(worst.ratio > 2.0 * r.raw_error_after.limit, "{worst:?}");
    let json = identify::report::report_json(&r);
    assert_eq!(json["raw_error"]["after"]["at_floor"], false);
    let left = json["residual_left"]["summary"]
        .as_str()
        .unwrap_or_default();
    assert!(left.contains(&format!("{} u ", worst.file)), "{left}");
    let term = proposed(&r, "command_drift");
    let (v, sd) = size(term, "command_drift_v_per_s");
    assert!((v - 2e-3).abs() < 3.0 * sd, "{v} ± {sd}");
    assert!(
        term.description.contains("null drifts"),
        "{}",
        term.description
    );
    assert_eq!(r.params.plant.corrections.command_drift_v_per_s, v);
    let with = r
        .raw_error_proposed
        .as_ref()
        .expect("raw error with the term");
    assert!(with.at_floor(), "{}", with.summary());
}

/// Issue 20, items 2 and 7: a rig with four effects outside the library at once — a flow
/// gain that differs between the spool directions (Cd·(1 ± 10 %), rounded over 0.1 mm at
/// null), a Cd that rises with the opening and levels off (+15 % of Cd at large openings,
/// over 0.2 mm), a damping force quadratic in the velocity (20 N at 0.1 m/s) and a cushion
/// spring the declared stiffness lacks (10 % of it, slightly progressive). The library
/// cannot explain it: the verdict stays `unexplained`; the search beyond the library proposes
/// the first three in physical words, and Cd and τ come out right beside them;
/// `calibrated.toml` carries them, and with them the worst raw band falls to under a tenth of
/// the library's. The spring is not found: at 10 % of the declared stiffness, open-loop tests
/// of a flow-controlled cylinder hardly see it, and the search stops at three terms.
///
/// The direction difference walks the body into an end stop in two of the five tests (the
/// 2 Hz / 2.1 V and 10 Hz / 4 V sines, after about 1 s). Fitted whole, those records made the
/// cost jump with the smallest change of a parameter, and the search found the direction term
/// only (this test was a known failure until 2026-11-28); the calibration now uses each record
/// up to its first end-stop contact (`identify::data::before_end_stops`).
///
/// The values: the direction term comes out at 0.116 (the rig's 0.10) and the quadratic
/// damping at 2711 ± 49 N·s²/m², 36 % and 15 σ above the rig's 2000 (the laws differ only
/// below 5 mm/s): it stands in for part of what the two-term forms miss (the spring, the
/// opening law's shape), and its uncertainty does not say so; the opening term, linear in
/// the opening where the rig's levels off, matches the rig's flow gain where the tests open
/// the spool (checked below) and runs past it beyond.
#[test]
fn three_effects_outside_the_library_are_proposed() {
    let fx = RigEffects {
        cd_spool: Some(0.10),
        cd_opening: Some(0.15),
        quadratic_damping: Some(2000.0),
        extra_spring: Some(368.0),
        ..Default::default()
    };
    let r = run(fx, 28);
    let s = summary(&r);
    let proposed: Vec<(&str, f64, f64)> = r
        .proposed
        .iter()
        .map(|t| {
            let k = [
                "flow_gain_direction",
                "quadratic_damping_n_s2_per_m2",
                "spring_n_per_m",
                "cd_opening_slope",
                "flow_gain_return_edge",
                "turbulent_leakage_m3_per_s_sqrt_pa",
                "command_lag_s",
                "command_drift_v_per_s",
            ]
            .into_iter()
            .find(|k| t.params.contains_key(*k))
            .expect("a sizing parameter");
            eprintln!(
                "{}: per record {:?}, scale {}",
                t.name, t.per_record, t.uncertainty_scale
            );
            (t.name.as_str(), t.params[k], t.uncertainties[k])
        })
        .collect();
    eprintln!(
        "three outside: {s}; proposed {proposed:?}; {:?}; candidates {:?}; notes {:?}; with them: {}",
        proposed_words(&r),
        r.proposed_candidates,
        r.notes,
        r.raw_error_proposed
            .as_ref()
            .map(|e| e.summary())
            .unwrap_or_default()
    );
    assert_eq!(r.verdict, Verdict::Unexplained, "{s}");
    // The rig's valve follows its command without a lag: none is proposed.
    assert!(
        proposed.iter().all(|p| p.0 != "command_lag"),
        "{proposed:?}"
    );
    let find = |name: &str| {
        proposed
            .iter()
            .find(|p| p.0 == name)
            .unwrap_or_else(|| panic!("{name} not proposed: {proposed:?}; {s}"))
    };
    let dir = find("flow_direction");
    assert!((dir.1 - 0.10).abs() < 0.03, "{dir:?}");
    let damping = find("quadratic_damping");
    assert!(damping.1 > 1000.0 && damping.1 < 3000.0, "{damping:?}");
    let opening = find("cd_opening");
    assert!(opening.1 > 0.05, "{opening:?}");
    // The twin's law is linear in the opening, the rig's levels off over 0.2 mm: they can
    // agree only where the tests open the spool. The largest sines open it to 0.17 mm
    // (2.1 V) and 0.32 mm (4 V, cut at its first end-stop contact); up to 0.2 mm the twin's
    // flow gain, Cd and both direction terms together, is the rig's within 4 %. (Beyond, the
    // linear law runs on: at full travel it is 29 % above the rig's. The README says so.)
    let p = &r.params;
    for x in [
        -0.2e-3, -0.1e-3, -0.05e-3, -0.02e-3, 0.02e-3, 0.05e-3, 0.1e-3, 0.2e-3,
    ] {
        let twin = p.plant.valve.cd * p.plant.corrections.edge_gains(x, p.plant.valve.xv_max_m).0;
        let a: f64 = x;
        let rig = 0.95
            * 0.1506
            * (1.0 + 0.10 * (a / 1e-4).tanh())
            * (1.0 + 0.15 * (1.0 - (-a.abs() / 2e-4).exp()));
        assert!(
            (twin / rig - 1.0).abs() < 0.04,
            "at {x} m: {twin} vs {rig}; {s}"
        );
    }
    assert!((r.params.plant.valve.tau_s - 0.019).abs() < 0.5e-3, "{s}");
    // calibrated.toml carries them, and the raw error with them is far below the library's.
    let c = &r.params.plant.corrections;
    assert_eq!(c.flow_gain_direction, dir.1);
    assert_eq!(c.quadratic_damping_n_s2_per_m2, damping.1);
    assert_eq!(c.cd_opening_slope, opening.1);
    let worst =
        |e: &identify::raw_error::RawErrorReport| e.worst.as_ref().map_or(f64::NAN, |w| w.ratio);
    let with = r
        .raw_error_proposed
        .as_ref()
        .expect("raw error with the proposed terms");
    assert!(
        worst(with) < 0.1 * worst(&r.raw_error_after),
        "{}",
        with.summary()
    );
    let json = identify::report::report_json(&r);
    let list = json["proposed"].as_array().expect("proposed list");
    assert_eq!(list.len(), r.proposed.len());
    for t in list {
        for key in ["name", "description", "params", "uncertainties"] {
            assert!(!t[key].is_null(), "{key}: {t}");
        }
    }
    let md = identify::report::report_markdown(&r, None);
    assert!(md.contains("## Proposed beyond the library"), "{md}");
    assert!(
        md.contains("more flow with the spool opened positive"),
        "{md}"
    );
}

/// Issue 20, item 2: a damping force quadratic in the velocity (22.5 N at 0.1 m/s), alone. The
/// library has no such law and follows it with what it has (a supply sag takes force away as
/// the flow grows; a valve overlap far under a micrometre trims the small openings); the
/// verdict stays `unexplained`. Beside the proposed damping those effects no longer earn
/// their parameters, and the twin with the proposed term (`calibrated.toml`) carries none of
/// the library's effects, as the rig has none: its damping is the rig's within 3σ and 5 %,
/// and every raw channel is at its floor. (On the ten-record timing campaign at 1 kHz the
/// damping came out at 2183 ± 100 N·s²/m² with the sag and the overlap kept, 2248 ± 22
/// without them; at 10 kHz 1805 ± 87 and 2247 ± 20.)
#[test]
fn a_quadratic_damping_is_proposed_without_the_effects_that_followed_it() {
    let truth = 2250.0;
    let fx = RigEffects {
        quadratic_damping: Some(truth),
        ..Default::default()
    };
    let r = run(fx, 29);
    let s = summary(&r);
    eprintln!(
        "quadratic damping: {s}; library {:?}; left out {:?}; proposed {:?}",
        effect_names(&r),
        r.proposed_leaves_out,
        proposed_words(&r),
    );
    assert_eq!(r.verdict, Verdict::Unexplained, "{s}");
    let (c, sc) = size(
        proposed(&r, "quadratic_damping"),
        "quadratic_damping_n_s2_per_m2",
    );
    assert!(
        (c - truth).abs() < 3.0 * sc && (c / truth - 1.0).abs() < 0.05,
        "{c} ± {sc}; {s}"
    );
    let on: Vec<_> = identify::EffectId::ALL
        .into_iter()
        .filter(|e| e.enabled(&r.params))
        .collect();
    assert!(on.is_empty(), "calibrated.toml carries {on:?}; {s}");
    for e in &r.effects {
        assert!(
            r.proposed_leaves_out
                .iter()
                .any(|l| l.name == e.effect.name()),
            "{} is in the library's twin but not said to be left out; {s}",
            e.effect.name()
        );
    }
    let with = r.raw_error_proposed.as_ref().expect("a proposed twin");
    assert!(with.at_floor(), "{}", with.summary());
    let json = identify::report::report_json(&r);
    assert_eq!(
        json["proposed_leaves_out"].as_array().map(Vec::len),
        Some(r.proposed_leaves_out.len())
    );
}

/// Issue 20, item 2: a lag of the valve command (a servo amplifier's first-order lag of
/// 4 ms, beside the delay) is outside the library. The verdict is `unexplained`, the lag is
/// proposed in words with its value (truth within 3σ or 20 %), calibrated.toml carries it
/// and its replay applies it: the worst raw band with it falls below the library's. (A rig
/// without the lag gets no such term: `three_effects_outside_the_library_are_proposed`.)
#[test]
fn a_lag_of_the_valve_command_is_proposed() {
    let fx = RigEffects {
        command_lag_s: Some(4e-3),
        ..Default::default()
    };
    let r = run(fx, 41);
    let s = summary(&r);
    eprintln!(
        "command lag: {s}; proposed {:?}; candidates {:?}; notes {:?}",
        r.proposed, r.proposed_candidates, r.notes
    );
    assert_eq!(r.verdict, Verdict::Unexplained, "{s}");
    let term = proposed(&r, "command_lag");
    let (v, sd) = size(term, "command_lag_s");
    assert!(
        (v - 4e-3).abs() <= (3.0 * sd).max(0.2 * 4e-3),
        "{v} ± {sd}: {}",
        term.description
    );
    assert!(
        term.description.contains("first-order lag"),
        "{}",
        term.description
    );
    assert_eq!(r.params.plant.corrections.command_lag_s, v);
    let worst =
        |e: &identify::raw_error::RawErrorReport| e.worst.as_ref().map_or(f64::NAN, |w| w.ratio);
    let with = r
        .raw_error_proposed
        .as_ref()
        .expect("raw error with the term");
    assert!(
        worst(with) < worst(&r.raw_error_after),
        "{}",
        with.summary()
    );
}

/// Issue 20, item 3 (any two effects at once): a soft hose (0.6 GPa beside 0.9 GPa chambers)
/// under a valve null drifting 1.1 mV/s, each hiding the other. Alone, the library's
/// compliance raises the held-out error under the drift, and the drift term removes too
/// little of the residual under the missing compliance (on the survey's case 33, 8 % against
/// the 10 % a term needs), so neither was found and the mass stood in for the oil column's
/// stiffness (18.0 kg against 11.7). Fitted together (`identify::pair`) they clear the bars
/// and each earns its place: the drift is proposed at the rig's rate, the twin with it
/// carries the compliance at the rig's hose modulus, and its raw error is at its floor. The
/// library's twin, which the verdict judges, stays `unexplained`.
#[test]
fn a_soft_hose_under_a_drifting_null_is_found_with_it() {
    let (hose, drift) = (0.6e9, 1.1e-3);
    let fx = RigEffects {
        compliance: Some((hose, 0.9e9)),
        null_drift_v_per_s: Some(drift),
        ..Default::default()
    };
    let r = run(fx, 61);
    let s = summary(&r);
    eprintln!(
        "hose under a null drift: {s}; proposed {:?}; beside them {:?}; left out {:?}; notes {:?}",
        proposed_words(&r),
        r.proposed_adds,
        r.proposed_leaves_out,
        r.notes
    );
    drift_proposed_beside(&r, drift, "compliance", &s);
    let c = &r.params.plant.effects.compliance;
    assert!(c.enabled, "calibrated.toml; {s}");
    assert!(
        (c.hose_bulk_modulus_pa - hose).abs() < 0.1 * hose,
        "hose {} Pa; {s}",
        c.hose_bulk_modulus_pa
    );
    assert!(
        (r.params.plant.body.mass_kg - 11.7).abs() < 0.5,
        "mass {}; {s}",
        r.params.plant.body.mass_kg
    );
    let with = r.raw_error_proposed.as_ref().expect("a proposed twin");
    assert!(with.at_floor(), "{}", with.summary());
    assert!(
        r.notes
            .iter()
            .any(|n| n.contains("fitted together")
                && n.contains("kept, each hiding the other alone")),
        "{:?}",
        r.notes
    );
}

/// Issue 20, items 2 and 3: a library effect beside one outside it — a friction (Coulomb
/// 40 N, Stribeck 15 N, viscous 80 N·s/m) beside the valve's null drifting 2 mV/s. Under the
/// drift's residual the friction does not earn its parameters (on the ten-record timing
/// campaign it screened at ΔBIC +26, 0.8 % of the residual) and a valve offset follows the
/// drift's mean instead. Once the drift is proposed, the library is searched again beside it:
/// the friction is found there, at the rig's size, and the twin with the proposed term
/// (`calibrated.toml`) carries the friction and the drift and leaves the offset out. The
/// library's own twin, which the verdict judges, stays as the library found it:
/// `unexplained`.
#[test]
fn a_friction_under_a_drifting_null_is_found_beside_the_proposed_drift() {
    let (coulomb, drift) = (40.0, 2e-3);
    let fx = RigEffects {
        friction: Some((coulomb, 15.0, 0.01, 80.0)),
        null_drift_v_per_s: Some(drift),
        ..Default::default()
    };
    let r = run(fx, 43);
    let s = summary(&r);
    eprintln!(
        "friction beside a null drift: {s}; library {:?}; proposed {:?}; beside them {:?}; \
         left out {:?}; notes {:?}",
        effect_names(&r),
        proposed_words(&r),
        r.proposed_adds,
        r.proposed_leaves_out,
        r.notes
    );
    drift_proposed_beside(&r, drift, "friction", &s);
    let friction = r
        .effects
        .iter()
        .chain(&r.proposed_adds)
        .find(|e| e.effect == identify::EffectId::Friction)
        .expect("friction in the proposed twin");
    let (fc, sc) = (
        friction.params["coulomb_n"],
        friction.uncertainties["coulomb_n"],
    );
    assert!(
        (fc - coulomb).abs() <= (3.0 * sc).max(0.15 * coulomb),
        "Coulomb {fc} ± {sc}; {s}"
    );
    let on: Vec<_> = identify::EffectId::ALL
        .into_iter()
        .filter(|e| e.enabled(&r.params))
        .collect();
    assert_eq!(on, [identify::EffectId::Friction], "calibrated.toml; {s}");
    let with = r.raw_error_proposed.as_ref().expect("a proposed twin");
    assert!(with.at_floor(), "{}", with.summary());
    let json = identify::report::report_json(&r);
    assert_eq!(
        json["proposed_twin_effects"],
        serde_json::json!(["friction"])
    );
    let md = identify::report::report_markdown(&r, None);
    assert!(md.contains("Library effects of the twin with the proposed terms: `friction`"));
}

/// The proposed term `name` of `r` (panics, listing what was proposed, when it is not there).
fn proposed<'a>(
    r: &'a CalibrationReport,
    name: &str,
) -> &'a seat_twin::identify::result::ProposedTerm {
    r.proposed
        .iter()
        .find(|t| t.name == name)
        .unwrap_or_else(|| panic!("no `{name}` proposed: {:?}", r.proposed))
}

/// The value and 1-σ of the proposed term `t`'s parameter `key` (SI).
fn size(t: &seat_twin::identify::result::ProposedTerm, key: &str) -> (f64, f64) {
    (t.params[key], t.uncertainties[key])
}

/// The library's verdict `unexplained`, the null drift proposed within 3σ of the rig's
/// `drift`, and the twin with it carrying the library's `effect` and no other.
fn drift_proposed_beside(r: &CalibrationReport, drift: f64, effect: &str, s: &str) {
    assert_eq!(r.verdict, Verdict::Unexplained, "{s}");
    let (v, sd) = size(proposed(r, "command_drift"), "command_drift_v_per_s");
    assert!((v - drift).abs() < 3.0 * sd, "{v} ± {sd}; {s}");
    assert_eq!(identify::report::proposed_twin_effects(r), [effect], "{s}");
}
