//! `seat-twin calibrate`: the twin calibrated on measured records, its report into a folder.

use super::{Outcome, RowCost, Run, announce, check_record_memory, estimate_wall_s, load_params};
use crate::dataset::{self, RecordKind};
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
}

impl Run for CalibrateArgs {
    fn run(&self) -> Result<Outcome> {
        let Self { data, preset, out } = self;
        let files: Vec<&std::path::Path> = data.iter().map(|p| p.as_path()).collect();
        check_record_memory("calibrate", &files, MEMORY)?;
        let params = load_params(preset)?;
        let records = data
            .iter()
            .map(|p| dataset::read_record(p, RecordKind::Measured))
            .collect::<Result<Vec<_>, _>>()?;
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
                .map(|(k, v)| format!("{k} = {}", identify::report::format_value(k, *v)))
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
                identify::report::format_parameter(&v.name, v.value, v.std)
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
