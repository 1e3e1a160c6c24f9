//! File dialogs and file work off the UI thread, each a background [`Job`]: rfd's async
//! dialogs run to completion on the job's thread (a cancelled or unavailable dialog gives no
//! file), and exports are written by a job. Results are polled each frame.

use super::job::{Job, Waker};
use crate::dataset::{self, RecordKind};
use crate::plot::{Figure, save_figure};
use crate::scenario::SampledMotion;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// What a file dialog is for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Purpose {
    /// Open a preset (TOML).
    OpenPreset,
    /// Save the preset (TOML).
    SavePreset,
    /// Load a platform record (CSV).
    LoadRecord,
    /// Open a session (TOML).
    OpenSession,
    /// Save the session (TOML).
    SaveSession,
    /// Load measured records (CSV, several at once).
    LoadMeasured,
    /// Export the traces (CSV).
    ExportCsv,
    /// Export the plots (PNG + SVG).
    ExportPng,
    /// Export the calibration report (a folder: report.md, report.json, calibrated.toml,
    /// plots), as `seat-twin calibrate --out` writes it.
    ExportReport,
    /// Export the twin as an FMI 2.0 co-simulation FMU, with the controller inside
    /// (`internal`) or its command as an input (`external`), as `seat-twin export fmu` does.
    ExportFmu(crate::export::fmu::ControllerPlacement),
    /// Export the controller as C99 (a folder: seat_controller.h/.c/.json), as
    /// `seat-twin export controller --rate 1000 --lang c` does.
    ExportController,
}

/// The rate of the controller code the app exports \[Hz\] (the CLI's `--rate` takes others).
pub const CONTROLLER_EXPORT_RATE_HZ: f64 = 1000.0;

impl Purpose {
    /// What the dialog is for, as its title.
    pub fn title(self) -> &'static str {
        match self {
            Purpose::OpenPreset => "Open preset",
            Purpose::SavePreset => "Save preset",
            Purpose::LoadRecord => "Load a platform record (CSV)",
            Purpose::OpenSession => "Open session",
            Purpose::SaveSession => "Save session",
            Purpose::LoadMeasured => "Load measured records (CSV)",
            Purpose::ExportCsv => "Export traces (CSV)",
            Purpose::ExportPng => "Export plots (PNG)",
            Purpose::ExportReport => "Export the calibration report (folder)",
            Purpose::ExportFmu(crate::export::fmu::ControllerPlacement::Internal) => {
                "Export FMU (FMI 2.0 co-simulation, controller inside)"
            }
            Purpose::ExportFmu(crate::export::fmu::ControllerPlacement::External) => {
                "Export FMU (FMI 2.0 co-simulation, command as input)"
            }
            Purpose::ExportController => "Export controller code (C99, folder)",
        }
    }

    // The web build opens no dialog.
    #[cfg_attr(target_arch = "wasm32", allow(dead_code))]
    fn saves(self) -> bool {
        matches!(
            self,
            Purpose::SavePreset
                | Purpose::SaveSession
                | Purpose::ExportCsv
                | Purpose::ExportPng
                | Purpose::ExportReport
                | Purpose::ExportFmu(_)
                | Purpose::ExportController
        )
    }

    /// The answer is a folder (the calibration report, the controller code), not a file.
    pub fn picks_folder(self) -> bool {
        matches!(self, Purpose::ExportReport | Purpose::ExportController)
    }

    fn filter(self) -> (&'static str, &'static [&'static str]) {
        match self {
            Purpose::OpenPreset | Purpose::SavePreset => ("preset", &["toml"]),
            Purpose::OpenSession | Purpose::SaveSession => ("session", &["toml"]),
            Purpose::LoadRecord | Purpose::LoadMeasured | Purpose::ExportCsv => ("CSV", &["csv"]),
            Purpose::ExportPng => ("PNG", &["png"]),
            Purpose::ExportReport | Purpose::ExportController => ("folder", &[]),
            Purpose::ExportFmu(_) => ("FMU", &["fmu"]),
        }
    }
}

/// A repaint waker for a job started from the UI.
fn waker_of(ctx: &egui::Context) -> Waker {
    let ctx = ctx.clone();
    Arc::new(move || ctx.request_repaint())
}

