//! What persists between runs: the theme, the last preset and folder, the speed, the
//! excitation editor and the view (eframe storage, `#[serde(default)]`, so a settings file
//! from an older build still reads).

use super::controls::ExcitationEditor;
use crate::engine::Speed;
use serde::{Deserialize, Serialize};
use std::path::PathBuf;

/// Theme choice (persisted).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
pub enum Theme {
    /// Follow the desktop.
    #[default]
    System,
    /// Light.
    Light,
    /// Dark.
    Dark,
}

impl Theme {
    /// The egui theme preference of this choice.
    pub fn preference(self) -> egui::ThemePreference {
        match self {
            Theme::System => egui::ThemePreference::System,
            Theme::Light => egui::ThemePreference::Light,
            Theme::Dark => egui::ThemePreference::Dark,
        }
    }
}

/// What persists between runs (eframe storage; the window layout persists through egui).
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(default)]
pub struct Settings {
    /// Theme.
    pub theme: Theme,
    /// The preset file last opened or saved.
    pub last_preset: Option<PathBuf>,
    /// Simulation speed.
    pub speed: Speed,
    /// Frame-time overlay.
    pub show_debug: bool,
    /// Schematic panel.
    pub show_schematic: bool,
    /// Recompute the simulated dwell points automatically after slider changes.
    pub dwell_auto: bool,
    /// The excitation editor.
    pub excitation: ExcitationEditor,
    /// Unwrapped phase in the frequency plots (default: wrapped into ±180°).
    pub phase_unwrapped: bool,
    /// UI scale (egui's zoom factor: 1 = 100 %), also changed with Ctrl + / Ctrl −.
    pub ui_scale: f32,
    /// Length of the scopes' time window \[s\], 1 … 60.
    pub scope_window_s: f64,
    /// The folder of the last file opened or saved (dialogs and typed paths start there).
    pub last_dir: Option<PathBuf>,
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            theme: Theme::System,
            last_preset: None,
            speed: Speed::RealTime,
            show_debug: false,
            show_schematic: true,
            dwell_auto: true,
            excitation: ExcitationEditor::default(),
            phase_unwrapped: false,
            last_dir: None,
            ui_scale: 1.0,
            scope_window_s: super::traces::WINDOW_S,
        }
    }
}
