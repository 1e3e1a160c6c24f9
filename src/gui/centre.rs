//! The centre of the app: the engine's banner when it stopped, the six scopes with their bar
//! (window length, Freeze) and the frequency plots (analytic curves, the twin's sine dwell,
//! the stability line). It owns what only it uses: the analytic curves, the dwell, the
//! curves hidden in the legends, the Freeze toggle, the last stable gains and the scopes'
//! frames; the app passes in what it shares and applies the [`CentreAction`]s returned.

use super::ab::AbView;
use super::format::shorten_numbers;
use super::frequency::{self, Analytic, Curves, Dwell, FreqAction, FreqView};
use super::job::Waker;
use super::scopes;
use super::settings::Settings;
use super::style;
use super::traces::Traces;
use crate::analysis::watch::Finding;
use crate::params::{ControllerParams, Params};
use egui::RichText;
use std::collections::BTreeSet;
use web_time::Instant;

/// Narrowest centre [points] that shows the scopes and the frequency plots side by side.
const TWO_COLUMNS_MIN_W: f32 = 700.0;
/// Height of the scopes when stacked above the frequency plots, at least [points].
const STACKED_SCOPES_MIN_H: f32 = 900.0;
/// Height of the frequency plots when stacked, at least [points].
const STACKED_FREQ_MIN_H: f32 = 760.0;

/// What the centre asks the app to do.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CentreAction {
    /// Back to rest at t = 0 (restarts a stopped engine).
    Reset,
    /// Put back the last gains with which both loops were stable, then reset.
    ResetToStableGains,
}

/// What the centre shows this frame and does not own.
pub struct CentreInput<'a> {
    /// The parameters being edited (SI).
    pub params: &'a Params,
    /// The live traces.
    pub traces: &'a Traces,
    /// The A/B view (its reference curves are drawn with the live ones).
    pub ab: &'a mut AbView,
    /// The scopes' window length and the phase unwrapping are settings.
    pub settings: &'a mut Settings,
    /// The simulation runs on (the scopes scroll unless frozen).
    pub running: bool,
    /// The engine's error, if it stopped.
    pub engine_error: Option<&'a str>,
    /// What the running twin's watch found.
    pub watch: Option<Finding>,
    /// The loop is unstable (this frame's verdict, see [`CentreView::follow`]).
    pub unstable: bool,
}

/// What [`CentreView::follow`] found this frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Followed {
    /// The linear verdict or the twin's watch says unstable.
    pub unstable: bool,
    /// The sine dwell is computing.
    pub dwell_busy: bool,
}

/// The centre's state.
pub struct CentreView {
    analytic: Analytic,
    dwell: Dwell,
    hidden_curves: BTreeSet<String>,
    scopes_frozen: bool,
    scope_frames: Vec<egui::Rect>,
    last_stable: Option<ControllerParams>,
    /// Time of the scopes in the last frame \[ms\].
    pub scopes_ms: f64,
    /// Time of the frequency plots in the last frame \[ms\].
    pub freq_ms: f64,
}

impl CentreView {
    /// A centre with no curve hidden, not frozen; the dwell job wakes the app with `waker`.
    pub fn new(waker: Waker) -> Self {
        Self {
            analytic: Analytic::default(),
            dwell: Dwell::new(waker),
            hidden_curves: BTreeSet::new(),
            scopes_frozen: false,
            scope_frames: Vec::new(),
            last_stable: None,
            scopes_ms: 0.0,
            freq_ms: 0.0,
        }
    }

    /// The analytic frequency curves (of the parameters last followed).
    pub fn curves(&self) -> &Curves {
        self.analytic.curves()
    }

    /// The simulated (sine dwell) frequency points of the twin.
    pub fn dwell(&self) -> &Dwell {
        &self.dwell
    }

    /// The sine dwell, to start or cancel it.
    pub fn dwell_mut(&mut self) -> &mut Dwell {
        &mut self.dwell
    }

    /// Curves switched off in the legends (`plot/name`).
    pub fn hidden_curves(&self) -> &BTreeSet<String> {
        &self.hidden_curves
    }

    /// Replaces the hidden curves (a session restored).
    pub fn set_hidden_curves(&mut self, hidden: BTreeSet<String>) {
        self.hidden_curves = hidden;
    }

    /// The last gains with which both loops were stable.
    pub fn last_stable(&self) -> Option<ControllerParams> {
        self.last_stable
    }

    /// The scopes' data areas drawn last frame, top to bottom.
    pub fn scope_frames(&self) -> &[egui::Rect] {
        &self.scope_frames
    }

    /// Follows the edited parameters in the same frame as the slider: the analytic curves,
    /// the verdict (the linear one, or the twin's `watch` unless it only saw a negative
    /// pressure), the last stable gains (only committed ones: not while `editing`, a drag
    /// only passes through them) and the dwell (recomputed when `dwell_auto`, never for an
    /// unstable loop: it would only diverge).
    pub fn follow(
        &mut self,
        params: &Params,
        watch: Option<Finding>,
        editing: bool,
        dwell_auto: bool,
    ) -> Followed {
        self.analytic.update(params);
        let unstable = self.analytic.curves().unstable()
            || watch.is_some_and(|f| !matches!(f, Finding::NegativePressure { .. }));
        if !unstable && !editing {
            self.last_stable = Some(params.controller);
        }
        let dwell_busy = self.dwell.poll(params, dwell_auto && !unstable);
        Followed {
            unstable,
            dwell_busy,
        }
    }

