//! Unit-aware sliders (with typed entry) for the parameters and the excitation editor.
//! Values stay SI in [`Params`]; the sliders show display units and convert at the edge.

use super::gain::GainSlider;
use super::units::MM_PER_M;
use crate::engine::Excitation;
use crate::params::{ControllerKind, ParamSpec, Params, spec};
use crate::scenario::{Cycloid, RandomRide, SampledMotion};
use egui::{Response, Slider, SliderClamping};
use serde::{Deserialize, Serialize};
use std::ops::RangeInclusive;
use std::path::PathBuf;

/// One parameter slider. What it shows (display unit and scale), what it accepts (valid range)
/// and its description come from the parameter table [`crate::params::PARAMS`]; the app adds
/// only its label, the slider's span, the scale type and the decimals.
struct ParamSlider {
    /// Dotted preset key of the parameter.
    key: &'static str,
    /// Short label beside the slider.
    label: &'static str,
    /// Slider span [display units]; typed values must lie in it too.
    span: RangeInclusive<f64>,
    logarithmic: bool,
    decimals: usize,
    /// A parameter that follows this one (the linear model's τ follows the valve's).
    follows: Option<&'static str>,
    /// What to add to the table's description, if anything.
    note: &'static str,
    /// A gain: drawn as a [`GainSlider`] with this resolution [display units] (a relative,
    /// symmetric-log rail; Shift for fine steps) instead of egui's absolute slider.
    steer: Option<f64>,
}

const fn param(
    key: &'static str,
    label: &'static str,
    span: RangeInclusive<f64>,
    logarithmic: bool,
    decimals: usize,
) -> ParamSlider {
    ParamSlider {
        key,
        label,
        span,
        logarithmic,
        decimals,
        follows: None,
        note: "",
        steer: None,
    }
}

/// A controller gain: a [`GainSlider`] with resolution `resolution` [display units].
const fn gain(
    key: &'static str,
    label: &'static str,
    span: RangeInclusive<f64>,
    decimals: usize,
    resolution: f64,
) -> ParamSlider {
    ParamSlider {
        steer: Some(resolution),
        ..param(key, label, span, true, decimals)
    }
}

/// The valve group.
const VALVE: [ParamSlider; 2] = [
    param("valve.cd", "Cd", 0.01..=0.5, false, 4),
    ParamSlider {
        follows: Some("linear.tau_s"),
        note: "The linear model G(s) follows it: one τ, as in the paper.",
        ..param("valve.tau_s", "τ", 0.0..=60.0, false, 1)
    },
];

/// The rig group.
const RIG: [ParamSlider; 4] = [
    param("body.mass_kg", "mass", 1.0..=200.0, true, 1),
    param("body.stiffness_n_per_m", "stiffness", 0.1..=100.0, true, 2),
    param(
        "supply.supply_pressure_pa",
        "supply",
        15.0..=250.0,
        false,
        0,
    ),
    param("passive.zeta", "passive ζ", 0.0..=2.0, false, 2),
];

/// Every controller gain; the panel shows those of the chosen structure. The spans keep the
/// sliders where loops can be stable (a Kp of +5000 V/m is valid in a preset but only ever
/// unstable).
const GAINS: [ParamSlider; 7] = [
    ParamSlider {
        note: "Negative is negative feedback.",
        ..gain("controller.kp_v_per_m", "Kp", -2000.0..=200.0, 2, 1.0)
    },
    gain("controller.ki_v_s_per_m", "Ki", -200.0..=200.0, 2, 0.1),
    ParamSlider {
        note: "Default 20.7 ms: the valve's delay plus the spool's lag.",
        ..param("controller.lead_s", "lead", 0.0..=100.0, false, 1)
    },
    gain("controller.lead_cutoff_hz", "lead fc", 0.5..=200.0, 1, 0.1),
    ParamSlider {
        note: "Negative opposes the body's motion.",
        ..gain("controller.sky_v_s_per_m", "Ksky", -200.0..=200.0, 2, 0.1)
    },
    gain("controller.leak_hz", "leak", 0.01..=10.0, 2, 0.001),
    ParamSlider {
        note: "Keeps the feedback off the valve's 80 Hz resonance.",
        ..gain("controller.sky_cutoff_hz", "sky fc", 0.5..=200.0, 1, 0.1)
    },
];

