//! Analysis of models and traces: frequency responses (analytic and linearised; simulated
//! sweeps) and vibration metrics.

pub mod frequency_response;
pub mod metrics;
pub mod sweep;
