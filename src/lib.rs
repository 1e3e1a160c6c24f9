//! # seat-twin — digital twin of a hydraulic active seat suspension
//!
//! The model — equations as implemented, units, parameters, the corrections to the paper and
//! the validity range — is documented in `docs/model.md` in the repository.
//!
//! The engine of seat-twin, a pure library with no UI, clock, thread or file access in its
//! core. The main types and how data flows:
//!
//! * [`params::Params`] — every physical parameter in SI, documented and validated;
//!   [`preset`] reads and writes them as TOML presets.
//! * [`model`] — the three plants: [`model::twin::Twin`] (10-state nonlinear multi-physics
//!   twin), [`model::linear::LinearModel`] (G(s) of Eq. 15) and [`model::passive::PassiveModel`].
//! * [`scenario`] — platform motions (cycloid, random ride, sine, CSV) and open-loop commands.
//! * [`simulation::Simulation`] — a model, the controller `V = Kp·u + (Ki/s)·ẍ`, saturation,
//!   the pure delay and an excitation, stepped by fixed-step RK4 ([`integrate`]) into a
//!   [`simulation::Trace`].
//! * [`experiments`] — the paper's experiments as one-call functions.
//! * [`export`] — the twin as an FMI 2.0 co-simulation FMU (its C API is this crate's
//!   `cdylib`) and the controller at a fixed rate as portable C99.
//! * [`analysis`] — frequency responses (exact, linearised, simulated), vibration metrics
//!   (RMS, ISO 2631-1 Wk, VDV, SEAT, A(8)).
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
pub mod cli;
pub mod control;
pub mod dataset;
pub mod delay;
pub mod dsp;
pub mod engine;
pub mod experiments;
pub mod export;
pub mod fsutil;
#[cfg(feature = "gui")]
pub mod gui;
pub mod identify;
pub mod integrate;
pub mod lti;
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
