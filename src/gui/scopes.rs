//! Live scrolling scopes (egui_plot): the last 1 … 60 s of accelerations, stroke
//! (with the end stops and contacts), pressures, flows, command and spool. The lines borrow
//! the trace buffers; nothing is copied per frame.

use super::plotkit::{self, LegendItem, Swatch, legend_ui, y_axis, y_marks};
use super::style::{
    CHANGE_MARK, CONTACT_FILL, CurveKind, END_STOP, LINEAR, P1, P2, PASSIVE, PLATFORM, REFERENCE,
    TWIN, guide_style, mark_style, style_of,
};
use super::traces::{Ch, MAX_WINDOW_S, Traces};
use super::units::MM_PER_M;
use crate::params::Params;
use egui::Color32;
use egui_plot::{HLine, Line, Plot, PlotPoint, PlotPoints, PlotUi, Span, VLine};
use std::collections::BTreeSet;

/// Number of scopes stacked in [`scopes_ui`].
pub const N_SCOPES: usize = 6;

/// Height of the time axis title under the last scope [px].
const X_TITLE_H: f32 = 18.0;

/// Height of a legend row above a scope [px].
const LEGEND_H: f32 = 18.0;

fn scope<'a>(
    id: &str,
    y_label: &str,
    unit: &'static str,
    height: f32,
    show_x_label: bool,
    live: bool,
    width: f32,
) -> Plot<'a> {
    // Live, the scopes scroll by themselves; frozen (or paused), time can be zoomed and
    // panned (wheel with Ctrl, drag, box with the right button; double-click: everything).
    let p = Plot::new(id)
        .height(height)
        .custom_y_axes(vec![y_axis(y_label)])
        .y_grid_spacer(move |input| y_marks(input, height))
        .allow_drag([!live, false])
        .allow_zoom([!live, false])
        .allow_scroll([!live, false])
        .allow_boxed_zoom(!live)
        .allow_double_click_reset(!live)
        .link_cursor(egui::Id::unique("scopes"), [true, false])
        .link_axis(egui::Id::unique("scopes_x"), [true, false])
        // Time ticks at least 60 px apart, whatever the window's length.
        .x_grid_spacer(move |input| plotkit::marks(input, width, 60.0))
        .x_axis_formatter(plotkit::y_tick)
        .label_formatter(move |pos| Some(hover_text(pos, unit)));
    if show_x_label {
        p.x_axis_label("time [s]")
    } else {
        p
    }
}

/// The hover readout: curve name, time and value with unit.
pub fn hover_text(pos: &egui_plot::HoverPosition<'_>, unit: &str) -> String {
    match pos {
        egui_plot::HoverPosition::NearDataPoint {
            plot_name,
            position,
            ..
        } => format!(
            "{plot_name}\nt = {:.3} s\n{} {unit}",
            position.x,
            readout(position.y)
        ),
        egui_plot::HoverPosition::Elsewhere { position } => {
            format!("t = {:.3} s\n{} {unit}", position.x, readout(position.y))
        }
    }
}

/// A value with four significant digits.
fn readout(v: f64) -> String {
    super::format::value_pm(v, f64::NAN)
}

fn window(pu: &mut PlotUi<'_>, t_now: f64, span_s: f64) {
    let t1 = t_now.max(span_s);
    pu.set_plot_bounds_x(t1 - span_s..=t1);
    pu.set_auto_bounds([false, true]);
}

/// Most points drawn per curve; a longer window is reduced to the minimum and maximum of
/// each group of samples, so peaks and spikes stay visible.
const MAX_LINE_POINTS: usize = 6000;

/// `pts`, or its min/max envelope when it has more than `max` points.
fn envelope(pts: &[PlotPoint], max: usize) -> PlotPoints<'_> {
    if pts.len() <= max {
        return PlotPoints::Borrowed(pts);
    }
    let group = pts.len().div_ceil(max / 2);
    let mut out = Vec::with_capacity(max + 2);
    for g in pts.chunks(group) {
        let (mut lo, mut hi) = (g[0], g[0]);
        for p in g {
            if p.y < lo.y {
                lo = *p;
            }
            if p.y > hi.y {
                hi = *p;
            }
        }
        if lo.x <= hi.x {
            out.extend([lo, hi]);
        } else {
            out.extend([hi, lo]);
        }
    }
    PlotPoints::Owned(out)
}

/// How the scopes show time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScopeView {
    /// Window length \[s\], 1 … [`MAX_WINDOW_S`].
    pub window_s: f64,
    /// Scrolling with the simulation (not frozen, not paused).
    pub live: bool,
}

/// The window lengths offered \[s\].
pub const WINDOWS_S: [f64; 7] = [1.0, 2.0, 5.0, 10.0, 20.0, 30.0, MAX_WINDOW_S];

/// Data areas of the six scopes drawn last frame (screen rects), top to bottom.
pub type ScopeFrames = Vec<egui::Rect>;

