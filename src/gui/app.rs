//! The app: state, engine events, layout, presets, dialogs and persistence.
//!
//! [`SeatTwinApp::ui`] does all the per-frame work and needs only an `egui::Ui`, so the
//! kittest tests drive the real app headless; the `eframe::App` impl adds persistence, the
//! window title and the frame-time readout.

mod accessors;
mod export;
mod file_ops;
mod panels;

use super::ab::{AbAction, AbView};
use super::controls::{self, ExcitationAction, ExcitationEditor, ExcitationKind, LoadedRecord};
use super::files::{self, CsvTable, Dialogs, Purpose, Writer};
use super::frequency::{self, Analytic, Curves, Dwell, FreqAction, FreqView};
use super::job::Waker;
use super::measured::{MeasuredAction, MeasuredData};
use super::schematic;
use super::scopes;
use super::traces::{Ch, Traces};
use super::units::{BAR_PER_PA, MM_PER_M};
use crate::analysis::watch::Finding;
use crate::engine::{self, Command, EngineHandle, Event, Speed};
use crate::params::{ControllerParams, Params};
use crate::plot::{Figure, Panel, Rgb, Scale, Series};
use crate::preset::{self, Preset, PresetMeta};
use egui::{Color32, Key, RichText};
use serde::{Deserialize, Serialize};
use std::collections::{BTreeSet, VecDeque};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Theme choice (persisted).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
pub enum Theme {
    /// Follow the desktop.
    #[default]
    System,
    /// Light.
    Light,
    /// Dark.
    Dark,
}

impl Theme {
    fn preference(self) -> egui::ThemePreference {
        match self {
            Theme::System => egui::ThemePreference::System,
            Theme::Light => egui::ThemePreference::Light,
            Theme::Dark => egui::ThemePreference::Dark,
        }
    }
}

/// What persists between runs (eframe storage; the window layout persists through egui).
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(default)]
pub struct Settings {
    /// Theme.
    pub theme: Theme,
    /// The preset file last opened or saved.
    pub last_preset: Option<PathBuf>,
    /// Simulation speed.
    pub speed: Speed,
    /// Frame-time overlay.
    pub show_debug: bool,
    /// Schematic panel.
    pub show_schematic: bool,
    /// Recompute the simulated dwell points automatically after slider changes.
    pub dwell_auto: bool,
    /// The excitation editor.
    pub excitation: ExcitationEditor,
    /// Unwrapped phase in the frequency plots (default: wrapped into ±180°).
    pub phase_unwrapped: bool,
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            theme: Theme::System,
            last_preset: None,
            speed: Speed::RealTime,
            show_debug: false,
            show_schematic: true,
            dwell_auto: true,
            excitation: ExcitationEditor::default(),
            phase_unwrapped: false,
        }
    }
}

/// The preset the current parameters came from.
#[derive(Debug, Clone)]
pub struct PresetInfo {
    /// Name shown in the title.
    pub name: String,
    /// Its description.
    pub description: String,
    /// The file, if any.
    pub path: Option<PathBuf>,
    /// Whether "Save" may overwrite `path` (the user chose it; shipped presets are not).
    pub user_file: bool,
    /// Parameters as loaded or last saved: the "modified" marker compares against these.
    pub baseline: Params,
}

/// What the engine last reported.
#[derive(Debug, Clone, Default)]
pub struct EngineView {
    /// Simulated time [s].
    pub t: f64,
    /// Real-time factor.
    pub realtime_factor: f64,
    /// Running (not paused, not failed).
    pub running: bool,
    /// Parameters the engine runs with (echo).
    pub params: Option<Params>,
    /// The A/B reference controller the engine runs (`None`: A/B off).
    pub reference: Option<ControllerParams>,
    /// End-stop contacts since the last restart: live twin, reference twin.
    pub contacts: (usize, usize),
}

/// An action waiting for "discard unsaved changes?".
#[derive(Debug, Clone, PartialEq)]
enum Pending {
    OpenDialog,
    LoadFile(PathBuf),
    Quit,
}

/// A message line under the toolbar.
#[derive(Debug, Clone)]
pub struct Notice {
    /// Text.
    pub text: String,
    /// An error (red) or information.
    pub error: bool,
    at: Instant,
}

/// Per-frame timing, for the debug overlay.
#[derive(Debug, Clone, Default)]
pub struct FrameStats {
    ui_ms: VecDeque<f64>,
    frame_at: VecDeque<Instant>,
    /// Whole-frame CPU time reported by eframe (UI + tessellation) [ms].
    pub cpu_ms: Option<f64>,
    /// Time of the scopes in the last frame [ms].
    pub scopes_ms: f64,
    /// Time of the frequency plots in the last frame [ms].
    pub freq_ms: f64,
}