/// The file dialog in flight (one at a time), as a background [`Job`].
#[derive(Default)]
pub struct Dialogs {
    open: Option<(Purpose, Job<Vec<PathBuf>>)>,
    /// The browser's file picker in flight (web): what the file is for, and its answer
    /// (`None`: cancelled).
    #[cfg(target_arch = "wasm32")]
    web: Option<(Purpose, std::sync::mpsc::Receiver<Option<PickedFile>>)>,
}

/// What the web build says where a desktop file dialog would open and the browser cannot
/// serve (measured campaigns, sessions, calibration reports, FMU and controller code).
pub const NOT_ON_THE_WEB: &str = "not in the web build: the browser opens presets and \
     platform records and downloads presets, the traces' CSV and the plots' SVG \
     (File menu); the other files need the desktop app";

/// A file saved through the browser (web): its name, bytes and MIME type.
pub type Download = (String, Vec<u8>, &'static str);

/// A file the browser's picker read (web): its name and bytes.
#[derive(Debug, Clone)]
pub struct PickedFile {
    /// The file's name (no folder: a browser does not tell it).
    pub name: String,
    /// Its contents.
    pub bytes: Vec<u8>,
}

impl Purpose {
    /// The browser's picker can serve it (web): opening a preset or a platform record.
    pub fn picked_on_the_web(self) -> bool {
        matches!(self, Purpose::OpenPreset | Purpose::LoadRecord)
    }

    /// The browser saves it as downloads (web): a preset, the traces' CSV, the plots.
    pub fn downloads_on_the_web(self) -> bool {
        matches!(
            self,
            Purpose::SavePreset | Purpose::ExportCsv | Purpose::ExportPng
        )
    }
}

impl Dialogs {
    /// The dialog currently open, if any.
    pub fn open(&self) -> Option<Purpose> {
        self.open.as_ref().map(|(p, _)| *p)
    }

    /// Opens a dialog on its own thread, in folder `dir`; ignored while another is open.
    pub fn request(
        &mut self,
        purpose: Purpose,
        suggested_name: &str,
        dir: &Path,
        ctx: &egui::Context,
    ) {
        if self.open.is_some() {
            return;
        }
        #[cfg(target_arch = "wasm32")]
        if purpose.picked_on_the_web() {
            self.web = Some((purpose, pick_in_the_browser(purpose, ctx)));
            return;
        }
        let name = suggested_name.to_owned();
        let dir = dir.to_path_buf();
        #[cfg(target_arch = "wasm32")]
        let job = Job::spawn("seat-twin-dialog", waker_of(ctx), move |_| {
            let _ = (name, dir);
            Ok(Vec::new())
        });
        #[cfg(not(target_arch = "wasm32"))]
        let job = Job::spawn("seat-twin-dialog", waker_of(ctx), move |_| {
            let (fname, ext) = purpose.filter();
            let mut dialog = rfd::AsyncFileDialog::new()
                .set_title(purpose.title())
                .set_directory(dir);
            if !ext.is_empty() {
                dialog = dialog.add_filter(fname, ext);
            }
            let path = |h: rfd::FileHandle| h.path().to_path_buf();
            let picked: Vec<PathBuf> = if purpose.picks_folder() {
                pollster::block_on(dialog.pick_folder())
                    .map(|d| path(d).join(&name))
                    .into_iter()
                    .collect()
            } else if purpose.saves() {
                pollster::block_on(dialog.set_file_name(name).save_file())
                    .map(path)
                    .into_iter()
                    .collect()
            } else if purpose == Purpose::LoadMeasured {
                pollster::block_on(dialog.pick_files())
                    .unwrap_or_default()
                    .into_iter()
                    .map(path)
                    .collect()
            } else {
                pollster::block_on(dialog.pick_file())
                    .map(path)
                    .into_iter()
                    .collect()
            };
            Ok(picked)
        });
        self.open = Some((purpose, job));
    }

    /// A file the browser's picker read (web): its purpose and the file, `None` inside
    /// when cancelled. Always `None` on the desktop.
    pub fn poll_picked(&mut self) -> Option<(Purpose, Option<PickedFile>)> {
        #[cfg(target_arch = "wasm32")]
        {
            let (purpose, rx) = self.web.as_ref()?;
            let purpose = *purpose;
            let picked = match rx.try_recv() {
                Ok(p) => p,
                Err(std::sync::mpsc::TryRecvError::Empty) => return None,
                Err(std::sync::mpsc::TryRecvError::Disconnected) => None,
            };
            self.web = None;
            Some((purpose, picked))
        }
        #[cfg(not(target_arch = "wasm32"))]
        None
    }

    /// A finished dialog: its purpose and the chosen files (empty: cancelled, no dialog
    /// available on this desktop, or the dialog's thread failed).
    pub fn poll(&mut self) -> Option<(Purpose, Vec<PathBuf>)> {
        let (purpose, job) = self.open.as_ref()?;
        let picked = job.poll()?.unwrap_or_default();
        let purpose = *purpose;
        self.open = None;
        Some((purpose, picked))
    }
}

/// Opens the browser's file picker for `purpose` and reads the chosen file; the answer
/// arrives on the receiver (and asks for a frame).
#[cfg(target_arch = "wasm32")]
fn pick_in_the_browser(
    purpose: Purpose,
    ctx: &egui::Context,
) -> std::sync::mpsc::Receiver<Option<PickedFile>> {
    let (tx, rx) = std::sync::mpsc::channel();
    let ctx = ctx.clone();
    wasm_bindgen_futures::spawn_local(async move {
        let (fname, ext) = purpose.filter();
        let mut dialog = rfd::AsyncFileDialog::new().set_title(purpose.title());
        if !ext.is_empty() {
            dialog = dialog.add_filter(fname, ext);
        }
        let picked = match dialog.pick_file().await {
            Some(h) => Some(PickedFile {
                name: h.file_name(),
                bytes: h.read().await,
            }),
            None => None,
        };
        let _ = tx.send(picked);
        ctx.request_repaint();
    });
    rx
}

/// Hands `bytes` to the browser as a download named `name` (web): the export's "save".
#[cfg(target_arch = "wasm32")]
pub fn download(name: &str, bytes: &[u8], mime: &str) -> Result<(), String> {
    use wasm_bindgen::JsCast;
    let fail = |e: wasm_bindgen::JsValue| format!("the download of {name} failed: {e:?}");
    let parts = js_sys::Array::of1(&js_sys::Uint8Array::from(bytes));
    let options = web_sys::BlobPropertyBag::new();
    options.set_type(mime);
    let blob =
        web_sys::Blob::new_with_u8_array_sequence_and_options(&parts, &options).map_err(fail)?;
    let url = web_sys::Url::create_object_url_with_blob(&blob).map_err(fail)?;
    let document = web_sys::window()
        .and_then(|w| w.document())
        .ok_or("no document")?;
    let a: web_sys::HtmlAnchorElement = document
        .create_element("a")
        .map_err(fail)?
        .dyn_into()
        .map_err(|_| "no anchor element".to_string())?;
    a.set_href(&url);
    a.set_download(name);
    a.click();
    web_sys::Url::revoke_object_url(&url).map_err(fail)
}

/// The folder files are saved to and opened from when the user has not chosen one yet: the
/// desktop's documents folder (`XDG_DOCUMENTS_DIR`, else `~/Documents`), else the home
/// folder, else the working directory. Always absolute.
pub fn documents_dir() -> PathBuf {
    let home = std::env::var_os("HOME")
        .map(PathBuf::from)
        .filter(|h| h.is_dir());
    let candidates = [
        std::env::var_os("XDG_DOCUMENTS_DIR").map(PathBuf::from),
        home.as_ref().map(|h| h.join("Documents")),
        home,
    ];
    candidates
        .into_iter()
        .flatten()
        .find(|d| d.is_absolute() && d.is_dir())
        .or_else(|| std::env::current_dir().ok())
        .unwrap_or_else(|| PathBuf::from("/"))
}

/// `path` made absolute against the working directory (as the file system will read it), for
/// showing people where a file went.
pub fn absolute(path: &Path) -> PathBuf {
    std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf())
}

