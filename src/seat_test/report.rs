//! `seat-twin seat-test`: `report.md`, `numbers.json` and PNG + SVG plots of one seat test.

use super::run::{CREST_FACTOR_LIMIT, SeatTestResult};
use crate::output::OutputError;
use crate::plot::{self, Figure, Panel, Series, SeriesStyle, palette};
use crate::preset::write_atomic;
use crate::scenario::classes::{InputClass, PSD_TOLERANCE_OF_PEAK};
use std::fmt::Write as _;
use std::path::Path;

/// Suspended mass of the paper's rig \[kg\].
pub const RIG_MASS_KG: f64 = 11.7;

/// Why the report could not be written: a file (named) or a plot.
pub type SeatReportError = OutputError;

/// Writes `report.md`, `numbers.json`, `platform_psd.{png,svg}` and
/// `seat_response.{png,svg}` into `out` (created if missing); `preset` names the preset.
pub fn write_seat_test(
    result: &SeatTestResult,
    class: &InputClass,
    preset: &str,
    out: &Path,
) -> Result<(), SeatReportError> {
    std::fs::create_dir_all(out).map_err(OutputError::io(out))?;
    platform_psd_figure(result, class, &out.join("platform_psd"))?;
    response_figure(result, &out.join("seat_response"))?;
    let json = serde_json::to_string_pretty(&result.numbers)
        .unwrap_or_else(|e| format!("{{\"error\": \"{e}\"}}"));
    let path = out.join("numbers.json");
    write_atomic(&path, json.as_bytes()).map_err(OutputError::io(&path))?;
    let md = markdown(result, class, preset);
    let path = out.join("report.md");
    write_atomic(&path, md.as_bytes()).map_err(OutputError::io(&path))?;
    Ok(())
}

/// The x range \[Hz\] of the spectra: up to the class band's upper edge, at most 20 Hz.
fn freq_range(class: &InputClass) -> (f64, f64) {
    (0.0, class.rms_band_hz.1.min(20.0))
}

fn platform_psd_figure(
    r: &SeatTestResult,
    class: &InputClass,
    path: &Path,
) -> Result<(), SeatReportError> {
    let (f0, f1) = freq_range(class);
    let tol = PSD_TOLERANCE_OF_PEAK * class.peak().1;
    let freqs: Vec<f64> = (0..=2000)
        .map(|i| f0 + (f1 - f0) * i as f64 / 2000.0)
        .collect();
    let target: Vec<f64> = freqs.iter().map(|&f| class.target_psd(f)).collect();
    let dashed = |label: &str, y: Vec<f64>| Series {
        label: label.to_string(),
        x: freqs.clone(),
        y,
        style: SeriesStyle::Line {
            color: palette(7),
            width: 1,
            dashed: true,
        },
    };
    let (fe, pe): (Vec<f64>, Vec<f64>) = r
        .psd_floor
        .freq_hz
        .iter()
        .zip(&r.psd_floor.psd)
        .filter(|(f, _)| **f >= f0 && **f <= f1)
        .map(|(f, p)| (*f, *p))
        .unzip();
    let title = format!(
        "{}: platform acceleration PSD (largest deviation {:.1} % of the peak at {:.2} Hz)",
        class.name, r.numbers.psd_error_percent, r.numbers.psd_error_at_hz
    );
    let mut panel = Panel::new(title, "frequency [Hz]", "PSD [(m/s²)²/Hz]").with_series(vec![
        Series::line("generated (Welch)", fe, pe, palette(0)),
        Series::line("target", freqs.clone(), target.clone(), palette(3)),
        dashed(
            "target ± 10 % of peak",
            target.iter().map(|g| g + tol).collect(),
        ),
        dashed("", target.iter().map(|g| (g - tol).max(0.0)).collect()),
    ]);
    panel.x_range = Some((f0, f1));
    let fig = Figure::new(
        format!(
            "Input class {} — {} (source: HVLab toolbox)",
            class.name,
            class.standard.citation()
        ),
        vec![panel],
    );
    plot::save_figure(&fig, path)?;
    Ok(())
}

