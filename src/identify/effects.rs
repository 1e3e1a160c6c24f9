//! The effect search: each round fits every remaining candidate effect on top of the current
//! model and ranks them by ΔBIC ([`rank_candidates`]); the best is re-fitted with all
//! parameters and kept only if it lowers the held-out error ([`try_effect`]); [`search`] runs
//! the rounds.

#[cfg(doc)]
use super::CalibrationOptions;
use super::context::{SearchContext, validation_rms, worst_raw_ratio};
use super::data::Campaign;
use super::fit::{self, Evaluator, FitResult, FittedValue, Knob, Screened};
use super::progress::Stage;
use super::refine::{self, REFINEMENT_MAX_RAW_RATIO, REFINEMENT_MIN_DBIC};
use super::replay::{PreparedRecord, StepRule};
use super::result::CandidateScore;
use super::starts::best_screened;
use super::{EffectId, IdentifyError};
use crate::params::Params;
use crate::simulation::step_for_rate;
use rayon::prelude::*;

/// Why two effects can be confounded, when the physics says so (for the ambiguity note).
fn confounding_hint(a: EffectId, b: EffectId, recs: &[PreparedRecord]) -> &'static str {
    let pair = |x, y| (a == x && b == y) || (a == y && b == x);
    let pressures = recs.iter().any(|r| r.p_meas_f.iter().any(|p| p.is_some()));
    if pair(EffectId::Friction, EffectId::SupplySag) && !pressures {
        " At steady flow a supply droop r and a viscous friction b reduce the velocity alike \
         (r ≈ b/A²); the chamber pressures p1, p2 separate them (sag lowers (p1 + p2)/2, \
         friction shifts p1 − p2): record them to decide."
    } else {
        ""
    }
}

/// A candidate effect fitted on top of the current model in one round.
#[derive(Debug, Clone)]
pub struct Ranked {
    /// The effect.
    pub effect: EffectId,
    /// Its screening fit (current knobs but the mass, and the effect's).
    pub fit: Screened,
    /// ΔBIC against the current model (negative = better).
    pub score: f64,
    /// Share of the current residual sum of squares it removes [-].
    pub gain: f64,
}

/// Fits every effect of `remaining` on top of `current` (in parallel; the mass stays fixed)
/// with [`CalibrationOptions::screen_iterations`] Jacobians, and ranks them by ΔBIC, best
/// first.
///
/// The screening replays at [`StepRule::Screening`] (the integrator's stability limit, not
/// the finer step a friction's reversals ask for). Where the current model has a friction
/// that asks for the finer step, it is first fitted again at the screening step (one short
/// fit), and the candidates start from there and are held against its residual; every
/// screening replay of the round then takes half the steps or fewer.
pub fn rank_candidates(
    cx: &SearchContext<'_>,
    current: &FitResult,
    knobs: &[Knob],
    remaining: &[EffectId],
    round: usize,
) -> Result<Vec<Ranked>, IdentifyError> {
    let (bic, options) = (&cx.bic, cx.options);
    let screening = Evaluator {
        records: cx.ev.records,
        monitor: cx.ev.monitor,
        step: StepRule::Screening,
    };
    let ev = &screening;
    ev.monitor
        .enter(Stage::Candidates { round }, remaining.len());
    let screen_knobs: Vec<Knob> = knobs.iter().copied().filter(|k| *k != Knob::Mass).collect();
    // The current model at the screening step: itself where that is its step, else fitted
    // again there (its own knobs, the screening's Jacobians), so that no candidate is
    // credited with what the others' knobs gain from the coarser step alone.
    let same_step = ev.records.iter().all(|r| {
        let rate = 1.0 / r.dt;
        step_for_rate(StepRule::Screening.largest_step_s(&current.params), rate)
            == step_for_rate(StepRule::Resolving.largest_step_s(&current.params), rate)
    });
    let reference = if same_step {
        Screened {
            params: current.params,
            rss: current.rss,
        }
    } else {
        fit::screen(
            ev,
            &current.params,
            &screen_knobs,
            options.screen_iterations,
        )?
    };
    let results: Vec<Result<(EffectId, Screened), IdentifyError>> = remaining
        .par_iter()
        .map(|&e| {
            let mut ks = screen_knobs.clone();
            ks.extend_from_slice(e.knobs());
            // From each start, keeping the fit with the smallest residual.
            let best = best_screened(ev, &reference.params, e, &ks, options.screen_iterations)?;
            ev.monitor.advance();
            best.map(|f| (e, f)).ok_or(IdentifyError::Cancelled)
        })
        .collect();
    ev.monitor.check()?;
    let mut ranked = Vec::with_capacity(results.len());
    for r in results {
        let (effect, fit) = r?;
        let k = effect.knobs().len();
        let score = bic.value(fit.rss, knobs.len() + k) - bic.value(reference.rss, knobs.len());
        let gain = 1.0 - fit.rss / reference.rss;
        ranked.push(Ranked {
            effect,
            fit,
            score,
            gain,
        });
    }
    ranked.sort_by(|a, b| a.score.total_cmp(&b.score));
    Ok(ranked)
}

