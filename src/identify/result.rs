//! What a calibration found: the [`CalibrationReport`] and its parts (errors per stage,
//! candidate scores, added effects, the verdict, the split, raw-signal NRMSE, the terms
//! proposed beyond the library and the parameters that drift). Plain types: the stages that
//! fill them ([`super::proposed`], [`super::drift`], …) import them from here.

use super::EffectId;
use super::diagnose;
use super::fit::FittedValue;
use super::raw_error::RawErrorReport;
use super::replay::{ChannelErrors, PreparedRecord, Replay};
use crate::params::Params;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// Error of the twin against the records at one stage.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ErrorSummary {
    /// What the value means.
    pub metric: String,
    /// RMS of the weighted residual (1 = sensor-noise level).
    pub value: f64,
    /// Pooled RMS errors per channel, SI: `du` [m/s], `ydd` [m/s²], `u` \[m\], `p1`, `p2` \[Pa\]
    /// (records with pressures only), and the normalised ones `du_nrmse`, `ydd_nrmse` [-].
    pub channels: BTreeMap<String, f64>,
    /// Per file.
    pub files: Vec<(String, ChannelErrors)>,
}

/// The text of the metric, as reported.
pub const METRIC: &str = "RMS of the noise-weighted residual of relative velocity du/dt \
(measured and twin u through the same zero-phase 25 Hz low-pass and central difference) and of \
body acceleration ydd (same low-pass), decimated to 250 Hz; each file and channel divided by \
max(estimated sensor noise, 1 % of the signal RMS); chamber pressures p1, p2 (same low-pass, \
floor on 1 % of their swing) are included for the records that have them; 1.0 = noise level";

/// A candidate effect's score in one round.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CandidateScore {
    /// The effect.
    pub effect: EffectId,
    /// Round (1 = first).
    pub round: usize,
    /// ΔBIC against the current model (negative = better).
    pub score: f64,
    /// Share of the residual sum of squares removed [-].
    pub relative_gain: f64,
    /// Fitted effect parameters (SI), by name with unit.
    pub params: BTreeMap<String, f64>,
}

/// An effect added to the twin.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AddedEffect {
    /// The effect.
    pub effect: EffectId,
    /// Final fitted parameters (SI), by name with unit.
    pub params: BTreeMap<String, f64>,
    /// Their 1-σ uncertainties (SI).
    pub uncertainties: BTreeMap<String, f64>,
    /// Why it was added.
    pub evidence: String,
}

/// A property of a record's sensor, estimated by the calibration (not a plant effect).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SensorEstimate {
    /// The channel: `u` or `ydd`.
    pub channel: String,
    /// `offset` (SI unit of the channel), `scale` (a ratio, 1 = exact) or `lag` \[s\].
    pub kind: String,
    /// The estimate.
    pub value: f64,
    /// Its 1-σ uncertainty.
    pub uncertainty: f64,
}

/// Verdict of a calibration.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// Effects were added and explain the residual.
    Explained,
    /// The twin with re-fitted declared parameters already matches to the noise level.
    NoMissingEffect,
    /// A residual above the noise remains that no library effect explains.
    Unexplained,
    /// The records cannot determine the parameters (too short, no excitation, channels
    /// missing): nothing is calibrated.
    InsufficientData,
}

impl Verdict {
    /// As in `report.json`.
    pub fn name(self) -> &'static str {
        match self {
            Verdict::Explained => "explained",
            Verdict::NoMissingEffect => "no_missing_effect",
            Verdict::Unexplained => "unexplained",
            Verdict::InsufficientData => "insufficient_data",
        }
    }
}

/// The paper's own calibration (section 4), the baseline to beat.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PaperBaseline {
    /// Sine tests used.
    pub files: Vec<String>,
    /// Cd from the gain ratio [-].
    pub cd: f64,
    /// τ from the phase slope \[s\].
    pub tau_s: f64,
}

/// Residual diagnostics at one stage.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Diagnostics {
    /// Whiteness of the weighted residual.
    pub whiteness: diagnose::Whiteness,
    /// Correlations with the signature features.
    pub correlations: Vec<diagnose::FeatureCorrelation>,
    /// Share of the raw acceleration residual's power above 30 Hz [-].
    pub high_frequency_share: f64,
}

/// A term proposed beyond the library (`report.json`'s `proposed` list).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ProposedTerm {
    /// The term's id ([`super::proposed::CorrectionId::name`]).
    pub name: String,
    /// What it is, in physical words, with its value and uncertainty.
    pub description: String,
    /// Its parameter (SI) by preset-key name (`cd_opening_slope`, …).
    pub params: BTreeMap<String, f64>,
    /// 1-σ uncertainty of each parameter (SI).
    pub uncertainties: BTreeMap<String, f64>,
    /// Why it was kept: ΔBIC, share of the residual removed, held-out error.
    pub evidence: String,
    /// Its size fitted on each record alone \[SI\], by file name ([`super::term_form`]); empty
    /// with fewer than three records that determine it.
    pub per_record: BTreeMap<String, f64>,
    /// The factor its size's 1-σ was scaled by for the records' disagreement, `√(χ²/dof)`
    /// where that is above 2 [-] (1: they agree within twice their noise).
    pub uncertainty_scale: f64,
}

