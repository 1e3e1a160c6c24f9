//! The measured-data window: load measured records, overlay them on the twin, show the
//! residual and its diagnosis, calibrate in the background (progress, cancel) and hand the
//! result back to the live twin.
//!
//! All work runs on worker threads through [`crate::identify`] — the same code as
//! `seat-twin replay` and `seat-twin calibrate` — and comes back over channels polled each
//! frame; the UI thread only draws.

mod replay;
mod views;

pub use replay::ReplayView;
use replay::replay_view;

use super::frequency::TWIN;
use super::job::{Job, Waker};
use super::style::{CALIBRATED, MEASURED, RESIDUAL};
use super::units::MM_PER_M;
use crate::dataset::{self, Record, RecordKind};
use crate::identify::replay::{MetricOptions, PreparedRecord};
use crate::identify::{
    self, CalibrationOptions, CalibrationReport, ErrorSummary, IdentifyError, Progress,
};
use crate::params::Params;
use egui::{Color32, RichText};
use egui_plot::{Line, Plot, PlotPoints};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

/// A record loaded in the window, with its metric preparation.
pub struct LoadedMeasured {
    /// The record as read.
    pub record: Record,
    /// Filtered channels and noise estimates of the error metric.
    pub prepared: Arc<PreparedRecord>,
    /// Used by the calibration.
    pub include: bool,
}

impl LoadedMeasured {
    /// The file name shown.
    pub fn name(&self) -> &str {
        &self.prepared.name
    }
}

/// A calibration running in the background.
/// Cancel is the job's own flag, which `identify::calibrate_with` checks at each replay.
struct Calibration {
    job: Job<CalibrationReport>,
    progress: Arc<Mutex<Option<Progress>>>,
    started: std::time::Instant,
}

/// What the window asks the app to do.
#[derive(Debug, Clone, PartialEq)]
pub enum MeasuredAction {
    /// Nothing.
    None,
    /// Open the file dialog for measured records.
    OpenDialog,
    /// Put these (calibrated) parameters on the live twin.
    Apply(Box<Params>),
    /// Put them on the live twin and save them as a preset (dialog).
    ApplyAndSave(Box<Params>),
    /// Write the calibration report into a folder (dialog).
    ExportReport,
}

/// State of the measured-data window.
pub struct MeasuredData {
    /// Window shown.
    pub open: bool,
    /// Loaded records.
    pub records: Vec<LoadedMeasured>,
    /// Index of the record drawn.
    pub selected: usize,
    /// Options of the calibration (defaults as in `seat-twin calibrate`).
    pub options: CalibrationOptions,
    /// Path typed by hand (for desktops without a file dialog).
    pub typed_path: String,
    waker: Waker,
    loading: Option<Job<Vec<(Record, PreparedRecord)>>>,
    /// The replay running: record index, parameters, job.
    replaying: Option<(usize, Params, Job<ReplayView>)>,
    view: Option<ReplayView>,
    calibration: Option<Calibration>,
    report: Option<CalibrationReport>,
    /// Replays of the selected record with the calibrated parameters, for the overlay.
    calibrated_view: Option<ReplayView>,
    calibrated_job: Option<(usize, Job<ReplayView>)>,
    last_error: Option<String>,
    last_info: Option<String>,
    /// Curves switched off in the plots' legends (`plot/name`).
    hidden: std::collections::BTreeSet<String>,
}

impl MeasuredData {
    /// An empty window; `waker` repaints the UI when a job finishes.
    pub fn new(waker: Arc<dyn Fn() + Send + Sync>) -> Self {
        Self {
            open: false,
            records: Vec::new(),
            selected: 0,
            options: CalibrationOptions::default(),
            typed_path: String::new(),
            waker,
            loading: None,
            replaying: None,
            view: None,
            calibration: None,
            report: None,
            calibrated_view: None,
            calibrated_job: None,
            last_error: None,
            last_info: None,
            hidden: Default::default(),
        }
    }

