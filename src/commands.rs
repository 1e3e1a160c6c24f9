//! The `tune` and `seat-test` subcommands of the `seat-twin` binary (a module of main.rs,
//! not of the library): options checked, the library run, its outputs written.

use super::load_params;
use anyhow::{Context, Result, bail};
use seat_twin::cli::{SeatTestArgs, TuneArgs, check_range};

pub(crate) fn find_class(name: &str) -> Result<&'static seat_twin::seat_test::InputClass> {
    seat_twin::seat_test::find(name).with_context(|| {
        format!(
            "unknown input class `{name}`; the classes are {}",
            seat_twin::seat_test::classes::names()
        )
    })
}

pub(crate) fn run_seat_test_command(a: SeatTestArgs) -> Result<()> {
    use seat_twin::seat_test::{SeatTestOptions, report, run_seat_test};
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

/// `seat-twin tune`.
pub(crate) fn run_tune(args: &TuneArgs) -> Result<()> {
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
    } = args;
    let (controller, seeds, duration, robust, evaluations) = (
        controller.as_deref(),
        *seeds,
        *duration,
        *robust,
        *evaluations,
    );
    let (preset, objective, excitation) =
        (preset.as_str(), objective.as_str(), excitation.as_str());
    use seat_twin::tune;
    let params = load_params(preset)?;
    let kind = match controller {
        Some(k) => k.parse().map_err(anyhow::Error::msg)?,
        None => params.controller.kind,
    };
    let objective: tune::Objective = objective.parse().map_err(anyhow::Error::msg)?;
    let input = match excitation {
        "ride" => tune::TuneInput::Ride,
        other => match other.strip_prefix("class:") {
            Some(name) => tune::TuneInput::Class(find_class(name)?),
            None => bail!(
                "--excitation {other}: expected `ride` or `class:NAME` (classes: {})",
                seat_twin::seat_test::classes::names()
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
        bail!(
            "the tuned gains' claim fails, so no tuned.toml was written:\n  - {}",
            result.failures.join("\n  - ")
        );
    }
    println!("wrote {} files to {}", files.len(), out.display());
    Ok(())
}
