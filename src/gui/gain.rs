//! The gain slider: a rail a person can steer over gains that span decades and both signs.
//!
//! egui's logarithmic slider puts the handle under the pointer, so a 150 px rail over
//! −2000 … 200 V/m (7.6 decades down to ±0.1) moves a gain a decade every 20 px: a 40 px
//! drag took Kp from −20 to −2000. Here the rail is drawn on a symmetric-log scale
//! `s = sign(K)·log10(1 + |K|/r)` (`r`: the gain's resolution, below which it is "about
//! zero", so the rail passes through 0 and both signs), and a drag moves `s` relatively:
//! [`PX_PER_DECADE`] pixels per decade of |K|, ten times finer with Shift held
//! ([`FINE`]). A click on the rail jumps there; arrow keys step 1/50 decade (Shift: 1/500);
//! the number beside it takes typed values and Shift-drags finely as well.

use egui::{DragValue, Response, Sense, Ui, Widget, WidgetInfo};
use std::ops::RangeInclusive;

/// Drag distance per decade of |gain| \[px\].
pub const PX_PER_DECADE: f32 = 100.0;
/// How much finer a Shift-drag or Shift-arrow steps.
pub const FINE: f32 = 10.0;
/// Arrow-key step [decades].
const KEY_STEP: f64 = 0.02;

/// The symmetric-log scale of a gain with resolution `r` (> 0) [display units].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SymLog {
    /// Magnitude below which the scale is nearly linear [display units], > 0.
    pub resolution: f64,
}

impl SymLog {
    /// Position on the scale of value `v` \[decades\].
    pub fn position(self, v: f64) -> f64 {
        v.signum() * (1.0 + v.abs() / self.resolution).log10()
    }

    /// Value at position `s` \[decades\] (inverse of [`Self::position`]).
    pub fn value(self, s: f64) -> f64 {
        s.signum() * self.resolution * (10f64.powf(s.abs()) - 1.0)
    }
}

/// Rounds to `digits` significant digits (what a drag lands on: −23.4, not −23.4172).
pub fn round_significant(v: f64, digits: i32) -> f64 {
    if v == 0.0 || !v.is_finite() {
        return v;
    }
    let magnitude = v.abs().log10().floor() as i32;
    let factor = 10f64.powi(digits - 1 - magnitude);
    (v * factor).round() / factor
}

/// A gain slider (see the module docs). Use it like `egui::Slider`: `changed()` on the
/// returned response says the value moved.
pub struct GainSlider<'a> {
    value: &'a mut f64,
    span: RangeInclusive<f64>,
    scale: SymLog,
    label: &'a str,
    suffix: String,
    decimals: usize,
}

impl<'a> GainSlider<'a> {
    /// A slider over `span` [display units] with resolution `resolution` (> 0).
    pub fn new(
        value: &'a mut f64,
        span: RangeInclusive<f64>,
        resolution: f64,
        label: &'a str,
    ) -> Self {
        Self {
            value,
            span,
            scale: SymLog { resolution },
            label,
            suffix: String::new(),
            decimals: 2,
        }
    }

    /// Unit text after the number (with its leading space).
    pub fn suffix(mut self, suffix: impl Into<String>) -> Self {
        self.suffix = suffix.into();
        self
    }

    /// Most decimals shown in the number.
    pub fn decimals(mut self, decimals: usize) -> Self {
        self.decimals = decimals;
        self
    }

