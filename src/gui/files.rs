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
    /// Load measured records (CSV, several at once).
    LoadMeasured,
    /// Export the traces (CSV).
    ExportCsv,
    /// Export the plots (PNG + SVG).
    ExportPng,
}

impl Purpose {
    /// What the dialog is for, as its title.
    pub fn title(self) -> &'static str {
        match self {
            Purpose::OpenPreset => "Open preset",
            Purpose::SavePreset => "Save preset",
            Purpose::LoadRecord => "Load a platform record (CSV)",
            Purpose::LoadMeasured => "Load measured records (CSV)",
            Purpose::ExportCsv => "Export traces (CSV)",
            Purpose::ExportPng => "Export plots (PNG)",
        }
    }

    fn saves(self) -> bool {
        matches!(
            self,
            Purpose::SavePreset | Purpose::ExportCsv | Purpose::ExportPng
        )
    }

    fn filter(self) -> (&'static str, &'static [&'static str]) {
        match self {
            Purpose::OpenPreset | Purpose::SavePreset => ("preset", &["toml"]),
            Purpose::LoadRecord | Purpose::LoadMeasured | Purpose::ExportCsv => ("CSV", &["csv"]),
            Purpose::ExportPng => ("PNG", &["png"]),
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
}

impl Dialogs {
    /// The dialog currently open, if any.
    pub fn open(&self) -> Option<Purpose> {
        self.open.as_ref().map(|(p, _)| *p)
    }

    /// Opens a dialog on its own thread; ignored while another is open.
    pub fn request(&mut self, purpose: Purpose, suggested_name: &str, ctx: &egui::Context) {
        if self.open.is_some() {
            return;
        }
        let name = suggested_name.to_owned();
        let job = Job::spawn("seat-twin-dialog", waker_of(ctx), move |_| {
            let (fname, ext) = purpose.filter();
            let mut dialog = rfd::AsyncFileDialog::new()
                .set_title(purpose.title())
                .add_filter(fname, ext);
            if let Ok(dir) = std::env::current_dir() {
                dialog = dialog.set_directory(dir);
            }
            let picked = if purpose.saves() {
                pollster::block_on(dialog.set_file_name(name).save_file())
                    .into_iter()
                    .collect::<Vec<_>>()
            } else if purpose == Purpose::LoadMeasured {
                pollster::block_on(dialog.pick_files()).unwrap_or_default()
            } else {
                pollster::block_on(dialog.pick_file())
                    .into_iter()
                    .collect::<Vec<_>>()
            };
            Ok(picked.into_iter().map(|h| h.path().to_path_buf()).collect())
        });
        self.open = Some((purpose, job));
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

/// "or path: [____] Load": a typed path, for desktops without a file dialog. Returns the
/// path when Load is clicked or Enter pressed in a non-empty field.
pub fn typed_path_ui(
    ui: &mut egui::Ui,
    text: &mut String,
    hint: &str,
    width: f32,
) -> Option<PathBuf> {
    ui.label("or path:");
    let r = ui.add(
        egui::TextEdit::singleline(text)
            .desired_width(width)
            .hint_text(hint),
    );
    let enter = r.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter));
    let load = ui.button("Load").clicked() || enter;
    (load && !text.trim().is_empty()).then(|| PathBuf::from(text.trim()))
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
