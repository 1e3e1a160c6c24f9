//! Writers of a calibration: `report.json`, `report.md`, `calibrated.toml` and the plots.
//!
//! This is the edge where SI values become display units (mm/s, ms, bar) in the Markdown and
//! the plots; `report.json` stays SI. Every file is written atomically. The figures are drawn
//! in [`super::figures`].

pub use super::figures::write_plots;
use super::units::{display_unit, format_parameter, format_value};
use super::{CalibrationReport, ErrorSummary, Verdict};
use crate::output::{OutputError, json_number};
use crate::preset::{Preset, PresetMeta, write_atomic};
use serde_json::{Value, json};
use std::fmt::Write as _;
use std::path::Path;

mod proposed;
use proposed::proposed_markdown;
pub use proposed::proposed_twin_effects;

/// Why the report could not be written (the error of every output writer,
/// [`crate::output::OutputError`]).
pub type ReportError = OutputError;

fn error_json(e: &ErrorSummary) -> Value {
    json!({
        "metric": e.metric,
        "value": e.value,
        "channels": e.channels,
        "files": e.files.iter().map(|(n, c)| json!({"file": n, "errors": c})).collect::<Vec<_>>(),
    })
}

/// One stage of the raw error measure: per record and channel, the noise floor and every
/// band; the bands above the limit; the worst.
fn raw_error_json(e: &super::raw_error::RawErrorReport) -> Value {
    json!({
        "at_floor": e.at_floor(),
        "summary": e.summary(),
        "worst": e.worst,
        "above": e.above,
        "ringing": e.ringing,
        "records": e.records,
    })
}

/// The `report.json` document (SI). Non-finite numbers become `null` (serde_json's rule), so
/// the document never holds NaN.
pub fn report_json(r: &CalibrationReport) -> Value {
    let mut calibrated = serde_json::Map::new();
    let mut unc = serde_json::Map::new();
    for v in &r.calibrated {
        calibrated.insert(v.name.clone(), json_number(v.value));
        unc.insert(v.name.clone(), json_number(v.std));
    }
    let first_round: Vec<Value> = r
        .candidates
        .iter()
        .filter(|c| c.round == 1)
        .map(|c| {
            json!({"name": c.effect.name(), "score": c.score,
                   "relative_gain": c.relative_gain, "params": c.params})
        })
        .collect();
    json!({
        "verdict": r.verdict.name(),
        "missing": r.missing,
        "effects": r.effects.iter().map(effect_json).collect::<Vec<_>>(),
        "candidates": first_round,
        "candidate_rounds": r.candidates.iter().map(|c| json!({
            "round": c.round, "name": c.effect.name(), "score": c.score,
            "relative_gain": c.relative_gain, "params": c.params})).collect::<Vec<_>>(),
        "score": "ΔBIC = n_eff·ln(RSS_candidate/RSS_current) + Δk·ln(n_eff) against the model of that round, on the fit records; negative is better",
        "calibrated_parameters": calibrated,
        "proposed": r.proposed.iter().map(|t| json!({
            "name": t.name,
            "description": t.description,
            "params": t.params,
            "uncertainties": t.uncertainties.iter()
                .map(|(k, v)| (k.clone(), json_number(*v))).collect::<serde_json::Map<_, _>>(),
            "evidence": t.evidence,
            "per_record": t.per_record,
            "uncertainty_scale": t.uncertainty_scale,
        })).collect::<Vec<_>>(),
        "proposed_explains": r.raw_error_proposed.as_ref().map(|e| e.at_floor()),
        "proposed_calibrated_parameters": r.proposed_calibrated.iter()
            .map(|v| (v.name.clone(), json!({"value": json_number(v.value), "uncertainty": json_number(v.std)})))
            .collect::<serde_json::Map<_, _>>(),
        "proposed_candidates": r.proposed_candidates,
        "proposed_leaves_out": r.proposed_leaves_out,
        "proposed_adds": r.proposed_adds.iter().map(effect_json).collect::<Vec<_>>(),
        "proposed_twin_effects": r.raw_error_proposed.as_ref().map(|_| proposed_twin_effects(r)),
        "drifts": r.drifts,
        "sensors": r.sensors,
        "calibrated_uncertainties": unc,
        "mass_fitted": r.mass_fitted,
        "paper_baseline": r.baseline,
        "error_nominal": error_json(&r.error_nominal),
        "error_paper_baseline": r.error_baseline.as_ref().map(error_json),
        "error_before": error_json(&r.error_before),
        "error_after": error_json(&r.error_after),
        "error_training": r.error_training,
        "error_validation": r.error_validation.as_ref().map(|v| json!({
            "before": v.before,
            "after": v.after,
            "metric": v.metric,
            "channels": v.channels.iter()
                .map(|(k, [b, a])| (k.clone(), json!({"before": b, "after": a})))
                .collect::<serde_json::Map<_, _>>(),
            "files": v.files,
            "split": r.split.rule,
        })),
        "split": r.split,
        "raw_nrmse": r.raw_nrmse,
        "raw_error": {
            "definition": r.raw_error_after.definition,
            "limit": r.raw_error_after.limit,
            "verdict_uses": "after",
            "before": raw_error_json(&r.raw_error_before),
            "after": raw_error_json(&r.raw_error_after),
            "proposed": r.raw_error_proposed.as_ref().map(raw_error_json),
        },
        "residual_left": r.residual_left,
        "diagnostics_before": r.diagnostics_before,
        "diagnostics_after": r.diagnostics_after,
        "n_residuals": r.n,
        "n_effective": r.n_eff,
        "replays": r.evaluations,
        "files": r.files,
        "notes": r.notes,
    })
}