/// An effect re-fitted with all parameters, and its validation.
#[derive(Debug, Clone)]
pub struct Trial {
    /// The re-fit (the current knobs and the effect's).
    pub refit: FitResult,
    /// The knobs of the re-fit.
    pub knobs: Vec<Knob>,
    /// Weighted RMS on the held-out records with the re-fit.
    pub validation_rms: f64,
    /// Whether it lowers the held-out error by at least
    /// [`CalibrationOptions::min_validation_gain`] (a NaN error does not).
    pub improves: bool,
    /// Refinements of the effect's law ([`REFINEMENTS`](refine::REFINEMENTS)) the first
    /// re-fit left uncertain and the criterion did not keep, with that fit's value and
    /// uncertainty: the plain law was re-fitted instead.
    pub pinned: Vec<FittedValue>,
}

/// Re-fits all of `knobs` and the effect of `best` from its screening fit, with
/// [`CalibrationOptions::max_iterations`] Jacobians, and validates the result on the
/// held-out records against `current_val`.
pub fn try_effect(
    cx: &SearchContext<'_>,
    campaign: &Campaign,
    preset: &Params,
    best: &Ranked,
    knobs: &[Knob],
    round: usize,
    current_val: f64,
) -> Result<Trial, IdentifyError> {
    let (ev, options) = (cx.ev, cx.options);
    ev.monitor.enter(
        Stage::Refit {
            round,
            effect: best.effect,
        },
        options.max_iterations + 1,
    );
    let mut trial_knobs = knobs.to_vec();
    trial_knobs.extend_from_slice(best.effect.knobs());
    // Every re-fit here: all of `knobs` from `p`, with the full Jacobian budget.
    let refit_from =
        |p: &Params, knobs: &[Knob]| fit::fit(ev, p, knobs, options.max_iterations, cx.bic.ratio());
    let mut refit = refit_from(&best.fit.params, &trial_knobs)?;
    // The mass was fitted before the effect was there and may have taken up part of it
    // (friction alone: 10.2 kg against the rig's 11.7, in a valley whose weighted residual is
    // a quarter above the one near the truth): the re-fit also starts from the declared mass,
    // and the better of the two is kept.
    if trial_knobs.contains(&Knob::Mass) {
        let mut declared_mass = best.fit.params;
        declared_mass.plant.body.mass_kg = preset.plant.body.mass_kg;
        if declared_mass != best.fit.params {
            let again = refit_from(&declared_mass, &trial_knobs)?;
            if again.rss < refit.rss {
                refit = again;
            }
        }
    }
    if best.effect == EffectId::Leakage {
        refit = refine::with_growth_starts(cx, refit, &trial_knobs)?;
    }
    let weighed = refine::weigh(cx, campaign, preset, refit, trial_knobs)?;
    let (refit, trial_knobs, pinned) = (weighed.fit, weighed.knobs, weighed.pinned);
    let validation_rms = validation_rms(&refit.params, cx.validation)?;
    ev.monitor.advance();
    Ok(Trial {
        improves: validation_rms < (1.0 - options.min_validation_gain) * current_val,
        refit,
        knobs: trial_knobs,
        validation_rms,
        pinned,
    })
}

