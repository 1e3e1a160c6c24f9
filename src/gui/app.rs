//! The app: the views, the parameters and the preset, and the one place where the views'
//! actions are applied.
//!
//! Each window and panel owns its state and returns actions (egui's View pattern):
//! [`CentreView`] (engine banner, scopes, frequency plots), [`ControlsPanel`] (parameters,
//! Tune, A/B, excitation), [`FilesView`] (dialogs, path prompt, discard question),
//! [`MeasuredData`], [`AbView`], [`TunePanel`] and the Lessons panel in [`Teaching`]. The app
//! lends them what they share (parameters, traces, settings), and carries out what comes
//! back: it alone sends to the engine ([`EngineLink`]) and changes the parameters.
//!
//! [`SeatTwinApp::ui`] does all the per-frame work and needs only an `egui::Ui`, so the
//! kittest tests drive the real app headless; the `eframe::App` impl adds persistence, the
//! window title and the frame-time readout.

mod accessors;
mod engine_link;
mod export;
mod file_ops;
mod panels;
mod state;
mod teaching;

pub use engine_link::{EngineLink, EngineView};
pub use state::{FrameStats, Notice, PresetInfo, WindowState, fitted_window};

pub use teaching::{PRESENTATION_SCALE, Teaching};

use super::ab::{self, AbView};
use super::centre::{CentreAction, CentreInput, CentreView};
use super::controls::{self, ExcitationAction, ExcitationKind, LoadedRecord};
use super::controls_panel::{ControlsAction, ControlsInput, ControlsPanel};
use super::files::{self, CsvTable, Purpose};
use super::files_view::{FileAction, FilesView, Pending};
use super::frequency::{Curves, Dwell};
use super::job::Waker;
use super::measured::{MeasuredAction, MeasuredData};
use super::schematic;
use super::session::{self, Session, SessionAb, SessionTune, SessionView};
use super::settings::{Settings, Theme};
use super::traces::{Ch, Traces};
use super::tune::TunePanel;
use super::units::{BAR_PER_PA, MM_PER_M};
use crate::engine::{Command, Speed};
use crate::params::{ControllerParams, Params};
use crate::plot::{Figure, Panel, Rgb, Scale, Series};
use crate::preset::{self, Preset, PresetMeta};
use egui::{Color32, Key, RichText};
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Duration;
use web_time::Instant;

/// Wall time the engine may step in one frame on the web, where it has no thread of its own
/// (at 60 frames a second this leaves about 4 ms for the UI).
const ENGINE_BUDGET: Duration = Duration::from_millis(12);
/// Wall time per frame for the engine and background jobs together on the web: jobs
/// ([`super::job::pump`]) get what the engine left, at least [`JOB_MIN_BUDGET`] (a step
/// longer than that still runs whole).
const FRAME_WORK_BUDGET: Duration = Duration::from_millis(14);
/// The least wall time per frame for background jobs on the web.
const JOB_MIN_BUDGET: Duration = Duration::from_millis(4);

/// Longest wait between a wake from a worker (engine, jobs) and the frame that shows it.
const REPAINT_PERIOD: Duration = Duration::from_millis(33);

/// The scales offered in the View menu.
pub const UI_SCALES: [f32; 6] = [0.8, 1.0, 1.25, 1.5, 1.75, 2.0];

/// How long an information notice stays (errors stay until replaced).
const NOTICE_LIFETIME: Duration = Duration::from_secs(8);

