//! Issue 20, items 4 and 7: the loop over 36 randomised rigs of our own — in-library effects
//! singly and in pairs, effects outside the library, a library effect beside one outside it,
//! sensor artefacts, a drifting Cd, the null case — each with its own declared mismatch (Cd ± 6 %, τ ± 2 ms) and noise seed.
//! It prints the verdict/effects confusion table, the share of fitted parameters whose
//! truth lies within 3σ, and the replayed raw error of each calibrated.toml against the
//! nominal one, and fails below the bars (see the end of the test). Slow (about two
//! minutes): run it with
//! `cargo test --no-default-features --test it identify::survey -- --ignored --nocapture`.

use super::rig::{RigEffects, above_noise, calibrate_paper, campaign_of, effect_names};
use rand::{Rng, SeedableRng};
use seat_twin::identify::{self, CalibrationReport, EffectId, Verdict};
use seat_twin::preset::Preset;

/// What a rig is, for judging a calibration.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Class {
    Null,
    Single,
    Pair,
    Outside,
    Sensor,
    Drift,
    Mixed,
}

impl Class {
    /// The classes of the first 30 rigs, in turn.
    const DRAWN: [Class; 6] = [
        Class::Null,
        Class::Single,
        Class::Pair,
        Class::Outside,
        Class::Sensor,
        Class::Drift,
    ];
    /// Every class, as the table lists them.
    const ALL: [Class; 7] = [
        Class::Null,
        Class::Single,
        Class::Pair,
        Class::Outside,
        Class::Mixed,
        Class::Sensor,
        Class::Drift,
    ];

    fn name(self) -> &'static str {
        match self {
            Class::Null => "null (no hidden effect)",
            Class::Single => "one library effect",
            Class::Pair => "two library effects",
            Class::Outside => "effect(s) outside the library",
            Class::Sensor => "sensor artefacts only",
            Class::Drift => "Cd drifting record to record",
            Class::Mixed => "a library effect beside one outside it",
        }
    }

    /// The verdict a right calibration gives.
    fn right_verdict(self) -> Verdict {
        match self {
            Class::Null | Class::Sensor => Verdict::NoMissingEffect,
            Class::Single | Class::Pair => Verdict::Explained,
            Class::Outside | Class::Mixed | Class::Drift => Verdict::Unexplained,
        }
    }
}

pub(super) struct Case {
    class: Class,
    label: String,
    pub(super) fx: RigEffects,
    library: Vec<EffectId>,
    pressures: bool,
    pub(super) cd: f64,
    pub(super) tau: f64,
}

/// A realistic magnitude of each library effect, drawn in a range around the single-effect
/// tests' values.
fn library_effect(e: EffectId, rng: &mut impl Rng, fx: &mut RigEffects) -> String {
    let f = rng.random_range(0.7..1.4);
    match e {
        EffectId::Friction => {
            fx.friction = Some((40.0 * f, 10.0 * f, 0.01, 80.0 * f));
            format!("friction Fc {:.0} N", 40.0 * f)
        }
        EffectId::ValveOverlap => {
            fx.overlap = Some(40e-6 * f);
            format!("overlap {:.0} µm", 40.0 * f)
        }
        EffectId::ValveOffset => {
            let s = if rng.random_bool(0.5) { 1.0 } else { -1.0 };
            fx.offset = Some(3e-6 * f * s);
            format!("offset {:+.1} µm", 3.0 * f * s)
        }
        EffectId::Leakage => {
            fx.leakage = Some(2.5e-12 * f);
            format!("leakage {:.1e}", 2.5e-12 * f)
        }
        EffectId::Compliance => {
            fx.compliance = Some((0.5e9 * f, 0.9e9));
            format!("hose β {:.2} GPa", 0.5 * f)
        }
        EffectId::SupplySag => {
            fx.sag = Some(1.5e10 * f);
            format!("sag {:.1e}", 1.5e10 * f)
        }
    }
}

