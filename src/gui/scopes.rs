//! Live scrolling scopes (egui_plot): the last [`WINDOW_S`] seconds of accelerations, stroke
//! (with the end stops and contacts), pressures, flows, command and spool. The lines borrow
//! the trace buffers; nothing is copied per frame.

use super::frequency::{LINEAR, PASSIVE, PLATFORM, TWIN};
use super::plotkit::{self, LegendItem, Swatch, legend_ui, y_axis, y_marks};
use super::traces::{Ch, Traces, WINDOW_S};
use super::units::MM_PER_M;
use crate::params::Params;
use egui::Color32;
use egui_plot::{HLine, Line, LineStyle, Plot, PlotUi, Span};
use std::collections::BTreeSet;

/// Upper chamber colour.
const P1_COLOR: Color32 = Color32::from_rgb(214, 39, 40);
/// Lower chamber colour.
const P2_COLOR: Color32 = Color32::from_rgb(148, 103, 189);
/// End-stop contact highlight.
const CONTACT: Color32 = Color32::from_rgba_premultiplied(200, 30, 30, 60);

/// Number of scopes stacked in [`scopes_ui`].
pub const N_SCOPES: usize = 6;

/// Height of a legend row above a scope [px].
const LEGEND_H: f32 = 18.0;

/// How each kind of curve is drawn wherever curves overlap: the twin solid and wider, the
/// linear model dashed on top of it, the passive reference dotted, the platform thin.
pub fn style_of(model: Model) -> (f32, LineStyle) {
    match model {
        Model::Twin => (2.2, LineStyle::Solid),
        Model::Linear => (1.6, LineStyle::dashed_dense()),
        Model::Passive => (1.6, LineStyle::dotted_dense()),
        Model::Platform => (1.0, LineStyle::Solid),
        Model::Second => (1.6, LineStyle::dashed_dense()),
    }
}

/// The kinds of curve, for their styles.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Model {
    /// The twin (solid, wide).
    Twin,
    /// The linear model (dashed).
    Linear,
    /// The passive reference (dotted).
    Passive,
    /// The platform (thin).
    Platform,
    /// The second of two twin channels in one scope (Q2 under Q1, p2 under p1): dashed.
    Second,
}

fn scope<'a>(
    id: &str,
    y_label: &str,
    unit: &'static str,
    height: f32,
    show_x_label: bool,
) -> Plot<'a> {
    let p = Plot::new(id)
        .height(height)
        .custom_y_axes(vec![y_axis(y_label)])
        .y_grid_spacer(move |input| y_marks(input, height))
        .allow_drag(false)
        .allow_zoom(false)
        .allow_scroll(false)
        .allow_boxed_zoom(false)
        .allow_double_click_reset(false)
        .link_cursor(egui::Id::unique("scopes"), [true, false])
        .link_axis(egui::Id::unique("scopes_x"), [true, false])
        .x_grid_spacer(egui_plot::uniform_grid_spacer(|_| [0.5, 1.0, 5.0]))
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

fn window(pu: &mut PlotUi<'_>, t_now: f64) {
    let t1 = t_now.max(WINDOW_S);
    pu.set_plot_bounds_x(t1 - WINDOW_S..=t1);
    pu.set_auto_bounds([false, true]);
}

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
) -> ScopeFrames {
    let spacing = ui.spacing().item_spacing.y;
    let h = ((ui.available_height() - (spacing * 2.0 + LEGEND_H) * N_SCOPES as f32)
        / N_SCOPES as f32)
        .max(60.0);
    let t = traces.t_now();
    let mut frames = Vec::with_capacity(N_SCOPES);
    // One scope: legend row, then the plot with the visible curves.
    let mut show = |ui: &mut egui::Ui,
                    id: &str,
                    y_label: &str,
                    unit: &'static str,
                    last: bool,
                    curves: &[(&str, Ch, Color32, Model)],
                    extra: &dyn Fn(&mut PlotUi<'_>, &BTreeSet<String>)| {
        let mut items: Vec<LegendItem<'_>> = curves
            .iter()
            .map(|&(name, _, color, m)| {
                let (w, st) = style_of(m);
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
                color: Color32::from_rgb(200, 30, 30),
                swatch: Swatch::Span,
            });
        }
        legend_ui(ui, id, &items, hidden);
        let hidden_now = hidden.clone();
        let r = scope(id, y_label, unit, h, last).show(ui, |pu| {
            window(pu, t);
            extra(pu, &hidden_now);
            for &(name, ch, color, m) in curves {
                if plotkit::hidden(&hidden_now, id, name) {
                    continue;
                }
                let (w, st) = style_of(m);
                pu.line(
                    Line::new(name.to_owned(), traces.channel(ch).points())
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
        &[
            ("platform", Ch::PlatformAcc, PLATFORM, Model::Platform),
            ("passive", Ch::PassiveAcc, PASSIVE, Model::Passive),
            ("twin", Ch::TwinAcc, TWIN, Model::Twin),
            ("linear", Ch::LinearAcc, LINEAR, Model::Linear),
        ],
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
        &[
            ("passive u", Ch::PassiveU, PASSIVE, Model::Passive),
            ("twin u", Ch::TwinU, TWIN, Model::Twin),
            ("linear u", Ch::LinearU, LINEAR, Model::Linear),
        ],
        &|pu, hidden| {
            if plotkit::hidden(hidden, "scope_stroke", "end stops, contacts") {
                return;
            }
            for &(a, b) in contacts {
                pu.span(
                    Span::new("end-stop contact", a..=b.max(a + 0.01))
                        .fill(CONTACT)
                        .border_color(Color32::from_rgb(200, 30, 30)),
                );
            }
            for y in [limit_mm, -limit_mm] {
                pu.hline(
                    HLine::new(format!("end stop ±{limit_mm:.0} mm"), y)
                        .color(Color32::from_rgb(200, 30, 30))
                        .style(LineStyle::dashed_dense()),
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
            ("p1 (upper)", Ch::P1, P1_COLOR, Model::Twin),
            ("p2 (lower)", Ch::P2, P2_COLOR, Model::Second),
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
            ("Q1", Ch::Q1, P1_COLOR, Model::Twin),
            ("Q2", Ch::Q2, P2_COLOR, Model::Second),
        ],
        &|_, _| {},
    );

    show(
        ui,
        "scope_v",
        "V_in [V]",
        "V",
        false,
        &[
            ("twin V_in", Ch::TwinVin, TWIN, Model::Twin),
            ("linear V_in", Ch::LinearVin, LINEAR, Model::Linear),
        ],
        &|_, _| {},
    );

    show(
        ui,
        "scope_xv",
        "spool x_v [mm]",
        "mm",
        true,
        &[("twin x_v", Ch::TwinXv, TWIN, Model::Twin)],
        &|_, _| {},
    );
    frames
}
