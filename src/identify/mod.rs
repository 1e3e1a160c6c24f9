//! Identification from measured records: replay, calibrate, trace the residual, add effects.
//!
//! The loop of issue 4, as a pure library (no files, threads of its own or clock; rayon
//! parallelises the replays):
//!
//! 1. [`replay`]: a [`crate::dataset::Record`] drives the twin in open loop with its `v_in` and
//!    platform motion (the measured platform acceleration conditioned by a zero-phase 30 Hz
//!    low-pass, [`replay::EXCITATION_CONDITIONING`]); the twin's channels come back aligned
//!    with the record, with residuals. The error metric ([`replay`] module docs) compares the
//!    relative velocity and the body acceleration through the same zero-phase filter, weighted
//!    by the sensor noise, because the position of an integrating plant drifts.
//! 2. The data are checked first: too short, no excitation, no `v_in`/`u` → verdict
//!    `insufficient_data`, naming what is missing, and nothing is fitted. Then the records are
//!    split ([`Split`]): with six or more, every third is held out; with fewer, the last
//!    third of each. Every fit below sees the fit part only.
//! 3. [`calibrate`]: the paper's own method (section 4: delay from the phase slope of the sine
//!    tests, Cd from their gain) gives the start; Levenberg–Marquardt then fits `Cd`, `τ` and
//!    (when the data can tell it) the mass, with uncertainties ([`fit`]). If Cd or τ stays
//!    undetermined, the verdict is `insufficient_data`.
//! 4. Each candidate effect of [`EffectId`] is fitted on top (in parallel) and scored by
//!    ΔBIC = n_eff·ln(RSS₁/RSS₀) + k·ln(n_eff), `n_eff` being the residual count corrected
//!    for autocorrelation, so a richer model must earn its parameters. The best one is tried
//!    if ΔBIC < 0 and it removes at least `min_relative_gain` of the residual (a further effect:
//!    `min_relative_gain_later` of what remains); all parameters are re-fitted, and the effect
//!    is kept only if it lowers the weighted error on the held-out part by at least
//!    `min_validation_gain`. The round repeats.
//! 5. [`diagnose`] gives the evidence: whiteness, correlations with the signature features,
//!    spectra. The verdict: `explained` when effects were added *and* every record's every
//!    channel is at the noise level (weighted RMS ≤ `noise_level_record` = 2.5, pooled ≤
//!    `noise_level` = 1.5); `no_missing_effect` when the re-fitted twin is there without any effect;
//!    otherwise `unexplained`, with the effects that helped and what is left
//!    ([`diagnose::ResidualLeft`]: records, channels, band, correlations).
//! 6. Errors are reported on all records, on the fit part and on the held-out part
//!    (`error_validation`), weighted and as raw-signal NRMSE ([`RawNrmse`]), every stage
//!    replayed exactly as `seat-twin replay` replays its preset.
//! ```no_run
//! use seat_twin::{dataset, identify, params::Params};
//! let rec = dataset::read_record("sine.csv".as_ref(), dataset::RecordKind::Measured)?;
//! let report = identify::calibrate(&Params::paper(), &[rec], &Default::default(), &|_| true)?;
//! println!("{:?}: error {} → {}", report.verdict, report.error_before.value,
//!          report.error_after.value);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod diagnose;
pub mod fit;
pub mod replay;
pub mod report;

use crate::analysis::frequency_response::first_harmonic;
use crate::dataset::Record;
use crate::params::{ParamError, Params};
use crate::simulation::SimError;
use fit::{Evaluator, FitResult, FittedValue, Knob};
use rayon::prelude::*;
use replay::{ChannelErrors, MetricOptions, PreparedRecord, Replay, replay_prepared, rms};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

pub use replay::SimChannels;

/// Why identification failed.
#[derive(Debug, thiserror::Error)]
pub enum IdentifyError {
    /// A record lacks a column the replay needs.
    #[error("{}: the column `{column}` is required for replay", file.display())]
    MissingColumn {
        /// The file.
        file: PathBuf,
        /// The column.
        column: String,
    },
    /// No records given.
    #[error("no measured records given")]
    NoRecords,
    /// The twin diverged on a record.
    #[error("{file}: {source}")]
    Simulation {
        /// The record's file name.
        file: String,
        /// The simulation error.
        source: SimError,
    },
    /// The starting parameters are invalid.
    #[error(transparent)]
    Params(#[from] ParamError),
    /// The caller cancelled.
    #[error("calibration cancelled")]
    Cancelled,
}

/// A physical effect of the twin's library ([`crate::params::EffectsParams`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, PartialOrd, Ord)]
#[serde(rename_all = "snake_case")]
pub enum EffectId {
    /// Coulomb + viscous friction of seals and slides.
    Friction,
    /// Spool overlap (dead band) around null.
    ValveOverlap,
    /// Valve null offset / command bias.
    ValveOffset,
    /// Internal leakage across the piston.
    Leakage,
    /// Reduced effective bulk modulus.
    Compliance,
    /// Supply pressure falling with drawn flow.
    SupplySag,
}

impl EffectId {
    /// All effects of the library.
    pub const ALL: [EffectId; 6] = [
        EffectId::Friction,
        EffectId::ValveOverlap,
        EffectId::ValveOffset,
        EffectId::Leakage,
        EffectId::Compliance,
        EffectId::SupplySag,
    ];

    /// The id used in presets and reports (`friction`, `valve_overlap`, …).
    pub fn name(self) -> &'static str {
        match self {
            EffectId::Friction => "friction",
            EffectId::ValveOverlap => "valve_overlap",
            EffectId::ValveOffset => "valve_offset",
            EffectId::Leakage => "leakage",
            EffectId::Compliance => "compliance",
            EffectId::SupplySag => "supply_sag",
        }
    }

