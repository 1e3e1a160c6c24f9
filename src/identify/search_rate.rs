//! Records sampled far faster than the twin needs: the search reads every k-th sample, the
//! final fit and every reported error read every sample.
//!
//! The replay steps the twin at every sample of a record (at most the preset's 0.5 ms, less
//! where friction or the integrator's limit asks for it). A 10 kHz record therefore costs five
//! times the steps of a 2 kHz one, and a calibration replays its campaign several hundred
//! times: a ten-record, 60 s campaign at 10 kHz took 53 s with no effect in it and 191 s with
//! friction on this project's 2-core machine (release build), 19.5 s and about 80 s this way.
//! Steps that span several samples, with the samples between interpolated, were tried and
//! reverted: at a friction's
//! stick–slip reversals the interpolated samples missed the raw record by several times a
//! low-noise 10 kHz floor, and the verdict turned wrong.
//!
//! So a record sampled at [`MIN_RATE_FOR_COARSE_SEARCH_HZ`] or more is searched on every k-th
//! sample, `k = ⌊rate / SEARCH_RATE_HZ⌋` ([`Record::decimated`]): exactly the record a
//! data acquisition sampling at about 2 kHz would have written, noise and quantisation
//! included, with no filter in between (the twin's signals lie below 1 kHz: its oil column
//! near 77 Hz, friction's reversals over a few milliseconds; only the sensors' white noise
//! folds into the lower band, where it reads as a 2 kHz record's noise). The whole loop runs
//! on those records as on any 2 kHz campaign — the declared fit, the effect search, the
//! search beyond the library, the drifts — and then:
//!
//! 1. every fit the report shows (the declared fit, the library's, the proposal's) is fitted
//!    again on every sample from where the search left it (`refit_on_every_sample`), so
//!    values and uncertainties are those of the records as recorded (a sensor filter that runs
//!    on the samples, such as the stroke sensor's lag, delays by `T − Δt/2` of the record's own
//!    step). The optimiser's steps there are steered by Jacobians of the read samples (the
//!    same residual rows, weighted alike); the residual it minimises, every step it accepts
//!    and the Jacobian of the uncertainties are on every sample;
//! 2. the report stage — replays, the raw error and the verdict, the sensors' rule, the
//!    ringing search — runs on every sample, as without this module;
//! 3. if the twin the search delivered was at its raw-error floor on the read samples but is
//!    not on every sample (10 kHz floors are √5 lower than 2 kHz floors in every band below
//!    the search's Nyquist), the campaign is calibrated again from the start on every sample,
//!    and a note says why. The faster path's result is kept where its twin is at its floor
//!    on every sample, and where it was not at its floor on the read samples either. That is
//!    no proof that the slower path would end in the same place: on the survey's 60
//!    randomised campaigns at 10 kHz the verdicts were the same, and one parameter (a
//!    chamber modulus beside soft hoses) ended at 3.0σ from the truth where the slower path
//!    had ended within 3σ.
//!
//! The evidence of each added effect (its ΔBIC, its share of the residual, the held-out error)
//! is the search's, on the read samples; a note in the report says so.

use super::data::{self, Campaign};
use super::fit::{self, Bic, Evaluator, Knob};
use super::pass::LibraryPass;
use super::progress::{Monitor, Stage};
use super::replay::{PreparedRecord, StepRule};
use super::{CalibrationOptions, IdentifyError};
use crate::dataset::Record;

/// About the rate the search reads a fast record at \[Hz\]: a record is read every
/// `⌊rate / SEARCH_RATE_HZ⌋`-th sample. 2 kHz is a rate the loop is proven at (the second demo
/// campaign; the randomised rigs at 1 kHz and 200 Hz), and one where the twin's step (0.5 ms,
/// 0.25 ms with a stiff friction) still fits the sample step.
pub const SEARCH_RATE_HZ: f64 = 2000.0;

/// Lowest sample rate at which a record is searched on fewer samples than it has \[Hz\]: twice
/// [`SEARCH_RATE_HZ`], so that at least every second sample is dropped.
pub const MIN_RATE_FOR_COARSE_SEARCH_HZ: f64 = 2.0 * SEARCH_RATE_HZ;

/// Jacobians of each fit on every sample, from the search's minimum on the read samples (the
/// covariance is taken at the last). Two bring a stroke sensor's lag to the rig's where the
/// search's, a filter on the read samples, is about (Δt_read − Δt)/2 = 0.2 ms long at 10 kHz
/// (the same delay `T − Δt/2` at the other step; 10σ there); four gave the same values as
/// two, to seven digits, on the survey case where the two rates' fits differ most (case 20 of
/// draw 2021 at 10 kHz).
pub const REFIT_JACOBIANS: usize = 2;

/// How many samples the search steps over in a record sampled at `rate_hz` (1: it reads
/// every one).
pub fn read_every(rate_hz: f64) -> usize {
    if rate_hz.is_finite() && rate_hz >= MIN_RATE_FOR_COARSE_SEARCH_HZ {
        (rate_hz / SEARCH_RATE_HZ).floor() as usize
    } else {
        1
    }
}