fn response_figure(r: &SeatTestResult, path: &Path) -> Result<(), SeatReportError> {
    let n = &r.numbers;
    let (f0, f1) = (0.0, 20.0);
    let spec = |p: &crate::scenario::class_motion::Psd| -> (Vec<f64>, Vec<f64>) {
        p.freq_hz
            .iter()
            .zip(&p.psd)
            .filter(|(f, _)| **f > 0.0 && **f <= f1)
            .map(|(f, v)| (*f, *v))
            .unzip()
    };
    let (ff, pf) = spec(&r.psd_floor);
    let (fs_, ps) = spec(&r.psd_seat);
    let psd_title = format!(
        "acceleration PSD: SEAT {:.0} %, a_w floor {:.2}, seat {:.2} m/s²",
        n.seat_percent, n.aw_floor, n.aw_seat
    );
    let mut psd = Panel::new(psd_title, "frequency [Hz]", "PSD [(m/s²)²/Hz]").with_series(vec![
        Series::line("floor (platform) ẍ", ff, pf, palette(0)),
        Series::line("seat (suspended body) ÿ", fs_, ps, palette(3)),
    ]);
    psd.x_range = Some((f0, f1));

    // Ten seconds from the start of the evaluated interval.
    let (t0, _) = r.motion.steady_interval_s();
    let window: Vec<&crate::simulation::Sample> = r
        .trace
        .samples
        .iter()
        .filter(|s| s.t >= t0 && s.t <= t0 + 10.0)
        .collect();
    let t: Vec<f64> = window.iter().map(|s| s.t).collect();
    let acc = Panel::new(
        "acceleration, 10 s of the evaluated interval",
        "time [s]",
        "acceleration [m/s²]",
    )
    .with_series(vec![
        Series::line(
            "floor ẍ",
            t.clone(),
            window.iter().map(|s| s.xdd).collect(),
            palette(0),
        ),
        Series::line(
            "seat ÿ",
            t,
            window.iter().map(|s| s.ydd).collect(),
            palette(3),
        ),
    ]);

    let all = &r.trace.samples;
    let stroke_title = format!(
        "relative displacement u: max |u| {:.1} mm, {} contact(s); platform x up to ±{:.0} mm",
        n.max_abs_u_mm, n.contacts, n.platform_max_abs_x_mm
    );
    let mut stroke = Panel::new(stroke_title, "time [s]", "displacement [mm]").with_series(vec![
        Series {
            label: "platform x".into(),
            x: all.iter().map(|s| s.t).collect(),
            y: all.iter().map(|s| 1e3 * s.x).collect(),
            style: SeriesStyle::Line {
                color: palette(7),
                width: 1,
                dashed: false,
            },
        },
        Series::line(
            "u",
            all.iter().map(|s| s.t).collect(),
            all.iter().map(|s| 1e3 * s.u).collect(),
            palette(2),
        ),
    ]);
    stroke.hlines = vec![
        (
            n.half_stroke_mm,
            format!("+{:.0} mm stop", n.half_stroke_mm),
        ),
        (
            -n.half_stroke_mm,
            format!("−{:.0} mm stop", n.half_stroke_mm),
        ),
    ];
    stroke.vspans = r
        .trace
        .contacts
        .iter()
        .map(|c| (c.t_start, c.t_end.max(c.t_start + 0.05)))
        .collect();
    let mut fig = Figure::new(
        format!(
            "Seat test {} on the {} model, {:.1} kg",
            n.class, n.model, n.mass_kg
        ),
        vec![psd, acc, stroke],
    );
    fig.height = 1000;
    plot::save_figure(&fig, path)?;
    Ok(())
}