/// The add rule's two bars for a model part already fitted both ways: the criterion favours
/// it (`score`, the ΔBIC of keeping it, < 0) and the held-out weighted RMS
/// `[with, without]` is lower with it by [`CalibrationOptions::min_validation_gain`] (a NaN
/// does not pass). What a library effect beside the proposed terms
/// ([`super::leave_out::criterion_leaves_out`]) and each member of a pair
/// ([`super::pair`]) must show to stay.
pub fn earns_place(
    score: f64,
    [with, without]: [f64; 2],
    options: &super::CalibrationOptions,
) -> bool {
    score < 0.0 && with < (1.0 - options.min_validation_gain) * without
}

/// An effect the search added.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Added {
    /// The effect.
    pub effect: EffectId,
    /// Its ΔBIC when added.
    pub score: f64,
    /// Share of the residual it removed [-].
    pub gain: f64,
    /// Held-out weighted RMS `[before, after]` adding it.
    pub validation: [f64; 2],
    /// Where it was added on the raw error's terms (under the criterion's bars, while the
    /// raw error was above its limit): that error's worst band `[before, after]` in units of
    /// its floor, and, where its sizes trade off, the worst band with it fitted out again.
    pub raw: Option<RawTerms>,
}

/// The raw error's evidence for an effect added on its terms ([`Added::raw`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RawTerms {
    /// The raw error's worst band `[before, after]` adding it \[× its floor\].
    pub worst: [f64; 2],
    /// The worst band of the model without it, fitted again from the re-fit's other
    /// parameters, where its sizes trade off \[× its floor\].
    pub without: Option<f64>,
}

/// What the effect search found.
#[derive(Debug, Clone)]
pub struct EffectSearch {
    /// The final fit (the declared fit if nothing was added), at the fit step.
    pub current: FitResult,
    /// Its knobs.
    pub knobs: Vec<Knob>,
    /// The effects added, in order.
    pub added: Vec<Added>,
    /// Every candidate's score, per round.
    pub candidates: Vec<CandidateScore>,
    /// Notes (rejected effects, ambiguous rounds).
    pub notes: Vec<String>,
}

/// The knobs that size `effect` (its others shape it): compliance has two, the chambers'
/// modulus and the hoses' (soft hoses beside stiff chambers leave the first at "off");
/// friction three, its Coulomb, viscous and Stribeck forces (a rig's friction may be mostly
/// one of them); every other effect its first.
pub fn size_knobs(effect: EffectId) -> &'static [Knob] {
    match effect {
        EffectId::Compliance => &[Knob::Compliance, Knob::HoseCompliance],
        EffectId::Friction => &[
            Knob::FrictionCoulomb,
            Knob::FrictionViscous,
            Knob::FrictionStribeck,
        ],
        e => &e.knobs()[..1],
    }
}

/// The value of size knob `k` that means "none" (θ = 0) in `params` \[SI\].
pub fn size_off(k: Knob, params: &Params) -> f64 {
    let mut p = *params;
    k.set(&mut p, 0.0);
    k.value(&p)
}

/// Why the re-fit `refit` leaves `effect` at no size of its own, if it does: none of its
/// sizes ([`size_knobs`]) determined (a 1-σ of at most half its value) and more than 2σ from
/// "off".
pub fn unsized_effect(refit: &FitResult, effect: EffectId) -> Option<String> {
    let size_of = |k: Knob| {
        let off = size_off(k, &refit.params);
        refit
            .values
            .iter()
            .find(|v| v.knob == k)
            .map(|v| (v, v.is_determined() && (v.value - off).abs() > 2.0 * v.std))
    };
    let sized: Vec<_> = size_knobs(effect)
        .iter()
        .filter_map(|&k| size_of(k))
        .collect();
    if sized.iter().any(|(_, ok)| *ok) {
        return None;
    }
    let shown: Vec<String> = sized
        .iter()
        .map(|(v, _)| super::units::format_parameter(&v.name, v.value, v.std))
        .collect();
    Some(format!(
        "its size is undetermined or within 2σ of none ({})",
        shown.join(", ")
    ))
}

