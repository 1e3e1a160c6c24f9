//! The stability line above the frequency plots: both loops' margins and isolation band,
//! or a red banner with the remedy the stability condition gives when a loop is unstable.

use super::*;

fn margin_text(m: &LoopMargins) -> String {
    let gm = if m.gain_margin.is_finite() && m.gain_margin <= 0.0 {
        // No gain keeps it stable (positive feedback).
        "−∞ dB".into()
    } else if m.gain_margin.is_finite() {
        format!("{:.1} dB", db(m.gain_margin))
    } else {
        "∞".into()
    };
    let pm = if m.phase_margin_deg.is_finite() {
        format!("{:.0}°", m.phase_margin_deg)
    } else if m.phase_margin_deg > 0.0 {
        "∞".into()
    } else {
        "−∞".into()
    };
    format!("GM {gm}, PM {pm}")
}

/// What to change to make the loop stable, from the stability condition itself: a positive
/// Kp is positive feedback at any gain (the margins are those of `V = Kp·u` with
/// `Kp < 0`); otherwise the smallest gain margin says how far |Kp| must come down.
pub fn remedy(curves: &Curves) -> String {
    let Some(p) = curves.params else {
        return String::new();
    };
    let kp = p.controller.kp_v_per_m;
    if kp > 0.0 {
        return format!(
            "Kp = {kp:.1} V/m feeds the stroke back with the wrong sign (positive feedback, \
             unstable at any gain): use a negative Kp."
        );
    }
    let unstable: Vec<&LoopMargins> = curves
        .margins
        .iter()
        .flatten()
        .filter(|m| !m.stable())
        .collect();
    let gm = unstable
        .iter()
        .map(|m| m.gain_margin)
        .filter(|g| g.is_finite() && *g > 0.0)
        .fold(f64::INFINITY, f64::min);
    if gm < 1.0 {
        let limit = kp.abs() * gm;
        format!(
            "|Kp| = {:.1} V/m is above the stability limit: keep Kp between −{limit:.1} and 0 V/m \
             (less |Kp| or a shorter τ).",
            kp.abs()
        )
    } else {
        "The phase margin is negative: reduce |Kp| or τ.".into()
    }
}

/// The stability line: margins, and a red banner with the remedy when a loop is unstable.
/// Returns the button the user pressed.
pub fn stability_ui(
    ui: &mut egui::Ui,
    curves: &Curves,
    last_stable: Option<ControllerParams>,
) -> FreqAction {
    let mut action = FreqAction::None;
    let [lin, twin] = &curves.margins;
    let (Some(lin), Some(twin)) = (lin, twin) else {
        return action;
    };
    if curves.unstable() {
        egui::Frame::new()
            .fill(Color32::from_rgb(180, 30, 30))
            .inner_margin(6.0)
            .corner_radius(4.0)
            .show(ui, |ui| {
                ui.set_width(ui.available_width());
                ui.label(
                    RichText::new(format!(
                        "UNSTABLE closed loop — twin: {}; linear: {}. {} The faint active \
                         curves are not a steady state.",
                        margin_text(twin),
                        margin_text(lin),
                        remedy(curves),
                    ))
                    .color(Color32::WHITE)
                    .strong(),
                );
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
        ui.label(format!(
            "Stable. Twin {}, isolation up to {}; linear {}, up to {}.",
            margin_text(twin),
            edge(&curves.crossings[1]),
            margin_text(lin),
            edge(&curves.crossings[0]),
        ));
    }
    action
}
