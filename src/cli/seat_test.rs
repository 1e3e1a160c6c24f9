//! `seat-twin seat-test`: a standard laboratory seat test, its report into a folder.

use super::{OptionError, Outcome, Run, check_range, find_class, load_params};
use crate::fsutil::OutputDir;
use crate::model::ModelKind;
use crate::scenario::ClassMotion;
use anyhow::{Context, Result};
use std::path::PathBuf;

/// Options of `seat-twin seat-test`.
#[derive(Debug, clap::Args)]
pub struct SeatTestArgs {
    /// Input spectral class: EM1–EM9 (ISO 7096), IT1–IT4 (EN 13490), AG1–AG3 (ISO 5007).
    #[arg(long)]
    pub class: String,
    /// Preset file or shipped preset name.
    #[arg(long, default_value = "paper", value_parser = super::preset_parser())]
    pub preset: String,
    /// Which model.
    #[arg(long, value_enum, default_value = "twin")]
    pub model: ModelKind,
    /// Suspended mass [kg] (default: the preset's; the paper's rig carries 11.7 kg).
    #[arg(long, allow_hyphen_values = true)]
    pub mass: Option<f64>,
    /// Record length including 2 s fades at both ends [s], 20.384..=3600 (the fades and one
    /// 16.384 s Welch segment between them).
    #[arg(long, default_value_t = crate::seat_test::run::DEFAULT_DURATION_S, allow_hyphen_values = true)]
    pub duration: f64,
    /// Seed of the class motion's phases, 0..=2^64−1.
    #[arg(long, default_value_t = 1, allow_hyphen_values = true, value_parser = super::parse_seed)]
    pub seed: u64,
    /// Output directory.
    #[arg(long)]
    pub out: PathBuf,
}

/// Allowed `--mass` [kg].
const MASS_RANGE_KG: (f64, f64) = (1.0, 500.0);
/// Longest `--duration` [s] (the class motion's limit).
const MAX_DURATION_S: f64 = 3600.0;

/// Shortest `--duration` [s]: the two fades and one Welch segment of the PSD check between
/// them (20.384 s with the 2 s fades at 1 kHz).
pub fn min_duration_s() -> f64 {
    use crate::scenario::class_motion::{CLASS_RATE_HZ, WELCH_SEGMENT};
    let fade = ClassMotion::new(&crate::seat_test::CLASSES[0], MAX_DURATION_S).fade_s;
    (WELCH_SEGMENT as f64 + 2.0 * (fade * CLASS_RATE_HZ).ceil()) / CLASS_RATE_HZ
}

impl Run for SeatTestArgs {
    fn validate(&self) -> Result<(), OptionError> {
        find_class(&self.class).map_err(|e| OptionError(e.to_string()))?;
        if let Some(m) = self.mass {
            check_range("--mass", m, MASS_RANGE_KG.0, MASS_RANGE_KG.1, "kg")?;
        }
        check_range(
            "--duration",
            self.duration,
            min_duration_s(),
            MAX_DURATION_S,
            "s (2 s fades at both ends and one 16.384 s Welch segment between them)",
        )
    }

    fn run(&self) -> Result<Outcome> {
        use crate::seat_test::{SeatTestOptions, report, run_seat_test};
        let a = self;
        let class = find_class(&a.class)?;
        let params = load_params(&a.preset)?;
        // The set is written whole into a hidden folder beside --out and moved at the end:
        // a failed write or a signal leaves --out as it was.
        let out_dir = OutputDir::create(&a.out).with_context(|| {
            format!("cannot write the seat-test report into {}", a.out.display())
        })?;
        let opts = SeatTestOptions {
            mass_kg: a.mass,
            duration_s: a.duration,
            seed: a.seed,
            ..SeatTestOptions::new(class, a.model)
        };
        let result = run_seat_test(&params, &opts).with_context(|| {
            format!(
                "seat test {} on the {} model",
                class.name,
                opts.model.name()
            )
        })?;
        report::write_seat_test(&result, class, &a.preset, out_dir.path())
            .with_context(|| format!("writing the seat-test report to {}", a.out.display()))?;
        out_dir
            .commit()
            .with_context(|| format!("moving the seat-test report into {}", a.out.display()))?;
        let n = &result.numbers;
        println!(
            "{} on the {} model, {:.1} kg: a_w floor {:.3} m/s², seat {:.3} m/s², SEAT {:.1} %, \
             VDV seat {:.3} m/s^1.75, max |u| {:.1} mm, {} contact(s), PSD error {:.1} % of peak{}",
            n.class,
            n.model,
            n.mass_kg,
            n.aw_floor,
            n.aw_seat,
            n.seat_percent,
            n.vdv_seat,
            n.max_abs_u_mm,
            n.contacts,
            n.psd_error_percent,
            if n.psd_within_tolerance {
                ""
            } else {
                " (outside the ±10 % tolerance)"
            }
        );
        if n.contacts > 0 {
            eprintln!(
                "warning: the seat reached its ±{:.0} mm stops {} time(s)",
                n.half_stroke_mm, n.contacts
            );
        }
        println!("report written to {}", a.out.join("report.md").display());
        Ok(Outcome::Done)
    }
}
