//! The Tune panel: `tune` on the nonlinear twin in a background [`Job`], with progress and
//! cancel, then the Pareto front (objective against max |u|) with clickable points, the
//! held-out objective before/after and the margins, and "Apply" for the chosen point.

use super::format::controller_text;
use super::job::{Job, JobCtx, Step, Waker};
use super::plotkit;
use super::units::MM_PER_M;
use crate::params::{ControllerParams, Params};
use crate::tune::{self, Evaluation, TuneOptions, TuneResult};
use egui::RichText;
use egui_plot::{AxisHints, MarkerShape, Plot, PlotPoint, Points};

/// Short settings for interactive use (the CLI's default is 3 + 3 rides × 60 s, 120
/// evaluations): 2 tuning and 2 held-out random rides of 20 s, 40 evaluations.
pub fn interactive_options(params: &Params) -> TuneOptions {
    TuneOptions {
        kind: params.controller.kind,
        tune_seeds: vec![1, 2],
        heldout_seeds: vec![101, 102],
        duration_s: 20.0,
        max_evaluations: 40,
        ..TuneOptions::default()
    }
}

/// Tuning `p` with `o` as job steps (a [`tune::TuneRun`]: the baseline, one optimiser
/// iteration, one robustness check per step), with the job's progress and cancel.
pub fn tune_steps(p: Params, o: TuneOptions) -> impl FnMut(&JobCtx) -> Step<TuneResult> + Send {
    let mut run: Option<tune::TuneRun> = None;
    move |ctx| {
        let run = match &mut run {
            Some(r) => r,
            None => {
                let reporter = ctx.clone();
                let progress: tune::Progress = std::sync::Arc::new(move |done, total| {
                    reporter.report(done, total);
                });
                match tune::TuneRun::new(&p, &o, Some(ctx.cancel_flag()), Some(progress)) {
                    Ok(r) => run.insert(r),
                    Err(e) => return Step::Done(Err(e.to_string())),
                }
            }
        };
        match run.step() {
            None => Step::More,
            Some(r) => Step::Done(r.map_err(|e| e.to_string())),
        }
    }
}

/// What the Tune panel asks the app to do.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TuneAction {
    /// Nothing.
    None,
    /// Set these gains on the live controller.
    Apply(ControllerParams),
}

/// The Tune panel's state.
#[derive(Default)]
pub struct TunePanel {
    job: Option<Job<TuneResult>>,
    options: Option<TuneOptions>,
    result: Option<TuneResult>,
    selected: Option<usize>,
    message: Option<(String, bool)>,
}

impl TunePanel {
    /// Starts tuning the current controller structure from the current gains.
    pub fn start(&mut self, params: &Params, opts: TuneOptions, waker: Waker) {
        if self.is_running() {
            return;
        }
        let p = *params;
        let o = opts.clone();
        self.options = Some(opts);
        self.message = None;
        self.job = Some(Job::spawn_steps("seat-twin-tune", waker, tune_steps(p, o)));
    }

    /// Whether a tuning runs.
    pub fn is_running(&self) -> bool {
        self.job.as_ref().is_some_and(|j| !j.is_finished())
    }

    /// `(evaluations done, budget)` of the running job.
    pub fn progress(&self) -> Option<(usize, usize)> {
        self.job
            .as_ref()
            .filter(|j| !j.is_finished())
            .map(Job::progress)
    }

    /// `(evaluations done, budget)` last reported by the latest job, running or not.
    pub fn last_progress(&self) -> Option<(usize, usize)> {
        self.job.as_ref().map(Job::progress)
    }

    /// Asks the running job to stop.
    pub fn cancel(&self) {
        if let Some(j) = &self.job {
            j.cancel();
        }
    }

    /// The last result.
    pub fn result(&self) -> Option<&TuneResult> {
        self.result.as_ref()
    }

    /// The chosen Pareto point (index into the result's front).
    pub fn selected(&self) -> Option<usize> {
        self.selected
    }

    /// Chooses a Pareto point.
    pub fn select(&mut self, i: usize) {
        if self.result.as_ref().is_some_and(|r| i < r.pareto.len()) {
            self.selected = Some(i);
        }
    }