    /// Parses an id.
    pub fn from_name(s: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|e| e.name() == s)
    }

    /// The parameters fitted for this effect.
    pub fn knobs(self) -> &'static [Knob] {
        match self {
            EffectId::Friction => &[Knob::FrictionCoulomb, Knob::FrictionViscous],
            EffectId::ValveOverlap => &[Knob::Overlap],
            EffectId::ValveOffset => &[Knob::Offset],
            EffectId::Leakage => &[Knob::Leakage],
            EffectId::Compliance => &[Knob::Compliance],
            EffectId::SupplySag => &[Knob::SupplySag],
        }
    }

    /// Whether the effect is enabled in `p`.
    pub fn enabled(self, p: &Params) -> bool {
        let e = &p.plant.effects;
        match self {
            EffectId::Friction => e.friction.enabled,
            EffectId::ValveOverlap => e.valve_overlap.enabled,
            EffectId::ValveOffset => e.valve_offset.enabled,
            EffectId::Leakage => e.leakage.enabled,
            EffectId::Compliance => e.compliance.enabled,
            EffectId::SupplySag => e.supply_sag.enabled,
        }
    }

    /// The signature feature of [`diagnose`] that points at this effect.
    pub fn signature(self) -> &'static str {
        match self {
            EffectId::Friction => "sign_velocity",
            EffectId::ValveOverlap => "small_command",
            EffectId::ValveOffset => "constant",
            EffectId::Leakage => "load_pressure",
            EffectId::Compliance => "high_frequency",
            EffectId::SupplySag => "flow_magnitude",
        }
    }
}

/// Options of [`calibrate`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CalibrationOptions {
    /// The error metric's filtering and weighting.
    pub metric: MetricOptions,
    /// Candidate effects to try (default: the whole library).
    pub candidates: Vec<EffectId>,
    /// Most effects added.
    pub max_effects: usize,
    /// Jacobians per full fit (declared parameters, re-fits).
    pub max_iterations: usize,
    /// Jacobians per candidate screening fit.
    pub screen_iterations: usize,
    /// Smallest share of the residual sum of squares the first effect must remove [-].
    pub min_relative_gain: f64,
    /// Smallest share of what remains that each further effect must remove [-]: what is
    /// left after the first effect is partly model-form error, which any flexible effect can
    /// soak up a little of, so a second effect must explain a large part of it.
    pub min_relative_gain_later: f64,
    /// ΔBIC difference below which the runner-up of a round is reported as equally plausible
    /// (a note in the report; 6 = "strong evidence" on the usual BIC scale).
    pub ambiguity_margin: f64,
    /// Fit the mass when its relative uncertainty would be below this [-].
    pub mass_max_rel_std: f64,
    /// Weighted RMS error at or below which the twin explains the data "to the noise level",
    /// pooled over all records.
    pub noise_level: f64,
    /// The same, for each record and channel on its own: `explained` needs every record's
    /// every channel at or below it. (2.5: an effect law of the library that matches the rig's
    /// to within its form — a smooth rather than sharp overlap edge, say — leaves up to about
    /// 2.4 on the smallest-command test of the test rig; an effect outside the library leaves
    /// 5–25.)
    pub noise_level_record: f64,
    /// Smallest relative drop of the validation error an added effect must give [-]: an
    /// effect that does not improve the error on the held-out records is rejected.
    pub min_validation_gain: f64,
    /// Largest RK4 step used while fitting [s] (the preset's own step, if smaller, wins);
    /// the reported errors always use the preset's step.
    pub fit_step_s: f64,
}

impl Default for CalibrationOptions {
    fn default() -> Self {
        Self {
            metric: MetricOptions::default(),
            candidates: EffectId::ALL.to_vec(),
            max_effects: 3,
            max_iterations: 8,
            screen_iterations: 4,
            min_relative_gain: 0.10,
            min_relative_gain_later: 0.40,
            ambiguity_margin: 6.0,
            mass_max_rel_std: 0.05,
            noise_level: 1.5,
            noise_level_record: 2.5,
            min_validation_gain: 0.01,
            fit_step_s: 2.5e-4,
        }
    }
}

/// Progress of a calibration, passed to the callback.
#[derive(Debug, Clone, PartialEq)]
pub struct Progress {
    /// Stage, e.g. "declared parameters", "candidates (round 1)".
    pub stage: String,
    /// Replays of the whole campaign so far.
    pub evaluations: usize,
}

/// Error of the twin against the records at one stage.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ErrorSummary {
    /// What the value means.
    pub metric: String,
    /// RMS of the weighted residual (1 = sensor-noise level).
    pub value: f64,
    /// Pooled RMS errors per channel, SI: `du` [m/s], `ydd` [m/s²], `u` [m], `p1`, `p2` [Pa]
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
    /// τ from the phase slope [s].
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

/// Everything a calibration found.
#[derive(Debug, Clone)]
pub struct CalibrationReport {
    /// The starting (nominal) parameters.
    pub nominal: Params,
    /// The calibrated parameters, with the added effects enabled.
    pub params: Params,
    /// Verdict.
    pub verdict: Verdict,
    /// Effects added, most important first.
    pub effects: Vec<AddedEffect>,
    /// Every candidate's score, per round (round 1 first).
    pub candidates: Vec<CandidateScore>,
    /// Final declared parameters (Cd, τ, mass if identifiable) with uncertainties.
    pub calibrated: Vec<FittedValue>,
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
    /// All records: calibrated (the `calibrated.toml`).
    pub after: BTreeMap<String, f64>,
    /// Held-out records only: `{nominal, before, after}` the same way.
    pub validation: BTreeMap<String, BTreeMap<String, f64>>,
}

