//! The Lessons panel: guided steps for a lecture. Each step sets a preset and an excitation,
//! says what to look at and what to try, and notices when the student has done it.
//!
//! The panel owns its state (which step, which are done, what the student has touched) and
//! returns a [`LessonAction`]; the app applies it. Whether a step is done is decided from a
//! [`LessonView`] of the live run, which the app builds each frame.

use super::controls::{ExcitationEditor, ExcitationKind};
use crate::params::{ControllerKind, Params};
use egui::RichText;

/// What the lessons see of the live run, each frame.
#[derive(Debug, Clone, Copy)]
pub struct LessonView<'a> {
    /// The live parameters.
    pub params: &'a Params,
    /// The excitation editor's state.
    pub excitation: &'a ExcitationEditor,
    /// The loop is unstable (linear verdict, or the running twin's own watch, or an engine
    /// divergence).
    pub unstable: bool,
    /// Seconds of data in the running metrics (since the last change) \[s\].
    pub counted_s: f64,
    /// SEAT of the twin and of the passive seat [%] over the counted data.
    pub seat_twin_percent: f64,
    /// SEAT of the passive seat [%].
    pub seat_passive_percent: f64,
    /// a_w of the platform [m/s²].
    pub aw_platform: f64,
}

/// One guided step.
pub struct Lesson {
    /// Title in the list.
    pub title: &'static str,
    /// The preset it starts from (compiled in, [`super::share::SHIPPED`]).
    pub preset: &'static str,
    /// What it explains, with the equations that matter.
    pub text: &'static str,
    /// What to try.
    pub task: &'static str,
    /// Sets the parameters and the excitation of the step on top of the preset.
    setup: fn(&mut Params, &mut ExcitationEditor),
    /// Done, given the live view and the parameters when the step started.
    done: fn(&LessonView<'_>, &Params) -> bool,
}

/// The passive seat's natural frequency `fn = √(k/m)/2π` \[Hz\].
pub fn passive_natural_hz(p: &Params) -> f64 {
    (p.plant.body.stiffness_n_per_m / p.plant.body.mass_kg).sqrt() / (2.0 * std::f64::consts::PI)
}

fn random_ride(e: &mut ExcitationEditor) {
    *e = ExcitationEditor::default();
    e.kind = ExcitationKind::Random;
}

fn sine(e: &mut ExcitationEditor, f_hz: f64) {
    *e = ExcitationEditor::default();
    e.kind = ExcitationKind::Sine;
    e.sine_accel_m_s2 = 0.5;
    e.sine_freq_hz = f_hz;
}

/// The steps, in order.
pub static LESSONS: [Lesson; 6] = [
    Lesson {
        title: "1 · The passive seat and its resonance",
        preset: "paper",
        text: "Without control the seat is a mass m on a spring k and a damper: \
               m·y'' = −k·(y − x) − c·(y' − x') (x platform, y body). Below its natural frequency \
               fn = √(k/m) / 2π the body follows the platform; near fn it moves MORE than \
               the platform (transmissibility > 1, SEAT > 100 %); well above it, less. \
               Look at the dotted passive curve in the transmissibility plot and at the \
               passive SEAT in the metrics table.",
        task: "The platform shakes with a sine at 2 Hz. Move its frequency (Excitation: \
               platform sine, f, Apply) to the passive seat's resonance, within ±20 % of fn, \
               and watch the passive body's acceleration grow.",
        setup: |_, e| sine(e, 2.0),
        done: |v, _| {
            let fn_hz = passive_natural_hz(v.params);
            v.excitation.kind == ExcitationKind::Sine
                && (0.8 * fn_hz..=1.2 * fn_hz).contains(&v.excitation.sine_freq_hz)
                && v.counted_s >= 2.0
        },
    },
    Lesson {
        title: "2 · Position feedback",
        preset: "paper",
        text: "The active seat drives a hydraulic cylinder between platform and body. With \
               only position feedback, V = Kp·u (u = stroke, the cylinder's extension), the \
               valve pushes the stroke back to mid-travel: the seat behaves like a stiff \
               spring, so the body follows the platform. Kp < 0 is negative feedback \
               [V/m].",
        task: "Ki is 0 here. Make Kp about twice as strong (more negative) and watch the \
               stroke scope: |u| shrinks, and the body's acceleration gets closer to the \
               platform's.",
        setup: |p, e| {
            p.controller.kind = ControllerKind::Paper;
            p.controller.ki_v_s_per_m = 0.0;
            random_ride(e);
        },
        done: |v, start| {
            v.params.controller.kp_v_per_m <= 1.9 * start.controller.kp_v_per_m
                && !v.unstable
                && v.counted_s >= 2.0
        },
    },
    Lesson {
        title: "3 · The valve delay and where instability comes from",
        preset: "paper",
        text: "The servo valve answers after a pure delay τ (≈ 20 ms here). A delay keeps the \
               gain and adds a phase lag: e^(−sτ) lags by ω·τ rad at ω. The loop Kp·G(s) with \
               G(s) = e^(−sτ)·Kv/(s·(1 + s/ωv)) is stable while its phase at the gain \
               crossover ωc stays above −180°. Raising |Kp| moves ωc up, where −ωc·τ eats \
               the phase margin: the loop rings, then grows.",
        task: "Raise |Kp| until the loop goes unstable (the Stable line turns red, the \
               twin rings). Then press “Reset to last stable gains”.",
        setup: |p, e| {
            p.controller.kind = ControllerKind::Paper;
            random_ride(e);
        },
        done: |v, _| v.unstable,
    },
    Lesson {
        title: "4 · Velocity feed-forward: the paper's controller",
        preset: "paper",
        text: "The paper adds the platform's velocity, measured as the integral of its \
               acceleration a_p: V = Kp·u + Ki·∫a_p dt = Kp·u + Ki·v_p. The cylinder then moves against the \
               platform before the position loop sees any error, so the body stays still: \
               y'' ≈ 0 in the band the valve can follow. SEAT = 100 %·a_w,body / a_w,platform \
               falls well below the passive seat's.",
        task: "Set Ki to 0 and see the twin's SEAT rise to the passive level or above; set \
               it back near the paper's value until the twin beats the passive seat again \
               for 5 s.",
        setup: |p, e| {
            p.controller.kind = ControllerKind::Paper;
            random_ride(e);
        },
        done: |v, start| {
            // Ki was touched (it differs, or it was restored after a change that reset the
            // metrics) and the twin beats the passive seat over at least 5 s.
            let ki = v.params.controller.ki_v_s_per_m;
            let back = (ki - start.controller.ki_v_s_per_m).abs()
                <= 0.2 * start.controller.ki_v_s_per_m.abs();
            back && v.counted_s >= 5.0 && v.seat_twin_percent < v.seat_passive_percent
        },
    },
    Lesson {
        title: "5 · ISO 2631-1: why 4–8 Hz matters",
        preset: "paper",
        text: "People feel vertical vibration most between about 4 and 8 Hz (the trunk's \
               resonance). ISO 2631-1 weights the acceleration with Wk(f) before taking the \
               RMS: a_w = √( (1/T)·∫ a_wk(t)² dt ). Wk ≈ 1 in 4–8 Hz, 0.48 at 1 Hz, and \
               falls above 8 Hz. The same rms at 6 Hz counts about twice what it counts at \
               1 Hz.",
        task: "The platform shakes with 0.5 m/s² at 1 Hz: note the platform's a_w in the \
               metrics table. Move the frequency into 4–8 Hz (same amplitude, Apply) and \
               see a_w roughly double although the RMS stays the same.",
        setup: |_, e| sine(e, 1.0),
        done: |v, _| {
            v.excitation.kind == ExcitationKind::Sine
                && (4.0..=8.0).contains(&v.excitation.sine_freq_hz)
                && v.counted_s >= 2.0
                && v.aw_platform > 0.3
        },
    },
    Lesson {
        title: "6 · The predictive controller beats the delay",
        preset: "tuned-predictive",
        text: "The valve's delay τ means the feed-forward always arrives late. The predictive \
               controller feeds the platform velocity predicted `lead` seconds ahead: \
               V = Kp·u + Ki·(v_p + T_lead·LP(a_p)), since v_p(t + T) ≈ v_p(t) + T·a_p(t). With \
               T_lead ≈ τ plus the spool's lag the cylinder moves in time, and the twin's \
               SEAT drops further than with the paper's controller.",
        task: "Set lead to 0 ms and see the twin's SEAT rise; set it back to about 20 ms and \
               let it run 5 s.",
        setup: |p, e| {
            p.controller.kind = ControllerKind::Predictive;
            random_ride(e);
        },
        done: |v, start| {
            v.params.controller.kind == ControllerKind::Predictive
                && v.params.controller.lead_s >= 0.5 * start.controller.lead_s
                && v.counted_s >= 5.0
                && v.seat_twin_percent < v.seat_passive_percent
        },
    },
];

/// What the panel asks the app to do.
#[derive(Debug, Clone, PartialEq)]
pub enum LessonAction {
    /// Nothing.
    None,
    /// Start step `n`: load its preset, set its parameters and excitation, reset.
    Start(usize),
}

/// The panel's state.
#[derive(Debug, Clone, Default)]
pub struct LessonsPanel {
    /// Shown.
    pub open: bool,
    /// The step in progress (0-based), if one was started.
    pub current: Option<usize>,
    /// The parameters when the current step started.
    start: Option<Params>,
    /// Steps completed.
    done: [bool; 6],
    /// The current step's "undo" part was seen (steps 4 and 6: the student first turns the
    /// feed-forward off, then back on).
    touched: bool,
}

impl LessonsPanel {
    /// Whether step `n` is done.
    pub fn is_done(&self, n: usize) -> bool {
        self.done.get(n).copied().unwrap_or(false)
    }

