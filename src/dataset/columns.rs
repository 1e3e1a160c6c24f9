//! The known columns of a record, their units and bounds, and the kinds of record.

use serde::{Deserialize, Serialize};
use std::fmt;

/// The known column names, in their usual order: `t` \[s\], `v_in` \[V\], `u` \[m\], `x` \[m\],
/// `xdd` \[m/s²\], `ydd` \[m/s²\], `p1` \[Pa\], `p2` \[Pa\].
pub const COLUMNS: [&str; 8] = ["t", "v_in", "u", "x", "xdd", "ydd", "p1", "p2"];

/// Slot of `t` in [`COLUMNS`].
pub(super) const T: usize = 0;

/// Largest magnitude a cell of the known column `name` may have (SI): `t` 1e9 s, `v_in`
/// 1e6 V, `u` and `x` 1000 m, `xdd` and `ydd` 1e6 m/s², `p1` and `p2` 1e10 Pa; infinity for
/// any other name. Far beyond any rig: a value past it is a broken file or a unit mix-up, and
/// would overflow the replay's derivatives and sums.
pub fn column_limit(name: &str) -> f64 {
    match name {
        "t" => 1e9,
        "v_in" => 1e6,
        "u" | "x" => 1e3,
        "xdd" | "ydd" => 1e6,
        "p1" | "p2" => 1e10,
        _ => f64::INFINITY,
    }
}

/// Unit of a known column, for messages.
pub(super) fn column_unit(name: &str) -> &'static str {
    match name {
        "t" => "s",
        "v_in" => "V",
        "u" | "x" => "m",
        "xdd" | "ydd" => "m/s²",
        "p1" | "p2" => "Pa",
        _ => "",
    }
}

/// What a record is for; decides the required columns and the allowed sample rate.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum RecordKind {
    /// A measured record for calibration: requires `t`, `v_in` and `u`; sample rate
    /// 200 Hz ..= 10 kHz.
    Measured,
    /// A platform record to drive the simulation: requires `t` and at least one of `x`,
    /// `xdd`; sample rate 10 Hz ..= 100 kHz. The simulation starts the platform at rest, so
    /// the record must too: its first sample is taken as the rest state (not checked, as
    /// measured noise makes "at rest" impossible to tell reliably).
    Excitation,
}

impl RecordKind {
    /// Allowed sample rates `(min, max)` \[Hz\], both inclusive.
    pub fn rate_range_hz(self) -> (f64, f64) {
        match self {
            RecordKind::Measured => (200.0, 10_000.0),
            RecordKind::Excitation => (10.0, 100_000.0),
        }
    }

    /// Columns that must all be present (besides [`RecordKind::one_of_columns`]).
    pub fn required_columns(self) -> &'static [&'static str] {
        match self {
            RecordKind::Measured => &["t", "v_in", "u"],
            RecordKind::Excitation => &["t"],
        }
    }

    /// Columns of which at least one must be present (empty: no such condition).
    pub fn one_of_columns(self) -> &'static [&'static str] {
        match self {
            RecordKind::Measured => &[],
            RecordKind::Excitation => &["x", "xdd"],
        }
    }
}

impl fmt::Display for RecordKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            RecordKind::Measured => "measured",
            RecordKind::Excitation => "excitation",
        })
    }
}