/// Definition of [`RawNrmse`].
pub const RAW_NRMSE: &str = "sqrt(sum over records of Σ(twin − measured)²) / sqrt(sum over \
records of Σ(measured − its record mean)²), raw samples on each record's own grid, the twin \
replayed exactly as `seat-twin replay --preset <that stage's parameters>` replays it (preset \
step, conditioned excitation)";

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

/// Coarse start for a candidate effect: its first parameter on a log grid (both signs for a
/// signed one), the others at 0; returns the best of the grid and "off".
fn multi_start(ev: &Evaluator<'_>, current: &Params, e: EffectId) -> Result<Params, IdentifyError> {
    let mut off = *current;
    for k in e.knobs() {
        k.set(&mut off, 0.0);
    }
    let signed = matches!(e, EffectId::ValveOffset);
    let mut grid = vec![0.0];
    for g in [0.1, 0.3, 1.0, 3.0, 10.0] {
        grid.push(g);
        if signed {
            grid.push(-g);
        }
    }
    let costs: Vec<Option<(f64, Params)>> = grid
        .par_iter()
        .map(|&g| {
            let mut p = off;
            e.knobs()[0].set(&mut p, g);
            ev.residuals(&p)
                .map(|r| (r.iter().map(|v| v * v).sum::<f64>(), p))
        })
        .collect();
    let mut best: Option<(f64, Params)> = None;
    for c in costs {
        let (cost, p) = c.ok_or(IdentifyError::Cancelled)?;
        if best.as_ref().is_none_or(|(b, _)| cost < *b) {
            best = Some((cost, p));
        }
    }
    Ok(best.map(|b| b.1).unwrap_or(off))
}

/// Replays one record through the twin: the simulated channels aligned with the record, the
/// residuals and the channel errors (default metric options).
pub fn replay(params: &Params, record: &Record) -> Result<Replay, IdentifyError> {
    params.validate()?;
    let rec = PreparedRecord::new(record, &MetricOptions::default())?;
    replay_prepared(params, &rec)
}

fn replay_all(params: &Params, recs: &[PreparedRecord]) -> Result<Vec<Replay>, IdentifyError> {
    recs.par_iter()
        .map(|r| replay_prepared(params, r))
        .collect()
}

/// Pooled raw NRMSE per channel over `replays`.
fn raw_pooled(replays: &[Replay]) -> BTreeMap<String, f64> {
    let mut acc: BTreeMap<&str, (f64, f64)> = BTreeMap::new();
    for r in replays {
        let n = r.errors.samples as f64;
        let raw = &r.errors.raw;
        for (name, c) in [
            ("u", Some(raw.u)),
            ("ydd", raw.ydd),
            ("p1", raw.p1),
            ("p2", raw.p2),
        ] {
            if let Some(c) = c {
                let e = acc.entry(name).or_insert((0.0, 0.0));
                e.0 += n * c.rms_error * c.rms_error;
                e.1 += n * c.measured_std * c.measured_std;
            }
        }
    }
    acc.into_iter()
        .filter(|(_, (_, d))| *d > 0.0)
        .map(|(k, (e, d))| (k.to_string(), (e / d).sqrt()))
        .collect()
}

/// Weighted RMS per channel (`du`, `ydd`, `p1`, `p2`) pooled over the replays.
fn weighted_channels(replays: &[Replay]) -> BTreeMap<String, f64> {
    let mut acc: BTreeMap<&str, (f64, f64)> = BTreeMap::new();
    for r in replays {
        let e = &r.errors;
        let n = e.samples as f64;
        for (name, v) in [
            ("du", Some(e.weighted_du)),
            ("ydd", e.weighted_ydd),
            ("p1", e.weighted_p1),
            ("p2", e.weighted_p2),
        ] {
            if let Some(v) = v {
                let a = acc.entry(name).or_insert((0.0, 0.0));
                a.0 += n * v * v;
                a.1 += n;
            }
        }
    }
    acc.into_iter()
        .filter(|(_, (_, n))| *n > 0.0)
        .map(|(k, (s, n))| (k.to_string(), (s / n).sqrt()))
        .collect()
}

fn stage_errors(recs: &[PreparedRecord], before: &[Replay], after: &[Replay]) -> StageErrors {
    let (cb, ca) = (weighted_channels(before), weighted_channels(after));
    StageErrors {
        before: rms(&weighted_of(recs, before)),
        after: rms(&weighted_of(recs, after)),
        metric: METRIC.to_string(),
        channels: cb
            .iter()
            .map(|(k, b)| (k.clone(), [*b, ca.get(k).copied().unwrap_or(*b)]))
            .collect(),
        files: recs.iter().map(part_name).collect(),
    }
}

/// A record's name, with the part when it is windowed.
fn part_name(r: &PreparedRecord) -> String {
    if r.window.len() == r.len {
        r.name.clone()
    } else {
        format!(
            "{} [{:.3}–{:.3} s]",
            r.name,
            r.window.start as f64 * r.dt,
            r.window.end.saturating_sub(1) as f64 * r.dt
        )
    }
}

/// Least number of records for a split by records (below it, each record is split in time).
pub const MIN_RECORDS_FOR_RECORD_SPLIT: usize = 6;