    /// Reads measured records on a worker thread (all or none: one bad file names itself
    /// and nothing is added).
    pub fn load_files(&mut self, paths: Vec<PathBuf>) {
        if paths.is_empty() {
            return;
        }
        let metric = self.options.metric;
        self.loading = Some(Job::spawn(
            "seat-twin-load",
            self.waker.clone(),
            move |_| read_measured(&paths, &metric),
        ));
        self.last_error = None;
    }

    /// Loads what a typed path names: files separated by `;`, folders, `*`/`?` patterns
    /// (see [`super::files::expand_paths`]); a path that names nothing is the window's error.
    pub fn load_typed(&mut self, text: &str) {
        match super::files::expand_paths(text) {
            Ok(paths) => self.load_files(paths),
            Err(e) => self.last_error = Some(format!("not loaded: {e}")),
        }
    }

    /// The demo campaign shipped in `assets/demo-campaign/`, if found.
    pub fn demo_campaign() -> Vec<PathBuf> {
        let dirs = [
            PathBuf::from("assets/demo-campaign"),
            Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/demo-campaign"),
        ];
        for d in dirs {
            if let Ok(entries) = std::fs::read_dir(&d) {
                let mut v: Vec<PathBuf> = entries
                    .filter_map(|e| e.ok().map(|e| e.path()))
                    .filter(|p| p.extension().is_some_and(|x| x == "csv"))
                    .collect();
                v.sort();
                if !v.is_empty() {
                    return v;
                }
            }
        }
        Vec::new()
    }

    /// Any job running (loading, replay, calibration).
    pub fn busy(&self) -> bool {
        self.loading.is_some()
            || self.replaying.is_some()
            || self.calibration.is_some()
            || self.calibrated_job.is_some()
    }

    /// The current replay of the selected record, if done.
    pub fn view(&self) -> Option<&ReplayView> {
        self.view.as_ref()
    }

    /// The last calibration's result.
    pub fn report(&self) -> Option<&CalibrationReport> {
        self.report.as_ref()
    }

    /// A calibration is running.
    pub fn calibrating(&self) -> bool {
        self.calibration.is_some()
    }

    /// The last error shown in the window.
    pub fn last_error(&self) -> Option<&str> {
        self.last_error.as_deref()
    }

    /// The last information line shown in the window.
    pub fn last_info(&self) -> Option<&str> {
        self.last_info.as_deref()
    }

    /// Starts a calibration of the included records from `params`.
    pub fn start_calibration(&mut self, params: &Params) {
        if self.calibration.is_some() {
            return;
        }
        let records: Vec<Record> = self
            .records
            .iter()
            .filter(|r| r.include)
            .map(|r| r.record.clone())
            .collect();
        if records.is_empty() {
            self.last_error = Some("no record selected for calibration".into());
            return;
        }
        let progress = Arc::new(Mutex::new(None));
        let (p2, w2) = (progress.clone(), self.waker.clone());
        let params = *params;
        let options = self.options.clone();
        let job = Job::spawn("seat-twin-calibrate", self.waker.clone(), move |ctx| {
            let cb = move |p: &Progress| {
                if let Ok(mut g) = p2.lock() {
                    *g = Some(p.clone());
                }
                w2();
            };
            identify::calibrate_with(&params, &records, &options, &ctx.cancel_flag(), &cb).map_err(
                |e| match e {
                    IdentifyError::Cancelled => "calibration cancelled".to_string(),
                    e => format!("calibration failed: {e}"),
                },
            )
        });
        self.calibration = Some(Calibration {
            job,
            progress,
            started: std::time::Instant::now(),
        });
        self.last_error = None;
        self.last_info = None;
    }

    /// Asks the running calibration to stop (it ends at its next replay).
    pub fn cancel_calibration(&mut self) {
        if let Some(c) = &self.calibration {
            c.job.cancel();
        }
    }