    /// The parameters and excitation of step `n` on top of its preset's parameters `p`.
    pub fn set_up(n: usize, p: &mut Params, e: &mut ExcitationEditor) {
        if let Some(l) = LESSONS.get(n) {
            (l.setup)(p, e);
        }
    }

    /// The step `n` started with these parameters (the app calls this after applying it).
    pub fn started(&mut self, n: usize, params: Params) {
        self.current = Some(n);
        self.start = Some(params);
        self.touched = false;
        self.open = true;
    }

    /// Checks the current step against the live view; true when it just completed.
    pub fn check(&mut self, view: &LessonView<'_>) -> bool {
        let (Some(n), Some(start)) = (self.current, self.start) else {
            return false;
        };
        if self.done[n] {
            return false;
        }
        let c = &view.params.controller;
        // Steps 4 and 6 ask to turn the feed-forward off first.
        match n {
            3 if c.ki_v_s_per_m.abs() < 0.05 * start.controller.ki_v_s_per_m.abs() => {
                self.touched = true;
            }
            5 if c.lead_s < 0.2 * start.controller.lead_s => self.touched = true,
            _ => {}
        }
        let needs_touch = matches!(n, 3 | 5);
        if (!needs_touch || self.touched) && (LESSONS[n].done)(view, &start) {
            self.done[n] = true;
            return true;
        }
        false
    }