/// The 30 rigs drawn from `seed` (2020: the README's table), then the six of
/// [`mixed_cases`].
pub(super) fn cases(seed: u64) -> Vec<Case> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let lib = EffectId::ALL;
    let mut out = Vec::new();
    for i in 0..30 {
        let class = Class::DRAWN[i % 6];
        let mut fx = RigEffects::default();
        let mut library = Vec::new();
        let mut label = Vec::new();
        match class {
            Class::Null => {}
            Class::Single => {
                let e = lib[(i / 6) % lib.len()];
                label.push(library_effect(e, &mut rng, &mut fx));
                library.push(e);
            }
            Class::Pair => {
                let pairs = [
                    (EffectId::Friction, EffectId::ValveOverlap),
                    (EffectId::Leakage, EffectId::Compliance),
                    (EffectId::ValveOffset, EffectId::SupplySag),
                    (EffectId::ValveOverlap, EffectId::Compliance),
                    (EffectId::ValveOffset, EffectId::Leakage),
                ];
                let (a, b) = pairs[(i / 6) % pairs.len()];
                for e in [a, b] {
                    label.push(library_effect(e, &mut rng, &mut fx));
                    library.push(e);
                }
            }
            Class::Outside => match (i / 6) % 5 {
                0 => {
                    let a = rng.random_range(0.08..0.2);
                    fx.cd_spool = Some(a);
                    label.push(format!("Cd per direction ±{:.1} %", 100.0 * a));
                }
                1 => {
                    let a = rng.random_range(0.1..0.2);
                    fx.cd_opening = Some(a);
                    label.push(format!("Cd rising with opening {:.1} %", 100.0 * a));
                }
                2 => {
                    let c = rng.random_range(1500.0..3000.0);
                    fx.quadratic_damping = Some(c);
                    label.push(format!("quadratic damping {c:.0} N·s²/m²"));
                }
                3 => {
                    let d = rng.random_range(1e-3..3e-3);
                    fx.null_drift_v_per_s = Some(d);
                    label.push(format!("valve null drifting {:.2} mV/s", 1e3 * d));
                }
                _ => {
                    let a = rng.random_range(0.08..0.15);
                    let c = rng.random_range(1500.0..3000.0);
                    fx.cd_spool = Some(a);
                    fx.quadratic_damping = Some(c);
                    label.push(format!(
                        "Cd per direction ±{:.1} % + damping {c:.0}",
                        100.0 * a
                    ));
                }
            },
            Class::Sensor => {
                let s = rng.random_range(0.95..1.05);
                fx.ydd_scale = Some(s);
                label.push(format!("ÿ scale {s:.3}"));
                if i % 2 == 0 {
                    let o = rng.random_range(-0.4..0.4);
                    fx.ydd_offset = Some(o);
                    label.push(format!("ÿ offset {o:+.2} m/s²"));
                } else {
                    let l = rng.random_range(1e-3..3e-3);
                    fx.u_lag_s = Some(l);
                    label.push(format!("u lag {:.1} ms", 1e3 * l));
                }
            }
            Class::Drift => {
                let d = rng.random_range(0.02..0.04);
                fx.cd_drift_per_test = Some(d);
                label.push(format!("Cd +{:.1} %/record", 100.0 * d));
            }
            Class::Mixed => unreachable!("drawn by `mixed_cases`"),
        }
        let pressures = library.contains(&EffectId::SupplySag);
        out.push(Case {
            class,
            label: if label.is_empty() {
                "none".into()
            } else {
                label.join(", ")
            },
            fx,
            library,
            pressures,
            cd: 0.1506 * rng.random_range(0.94..1.06),
            tau: 0.0175 + rng.random_range(-0.002..0.002),
        });
    }
    out.extend(mixed_cases(seed));
    out
}

