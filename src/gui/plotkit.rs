//! Shared plot and table furniture: y axes that always carry numbers, a clickable legend
//! drawn above the plot (off the data) with a swatch per line style, wrapped phase, and the
//! striped tables with a header row.

use egui::{Color32, Pos2, Sense, Shape, Stroke, pos2, vec2};
use egui_plot::{AxisHints, GridInput, GridMark, LineStyle};
use std::collections::BTreeSet;

/// Width reserved for every y axis (tick numbers and the axis title), so that stacked plots
/// have their data areas on the same x positions.
pub const Y_AXIS_WIDTH: f32 = 64.0;

/// Fewest pixels between two labelled y ticks (the axis of [`y_axis`] draws every label
/// at full strength from 16 px apart).
const MIN_TICK_PX: f64 = 22.0;

/// A y axis whose tick labels are all drawn in full (egui_plot's default fades labels
/// closer than 30 px and hides them below 20 px, which left a short scope with only "0"),
/// with [`y_tick`] numbers and the common width [`Y_AXIS_WIDTH`].
pub fn y_axis<'a>(label: &str) -> AxisHints<'a> {
    AxisHints::new_y()
        .label(label.to_owned())
        .formatter(y_tick)
        .min_thickness(Y_AXIS_WIDTH)
        .label_spacing(14.0..=16.0)
}

/// A "nice" step (1, 2, 2.5 or 5 × 10^k) at least `min_step`.
pub fn nice_step(min_step: f64) -> f64 {
    if !(min_step.is_finite() && min_step > 0.0) {
        return 1.0;
    }
    let e = min_step.log10().floor();
    let base = 10f64.powf(e);
    for m in [1.0, 2.0, 2.5, 5.0, 10.0] {
        if m * base >= min_step * (1.0 - 1e-9) {
            return m * base;
        }
    }
    10.0 * base
}

/// Y grid marks: one step for the whole axis, chosen so that the marks are at least
/// `MIN_TICK_PX` apart on a plot `height_px` high, and at most about six in view. Every
/// mark gets the same step size, so all of them are labelled, however small the amplitude
/// (a ±0.004 m/s² trace reads −0.004, −0.002, 0, 0.002, 0.004).
pub fn y_marks(input: GridInput, height_px: f32) -> Vec<GridMark> {
    marks(input, height_px, MIN_TICK_PX as f32)
}

/// Grid marks of one step on an axis `length_px` long, at least `min_px` apart and at most
/// about eight in view (see [`y_marks`]; x axes need wider gaps for their labels).
pub fn marks(input: GridInput, length_px: f32, min_px: f32) -> Vec<GridMark> {
    let (lo, hi) = input.bounds;
    let span = hi - lo;
    if !(span.is_finite() && span > 0.0) {
        return Vec::new();
    }
    let by_pixels = span * f64::from(min_px) / f64::from(length_px.max(1.0));
    let step = nice_step(by_pixels.max(span / 8.0));
    let first = (lo / step).ceil() as i64;
    let last = (hi / step).floor() as i64;
    (first..=last.min(first + 100))
        .map(|k| GridMark {
            value: k as f64 * step,
            step_size: step,
        })
        .collect()
}

/// Tick text for a y mark: as many decimals as the step needs, no more (0.002, 12.5, 100).
pub fn y_tick(mark: GridMark, _range: &std::ops::RangeInclusive<f64>) -> String {
    let step = mark.step_size.abs();
    let decimals = if step > 0.0 && step.is_finite() {
        (-step.log10().floor()).clamp(0.0, 8.0) as usize
    } else {
        0
    };
    let v = if mark.value.abs() < step * 1e-6 {
        0.0
    } else {
        mark.value
    };
    let s = format!("{v:.decimals$}");
    // Typographic minus, as elsewhere in the app.
    s.replacen('-', "−", 1)
}

/// Wraps a phase in degrees into (−180°, 180°].
pub fn wrap_deg(d: f64) -> f64 {
    let w = (d + 180.0).rem_euclid(360.0) - 180.0;
    if w == -180.0 { 180.0 } else { w }
}

/// How an item is drawn, for its legend swatch.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Swatch {
    /// A line of the given width and style.
    Line(f32, LineStyle),
    /// Filled markers.
    Marker,
    /// A shaded span.
    Span,
}

/// One legend entry.
pub struct LegendItem<'a> {
    /// Name (also the key for hiding it).
    pub name: &'a str,
    /// Colour.
    pub color: Color32,
    /// Swatch.
    pub swatch: Swatch,
}

/// The hidden-curve key of `name` in plot `plot`.
pub fn key(plot: &str, name: &str) -> String {
    format!("{plot}/{name}")
}

/// Whether `name` in `plot` is hidden.
pub fn hidden(hidden: &BTreeSet<String>, plot: &str, name: &str) -> bool {
    hidden.contains(&key(plot, name))
}

/// A striped table: a bold header row, then the rows `body` adds (each closed by
/// `ui.end_row()`), one column per header.
pub fn table_ui(ui: &mut egui::Ui, id: &str, headers: &[&str], body: impl FnOnce(&mut egui::Ui)) {
    egui::Grid::new(id)
        .striped(true)
        .num_columns(headers.len())
        .show(ui, |ui| {
            for h in headers {
                ui.strong(*h);
            }
            ui.end_row();
            body(ui);
        });
}