/// The campaign the search reads, when some record is sampled at
/// [`MIN_RATE_FOR_COARSE_SEARCH_HZ`] or more: every record read every [`read_every`]-th
/// sample, prepared and split as `full` is, with the note the report gives. `None` when every
/// record is read whole, or when the records so read would not pass the data check that the
/// records as recorded passed (then the search reads every sample).
pub fn coarse_campaign(
    records: &[Record],
    full: &Campaign,
    options: &CalibrationOptions,
) -> Result<Option<(Campaign, String)>, IdentifyError> {
    let every: Vec<usize> = records
        .iter()
        .map(|r| read_every(r.sample_rate_hz()))
        .collect();
    if every.iter().all(|&k| k == 1) {
        return Ok(None);
    }
    let read: Vec<Record> = records
        .iter()
        .zip(&every)
        .map(|(r, &k)| r.decimated(k))
        .collect();
    let checked = data::check(&read, options)?;
    if !checked.missing.is_empty() || checked.records.len() != full.all.len() {
        return Ok(None);
    }
    let coarse = data::split(checked.records);
    // One phrase per sample rate: "the 10 records sampled at 10000 Hz on every 5th sample
    // (2000 Hz)".
    let mut groups: Vec<(f64, usize, usize)> = Vec::new();
    for (r, &k) in records.iter().zip(&every).filter(|(_, k)| **k > 1) {
        let rate = r.sample_rate_hz();
        match groups
            .iter_mut()
            .find(|g| g.1 == k && (g.0 / rate - 1.0).abs() < 0.01)
        {
            Some(g) => g.2 += 1,
            None => groups.push((rate, k, 1)),
        }
    }
    let read: Vec<String> = groups
        .iter()
        .map(|&(rate, k, n)| {
            format!(
                "{} sampled at {} Hz on every {} sample ({} Hz)",
                if n == 1 {
                    "the record".to_string()
                } else {
                    format!("the {n} records")
                },
                crate::format::general(rate.round()),
                ordinal(k),
                crate::format::general((rate / k as f64).round())
            )
        })
        .collect();
    let whole = every.iter().filter(|&&k| k == 1).count();
    let note = format!(
        "sampled faster than the search needs: the effect search read {}{} — the records an \
         acquisition at that rate would have written; the declared fit, the library's and \
         any proposal's were then fitted again on every sample, and every error, the verdict \
         included, is on every sample. The evidence of each effect (ΔBIC, share of the \
         residual, held-out error) is the search's",
        read.join(", "),
        if whole > 0 {
            format!(" and the other {whole} whole")
        } else {
            String::new()
        }
    );
    Ok(Some((coarse, note)))
}

/// The records read on fewer samples (`coarse`) with the weights of the same records on every
/// sample (`fine`, matched by name): their weighted residual has `fine`'s rows, so its
/// Jacobian steers a fit on `fine` ([`refit_on_every_sample`]). `None` where a record has no
/// match with as many residual rows.
fn steering_records(
    coarse: &[PreparedRecord],
    fine: &[PreparedRecord],
) -> Option<Vec<PreparedRecord>> {
    fine.iter()
        .map(|f| {
            let c = coarse.iter().find(|c| c.name == f.name)?;
            (c.residual_len() == f.residual_len()).then(|| PreparedRecord {
                scale_du: f.scale_du,
                scale_ydd: f.scale_ydd,
                scale_p: f.scale_p,
                scale_u_drift: f.scale_u_drift,
                cd_factor: f.cd_factor,
                ..c.clone()
            })
        })
        .collect()
}

/// `2nd`, `3rd`, `4th`, … `21st`.
fn ordinal(k: usize) -> String {
    let suffix = match (k % 10, k % 100) {
        (_, 11..=13) => "th",
        (1, _) => "st",
        (2, _) => "nd",
        (3, _) => "rd",
        _ => "th",
    };
    format!("{k}{suffix}")
}