/// The calibrated preset.
pub fn calibrated_preset(r: &CalibrationReport) -> Preset {
    let effects: Vec<&str> = r.effects.iter().map(|e| e.effect.name()).collect();
    Preset {
        meta: PresetMeta {
            name: "calibrated".into(),
            description: format!(
                "Calibrated by `seat-twin calibrate` on {} record(s); verdict {}; effects: {}",
                r.files.len(),
                r.verdict.name(),
                if effects.is_empty() {
                    "none".to_string()
                } else {
                    effects.join(", ")
                }
            ),
            ..PresetMeta::default()
        },
        params: r.params,
        // A drift of Cd: each record's own value, which `seat-twin replay` applies.
        per_record: crate::preset::PerRecord {
            cd: r
                .drifts
                .iter()
                .find(|d| d.parameter == super::fit::Knob::Cd.name())
                .map(|d| d.per_record.clone())
                .unwrap_or_default(),
        },
    }
}

/// A number with `decimals` decimals, or `—` when it is not finite.
fn num(v: f64, decimals: usize) -> String {
    crate::format::fixed_or(v, decimals, "—")
}

fn channel_list(m: &std::collections::BTreeMap<String, f64>) -> String {
    let order = ["u", "ydd", "p1", "p2"];
    let mut parts = Vec::new();
    for c in order {
        if let Some(v) = m.get(c) {
            parts.push(format!("{c} {}", num(*v, 3)));
        }
    }
    parts.join(", ")
}

/// The verdict's measure in words and as a table: per record and raw channel, the worst band's
/// ratio to the noise floor before and after, with its band and time window.
fn raw_error_markdown(s: &mut String, r: &CalibrationReport) {
    use super::raw_error::band_text;
    let (b, a) = (&r.raw_error_before, &r.raw_error_after);
    let _ = writeln!(
        s,
        "## Raw error against the noise floor (the verdict's measure)\n\n{}.\n\nDefinition: \
         {}. At the floor: every ratio ≤ {:.1}.\n",
        a.summary(),
        a.definition,
        a.limit
    );
    let _ = writeln!(
        s,
        "| record | channel | noise σ | worst ratio before | worst ratio after | its band | its window [s] | above 25 Hz sample by sample, after (not in the verdict) |\n|---|---|---|---|---|---|---|---|"
    );
    for (rb, ra) in b.records.iter().zip(&a.records) {
        for (cb, ca) in rb.channels.iter().zip(&ra.channels) {
            let (Some(wb), Some(wa)) = (cb.worst(), ca.worst()) else {
                continue;
            };
            let _ = writeln!(
                s,
                "| {} | {} | {:.3e} {} | {} | {} | {} | {}–{} | {} |",
                ra.file,
                ca.channel,
                ca.noise.rms,
                ca.unit,
                num(wb.ratio, 2),
                num(wa.ratio, 2),
                band_text(wa.band_hz),
                num(wa.window_s[0], 1),
                num(wa.window_s[1], 1),
                ca.bands
                    .iter()
                    .find_map(|b| b.residual_ratio)
                    .map_or("—".into(), |v| num(v, 2))
            );
        }
    }
    let _ = writeln!(s);
}

