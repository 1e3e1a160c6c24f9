//! A term beyond the library and an effect of the library tried together, where each hides
//! the other (issue 20, item 3: "any two effects at once").
//!
//! A rig with a soft hose and a drifting valve null leaves two residuals, each large enough
//! to keep the other's fit from clearing its bars: the library's compliance removes a quarter
//! of the residual but raises the held-out error under the drift (2.945 → 2.983), and the
//! drift term, which the criterion favours (ΔBIC −19.5), removes only 8 % under the missing
//! compliance, under the 10 % a term needs. Alone, each is refused; the mass then stands in
//! for the oil column's stiffness. So where no term clears the bars alone in the search's
//! first round (later rounds search the library again beside the kept terms instead) but the
//! criterion favours one, that term is fitted together with each effect the library's last round
//! favoured (ΔBIC < 0) and did not add ([`partners`]), every knob free. The pair is kept
//! when, together, it clears the bars a single term must (ΔBIC < 0, the gain bar, the
//! held-out records lower by [`CalibrationOptions::min_validation_gain`]), and each member
//! earns its place in it: the pair fitted again without either member is worse by the
//! criterion and on the held-out records by the same margin. The term is proposed, the
//! effect goes into the twin with the proposed terms only ([`super::proposed::Proposal::beside`]);
//! the library's twin and its verdict are left as they are.

use super::context::{SearchContext, validation_rms};
use super::effects::{self, Added, EffectSearch};
use super::fit::{self, FitResult, Knob, Screened};
use super::proposed::CorrectionId;
use super::starts::best_screened;
use super::{CalibrationOptions, EffectId, IdentifyError};
use crate::params::Params;

/// Most library effects a term is paired with: the criterion's best of the library's last
/// round that it did not add.
pub const MAX_PARTNERS: usize = 2;

/// The library's effects to pair a term with: those of the library search's last round that
/// the criterion favoured (ΔBIC < 0) and that were not added, best first, at most
/// [`MAX_PARTNERS`].
pub fn partners(search: &EffectSearch) -> Vec<EffectId> {
    let Some(last) = search.candidates.iter().map(|c| c.round).max() else {
        return Vec::new();
    };
    let mut favoured: Vec<(EffectId, f64)> = search
        .candidates
        .iter()
        .filter(|c| c.round == last && c.score < 0.0)
        .filter(|c| !search.added.iter().any(|a| a.effect == c.effect))
        .map(|c| (c.effect, c.score))
        .collect();
    favoured.sort_by(|a, b| a.1.total_cmp(&b.1));
    favoured
        .into_iter()
        .map(|f| f.0)
        .take(MAX_PARTNERS)
        .collect()
}

/// A pair kept: the term with its evidence (as [`super::proposed::Proposal::kept`] holds it),
/// the library's effect (as [`Added`]), and their joint fit.
pub struct Pair {
    /// The term, its ΔBIC and gain together with the effect, and the held-out error
    /// `[before, after]`.
    pub term: (CorrectionId, f64, f64, [f64; 2]),
    /// The library's effect, with the same evidence.
    pub effect: Added,
    /// The joint fit.
    pub fit: FitResult,
    /// Its knobs.
    pub knobs: Vec<Knob>,
}

/// Whether the pair's fit `with` (of `k_with` knobs, held-out RMS `val_with`) beats the
/// fit without one member (`without`, `k_without` knobs, `val_without`) by the add rule's
/// bars: a lower criterion and a held-out RMS lower by the validation margin.
fn earns(
    cx: &SearchContext<'_>,
    (with, k_with, val_with): (&FitResult, usize, f64),
    (without, k_without, val_without): (&FitResult, usize, f64),
) -> bool {
    let score = cx.bic.value(with.rss, k_with) - cx.bic.value(without.rss, k_without);
    effects::earns_place(score, [val_with, val_without], cx.options)
}

