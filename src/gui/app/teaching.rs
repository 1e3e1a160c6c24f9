//! Teaching: the Lessons window, presentation mode, setup links (the web page's `#s=…`,
//! View ▸ Copy/Paste setup link) and the state the web page's JavaScript API reads.

use super::{Notice, SeatTwinApp};
use crate::engine::{Command, Speed};
use crate::gui::controls;
use crate::gui::lessons::{LESSONS, LessonAction, LessonView, LessonsPanel};
use crate::gui::share::{self, Setup};
use crate::params::Params;
use crate::preset::Preset;

/// UI scale of presentation mode (readable from the back of a lecture hall).
pub const PRESENTATION_SCALE: f32 = 1.75;

/// The teaching state of the app.
#[derive(Default)]
pub struct Teaching {
    /// The Lessons window.
    pub lessons: LessonsPanel,
    /// Presentation mode: large text, thick lines.
    pub presentation: bool,
    /// The UI scale before presentation mode.
    scale_before: Option<f32>,
    /// The "paste setup link" prompt, while open.
    paste: Option<String>,
    /// The loop was unstable in the last frame (linear verdict, the twin's watch, or a
    /// divergence).
    pub unstable: bool,
    /// Repaints the app after a change from outside a frame (the web page's API).
    pub ctx: Option<egui::Context>,
    /// Simulated time stepped in the frames [s] and the wall time it took [s] (web only:
    /// on the desktop the engine steps in its thread and these stay 0).
    pumped: (f64, f64),
}

impl Teaching {
    /// One frame's engine work: `wall` spent stepping in
    /// [`crate::engine::EngineHandle::pump`] (zero on the desktop), `simulated` seconds gained.
    pub fn engine_stepped(&mut self, wall: std::time::Duration, simulated: f64) {
        if !wall.is_zero() && simulated > 0.0 {
            self.pumped.0 += simulated;
            self.pumped.1 += wall.as_secs_f64();
        }
    }

    /// Simulated over wall time spent stepping in the frames (the web engine's own
    /// real-time factor, without the time the page spends drawing); 0 before any step.
    pub fn engine_rtf(&self) -> f64 {
        if self.pumped.1 > 0.0 {
            self.pumped.0 / self.pumped.1
        } else {
            0.0
        }
    }
}

impl SeatTwinApp {
    /// The current setup (what a link carries). A preset that is not compiled in travels as
    /// the paper's preset with every parameter that differs.
    pub fn setup(&self) -> Setup {
        let preset = if share::shipped_preset(&self.preset.name).is_ok() {
            self.preset.name.clone()
        } else {
            "paper".to_string()
        };
        Setup {
            preset,
            params: self.params,
            excitation: self.settings.excitation.clone(),
            speed: self.settings.speed,
            presentation: self.teach.presentation,
            lesson: self.teach.lessons.current,
        }
    }

    /// The current setup as a link string (`1;preset=…`, without `#s=`).
    pub fn link(&self) -> String {
        self.setup().encode()
    }

    /// Restores a setup from a link string; a bad link leaves the app as it was and says
    /// why (the error is also returned).
    pub fn apply_link(&mut self, text: &str) -> Result<(), String> {
        match Setup::decode(text) {
            Ok(s) => {
                self.apply_setup(s);
                self.info("setup restored from the link");
                Ok(())
            }
            Err(e) => {
                self.error(format!("{e}; the setup was not changed"));
                Err(e)
            }
        }
    }

    /// Applies a setup: its preset (the "modified" marker compares against it), its
    /// parameters, excitation, speed, view and lesson step; the run restarts from rest.
    pub fn apply_setup(&mut self, s: Setup) {
        let base = share::shipped_preset(&s.preset).unwrap_or_else(|_| Preset::paper());
        self.set_preset(
            Preset {
                params: s.params,
                ..base.clone()
            },
            None,
            false,
        );
        self.preset.name = s.preset.clone();
        self.preset.baseline = base.params;
        self.settings.excitation = s.excitation;
        self.apply_excitation();
        self.set_speed(s.speed);
        self.set_presentation(s.presentation);
        if let Some(n) = s.lesson {
            self.teach.lessons.started(n, self.params);
        }
    }