    /// Collects finished jobs and starts the replay of the selected record when the live
    /// parameters or the selection changed. Call once per frame.
    pub fn poll(&mut self, params: &Params) {
        if let Some(r) = self.loading.as_ref().and_then(Job::poll) {
            self.loading = None;
            match r {
                Ok(recs) => {
                    let n = recs.len();
                    let warnings: Vec<String> = recs
                        .iter()
                        .flat_map(|(r, _)| r.warnings.iter().cloned())
                        .collect();
                    self.selected = self.records.len();
                    for (record, prepared) in recs {
                        // The same file loaded twice replaces the earlier copy.
                        self.records.retain(|r| r.record.path != record.path);
                        self.records.push(LoadedMeasured {
                            record,
                            prepared: Arc::new(prepared),
                            include: true,
                        });
                    }
                    self.selected = self.selected.min(self.records.len().saturating_sub(n));
                    self.view = None;
                    self.calibrated_view = None;
                    let loaded = loaded_text(n, self.records.len());
                    self.last_info = Some(if warnings.is_empty() {
                        loaded
                    } else {
                        format!("{loaded}; {}", warnings.join(" "))
                    });
                }
                Err(e) => self.last_error = Some(e),
            }
        }
        if let Some((_, _, job)) = &self.replaying
            && let Some(r) = job.poll()
        {
            self.replaying = None;
            match r {
                Ok(v) => self.view = Some(v),
                Err(e) => {
                    self.last_error = Some(format!("replay failed: {e}"));
                    self.view = None;
                }
            }
        }
        if let Some((_, job)) = &self.calibrated_job
            && let Some(r) = job.poll()
        {
            self.calibrated_job = None;
            self.calibrated_view = r.ok();
        }
        if let Some(c) = &self.calibration
            && let Some(r) = c.job.poll()
        {
            let secs = c.started.elapsed().as_secs_f64();
            self.calibration = None;
            match r {
                Ok(rep) => {
                    self.last_info = Some(format!(
                        "calibrated in {secs:.1} s ({} replays): {}",
                        rep.evaluations,
                        rep.verdict.name()
                    ));
                    self.report = Some(rep);
                    self.calibrated_view = None;
                }
                Err(e) => self.last_error = Some(e),
            }
        }
        self.start_replays(params);
    }

    fn start_replays(&mut self, params: &Params) {
        let Some(rec) = self.records.get(self.selected) else {
            self.view = None;
            return;
        };
        let stale = |v: Option<(usize, &Params)>| v != Some((self.selected, params));
        let current = self.view.as_ref().map(|v| (v.record, &v.params));
        let running = self.replaying.as_ref().map(|(i, p, _)| (*i, p));
        if stale(current) && running.is_none() {
            let (p, rec, i) = (*params, rec.prepared.clone(), self.selected);
            let job = Job::spawn("seat-twin-replay", self.waker.clone(), move |_| {
                replay_view(&p, &rec, i)
            });
            self.replaying = Some((i, p, job));
        }
        if let Some(rep) = &self.report {
            let have = self.calibrated_view.as_ref().map(|v| v.record);
            if have != Some(self.selected) && self.calibrated_job.is_none() {
                let (p, rec, i) = (rep.params, rec.prepared.clone(), self.selected);
                let job = Job::spawn("seat-twin-replay", self.waker.clone(), move |_| {
                    replay_view(&p, &rec, i)
                });
                self.calibrated_job = Some((i, job));
            }
        }
    }

