//! Analysis of models and traces: frequency responses and vibration metrics.

pub mod frequency_response;
pub mod metrics;