/// The seat-twin desktop app.
pub struct SeatTwinApp {
    /// Persisted settings.
    pub settings: Settings,
    /// The parameters being edited (SI); the engine runs them once validated.
    params: Params,
    /// The preset they came from (the "modified" marker compares against it).
    preset: PresetInfo,
    /// The shipped presets `(name, file)` of the Presets menu.
    shipped: Vec<(String, PathBuf)>,
    /// The engine: commands out, events in, its last status and error.
    engine: EngineLink,
    /// The live traces the engine sent (the scopes, metrics and exports read them).
    traces: Traces,
    /// The centre: engine banner, scopes, frequency plots.
    centre: CentreView,
    /// Dialogs, writes, the typed-path prompt and the discard question.
    files: FilesView,
    /// The message line under the toolbar.
    notice: Option<Notice>,
    /// The window: title, fitted size, frame timings.
    window: WindowState,
    /// The measured-data window.
    measured: MeasuredData,
    /// The left panel: parameters, Tune, A/B, excitation.
    controls: ControlsPanel,
    /// The A/B view (its controls are in the left panel, its curves in the centre).
    ab: AbView,
    /// The Tune panel (in the left panel).
    tune: TunePanel,
    /// Lessons, presentation mode, setup links.
    teach: Teaching,
}

impl SeatTwinApp {
    /// Builds the app: loads the last preset (or the paper's), starts the engine. `waker`
    /// is called by the engine and the worker threads when something arrived (the app
    /// passes `ctx.request_repaint()`, tests a no-op).
    pub fn new(settings: Settings, waker: impl Fn() + Send + Sync + 'static) -> Self {
        let waker: Waker = Arc::new(waker);
        let mut notice = None;
        let (preset, path) = match settings.last_preset.as_deref() {
            Some(p) => match Preset::load(p) {
                Ok(pr) => (pr, Some(p.to_path_buf())),
                Err(e) => {
                    notice = Some(Notice {
                        text: format!("the last preset could not be loaded: {e}"),
                        error: true,
                        at: Instant::now(),
                    });
                    (Preset::paper(), None)
                }
            },
            None => (
                preset::resolve("paper").unwrap_or_else(|_| Preset::paper()),
                None,
            ),
        };
        let user_file = path.is_some();
        let params = preset.params;
        let engine = EngineLink::spawn(&params, waker.clone());
        let measured = MeasuredData::new(waker.clone());
        let mut app = Self {
            params,
            preset: PresetInfo {
                name: if preset.meta.name.is_empty() {
                    "paper".into()
                } else {
                    preset.meta.name.clone()
                },
                description: preset.meta.description.clone(),
                path,
                user_file,
                baseline: params,
            },
            shipped: preset::shipped_presets(),
            engine,
            traces: Traces::new(),
            centre: CentreView::new(waker),
            files: FilesView::default(),
            notice,
            window: WindowState::default(),
            measured,
            settings,
            controls: ControlsPanel::default(),
            ab: AbView::default(),
            tune: TunePanel::default(),
            teach: Teaching::default(),
        };
        if app.settings.excitation.kind == ExcitationKind::Record {
            // The record itself is not persisted.
            app.settings.excitation.kind = ExcitationKind::Random;
        }
        app.send_engine_setup();
        app
    }

    /// Builds the app inside eframe: settings from storage, theme, repaint waker.
    pub fn from_creation_context(cc: &eframe::CreationContext<'_>) -> Self {
        let settings: Settings = cc
            .storage
            .and_then(|s| eframe::get_value(s, eframe::APP_KEY))
            .unwrap_or_default();
        cc.egui_ctx.set_theme(settings.theme.preference());
        if settings.ui_scale.is_finite() && (0.5..=3.0).contains(&settings.ui_scale) {
            cc.egui_ctx.set_zoom_factor(settings.ui_scale);
        }
        let ctx = cc.egui_ctx.clone();
        // The engine wakes the app after every step (~100 times a second while running):
        // a repaint at most REPAINT_PERIOD after the first wake folds them into ~30 frames
        // a second, smooth for the scopes at a third of the CPU.
        Self::new(settings, move || ctx.request_repaint_after(REPAINT_PERIOD))
    }

    fn send_engine_setup(&mut self) {
        if self.ab.is_on() {
            self.send(Command::SetReference(self.ab.command()));
        }
        if let Some(e) = self.settings.excitation.excitation() {
            self.send(Command::SetExcitation(Box::new(e)));
        }
        self.send(Command::SetSpeed(self.settings.speed));
        self.send(self.engine.run_command());
    }