/// Six rigs with a library effect beside one outside the library, drawn from `seed` on a
/// generator of their own, so that the first 30 rigs of a draw stay as they were drawn
/// before these were added (2026-12-03). Right: `unexplained` (the library cannot explain
/// them), the outside effect proposed as its term, and the twin with the proposed terms
/// carrying the library effect and no other.
fn mixed_cases(seed: u64) -> Vec<Case> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed ^ 0x6d69_7865_6400);
    let pairs = [
        (EffectId::Friction, "drift"),
        (EffectId::ValveOverlap, "damping"),
        (EffectId::Leakage, "direction"),
        (EffectId::Compliance, "drift"),
        (EffectId::ValveOffset, "damping"),
        (EffectId::SupplySag, "opening"),
    ];
    pairs
        .iter()
        .map(|&(e, outside)| {
            let mut fx = RigEffects::default();
            let mut label = vec![library_effect(e, &mut rng, &mut fx)];
            label.push(match outside {
                "drift" => {
                    let d = rng.random_range(1e-3..3e-3);
                    fx.null_drift_v_per_s = Some(d);
                    format!("null drift {:.2} mV/s", 1e3 * d)
                }
                "damping" => {
                    let c = rng.random_range(1500.0..3000.0);
                    fx.quadratic_damping = Some(c);
                    format!("damping {c:.0} N·s²/m²")
                }
                "direction" => {
                    let a = rng.random_range(0.08..0.2);
                    fx.cd_spool = Some(a);
                    format!("Cd per direction ±{:.1} %", 100.0 * a)
                }
                _ => {
                    let a = rng.random_range(0.1..0.2);
                    fx.cd_opening = Some(a);
                    format!("Cd rising {:.1} %", 100.0 * a)
                }
            });
            Case {
                class: Class::Mixed,
                label: label.join(" + "),
                fx,
                library: vec![e],
                pressures: e == EffectId::SupplySag,
                cd: 0.1506 * rng.random_range(0.94..1.06),
                tau: 0.0175 + rng.random_range(-0.002..0.002),
            }
        })
        .collect()
}

/// Fitted parameters whose truth is known in the library's own form: (name, value, σ, truth).
fn checked_parameters(c: &Case, r: &CalibrationReport) -> Vec<(String, f64, f64, f64)> {
    let mut out = Vec::new();
    // Cd and τ are the library's only where the rig's valve is (no Cd law of its own, no drift).
    let plain_valve = c.fx.cd_spool.is_none()
        && c.fx.cd_opening.is_none()
        && c.fx.cd_drift_per_test.is_none()
        && c.fx.null_drift_v_per_s.is_none();
    // What calibrated.toml carries: with terms proposed beyond the library, the parameters
    // re-fitted beside them.
    let calibrated = if r.proposed_calibrated.is_empty() {
        &r.calibrated
    } else {
        &r.proposed_calibrated
    };
    for v in calibrated {
        let truth = match v.name.as_str() {
            "cd" if plain_valve => Some(c.cd),
            "tau_s" if plain_valve => Some(c.tau),
            "mass_kg" => Some(11.7),
            _ => None,
        };
        if let Some(t) = truth {
            out.push((v.name.clone(), v.value, v.std, t));
        }
    }
    for e in &r.effects {
        for (k, v) in &e.params {
            let truth = match k.as_str() {
                "bias_v" => c.fx.offset.map(|o| -o / 8e-5),
                "droop_pa_per_m3_s" => c.fx.sag,
                // The rig's leakage grows by |Δp|/200 bar (rig.rs): g = 5e-8 /Pa. Without its
                // growth (kept only where the records call for it) the coefficient is a
                // compromise with no truth of its own; so is one modulus for hoses and
                // chambers.
                "coefficient_m3_per_s_pa" if e.params.contains_key("growth_per_pa") => c.fx.leakage,
                "growth_per_pa" => c.fx.leakage.map(|_| 5e-8),
                // The rig's chambers and hoses have moduli of their own (rig.rs).
                "effective_bulk_modulus_pa" if e.params.contains_key("hose_bulk_modulus_pa") => {
                    c.fx.compliance.map(|(_, chambers)| chambers)
                }
                "hose_bulk_modulus_pa" => c.fx.compliance.map(|(hose, _)| hose),
                _ => None,
            };
            if let Some(t) = truth {
                out.push((k.clone(), *v, e.uncertainties[k], t));
            }
        }
    }
    for s in &r.sensors {
        let truth = match (s.channel.as_str(), s.kind.as_str()) {
            ("ydd", "scale") => c.fx.ydd_scale,
            ("ydd", "offset") => c.fx.ydd_offset,
            ("u", "lag") => c.fx.u_lag_s,
            _ => None,
        };
        if let Some(t) = truth {
            out.push((
                format!("{} {}", s.channel, s.kind),
                s.value,
                s.uncertainty,
                t,
            ));
        }
    }
    out
}

