//! Unit-aware sliders (with typed entry) for the parameters and the excitation editor.
//! Values stay SI in [`Params`]; the sliders show display units and convert at the edge.

use super::units::{BAR_PER_PA, KN_PER_N, MM_PER_M, MS_PER_S};
use crate::engine::Excitation;
use crate::params::{ParamError, Params};
use crate::scenario::{Cycloid, RandomRide, SampledMotion};
use egui::{Response, Slider, SliderClamping};
use serde::{Deserialize, Serialize};
use std::ops::RangeInclusive;

/// One parameter control: a slider over an SI value shown as `value·scale` with a unit.
struct Knob {
    label: &'static str,
    get: fn(&Params) -> f64,
    set: fn(&mut Params, f64),
    scale: f64,
    range: RangeInclusive<f64>,
    suffix: &'static str,
    logarithmic: bool,
    decimals: usize,
    hover: &'static str,
}

/// The range [SI] that [`Params::validate`] accepts for one parameter, read from the
/// validation itself: the paper's parameters with this one set far out of range must fail
/// with an out-of-range error that names the bounds.
pub fn validation_range(set: fn(&mut Params, f64)) -> Option<(f64, f64)> {
    let mut p = Params::paper();
    set(&mut p, f64::NEG_INFINITY);
    match p.validate() {
        Err(ParamError::OutOfRange { min, max, .. }) => Some((min, max)),
        _ => None,
    }
}

impl Knob {
    /// The range a typed or dragged value must lie in [display units]: the slider's range
    /// within the range the parameter's validation accepts.
    fn accepted(&self) -> (f64, f64) {
        let (mut lo, mut hi) = (*self.range.start(), *self.range.end());
        if let Some((a, b)) = validation_range(self.set) {
            lo = lo.max(a * self.scale);
            hi = hi.min(b * self.scale);
        }
        (lo, hi)
    }

    /// Draws the slider (typed values apply on Enter or focus loss only, never per
    /// keystroke) and returns the new value [display units] when the user set one.
    fn ui(&self, ui: &mut egui::Ui, p: &Params) -> Option<f64> {
        let mut shown = (self.get)(p) * self.scale;
        let before = shown;
        let mut slider = Slider::new(&mut shown, self.range.clone())
            .text(self.label)
            .suffix(self.suffix)
            .clamping(SliderClamping::Never)
            .update_while_editing(false)
            .logarithmic(self.logarithmic)
            .max_decimals(self.decimals)
            .min_decimals(self.decimals.min(2));
        if self.logarithmic {
            slider = slider.smallest_positive(0.1);
        }
        let response = ui.add(slider).on_hover_text(self.hover);
        (response.changed() && shown != before).then_some(shown)
    }
}

/// Refused values, by control label, shown next to the control until a value is accepted.
pub type FieldErrors = std::collections::BTreeMap<&'static str, String>;

fn knobs_controller() -> [Knob; 2] {
    [
        Knob {
            label: "Kp",
            get: |p| p.controller.kp_v_per_m,
            set: |p, v| p.controller.kp_v_per_m = v,
            scale: 1.0,
            range: -2000.0..=200.0,
            suffix: " V/m",
            logarithmic: true,
            decimals: 2,
            hover: "Position gain Kp [V/m] of V = Kp·u + (Ki/s)·a_platform. Negative is negative \
                    feedback; paper: −5.",
        },
        Knob {
            label: "Ki",
            get: |p| p.controller.ki_v_s_per_m,
            set: |p, v| p.controller.ki_v_s_per_m = v,
            scale: 1.0,
            range: -200.0..=200.0,
            suffix: " V·s/m",
            logarithmic: true,
            decimals: 2,
            hover: "Gain Ki [V·s/m] on the integral of the platform acceleration; paper: −7.5.",
        },
    ]
}

fn knobs_valve() -> [Knob; 2] {
    [
        Knob {
            label: "Cd",
            get: |p| p.plant.valve.cd,
            set: |p, v| p.plant.valve.cd = v,
            scale: 1.0,
            range: 0.01..=0.5,
            suffix: "",
            logarithmic: false,
            decimals: 4,
            hover: "Flow coefficient Cd [-]; paper: 0.1074 initial, 0.1506 adjusted.",
        },
        Knob {
            label: "τ",
            get: |p| p.plant.valve.tau_s,
            // The linear model's delay follows the twin's: one τ, as in the paper.
            set: |p, v| {
                p.plant.valve.tau_s = v;
                p.linear.tau_s = v;
            },
            scale: MS_PER_S,
            range: 0.0..=60.0,
            suffix: " ms",
            logarithmic: false,
            decimals: 1,
            hover: "Pure input delay of the valve command (twin) [ms]; paper: 17.5 ms. The linear \
                    model G(s) follows it.",
        },
    ]
}

fn knobs_rig() -> [Knob; 4] {
    [
        Knob {
            label: "mass",
            get: |p| p.plant.body.mass_kg,
            set: |p, v| p.plant.body.mass_kg = v,
            scale: 1.0,
            range: 1.0..=200.0,
            suffix: " kg",
            logarithmic: true,
            decimals: 1,
            hover: "Suspended mass incl. seat, operator and payload [kg]; paper: 11.7 kg.",
        },
        Knob {
            label: "stiffness",
            get: |p| p.plant.body.stiffness_n_per_m,
            set: |p, v| p.plant.body.stiffness_n_per_m = v,
            scale: KN_PER_N,
            range: 0.1..=100.0,
            suffix: " kN/m",
            logarithmic: true,
            decimals: 2,
            hover: "Equivalent stiffness of the springs [kN/m]; paper: 3.68 kN/m.",
        },
        Knob {
            label: "supply",
            get: |p| p.plant.supply.supply_pressure_pa,
            set: |p, v| p.plant.supply.supply_pressure_pa = v,
            scale: BAR_PER_PA,
            range: 15.0..=250.0,
            suffix: " bar",
            logarithmic: false,
            decimals: 0,
            hover: "Supply pressure pA [bar]; paper: 100 bar (return 10 bar).",
        },
        Knob {
            label: "passive ζ",
            get: |p| p.passive.zeta,
            set: |p, v| p.passive.zeta = v,
            scale: 1.0,
            range: 0.0..=2.0,
            suffix: "",
            logarithmic: false,
            decimals: 2,
            hover: "Damping ratio of the passive reference suspension; paper: 0.3.",
        },
    ]
}