    /// Starts lesson step `n`: its preset, its parameters and excitation, from rest.
    pub fn start_lesson(&mut self, n: usize) {
        let Some(lesson) = LESSONS.get(n) else {
            return;
        };
        let preset = share::shipped_preset(lesson.preset).unwrap_or_else(|_| Preset::paper());
        let mut params = preset.params;
        LessonsPanel::set_up(n, &mut params, &mut self.settings.excitation);
        let baseline = preset.params;
        self.set_preset(Preset { params, ..preset }, None, false);
        self.preset.name = lesson.preset.to_string();
        self.preset.baseline = baseline;
        self.apply_excitation();
        self.reset();
        self.teach.lessons.started(n, self.params);
    }

    /// Sets the slider labelled `label` to `shown` [display units] through the same path a
    /// drag takes ([`controls::edit_slider`]), then applies it to the engine.
    pub fn set_slider(&mut self, label: &str, shown: f64) -> Result<(), String> {
        let mut p = self.params;
        controls::edit_slider(label, shown, &mut p, self.controls.field_errors_mut())?;
        if p != self.params {
            self.params = p;
            self.apply_params();
        }
        Ok(())
    }

    /// Background jobs as JSON (the web page's API): the sine dwell (`running`, `done`,
    /// `total` frequencies, `points` shown, `cancelled`) and Tune (`running`, `done`, `total`
    /// evaluations, `result`: whether one is there, `message`: cancelled or failed).
    pub fn jobs_json(&self) -> String {
        let dwell = self.centre.dwell().progress();
        let tune = self.tune.last_progress();
        serde_json::json!({
            "dwell": {
                "running": dwell.is_some(),
                "done": dwell.map_or(0, |p| p.0),
                "total": dwell.map_or(0, |p| p.1),
                "points": self.centre.dwell().mag.len(),
                "cancelled": self.centre.dwell().cancelled,
            },
            "tune": {
                "running": self.tune.is_running(),
                "done": tune.map_or(0, |p| p.0),
                "total": tune.map_or(0, |p| p.1),
                "result": self.tune.result().is_some(),
                "message": self.tune.message().map(|m| m.0.clone()),
            },
        })
        .to_string()
    }

    /// Forgets the frame times so far (the web page's API: a measurement from now on).
    pub fn reset_frame_stats(&mut self) {
        self.window.stats.clear();
    }

    /// Starts the sine dwell of the twin now, as the Recompute button does.
    pub fn start_dwell(&mut self) {
        self.centre.dwell_mut().start(&self.params);
    }

    /// Cancels the sine dwell, as its Cancel button does.
    pub fn cancel_dwell(&mut self) {
        self.centre.dwell_mut().cancel();
    }

    /// Opens the file dialog for `purpose`, as the File menu does (the web page's API: the
    /// browser's picker for a preset or a record, downloads for a preset, the traces' CSV
    /// and the plots).
    pub fn request_file_by_api(&mut self, purpose: crate::gui::files::Purpose) {
        use crate::gui::files::Purpose;
        let name = match purpose {
            Purpose::ExportCsv => "traces.csv".to_string(),
            Purpose::ExportPng => "plots.png".to_string(),
            Purpose::SavePreset => format!("{}.toml", self.preset.name),
            _ => String::new(),
        };
        let name = name.as_str();
        if let Some(ctx) = self.teach.ctx.clone() {
            self.request_file(purpose, name, &ctx);
        }
    }

    /// Shows an error message under the toolbar (until replaced).
    pub fn show_error(&mut self, text: impl Into<String>) {
        self.error(text);
    }

    /// Asks for a frame (after a change from outside one: the web page's API).
    pub fn repaint(&self) {
        if let Some(ctx) = &self.teach.ctx {
            ctx.request_repaint();
        }
    }

    /// Sets the simulation speed.
    pub fn set_speed(&mut self, speed: Speed) {
        self.settings.speed = speed;
        self.send(Command::SetSpeed(speed));
    }

