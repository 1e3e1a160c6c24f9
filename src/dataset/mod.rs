//! Recorded data sets: the rig's CSV records, read for calibration or to drive a simulation.
//!
//! # The format (a stable contract; other tools write it)
//!
//! * UTF-8 text, comma-separated, `\n` or `\r\n` line ends; a UTF-8 byte-order mark is
//!   skipped.
//! * Optional comment lines starting with `#` before the header. Those of the form
//!   `# key: value` are metadata, kept in file order ([`Record::metadata`]); none is
//!   required. Blank lines are ignored anywhere. Comment lines after the header are skipped
//!   (with one warning), but are not metadata.
//! * One header row, then one row per sample, uniformly sampled. Known columns, in any order,
//!   SI units: `t` \[s\] (strictly increasing), `v_in` \[V\], `u` \[m\], `x` \[m\], `xdd` \[m/s²\],
//!   `ydd` \[m/s²\], `p1` and `p2` \[Pa\]. Unknown columns are ignored with a warning
//!   ([`Record::warnings`]); their cells are not read. A column name given twice is an
//!   error. Names and cells may be padded with spaces or tabs.
//! * Every row has as many fields as the header; every cell of a known column is a finite
//!   number (`NaN`, `inf` and empty cells are errors) within a bound far beyond any rig
//!   ([`column_limit`]: `t` ±1e9 s, `v_in` ±1e6 V, `u` and `x` ±1000 m, `xdd` and `ydd`
//!   ±1e6 m/s², `p1` and `p2` ±1e10 Pa), so that no later computation overflows.
//! * A NUL byte anywhere is an error: the file is not text.
//!
//! ```text
//! # experiment: sine 5 Hz 0.72 V
//! # sample_rate_hz: 1000
//! t,v_in,u,x,xdd,ydd
//! 0.000,0.72,0,1.83747616e-05,-0.097796809,0.197458573
//! ```
//!
//! The step `dt` is the median of the time steps; every step must be within
//! `±(1 % of dt + 1 ns)` of it (times are usually printed rounded, e.g. to 1 ms at 1 kHz), so a
//! missing, repeated or shifted sample is an error naming its line. What else is required
//! depends on the [`RecordKind`].
//!
//! Every problem is a [`DatasetError`] whose message names the file, the 1-based line in the
//! file (comment and blank lines counted) and, for a cell, the column; reading never panics.
//! Values that are allowed but far outside what the rig can produce give a warning
//! ([`Record::warnings`]): a stroke `u` beyond ±35 mm (a record in millimetres instead of
//! metres?) and a command `v_in` beyond the valve's ±10 V.
//! [`write_csv_atomic`] writes the same format through a temporary file in the target
//! directory, so a crash never leaves half a file.
//!
//! The module's parts, one job each: `columns` (the known columns, their units and bounds,
//! the record kinds), `read` (file access and parsing), `validate` (uniform sampling, sample
//! rate, plausibility warnings), `error` (the errors and their messages), `write` (the
//! writer). Everything public is re-exported here.

mod columns;
mod error;
mod lines;
mod read;
mod validate;
mod write;

pub use columns::{COLUMNS, RecordKind, column_limit};
pub use error::DatasetError;
pub use read::{ReadOptions, parse_record, parse_record_bytes, read_record, read_record_with};
pub use validate::{RIG_HALF_STROKE_M, RIG_V_IN_MAX_V};
pub use write::{CsvWriter, write_csv, write_csv_atomic};

use serde::Serialize;
use std::path::PathBuf;

/// Largest file [`read_record`] reads: 512 MiB.
pub const MAX_FILE_BYTES: u64 = 512 * 1024 * 1024;

/// Most data rows a record may have: 20 million.
pub const MAX_ROWS: usize = 20_000_000;

/// Allowed deviation of any time step from the median step, as a fraction of it (1 %).
pub const DT_REL_TOLERANCE: f64 = 0.01;

/// Allowed deviation of any time step from the median step in addition to
/// [`DT_REL_TOLERANCE`] \[s\] (1 ns).
pub const DT_ABS_TOLERANCE_S: f64 = 1e-9;

