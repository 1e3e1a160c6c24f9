//! `seat-twin seat-test`: a standard laboratory seat test, its report into a folder.

use super::{Run, check_range, find_class, load_params};
use crate::model::ModelKind;
use anyhow::{Context, Result};
use std::path::PathBuf;

/// Options of `seat-twin seat-test`.
#[derive(Debug, clap::Args)]
pub struct SeatTestArgs {
    /// Input spectral class: EM1–EM9 (ISO 7096), IT1–IT4 (EN 13490), AG1–AG3 (ISO 5007).
    #[arg(long)]
    pub class: String,
    /// Preset file or shipped preset name.
    #[arg(long, default_value = "paper")]
    pub preset: String,
    /// Which model.
    #[arg(long, value_enum, default_value = "twin")]
    pub model: ModelKind,
    /// Suspended mass [kg] (default: the preset's; the paper's rig carries 11.7 kg).
    #[arg(long, allow_hyphen_values = true)]
    pub mass: Option<f64>,
    /// Record length including 2 s fades at both ends [s].
    #[arg(long, default_value_t = crate::seat_test::run::DEFAULT_DURATION_S, allow_hyphen_values = true)]
    pub duration: f64,
    /// Seed of the class motion's phases.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Output directory.
    #[arg(long)]
    pub out: PathBuf,
}

impl Run for SeatTestArgs {
    fn run(&self) -> Result<()> {
        use crate::seat_test::{SeatTestOptions, report, run_seat_test};
        let a = self;
        let class = find_class(&a.class)?;
        let params = load_params(&a.preset)?;
        if let Some(m) = a.mass {
            check_range("--mass", m, 1.0, 500.0, "kg")?;
        }
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
        report::write_seat_test(&result, class, &a.preset, &a.out)
            .with_context(|| format!("writing the seat-test report to {}", a.out.display()))?;
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
        Ok(())
    }
}
