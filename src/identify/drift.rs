//! Parameters that change from record to record (issue 20, item 5): oil warming up during a
//! campaign changes its viscosity (the valve's discharge coefficient) and its bulk modulus.
//!
//! After the final fit, each drift candidate ([`drift_knobs`]: Cd always, the effective bulk
//! modulus when the compliance effect was added) is fitted again on every record alone, all
//! other parameters held at their final values, with its 1-σ uncertainty. A **drift** is
//! reported when the per-record values
//! 1. differ by more than their uncertainties can explain: χ² of their scatter about the
//!    weighted mean over `k − 1` degrees of freedom above [`DRIFT_CHI2`],
//! 2. span more than [`DRIFT_MIN_RELATIVE_RANGE`] of their mean, and
//! 3. change with the record order of the campaign (Spearman rank correlation with the file
//!    order of magnitude at least [`DRIFT_MIN_RANK_CORRELATION`]; 3 records: monotone), as a
//!    warming or a wearing does.
//!
//! With four records or more, 1 and 2 must also hold with any one record left out: a drift
//! moves every record, while one record that a model-form error sets apart (the random ride
//! among sines, last in the campaign's order) lifts the χ² and, by its place, the rank
//! correlation too.
//!
//! A scatter that fails 3 (or the test without one record) is the mark of a model-form error
//! (the parameter absorbs an effect that depends on the test's amplitude or frequency), not
//! of a drift: it is noted, not reported as a drift.

use super::IdentifyError;
use super::fit::{self, Evaluator, Knob};
use super::progress::Monitor;
use super::replay::PreparedRecord;
use super::replay::StepRule;
use super::result::Drift;
use crate::params::Params;
use rayon::prelude::*;
use std::collections::BTreeMap;

/// Smallest χ²/(k − 1) of the per-record values for a drift [-] (a scatter of 5σ).
pub const DRIFT_CHI2: f64 = 25.0;
/// Smallest range of the per-record values, relative to their mean, for a drift [-].
pub const DRIFT_MIN_RELATIVE_RANGE: f64 = 0.02;
/// Smallest |Spearman rank correlation| of the values with the record order for a drift [-].
pub const DRIFT_MIN_RANK_CORRELATION: f64 = 0.8;
/// Fewest records a drift can be told from.
pub const DRIFT_MIN_RECORDS: usize = 3;

/// Jacobians per per-record fit.
const PER_RECORD_JACOBIANS: usize = 4;

/// The parameters tried for a drift in `p`: Cd, and the effective bulk modulus when the
/// compliance effect is on.
pub fn drift_knobs(p: &Params) -> Vec<Knob> {
    let mut k = vec![Knob::Cd];
    if p.plant.effects.compliance.enabled {
        k.push(Knob::Compliance);
    }
    k
}

/// Spearman rank correlation of `v` with `0, 1, …` (no ties expected in fitted values).
pub fn rank_correlation(v: &[f64]) -> f64 {
    let n = v.len();
    if n < 2 {
        return 0.0;
    }
    let mut idx: Vec<usize> = (0..n).collect();
    idx.sort_by(|&a, &b| v[a].total_cmp(&v[b]));
    let mut rank = vec![0.0; n];
    for (r, &i) in idx.iter().enumerate() {
        rank[i] = r as f64;
    }
    let d2: f64 = rank
        .iter()
        .enumerate()
        .map(|(i, r)| (r - i as f64).powi(2))
        .sum();
    let nf = n as f64;
    1.0 - 6.0 * d2 / (nf * (nf * nf - 1.0))
}

/// χ² per degree of freedom of `values` with 1-σ `stds` about their weighted mean, and that
/// mean.
pub fn scatter(values: &[f64], stds: &[f64]) -> (f64, f64) {
    let w: Vec<f64> = stds.iter().map(|s| 1.0 / (s * s).max(1e-300)).collect();
    let sw: f64 = w.iter().sum();
    let mean = values.iter().zip(&w).map(|(v, w)| v * w).sum::<f64>() / sw;
    let chi2: f64 = values
        .iter()
        .zip(stds)
        .map(|(v, s)| ((v - mean) / s).powi(2))
        .sum();
    (chi2 / (values.len().saturating_sub(1)).max(1) as f64, mean)
}

/// The drift test of the [module docs](self) on per-record `values` with `stds`: `Some` with
/// (χ²/dof, rank correlation) when it is a drift, else `None`.
pub fn is_drift(values: &[f64], stds: &[f64]) -> Option<(f64, f64)> {
    if values.len() < DRIFT_MIN_RECORDS || stds.iter().any(|s| !(s.is_finite() && *s > 0.0)) {
        return None;
    }
    let chi2 = large_scatter(values, stds)?;
    let rho = rank_correlation(values);
    let ordered = if values.len() == 3 {
        rho.abs() > 0.99
    } else {
        rho.abs() >= DRIFT_MIN_RANK_CORRELATION
    };
    (ordered && not_one_record(values, stds)).then_some((chi2, rho))
}