    /// Puts a result back (from a session file), stopping a running job.
    pub fn restore(&mut self, result: Option<TuneResult>, selected: Option<usize>) {
        self.cancel();
        self.job = None;
        self.message = None;
        self.selected = selected.filter(|&i| result.as_ref().is_some_and(|r| i < r.pareto.len()));
        self.result = result;
    }

    /// The last message (text, is error): cancelled, failed.
    pub fn message(&self) -> Option<&(String, bool)> {
        self.message.as_ref()
    }

    /// Takes a finished job's result (call once per frame).
    pub fn poll(&mut self) {
        let Some(job) = self.job.as_mut() else {
            return;
        };
        let cancelled = job.is_cancelled();
        match job.poll() {
            None => {}
            Some(Ok(r)) => {
                // The tuned point, if it is on the front; else the front's best objective.
                self.selected = r
                    .pareto
                    .iter()
                    .position(|e| e.gains == r.tuned.gains)
                    .or_else(|| (!r.pareto.is_empty()).then_some(0));
                self.result = Some(r);
            }
            Some(Err(e)) if cancelled => self.message = Some((format!("cancelled ({e})"), false)),
            Some(Err(e)) => self.message = Some((format!("tuning failed: {e}"), true)),
        }
    }

    /// The panel. `params` are the live parameters (the structure tuned and the start).
    pub fn ui(&mut self, ui: &mut egui::Ui, params: &Params, waker: &Waker) -> TuneAction {
        let mut action = TuneAction::None;
        let opts = interactive_options(params);
        ui.weak(format!(
            "Tunes the {} gains on the nonlinear twin: {} tuning + {} held-out random rides \
             × {:.0} s, up to {} evaluations, objective a_w; constraints: no end-stop \
             contact, max |u| ≤ 30 mm, GM ≥ 6 dB, PM ≥ 45°.",
            params.controller.kind,
            opts.tune_seeds.len(),
            opts.heldout_seeds.len(),
            opts.duration_s,
            opts.max_evaluations
        ));
        ui.horizontal(|ui| {
            if ui
                .add_enabled(!self.is_running(), egui::Button::new("Tune"))
                .clicked()
            {
                self.start(params, opts, waker.clone());
            }
            if let Some((done, total)) = self.progress()
                && super::plotkit::progress_cancel_ui(ui, done, total, "Cancel tuning")
            {
                self.cancel();
            }
        });
        if let Some((m, error)) = &self.message {
            let color = if *error {
                super::style::ERROR_TEXT
            } else {
                ui.visuals().weak_text_color()
            };
            ui.colored_label(color, m);
        }
        let Some(r) = &self.result else {
            return action;
        };
        if r.kind != params.controller.kind {
            // A front of other gains: never offered for Apply (it would switch the
            // structure back without saying so).
            ui.weak(format!(
                "The last result tuned the {} gains; the structure is now {}. Press Tune for \
                 its gains.",
                r.kind, params.controller.kind
            ));
            return action;
        }
        ui.label(format!(
            "{} evaluations ({}). Held-out a_w: {:.3} before, {:.3} m/s² after ({:+.1} %).",
            r.evaluations,
            r.stop_reason,
            r.baseline_heldout.objective,
            r.tuned_heldout.objective,
            100.0 * (r.tuned_heldout.objective / r.baseline_heldout.objective - 1.0)
        ));
        if let Some(first) = r.failures.first() {
            ui.colored_label(
                super::style::FAILED_TEXT,
                format!(
                    "The claim fails where instability shows: {first}{}",
                    if r.failures.len() > 1 {
                        format!(" (and {} more)", r.failures.len() - 1)
                    } else {
                        String::new()
                    }
                ),
            );
        } else {
            ui.weak(
                "Checked at all 27 points of the spread: stable at rest and settled after a \
                 bump on the twin (the Pareto points are stable there by the eigenvalues).",
            );
        }
        if r.pareto.is_empty() {
            ui.weak("no feasible point: the start was kept");
            return action;
        }
        let clicked = pareto_plot(ui, &r.pareto, self.selected);
        if let Some(i) = clicked {
            self.selected = Some(i);
        }
        if let Some(e) = self.selected.and_then(|i| r.pareto.get(i)) {
            let decimals = separating_decimals(r.pareto.iter().map(|e| e.objective));
            ui.label(RichText::new(point_text(e, decimals)).monospace());
            if ui
                .button("Apply")
                .on_hover_text("Sets these gains on the live controller.")
                .clicked()
            {
                action = TuneAction::Apply(e.controller);
            }
        }
        action
    }
}

