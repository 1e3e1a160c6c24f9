//! Writers of a tuning run: `tuned.toml`, `report.json` (SI except the keys that name their
//! display unit, as the interface asks: `max_abs_u_mm`), `report.md` and the plots (Pareto
//! front, transmissibility before and after). Every file is written atomically.

use super::{Evaluation, TuneResult};
use crate::analysis::frequency_response as fr;
use crate::control::ControlLaw;
use crate::params::Params;
use crate::plot::{Figure, Panel, PlotError, Scale, Series, palette, save_figure};
use crate::preset::{Preset, PresetError, PresetMeta, write_atomic};
use serde_json::{Value, json};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Why the outputs could not be written.
#[derive(Debug, thiserror::Error)]
pub enum TuneReportError {
    /// A file could not be written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The error.
        source: std::io::Error,
    },
    /// A plot failed.
    #[error(transparent)]
    Plot(#[from] PlotError),
    /// The preset failed.
    #[error(transparent)]
    Preset(#[from] PresetError),
}

/// A JSON number, or null for a value that is not finite (never NaN in a report).
fn num(v: f64) -> Value {
    if v.is_finite() { json!(v) } else { Value::Null }
}

fn gains_json(e: &Evaluation) -> Value {
    let mut m = serde_json::Map::new();
    for (k, v) in &e.gains {
        m.insert(k.clone(), num(*v));
    }
    Value::Object(m)
}

fn eval_json(e: &Evaluation) -> Value {
    json!({
        "gains": gains_json(e),
        "objective": num(e.objective),
        "max_abs_u_mm": num(e.max_abs_u_m * 1e3),
        "contacts": e.contacts,
        "gain_margin_db": num(e.gain_margin_db),
        "phase_margin_deg": num(e.phase_margin_deg),
        "feasible": e.feasible,
    })
}

/// The `report.json` document.
pub fn report_json(r: &TuneResult, wall_s: f64) -> Value {
    json!({
        "controller": {"kind": r.kind.name(), "gains": gains_json(&r.tuned)},
        "objective": {
            "name": r.objective.name(),
            "unit": r.objective.unit(),
            "baseline": num(r.baseline.objective),
            "tuned": num(r.tuned.objective),
            "baseline_heldout": num(r.baseline_heldout.objective),
            "tuned_heldout": num(r.tuned_heldout.objective),
        },
        "constraints": {
            "gain_margin_db": num(r.tuned.gain_margin_db),
            "phase_margin_deg": num(r.tuned.phase_margin_deg),
            "max_abs_u_mm": num(r.tuned.max_abs_u_m * 1e3),
            "contacts": r.tuned.contacts,
            "max_abs_u_mm_heldout": num(r.tuned_heldout.max_abs_u_m * 1e3),
            "contacts_heldout": r.tuned_heldout.contacts,
            "limits": {"gain_margin_db": super::MIN_GAIN_MARGIN_DB,
                       "phase_margin_deg": super::MIN_PHASE_MARGIN_DEG,
                       "max_abs_u_mm": super::MAX_ABS_U_M * 1e3},
        },
        "baseline": eval_json(&r.baseline),
        "tuned": eval_json(&r.tuned),
        "baseline_heldout": eval_json(&r.baseline_heldout),
        "tuned_heldout": eval_json(&r.tuned_heldout),
        "robustness": r.robustness.iter().map(|row| json!({
            "cd": row.cd, "tau_s": row.tau_s, "mass_kg": row.mass_kg,
            "objective": num(row.objective), "contacts": row.contacts,
            "max_abs_u_mm": num(row.max_abs_u_m * 1e3),
        })).collect::<Vec<_>>(),
        "pareto": r.pareto.iter().map(|e| json!({
            "objective": num(e.objective),
            "max_abs_u_mm": num(e.max_abs_u_m * 1e3),
            "gains": gains_json(e),
        })).collect::<Vec<_>>(),
        "evaluations": r.evaluations,
        "wall_s": wall_s,
        "tune_seeds": r.tune_seeds,
        "heldout_seeds": r.heldout_seeds,
        "duration_s": r.duration_s,
        "robust": r.robust,
        "stop_reason": r.stop_reason,
        "input": r.input,
    })
}

fn pct_change(before: f64, after: f64) -> String {
    if before.is_finite() && after.is_finite() && before != 0.0 {
        format!("{:+.1} %", 100.0 * (after - before) / before)
    } else {
        "n/a".into()
    }
}

fn fmt_num(v: f64, digits: usize) -> String {
    if v.is_finite() {
        format!("{v:.digits$}")
    } else {
        "n/a (diverged or not simulated)".into()
    }
}

fn gains_text(e: &Evaluation) -> String {
    e.gains
        .iter()
        .map(|(k, v)| match k.as_str() {
            "kp_v_per_m" => format!("Kp = {v:.1} V/m"),
            "ki_v_s_per_m" => format!("Ki = {v:.2} V·s/m"),
            "lead_s" => format!("lead = {:.1} ms", v * 1e3),
            "sky_v_s_per_m" => format!("Ksky = {v:.2} V·s/m"),
            other => format!("{other} = {v}"),
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// The `report.md` text.
pub fn report_md(r: &TuneResult, params: &Params, wall_s: f64) -> String {
    let unit = r.objective.unit();
    let mut s = String::new();
    let _ = writeln!(s, "# Controller tuning on the nonlinear twin\n");
    let _ = writeln!(
        s,
        "Structure **{}**, objective **{}** of the body ({unit}), {} tuning ride(s) (seeds {:?}) \
         and {} held-out ride(s) (seeds {:?}) of {:.0} s each ({}), metrics after the first \
         {:.0} s.{}\n",
        r.kind,
        r.objective.name(),
        r.tune_seeds.len(),
        r.tune_seeds,
        r.heldout_seeds.len(),
        r.heldout_seeds,
        r.duration_s,
        r.input,
        super::SETTLE_S,
        if r.robust {
            " Optimised for the worst case over the parameter spread (Cd ±10 %, τ ±3 ms, mass ±20 %)."
        } else {
            ""
        }
    );
    let _ = writeln!(
        s,
        "Plant: Cd = {:.4}, τ = {:.1} ms, mass = {:.1} kg.\n",
        params.plant.valve.cd,
        params.plant.valve.tau_s * 1e3,
        params.plant.body.mass_kg
    );
    let _ = writeln!(s, "## Result\n");
    let _ = writeln!(
        s,
        "| | gains | objective (tuning) | objective (held-out) | max abs u (mm) | contacts | GM (dB) | PM (deg) |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|");
    for (name, e, h) in [
        ("start (preset)", &r.baseline, &r.baseline_heldout),
        ("tuned", &r.tuned, &r.tuned_heldout),
    ] {
        let _ = writeln!(
            s,
            "| {name} | {} | {} | {} | {} | {} | {} | {} |",
            gains_text(e),
            fmt_num(e.objective, 4),
            fmt_num(h.objective, 4),
            fmt_num(e.max_abs_u_m.max(h.max_abs_u_m) * 1e3, 1),
            e.contacts + h.contacts,
            fmt_num(e.gain_margin_db, 1),
            fmt_num(e.phase_margin_deg, 1),
        );
    }
    let _ = writeln!(
        s,
        "\nChange of the objective: {} on the tuning rides, **{} on the held-out rides**.",
        pct_change(r.baseline.objective, r.tuned.objective),
        pct_change(r.baseline_heldout.objective, r.tuned_heldout.objective)
    );
    if !r.baseline.feasible {
        let _ = writeln!(
            s,
            "\nThe starting gains do not meet every constraint (max |u| ≤ {:.0} mm, no contact, \
             GM ≥ {:.0} dB, PM ≥ {:.0}°); the tuned gains do{}.",
            super::MAX_ABS_U_M * 1e3,
            super::MIN_GAIN_MARGIN_DB,
            super::MIN_PHASE_MARGIN_DEG,
            if r.tuned.feasible { "" } else { " not either" }
        );
    }
    if !r.tuned_heldout.feasible && r.tuned.feasible {
        let _ = writeln!(
            s,
            "\n**On the held-out rides the tuned gains break the stroke constraint** (max |u| = \
             {:.1} mm, {} contact(s)): the tuning rides did not cover the worst of the band.",
            r.tuned_heldout.max_abs_u_m * 1e3,
            r.tuned_heldout.contacts
        );
    }
    let _ = writeln!(
        s,
        "\nSearch: Nelder–Mead (argmin), {} evaluations, stopped: {}. Wall time {:.1} s.\n",
        r.evaluations, r.stop_reason, wall_s
    );
    let _ = writeln!(s, "## Robustness of the tuned gains\n");
    let _ = writeln!(
        s,
        "The tuned gains on the tuning rides across Cd ±10 %, τ ±3 ms and mass ±20 %.\n"
    );
    let _ = writeln!(
        s,
        "| Cd | τ (ms) | mass (kg) | objective ({unit}) | max abs u (mm) | contacts |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|");
    for row in &r.robustness {
        let _ = writeln!(
            s,
            "| {:.4} | {:.1} | {:.1} | {} | {} | {} |",
            row.cd,
            row.tau_s * 1e3,
            row.mass_kg,
            fmt_num(row.objective, 4),
            fmt_num(row.max_abs_u_m * 1e3, 1),
            row.contacts
        );
    }
    let worst = r
        .robustness
        .iter()
        .map(|row| row.objective)
        .fold(f64::NEG_INFINITY, f64::max);
    let _ = writeln!(
        s,
        "\nWorst case over the spread: {} {unit}; contacts over the spread: {}.\n",
        fmt_num(worst, 4),
        r.robustness.iter().map(|row| row.contacts).sum::<usize>()
    );
    let _ = writeln!(s, "## Pareto front (feasible evaluations)\n");
    let _ = writeln!(s, "| objective ({unit}) | max abs u (mm) | gains |");
    let _ = writeln!(s, "|---|---|---|");
    for e in &r.pareto {
        let _ = writeln!(
            s,
            "| {} | {} | {} |",
            fmt_num(e.objective, 4),
            fmt_num(e.max_abs_u_m * 1e3, 1),
            gains_text(e)
        );
    }
    let _ = writeln!(
        s,
        "\nFiles: `tuned.toml` (a preset with the tuned controller), `report.json`, \
         `pareto.png/.svg`, `transmissibility.png/.svg`."
    );
    s
}

/// Writes `tuned.toml`, `report.json`, `report.md` and the plots into `dir` (which must exist).
pub fn write_outputs(
    r: &TuneResult,
    params: &Params,
    dir: &Path,
    wall_s: f64,
) -> Result<Vec<PathBuf>, TuneReportError> {
    let io = |path: PathBuf| move |source| TuneReportError::Io { path, source };
    let mut written = Vec::new();
    let mut tuned = *params;
    tuned.controller = r.tuned.controller;
    let preset = Preset {
        meta: PresetMeta {
            name: format!("tuned-{}", r.kind),
            description: format!(
                "{} controller tuned on the twin for {}: {} -> {} on the tuning rides, {} -> {} held out",
                r.kind,
                r.objective.name(),
                fmt_num(r.baseline.objective, 4),
                fmt_num(r.tuned.objective, 4),
                fmt_num(r.baseline_heldout.objective, 4),
                fmt_num(r.tuned_heldout.objective, 4),
            ),
            ..PresetMeta::default()
        },
        params: tuned,
    };
    let path = dir.join("tuned.toml");
    preset.save(&path)?;
    written.push(path);
    let path = dir.join("report.json");
    let text = serde_json::to_string_pretty(&report_json(r, wall_s)).unwrap_or_default();
    write_atomic(&path, text.as_bytes()).map_err(io(path.clone()))?;
    written.push(path);
    let path = dir.join("report.md");
    write_atomic(&path, report_md(r, params, wall_s).as_bytes()).map_err(io(path.clone()))?;
    written.push(path);
    // Pareto front: every feasible evaluation, the front, start and tuned.
    let mut p = Panel::new("", "max |u| on the tuning rides [mm]", r.objective.unit());
    let front_x: Vec<f64> = r.pareto.iter().map(|e| e.max_abs_u_m * 1e3).collect();
    let front_y: Vec<f64> = r.pareto.iter().map(|e| e.objective).collect();
    p.series
        .push(Series::line("Pareto front", front_x, front_y, palette(0)));
    for (label, e, c) in [("start", &r.baseline, 3), ("tuned", &r.tuned, 1)] {
        p.series.push(Series::markers(
            label,
            vec![e.max_abs_u_m * 1e3],
            vec![e.objective],
            palette(c),
        ));
    }
    let fig = Figure::new(
        format!(
            "{} of the body against stroke use ({})",
            r.objective.name(),
            r.kind
        ),
        vec![p],
    );
    let (png, svg) = save_figure(&fig, &dir.join("pareto"))?;
    written.extend([png, svg]);
    // Transmissibility of the twin's linearised loop, start and tuned.
    let freqs = fr::log_space(0.3, 30.0, 240);
    let lin = fr::linearise_twin(params);
    let mut t = Panel::new("", "frequency [Hz]", "|T| = |ÿ/ẍ| [-]");
    t.x_scale = Scale::Log10;
    t.y_scale = Scale::Log10;
    for (label, c, color) in [
        ("start", params.controller, 3),
        ("tuned", r.tuned.controller, 1),
    ] {
        let mut q = *params;
        q.controller = c;
        let law = ControlLaw::new(&q);
        let y = freqs
            .iter()
            .map(|&f| lin.transmissibility(&law, f).norm())
            .collect();
        t.series
            .push(Series::line(label, freqs.clone(), y, palette(color)));
    }
    let fig = Figure::new(
        "Transmissibility of the twin (linearised), before and after",
        vec![t],
    );
    let (png, svg) = save_figure(&fig, &dir.join("transmissibility"))?;
    written.extend([png, svg]);
    Ok(written)
}
