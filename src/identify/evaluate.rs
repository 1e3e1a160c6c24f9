//! Errors, diagnostics and replays of a stage, pooled over records: the numbers every stage
//! of the calibration reports.

use super::IdentifyError;
use super::diagnose;
use super::replay::{PreparedRecord, RawChannel, Replay, part_name, replay_prepared, rms};
use super::result::{
    CalibrationReport, Diagnostics, ErrorSummary, METRIC, RAW_NRMSE, RawNrmse, Split, StageErrors,
    Verdict,
};
use crate::params::Params;
use rayon::prelude::*;
use std::collections::BTreeMap;

/// `p` with the preset's numerics back (undoes [`fit_params`](super::stages::fit_params)):
/// what the reported errors replay with.
pub fn with_numerics_of(mut p: Params, preset: &Params) -> Params {
    p.numerics = preset.numerics;
    p
}

/// Replays every record with `params` (in parallel).
pub(super) fn replay_all(
    params: &Params,
    recs: &[PreparedRecord],
) -> Result<Vec<Replay>, IdentifyError> {
    recs.par_iter()
        .map(|r| replay_prepared(params, r))
        .collect()
}

/// The replays of `recs` taken from `replays`, the replays of `all` with the same parameters:
/// a replay depends only on the parameters and the record, and `recs` (the fit or the
/// held-out part) are copies of records of `all`, so the report replays each twin once.
/// Where a record of `recs` is not in `all` exactly once by name, length and Cd factor, the
/// part is replayed with `params`.
pub(super) fn replays_of(
    params: &Params,
    all: &[PreparedRecord],
    replays: &[Replay],
    recs: &[PreparedRecord],
) -> Result<Vec<Replay>, IdentifyError> {
    match picked(all, replays, recs) {
        Some(r) => Ok(r),
        None => replay_all(params, recs),
    }
}

/// [`replays_of`]'s pick: `None` where a record cannot be matched.
fn picked(
    all: &[PreparedRecord],
    replays: &[Replay],
    recs: &[PreparedRecord],
) -> Option<Vec<Replay>> {
    if replays.len() != all.len() {
        return None;
    }
    recs.iter()
        .map(|r| {
            let mut same = all
                .iter()
                .zip(replays)
                .filter(|(a, _)| a.name == r.name && a.len == r.len && a.cd_factor == r.cd_factor);
            match (same.next(), same.next()) {
                (Some((_, rep)), None) => Some(rep.clone()),
                _ => None,
            }
        })
        .collect()
}

/// Per channel, `√(Σ num / Σ den)` over `replays`, where `terms` gives each replay's
/// `(num, den)` per channel (`None` for a channel it lacks); a channel whose `Σ den` is not
/// positive is left out.
fn pooled<const K: usize>(
    replays: &[Replay],
    terms: impl Fn(&Replay) -> [(&'static str, Option<(f64, f64)>); K],
) -> BTreeMap<String, f64> {
    let mut acc: BTreeMap<&str, (f64, f64)> = BTreeMap::new();
    for r in replays {
        for (name, term) in terms(r) {
            if let Some((num, den)) = term {
                let e = acc.entry(name).or_insert((0.0, 0.0));
                e.0 += num;
                e.1 += den;
            }
        }
    }
    acc.into_iter()
        .filter(|(_, (_, d))| *d > 0.0)
        .map(|(k, (e, d))| (k.to_string(), (e / d).sqrt()))
        .collect()
}

/// Pooled raw NRMSE per channel over `replays`.
pub(super) fn raw_pooled(replays: &[Replay]) -> BTreeMap<String, f64> {
    pooled(replays, |r| {
        let n = r.errors.samples as f64;
        let raw = &r.errors.raw;
        let term = |c: RawChannel| {
            (
                n * c.rms_error * c.rms_error,
                n * c.measured_std * c.measured_std,
            )
        };
        [
            ("u", Some(term(raw.u))),
            ("ydd", raw.ydd.map(term)),
            ("p1", raw.p1.map(term)),
            ("p2", raw.p2.map(term)),
        ]
    })
}

/// Weighted RMS per channel (`du`, `ydd`, `p1`, `p2`) pooled over the replays.
pub(super) fn weighted_channels(replays: &[Replay]) -> BTreeMap<String, f64> {
    pooled(replays, |r| {
        let e = &r.errors;
        let n = e.samples as f64;
        let term = |v: f64| (n * v * v, n);
        [
            ("du", Some(term(e.weighted_du))),
            ("ydd", e.weighted_ydd.map(term)),
            ("p1", e.weighted_p1.map(term)),
            ("p2", e.weighted_p2.map(term)),
        ]
    })
}

/// Weighted error before and after, pooled and per channel, on `recs`.
pub(super) fn stage_errors(
    recs: &[PreparedRecord],
    before: &[Replay],
    after: &[Replay],
) -> StageErrors {
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

/// Diagnostics of a stage that was not reached.
pub(super) fn empty_diagnostics() -> Diagnostics {
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

/// The error summary of a stage: weighted RMS, pooled channel errors, per-file errors.
pub(super) fn summary(
    recs: &[PreparedRecord],
    replays: &[Replay],
    weighted: &[f64],
) -> ErrorSummary {
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

/// The weighted residuals of every record, concatenated.
pub(super) fn weighted_of(recs: &[PreparedRecord], replays: &[Replay]) -> Vec<f64> {
    let mut w = Vec::new();
    for (p, r) in recs.iter().zip(replays) {
        p.weighted_residuals(&r.sim, &mut w);
    }
    w
}

/// Whiteness, signature correlations and high-frequency share of a stage's residual.
pub(super) fn diagnostics(
    recs: &[PreparedRecord],
    replays: &[Replay],
    weighted: &[f64],
) -> Diagnostics {
    Diagnostics {
        whiteness: diagnose::whiteness(weighted, 20),
        correlations: diagnose::feature_correlations(recs, replays),
        high_frequency_share: diagnose::high_frequency_share(recs, replays, 30.0),
    }
}

/// A report for data that cannot be calibrated: the nominal replay (when possible), no
/// effect, nothing fitted.
pub(super) fn insufficient_report(
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
    let sims: Vec<_> = nominal_replays.iter().map(|r| &r.sim).collect();
    let raw_error =
        super::raw_error::raw_error_report(&all, &sims, super::raw_error::DEFAULT_LIMIT);
    CalibrationReport {
        nominal: *params,
        params: *params,
        proposed: Vec::new(),
        proposed_calibrated: Vec::new(),
        proposed_adds: Vec::new(),
        proposed_candidates: Vec::new(),
        proposed_leaves_out: Vec::new(),
        raw_error_proposed: None,
        drifts: Vec::new(),
        verdict: Verdict::InsufficientData,
        effects: Vec::new(),
        candidates: Vec::new(),
        calibrated: Vec::new(),
        sensors: Vec::new(),
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
            proposed: None,
            validation: BTreeMap::new(),
        },
        residual_left: None,
        raw_error_before: raw_error.clone(),
        raw_error_after: raw_error,
    }
}

/// `+0.123`, or `—` when not defined.
pub(super) fn fmt_signed(v: f64) -> String {
    if v.is_finite() {
        format!("{v:+.3}")
    } else {
        "—".into()
    }
}