    /// The window; returns what the app should do.
    /// It stays inside `area` (the app passes the space below its menu, toolbar and
    /// path prompt, so the window never hides them).
    pub fn window_ui(
        &mut self,
        ctx: &egui::Context,
        params: &Params,
        area: egui::Rect,
    ) -> MeasuredAction {
        let mut action = MeasuredAction::None;
        let mut open = self.open;
        let size = egui::vec2(1300.0, 820.0).min(area.size() - egui::vec2(24.0, 24.0));
        egui::Window::new("Measured data")
            .open(&mut open)
            .constrain_to(area)
            .default_pos(area.min + egui::vec2(12.0, 12.0))
            .default_size(size)
            .vscroll(true)
            .show(ctx, |ui| action = self.contents_ui(ui, params));
        self.open = open;
        action
    }

    fn contents_ui(&mut self, ui: &mut egui::Ui, params: &Params) -> MeasuredAction {
        let mut action = MeasuredAction::None;
        ui.horizontal_wrapped(|ui| {
            if ui.button("Load measured records…").clicked() {
                action = MeasuredAction::OpenDialog;
            }
            if ui
                .button("Load demo campaign")
                .on_hover_text("assets/demo-campaign: 8 sine tests, a bump and a ride")
                .clicked()
            {
                self.load_files(Self::demo_campaign());
            }
            if let Some(text) = super::files::typed_path_ui(
                ui,
                &mut self.typed_path,
                "files; a folder; campaign/*.csv",
                240.0,
            ) {
                self.load_typed(&text);
            }
            if !self.records.is_empty() && ui.button("Clear").clicked() {
                self.records.clear();
                self.view = None;
                self.calibrated_view = None;
                self.selected = 0;
            }
        });
        if self.loading.is_some() {
            ui.horizontal(|ui| {
                ui.spinner();
                ui.label("reading…");
            });
        }
        if let Some(e) = &self.last_error {
            ui.colored_label(super::style::ERROR_TEXT, e);
        }
        if let Some(i) = &self.last_info {
            ui.weak(i);
        }
        if self.records.is_empty() {
            ui.label(
                "Load one or more measured records (CSV: t, v_in, u; optional x, xdd, ydd, \
                 p1, p2; SI). The twin replays the selected one with the live parameters; \
                 Calibrate fits Cd, τ (and the mass) and looks for a missing effect.",
            );
            return action;
        }
        ui.separator();
        ui.columns(2, |cols| {
            self.overlay_ui(&mut cols[0]);
            self.records_ui(&mut cols[1]);
            cols[1].separator();
            let a = self.calibration_ui(&mut cols[1], params);
            if a != MeasuredAction::None {
                action = a;
            }
            cols[1].separator();
            self.diagnosis_ui(&mut cols[1]);
        });
        action
    }

    fn records_ui(&mut self, ui: &mut egui::Ui) {
        ui.strong(
            "Records (tick “use” to include one in the calibration; click a name to draw it)",
        );
        crate::gui::plotkit::table_ui(
            ui,
            "measured_records",
            &["use", "file", "duration", "rate", "channels"],
            |ui| {
                for (i, r) in self.records.iter_mut().enumerate() {
                    ui.checkbox(&mut r.include, "");
                    if ui
                        .selectable_label(self.selected == i, &r.prepared.name)
                        .on_hover_text(metadata_text(&r.record))
                        .clicked()
                    {
                        self.selected = i;
                    }
                    ui.monospace(format!("{:.1} s", r.record.duration_s()));
                    ui.monospace(format!("{:.0} Hz", r.record.sample_rate_hz()));
                    ui.label(channels_text(&r.record));
                    ui.end_row();
                }
            },
        );
    }

