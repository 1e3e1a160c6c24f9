//! The app's plain state types: the preset in use, the notice line, the window and
//! the frame timings.

use crate::params::Params;
use std::collections::VecDeque;
use std::path::PathBuf;
use web_time::Instant;

/// The preset the current parameters came from.
#[derive(Debug, Clone)]
pub struct PresetInfo {
    /// Name shown in the title.
    pub name: String,
    /// Its description.
    pub description: String,
    /// The file, if any.
    pub path: Option<PathBuf>,
    /// Whether "Save" may overwrite `path` (the user chose it; shipped presets are not).
    pub user_file: bool,
    /// Parameters as loaded or last saved: the "modified" marker compares against these.
    pub baseline: Params,
}

/// A message line under the toolbar.
#[derive(Debug, Clone)]
pub struct Notice {
    /// Text.
    pub text: String,
    /// An error (red) or information.
    pub error: bool,
    pub(super) at: Instant,
}

/// Per-frame timing, for the debug overlay.
#[derive(Debug, Clone, Default)]
pub struct FrameStats {
    ui_ms: VecDeque<f64>,
    frame_at: VecDeque<Instant>,
    /// Whole-frame CPU time reported by eframe (UI + tessellation) \[ms\].
    pub cpu_ms: Option<f64>,
}

impl FrameStats {
    pub(super) fn record(&mut self, ui_ms: f64) {
        if self.ui_ms.len() >= 120 {
            self.ui_ms.pop_front();
            self.frame_at.pop_front();
        }
        self.ui_ms.push_back(ui_ms);
        self.frame_at.push_back(Instant::now());
    }

    /// Forgets the frames so far (a measurement starts afresh).
    pub fn clear(&mut self) {
        self.ui_ms.clear();
        self.frame_at.clear();
    }

    /// Mean time of `SeatTwinApp::ui` over the last 120 frames \[ms\].
    pub fn mean_ui_ms(&self) -> f64 {
        self.ui_ms.iter().sum::<f64>() / self.ui_ms.len().max(1) as f64
    }

    /// 95th percentile of the time of `SeatTwinApp::ui` over the last 120 frames \[ms\] (the
    /// nearest-rank value: 6 of 120 frames are slower).
    pub fn p95_ui_ms(&self) -> f64 {
        let mut v: Vec<f64> = self.ui_ms.iter().copied().collect();
        if v.is_empty() {
            return 0.0;
        }
        v.sort_by(f64::total_cmp);
        let rank = (0.95 * v.len() as f64).ceil() as usize;
        v[rank.clamp(1, v.len()) - 1]
    }

    /// Largest time of `SeatTwinApp::ui` over the last 120 frames \[ms\].
    pub fn max_ui_ms(&self) -> f64 {
        self.ui_ms.iter().copied().fold(0.0, f64::max)
    }

    /// Frames per second over the last 120 frames.
    pub fn fps(&self) -> f64 {
        match (self.frame_at.front(), self.frame_at.back()) {
            (Some(a), Some(b)) if self.frame_at.len() > 1 => {
                (self.frame_at.len() - 1) as f64 / b.duration_since(*a).as_secs_f64().max(1e-9)
            }
            _ => 0.0,
        }
    }
}

/// The app's window: its title as last set, whether its size was checked against the
/// monitor, and the frame timings of the debug overlay.
#[derive(Debug, Clone, Default)]
pub struct WindowState {
    /// Per-frame timing.
    pub stats: FrameStats,
    title: String,
    checked: bool,
}

impl WindowState {
    /// Once, a window size remembered from a larger screen is cut to fit this one; the
    /// title is set when it changed.
    pub fn follow(&mut self, ui: &egui::Ui, title: String) {
        if !self.checked {
            let (monitor, inner) =
                ui.input(|i| (i.viewport().monitor_size, i.viewport().inner_rect));
            if let (Some(m), Some(r)) = (monitor, inner) {
                self.checked = true;
                if let Some(size) = fitted_window(r.size(), m) {
                    ui.ctx()
                        .send_viewport_cmd(egui::ViewportCommand::InnerSize(size));
                }
            }
        }
        if title != self.title {
            ui.ctx()
                .send_viewport_cmd(egui::ViewportCommand::Title(title.clone()));
            self.title = title;
        }
    }
}

/// The window size to set at start for a `window` \[points\] on `monitor`, or `None` to keep
/// it: a window that does not fit (with room for the desktop's panels and the title bar) is
/// cut to 90 % of the monitor; one at most half the monitor both ways (remembered from a
/// smaller screen) grows to 75 % of it.
pub fn fitted_window(window: egui::Vec2, monitor: egui::Vec2) -> Option<egui::Vec2> {
    let room = monitor * 0.95 - egui::vec2(0.0, 40.0);
    if window.x > room.x || window.y > room.y {
        Some(window.min(monitor * 0.9))
    } else if window.x <= monitor.x * 0.5 && window.y <= monitor.y * 0.5 {
        Some(monitor * 0.75)
    } else {
        None
    }
}
