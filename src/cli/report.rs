//! `seat-twin report`: the paper's sections 4–6 reproduced into a folder.

use super::{Heartbeat, Outcome, Run, load_params};
use crate::format::general;
use crate::fsutil::OutputDir;
use anyhow::{Context, Result};
use std::path::PathBuf;

/// Options of `seat-twin report`.
#[derive(Debug, clap::Args)]
pub struct ReportArgs {
    /// Preset file or shipped preset name.
    #[arg(long, default_value = "paper", value_parser = super::preset_parser())]
    pub preset: String,
    /// Output directory.
    #[arg(long, default_value = "out/report")]
    pub out: PathBuf,
}

impl Run for ReportArgs {
    fn run(&self) -> Result<Outcome> {
        let Self { preset, out } = self;
        let params = load_params(preset)?;
        // The whole set goes into a temporary folder beside --out and is moved into place
        // at the end: a failure or Ctrl-C leaves --out as it was.
        let dir = OutputDir::create(out)
            .with_context(|| format!("cannot write the report into {}", out.display()))?;
        let default_step = crate::params::NumericsParams::default().max_step_s;
        let factor = default_step / params.numerics.max_step_s;
        if factor > 4.0 {
            eprintln!(
                "note: numerics.max_step_s = {} s is {}× finer than the default {} s: the \
                 twin's runs take about {}× as long as usual (minutes, not seconds)",
                general(params.numerics.max_step_s),
                general(factor.round()),
                general(default_step),
                general(factor.round())
            );
        }
        let heartbeat = Heartbeat::start("report".into(), std::time::Duration::from_secs(10));
        let summary = crate::report::write_report(&params, preset, dir.path())
            .with_context(|| format!("the report on preset {preset}"))?;
        drop(heartbeat);
        dir.commit()
            .with_context(|| format!("moving the report into {}", out.display()))?;
        println!("{summary}");
        println!("report written to {}", out.join("report.md").display());
        Ok(Outcome::Done)
    }
}