/// Whether the calibration found the rig's effects: the library's exactly, the sensor properties
/// that matter, the drifting Cd, or each effect outside the library as its proposed term.
pub(super) fn effects_right(c: &Case, r: &CalibrationReport) -> bool {
    let mut found: Vec<EffectId> = r.effects.iter().map(|e| e.effect).collect();
    found.sort();
    let mut truth = c.library.clone();
    truth.sort();
    match c.class {
        Class::Null | Class::Single | Class::Pair => found == truth,
        Class::Sensor => {
            // Every property large enough to matter is reported (a scale within 0.5 % of 1
            // or an offset under 0.05 m/s² may rightly read as exact).
            found.is_empty()
                && [
                    (
                        "ydd",
                        "scale",
                        c.fx.ydd_scale.filter(|s| (s - 1.0).abs() >= 0.005),
                    ),
                    ("ydd", "offset", c.fx.ydd_offset.filter(|o| o.abs() >= 0.05)),
                    ("u", "lag", c.fx.u_lag_s),
                ]
                .iter()
                .filter(|(_, _, v)| v.is_some())
                .all(|(ch, k, _)| r.sensors.iter().any(|s| s.channel == *ch && s.kind == *k))
        }
        Class::Outside | Class::Mixed => {
            // Each of the rig's effects outside the library proposed as the term that
            // describes it (more terms may come with it): Cd per direction as the
            // direction difference, Cd rising with the opening as the opening term. The twin
            // with the proposed terms (calibrated.toml) carries the rig's library effects and
            // no other: none where the rig has none (a valve offset kept beside a direction
            // term stands in for part of it, and is wrong).
            let mut twin = identify::report::proposed_twin_effects(r);
            twin.sort();
            let mut names: Vec<&str> = truth.iter().map(|e| e.name()).collect();
            names.sort();
            let expected = [
                (c.fx.cd_spool.is_some(), "flow_direction"),
                (c.fx.cd_opening.is_some(), "cd_opening"),
                (c.fx.quadratic_damping.is_some(), "quadratic_damping"),
                (c.fx.null_drift_v_per_s.is_some(), "command_drift"),
            ];
            !r.proposed.is_empty()
                && twin == names
                && expected
                    .iter()
                    .filter(|(present, _)| *present)
                    .all(|(_, name)| r.proposed.iter().any(|t| t.name == *name))
        }
        Class::Drift => r.drifts.iter().any(|d| d.parameter == "cd"),
    }
}