/// The report text.
pub fn markdown(r: &SeatTestResult, class: &InputClass, preset: &str) -> String {
    let n = &r.numbers;
    let (fp, gp) = class.peak();
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# Seat test {} on the {} model\n\nPreset `{preset}`, suspended mass {:.1} kg, \
         {:.0} s record (seed {}), {:.0} s evaluated after the fades.\n",
        n.class, n.model, n.mass_kg, n.duration_s, n.seed, n.evaluated_s
    );

    let _ = writeln!(s, "## Input class\n");
    let _ = writeln!(
        s,
        "{} of {}: target PSD `G(f) = {:.2} · |H_hp|² · |H_lp|²` (m/s²)²/Hz with a \
         Butterworth high-pass of order {} at {} Hz and low-pass of order {} at {} Hz; \
         peak {:.3} (m/s²)²/Hz at {:.2} Hz; tolerance ±{:.0} % of the peak; rms {:.2} m/s² in \
         {}–{} Hz.\n",
        class.name,
        class.standard.citation(),
        class.g0,
        class.high_pass.order,
        class.high_pass.corner_hz,
        class.low_pass.order,
        class.low_pass.corner_hz,
        gp,
        fp,
        100.0 * PSD_TOLERANCE_OF_PEAK,
        class.rms_m_s2,
        class.rms_band_hz.0,
        class.rms_band_hz.1
    );
    let _ = writeln!(
        s,
        "Source: the HVLab HRV Toolbox (ISVR, University of Southampton), `hvtestspectrum.m` \
         and `hvtestsignal.m`; the standard's own table could not be read. The class mapping \
         and what else is uncertain are listed in the engine's `scenario::classes` docs.{}\n",
        if class.note.is_empty() {
            String::new()
        } else {
            format!(" For this class: {}.", class.note)
        }
    );

    let _ = writeln!(s, "## Generated platform motion\n");
    let _ = writeln!(
        s,
        "A random-phase multisine on the record's frequency grid, 0.2–50 Hz, its line \
         amplitudes equalised to the target as a shaker controller equalises its drive, with \
         quintic fades of {:.0} s at both ends (starts and ends at rest, no drift).\n",
        r.motion.fade_s
    );
    let _ = writeln!(s, "| check | value | requirement |\n|---|---|---|");
    let _ = writeln!(
        s,
        "| largest PSD deviation in {}–{} Hz (Welch, Δf = {:.3} Hz, {} segments) | {:.1} % of \
         the peak at {:.2} Hz | ≤ 10 % ({}) |",
        class.rms_band_hz.0,
        class.rms_band_hz.1,
        super::run::SEAT_TEST_RATE_HZ / crate::scenario::class_motion::WELCH_SEGMENT as f64,
        r.psd_check.segments,
        n.psd_error_percent,
        n.psd_error_at_hz,
        if n.psd_within_tolerance {
            "met"
        } else {
            "NOT met"
        }
    );
    let _ = writeln!(
        s,
        "| rms in {}–{} Hz | {:.3} m/s² | {:.3} m/s² from the target PSD; {:.2} m/s² stated |",
        class.rms_band_hz.0, class.rms_band_hz.1, n.floor_band_rms, n.target_band_rms, n.stated_rms
    );
    let _ = writeln!(
        s,
        "| platform displacement the class needs | ±{:.1} mm peak, {:.1} mm peak-to-peak, \
         {:.1} mm rms | — |\n",
        n.platform_max_abs_x_mm, n.platform_peak_to_peak_mm, n.platform_rms_x_mm
    );

    let _ = writeln!(s, "## Result\n");
    let _ = writeln!(s, "| quantity | floor | seat |\n|---|---|---|");
    let _ = writeln!(
        s,
        "| a_w (ISO 2631-1 Wk) [m/s²] | {:.3} | {:.3} |",
        n.aw_floor, n.aw_seat
    );
    let _ = writeln!(
        s,
        "| VDV [m/s^1.75] | {:.3} | {:.3} |",
        n.vdv_floor, n.vdv_seat
    );
    let _ = writeln!(
        s,
        "| crest factor (weighted) | {:.2} | {:.2} |\n",
        n.crest_factor_floor, n.crest_factor_seat
    );
    let crest_high = n.crest_factor_seat.max(n.crest_factor_floor) > CREST_FACTOR_LIMIT;
    let _ = writeln!(
        s,
        "**SEAT = {:.1} %** (100 · a_w,seat / a_w,floor); by VDV {:.1} %. {}\n",
        n.seat_percent,
        n.seat_vdv_percent,
        if crest_high {
            "A crest factor is above 9: ISO 2631-1 asks for the VDV as well; use the VDV ratio."
        } else {
            "Both crest factors are below 9, so the weighted rms is the measure."
        }
    );
    let what = if n.model == "twin" {
        "end-stop contact"
    } else {
        "stroke overrun (this model has no end stops)"
    };
    if n.contacts > 0 {
        let first = r.trace.contacts.first().map(|c| c.t_start).unwrap_or(0.0);
        let _ = writeln!(
            s,
            "**The seat hits its ±{:.0} mm stops.** {} {what} event(s), the first at t = {:.2} s; \
             max |u| = {:.1} mm. The SEAT value above includes the impacts.\n",
            n.half_stroke_mm, n.contacts, first, n.max_abs_u_mm
        );
    } else {
        let _ = writeln!(
            s,
            "The seat stays off its ±{:.0} mm stops: max |u| = {:.1} mm ({:.0} % of the half \
             stroke).\n",
            n.half_stroke_mm,
            n.max_abs_u_mm,
            100.0 * n.max_abs_u_mm / n.half_stroke_mm
        );
    }
    let _ = writeln!(
        s,
        "The class needs the platform to travel ±{:.1} mm ({:.1} mm peak-to-peak). The paper \
         does not state the travel of its vibrating platform; the only travel it states is the \
         cylinder's ±{:.0} mm{}.\n",
        n.platform_max_abs_x_mm,
        n.platform_peak_to_peak_mm,
        n.half_stroke_mm,
        if n.platform_max_abs_x_mm > n.half_stroke_mm {
            ", which this class's platform motion exceeds: whether the rig's platform could \
             produce it is not known"
        } else {
            ""
        }
    );

    let _ = writeln!(s, "## What this model is valid for\n");
    let _ = writeln!(
        s,
        "The model is the paper's scaled rig: a suspended body of {RIG_MASS_KG} kg on springs of \
         {:.0} N/m in total, a double-rod cylinder with ±{:.0} mm of stroke and a proportional \
         valve with its delay. The \"seat\" is that suspended body: no cushion and no human \
         body are modelled, and gravity is not (the static load is taken as balanced).\n",
        n.spring_stiffness_n_per_m, n.half_stroke_mm
    );
    if (n.mass_kg - RIG_MASS_KG).abs() > 1e-9 {
        let _ = writeln!(
            s,
            "This run uses {:.1} kg instead of the rig's {RIG_MASS_KG} kg: only the inertia \
             changes; springs, cylinder, valve and controller gains stay those of the rig, so \
             this is what the same hardware would do with that mass, not a model of a real \
             seat built for it.\n",
            n.mass_kg
        );
    } else {
        let _ = writeln!(
            s,
            "This run uses the rig's own {RIG_MASS_KG} kg. The standards test with people \
             (ISO 10326-1: a light and a heavy test person) or, for the run-in of ISO 7096, a \
             75 kg inert mass (both from secondary notes, not read in the standards); use \
             `--mass 75` to see the rig's hardware carry 75 kg.\n"
        );
    }
    let _ = writeln!(
        s,
        "The standards' acceptance limits (the SEAT limit per class, the damping test at \
         resonance) were not found in public text and are not applied: this is a \
         measurement of the scaled rig on a standard input, not a certification.\n"
    );
    let _ = writeln!(
        s,
        "## Files\n\n- `numbers.json`: the numbers above (SI unless the name says mm).\n\
         - `platform_psd.png/.svg`: the generated platform PSD against the target and its \
         tolerance band.\n- `seat_response.png/.svg`: floor and seat PSD, a 10 s stretch of \
         both accelerations, and u against the stops."
    );
    s
}
