//! Frequency plots that follow the sliders: transmissibility |T| and phase (linear active,
//! twin linearised, passive), the Bode of `u̇/V_in` (twin vs G(s)), the |T| = 1 crossings,
//! the loop margins, and the twin's simulated sine-dwell points computed on a background
//! thread with progress and cancel.
//!
//! The analytic curves are recomputed on the frame the parameters change (the twin's
//! linearisation only when a plant parameter changes, not for a gain).

mod curves;
mod dwell;
mod stability;

pub use curves::{Analytic, Curve, Curves, PlantCache};
pub use dwell::{Dwell, DwellPoint, dwell_steps};
pub use stability::{margin_text, stability_ui};

use super::plotkit::{self, LegendItem, Swatch, legend_ui, wrap_deg, y_axis, y_marks};
use super::style::{CurveKind, frequency_style_of};
use super::units::{db, deg};
use crate::analysis::dwell::{self as sine_dwell, DwellOptions};
use crate::analysis::frequency_response::{self as fr, Crossing, LinearisedModel, OpenLoop};
use crate::analysis::stability::{LoopPlant, MarginGrid, Stability};
use crate::control::ControlLaw;
use crate::model::ModelKind;
use crate::params::{ControllerParams, Params};
use egui::{Color32, RichText};
use egui_plot::{Line, LineStyle, MarkerShape, Plot, PlotPoint, PlotPoints, Points, VLine};
use num_complex::Complex64;
use std::collections::BTreeSet;
use std::f64::consts::PI;
use std::time::Duration;
use web_time::Instant;

/// Frequency range of the plots \[Hz\].
pub const F_RANGE_HZ: (f64, f64) = (0.1, 100.0);
/// Points of the analytic curves.
pub const N_POINTS: usize = 240;
/// Frequencies of the simulated dwell \[Hz\].
pub const DWELL_RANGE_HZ: (f64, f64) = (0.3, 30.0);
/// Number of dwell points.
pub const N_DWELL: usize = 14;
/// Legend of the simulated transmissibility points.
pub const T_DWELL_NAME: &str = "twin simulated (dwell)";
/// Legend of the simulated u̇/V_in points.
pub const BODE_DWELL_NAME: &str = "twin simulated (sine dwell, ≤ 1.1 V)";
/// Legends of the transmissibility curves: linear model, linearised twin, passive seat.
pub const T_NAMES: [&str; 3] = ["linear active", "twin active (linearised)", "passive"];
/// Legends of the u̇/V_in curves: linearised twin, G(s).
pub const BODE_NAMES: [&str; 2] = ["twin (linearised)", "G(s)"];
/// Highest frequency of the simulated u̇/V_in points \[Hz\] (Table 1's range: above it the
/// phase between neighbouring dwell points could not be unwrapped reliably).
pub const BODE_DWELL_MAX_HZ: f64 = 20.0;
/// Command amplitude of the simulated u̇/V_in point at `freq_hz` \[V\]: Table 1's 1.1 V where
/// the stroke allows, less at low frequency so that the piston stays within ±15 mm of
/// mid-stroke (at the paper's gain of 133 mm/(s·V), 1.1 V at 0.3 Hz would swing ±78 mm,
/// into the end stops at ±35 mm).
pub fn bode_dwell_amplitude_v(freq_hz: f64) -> f64 {
    const STROKE_AMPLITUDE_M: f64 = 0.015;
    const NOMINAL_GAIN_M_PER_S_V: f64 = 0.133;
    (STROKE_AMPLITUDE_M * 2.0 * PI * freq_hz / NOMINAL_GAIN_M_PER_S_V).clamp(0.05, 1.1)
}
/// Pause after the last parameter change before the dwell restarts.
pub const DWELL_DEBOUNCE: Duration = Duration::from_millis(400);

/// The models' colours (defined in [`super::style`], re-exported for the views that draw
/// beside the frequency plots).
pub use super::style::{LINEAR, PASSIVE, PLATFORM, TWIN};

