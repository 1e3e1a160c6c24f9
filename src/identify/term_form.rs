//! Whether the records agree on the size of a term proposed beyond the library (issue 20,
//! item 4: an uncertainty that says where the data cannot pin a value).
//!
//! A proposed term has a form of its own (a flow gain per direction that builds up as
//! `x/√(x² + w²)`, a Cd linear in the opening), and a rig's effect need not have it. Where it
//! has not, the size the joint fit gives is a compromise between the tests, and its 1-σ,
//! which assumes the form, says nothing of that: on the survey's rigs with a Cd per direction
//! of ±14.8 % the term read 16.00 ± 0.08 %, 15σ away. So the term's size is fitted again on
//! each record alone, beside that record's own Cd and τ (which take up what the record asks
//! of the flow gain and the timing), every other parameter held at the proposal's values
//! ([`super::drift::per_record_beside`]), and the scatter of those sizes about their
//! weighted mean is held against their own 1-σ: χ² per degree of freedom. (With Cd and τ
//! held too, each record's size stayed at the joint fit's compromise: the test saw nothing.) Above [`DISAGREE_CHI2`] the
//! records disagree beyond their noise, the reported 1-σ is scaled by `S = √(χ²/dof)` (the
//! scale factor with which particle physics combines measurements that disagree), and the
//! report says so. A term of the rig's own form (a drifting null, a quadratic damping) gives
//! a χ²/dof near 1.

use super::IdentifyError;
use super::drift::{DRIFT_MIN_RECORDS, per_record_beside, scatter};
use super::fit::Knob;
use super::progress::Monitor;
use super::replay::PreparedRecord;
use crate::params::Params;
use std::collections::BTreeMap;

/// Smallest χ²/dof of the per-record values for the records to disagree [-]: a scatter of
/// twice their 1-σ (with five records, about 0.3 % of noise alone goes that far).
pub const DISAGREE_CHI2: f64 = 4.0;

/// The records' agreement on one parameter's size.
#[derive(Debug, Clone, PartialEq)]
pub struct Agreement {
    /// χ² of the per-record values about their weighted mean, per degree of freedom [-].
    pub chi2_per_dof: f64,
    /// The factor the joint fit's 1-σ is scaled by ([`scale_factor`]) [-].
    pub scale: f64,
    /// The value fitted on each record alone \[SI\], by file name.
    pub per_record: BTreeMap<String, f64>,
    /// Their 1-σ \[SI\], by file name.
    pub per_record_uncertainty: BTreeMap<String, f64>,
}

impl Agreement {
    /// The smallest and largest per-record value \[SI\].
    pub fn range(&self) -> (f64, f64) {
        self.per_record
            .values()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                (a.min(*v), b.max(*v))
            })
    }
}

/// `knob` fitted on each of `records` alone from `params`; `None` with fewer than
/// [`DRIFT_MIN_RECORDS`] records whose fit determines it (a finite, positive 1-σ).
pub fn agreement(
    params: &Params,
    records: &[PreparedRecord],
    knob: Knob,
    n_eff_ratio: f64,
    monitor: &Monitor<'_>,
) -> Result<Option<Agreement>, IdentifyError> {
    if records.len() < DRIFT_MIN_RECORDS {
        return Ok(None);
    }
    let (values, stds) = per_record_beside(
        params,
        records,
        &[knob, Knob::Cd, Knob::Tau],
        n_eff_ratio,
        monitor,
    )?;
    let kept: Vec<(&str, f64, f64)> = records
        .iter()
        .zip(values.iter().zip(&stds))
        .filter(|(_, (v, s))| v.is_finite() && s.is_finite() && **s > 0.0)
        .map(|(r, (v, s))| (r.name.as_str(), *v, *s))
        .collect();
    if kept.len() < DRIFT_MIN_RECORDS {
        return Ok(None);
    }
    let v: Vec<f64> = kept.iter().map(|k| k.1).collect();
    let s: Vec<f64> = kept.iter().map(|k| k.2).collect();
    let (chi2_per_dof, _) = scatter(&v, &s);
    Ok(Some(Agreement {
        chi2_per_dof,
        scale: scale_factor(chi2_per_dof),
        per_record: kept.iter().map(|k| (k.0.to_string(), k.1)).collect(),
        per_record_uncertainty: kept.iter().map(|k| (k.0.to_string(), k.2)).collect(),
    }))
}

/// The factor a 1-σ is scaled by for a scatter of `chi2_per_dof`: `√(χ²/dof)` where the
/// records disagree (above [`DISAGREE_CHI2`]), else 1.
pub fn scale_factor(chi2_per_dof: f64) -> f64 {
    if chi2_per_dof > DISAGREE_CHI2 {
        chi2_per_dof.sqrt()
    } else {
        1.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The scale factor of values that agree within their 1-σ, or scatter up to twice it, is
    /// 1; of values that scatter ten times their 1-σ, 10.
    #[test]
    fn the_scale_is_the_root_of_the_scatters_chi2_and_never_below_one() {
        let stds = [1.0; 5];
        let (agree, _) = scatter(&[0.1, -0.2, 0.3, 0.0, -0.1], &stds);
        assert_eq!(scale_factor(agree), 1.0);
        let (twice, _) = scatter(&[2.0, -2.0, 2.0, -2.0, 0.0], &stds);
        assert_eq!(scale_factor(twice), 1.0, "{twice}");
        let (apart, _) = scatter(&[10.0, -10.0, 10.0, -10.0, 0.0], &stds);
        assert!((scale_factor(apart) - 10.0).abs() < 1e-12, "{apart}");
    }
}