#[test]
#[ignore = "slow: 36 calibrations; run with --ignored --nocapture to print the table"]
fn randomised_rigs_confusion_table() {
    // `SURVEY_SEED=2021` draws another 30 rigs (magnitudes, mismatches, noise) of the same
    // classes: rigs the development did not see.
    let seed: u64 = std::env::var("SURVEY_SEED")
        .ok()
        .and_then(|v| v.trim().parse().ok())
        .unwrap_or(2020);
    let cases = cases(seed);
    let mut rows = Vec::new();
    let mut params_total = 0;
    let mut params_in = 0;
    let mut misses = Vec::new();
    let mut replay_ok = 0;
    let mut replay_ok_before_stops = 0;
    let started = std::time::Instant::now();
    // `SURVEY_CASES=1,2,19` runs only those cases (for development; the table then counts them);
    // `SURVEY_RATE_HZ=200` samples the records at 200 Hz instead of 1 kHz; `SURVEY_OUT=dir`
    // writes each case's report (below).
    let only: Option<Vec<usize>> = std::env::var("SURVEY_CASES")
        .ok()
        .map(|v| v.split(',').filter_map(|s| s.trim().parse().ok()).collect());
    for (i, c) in cases.iter().enumerate() {
        if only.as_ref().is_some_and(|o| !o.contains(&i)) {
            continue;
        }
        let recs = records_of(seed, i, c);
        let t0 = std::time::Instant::now();
        let r = match declared_daq_filter() {
            Some(start) => super::rig::calibrate_from(&start, &recs),
            None => calibrate_paper(&recs),
        };
        let secs = t0.elapsed().as_secs_f64();
        for (name, v, s, t) in checked_parameters(c, &r) {
            params_total += 1;
            if (v - t).abs() <= 3.0 * s {
                params_in += 1;
            } else {
                misses.push(format!(
                    "case {i} ({}): {name} = {v:.6e} ± {s:.2e}, truth {t:.6e} ({:.1}σ)",
                    c.label,
                    (v - t).abs() / s
                ));
            }
        }
        let (nominal, after) = replayed_above_noise(&r, &recs);
        let halved = (0..2).all(|k| after[k] <= 0.5 * nominal[k]);
        replay_ok += usize::from(halved);
        // The same up to the records' end-stop contacts, where a record reaches one.
        let before_stops = replayed_above_noise_before_stops(&r, &recs);
        let halved_before_stops =
            before_stops.map_or(halved, |(n, a)| (0..2).all(|k| a[k] <= 0.5 * n[k]));
        replay_ok_before_stops += usize::from(halved_before_stops);
        let stops = before_stops.map_or(String::new(), |(n, a)| {
            format!(
                " (up to the end-stop contacts: u {:.1}→{:.1} µm, ÿ {:.3}→{:.3} m/s²)",
                1e6 * n[0],
                1e6 * a[0],
                n[1],
                a[1]
            )
        });
        // `SURVEY_OUT=dir` writes each case's report, calibrated.toml and plots into
        // `dir/case-NN`, and its records into `dir/case-NN/records` (for development: to look at
        // a case's residuals, or to replay its records with the CLI).
        if let Ok(out) = std::env::var("SURVEY_OUT") {
            let dir = std::path::Path::new(&out).join(format!("case-{i:02}"));
            identify::report::write_all(&r, &dir, Some(secs)).expect("report written");
            write_records(&recs, &dir.join("records"));
        }
        if only.is_some() {
            eprintln!(
                "case {i} in full (truth: cd {:.6}, tau {:.6} s): {}",
                c.cd,
                c.tau,
                super::rig::summary(&r)
            );
            for n in &r.notes {
                eprintln!("  note: {n}");
            }
            for e in &r.effects {
                eprintln!(
                    "  {}: {:?} ± {:?}",
                    e.effect.name(),
                    e.params,
                    e.uncertainties
                );
            }
        }
        let verdict_ok = r.verdict == c.class.right_verdict();
        let fx_ok = effects_right(c, &r);
        eprintln!(
            "case {i:2} {:<30} {:<45} verdict {:<18} {} effects {:?} proposed {:?} (leaving out {:?}, adding {:?}) drifts {:?} sensors {:?}; u {:.1}→{:.1} µm, ÿ {:.3}→{:.3} m/s² above noise{stops}; {secs:.1} s",
            c.class.name(),
            c.label,
            r.verdict.name(),
            if verdict_ok && fx_ok { "ok" } else { "WRONG" },
            effect_names(&r),
            r.proposed
                .iter()
                .map(|t| {
                    // Its size (the direction term also has the travel it builds over).
                    let (k, v) = t
                        .params
                        .iter()
                        .find(|(k, _)| !k.contains("width"))
                        .expect("a sizing parameter");
                    format!("{} {v:.4e} ± {:.1e}", t.name, t.uncertainties[k])
                })
                .collect::<Vec<_>>(),
            r.proposed_leaves_out
                .iter()
                .map(|l| l.name.as_str())
                .collect::<Vec<_>>(),
            r.proposed_adds
                .iter()
                .map(|e| e.effect.name())
                .collect::<Vec<_>>(),
            r.drifts
                .iter()
                .map(|d| d.parameter.as_str())
                .collect::<Vec<_>>(),
            r.sensors
                .iter()
                .map(|s| format!("{} {}", s.channel, s.kind))
                .collect::<Vec<_>>(),
            1e6 * nominal[0],
            1e6 * after[0],
            nominal[1],
            after[1],
        );
        rows.push((
            c.class,
            r.verdict,
            verdict_ok,
            fx_ok,
            halved,
            c.label.clone(),
        ));
    }
    let verdicts = [
        Verdict::Explained,
        Verdict::NoMissingEffect,
        Verdict::Unexplained,
        Verdict::InsufficientData,
    ];
    let mut table = String::from(
        "| rig (truth) | right verdict | explained | no_missing_effect | unexplained | insufficient_data | effects right | replay ≤ ½ nominal |\n|---|---|---|---|---|---|---|---|\n",
    );
    for cl in Class::ALL {
        let these: Vec<_> = rows.iter().filter(|r| r.0 == cl).collect();
        let count = |v: Verdict| these.iter().filter(|r| r.1 == v).count();
        table.push_str(&format!(
            "| {} ({}) | `{}` | {} | {} | {} | {} | {}/{} | {}/{} |\n",
            cl.name(),
            these.len(),
            cl.right_verdict().name(),
            count(verdicts[0]),
            count(verdicts[1]),
            count(verdicts[2]),
            count(verdicts[3]),
            these.iter().filter(|r| r.3).count(),
            these.len(),
            these.iter().filter(|r| r.4).count(),
            these.len(),
        ));
    }
    let right = rows.iter().filter(|r| r.2).count();
    let both = rows.iter().filter(|r| r.2 && r.3).count();
    eprintln!(
        "\n{table}\nverdict right: {right}/{}; verdict and effects right: {both}/{}; \
         truth within 3σ: {params_in}/{params_total} fitted parameters; calibrated.toml \
         replayed leaves ≤ ½ the nominal error above noise on u and ÿ: {replay_ok}/{} \
         (whole records; up to the end-stop contacts, the part a calibration fits: \
         {replay_ok_before_stops}/{}); {:.0} s\nparameters outside 3σ:\n{}",
        rows.len(),
        rows.len(),
        rows.len(),
        rows.len(),
        started.elapsed().as_secs_f64(),
        misses.join("\n")
    );
    // A rig with an effect outside the library must never be called `explained`; over the
    // whole survey, the bars: at least 90 % of the fitted parameters within 3σ of
    // the truth, and (what the survey reached on 2026-11-27: 30/30, 72 of 72, 30/30) at most
    // one wrong verdict and one calibrated.toml that does not halve the nominal error.
    //
    // The six rigs with a library effect beside one outside it (added 2026-12-03) count for
    // the parameters' bar but not for the verdicts' and replays' bars, which guard what the
    // first 30 reached: on the development draw their replay falls short in two of six
    // (case 30, ÿ above 25 Hz; case 33, compliance and the drift both missed) — a known
    // failure the README lists, printed in the table above. Every rig counts for the issue's
    // bar on verdict and effects together: right in at least 9 of 10.
    if only.is_none() {
        assert!(
            10 * params_in >= 9 * params_total,
            "truth within 3σ: {params_in}/{params_total}"
        );
        assert!(
            10 * both >= 9 * rows.len(),
            "verdict and effects right: {both}/{}",
            rows.len()
        );
        let drawn: Vec<_> = rows.iter().filter(|r| r.0 != Class::Mixed).collect();
        let right = drawn.iter().filter(|r| r.2).count();
        assert!(
            right + 1 >= drawn.len(),
            "verdict right: {right}/{}",
            drawn.len()
        );
        let halved = drawn.iter().filter(|r| r.4).count();
        assert!(
            halved + 1 >= drawn.len(),
            "replay halved: {halved}/{} (the first 30 rigs)",
            drawn.len()
        );
    }
    for r in &rows {
        assert!(
            !(matches!(r.0, Class::Outside | Class::Mixed) && r.1 == Verdict::Explained),
            "{}: an effect outside the library was called explained",
            r.5
        );
    }
}