/// Formats a log10-frequency axis mark as Hz.
fn hz_axis(mark: egui_plot::GridMark, _range: &std::ops::RangeInclusive<f64>) -> String {
    let f = 10f64.powf(mark.value);
    if (mark.value - mark.value.round()).abs() > 1e-6 {
        // Only label decades and 2, 5 multiples.
        let lead = f / 10f64.powf(mark.value.floor());
        if (lead - 2.0).abs() > 0.05 && (lead - 5.0).abs() > 0.05 {
            return String::new();
        }
    }
    if f >= 1.0 {
        format!("{f:.0}")
    } else {
        format!("{f:.1}")
    }
}

/// Grid marks at decades (strong) and 2…9 within each decade (faint).
fn log_grid(input: egui_plot::GridInput) -> Vec<egui_plot::GridMark> {
    let (lo, hi) = input.bounds;
    let mut out = Vec::new();
    let mut d = lo.floor() as i32 - 1;
    while (d as f64) <= hi + 1.0 {
        for k in 1..10 {
            let v = d as f64 + (k as f64).log10();
            if v >= lo && v <= hi {
                out.push(egui_plot::GridMark {
                    value: v,
                    step_size: if k == 1 { 1.0 } else { 0.1 },
                });
            }
        }
        d += 1;
    }
    out
}

/// Room right of 100 Hz on the frequency axes [decades]: the "100" tick label is centred
/// on the plot's right edge otherwise, and the panel cut off its right half.
const X_LABEL_ROOM_DECADES: f64 = 0.12;

fn freq_plot<'a>(id: &str, y_label: &str, unit: &'static str, height: f32) -> Plot<'a> {
    Plot::new(id)
        .height(height)
        .x_axis_label("frequency [Hz]")
        .custom_y_axes(vec![y_axis(y_label)])
        .x_axis_formatter(hz_axis)
        .x_grid_spacer(log_grid)
        .y_grid_spacer(move |input| y_marks(input, height))
        .label_formatter(move |pos| {
            Some(match pos {
                egui_plot::HoverPosition::NearDataPoint {
                    plot_name,
                    position,
                    ..
                } => format!(
                    "{plot_name}\n{:.2} Hz\n{:.1} {unit}",
                    10f64.powf(position.x),
                    position.y
                ),
                egui_plot::HoverPosition::Elsewhere { position } => {
                    format!("{:.2} Hz\n{:.1} {unit}", 10f64.powf(position.x), position.y)
                }
            })
        })
        .default_x_bounds(
            F_RANGE_HZ.0.log10(),
            F_RANGE_HZ.1.log10() + X_LABEL_ROOM_DECADES,
        )
        .allow_scroll(false)
        .link_axis(egui::Id::unique("freq"), [true, false])
}

/// Colour of the simulated (sine dwell) points: the theme's strongest text colour (white on
/// dark, black on light), so points on the twin's blue line stay visible in either theme.
pub fn dwell_color(ui: &egui::Ui) -> Color32 {
    ui.visuals().strong_text_color()
}

/// What the frequency panel asks the app to do.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FreqAction {
    /// Nothing.
    None,
    /// Put back the last gains with which both loops were stable.
    ResetToStableGains,
}

/// View options of the frequency panel.
pub struct FreqView<'a> {
    /// Unwrapped phase (else wrapped into ±180°, the default).
    pub phase_unwrapped: &'a mut bool,
    /// Curves hidden in the legends.
    pub hidden: &'a mut BTreeSet<String>,
    /// The last stable gains, if they differ from the current ones.
    pub last_stable: Option<ControllerParams>,
    /// A/B on: the curves of the reference controller on the same plant (its linearised
    /// twin's transmissibility is drawn with the live one's).
    pub reference: Option<&'a Curves>,
    /// What the running twin's watch found (an oscillation the linear verdict may not see).
    pub watch: Option<crate::analysis::watch::Finding>,
}

/// Legend name of the A/B reference's transmissibility.
pub const REFERENCE_NAME: &str = "B: reference";

/// The phase curve as shown: wrapped into ±180° (default) or unwrapped. Wrapping breaks the
/// line where it jumps, so no vertical stroke crosses the plot.
pub fn shown_phase(c: &[PlotPoint], unwrapped: bool) -> Vec<Vec<PlotPoint>> {
    if unwrapped {
        return vec![c.to_vec()];
    }
    let mut out: Vec<Vec<PlotPoint>> = vec![Vec::new()];
    let mut prev: Option<f64> = None;
    for p in c {
        let y = wrap_deg(p.y);
        if prev.is_some_and(|q| (y - q).abs() > 180.0) {
            out.push(Vec::new());
        }
        if let Some(seg) = out.last_mut() {
            seg.push(PlotPoint::new(p.x, y));
        }
        prev = Some(y);
    }
    out
}

