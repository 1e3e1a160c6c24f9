//! The measured-data window's views: the replay overlay (measured against twin) and the
//! residual diagnosis.

use super::*;
use crate::gui::plotkit::{self, LegendItem, Swatch, legend_ui, y_axis, y_marks};
use egui_plot::LineStyle;

/// (name, points, colour, width) of one plot's curve.
type Curve<'a> = (&'static str, &'a [[f64; 2]], Color32, f32);

/// The twin with the live parameters, the calibrated twin (if any) and the measured channel
/// last, thin: visible where the twin covers it.
fn three<'a>(
    live: &'a [[f64; 2]],
    cal: Option<&'a [[f64; 2]]>,
    measured: &'a [[f64; 2]],
) -> Vec<Curve<'a>> {
    let mut v: Vec<Curve<'a>> = vec![("twin (live parameters)", live, TWIN, 2.0)];
    if let Some(c) = cal {
        v.push(("twin (calibrated)", c, CALIBRATED, 2.0));
    }
    v.push(("measured", measured, MEASURED, 1.0));
    v
}

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
        // Numbers on every y axis (plotkit's axis: egui_plot's default left the residual
        // with only "0"), and the legend in a row above each plot, off the data; a click
        // on an entry hides its curve.
        const HEIGHT: f32 = 150.0;
        let plot = |id: &str, label: &str| {
            Plot::new(id.to_owned())
                .height(HEIGHT)
                .custom_y_axes(vec![y_axis(label)])
                .y_grid_spacer(|input| y_marks(input, HEIGHT))
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
        };
        let hidden = &mut self.hidden;
        let mut show =
            |ui: &mut egui::Ui, id: &str, label: &str, x_label: bool, curves: &[Curve<'_>]| {
                let items: Vec<LegendItem<'_>> = curves
                    .iter()
                    .map(|&(name, _, color, w)| LegendItem {
                        name,
                        color,
                        swatch: Swatch::Line(w, LineStyle::Solid),
                    })
                    .collect();
                legend_ui(ui, id, &items, hidden);
                let p = plot(id, label);
                let p = if x_label {
                    p.x_axis_label("time [s]")
                } else {
                    p
                };
                p.show(ui, |pu| {
                    for &(name, pts, color, w) in curves {
                        if !plotkit::hidden(hidden, id, name) {
                            pu.line(
                                Line::new(name, PlotPoints::from(pts.to_vec()))
                                    .color(color)
                                    .width(w),
                            );
                        }
                    }
                });
            };
        show(
            ui,
            "measured_du",
            "du/dt [mm/s]",
            false,
            &three(&v.du[1], cal.map(|c| c.du[1].as_slice()), &v.du[0]),
        );
        show(
            ui,
            "measured_u",
            "stroke u [mm]",
            false,
            &three(&v.u[1], cal.map(|c| c.u[1].as_slice()), &v.u[0]),
        );
        if !v.ydd[0].is_empty() {
            show(
                ui,
                "measured_ydd",
                "body accel. [m/s²]",
                false,
                &three(&v.ydd[1], cal.map(|c| c.ydd[1].as_slice()), &v.ydd[0]),
            );
        }
        let mut residual: Vec<Curve<'_>> =
            vec![("twin − measured (live)", &v.residual, RESIDUAL, 1.0)];
        if let Some(c) = cal {
            residual.push(("twin − measured (calibrated)", &c.residual, CALIBRATED, 1.0));
        }
        show(ui, "measured_res", "residual du/dt [mm/s]", true, &residual);
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
        // The verdict's measure: every raw channel and band against its noise floor.
        let above = !v.raw.at_floor();
        ui.label(
            RichText::new(format!(
                "raw error: {}",
                if above {
                    format!(
                        "above the noise floor, the twin misses something here: {}",
                        v.raw.summary()
                    )
                } else {
                    v.raw.summary()
                }
            ))
            .color(if above {
                crate::gui::style::CAUTION_TEXT
            } else {
                crate::gui::style::OK_TEXT
            }),
        );
        ui.weak(format!(
            "weighted error {:.2} (the fit's metric, 1.0 = sensor noise)",
            v.weighted_rms
        ));
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
