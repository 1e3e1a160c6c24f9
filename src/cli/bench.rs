//! `seat-twin bench`: real-time factors and accuracy on this machine.

use super::{Run, load_params};
use anyhow::Result;

/// Options of `seat-twin bench`.
#[derive(Debug, clap::Args)]
pub struct BenchArgs {
    /// Preset file or shipped preset name.
    #[arg(long, default_value = "paper")]
    pub preset: String,
}

impl Run for BenchArgs {
    fn run(&self) -> Result<()> {
        let params = load_params(&self.preset)?;
        let text = crate::bench::run_bench(&params)?;
        println!("{text}");
        Ok(())
    }
}
