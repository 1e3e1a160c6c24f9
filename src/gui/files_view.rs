//! The app's file business as one view: the dialog and the writes in flight, the typed-path
//! prompt (shown when no file dialog is available), and the "discard unsaved changes?"
//! question with the action waiting for it. It reads and writes no file itself: it returns
//! [`FileAction`]s, and the app, which owns the parameters and the preset, carries them out.

use super::files::{Dialogs, PickedFile, Purpose, Writer};
use egui::Key;
use std::path::PathBuf;

/// An action waiting for "discard unsaved changes?".
#[derive(Debug, Clone, PartialEq)]
pub enum Pending {
    /// The Open preset dialog.
    OpenDialog,
    /// A preset file (the Presets menu).
    LoadFile(PathBuf),
    /// The Open session dialog.
    OpenSessionDialog,
    /// Closing the window.
    Quit,
}

/// What the file view asks the app to do.
#[derive(Debug, Clone)]
pub enum FileAction {
    /// Run this action: confirmed, or there was nothing to lose.
    Run(Pending),
    /// Use the files chosen in a dialog or typed, for `purpose`.
    Use(Purpose, Vec<PathBuf>),
    /// Measured records typed into the prompt: files separated by `;`, folders, patterns
    /// (see [`super::files::expand_paths`]).
    LoadMeasuredTyped(String),
    /// A file the browser's picker read (web).
    Picked(Purpose, PickedFile),
    /// A dialog ended with no file (cancelled, or no dialog on this desktop): offer the
    /// typed-path prompt for `purpose`.
    NoFileChosen(Purpose),
    /// A message for the notice line.
    Info(String),
    /// An error for the notice line.
    Error(String),
}

/// The file view's state.
#[derive(Default)]
pub struct FilesView {
    /// The file dialog in flight.
    pub dialogs: Dialogs,
    /// The writes in flight.
    pub writer: Writer,
    pending: Option<Pending>,
    quit_confirmed: bool,
    path_prompt: Option<(Purpose, String)>,
}

impl FilesView {
    /// `action` to run now (`Some`), or kept until the user answers "discard unsaved
    /// changes?" (`None`) when the parameters are `modified`.
    pub fn guard(&mut self, action: Pending, modified: bool) -> Option<Pending> {
        if modified {
            self.pending = Some(action);
            None
        } else {
            Some(action)
        }
    }

    /// Whether the "discard unsaved changes?" prompt is showing.
    pub fn is_confirm_open(&self) -> bool {
        self.pending.is_some()
    }

    /// The window is asked to close: `true` if it must stay open and ask first (the
    /// parameters are `modified` and quitting was not confirmed yet).
    pub fn hold_close(&mut self, modified: bool) -> bool {
        if modified && !self.quit_confirmed {
            self.pending = Some(Pending::Quit);
            true
        } else {
            false
        }
    }

    /// Quitting was confirmed: the next close request goes through.
    pub fn confirm_quit(&mut self) {
        self.quit_confirmed = true;
    }

    /// The typed-path prompt: purpose and text.
    pub fn path_prompt(&self) -> Option<&(Purpose, String)> {
        self.path_prompt.as_ref()
    }

    /// Opens the typed-path prompt for `purpose` with `suggested` as its text.
    pub fn prompt_path(&mut self, purpose: Purpose, suggested: String) {
        self.path_prompt = Some((purpose, suggested));
    }

    /// Whether a write is in flight.
    pub fn busy(&self) -> bool {
        self.writer.busy() > 0
    }

    /// What finished since the last frame: browser picks, dialogs, writes.
    pub fn poll(&mut self) -> Vec<FileAction> {
        let mut out = Vec::new();
        while let Some((purpose, picked)) = self.dialogs.poll_picked() {
            out.push(match picked {
                Some(p) => FileAction::Picked(purpose, p),
                None => FileAction::Info("no file chosen".into()),
            });
        }
        while let Some((purpose, paths)) = self.dialogs.poll() {
            out.push(if cfg!(target_arch = "wasm32") {
                // No file system in a browser: a typed path cannot help.
                FileAction::Error(super::files::NOT_ON_THE_WEB.into())
            } else if paths.is_empty() {
                FileAction::NoFileChosen(purpose)
            } else {
                FileAction::Use(purpose, paths)
            });
        }
        while let Some(r) = self.writer.poll() {
            out.push(match r {
                Ok(m) => FileAction::Info(m),
                Err(e) => FileAction::Error(format!("export failed: {e}")),
            });
        }
        out
    }

    /// The typed-path prompt's row (nothing when it is closed).
    pub fn path_prompt_ui(&mut self, ui: &mut egui::Ui) -> Option<FileAction> {
        let (purpose, mut text) = self.path_prompt.clone()?;
        let mut done: Option<bool> = None;
        ui.horizontal(|ui| {
            let what = if purpose.picks_folder() {
                "folder"
            } else {
                "file"
            };
            ui.label(format!("{} — {what} path:", purpose.title()));
            let r = ui.add(
                egui::TextEdit::singleline(&mut text)
                    .id(egui::Id::unique("path_prompt"))
                    .desired_width(360.0)
                    .hint_text(if purpose == Purpose::LoadMeasured {
                        "files separated by ;  a folder  or campaign/*.csv"
                    } else {
                        "path/to/file"
                    }),
            );
            let enter = r.lost_focus() && ui.input(|i| i.key_pressed(Key::Enter));
            if ui.button("OK").clicked() || enter {
                done = Some(true);
            }
            if ui.button("Cancel").clicked() {
                done = Some(false);
            }
        });
        match done {
            Some(true) if purpose == Purpose::LoadMeasured => {
                self.path_prompt = None;
                Some(FileAction::LoadMeasuredTyped(text))
            }
            Some(true) if !text.trim().is_empty() => {
                self.path_prompt = None;
                let path = PathBuf::from(text.trim());
                Some(FileAction::Use(purpose, vec![path]))
            }
            Some(true) => {
                self.path_prompt = Some((purpose, text));
                Some(FileAction::Error("type a file path first".into()))
            }
            Some(false) => {
                self.path_prompt = None;
                None
            }
            None => {
                self.path_prompt = Some((purpose, text));
                None
            }
        }
    }

    /// The "discard unsaved changes?" question while an action waits for it; the changes
    /// are to the preset `preset_name`.
    pub fn confirm_ui(&mut self, ctx: &egui::Context, preset_name: &str) -> Option<FileAction> {
        let action = self.pending.clone()?;
        let mut decision: Option<bool> = None;
        egui::Modal::new(egui::Id::unique("discard")).show(ctx, |ui| {
            ui.set_width(360.0);
            ui.heading("Unsaved changes");
            ui.label(format!(
                "The parameters differ from the preset “{preset_name}”. Discard the changes?"
            ));
            ui.add_space(8.0);
            ui.horizontal(|ui| {
                if ui.button("Discard changes").clicked() {
                    decision = Some(true);
                }
                if ui.button("Cancel").clicked() {
                    decision = Some(false);
                }
            });
        });
        match decision {
            Some(true) => {
                self.pending = None;
                Some(FileAction::Run(action))
            }
            Some(false) => {
                self.pending = None;
                None
            }
            None => None,
        }
    }
}