    fn send(&mut self, c: Command) {
        self.engine.send(c);
    }

    // ----- actions -----

    fn info(&mut self, text: impl Into<String>) {
        self.notice = Some(Notice {
            text: text.into(),
            error: false,
            at: Instant::now(),
        });
    }

    fn error(&mut self, text: impl Into<String>) {
        self.notice = Some(Notice {
            text: text.into(),
            error: true,
            at: Instant::now(),
        });
    }

    /// Applies edited parameters: validated here, then sent to the running engine.
    fn apply_params(&mut self) {
        match self.params.validate() {
            Ok(()) => {
                self.controls.set_param_error(None);
                let p = Box::new(self.params);
                self.send(Command::SetParams(p));
                self.traces.reset_metrics();
                self.engine.watch = None;
            }
            Err(e) => self
                .controls
                .set_param_error(Some(format!("not applied: {e}"))),
        }
    }

    /// Sets the UI scale (zoom factor, clamped to 0.5 … 3) and remembers it.
    pub fn set_ui_scale(&mut self, ctx: &egui::Context, scale: f32) {
        let z = scale.clamp(0.5, 3.0);
        ctx.set_zoom_factor(z);
        self.settings.ui_scale = z;
    }

    /// Toggles run/pause.
    pub fn toggle_running(&mut self) {
        self.engine.toggle_running();
    }

    /// Back to rest at t = 0; clears an engine error (restarts a dead engine thread).
    pub fn reset(&mut self) {
        if self.engine.respawn_if_gone(&self.params) {
            self.send_engine_setup();
        }
        self.send(Command::Reset);
        if self.engine.want_running {
            self.send(Command::Run);
        }
        self.traces.clear();
        self.engine.forget_run();
    }

    /// The text of the toolbar clock (simulated time and real-time factor).
    pub fn clock_text(&self) -> String {
        self.engine.clock_text()
    }

    /// Whether the parameters differ from the preset's.
    pub fn is_modified(&self) -> bool {
        self.params != self.preset.baseline
    }

    /// TEST HOOK: makes the engine's next step panic (see `Command::InjectFault`). The UI
    /// never calls it.
    #[doc(hidden)]
    pub fn inject_engine_fault(&mut self) {
        self.send(Command::InjectFault);
    }

    /// Puts back the last gains with which both loops were stable and restarts the
    /// simulation from rest with them.
    pub fn reset_to_last_stable_gains(&mut self) {
        if let Some(g) = self.centre.last_stable() {
            self.params.controller = g;
            self.controls.field_errors_mut().remove("Kp");
            self.controls.field_errors_mut().remove("Ki");
            self.apply_params();
        }
        self.reset();
    }

    /// Starts tuning the live controller with these options (the Tune button uses
    /// [`super::tune::interactive_options`]).
    pub fn start_tune(&mut self, opts: crate::tune::TuneOptions) {
        self.tune
            .start(&self.params, opts, self.engine.waker().clone());
    }

    /// Sets the controller of a chosen Pareto point on the live twin (the preset is then
    /// modified, as with a slider).
    pub fn apply_tuned(&mut self, c: ControllerParams) {
        let mut p = self.params;
        p.controller = c;
        match p.validate() {
            Ok(()) => {
                self.params = p;
                self.controls.field_errors_mut().clear();
                self.apply_params();
                self.info(format!(
                    "tuned gains applied: {}",
                    super::format::controller_text(&c)
                ));
            }
            Err(e) => self.error(format!("tuned gains not applied: {e}")),
        }
    }

    /// Switches A/B on or off (the engine restarts A and B together from rest).
    pub fn set_ab(&mut self, on: bool) {
        self.ab.set_on(on);
        self.send_reference();
    }

    /// Pins the current controller as the A/B reference (B).
    pub fn set_current_as_reference(&mut self) {
        self.ab.set_reference(self.params.controller);
        if self.ab.is_on() {
            self.send_reference();
        }
    }