/// The fit/validation split: with [`MIN_RECORDS_FOR_RECORD_SPLIT`] records or more every third
/// one (the 3rd, 6th, … in the order given) is held out; with fewer, holding out whole records
/// would take away too much of what the effects show in (one of five tests may be the only
/// one that excites an effect), so the last third of each record is held out instead.
fn split_records(recs: &[PreparedRecord]) -> (Vec<PreparedRecord>, Vec<PreparedRecord>, String) {
    if recs.len() >= MIN_RECORDS_FOR_RECORD_SPLIT {
        let (mut fit, mut val) = (Vec::new(), Vec::new());
        for (i, r) in recs.iter().enumerate() {
            if i % 3 == 2 {
                val.push(r.clone());
            } else {
                fit.push(r.clone());
            }
        }
        (
            fit,
            val,
            "every third record in the order given (3rd, 6th, …) is held out: it is never \
             used by any fit, the paper's method included, and serves only to validate"
                .into(),
        )
    } else {
        let fit = recs
            .iter()
            .map(|r| r.windowed(0..(2 * r.len) / 3))
            .collect();
        let val = recs
            .iter()
            .map(|r| r.windowed((2 * r.len) / 3..r.len))
            .collect();
        (
            fit,
            val,
            "fewer than six records: the first two thirds of each record are fitted, the last \
             third is held out for validation (the replay runs through the whole record)"
                .into(),
        )
    }
}

/// What the data lack for a calibration, one sentence each (empty: enough).
fn missing_data(records: &[Record], recs: &[PreparedRecord]) -> Vec<String> {
    let mut missing = Vec::new();
    let total: f64 = recs.iter().map(|r| r.duration_s()).sum();
    if total < MIN_TOTAL_DURATION_S {
        missing.push(format!(
            "duration: {total:.3} s of usable records in total, at least {MIN_TOTAL_DURATION_S} s \
             needed (a few periods of the slowest dynamics: valve delay, oil column, position loop)"
        ));
    }
    if let Some(r) = recs.iter().find(|r| r.dt > 1.0 / MIN_SAMPLE_RATE_HZ) {
        missing.push(format!(
            "sample rate: {} is sampled at {:.1} Hz, at least {MIN_SAMPLE_RATE_HZ} Hz needed \
             (the metric compares the band up to 25 Hz)",
            r.name,
            1.0 / r.dt
        ));
    }
    if !recs.is_empty() {
        let v_var = recs
            .iter()
            .map(|r| {
                let m = r.v_in.iter().sum::<f64>() / r.len.max(1) as f64;
                rms(&r.v_in.iter().map(|v| v - m).collect::<Vec<_>>())
            })
            .fold(0.0f64, f64::max);
        if v_var < MIN_COMMAND_RMS_V {
            missing.push(format!(
                "excitation: the command v_in varies by at most {v_var:.3} V RMS in any record \
                 (at least {MIN_COMMAND_RMS_V} V needed to see the valve's gain and delay)"
            ));
        }
        let u_moves = recs.iter().any(|r| {
            let m = r.u.iter().sum::<f64>() / r.len.max(1) as f64;
            let dev = rms(&r.u.iter().map(|v| v - m).collect::<Vec<_>>());
            dev > 5.0 * r.noise_u.max(1e-7)
        });
        if !u_moves {
            missing.push(
                "excitation: the stroke u never moves above five times its sensor noise".into(),
            );
        }
    }
    if recs.is_empty() && !records.is_empty() {
        missing.push("channels: no record has both `v_in` and `u`".into());
    }
    missing
}

/// Least total duration of the records [s].
pub const MIN_TOTAL_DURATION_S: f64 = 2.0;
/// Least sample rate [Hz].
pub const MIN_SAMPLE_RATE_HZ: f64 = 100.0;
/// Least RMS variation of `v_in` in at least one record [V].
pub const MIN_COMMAND_RMS_V: f64 = 0.02;

fn empty_diagnostics() -> Diagnostics {
    Diagnostics {
        whiteness: diagnose::Whiteness {
            lag1: 0.0,
            share_outside: 0.0,
            ljung_box: 0.0,
            max_lag: 0,
        },
        correlations: Vec::new(),
        high_frequency_share: 0.0,
    }
}

fn summary(recs: &[PreparedRecord], replays: &[Replay], weighted: &[f64]) -> ErrorSummary {
    let mut channels = BTreeMap::new();
    let pooled = |f: &dyn Fn(&Replay) -> Option<f64>| -> Option<f64> {
        let (mut s, mut n) = (0.0, 0usize);
        for r in replays {
            if let Some(v) = f(r) {
                s += v * v * r.errors.samples as f64;
                n += r.errors.samples;
            }
        }
        (n > 0).then(|| (s / n as f64).sqrt())
    };
    for (name, f) in [
        (
            "du",
            &(|r: &Replay| Some(r.errors.du)) as &dyn Fn(&Replay) -> Option<f64>,
        ),
        ("du_nrmse", &|r: &Replay| Some(r.errors.du_nrmse)),
        ("ydd", &|r: &Replay| r.errors.ydd),
        ("ydd_nrmse", &|r: &Replay| r.errors.ydd_nrmse),
        ("u", &|r: &Replay| Some(r.errors.u)),
        ("p1", &|r: &Replay| r.errors.p1),
        ("p2", &|r: &Replay| r.errors.p2),
    ] {
        if let Some(v) = pooled(f) {
            channels.insert(name.to_string(), v);
        }
    }
    ErrorSummary {
        metric: METRIC.to_string(),
        value: rms(weighted),
        channels,
        files: recs
            .iter()
            .zip(replays)
            .map(|(p, r)| (p.name.clone(), r.errors))
            .collect(),
    }
}