/// One analytic curve of a frequency plot: its legend name, colour and stroke.
#[derive(Clone, Copy)]
pub(crate) struct CurveStyle {
    pub(crate) name: &'static str,
    pub(crate) color: Color32,
    pub(crate) width: f32,
    pub(crate) style: LineStyle,
}

/// Each curve with its style, then `extra` (the A/B reference) if there is one.
fn styled<'a>(
    styles: &[CurveStyle],
    curves: &'a [Curve],
    extra: Option<(CurveStyle, &'a Curve)>,
) -> Vec<(CurveStyle, &'a [PlotPoint])> {
    styles
        .iter()
        .copied()
        .zip(curves)
        .chain(extra)
        .map(|(s, c)| (s, c.as_slice()))
        .collect()
}

/// What one of the four frequency plots shows: its lines (with their styles), the simulated
/// dwell points if shown, and whether the y axis is a phase (wrapped unless unwrapped).
pub(crate) struct FreqPanel<'a> {
    pub(crate) id: &'static str,
    pub(crate) y_label: &'static str,
    pub(crate) unit: &'static str,
    pub(crate) lines: Vec<(CurveStyle, &'a [PlotPoint])>,
    pub(crate) dwell: Option<(&'static str, Color32, &'a [PlotPoint])>,
    pub(crate) phase: bool,
}

impl FreqPanel<'_> {
    /// The legend row (one clickable entry per line and the dwell points), then the plot;
    /// `extra` draws what belongs to this plot only (reference lines, markers). The plot
    /// takes its share of the height left once its legend is drawn (`remaining` plots,
    /// this one included, each with a legend row), so a legend that wraps to two rows never
    /// pushes the last plot out of the window.
    fn ui(
        &self,
        ui: &mut egui::Ui,
        remaining: usize,
        unwrapped: bool,
        hidden: &mut BTreeSet<String>,
        extra: impl FnOnce(&mut egui_plot::PlotUi<'_>),
    ) {
        let mut items: Vec<LegendItem<'_>> = self
            .lines
            .iter()
            .map(|(c, _)| LegendItem {
                name: c.name,
                color: c.color,
                swatch: Swatch::Line(c.width, c.style),
            })
            .collect();
        if let Some((name, color, _)) = self.dwell {
            items.push(LegendItem {
                name,
                color,
                swatch: Swatch::Marker,
            });
        }
        legend_ui(ui, self.id, &items, hidden);
        let legend_h = 18.0 + ui.spacing().item_spacing.y;
        let n = remaining.max(1) as f32;
        // Below this the phase keeps only one tick label: the centre scrolls instead.
        let height = ((ui.available_height() - 12.0 - (n - 1.0) * legend_h) / n).max(120.0);
        let shown = |name: &str| !plotkit::hidden(hidden, self.id, name);
        let segments = |c: &[PlotPoint]| {
            if self.phase {
                shown_phase(c, unwrapped)
            } else {
                vec![c.to_vec()]
            }
        };
        freq_plot(self.id, self.y_label, self.unit, height).show(ui, |pu| {
            for (c, points) in self.lines.iter().filter(|(c, _)| shown(c.name)) {
                for seg in segments(points) {
                    pu.line(
                        Line::new(c.name, PlotPoints::Owned(seg))
                            .color(c.color)
                            .width(plotkit::line_width(pu.ctx(), c.width))
                            .style(c.style),
                    );
                }
            }
            if let Some((name, color, points)) = self.dwell.filter(|(n, ..)| shown(n)) {
                pu.points(
                    Points::new(name, PlotPoints::Owned(segments(points).concat()))
                        .color(color)
                        .shape(MarkerShape::Diamond)
                        .radius(5.0)
                        .filled(true),
                );
            }
            extra(pu);
        });
    }
}

