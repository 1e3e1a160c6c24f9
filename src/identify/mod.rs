//! Identification from measured records: replay, calibrate, trace the residual, add effects.
//!
//! The loop of issue 4, as a pure library (no files, threads of its own or clock; rayon
//! parallelises the replays):
//!
//! 1. [`replay`]: a [`crate::dataset::Record`] drives the twin in open loop with its `v_in` and
//!    platform motion; the twin's channels come back aligned with the record, with residuals.
//!    The error metric ([`replay`] module docs) compares the relative velocity and the body
//!    acceleration through the same zero-phase filter, weighted by the sensor noise, because
//!    the position of an integrating plant drifts.
//! 2. [`calibrate`]: the paper's own method (section 4: delay from the phase slope of the sine
//!    tests, Cd from their gain) gives the start; Levenberg–Marquardt then fits `Cd`, `τ` and
//!    (when the data can tell it) the mass, with uncertainties ([`fit`]).
//! 3. Each candidate effect of [`EffectId`] is fitted on top (in parallel) and scored by
//!    ΔBIC = n_eff·ln(RSS₁/RSS₀) + k·ln(n_eff), `n_eff` being the residual count corrected
//!    for autocorrelation, so a richer model must earn its parameters. The best one is added
//!    if ΔBIC < 0 and it removes at least `min_relative_gain` of the residual (a further effect:
//!    `min_relative_gain_later` of what remains); all parameters are re-fitted and the round
//!    repeats.
//! 4. [`diagnose`] gives the evidence: whiteness, correlations with the signature features,
//!    spectra. The verdict is `explained`, `no_missing_effect` or `unexplained`.
//!
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
        let e = &p.effects;
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
    /// Weighted RMS error at or below which the twin explains the data "to the noise level".
    pub noise_level: f64,
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
}

impl Verdict {
    /// As in `report.json`.
    pub fn name(self) -> &'static str {
        match self {
            Verdict::Explained => "explained",
            Verdict::NoMissingEffect => "no_missing_effect",
            Verdict::Unexplained => "unexplained",
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
}

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
    let cd = (params.valve.cd * ratio_sum / wsum).clamp(1e-3, 1.0);
    let tau = (params.valve.tau_s + sxy / sxx).clamp(0.0, 0.1);
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

/// Calibrates the twin on measured records: the paper's method, then Levenberg–Marquardt on
/// the declared parameters, then the effect loop (see the [module docs](self)). `progress` is
/// called after every campaign replay; returning `false` cancels
/// ([`IdentifyError::Cancelled`]).
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
    let recs: Vec<PreparedRecord> = records
        .par_iter()
        .map(|r| PreparedRecord::new(r, &options.metric))
        .collect::<Result<_, _>>()?;
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
        records: &recs,
        on_eval: &on_eval,
        evaluations: AtomicUsize::new(0),
        cancelled: AtomicBool::new(false),
    };
    let set_stage = |s: String| {
        if let Ok(mut g) = stage.lock() {
            *g = s;
        }
    };
    let mut notes = Vec::new();

    // Fits run with a coarser (still accurate) step; reported errors use the preset's.
    let mut fit_params = *params;
    fit_params.numerics.max_step_s = params.numerics.max_step_s.max(options.fit_step_s);
    let restore = |mut p: Params| {
        p.numerics = params.numerics;
        p
    };

    // 1. Nominal.
    let nominal_replays = replay_all(params, &recs)?;
    let w_nom = weighted_of(&recs, &nominal_replays);
    let error_nominal = summary(&recs, &nominal_replays, &w_nom);
    if !on_eval(1) {
        return Err(IdentifyError::Cancelled);
    }

    // 2. Paper's method.
    set_stage("paper's section-4 calibration".into());
    let baseline = paper_baseline(params, &recs, &nominal_replays);
    let mut start = fit_params;
    let mut error_baseline = None;
    if let Some(b) = &baseline {
        start.valve.cd = b.cd;
        start.valve.tau_s = b.tau_s;
        let reps = replay_all(&restore(start), &recs)?;
        let w = weighted_of(&recs, &reps);
        error_baseline = Some(summary(&recs, &reps, &w));
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
        notes.push(format!(
            "mass not identifiable from these records (relative 1-σ ≈ {:.0} %): kept at {} kg",
            100.0 * mass_rel_std,
            params.body.mass_kg
        ));
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
    let before_r = ev
        .residuals(&before.params)
        .ok_or(IdentifyError::Cancelled)?;
    let n_eff = fit::effective_count(&before_r);
    let bic = |rss: f64, k: usize| n_eff * (rss / n as f64).ln() + k as f64 * n_eff.ln();

    // 4. Effect loop.
    let mut current: FitResult = before.clone();
    let mut knobs = declared.clone();
    let mut added: Vec<(EffectId, f64, f64)> = Vec::new();
    let mut candidates = Vec::new();
    let mut remaining: Vec<EffectId> = options
        .candidates
        .iter()
        .copied()
        .filter(|e| !e.enabled(params))
        .collect();
    let before_noise = rms(&before_r) <= options.noise_level;
    let mut round = 0;
    while !remaining.is_empty() && added.len() < options.max_effects {
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
                confounding_hint(best, other, &recs),
            ));
        }
        set_stage(format!("re-fit with {}", best.name()));
        knobs.extend_from_slice(best.knobs());
        let refit = fit::fit(
            &ev,
            &best_fit.params,
            &knobs,
            options.max_iterations,
            n_eff / n as f64,
        )?;
        added.push((best, score, gain));
        current = refit;
        remaining.retain(|e| *e != best);
    }

    // 5. Final replays, diagnostics, verdict.
    set_stage("diagnostics".into());
    let before_params = restore(before.params);
    current.params = restore(current.params);
    let replays_before = replay_all(&before_params, &recs)?;
    let w_before = weighted_of(&recs, &replays_before);
    let error_before = summary(&recs, &replays_before, &w_before);
    let diagnostics_before = diagnostics(&recs, &replays_before, &w_before);
    let replays_after = replay_all(&current.params, &recs)?;
    let w_after = weighted_of(&recs, &replays_after);
    let error_after = summary(&recs, &replays_after, &w_after);
    let diagnostics_after = diagnostics(&recs, &replays_after, &w_after);

    let verdict = if !added.is_empty() {
        Verdict::Explained
    } else if before_noise {
        Verdict::NoMissingEffect
    } else {
        Verdict::Unexplained
    };
    let effects = added
        .iter()
        .map(|(e, score, gain)| {
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
                     (acceleration: {:+.3} → {:+.3})",
                    a.feature, a.velocity, b.velocity, a.acceleration, b.acceleration
                ),
                _ => format!(
                    "; high-frequency share of the acceleration residual: {:.3} before, {:.3} after",
                    diagnostics_before.high_frequency_share, diagnostics_after.high_frequency_share
                ),
            };
            AddedEffect {
                effect: *e,
                params: vals
                    .iter()
                    .map(|v| (v.name.clone(), v.value))
                    .collect(),
                uncertainties: vals.iter().map(|v| (v.name.clone(), v.std)).collect(),
                evidence: format!(
                    "ΔBIC = {score:.1} when added; removed {:.1} % of the remaining weighted \
                     residual sum of squares{sig}",
                    100.0 * gain
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
        files: recs.iter().map(|r| r.name.clone()).collect(),
        replays_before,
        replays_after,
        replays_nominal: nominal_replays,
        records: recs,
        notes,
    })
}