fn weighted_of(recs: &[PreparedRecord], replays: &[Replay]) -> Vec<f64> {
    let mut w = Vec::new();
    for (p, r) in recs.iter().zip(replays) {
        p.weighted_residuals(&r.sim, &mut w);
    }
    w
}

fn diagnostics(recs: &[PreparedRecord], replays: &[Replay], weighted: &[f64]) -> Diagnostics {
    Diagnostics {
        whiteness: diagnose::whiteness(weighted, 20),
        correlations: diagnose::feature_correlations(recs, replays),
        high_frequency_share: diagnose::high_frequency_share(recs, replays, 30.0),
    }
}

/// The paper's section-4 method on the open-loop sine tests (platform still, sinusoidal
/// `v_in`): `u̇/V_in` at each test's frequency, measured vs nominal twin; Cd scales with the
/// mean gain ratio, τ shifts by the slope of the phase difference.
fn paper_baseline(
    params: &Params,
    recs: &[PreparedRecord],
    nominal: &[Replay],
) -> Option<PaperBaseline> {
    let mut files = Vec::new();
    let (mut ratio_sum, mut wsum) = (0.0, 0.0);
    let (mut sxy, mut sxx) = (0.0, 0.0);
    for (p, r) in recs.iter().zip(nominal) {
        if p.platform_moves {
            continue;
        }
        let Some(f) = sine_frequency(&p.v_in, p.dt) else {
            continue;
        };
        let periods = ((p.duration_s() - 0.5) * f).floor() as usize;
        if periods < 1 {
            continue;
        }
        let v = first_harmonic(&p.v_in, p.dt, 0.0, f, periods);
        // Is v_in a sine? Its first harmonic must carry (almost) all its power.
        let v_rms = rms(&p.v_in[p.len - (periods as f64 / f / p.dt) as usize..]);
        if !(v.norm() > 0.0 && (v.norm() / (v_rms * 2f64.sqrt()) - 1.0).abs() < 0.05) {
            continue;
        }
        let gm = first_harmonic(&p.du_meas_f, p.dt, 0.0, f, periods) / v;
        let gs = first_harmonic(&r.twin_du, p.dt, 0.0, f, periods) / v;
        if !(gm.norm().is_finite() && gs.norm() > 0.0) {
            continue;
        }
        let w = 1.0;
        ratio_sum += w * gm.norm() / gs.norm();
        wsum += w;
        let dphi = (gm / gs).arg();
        let x = 2.0 * std::f64::consts::PI * f;
        sxy += x * (-dphi);
        sxx += x * x;
        files.push(p.name.clone());
    }
    if files.is_empty() || wsum == 0.0 {
        return None;
    }
    let cd = (params.plant.valve.cd * ratio_sum / wsum).clamp(1e-3, 1.0);
    let tau = (params.plant.valve.tau_s + sxy / sxx).clamp(0.0, 0.1);
    Some(PaperBaseline {
        files,
        cd,
        tau_s: tau,
    })
}

/// Frequency of a sinusoidal command from its upward zero crossings [Hz].
fn sine_frequency(v: &[f64], dt: f64) -> Option<f64> {
    let mut crossings = Vec::new();
    for i in 1..v.len() {
        if v[i - 1] < 0.0 && v[i] >= 0.0 {
            let frac = -v[i - 1] / (v[i] - v[i - 1]);
            crossings.push((i - 1) as f64 + frac);
        }
    }
    if crossings.len() < 2 {
        return None;
    }
    let span = (crossings[crossings.len() - 1] - crossings[0]) * dt;
    (span > 0.0).then(|| (crossings.len() - 1) as f64 / span)
}

/// A report for data that cannot be calibrated: the nominal replay (when possible), no
/// effect, nothing fitted.
fn insufficient_report(
    params: &Params,
    all: Vec<PreparedRecord>,
    nominal_replays: Vec<Replay>,
    missing: Vec<String>,
    notes: Vec<String>,
) -> CalibrationReport {
    let w = weighted_of(&all, &nominal_replays);
    let mut error_nominal = summary(&all, &nominal_replays, &w);
    if w.is_empty() {
        // Nothing could be replayed: no error to report (null in report.json, — in report.md).
        error_nominal.value = f64::NAN;
    }
    let raw = raw_pooled(&nominal_replays);
    CalibrationReport {
        nominal: *params,
        params: *params,
        verdict: Verdict::InsufficientData,
        effects: Vec::new(),
        candidates: Vec::new(),
        calibrated: Vec::new(),
        mass_fitted: false,
        correlation: (Vec::new(), Vec::new()),
        baseline: None,
        error_before: error_nominal.clone(),
        error_after: error_nominal.clone(),
        error_nominal,
        error_baseline: None,
        diagnostics_before: empty_diagnostics(),
        diagnostics_after: empty_diagnostics(),
        n: w.len(),
        n_eff: 0.0,
        evaluations: 0,
        files: all.iter().map(|r| r.name.clone()).collect(),
        replays_before: nominal_replays.clone(),
        replays_after: nominal_replays.clone(),
        replays_nominal: nominal_replays,
        records: all,
        notes,
        missing,
        split: Split::default(),
        error_training: None,
        error_validation: None,
        raw_nrmse: RawNrmse {
            definition: RAW_NRMSE.into(),
            nominal: raw.clone(),
            before: raw.clone(),
            after: raw,
            validation: BTreeMap::new(),
        },
        residual_left: None,
    }
}

/// Largest weighted RMS of any channel of a record.
fn worst_channel(c: &ChannelErrors) -> f64 {
    [
        Some(c.weighted_du),
        c.weighted_ydd,
        c.weighted_p1,
        c.weighted_p2,
    ]
    .into_iter()
    .flatten()
    .fold(0.0, f64::max)
}