/// `term` (its screening fit `screened` on top of `current`, of `knobs`, whose held-out RMS
/// is `current_val`) fitted together with each of `partners`; the best pair by the criterion
/// that clears the bars (module docs), and a note for each pair tried.
pub fn try_pairs(
    cx: &SearchContext<'_>,
    (current, knobs, current_val): (&FitResult, &[Knob], f64),
    (term, screened): (CorrectionId, &Screened),
    partners: &[EffectId],
) -> Result<(Option<Pair>, Vec<String>), IdentifyError> {
    let (ev, options): (_, &CalibrationOptions) = (cx.ev, cx.options);
    let screen_knobs: Vec<Knob> = knobs
        .iter()
        .copied()
        .filter(|k| *k != Knob::Mass)
        .chain(term.knobs().iter().copied())
        .collect();
    let (mut best, mut notes): (Option<Pair>, Vec<String>) = (None, Vec::new());
    for &effect in partners {
        if effect.enabled(&current.params) {
            continue;
        }
        let mut ks = screen_knobs.clone();
        ks.extend_from_slice(effect.knobs());
        let Some(start) =
            best_screened(ev, &screened.params, effect, &ks, options.screen_iterations)?
        else {
            continue;
        };
        let mut all: Vec<Knob> = knobs.to_vec();
        all.extend_from_slice(term.knobs());
        all.extend_from_slice(effect.knobs());
        let joint = fit::fit(
            ev,
            &start.params,
            &all,
            options.max_iterations,
            cx.bic.ratio(),
        )?;
        let val = validation_rms(&joint.params, cx.validation)?;
        let score = cx.bic.value(joint.rss, all.len()) - cx.bic.value(current.rss, knobs.len());
        let gain = 1.0 - joint.rss / current.rss;
        let clears = gain >= options.min_relative_gain
            && effects::earns_place(score, [val, current_val], options);
        // Each member earns its place: the pair fitted again without it.
        let mut members = String::new();
        let mut each = clears;
        if clears {
            // The pair fitted again from `p` without the knobs `out`: (fit, knobs, held-out).
            let without =
                |p: Params, out: &[Knob]| -> Result<(FitResult, usize, f64), IdentifyError> {
                    let ks: Vec<Knob> = all.iter().copied().filter(|k| !out.contains(k)).collect();
                    let f = fit::fit(ev, &p, &ks, options.max_iterations, cx.bic.ratio())?;
                    let v = validation_rms(&f.params, cx.validation)?;
                    Ok((f, ks.len(), v))
                };
            let mut p = joint.params;
            term.knob().set(&mut p, 0.0);
            let (no_term, k_term, v_term) = without(p, term.knobs())?;
            let mut p = joint.params;
            effect.disable(&mut p);
            let (no_effect, k_effect, v_effect) = without(p, effect.knobs())?;
            let with = (&joint, all.len(), val);
            each = earns(cx, with, (&no_term, k_term, v_term))
                && earns(cx, with, (&no_effect, k_effect, v_effect));
            members = format!(
                "; without `{}` the held-out RMS is {v_term:.3}, without `{}` {v_effect:.3}",
                term.name(),
                effect.name()
            );
        }
        notes.push(format!(
            "beyond the library, `{}` and the library's `{}` fitted together: ΔBIC {score:.1}, \
             {:.1} % of the residual, held-out weighted RMS {current_val:.3} → {val:.3}{members}: {}",
            term.name(),
            effect.name(),
            100.0 * gain,
            if each {
                "kept, each hiding the other alone"
            } else if clears {
                "not kept, one of them does not earn its place in the pair"
            } else {
                "not kept"
            }
        ));
        if each && best.as_ref().is_none_or(|b| score < b.term.1) {
            best = Some(Pair {
                term: (term, score, gain, [current_val, val]),
                effect: Added {
                    effect,
                    score,
                    gain,
                    validation: [current_val, val],
                    raw: None,
                },
                fit: joint,
                knobs: all,
            });
        }
    }
    Ok((best, notes))
}