/// Criteria 1 and 2 of the [module docs](self): a scatter beyond the uncertainties and a range
/// beyond [`DRIFT_MIN_RELATIVE_RANGE`] of the mean; the χ²/dof where both hold.
fn large_scatter(values: &[f64], stds: &[f64]) -> Option<f64> {
    let (chi2, mean) = scatter(values, stds);
    let (lo, hi) = values
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(*v), b.max(*v))
        });
    (chi2 > DRIFT_CHI2 && (hi - lo) > DRIFT_MIN_RELATIVE_RANGE * mean.abs()).then_some(chi2)
}

/// Whether [`large_scatter`] holds with each record left out in turn (four records or more;
/// with three, one left out leaves too few to tell).
fn not_one_record(values: &[f64], stds: &[f64]) -> bool {
    values.len() <= DRIFT_MIN_RECORDS
        || (0..values.len()).all(|i| {
            let rest = |x: &[f64]| -> Vec<f64> {
                x.iter()
                    .enumerate()
                    .filter(|&(j, _)| j != i)
                    .map(|(_, v)| *v)
                    .collect()
            };
            large_scatter(&rest(values), &rest(stds)).is_some()
        })
}

/// `knob` fitted on each of `records` alone (in parallel, [`PER_RECORD_JACOBIANS`] Jacobians),
/// every other parameter held at `params`: its value and 1-σ on each record, in their order.
/// A record replayed with its own Cd factor ([`give_records_their_cd`]) has Cd times it.
pub fn per_record(
    params: &Params,
    records: &[PreparedRecord],
    knob: Knob,
    n_eff_ratio: f64,
    monitor: &Monitor<'_>,
) -> Result<(Vec<f64>, Vec<f64>), IdentifyError> {
    per_record_beside(params, records, &[knob], n_eff_ratio, monitor)
}

/// [`per_record`] of `knobs[0]`, fitted beside the other `knobs` on each record.
pub fn per_record_beside(
    params: &Params,
    records: &[PreparedRecord],
    knobs: &[Knob],
    n_eff_ratio: f64,
    monitor: &Monitor<'_>,
) -> Result<(Vec<f64>, Vec<f64>), IdentifyError> {
    let knob = knobs[0];
    let fits: Vec<Result<(f64, f64), IdentifyError>> = records
        .par_iter()
        .map(|rec| {
            let ev = Evaluator {
                records: std::slice::from_ref(rec),
                monitor,
                step: StepRule::Resolving,
            };
            let f = fit::fit(&ev, params, knobs, PER_RECORD_JACOBIANS, n_eff_ratio)?;
            let k = if knob == Knob::Cd { rec.cd_factor } else { 1.0 };
            Ok((k * f.values[0].value, k * f.values[0].std))
        })
        .collect();
    let mut values = Vec::with_capacity(fits.len());
    let mut stds = Vec::with_capacity(fits.len());
    for f in fits {
        let (v, s) = f?;
        values.push(v);
        stds.push(s);
    }
    Ok((values, stds))
}

/// Per-record fits of every drift candidate of `params` on `records` (whole records, in the
/// campaign's order), and the drifts found, with notes for scatters that are not drifts.
pub fn find(
    params: &Params,
    records: &[PreparedRecord],
    n_eff_ratio: f64,
    monitor: &Monitor<'_>,
) -> Result<(Vec<Drift>, Vec<String>), IdentifyError> {
    let (mut drifts, mut notes) = (Vec::new(), Vec::new());
    if records.len() < DRIFT_MIN_RECORDS {
        return Ok((drifts, notes));
    }
    for knob in drift_knobs(params) {
        let (values, stds) = per_record(params, records, knob, n_eff_ratio, monitor)?;
        let name = knob.name().to_string();
        let by_file = |x: &[f64]| -> BTreeMap<String, f64> {
            records
                .iter()
                .map(|r| r.name.clone())
                .zip(x.iter().copied())
                .collect()
        };
        let listed: Vec<String> = records
            .iter()
            .zip(&values)
            .zip(&stds)
            .map(|((r, v), s)| {
                format!(
                    "{} {}",
                    r.name,
                    super::units::format_parameter(&name, *v, *s)
                )
            })
            .collect();
        match is_drift(&values, &stds) {
            Some((chi2, rho)) => {
                let first = values[0];
                let last = values[values.len() - 1];
                drifts.push(Drift {
                    parameter: name.clone(),
                    per_record: by_file(&values),
                    per_record_uncertainty: by_file(&stds),
                    uncertainty: (stds.iter().map(|s| s * s).sum::<f64>() / stds.len() as f64)
                        .sqrt(),
                    chi2_per_dof: chi2,
                    rank_correlation: rho,
                    description: format!(
                        "`{name}` changes from record to record, {} by {:+.1} % from the first \
                         record to the last (χ²/dof = {chi2:.0} against one value for all; rank \
                         correlation with the record order {rho:+.2}): {}",
                        if last >= first { "rising" } else { "falling" },
                        100.0 * (last / first - 1.0),
                        listed.join(", ")
                    ),
                });
            }
            None => {
                let (chi2, _) = scatter(&values, &stds);
                if chi2 > DRIFT_CHI2 && values.len() >= DRIFT_MIN_RECORDS {
                    notes.push(format!(
                        "`{name}` fitted on each record alone scatters more than its \
                         uncertainty (χ²/dof = {chi2:.0}) but not as a trend through the \
                         campaign (none, or only one record set apart), so it is reported as \
                         model-form error, not as a drift: {}",
                        listed.join(", ")
                    ));
                }
            }
        }
    }
    Ok((drifts, notes))
}

