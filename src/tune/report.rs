//! Writers of a tuning run: `tuned.toml`, `report.json` (SI except the keys that name their
//! display unit, as the interface asks: `max_abs_u_mm`), `report.md` and the plots (Pareto
//! front, transmissibility before and after). Every file is written atomically.

use super::{Evaluation, TuneResult};
use crate::analysis::frequency_response as fr;
use crate::control::ControlLaw;
use crate::output::{OutputError, json_number};
use crate::params::Params;
use crate::plot::{Figure, Panel, Scale, Series, palette, save_figure};
use crate::preset::{Preset, PresetMeta, write_atomic};
use serde_json::{Value, json};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Why the outputs could not be written (the error of every output writer,
/// [`crate::output::OutputError`]).
pub type TuneReportError = OutputError;

fn gains_json(e: &Evaluation) -> Value {
    let mut m = serde_json::Map::new();
    for (k, v) in &e.gains {
        m.insert(k.clone(), json_number(*v));
    }
    Value::Object(m)
}

fn eval_json(e: &Evaluation) -> Value {
    json!({
        "gains": gains_json(e),
        "objective": json_number(e.objective),
        "max_abs_u_mm": json_number(e.max_abs_u_m * 1e3),
        "contacts": e.contacts,
        "gain_margin_db": json_number(e.gain_margin_db),
        "phase_margin_deg": json_number(e.phase_margin_deg),
        "delay_margin_s": json_number(e.delay_margin_s),
        "unstable_spread_points": e.unstable_points,
        "worst_growth_rate_per_s": json_number(e.worst_growth_rate_per_s),
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
            "baseline": json_number(r.baseline.objective),
            "tuned": json_number(r.tuned.objective),
            "baseline_heldout": json_number(r.baseline_heldout.objective),
            "tuned_heldout": json_number(r.tuned_heldout.objective),
        },
        "constraints": {
            "gain_margin_db": json_number(r.tuned.gain_margin_db),
            "phase_margin_deg": json_number(r.tuned.phase_margin_deg),
            "delay_margin_s": json_number(r.tuned.delay_margin_s),
            "unstable_spread_points": r.tuned.unstable_points,
            "max_abs_u_mm": json_number(r.tuned.max_abs_u_m * 1e3),
            "contacts": r.tuned.contacts,
            "max_abs_u_mm_heldout": json_number(r.tuned_heldout.max_abs_u_m * 1e3),
            "contacts_heldout": r.tuned_heldout.contacts,
            "limits": {"gain_margin_db": super::MIN_GAIN_MARGIN_DB,
                       "phase_margin_deg": super::MIN_PHASE_MARGIN_DEG,
                       "delay_margin_s": super::MIN_DELAY_MARGIN_S,
                       "settle_rms_m_s2": crate::analysis::settle::SETTLE_RMS_M_S2,
                       "max_abs_u_mm": super::MAX_ABS_U_M * 1e3},
        },
        "baseline": eval_json(&r.baseline),
        "tuned": eval_json(&r.tuned),
        "baseline_heldout": eval_json(&r.baseline_heldout),
        "tuned_heldout": eval_json(&r.tuned_heldout),
        "robustness": r.robustness.iter().map(|row| json!({
            "cd": row.cd, "tau_s": row.tau_s, "mass_kg": row.mass_kg,
            "objective": json_number(row.objective), "contacts": row.contacts,
            "max_abs_u_mm": json_number(row.max_abs_u_m * 1e3),
            "stable": row.stable,
            "growth_rate_per_s": json_number(row.growth_rate_per_s),
            "delay_margin_s": json_number(row.delay_margin_s),
            "settle": row.settle.map(|st| json!({
                "rms_last_2s_m_s2": json_number(st.rms_last_2s_m_s2),
                "growth_ratio": json_number(st.growth_ratio),
                "freq_hz": json_number(st.freq_hz),
                "settled": st.settled(),
            })),
            "passes": row.passes(super::tau_max_s(&r.robustness)),
        })).collect::<Vec<_>>(),
        "claim_holds": r.failures.is_empty(),
        "failures": r.failures,
        "pareto": r.pareto.iter().map(|e| json!({
            "objective": json_number(e.objective),
            "max_abs_u_mm": json_number(e.max_abs_u_m * 1e3),
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
    crate::format::fixed_or(v, digits, "n/a (diverged or not simulated)")
}

/// A margin for people: the number, or in words when there is no crossing (infinite).
fn margin_text(v: f64, digits: usize, none: &str) -> String {
    if v.is_infinite() && v > 0.0 {
        format!("∞ ({none})")
    } else {
        fmt_num(v, digits)
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
        "| | gains | objective (tuning) | objective (held-out) | max abs u (mm) | contacts | GM (dB) | PM (deg) | delay margin (ms) | unstable spread points |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|---|");
    for (name, e, h) in [
        ("start (preset)", &r.baseline, &r.baseline_heldout),
        ("tuned", &r.tuned, &r.tuned_heldout),
    ] {
        let _ = writeln!(
            s,
            "| {name} | {} | {} | {} | {} | {} | {} | {} | {} | {} of 27 |",
            gains_text(e),
            fmt_num(e.objective, 4),
            fmt_num(h.objective, 4),
            fmt_num(e.max_abs_u_m.max(h.max_abs_u_m) * 1e3, 1),
            e.contacts + h.contacts,
            margin_text(e.gain_margin_db, 1, "no −180° crossing"),
            margin_text(e.phase_margin_deg, 0, "no unity crossing"),
            margin_text(e.delay_margin_s * 1e3, 2, "no unity crossing"),
            e.unstable_points,
        );
    }
    if r.failures.is_empty() {
        let _ = writeln!(
            s,
            "\n**The claim holds at every point of the spread**: the loop linearised at rest is \
             stable (closed-loop eigenvalues with the delay) and the nonlinear twin settles after \
             a bump at all 27 points."
        );
    } else {
        let _ = writeln!(
            s,
            "\n**The claim fails — no tuned preset is written.** Why:\n"
        );
        for f in &r.failures {
            let _ = writeln!(s, "- {f}");
        }
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
        "The tuned gains across Cd ±10 %, τ ±3 ms and mass ±20 %: the objective on the tuning \
         rides; the loop linearised at rest (closed-loop eigenvalues with the delay: the growth \
         rate of the rightmost mode, negative when every mode decays; the smallest delay margin \
         over every crossover); and the nonlinear twin left at rest after a 30 mm cycloidal \
         bump for {:.0} s (RMS of ÿ over the last 2 s, settled below {} m/s² and not growing).\n",
        crate::analysis::settle::SETTLE_RUN_S,
        crate::analysis::settle::SETTLE_RMS_M_S2,
    );
    let _ = writeln!(
        s,
        "| Cd | τ (ms) | mass (kg) | objective ({unit}) | max abs u (mm) | contacts | stable | growth rate (1/s) | delay margin (ms) | settle ÿ RMS (m/s²) | settled |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|---|---|");
    for row in &r.robustness {
        let (rms, settled) = row.settle.map_or(("diverged".to_string(), "no"), |st| {
            (
                format!("{:.2e}", st.rms_last_2s_m_s2),
                if st.settled() { "yes" } else { "**no**" },
            )
        });
        let _ = writeln!(
            s,
            "| {:.4} | {:.1} | {:.1} | {} | {} | {} | {} | {} | {} | {rms} | {settled} |",
            row.cd,
            row.tau_s * 1e3,
            row.mass_kg,
            fmt_num(row.objective, 4),
            fmt_num(row.max_abs_u_m * 1e3, 1),
            row.contacts,
            if row.stable { "yes" } else { "**no**" },
            fmt_num(row.growth_rate_per_s, 3),
            margin_text(row.delay_margin_s * 1e3, 2, "no unity crossing"),
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
        "\nFiles: {}`report.json`, `pareto.png/.svg`, `transmissibility.png/.svg`.",
        if r.failures.is_empty() {
            "`tuned.toml` (a preset with the tuned controller), "
        } else {
            ""
        }
    );
    s
}

/// What a tuned preset's header states: what was tuned, the held-out objective, and what was
/// checked — the spread, the worst margins over every crossing, the worst settle.
pub fn preset_description(r: &TuneResult) -> String {
    let worst_settle = r
        .robustness
        .iter()
        .filter_map(|row| row.settle.map(|s| s.rms_last_2s_m_s2))
        .fold(0.0, f64::max);
    let worst_growth = r
        .robustness
        .iter()
        .map(|row| row.growth_rate_per_s)
        .fold(f64::NEG_INFINITY, f64::max);
    let worst_dm = r
        .robustness
        .iter()
        .map(|row| row.delay_margin_s)
        .fold(f64::INFINITY, f64::min);
    format!(
        "{} controller tuned on the twin (`seat-twin tune --controller {}{}`) for {}: {} -> {} \
         on {} held-out ride(s) ({}). Checked over the spread Cd ±10 %, τ ±3 ms, mass ±20 % \
         (27 points): stable at rest at every point (rightmost closed-loop mode {} 1/s at \
         worst) and for every τ up to the spread's top (smallest delay margin {} ms), the twin \
         settles after a bump at every point (ÿ RMS \
         over the last 2 s ≤ {:.1e} m/s²); nominal GM {} dB, PM {}°, delay margin {} ms, \
         max |u| {} mm, no end-stop contact",
        r.kind,
        r.kind,
        if r.robust { " --robust" } else { "" },
        r.objective.name(),
        fmt_num(r.baseline_heldout.objective, 4),
        fmt_num(r.tuned_heldout.objective, 4),
        r.heldout_seeds.len(),
        r.input,
        fmt_num(worst_growth, 3),
        fmt_num(worst_dm * 1e3, 2),
        worst_settle,
        margin_text(r.tuned.gain_margin_db, 1, "no −180° crossing"),
        margin_text(r.tuned.phase_margin_deg, 0, "no unity crossing"),
        margin_text(r.tuned.delay_margin_s * 1e3, 2, "no unity crossing"),
        fmt_num(
            r.tuned.max_abs_u_m.max(r.tuned_heldout.max_abs_u_m) * 1e3,
            1
        ),
    )
}

/// Writes `report.json`, `report.md`, the plots and — only when the claim holds at every
/// point of the spread ([`TuneResult::failures`] empty) — `tuned.toml` into `dir` (which must
/// exist).
pub fn write_outputs(
    r: &TuneResult,
    params: &Params,
    dir: &Path,
    wall_s: f64,
) -> Result<Vec<PathBuf>, TuneReportError> {
    let mut written = Vec::new();
    if r.failures.is_empty() {
        let mut tuned = *params;
        tuned.controller = r.tuned.controller;
        let preset = Preset {
            meta: PresetMeta {
                name: format!("tuned-{}", r.kind),
                description: preset_description(r),
                ..PresetMeta::default()
            },
            params: tuned,
            per_record: Default::default(),
        };
        let path = dir.join("tuned.toml");
        preset.save(&path)?;
        written.push(path);
    }
    let path = dir.join("report.json");
    let text = serde_json::to_string_pretty(&report_json(r, wall_s)).unwrap_or_default();
    write_atomic(&path, text.as_bytes()).map_err(OutputError::io(&path))?;
    written.push(path);
    let path = dir.join("report.md");
    write_atomic(&path, report_md(r, params, wall_s).as_bytes()).map_err(OutputError::io(&path))?;
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