/// The dwell progress row: progress and Cancel, "up to date", or why nothing is shown.
fn dwell_status_ui(ui: &mut egui::Ui, dwell: &mut Dwell, params: &Params, unstable: bool) {
    ui.label(RichText::new("Simulated twin (sine dwell):").strong());
    match dwell.progress() {
        _ if unstable => {
            ui.label("not shown: the closed loop is unstable");
        }
        Some((done, total)) => {
            if plotkit::progress_cancel_ui(ui, done, total, "Cancel") {
                dwell.cancel();
            }
        }
        None if dwell.is_current(params) => {
            ui.label(format!("{} points, up to date", dwell.mag.len()));
        }
        None if dwell.cancelled => {
            ui.label("cancelled");
            if ui.button("Recompute").clicked() {
                dwell.start(params);
            }
        }
        None => {
            ui.label("waiting for the sliders to settle…");
        }
    }
    if !unstable && !dwell.failures.is_empty() {
        ui.colored_label(
            super::style::FAILED_TEXT,
            format!("{} point(s) diverged", dwell.failures.len()),
        )
        .on_hover_text(
            dwell
                .failures
                .iter()
                .map(|(f, r)| format!("{f:.2} Hz: {r}"))
                .collect::<Vec<_>>()
                .join("\n"),
        );
    }
}

/// The |T| = 1 crossings (end of the isolation band) of the linear model and the twin: a
/// dotted line and a label each, at the top of the plot.
fn crossing_marks(pu: &mut egui_plot::PlotUi<'_>, curves: &Curves, colors: [Color32; 2]) {
    let top = curves.t_mag[0]
        .iter()
        .chain(&curves.t_mag[1])
        .map(|p| p.y)
        .fold(f64::NEG_INFINITY, f64::max)
        .max(0.0);
    for (i, cs) in curves.crossings.iter().enumerate() {
        for c in cs.iter().filter(|c| c.rising).take(1) {
            let x = c.freq_hz.log10();
            pu.vline(
                VLine::new("", x)
                    .color(colors[i].gamma_multiply(0.8))
                    .style(super::style::mark_style()),
            );
            // Linear to the right of its line, twin to the left.
            let (text, anchor) = if i == 0 {
                (
                    format!(" |T|=1 @ {:.2} Hz", c.freq_hz),
                    egui::Align2::LEFT_TOP,
                )
            } else {
                (
                    format!("|T|=1 @ {:.2} Hz ", c.freq_hz),
                    egui::Align2::RIGHT_TOP,
                )
            };
            pu.text(
                egui_plot::Text::new(
                    "",
                    PlotPoint::new(x, top),
                    RichText::new(text).color(colors[i]).small(),
                )
                .anchor(anchor),
            );
        }
    }
}

/// Draws the stability banner (if needed), the four frequency plots and the dwell progress.
pub fn frequency_ui(
    ui: &mut egui::Ui,
    curves: &Curves,
    dwell: &mut Dwell,
    params: &Params,
    view: FreqView<'_>,
) -> FreqAction {
    let action = stability_ui(ui, curves, view.last_stable, view.watch);
    let unstable = curves.unstable();
    // Wrapped, so that a long status (progress, failures) never widens the column.
    ui.horizontal_wrapped(|ui| {
        // In a scope, which takes one auto id whatever it holds: the dwell status has one to
        // three widgets as the dwell waits, runs or ends, and the checkbox's auto id (counted
        // from the widgets before it) would change with them, so a click that arrives as the
        // status changes (an accessibility action does) would miss.
        ui.scope(|ui| dwell_status_ui(ui, dwell, params, unstable));
        ui.separator();
        ui.checkbox(&mut *view.phase_unwrapped, "unwrapped phase")
            .on_hover_text("Off: phase wrapped into ±180°. On: continuous (unwrapped) phase.");
    });
    let show_dwell = dwell_shown(curves, dwell, params);
    let hidden = view.hidden;
    let unwrapped = *view.phase_unwrapped;
    let [t_mag, t_phase, bode_mag, bode_phase] = freq_panels(
        curves,
        dwell,
        view.reference,
        show_dwell.then(|| dwell_color(ui)),
    );
    let t_colors = [t_mag.lines[0].0.color, t_mag.lines[1].0.color];
    t_mag.ui(ui, 4, unwrapped, hidden, |pu| {
        pu.hline(
            egui_plot::HLine::new("|T| = 1", 0.0)
                .color(Color32::GRAY)
                .style(super::style::guide_style()),
        );
        // The |T| = 1 crossings of an unstable loop mean nothing.
        if !unstable {
            crossing_marks(pu, curves, t_colors);
        }
    });
    t_phase.ui(ui, 3, unwrapped, hidden, |_| {});
    bode_mag.ui(ui, 2, unwrapped, hidden, |_| {});
    bode_phase.ui(ui, 1, unwrapped, hidden, |_| {});
    action
}