    fn send_reference(&mut self) {
        self.send(Command::SetReference(self.ab.command()));
        self.traces.clear();
        self.engine.forget_run();
    }

    // ----- per frame -----

    fn handle_measured(&mut self, action: MeasuredAction, ctx: &egui::Context) {
        match action {
            MeasuredAction::None => {}
            MeasuredAction::OpenDialog => self.request_file(Purpose::LoadMeasured, "", ctx),
            MeasuredAction::ExportReport => {
                self.request_file(Purpose::ExportReport, "calibration", ctx)
            }
            MeasuredAction::Apply(p) | MeasuredAction::ApplyAndSave(p) if p.validate().is_err() => {
                self.error("calibrated parameters refused (out of range)");
            }
            MeasuredAction::Apply(p) => {
                self.params = *p;
                self.apply_params();
                let effects = super::format::active_effects(&self.params);
                self.info(if effects.is_empty() {
                    "calibrated parameters applied to the live twin (no model effects)".to_string()
                } else {
                    format!(
                        "calibrated parameters applied to the live twin; effects on: {}",
                        effects.join("; ")
                    )
                });
            }
            MeasuredAction::ApplyAndSave(p) => {
                self.params = *p;
                self.apply_params();
                self.request_file(Purpose::SavePreset, "calibrated.toml", ctx);
            }
        }
    }

