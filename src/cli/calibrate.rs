//! `seat-twin calibrate`: the twin calibrated on measured records, its report into a folder.

use super::{
    OptionError, Outcome, RowCost, Run, announce, check_record_memory, estimate_wall_s,
    estimated_rows, load_params,
};
use crate::dataset::{self, DatasetError, ReadOptions, Record, RecordKind};
use crate::format::general as fmt_value;
use crate::fsutil::OutputDir;
use crate::identify;
use crate::model::ModelKind;
use anyhow::{Context, Result};
use std::path::PathBuf;

/// Peak memory of a calibration per record row: measured 1240 bytes a row on a 200 000-row
/// record of 3 columns (`/usr/bin/time -v`); the columns' share is an estimate.
const MEMORY: RowCost = RowCost {
    row: 1100,
    column: 50,
};

/// Most data rows a calibration takes, all its records together: 2 million (33 min at 1 kHz).
/// A calibration fits over every row at once and holds about [`MEMORY`] a row (2.5 GB at
/// the limit with 3 columns), so a longer record is refused before it is read whole, and
/// before any output, with the rows, the limit and what to do (decimate or cut the record).
pub const MAX_CALIBRATE_ROWS: usize = 2_000_000;

/// Replays of a typical calibration (the stages, the Jacobians and the effect search), the
/// basis of the up-front estimate; the count of a run is printed with its stages.
const TYPICAL_REPLAYS: usize = 100;

/// Options of `seat-twin calibrate`.
#[derive(Debug, clap::Args)]
pub struct CalibrateArgs {
    /// Measured records (one or more CSV files).
    #[arg(long, num_args = 1.., required = true)]
    pub data: Vec<PathBuf>,
    /// Preset file or shipped preset name to start from.
    #[arg(long, default_value = "paper", value_parser = super::preset_parser())]
    pub preset: String,
    /// Output directory.
    #[arg(long)]
    pub out: PathBuf,
    /// The data acquisition's anti-alias filter, declared (kept in calibrated.toml).
    #[command(flatten)]
    pub acquisition: super::AcquisitionArgs,
}

impl Run for CalibrateArgs {
    fn run(&self) -> Result<Outcome> {
        let Self {
            data,
            preset,
            out,
            acquisition,
        } = self;
        let files: Vec<&std::path::Path> = data.iter().map(|p| p.as_path()).collect();
        check_estimated_rows(&files, MAX_CALIBRATE_ROWS)?;
        check_record_memory("calibrate", &files, MEMORY)?;
        let params = acquisition.apply(load_params(preset)?)?;
        let records = read_within(&files, MAX_CALIBRATE_ROWS)?;
        for r in &records {
            for w in &r.warnings {
                eprintln!("warning: {}: {w}", r.path.display());
            }
        }
        // Issue 12: the output set is written whole into a temporary folder beside --out and
        // moved into place at the end; creating it now checks --out is writable before the
        // long calibration starts.
        let out_dir = OutputDir::create(out)
            .with_context(|| format!("cannot write the results into {}", out.display()))?;
        let record_s: f64 = records.iter().map(|r| r.duration_s()).sum();
        let heartbeat = announce(
            "calibrate",
            &format!(
                "each replay simulates the {} s of the records; a calibration makes about \
                 {TYPICAL_REPLAYS} replays",
                fmt_value(record_s.round())
            ),
            TYPICAL_REPLAYS as f64
                * estimate_wall_s(ModelKind::Twin, record_s, params.numerics.max_step_s),
        );
        let started = std::time::Instant::now();
        let last = std::sync::Mutex::new(String::new());
        let report = identify::calibrate(
            &params,
            &records,
            &identify::CalibrationOptions::default(),
            &|p| {
                if let Ok(mut l) = last.lock()
                    && *l != p.stage
                {
                    eprintln!(
                        "[{:6.1} s] {} ({} replays so far)",
                        started.elapsed().as_secs_f64(),
                        p.stage,
                        p.evaluations
                    );
                    *l = p.stage.clone();
                }
                true
            },
        )?;
        drop(heartbeat);
        let elapsed = started.elapsed().as_secs_f64();
        identify::report::write_all(&report, out_dir.path(), Some(elapsed))?;
        out_dir
            .commit()
            .with_context(|| format!("moving the results into {}", out.display()))?;
        println!("verdict: {}", report.verdict.name());
        for m in &report.missing {
            println!("missing: {m}");
        }
        for e in &report.effects {
            let params: Vec<String> = e
                .params
                .iter()
                .map(|(k, v)| format!("{k} = {}", identify::units::format_value(k, *v)))
                .collect();
            println!("effect {}: {}", e.effect.name(), params.join(", "));
        }
        for t in &report.proposed {
            println!("proposed {}: {}", t.name, t.description);
        }
        if let Some(e) = &report.raw_error_proposed {
            println!(
                "with the proposed terms (in calibrated.toml): {}",
                e.summary()
            );
        }
        for d in &report.drifts {
            println!("drift: {}", d.description);
        }
        let calibrated = report.verdict != identify::Verdict::InsufficientData;
        for v in report.calibrated.iter().filter(|_| calibrated) {
            println!(
                "{}",
                identify::units::format_parameter(&v.name, v.value, v.std)
            );
        }
        println!(
            "weighted error: nominal {:.3}, before {:.3}, after {:.3}",
            report.error_nominal.value, report.error_before.value, report.error_after.value
        );
        if let Some(v) = &report.error_validation {
            println!(
                "validation (held-out): before {:.3}, after {:.3}",
                v.before, v.after
            );
        }
        println!(
            "calibrated in {elapsed:.1} s ({} replays); report in {}",
            report.evaluations,
            out.join("report.md").display()
        );
        if calibrated {
            Ok(Outcome::Done)
        } else {
            eprintln!(
                "note: verdict insufficient_data: nothing was calibrated and no calibrated.toml \
                 was written (exit code {})",
                super::EXIT_NO_RESULT
            );
            Ok(Outcome::NoResult)
        }
    }
}

