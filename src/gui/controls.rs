//! Unit-aware sliders (with typed entry) for the parameters and the excitation editor.
//! Values stay SI in [`Params`]; the sliders show display units and convert at the edge.

use super::units::{BAR_PER_PA, KN_PER_N, MM_PER_M, MS_PER_S};
use crate::engine::Excitation;
use crate::params::Params;
use crate::scenario::{Cycloid, RandomRide, SampledMotion};
use egui::{Response, Slider, SliderClamping};
use serde::{Deserialize, Serialize};
use std::ops::RangeInclusive;

/// One slider over an SI value shown as `value·scale` with a unit suffix. Typed values may
/// leave the slider's range (validation decides). Returns the response; the value is written
/// back only when the slider changed it.
#[allow(clippy::too_many_arguments)]
fn si_slider(
    ui: &mut egui::Ui,
    label: &str,
    value_si: &mut f64,
    scale: f64,
    range: RangeInclusive<f64>,
    suffix: &str,
    logarithmic: bool,
    decimals: usize,
    hover: &str,
) -> Response {
    let mut shown = *value_si * scale;
    let mut slider = Slider::new(&mut shown, range)
        .text(label)
        .suffix(suffix)
        .clamping(SliderClamping::Never)
        .logarithmic(logarithmic)
        .max_decimals(decimals)
        .min_decimals(decimals.min(2));
    if logarithmic {
        slider = slider.smallest_positive(0.1);
    }
    let response = ui.add(slider).on_hover_text(hover);
    if response.changed() && shown.is_finite() {
        *value_si = shown / scale;
    }
    response
}

/// The parameter sliders. Returns true if a parameter changed this frame.
pub fn params_ui(ui: &mut egui::Ui, p: &mut Params) -> bool {
    let mut changed = false;
    ui.spacing_mut().slider_width = 150.0;
    egui::CollapsingHeader::new("Controller")
        .default_open(true)
        .show(ui, |ui| {
            changed |= si_slider(
                ui,
                "Kp",
                &mut p.controller.kp_v_per_m,
                1.0,
                -2000.0..=200.0,
                " V/m",
                true,
                2,
                "Position gain Kp [V/m] of V = Kp·u + (Ki/s)·a_platform. Negative is negative feedback; \
                 paper: −5.",
            )
            .changed();
            changed |= si_slider(
                ui,
                "Ki",
                &mut p.controller.ki_v_s_per_m,
                1.0,
                -200.0..=200.0,
                " V·s/m",
                true,
                2,
                "Gain Ki [V·s/m] on the integral of the platform acceleration; paper: −7.5.",
            )
            .changed();
        });
    egui::CollapsingHeader::new("Valve")
        .default_open(true)
        .show(ui, |ui| {
            changed |= si_slider(
                ui,
                "Cd",
                &mut p.valve.cd,
                1.0,
                0.01..=0.5,
                "",
                false,
                4,
                "Flow coefficient Cd [-]; paper: 0.1074 initial, 0.1506 adjusted.",
            )
            .changed();
            let tau = si_slider(
                ui,
                "τ",
                &mut p.valve.tau_s,
                MS_PER_S,
                0.0..=60.0,
                " ms",
                false,
                1,
                "Pure input delay of the valve command (twin) [ms]; paper: 17.5 ms. The linear \
                 model G(s) follows it.",
            )
            .changed();
            if tau {
                // The linear model's delay follows the twin's: one τ, as in the paper.
                p.linear.tau_s = p.valve.tau_s;
            }
            changed |= tau;
        });
    egui::CollapsingHeader::new("Rig")
        .default_open(true)
        .show(ui, |ui| {
            changed |= si_slider(
                ui,
                "mass",
                &mut p.body.mass_kg,
                1.0,
                1.0..=200.0,
                " kg",
                true,
                1,
                "Suspended mass incl. seat, operator and payload [kg]; paper: 11.7 kg.",
            )
            .changed();
            changed |= si_slider(
                ui,
                "stiffness",
                &mut p.body.stiffness_n_per_m,
                KN_PER_N,
                0.1..=100.0,
                " kN/m",
                true,
                2,
                "Equivalent stiffness of the springs [kN/m]; paper: 3.68 kN/m.",
            )
            .changed();
            changed |= si_slider(
                ui,
                "supply",
                &mut p.supply.supply_pressure_pa,
                BAR_PER_PA,
                15.0..=250.0,
                " bar",
                false,
                0,
                "Supply pressure pA [bar]; paper: 100 bar (return 10 bar).",
            )
            .changed();
            changed |= si_slider(
                ui,
                "passive ζ",
                &mut p.passive.zeta,
                1.0,
                0.0..=2.0,
                "",
                false,
                2,
                "Damping ratio of the passive reference suspension; paper: 0.3.",
            )
            .changed();
        });
    changed
}

