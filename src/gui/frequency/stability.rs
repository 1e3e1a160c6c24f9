//! The stability line above the frequency plots: the closed-loop verdict of both loops (their
//! eigenvalues with the delay, [`crate::analysis::stability`]), the worst margins over every
//! crossing (amber under 6 dB / 45°), the isolation band — or a red banner with the growing
//! mode and the remedy when a loop is unstable. Hovering the line lists every crossing.

use super::*;
use crate::analysis::stability::LoopMargins;
use crate::analysis::watch::Finding;

/// Margins under these show amber [dB], [deg].
const AMBER_GM_DB: f64 = 6.0;
const AMBER_PM_DEG: f64 = 45.0;

/// The worst margins in words: numbers wrapped to ±180°, "∞" with the reason when there is no
/// crossing.
pub fn margin_text(m: &LoopMargins) -> String {
    let gm = match m.worst_gain() {
        Some(c) => format!("GM {:.1} dB at {:.2} Hz", c.gain_margin_db, c.freq_hz),
        None => "GM ∞ (phase never reaches −180°)".into(),
    };
    let pm = match m.worst_phase() {
        Some(c) => format!(
            "PM {:.0}° at {:.2} Hz, delay margin {}",
            c.phase_margin_deg,
            c.freq_hz,
            delay_text(m.delay_margin_s())
        ),
        None => "PM ∞ (|L| never reaches 1)".into(),
    };
    format!("{gm}, {pm}")
}

/// A delay margin for people: ms below a second, s above, in words when there is none.
fn delay_text(dm_s: f64) -> String {
    if !dm_s.is_finite() {
        "∞ (no destabilising crossover)".into()
    } else if dm_s < 1.0 {
        format!("{:.2} ms", dm_s * 1e3)
    } else {
        format!("{dm_s:.2} s")
    }
}

/// Every crossing of a loop, one per line (the Stable line's tooltip).
pub fn crossings_text(m: &LoopMargins) -> String {
    let mut out = Vec::new();
    for c in &m.gain_crossovers {
        out.push(if c.destabilising {
            format!(
                "|L| = 1 at {:.3} Hz (falling): PM {:.1}°, delay margin {}",
                c.freq_hz,
                c.phase_margin_deg,
                delay_text(c.delay_margin_s)
            )
        } else {
            format!(
                "|L| = 1 at {:.3} Hz (rising): PM {:.1}° (more delay moves the pole on the \
                 axis leftwards here)",
                c.freq_hz, c.phase_margin_deg
            )
        });
    }
    for c in &m.phase_crossovers {
        out.push(format!(
            "∠L = −180° at {:.3} Hz: GM {:.1} dB",
            c.freq_hz, c.gain_margin_db
        ));
    }
    if out.is_empty() {
        out.push("no crossing".into());
    }
    out.join("\n")
}

/// Whether a margin is under the amber limits.
fn thin(m: &LoopMargins) -> bool {
    m.gain_margin_db().abs() < AMBER_GM_DB || m.phase_margin_deg().abs() < AMBER_PM_DEG
}

/// The stability line: the verdict and margins, and a red banner with the growing mode and
/// the remedy when a loop is unstable. Returns the button the user pressed.
pub fn stability_ui(
    ui: &mut egui::Ui,
    curves: &Curves,
    last_stable: Option<ControllerParams>,
    watch: Option<Finding>,
) -> FreqAction {
    let mut action = FreqAction::None;
    let [lin, twin] = &curves.stability;
    let (Some(lin), Some(twin)) = (lin, twin) else {
        return action;
    };
    let hover = format!(
        "Twin (linearised at rest), every crossing of the loop gain:\n{}\n\nG(s):\n{}\n\n\
         The verdict comes from the closed-loop eigenvalues with the delay; the margins \
         describe the loop.",
        crossings_text(&twin.margins),
        crossings_text(&lin.margins)
    );
    let oscillating = watch.filter(|f| !matches!(f, Finding::NegativePressure { .. }));
    if curves.unstable() || oscillating.is_some() {
        let text = if curves.unstable() {
            format!(
                "UNSTABLE closed loop — twin: {}; linear: {}. {}{} The faint active curves are \
                 not a steady state.",
                twin.mode_text(),
                lin.mode_text(),
                curves.remedy,
                oscillating.map_or(String::new(), |f| format!(" Also: {f}.")),
            )
        } else {
            format!(
                "UNSTABLE running twin — {}. The loop linearised at rest reads stable ({}), so \
                 the twin rings away from that point or its own way: lower |Kp| and the \
                 feedback gains, or shorten τ. Reset restarts from rest.",
                oscillating.map_or(String::new(), |f| f.to_string()),
                margin_text(&twin.margins),
            )
        };
        egui::Frame::new()
            .fill(crate::gui::style::UNSTABLE_FILL)
            .inner_margin(6.0)
            .corner_radius(4.0)
            .show(ui, |ui| {
                ui.set_width(ui.available_width());
                ui.label(RichText::new(text).color(Color32::WHITE).strong())
                    .on_hover_text(&hover);
                if let Some(g) = last_stable
                    && ui
                        .button("Reset to last stable gains")
                        .on_hover_text(format!(
                            "{}, and the simulation from rest",
                            crate::gui::format::controller_text(&g)
                        ))
                        .clicked()
                {
                    action = FreqAction::ResetToStableGains;
                }
            });
    } else {
        let edge = |cs: &[Crossing]| {
            cs.iter()
                .find(|c| c.rising)
                .map(|c| format!("{:.2} Hz", c.freq_hz))
                .unwrap_or_else(|| "none".into())
        };
        let text = format!(
            "Stable. Twin {}, isolation up to {}; linear {}, up to {}.",
            margin_text(&twin.margins),
            edge(&curves.crossings[1]),
            margin_text(&lin.margins),
            edge(&curves.crossings[0]),
        );
        let rich = if thin(&twin.margins) || thin(&lin.margins) {
            RichText::new(format!("{text} Thin margin (< 6 dB or < 45°)."))
                .color(crate::gui::style::WARNING_TEXT)
        } else {
            RichText::new(text)
        };
        ui.label(rich).on_hover_text(hover);
    }
    if let Some(f @ Finding::NegativePressure { .. }) = watch {
        ui.label(
            RichText::new(format!("Outside the model: {f}."))
                .color(crate::gui::style::WARNING_TEXT),
        );
    }
    action
}