/// The refusal of a calibration on more than `limit` rows: `file` and what it has, the limit,
/// and what to do.
fn too_many_rows(file: &std::path::Path, has: &str, limit: usize) -> OptionError {
    OptionError(format!(
        "calibrate: {}: {has}, over the limit of {limit} rows a calibration takes (all its \
         records together; it holds about {} bytes a row); decimate the record (keep every \
         n-th row, down to the 200 Hz a measured record needs) or cut it into parts",
        file.display(),
        MEMORY.row + 3 * MEMORY.column,
    ))
}

/// Refuses records whose rows, estimated from their size without reading them, are over
/// `limit` all together (the estimate is close for a record of uniform rows; [`read_within`]
/// checks the exact count).
fn check_estimated_rows(files: &[&std::path::Path], limit: usize) -> Result<(), OptionError> {
    let mut rows = 0;
    for &file in files {
        let Some((r, _)) = estimated_rows(file) else {
            continue;
        };
        rows += r;
        if rows > limit as u64 {
            let has = if files.len() == 1 {
                format!("about {} data rows (from its size)", rows)
            } else {
                format!("the records up to this one have about {rows} data rows (from their size)")
            };
            return Err(too_many_rows(file, &has, limit));
        }
    }
    Ok(())
}

/// Reads the measured records, all together at most `limit` rows: a record past the limit is
/// refused at its first row over it, before the rest is stored.
fn read_within(files: &[&std::path::Path], limit: usize) -> Result<Vec<Record>> {
    let mut records: Vec<Record> = Vec::with_capacity(files.len());
    for &file in files {
        let used: usize = records.iter().map(Record::len).sum();
        let options = ReadOptions {
            max_rows: limit - used,
            ..Default::default()
        };
        match dataset::read_record_with(file, RecordKind::Measured, options) {
            Ok(r) => records.push(r),
            Err(DatasetError::TooManyRows { line, .. }) => {
                let has = if used == 0 {
                    format!(
                        "more than {limit} data rows (line {line} is row {})",
                        limit + 1
                    )
                } else {
                    format!(
                        "more than {} data rows (line {line}), {used} more in the records \
                         before it",
                        limit - used
                    )
                };
                return Err(too_many_rows(file, &has, limit).into());
            }
            Err(e) => return Err(e.into()),
        }
    }
    Ok(records)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::fmt::Write as _;

    /// A measured record of `rows` rows at 1 kHz.
    fn record(dir: &std::path::Path, name: &str, rows: usize) -> std::path::PathBuf {
        let mut text = String::from("t,v_in,u\n");
        for i in 0..rows {
            let _ = writeln!(text, "{},0.5,0.001", i as f64 / 1000.0);
        }
        let path = dir.join(name);
        std::fs::write(&path, text).unwrap();
        path
    }

    /// Issue 21, item 7: calibrate takes at most its row limit, all records together; a
    /// record past it is refused by name with the rows, the limit and what to do, both from
    /// the size estimate (before reading) and from the exact count (while reading).
    #[test]
    fn records_over_the_row_limit_are_refused_with_their_rows_and_the_limit() {
        let dir = tempfile::tempdir().unwrap();
        let a = record(dir.path(), "a.csv", 600);
        let b = record(dir.path(), "b.csv", 500);
        assert!(check_estimated_rows(&[&a, &b], 1200).is_ok());
        let records = read_within(&[&a, &b], 1100).unwrap();
        assert_eq!(records.iter().map(Record::len).sum::<usize>(), 1100);

        let e = check_estimated_rows(&[&a], 500).unwrap_err().0;
        assert!(
            e.starts_with(&format!("calibrate: {}: about 6", a.display())),
            "{e}"
        );
        assert!(
            e.contains("data rows (from its size), over the limit of 500 rows"),
            "{e}"
        );
        assert!(e.contains("decimate the record"), "{e}");
        let e = check_estimated_rows(&[&a, &b], 1000).unwrap_err().0;
        assert!(
            e.starts_with(&format!("calibrate: {}: the records", b.display())),
            "{e}"
        );

        let e = read_within(&[&a], 599).unwrap_err().to_string();
        assert_eq!(
            e,
            format!(
                "calibrate: {}: more than 599 data rows (line 601 is row 600), over the limit \
                 of 599 rows a calibration takes (all its records together; it holds about \
                 1250 bytes a row); decimate the record (keep every n-th row, down to the \
                 200 Hz a measured record needs) or cut it into parts",
                a.display()
            )
        );
        let e = read_within(&[&a, &b], 1099).unwrap_err().to_string();
        assert!(
            e.starts_with(&format!(
                "calibrate: {}: more than 499 data rows (line 501), 600 more in the records \
                 before it, over the limit of 1099 rows",
                b.display()
            )),
            "{e}"
        );
    }
}