/// Draws the six scopes, sharing the available height. `hidden` holds the curves switched
/// off in the legends; the data areas are returned (they line up: same x range and the
/// same y-axis width).
pub fn scopes_ui(
    ui: &mut egui::Ui,
    traces: &Traces,
    params: &Params,
    hidden: &mut BTreeSet<String>,
    ab: bool,
    view: ScopeView,
) -> ScopeFrames {
    let span = view.window_s.clamp(1.0, MAX_WINDOW_S);
    // With A/B on, the reference twin (B) is overlaid on the twin (A) where they differ most.
    let with_b = |mut v: Vec<(&'static str, Ch, Color32, CurveKind)>, b: (&'static str, Ch)| {
        if ab {
            v.push((b.0, b.1, REFERENCE, CurveKind::Reference));
        }
        v
    };
    let spacing = ui.spacing().item_spacing.y;
    // The last scope's "time [s]" title takes a line below all of them.
    let h = ((ui.available_height() - X_TITLE_H - (spacing * 2.0 + LEGEND_H) * N_SCOPES as f32)
        / N_SCOPES as f32)
        // Below this a scope loses its tick labels: the centre scrolls instead.
        .max(90.0);
    let t = traces.t_now();
    let mut frames = Vec::with_capacity(N_SCOPES);
    // One scope: legend row, then the plot with the visible curves.
    let mut show = |ui: &mut egui::Ui,
                    id: &str,
                    y_label: &str,
                    unit: &'static str,
                    last: bool,
                    curves: &[(&str, Ch, Color32, CurveKind)],
                    extra: &dyn Fn(&mut PlotUi<'_>, &BTreeSet<String>)| {
        let mut items: Vec<LegendItem<'_>> = curves
            .iter()
            .map(|&(name, _, color, m)| {
                let (w, st) = style_of(m);
                let w = plotkit::line_width(ui.ctx(), w);
                LegendItem {
                    name,
                    color,
                    swatch: Swatch::Line(w, st),
                }
            })
            .collect();
        if id == "scope_stroke" {
            items.push(LegendItem {
                name: "end stops, contacts",
                color: END_STOP,
                swatch: Swatch::Span,
            });
        }
        legend_ui(ui, id, &items, hidden);
        let hidden_now = hidden.clone();
        let width = ui.available_width();
        let r = scope(id, y_label, unit, h, last, view.live, width).show(ui, |pu| {
            if view.live {
                window(pu, t, span);
            }
            extra(pu, &hidden_now);
            // Parameter changes: the metrics restart there.
            for &tc in traces.changes() {
                pu.vline(
                    VLine::new("parameter change (metrics restart)", tc)
                        .color(CHANGE_MARK)
                        .style(mark_style()),
                );
            }
            for &(name, ch, color, m) in curves {
                if plotkit::hidden(&hidden_now, id, name) {
                    continue;
                }
                let (w, st) = style_of(m);
                let w = plotkit::line_width(pu.ctx(), w);
                // Live: the window's points; frozen: all that is kept, to pan over.
                let pts = if view.live {
                    traces.channel(ch).window(t, span)
                } else {
                    traces.channel(ch).points()
                };
                let max = if view.live {
                    MAX_LINE_POINTS
                } else {
                    4 * MAX_LINE_POINTS
                };
                pu.line(
                    Line::new(name.to_owned(), envelope(pts, max))
                        .color(color)
                        .width(w)
                        .style(st),
                );
            }
        });
        frames.push(*r.transform.frame());
    };

    show(
        ui,
        "scope_acc",
        "accel. [m/s²]",
        "m/s²",
        false,
        &with_b(
            vec![
                ("platform", Ch::PlatformAcc, PLATFORM, CurveKind::Platform),
                ("passive", Ch::PassiveAcc, PASSIVE, CurveKind::Passive),
                ("twin", Ch::TwinAcc, TWIN, CurveKind::Twin),
                ("linear", Ch::LinearAcc, LINEAR, CurveKind::Linear),
            ],
            ("B: reference", Ch::RefAcc),
        ),
        &|_, _| {},
    );

    let limit_mm = params.plant.cylinder.stroke_m / 2.0 * MM_PER_M;
    let contacts = traces.contacts();
    show(
        ui,
        "scope_stroke",
        "stroke u [mm]",
        "mm",
        false,
        &with_b(
            vec![
                ("passive u", Ch::PassiveU, PASSIVE, CurveKind::Passive),
                ("twin u", Ch::TwinU, TWIN, CurveKind::Twin),
                ("linear u", Ch::LinearU, LINEAR, CurveKind::Linear),
            ],
            ("B: reference u", Ch::RefU),
        ),
        &|pu, hidden| {
            if plotkit::hidden(hidden, "scope_stroke", "end stops, contacts") {
                return;
            }
            for &(a, b) in contacts {
                pu.span(
                    Span::new("end-stop contact", a..=b.max(a + 0.01))
                        .fill(CONTACT_FILL)
                        .border_color(END_STOP),
                );
            }
            for y in [limit_mm, -limit_mm] {
                pu.hline(
                    HLine::new(format!("end stop ±{limit_mm:.0} mm"), y)
                        .color(END_STOP)
                        .style(guide_style()),
                );
            }
        },
    );

    show(
        ui,
        "scope_p",
        "pressure [bar]",
        "bar",
        false,
        &[
            ("p1 (upper)", Ch::P1, P1, CurveKind::Twin),
            ("p2 (lower)", Ch::P2, P2, CurveKind::Second),
        ],
        &|_, _| {},
    );

    show(
        ui,
        "scope_q",
        "flow [L/min]",
        "L/min",
        false,
        &[
            ("Q1", Ch::Q1, P1, CurveKind::Twin),
            ("Q2", Ch::Q2, P2, CurveKind::Second),
        ],
        &|_, _| {},
    );

    show(
        ui,
        "scope_v",
        "V_in [V]",
        "V",
        false,
        &with_b(
            vec![
                ("twin V_in", Ch::TwinVin, TWIN, CurveKind::Twin),
                ("linear V_in", Ch::LinearVin, LINEAR, CurveKind::Linear),
            ],
            ("B: reference V_in", Ch::RefVin),
        ),
        &|_, _| {},
    );

    show(
        ui,
        "scope_xv",
        "spool x_v [mm]",
        "mm",
        true,
        &[("twin x_v", Ch::TwinXv, TWIN, CurveKind::Twin)],
        &|_, _| {},
    );
    frames
}