/// The paper's parameters with the rig's anti-alias filter declared, when the survey's records
/// pass through one (`SURVEY_DAQ_AA_HZ`) and `SURVEY_DAQ_AA_DECLARED=1` says the user declares
/// it (a second-order Butterworth, as the rig's); `None` otherwise.
fn declared_daq_filter() -> Option<seat_twin::params::Params> {
    let hz: f64 = std::env::var("SURVEY_DAQ_AA_HZ")
        .ok()?
        .trim()
        .parse()
        .ok()?;
    (std::env::var("SURVEY_DAQ_AA_DECLARED").ok()?.trim() == "1").then(|| {
        let mut p = seat_twin::params::Params::paper();
        p.sensors.antialias_hz = hz;
        p.sensors.antialias_order = 2.0;
        p
    })
}

/// The records of case `i` (`c`) of the draw `seed`: noise seeds 500 + i for the README's
/// table (2020), others for other draws; sampled at 1 kHz, or at `SURVEY_RATE_HZ` (a divisor
/// of the rig's 20 kHz, 200 Hz to 10 kHz) for the survey at other rates.
pub(super) fn records_of(seed: u64, i: usize, c: &Case) -> Vec<seat_twin::dataset::Record> {
    let rate_hz = std::env::var("SURVEY_RATE_HZ")
        .ok()
        .and_then(|v| v.trim().parse().ok())
        .filter(|r: &f64| (200.0..=10_000.0).contains(r))
        .unwrap_or(1000.0);
    records_at(seed, i, c, rate_hz)
}