/// `from` with `effect` switched off, fitted again in `knobs` (the effect's own left out):
/// where a re-fit moved the other parameters to a deeper valley of the model as it was.
fn fitted_without(
    cx: &SearchContext<'_>,
    from: &Params,
    effect: EffectId,
    knobs: &[Knob],
) -> Result<FitResult, IdentifyError> {
    let mut restart = *from;
    effect.disable(&mut restart);
    fit::fit(
        cx.ev,
        &restart,
        knobs,
        cx.options.max_iterations,
        cx.bic.ratio(),
    )
}

/// Rounds of [`rank_candidates`] and [`try_effect`] from the declared fit `start` (of
/// `knobs`): the best candidate is tried when its ΔBIC < 0 and it removes at least
/// [`CalibrationOptions::min_relative_gain`] of the residual
/// ([`CalibrationOptions::min_relative_gain_later`] after the first effect), and added when it
/// improves the held-out error.
///
/// While the raw error (the verdict's measure) is above its limit, a round's best that does
/// not qualify is still tried: the criterion's best if its ΔBIC < 0, else the candidate whose
/// screening fit lowers the raw error's worst band most, if by a quarter. Either is added only
/// if its re-fit lowers that band by a quarter, improves the held-out error and leaves every
/// uncertainty finite and its size determined: one of its sizes more than 2σ from none, or,
/// where its sizes trade off, the model without it (fitted again from the re-fit's other
/// parameters) unable to take the same quarter off that band.
///
/// Stops when a round's best does not qualify (and is not tried, or tried and not added),
/// after [`CalibrationOptions::max_effects`] effects or twice as many rounds, or when no
/// candidate is left. The candidates are [`CalibrationOptions::candidates`] but those the
/// preset `params` has on and those of `exclude` (effects `start` has on already: the
/// library's, where the search runs again beside the terms proposed beyond it). With
/// `by_raw_error` false a round's best is tried only on the criterion's bars, never on the
/// raw error's: beside proposed terms, what is left above the floor is in part their own form
/// error, which a library effect tried on the raw error's terms would stand in for (a supply
/// sag at 3 % of the residual, on a rig with four effects outside the library and none of
/// it).
pub fn search(
    cx: &SearchContext<'_>,
    campaign: &Campaign,
    params: &Params,
    (start, knobs): (&FitResult, &[Knob]),
    (exclude, by_raw_error): (&[EffectId], bool),
) -> Result<EffectSearch, IdentifyError> {
    let options = cx.options;
    let mut current = start.clone();
    let mut current_val = validation_rms(&current.params, &campaign.validation)?;
    let mut knobs = knobs.to_vec();
    let mut added: Vec<Added> = Vec::new();
    let mut candidates = Vec::new();
    let mut notes = Vec::new();
    let mut pinned = Vec::new();
    let mut remaining: Vec<EffectId> = options
        .candidates
        .iter()
        .copied()
        .filter(|e| !e.enabled(params) && !exclude.contains(e))
        .collect();
    let mut round = 0;
    while !remaining.is_empty()
        && added.len() < options.max_effects
        && round < 2 * options.max_effects
    {
        round += 1;
        let mut ranked = rank_candidates(cx, &current, &knobs, &remaining, round)?;
        for r in &ranked {
            candidates.push(CandidateScore {
                effect: r.effect,
                round,
                score: r.score,
                relative_gain: r.gain,
                params: r
                    .effect
                    .knobs()
                    .iter()
                    .map(|k| (k.name().to_string(), k.value(&r.fit.params)))
                    .collect(),
            });
        }
        let min_gain = if added.is_empty() {
            options.min_relative_gain
        } else {
            options.min_relative_gain_later
        };
        // The criterion's best among the candidates that clear the gain bar: one with fewer
        // parameters may rank above by the criterion and still remove too little (beside an
        // overlap at 200 Hz, compliance ΔBIC −26.0 at 34 %, friction −22.8 at 42 %: friction
        // is the rig's). Without one, the criterion's best overall.
        let mut pick = ranked
            .iter()
            .position(|r| r.score < 0.0 && r.gain >= min_gain)
            .unwrap_or(0);
        if pick >= ranked.len() {
            break;
        }
        let qualifies = ranked[pick].score < 0.0 && ranked[pick].gain >= min_gain;
        // Under the gain bar, a candidate the criterion favours is still tried while the raw
        // error (the verdict's measure) is above its limit: the weighted fit metric can
        // under-rate an effect whose signature lies where it weighs little (friction's at
        // the reversals, beside an overlap's). It is kept only if it also takes a quarter
        // off the raw error's worst band.
        let raw_before = if !qualifies && by_raw_error {
            Some(worst_raw_ratio(cx, campaign, params, &current.params)?)
                .filter(|&w| w > options.raw_error_limit)
        } else {
            None
        };
        // Where the criterion favours none, the candidates' screening fits are judged by the
        // raw error instead, and the one that lowers its worst band most is tried, if by a
        // quarter: the weighted metric stops at 25 Hz, and an effect that damps the oil
        // column's ringing shows above it (friction through an acquisition's anti-alias
        // filter, which takes away the ringing that point sampling folds below 25 Hz).
        let mut by_raw = None;
        if let Some(before) = raw_before
            && ranked[pick].score >= 0.0
        {
            let mut lowest: Option<(usize, f64)> = None;
            for (i, r) in ranked.iter().enumerate() {
                let w = worst_raw_ratio(cx, campaign, params, &r.fit.params)?;
                if lowest.is_none_or(|(_, l)| w < l) {
                    lowest = Some((i, w));
                }
            }
            match lowest {
                Some((i, w)) if w <= REFINEMENT_MAX_RAW_RATIO * before => {
                    by_raw = Some((ranked[pick].score, w));
                    pick = i;
                }
                _ => break,
            }
        }
        let best = ranked.remove(pick);
        let runner_up = ranked.first().map(|r| (r.effect, r.score, r.gain));
        if !qualifies && raw_before.is_none() {
            break;
        }
        let trial = try_effect(cx, campaign, params, &best, &knobs, round, current_val)?;
        remaining.retain(|e| *e != best.effect);
        let (score, trial_val) = (best.score, trial.validation_rms);
        let mut raw_terms = None;
        if let Some(before) = raw_before {
            let after = worst_raw_ratio(cx, campaign, params, &trial.refit.params)?;
            // Its size determined and more than 2σ from "off", and every uncertainty of the
            // re-fit finite: an effect tried below the bar must not leave the fit degenerate,
            // nor enter at no size only to let the others' fit move on.
            let mut why: Vec<String> = trial
                .refit
                .values
                .iter()
                .filter(|v| !v.std.is_finite())
                .map(|v| format!("{}'s uncertainty is not determined", v.name))
                .collect();
            let no_size = unsized_effect(&trial.refit, best.effect);
            let lowers_raw = after <= REFINEMENT_MAX_RAW_RATIO * before;
            // Sizes that trade off (friction's Coulomb, Stribeck and viscous forces at 200 Hz
            // through an acquisition filter: each within 2σ of none below 25 Hz) leave each
            // undetermined alone, not the effect. Where only that stands against it, the raw
            // error judges the effect as a whole: the model without it, fitted again from the
            // re-fit's other parameters, must not take the same quarter off the worst band.
            let degenerate = !why.is_empty();
            let without = if (no_size.is_some() || degenerate) && trial.improves && lowers_raw {
                let again = fitted_without(cx, &trial.refit.params, best.effect, &knobs)?;
                let w = worst_raw_ratio(cx, campaign, params, &again.params)?;
                Some((again, w))
            } else {
                None
            };
            let as_a_whole = without
                .as_ref()
                .map(|(_, w)| *w)
                .filter(|&w| !degenerate && w > REFINEMENT_MAX_RAW_RATIO * before);
            if let Some(no_size) = &no_size
                && as_a_whole.is_none()
            {
                why.insert(0, no_size.clone());
            }
            let determinate = why.is_empty();
            let kept = trial.improves && determinate && lowers_raw;
            raw_terms = Some(RawTerms {
                worst: [before, after],
                without: as_a_whole,
            });
            let why_tried = match by_raw {
                Some((best_score, screened)) => format!(
                    "the criterion favoured no candidate (best ΔBIC {best_score:+.1}; `{}` \
                     {score:+.1}, {:.1} % of the weighted residual), but the raw error was above \
                     its limit (worst band {before:.1}× its floor) and `{}`'s screening fit \
                     lowered it most (to {screened:.1}×)",
                    best.effect.name(),
                    100.0 * best.gain,
                    best.effect.name(),
                ),
                None => format!(
                    "`{}` removed {:.1} % of the weighted residual (ΔBIC {score:.1}), under the \
                     {:.0} % a further effect needs, but the raw error was above its limit \
                     (worst band {before:.1}× its floor)",
                    best.effect.name(),
                    100.0 * best.gain,
                    100.0 * min_gain,
                ),
            };
            notes.push(format!(
                "round {round}: {why_tried}: tried, it {} the worst band to {after:.1}× and the \
                 held-out weighted RMS {current_val:.3} → {trial_val:.3}{}: {}",
                if after < before { "lowers" } else { "leaves" },
                match (&no_size, as_a_whole) {
                    _ if !determinate => format!(", but {}", why.join(", ")),
                    (Some(no_size), Some(w)) => format!(
                        "; {no_size}, but the model without it, fitted again from the re-fit's \
                         other parameters, leaves the worst band at {w:.1}×: its sizes trade \
                         off, the effect as a whole is determined"
                    ),
                    _ => String::new(),
                },
                if kept { "added" } else { "not added" }
            ));
            if !kept {
                // A re-fit that lowered the raw error with the tried effect at no size of its
                // own: the other parameters moved to a deeper valley of the model as it was.
                // Fitted again from there without the effect, that is kept if deeper.
                if let Some((again, w)) = without
                    && again.rss < current.rss
                    && w < before
                {
                    notes.push(format!(
                        "round {round}: fitted again from that re-fit's other parameters \
                         without `{}`, the model as it was reaches a deeper valley (weighted \
                         residual −{:.1} %, worst raw band {before:.1}× → {w:.1}×): kept",
                        best.effect.name(),
                        100.0 * (1.0 - again.rss / current.rss),
                    ));
                    current = again;
                }
                break;
            }
        }
        if !trial.improves {
            notes.push(format!(
                "round {round}: `{}` improved the fit records (ΔBIC {score:.1}, {:.1} % of the \
                 residual) but not the held-out ones (validation weighted RMS {current_val:.3} → \
                 {trial_val:.3}): rejected",
                best.effect.name(),
                100.0 * best.gain
            ));
            continue;
        }
        // An effect that qualified by its screening fit must also earn its place in its
        // re-fit. Its screening fit moves every other parameter too; where the fit before it
        // had not settled in its valley, the residual it removes may all be theirs (overlap
        // beside soft hoses at 10 kHz: friction "removed" 56 % at 0.03 ± 2.1 N Coulomb).
        // Where none of its sizes is determined and 2σ from none (correlated sizes, as a
        // friction's Coulomb and Stribeck forces at 200 Hz, each may not be), the model
        // without it is fitted again from the re-fit's other parameters: the effect stays
        // only if the criterion still favours it against that.
        if raw_before.is_none()
            && let Some(no_size) = unsized_effect(&trial.refit, best.effect)
        {
            let again = fitted_without(cx, &trial.refit.params, best.effect, &knobs)?;
            let earns = cx.bic.value(trial.refit.rss, trial.knobs.len())
                - cx.bic.value(again.rss, knobs.len());
            if earns >= 0.0 {
                let deeper = again.rss < current.rss;
                notes.push(format!(
                    "round {round}: `{}` removed {:.1} % of the weighted residual (ΔBIC \
                     {score:.1}), but in its re-fit {no_size}, and the model without it, \
                     fitted again from that re-fit's other parameters, does as well (ΔBIC \
                     {earns:+.1} for the effect): the other parameters moved, not the effect; \
                     not added{}",
                    best.effect.name(),
                    100.0 * best.gain,
                    if deeper {
                        format!(
                            "; that fit is deeper than the one before (weighted residual \
                             −{:.1} %) and is kept",
                            100.0 * (1.0 - again.rss / current.rss)
                        )
                    } else {
                        String::new()
                    }
                ));
                if deeper {
                    current_val = validation_rms(&again.params, &campaign.validation)?;
                    current = again;
                }
                continue;
            }
        }
        if by_raw.is_some() {
            // Chosen by the raw error, not the criterion: the note above says so.
        } else if let Some((other, other_score, other_gain)) = runner_up
            && other_score < score
        {
            notes.push(format!(
                "round {round}: `{}` ranked first by the criterion (ΔBIC {other_score:.1}) but \
                 removed {:.1} % of the residual, under the {:.0} % bar; `{}` (ΔBIC {score:.1}, \
                 {:.1} %) was added",
                other.name(),
                100.0 * other_gain,
                100.0 * min_gain,
                best.effect.name(),
                100.0 * best.gain,
            ));
        } else if let Some((other, other_score, _)) = runner_up
            && other_score < 0.0
            && other_score - score < options.ambiguity_margin
        {
            notes.push(format!(
                "round {round}: `{}` (ΔBIC {score:.1}) and `{}` (ΔBIC {other_score:.1}) explain \
                 the residual about equally (difference {:.1} < {:.0}): the data cannot tell \
                 them apart, `{}` was added by a narrow margin.{}",
                best.effect.name(),
                other.name(),
                other_score - score,
                options.ambiguity_margin,
                best.effect.name(),
                confounding_hint(best.effect, other, &campaign.all),
            ));
        }
        for v in &trial.pinned {
            notes.push(format!(
                "round {round}: `{}`: these records leave {} uncertain ({}) and it improves \
                 neither the fit (ΔBIC > {REFINEMENT_MIN_DBIC}) nor the raw error's worst band \
                 by a quarter; the effect keeps its plain law ({})",
                best.effect.name(),
                v.name,
                super::units::format_parameter(&v.name, v.value, v.std),
                match v.knob {
                    Knob::HoseCompliance => "one modulus for hoses and chambers",
                    _ => "a leakage coefficient that does not change with the pressure",
                }
            ));
        }
        pinned.extend(trial.pinned);
        knobs = trial.knobs;
        added.push(Added {
            effect: best.effect,
            score,
            gain: best.gain,
            validation: [current_val, trial_val],
            raw: raw_terms,
        });
        current = trial.refit;
        current_val = trial_val;
    }
    let revisited = refine::revisit(cx, campaign, params, &current, &knobs, &pinned, current_val)?;
    if let Some(r) = revisited {
        notes.push(r.note);
        if r.kept {
            current = r.fit;
            knobs = r.knobs;
        }
    }
    // The hoses' and chambers' moduli, where both were fitted: their split's profile.
    let split = super::profile::hose_split(
        cx.ev,
        &current,
        &knobs,
        options.max_iterations,
        cx.bic.ratio(),
    )?;
    if let Some(split) = split {
        if let Some(end) = &split.fit {
            current = end.clone();
        }
        if split.trades_off() {
            split.apply(&mut current);
            notes.push(split.note(&current));
        } else if let Some(note) = super::profile::undetermined_note(&current) {
            notes.push(note);
        }
    }
    // The mass, where a modulus of the oil was fitted beside it: its profile.
    let mass = super::profile::mass_trade(
        cx.ev,
        &current,
        &knobs,
        options.max_iterations,
        cx.bic.ratio(),
    )?;
    if let Some(mass) = mass.filter(|m| m.trades_off()) {
        mass.apply(&mut current);
        notes.push(mass.note(&current));
    }
    Ok(EffectSearch {
        current,
        knobs,
        added,
        candidates,
        notes,
    })
}
