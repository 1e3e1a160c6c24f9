//! The report's section on the terms proposed beyond the library
//! ([`crate::identify::proposed`]): the terms in words, the library's effects found beside
//! them and those the twin with them leaves out.

use super::super::CalibrationReport;
use super::super::result::LeftOut;
use super::super::units::format_parameter;
use std::fmt::Write as _;

/// The library's effects the twin with the proposed terms (`calibrated.toml`) carries: the
/// library's twin's, but those it leaves out, and those found beside the terms.
pub fn proposed_twin_effects(r: &CalibrationReport) -> Vec<&'static str> {
    r.effects
        .iter()
        .filter(|e| {
            !r.proposed_leaves_out
                .iter()
                .any(|l| l.name == e.effect.name())
        })
        .chain(&r.proposed_adds)
        .map(|e| e.effect.name())
        .collect()
}

/// The terms proposed beyond the library, in words, and what they leave.
pub(super) fn proposed_markdown(s: &mut String, r: &CalibrationReport) {
    let Some(raw) = &r.raw_error_proposed else {
        return;
    };
    let _ = writeln!(
        s,
        "## Proposed beyond the library\n\n\
         The library's effects leave a residual above the noise; a search over corrections \
         outside the library (Cd against spool opening, flow gain per direction and per \
         metering edge, a spring, quadratic damping, a turbulent leakage, a lag and a drift of \
         the valve command; ranked by ΔBIC, each kept only if it lowers the held-out error) \
         proposes:\n"
    );
    for t in &r.proposed {
        let _ = writeln!(s, "- **{}**: {}. {}.", t.name, t.description, t.evidence);
    }
    let declared: Vec<String> = r
        .proposed_calibrated
        .iter()
        .map(|v| format_parameter(&v.name, v.value, v.std))
        .collect();
    let _ = writeln!(
        s,
        "\nWith {}: {}. The verdict stays `{}`: it judges the library. `calibrated.toml` \
         carries the proposed terms, with the declared parameters re-fitted alongside them \
         ({}), and `seat-twin replay` applies them.\n",
        if r.proposed.len() == 1 {
            "this term"
        } else {
            "these terms"
        },
        if raw.at_floor() {
            format!(
                "every raw channel of every record is at its noise floor ({})",
                raw.summary()
            )
        } else {
            format!(
                "the residual is smaller but not at the floor everywhere: {}",
                raw.summary()
            )
        },
        r.verdict.name(),
        declared.join(", ")
    );
    if !r.proposed_adds.is_empty() {
        let it = if r.proposed_adds.len() == 1 {
            "it"
        } else {
            "them"
        };
        let _ = writeln!(
            s,
            "Beside the proposed terms the library was searched again, and found what the \
             effect it lacks had hidden from it:\n"
        );
        for e in &r.proposed_adds {
            let _ = writeln!(
                s,
                "- **{}** ({}): {}.",
                e.effect.name(),
                e.params
                    .iter()
                    .map(|(k, v)| {
                        let std = e.uncertainties.get(k).copied().unwrap_or(f64::NAN);
                        format_parameter(k, *v, std)
                    })
                    .collect::<Vec<_>>()
                    .join(", "),
                e.evidence
            );
        }
        let _ = writeln!(
            s,
            "\nThe twin with the proposed terms (`calibrated.toml`) carries {it}; the library's \
             twin, which the verdict judges and the effects below list, does not: alone, the \
             library did not find {it}.\n",
        );
    }
    left_out_markdown(s, r);
    let _ = writeln!(
        s,
        "Library effects of the twin with the proposed terms: {}.\n",
        match proposed_twin_effects(r) {
            names if names.is_empty() => "none".to_string(),
            names => names
                .iter()
                .map(|n| format!("`{n}`"))
                .collect::<Vec<_>>()
                .join(", "),
        }
    );
}