    /// The panel's contents.
    pub fn ui(&mut self, ui: &mut egui::Ui) -> LessonAction {
        let mut action = LessonAction::None;
        ui.label(
            "Guided steps: each one sets a preset and an excitation, says what to look at \
             and what to try, and ticks itself when you have done it.",
        );
        ui.separator();
        for (n, l) in LESSONS.iter().enumerate() {
            ui.horizontal(|ui| {
                let mut done = self.done[n];
                ui.add_enabled(false, egui::Checkbox::without_text(&mut done));
                let title = RichText::new(l.title);
                let title = if self.current == Some(n) {
                    title.strong()
                } else {
                    title
                };
                if ui
                    .selectable_label(self.current == Some(n), title)
                    .on_hover_text("Start this step (sets its preset and excitation)")
                    .clicked()
                {
                    action = LessonAction::Start(n);
                }
            });
        }
        if let Some(n) = self.current {
            let l = &LESSONS[n];
            ui.separator();
            ui.heading(l.title);
            ui.label(l.text);
            ui.add_space(4.0);
            ui.label(RichText::new(format!("Try: {}", l.task)).strong());
            ui.add_space(4.0);
            if self.done[n] {
                ui.colored_label(super::style::OK_TEXT, "Done — well spotted.");
                if n + 1 < LESSONS.len() && ui.button("Next step").clicked() {
                    action = LessonAction::Start(n + 1);
                }
            } else {
                ui.weak("Not done yet: the step ticks itself when it sees it.");
                if ui.button("Restart this step").clicked() {
                    action = LessonAction::Start(n);
                }
            }
        }
        action
    }
}