/// An added effect in report.json.
fn effect_json(e: &super::AddedEffect) -> serde_json::Value {
    json!({
        "name": e.effect.name(),
        "params": e.params,
        "uncertainties": e.uncertainties.iter()
            .map(|(k, v)| (k.clone(), json_number(*v))).collect::<serde_json::Map<_, _>>(),
        "evidence": e.evidence,
    })
}

/// The Markdown report.
pub fn report_markdown(r: &CalibrationReport, elapsed_s: Option<f64>) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "# seat-twin calibration\n");
    let _ = writeln!(
        s,
        "**Verdict: `{}`** — {}\n",
        r.verdict.name(),
        match r.verdict {
            Verdict::Explained =>
                "with the added effect(s) below, every raw channel of every record is at its noise floor in every band (see the table below).",
            Verdict::NoMissingEffect =>
                "the twin with re-fitted declared parameters has every raw channel of every record at its noise floor in every band; nothing was added.",
            Verdict::Unexplained => match &r.raw_error_proposed {
                Some(p) if p.at_floor() =>
                    "a residual above the sensor noise remains that the library does not explain; the terms proposed beyond the library (below) explain it: with them every raw channel is at its noise floor.",
                Some(_) =>
                    "a residual above the sensor noise remains; the effects below (if any) and the terms proposed beyond the library reduce it, but what is left is explained by neither (see \"What is left\").",
                None =>
                    "a residual above the sensor noise remains; the effects below (if any) helped, but what is left is not in the library (see \"What is left\").",
            },
            Verdict::InsufficientData =>
                "the records cannot determine the twin's parameters; nothing was calibrated and no calibrated.toml was written.",
        }
    );
    proposed_markdown(&mut s, r);
    raw_error_markdown(&mut s, r);
    if !r.missing.is_empty() {
        let _ = writeln!(s, "## What is missing\n");
        for m in &r.missing {
            let _ = writeln!(s, "- {m}");
        }
        let _ = writeln!(s);
    }
    let _ = writeln!(s, "Records: {}.\n", r.files.join(", "));
    if !r.split.rule.is_empty() {
        let _ = writeln!(
            s,
            "Fit/validation split: {}. Fitted: {}. Held out: {}.\n",
            r.split.rule,
            r.split.fit.join(", "),
            r.split.validation.join(", ")
        );
    }
    let _ = writeln!(s, "## Error metric\n\n{}\n", super::METRIC);
    let _ = writeln!(
        s,
        "| stage (all records) | weighted RMS | u̇ RMS [mm/s] | ÿ RMS [m/s²] | u RMS [mm] |\n|---|---|---|---|---|"
    );
    let row = |s: &mut String, name: &str, e: &ErrorSummary| {
        let c = |k: &str| e.channels.get(k).copied().unwrap_or(f64::NAN);
        let _ = writeln!(
            s,
            "| {name} | {} | {} | {} | {} |",
            num(e.value, 3),
            num(1e3 * c("du"), 3),
            num(c("ydd"), 4),
            num(1e3 * c("u"), 3)
        );
    };
    row(&mut s, "nominal (preset as given)", &r.error_nominal);
    if let Some(e) = &r.error_baseline {
        row(&mut s, "paper's section-4 method", e);
    }
    if r.verdict != Verdict::InsufficientData {
        row(
            &mut s,
            "before (declared parameters re-fitted)",
            &r.error_before,
        );
        row(&mut s, "after (with added effects)", &r.error_after);
    }
    if r.error_training.is_some() || r.error_validation.is_some() {
        let _ = writeln!(s, "\n### Fit and validation\n");
        let _ = writeln!(
            s,
            "| records | weighted RMS before | after | per channel (before → after) |\n|---|---|---|---|"
        );
        for (name, e) in [
            ("fitted", &r.error_training),
            ("held out (validation)", &r.error_validation),
        ] {
            if let Some(e) = e {
                let ch: Vec<String> = e
                    .channels
                    .iter()
                    .map(|(k, [b, a])| format!("{k} {} → {}", num(*b, 3), num(*a, 3)))
                    .collect();
                let _ = writeln!(
                    s,
                    "| {name} | {} | {} | {} |",
                    num(e.before, 3),
                    num(e.after, 3),
                    ch.join(", ")
                );
            }
        }
    }
    let _ = writeln!(
        s,
        "\n### Raw signals\n\nNRMSE of the raw channels: {}.\n",
        super::RAW_NRMSE
    );
    let _ = writeln!(
        s,
        "| stage | all records | held-out records |\n|---|---|---|"
    );
    for (name, all) in [
        ("nominal", &r.raw_nrmse.nominal),
        ("before", &r.raw_nrmse.before),
        ("after", &r.raw_nrmse.after),
    ] {
        let val = r
            .raw_nrmse
            .validation
            .get(name)
            .map(channel_list)
            .unwrap_or_else(|| "—".into());
        let _ = writeln!(s, "| {name} | {} | {val} |", channel_list(all));
    }
    if r.verdict == Verdict::InsufficientData {
        if !r.notes.is_empty() {
            let _ = writeln!(s, "\n## Notes\n");
            for n in &r.notes {
                let _ = writeln!(s, "- {n}");
            }
        }
        return s;
    }
    let _ = writeln!(s, "\n## Declared parameters\n");
    let _ = writeln!(
        s,
        "| parameter | nominal | paper method | calibrated (± 1-σ) |\n|---|---|---|---|"
    );
    for v in &r.calibrated {
        let nominal = v.knob.value(&r.nominal);
        let paper = match (&r.baseline, v.knob) {
            (Some(b), super::Knob::Cd) => format_value(&v.name, b.cd),
            (Some(b), super::Knob::Tau) => format_value(&v.name, b.tau_s),
            _ => "—".into(),
        };
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} |",
            v.name,
            format_value(&v.name, nominal),
            paper,
            format_parameter(&v.name, v.value, v.std)
        );
    }
    let _ = writeln!(s, "\n## Sensors\n");
    if r.sensors.is_empty() {
        let _ = writeln!(
            s,
            "No sensor property estimated more than 3σ from exact (or no ÿ to tell them from the plant).\n"
        );
    }
    for e in &r.sensors {
        let text = match e.kind.as_str() {
            "lag" => format!(
                "the {} sensor lags: a first-order filter on its samples of time constant \
                 {:.2} ± {:.2} ms (it reads about half a sample less late than that)",
                e.channel,
                1e3 * e.value,
                1e3 * e.uncertainty
            ),
            "scale" => format!(
                "the {} sensor reads {:.2} ± {:.2} % {} (scale {:.4} ± {:.4})",
                e.channel,
                100.0 * (e.value - 1.0).abs(),
                100.0 * e.uncertainty,
                if e.value < 1.0 { "low" } else { "high" },
                e.value,
                e.uncertainty
            ),
            _ => format!(
                "the {} sensor has an offset of {:.4} ± {:.4} {}",
                e.channel,
                e.value,
                e.uncertainty,
                if e.channel == "ydd" { "m/s²" } else { "(SI)" }
            ),
        };
        let _ = writeln!(
            s,
            "- {text} (a property of the measurement, not of the plant; calibrated.toml carries it and replay applies it)"
        );
    }
    if !r.drifts.is_empty() {
        let _ = writeln!(s, "\n## Drifts\n");
        for d in &r.drifts {
            let _ = writeln!(
                s,
                "- {} (a parameter that changes during the campaign, as oil warming up does: \
                 not averaged away; calibrated.toml holds the value fitted on all records).",
                d.description
            );
        }
    }
    let _ = writeln!(s, "\n## Effects added\n");
    if r.effects.is_empty() {
        let _ = writeln!(s, "None.\n");
    }
    for e in &r.effects {
        let _ = writeln!(s, "### `{}`\n", e.effect.name());
        for (k, v) in &e.params {
            let u = e.uncertainties.get(k).copied().unwrap_or(f64::NAN);
            let _ = writeln!(s, "- {}", format_parameter(k, *v, u));
        }
        let _ = writeln!(s, "\nEvidence: {}\n", e.evidence);
    }
    if let Some(left) = &r.residual_left {
        let _ = writeln!(s, "## What is left\n\n{}\n", left.summary);
        let _ = writeln!(s, "| band [Hz] | share of the residual power |\n|---|---|");
        for (b, share) in &left.bands {
            let _ = writeln!(
                s,
                "| {}–{} | {} % |",
                num(b[0], 1),
                num(b[1], 1),
                num(100.0 * share, 1)
            );
        }
        let _ = writeln!(s);
    }
    let _ = writeln!(
        s,
        "## Candidates\n\nScore = ΔBIC against the model of the round, on the fit records \
         (n = {}, n_eff = {:.0}); an effect is added when ΔBIC < 0, it removes enough of the \
         residual and it lowers the validation error on the held-out records. While the raw \
         error is above its limit, one under those bars is also added when it takes a quarter \
         off the raw error's worst band with its size determined (its evidence and the notes \
         say so).\n",
        r.n, r.n_eff
    );
    let _ = writeln!(
        s,
        "| round | effect | ΔBIC | residual removed | parameters |\n|---|---|---|---|---|"
    );
    for c in &r.candidates {
        let p: Vec<String> = c
            .params
            .iter()
            .map(|(k, v)| format!("{} = {}", display_unit(k).0, format_value(k, *v)))
            .collect();
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} % | {} |",
            c.round,
            c.effect.name(),
            num(c.score, 1),
            num(100.0 * c.relative_gain, 1),
            p.join(", ")
        );
    }
    let _ = writeln!(s, "\n## Residual diagnostics\n");
    let _ = writeln!(s, "| | before | after |\n|---|---|---|");
    let (wb, wa) = (
        &r.diagnostics_before.whiteness,
        &r.diagnostics_after.whiteness,
    );
    let _ = writeln!(
        s,
        "| lag-1 autocorrelation | {} | {} |",
        num(wb.lag1, 3),
        num(wa.lag1, 3)
    );
    let _ = writeln!(
        s,
        "| share of lags 1–{} outside the white-noise band | {} | {} |",
        wb.max_lag,
        num(wb.share_outside, 2),
        num(wa.share_outside, 2)
    );
    let _ = writeln!(
        s,
        "| ÿ residual power above 30 Hz | {} | {} |",
        num(r.diagnostics_before.high_frequency_share, 3),
        num(r.diagnostics_after.high_frequency_share, 3)
    );
    let signed = |v: f64| {
        if v.is_finite() {
            format!("{v:+.3}")
        } else {
            "—".into()
        }
    };
    for (b, a) in r
        .diagnostics_before
        .correlations
        .iter()
        .zip(&r.diagnostics_after.correlations)
    {
        let _ = writeln!(
            s,
            "| corr(u̇ residual, `{}`) → {} | {} | {} |",
            b.feature,
            b.effect,
            signed(b.velocity),
            signed(a.velocity)
        );
        let _ = writeln!(
            s,
            "| corr(ÿ residual, `{}`) → {} | {} | {} |",
            b.feature,
            b.effect,
            signed(b.acceleration),
            signed(a.acceleration)
        );
    }
    let _ = writeln!(s, "\n## Per file (weighted RMS; u̇ NRMSE before → after)\n");
    for ((n, b), (_, a)) in r.error_before.files.iter().zip(&r.error_after.files) {
        let _ = writeln!(
            s,
            "- {n}: weighted {} → {}; u̇ {} % → {} %{}",
            num(b.weighted, 3),
            num(a.weighted, 3),
            num(100.0 * b.du_nrmse, 2),
            num(100.0 * a.du_nrmse, 2),
            match (b.ydd_nrmse, a.ydd_nrmse) {
                (Some(x), Some(y)) =>
                    format!(" (ÿ {} % → {} %)", num(100.0 * x, 2), num(100.0 * y, 2)),
                _ => String::new(),
            }
        );
    }
    if !r.notes.is_empty() {
        let _ = writeln!(s, "\n## Notes\n");
        for n in &r.notes {
            let _ = writeln!(s, "- {n}");
        }
    }
    let _ = writeln!(s, "\nReplays of the whole campaign: {}.", r.evaluations);
    if let Some(t) = elapsed_s {
        let _ = writeln!(s, "Wall time: {t:.1} s.");
    }
    let _ = writeln!(
        s,
        "\nPlots: `measured_vs_twin`, `residual` (filtered), `raw_residual` (every raw channel, unfiltered), `residual_spectrum`, `signature_correlation` (PNG and SVG)."
    );
    s
}