/// [`records_of`] at `rate_hz`.
pub(super) fn records_at(
    seed: u64,
    i: usize,
    c: &Case,
    rate_hz: f64,
) -> Vec<seat_twin::dataset::Record> {
    let noise_seed = 500u64.wrapping_add(seed.wrapping_sub(2020).wrapping_mul(1000));
    // `SURVEY_DAQ_AA_HZ=80` records every measured channel through a data acquisition's
    // anti-alias filter at that corner (a second-order Butterworth).
    let mut fx = c.fx;
    fx.daq_antialias_hz = std::env::var("SURVEY_DAQ_AA_HZ")
        .ok()
        .and_then(|v| v.trim().parse().ok());
    campaign_of(c.cd, c.tau, fx, noise_seed + i as u64, c.pressures, rate_hz)
}

/// The raw error above the noise on u and ÿ ([`above_noise`]) of `recs` replayed with the
/// paper's preset and with `r`'s calibrated.toml, saved, loaded and replayed independently.
pub(super) fn replayed_above_noise(
    r: &CalibrationReport,
    recs: &[seat_twin::dataset::Record],
) -> ([f64; 2], [f64; 2]) {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("calibrated.toml");
    identify::report::calibrated_preset(r)
        .save(&path)
        .expect("save");
    let cal = Preset::load(&path).expect("load");
    let mut nominal = Preset::paper();
    if let Some(start) = declared_daq_filter() {
        nominal.params = start;
    }
    (above_noise(&nominal, recs), above_noise(&cal, recs))
}

/// [`replayed_above_noise`] of `recs` cut at their first end-stop contact, as a calibration
/// cuts them (`identify::data::before_end_stops`), or `None` when no record reaches a stop.
fn replayed_above_noise_before_stops(
    r: &CalibrationReport,
    recs: &[seat_twin::dataset::Record],
) -> Option<([f64; 2], [f64; 2])> {
    let stroke = Preset::paper().params.plant.cylinder.stroke_m;
    let (cut, notes) = identify::data::before_end_stops(recs, stroke);
    (!notes.is_empty()).then(|| replayed_above_noise(r, &cut))
}

/// Writes `recs` as CSV files into `dir` (named as the records are), for the CLI to read.
pub(super) fn write_records(recs: &[seat_twin::dataset::Record], dir: &std::path::Path) {
    std::fs::create_dir_all(dir).expect("records dir");
    for rec in recs {
        let mut cols: Vec<(&str, &Vec<f64>)> = vec![("t", &rec.t)];
        for (name, col) in [
            ("v_in", &rec.v_in),
            ("u", &rec.u),
            ("x", &rec.x),
            ("xdd", &rec.xdd),
            ("ydd", &rec.ydd),
            ("p1", &rec.p1),
            ("p2", &rec.p2),
        ] {
            if let Some(c) = col {
                cols.push((name, c));
            }
        }
        let header: Vec<&str> = cols.iter().map(|(n, _)| *n).collect();
        let rows = (0..rec.t.len()).map(|i| cols.iter().map(|(_, c)| c[i]).collect());
        seat_twin::dataset::write_csv_atomic(&dir.join(&rec.path), &header, &[], rows)
            .expect("record written");
    }
}