impl FrameStats {
    fn record(&mut self, ui_ms: f64) {
        if self.ui_ms.len() >= 120 {
            self.ui_ms.pop_front();
            self.frame_at.pop_front();
        }
        self.ui_ms.push_back(ui_ms);
        self.frame_at.push_back(Instant::now());
    }

    /// Mean time of `SeatTwinApp::ui` over the last 120 frames [ms].
    pub fn mean_ui_ms(&self) -> f64 {
        self.ui_ms.iter().sum::<f64>() / self.ui_ms.len().max(1) as f64
    }

    /// Largest time of `SeatTwinApp::ui` over the last 120 frames [ms].
    pub fn max_ui_ms(&self) -> f64 {
        self.ui_ms.iter().copied().fold(0.0, f64::max)
    }

    /// Frames per second over the last 120 frames.
    pub fn fps(&self) -> f64 {
        match (self.frame_at.front(), self.frame_at.back()) {
            (Some(a), Some(b)) if self.frame_at.len() > 1 => {
                (self.frame_at.len() - 1) as f64 / b.duration_since(*a).as_secs_f64().max(1e-9)
            }
            _ => 0.0,
        }
    }
}

/// The seat-twin desktop app.
pub struct SeatTwinApp {
    /// Persisted settings.
    pub settings: Settings,
    params: Params,
    preset: PresetInfo,
    shipped: Vec<(String, PathBuf)>,
    engine: EngineHandle,
    waker: Waker,
    engine_view: EngineView,
    engine_error: Option<String>,
    engine_alive: bool,
    want_running: bool,
    traces: Traces,
    analytic: Analytic,
    dwell: Dwell,
    dialogs: Dialogs,
    writer: Writer,
    notice: Option<Notice>,
    pending: Option<Pending>,
    quit_confirmed: bool,
    param_error: Option<String>,
    frame_stats: FrameStats,
    title: String,
    measured: MeasuredData,
    field_errors: controls::FieldErrors,
    hidden_curves: BTreeSet<String>,
    last_stable: Option<ControllerParams>,
    /// What the running twin's watch found since the last reset or change (it can ring while
    /// the linear verdict at rest says stable).
    twin_watch: Option<crate::analysis::watch::Finding>,
    scope_frames: Vec<egui::Rect>,
    path_prompt: Option<(Purpose, String)>,
    ab: AbView,
    tune: super::tune::TunePanel,
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
        let engine = spawn_engine(&params, &waker);
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
            waker: waker.clone(),
            engine_view: EngineView::default(),
            engine_error: None,
            engine_alive: true,
            want_running: true,
            traces: Traces::new(),
            analytic: Analytic::default(),
            dwell: Dwell::new(waker),
            dialogs: Dialogs::default(),
            writer: Writer::default(),
            notice,
            pending: None,
            quit_confirmed: false,
            param_error: None,
            frame_stats: FrameStats::default(),
            title: String::new(),
            measured,
            settings,
            field_errors: controls::FieldErrors::new(),
            hidden_curves: BTreeSet::new(),
            last_stable: None,
            twin_watch: None,
            scope_frames: Vec::new(),
            path_prompt: None,
            ab: AbView::default(),
            tune: super::tune::TunePanel::default(),
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
        let ctx = cc.egui_ctx.clone();
        Self::new(settings, move || ctx.request_repaint())
    }

    fn send_engine_setup(&mut self) {
        if self.ab.is_on() {
            self.send(Command::SetReference(self.ab.command()));
        }
        if let Some(e) = self.settings.excitation.excitation() {
            self.send(Command::SetExcitation(Box::new(e)));
        }
        self.send(Command::SetSpeed(self.settings.speed));
        self.send(if self.want_running {
            Command::Run
        } else {
            Command::Pause
        });
    }

    fn send(&mut self, c: Command) {
        if !self.engine.send(c) {
            self.engine_alive = false;
        }
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
                self.param_error = None;
                let p = Box::new(self.params);
                self.send(Command::SetParams(p));
                self.traces.reset_metrics();
                self.twin_watch = None;
            }
            Err(e) => self.param_error = Some(format!("not applied: {e}")),
        }
    }

    /// Toggles run/pause.
    pub fn toggle_running(&mut self) {
        self.want_running = !self.want_running;
        let c = if self.want_running {
            Command::Run
        } else {
            Command::Pause
        };
        self.send(c);
    }

    /// Back to rest at t = 0; clears an engine error (restarts a dead engine thread).
    pub fn reset(&mut self) {
        if !self.engine_alive {
            self.engine = spawn_engine(&self.params, &self.waker);
            self.engine_alive = true;
            self.send_engine_setup();
        }
        self.send(Command::Reset);
        if self.want_running {
            self.send(Command::Run);
        }
        self.traces.clear();
        self.engine_error = None;
        self.twin_watch = None;
    }

    /// The Tune panel.
    pub fn tune_panel(&self) -> &super::tune::TunePanel {
        &self.tune
    }

    /// The Tune panel, to drive it (tests, menus).
    pub fn tune_panel_mut(&mut self) -> &mut super::tune::TunePanel {
        &mut self.tune
    }

    /// Starts tuning the live controller with these options (the Tune button uses
    /// [`super::tune::interactive_options`]).
    pub fn start_tune(&mut self, opts: crate::tune::TuneOptions) {
        self.tune.start(&self.params, opts, self.waker.clone());
    }

    /// Sets the controller of a chosen Pareto point on the live twin (the preset is then
    /// modified, as with a slider).
    pub fn apply_tuned(&mut self, c: ControllerParams) {
        let mut p = self.params;
        p.controller = c;
        match p.validate() {
            Ok(()) => {
                self.params = p;
                self.field_errors.clear();
                self.apply_params();
                self.info(format!(
                    "tuned gains applied: {}",
                    super::format::controller_text(&c)
                ));
            }
            Err(e) => self.error(format!("tuned gains not applied: {e}")),
        }
    }

    /// The A/B state.
    pub fn ab(&self) -> &AbView {
        &self.ab
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
        self.engine_error = None;
        self.twin_watch = None;
    }

    // ----- per frame -----

    fn drain_engine(&mut self) {
        loop {
            match self.engine.events.try_recv() {
                Ok(ev) => self.handle_event(ev),
                Err(std::sync::mpsc::TryRecvError::Empty) => break,
                Err(std::sync::mpsc::TryRecvError::Disconnected) => {
                    if self.engine_alive {
                        self.engine_alive = false;
                        self.engine_error = Some(
                            "the engine thread has stopped. Press Reset to restart it.".into(),
                        );
                    }
                    break;
                }
            }
        }
    }

    fn handle_event(&mut self, ev: Event) {
        match ev {
            Event::Samples(b) => self.traces.push_batch(&b),
            Event::Status {
                t,
                realtime_factor,
                running,
                params,
                reference,
                contacts,
            } => {
                self.engine_view = EngineView {
                    t,
                    realtime_factor,
                    running,
                    params: Some(*params),
                    reference,
                    contacts,
                }
            }
            Event::Contact(_) => self.traces.contact_count += 1,
            Event::Error(msg) => self.engine_error = Some(msg),
            Event::Restarted => self.traces.mark_restart(),
            Event::Watch(f) => self.twin_watch = Some(f),
        }
    }

    /// The simulated (sine dwell) frequency points of the twin.
    pub fn dwell(&self) -> &Dwell {
        &self.dwell
    }

    /// The measured-data window's state.
    pub fn measured(&self) -> &MeasuredData {
        &self.measured
    }

    /// The measured-data window's state, to drive it (tests, dialogs).
    pub fn measured_mut(&mut self) -> &mut MeasuredData {
        &mut self.measured
    }

    fn handle_measured(&mut self, action: MeasuredAction, ctx: &egui::Context) {
        match action {
            MeasuredAction::None => {}
            MeasuredAction::OpenDialog => self.dialogs.request(Purpose::LoadMeasured, "", ctx),
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
                self.dialogs
                    .request(Purpose::SavePreset, "calibrated.toml", ctx);
            }
        }
    }

    /// The whole UI for one frame (everything but eframe's window business).
    pub fn ui(&mut self, ui: &mut egui::Ui) {
        let t0 = Instant::now();
        let ctx = ui.ctx().clone();
        self.drain_engine();
        self.poll_files(&ctx);
        self.measured.poll(&self.params);
        self.tune.poll();

        if !ctx.egui_wants_keyboard_input() && ui.input(|i| i.key_pressed(Key::Space)) {
            self.toggle_running();
        }
        if ui.input(|i| i.viewport().close_requested())
            && self.is_modified()
            && !self.quit_confirmed
        {
            ctx.send_viewport_cmd(egui::ViewportCommand::CancelClose);
            self.pending = Some(Pending::Quit);
        }

        egui::Panel::top("menu").show(ui, |ui| {
            egui::MenuBar::new().ui(ui, |ui| self.menu_ui(ui, &ctx));
        });
        egui::Panel::top("toolbar").show(ui, |ui| self.toolbar_ui(ui));
        if self.path_prompt.is_some() {
            egui::Panel::top("path_prompt").show(ui, |ui| self.path_prompt_ui(ui, &ctx));
        }

        let mut params_changed = false;
        egui::Panel::left("controls")
            .resizable(true)
            .default_size(330.0)
            .show(ui, |ui| {
                egui::ScrollArea::vertical().show(ui, |ui| {
                    params_changed = self.controls_ui(ui, &ctx);
                });
            });
        if params_changed {
            self.apply_params();
        }
        // Same frame as the slider: the analytic curves follow the edited parameters.
        self.analytic.update(&self.params);
        let unstable = self.analytic.curves().unstable()
            || self
                .twin_watch
                .is_some_and(|f| !matches!(f, Finding::NegativePressure { .. }));
        if !unstable {
            self.last_stable = Some(self.params.controller);
        }
        // No sine dwell of an unstable loop: it would only diverge.
        let dwell_busy = self
            .dwell
            .poll(&self.params, self.settings.dwell_auto && !unstable);

        egui::Panel::right("side")
            .resizable(true)
            .default_size(330.0)
            .show(ui, |ui| {
                egui::ScrollArea::vertical().show(ui, |ui| self.side_ui(ui));
            });

        egui::CentralPanel::default().show(ui, |ui| {
            if let Some(err) = self.engine_error.clone() {
                egui::Frame::new()
                    .fill(Color32::from_rgb(150, 20, 20))
                    .inner_margin(6.0)
                    .corner_radius(4.0)
                    .show(ui, |ui| {
                        ui.horizontal_wrapped(|ui| {
                            ui.label(
                                RichText::new(format!(
                                    "Engine stopped: {}",
                                    super::format::shorten_numbers(&err)
                                ))
                                .color(Color32::WHITE)
                                .strong(),
                            );
                            if ui.button("Reset").clicked() {
                                self.reset();
                            }
                            if unstable
                                && self.last_stable.is_some()
                                && ui
                                    .button("Reset to last stable gains")
                                    .on_hover_text(
                                        "The current gains make the loop unstable: Reset alone \
                                         would diverge again",
                                    )
                                    .clicked()
                            {
                                self.reset_to_last_stable_gains();
                            }
                        });
                    });
            }
            let mut action = FreqAction::None;
            ui.columns(2, |cols| {
                let t_scopes = Instant::now();
                self.scope_frames = scopes::scopes_ui(
                    &mut cols[0],
                    &self.traces,
                    &self.params,
                    &mut self.hidden_curves,
                    self.ab.is_on(),
                );
                self.frame_stats.scopes_ms = t_scopes.elapsed().as_secs_f64() * 1e3;
                let t_freq = Instant::now();
                let last_stable = self.last_stable.filter(|g| *g != self.params.controller);
                let reference = self.ab.curves(&self.params);
                action = frequency::frequency_ui(
                    &mut cols[1],
                    self.analytic.curves(),
                    &mut self.dwell,
                    &self.params,
                    FreqView {
                        phase_unwrapped: &mut self.settings.phase_unwrapped,
                        hidden: &mut self.hidden_curves,
                        last_stable,
                        reference,
                        watch: self.twin_watch,
                    },
                );
                self.frame_stats.freq_ms = t_freq.elapsed().as_secs_f64() * 1e3;
            });
            if action == FreqAction::ResetToStableGains {
                self.reset_to_last_stable_gains();
            }
        });

        if self.measured.open {
            let action = self.measured.window_ui(&ctx, &self.params);
            self.handle_measured(action, &ctx);
        }
        self.confirm_ui(&ctx);
        if self.settings.show_debug {
            self.debug_overlay(&ctx);
        }
        if let Some(n) = &self.notice
            && !n.error
            && n.at.elapsed() > Duration::from_secs(8)
        {
            self.notice = None;
        }
        if dwell_busy || self.writer.busy() > 0 || self.notice.is_some() || self.measured.busy() {
            ctx.request_repaint_after(Duration::from_millis(100));
        }
        self.frame_stats.record(t0.elapsed().as_secs_f64() * 1e3);
    }
}

fn spawn_engine(params: &Params, waker: &Waker) -> EngineHandle {
    let w = waker.clone();
    engine::spawn(*params, move || w())
}

impl eframe::App for SeatTwinApp {
    fn ui(&mut self, ui: &mut egui::Ui, frame: &mut eframe::Frame) {
        self.frame_stats.cpu_ms = frame.info().cpu_usage.map(|c| f64::from(c) * 1e3);
        let title = self.window_title();
        if title != self.title {
            ui.ctx()
                .send_viewport_cmd(egui::ViewportCommand::Title(title.clone()));
            self.title = title;
        }
        SeatTwinApp::ui(self, ui);
    }

    fn save(&mut self, storage: &mut dyn eframe::Storage) {
        eframe::set_value(storage, eframe::APP_KEY, &self.settings);
    }
}