    fn calibration_ui(&mut self, ui: &mut egui::Ui, params: &Params) -> MeasuredAction {
        let mut action = MeasuredAction::None;
        ui.strong("Calibration");
        let n = self.records.iter().filter(|r| r.include).count();
        if let Some(c) = &self.calibration {
            let p = c.progress.lock().ok().and_then(|g| g.clone());
            // The button first: the progress text changes length every frame, and a button
            // after it would move under the pointer.
            ui.horizontal(|ui| {
                ui.spinner();
                if c.job.is_cancelled() {
                    ui.weak("cancelling…");
                } else if ui.button("Cancel calibration").clicked() {
                    c.job.cancel();
                }
                ui.label(match &p {
                    Some(p) => format!(
                        "{} — {} replays, {:.0} s",
                        p.stage,
                        p.evaluations,
                        c.started.elapsed().as_secs_f64()
                    ),
                    None => "starting…".into(),
                });
            });
        } else {
            ui.horizontal(|ui| {
                if ui
                    .add_enabled(
                        n > 0,
                        egui::Button::new(format!("Calibrate on {n} record(s)")),
                    )
                    .on_hover_text(
                        "From the live parameters: the paper's method, then Levenberg–Marquardt \
                         on Cd, τ (and the mass), then the effect library ranked by ΔBIC — \
                         the same as `seat-twin calibrate`",
                    )
                    .clicked()
                {
                    self.start_calibration(params);
                }
            });
        }
        let Some(r) = &self.report else {
            return action;
        };
        ui.label(
            RichText::new(format!("verdict: {}", r.verdict.name()))
                .strong()
                .color(match r.verdict {
                    identify::Verdict::Explained => super::style::OK_TEXT,
                    identify::Verdict::NoMissingEffect => super::style::NEUTRAL_TEXT,
                    identify::Verdict::Unexplained => super::style::CAUTION_TEXT,
                    identify::Verdict::InsufficientData => super::style::INSUFFICIENT_TEXT,
                }),
        );
        for m in &r.missing {
            ui.label(format!("missing: {m}"));
        }
        crate::gui::plotkit::table_ui(
            ui,
            "measured_errors",
            &["stage", "weighted error", "du/dt [mm/s]", "ydd [m/s²]"],
            |ui| {
                let mut row = |name: &str, e: &ErrorSummary| {
                    ui.label(name);
                    ui.monospace(format!("{:.3}", e.value));
                    ui.monospace(
                        e.channels
                            .get("du")
                            .map(|v| format!("{:.3}", v * MM_PER_M))
                            .unwrap_or_else(|| "–".into()),
                    );
                    ui.monospace(
                        e.channels
                            .get("ydd")
                            .map(|v| format!("{v:.4}"))
                            .unwrap_or_else(|| "–".into()),
                    );
                    ui.end_row();
                };
                row("nominal", &r.error_nominal);
                if let Some(b) = &r.error_baseline {
                    row("paper's method", b);
                }
                row("before (Cd, τ re-fitted)", &r.error_before);
                row("after (with effects)", &r.error_after);
            },
        );
        if let Some(v) = &r.error_validation {
            ui.monospace(format!(
                "validation (held-out records): weighted error {:.3} before → {:.3} after",
                v.before, v.after
            ));
        }
        ui.weak("weighted error: the fit's metric, 1.0 = sensor-noise level");
        let worst = |e: &identify::raw_error::RawErrorReport| {
            e.worst
                .as_ref()
                .map_or("–".to_string(), |w| format!("{:.1}×", w.ratio))
        };
        ui.label(
            RichText::new(format!(
                "raw error (the verdict's measure, worst band against its noise floor, limit \
                 {:.1}): before {}, after {}{}",
                r.raw_error_after.limit,
                worst(&r.raw_error_before),
                worst(&r.raw_error_after),
                r.raw_error_proposed
                    .as_ref()
                    .map(|p| format!(", with the proposed terms {}", worst(p)))
                    .unwrap_or_default()
            ))
            .strong(),
        );
        ui.label(r.raw_error_after.summary());
        for t in &r.proposed {
            ui.label(format!("proposed beyond the library: {}", t.description));
        }
        for d in &r.drifts {
            ui.label(format!("drift: {}", d.description));
        }
        for v in &r.calibrated {
            ui.monospace(super::format::fitted(&v.name, v.value, v.std));
        }
        if r.effects.is_empty() {
            ui.label("effects added: none");
        }
        for e in &r.effects {
            let params: Vec<String> = e
                .params
                .iter()
                .map(|(k, v)| {
                    let std = e.uncertainties.get(k).copied().unwrap_or(f64::NAN);
                    super::format::fitted(k, *v, std)
                })
                .collect();
            ui.label(RichText::new(format!("added: {}", e.effect.name())).strong());
            ui.monospace(params.join(", "));
            ui.weak(glyph_safe(&e.evidence));
        }
        ui.collapsing("candidate scores (ΔBIC, negative = better)", |ui| {
            crate::gui::plotkit::table_ui(
                ui,
                "measured_candidates",
                &["round", "effect", "ΔBIC", "share removed"],
                |ui| {
                    for c in &r.candidates {
                        ui.monospace(c.round.to_string());
                        ui.label(c.effect.name());
                        ui.monospace(format!("{:.1}", c.score));
                        ui.monospace(format!("{:.0} %", c.relative_gain * 100.0));
                        ui.end_row();
                    }
                },
            );
        });
        for note in &r.notes {
            ui.weak(glyph_safe(note));
        }
        ui.horizontal(|ui| {
            if ui
                .button("Apply to the live twin")
                .on_hover_text("The calibrated parameters and effects replace the live ones")
                .clicked()
            {
                action = MeasuredAction::Apply(Box::new(r.params));
            }
            if ui.button("Apply and save as preset…").clicked() {
                action = MeasuredAction::ApplyAndSave(Box::new(r.params));
            }
            if ui
                .button("Export report…")
                .on_hover_text(
                    "report.md, report.json, calibrated.toml and the plots into a folder, \
                     as `seat-twin calibrate --out` writes them",
                )
                .clicked()
            {
                action = MeasuredAction::ExportReport;
            }
        });
        action
    }
}

