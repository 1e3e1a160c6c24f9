//! The session file: one TOML file that keeps what a teaching or design session needs to be
//! reopened or handed over — the parameters (as the preset format writes them), the
//! excitation editor, the A/B state, the view and the Tune panel's last result. SI units
//! throughout, as in the preset format.
//!
//! A file is read whole and checked before anything in the app changes: a bad file, or one
//! written by a newer build (`format_version` above [`FORMAT_VERSION`]), is refused with a
//! message naming the file and the field. Writes are atomic ([`crate::fsutil`]).

use super::controls::ExcitationEditor;
use crate::params::{ControllerParams, Params};
use crate::preset::{Preset, PresetMeta};
use crate::tune::TuneResult;
use serde::{Deserialize, Serialize};
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

/// The session format this build writes and reads.
pub const FORMAT_VERSION: u32 = 1;

/// Largest session file read \[bytes\] (a tune result with a long Pareto front is a few tens of
/// kB).
pub const MAX_SESSION_BYTES: u64 = 8 << 20;

/// The A/B state.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SessionAb {
    /// A/B on.
    pub on: bool,
    /// The reference controller (B).
    pub reference: ControllerParams,
}

/// The view settings.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct SessionView {
    /// Hidden curves (the frequency plots' legend keys).
    pub hidden_curves: BTreeSet<String>,
    /// Unwrapped phase.
    pub phase_unwrapped: bool,
    /// Scope window length \[s\], 1 … 60.
    pub scope_window_s: f64,
    /// Schematic panel shown.
    pub show_schematic: bool,
    /// UI scale (zoom factor), 0.5 … 3.
    pub ui_scale: f32,
}

impl Default for SessionView {
    fn default() -> Self {
        let s = super::settings::Settings::default();
        Self {
            hidden_curves: BTreeSet::new(),
            phase_unwrapped: s.phase_unwrapped,
            scope_window_s: s.scope_window_s,
            show_schematic: s.show_schematic,
            ui_scale: s.ui_scale,
        }
    }
}

/// The controllers of a tune result's evaluations (report.json leaves them out; a session
/// needs them to apply a Pareto point again).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TuneControllers {
    /// Of `baseline` and `baseline_heldout`.
    pub baseline: ControllerParams,
    /// Of `tuned` and `tuned_heldout`.
    pub tuned: ControllerParams,
    /// Of each Pareto point, in order.
    pub pareto: Vec<ControllerParams>,
}

/// The Tune panel's last result.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct SessionTune {
    /// The chosen Pareto point.
    pub selected: Option<usize>,
    /// The evaluations' controllers.
    pub controllers: TuneControllers,
    /// The result, as report.json holds it.
    pub result: TuneResult,
}

impl SessionTune {
    /// Keeps `result` with its controllers.
    pub fn new(result: &TuneResult, selected: Option<usize>) -> Self {
        Self {
            selected,
            controllers: TuneControllers {
                baseline: result.baseline.controller,
                tuned: result.tuned.controller,
                pareto: result.pareto.iter().map(|e| e.controller).collect(),
            },
            result: result.clone(),
        }
    }

    /// The result with its controllers put back.
    pub fn restored(&self) -> TuneResult {
        let mut r = self.result.clone();
        let c = &self.controllers;
        r.baseline.controller = c.baseline;
        r.baseline_heldout.controller = c.baseline;
        r.tuned.controller = c.tuned;
        r.tuned_heldout.controller = c.tuned;
        for (e, c) in r.pareto.iter_mut().zip(&c.pareto) {
            e.controller = *c;
        }
        r
    }
}

/// A session file.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Session {
    /// [`FORMAT_VERSION`].
    pub format_version: u32,
    /// The preset's name and parameters, as a preset file holds them (its TOML text).
    pub preset: String,
    /// The excitation editor (a loaded record is kept by `record_path`).
    pub excitation: ExcitationEditor,
    /// The platform record the excitation plays, if one was loaded.
    #[serde(default)]
    pub record_path: Option<PathBuf>,
    /// The A/B state.
    pub ab: SessionAb,
    /// The view settings.
    #[serde(default)]
    pub view: SessionView,
    /// The Tune panel's last result.
    #[serde(default)]
    pub tune: Option<SessionTune>,
}