impl ParamSlider {
    fn spec(&self) -> &'static ParamSpec {
        spec(self.key).expect("every slider's key is in the parameter table")
    }

    /// The range a typed or dragged value must lie in [display units]: the slider's span
    /// within the parameter's valid range.
    fn accepted(&self) -> (f64, f64) {
        let (a, b) = self.spec().display_range();
        (a.max(*self.span.start()), b.min(*self.span.end()))
    }

    /// The tooltip: the table's description, unit, paper value and the accepted range.
    fn hover(&self) -> String {
        let s = self.spec();
        let fmt = super::format::compact;
        let unit = s.display.unit;
        let paper = s
            .paper
            .map(|v| format!(" Paper: {} {unit}.", fmt(s.to_display(v))))
            .unwrap_or_default();
        let (lo, hi) = self.accepted();
        format!(
            "{} {} [{}].{paper} {} Accepted here: {} … {} {unit}.",
            s.symbol,
            s.doc,
            if unit.is_empty() { "-" } else { unit },
            self.note,
            fmt(lo),
            fmt(hi)
        )
    }

    /// Draws the slider (never clamping; typed values apply on Enter or focus loss only) and
    /// writes an accepted value to `p`; a refused one leaves `p` as it was and its message
    /// stays next to the slider. Returns true if `p` changed.
    fn ui(&self, ui: &mut egui::Ui, p: &mut Params, errors: &mut FieldErrors) -> bool {
        let s = self.spec();
        let mut shown = s.to_display(s.get(p));
        let before = shown;
        let suffix = match s.display.unit {
            "" => String::new(),
            u => format!(" {u}"),
        };
        let hover = match self.steer {
            Some(_) => format!(
                "{} Drag: a decade per {} px; Shift-drag or Shift-arrows: {}× finer; a click jumps.",
                self.hover(),
                super::gain::PX_PER_DECADE,
                super::gain::FINE
            ),
            None => self.hover(),
        };
        if let Some(resolution) = self.steer {
            let response = ui
                .add(
                    GainSlider::new(&mut shown, self.span.clone(), resolution, self.label)
                        .suffix(suffix)
                        .decimals(self.decimals),
                )
                .on_hover_text(hover);
            return self.commit(ui, response, shown, before, p, errors);
        }
        let mut slider = Slider::new(&mut shown, self.span.clone())
            .text(self.label)
            .suffix(suffix)
            .clamping(SliderClamping::Never)
            .update_while_editing(false)
            .logarithmic(self.logarithmic)
            .max_decimals(self.decimals)
            .min_decimals(self.decimals.min(2));
        if self.logarithmic {
            slider = slider.smallest_positive(0.1);
        }
        let response = ui.add(slider).on_hover_text(hover);
        self.commit(ui, response, shown, before, p, errors)
    }

    /// Writes an edited value `shown` [display units] to `p` if accepted (see [`try_edit`]);
    /// shows the refusal otherwise. Returns true if `p` changed.
    fn commit(
        &self,
        ui: &mut egui::Ui,
        response: Response,
        shown: f64,
        before: f64,
        p: &mut Params,
        errors: &mut FieldErrors,
    ) -> bool {
        let changed = response.changed() && shown != before && self.apply(shown, p, errors);
        show_error(ui, errors, self.label);
        changed
    }

    /// Writes `shown` [display units] to `p` (and to the parameter that follows this one)
    /// if accepted ([`try_edit`]); true if `p` changed.
    fn apply(&self, shown: f64, p: &mut Params, errors: &mut FieldErrors) -> bool {
        let s = self.spec();
        try_edit(
            self.label,
            self.accepted(),
            s.display.unit,
            shown,
            p,
            errors,
            |c| {
                let v = s.from_display(shown);
                s.set_unchecked(c, v);
                if let Some(f) = self.follows.and_then(spec) {
                    f.set_unchecked(c, v);
                }
            },
        )
    }
}

/// Sets the slider labelled `label` (`Kp`, `Ki`, `lead`, `τ`, `mass`, …) to `shown` [its
/// display unit] as dragging it there would: the same span, the same validation, the same
/// follower. The web page's JavaScript API and the tests go through here. The refusal is
/// the error (and stays next to the slider, as a dragged one does).
pub fn edit_slider(
    label: &str,
    shown: f64,
    p: &mut Params,
    errors: &mut FieldErrors,
) -> Result<(), String> {
    let slider = VALVE
        .iter()
        .chain(&RIG)
        .chain(&GAINS)
        .find(|k| k.label == label)
        .ok_or_else(|| {
            let labels: Vec<&str> = VALVE
                .iter()
                .chain(&RIG)
                .chain(&GAINS)
                .map(|k| k.label)
                .collect();
            format!("no slider `{label}` (one of: {})", labels.join(", "))
        })?;
    if slider.apply(shown, p, errors) {
        Ok(())
    } else {
        Err(errors
            .get(slider.label)
            .cloned()
            .unwrap_or_else(|| format!("{label} refused")))
    }
}

