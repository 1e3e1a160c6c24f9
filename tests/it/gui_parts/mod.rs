//! The app's own parts (formatting, units, traces, jobs, links, lessons, …) tested one by
//! one, through the library's `gui` module. They sit here rather than beside their code so that
//! the library's unit-test build leaves the app out: compiling `gui` a second time for 35
//! tests cost 40–85 s of CPU in every cold `cargo test` (measured on 2 cores, 2026-11-29).
#![cfg(feature = "gui")]

mod app;
mod files_view;
mod format;
mod frequency_curves;
mod frequency_dwell;
mod gain;
mod job;
mod lessons;
mod plotkit;
mod schematic;
mod share;
mod traces;
mod tune;
mod units;