/// "or path: \[____\] Load": a typed path, for desktops without a file dialog. Returns the
/// text when Load is clicked or Enter pressed in a non-empty field.
pub fn typed_path_ui(
    ui: &mut egui::Ui,
    text: &mut String,
    hint: &str,
    width: f32,
) -> Option<String> {
    ui.label("or path:");
    let r = ui.add(
        egui::TextEdit::singleline(text)
            .desired_width(width)
            .hint_text(hint),
    );
    let enter = r.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter));
    let load = ui.button("Load").clicked() || enter;
    (load && !text.trim().is_empty()).then(|| text.trim().to_string())
}

/// The files a typed path names: several paths separated by `;` (or new lines), each a
/// file, a folder (its `*.csv` files) or a pattern with `*` / `?` in the file name
/// (`campaign/*.csv`). Sorted within a folder or pattern; duplicates dropped. A folder or a
/// pattern that matches no CSV file, or a path that does not exist, is an error naming it.
pub fn expand_paths(text: &str) -> Result<Vec<PathBuf>, String> {
    let mut out: Vec<PathBuf> = Vec::new();
    let parts = text
        .split([';', '\n'])
        .map(|p| p.trim().trim_matches('"').trim_matches('\''))
        .filter(|p| !p.is_empty());
    for part in parts {
        let path = PathBuf::from(part);
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        let found = if name.contains(['*', '?']) {
            let dir = match path.parent() {
                Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
                _ => PathBuf::from("."),
            };
            let v = list_dir(&dir, |f| wildcard_match(&name, f))?;
            if v.is_empty() {
                return Err(format!("{part}: no file matches"));
            }
            v
        } else if path.is_dir() {
            let v = list_dir(&path, |f| {
                Path::new(f)
                    .extension()
                    .is_some_and(|x| x.eq_ignore_ascii_case("csv"))
            })?;
            if v.is_empty() {
                return Err(format!("{part}: no .csv file in this folder"));
            }
            v
        } else if path.is_file() {
            vec![path]
        } else {
            return Err(format!("{part}: no such file or folder"));
        };
        for f in found {
            if !out.contains(&f) {
                out.push(f);
            }
        }
    }
    Ok(out)
}