    fn rail_ui(&mut self, ui: &mut Ui) -> Response {
        let size = egui::vec2(ui.spacing().slider_width, ui.spacing().interact_size.y);
        let (rect, mut response) = ui.allocate_exact_size(size, Sense::click_and_drag());
        let id = response.id;
        let sc = self.scale;
        let (s_lo, s_hi) = (
            sc.position(*self.span.start()),
            sc.position(*self.span.end()),
        );
        let radius = (rect.height() / 2.5).round();
        let rail = rect.shrink2(egui::vec2(radius, 0.0));
        let x_of = |s: f64| {
            rail.left() + ((s - s_lo) / (s_hi - s_lo)).clamp(0.0, 1.0) as f32 * rail.width()
        };
        let old = *self.value;
        let fine = ui.input(|i| i.modifiers.shift);
        let per_px = 1.0 / f64::from(PX_PER_DECADE * if fine { FINE } else { 1.0 });
        let digits = if fine { 4 } else { 3 };
        let mut new = old;

        if response.dragged() {
            // The unrounded position lives in memory, so rounding never stalls a slow drag.
            let start = if response.drag_started() {
                None
            } else {
                ui.data(|d| d.get_temp::<f64>(id))
            };
            let s0 = start.unwrap_or_else(|| sc.position(old));
            let dx = f64::from(response.drag_delta().x);
            let s = (s0 + dx * per_px).clamp(s_lo, s_hi);
            ui.data_mut(|d| d.insert_temp(id, s));
            if dx != 0.0 {
                new = round_significant(sc.value(s), digits);
            }
        } else if response.clicked()
            && let Some(p) = response.interact_pointer_pos()
        {
            let s = s_lo + f64::from((p.x - rail.left()) / rail.width()) * (s_hi - s_lo);
            new = round_significant(sc.value(s.clamp(s_lo, s_hi)), 3);
        }
        if response.has_focus() {
            ui.memory_mut(|m| {
                m.set_focus_lock_filter(
                    id,
                    egui::EventFilter {
                        horizontal_arrows: true,
                        ..Default::default()
                    },
                )
            });
            let steps = ui.input(|i| {
                i.num_presses(egui::Key::ArrowRight) as f64
                    - i.num_presses(egui::Key::ArrowLeft) as f64
            });
            if steps != 0.0 {
                let step = KEY_STEP / if fine { f64::from(FINE) } else { 1.0 };
                let s = (sc.position(old) + steps * step).clamp(s_lo, s_hi);
                new = round_significant(sc.value(s), digits);
            }
        }
        if let Some(v) = accesskit_set_value(ui, id) {
            new = v;
        }
        if new != old {
            *self.value = new;
            response.mark_changed();
        }

        response.widget_info(|| WidgetInfo::slider(ui.is_enabled(), *self.value, self.label));
        let (lo, hi) = (*self.span.start(), *self.span.end());
        ui.ctx().accesskit_node_builder(id, |b| {
            b.set_min_numeric_value(lo);
            b.set_max_numeric_value(hi);
            b.add_action(egui::accesskit::Action::SetValue);
        });

        if ui.is_rect_visible(rect) {
            let visuals = ui.style().interact(&response);
            let painter = ui.painter();
            let rail_rect =
                egui::Rect::from_center_size(rect.center(), egui::vec2(rect.width(), radius));
            painter.rect_filled(
                rail_rect,
                radius / 2.0,
                ui.visuals().widgets.inactive.bg_fill,
            );
            if s_lo < 0.0 && s_hi > 0.0 {
                // Zero: where the sign changes.
                let x = x_of(0.0);
                painter.vline(
                    x,
                    rect.center().y - radius..=rect.center().y + radius,
                    ui.visuals().widgets.noninteractive.fg_stroke,
                );
            }
            let x = x_of(sc.position(*self.value));
            painter.circle(
                egui::pos2(x, rect.center().y),
                radius,
                visuals.bg_fill,
                visuals.fg_stroke,
            );
        }
        response
    }
}

fn accesskit_set_value(ui: &Ui, id: egui::Id) -> Option<f64> {
    use egui::accesskit::{Action, ActionData};
    ui.input(|i| {
        i.accesskit_action_requests(id, Action::SetValue)
            .filter_map(|r| match r.data {
                Some(ActionData::NumericValue(v)) => Some(v),
                _ => None,
            })
            .last()
    })
}

impl Widget for GainSlider<'_> {
    fn ui(mut self, ui: &mut Ui) -> Response {
        ui.horizontal(|ui| {
            let mut response = self.rail_ui(ui);
            // Typed entry; a drag on the number changes |K| by about 0.5 % per pixel.
            let mut typed = *self.value;
            let speed = typed.abs().max(self.scale.resolution) * 0.005;
            let number = ui.add(
                DragValue::new(&mut typed)
                    .speed(speed)
                    .suffix(self.suffix.clone())
                    .max_decimals(self.decimals)
                    .min_decimals(self.decimals.min(2))
                    .update_while_editing(false),
            );
            if number.changed() && typed != *self.value {
                *self.value = typed;
                response.mark_changed();
            }
            let label = ui.label(self.label);
            response = response.labelled_by(label.id);
            response.union(number)
        })
        .inner
    }
}