/// Refused values, by control label, shown next to the control until a value is accepted.
pub type FieldErrors = std::collections::BTreeMap<&'static str, String>;

/// Tries one edit of the control `label`: the value `shown` [display units] must lie in
/// `accepted` and the whole parameter set, with `set` applied, must validate. Only then is it
/// written to `p`; otherwise the message goes to `errors` and `p` stays as it was.
fn try_edit(
    label: &'static str,
    (lo, hi): (f64, f64),
    unit: &str,
    shown: f64,
    p: &mut Params,
    errors: &mut FieldErrors,
    set: impl FnOnce(&mut Params),
) -> bool {
    let fmt = super::format::compact;
    if !(shown.is_finite() && shown >= lo && shown <= hi) {
        errors.insert(
            label,
            format!(
                "{label} = {} {unit} refused: allowed {} … {} {unit}",
                fmt(shown),
                fmt(lo),
                fmt(hi)
            ),
        );
        return false;
    }
    let mut candidate = *p;
    set(&mut candidate);
    match candidate.validate() {
        Ok(()) => {
            *p = candidate;
            // A message is about the last attempt: an accepted value anywhere ends it.
            errors.clear();
            true
        }
        Err(e) => {
            errors.insert(label, format!("{label} refused: {e}"));
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
    egui::CollapsingHeader::new("Controller")
        .default_open(true)
        .show(ui, |ui| changed |= controller_ui(ui, p, errors));
    for (title, knobs) in [("Valve", &VALVE[..]), ("Rig", &RIG[..])] {
        egui::CollapsingHeader::new(title)
            .default_open(true)
            .show(ui, |ui| {
                for k in knobs {
                    changed |= k.ui(ui, p, errors);
                }
            });
    }
    changed
}

/// The refusal message of control `label`, if any, next to it.
fn show_error(ui: &mut egui::Ui, errors: &FieldErrors, label: &str) {
    if let Some(e) = errors.get(label) {
        ui.colored_label(super::style::ERROR_TEXT, e);
    }
}

/// One-line description of a controller structure for the panel.
pub fn kind_summary(kind: ControllerKind) -> &'static str {
    // Only glyphs the app's font draws (no combining dots): v_p is the platform velocity
    // integrated from its accelerometer, v_b the body velocity estimated from its own.
    match kind {
        ControllerKind::Paper => "V = Kp·u + Ki·v_p (the paper's Eq. 16)",
        ControllerKind::Predictive => "V = Kp·u + Ki·(v_p + L·LP(a_p)): v_p predicted L ahead",
        ControllerKind::Skyhook => "V = Kp·u + Ki·v_p + Ksky·LP(v_b): body-velocity feedback",
        ControllerKind::Smith => "Smith predictor on G(s) with its delay, plus Ki·v_p",
    }
}

/// The controller panel: a structure combo box and the gain sliders of that structure. Like
/// every control, a refused value (outside its range in the parameter table or invalid as a
/// whole) never reaches `p`. Returns true if the controller changed.
pub fn controller_ui(ui: &mut egui::Ui, p: &mut Params, errors: &mut FieldErrors) -> bool {
    let mut changed = false;
    let mut kind = p.controller.kind;
    egui::ComboBox::from_label("structure")
        .selected_text(kind.name())
        .show_ui(ui, |ui| {
            for k in ControllerKind::ALL {
                ui.selectable_value(&mut kind, k, k.name())
                    .on_hover_text(kind_summary(k));
            }
        });
    if kind != p.controller.kind {
        let mut candidate = *p;
        candidate.controller.kind = kind;
        match candidate.validate() {
            Ok(()) => {
                *p = candidate;
                errors.clear();
                changed = true;
            }
            Err(e) => {
                errors.insert("structure", format!("structure {kind} refused: {e}"));
            }
        }
    }
    show_error(ui, errors, "structure");
    ui.weak(kind_summary(p.controller.kind));
    for gain in &GAINS {
        if gain.spec().applies_to(p.controller.kind) {
            changed |= gain.ui(ui, p, errors);
        }
    }
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
    /// A seat-test input class (ISO 7096, ISO 5007, EN 13490).
    Class,
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
            ExcitationKind::Class => "seat-test class",
            ExcitationKind::Record => "CSV record",
        }
    }
}

