//! One pass of the library over a campaign: the declared fit, the effect search, the search
//! beyond the library and the drifts ([`library_pass`]); `calibrate_with` runs it once, or
//! again with each record's own Cd when Cd drifts.

use super::fit::{self, Evaluator, Knob};
use super::progress::{self, Stage};
use super::replay::StepRule;
use super::{
    CalibrationOptions, IdentifyError, context, data, drift, effects, proposed, result, stages,
};
use crate::params::Params;

/// One calibration of the campaign by the library from `start`: the declared fit, the effect
/// search, the search beyond the library and the drifts.
pub(super) struct LibraryPass {
    pub(super) declared: stages::Declared,
    pub(super) bic: fit::Bic,
    pub(super) search: effects::EffectSearch,
    pub(super) proposal: Option<proposed::Proposal>,
    /// The scores of the terms the search beyond the library tried (kept or not).
    pub(super) proposed_candidates: Vec<result::ProposedScore>,
    /// The parameters the drifts were judged at (the proposal's, else the search's).
    pub(super) final_params: Params,
    pub(super) drifts: Vec<result::Drift>,
    pub(super) notes: Vec<String>,
}

/// A [`LibraryPass`], or the declared fit that left Cd or τ undetermined.
pub(super) enum Pass {
    Done(Box<LibraryPass>),
    Undetermined(Box<stages::Declared>),
}

/// Runs a [`LibraryPass`] on `campaign` (its records with the Cd factors they carry).
pub(super) fn library_pass(
    params: &Params,
    campaign: &data::Campaign,
    start: &Params,
    options: &CalibrationOptions,
    monitor: &progress::Monitor<'_>,
) -> Result<Pass, IdentifyError> {
    let ev = Evaluator {
        records: &campaign.fit,
        monitor,
        step: StepRule::Resolving,
    };
    let declared = stages::declared_fit(&ev, start, params.plant.body.mass_kg, options)?;
    let mut notes = declared.notes.clone();
    let bic = fit::Bic::at(&ev, &declared.fit)?;
    let cx = context::SearchContext {
        ev: &ev,
        bic,
        validation: &campaign.validation,
        options,
    };
    let search = effects::search(
        &cx,
        campaign,
        params,
        (&declared.fit, &declared.knobs),
        (&[], true),
    )?;
    if !declared.undetermined.is_empty() {
        // An effect can hide Cd and τ from the declared fit (an overlap as wide as the small
        // tests' spool travel): they count as determined only if the search added an effect
        // and its fit determines both.
        let determined =
            !search.added.is_empty() && !search.current.values.iter().any(stages::undetermined);
        if !determined {
            return Ok(Pass::Undetermined(Box::new(declared)));
        }
        notes.push(format!(
            "the declared parameters alone left {} undetermined; with the effect(s) added \
             they are determined",
            declared.undetermined.len()
        ));
    }
    notes.extend(search.notes.iter().cloned());
    let beyond = beyond_the_library(params, &cx, campaign, &search)?;
    notes.extend(beyond.notes);
    let proposal = beyond.proposal;
    monitor.enter(Stage::Drifts, 1);
    let final_params = proposal
        .as_ref()
        .map_or(search.current.params, |p| p.fit.params);
    let (mut drifts, drift_notes) =
        drift::find(&final_params, &campaign.all, bic.ratio(), monitor)?;
    notes.extend(drift_notes);
    // An effect added to follow a drifting Cd bends each record's Cd towards itself (supply
    // sag raises the large tests' Cd), so that the drift no longer looks ordered. Where the
    // library's twin still leaves the raw error above its limit, each record's Cd is also
    // read where no effect was added yet (the declared fit); a drift found there is
    // calibrated as one by `calibrate_with`, which judges the effects again with each
    // record's own Cd.
    if !search.added.is_empty()
        && !drifts.iter().any(|d| d.parameter == Knob::Cd.name())
        && !context::raw_error_at(&cx, campaign, params, &final_params)?.at_floor()
    {
        let (plain, _) = drift::find(&declared.fit.params, &campaign.all, bic.ratio(), monitor)?;
        if let Some(d) = plain.into_iter().find(|d| d.parameter == Knob::Cd.name()) {
            notes.push(format!(
                "with {} added the raw error stays above its limit; read before any effect \
                 was added, `cd` drifts through the campaign",
                search
                    .added
                    .iter()
                    .map(|a| format!("`{}`", a.effect.name()))
                    .collect::<Vec<_>>()
                    .join(", ")
            ));
            drifts.push(d);
        }
    }
    monitor.advance();
    Ok(Pass::Done(Box::new(LibraryPass {
        declared,
        bic,
        search,
        proposal,
        proposed_candidates: beyond.candidates,
        final_params,
        drifts,
        notes,
    })))
}

/// The search beyond the library ([`proposed`]), run only when the library's final twin,
/// replayed at the preset's step, leaves a raw residual above the floor on some record
/// ([`raw_error`]), and when [`CalibrationOptions::max_proposed`] allows it.
fn beyond_the_library(
    params: &Params,
    cx: &context::SearchContext<'_>,
    campaign: &data::Campaign,
    search: &effects::EffectSearch,
) -> Result<proposed::Searched, IdentifyError> {
    if cx.options.max_proposed == 0
        || context::raw_error_at(cx, campaign, params, &search.current.params)?.at_floor()
    {
        return Ok(proposed::Searched::default());
    }
    let library: Vec<_> = search.added.iter().map(|a| a.effect).collect();
    let partners = super::pair::partners(search);
    proposed::search(
        cx,
        campaign,
        params,
        &search.current,
        &search.knobs,
        (&library, &partners),
    )
}