    /// What happens when a finite excitation ends: restart (the app's default) or pause at
    /// its end ([`Command::SetRepeat`]).
    pub fn set_repeat(&mut self, repeat: bool) {
        self.send(Command::SetRepeat(repeat));
    }

    /// Presentation mode on or off: large text (UI scale [`PRESENTATION_SCALE`]) and thick
    /// plot lines; off restores the scale from before.
    pub fn set_presentation(&mut self, on: bool) {
        if on == self.teach.presentation {
            return;
        }
        self.teach.presentation = on;
        let Some(ctx) = self.teach.ctx.clone() else {
            return;
        };
        if on {
            self.teach.scale_before = Some(self.settings.ui_scale);
            self.set_ui_scale(&ctx, PRESENTATION_SCALE);
        } else {
            let back = self.teach.scale_before.take().unwrap_or(1.0);
            self.set_ui_scale(&ctx, back);
        }
        crate::gui::plotkit::set_presentation(&ctx, on);
    }

    /// The Lessons window (while open), the paste prompt, and the lesson check of this frame.
    pub(super) fn teaching_ui(&mut self, ctx: &egui::Context) {
        if self.teach.ctx.is_none() {
            self.teach.ctx = Some(ctx.clone());
            crate::gui::plotkit::set_presentation(ctx, self.teach.presentation);
        }
        let mut open = self.teach.lessons.open;
        let mut action = LessonAction::None;
        if open {
            egui::Window::new("Lessons")
                .open(&mut open)
                .default_width(420.0)
                .default_pos(ctx.content_rect().right_top() + egui::vec2(-440.0, 80.0))
                .show(ctx, |ui| {
                    egui::ScrollArea::vertical()
                        .max_height(ctx.content_rect().height() * 0.7)
                        .show(ui, |ui| action = self.teach.lessons.ui(ui));
                });
            self.teach.lessons.open = open;
        }
        if let LessonAction::Start(n) = action {
            self.start_lesson(n);
        }
        self.paste_prompt_ui(ctx);
        let (rows, platform) = self.traces.metrics.rows();
        let view = LessonView {
            params: &self.params,
            excitation: &self.settings.excitation,
            unstable: self.teach.unstable,
            counted_s: self.traces.metrics.counted_s(),
            seat_twin_percent: rows[0].2,
            seat_passive_percent: rows[2].2,
            aw_platform: platform.aw,
        };
        if self.teach.lessons.check(&view)
            && let Some(n) = self.teach.lessons.current
        {
            self.info(format!("lesson step {} done", n + 1));
        }
    }

    /// The View menu's teaching entries.
    pub(super) fn teaching_menu_ui(&mut self, ui: &mut egui::Ui) {
        if ui.button("Lessons…").clicked() {
            self.teach.lessons.open = true;
        }
        let mut on = self.teach.presentation;
        if ui
            .checkbox(&mut on, "Presentation mode")
            .on_hover_text("Large text and thick lines, for a projector")
            .changed()
        {
            self.set_presentation(on);
        }
        if ui
            .button("Copy setup link")
            .on_hover_text(
                "Preset, controller, excitation and view as one short text (the web page's \
                 #s=… link); paste it into the web page's address or here",
            )
            .clicked()
        {
            let text = self.share_text();
            ui.ctx().copy_text(text);
            self.info("setup link copied");
        }
        if ui.button("Paste setup link…").clicked() {
            self.teach.paste = Some(String::new());
        }
    }

    /// The link as it is shared: the page's address with `#s=` on the web, the bare string
    /// on the desktop (the web page and this app read both).
    fn share_text(&self) -> String {
        #[cfg(target_arch = "wasm32")]
        {
            share::page_link(&self.link())
        }
        #[cfg(not(target_arch = "wasm32"))]
        {
            format!("#s={}", self.link())
        }
    }

