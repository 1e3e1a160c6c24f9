//! `seat-twin tune`: a controller's gains tuned on the twin, the result into a folder.

use super::{Run, check_range, find_class, load_params};
use crate::tune;
use anyhow::{Context, Result, bail};
use std::path::PathBuf;

/// Options of `seat-twin tune`.
#[derive(Debug, clap::Args)]
pub struct TuneArgs {
    /// Preset file or shipped preset name (its plant, and its gains as the start).
    #[arg(long, default_value = "paper")]
    pub preset: String,
    /// Controller structure: paper, predictive, skyhook or smith (default: the preset's).
    #[arg(long)]
    pub controller: Option<String>,
    /// Objective: aw (Wk-weighted RMS), vdv or seat.
    #[arg(long, default_value = "aw")]
    pub objective: String,
    /// Tuning input: `ride` (the paper's random ride) or `class:NAME` (a seat-test input class).
    #[arg(long, default_value = "ride")]
    pub excitation: String,
    /// Number of tuning rides (seeds 1..=N); as many held-out rides use seeds 101...
    #[arg(long, default_value_t = 3, allow_negative_numbers = true)]
    pub seeds: i64,
    /// Duration of each ride [s], 5..=600.
    #[arg(long, default_value_t = 60.0, allow_negative_numbers = true)]
    pub duration: f64,
    /// Optimise the worst case over Cd ±10 %, τ ±3 ms, mass ±20 %.
    #[arg(long)]
    pub robust: bool,
    /// Budget of objective evaluations, 10..=10000.
    #[arg(long, default_value_t = 120, allow_negative_numbers = true)]
    pub evaluations: i64,
    /// Output directory.
    #[arg(long)]
    pub out: PathBuf,
}

impl Run for TuneArgs {
    fn run(&self) -> Result<()> {
        let TuneArgs {
            preset,
            controller,
            objective,
            excitation,
            seeds,
            duration,
            robust,
            evaluations,
            out,
        } = self;
        let (seeds, duration, robust, evaluations) = (*seeds, *duration, *robust, *evaluations);
        let params = load_params(preset)?;
        let kind = match controller.as_deref() {
            Some(k) => k.parse().map_err(anyhow::Error::msg)?,
            None => params.controller.kind,
        };
        let objective: tune::Objective = objective.parse().map_err(anyhow::Error::msg)?;
        let input = match excitation.as_str() {
            "ride" => tune::TuneInput::Ride,
            other => match other.strip_prefix("class:") {
                Some(name) => tune::TuneInput::Class(find_class(name)?),
                None => bail!(
                    "--excitation {other}: expected `ride` or `class:NAME` (classes: {})",
                    crate::seat_test::classes::names()
                ),
            },
        };
        check_range("--seeds", seeds as f64, 1.0, 20.0, "")?;
        check_range("--duration", duration, 5.0, 600.0, "s")?;
        check_range("--evaluations", evaluations as f64, 10.0, 10_000.0, "")?;
        std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
        let n = seeds as u64;
        let opts = tune::TuneOptions {
            kind,
            objective,
            input,
            tune_seeds: (1..=n).collect(),
            heldout_seeds: (101..101 + n).collect(),
            duration_s: duration,
            robust,
            max_evaluations: evaluations as usize,
        };
        let started = std::time::Instant::now();
        eprintln!(
            "tuning {kind} for {} on {n} ride(s) of {duration:.0} s of {} (held out: {n}){}",
            objective.name(),
            input.describe(),
            if robust {
                ", worst case over the spread"
            } else {
                ""
            }
        );
        let result = tune::tune(&params, &opts, None)?;
        let wall = started.elapsed().as_secs_f64();
        let mut start = params;
        start.controller.kind = kind;
        let files = tune::report::write_outputs(&result, &start, out, wall)?;
        let unit = objective.unit();
        println!(
            "{}: start {:.4} {unit} -> tuned {:.4} {unit} (held out {:.4} -> {:.4}); {} evaluations in {wall:.1} s",
            objective.name(),
            result.baseline.objective,
            result.tuned.objective,
            result.baseline_heldout.objective,
            result.tuned_heldout.objective,
            result.evaluations
        );
        for (k, v) in &result.tuned.gains {
            println!("  {k} = {v:.4}");
        }
        println!(
            "  GM {:.1} dB, PM {:.1} deg, max |u| {:.1} mm, contacts {}",
            result.tuned.gain_margin_db,
            result.tuned.phase_margin_deg,
            result.tuned.max_abs_u_m * 1e3,
            result.tuned.contacts
        );
        println!("wrote {} files to {}", files.len(), out.display());
        Ok(())
    }
}
