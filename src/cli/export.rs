//! `seat-twin export fmu|controller`: the twin as an FMI 2.0 co-simulation FMU, the tuned
//! controller as portable C99 (see [`crate::export`]).

use super::{OptionError, Outcome, Run, check_output_is_not_an_input, preset_file};
use crate::export::fmu::{self, ControllerPlacement};
use anyhow::{Context, Result};
use std::path::PathBuf;

/// Options of `seat-twin export`.
#[derive(Debug, clap::Args)]
pub struct ExportArgs {
    /// What to export.
    #[command(subcommand)]
    pub what: ExportWhat,
}

/// The exports.
#[derive(Debug, clap::Subcommand)]
pub enum ExportWhat {
    /// The twin as an FMI 2.0 co-simulation FMU (Linux x86-64): inputs xdd, x (and v_in_ext
    /// with --controller external); outputs u, ydd, p1, p2, q1, q2, xv, v_in; the preset's
    /// keys as parameters.
    Fmu(ExportFmuArgs),
    /// The preset's controller at a fixed rate as portable C99: seat_controller.h,
    /// seat_controller.c (double and float variants) and seat_controller.json (the
    /// discretised transfer functions) in DIR.
    Controller(ExportControllerArgs),
}

/// `--lang` of `export controller`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum LangArg {
    /// C99: one header and one source file.
    C,
}

/// Options of `seat-twin export controller`.
#[derive(Debug, clap::Args)]
pub struct ExportControllerArgs {
    /// Preset file or shipped preset name.
    #[arg(long, default_value = "paper", value_parser = super::preset_parser())]
    pub preset: String,
    /// Controller rate [Hz] (50 to 100000).
    #[arg(long, allow_hyphen_values = true)]
    pub rate: f64,
    /// Language.
    #[arg(long, value_enum)]
    pub lang: LangArg,
    /// Output directory (written whole or not at all).
    #[arg(long)]
    pub out: PathBuf,
}

impl Run for ExportControllerArgs {
    fn validate(&self) -> Result<(), OptionError> {
        let (lo, hi) = crate::export::controller::RATE_RANGE_HZ;
        super::check_range("--rate", self.rate, lo, hi, "Hz")
    }

    fn run(&self) -> Result<Outcome> {
        let preset_path = preset_file(&self.preset);
        let mut inputs: Vec<(&str, &std::path::Path)> = Vec::new();
        inputs.extend(preset_path.as_deref().map(|p| ("--preset", p)));
        check_output_is_not_an_input(&self.out, &inputs)?;
        let preset = crate::preset::resolve(&self.preset)?;
        let LangArg::C = self.lang;
        crate::export::controller::write(
            &preset,
            &self.preset,
            self.rate,
            &self.out,
            &mut |_, _| {},
        )
        .with_context(|| format!("exporting the controller to {}", self.out.display()))?;
        println!(
            "wrote {}: {} controller at {} Hz ({})",
            self.out.display(),
            preset.params.controller.kind.name(),
            crate::format::general(self.rate),
            crate::export::controller::FILES.join(", ")
        );
        Ok(Outcome::Done)
    }
}

/// `--controller` of `export fmu`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum PlacementArg {
    /// The preset's controller inside the FMU (closed loop, as `simulate` runs it).
    Internal,
    /// The valve command is the FMU's input `v_in_ext`.
    External,
}

/// Options of `seat-twin export fmu`.
#[derive(Debug, clap::Args)]
pub struct ExportFmuArgs {
    /// Preset file or shipped preset name.
    #[arg(long, default_value = "paper", value_parser = super::preset_parser())]
    pub preset: String,
    /// Where the controller runs.
    #[arg(long, value_enum, default_value = "internal")]
    pub controller: PlacementArg,
    /// The shared library to pack (default: libseat_twin.so beside this executable).
    #[arg(long)]
    pub library: Option<PathBuf>,
    /// Output file (.fmu).
    #[arg(long)]
    pub out: PathBuf,
}

impl Run for ExportArgs {
    fn validate(&self) -> Result<(), OptionError> {
        match &self.what {
            ExportWhat::Fmu(a) => a.validate(),
            ExportWhat::Controller(a) => a.validate(),
        }
    }

    fn run(&self) -> Result<Outcome> {
        match &self.what {
            ExportWhat::Fmu(a) => a.run(),
            ExportWhat::Controller(a) => a.run(),
        }
    }
}

impl Run for ExportFmuArgs {
    fn validate(&self) -> Result<(), OptionError> {
        if self.out.extension().is_none_or(|e| e != "fmu") {
            return Err(OptionError(format!(
                "--out {} must end in .fmu (importers recognise the archive by it)",
                self.out.display()
            )));
        }
        Ok(())
    }

    fn run(&self) -> Result<Outcome> {
        let preset_path = preset_file(&self.preset);
        let mut inputs: Vec<(&str, &std::path::Path)> = Vec::new();
        inputs.extend(preset_path.as_deref().map(|p| ("--preset", p)));
        inputs.extend(self.library.as_deref().map(|p| ("--library", p)));
        check_output_is_not_an_input(&self.out, &inputs)?;
        let preset = crate::preset::resolve(&self.preset)?;
        let placement = match self.controller {
            PlacementArg::Internal => ControllerPlacement::Internal,
            PlacementArg::External => ControllerPlacement::External,
        };
        let library = self
            .library
            .clone()
            .unwrap_or_else(fmu::library_beside_executable);
        let summary = fmu::write(&preset, placement, &library, &self.out, &mut |_, _| {})
            .with_context(|| format!("exporting the FMU to {}", self.out.display()))?;
        println!(
            "wrote {} ({} kB): FMI 2.0 co-simulation, controller {}, {} variables, internal \
             step {} s, guid {}",
            self.out.display(),
            summary.bytes / 1000,
            placement.name(),
            summary.variables,
            crate::format::general(preset.params.numerics.max_step_s),
            summary.guid
        );
        Ok(Outcome::Done)
    }
}
