//! The app's panels: menu, toolbar, what the controls panel asks for, the side panel
//! (schematic, metrics) and the debug overlay.

use super::*;

impl SeatTwinApp {
    pub(super) fn menu_ui(&mut self, ui: &mut egui::Ui, ctx: &egui::Context) {
        ui.menu_button("File", |ui| {
            if ui.button("Open preset…").clicked() {
                self.guarded(Pending::OpenDialog, ctx);
            }
            if ui.button("Save preset").clicked() {
                self.save(ctx);
            }
            if ui.button("Save preset as…").clicked() {
                self.save_as(ctx);
            }
            ui.separator();
            if ui.button("Open session…").clicked() {
                self.guarded(Pending::OpenSessionDialog, ctx);
            }
            if ui.button("Save session…").clicked() {
                self.request_file(Purpose::SaveSession, "session.toml", ctx);
            }
            ui.separator();
            if ui.button("Load platform record (CSV)…").clicked() {
                self.request_file(Purpose::LoadRecord, "", ctx);
            }
            if ui.button("Export traces (CSV)…").clicked() {
                self.request_file(Purpose::ExportCsv, "traces.csv", ctx);
            }
            if ui.button("Export plots (PNG)…").clicked() {
                self.request_file(Purpose::ExportPng, "plots.png", ctx);
            }
            ui.separator();
            use crate::export::fmu::ControllerPlacement;
            if ui
                .button("Export FMU…")
                .on_hover_text("FMI 2.0 co-simulation FMU of the twin with this controller inside")
                .clicked()
            {
                let purpose = Purpose::ExportFmu(ControllerPlacement::Internal);
                self.request_file(purpose, "seat_twin.fmu", ctx);
            }
            if ui
                .button("Export FMU, command as input…")
                .on_hover_text(
                    "the FMU without its controller: the valve command v_in_ext is an input",
                )
                .clicked()
            {
                let purpose = Purpose::ExportFmu(ControllerPlacement::External);
                self.request_file(purpose, "seat_twin.fmu", ctx);
            }
            if ui
                .button("Export controller code…")
                .on_hover_text("this controller as C99 at 1 kHz (double and float), in a folder")
                .clicked()
            {
                self.request_file(Purpose::ExportController, "seat_controller", ctx);
            }
            ui.separator();
            if ui.button("Quit").clicked() {
                ctx.send_viewport_cmd(egui::ViewportCommand::Close);
            }
        });
        ui.menu_button("Data", |ui| {
            if ui.button("Measured data & calibration…").clicked() {
                self.measured.open = true;
            }
            if ui.button("Load measured records (CSV)…").clicked() {
                self.measured.open = true;
                self.request_file(Purpose::LoadMeasured, "", ctx);
            }
            if ui.button("Load the demo campaign").clicked() {
                self.measured.open = true;
                self.measured.load_files(MeasuredData::demo_campaign());
            }
        });
        ui.menu_button("Presets", |ui| {
            if self.shipped.is_empty() {
                // The web build (or a binary without its presets/ folder): the presets
                // compiled into the app.
                for (name, _) in crate::gui::share::SHIPPED {
                    if ui.button(name).clicked() {
                        match crate::gui::share::shipped_preset(name) {
                            Ok(p) => self.set_preset(p, None, false),
                            Err(e) => self.error(format!("preset not loaded: {e}")),
                        }
                    }
                }
            }
            for (name, path) in self.shipped.clone() {
                if ui
                    .button(&name)
                    .on_hover_text(path.display().to_string())
                    .clicked()
                {
                    self.guarded(Pending::LoadFile(path), ctx);
                }
            }
        });
        ui.menu_button("View", |ui| {
            let before = self.settings.theme;
            ui.radio_value(&mut self.settings.theme, Theme::System, "System theme");
            ui.radio_value(&mut self.settings.theme, Theme::Light, "Light");
            ui.radio_value(&mut self.settings.theme, Theme::Dark, "Dark");
            if self.settings.theme != before {
                ctx.set_theme(self.settings.theme.preference());
            }
            ui.separator();
            ui.label("UI scale (Ctrl + / Ctrl −)");
            ui.horizontal(|ui| {
                for z in UI_SCALES {
                    let on = (self.settings.ui_scale - z).abs() < 0.01;
                    if ui
                        .selectable_label(on, format!("{:.0} %", z * 100.0))
                        .clicked()
                    {
                        self.set_ui_scale(ctx, z);
                    }
                }
            });
            ui.separator();
            ui.checkbox(&mut self.settings.show_schematic, "Schematic");
            ui.checkbox(&mut self.settings.dwell_auto, "Auto-recompute dwell points");
            ui.checkbox(&mut self.settings.show_debug, "Frame-time overlay");
            ui.separator();
            self.teaching_menu_ui(ui);
        });
    }

