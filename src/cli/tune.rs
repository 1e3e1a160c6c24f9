//! `seat-twin tune`: a controller's gains tuned on the twin, the result into a folder.

use super::{
    OptionError, Outcome, Run, announce, check_range, estimate_wall_s, find_class, load_params,
};
use crate::format::general;
use crate::fsutil::OutputDir;
use crate::model::ModelKind;
use crate::tune;
use anyhow::{Context, Result, bail};
use std::path::PathBuf;

/// Options of `seat-twin tune`.
#[derive(Debug, clap::Args)]
pub struct TuneArgs {
    /// Preset file or shipped preset name (its plant, and its gains as the start).
    #[arg(long, default_value = "paper", value_parser = super::preset_parser())]
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
    /// Duration of each ride [s], 5..=600 (20..=600 with `--excitation class:NAME`).
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

/// Allowed `--seeds`.
const SEEDS_RANGE: (f64, f64) = (1.0, 20.0);
/// Allowed `--duration` [s] with `--excitation ride`.
const DURATION_RANGE_S: (f64, f64) = (5.0, 600.0);
/// Allowed `--evaluations`.
const EVALUATIONS_RANGE: (f64, f64) = (10.0, 10_000.0);

impl TuneArgs {
    /// The tuning input named by `--excitation`.
    fn input(&self) -> Result<tune::TuneInput> {
        match self.excitation.as_str() {
            "ride" => Ok(tune::TuneInput::Ride),
            other => match other.strip_prefix("class:") {
                Some(name) => Ok(tune::TuneInput::Class(find_class(name)?)),
                None => bail!(
                    "--excitation {other}: expected `ride` or `class:NAME` (classes: {})",
                    crate::scenario::classes::names()
                ),
            },
        }
    }
}

impl Run for TuneArgs {
    fn validate(&self) -> Result<(), OptionError> {
        let option = |e: anyhow::Error| OptionError(e.to_string());
        if let Some(k) = &self.controller {
            k.parse::<crate::params::ControllerKind>()
                .map_err(|e| OptionError(e.to_string()))?;
        }
        self.objective
            .parse::<tune::Objective>()
            .map_err(|e| OptionError(e.to_string()))?;
        let input = self.input().map_err(option)?;
        check_range(
            "--seeds",
            self.seeds as f64,
            SEEDS_RANGE.0,
            SEEDS_RANGE.1,
            "",
        )?;
        let (lo, hi) = DURATION_RANGE_S;
        check_range("--duration", self.duration, lo, hi, "s")?;
        if let tune::TuneInput::Class(class) = input {
            // A class record has its own shortest length (the fades and the spectrum).
            if let Err(crate::scenario::class_motion::SignalError::OutOfRange {
                min, max, ..
            }) = crate::scenario::ClassMotion::new(class, self.duration).validate()
            {
                check_range(
                    "--duration",
                    self.duration,
                    min.max(lo),
                    max.min(hi),
                    &format!("s with --excitation {}", self.excitation),
                )?;
            }
        }
        check_range(
            "--evaluations",
            self.evaluations as f64,
            EVALUATIONS_RANGE.0,
            EVALUATIONS_RANGE.1,
            "",
        )
    }

