//! The data stage: which records can be replayed, whether they can determine the twin at all
//! (`insufficient_data` otherwise), and the split into fitted and held-out parts.

use super::evaluate::{insufficient_report, replay_all};
use super::replay::{PreparedRecord, part_name, rms};
use super::result::CalibrationReport;
use super::result::Split;
use super::{CalibrationOptions, IdentifyError};
use crate::dataset::Record;
use crate::params::Params;
use rayon::prelude::*;

/// Least number of records for a split by records (below it, each record is split in time).
pub const MIN_RECORDS_FOR_RECORD_SPLIT: usize = 6;

/// The fit/validation split: with [`MIN_RECORDS_FOR_RECORD_SPLIT`] records or more every third
/// one (the 3rd, 6th, … in the order given) is held out; with fewer, holding out whole records
/// would take away too much of what the effects show in (one of five tests may be the only
/// one that excites an effect), so the last third of each record is held out instead.
pub fn split_rule(recs: &[PreparedRecord]) -> (Vec<PreparedRecord>, Vec<PreparedRecord>, String) {
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
pub(super) fn missing_data(records: &[Record], recs: &[PreparedRecord]) -> Vec<String> {
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

/// Least total duration of the records \[s\].
pub const MIN_TOTAL_DURATION_S: f64 = 2.0;
/// Least sample rate \[Hz\].
pub const MIN_SAMPLE_RATE_HZ: f64 = 100.0;
/// Least RMS variation of `v_in` in at least one record \[V\].
pub const MIN_COMMAND_RMS_V: f64 = 0.02;

/// The records that can be replayed, prepared, and what keeps a calibration from them.
#[derive(Debug, Clone)]
pub struct DataCheck {
    /// The records with `v_in` and `u` and two samples or more, prepared.
    pub records: Vec<PreparedRecord>,
    /// Notes for the report (records left out for a missing column).
    pub notes: Vec<String>,
    /// What the data lack, one sentence each; empty when a calibration can run.
    pub missing: Vec<String>,
}

/// How close \[m\] a measured stroke may come to an end stop (`±Lc/2`) before the rest of its
/// record is left out of the calibration: [`before_end_stops`].
pub const END_STOP_MARGIN_M: f64 = 1.0e-3;

/// The shortest part \[s\] of a record before its first end-stop contact that is still used;
/// a record that reaches a stop sooner is left out.
pub const MIN_BEFORE_END_STOP_S: f64 = 0.5;

/// The first sample of a measured stroke `u` \[m\] that comes within [`END_STOP_MARGIN_M`] of
/// an end stop (`±stroke_m/2`), if any: where [`before_end_stops`] cuts a record.
pub fn first_end_stop_contact(u: &[f64], stroke_m: f64) -> Option<usize> {
    let limit = 0.5 * stroke_m - END_STOP_MARGIN_M;
    u.iter().position(|x| x.abs() >= limit)
}

/// The records up to their first end-stop contact, with a note for each record cut or left
/// out. A stroke `u` that comes within [`END_STOP_MARGIN_M`] of `±stroke_m/2` ends the part
/// that is fitted and replayed there: where the body lands on a stop depends on everything
/// before it (an open-loop test of a flow-controlled cylinder integrates every flow error
/// into the stroke), so a replay's error after the contact jumps with the smallest change of
/// a parameter and no fit can follow its slope. A rig whose flow gain differs by 10 % between
/// the spool directions walks into a stop within a second of a large sine test; fitted
/// whole, its cost changed by +71 % and −1 % for Cd 0.1 % lower and higher, and the search
/// beyond the library found one of its three terms; fitted up to the contacts, all three.
pub fn before_end_stops(records: &[Record], stroke_m: f64) -> (Vec<Record>, Vec<String>) {
    let mut notes = Vec::new();
    let kept = records
        .iter()
        .filter_map(|r| {
            let contact =
                r.u.as_ref()
                    .and_then(|u| first_end_stop_contact(u, stroke_m));
            let Some(i) = contact else {
                return Some(r.clone());
            };
            let (at, whole) = (r.t[i] - r.t[0], r.duration_s());
            let reach = format!(
                "end stops: {}'s stroke comes within {:.1} mm of an end stop (±{:.1} mm) at \
                 {at:.3} s",
                r.path.display(),
                1e3 * END_STOP_MARGIN_M,
                500.0 * stroke_m
            );
            let why = "the replay's error after a stop contact jumps with the smallest change \
                       of a parameter";
            if at < MIN_BEFORE_END_STOP_S {
                notes.push(format!(
                    "{reach}, less than {MIN_BEFORE_END_STOP_S} s after its start: the record \
                     was left out ({why})"
                ));
                None
            } else {
                notes.push(format!(
                    "{reach}: calibrated and replayed up to there ({at:.3} of its {whole:.3} s; \
                     {why})"
                ));
                Some(r.truncated(i))
            }
        })
        .collect();
    (kept, notes)
}

/// Prepares the records that can be replayed and checks that together they can determine the
/// twin: long enough, sampled fast enough, excited, with the `v_in` and `u` channels
/// ([`MIN_TOTAL_DURATION_S`], [`MIN_SAMPLE_RATE_HZ`], [`MIN_COMMAND_RMS_V`]).
pub fn check(records: &[Record], options: &CalibrationOptions) -> Result<DataCheck, IdentifyError> {
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
    let mut prepared: Vec<PreparedRecord> = usable
        .par_iter()
        .map(|r| PreparedRecord::new(r, &options.metric))
        .collect::<Result<_, _>>()?;
    super::replay::share_sensor_noise(&mut prepared, &options.metric);
    let mut missing = missing_data(records, &prepared);
    if prepared.is_empty() {
        missing.extend(column_notes);
    } else {
        notes.extend(column_notes);
    }
    Ok(DataCheck {
        records: prepared,
        notes,
        missing,
    })
}

/// The prepared records, split into the part every fit sees and the part held out.
#[derive(Debug, Clone)]
pub struct Campaign {
    /// Every record, whole.
    pub all: Vec<PreparedRecord>,
    /// What the fits see.
    pub fit: Vec<PreparedRecord>,
    /// What validates (never fitted).
    pub validation: Vec<PreparedRecord>,
    /// The rule and the names of both parts.
    pub split: Split,
}

/// Splits the records into fit and validation parts (see [`split_rule`]).
pub fn split(all: Vec<PreparedRecord>) -> Campaign {
    let (fit, validation, rule) = split_rule(&all);
    let split = Split {
        rule,
        fit: fit.iter().map(part_name).collect(),
        validation: validation.iter().map(part_name).collect(),
    };
    Campaign {
        all,
        fit,
        validation,
        split,
    }
}

/// The report for data the check found insufficient: the nominal replay of the usable
/// records when every one of them replays, else nothing replayed.
pub fn insufficient_data(params: &Params, checked: DataCheck) -> CalibrationReport {
    let all = checked.records;
    let nominal = replay_all(params, &all).unwrap_or_default();
    let nominal = if nominal.len() == all.len() {
        nominal
    } else {
        Vec::new()
    };
    let all = if nominal.is_empty() { Vec::new() } else { all };
    insufficient_report(params, all, nominal, checked.missing, checked.notes)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    /// A 3 s record at 1 kHz whose stroke runs at `speed` \[m/s\] from mid-stroke.
    fn walking(name: &str, speed: f64) -> Record {
        let t: Vec<f64> = (0..=3000).map(|i| i as f64 * 1e-3).collect();
        Record {
            path: name.into(),
            metadata: vec![],
            dt: 1e-3,
            v_in: Some(t.iter().map(|t| (20.0 * t).sin()).collect()),
            u: Some(t.iter().map(|t| speed * t).collect()),
            x: None,
            xdd: None,
            ydd: Some(vec![0.0; t.len()]),
            p1: None,
            p2: None,
            t,
            warnings: vec![],
        }
    }

    /// A stroke of ±35 mm: a record that comes within 1 mm of a stop at 1.7 s is cut there, one
    /// that does so at 0.34 s is left out, one that stays clear is kept whole; the notes name
    /// the files and the times.
    #[test]
    fn records_end_at_their_first_end_stop_contact() {
        let recs = [
            walking("cut.csv", 0.02),
            walking("early.csv", -0.1),
            walking("clear.csv", 0.01),
        ];
        let (kept, notes) = before_end_stops(&recs, 0.07);
        assert_eq!(kept.len(), 2);
        assert_eq!(kept[0].path, PathBuf::from("cut.csv"));
        // 0.02·t ≥ 0.034 from t = 1.7 s (sample 1700; rounding may take the next one).
        assert!((1700..=1701).contains(&kept[0].len()), "{}", kept[0].len());
        for c in [&kept[0].v_in, &kept[0].u, &kept[0].ydd] {
            assert_eq!(c.as_ref().unwrap().len(), kept[0].len());
        }
        assert!(kept[0].u.as_ref().unwrap().iter().all(|u| u.abs() < 0.034));
        assert_eq!(kept[1], recs[2]);
        assert_eq!(notes.len(), 2, "{notes:?}");
        assert!(
            notes[0].contains("cut.csv")
                && notes[0].contains("1.70")
                && notes[0].contains("±35.0 mm"),
            "{}",
            notes[0]
        );
        assert!(
            notes[1].contains("early.csv") && notes[1].contains("left out"),
            "{}",
            notes[1]
        );
    }
}