    fn paste_prompt_ui(&mut self, ctx: &egui::Context) {
        let Some(mut text) = self.teach.paste.take() else {
            return;
        };
        let mut keep = true;
        let mut apply = false;
        egui::Window::new("Paste setup link")
            .collapsible(false)
            .show(ctx, |ui| {
                ui.label("A setup link (the whole address, or the part from #s=):");
                let r = ui.add(egui::TextEdit::singleline(&mut text).desired_width(420.0));
                apply = r.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter));
                ui.horizontal(|ui| {
                    apply |= ui.button("Apply").clicked();
                    keep = !ui.button("Cancel").clicked();
                });
            });
        if apply {
            let fragment = text.split_once('#').map_or(text.as_str(), |(_, f)| f);
            if self.apply_link(fragment).is_ok() {
                return;
            }
        }
        if keep {
            self.teach.paste = Some(text);
        }
    }

    /// The page's `window.seatTwin.state()`: simulated time \[s\], a_w of each model [m/s²]
    /// over the running metrics (500 Hz, the first 1 s left out, as the scopes' table),
    /// the twin's largest |u| \[m\], the stability verdict, the preset; then the lesson step,
    /// real-time factor and frame times.
    pub fn state_json(&self) -> String {
        let (rows, platform) = self.traces.metrics.rows();
        let stats = self.frame_stats();
        let lesson = self.teach.lessons.current;
        serde_json::json!({
            "t_s": self.engine.view.t,
            "aw": {"twin": rows[0].1.aw, "linear": rows[1].1.aw, "passive": rows[2].1.aw},
            "max_abs_u_m": self.traces.metrics.max_u_twin,
            "stable": !self.teach.unstable && self.engine.error.is_none(),
            "preset": self.preset.name,
            "aw_platform": platform.aw,
            "counted_s": self.traces.metrics.counted_s(),
            "running": self.engine.view.running,
            "error": self.engine.error,
            "notice": self.notice.as_ref().map(|n: &Notice| n.text.clone()),
            "kp_v_per_m": self.params.controller.kp_v_per_m,
            "lesson": lesson.map(|n| n + 1),
            "lesson_done": lesson.is_some_and(|n| self.teach.lessons.is_done(n)),
            "presentation": self.teach.presentation,
            "rtf": self.engine.view.realtime_factor,
            "engine_rtf": self.teach.engine_rtf(),
            "ui_ms_mean": stats.mean_ui_ms(),
            "ui_ms_p95": stats.p95_ui_ms(),
            "ui_ms_max": stats.max_ui_ms(),
            "cpu_ms": stats.cpu_ms,
            "fps": stats.fps(),
        })
        .to_string()
    }

    /// Started by a page address `?seed=N&excitation=random[&duration=T][&speed=max]`: the
    /// random ride exactly as `seat-twin simulate --scenario random --seed N --duration T`
    /// builds it (T default 60 s, the CLI's; the CLI's fade-in of min(T/4, 2) s), paused at
    /// its end so its a_w can be read. A bad query is an error message and the defaults.
    pub fn apply_query(&mut self, seed: &str, duration: Option<&str>) -> Result<(), String> {
        let seed: u64 = seed
            .parse()
            .map_err(|_| format!("?seed={seed}: a whole number 0 … 2^64−1"))?;
        let duration_s = match duration {
            None => 60.0,
            Some(d) => d
                .parse::<f64>()
                .ok()
                .filter(|d| (1.0..=3600.0).contains(d))
                .ok_or_else(|| format!("?duration={d}: a number of seconds, 1 … 3600"))?,
        };
        let e = &mut self.settings.excitation;
        e.kind = crate::gui::controls::ExcitationKind::Random;
        e.random = crate::scenario::RandomRide {
            seed,
            duration_s,
            fade_in_s: (duration_s / 4.0).min(2.0),
            ..Default::default()
        };
        self.set_repeat(false);
        self.apply_excitation();
        Ok(())
    }

    /// For the tests: the parameters a lesson step starts with.
    pub fn lesson_params(n: usize) -> Option<Params> {
        let l = LESSONS.get(n)?;
        let mut p = share::shipped_preset(l.preset).ok()?.params;
        let mut e = crate::gui::controls::ExcitationEditor::default();
        LessonsPanel::set_up(n, &mut p, &mut e);
        Some(p)
    }
}
