//! Live scrolling scopes (egui_plot): the last [`WINDOW_S`] seconds of accelerations, stroke
//! (with the end stops and contacts), pressures, flows, command and spool. The lines borrow
//! the trace buffers; nothing is copied per frame.

use super::frequency::{LINEAR, PASSIVE, PLATFORM, TWIN};
use super::traces::{Ch, Traces, WINDOW_S};
use super::units::MM_PER_M;
use crate::params::Params;
use egui::Color32;
use egui_plot::{Corner, HLine, Legend, Line, LineStyle, Plot, PlotUi, Span};

/// Upper chamber colour.
const P1_COLOR: Color32 = Color32::from_rgb(214, 39, 40);
/// Lower chamber colour.
const P2_COLOR: Color32 = Color32::from_rgb(148, 103, 189);
/// End-stop contact highlight.
const CONTACT: Color32 = Color32::from_rgba_premultiplied(200, 30, 30, 60);

/// Number of scopes stacked in [`scopes_ui`].
pub const N_SCOPES: usize = 6;

fn scope<'a>(id: &str, y_label: &str, height: f32, show_x_label: bool) -> Plot<'a> {
    let p = Plot::new(id)
        .height(height)
        .y_axis_label(y_label.to_owned())
        .y_axis_min_width(44.0)
        .allow_drag(false)
        .allow_zoom(false)
        .allow_scroll(false)
        .allow_boxed_zoom(false)
        .allow_double_click_reset(false)
        .link_cursor(egui::Id::unique("scopes"), [true, false])
        .x_grid_spacer(egui_plot::uniform_grid_spacer(|_| [0.5, 1.0, 5.0]))
        .legend(
            Legend::default()
                .position(Corner::LeftTop)
                .text_style(egui::TextStyle::Small)
                .background_alpha(0.6),
        );
    if show_x_label {
        p.x_axis_label("time [s]")
    } else {
        p
    }
}

fn window(pu: &mut PlotUi<'_>, t_now: f64) {
    let t1 = t_now.max(WINDOW_S);
    pu.set_plot_bounds_x(t1 - WINDOW_S..=t1);
    pu.set_auto_bounds([false, true]);
}

/// Draws the six scopes, sharing the available height.
pub fn scopes_ui(ui: &mut egui::Ui, traces: &Traces, params: &Params) {
    let spacing = ui.spacing().item_spacing.y;
    let h = ((ui.available_height() - spacing * N_SCOPES as f32) / N_SCOPES as f32).max(70.0);
    let t = traces.t_now();
    let line = |name: &str, ch: Ch, color: Color32| {
        Line::new(name.to_owned(), traces.channel(ch).points())
            .color(color)
            .width(1.5)
    };

    scope("scope_acc", "accel. [m/s²]", h, false).show(ui, |pu| {
        window(pu, t);
        pu.line(line("platform", Ch::PlatformAcc, PLATFORM).width(1.0));
        pu.line(line("passive", Ch::PassiveAcc, PASSIVE));
        pu.line(line("linear", Ch::LinearAcc, LINEAR));
        pu.line(line("twin", Ch::TwinAcc, TWIN));
    });

    let limit_mm = params.cylinder.stroke_m / 2.0 * MM_PER_M;
    scope("scope_stroke", "stroke u [mm]", h, false).show(ui, |pu| {
        window(pu, t);
        for &(a, b) in traces.contacts() {
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
        pu.line(line("passive u", Ch::PassiveU, PASSIVE));
        pu.line(line("linear u", Ch::LinearU, LINEAR));
        pu.line(line("twin u", Ch::TwinU, TWIN));
    });

    scope("scope_p", "pressure [bar]", h, false).show(ui, |pu| {
        window(pu, t);
        pu.line(line("p1 (upper)", Ch::P1, P1_COLOR));
        pu.line(line("p2 (lower)", Ch::P2, P2_COLOR));
    });

    scope("scope_q", "flow [L/min]", h, false).show(ui, |pu| {
        window(pu, t);
        pu.line(line("Q1", Ch::Q1, P1_COLOR));
        pu.line(line("Q2", Ch::Q2, P2_COLOR));
    });

    scope("scope_v", "V_in [V]", h, false).show(ui, |pu| {
        window(pu, t);
        pu.line(line("linear V_in", Ch::LinearVin, LINEAR));
        pu.line(line("twin V_in", Ch::TwinVin, TWIN));
    });

    scope("scope_xv", "spool x_v [mm]", h, true).show(ui, |pu| {
        window(pu, t);
        pu.line(line("twin x_v", Ch::TwinXv, TWIN));
    });
}
