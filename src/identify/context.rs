//! What the effect search and its refinements work with: the fit's evaluator and criterion,
//! the held-out records and the options ([`SearchContext`]), and the two errors a step is
//! judged by beside the criterion: the held-out records' weighted RMS ([`validation_rms`])
//! and the verdict's raw error ([`raw_error_at`], [`worst_raw_ratio`]).

use super::data::Campaign;
use super::evaluate::{replay_all, weighted_of, with_numerics_of};
use super::fit::{Bic, Evaluator};
use super::raw_error::{RawErrorReport, raw_error_report};
use super::replay::{PreparedRecord, SimChannels, rms};
use super::{CalibrationOptions, IdentifyError};
use crate::params::Params;

/// What every round of the search works with.
pub struct SearchContext<'a> {
    /// Replays of the fit records.
    pub ev: &'a Evaluator<'a>,
    /// BIC counts of the declared fit.
    pub bic: Bic,
    /// The held-out records.
    pub validation: &'a [PreparedRecord],
    /// The options.
    pub options: &'a CalibrationOptions,
}

/// Weighted RMS error of `p` on the held-out records.
pub fn validation_rms(p: &Params, validation: &[PreparedRecord]) -> Result<f64, IdentifyError> {
    let reps = replay_all(p, validation)?;
    Ok(rms(&weighted_of(validation, &reps)))
}

/// The raw error ([`raw_error`](super::raw_error), the verdict's measure) of `p` replayed
/// on every record at the preset's step.
pub fn raw_error_at(
    cx: &SearchContext<'_>,
    campaign: &Campaign,
    preset: &Params,
    p: &Params,
) -> Result<RawErrorReport, IdentifyError> {
    raw_error_of(campaign, preset, p, cx.options)
}

/// [`raw_error_at`] without a search's context: the raw error of `p` replayed on every
/// record of `campaign` at the preset's step, against `options`' limit.
pub fn raw_error_of(
    campaign: &Campaign,
    preset: &Params,
    p: &Params,
    options: &CalibrationOptions,
) -> Result<RawErrorReport, IdentifyError> {
    let reps = replay_all(&with_numerics_of(*p, preset), &campaign.all)?;
    let sims: Vec<&SimChannels> = reps.iter().map(|r| &r.sim).collect();
    Ok(raw_error_report(
        &campaign.all,
        &sims,
        options.raw_error_limit,
    ))
}

/// The largest ratio of the raw error to its noise floor in any band of any record
/// ([`raw_error_at`]).
pub fn worst_raw_ratio(
    cx: &SearchContext<'_>,
    campaign: &Campaign,
    preset: &Params,
    p: &Params,
) -> Result<f64, IdentifyError> {
    let report = raw_error_at(cx, campaign, preset, p)?;
    Ok(report.worst.map_or(f64::INFINITY, |w| w.ratio))
}
