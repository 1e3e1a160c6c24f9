//! The app's files: presets (open, apply, save, save as, the discard guard), platform
//! records, the dialog results and the typed-path prompt.

use super::*;

impl SeatTwinApp {
    /// Loads a preset file; a bad file leaves everything as it was and says why.
    pub fn open_preset_file(&mut self, path: &Path) {
        match Preset::load(path) {
            Ok(p) => {
                let shipped = self.shipped.iter().any(|(_, f)| f == path);
                self.set_preset(p, Some(path.to_path_buf()), !shipped);
                self.settings.last_preset = Some(path.to_path_buf());
                self.info(format!("preset loaded from {}", path.display()));
            }
            Err(e) => self.error(format!("preset not loaded: {e}")),
        }
    }

    pub(super) fn set_preset(&mut self, p: Preset, path: Option<PathBuf>, user_file: bool) {
        let name = if p.meta.name.is_empty() {
            path.as_deref()
                .and_then(|f| f.file_stem())
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_else(|| "unnamed".into())
        } else {
            p.meta.name.clone()
        };
        self.params = p.params;
        // Messages about the parameters that were there are about them, not the new preset.
        self.controls.clear();
        self.preset = PresetInfo {
            name,
            description: p.meta.description,
            path,
            user_file,
            baseline: p.params,
        };
        self.apply_params();
    }

    /// The parameters on screen as a preset, under the current preset's name.
    fn preset_now(&self) -> Preset {
        Preset {
            meta: PresetMeta {
                name: self.preset.name.clone(),
                description: self.preset.description.clone(),
                ..Default::default()
            },
            params: self.params,
            per_record: Default::default(),
        }
    }