/// The files in `dir` whose names pass `keep`, sorted.
fn list_dir(dir: &Path, keep: impl Fn(&str) -> bool) -> Result<Vec<PathBuf>, String> {
    let entries = std::fs::read_dir(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let mut v: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_file())
        .filter(|p| p.file_name().is_some_and(|n| keep(&n.to_string_lossy())))
        .collect();
    v.sort();
    Ok(v)
}

/// `*` (any run of characters) and `?` (one character) against a whole file name.
pub fn wildcard_match(pattern: &str, name: &str) -> bool {
    let p: Vec<char> = pattern.chars().collect();
    let n: Vec<char> = name.chars().collect();
    // The classic two-pointer match with backtracking to the last `*`.
    let (mut i, mut j) = (0, 0);
    let mut star: Option<(usize, usize)> = None;
    while j < n.len() {
        if i < p.len() && (p[i] == '?' || p[i] == n[j]) {
            i += 1;
            j += 1;
        } else if i < p.len() && p[i] == '*' {
            star = Some((i, j));
            i += 1;
        } else if let Some((si, sj)) = star {
            i = si + 1;
            j = sj + 1;
            star = Some((si, sj + 1));
        } else {
            return false;
        }
    }
    p[i..].iter().all(|&c| c == '*')
}

/// Reads a platform record (CSV with `t` and `x` and/or `xdd`, SI) for the live simulation.
pub fn read_platform_record(path: &Path) -> anyhow::Result<SampledMotion> {
    let rec = dataset::read_record(path, RecordKind::Excitation)?;
    SampledMotion::from_record(&rec)
        .ok_or_else(|| anyhow::anyhow!("{}: no `x` or `xdd` column", path.display()))
}

/// A CSV table ready to be written.
pub struct CsvTable {
    /// Column names.
    pub header: Vec<&'static str>,
    /// `# key: value` lines.
    pub comments: Vec<(String, String)>,
    /// Rows, all finite.
    pub rows: Vec<Vec<f64>>,
}

/// Background file writer: each write is a [`Job`] that reports one message (success or
/// error) when done.
#[derive(Default)]
pub struct Writer {
    jobs: Vec<Job<String>>,
}