/// One candidate correction's score in one round.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ProposedScore {
    /// The correction.
    pub name: String,
    /// Round (1 = first).
    pub round: usize,
    /// ΔBIC against the model of the round (negative = better).
    pub score: f64,
    /// Share of the residual sum of squares removed [-].
    pub relative_gain: f64,
    /// Its fitted parameter (SI).
    pub value: f64,
}

/// An effect the library added that the twin with the proposed terms leaves out: beside them
/// it no longer earns its parameters, or the records, each fitted alone, do not say it is
/// there (`report.json`'s `proposed_leaves_out` list).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LeftOut {
    /// The effect's name (`supply_sag`, …).
    pub name: String,
    /// ΔBIC of keeping it beside the proposed terms (≥ 0: the criterion does not favour it).
    pub score: f64,
    /// Held-out weighted RMS `[with it, without it]`.
    pub validation: [f64; 2],
    /// The raw error's worst band, as a multiple of its noise floor, `[with it, without it]`.
    pub raw_worst: [f64; 2],
    /// Where the records left it out, though the criterion kept it: their say on its size.
    pub by_records: Option<SizeByRecord>,
}

/// A library effect's size fitted on each record alone (`proposed_leaves_out[].by_records`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SizeByRecord {
    /// The size, by the name `calibrated_parameters` gives it (`bias_v`, `overlap_m`, …).
    pub parameter: String,
    /// Its value meaning none \[SI\].
    pub none: f64,
    /// Its value fitted on each record alone \[SI\], by file name.
    pub per_record: BTreeMap<String, f64>,
    /// Their weighted mean \[SI\].
    pub mean: f64,
    /// The mean's 1-σ \[SI\], scaled by √(χ²/dof) where the records disagree.
    pub mean_uncertainty: f64,
    /// χ² of the per-record values about their mean, per degree of freedom [-].
    pub chi2_per_dof: f64,
}

/// A parameter that changes from record to record (`report.json`'s `drifts` list).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Drift {
    /// The parameter, by preset-key name (`cd`, `effective_bulk_modulus_pa`).
    pub parameter: String,
    /// Its value fitted on each record alone \[SI\], by file name.
    pub per_record: BTreeMap<String, f64>,
    /// The 1-σ uncertainty of each per-record value \[SI\], by file name.
    pub per_record_uncertainty: BTreeMap<String, f64>,
    /// Typical (RMS) 1-σ uncertainty of a per-record value \[SI\].
    pub uncertainty: f64,
    /// χ² of the scatter over its degrees of freedom [-].
    pub chi2_per_dof: f64,
    /// Spearman rank correlation of the values with the record order [-].
    pub rank_correlation: f64,
    /// In words.
    pub description: String,
}