/// Whether the dwell points are shown: they belong to these parameters (or are arriving for
/// them) and the loop is stable. Points simulated for other parameters, or for an unstable
/// loop, are not shown — in the view nor in an export.
pub(crate) fn dwell_shown(curves: &Curves, dwell: &Dwell, params: &Params) -> bool {
    !curves.unstable() && (dwell.is_current(params) || dwell.progress().is_some())
}

/// The four frequency plots (|T|, its phase, |u̇/V_in|, its phase) as the view draws them
/// and an export writes them: every curve with its name and style, the A/B reference on the
/// transmissibility plots, and the dwell points in `dwell_color` when they are shown. An
/// unstable loop's active curves are faint.
pub(crate) fn freq_panels<'a>(
    curves: &'a Curves,
    dwell: &'a Dwell,
    reference: Option<&'a Curves>,
    dwell_c: Option<Color32>,
) -> [FreqPanel<'a>; 4] {
    let unstable = curves.unstable();
    // Unstable: the active curves are faint (not a steady state).
    let active = |c: Color32| if unstable { c.gamma_multiply(0.45) } else { c };
    let curve = |name: &'static str, color: Color32, kind: CurveKind| {
        let (width, style) = frequency_style_of(kind);
        CurveStyle {
            name,
            color,
            width,
            style,
        }
    };
    let t_styles = [
        curve(T_NAMES[0], active(LINEAR), CurveKind::Linear),
        curve(T_NAMES[1], active(TWIN), CurveKind::Twin),
        curve(T_NAMES[2], PASSIVE, CurveKind::Passive),
    ];
    let (ref_w, ref_style) = super::style::style_of(super::style::CurveKind::Reference);
    let reference_style = CurveStyle {
        name: REFERENCE_NAME,
        color: super::style::REFERENCE,
        width: ref_w,
        style: ref_style,
    };
    let t_mag = FreqPanel {
        id: "t_mag",
        y_label: "|T| [dB]",
        unit: "dB",
        lines: styled(
            &t_styles,
            &curves.t_mag,
            reference.map(|r| (reference_style, &r.t_mag[1])),
        ),
        dwell: dwell_c.map(|c| (T_DWELL_NAME, c, dwell.mag.as_slice())),
        phase: false,
    };
    let t_phase = FreqPanel {
        id: "t_phase",
        y_label: "phase T [deg]",
        unit: "°",
        lines: styled(
            &t_styles,
            &curves.t_phase,
            reference.map(|r| (reference_style, &r.t_phase[1])),
        ),
        dwell: dwell_c.map(|c| (T_DWELL_NAME, c, dwell.phase.as_slice())),
        phase: true,
    };
    let b_styles = [
        curve(BODE_NAMES[0], TWIN, CurveKind::Twin),
        curve(BODE_NAMES[1], LINEAR, CurveKind::Linear),
    ];
    let bode_mag = FreqPanel {
        id: "bode_mag",
        y_label: "|du/dt / V_in| [dB]",
        unit: "dB re (mm/s)/V",
        lines: styled(&b_styles, &curves.bode_mag, None),
        dwell: dwell_c.map(|c| (BODE_DWELL_NAME, c, dwell.bode_mag.as_slice())),
        phase: false,
    };
    let bode_phase = FreqPanel {
        id: "bode_phase",
        y_label: "phase [deg]",
        unit: "°",
        lines: styled(&b_styles, &curves.bode_phase, None),
        dwell: dwell_c.map(|c| (BODE_DWELL_NAME, c, dwell.bode_phase.as_slice())),
        phase: true,
    };
    [t_mag, t_phase, bode_mag, bode_phase]
}
