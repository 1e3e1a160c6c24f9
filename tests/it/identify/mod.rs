//! The identification loop against an independent "true rig".
//!
//! The rig below is written here, apart from the library: its own integration (RK4 at 50 µs),
//! its own square-root regularisation and delay interpolation, and effect laws deliberately
//! different in form from the library's (Stribeck + tanh friction where the library fits
//! Coulomb + viscous, a smooth overlap edge, a spool-position offset, a pressure-dependent
//! leakage, separate hose and chamber bulk moduli, a supply droop solved by iteration), and one
//! effect outside the library (a Cd that depends on the spool position). Its declared
//! parameters are off from the preset (Cd −5 %, τ +1.5 ms), and its records carry sensor
//! noise (0.08 m/s² on accelerations, 0.01 mm on u plus 18.3 µm quantisation). Most
//! campaigns have no pressure channels, as the issue expects; the supply-sag case and one
//! friction case record `p1`, `p2` too (0.2 bar noise, 12-bit on 250 bar).
//!
//! `rig` holds the true rig and the campaign helpers; `effects` checks the verdicts for every
//! library effect and the pairs; `outside` those for effects outside the library, which are
//! proposed beyond it; `records` checks the replay
//! of the raw records, degenerate data and the held-out claims of `calibrated.toml`; `twin_made`
//! the fits and the report on records the twin made itself.

mod campaigns;
mod effects;
mod outside;
mod records;
mod rig;
mod survey;
mod survey_cases;
mod timing;
mod twin_made;