impl Writer {
    fn spawn(
        &mut self,
        ctx: &egui::Context,
        job: impl FnOnce() -> Result<String, String> + Send + 'static,
    ) {
        self.jobs
            .push(Job::spawn("seat-twin-writer", waker_of(ctx), move |_| {
                job()
            }));
    }

    /// Writes in flight.
    pub fn busy(&self) -> usize {
        self.jobs.len()
    }

    /// Writes a CSV table atomically.
    pub fn write_csv(&mut self, ctx: &egui::Context, path: PathBuf, table: CsvTable) {
        self.spawn(ctx, move || {
            dataset::write_csv_atomic(
                &path,
                &table.header,
                &table.comments,
                table.rows.into_iter(),
            )
            .map(|()| format!("traces written to {}", path.display()))
            .map_err(|e| format!("{}: {e}", path.display()))
        });
    }

    /// Writes figures as `<stem>-<suffix>.png` and `.svg`.
    pub fn write_figures(
        &mut self,
        ctx: &egui::Context,
        stem: PathBuf,
        figures: Vec<(&'static str, Figure)>,
    ) {
        self.spawn(ctx, move || {
            let mut written = Vec::new();
            for (suffix, fig) in figures {
                let mut name = stem.clone().into_os_string();
                name.push(format!("-{suffix}"));
                let (png, _svg) = save_figure(&fig, Path::new(&name)).map_err(|e| e.to_string())?;
                written.push(png.display().to_string());
            }
            Ok(format!("plots written: {} (and .svg)", written.join(", ")))
        });
    }

    /// Writes a calibration report into folder `dir` as `seat-twin calibrate --out` does
    /// (staged in a hidden folder beside it and moved there at the end).
    pub fn write_report(
        &mut self,
        ctx: &egui::Context,
        dir: PathBuf,
        report: crate::identify::CalibrationReport,
    ) {
        self.spawn(ctx, move || {
            let fail = |e: &dyn std::fmt::Display| format!("{}: {e}", dir.display());
            let out = crate::fsutil::OutputDir::create(&dir).map_err(|e| fail(&e))?;
            crate::identify::report::write_all(&report, out.path(), None).map_err(|e| fail(&e))?;
            out.commit().map_err(|e| fail(&e))?;
            Ok(format!(
                "calibration report written to {} (report.md, report.json, calibrated.toml, plots)",
                dir.display()
            ))
        });
    }

    /// Exports the twin of `preset` as an FMU to `path` (`seat-twin export fmu`), with the
    /// shared library built beside the app's executable.
    pub fn write_fmu(
        &mut self,
        ctx: &egui::Context,
        path: PathBuf,
        preset: crate::preset::Preset,
        placement: crate::export::fmu::ControllerPlacement,
    ) {
        self.spawn(ctx, move || {
            let library = crate::export::fmu::library_beside_executable();
            crate::export::fmu::write(&preset, placement, &library, &path, &mut |_, _| {})
                .map(|_| format!("FMU written to {}", path.display()))
                .map_err(|e| format!("FMU not written: {e}"))
        });
    }

    /// Exports the controller of `preset` as C99 into the folder `dir`
    /// (`seat-twin export controller --rate 1000 --lang c`).
    pub fn write_controller(
        &mut self,
        ctx: &egui::Context,
        dir: PathBuf,
        preset: crate::preset::Preset,
    ) {
        self.spawn(ctx, move || {
            let name = preset.meta.name.clone();
            crate::export::controller::write(
                &preset,
                &name,
                CONTROLLER_EXPORT_RATE_HZ,
                &dir,
                &mut |_, _| {},
            )
            .map(|()| {
                format!(
                    "controller code at {} Hz written to {} (seat_controller.h, .c, .json)",
                    CONTROLLER_EXPORT_RATE_HZ,
                    dir.display()
                )
            })
            .map_err(|e| format!("controller code not written: {e}"))
        });
    }

    /// A finished write's message.
    pub fn poll(&mut self) -> Option<Result<String, String>> {
        let (i, r) = self
            .jobs
            .iter()
            .enumerate()
            .find_map(|(i, j)| j.poll().map(|r| (i, r)))?;
        self.jobs.remove(i);
        Some(r)
    }
}