/// Writes `report.json`, `report.md`, `calibrated.toml` and the plots into `dir` (created if
/// needed; with the verdict `insufficient_data`, only the two reports). Each file is written
/// atomically.
pub fn write_all(
    r: &CalibrationReport,
    dir: &Path,
    elapsed_s: Option<f64>,
) -> Result<(), ReportError> {
    let io = OutputError::io;
    std::fs::create_dir_all(dir).map_err(io(dir))?;
    // Data that cannot determine the twin give no calibrated preset and no plots.
    if r.verdict != Verdict::InsufficientData {
        write_plots(r, dir)?;
        calibrated_preset(r).save(&dir.join("calibrated.toml"))?;
    }
    let json = serde_json::to_string_pretty(&report_json(r)).unwrap_or_default();
    let p = dir.join("report.json");
    write_atomic(&p, json.as_bytes()).map_err(io(&p))?;
    let p = dir.join("report.md");
    write_atomic(&p, report_markdown(r, elapsed_s).as_bytes()).map_err(io(&p))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dataset::Record;
    use crate::identify::testdata::{true_params, twin_record};
    use crate::identify::{CalibrationOptions, Progress, Stage, calibrate_with};
    use crate::params::Params;
    use std::sync::atomic::AtomicBool;

    fn calibrated(records: &[Record]) -> CalibrationReport {
        let cancel = AtomicBool::new(false);
        calibrate_with(
            &Params::paper(),
            records,
            &CalibrationOptions::default(),
            &cancel,
            &|_: &Progress| {},
        )
        .unwrap()
    }

    /// Data that cannot be calibrated: NaN never reaches a report; JSON says null, Markdown —.
    #[test]
    fn insufficient_data_reports_null_and_dash_never_nan() {
        let mut rec = twin_record(&Params::paper(), 0.001, "two-rows.csv").unwrap();
        rec.v_in = None;
        let r = calibrated(&[rec]);
        assert_eq!(r.verdict, Verdict::InsufficientData);
        assert!(r.error_nominal.value.is_nan());
        let j = report_json(&r);
        assert!(j["error_nominal"]["value"].is_null());
        assert!(!j["missing"].as_array().unwrap().is_empty());
        let text = serde_json::to_string(&j).unwrap();
        assert!(!text.contains("NaN"), "{text}");
        let md = report_markdown(&r, None);
        assert!(!md.contains("NaN"), "{md}");
        assert!(md.contains("| nominal (preset as given) | — |"), "{md}");
        assert!(md.contains("no `v_in`"), "{md}");
        // Nothing calibrated: no calibrated.toml, only the two reports.
        let dir = tempfile::tempdir().unwrap();
        write_all(&r, dir.path(), None).unwrap();
        let mut names: Vec<String> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        assert_eq!(names, ["report.json", "report.md"]);
    }

    /// One cancel flag stops the run; the observer saw the stages in order up to there.
    #[test]
    fn cancel_stops_at_the_stage_it_is_set_in() {
        let rec = twin_record(&true_params(), 3.0, "a.csv").unwrap();
        let cancel = AtomicBool::new(false);
        let seen = std::sync::Mutex::new(Vec::new());
        let observer = |p: &Progress| {
            let mut s = seen.lock().unwrap();
            if s.last() != Some(&p.stage) {
                s.push(p.stage);
            }
            if p.stage == Stage::DeclaredFit {
                cancel.store(true, std::sync::atomic::Ordering::Relaxed);
            }
        };
        let r = calibrate_with(
            &Params::paper(),
            &[rec],
            &CalibrationOptions::default(),
            &cancel,
            &observer,
        );
        assert!(matches!(r, Err(crate::identify::IdentifyError::Cancelled)));
        assert_eq!(
            *seen.lock().unwrap(),
            [Stage::Nominal, Stage::PaperBaseline, Stage::DeclaredFit]
        );
    }
}
