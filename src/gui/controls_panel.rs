//! The left panel: the parameters (sliders with their refused values beside them, the
//! message of a parameter set that was not applied, the model effects on, Revert), then the
//! Tune, A/B and Excitation sections. It owns the refusals; the parameters, the Tune and A/B
//! views and the excitation editor are lent to it, and what needs the engine or a file comes
//! back as [`ControlsAction`]s.

use super::ab::{AbAction, AbView};
use super::controls::{self, ExcitationAction, ExcitationEditor, FieldErrors};
use super::files::Purpose;
use super::format::active_effects;
use super::job::Waker;
use super::style;
use super::tune::{TuneAction, TunePanel};
use crate::params::{ControllerParams, Params};
use egui::RichText;

/// What the controls panel asks the app to do.
#[derive(Debug, Clone, PartialEq)]
pub enum ControlsAction {
    /// A slider or field changed the parameters: validate and send them.
    ParamsEdited,
    /// Put back the preset's parameters.
    Revert,
    /// Set these tuned gains on the live controller.
    ApplyTuned(ControllerParams),
    /// A/B switched or a new reference: send it to the engine.
    SendReference,
    /// The excitation editor's action.
    Excitation(ExcitationAction),
}

/// What the panel shows this frame and does not own.
pub struct ControlsInput<'a> {
    /// The parameters being edited (SI).
    pub params: &'a mut Params,
    /// The parameters differ from the preset's (Revert is enabled).
    pub modified: bool,
    /// The Tune panel.
    pub tune: &'a mut TunePanel,
    /// The A/B view.
    pub ab: &'a mut AbView,
    /// The excitation editor (a persisted setting).
    pub excitation: &'a mut ExcitationEditor,
    /// Wakes the app from the Tune job.
    pub waker: &'a Waker,
    /// The file dialog open, if any.
    pub dialog_open: Option<Purpose>,
}

/// The controls panel's state: the values it refused.
#[derive(Default)]
pub struct ControlsPanel {
    field_errors: FieldErrors,
    param_error: Option<String>,
}

impl ControlsPanel {
    /// Refused parameter values, by control label (shown next to the control).
    pub fn field_errors(&self) -> &FieldErrors {
        &self.field_errors
    }

    /// The refusals, to edit through the same path as a slider or to clear them.
    pub fn field_errors_mut(&mut self) -> &mut FieldErrors {
        &mut self.field_errors
    }

    /// Why the last parameter set was not applied (`None`: it was).
    pub fn set_param_error(&mut self, error: Option<String>) {
        self.param_error = error;
    }

    /// Forgets every refusal (new parameters: the messages were about the old ones).
    pub fn clear(&mut self) {
        self.field_errors.clear();
        self.param_error = None;
    }

    /// The panel's contents.
    pub fn ui(&mut self, ui: &mut egui::Ui, input: ControlsInput<'_>) -> Vec<ControlsAction> {
        let ControlsInput {
            params,
            modified,
            tune,
            ab,
            excitation,
            waker,
            dialog_open,
        } = input;
        let mut actions = Vec::new();
        ui.heading("Parameters");
        if controls::params_ui(ui, params, &mut self.field_errors) {
            actions.push(ControlsAction::ParamsEdited);
        }
        if let Some(e) = &self.param_error {
            ui.colored_label(style::ERROR_TEXT, e);
        }
        let effects = active_effects(params);
        ui.label(RichText::new("Model effects").strong());
        if effects.is_empty() {
            ui.weak("none (the paper's model)");
        } else {
            for e in effects {
                ui.label(format!("on: {e}"));
            }
        }
        ui.horizontal(|ui| {
            if ui
                .add_enabled(modified, egui::Button::new("Revert to preset"))
                .clicked()
            {
                actions.push(ControlsAction::Revert);
            }
        });
        egui::CollapsingHeader::new("Tune")
            .default_open(false)
            .show(ui, |ui| {
                if let TuneAction::Apply(c) = tune.ui(ui, params, waker) {
                    actions.push(ControlsAction::ApplyTuned(c));
                }
            });
        ui.separator();
        ui.heading("A/B comparison");
        if ab.controls_ui(ui, &params.controller) == AbAction::Send {
            actions.push(ControlsAction::SendReference);
        }
        ui.separator();
        ui.heading("Excitation");
        match controls::excitation_ui(ui, excitation, params.plant.body.mass_kg) {
            ExcitationAction::None => {}
            other => actions.push(ControlsAction::Excitation(other)),
        }
        if let Some(p) = dialog_open {
            ui.weak(format!("file dialog open ({p:?})…"));
        }
        actions
    }
}