/// Calibrates the twin on measured records: the paper's method, then Levenberg–Marquardt on
/// the declared parameters, then the effect loop (see the [module docs](self)). `progress` is
/// called after every campaign replay; returning `false` cancels
/// ([`IdentifyError::Cancelled`]).
///
/// The records are split (see [`CalibrationReport::split`]): every fit uses the fit part only,
/// the held-out part validates each added effect and the final parameters. Data too short,
/// without excitation or without the `v_in`/`u` channels give the verdict
/// [`Verdict::InsufficientData`] and nothing fitted.
pub fn calibrate(
    params: &Params,
    records: &[Record],
    options: &CalibrationOptions,
    progress: &(dyn Fn(&Progress) -> bool + Sync),
) -> Result<CalibrationReport, IdentifyError> {
    params.validate()?;
    if records.is_empty() {
        return Err(IdentifyError::NoRecords);
    }
    let mut notes = Vec::new();
    let mut column_notes = Vec::new();
    let usable: Vec<&Record> = records
        .iter()
        .filter(|r| {
            let lacks: Vec<&str> = [("v_in", r.v_in.is_some()), ("u", r.u.is_some())]
                .into_iter()
                .filter(|(_, have)| !have)
                .map(|(c, _)| c)
                .collect();
            if !lacks.is_empty() {
                column_notes.push(format!(
                    "channels: {} has no `{}` column (needed to replay it); the record was left \
                     out",
                    r.path.display(),
                    lacks.join("`, `")
                ));
            }
            lacks.is_empty() && r.len() >= 2
        })
        .collect();
    let all: Vec<PreparedRecord> = usable
        .par_iter()
        .map(|r| PreparedRecord::new(r, &options.metric))
        .collect::<Result<_, _>>()?;
    let mut missing = missing_data(records, &all);
    if all.is_empty() {
        missing.extend(column_notes);
    } else {
        notes.extend(column_notes);
    }
    if !missing.is_empty() {
        let nominal = replay_all(params, &all).unwrap_or_default();
        let nominal = if nominal.len() == all.len() {
            nominal
        } else {
            Vec::new()
        };
        let all = if nominal.is_empty() { Vec::new() } else { all };
        return Ok(insufficient_report(params, all, nominal, missing, notes));
    }
    let (fit_recs, val_recs, rule) = split_records(&all);
    let split = Split {
        rule,
        fit: fit_recs.iter().map(part_name).collect(),
        validation: val_recs.iter().map(part_name).collect(),
    };

    let stage = std::sync::Mutex::new(String::from("nominal replay"));
    let cancelled = AtomicBool::new(false);
    let on_eval = |count: usize| -> bool {
        let s = stage.lock().map(|s| s.clone()).unwrap_or_default();
        let ok = progress(&Progress {
            stage: s,
            evaluations: count,
        });
        if !ok {
            cancelled.store(true, Ordering::Relaxed);
        }
        ok
    };
    let ev = Evaluator {
        records: &fit_recs,
        on_eval: &on_eval,
        evaluations: AtomicUsize::new(0),
        cancelled: AtomicBool::new(false),
    };
    let set_stage = |s: String| {
        if let Ok(mut g) = stage.lock() {
            *g = s;
        }
    };

    // Fits run with a coarser (still accurate) step; reported errors use the preset's.
    let mut fit_params = *params;
    fit_params.numerics.max_step_s = params.numerics.max_step_s.max(options.fit_step_s);
    let restore = |mut p: Params| {
        p.numerics = params.numerics;
        p
    };

    // 1. Nominal.
    let nominal_replays = replay_all(params, &all)?;
    let w_nom = weighted_of(&all, &nominal_replays);
    let error_nominal = summary(&all, &nominal_replays, &w_nom);
    if !on_eval(1) {
        return Err(IdentifyError::Cancelled);
    }

    // 2. Paper's method (on the fit records only).
    set_stage("paper's section-4 calibration".into());
    let nominal_fit = replay_all(params, &fit_recs)?;
    let baseline = paper_baseline(params, &fit_recs, &nominal_fit);
    let mut start = fit_params;
    let mut error_baseline = None;
    if let Some(b) = &baseline {
        start.plant.valve.cd = b.cd;
        start.plant.valve.tau_s = b.tau_s;
        let reps = replay_all(&restore(start), &all)?;
        let w = weighted_of(&all, &reps);
        error_baseline = Some(summary(&all, &reps, &w));
    } else {
        notes.push("no open-loop sine test found: the fit starts from the nominal Cd and τ".into());
    }

    // 3. Declared parameters; is the mass identifiable?
    set_stage("declared parameters (Cd, τ, mass)".into());
    let n = ev.residual_len();
    let probe = fit::fit(&ev, &start, &[Knob::Cd, Knob::Tau, Knob::Mass], 1, 1.0)?;
    let probe_r = ev
        .residuals(&probe.params)
        .ok_or(IdentifyError::Cancelled)?;
    let n_eff0 = fit::effective_count(&probe_r);
    let mass_rel_std = probe.values[2].std / probe.values[2].value * (n as f64 / n_eff0).sqrt();
    let mass_fitted = mass_rel_std.is_finite() && mass_rel_std < options.mass_max_rel_std;
    let declared: Vec<Knob> = if mass_fitted {
        vec![Knob::Cd, Knob::Tau, Knob::Mass]
    } else {
        notes.push(if mass_rel_std.is_finite() {
            format!(
                "mass not identifiable from these records (relative 1-σ ≈ {:.0} %): kept at {} kg",
                100.0 * mass_rel_std,
                params.plant.body.mass_kg
            )
        } else {
            format!(
                "mass not identifiable from these records: kept at {} kg",
                params.plant.body.mass_kg
            )
        });
        vec![Knob::Cd, Knob::Tau]
    };
    let base_start = if mass_fitted { probe.params } else { start };
    let before = fit::fit(
        &ev,
        &base_start,
        &declared,
        options.max_iterations,
        n_eff0 / n as f64,
    )?;
    notes.push(format!(
        "declared-parameter fit stopped: {} after {} replays",
        before.termination, before.evaluations
    ));
    // Can the data tell Cd and τ at all?
    let undetermined: Vec<String> = before
        .values
        .iter()
        .filter_map(|v| {
            let bad = match v.knob {
                Knob::Cd => !(v.std.is_finite() && v.std <= 0.2 * v.value),
                Knob::Tau => !(v.std.is_finite() && v.std <= 5e-3),
                _ => false,
            };
            bad.then(|| {
                format!(
                    "excitation: the records do not determine `{}` (1-σ {}); record longer or \
                     larger command and platform motions",
                    v.name,
                    if v.std.is_finite() {
                        format!("{:.3e}", v.std)
                    } else {
                        "unbounded".into()
                    }
                )
            })
        })
        .collect();
    if !undetermined.is_empty() {
        return Ok(insufficient_report(
            params,
            all,
            nominal_replays,
            undetermined,
            notes,
        ));
    }
    let before_r = ev
        .residuals(&before.params)
        .ok_or(IdentifyError::Cancelled)?;
    let n_eff = fit::effective_count(&before_r);
    let bic = |rss: f64, k: usize| n_eff * (rss / n as f64).ln() + k as f64 * n_eff.ln();
    let val_rms = |p: &Params| -> Result<f64, IdentifyError> {
        let reps = replay_all(p, &val_recs)?;
        Ok(rms(&weighted_of(&val_recs, &reps)))
    };

    // 4. Effect loop.
    let mut current: FitResult = before.clone();
    let mut current_val = val_rms(&current.params)?;
    let mut knobs = declared.clone();
    let mut added: Vec<(EffectId, f64, f64, [f64; 2])> = Vec::new();
    let mut candidates = Vec::new();
    let mut remaining: Vec<EffectId> = options
        .candidates
        .iter()
        .copied()
        .filter(|e| !e.enabled(params))
        .collect();
    let mut round = 0;
    while !remaining.is_empty()
        && added.len() < options.max_effects
        && round < 2 * options.max_effects
    {
        round += 1;
        set_stage(format!("candidate effects (round {round})"));
        let screen_knobs: Vec<Knob> = knobs.iter().copied().filter(|k| *k != Knob::Mass).collect();
        let results: Vec<Result<(EffectId, FitResult), IdentifyError>> = remaining
            .par_iter()
            .map(|&e| {
                let mut ks = screen_knobs.clone();
                ks.extend_from_slice(e.knobs());
                let p0 = multi_start(&ev, &current.params, e)?;
                fit::fit(&ev, &p0, &ks, options.screen_iterations, n_eff / n as f64).map(|f| (e, f))
            })
            .collect();
        if cancelled.load(Ordering::Relaxed) {
            return Err(IdentifyError::Cancelled);
        }
        let mut scored: Vec<(EffectId, FitResult, f64, f64)> = Vec::new();
        for r in results {
            let (e, f) = r?;
            let k = e.knobs().len();
            let score = bic(f.rss, knobs.len() + k) - bic(current.rss, knobs.len());
            let gain = 1.0 - f.rss / current.rss;
            scored.push((e, f, score, gain));
        }
        scored.sort_by(|a, b| a.2.total_cmp(&b.2));
        for (e, f, score, gain) in &scored {
            candidates.push(CandidateScore {
                effect: *e,
                round,
                score: *score,
                relative_gain: *gain,
                params: e
                    .knobs()
                    .iter()
                    .map(|k| (k.name().to_string(), k.value(&f.params)))
                    .collect(),
            });
        }
        let runner_up = scored.get(1).map(|(e, _, s, _)| (*e, *s));
        let Some((best, best_fit, score, gain)) = scored.into_iter().next() else {
            break;
        };
        let min_gain = if added.is_empty() {
            options.min_relative_gain
        } else {
            options.min_relative_gain_later
        };
        if !(score < 0.0 && gain >= min_gain) {
            break;
        }
        set_stage(format!("re-fit with {}", best.name()));
        let mut trial_knobs = knobs.clone();
        trial_knobs.extend_from_slice(best.knobs());
        let refit = fit::fit(
            &ev,
            &best_fit.params,
            &trial_knobs,
            options.max_iterations,
            n_eff / n as f64,
        )?;
        remaining.retain(|e| *e != best);
        // Validation: the effect must improve the error on the held-out records.
        let trial_val = val_rms(&refit.params)?;
        // (A NaN validation error does not improve either.)
        let improves = trial_val < (1.0 - options.min_validation_gain) * current_val;
        if !improves {
            notes.push(format!(
                "round {round}: `{}` improved the fit records (ΔBIC {score:.1}, {:.1} % of the \
                 residual) but not the held-out ones (validation weighted RMS {current_val:.3} → \
                 {trial_val:.3}): rejected",
                best.name(),
                100.0 * gain
            ));
            continue;
        }
        if let Some((other, other_score)) = runner_up
            && other_score < 0.0
            && other_score - score < options.ambiguity_margin
        {
            notes.push(format!(
                "round {round}: `{}` (ΔBIC {score:.1}) and `{}` (ΔBIC {other_score:.1}) explain \
                 the residual about equally (difference {:.1} < {:.0}): the data cannot tell \
                 them apart, `{}` was added by a narrow margin.{}",
                best.name(),
                other.name(),
                other_score - score,
                options.ambiguity_margin,
                best.name(),
                confounding_hint(best, other, &all),
            ));
        }
        knobs = trial_knobs;
        added.push((best, score, gain, [current_val, trial_val]));
        current = refit;
        current_val = trial_val;
    }

    // 5. Final replays (preset step, as `seat-twin replay` runs them), diagnostics, verdict.
    set_stage("diagnostics".into());
    let before_params = restore(before.params);
    current.params = restore(current.params);
    let replays_before = replay_all(&before_params, &all)?;
    let w_before = weighted_of(&all, &replays_before);
    let error_before = summary(&all, &replays_before, &w_before);
    let diagnostics_before = diagnostics(&all, &replays_before, &w_before);
    let replays_after = replay_all(&current.params, &all)?;
    let w_after = weighted_of(&all, &replays_after);
    let error_after = summary(&all, &replays_after, &w_after);
    let diagnostics_after = diagnostics(&all, &replays_after, &w_after);
    let fit_before = replay_all(&before_params, &fit_recs)?;
    let fit_after = replay_all(&current.params, &fit_recs)?;
    let error_training = stage_errors(&fit_recs, &fit_before, &fit_after);
    let val_nominal = replay_all(params, &val_recs)?;
    let val_before = replay_all(&before_params, &val_recs)?;
    let val_after = replay_all(&current.params, &val_recs)?;
    let error_validation = stage_errors(&val_recs, &val_before, &val_after);
    let raw_nrmse = RawNrmse {
        definition: RAW_NRMSE.into(),
        nominal: raw_pooled(&nominal_replays),
        before: raw_pooled(&replays_before),
        after: raw_pooled(&replays_after),
        validation: [
            ("nominal", &val_nominal),
            ("before", &val_before),
            ("after", &val_after),
        ]
        .into_iter()
        .map(|(k, r)| (k.to_string(), raw_pooled(r)))
        .collect(),
    };

    let at_noise = |e: &ErrorSummary| {
        e.value <= options.noise_level
            && e.files
                .iter()
                .all(|(_, c)| worst_channel(c) <= options.noise_level_record)
    };
    let verdict = if !added.is_empty() {
        if at_noise(&error_after) {
            Verdict::Explained
        } else {
            Verdict::Unexplained
        }
    } else if at_noise(&error_before) {
        Verdict::NoMissingEffect
    } else {
        Verdict::Unexplained
    };
    let residual_left = (verdict == Verdict::Unexplained)
        .then(|| diagnose::residual_left(&all, &replays_after, options.noise_level_record));
    let effects = added
        .iter()
        .map(|(e, score, gain, val)| {
            let vals: Vec<&FittedValue> = current
                .values
                .iter()
                .filter(|v| e.knobs().contains(&v.knob))
                .collect();
            let corr = diagnostics_before
                .correlations
                .iter()
                .find(|c| c.feature == e.signature());
            let corr_after = diagnostics_after
                .correlations
                .iter()
                .find(|c| c.feature == e.signature());
            let sig = match (corr, corr_after) {
                (Some(a), Some(b)) => format!(
                    "; correlation of the velocity residual with `{}`: {:+.3} before, {:+.3} after \
                     (acceleration: {} → {})",
                    a.feature,
                    a.velocity,
                    b.velocity,
                    fmt_signed(a.acceleration),
                    fmt_signed(b.acceleration)
                ),
                _ => format!(
                    "; high-frequency share of the acceleration residual: {:.3} before, {:.3} after",
                    diagnostics_before.high_frequency_share, diagnostics_after.high_frequency_share
                ),
            };
            AddedEffect {
                effect: *e,
                params: vals.iter().map(|v| (v.name.clone(), v.value)).collect(),
                uncertainties: vals.iter().map(|v| (v.name.clone(), v.std)).collect(),
                evidence: format!(
                    "ΔBIC = {score:.1} when added; removed {:.1} % of the remaining weighted \
                     residual sum of squares on the fit records; validation weighted RMS \
                     {:.3} → {:.3} on the held-out records{sig}",
                    100.0 * gain,
                    val[0],
                    val[1]
                ),
            }
        })
        .collect();
    let calibrated = current
        .values
        .iter()
        .filter(|v| matches!(v.knob, Knob::Cd | Knob::Tau | Knob::Mass))
        .cloned()
        .collect();
    Ok(CalibrationReport {
        nominal: *params,
        params: current.params,
        verdict,
        effects,
        candidates,
        calibrated,
        mass_fitted,
        correlation: (
            knobs.iter().map(|k| k.name().to_string()).collect(),
            current.correlation.clone(),
        ),
        baseline,
        error_nominal,
        error_baseline,
        error_before,
        error_after,
        diagnostics_before,
        diagnostics_after,
        n,
        n_eff,
        evaluations: ev.evaluations.load(Ordering::Relaxed),
        files: all.iter().map(|r| r.name.clone()).collect(),
        replays_before,
        replays_after,
        replays_nominal: nominal_replays,
        records: all,
        notes,
        missing: Vec::new(),
        split,
        error_training: Some(error_training),
        error_validation: Some(error_validation),
        raw_nrmse,
        residual_left,
    })
}

/// `+0.123`, or `—` when not defined.
fn fmt_signed(v: f64) -> String {
    if v.is_finite() {
        format!("{v:+.3}")
    } else {
        "—".into()
    }
}
