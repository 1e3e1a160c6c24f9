//! The A/B view: a second twin in the engine thread runs a reference controller (B) on the
//! same plant and the same excitation as the live one (A). The scopes overlay B on A, the
//! metrics stand side by side with the difference in %, and the frequency plots draw B's
//! transmissibility with A's. Off by default: B costs a second twin.

use super::format::controller_text;
use super::frequency::{Analytic, Curves};
use super::traces::{AbMetrics, difference_percent};
use super::units::MM_PER_M;
use crate::params::{ControllerParams, Params};

/// What the A/B panel asks the app to do.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum AbAction {
    /// Nothing.
    None,
    /// Switch A/B on or off, or a new reference: send it to the engine.
    Send,
}

/// The A/B state: on/off, the reference controller (default: the paper's gains) and its
/// analytic curves.
#[derive(Default)]
pub struct AbView {
    on: bool,
    reference: ControllerParams,
    analytic: Analytic,
}

/// The reference twin's parameters: the live plant with the reference controller.
pub fn reference_params(params: &Params, reference: ControllerParams) -> Params {
    Params {
        controller: reference,
        ..*params
    }
}

impl AbView {
    /// Whether A/B runs.
    pub fn is_on(&self) -> bool {
        self.on
    }

    /// The reference's curves as last drawn (the view updates them every frame), if A/B is
    /// on: what an export shows.
    pub fn drawn_curves(&self) -> Option<&Curves> {
        self.on.then(|| self.analytic.curves())
    }

    /// The reference controller (B).
    pub fn reference(&self) -> ControllerParams {
        self.reference
    }

    /// Switches A/B on or off.
    pub fn set_on(&mut self, on: bool) {
        self.on = on;
    }

    /// Pins a controller as the reference.
    pub fn set_reference(&mut self, c: ControllerParams) {
        self.reference = c;
    }

    /// What the engine should run as B (`None`: off).
    pub fn command(&self) -> Option<ControllerParams> {
        self.on.then_some(self.reference)
    }

    /// B's analytic curves for the live plant, recomputed when the plant or B changed;
    /// `None` while A/B is off.
    pub fn curves(&mut self, params: &Params) -> Option<&Curves> {
        if !self.on {
            return None;
        }
        self.analytic
            .update(&reference_params(params, self.reference));
        Some(self.analytic.curves())
    }

    /// The A/B controls: the switch, what B is, "Set current as reference".
    pub fn controls_ui(&mut self, ui: &mut egui::Ui, current: &ControllerParams) -> AbAction {
        let mut action = AbAction::None;
        let was_on = self.on;
        if ui
            .checkbox(&mut self.on, "A/B: compare with a reference twin")
            .on_hover_text(
                "Runs a second twin (B) with the reference controller on the same plant and \
                 excitation as the live twin (A). Costs a second twin in the engine thread.",
            )
            .changed()
        {
            action = AbAction::Send;
        }
        ui.weak(format!("B = {}", controller_text(&self.reference)));
        ui.horizontal(|ui| {
            if ui
                .add_enabled(
                    self.reference != *current,
                    egui::Button::new("Set current as reference"),
                )
                .on_hover_text("B runs the controller now on the sliders (A and B restart).")
                .clicked()
            {
                self.reference = *current;
                // A new reference while off is sent when A/B goes on.
                if was_on {
                    action = AbAction::Send;
                }
            }
            if ui
                .add_enabled(
                    self.reference != ControllerParams::default(),
                    egui::Button::new("Paper's gains"),
                )
                .on_hover_text("B runs the paper's controller, Kp = −5 V/m, Ki = −7.5 V·s/m.")
                .clicked()
            {
                self.reference = ControllerParams::default();
                if was_on {
                    action = AbAction::Send;
                }
            }
        });
        action
    }
}

/// The A/B metrics side by side: a_w, VDV, max |u| and contacts of A and B, and A against B
/// in %.
pub fn metrics_ui(ui: &mut egui::Ui, m: Option<AbMetrics>, contacts: (usize, usize)) {
    ui.strong("A/B: live twin (A) against the reference (B)");
    let Some(m) = m else {
        ui.weak("waiting for B's first settled second…");
        return;
    };
    let pct = |a: f64, b: f64| {
        let d = difference_percent(a, b);
        if d.is_finite() {
            format!("{d:+.1} %")
        } else {
            "–".into()
        }
    };
    crate::gui::plotkit::table_ui(
        ui,
        "ab_metrics",
        &["", "A (live)", "B (ref)", "A vs B"],
        |ui| {
            let rows = [
                ("a_w [m/s²]", m.a.aw, m.b.aw, 3),
                ("VDV [m/s^1.75]", m.a.vdv, m.b.vdv, 3),
                (
                    "max |u| [mm]",
                    m.max_u_a * MM_PER_M,
                    m.max_u_b * MM_PER_M,
                    1,
                ),
                ("contacts", contacts.0 as f64, contacts.1 as f64, 0),
            ];
            for (name, a, b, dec) in rows {
                ui.label(name);
                ui.monospace(format!("{a:.dec$}"));
                ui.monospace(format!("{b:.dec$}"));
                ui.monospace(pct(a, b));
                ui.end_row();
            }
        },
    );
}