/// Which excitation the editor builds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
pub enum ExcitationKind {
    /// Band-limited random ride.
    #[default]
    Random,
    /// Repeated cycloidal bump, up then down.
    Cycloid,
    /// Platform sine.
    Sine,
    /// Open-loop valve sine, platform still.
    ValveSine,
    /// A loaded CSV platform record.
    Record,
}

impl ExcitationKind {
    fn label(self) -> &'static str {
        match self {
            ExcitationKind::Random => "random ride",
            ExcitationKind::Cycloid => "cycloid bump",
            ExcitationKind::Sine => "platform sine",
            ExcitationKind::ValveSine => "valve sine (open loop)",
            ExcitationKind::Record => "CSV record",
        }
    }
}

/// A loaded platform record.
#[derive(Debug, Clone)]
pub struct LoadedRecord {
    /// File name shown in the UI.
    pub name: String,
    /// The motion.
    pub motion: SampledMotion,
}

/// The excitation editor's state (persisted, except the loaded record).
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(default)]
pub struct ExcitationEditor {
    /// Selected kind.
    pub kind: ExcitationKind,
    /// Random ride settings.
    pub random: RandomRide,
    /// Cycloid bump.
    pub cycloid: Cycloid,
    /// Cycloid repeat period [s].
    pub cycloid_period_s: f64,
    /// Platform sine acceleration amplitude [m/s²].
    pub sine_accel_m_s2: f64,
    /// Platform sine frequency [Hz].
    pub sine_freq_hz: f64,
    /// Valve sine amplitude [V].
    pub valve_amplitude_v: f64,
    /// Valve sine frequency [Hz].
    pub valve_freq_hz: f64,
    /// The loaded record (not persisted).
    #[serde(skip)]
    pub record: Option<LoadedRecord>,
}

impl Default for ExcitationEditor {
    fn default() -> Self {
        Self {
            kind: ExcitationKind::Random,
            random: RandomRide {
                duration_s: 300.0,
                ..Default::default()
            },
            cycloid: Cycloid::default(),
            cycloid_period_s: 3.0,
            sine_accel_m_s2: 0.5,
            sine_freq_hz: 2.0,
            valve_amplitude_v: 1.0,
            valve_freq_hz: 2.0,
            record: None,
        }
    }
}

impl ExcitationEditor {
    /// The excitation to send, or `None` for a record kind without a loaded record.
    pub fn excitation(&self) -> Option<Excitation> {
        Some(match self.kind {
            ExcitationKind::Random => Excitation::Random(self.random),
            ExcitationKind::Cycloid => Excitation::Cycloid {
                bump: self.cycloid,
                period_s: self.cycloid_period_s,
            },
            ExcitationKind::Sine => Excitation::Sine {
                accel_m_s2: self.sine_accel_m_s2,
                freq_hz: self.sine_freq_hz,
            },
            ExcitationKind::ValveSine => Excitation::ValveSine {
                amplitude_v: self.valve_amplitude_v,
                freq_hz: self.valve_freq_hz,
            },
            ExcitationKind::Record => Excitation::Record(self.record.as_ref()?.motion.clone()),
        })
    }

    /// A problem that keeps the excitation from being applied, if any.
    pub fn problem(&self) -> Option<String> {
        match self.kind {
            ExcitationKind::Random if self.random.f_high_hz <= self.random.f_low_hz => {
                Some("the upper band edge must be above the lower one".into())
            }
            ExcitationKind::Record if self.record.is_none() => {
                Some("no record loaded: press “Load CSV…”".into())
            }
            _ => None,
        }
    }
}