    /// The centre: the engine banner, the scopes and the frequency plots.
    pub fn ui(&mut self, ui: &mut egui::Ui, input: CentreInput<'_>) -> Vec<CentreAction> {
        let mut actions = Vec::new();
        if let Some(err) = input.engine_error {
            self.engine_banner_ui(ui, err, input.unstable, &mut actions);
        }
        let CentreInput {
            params,
            traces,
            ab,
            settings,
            running,
            engine_error,
            watch,
            unstable: _,
        } = input;
        let live = running && engine_error.is_none();
        let mut freq = FreqAction::None;
        // Side by side when the centre is wide enough; stacked (scopes, then the
        // frequency plots, each a screen high at most) on a small window or with a
        // large UI scale, where two columns would squeeze both unreadable.
        if ui.available_width() >= TWO_COLUMNS_MIN_W {
            ui.columns(2, |cols| {
                let [left, right] = cols else { return };
                self.scopes_column_ui(left, traces, params, ab.is_on(), settings, live);
                freq = self.frequency_column_ui(right, params, ab, settings, watch);
            });
        } else {
            let w = ui.available_width();
            let h = ui.available_height();
            ui.allocate_ui(egui::vec2(w, h.max(STACKED_SCOPES_MIN_H)), |ui| {
                self.scopes_column_ui(ui, traces, params, ab.is_on(), settings, live)
            });
            ui.separator();
            ui.allocate_ui(egui::vec2(w, h.max(STACKED_FREQ_MIN_H)), |ui| {
                freq = self.frequency_column_ui(ui, params, ab, settings, watch);
            });
        }
        if freq == FreqAction::ResetToStableGains {
            actions.push(CentreAction::ResetToStableGains);
        }
        actions
    }

    /// The red banner of a stopped engine, with Reset (and Reset to the last stable gains
    /// when the gains are what made it diverge).
    fn engine_banner_ui(
        &self,
        ui: &mut egui::Ui,
        err: &str,
        unstable: bool,
        actions: &mut Vec<CentreAction>,
    ) {
        egui::Frame::new()
            .fill(style::ENGINE_STOPPED_FILL)
            .inner_margin(6.0)
            .corner_radius(4.0)
            .show(ui, |ui| {
                ui.horizontal_wrapped(|ui| {
                    ui.label(
                        RichText::new(format!("Engine stopped: {}", shorten_numbers(err)))
                            .color(egui::Color32::WHITE)
                            .strong(),
                    );
                    if ui.button("Reset").clicked() {
                        actions.push(CentreAction::Reset);
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
                        actions.push(CentreAction::ResetToStableGains);
                    }
                });
            });
    }

    /// The scopes' window length and Freeze.
    fn scope_bar_ui(&mut self, ui: &mut egui::Ui, settings: &mut Settings) {
        ui.horizontal(|ui| {
            ui.label("scopes:");
            egui::ComboBox::from_id_salt("scope_window")
                .selected_text(format!("{:.0} s", settings.scope_window_s))
                .width(64.0)
                .show_ui(ui, |ui| {
                    for w in scopes::WINDOWS_S {
                        ui.selectable_value(&mut settings.scope_window_s, w, format!("{w:.0} s"));
                    }
                })
                .response
                .on_hover_text("Length of the time window shown");
            ui.toggle_value(&mut self.scopes_frozen, "Freeze")
                .on_hover_text(
                    "Stops the scrolling while the simulation runs on; frozen or paused, drag to \
                 pan in time, Ctrl + wheel to zoom, double-click for all that is kept (60 s)",
                );
        });
    }

    /// The scopes with their bar (window, Freeze).
    fn scopes_column_ui(
        &mut self,
        ui: &mut egui::Ui,
        traces: &Traces,
        params: &Params,
        ab_on: bool,
        settings: &mut Settings,
        live: bool,
    ) {
        let t_scopes = Instant::now();
        self.scope_bar_ui(ui, settings);
        let view = scopes::ScopeView {
            window_s: settings.scope_window_s,
            live: live && !self.scopes_frozen,
        };
        self.scope_frames =
            scopes::scopes_ui(ui, traces, params, &mut self.hidden_curves, ab_on, view);
        self.scopes_ms = t_scopes.elapsed().as_secs_f64() * 1e3;
    }

    /// The stability line and the four frequency plots.
    fn frequency_column_ui(
        &mut self,
        ui: &mut egui::Ui,
        params: &Params,
        ab: &mut AbView,
        settings: &mut Settings,
        watch: Option<Finding>,
    ) -> FreqAction {
        let t_freq = Instant::now();
        let last_stable = self.last_stable.filter(|g| *g != params.controller);
        let reference = ab.curves(params);
        let action = frequency::frequency_ui(
            ui,
            self.analytic.curves(),
            &mut self.dwell,
            params,
            FreqView {
                phase_unwrapped: &mut settings.phase_unwrapped,
                hidden: &mut self.hidden_curves,
                last_stable,
                reference,
                watch,
            },
        );
        self.freq_ms = t_freq.elapsed().as_secs_f64() * 1e3;
        action
    }
}
