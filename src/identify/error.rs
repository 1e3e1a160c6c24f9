//! Why identification fails ([`IdentifyError`]).

use crate::params::ParamError;
use crate::simulation::SimError;
use std::path::PathBuf;

/// Why identification failed.
#[derive(Debug, thiserror::Error)]
pub enum IdentifyError {
    /// A record lacks a column the replay needs.
    #[error("{}: the column `{column}` is required for replay", file.display())]
    MissingColumn {
        /// The file.
        file: PathBuf,
        /// The column.
        column: String,
    },
    /// No records given.
    #[error("no measured records given")]
    NoRecords,
    /// The twin diverged on a record.
    #[error("{file}: {source}")]
    Simulation {
        /// The record's file name.
        file: String,
        /// The simulation error.
        source: SimError,
    },
    /// The declared anti-alias filter's corner is far above what a record samples.
    #[error(
        "{file}: the declared anti-alias corner sensors.antialias_hz = {} Hz is above \
         5 times the record's sample rate ({} Hz); an acquisition's anti-alias filter \
         sits below the sample rate: give its corner, or 0 for none",
        crate::format::general(*corner_hz),
        crate::format::general(*rate_hz)
    )]
    AntialiasAboveRate {
        /// The record's file name.
        file: String,
        /// The declared corner \[Hz\].
        corner_hz: f64,
        /// The record's sample rate \[Hz\].
        rate_hz: f64,
    },
    /// The starting parameters are invalid.
    #[error(transparent)]
    Params(#[from] ParamError),
    /// The caller cancelled.
    #[error("calibration cancelled")]
    Cancelled,
}
