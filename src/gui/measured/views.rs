//! The measured-data window's views: the replay overlay (measured against twin) and the
//! residual diagnosis.

use super::*;

impl MeasuredData {
    pub(super) fn overlay_ui(&mut self, ui: &mut egui::Ui) {
        let name = self
            .records
            .get(self.selected)
            .map(|r| r.prepared.name.clone())
            .unwrap_or_default();
        ui.horizontal(|ui| {
            ui.strong(format!("Measured vs twin: {name}"));
            if self.replaying.is_some() || self.calibrated_job.is_some() {
                ui.spinner();
                ui.weak("replaying…");
            }
        });
        let Some(v) = &self.view else {
            return;
        };
        let cal = self
            .calibrated_view
            .as_ref()
            .filter(|c| c.record == v.record);
        let plot = |id: &str, label: &str| {
            Plot::new(id.to_owned())
                .height(150.0)
                .y_axis_label(label.to_owned())
                .y_axis_min_width(44.0)
                .label_formatter(|pos| {
                    let (name, p) = match pos {
                        egui_plot::HoverPosition::NearDataPoint {
                            plot_name,
                            position,
                            ..
                        } => (format!("{plot_name}\n"), position),
                        egui_plot::HoverPosition::Elsewhere { position } => {
                            (String::new(), position)
                        }
                    };
                    Some(format!(
                        "{name}t = {:.3} s\n{}",
                        p.x,
                        crate::gui::format::value_pm(p.y, f64::NAN)
                    ))
                })
                .link_axis(egui::Id::unique("measured_link"), [true, false])
                .link_cursor(egui::Id::unique("measured_link"), [true, false])
                .legend(
                    Legend::default()
                        .position(Corner::LeftTop)
                        .text_style(egui::TextStyle::Small)
                        .background_alpha(0.6),
                )
        };
        let line = |name: &str, pts: &[[f64; 2]], c: Color32, w: f32| {
            Line::new(name.to_owned(), PlotPoints::from(pts.to_vec()))
                .color(c)
                .width(w)
        };
        plot("measured_du", "du/dt [mm/s]").show(ui, |pu| {
            pu.line(line("twin (live parameters)", &v.du[1], TWIN, 2.0));
            if let Some(c) = cal {
                pu.line(line("twin (calibrated)", &c.du[1], CALIBRATED, 2.0));
            }
            // On top, thin: visible where the twin covers it.
            pu.line(line("measured", &v.du[0], MEASURED, 1.0));
        });
        plot("measured_u", "stroke u [mm]").show(ui, |pu| {
            pu.line(line("twin (live parameters)", &v.u[1], TWIN, 2.0));
            if let Some(c) = cal {
                pu.line(line("twin (calibrated)", &c.u[1], CALIBRATED, 2.0));
            }
            // On top, thin: visible where the twin covers it.
            pu.line(line("measured", &v.u[0], MEASURED, 1.0));
        });
        if !v.ydd[0].is_empty() {
            plot("measured_ydd", "body accel. [m/s²]").show(ui, |pu| {
                pu.line(line("twin (live parameters)", &v.ydd[1], TWIN, 2.0));
                if let Some(c) = cal {
                    pu.line(line("twin (calibrated)", &c.ydd[1], CALIBRATED, 2.0));
                }
                // On top, thin: visible where the twin covers it.
                pu.line(line("measured", &v.ydd[0], MEASURED, 1.0));
            });
        }
        plot("measured_res", "residual du/dt [mm/s]")
            .x_axis_label("time [s]")
            .show(ui, |pu| {
                pu.line(line("twin − measured (live)", &v.residual, RESIDUAL, 1.0));
                if let Some(c) = cal {
                    pu.line(line(
                        "twin − measured (calibrated)",
                        &c.residual,
                        CALIBRATED,
                        1.0,
                    ));
                }
            });
    }

    pub(super) fn diagnosis_ui(&self, ui: &mut egui::Ui) {
        let Some(v) = &self.view else {
            return;
        };
        ui.strong("Residual of this record (live parameters)");
        let e = &v.errors;
        ui.monospace(format!(
            "RMS: du/dt {:.2} mm/s ({:.1} % of signal), u {:.2} mm{}{}",
            e.du * MM_PER_M,
            e.du_nrmse * 100.0,
            e.u * MM_PER_M,
            e.ydd
                .map(|y| format!(", ydd {y:.3} m/s²"))
                .unwrap_or_default(),
            match (e.p1, e.p2) {
                (Some(a), Some(b)) => format!(", p1 {:.2} bar, p2 {:.2} bar", a * 1e-5, b * 1e-5),
                _ => String::new(),
            }
        ));
        let above = v.weighted_rms > self.options.noise_level;
        ui.label(
            RichText::new(format!(
                "weighted error {:.2} (1.0 = sensor noise): {}",
                v.weighted_rms,
                if above {
                    "above the noise, the twin misses something here"
                } else {
                    "at the noise level (or within 1 % of the signal)"
                }
            ))
            .color(if above {
                Color32::from_rgb(220, 120, 20)
            } else {
                Color32::from_rgb(40, 160, 60)
            }),
        );
        let w = &v.whiteness;
        ui.weak(format!(
            "whiteness of the (25 Hz low-passed, so never white) residual: lag-1 \
             autocorrelation {:.2}, {:.0} % of {} lags outside the white-noise band",
            w.lag1,
            w.share_outside * 100.0,
            w.max_lag,
        ));
        ui.label("correlation of the residual with each effect's signature:");
        crate::gui::plotkit::table_ui(
            ui,
            "measured_corr",
            &["feature", "suggests", "velocity", "accel."],
            |ui| {
                let strongest = v
                    .correlations
                    .iter()
                    .map(|c| c.velocity.abs())
                    .fold(0.0, f64::max);
                for c in &v.correlations {
                    ui.label(&c.feature);
                    let t = RichText::new(&c.effect);
                    ui.label(if c.velocity.abs() == strongest && strongest > 0.2 {
                        t.strong()
                    } else {
                        t
                    });
                    ui.monospace(format!("{:+.2}", c.velocity));
                    ui.monospace(if c.acceleration.is_finite() {
                        format!("{:+.2}", c.acceleration)
                    } else {
                        "–".into()
                    });
                    ui.end_row();
                }
            },
        );
        ui.weak(
            "Correlations hint; the calibration decides, by fitting each effect and ranking \
             them by ΔBIC.",
        );
    }
}