/// Gives every record of `campaign` (whole, fit and held-out parts alike, matched by file
/// name) its own Cd from a drift's `per_record` values: the factor
/// [`PreparedRecord::cd_factor`] = value / `campaign_cd`, so that a replay at the campaign
/// value `campaign_cd` uses the record's value; 1 for a record not listed.
pub fn give_records_their_cd(
    campaign: &mut super::data::Campaign,
    per_record: &BTreeMap<String, f64>,
    campaign_cd: f64,
) {
    let parts = [
        &mut campaign.all,
        &mut campaign.fit,
        &mut campaign.validation,
    ];
    for rec in parts.into_iter().flat_map(|p| p.iter_mut()) {
        rec.cd_factor = per_record
            .get(&rec.name)
            .filter(|_| campaign_cd > 0.0)
            .map_or(1.0, |v| v / campaign_cd);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_drift_is_ordered_significant_and_large() {
        let s = [1e-3; 5];
        // Cd warming up 3 % per record: a drift.
        let v: Vec<f64> = (0..5).map(|i| 0.143 * (1.0 + 0.03 * i as f64)).collect();
        let (chi2, rho) = is_drift(&v, &s).expect("a drift");
        assert!(chi2 > DRIFT_CHI2 && (rho - 1.0).abs() < 1e-12);
        // The same values out of order: scatter, not a drift.
        let shuffled = [v[2], v[0], v[4], v[1], v[3]];
        assert!(rank_correlation(&shuffled).abs() < 0.8);
        assert!(is_drift(&shuffled, &s).is_none());
        // Within the uncertainty: no drift.
        let big = [0.01; 5];
        assert!(is_drift(&v, &big).is_none());
        // Significant but tiny (0.5 % over the campaign): no drift.
        let tiny: Vec<f64> = (0..5).map(|i| 0.143 * (1.0 + 0.00125 * i as f64)).collect();
        assert!(is_drift(&tiny, &[1e-6; 5]).is_none());
        // Too few records.
        assert!(is_drift(&v[..2], &s[..2]).is_none());
        assert!((rank_correlation(&[3.0, 2.0, 1.0]) + 1.0).abs() < 1e-12);
    }

    /// The chambers' modulus fitted record by record on case 25 of the 2025 survey draw at
    /// 200 Hz (soft hoses, the split between hoses and chambers not told by the sines): four
    /// sines agree, the ride, last in the campaign, reads a third higher. Ordered by its place
    /// (rank correlation 0.9) and far beyond the uncertainties, but one record: not a drift.
    #[test]
    fn one_record_apart_is_not_a_drift() {
        let v = [0.669e9, 0.661e9, 0.6712e9, 0.6733e9, 0.8963e9];
        let s = [0.045e9, 0.081e9, 0.0049e9, 0.0065e9, 0.0095e9];
        assert!(rank_correlation(&v) >= DRIFT_MIN_RANK_CORRELATION);
        assert!(scatter(&v, &s).0 > DRIFT_CHI2);
        assert!(is_drift(&v, &s).is_none());
        // A drift of one record in five, as in the survey's drift rigs (Cd +3 % per record),
        // stays a drift with any record left out.
        let cd: Vec<f64> = (0..5).map(|i| 0.15 * (1.0 + 0.03 * i as f64)).collect();
        assert!(is_drift(&cd, &[2e-4; 5]).is_some());
    }
}