    pub(super) fn toolbar_ui(&mut self, ui: &mut egui::Ui) {
        ui.horizontal(|ui| {
            let label = if self.engine.want_running {
                "Pause"
            } else {
                "Run"
            };
            if ui
                .button(label)
                .on_hover_text("Run / pause (space bar)")
                .clicked()
            {
                self.toggle_running();
            }
            if ui
                .button("Reset")
                .on_hover_text("Back to rest at t = 0")
                .clicked()
            {
                self.reset();
            }
            ui.separator();
            ui.label("speed");
            let before = self.settings.speed;
            for s in [Speed::Slow, Speed::RealTime, Speed::Fast, Speed::Max] {
                ui.selectable_value(&mut self.settings.speed, s, s.label());
            }
            if self.settings.speed != before {
                self.send(Command::SetSpeed(self.settings.speed));
            }
            ui.separator();
            let v = &self.engine.view;
            let state = if self.engine.error.is_some() {
                RichText::new("stopped (error)").color(crate::gui::style::ERROR_TEXT)
            } else if v.running {
                RichText::new("running").color(crate::gui::style::OK_TEXT)
            } else {
                RichText::new("paused")
            };
            ui.label(state);
            ui.monospace(self.clock_text())
                .on_hover_text("Simulated time (the scopes' time axis) and how fast it runs");
            ui.separator();
            let modified = self.is_modified();
            let name = RichText::new(format!(
                "preset: {}{}",
                self.preset.name,
                if modified { " * modified" } else { "" }
            ));
            ui.label(if modified { name.italics() } else { name })
                .on_hover_text(&self.preset.description);
            if let Some(n) = &self.notice {
                ui.separator();
                let color = if n.error {
                    crate::gui::style::ERROR_TEXT
                } else {
                    ui.visuals().weak_text_color()
                };
                ui.add(egui::Label::new(RichText::new(&n.text).color(color)).truncate());
            }
        });
    }

    /// Carries out what the controls panel asked for.
    pub(super) fn apply_controls_action(&mut self, action: ControlsAction, ctx: &egui::Context) {
        match action {
            ControlsAction::ParamsEdited => self.apply_params(),
            ControlsAction::Revert => {
                self.params = self.preset.baseline;
                self.controls.field_errors_mut().clear();
                self.apply_params();
            }
            ControlsAction::ApplyTuned(c) => self.apply_tuned(c),
            ControlsAction::SendReference => self.send_reference(),
            ControlsAction::Excitation(ExcitationAction::None) => {}
            ControlsAction::Excitation(ExcitationAction::Apply) => {
                if let Some(p) = self.settings.excitation.problem() {
                    self.error(format!("excitation not applied: {p}"));
                } else {
                    self.apply_excitation();
                }
            }
            ControlsAction::Excitation(ExcitationAction::LoadRecord) => {
                self.request_file(Purpose::LoadRecord, "", ctx)
            }
            ControlsAction::Excitation(ExcitationAction::LoadRecordPath(p)) => {
                self.load_record_file(&p)
            }
        }
    }

    pub(super) fn side_ui(&mut self, ui: &mut egui::Ui) {
        if self.settings.show_schematic {
            ui.heading("Rig");
            let h = (ui.available_width() * 1.15).clamp(260.0, 460.0);
            schematic::schematic_ui(
                ui,
                self.traces.last_row().map(|r| &r.twin),
                &self.params,
                h,
                self.traces.pressure_range_pa(),
            );
            ui.separator();
        }
        ui.heading("Metrics");
        let (rows, platform) = self.traces.metrics.rows();
        ui.weak(format!(
            "over {:.1} s since the last change (ISO 2631-1 Wk)",
            self.traces.metrics.counted_s()
        ));
        crate::gui::plotkit::table_ui(ui, "metrics", &["", "RMS", "a_w", "VDV", "SEAT"], |ui| {
            ui.label("platform");
            ui.monospace(format!("{:.3}", platform.rms));
            ui.monospace(format!("{:.3}", platform.aw));
            ui.monospace(format!("{:.3}", platform.vdv));
            ui.label("");
            ui.end_row();
            for (name, m, seat) in rows {
                ui.label(name);
                ui.monospace(format!("{:.3}", m.rms));
                ui.monospace(format!("{:.3}", m.aw));
                ui.monospace(format!("{:.3}", m.vdv));
                if seat.is_finite() {
                    ui.monospace(format!("{seat:.0} %"));
                } else {
                    ui.monospace("–");
                }
                ui.end_row();
            }
        });
        ui.weak("RMS, a_w [m/s²]; VDV [m/s^1.75]; SEAT = a_w body / a_w platform");
        ui.label(format!(
            "end-stop contacts (twin): {}",
            self.traces.contact_count
        ));
        if self.ab.is_on() {
            ui.separator();
            crate::gui::ab::metrics_ui(ui, self.traces.metrics.ab(), self.engine.view.contacts);
        }
        if let Some(r) = self.traces.last_row() {
            ui.weak(format!(
                "now: u {:+.1} mm, p1 {:.1} bar, p2 {:.1} bar",
                r.twin.u * MM_PER_M,
                r.twin.p1 * BAR_PER_PA,
                r.twin.p2 * BAR_PER_PA
            ));
        }
    }

    pub(super) fn debug_overlay(&self, ctx: &egui::Context) {
        egui::Area::new(egui::Id::unique("frame_time"))
            .anchor(egui::Align2::RIGHT_BOTTOM, [-8.0, -8.0])
            .order(egui::Order::Foreground)
            .interactable(false)
            .show(ctx, |ui| {
                egui::Frame::popup(ui.style()).show(ui, |ui| {
                    let s = &self.window.stats;
                    ui.monospace(format!(
                        "UI build {:.2} ms (max {:.2})\n  scopes {:.2} ms, freq. plots {:.2} ms\nframe CPU {}\n{:.0} frames/s\nfreq. curves {:.2} ms",
                        s.mean_ui_ms(),
                        s.max_ui_ms(),
                        self.centre.scopes_ms,
                        self.centre.freq_ms,
                        s.cpu_ms
                            .map(|c| format!("{c:.2} ms"))
                            .unwrap_or_else(|| "n/a".into()),
                        s.fps(),
                        self.centre.curves().compute_ms,
                    ));
                });
            });
    }

    pub(super) fn window_title(&self) -> String {
        format!(
            "seat-twin — {}{}",
            self.preset.name,
            if self.is_modified() {
                " (modified)"
            } else {
                ""
            }
        )
    }
}