/// Fits the pass's fits (the declared one, the library's and the proposal's) again on the
/// fit records of `fine`, each from where the search on `coarse` left it, with the same
/// knobs and at most [`REFIT_JACOBIANS`] Jacobians; the criterion's counts are taken on
/// `fine` too. The optimiser steps with Jacobians taken on `coarse`'s records weighted as
/// `fine`'s ([`steering_records`]): the fit's residual is low-passed and decimated to the
/// same rows at either rate, and its slopes differ by the twin's step only, while a replay
/// of a 10 kHz record costs about four of its 2 kHz read. The residual minimised, each step
/// accepted and the Jacobian of the uncertainties are on every sample ([`fit::fit_steered`]).
/// A drifting Cd's per-record values move with the campaign's Cd, so that each record keeps
/// the factor its replays use (`fine` carries the search's factors).
pub(super) fn refit_on_every_sample(
    pass: &mut LibraryPass,
    coarse: &Campaign,
    fine: &Campaign,
    monitor: &Monitor<'_>,
) -> Result<(), IdentifyError> {
    let fits = 2 + usize::from(pass.proposal.is_some());
    let cd_before = pass.final_params.plant.valve.cd;
    monitor.enter(Stage::RecordRate, fits * (REFIT_JACOBIANS + 1));
    let ev = Evaluator {
        records: &fine.fit,
        monitor,
        step: StepRule::Resolving,
    };
    let steering = steering_records(&coarse.fit, &fine.fit);
    let steer = steering.as_ref().map(|records| Evaluator {
        records,
        monitor,
        step: StepRule::Resolving,
    });
    let bic = Bic::at(&ev, &pass.declared.fit)?;
    let again = |f: &fit::FitResult, knobs: &[Knob]| {
        fit::fit_steered(
            &ev,
            steer.as_ref(),
            &f.params,
            knobs,
            REFIT_JACOBIANS,
            bic.ratio(),
        )
    };
    // The declared fit serves the report as the twin "before" (its replays and the
    // criterion's baseline): its minimum is found again on every sample, without the
    // Jacobian of uncertainties nothing reads (its values keep the search's 1-σ).
    let declared = fit::screen_steered(
        &ev,
        steer.as_ref(),
        &pass.declared.fit.params,
        &pass.declared.knobs,
        REFIT_JACOBIANS,
    )?;
    let d = &mut pass.declared.fit;
    for v in &mut d.values {
        v.value = v.knob.value(&declared.params);
    }
    (d.params, d.rss, d.n) = (declared.params, declared.rss, ev.residual_len());
    pass.search.current = again(&pass.search.current, &pass.search.knobs)?;
    if let Some(p) = &mut pass.proposal {
        p.fit = again(&p.fit, &p.knobs)?;
    }
    pass.final_params = pass
        .proposal
        .as_ref()
        .map_or(pass.search.current.params, |p| p.fit.params);
    pass.bic = bic;
    let scale = pass.final_params.plant.valve.cd / cd_before;
    for d in pass
        .drifts
        .iter_mut()
        .filter(|d| d.parameter == Knob::Cd.name())
    {
        for v in d
            .per_record
            .values_mut()
            .chain(d.per_record_uncertainty.values_mut())
        {
            *v *= scale;
        }
        d.uncertainty *= scale;
    }
    monitor.check()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::identify::replay::MetricOptions;

    /// A 10 kHz record of `n` samples and its every-5th-sample read have the same residual
    /// rows, whatever `n`, so the refit on every sample is steered (not silently unsteered).
    #[test]
    fn a_10_khz_record_and_its_read_samples_have_the_same_residual_rows() {
        for n in [20_001, 20_002, 20_003, 20_004, 20_005, 23_457] {
            let dt = 1e-4;
            let t: Vec<f64> = (0..n).map(|i| i as f64 * dt).collect();
            let wave = |a: f64, f: f64| -> Vec<f64> {
                t.iter()
                    .map(|t| a * (2.0 * std::f64::consts::PI * f * t).sin())
                    .collect()
            };
            let rec = Record {
                path: "ten_khz.csv".into(),
                metadata: vec![],
                dt,
                t: t.clone(),
                v_in: Some(wave(0.5, 3.0)),
                u: Some(wave(2e-3, 3.0)),
                x: None,
                xdd: None,
                ydd: Some(wave(0.4, 3.0)),
                p1: None,
                p2: None,
                warnings: vec![],
            };
            let opt = MetricOptions::default();
            let fine = PreparedRecord::new(&rec, &opt).expect("a valid record");
            let coarse = PreparedRecord::new(&rec.decimated(read_every(1.0 / dt)), &opt)
                .expect("a valid record");
            let steering = steering_records(&[coarse], std::slice::from_ref(&fine));
            let s = steering.unwrap_or_else(|| panic!("{n} samples: rows differ"));
            assert_eq!(s[0].residual_len(), fine.residual_len());
            assert_eq!(
                (s[0].scale_du, s[0].scale_ydd),
                (fine.scale_du, fine.scale_ydd)
            );
        }
    }

    /// 10 kHz is read every 5th sample (2 kHz), 8 kHz every 4th, 5 kHz every 2nd (2.5 kHz);
    /// below 4 kHz every sample.
    #[test]
    fn fast_records_are_read_at_about_the_search_rate() {
        assert_eq!(read_every(10_000.0), 5);
        assert_eq!(read_every(8_000.0), 4);
        assert_eq!(read_every(5_000.0), 2);
        assert_eq!(read_every(4_000.0), 2);
        assert_eq!(read_every(3_999.0), 1);
        assert_eq!(read_every(2_000.0), 1);
        assert_eq!(read_every(200.0), 1);
        assert_eq!(read_every(f64::NAN), 1);
        assert_eq!(
            [2, 3, 4, 5, 11, 12, 21, 22].map(ordinal),
            ["2nd", "3rd", "4th", "5th", "11th", "12th", "21st", "22nd"]
        );
    }
}
