//! Analysis of models and traces: frequency responses (analytic and linearised in
//! `frequency_response`, by simulated sine dwells in `dwell`) and vibration metrics.

pub mod dwell;
pub mod frequency_response;
pub mod metrics;
pub mod response;
pub mod settle;
pub mod stability;
pub mod watch;
