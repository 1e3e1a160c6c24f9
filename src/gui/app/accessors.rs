//! Read access to the app's state, for tests, the web page's API and the debug overlay:
//! plain getters, no behaviour.

use super::*;

impl SeatTwinApp {
    /// The parameters being edited (SI).
    pub fn params(&self) -> &Params {
        &self.params
    }

    /// The parameters the engine last reported running with.
    pub fn engine_params(&self) -> Option<&Params> {
        self.engine.view.params.as_ref()
    }

    /// What the engine last reported.
    pub fn engine_view(&self) -> &EngineView {
        &self.engine.view
    }

    /// Whether the user wants the simulation running (space bar / Run button).
    pub fn wants_running(&self) -> bool {
        self.engine.want_running
    }

    /// The engine's error, if it stopped.
    pub fn engine_error(&self) -> Option<&str> {
        self.engine.error.as_deref()
    }

    /// The analytic frequency curves shown.
    pub fn curves(&self) -> &Curves {
        self.centre.curves()
    }

    /// The simulated (sine dwell) frequency points of the twin.
    pub fn dwell(&self) -> &Dwell {
        self.centre.dwell()
    }

    /// The live traces.
    pub fn traces(&self) -> &Traces {
        &self.traces
    }

    /// The current preset.
    pub fn preset(&self) -> &PresetInfo {
        &self.preset
    }

    /// The message line.
    pub fn notice(&self) -> Option<&Notice> {
        self.notice.as_ref()
    }

    /// Whether the "discard unsaved changes?" prompt is showing.
    pub fn is_confirm_open(&self) -> bool {
        self.files.is_confirm_open()
    }

    /// Frame timing.
    pub fn frame_stats(&self) -> &FrameStats {
        &self.window.stats
    }

    /// Refused parameter values, by control label (shown next to the control).
    pub fn field_errors(&self) -> &controls::FieldErrors {
        self.controls.field_errors()
    }

    /// Curves switched off in the legends (`plot/name`).
    pub fn hidden_curves(&self) -> &BTreeSet<String> {
        self.centre.hidden_curves()
    }

    /// The last gains with which both loops were stable.
    pub fn last_stable_gains(&self) -> Option<ControllerParams> {
        self.centre.last_stable()
    }

    /// The scopes' data areas drawn last frame, top to bottom.
    pub fn scope_frames(&self) -> &[egui::Rect] {
        self.centre.scope_frames()
    }

    /// The typed-path prompt shown when no file dialog is available: purpose and text.
    pub fn path_prompt(&self) -> Option<&(Purpose, String)> {
        self.files.path_prompt()
    }

    /// The shipped presets `(name, file)` in the Presets menu.
    pub fn shipped_presets(&self) -> &[(String, PathBuf)] {
        &self.shipped
    }

    /// The Tune panel.
    pub fn tune_panel(&self) -> &crate::gui::tune::TunePanel {
        &self.tune
    }

    /// The Tune panel, to drive it (tests, menus).
    pub fn tune_panel_mut(&mut self) -> &mut crate::gui::tune::TunePanel {
        &mut self.tune
    }

    /// The A/B state.
    pub fn ab(&self) -> &AbView {
        &self.ab
    }

    /// The measured-data window's state.
    pub fn measured(&self) -> &MeasuredData {
        &self.measured
    }

    /// The measured-data window's state, to drive it (tests, dialogs).
    pub fn measured_mut(&mut self) -> &mut MeasuredData {
        &mut self.measured
    }
}
