//! Exports to the tools engineers use next: the twin as an FMI 2.0 co-simulation FMU
//! ([`fmu`], with the C API in `fmi2`), and the tuned controller as portable C99
//! ([`controller`]).
//!
//! Both are plain functions that write their files atomically and report progress through a
//! callback, so the CLI (`seat-twin export fmu|controller`) and the app call the same code.

pub mod controller;
#[cfg(not(target_arch = "wasm32"))]
pub mod fmi2;
pub mod fmu;
pub mod zip;
