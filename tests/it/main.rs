//! All integration tests in one binary: linking the engine (and, with the `gui` feature, eframe)
//! once instead of once per file keeps a cold `cargo test` several minutes shorter.
//! Each module is one area; its own docs say what it proves.

mod cli;
mod cli_hardening;
mod cli_input;
mod cli_round2;
mod control;
mod dataset_props;
mod engine;
mod export;
mod fuzz;
mod gui;
mod gui_edges;
mod gui_lab;
mod gui_measured;
mod gui_parts;
mod gui_session;
mod gui_use;
mod gui_web;
mod identify;
mod integrator;
mod memory;
mod paper;
mod physics;
mod presets;
mod seat_test;
mod stability;
mod support;
mod tune;
