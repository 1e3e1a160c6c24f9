//! The stages of a calibration before and after the effect search ([`super::effects`]): the
//! nominal replay, the paper's method, the declared-parameter fit, and the final replays
//! with the verdict. Each takes what it needs and returns a typed result;
//! [`super::calibrate_with`] runs them in order.

use super::data::Campaign;
use super::diagnose;
use super::effects::EffectSearch;
use super::evaluate::{
    diagnostics, fmt_signed, raw_pooled, replay_all, replays_of, stage_errors, summary,
    weighted_of, with_numerics_of,
};
use super::fit::{self, Bic, Evaluator, FitResult, FittedValue, Knob};
use super::paper::paper_baseline;
use super::progress::{Monitor, Stage};
use super::raw_error::{RawErrorReport, raw_error_report};
use super::replay::{PreparedRecord, Replay};
use super::result::{
    AddedEffect, CalibrationReport, ErrorSummary, PaperBaseline, RAW_NRMSE, RawNrmse, Verdict,
};
use super::sensors::{keep_needed_sensors, set_back_exact_sensors, with_sized_sensors};
use super::{CalibrationOptions, IdentifyError};
use crate::params::Params;

/// The parameters a stage fits with: the preset's, with the RK4 step coarsened to
/// [`CalibrationOptions::fit_step_s`] (the reported errors always use the preset's step).
pub fn fit_params(params: &Params, options: &CalibrationOptions) -> Params {
    let mut p = *params;
    p.numerics.max_step_s = params.numerics.max_step_s.max(options.fit_step_s);
    p
}

/// The nominal stage's result.
#[derive(Debug, Clone)]
pub struct Nominal {
    /// Every record replayed with the nominal parameters.
    pub replays: Vec<Replay>,
    /// Their error.
    pub error: ErrorSummary,
}

/// Replays every record with the nominal parameters.
pub fn nominal(
    params: &Params,
    campaign: &Campaign,
    monitor: &Monitor<'_>,
) -> Result<Nominal, IdentifyError> {
    monitor.enter(Stage::Nominal, 1);
    let replays = replay_all(params, &campaign.all)?;
    let w = weighted_of(&campaign.all, &replays);
    let error = summary(&campaign.all, &replays, &w);
    monitor.advance();
    monitor.check()?;
    Ok(Nominal { replays, error })
}

/// The paper-method stage's result.
#[derive(Debug, Clone)]
pub struct Paper {
    /// The paper's Cd and τ, if open-loop sine tests were among the fit records.
    pub baseline: Option<PaperBaseline>,
    /// Where the declared fit starts: `start` with the paper's Cd and τ, if any.
    pub start: Params,
    /// Error of the paper's Cd and τ on all records (preset's step).
    pub error: Option<ErrorSummary>,
}

/// The paper's section-4 calibration on the fit records, from `start` (the fit parameters);
/// `nominal` is the [`nominal`] stage of `campaign`.
pub fn paper(
    params: &Params,
    start: &Params,
    campaign: &Campaign,
    nominal: &Nominal,
    monitor: &Monitor<'_>,
) -> Result<Paper, IdentifyError> {
    monitor.enter(Stage::PaperBaseline, 1);
    let nominal_fit = replays_of(params, &campaign.all, &nominal.replays, &campaign.fit)?;
    let baseline = paper_baseline(params, &campaign.fit, &nominal_fit);
    let mut start = *start;
    let mut error = None;
    if let Some(b) = &baseline {
        start.plant.valve.cd = b.cd;
        start.plant.valve.tau_s = b.tau_s;
        let reps = replay_all(&with_numerics_of(start, params), &campaign.all)?;
        let w = weighted_of(&campaign.all, &reps);
        error = Some(summary(&campaign.all, &reps, &w));
    }
    monitor.advance();
    Ok(Paper {
        baseline,
        start,
        error,
    })
}