    fn run(&self) -> Result<Outcome> {
        let TuneArgs {
            preset,
            controller,
            objective,
            seeds,
            duration,
            robust,
            evaluations,
            out,
            ..
        } = self;
        let (seeds, duration, robust, evaluations) = (*seeds, *duration, *robust, *evaluations);
        let params = load_params(preset)?;
        let kind = match controller.as_deref() {
            Some(k) => k.parse().map_err(anyhow::Error::msg)?,
            None => params.controller.kind,
        };
        let objective: tune::Objective = objective.parse().map_err(anyhow::Error::msg)?;
        let input = self.input()?;
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
        // The whole set is written into a hidden folder beside --out and moved into place at
        // the end: an error or a signal leaves --out as it was. Creating it now checks that
        // --out is writable before the long search.
        let out_dir = OutputDir::create(out)
            .with_context(|| format!("cannot write the results into {}", out.display()))?;
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
        // Each evaluation runs every ride on every plant (9 of the spread when robust); then
        // the start, the held-out rides and the 27-plant robustness table.
        let plants = if robust { 9.0 } else { 1.0 };
        let rides = n as f64 * duration;
        let simulated = (evaluations as f64 + 1.0) * plants * rides + 2.0 * rides + 27.0 * rides;
        let heartbeat = announce(
            "tune",
            &format!(
                "at most {evaluations} evaluations of {} twin run(s) of {} s each, {} s \
                 simulated in all",
                n as f64 * plants,
                general(duration),
                general(simulated.round())
            ),
            estimate_wall_s(ModelKind::Twin, simulated, params.numerics.max_step_s),
        );
        let last = std::sync::Mutex::new(std::time::Instant::now());
        let progress: tune::Progress = std::sync::Arc::new(move |done, budget| {
            if let Ok(mut l) = last.lock()
                && (l.elapsed().as_secs_f64() >= 10.0 || done == budget)
            {
                eprintln!(
                    "[{:6.0} s] tune: evaluation {done} of at most {budget}",
                    started.elapsed().as_secs_f64()
                );
                *l = std::time::Instant::now();
            }
        });
        let result = tune::tune_observed(&params, &opts, None, Some(progress))?;
        drop(heartbeat);
        let wall = started.elapsed().as_secs_f64();
        let mut start = params;
        start.controller.kind = kind;
        let files = tune::report::write_outputs(&result, &start, out_dir.path(), wall)?;
        out_dir
            .commit()
            .with_context(|| format!("moving the results into {}", out.display()))?;
        let unit = objective.unit();
        let value = |e: &tune::Evaluation| {
            if e.objective.is_finite() {
                format!("{:.4} {unit}", e.objective)
            } else if e.unstable_points > 0 {
                format!(
                    "not simulated (unstable where the rides run; {} of 27 spread points)",
                    e.unstable_points
                )
            } else {
                "diverged".to_string()
            }
        };
        println!(
            "{}: start {} -> tuned {} (held out {} -> {}); {} evaluations in {wall:.1} s",
            objective.name(),
            value(&result.baseline),
            value(&result.tuned),
            value(&result.baseline_heldout),
            value(&result.tuned_heldout),
            result.evaluations
        );
        for (k, v) in &result.tuned.gains {
            println!("  {k} = {v:.4}");
        }
        let words = |v: f64, scale: f64, digits: usize, unit: &str| {
            if v.is_finite() {
                format!("{:.digits$} {unit}", v * scale)
            } else {
                "∞ (no crossing)".to_string()
            }
        };
        let stroke = if result.tuned.max_abs_u_m.is_finite() {
            format!(
                "max |u| {:.1} mm, contacts {}",
                result.tuned.max_abs_u_m * 1e3,
                result.tuned.contacts
            )
        } else {
            "rides not simulated".to_string()
        };
        println!(
            "  GM {}, PM {}, delay margin {}, {stroke}",
            words(result.tuned.gain_margin_db, 1.0, 1, "dB"),
            words(result.tuned.phase_margin_deg, 1.0, 1, "deg"),
            words(result.tuned.delay_margin_s, 1e3, 2, "ms"),
        );
        if !result.failures.is_empty() {
            println!(
                "wrote {} files to {} (no tuned.toml)",
                files.len(),
                out.display()
            );
            eprintln!(
                "tune: the tuned gains' claim fails, so no tuned.toml was written:\n  - {}",
                result.failures.join("\n  - ")
            );
            return Ok(Outcome::NoResult);
        }
        println!("wrote {} files to {}", files.len(), out.display());
        Ok(Outcome::Done)
    }
}