    /// The whole UI for one frame (everything but eframe's window business).
    pub fn ui(&mut self, ui: &mut egui::Ui) {
        let t0 = Instant::now();
        let ctx = ui.ctx().clone();
        // On the web the engine runs here, in the frame (on the desktop in its thread).
        let sim_before = self.engine.view.t;
        let stepping = self.engine.pump(ENGINE_BUDGET);
        #[cfg(target_arch = "wasm32")]
        if self.engine.view.running && self.settings.speed == Speed::Max {
            // As fast as it goes: the next frame steps on at once.
            ctx.request_repaint();
        }
        // Background jobs (dwells, Tune) run here too on the web, in slices, after the
        // engine; on the desktop they have threads and this returns at once.
        let job_budget = FRAME_WORK_BUDGET
            .saturating_sub(stepping)
            .max(JOB_MIN_BUDGET);
        if super::job::pump(job_budget) {
            ctx.request_repaint();
        }
        self.engine.drain(&mut self.traces);
        self.teach
            .engine_stepped(stepping, self.engine.view.t - sim_before);
        // Ctrl + / Ctrl − change the zoom inside egui: remember it with the settings.
        self.settings.ui_scale = ctx.zoom_factor();
        self.poll_files(&ctx);
        self.measured.poll(&self.params);
        self.tune.poll();

        if !ctx.egui_wants_keyboard_input() && ui.input(|i| i.key_pressed(Key::Space)) {
            self.toggle_running();
        }
        if ui.input(|i| i.viewport().close_requested()) && self.files.hold_close(self.is_modified())
        {
            ctx.send_viewport_cmd(egui::ViewportCommand::CancelClose);
        }

        egui::Panel::top("menu").show(ui, |ui| {
            egui::MenuBar::new().ui(ui, |ui| self.menu_ui(ui, &ctx));
        });
        egui::Panel::top("toolbar").show(ui, |ui| self.toolbar_ui(ui));
        if self.files.path_prompt().is_some() {
            let mut typed = None;
            egui::Panel::top("path_prompt").show(ui, |ui| typed = self.files.path_prompt_ui(ui));
            if let Some(action) = typed {
                self.apply_file_action(action, &ctx);
            }
        }
        // Windows stay below the menu, the toolbar and the path prompt.
        let below_toolbar = ui.available_rect_before_wrap();

        let mut controls_actions = Vec::new();
        let modified = self.is_modified();
        egui::Panel::left("controls")
            .resizable(true)
            .default_size(330.0)
            .show(ui, |ui| {
                egui::ScrollArea::vertical().show(ui, |ui| {
                    let input = ControlsInput {
                        params: &mut self.params,
                        modified,
                        tune: &mut self.tune,
                        ab: &mut self.ab,
                        excitation: &mut self.settings.excitation,
                        waker: self.engine.waker(),
                        dialog_open: self.files.dialogs.open(),
                    };
                    controls_actions = self.controls.ui(ui, input);
                });
            });
        for action in controls_actions {
            self.apply_controls_action(action, &ctx);
        }
        // Same frame as the slider: the analytic curves follow the edited parameters.
        // "Last stable" means last *committed*: gains a drag only passes through (the
        // pointer still down, or a widget still dragged) are not remembered.
        let editing = ctx.dragged_id().is_some() || ui.input(|i| i.pointer.any_down());
        let followed = self.centre.follow(
            &self.params,
            self.engine.watch,
            editing,
            self.settings.dwell_auto,
        );
        let unstable = followed.unstable;
        self.teach.unstable = unstable;

        egui::Panel::right("side")
            .resizable(true)
            .default_size(330.0)
            .show(ui, |ui| {
                egui::ScrollArea::vertical().show(ui, |ui| self.side_ui(ui));
            });

        let mut centre_actions = Vec::new();
        egui::CentralPanel::default().show(ui, |ui| {
            // On a small window or with large text the plots keep a readable height and the
            // centre scrolls, instead of squeezing or cutting the last scope.
            egui::ScrollArea::vertical()
                .auto_shrink(false)
                .show(ui, |ui| {
                    let input = CentreInput {
                        params: &self.params,
                        traces: &self.traces,
                        ab: &mut self.ab,
                        settings: &mut self.settings,
                        running: self.engine.want_running,
                        engine_error: self.engine.error.as_deref(),
                        watch: self.engine.watch,
                        unstable,
                    };
                    centre_actions = self.centre.ui(ui, input);
                });
        });
        for action in centre_actions {
            match action {
                CentreAction::Reset => self.reset(),
                CentreAction::ResetToStableGains => self.reset_to_last_stable_gains(),
            }
        }

        if self.measured.open {
            let action = self.measured.window_ui(&ctx, &self.params, below_toolbar);
            self.handle_measured(action, &ctx);
        }
        if let Some(action) = self.files.confirm_ui(&ctx, &self.preset.name) {
            self.apply_file_action(action, &ctx);
        }
        self.teaching_ui(&ctx);
        if self.settings.show_debug {
            self.debug_overlay(&ctx);
        }
        // An information notice expires after NOTICE_LIFETIME: one repaint is booked for
        // that moment. An error stays until replaced, and needs no repaint at all.
        if let Some(n) = &self.notice
            && !n.error
        {
            match NOTICE_LIFETIME.checked_sub(n.at.elapsed()) {
                Some(left) if !left.is_zero() => ctx.request_repaint_after(left),
                _ => self.notice = None,
            }
        }
        if followed.dwell_busy || self.files.busy() || self.measured.busy() {
            ctx.request_repaint_after(Duration::from_millis(100));
        }
        self.window.stats.record(t0.elapsed().as_secs_f64() * 1e3);
    }
}

impl eframe::App for SeatTwinApp {
    fn ui(&mut self, ui: &mut egui::Ui, frame: &mut eframe::Frame) {
        self.window.stats.cpu_ms = frame.info().cpu_usage.map(|c| f64::from(c) * 1e3);
        let title = self.window_title();
        self.window.follow(ui, title);
        SeatTwinApp::ui(self, ui);
    }

    /// The web page's API reaches the app through this ([`eframe::WebRunner::app_mut`]).
    #[cfg(target_arch = "wasm32")]
    fn as_any_mut(&mut self) -> Option<&mut dyn std::any::Any> {
        Some(&mut *self)
    }

    fn save(&mut self, storage: &mut dyn eframe::Storage) {
        eframe::set_value(storage, eframe::APP_KEY, &self.settings);
    }
}