/// Everything a calibration found.
#[derive(Debug, Clone)]
pub struct CalibrationReport {
    /// The starting (nominal) parameters.
    pub nominal: Params,
    /// The calibrated parameters (`calibrated.toml`): the added effects enabled and, when
    /// terms beyond the library were proposed, those terms with every parameter re-fitted
    /// alongside them ([`Self::proposed_calibrated`]).
    pub params: Params,
    /// Terms beyond the library ([`super::proposed`]), in physical words, empty when none was
    /// kept. The verdict does not count them: it stays the library's.
    pub proposed: Vec<ProposedTerm>,
    /// The declared parameters re-fitted with the proposed terms (empty without them).
    pub proposed_calibrated: Vec<FittedValue>,
    /// Every candidate correction's score, per round (empty when the search did not run).
    pub proposed_candidates: Vec<ProposedScore>,
    /// The library's effects the twin with the proposed terms leaves out (empty without
    /// proposed terms): [`Self::effects`] keeps them, as the library's twin does.
    pub proposed_leaves_out: Vec<LeftOut>,
    /// Effects of the library found only beside the proposed terms (empty without them): the
    /// twin with the proposed terms carries them; [`Self::effects`], the library's twin, does
    /// not, as the library alone did not find them.
    pub proposed_adds: Vec<AddedEffect>,
    /// The raw error measure with the proposed terms (`calibrated.toml`), if any.
    pub raw_error_proposed: Option<RawErrorReport>,
    /// Parameters that change from record to record ([`super::drift`]), empty when none.
    pub drifts: Vec<Drift>,
    /// Verdict.
    pub verdict: Verdict,
    /// Effects added, most important first.
    pub effects: Vec<AddedEffect>,
    /// Every candidate's score, per round (round 1 first).
    pub candidates: Vec<CandidateScore>,
    /// Final declared parameters (Cd, τ, mass if identifiable) with uncertainties.
    pub calibrated: Vec<FittedValue>,
    /// Sensor properties found: those estimated more than 3σ from exact (the others are
    /// set back to exact and not applied).
    pub sensors: Vec<SensorEstimate>,
    /// Whether the mass was identifiable and fitted.
    pub mass_fitted: bool,
    /// Correlation matrix of the final fit, with its knob names.
    pub correlation: (Vec<String>, Vec<Vec<f64>>),
    /// The paper's section-4 calibration.
    pub baseline: Option<PaperBaseline>,
    /// Error with the nominal parameters.
    pub error_nominal: ErrorSummary,
    /// Error after the paper's method (if sine tests were present).
    pub error_baseline: Option<ErrorSummary>,
    /// Error with re-fitted declared parameters, no effect.
    pub error_before: ErrorSummary,
    /// Error with the added effects.
    pub error_after: ErrorSummary,
    /// Diagnostics before adding effects.
    pub diagnostics_before: Diagnostics,
    /// Diagnostics after.
    pub diagnostics_after: Diagnostics,
    /// Residual count and its effective (decorrelated) count.
    pub n: usize,
    /// Effective count used by the BIC.
    pub n_eff: f64,
    /// Replays of the whole campaign.
    pub evaluations: usize,
    /// Record names.
    pub files: Vec<String>,
    /// Replays before (declared parameters re-fitted), per record.
    pub replays_before: Vec<Replay>,
    /// Replays after, per record.
    pub replays_after: Vec<Replay>,
    /// Replays nominal, per record.
    pub replays_nominal: Vec<Replay>,
    /// The prepared records (measured channels for plots).
    pub records: Vec<PreparedRecord>,
    /// Notes (mass identifiability, termination reasons, warnings).
    pub notes: Vec<String>,
    /// What the data lack (verdict `insufficient_data`), one sentence each.
    pub missing: Vec<String>,
    /// How records were split into fit and validation.
    pub split: Split,
    /// Error on the records (or parts) used for the fit, before and after the effects.
    pub error_training: Option<StageErrors>,
    /// Error on the held-out records (or parts), before and after the effects.
    pub error_validation: Option<StageErrors>,
    /// Raw-signal NRMSE per channel, as `seat-twin replay` replays each stage.
    pub raw_nrmse: RawNrmse,
    /// What the twin still misses after the effects (when not at the noise level).
    pub residual_left: Option<diagnose::ResidualLeft>,
    /// The raw error measure ([`super::raw_error`]) of every record and raw channel with the
    /// declared parameters re-fitted, no effect (nominal when nothing was fitted).
    pub raw_error_before: RawErrorReport,
    /// The same with the calibrated parameters: the verdict's measure.
    pub raw_error_after: RawErrorReport,
}

/// How the records were split into the part that is fitted and the part held out.
#[derive(Debug, Clone, PartialEq, Serialize, Default)]
pub struct Split {
    /// The rule, in words.
    pub rule: String,
    /// Records (or record parts) the fit used.
    pub fit: Vec<String>,
    /// Records (or record parts) held out for validation.
    pub validation: Vec<String>,
}

/// Weighted error before and after the effects, on one set of records.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StageErrors {
    /// Weighted RMS before (declared parameters re-fitted, no effect); 1 = noise level.
    pub before: f64,
    /// Weighted RMS after (with the added effects).
    pub after: f64,
    /// The metric ([`METRIC`]).
    pub metric: String,
    /// Per channel: `[before, after]` (weighted RMS of that channel alone).
    pub channels: BTreeMap<String, [f64; 2]>,
    /// The records (or parts) it covers.
    pub files: Vec<String>,
}

/// Raw-signal NRMSE (RMS of twin − measured over the measured channel's standard deviation,
/// pooled over records) per channel `u`, `ydd`, `p1`, `p2`, for each stage.
#[derive(Debug, Clone, PartialEq, Serialize, Default)]
pub struct RawNrmse {
    /// Definition, in words.
    pub definition: String,
    /// All records: nominal parameters.
    pub nominal: BTreeMap<String, f64>,
    /// All records: declared parameters re-fitted, no effect.
    pub before: BTreeMap<String, f64>,
    /// All records: calibrated with the library's effects (the `calibrated.toml` unless
    /// terms beyond the library were proposed).
    pub after: BTreeMap<String, f64>,
    /// All records: with the proposed terms (the `calibrated.toml` then), if any.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub proposed: Option<BTreeMap<String, f64>>,
    /// Held-out records only: `{nominal, before, after}` the same way.
    pub validation: BTreeMap<String, BTreeMap<String, f64>>,
}

/// Definition of [`RawNrmse`].
pub const RAW_NRMSE: &str = "sqrt(sum over records of Σ(twin − measured)²) / sqrt(sum over \
records of Σ(measured − its record mean)²), raw samples on each record's own grid, the twin \
replayed exactly as `seat-twin replay --preset <that stage's parameters>` replays it (preset \
step, conditioned excitation)";