/// "3 records loaded (10 in the window)": what was just read and what the list holds.
fn loaded_text(new: usize, total: usize) -> String {
    let records = |n: usize| if n == 1 { "record" } else { "records" };
    if new == total {
        format!("{new} {} loaded", records(new))
    } else {
        format!("{new} {} loaded ({total} in the window)", records(new))
    }
}

/// Reads and prepares records; the first bad file is the error.
fn read_measured(
    paths: &[PathBuf],
    metric: &MetricOptions,
) -> Result<Vec<(Record, PreparedRecord)>, String> {
    let mut out = Vec::with_capacity(paths.len());
    for p in paths {
        let rec = dataset::read_record(p, RecordKind::Measured).map_err(|e| e.to_string())?;
        let prep = PreparedRecord::new(&rec, metric).map_err(|e| e.to_string())?;
        out.push((rec, prep));
    }
    Ok(out)
}

fn channels_text(r: &Record) -> String {
    let mut v = vec!["v_in", "u"];
    for (name, present) in [
        ("x", r.x.is_some()),
        ("xdd", r.xdd.is_some()),
        ("ydd", r.ydd.is_some()),
        ("p1", r.p1.is_some()),
        ("p2", r.p2.is_some()),
    ] {
        if present {
            v.push(name);
        }
    }
    v.join(", ")
}

fn metadata_text(r: &Record) -> String {
    if r.metadata.is_empty() {
        return r.path.display().to_string();
    }
    let mut s = r.path.display().to_string();
    for (k, v) in &r.metadata {
        s.push_str(&format!("\n{k}: {v}"));
    }
    s
}

/// Text from the engine's reports with the few characters egui's bundled font lacks
/// (arrows, combining dots) spelled out.
fn glyph_safe(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '→' => out.push_str("->"),
            '⇒' => out.push_str("=>"),
            'ẍ' => out.push_str("xdd"),
            'ẏ' => out.push_str("yd"),
            '\u{0307}' => out.push('\''),
            '⁻' => out.push('-'),
            'ᵀ' => out.push_str("^T"),
            c => out.push(c),
        }
    }
    out
}