/// A fixed-width progress bar reading "done/total", then a cancel button (at a fixed place,
/// so it does not move while the count changes). Returns whether the button was clicked.
pub fn progress_cancel_ui(ui: &mut egui::Ui, done: usize, total: usize, cancel: &str) -> bool {
    ui.add(
        egui::ProgressBar::new(done as f32 / total.max(1) as f32)
            .desired_width(120.0)
            .text(format!("{done}/{total}")),
    );
    ui.button(cancel).clicked()
}

/// Width of a legend swatch [px].
const SWATCH_W: f32 = 22.0;

/// A legend row above a plot: each entry a toggle (click hides or shows the curve), with a
/// swatch of its colour and style. Hidden entries are drawn faint. Each entry is one widget
/// of a known size, so the row wraps within the column however many entries it has (a
/// nested layout per entry would not wrap, and would widen the column instead).
pub fn legend_ui(
    ui: &mut egui::Ui,
    plot: &str,
    items: &[LegendItem<'_>],
    hidden_set: &mut BTreeSet<String>,
) {
    ui.horizontal_wrapped(|ui| {
        ui.spacing_mut().item_spacing.x = 6.0;
        for it in items {
            let k = key(plot, it.name);
            let shown = !hidden_set.contains(&k);
            if legend_entry(ui, it, shown)
                .on_hover_text("click to hide or show this curve")
                .clicked()
            {
                if shown {
                    hidden_set.insert(k);
                } else {
                    hidden_set.remove(&k);
                }
            }
        }
    });
}

/// One legend entry: swatch and name in a selectable frame, allocated at its full size.
fn legend_entry(ui: &mut egui::Ui, it: &LegendItem<'_>, shown: bool) -> egui::Response {
    let text = egui::RichText::new(it.name).small();
    let text = if shown {
        text
    } else {
        text.weak().strikethrough()
    };
    let galley = egui::WidgetText::from(text).into_galley(
        ui,
        Some(egui::TextWrapMode::Extend),
        f32::INFINITY,
        egui::TextStyle::Small,
    );
    let pad = vec2(4.0, 1.0);
    let gap = 2.0;
    let size = vec2(
        SWATCH_W + gap + galley.size().x + 2.0 * pad.x,
        galley.size().y.max(12.0) + 2.0 * pad.y,
    );
    let (rect, response) = ui.allocate_exact_size(size, Sense::click());
    response.widget_info(|| {
        egui::WidgetInfo::selected(
            egui::accesskit::Role::Button,
            ui.is_enabled(),
            shown,
            it.name,
        )
    });
    if ui.is_rect_visible(rect) {
        let visuals = ui.style().interact_selectable(&response, shown);
        let text_rect = egui::Rect::from_min_size(
            pos2(rect.left() + SWATCH_W + gap, rect.top()),
            vec2(galley.size().x + 2.0 * pad.x, rect.height()),
        );
        if shown || response.hovered() {
            ui.painter()
                .rect_filled(text_rect, visuals.corner_radius, visuals.weak_bg_fill);
        }
        let c = if shown {
            it.color
        } else {
            it.color.gamma_multiply(0.3)
        };
        let swatch = egui::Rect::from_min_size(
            pos2(rect.left(), rect.center().y - 6.0),
            vec2(SWATCH_W, 12.0),
        );
        paint_swatch(ui, swatch, c, it.swatch);
        let text_pos = pos2(
            text_rect.left() + pad.x,
            text_rect.center().y - galley.size().y / 2.0,
        );
        ui.painter().galley(text_pos, galley, visuals.text_color());
    }
    response
}

fn paint_swatch(ui: &egui::Ui, rect: egui::Rect, c: Color32, s: Swatch) {
    let p = ui.painter();
    let (y, x0, x1) = (rect.center().y, rect.left() + 1.0, rect.right() - 1.0);
    match s {
        Swatch::Line(w, LineStyle::Solid) => {
            p.line_segment([pos2(x0, y), pos2(x1, y)], Stroke::new(w, c));
        }
        Swatch::Line(w, LineStyle::Dashed { .. }) => {
            p.extend(Shape::dashed_line(
                &[pos2(x0, y), pos2(x1, y)],
                Stroke::new(w, c),
                5.0,
                3.0,
            ));
        }
        Swatch::Line(w, LineStyle::Dotted { .. }) => {
            p.extend(Shape::dotted_line(
                &[pos2(x0, y), pos2(x1, y)],
                c,
                4.0,
                w * 0.6,
            ));
        }
        Swatch::Marker => {
            p.circle_filled(Pos2::new(rect.center().x, y), 4.0, c);
        }
        Swatch::Span => {
            p.rect_filled(rect.shrink(1.0), 1.0, c);
        }
    }
}

/// The key of presentation mode in egui's memory (read by every plot line).
fn presentation_id() -> egui::Id {
    egui::Id::unique("seat_twin_presentation")
}

/// Presentation mode on or off for the plots: their lines are drawn [`PRESENTATION_LINE`]
/// times as thick.
pub fn set_presentation(ctx: &egui::Context, on: bool) {
    ctx.data_mut(|d| d.insert_temp(presentation_id(), on));
}

/// How much thicker plot lines are in presentation mode.
pub const PRESENTATION_LINE: f32 = 2.0;

/// A plot line's width \[points\] in the current mode: `width`, or thicker in presentation
/// mode.
pub fn line_width(ctx: &egui::Context, width: f32) -> f32 {
    let on = ctx
        .data(|d| d.get_temp::<bool>(presentation_id()))
        .unwrap_or(false);
    if on { width * PRESENTATION_LINE } else { width }
}
