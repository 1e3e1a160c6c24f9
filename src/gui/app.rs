//! The app: state, engine events, layout, presets, dialogs and persistence.
//!
//! [`SeatTwinApp::ui`] does all the per-frame work and needs only an `egui::Ui`, so the
//! kittest tests drive the real app headless; the `eframe::App` impl adds persistence, the
//! window title and the frame-time readout.

use super::controls::{self, ExcitationAction, ExcitationEditor, ExcitationKind, LoadedRecord};
use super::files::{self, CsvTable, Dialogs, Purpose, Writer};
use super::frequency::{self, Analytic, Curves, Dwell, FreqAction, FreqView};
use super::measured::{MeasuredAction, MeasuredData};
use super::schematic;
use super::scopes;
use super::traces::{Ch, Traces};
use super::units::{BAR_PER_PA, MM_PER_M};
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

type Waker = Arc<dyn Fn() + Send + Sync>;

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
    scope_frames: Vec<egui::Rect>,
    path_prompt: Option<(Purpose, String)>,
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
            waker,
            engine_view: EngineView::default(),
            engine_error: None,
            engine_alive: true,
            want_running: true,
            traces: Traces::new(),
            analytic: Analytic::default(),
            dwell: Dwell::default(),
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
            scope_frames: Vec::new(),
            path_prompt: None,
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

    // ----- accessors (tests, overlay) -----

    /// The parameters being edited (SI).
    pub fn params(&self) -> &Params {
        &self.params
    }

    /// The parameters the engine last reported running with.
    pub fn engine_params(&self) -> Option<&Params> {
        self.engine_view.params.as_ref()
    }

    /// What the engine last reported.
    pub fn engine_view(&self) -> &EngineView {
        &self.engine_view
    }

    /// Whether the user wants the simulation running (space bar / Run button).
    pub fn wants_running(&self) -> bool {
        self.want_running
    }

    /// The engine's error, if it stopped.
    pub fn engine_error(&self) -> Option<&str> {
        self.engine_error.as_deref()
    }

    /// The analytic frequency curves shown.
    pub fn curves(&self) -> &Curves {
        self.analytic.curves()
    }

    /// The live traces.
    pub fn traces(&self) -> &Traces {
        &self.traces
    }

    /// The current preset.
    pub fn preset(&self) -> &PresetInfo {
        &self.preset
    }

    /// Whether the parameters differ from the preset's.
    pub fn is_modified(&self) -> bool {
        self.params != self.preset.baseline
    }

    /// The message line.
    pub fn notice(&self) -> Option<&Notice> {
        self.notice.as_ref()
    }

    /// Whether the "discard unsaved changes?" prompt is showing.
    pub fn is_confirm_open(&self) -> bool {
        self.pending.is_some()
    }

    /// Frame timing.
    pub fn frame_stats(&self) -> &FrameStats {
        &self.frame_stats
    }

    /// Refused parameter values, by control label (shown next to the control).
    pub fn field_errors(&self) -> &controls::FieldErrors {
        &self.field_errors
    }

    /// Curves switched off in the legends (`plot/name`).
    pub fn hidden_curves(&self) -> &BTreeSet<String> {
        &self.hidden_curves
    }

    /// The last gains with which both loops were stable.
    pub fn last_stable_gains(&self) -> Option<ControllerParams> {
        self.last_stable
    }

    /// The scopes' data areas drawn last frame, top to bottom.
    pub fn scope_frames(&self) -> &[egui::Rect] {
        &self.scope_frames
    }

    /// The typed-path prompt shown when no file dialog is available: purpose and text.
    pub fn path_prompt(&self) -> Option<&(Purpose, String)> {
        self.path_prompt.as_ref()
    }

    /// The text of the toolbar clock (simulated time and real-time factor).
    pub fn clock_text(&self) -> String {
        let v = &self.engine_view;
        if self.engine_error.is_some() {
            format!("t = {:8.2} s   stopped", v.t)
        } else if !v.running {
            format!("t = {:8.2} s   paused", v.t)
        } else {
            format!(
                "t = {:8.2} s   ×{:.2} real time",
                v.t,
                v.realtime_factor.max(0.0)
            )
        }
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
        if let Some(g) = self.last_stable {
            self.params.controller = g;
            self.field_errors.remove("Kp");
            self.field_errors.remove("Ki");
            self.apply_params();
        }
        self.reset();
    }

    /// The shipped presets `(name, file)` in the Presets menu.
    pub fn shipped_presets(&self) -> &[(String, PathBuf)] {
        &self.shipped
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
    }

    /// Loads a preset file; a bad file leaves everything as it was and says why.
    pub fn open_preset_file(&mut self, path: &Path) {
        match Preset::load(path) {
            Ok(p) => {
                let shipped = self.shipped.iter().any(|(_, f)| f == path);
                self.set_preset(p, Some(path.to_path_buf()), !shipped);
                self.settings.last_preset = Some(path.to_path_buf());
                self.info(format!("preset loaded from {}", path.display()));
            }
            Err(e) => self.error(format!("preset not loaded: {e}")),
        }
    }

    fn set_preset(&mut self, p: Preset, path: Option<PathBuf>, user_file: bool) {
        let name = if p.meta.name.is_empty() {
            path.as_deref()
                .and_then(|f| f.file_stem())
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_else(|| "unnamed".into())
        } else {
            p.meta.name.clone()
        };
        self.params = p.params;
        self.preset = PresetInfo {
            name,
            description: p.meta.description,
            path,
            user_file,
            baseline: p.params,
        };
        self.apply_params();
    }

    /// Saves the parameters as a preset file.
    pub fn save_preset_file(&mut self, path: &Path) {
        let name = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| self.preset.name.clone());
        let p = Preset {
            meta: PresetMeta {
                name: name.clone(),
                description: self.preset.description.clone(),
                ..Default::default()
            },
            params: self.params,
        };
        match p.save(path) {
            Ok(()) => {
                self.preset = PresetInfo {
                    name,
                    description: p.meta.description,
                    path: Some(path.to_path_buf()),
                    user_file: true,
                    baseline: self.params,
                };
                self.settings.last_preset = Some(path.to_path_buf());
                self.info(format!("preset saved to {}", path.display()));
            }
            Err(e) => self.error(format!("preset not saved: {e}")),
        }
    }

    /// Loads a CSV platform record and switches the excitation to it.
    pub fn load_record_file(&mut self, path: &Path) {
        match files::read_platform_record(path) {
            Ok(motion) => {
                let name = path
                    .file_name()
                    .map(|s| s.to_string_lossy().into_owned())
                    .unwrap_or_default();
                self.settings.excitation.record = Some(LoadedRecord { name, motion });
                self.settings.excitation.kind = ExcitationKind::Record;
                self.apply_excitation();
                self.info(format!("record loaded from {}", path.display()));
            }
            Err(e) => self.error(format!("record not loaded: {e:#}")),
        }
    }

    /// Switches the excitation editor to `kind` and applies it (restarts from rest).
    pub fn set_excitation_kind(&mut self, kind: ExcitationKind) {
        self.settings.excitation.kind = kind;
        if let Some(p) = self.settings.excitation.problem() {
            self.error(format!("excitation not applied: {p}"));
        } else {
            self.apply_excitation();
        }
    }

    fn apply_excitation(&mut self) {
        if let Some(e) = self.settings.excitation.excitation() {
            self.send(Command::SetExcitation(Box::new(e)));
            self.traces.clear();
            self.engine_error = None;
        }
    }

    /// Runs `action` now, or asks first if there are unsaved changes.
    fn guarded(&mut self, action: Pending, ctx: &egui::Context) {
        if self.is_modified() {
            self.pending = Some(action);
        } else {
            self.run_pending(action, ctx);
        }
    }

    fn run_pending(&mut self, action: Pending, ctx: &egui::Context) {
        match action {
            Pending::OpenDialog => self.dialogs.request(Purpose::OpenPreset, "", ctx),
            Pending::LoadFile(p) => self.open_preset_file(&p),
            Pending::Quit => {
                self.quit_confirmed = true;
                ctx.send_viewport_cmd(egui::ViewportCommand::Close);
            }
        }
    }

    fn save(&mut self, ctx: &egui::Context) {
        match (&self.preset.path, self.preset.user_file) {
            (Some(p), true) => {
                let p = p.clone();
                self.save_preset_file(&p);
            }
            _ => self.save_as(ctx),
        }
    }

    fn save_as(&mut self, ctx: &egui::Context) {
        let name = format!("{}.toml", self.preset.name);
        self.dialogs.request(Purpose::SavePreset, &name, ctx);
    }

    /// The traces in the window as a CSV table (SI, the dataset format; twin columns carry
    /// the dataset's names so the file reads back as a measured record).
    pub fn traces_table(&self) -> CsvTable {
        let header = vec![
            "t",
            "x",
            "xdd",
            "u",
            "du",
            "ydd",
            "v_in",
            "xv",
            "p1",
            "p2",
            "q1",
            "q2",
            "contact",
            "linear_u",
            "linear_ydd",
            "linear_v_in",
            "passive_u",
            "passive_ydd",
        ];
        let rows = self
            .traces
            .rows()
            .iter()
            .map(|r| {
                let (w, l, p) = (&r.twin, &r.linear, &r.passive);
                vec![
                    r.t,
                    w.x,
                    w.xdd,
                    w.u,
                    w.du,
                    w.ydd,
                    w.v_in,
                    w.xv,
                    w.p1,
                    w.p2,
                    w.q1,
                    w.q2,
                    f64::from(u8::from(w.contact)),
                    l.u,
                    l.ydd,
                    l.v_in,
                    p.u,
                    p.ydd,
                ]
            })
            .filter(|row| row.iter().all(|v| v.is_finite()))
            .collect();
        let c = &self.params.controller;
        let comments = vec![
            (
                "source".into(),
                "seat-twin live traces (twin, linear, passive)".into(),
            ),
            ("preset".into(), self.preset.name.clone()),
            ("kp_v_per_m".into(), c.kp_v_per_m.to_string()),
            ("ki_v_s_per_m".into(), c.ki_v_s_per_m.to_string()),
            (
                "units".into(),
                "SI (s, m, m/s², V, Pa, m³/s); t continues across restarts".into(),
            ),
        ];
        CsvTable {
            header,
            comments,
            rows,
        }
    }

    /// The current plots as report figures: frequency responses and scopes.
    pub fn plot_figures(&self) -> Vec<(&'static str, Figure)> {
        let c = self.analytic.curves();
        let xy = |pts: &[egui_plot::PlotPoint], logx: bool| -> (Vec<f64>, Vec<f64>) {
            pts.iter()
                .map(|p| (if logx { 10f64.powf(p.x) } else { p.x }, p.y))
                .unzip()
        };
        let line = |label: &str, pts: &[egui_plot::PlotPoint], color: Rgb, logx: bool| {
            let (x, y) = xy(pts, logx);
            Series::line(label, x, y, color)
        };
        let (lin_c, twin_c, pas_c) = (Rgb(255, 127, 14), Rgb(31, 119, 180), Rgb(44, 160, 44));
        let mut t_mag = Panel::new("Transmissibility", "frequency [Hz]", "|T| [dB]");
        t_mag.x_scale = Scale::Log10;
        t_mag.series = vec![
            line("linear active", &c.t_mag[0], lin_c, true),
            line("twin active (linearised)", &c.t_mag[1], twin_c, true),
            line("passive", &c.t_mag[2], pas_c, true),
        ];
        if !self.dwell.mag.is_empty() {
            let (x, y) = xy(&self.dwell.mag, true);
            t_mag
                .series
                .push(Series::markers("twin simulated (dwell)", x, y, twin_c));
        }
        t_mag.hlines = vec![(0.0, "|T| = 1".into())];
        let mut t_ph = Panel::new("", "frequency [Hz]", "phase T [deg]");
        t_ph.x_scale = Scale::Log10;
        t_ph.series = vec![
            line("linear active", &c.t_phase[0], lin_c, true),
            line("twin active", &c.t_phase[1], twin_c, true),
            line("passive", &c.t_phase[2], pas_c, true),
        ];
        let mut b_mag = Panel::new(
            "Valve/actuator (du/dt)/V_in",
            "frequency [Hz]",
            "|du/dt / V_in| [dB re (mm/s)/V]",
        );
        b_mag.x_scale = Scale::Log10;
        b_mag.series = vec![
            line("twin (linearised)", &c.bode_mag[0], twin_c, true),
            line("G(s)", &c.bode_mag[1], lin_c, true),
        ];
        let mut b_ph = Panel::new("", "frequency [Hz]", "phase (du/dt)/V_in [deg]");
        b_ph.x_scale = Scale::Log10;
        b_ph.series = vec![
            line("twin (linearised)", &c.bode_phase[0], twin_c, true),
            line("G(s)", &c.bode_phase[1], lin_c, true),
        ];
        let mut freq = Figure::new(
            format!(
                "seat-twin — {} (Kp = {:.2} V/m, Ki = {:.2} V·s/m)",
                self.preset.name,
                self.params.controller.kp_v_per_m,
                self.params.controller.ki_v_s_per_m
            ),
            vec![t_mag, t_ph, b_mag, b_ph],
        );
        freq.height = 1200;

        let tr = &self.traces;
        let ch = |label: &str, chan: Ch, color: Rgb| {
            line(label, tr.channel(chan).points(), color, false)
        };
        let mut acc = Panel::new("Live traces", "time [s]", "acceleration [m/s²]");
        acc.series = vec![
            ch("platform", Ch::PlatformAcc, Rgb(127, 127, 127)),
            ch("passive", Ch::PassiveAcc, pas_c),
            ch("linear", Ch::LinearAcc, lin_c),
            ch("twin", Ch::TwinAcc, twin_c),
        ];
        let mut stroke = Panel::new("", "time [s]", "stroke u [mm]");
        let lim = self.params.plant.cylinder.stroke_m / 2.0 * MM_PER_M;
        stroke.series = vec![
            ch("passive", Ch::PassiveU, pas_c),
            ch("linear", Ch::LinearU, lin_c),
            ch("twin", Ch::TwinU, twin_c),
        ];
        stroke.hlines = vec![(lim, "end stop".into()), (-lim, "end stop".into())];
        stroke.vspans = tr.contacts().to_vec();
        let mut pr = Panel::new("", "time [s]", "pressure [bar]");
        pr.series = vec![
            ch("p1", Ch::P1, Rgb(214, 39, 40)),
            ch("p2", Ch::P2, Rgb(148, 103, 189)),
        ];
        let mut q = Panel::new("", "time [s]", "flow [L/min]");
        q.series = vec![
            ch("Q1", Ch::Q1, Rgb(214, 39, 40)),
            ch("Q2", Ch::Q2, Rgb(148, 103, 189)),
        ];
        let mut v = Panel::new("", "time [s]", "V_in [V]");
        v.series = vec![
            ch("linear", Ch::LinearVin, lin_c),
            ch("twin", Ch::TwinVin, twin_c),
        ];
        let mut xv = Panel::new("", "time [s]", "spool x_v [mm]");
        xv.series = vec![ch("twin", Ch::TwinXv, twin_c)];
        let mut scopes = Figure::new(
            format!("seat-twin — {} live traces", self.preset.name),
            vec![acc, stroke, pr, q, v, xv],
        );
        scopes.height = 1500;
        vec![("frequency", freq), ("scopes", scopes)]
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
            } => {
                self.engine_view = EngineView {
                    t,
                    realtime_factor,
                    running,
                    params: Some(*params),
                }
            }
            Event::Contact(_) => self.traces.contact_count += 1,
            Event::Error(msg) => self.engine_error = Some(msg),
            Event::Restarted => self.traces.mark_restart(),
        }
    }

    fn poll_files(&mut self, ctx: &egui::Context) {
        while let Some((purpose, paths)) = self.dialogs.poll() {
            if paths.is_empty() {
                // Cancelled, or no dialog on this desktop: offer a typed path instead.
                let suggested = match purpose {
                    Purpose::ExportCsv => "traces.csv",
                    Purpose::ExportPng => "plots.png",
                    Purpose::SavePreset => "preset.toml",
                    _ => "",
                };
                self.path_prompt = Some((purpose, suggested.to_string()));
                self.info("no file chosen (dialog cancelled, or no file dialog on this desktop): type a path below");
                continue;
            }
            self.use_paths(purpose, paths, ctx);
        }
        while let Some(r) = self.writer.poll() {
            match r {
                Ok(m) => self.info(m),
                Err(e) => self.error(format!("export failed: {e}")),
            }
        }
    }

    /// Opens the typed-path prompt for `purpose` (the fallback when no file dialog shows).
    pub fn prompt_path(&mut self, purpose: Purpose, suggested: &str) {
        self.path_prompt = Some((purpose, suggested.to_string()));
    }

    fn path_prompt_ui(&mut self, ui: &mut egui::Ui, ctx: &egui::Context) {
        let Some((purpose, mut text)) = self.path_prompt.clone() else {
            return;
        };
        let mut done: Option<bool> = None;
        ui.horizontal(|ui| {
            ui.label(format!("{} — file path:", purpose.title()));
            let r = ui.add(
                egui::TextEdit::singleline(&mut text)
                    .id(egui::Id::unique("path_prompt"))
                    .desired_width(360.0)
                    .hint_text("path/to/file"),
            );
            let enter = r.lost_focus() && ui.input(|i| i.key_pressed(Key::Enter));
            if ui.button("OK").clicked() || enter {
                done = Some(true);
            }
            if ui.button("Cancel").clicked() {
                done = Some(false);
            }
        });
        match done {
            Some(true) if !text.trim().is_empty() => {
                self.path_prompt = None;
                let path = PathBuf::from(text.trim());
                self.use_paths(purpose, vec![path], ctx);
            }
            Some(true) => self.error("type a file path first"),
            Some(false) => self.path_prompt = None,
            None => self.path_prompt = Some((purpose, text)),
        }
    }

    fn use_paths(&mut self, purpose: Purpose, mut paths: Vec<PathBuf>, ctx: &egui::Context) {
        {
            if purpose == Purpose::LoadMeasured {
                self.measured.load_files(paths);
                return;
            }
            let path = paths.swap_remove(0);
            match purpose {
                Purpose::LoadMeasured => {}
                Purpose::OpenPreset => self.open_preset_file(&path),
                Purpose::SavePreset => self.save_preset_file(&path),
                Purpose::LoadRecord => self.load_record_file(&path),
                Purpose::ExportCsv => {
                    let table = self.traces_table();
                    if table.rows.is_empty() {
                        self.error("nothing to export yet: run the simulation first");
                    } else {
                        self.writer.write_csv(ctx, path, table);
                    }
                }
                Purpose::ExportPng => {
                    let stem = path.with_extension("");
                    let figs = self.plot_figures();
                    self.writer.write_figures(ctx, stem, figs);
                }
            }
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
        let unstable = self.analytic.curves().unstable();
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
                );
                self.frame_stats.scopes_ms = t_scopes.elapsed().as_secs_f64() * 1e3;
                let t_freq = Instant::now();
                let last_stable = self.last_stable.filter(|g| *g != self.params.controller);
                action = frequency::frequency_ui(
                    &mut cols[1],
                    self.analytic.curves(),
                    &mut self.dwell,
                    &self.params,
                    FreqView {
                        phase_unwrapped: &mut self.settings.phase_unwrapped,
                        hidden: &mut self.hidden_curves,
                        last_stable,
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
        if dwell_busy || self.writer.busy > 0 || self.notice.is_some() || self.measured.busy() {
            ctx.request_repaint_after(Duration::from_millis(100));
        }
        self.frame_stats.record(t0.elapsed().as_secs_f64() * 1e3);
    }

    fn menu_ui(&mut self, ui: &mut egui::Ui, ctx: &egui::Context) {
        ui.menu_button("File", |ui| {
            if ui.button("Open preset…").clicked() {
                self.guarded(Pending::OpenDialog, ctx);
            }
            if ui.button("Save preset").clicked() {
                self.save(ctx);
            }
            if ui.button("Save preset as…").clicked() {
                self.save_as(ctx);
            }
            ui.separator();
            if ui.button("Load platform record (CSV)…").clicked() {
                self.dialogs.request(Purpose::LoadRecord, "", ctx);
            }
            if ui.button("Export traces (CSV)…").clicked() {
                self.dialogs.request(Purpose::ExportCsv, "traces.csv", ctx);
            }
            if ui.button("Export plots (PNG)…").clicked() {
                self.dialogs.request(Purpose::ExportPng, "plots.png", ctx);
            }
            ui.separator();
            if ui.button("Quit").clicked() {
                ctx.send_viewport_cmd(egui::ViewportCommand::Close);
            }
        });
        ui.menu_button("Data", |ui| {
            if ui.button("Measured data & calibration…").clicked() {
                self.measured.open = true;
            }
            if ui.button("Load measured records (CSV)…").clicked() {
                self.measured.open = true;
                self.dialogs.request(Purpose::LoadMeasured, "", ctx);
            }
            if ui.button("Load the demo campaign").clicked() {
                self.measured.open = true;
                self.measured.load_files(MeasuredData::demo_campaign());
            }
        });
        ui.menu_button("Presets", |ui| {
            if self.shipped.is_empty() {
                ui.weak("no presets/ directory found");
            }
            for (name, path) in self.shipped.clone() {
                if ui
                    .button(&name)
                    .on_hover_text(path.display().to_string())
                    .clicked()
                {
                    self.guarded(Pending::LoadFile(path), ctx);
                }
            }
        });
        ui.menu_button("View", |ui| {
            let before = self.settings.theme;
            ui.radio_value(&mut self.settings.theme, Theme::System, "System theme");
            ui.radio_value(&mut self.settings.theme, Theme::Light, "Light");
            ui.radio_value(&mut self.settings.theme, Theme::Dark, "Dark");
            if self.settings.theme != before {
                ctx.set_theme(self.settings.theme.preference());
            }
            ui.separator();
            ui.checkbox(&mut self.settings.show_schematic, "Schematic");
            ui.checkbox(&mut self.settings.dwell_auto, "Auto-recompute dwell points");
            ui.checkbox(&mut self.settings.show_debug, "Frame-time overlay");
        });
    }

    fn toolbar_ui(&mut self, ui: &mut egui::Ui) {
        ui.horizontal(|ui| {
            let label = if self.want_running { "Pause" } else { "Run" };
            if ui
                .button(label)
                .on_hover_text("Run / pause (space bar)")
                .clicked()
            {
                self.toggle_running();
            }
            if ui
                .button("Reset")
                .on_hover_text("Back to rest at t = 0")
                .clicked()
            {
                self.reset();
            }
            ui.separator();
            ui.label("speed");
            let before = self.settings.speed;
            for s in [Speed::Slow, Speed::RealTime, Speed::Fast, Speed::Max] {
                ui.selectable_value(&mut self.settings.speed, s, s.label());
            }
            if self.settings.speed != before {
                self.send(Command::SetSpeed(self.settings.speed));
            }
            ui.separator();
            let v = &self.engine_view;
            let state = if self.engine_error.is_some() {
                RichText::new("stopped (error)").color(Color32::from_rgb(220, 50, 40))
            } else if v.running {
                RichText::new("running").color(Color32::from_rgb(40, 160, 60))
            } else {
                RichText::new("paused")
            };
            ui.label(state);
            ui.monospace(self.clock_text())
                .on_hover_text("Simulated time (the scopes' time axis) and how fast it runs");
            ui.separator();
            let modified = self.is_modified();
            let name = RichText::new(format!(
                "preset: {}{}",
                self.preset.name,
                if modified { " * modified" } else { "" }
            ));
            ui.label(if modified { name.italics() } else { name })
                .on_hover_text(&self.preset.description);
            if let Some(n) = &self.notice {
                ui.separator();
                let color = if n.error {
                    Color32::from_rgb(220, 50, 40)
                } else {
                    ui.visuals().weak_text_color()
                };
                ui.add(egui::Label::new(RichText::new(&n.text).color(color)).truncate());
            }
        });
    }

    fn controls_ui(&mut self, ui: &mut egui::Ui, ctx: &egui::Context) -> bool {
        ui.heading("Parameters");
        let changed = controls::params_ui(ui, &mut self.params, &mut self.field_errors);
        if let Some(e) = &self.param_error {
            ui.colored_label(Color32::from_rgb(220, 50, 40), e);
        }
        let effects = super::format::active_effects(&self.params);
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
                .add_enabled(self.is_modified(), egui::Button::new("Revert to preset"))
                .clicked()
            {
                self.params = self.preset.baseline;
                self.field_errors.clear();
                self.apply_params();
            }
        });
        ui.separator();
        ui.heading("Excitation");
        match controls::excitation_ui(ui, &mut self.settings.excitation) {
            ExcitationAction::None => {}
            ExcitationAction::Apply => {
                if let Some(p) = self.settings.excitation.problem() {
                    self.error(format!("excitation not applied: {p}"));
                } else {
                    self.apply_excitation();
                }
            }
            ExcitationAction::LoadRecord => self.dialogs.request(Purpose::LoadRecord, "", ctx),
            ExcitationAction::LoadRecordPath(p) => self.load_record_file(&p),
        }
        if let Some(p) = self.dialogs.open() {
            ui.weak(format!("file dialog open ({p:?})…"));
        }
        changed
    }

    fn side_ui(&mut self, ui: &mut egui::Ui) {
        if self.settings.show_schematic {
            ui.heading("Rig");
            let h = (ui.available_width() * 1.15).clamp(260.0, 460.0);
            schematic::schematic_ui(
                ui,
                self.traces.last_row().map(|r| &r.twin),
                &self.params,
                h,
                self.traces.pressure_range_pa(),
            );
            ui.separator();
        }
        ui.heading("Metrics");
        let (rows, platform) = self.traces.metrics.rows();
        ui.weak(format!(
            "over {:.1} s since the last change (ISO 2631-1 Wk)",
            self.traces.metrics.counted_s()
        ));
        egui::Grid::new("metrics")
            .striped(true)
            .num_columns(5)
            .show(ui, |ui| {
                for h in ["", "RMS", "a_w", "VDV", "SEAT"] {
                    ui.strong(h);
                }
                ui.end_row();
                ui.label("platform");
                ui.monospace(format!("{:.3}", platform.rms));
                ui.monospace(format!("{:.3}", platform.aw));
                ui.monospace(format!("{:.3}", platform.vdv));
                ui.label("");
                ui.end_row();
                for (name, m, seat) in rows {
                    ui.label(name);
                    ui.monospace(format!("{:.3}", m.rms));
                    ui.monospace(format!("{:.3}", m.aw));
                    ui.monospace(format!("{:.3}", m.vdv));
                    if seat.is_finite() {
                        ui.monospace(format!("{seat:.0} %"));
                    } else {
                        ui.monospace("–");
                    }
                    ui.end_row();
                }
            });
        ui.weak("RMS, a_w [m/s²]; VDV [m/s^1.75]; SEAT = a_w body / a_w platform");
        ui.label(format!(
            "end-stop contacts (twin): {}",
            self.traces.contact_count
        ));
        if let Some(r) = self.traces.last_row() {
            ui.weak(format!(
                "now: u {:+.1} mm, p1 {:.1} bar, p2 {:.1} bar",
                r.twin.u * MM_PER_M,
                r.twin.p1 * BAR_PER_PA,
                r.twin.p2 * BAR_PER_PA
            ));
        }
    }

    fn confirm_ui(&mut self, ctx: &egui::Context) {
        let Some(action) = self.pending.clone() else {
            return;
        };
        let mut decision: Option<bool> = None;
        egui::Modal::new(egui::Id::unique("discard")).show(ctx, |ui| {
            ui.set_width(360.0);
            ui.heading("Unsaved changes");
            ui.label(format!(
                "The parameters differ from the preset “{}”. Discard the changes?",
                self.preset.name
            ));
            ui.add_space(8.0);
            ui.horizontal(|ui| {
                if ui.button("Discard changes").clicked() {
                    decision = Some(true);
                }
                if ui.button("Cancel").clicked() {
                    decision = Some(false);
                }
            });
        });
        match decision {
            Some(true) => {
                self.pending = None;
                self.run_pending(action, ctx);
            }
            Some(false) => self.pending = None,
            None => {}
        }
    }

    fn debug_overlay(&self, ctx: &egui::Context) {
        egui::Area::new(egui::Id::unique("frame_time"))
            .anchor(egui::Align2::RIGHT_BOTTOM, [-8.0, -8.0])
            .order(egui::Order::Foreground)
            .interactable(false)
            .show(ctx, |ui| {
                egui::Frame::popup(ui.style()).show(ui, |ui| {
                    let s = &self.frame_stats;
                    ui.monospace(format!(
                        "UI build {:.2} ms (max {:.2})\n  scopes {:.2} ms, freq. plots {:.2} ms\nframe CPU {}\n{:.0} frames/s\nfreq. curves {:.2} ms",
                        s.mean_ui_ms(),
                        s.max_ui_ms(),
                        s.scopes_ms,
                        s.freq_ms,
                        s.cpu_ms
                            .map(|c| format!("{c:.2} ms"))
                            .unwrap_or_else(|| "n/a".into()),
                        s.fps(),
                        self.analytic.curves().compute_ms,
                    ));
                });
            });
    }

    fn window_title(&self) -> String {
        format!(
            "seat-twin — {}{}",
            self.preset.name,
            if self.is_modified() {
                " (modified)"
            } else {
                ""
            }
        )
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
