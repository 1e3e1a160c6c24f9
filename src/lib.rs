//! # seat-twin — digital twin of a hydraulic active seat suspension
//!
//! The model — equations as implemented, units, parameters, the corrections to the paper and
//! the validity range — is documented in `docs/model.md` in the repository.
//!
//! # The pure engine
//!
//! No UI, clock, thread or file in these modules (rayon parallelises some sweeps); the same
//! parameters, excitation and seed give the same output bit for bit.
//!
//! * [`params`] — every physical parameter in SI, documented and validated, from one table
//!   ([`params::PARAMS`]) that validation, sliders, calibration knobs and reports read.
//! * [`model`] — the three plants as pure right-hand sides `derivatives(t, state, inputs)`:
//!   [`model::twin::Twin`] (10-state nonlinear multi-physics twin),
//!   [`model::linear::LinearModel`] (G(s) of Eq. 15) and [`model::passive::PassiveModel`].
//! * [`control`] — one [`control::Controller`] for every structure (paper, predictive,
//!   skyhook, Smith) and its transfer functions ([`control::ControlLaw`]).
//! * [`scenario`] — every excitation: platform motions (cycloid, random ride, sine, records,
//!   the seat-test classes' motions in [`scenario::class_motion`]) and open-loop commands.
//! * [`simulation`] — the problem (a model, its command path: controller, saturation, pure
//!   delay ([`simulation::delay`]), and an excitation) stepped on a fixed grid into a
//!   [`simulation::Trace`] by [`simulation::Simulation`] with one of three steppers
//!   ([`simulation::integrate::Method`]): the exponential RK4 ([`simulation::integrate::Etd4`],
//!   the twin's default: its Jacobian at rest taken exactly), classical RK4, or the exact
//!   first-order-hold transition of a linear model ([`simulation::lti`]).
//! * [`experiments`] — the paper's experiments as one-call functions.
//! * [`analysis`] — frequency responses (exact, linearised, simulated by sine dwells), the
//!   stability verdict and margins, vibration metrics (RMS, ISO 2631-1 Wk, VDV, SEAT, A(8)).
//! * [`dsp`] — biquads, Butterworth filters and zero-phase filtering, shared by the metrics and
//!   the identification.
//! * [`identify`] — measured records → replay → calibrate → diagnose (cost function, optimiser,
//!   observer, cancel flag, stop reason).
//! * [`tune`] — the gain search on the nonlinear twin under stability and stroke constraints.
//! * [`seat_test`] — the laboratory seat tests of ISO 7096 / ISO 5007 / EN 13490 on any model.
//! * [`format`](mod@format) — numbers for people: the one formatter of messages, reports and
//!   widgets.
//!
//! # The faces
//!
//! Where the engine meets files, threads, clocks and people:
//!
//! * [`engine`] — the worker thread of the app: [`engine::Command`] in, [`engine::Event`] out.
//! * [`cli`] — the headless `seat-twin` subcommands, one file each (the binary's `main.rs`
//!   parses and dispatches).
//! * `gui` (feature `gui`) — the egui desktop app, a client of [`engine`].
//! * [`report`], [`bench`](mod@bench) — `seat-twin report` (the paper's sections 4–6
//!   reproduced) and `seat-twin bench` (real-time factors and accuracy on this machine).
//! * [`dataset`], [`preset`] — the rig's CSV records and the TOML presets, read and written.
//! * [`export`] — the twin as an FMI 2.0 co-simulation FMU (the C API in this crate's
//!   shared library) and the controller as portable C99.
//! * [`plot`] — PNG and SVG figures; [`output`], [`fsutil`] — output sets written whole or not
//!   at all (temporary file, then rename).
//!
//! ```
//! use seat_twin::{experiments, model::ModelKind, params::Params};
//! let params = Params::paper();
//! let trace = experiments::cycloid(&params, ModelKind::Twin, &Default::default(), 2.0, 1000.0)
//!     .expect("the paper's bump does not diverge");
//! let peak_body = trace.samples.iter().map(|s| s.ydd.abs()).fold(0.0, f64::max);
//! assert!(peak_body < 0.754); // the active seat reduces the platform's 0.754 m/s² peak
//! ```
#![warn(missing_docs)]

pub mod analysis;
pub mod bench;
// The command line has no place in the browser build (the web app is the app's UI).
#[cfg(not(target_arch = "wasm32"))]
pub mod cli;
pub mod control;
pub mod dataset;
pub mod dsp;
pub mod engine;
pub mod experiments;
pub mod export;
pub mod format;
pub mod fsutil;
// Left out of the library's unit-test build: the app's own tests are integration tests
// (`tests/it/gui_parts`), so a cold `cargo test` compiles `gui` once, not twice.
#[cfg(all(feature = "gui", not(test)))]
pub mod gui;
pub mod identify;
pub mod model;
pub mod output;
pub mod params;
pub mod plot;
pub mod preset;
pub mod report;
pub mod scenario;
pub mod seat_test;
pub mod simulation;
pub mod tune;