/// A record read from a CSV file: uniformly sampled columns, all of the same length.
///
/// Columns absent from the file, or not asked for ([`read_record_with`]), are `None`. A parsed
/// record has at least two samples.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Record {
    /// The file it was read from (as given; used in messages).
    pub path: PathBuf,
    /// `# key: value` comment lines before the header, in file order, trimmed.
    pub metadata: Vec<(String, String)>,
    /// Sampling step \[s\]: the median of the time steps.
    pub dt: f64,
    /// Time \[s\], strictly increasing, uniformly spaced by `dt` (±1 %).
    pub t: Vec<f64>,
    /// Valve command voltage `v_in` \[V\].
    pub v_in: Option<Vec<f64>>,
    /// Relative displacement `u = y − x` (seat body minus platform) \[m\], positive up, 0 at
    /// mid-stroke.
    pub u: Option<Vec<f64>>,
    /// Platform (seat-base) position `x` \[m\].
    pub x: Option<Vec<f64>>,
    /// Platform (seat-base) acceleration `ẍ` \[m/s²\].
    pub xdd: Option<Vec<f64>>,
    /// Seat (body) acceleration `ÿ` \[m/s²\].
    pub ydd: Option<Vec<f64>>,
    /// Upper chamber pressure `p1` \[Pa\].
    pub p1: Option<Vec<f64>>,
    /// Lower chamber pressure `p2` \[Pa\].
    pub p2: Option<Vec<f64>>,
    /// Things that were accepted but may deserve a look (unknown columns, comments after
    /// the header, a `sample_rate_hz` metadata value that disagrees with the times by more
    /// than 1 %), one sentence each.
    pub warnings: Vec<String>,
}

impl Record {
    /// Sample rate `1 / dt` \[Hz\].
    pub fn sample_rate_hz(&self) -> f64 {
        1.0 / self.dt
    }

    /// Time from the first to the last sample \[s\] (0 for fewer than two samples).
    pub fn duration_s(&self) -> f64 {
        match (self.t.first(), self.t.last()) {
            (Some(a), Some(b)) => b - a,
            _ => 0.0,
        }
    }

    /// Number of samples (rows).
    pub fn len(&self) -> usize {
        self.t.len()
    }

    /// Whether the record has no samples (never for a parsed record).
    pub fn is_empty(&self) -> bool {
        self.t.is_empty()
    }

    /// Value of the first metadata entry with this key (exact, case-sensitive), if any.
    pub fn metadata_value(&self, key: &str) -> Option<&str> {
        self.metadata
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_str())
    }

    /// The record's first `n` samples (all of it when `n` is not shorter), every column cut
    /// alike.
    pub fn truncated(&self, n: usize) -> Record {
        self.with_columns(self.dt, |v| v[..n.min(v.len())].to_vec())
    }

    /// Every `k`-th sample of the record, from the first (`k` ≥ 1; 1 gives the record
    /// itself), every column alike: the record a data acquisition sampling `k` times slower
    /// would have written, without an anti-alias filter (each kept sample is the recorded one,
    /// noise and quantisation included; the noise's variance per sample is unchanged).
    pub fn decimated(&self, k: usize) -> Record {
        let k = k.max(1);
        self.with_columns(self.dt * k as f64, |v| {
            v.iter().step_by(k).copied().collect()
        })
    }

    /// The record with each column (the time too) made by `f` from its own, the sampling step
    /// `dt` \[s\], and the same file, metadata and warnings.
    fn with_columns(&self, dt: f64, f: impl Fn(&[f64]) -> Vec<f64>) -> Record {
        let col = |c: &Option<Vec<f64>>| c.as_deref().map(&f);
        Record {
            t: f(&self.t),
            v_in: col(&self.v_in),
            u: col(&self.u),
            x: col(&self.x),
            xdd: col(&self.xdd),
            ydd: col(&self.ydd),
            p1: col(&self.p1),
            p2: col(&self.p2),
            path: self.path.clone(),
            metadata: self.metadata.clone(),
            dt,
            warnings: self.warnings.clone(),
        }
    }

    /// The column called `name` (one of [`COLUMNS`]), if present.
    pub fn column(&self, name: &str) -> Option<&[f64]> {
        match name {
            "t" => Some(&self.t),
            "v_in" => self.v_in.as_deref(),
            "u" => self.u.as_deref(),
            "x" => self.x.as_deref(),
            "xdd" => self.xdd.as_deref(),
            "ydd" => self.ydd.as_deref(),
            "p1" => self.p1.as_deref(),
            "p2" => self.p2.as_deref(),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests;