/// The library's effects the twin with the proposed terms leaves out, by the reason: the
/// criterion's (they no longer earn their parameters) and the records' (each record fitted
/// alone does not say the effect is there).
fn left_out_markdown(s: &mut String, r: &CalibrationReport) {
    let (by_records, by_criterion): (Vec<&LeftOut>, Vec<&LeftOut>) = r
        .proposed_leaves_out
        .iter()
        .partition(|l| l.by_records.is_some());
    if !by_criterion.is_empty() {
        let names: Vec<String> = by_criterion
            .iter()
            .map(|l| {
                format!(
                    "`{}` (ΔBIC {:+.1} for keeping it; held-out weighted RMS {:.3} → {:.3} and \
                     the raw error's worst band {:.1}× → {:.1}× its floor without it)",
                    l.name,
                    l.score,
                    l.validation[0],
                    l.validation[1],
                    l.raw_worst[0],
                    l.raw_worst[1]
                )
            })
            .collect();
        let one = names.len() == 1;
        let _ = writeln!(
            s,
            "Beside the proposed terms the library's {} no longer {} (an effect is added \
             only where the criterion and the held-out records both favour it, and is kept \
             where the raw error needs it): the library had added \
             {} to follow the effect it lacks. The twin with the proposed terms \
             (`calibrated.toml`) leaves {2} out; the effects listed below are the library's \
             twin, which the verdict judges.\n",
            names.join(" and "),
            if one {
                "earns its parameters"
            } else {
                "earn their parameters"
            },
            if one { "it" } else { "them" },
        );
    }
    for l in by_records {
        let Some(b) = &l.by_records else { continue };
        let unit = super::super::units::format_value;
        let values: Vec<String> = b
            .per_record
            .iter()
            .map(|(file, v)| format!("{file} {}", unit(&b.parameter, *v)))
            .collect();
        let _ = writeln!(
            s,
            "The joint fit keeps the library's `{}` beside the proposed terms (ΔBIC {:+.1} for \
             keeping it), but the records, each fitted alone (beside its own Cd and τ), do not \
             say it is there: `{}` comes out at {} (χ²/dof = {:.1}), a mean of {} ± {}, \
             {:.1}σ from none ({}). An effect of the hardware is the same on every record; \
             this one takes the size each record asks for, to take up what a proposed term's \
             form misses. The twin with the proposed terms (`calibrated.toml`) leaves it out, \
             and is the worse for it on these records: held-out weighted RMS {:.3} → {:.3}, \
             the raw error's worst band {:.1}× → {:.1}× its floor. The effects listed below \
             are the library's twin, which the verdict judges.\n",
            l.name,
            l.score,
            b.parameter,
            values.join(", "),
            b.chi2_per_dof,
            unit(&b.parameter, b.mean),
            unit(&b.parameter, b.mean_uncertainty),
            (b.mean - b.none).abs() / b.mean_uncertainty,
            unit(&b.parameter, b.none),
            l.validation[0],
            l.validation[1],
            l.raw_worst[0],
            l.raw_worst[1]
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::identify::result::{AddedEffect, LeftOut};
    use crate::identify::{EffectId, data};
    use crate::params::Params;

    fn added(effect: EffectId) -> AddedEffect {
        AddedEffect {
            effect,
            params: Default::default(),
            uncertainties: Default::default(),
            evidence: String::new(),
        }
    }

    /// The twin with the proposed terms carries the library's effects but those it leaves
    /// out, and those found beside the terms (the library's twin does not).
    #[test]
    fn the_proposed_twin_leaves_out_the_followers_and_adds_what_was_found_beside() {
        let empty = data::DataCheck {
            records: Vec::new(),
            notes: Vec::new(),
            missing: Vec::new(),
        };
        let mut r = data::insufficient_data(&Params::paper(), empty);
        r.effects = vec![added(EffectId::ValveOffset), added(EffectId::Leakage)];
        r.proposed_leaves_out = vec![LeftOut {
            name: "valve_offset".into(),
            score: 5.7,
            validation: [0.545, 0.544],
            raw_worst: [1.45, 1.44],
            by_records: None,
        }];
        assert_eq!(proposed_twin_effects(&r), ["leakage"]);
        r.proposed_adds = vec![added(EffectId::Friction)];
        assert_eq!(proposed_twin_effects(&r), ["leakage", "friction"]);
        r.proposed_leaves_out.clear();
        assert_eq!(
            proposed_twin_effects(&r),
            ["valve_offset", "leakage", "friction"]
        );
    }

    /// An effect left out by the criterion and one left out by the records are told apart in
    /// words, the second with each record's size, the mean's distance from none and what
    /// leaving it out costs the fit.
    #[test]
    fn effects_left_out_by_the_records_are_said_to_be_so_with_each_records_size() {
        let empty = data::DataCheck {
            records: Vec::new(),
            notes: Vec::new(),
            missing: Vec::new(),
        };
        let mut r = data::insufficient_data(&Params::paper(), empty);
        let by_criterion = LeftOut {
            name: "supply_sag".into(),
            score: 4.4,
            validation: [0.707, 0.707],
            raw_worst: [1.47, 1.47],
            by_records: None,
        };
        let by_records = LeftOut {
            name: "valve_offset".into(),
            score: -7.2,
            validation: [0.783, 0.825],
            raw_worst: [11.6, 12.3],
            by_records: Some(crate::identify::result::SizeByRecord {
                parameter: "effects.valve_offset.bias_v".into(),
                none: 0.0,
                per_record: [
                    ("a.csv".to_string(), -1.7e-3),
                    ("b.csv".to_string(), 3.5e-3),
                ]
                .into_iter()
                .collect(),
                mean: 2e-4,
                mean_uncertainty: 1e-3,
                chi2_per_dof: 14.4,
            }),
        };
        r.proposed_leaves_out = vec![by_criterion, by_records];
        let mut s = String::new();
        left_out_markdown(&mut s, &r);
        assert!(s.contains("library's `supply_sag` (ΔBIC +4.4"), "{s}");
        assert!(s.contains("no longer earns its parameters"), "{s}");
        assert!(s.contains("keeps the library's `valve_offset`"), "{s}");
        assert!(s.contains("do not say it is there"), "{s}");
        assert!(
            s.contains("a.csv") && s.contains("b.csv") && s.contains("χ²/dof = 14.4"),
            "{s}"
        );
        assert!(s.contains("0.2σ from none"), "{s}");
        assert!(s.contains("11.6× → 12.3×"), "{s}");
        assert!(!s.contains("  "), "{s}");
    }
}
