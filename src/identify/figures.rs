//! The calibration's figures: measured against the twin before and after, the residuals,
//! their spectra and the signature correlations (PNG + SVG each, SI converted to display
//! units here).

use super::CalibrationReport;
use crate::output::OutputError;
use crate::plot::{Figure, Panel, Scale, Series, palette, save_figure};
use std::path::Path;

/// Sample indices that keep at most `max` points of `x`, and their step.
fn thin(x: &[f64], max: usize) -> (Vec<usize>, usize) {
    let step = x.len().div_ceil(max.max(1)).max(1);
    ((0..x.len()).step_by(step).collect(), step)
}

/// Records shown in the time plots: up to four, the longest first, then the largest residual.
fn shown(r: &CalibrationReport) -> Vec<usize> {
    let mut idx: Vec<usize> = (0..r.records.len()).collect();
    idx.sort_by(|&a, &b| {
        r.error_before.files[b]
            .1
            .du_nrmse
            .total_cmp(&r.error_before.files[a].1.du_nrmse)
    });
    idx.truncate(4);
    idx
}

/// One raw channel's panel: name, axis label, display scale, measured channel (if recorded),
/// twin before and after, and the estimated noise RMS [SI].
type RawPanel<'a> = (
    &'a str,
    &'a str,
    f64,
    Option<&'a Vec<f64>>,
    [&'a Vec<f64>; 2],
    f64,
);

/// The raw residual of every channel of the shown records (u in mm, ÿ in m/s², p in bar),
/// before and after, with the band ±3σ of the channel's estimated sensor noise.
fn raw_residual_panels(r: &CalibrationReport) -> Vec<Panel> {
    let (c_before, c_after) = (palette(1), palette(2));
    let mut panels = Vec::new();
    for i in shown(r) {
        let rec = &r.records[i];
        let (ix, _) = thin(&rec.t, 3000);
        let t: Vec<f64> = ix.iter().map(|&j| rec.t[j]).collect();
        let (b, a) = (&r.replays_before[i].sim, &r.replays_after[i].sim);
        let channels: [RawPanel<'_>; 4] = [
            (
                "u",
                "Δu [mm]",
                1e3,
                Some(&rec.u),
                [&b.u, &a.u],
                rec.floor_u.rms,
            ),
            (
                "ÿ",
                "Δÿ [m/s²]",
                1.0,
                rec.ydd.as_ref(),
                [&b.ydd, &a.ydd],
                rec.floor_ydd.rms,
            ),
            (
                "p1",
                "Δp1 [bar]",
                1e-5,
                rec.p_raw[0].as_ref(),
                [&b.p1, &a.p1],
                rec.floor_p[0].rms,
            ),
            (
                "p2",
                "Δp2 [bar]",
                1e-5,
                rec.p_raw[1].as_ref(),
                [&b.p2, &a.p2],
                rec.floor_p[1].rms,
            ),
        ];
        for (name, axis, k, meas, [tb, ta], sigma) in channels {
            let Some(meas) = meas else { continue };
            let res = |twin: &[f64]| -> Vec<f64> {
                ix.iter().map(|&j| k * (twin[j] - meas[j])).collect()
            };
            let mut p = Panel::new(
                format!("{}: raw {name} residual", rec.name),
                "time [s]",
                axis,
            )
            .with_series(vec![
                Series::line("before", t.clone(), res(tb), c_before),
                Series::line("after", t.clone(), res(ta), c_after),
            ]);
            p.hlines = vec![
                (3.0 * k * sigma, "+3σ noise".into()),
                (-3.0 * k * sigma, "−3σ noise".into()),
            ];
            panels.push(p);
        }
    }
    panels
}

