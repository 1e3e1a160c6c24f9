//! `seat-twin replay`: a measured record replayed through the twin into one CSV file.

use super::{
    Outcome, RowCost, Run, check_output_is_not_an_input, check_record_memory, load_params,
    preset_file,
};

/// Peak memory of a replay per record row: measured 198 bytes a row with 3 columns and 328
/// with 8 (`/usr/bin/time -v`, 1 million rows).
const MEMORY: RowCost = RowCost {
    row: 120,
    column: 26,
};
use crate::dataset::{self, RecordKind};
use crate::identify;
use anyhow::{Context, Result};
use std::path::PathBuf;

/// Options of `seat-twin replay`.
#[derive(Debug, clap::Args)]
pub struct ReplayArgs {
    /// Measured record (CSV: t, v_in, u; optional x, xdd, ydd, p1, p2).
    #[arg(long)]
    pub data: PathBuf,
    /// Preset file or shipped preset name.
    #[arg(long, default_value = "paper", value_parser = super::preset_parser())]
    pub preset: String,
    /// Output file (CSV).
    #[arg(long)]
    pub out: PathBuf,
}

impl Run for ReplayArgs {
    fn run(&self) -> Result<Outcome> {
        let Self { data, preset, out } = self;
        let preset_file = preset_file(preset);
        let mut inputs = vec![("--data", data.as_path())];
        inputs.extend(preset_file.as_deref().map(|p| ("--preset", p)));
        check_output_is_not_an_input(out, &inputs)?;
        check_record_memory("replay", &[data], MEMORY)?;
        let params = load_params(preset)?;
        let rec = dataset::read_record(data, RecordKind::Measured)?;
        for w in &rec.warnings {
            eprintln!("warning: {}: {w}", data.display());
        }
        let rep = identify::replay(&params, &rec)?;
        let s = &rep.sim;
        let comments = [
            ("model".into(), "twin".into()),
            ("preset".into(), preset.clone()),
            ("replayed".into(), data.display().to_string()),
            (
                "excitation".into(),
                identify::replay::EXCITATION_CONDITIONING.into(),
            ),
            ("units".into(), identify::SimChannels::CSV_UNITS.into()),
        ];
        s.write_csv(&rec.t, out, &comments)
            .with_context(|| format!("writing {}", out.display()))?;
        let e = &rep.errors;
        println!(
            "{} samples replayed to {}; RMS error: du {:.3} mm/s ({:.1} %), u {:.3} mm{}",
            s.t.len(),
            out.display(),
            1e3 * e.du,
            100.0 * e.du_nrmse,
            1e3 * e.u,
            e.ydd
                .map(|y| format!(", ydd {y:.3} m/s^2"))
                .unwrap_or_default()
        );
        Ok(Outcome::Done)
    }
}
