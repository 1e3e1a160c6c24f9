//! `seat-twin replay`: a measured record replayed through the twin into one CSV file.

use super::{
    Outcome, RowCost, Run, check_output_is_not_an_input, check_record_memory, load_preset,
    preset_file,
};
use crate::dataset::{self, CsvWriter, RecordKind};

use crate::fsutil;
use crate::identify;
use anyhow::{Context, Result};
use std::path::PathBuf;

/// Peak memory of a replay per record row, measured with `/usr/bin/time -v` (release build)
/// on 2 million rows: 39 bytes with 3 columns, 82 with 8 (the reader stores only the
/// replayed columns, the twin's samples go to the file as they are made).
const MEMORY: RowCost = RowCost { row: 14, column: 9 };
/// The record's columns a replay reads: the command, the stroke, the platform and the seat.
const REPLAYED_COLUMNS: [&str; 6] = ["t", "v_in", "u", "x", "xdd", "ydd"];

/// Options of `seat-twin replay`.
#[derive(Debug, clap::Args)]
pub struct ReplayArgs {
    /// Measured record (CSV: t, v_in, u; optional x, xdd, ydd, p1, p2).
    #[arg(long)]
    pub data: PathBuf,
    /// Preset file or shipped preset name. A calibrated preset that lists this record's file
    /// name in `[per_record.cd]` (a drift of Cd) replays it with that Cd.
    #[arg(long, default_value = "paper", value_parser = super::preset_parser())]
    pub preset: String,
    /// Output file (CSV).
    #[arg(long)]
    pub out: PathBuf,
    /// The data acquisition's anti-alias filter, declared (overrides the preset's).
    #[command(flatten)]
    pub acquisition: super::AcquisitionArgs,
}

impl Run for ReplayArgs {
    fn run(&self) -> Result<Outcome> {
        let Self {
            data,
            preset,
            out,
            acquisition,
        } = self;
        let preset_file = preset_file(preset);
        let mut inputs = vec![("--data", data.as_path())];
        inputs.extend(preset_file.as_deref().map(|p| ("--preset", p)));
        check_output_is_not_an_input(out, &inputs)?;
        check_record_memory("replay", &[data], MEMORY)?;
        let mut loaded = load_preset(preset)?;
        loaded.params = acquisition.apply(loaded.params)?;
        // The pressures are not replayed: not storing them saves 16 bytes a row.
        let rec = dataset::read_record_with(
            data,
            RecordKind::Measured,
            dataset::ReadOptions {
                keep: &REPLAYED_COLUMNS,
                ..Default::default()
            },
        )?;
        for w in &rec.warnings {
            eprintln!("warning: {}: {w}", data.display());
        }
        // A calibration that found Cd drifting through the campaign lists each record's own
        // value ([per_record.cd]): the record replayed is matched by its file name.
        let file = data
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        let (params, listed) = loaded.per_record.params_for(&loaded.params, &file);
        let per_record = if loaded.per_record.is_empty() {
            None
        } else if listed {
            Some(format!(
                "cd = {} for {file}, its own value from the preset's [per_record.cd]",
                params.plant.valve.cd
            ))
        } else {
            Some(format!(
                "{file} is not in the preset's [per_record.cd]: replayed with the campaign \
                 value valve.cd = {}",
                params.plant.valve.cd
            ))
        };
        if let Some(n) = &per_record {
            eprintln!("note: {n}");
        }
        let mut comments = vec![
            ("model".into(), "twin".into()),
            ("preset".into(), preset.clone()),
            ("replayed".into(), data.display().to_string()),
            (
                "excitation".into(),
                identify::replay::EXCITATION_CONDITIONING.into(),
            ),
            ("units".into(), identify::SimChannels::CSV_UNITS.into()),
        ];
        comments.extend(per_record.map(|n| ("per_record".into(), n)));
        // The twin's samples are written as they are made (into a temporary file renamed at
        // the end): the replay holds the record and a few values a row, not every channel.
        let mut errors = None;
        fsutil::write_atomic(out, |w| -> Result<()> {
            let mut csv = CsvWriter::start(w, &identify::SimChannels::CSV_COLUMNS, &comments)?;
            let mut failed = None;
            let e = identify::replay::replay_streamed(
                &params,
                rec,
                &identify::replay::MetricOptions::default(),
                |t, s| {
                    let row = [t, s.u, s.ydd, s.p1, s.p2, s.xv, s.q1, s.q2];
                    if failed.is_none()
                        && let Err(e) = csv.row(&mut *w, &row)
                    {
                        failed = Some(e);
                    }
                },
            )?;
            if let Some(e) = failed {
                return Err(e).with_context(|| format!("writing {}", out.display()));
            }
            errors = Some(e);
            Ok(())
        })?;
        let Some(e) = errors else {
            anyhow::bail!("the replay of {} made no sample", data.display());
        };
        let ydd_text = |ydd: Option<f64>| {
            ydd.map(|y| format!(", ydd {y:.3} m/s^2"))
                .unwrap_or_default()
        };
        println!(
            "{} samples replayed to {}; RMS error: du {:.3} mm/s ({:.1} %), u {:.3} mm{}",
            e.samples,
            out.display(),
            1e3 * e.du,
            100.0 * e.du_nrmse,
            1e3 * e.u,
            ydd_text(e.ydd)
        );
        if let Some(b) = e.before_end_stop {
            eprintln!(
                "note: the measured stroke comes within {:.1} mm of an end stop (±{:.1} mm) at \
                 {:.3} s; up to there ({} samples, the part a calibration fits) the RMS error \
                 is u {:.3} mm{}. After the contact the error is mostly the stop's impact, \
                 which the twin takes a little sooner, later or not at all with the smallest \
                 change of a parameter",
                1e3 * identify::data::END_STOP_MARGIN_M,
                500.0 * params.plant.cylinder.stroke_m,
                b.at_s,
                b.samples,
                1e3 * b.u,
                ydd_text(b.ydd)
            );
        }
        Ok(Outcome::Done)
    }
}