    /// Saves the parameters as a preset file.
    pub fn save_preset_file(&mut self, path: &Path) {
        let name = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| self.preset.name.clone());
        let p = Preset {
            meta: PresetMeta {
                name: name.clone(),
                description: self.preset.description.clone(),
                ..Default::default()
            },
            params: self.params,
            per_record: Default::default(),
        };
        match p.save(path) {
            Ok(()) => {
                self.preset = PresetInfo {
                    name,
                    description: p.meta.description,
                    path: Some(path.to_path_buf()),
                    user_file: true,
                    baseline: self.params,
                };
                self.settings.last_preset = Some(path.to_path_buf());
                self.info(format!("preset saved to {}", path.display()));
            }
            Err(e) => self.error(format!("preset not saved: {e}")),
        }
    }

    /// Loads a CSV platform record and switches the excitation to it.
    pub fn load_record_file(&mut self, path: &Path) {
        match LoadedRecord::read(path) {
            Ok(record) => {
                self.settings.excitation.record = Some(record);
                self.settings.excitation.kind = ExcitationKind::Record;
                self.apply_excitation();
                self.info(format!("record loaded from {}", path.display()));
            }
            Err(e) => self.error(format!("record not loaded: {e:#}")),
        }
    }

    /// Switches the excitation editor to `kind` and applies it (restarts from rest).
    pub fn set_excitation_kind(&mut self, kind: ExcitationKind) {
        self.settings.excitation.kind = kind;
        if let Some(p) = self.settings.excitation.problem() {
            self.error(format!("excitation not applied: {p}"));
        } else {
            self.apply_excitation();
        }
    }

    pub(super) fn apply_excitation(&mut self) {
        if let Some(e) = self.settings.excitation.excitation() {
            self.send(Command::SetExcitation(Box::new(e)));
            self.traces.clear();
            self.engine.forget_run();
        }
    }

    /// Runs `action` now, or asks first if there are unsaved changes.
    pub(super) fn guarded(&mut self, action: Pending, ctx: &egui::Context) {
        if let Some(action) = self.files.guard(action, self.is_modified()) {
            self.run_pending(action, ctx);
        }
    }

    pub(super) fn run_pending(&mut self, action: Pending, ctx: &egui::Context) {
        match action {
            Pending::OpenDialog => self.request_file(Purpose::OpenPreset, "", ctx),
            Pending::LoadFile(p) => self.open_preset_file(&p),
            Pending::OpenSessionDialog => self.request_file(Purpose::OpenSession, "", ctx),
            Pending::Quit => {
                self.files.confirm_quit();
                ctx.send_viewport_cmd(egui::ViewportCommand::Close);
            }
        }
    }

    pub(super) fn save(&mut self, ctx: &egui::Context) {
        match (&self.preset.path, self.preset.user_file) {
            (Some(p), true) => {
                let p = p.clone();
                self.save_preset_file(&p);
            }
            _ => self.save_as(ctx),
        }
    }

    pub(super) fn save_as(&mut self, ctx: &egui::Context) {
        let name = format!("{}.toml", self.preset.name);
        self.request_file(Purpose::SavePreset, &name, ctx);
    }

    /// The folder dialogs open in and typed paths default to: the last one used, else the
    /// documents folder (see [`files::documents_dir`]).
    pub fn file_dir(&self) -> PathBuf {
        self.settings
            .last_dir
            .clone()
            .filter(|d| d.is_dir())
            .unwrap_or_else(files::documents_dir)
    }

    /// Opens the file dialog for `purpose` in [`Self::file_dir`], suggesting `name`.
    pub(super) fn request_file(&mut self, purpose: Purpose, name: &str, ctx: &egui::Context) {
        #[cfg(target_arch = "wasm32")]
        if purpose.downloads_on_the_web() {
            // The browser saves it: downloads.
            self.download(purpose, name);
            return;
        }
        let dir = self.file_dir();
        self.files.dialogs.request(purpose, name, &dir, ctx);
    }

    /// The full path a typed-path prompt suggests for `purpose` (empty for opening).
    pub fn suggested_path(&self, purpose: Purpose) -> String {
        let name = match purpose {
            Purpose::ExportCsv => "traces.csv",
            Purpose::ExportPng => "plots.png",
            Purpose::SavePreset => "preset.toml",
            Purpose::SaveSession => "session.toml",
            Purpose::ExportReport => "calibration",
            Purpose::ExportFmu(_) => "seat_twin.fmu",
            Purpose::ExportController => "seat_controller",
            Purpose::OpenPreset
            | Purpose::OpenSession
            | Purpose::LoadRecord
            | Purpose::LoadMeasured => "",
        };
        if name.is_empty() {
            String::new()
        } else {
            self.file_dir().join(name).display().to_string()
        }
    }

    /// The files that saving for `purpose` under the suggested `name` makes, in memory: (file
    /// name, bytes, MIME type). The web app hands them to the browser as downloads (the
    /// desktop writes the same contents through its dialogs and atomic writers): the traces'
    /// CSV, the plots' PNG and SVG (`<stem>-<plot>.png`, `.svg`; SVG only in the web build),
    /// the preset's TOML.
    pub fn download_files(
        &self,
        purpose: Purpose,
        name: &str,
    ) -> Result<Vec<files::Download>, String> {
        let stem = Path::new(name)
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .filter(|s| !s.is_empty());
        match purpose {
            Purpose::ExportCsv => {
                let table = self.traces_table();
                if table.rows.is_empty() {
                    return Err("nothing to export yet: run the simulation first".into());
                }
                let mut bytes = Vec::new();
                crate::dataset::write_csv(
                    &mut bytes,
                    &table.header,
                    &table.comments,
                    table.rows.into_iter(),
                )
                .map_err(|e| format!("export failed: {e}"))?;
                Ok(vec![(name.to_string(), bytes, "text/csv")])
            }
            Purpose::ExportPng => {
                let stem = stem.unwrap_or_else(|| "plots".into());
                let mut out = Vec::new();
                let failed = |e: crate::plot::PlotError| format!("export failed: {e}");
                for (suffix, fig) in self.plot_figures() {
                    // The web build draws no PNG (no font rasteriser there): SVG only.
                    if !cfg!(target_arch = "wasm32") {
                        let (png, _) = crate::plot::figure_bytes(&fig).map_err(failed)?;
                        out.push((format!("{stem}-{suffix}.png"), png, "image/png"));
                    }
                    let svg = crate::plot::figure_svg(&fig).map_err(failed)?;
                    out.push((
                        format!("{stem}-{suffix}.svg"),
                        svg.into_bytes(),
                        "image/svg+xml",
                    ));
                }
                Ok(out)
            }
            Purpose::SavePreset => {
                let mut p = self.preset_now();
                if let Some(stem) = stem {
                    p.meta.name = stem;
                }
                Ok(vec![(
                    format!("{}.toml", p.meta.name),
                    p.to_toml().into_bytes(),
                    "application/toml",
                )])
            }
            other => Err(format!("{}: {}", other.title(), files::NOT_ON_THE_WEB)),
        }
    }

    /// Saves for `purpose` through the browser (web): the files of [`Self::download_files`]
    /// as downloads.
    #[cfg(target_arch = "wasm32")]
    fn download(&mut self, purpose: Purpose, name: &str) {
        let name = if name.is_empty() {
            match purpose {
                Purpose::ExportCsv => "traces.csv".to_string(),
                Purpose::ExportPng => "plots.png".to_string(),
                _ => format!("{}.toml", self.preset.name),
            }
        } else {
            name.to_string()
        };
        let made = match self.download_files(purpose, &name) {
            Ok(f) => f,
            Err(e) => {
                self.error(e);
                return;
            }
        };
        let mut names = Vec::new();
        for (file, bytes, mime) in &made {
            if let Err(e) = files::download(file, bytes, mime) {
                self.error(format!("export failed: {e}"));
                return;
            }
            names.push(file.as_str());
        }
        let message = format!("downloaded: {}", names.join(", "));
        if purpose == Purpose::SavePreset {
            // Saved: what is on screen is now the preset's content.
            if let Some((file, _, _)) = made.first() {
                self.preset.name = file.trim_end_matches(".toml").to_string();
            }
            self.preset.baseline = self.params;
        }
        self.info(message);
    }

    /// A file the browser's picker read (web): a preset or a platform record, parsed from
    /// its bytes as the desktop parses a file.
    fn use_picked(&mut self, purpose: Purpose, picked: files::PickedFile) {
        let path = PathBuf::from(&picked.name);
        match purpose {
            Purpose::OpenPreset => match Preset::from_bytes(&picked.bytes, &path) {
                Ok(p) => {
                    self.set_preset(p, None, false);
                    self.info(format!("preset loaded from {}", picked.name));
                }
                Err(e) => self.error(format!("preset not loaded: {e}")),
            },
            Purpose::LoadRecord => {
                let record = crate::dataset::parse_record_bytes(
                    &picked.bytes,
                    &path,
                    crate::dataset::RecordKind::Excitation,
                )
                .map_err(anyhow::Error::from)
                .and_then(|rec| {
                    crate::scenario::SampledMotion::from_record(&rec)
                        .ok_or_else(|| anyhow::anyhow!("{}: no `x` or `xdd` column", picked.name))
                });
                match record {
                    Ok(motion) => {
                        self.settings.excitation.record = Some(LoadedRecord {
                            name: picked.name.clone(),
                            path,
                            motion,
                        });
                        self.settings.excitation.kind = ExcitationKind::Record;
                        self.apply_excitation();
                        self.info(format!("record loaded from {}", picked.name));
                    }
                    Err(e) => self.error(format!("record not loaded: {e:#}")),
                }
            }
            _ => self.error(files::NOT_ON_THE_WEB),
        }
    }

    /// Carries out what the dialogs, the writes and the typed-path prompt finished.
    pub(super) fn poll_files(&mut self, ctx: &egui::Context) {
        for action in self.files.poll() {
            self.apply_file_action(action, ctx);
        }
    }

    /// Carries out one of the file view's actions.
    pub(super) fn apply_file_action(&mut self, action: FileAction, ctx: &egui::Context) {
        match action {
            FileAction::Run(pending) => self.run_pending(pending, ctx),
            FileAction::Use(purpose, paths) => self.use_paths(purpose, paths, ctx),
            // Several files, folders and patterns (see files::expand_paths).
            FileAction::LoadMeasuredTyped(text) => self.measured.load_typed(&text),
            FileAction::Picked(purpose, picked) => self.use_picked(purpose, picked),
            FileAction::NoFileChosen(purpose) => {
                // Cancelled, or no dialog on this desktop: offer a typed path instead.
                self.files
                    .prompt_path(purpose, self.suggested_path(purpose));
                self.info("no file chosen (dialog cancelled, or no file dialog on this desktop): type a path below");
            }
            FileAction::Info(m) => self.info(m),
            FileAction::Error(m) => self.error(m),
        }
    }

    /// Opens the typed-path prompt for `purpose` (the fallback when no file dialog shows).
    pub fn prompt_path(&mut self, purpose: Purpose, suggested: &str) {
        self.files.prompt_path(purpose, suggested.to_string());
    }

    /// Uses files chosen in a dialog or typed for `purpose` (the first, or all of them for
    /// measured records); the folder is remembered for the next dialog and typed path.
    pub fn use_paths(&mut self, purpose: Purpose, paths: Vec<PathBuf>, ctx: &egui::Context) {
        {
            // Relative paths are read against the working directory; shown and remembered
            // in full.
            let paths: Vec<PathBuf> = paths.iter().map(|p| files::absolute(p)).collect();
            if let Some(dir) = paths
                .first()
                .and_then(|p| p.parent())
                .filter(|d| d.is_dir())
            {
                self.settings.last_dir = Some(dir.to_path_buf());
            }
            if purpose == Purpose::LoadMeasured {
                self.measured.load_files(paths);
                return;
            }
            let mut paths = paths;
            let path = paths.swap_remove(0);
            match purpose {
                Purpose::LoadMeasured => {}
                Purpose::OpenPreset => self.open_preset_file(&path),
                Purpose::SavePreset => self.save_preset_file(&path),
                Purpose::LoadRecord => self.load_record_file(&path),
                Purpose::OpenSession => self.open_session_file(&path, ctx),
                Purpose::SaveSession => self.save_session_file(&path),
                Purpose::ExportCsv => {
                    let table = self.traces_table();
                    if table.rows.is_empty() {
                        self.error("nothing to export yet: run the simulation first");
                    } else {
                        self.files.writer.write_csv(ctx, path, table);
                    }
                }
                Purpose::ExportReport => match self.measured.report() {
                    Some(r) => self.files.writer.write_report(ctx, path, r.clone()),
                    None => self.error("no calibration report yet: calibrate first"),
                },
                Purpose::ExportFmu(placement) => {
                    let preset = self.preset_now();
                    self.files.writer.write_fmu(ctx, path, preset, placement);
                }
                Purpose::ExportController => {
                    let preset = self.preset_now();
                    self.files.writer.write_controller(ctx, path, preset);
                }
                Purpose::ExportPng => {
                    let stem = path.with_extension("");
                    let figs = self.plot_figures();
                    self.files.writer.write_figures(ctx, stem, figs);
                }
            }
        }
    }

    /// Saves the session (parameters, excitation, A/B, view, the last tune result).
    pub fn save_session_file(&mut self, path: &Path) {
        let s = Session {
            format_version: session::FORMAT_VERSION,
            preset: Session::preset_of(&self.preset.name, &self.preset.description, &self.params),
            excitation: self.settings.excitation.clone(),
            record_path: self
                .settings
                .excitation
                .record
                .as_ref()
                .map(|r| r.path.clone()),
            ab: SessionAb {
                on: self.ab.is_on(),
                reference: self.ab.reference(),
            },
            view: SessionView {
                hidden_curves: self.centre.hidden_curves().clone(),
                phase_unwrapped: self.settings.phase_unwrapped,
                scope_window_s: self.settings.scope_window_s,
                show_schematic: self.settings.show_schematic,
                ui_scale: self.settings.ui_scale,
            },
            tune: self
                .tune
                .result()
                .map(|r| SessionTune::new(r, self.tune.selected())),
        };
        match s.save(path) {
            Ok(()) => self.info(format!("session saved to {}", path.display())),
            Err(e) => self.error(format!("session not saved: {e}")),
        }
    }

    /// Opens a session file: everything in it is checked first (a bad file changes nothing
    /// and says why), then restored, and the engine restarts from rest with it.
    pub fn open_session_file(&mut self, path: &Path, ctx: &egui::Context) {
        let refuse = |app: &mut Self, e: &dyn std::fmt::Display| {
            app.error(format!("session not opened: {e}"));
        };
        let (s, preset) = match Session::load(path) {
            Ok(x) => x,
            Err(e) => return refuse(self, &e),
        };
        let mut excitation = s.excitation.clone();
        excitation.typed_path.clear();
        excitation.record = None;
        if let Some(rp) = &s.record_path {
            match LoadedRecord::read(rp) {
                Ok(record) => excitation.record = Some(record),
                Err(e) => {
                    let e = format!("{}: field `record_path`: {e:#}", path.display());
                    return refuse(self, &e);
                }
            }
        }
        if let Some(p) = excitation.problem() {
            let e = format!("{}: field `excitation`: {p}", path.display());
            return refuse(self, &e);
        }
        if let Err(e) = ab::reference_params(&preset.params, s.ab.reference).validate() {
            let e = format!("{}: field `ab.reference`: {e}", path.display());
            return refuse(self, &e);
        }
        // Checked: restore it all.
        self.set_preset(preset, None, false);
        self.settings.excitation = excitation;
        self.ab.set_reference(s.ab.reference);
        self.ab.set_on(s.ab.on);
        let v = s.view;
        self.centre.set_hidden_curves(v.hidden_curves);
        self.settings.phase_unwrapped = v.phase_unwrapped;
        self.settings.scope_window_s = v.scope_window_s;
        self.settings.show_schematic = v.show_schematic;
        self.set_ui_scale(ctx, v.ui_scale);
        match &s.tune {
            Some(t) => self.tune.restore(Some(t.restored()), t.selected),
            None => self.tune.restore(None, None),
        }
        self.send(Command::SetReference(self.ab.command()));
        self.apply_excitation();
        self.reset();
        self.info(format!("session opened from {}", path.display()));
    }
}