/// Tries one edit: the value must lie in the control's accepted range and the whole
/// parameter set must validate. Only then is it written to `p`.
fn try_edit(knob: &Knob, p: &mut Params, shown: f64, errors: &mut FieldErrors) -> bool {
    let (lo, hi) = knob.accepted();
    let unit = knob.suffix.trim();
    let fmt = super::format::compact;
    if !(shown.is_finite() && shown >= lo && shown <= hi) {
        errors.insert(
            knob.label,
            format!(
                "{} = {} {unit} refused: allowed {} … {} {unit}",
                knob.label,
                fmt(shown),
                fmt(lo),
                fmt(hi)
            ),
        );
        return false;
    }
    let mut candidate = *p;
    (knob.set)(&mut candidate, shown / knob.scale);
    match candidate.validate() {
        Ok(()) => {
            *p = candidate;
            // A message is about the last attempt: an accepted value anywhere ends it.
            errors.clear();
            true
        }
        Err(e) => {
            errors.insert(knob.label, format!("{} refused: {e}", knob.label));
            false
        }
    }
}

/// The parameter sliders. A value is written to `p` only when it is accepted (in range and
/// valid as a whole); a refused value leaves `p` as it was (the field shows the old value
/// again) and its message stays next to the control. Returns true if a parameter changed.
pub fn params_ui(ui: &mut egui::Ui, p: &mut Params, errors: &mut FieldErrors) -> bool {
    let mut changed = false;
    ui.spacing_mut().slider_width = 150.0;
    let mut group = |ui: &mut egui::Ui, knobs: &[Knob]| {
        for k in knobs {
            if let Some(v) = k.ui(ui, p) {
                changed |= try_edit(k, p, v, errors);
            }
            if let Some(e) = errors.get(k.label) {
                ui.colored_label(egui::Color32::from_rgb(220, 50, 40), e);
            }
        }
    };
    egui::CollapsingHeader::new("Controller")
        .default_open(true)
        .show(ui, |ui| group(ui, &knobs_controller()));
    egui::CollapsingHeader::new("Valve")
        .default_open(true)
        .show(ui, |ui| group(ui, &knobs_valve()));
    egui::CollapsingHeader::new("Rig")
        .default_open(true)
        .show(ui, |ui| group(ui, &knobs_rig()));
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
    /// A record path typed by hand (for desktops without a file dialog; not persisted).
    #[serde(skip)]
    pub typed_path: String,
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
            typed_path: String::new(),
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
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ExcitationAction {
    /// Nothing.
    None,
    /// Send the edited excitation to the engine (restarts from rest).
    Apply,
    /// Open the file dialog for a CSV record.
    LoadRecord,
    /// Load the CSV record at a typed path.
    LoadRecordPath(std::path::PathBuf),
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
                        .update_while_editing(false)
                        .text("S0")
                        .suffix(" (m/s²)²/Hz"),
                ),
            );
            commit(
                ui.add(
                    Slider::new(&mut ed.random.f_low_hz, 0.05..=20.0)
                        .logarithmic(true)
                        .update_while_editing(false)
                        .text("f low")
                        .suffix(" Hz"),
                ),
            );
            commit(
                ui.add(
                    Slider::new(&mut ed.random.f_high_hz, 0.5..=100.0)
                        .logarithmic(true)
                        .update_while_editing(false)
                        .text("f high")
                        .suffix(" Hz"),
                ),
            );
        }
        ExcitationKind::Cycloid => {
            let mut h = ed.cycloid.height_m * MM_PER_M;
            let r = ui.add(
                Slider::new(&mut h, -60.0..=60.0)
                    .update_while_editing(false)
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
                        .update_while_editing(false)
                        .text("rise time")
                        .suffix(" s"),
                ),
            );
            commit(
                ui.add(
                    Slider::new(&mut ed.cycloid_period_s, 1.0..=20.0)
                        .update_while_editing(false)
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
                        .update_while_editing(false)
                        .text("amplitude")
                        .suffix(" m/s²"),
                ),
            );
            commit(
                ui.add(
                    Slider::new(&mut ed.sine_freq_hz, 0.1..=50.0)
                        .logarithmic(true)
                        .update_while_editing(false)
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
                        .update_while_editing(false)
                        .text("amplitude")
                        .suffix(" V"),
                ),
            );
            commit(
                ui.add(
                    Slider::new(&mut ed.valve_freq_hz, 0.1..=100.0)
                        .logarithmic(true)
                        .update_while_editing(false)
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
            ui.horizontal(|ui| {
                ui.label("or path:");
                let r = ui.add(
                    egui::TextEdit::singleline(&mut ed.typed_path)
                        .desired_width(170.0)
                        .hint_text("record.csv"),
                );
                let enter = r.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter));
                if (ui.button("Load").clicked() || enter) && !ed.typed_path.trim().is_empty() {
                    action =
                        ExcitationAction::LoadRecordPath(ed.typed_path.trim().to_string().into());
                }
            });
        }
    }
    action
}
