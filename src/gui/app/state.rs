//! The app's plain state types: the preset in use, the notice line and the frame
//! timings.

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
    /// Whole-frame CPU time reported by eframe (UI + tessellation) [ms].
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

    /// Mean time of `SeatTwinApp::ui` over the last 120 frames [ms].
    pub fn mean_ui_ms(&self) -> f64 {
        self.ui_ms.iter().sum::<f64>() / self.ui_ms.len().max(1) as f64
    }

    /// 95th percentile of the time of `SeatTwinApp::ui` over the last 120 frames [ms] (the
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

    /// Largest time of `SeatTwinApp::ui` over the last 120 frames [ms].
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