/// A loaded platform record.
#[derive(Debug, Clone)]
pub struct LoadedRecord {
    /// File name shown in the UI.
    pub name: String,
    /// The file (a session file keeps the record by it).
    pub path: PathBuf,
    /// The motion.
    pub motion: SampledMotion,
}

impl LoadedRecord {
    /// Reads a CSV platform record ([`super::files::read_platform_record`]).
    pub fn read(path: &std::path::Path) -> anyhow::Result<Self> {
        let motion = super::files::read_platform_record(path)?;
        let name = path
            .file_name()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        Ok(Self {
            name,
            path: path.to_path_buf(),
            motion,
        })
    }
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
    /// Cycloid repeat period \[s\].
    pub cycloid_period_s: f64,
    /// Platform sine acceleration amplitude [m/s²].
    pub sine_accel_m_s2: f64,
    /// Platform sine frequency \[Hz\].
    pub sine_freq_hz: f64,
    /// Valve sine amplitude \[V\].
    pub valve_amplitude_v: f64,
    /// Valve sine frequency \[Hz\].
    pub valve_freq_hz: f64,
    /// Seat-test class name (e.g. `"EM6"`).
    pub class_name: String,
    /// Seat-test class record length \[s\] (a new seed follows when it ends).
    pub class_duration_s: f64,
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
            class_name: "EM6".into(),
            class_duration_s: crate::seat_test::run::DEFAULT_DURATION_S,
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
            ExcitationKind::Class => Excitation::Class {
                class: crate::seat_test::find(&self.class_name)?,
                duration_s: self.class_duration_s,
                seed: 1,
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
            ExcitationKind::Class if crate::seat_test::find(&self.class_name).is_none() => {
                Some(format!("unknown seat-test class `{}`", self.class_name))
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

/// What to know about a seat-test class on this rig: its standard, band rms and the mass the
/// standard tests with against the suspended mass here.
pub fn class_note(class: &crate::seat_test::InputClass, mass_kg: f64) -> String {
    let mut s = format!(
        "{}: {} — platform rms {:.2} m/s² in {:.2}–{:.2} Hz. The standard tests with people \
         (or a 75 kg inert mass); this twin carries {:.1} kg{}, so the result is this rig's \
         hardware on the standard input, not a seat certification.",
        class.name,
        class.standard.citation(),
        class.rms_m_s2,
        class.rms_band_hz.0,
        class.rms_band_hz.1,
        mass_kg,
        if (mass_kg - crate::seat_test::report::RIG_MASS_KG).abs() < 1e-9 {
            " (the paper's rig)"
        } else {
            ""
        }
    );
    if !class.note.is_empty() {
        s.push(' ');
        s.push_str(class.note);
    }
    s
}

/// The excitation editor; `mass_kg` is the suspended mass (for the seat-test class note).
pub fn excitation_ui(
    ui: &mut egui::Ui,
    ed: &mut ExcitationEditor,
    mass_kg: f64,
) -> ExcitationAction {
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
                ExcitationKind::Class,
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
        ExcitationKind::Class => {
            let before = ed.class_name.clone();
            egui::ComboBox::from_label("class")
                .selected_text(ed.class_name.as_str())
                .height(420.0)
                .show_ui(ui, |ui| {
                    for c in &crate::seat_test::CLASSES {
                        ui.selectable_value(&mut ed.class_name, c.name.to_string(), c.name)
                            .on_hover_text(c.standard.citation());
                    }
                });
            if ed.class_name != before {
                action = ExcitationAction::Apply;
            }
            if committed(
                &ui.add(
                    Slider::new(&mut ed.class_duration_s, 20.0..=600.0)
                        .update_while_editing(false)
                        .text("record")
                        .suffix(" s"),
                )
                .on_hover_text(
                    "Length of each generated record (a new seed follows). The generator meets \
                     the class's PSD within its tolerance on the standard's 180 s; shorter \
                     records can miss it by more.",
                ),
            ) {
                action = ExcitationAction::Apply;
            }
            if let Some(c) = crate::seat_test::find(&ed.class_name) {
                ui.add(egui::Label::new(egui::RichText::new(class_note(c, mass_kg)).weak()).wrap());
            }
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
                if let Some(p) =
                    super::files::typed_path_ui(ui, &mut ed.typed_path, "record.csv", 170.0)
                {
                    action = ExcitationAction::LoadRecordPath(p.into());
                }
            });
        }
    }
    action
}