/// One Pareto point for people, a_w with `decimals` decimals (see [`separating_decimals`]).
pub fn point_text(e: &Evaluation, decimals: usize) -> String {
    format!(
        "{}\na_w {:.decimals$} m/s², max |u| {:.1} mm, GM {:.1} dB, PM {:.0}°, delay margin {}",
        controller_text(&e.controller),
        e.objective,
        e.max_abs_u_m * MM_PER_M,
        e.gain_margin_db,
        e.phase_margin_deg,
        if e.delay_margin_s.is_finite() {
            format!("{:.1} ms", e.delay_margin_s * 1e3)
        } else {
            "∞ (no destabilising crossover)".into()
        }
    )
}

/// The fewest decimals (3 … 6) with which all `values` read differently: two points of a
/// Pareto front never show the same a_w, so neither looks dominated by the other.
pub fn separating_decimals(values: impl Iterator<Item = f64> + Clone) -> usize {
    (3..=6)
        .find(|&d| {
            let mut shown: Vec<String> = values.clone().map(|v| format!("{v:.d$}")).collect();
            let n = shown.len();
            shown.sort();
            shown.dedup();
            shown.len() == n
        })
        .unwrap_or(6)
}

/// The front as points (max |u| [mm], objective); returns the index of a clicked point.
fn pareto_plot(ui: &mut egui::Ui, front: &[Evaluation], selected: Option<usize>) -> Option<usize> {
    let pts: Vec<PlotPoint> = front
        .iter()
        .map(|e| PlotPoint::new(e.max_abs_u_m * MM_PER_M, e.objective))
        .collect();
    let decimals = separating_decimals(front.iter().map(|e| e.objective));
    const HEIGHT: f32 = 170.0;
    let width = ui.available_width();
    let r = Plot::new("pareto")
        .height(HEIGHT)
        // Numbered ticks on both axes (egui_plot's default left one x label, "20").
        .custom_x_axes(vec![
            AxisHints::new_x()
                .label("max |u| [mm]")
                .formatter(plotkit::y_tick)
                .label_spacing(28.0..=32.0),
        ])
        .custom_y_axes(vec![plotkit::y_axis("a_w [m/s²]")])
        .x_grid_spacer(move |input| plotkit::marks(input, width, 48.0))
        .y_grid_spacer(move |input| plotkit::y_marks(input, HEIGHT))
        .label_formatter(move |pos| {
            let (name, p) = match pos {
                egui_plot::HoverPosition::NearDataPoint {
                    plot_name,
                    position,
                    ..
                } => (format!("{plot_name}\n"), position),
                egui_plot::HoverPosition::Elsewhere { position } => (String::new(), position),
            };
            Some(format!(
                "{name}max |u| {:.2} mm\na_w {:.decimals$} m/s²",
                p.x, p.y
            ))
        })
        .allow_drag(false)
        .allow_zoom(false)
        .allow_scroll(false)
        .show(ui, |pu| {
            pu.points(
                Points::new("Pareto front", pts.as_slice())
                    .color(super::style::TWIN)
                    .shape(MarkerShape::Circle)
                    .radius(4.0)
                    .filled(true),
            );
            if let Some(p) = selected.and_then(|i| pts.get(i)) {
                pu.points(
                    Points::new("chosen", vec![[p.x, p.y]])
                        .color(super::style::REFERENCE)
                        .shape(MarkerShape::Diamond)
                        .radius(7.0)
                        .filled(true),
                );
            }
            pu.pointer_coordinate()
        });
    if !r.response.clicked() {
        return None;
    }
    // The point nearest the click, in screen space.
    let pos = r.response.interact_pointer_pos()?;
    pts.iter()
        .enumerate()
        .map(|(i, p)| (i, r.transform.position_from_point(p).distance(pos)))
        .filter(|&(_, d)| d < 20.0)
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(i, _)| i)
}
