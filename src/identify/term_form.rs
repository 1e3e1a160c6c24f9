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

/// Smallest distance of a library effect's size from none, in the records' own 1-σ
/// ([`Agreement::mean`]), for the records to say that the effect is there [-]: the
/// 3σ the uncertainties are held to.
pub const SUPPORT_SIGMAS: f64 = 3.0;

impl Agreement {
    /// The weighted mean of the per-record values \[SI\] and its 1-σ: what their own 1-σ give
    /// where the records agree; where they disagree beyond their noise (χ²/dof above
    /// [`DISAGREE_CHI2`]), the larger of that, scaled by [`Self::scale`], and the standard
    /// error of their plain scatter. Records that disagree tens of times beyond their noise
    /// leave the noise's weights saying little of the mean, and the scatter itself is its
    /// uncertainty (a valve offset beside a flow gain per direction: −0.9 mV on one record,
    /// +1.3 mV on another, each ± 0.02 mV). Where they agree, a record that hardly sees the
    /// effect (a wide 1-σ about "none") keeps its small weight.
    pub fn mean(&self) -> (f64, f64) {
        let v: Vec<f64> = self.per_record.values().copied().collect();
        let s: Vec<f64> = self.per_record_uncertainty.values().copied().collect();
        let (_, mean) = scatter(&v, &s);
        let weight: f64 = s.iter().map(|s| 1.0 / (s * s).max(1e-300)).sum();
        let by_noise = self.scale / weight.sqrt();
        if self.chi2_per_dof <= DISAGREE_CHI2 {
            return (mean, by_noise);
        }
        let n = v.len() as f64;
        let plain = v.iter().sum::<f64>() / n;
        let spread =
            (v.iter().map(|x| (x - plain).powi(2)).sum::<f64>() / (n - 1.0).max(1.0)).sqrt();
        (mean, by_noise.max(spread / n.sqrt()))
    }
}

/// What the records alone say of a library effect's size: the size knob whose per-record
/// mean lies farthest from none.
#[derive(Debug, Clone, PartialEq)]
pub struct Support {
    /// The size knob.
    pub knob: Knob,
    /// Its value meaning none \[SI\].
    pub off: f64,
    /// Its per-record mean's distance from `off`, in that mean's 1-σ [-].
    pub sigmas: f64,
    /// The per-record values.
    pub agreement: Agreement,
}

/// Whether the records, each fitted alone ([`agreement`]: beside its own Cd and τ, every
/// other parameter held at `params`), say that `effect` is there: its sizes
/// ([`super::effects::size_knobs`]) fitted on each record, the one whose weighted mean lies
/// farthest from none, in that mean's 1-σ scaled by the records' scatter. An effect of the
/// hardware is the same on every record; one that a joint fit keeps to take up what another
/// term's form misses takes a size each record asks for, and those sizes need not agree, nor
/// lie away from none (on the survey's rigs, a valve offset beside a flow gain per direction
/// fitted −1.7 mV on one record and +3.5 mV on another). `None` where no size's per-record
/// fits are determined on [`DRIFT_MIN_RECORDS`] records: the records cannot say.
pub fn support(
    params: &Params,
    records: &[PreparedRecord],
    effect: super::EffectId,
    n_eff_ratio: f64,
    monitor: &Monitor<'_>,
) -> Result<Option<Support>, IdentifyError> {
    let mut best: Option<Support> = None;
    for &knob in super::effects::size_knobs(effect) {
        let Some(agreement) = agreement(params, records, knob, n_eff_ratio, monitor)? else {
            continue;
        };
        let off = super::effects::size_off(knob, params);
        let (mean, std) = agreement.mean();
        let sigmas = (mean - off).abs() / std;
        if !sigmas.is_finite() {
            continue;
        }
        if best.as_ref().is_none_or(|b| sigmas > b.sigmas) {
            best = Some(Support {
                knob,
                off,
                sigmas,
                agreement,
            });
        }
    }
    Ok(best)
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

    fn agreement_of(values: &[f64], stds: &[f64]) -> Agreement {
        let (chi2_per_dof, _) = scatter(values, stds);
        let name = |i: usize| format!("r{i}.csv");
        Agreement {
            chi2_per_dof,
            scale: scale_factor(chi2_per_dof),
            per_record: values
                .iter()
                .enumerate()
                .map(|(i, v)| (name(i), *v))
                .collect(),
            per_record_uncertainty: stds
                .iter()
                .enumerate()
                .map(|(i, s)| (name(i), *s))
                .collect(),
        }
    }

    /// Records that agree: the mean's 1-σ is the noise's, σ/√n. Records that scatter far
    /// beyond their noise and on both sides of none (a stand-in's sizes): the 1-σ is the
    /// scatter's standard error, and the mean lies within it of none; the noise's weights
    /// alone, even scaled by √(χ²/dof), would put it 3σ away.
    #[test]
    fn the_mean_of_records_that_disagree_is_held_against_their_scatter() {
        let (m, s) = agreement_of(&[1.0, 1.1, 0.9, 1.05, 0.95], &[0.1; 5]).mean();
        assert!(
            (m - 1.0).abs() < 1e-12 && (s - 0.1 / 5f64.sqrt()).abs() < 1e-12,
            "{m} {s}"
        );
        let values = [-0.25e-3, -0.93e-3, -0.58e-3, 1.26e-3, -0.61e-3];
        let stds = [0.02e-3, 0.05e-3, 0.03e-3, 0.2e-3, 0.03e-3];
        let a = agreement_of(&values, &stds);
        let weighted = a.scale / stds.iter().map(|s| 1.0 / (s * s)).sum::<f64>().sqrt();
        let (m, s) = a.mean();
        assert!(m.abs() > 3.0 * weighted, "{m} against {weighted}");
        assert!(m.abs() < SUPPORT_SIGMAS * s, "{m} ± {s}");
        assert!(s > weighted);
        // Records that agree, one of which hardly sees the effect (at "none", with a 1-σ ten
        // times the others'): its small weight stands, and so does the mean's 1-σ.
        let stds = [0.1, 0.1, 0.1, 0.1, 1.0];
        let a = agreement_of(&[1.0, 1.1, 0.9, 1.05, 0.0], &stds);
        let (m, s) = a.mean();
        let by_noise = 1.0 / stds.iter().map(|s| 1.0 / (s * s)).sum::<f64>().sqrt();
        assert!((s - by_noise).abs() < 1e-12 && m / s > 15.0, "{m} ± {s}");
    }
}