/// The declared-parameter fit's result.
#[derive(Debug, Clone)]
pub struct Declared {
    /// The fit (Cd, τ and, if identifiable, the mass).
    pub fit: FitResult,
    /// The knobs fitted.
    pub knobs: Vec<Knob>,
    /// Whether the mass was identifiable and fitted.
    pub mass_fitted: bool,
    /// Notes for the report (mass identifiability, why the fit stopped).
    pub notes: Vec<String>,
    /// Why the data cannot determine Cd or τ, one sentence each (empty: they can).
    pub undetermined: Vec<String>,
}

/// Largest 1-σ of Cd, relative to its value, for Cd to count as determined [-].
pub const CD_MAX_REL_STD: f64 = 0.2;
/// Largest 1-σ of τ for τ to count as determined \[s\].
pub const TAU_MAX_STD_S: f64 = 5e-3;

/// Whether a fitted Cd or τ is left undetermined by its 1-σ ([`CD_MAX_REL_STD`],
/// [`TAU_MAX_STD_S`]); other knobs are judged elsewhere.
pub(super) fn undetermined(v: &FittedValue) -> bool {
    match v.knob {
        Knob::Cd => !(v.std.is_finite() && v.std <= CD_MAX_REL_STD * v.value),
        Knob::Tau => !(v.std.is_finite() && v.std <= TAU_MAX_STD_S),
        _ => false,
    }
}

