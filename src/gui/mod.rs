//! The desktop app (feature `gui`): eframe/egui front end over the [`engine`](crate::engine).
//!
//! ```text
//!  sliders ──SetParams──► engine thread ──Samples/Status──► Traces ──► scopes (egui_plot)
//!     │                                                        └────► metrics, schematic
//!     └──► Analytic (same frame) ──► frequency plots ◄── Dwell (background sine dwell)
//! ```
//!
//! * [`app::SeatTwinApp`] — the views and the one place their actions are applied;
//!   `SeatTwinApp::ui` is the whole per-frame work and runs headless under `egui_kittest`.
//! * [`controls_panel`] — the left panel (parameters, Tune, A/B, excitation), as one view.
//! * [`centre`] — the engine banner, the scopes and the frequency plots, as one view.
//! * [`traces`] — bounded sliding windows of the engine's batches (plots borrow them).
//! * [`frequency`] — analytic responses, margins, the background dwell job.
//! * [`measured`] — measured records: replay overlay, residual diagnosis, calibration in
//!   the background.
//! * [`lessons`] — the guided steps for a lecture; [`share`] — setup links (`#s=…`) and
//!   the presets compiled in; `web` — the browser entry (wasm32 only).
//! * [`settings`] — what persists between runs; [`session`] — the session file.
//! * [`scopes`], [`schematic`], [`controls`] — widgets; [`files`] — dialogs and exports
//!   off the UI thread; [`files_view`] — the path prompt and the discard question;
//!   [`units`] — display units; [`format`](mod@format) — numbers for people;
//!   [`plotkit`] — y axes, clickable legends, wrapped phase.

pub mod ab;
pub mod app;
pub mod centre;
pub mod controls;
pub mod controls_panel;
pub mod files;
pub mod files_view;
pub mod format;
pub mod frequency;
pub mod gain;
pub mod job;
pub mod lessons;
pub mod measured;
pub mod plotkit;
pub mod schematic;
pub mod scopes;
pub mod session;
pub mod settings;
pub mod share;
pub mod style;
pub mod traces;
pub mod tune;
pub mod units;
#[cfg(target_arch = "wasm32")]
pub mod web;

pub use app::SeatTwinApp;

/// Opens the app window and runs until it is closed.
#[cfg(not(target_arch = "wasm32"))]
pub fn run_native() -> Result<(), eframe::Error> {
    let options = eframe::NativeOptions {
        viewport: egui::ViewportBuilder::default()
            .with_title("seat-twin")
            .with_inner_size([1600.0, 1000.0])
            // Small enough for a 1280×720 screen: the centre scrolls below this.
            .with_min_inner_size([800.0, 500.0]),
        ..Default::default()
    };
    eframe::run_native(
        "seat-twin",
        options,
        Box::new(|cc| Ok(Box::new(SeatTwinApp::from_creation_context(cc)))),
    )
}