/// Writes the five figures into `dir` (PNG + SVG each).
pub fn write_plots(r: &CalibrationReport, dir: &Path) -> Result<(), OutputError> {
    let (c_meas, c_before, c_after) = (palette(0), palette(1), palette(2));
    let mut fit_panels = Vec::new();
    let mut res_panels = Vec::new();
    for i in shown(r) {
        let rec = &r.records[i];
        let (ix, _) = thin(&rec.t, 3000);
        let pick = |v: &[f64], k: f64| ix.iter().map(|&j| k * v[j]).collect::<Vec<f64>>();
        let t = pick(&rec.t, 1.0);
        // A "before" and an "after" curve of the channel each replay gives.
        let before_after = |labels: [&str; 2], before: &[f64], after: &[f64], k: f64| {
            vec![
                Series::line(labels[0], t.clone(), pick(before, k), c_before),
                Series::line(labels[1], t.clone(), pick(after, k), c_after),
            ]
        };
        let (b, a) = (&r.replays_before[i], &r.replays_after[i]);
        let mut fit = vec![Series::line(
            "measured",
            t.clone(),
            pick(&rec.du_meas_f, 1e3),
            c_meas,
        )];
        fit.extend(before_after(
            ["twin before", "twin after"],
            &b.twin_du,
            &a.twin_du,
            1e3,
        ));
        fit_panels.push(
            Panel::new(
                format!("{}: relative velocity", rec.name),
                "time [s]",
                "u̇ [mm/s]",
            )
            .with_series(fit),
        );
        res_panels.push(
            Panel::new(
                format!("{}: velocity residual (twin − measured)", rec.name),
                "time [s]",
                "Δu̇ [mm/s]",
            )
            .with_series(before_after(
                ["before", "after"],
                &b.residual_du,
                &a.residual_du,
                1e3,
            )),
        );
        if let (Some(rb), Some(ra)) = (&b.residual_ydd, &a.residual_ydd) {
            res_panels.push(
                Panel::new(
                    format!("{}: acceleration residual", rec.name),
                    "time [s]",
                    "Δÿ [m/s²]",
                )
                .with_series(before_after(["before", "after"], rb, ra, 1.0)),
            );
        }
    }
    let h = |n: usize| (260 * n as u32).clamp(400, 2400);
    let mut fig = Figure::new(
        "Raw residual (twin − measured, unfiltered) of every channel, before and after",
        raw_residual_panels(r),
    );
    fig.height = h(fig.panels.len());
    save_figure(&fig, &dir.join("raw_residual"))?;
    let mut fig = Figure::new("Measured vs twin, before and after", fit_panels);
    fig.height = h(fig.panels.len());
    save_figure(&fig, &dir.join("measured_vs_twin"))?;
    let mut fig = Figure::new("Residual before and after", res_panels);
    fig.height = h(fig.panels.len());
    save_figure(&fig, &dir.join("residual"))?;

    // Spectrum of the raw acceleration residual (else velocity), the longest record.
    let longest = (0..r.records.len()).max_by_key(|&i| r.records[i].len);
    let mut sp = Panel::new("", "frequency [Hz]", "amplitude density");
    sp.x_scale = Scale::Log10;
    sp.y_scale = Scale::Log10;
    if let Some(i) = longest {
        let rec = &r.records[i];
        let res = |rep: &super::Replay| -> Vec<f64> {
            match &rec.ydd {
                Some(y) => rep.sim.ydd.iter().zip(y).map(|(a, b)| a - b).collect(),
                None => rep.residual_du.clone(),
            }
        };
        sp.title = format!(
            "{}: spectrum of the {} residual",
            rec.name,
            if rec.ydd.is_some() {
                "ÿ [m/s²/√Hz]"
            } else {
                "u̇ [m/s/√Hz]"
            }
        );
        for (label, rep, c) in [
            ("before", &r.replays_before[i], c_before),
            ("after", &r.replays_after[i], c_after),
        ] {
            let (f, a) = super::diagnose::spectrum(&res(rep), rec.dt);
            let (ix, _) = thin(&f, 4000);
            sp.series.push(Series::line(
                label,
                ix.iter().map(|&j| f[j]).collect(),
                ix.iter().map(|&j| a[j]).collect(),
                c,
            ));
        }
    }
    save_figure(
        &Figure::new("Residual spectrum", vec![sp]),
        &dir.join("residual_spectrum"),
    )?;

    // Correlation with the signature features.
    let mut cp = Panel::new(
        "1 sign_velocity (friction) · 2 small_command (overlap) · 3 load_pressure (leakage) · \
         4 flow_magnitude (supply sag) · 5 constant (offset) · 6 HF share (compliance)",
        "feature",
        "correlation [-]",
    );
    for (label, d, c) in [
        ("u̇ residual before", &r.diagnostics_before, c_before),
        ("u̇ residual after", &r.diagnostics_after, c_after),
    ] {
        let mut x: Vec<f64> = (1..=d.correlations.len()).map(|k| k as f64).collect();
        let mut y: Vec<f64> = d.correlations.iter().map(|c| c.velocity).collect();
        x.push(6.0);
        y.push(d.high_frequency_share);
        cp.series.push(Series::markers(label, x, y, c));
    }
    for (label, d, c) in [
        ("ÿ residual before", &r.diagnostics_before, palette(3)),
        ("ÿ residual after", &r.diagnostics_after, palette(4)),
    ] {
        let x: Vec<f64> = (1..=d.correlations.len())
            .map(|k| k as f64 + 0.15)
            .collect();
        let y: Vec<f64> = d.correlations.iter().map(|c| c.acceleration).collect();
        cp.series.push(Series::markers(label, x, y, c));
    }
    cp.y_range = Some((-1.0, 1.0));
    cp.x_range = Some((0.5, 6.5));
    cp.hlines = vec![(0.0, String::new())];
    save_figure(
        &Figure::new("Residual vs signature features", vec![cp]),
        &dir.join("signature_correlation"),
    )?;
    Ok(())
}