/// What the excitation editor asks the app to do.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ExcitationAction {
    /// Nothing.
    None,
    /// Send the edited excitation to the engine (restarts from rest).
    Apply,
    /// Open the file dialog for a CSV record.
    LoadRecord,
}

/// Applies a slider when the user lets go (or typed a value), not on every drag frame.
fn committed(r: &Response) -> bool {
    r.drag_stopped() || (r.changed() && !r.dragged())
}

/// The excitation editor.
pub fn excitation_ui(ui: &mut egui::Ui, ed: &mut ExcitationEditor) -> ExcitationAction {
    let mut action = ExcitationAction::None;
    let before = ed.kind;
    egui::ComboBox::from_label("excitation")
        .selected_text(ed.kind.label())
        .show_ui(ui, |ui| {
            for k in [
                ExcitationKind::Random,
                ExcitationKind::Cycloid,
                ExcitationKind::Sine,
                ExcitationKind::ValveSine,
                ExcitationKind::Record,
            ] {
                ui.selectable_value(&mut ed.kind, k, k.label());
            }
        });
    if ed.kind != before {
        action = ExcitationAction::Apply;
    }
    let mut commit = |r: Response| {
        if committed(&r) {
            action = ExcitationAction::Apply;
        }
    };
    match ed.kind {
        ExcitationKind::Random => {
            commit(
                ui.add(
                    Slider::new(&mut ed.random.s0, 0.001..=1.0)
                        .logarithmic(true)
                        .text("S0")
                        .suffix(" (m/s²)²/Hz"),
                ),
            );
            commit(
                ui.add(
                    Slider::new(&mut ed.random.f_low_hz, 0.05..=20.0)
                        .logarithmic(true)
                        .text("f low")
                        .suffix(" Hz"),
                ),
            );
            commit(
                ui.add(
                    Slider::new(&mut ed.random.f_high_hz, 0.5..=100.0)
                        .logarithmic(true)
                        .text("f high")
                        .suffix(" Hz"),
                ),
            );
        }
        ExcitationKind::Cycloid => {
            let mut h = ed.cycloid.height_m * MM_PER_M;
            let r = ui.add(
                Slider::new(&mut h, -60.0..=60.0)
                    .text("height")
                    .suffix(" mm"),
            );
            if r.changed() {
                ed.cycloid.height_m = h / MM_PER_M;
            }
            commit(r);
            commit(
                ui.add(
                    Slider::new(&mut ed.cycloid.rise_time_s, 0.05..=3.0)
                        .text("rise time")
                        .suffix(" s"),
                ),
            );
            commit(
                ui.add(
                    Slider::new(&mut ed.cycloid_period_s, 1.0..=20.0)
                        .text("period")
                        .suffix(" s"),
                ),
            );
        }
        ExcitationKind::Sine => {
            commit(
                ui.add(
                    Slider::new(&mut ed.sine_accel_m_s2, 0.01..=5.0)
                        .logarithmic(true)
                        .text("amplitude")
                        .suffix(" m/s²"),
                ),
            );
            commit(
                ui.add(
                    Slider::new(&mut ed.sine_freq_hz, 0.1..=50.0)
                        .logarithmic(true)
                        .text("frequency")
                        .suffix(" Hz"),
                ),
            );
        }
        ExcitationKind::ValveSine => {
            commit(
                ui.add(
                    Slider::new(&mut ed.valve_amplitude_v, 0.01..=10.0)
                        .logarithmic(true)
                        .text("amplitude")
                        .suffix(" V"),
                ),
            );
            commit(
                ui.add(
                    Slider::new(&mut ed.valve_freq_hz, 0.1..=100.0)
                        .logarithmic(true)
                        .text("frequency")
                        .suffix(" Hz"),
                ),
            );
        }
        ExcitationKind::Record => {
            ui.horizontal(|ui| {
                if ui.button("Load CSV…").clicked() {
                    action = ExcitationAction::LoadRecord;
                }
                match &ed.record {
                    Some(r) => ui.label(format!("{} ({:.1} s)", r.name, r.motion.duration_s())),
                    None => ui.weak("none loaded"),
                };
            });
        }
    }
    action
}