/// A session file that could not be read, written or used.
#[derive(Debug, thiserror::Error)]
pub enum SessionError {
    /// Reading or writing failed.
    #[error("{file}: {error}")]
    Io {
        /// The file.
        file: PathBuf,
        /// The error.
        error: std::io::Error,
    },
    /// Over [`MAX_SESSION_BYTES`].
    #[error("{file}: {size} bytes is over the {MAX_SESSION_BYTES}-byte limit of a session file")]
    TooLarge {
        /// The file.
        file: PathBuf,
        /// Its size \[bytes\].
        size: u64,
    },
    /// Not a session file of this format.
    #[error("{file}: {message}")]
    Parse {
        /// The file.
        file: PathBuf,
        /// What and where (the field, line and column).
        message: String,
    },
    /// Written by a newer build.
    #[error(
        "{file}: session format_version {found} is newer than this build reads ({FORMAT_VERSION})"
    )]
    NewerVersion {
        /// The file.
        file: PathBuf,
        /// The version found.
        found: u32,
    },
    /// The parameters (field `preset`) are not a valid preset.
    #[error("{file}: field `preset`: {reason}")]
    Preset {
        /// The file.
        file: PathBuf,
        /// The preset reader's message.
        reason: String,
    },
}

impl Session {
    /// The parameters as a preset.
    pub fn preset_of(name: &str, description: &str, params: &Params) -> String {
        Preset {
            meta: PresetMeta {
                name: name.into(),
                description: description.into(),
                ..Default::default()
            },
            params: *params,
            per_record: Default::default(),
        }
        .to_toml()
    }

    /// Writes the session atomically.
    pub fn save(&self, path: &Path) -> Result<(), SessionError> {
        let io = |error| SessionError::Io {
            file: path.to_path_buf(),
            error,
        };
        let body = toml::to_string_pretty(self).map_err(|e| io(std::io::Error::other(e)))?;
        let text = format!("# seat-twin session. SI units; `preset` is a preset file.\n\n{body}");
        crate::fsutil::write_atomic_bytes(path, text.as_bytes()).map_err(io)
    }

    /// Reads and checks a session file; also returns its parameters (validated).
    pub fn load(path: &Path) -> Result<(Self, Preset), SessionError> {
        use std::io::Read;
        let file = path.to_path_buf();
        let io = |error| SessionError::Io {
            file: file.clone(),
            error,
        };
        let f = crate::fsutil::open_input(path).map_err(io)?;
        let mut bytes = Vec::new();
        f.take(MAX_SESSION_BYTES + 1)
            .read_to_end(&mut bytes)
            .map_err(io)?;
        if bytes.len() as u64 > MAX_SESSION_BYTES {
            return Err(SessionError::TooLarge {
                file,
                size: bytes.len() as u64,
            });
        }
        let parse = |message: String| SessionError::Parse {
            file: file.clone(),
            message,
        };
        let text = std::str::from_utf8(&bytes)
            .map_err(|e| parse(format!("not UTF-8 text (byte {})", e.valid_up_to())))?;
        // The version first, so a newer file is refused as newer, not as malformed.
        #[derive(Deserialize)]
        struct Version {
            format_version: Option<u32>,
        }
        let version: toml::Table = toml::from_str(text).map_err(|e| parse(e.to_string()))?;
        let version: Version = version
            .try_into()
            .map_err(|e: toml::de::Error| parse(e.to_string()))?;
        match version.format_version {
            None => {
                return Err(parse(
                    "field `format_version` is missing: not a session file (a preset is opened with File → Open preset…)"
                        .into(),
                ));
            }
            Some(v) if v > FORMAT_VERSION => {
                return Err(SessionError::NewerVersion { file, found: v });
            }
            Some(_) => {}
        }
        let session: Session = toml::from_str(text).map_err(|e| parse(e.to_string()))?;
        let preset =
            Preset::from_toml(&session.preset, path).map_err(|e| SessionError::Preset {
                file: file.clone(),
                reason: e.to_string(),
            })?;
        if let Some(t) = &session.tune {
            if t.controllers.pareto.len() != t.result.pareto.len() {
                return Err(parse(format!(
                    "field `tune.controllers.pareto`: {} controllers for {} Pareto points",
                    t.controllers.pareto.len(),
                    t.result.pareto.len()
                )));
            }
            if t.selected.is_some_and(|i| i >= t.result.pareto.len()) {
                return Err(parse("field `tune.selected`: past the Pareto front".into()));
            }
        }
        let v = &session.view;
        if !(1.0..=60.0).contains(&v.scope_window_s) {
            return Err(parse(format!(
                "field `view.scope_window_s`: {} s is outside 1 … 60 s",
                v.scope_window_s
            )));
        }
        if !(0.5..=3.0).contains(&v.ui_scale) {
            return Err(parse(format!(
                "field `view.ui_scale`: {} is outside 0.5 … 3",
                v.ui_scale
            )));
        }
        Ok((session, preset))
    }
}