/// Fits Cd, τ and — when a one-Jacobian probe shows its relative 1-σ below
/// [`CalibrationOptions::mass_max_rel_std`] — the mass, from `start`. Says which of Cd and τ
/// the data leave undetermined.
pub fn declared_fit(
    ev: &Evaluator<'_>,
    start: &Params,
    nominal_mass_kg: f64,
    options: &CalibrationOptions,
) -> Result<Declared, IdentifyError> {
    ev.monitor
        .enter(Stage::DeclaredFit, 1 + options.max_iterations);
    let mut notes = Vec::new();
    let n = ev.residual_len();
    let probe = fit::fit(ev, start, &[Knob::Cd, Knob::Tau, Knob::Mass], 1, 1.0)?;
    let probe_r = ev
        .residuals(&probe.params)
        .ok_or(IdentifyError::Cancelled)?;
    let n_eff0 = fit::effective_count(&probe_r);
    // Relative to the declared mass, not to the probe's value: with an effect still missing,
    // the probe's one step can take the mass far off (survey draw 2020 at 10 kHz: 80 kg
    // from 11.7), where the same 1-σ reads as a small fraction.
    let mass_rel_std = probe.values[2].std / nominal_mass_kg * (n as f64 / n_eff0).sqrt();
    let mass_fitted = mass_rel_std.is_finite() && mass_rel_std < options.mass_max_rel_std;
    let mut knobs: Vec<Knob> = if mass_fitted {
        vec![Knob::Cd, Knob::Tau, Knob::Mass]
    } else {
        notes.push(if mass_rel_std.is_finite() {
            format!(
                "mass not identifiable from these records (relative 1-σ ≈ {:.0} %): kept at \
                 {nominal_mass_kg} kg",
                100.0 * mass_rel_std,
            )
        } else {
            format!("mass not identifiable from these records: kept at {nominal_mass_kg} kg")
        });
        vec![Knob::Cd, Knob::Tau]
    };

    let base_start = if mass_fitted { probe.params } else { *start };
    let fit = fit::fit(
        ev,
        &base_start,
        &knobs,
        options.max_iterations,
        n_eff0 / n as f64,
    )?;
    notes.push(format!(
        "declared-parameter fit stopped: {} after {} replays",
        fit.termination, fit.evaluations
    ));
    let undetermined: Vec<String> = fit
        .values
        .iter()
        .filter(|v| undetermined(v))
        .map(|v| {
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
        .collect();
    // The sensors: with ÿ on every record, the stroke sensor's lag parts from the valve's
    // delay (ÿ is not lagged) and the accelerometer's scale and offset from the plant. They
    // are fitted from the declared fit and kept only when the fit earns their three
    // parameters by ΔBIC < −10 (strong evidence), every one with a finite uncertainty.
    // A property the data pin at its bound (a lag at 0) or cannot size (an infinite
    // uncertainty) is dropped and the others re-fitted without it: an accelerometer offset
    // and scale stand on their own when the stroke sensor has no lag.
    let mut fit = fit;
    if undetermined.is_empty() && ev.records.iter().all(|r| r.ydd.is_some()) {
        let mut sensors = Knob::SENSORS.to_vec();
        let mut with = knobs.clone();
        with.extend(&sensors);
        // The stroke filter starts at 2 ms: it runs on the samples, and a time constant well
        // under a sample interval hardly changes them, so from 0 the fit could not move it.
        let mut sensor_start = fit.params;
        if sensor_start.sensors.u_lag_s == 0.0 {
            sensor_start.sensors.u_lag_s = SENSOR_LAG_START_S;
        }
        let mut s = fit::fit(
            ev,
            &sensor_start,
            &with,
            options.max_iterations,
            n_eff0 / n as f64,
        )?;
        // At its bound first (a singular fit leaves every uncertainty undefined), else the
        // properties without a finite uncertainty.
        let at_bound: Vec<Knob> = s
            .values
            .iter()
            .filter(|v| v.knob == Knob::SensorULag && v.value <= 0.0)
            .map(|v| v.knob)
            .collect();
        let drop = if at_bound.is_empty() {
            s.values
                .iter()
                .filter(|v| v.knob.sensor().is_some() && !v.std.is_finite())
                .map(|v| v.knob)
                .collect()
        } else {
            at_bound
        };
        if !drop.is_empty() && drop.len() < sensors.len() {
            sensors.retain(|k| !drop.contains(k));
            with = knobs.clone();
            with.extend(&sensors);
            let mut start = sensor_start;
            for k in &drop {
                if let Some((_, _, exact)) = k.sensor() {
                    k.spec().set_unchecked(&mut start, exact);
                }
            }
            s = fit::fit(ev, &start, &with, options.max_iterations, n_eff0 / n as f64)?;
        }
        let bic = fit::Bic { n, n_eff: n_eff0 };
        let gain = bic.value(s.rss, with.len()) - bic.value(fit.rss, knobs.len());
        let finite = s.values.iter().all(|v| v.std.is_finite());
        notes.push(format!(
            "sensor properties (ÿ scale and offset, u lag) {}: ΔBIC {gain:.1}",
            if gain < -10.0 && finite {
                "estimated"
            } else {
                "not supported by the data, kept exact"
            }
        ));
        if gain < -10.0 && finite {
            fit = s;
            knobs = with;
        }
    }
    Ok(Declared {
        fit,
        knobs,
        mass_fitted,
        notes,
        undetermined,
    })
}

/// Where the fit of the stroke sensor's filter time constant starts [s]: a few samples at the
/// usual 0.5–2 kHz, where the sampled filter's effect on the record is clearly non-zero.
const SENSOR_LAG_START_S: f64 = 2e-3;

/// The verdict from the raw error measure ([`super::raw_error`]) of the calibrated twin, the
/// one the report shows and calibrated.toml carries: `explained` when effects were added and
/// every record's every raw channel is at its noise floor in every band, `no_missing_effect`
/// when none was added and it is, else `unexplained`. The same measure is the report's
/// ([`CalibrationReport::raw_error_after`]), so the verdict can never disagree with the raw
/// residual the report shows. Until 2026-11-30 a calibration that added no effect was judged
/// on the twin before the last steps (the sensors within 3σ of exact set back, the mass
/// searched again for the oil column's ringing): a null rig at 10 kHz read `unexplained` on
/// one band at 3.01× its floor before the mass's search while the report, and the twin it
/// delivered, had every band at 2.13× or less (survey draw 2020, case 24).
pub fn verdict(effects_added: bool, after: &RawErrorReport) -> Verdict {
    match (after.at_floor(), effects_added) {
        (true, true) => Verdict::Explained,
        (true, false) => Verdict::NoMissingEffect,
        (false, _) => Verdict::Unexplained,
    }
}

/// The declared parameters (Cd, τ, mass) of a fit, with their uncertainties.
fn declared_values(fit: &FitResult) -> Vec<FittedValue> {
    fit.values
        .iter()
        .filter(|v| matches!(v.knob, Knob::Cd | Knob::Tau | Knob::Mass))
        .cloned()
        .collect()
}

/// The effect `a` as reported, with its values among `values` (the fit's) and `signature`
/// (its evidence from the diagnostics, empty where there is none).
fn added_effect(a: &super::effects::Added, values: &[FittedValue], signature: &str) -> AddedEffect {
    let vals: Vec<_> = values
        .iter()
        .filter(|v| a.effect.knobs().contains(&v.knob))
        .collect();
    AddedEffect {
        effect: a.effect,
        params: vals.iter().map(|v| (v.name.clone(), v.value)).collect(),
        uncertainties: vals.iter().map(|v| (v.name.clone(), v.std)).collect(),
        evidence: format!(
            "ΔBIC = {:.1} when added; removed {:.1} % of the remaining weighted residual sum of \
             squares on the fit records; validation weighted RMS {:.3} → {:.3} on the held-out \
             records{signature}{}",
            a.score,
            100.0 * a.gain,
            a.validation[0],
            a.validation[1],
            a.raw.map_or(String::new(), |r| format!(
                "; added on the raw error's terms, under the criterion's bars: the raw error's \
                 worst band {:.1}× → {:.1}× its floor{}",
                r.worst[0],
                r.worst[1],
                r.without.map_or(String::new(), |w| format!(
                    ", {w:.1}× with the effect fitted out again from the other parameters: its \
                     sizes trade off, the effect as a whole is determined"
                ))
            ))
        ),
    }
}

/// The proposed fit beyond the library, as the report needs it.
struct Beyond {
    terms: Vec<super::result::ProposedTerm>,
    calibrated: Vec<FittedValue>,
    left_out: Vec<super::result::LeftOut>,
    adds: Vec<AddedEffect>,
    raw: RawErrorReport,
    nrmse: std::collections::BTreeMap<String, f64>,
    val: std::collections::BTreeMap<String, f64>,
    params: Params,
}

/// What the stages before the report found.
pub struct Findings {
    /// The records and their split.
    pub campaign: Campaign,
    /// The nominal stage.
    pub nominal: Nominal,
    /// The paper's method.
    pub paper: Paper,
    /// The declared fit.
    pub declared: Declared,
    /// The effect search.
    pub search: EffectSearch,
    /// The corrections proposed beyond the library, if any were kept.
    pub proposal: Option<super::proposed::Proposal>,
    /// The scores of the terms the search beyond the library tried, kept or not.
    pub proposed_candidates: Vec<super::result::ProposedScore>,
    /// Parameters that change from record to record.
    pub drifts: Vec<super::result::Drift>,
    /// BIC counts of the declared fit.
    pub bic: Bic,
    /// Notes of every stage, in order.
    pub notes: Vec<String>,
}

/// The last stage: replays before and after at the preset's step (as `seat-twin replay`
/// runs them) on all, fit and held-out records, errors, raw NRMSE, diagnostics, the verdict,
/// what is left and the evidence of each added effect.
pub fn report(
    params: &Params,
    found: Findings,
    options: &CalibrationOptions,
    monitor: &Monitor<'_>,
) -> Result<CalibrationReport, IdentifyError> {
    let (all, fit_recs, val_recs) = (
        &found.campaign.all,
        &found.campaign.fit,
        &found.campaign.validation,
    );
    let before_params = with_numerics_of(found.declared.fit.params, params);
    let mut current = found.search.current;
    current.params = with_numerics_of(current.params, params);
    let estimated = with_sized_sensors(&current);
    let (mut sensors, mut sensor_notes) = set_back_exact_sensors(&mut current);
    // The calibrated twin's replays; when they ring out of time with the records, the mass
    // is searched again for that ringing (and the replays are those of the mass kept).
    let mut replays_after = replay_all(&current.params, all)?;
    let sims_after: Vec<_> = replays_after.iter().map(|r| &r.sim).collect();
    let mut raw_error_after = raw_error_report(all, &sims_after, options.raw_error_limit);
    // Sensor properties within 3σ of exact that the raw error needs are kept as estimated
    // (the twin judged is the twin delivered).
    let needs_sensors = !raw_error_after.at_floor() && current.params != estimated.params;
    if needs_sensors
        && let Some(kept) =
            keep_needed_sensors(&estimated, &raw_error_after, all, options.raw_error_limit)?
    {
        sensor_notes = vec![kept.note];
        sensors = kept.sensors;
        current = kept.fit;
        replays_after = kept.replays;
        raw_error_after = kept.raw;
    }
    let (replays_after, raw_error_after, ringing_note) = match super::ringing::refine_for_ringing(
        &mut current,
        all,
        &raw_error_after,
        options.raw_error_limit,
        monitor,
    )? {
        Some((refined, replays, raw)) => (replays, raw, Some(refined.note())),
        None => (replays_after, raw_error_after, None),
    };
    monitor.enter(Stage::Report, 7);
    let replay = |p: &Params, recs: &[PreparedRecord]| -> Result<Vec<Replay>, IdentifyError> {
        let r = replay_all(p, recs)?;
        monitor.advance();
        Ok(r)
    };
    // A part's replays taken from those of every record with the same parameters (`of`).
    let part = |p: &Params,
                of: &[Replay],
                recs: &[PreparedRecord]|
     -> Result<Vec<Replay>, IdentifyError> {
        let r = replays_of(p, all, of, recs)?;
        monitor.advance();
        Ok(r)
    };
    // Beyond the library: the proposed fit, replayed as its calibrated.toml is.
    let beyond = match &found.proposal {
        Some(prop) => {
            let mut fit = prop.fit.clone();
            fit.params = with_numerics_of(fit.params, params);
            // Its sensor properties are set back the same way (the report lists the library's).
            let _ = set_back_exact_sensors(&mut fit);
            let reps = replay_all(&fit.params, all)?;
            let sims: Vec<_> = reps.iter().map(|r| &r.sim).collect();
            let raw = raw_error_report(all, &sims, options.raw_error_limit);
            let nrmse = raw_pooled(&reps);
            let val = raw_pooled(&replays_of(&fit.params, all, &reps, val_recs)?);
            // Whether the records agree on each term's size ([`super::term_form`]).
            let agreements = prop
                .kept
                .iter()
                .map(|&(c, ..)| {
                    super::term_form::agreement(
                        &fit.params,
                        all,
                        c.knob(),
                        found.bic.ratio(),
                        monitor,
                    )
                })
                .collect::<Result<Vec<_>, _>>()?;
            Some(Beyond {
                terms: super::proposed::terms(prop, &fit, &agreements),
                calibrated: declared_values(&fit),
                left_out: prop.left_out.clone(),
                adds: prop
                    .beside
                    .iter()
                    .map(|a| added_effect(a, &fit.values, ""))
                    .collect(),
                raw,
                nrmse,
                val,
                params: fit.params,
            })
        }
        None => None,
    };
    let replays_before = replay(&before_params, all)?;
    let w_before = weighted_of(all, &replays_before);
    let error_before = summary(all, &replays_before, &w_before);
    let diagnostics_before = diagnostics(all, &replays_before, &w_before);
    monitor.advance();
    let w_after = weighted_of(all, &replays_after);
    let error_after = summary(all, &replays_after, &w_after);
    let diagnostics_after = diagnostics(all, &replays_after, &w_after);
    let fit_before = part(&before_params, &replays_before, fit_recs)?;
    let fit_after = part(&current.params, &replays_after, fit_recs)?;
    let error_training = stage_errors(fit_recs, &fit_before, &fit_after);
    // Nominal is the preset as it is: without the per-record Cd of a drift.
    let plain: Vec<_> = val_recs
        .iter()
        .map(|r| PreparedRecord {
            cd_factor: 1.0,
            ..r.clone()
        })
        .collect();
    let val_nominal = part(params, &found.nominal.replays, &plain)?;
    let val_before = part(&before_params, &replays_before, val_recs)?;
    let val_after = part(&current.params, &replays_after, val_recs)?;
    let error_validation = stage_errors(val_recs, &val_before, &val_after);
    let raw_nrmse = RawNrmse {
        definition: RAW_NRMSE.into(),
        nominal: raw_pooled(&found.nominal.replays),
        before: raw_pooled(&replays_before),
        after: raw_pooled(&replays_after),
        proposed: None,
        validation: [
            ("nominal", &val_nominal),
            ("before", &val_before),
            ("after", &val_after),
        ]
        .into_iter()
        .map(|(k, r)| (k.to_string(), raw_pooled(r)))
        .collect(),
    };
    let sims_before: Vec<_> = replays_before.iter().map(|r| &r.sim).collect();
    let raw_error_before = raw_error_report(all, &sims_before, options.raw_error_limit);
    // A parameter that drifts through the campaign is not in the library, however well the
    // twin follows each record with its own value.
    let verdict = if found.drifts.is_empty() {
        verdict(!found.search.added.is_empty(), &raw_error_after)
    } else {
        Verdict::Unexplained
    };
    let residual_left = (verdict == Verdict::Unexplained).then(|| {
        let mut left = diagnose::residual_left(all, &replays_after, options.noise_level_record);
        left.summary = format!(
            "Raw channels: {}. {}",
            raw_error_after.summary(),
            left.summary
        );
        left
    });
    let effects = found
        .search
        .added
        .iter()
        .map(|a| {
            let feature = |d: &super::result::Diagnostics| {
                d.correlations
                    .iter()
                    .find(|c| c.feature == a.effect.signature())
                    .cloned()
            };
            let sig = match (feature(&diagnostics_before), feature(&diagnostics_after)) {
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
            added_effect(a, &current.values, &sig)
        })
        .collect();
    let calibrated = declared_values(&current);
    let mut raw_nrmse = raw_nrmse;
    if let Some(b) = &beyond {
        raw_nrmse.proposed = Some(b.nrmse.clone());
        raw_nrmse
            .validation
            .insert("proposed".into(), b.val.clone());
    }
    let (
        out_params,
        proposed,
        proposed_calibrated,
        proposed_leaves_out,
        proposed_adds,
        raw_error_proposed,
    ) = match beyond {
        Some(b) => (
            b.params,
            b.terms,
            b.calibrated,
            b.left_out,
            b.adds,
            Some(b.raw),
        ),
        None => (
            current.params,
            Vec::new(),
            Vec::new(),
            Vec::new(),
            Vec::new(),
            None,
        ),
    };
    Ok(CalibrationReport {
        nominal: *params,
        params: out_params,
        proposed,
        proposed_calibrated,
        proposed_candidates: found.proposed_candidates,
        proposed_leaves_out,
        proposed_adds,
        raw_error_proposed,
        drifts: found.drifts,
        verdict,
        effects,
        candidates: found.search.candidates,
        calibrated,
        sensors,
        mass_fitted: found.declared.mass_fitted,
        correlation: (
            found
                .search
                .knobs
                .iter()
                .map(|k| k.name().to_string())
                .collect(),
            current.correlation.clone(),
        ),
        baseline: found.paper.baseline,
        error_nominal: found.nominal.error,
        error_baseline: found.paper.error,
        error_before,
        error_after,
        diagnostics_before,
        diagnostics_after,
        n: found.bic.n,
        n_eff: found.bic.n_eff,
        evaluations: monitor.evaluations(),
        files: all.iter().map(|r| r.name.clone()).collect(),
        replays_before,
        replays_after,
        replays_nominal: found.nominal.replays,
        records: found.campaign.all,
        notes: found
            .notes
            .into_iter()
            .chain(sensor_notes)
            .chain(ringing_note)
            .collect(),
        missing: Vec::new(),
        split: found.campaign.split,
        error_training: Some(error_training),
        error_validation: Some(error_validation),
        raw_nrmse,
        residual_left,
        raw_error_before,
        raw_error_after,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::identify::replay::SimChannels;

    /// A 12-bit stroke record (10 µm noise) of a 2 Hz motion, and the twin's replay of it:
    /// the same motion, its own noise, plus `drift` [m] at time `t` [s].
    fn stroke_case(drift: impl Fn(f64) -> f64) -> (PreparedRecord, SimChannels) {
        use rand::SeedableRng;
        use rand_distr::{Distribution, Normal};
        let (dt, n) = (1e-3, 8001);
        let lsb = 0.075 / 4096.0;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let nd = Normal::new(0.0, 1e-5).unwrap();
        let t: Vec<f64> = (0..n).map(|i| i as f64 * dt).collect();
        let motion = |t: f64| 0.01 * (2.0 * std::f64::consts::PI * 2.0 * t).sin();
        let u: Vec<f64> = t
            .iter()
            .map(|&t| lsb * ((motion(t) + nd.sample(&mut rng)) / lsb).round())
            .collect();
        let rec = crate::dataset::Record {
            path: "drift.csv".into(),
            metadata: vec![],
            dt,
            t: t.clone(),
            v_in: Some(
                t.iter()
                    .map(|t| (2.0 * std::f64::consts::PI * 2.0 * t).cos())
                    .collect(),
            ),
            u: Some(u),
            x: None,
            xdd: None,
            ydd: None,
            p1: None,
            p2: None,
            warnings: vec![],
        };
        let prep = PreparedRecord::new(&rec, &Default::default()).unwrap();
        let sim = SimChannels {
            t: t.clone(),
            u: t.iter()
                .map(|&t| motion(t) + drift(t) + nd.sample(&mut rng))
                .collect(),
            ydd: vec![0.0; n],
            p1: vec![0.0; n],
            p2: vec![0.0; n],
            ..Default::default()
        };
        (prep, sim)
    }

    /// Issue 20: a twin whose stroke drifts away from the record's, slowly (0.4 mm over 8 s,
    /// growing with t², as a valve null drifting with the oil temperature makes it), is not
    /// at the noise level. The old verdict judged the low-passed velocity weighted by its
    /// floor (1 % of its RMS), where this drift sits far below the limit 2.5 and read
    /// `explained`; the raw measure sees it in u's 0–0.5 Hz band, in the last seconds.
    #[test]
    fn verdict_sees_a_slow_stroke_drift_the_weighted_velocity_missed() {
        let (prep, sim) = stroke_case(|t| -4e-4 * (t / 8.0).powi(2));
        let old = prep.channel_errors(&sim);
        assert!(
            old.weighted_du < CalibrationOptions::default().noise_level_record,
            "the old measure called this at the noise level: {old:?}"
        );
        let raw = raw_error_report(std::slice::from_ref(&prep), &[&sim], 3.0);
        let (_, clean) = stroke_case(|_| 0.0);
        let at_floor = raw_error_report(std::slice::from_ref(&prep), &[&clean], 3.0);
        assert!(at_floor.at_floor(), "{}", at_floor.summary());
        assert_eq!(verdict(true, &at_floor), Verdict::Explained);
        assert_eq!(verdict(false, &at_floor), Verdict::NoMissingEffect);
        assert!(!raw.at_floor());
        assert_eq!(verdict(true, &raw), Verdict::Unexplained);
        assert_eq!(verdict(false, &raw), Verdict::Unexplained);
        let w = &raw.above[0];
        assert_eq!((w.file.as_str(), w.channel.as_str()), ("drift.csv", "u"));
        assert_eq!(w.band_hz, [0.0, 0.5]);
        assert!(w.ratio > 10.0 && w.window_s[0] >= 6.0, "{w:?}");
        let s = raw.summary();
        assert!(s.contains("drift.csv u 0–0.5 Hz"), "{s}");
    }

    /// The BIC prefers the smaller model unless the larger one lowers the RSS by enough.
    #[test]
    fn bic_charges_each_parameter_ln_n_eff() {
        let b = Bic {
            n: 1000,
            n_eff: 100.0,
        };
        let d = b.value(1.0, 3) - b.value(1.0, 2);
        assert!((d - 100f64.ln()).abs() < 1e-12);
        // Halving the RSS is worth n_eff·ln 2 ≈ 69 > ln 100 ≈ 4.6.
        assert!(b.value(0.5, 3) < b.value(1.0, 2));
        // 1 % less RSS (ΔBIC ≈ −1.0 + 4.6) is not.
        assert!(b.value(0.99, 3) > b.value(1.0, 2));
        assert!((b.ratio() - 0.1).abs() < 1e-15);
    }
}
