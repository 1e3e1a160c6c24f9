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

use serde::{Deserialize, Serialize};
use std::collections::HashMap;
use std::fmt::{self, Write as _};
use std::fs::File;
use std::io::{self, Read, Write};
use std::path::{Path, PathBuf};

/// Largest file [`read_record`] reads: 512 MiB.
pub const MAX_FILE_BYTES: u64 = 512 * 1024 * 1024;

/// Most data rows a record may have: 20 million.
pub const MAX_ROWS: usize = 20_000_000;

/// Allowed deviation of any time step from the median step, as a fraction of it (1 %).
pub const DT_REL_TOLERANCE: f64 = 0.01;

/// Allowed deviation of any time step from the median step in addition to
/// [`DT_REL_TOLERANCE`] \[s\] (1 ns).
pub const DT_ABS_TOLERANCE_S: f64 = 1e-9;

/// The known column names, in their usual order: `t` \[s\], `v_in` \[V\], `u` \[m\], `x` \[m\],
/// `xdd` \[m/s²\], `ydd` \[m/s²\], `p1` \[Pa\], `p2` \[Pa\].
pub const COLUMNS: [&str; 8] = ["t", "v_in", "u", "x", "xdd", "ydd", "p1", "p2"];

/// Slot of `t` in [`COLUMNS`].
const T: usize = 0;
/// Relative slack on the sample-rate limits, for the rounding of printed times.
const RATE_SLACK: f64 = 1e-6;
/// Unknown columns warned about one by one; the rest are summed up in one warning.
const MAX_UNKNOWN_WARNINGS: usize = 10;
/// Longest cell or row text quoted in a message, in characters.
const QUOTE_CHARS: usize = 60;
/// Bytes [`read_record`] reads and checks for text before it reads the rest, so that a device
/// or a binary file fails at once.
const PROBE_BYTES: u64 = 64 * 1024;

/// Half the rig's stroke \[m\]: a measured `u` beyond it gives a warning.
pub const RIG_HALF_STROKE_M: f64 = 0.035;
/// The valve's command range \[V\]: a `v_in` beyond ±this gives a warning.
pub const RIG_V_IN_MAX_V: f64 = 10.0;

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
fn column_unit(name: &str) -> &'static str {
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

/// A record read from a CSV file: uniformly sampled columns, all of the same length.
///
/// Columns absent from the file are `None`. A parsed record has at least two samples.
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

/// Why a record could not be read. Every message starts with the file.
#[derive(Debug, thiserror::Error)]
pub enum DatasetError {
    /// The file could not be opened or read.
    #[error("{file}: cannot read: {error}")]
    Io {
        /// The file.
        file: PathBuf,
        /// The I/O error (in the message, not a separate source, so it is printed once).
        error: io::Error,
    },
    /// The file is not UTF-8 text.
    #[error("{file}: line {line}: not UTF-8 text: {detail}")]
    Encoding {
        /// The file.
        file: PathBuf,
        /// 1-based line of the first invalid byte.
        line: usize,
        /// Which byte, where, and a hint.
        detail: String,
    },
    /// No header row, or no data row after it.
    #[error("{file}: {detail}")]
    Empty {
        /// The file.
        file: PathBuf,
        /// What is missing.
        detail: String,
    },
    /// A column the record kind needs is not in the header.
    #[error("{}", missing_column_message(.file, *.line, .columns, *.kind, .header))]
    MissingColumn {
        /// The file.
        file: PathBuf,
        /// 1-based line of the header.
        line: usize,
        /// The missing column; with several names, at least one of them is needed.
        columns: Vec<String>,
        /// The kind of record asked for.
        kind: RecordKind,
        /// The header's column names as found.
        header: Vec<String>,
    },
    /// The same column name appears twice in the header.
    #[error(
        "{file}: line {line}: column \"{column}\" appears twice in the header (fields {first} and {second})"
    )]
    DuplicateColumn {
        /// The file.
        file: PathBuf,
        /// 1-based line of the header.
        line: usize,
        /// The repeated name.
        column: String,
        /// 1-based field number of its first occurrence.
        first: usize,
        /// 1-based field number of its second occurrence.
        second: usize,
    },
    /// A cell is not a finite number, or beyond its column's [`column_limit`].
    #[error("{file}: line {line}, column \"{column}\": {value:?} {reason}")]
    Parse {
        /// The file.
        file: PathBuf,
        /// 1-based line in the file.
        line: usize,
        /// The column's name.
        column: String,
        /// The offending cell, shortened to 60 characters.
        value: String,
        /// What is wrong, e.g. `is not a number`, `is not a finite number`,
        /// `is beyond ±1000 m`.
        reason: String,
    },
    /// A row with more or fewer fields than the header.
    #[error("{}", field_count_message(.file, *.line, .column, *.found, *.expected, *.header_line, .row))]
    FieldCount {
        /// The file.
        file: PathBuf,
        /// 1-based line of the row.
        line: usize,
        /// The header's name of the first missing field (too few fields) or of the last
        /// field (too many).
        column: String,
        /// Fields in the row.
        found: usize,
        /// Fields in the header.
        expected: usize,
        /// 1-based line of the header.
        header_line: usize,
        /// The row, shortened to 60 characters.
        row: String,
    },
    /// Times not strictly increasing, not uniformly sampled, or too few samples.
    #[error("{file}: line {line}: {reason}")]
    Time {
        /// The file.
        file: PathBuf,
        /// 1-based line of the offending sample.
        line: usize,
        /// What is wrong, naming the times involved.
        reason: String,
    },
    /// The sample rate is outside what the record kind allows.
    #[error("{file}: sample rate {} Hz (step {} s) is outside {min} ..= {max} Hz allowed for {}", sig(*.rate_hz), sig(1.0 / *.rate_hz), kind_phrase(*.kind))]
    SampleRate {
        /// The file.
        file: PathBuf,
        /// The record's sample rate \[Hz\].
        rate_hz: f64,
        /// Smallest allowed rate \[Hz\].
        min: f64,
        /// Largest allowed rate \[Hz\].
        max: f64,
        /// The kind of record asked for.
        kind: RecordKind,
    },
    /// The file is larger than [`MAX_FILE_BYTES`]; refused before reading.
    #[error("{file}: {bytes} bytes is over the limit of {limit} bytes (512 MiB)")]
    TooLarge {
        /// The file.
        file: PathBuf,
        /// Its size \[bytes\].
        bytes: u64,
        /// The limit \[bytes\].
        limit: u64,
    },
    /// The record has more than [`MAX_ROWS`] data rows.
    #[error("{file}: line {line}: more than {limit} data rows")]
    TooManyRows {
        /// The file.
        file: PathBuf,
        /// 1-based line of the first row over the limit.
        line: usize,
        /// The limit \[rows\].
        limit: usize,
    },
}

fn field_count_message(
    file: &Path,
    line: usize,
    column: &str,
    found: usize,
    expected: usize,
    header_line: usize,
    row: &str,
) -> String {
    let fields = |n: usize| format!("{n} field{}", if n == 1 { "" } else { "s" });
    let what = if found < expected {
        format!("column {} is missing", quote(column))
    } else {
        format!(
            "fields past the last column {} are not expected",
            quote(column)
        )
    };
    format!(
        "{}: line {line}: {what}: the row {row:?} has {}, the header (line {header_line}) has \
         {expected}",
        file.display(),
        fields(found),
    )
}

/// "a measured record" / "an excitation record".
fn kind_phrase(kind: RecordKind) -> &'static str {
    match kind {
        RecordKind::Measured => "a measured record",
        RecordKind::Excitation => "an excitation record",
    }
}

fn missing_column_message(
    file: &Path,
    line: usize,
    columns: &[String],
    kind: RecordKind,
    header: &[String],
) -> String {
    let quoted: Vec<String> = columns.iter().map(|c| format!("{c:?}")).collect();
    let mut s = format!(
        "{}: line {line}: missing column {}",
        file.display(),
        quoted.join(" or ")
    );
    let need = match kind {
        RecordKind::Measured => "a measured record needs t, v_in and u",
        RecordKind::Excitation => "an excitation record needs t and at least one of x, xdd",
    };
    let _ = write!(s, " ({need}); the header has ");
    if header.is_empty() {
        s.push_str("no columns");
    } else {
        let shown: Vec<String> = header.iter().take(20).map(|h| quote(h)).collect();
        s.push_str(&shown.join(", "));
        if header.len() > 20 {
            let _ = write!(s, ", … ({} in all)", header.len());
        }
    }
    if !header.is_empty() && header.iter().all(|h| h.parse::<f64>().is_ok()) {
        s.push_str(" — this line looks like data: is the header row missing?");
    }
    s
}

/// `{:?}` of a string shortened to [`QUOTE_CHARS`] characters.
fn quote(s: &str) -> String {
    format!("{:?}", shorten(s))
}

fn shorten(s: &str) -> String {
    match s.char_indices().nth(QUOTE_CHARS) {
        Some((i, _)) => format!("{}…", &s[..i]),
        None => s.to_string(),
    }
}

/// A number with 6 significant digits, printed without trailing noise.
fn sig(x: f64) -> String {
    if !x.is_finite() {
        return format!("{x}");
    }
    let rounded: f64 = format!("{x:.5e}").parse().unwrap_or(x);
    fmt_num(rounded)
}

/// Shortest round-trip text of a finite `f64`: plain for 1e-5 <= |x| < 1e15 (and 0),
/// scientific otherwise.
fn fmt_num(x: f64) -> String {
    let mut s = String::new();
    let _ = write_num(&mut s, x);
    s
}

fn write_num<W: fmt::Write>(w: &mut W, x: f64) -> fmt::Result {
    let a = x.abs();
    if a == 0.0 || (1e-5..1e15).contains(&a) {
        write!(w, "{x}")
    } else {
        write!(w, "{x:e}")
    }
}

/// Reads a record from a CSV file (see the [module docs](self) for the format).
///
/// Files over [`MAX_FILE_BYTES`] are refused before reading; a file that is not text (a
/// binary file, `/dev/zero`, `/dev/urandom`) is refused after its first 64 KiB.
pub fn read_record(path: &Path, kind: RecordKind) -> Result<Record, DatasetError> {
    let io_err = |error| DatasetError::Io {
        file: path.to_path_buf(),
        error,
    };
    let file = File::open(path).map_err(io_err)?;
    let meta = file.metadata().map_err(io_err)?;
    if meta.is_dir() {
        return Err(io_err(io::Error::new(
            io::ErrorKind::IsADirectory,
            "is a directory, not a CSV file",
        )));
    }
    let bytes = meta.len();
    if bytes > MAX_FILE_BYTES {
        return Err(DatasetError::TooLarge {
            file: path.to_path_buf(),
            bytes,
            limit: MAX_FILE_BYTES,
        });
    }
    let mut data = Vec::with_capacity(usize::try_from(bytes).unwrap_or(0));
    // `take` guards against a file that grows while it is read, and against devices.
    let mut reader = file.take(MAX_FILE_BYTES + 1);
    (&mut reader)
        .take(PROBE_BYTES)
        .read_to_end(&mut data)
        .map_err(io_err)?;
    check_text(&data, path, true)?;
    reader.read_to_end(&mut data).map_err(io_err)?;
    parse_record_bytes(&data, path, kind)
}

/// Parses a record from the raw bytes of a file, which must be UTF-8; `path` is used in
/// messages only.
pub fn parse_record_bytes(
    bytes: &[u8],
    path: &Path,
    kind: RecordKind,
) -> Result<Record, DatasetError> {
    if bytes.len() as u64 > MAX_FILE_BYTES {
        return Err(DatasetError::TooLarge {
            file: path.to_path_buf(),
            bytes: bytes.len() as u64,
            limit: MAX_FILE_BYTES,
        });
    }
    check_text(bytes, path, false)?;
    match std::str::from_utf8(bytes) {
        Ok(text) => parse_record(text, path, kind),
        // Not reached: `check_text` has found any invalid byte.
        Err(_) => Err(DatasetError::Encoding {
            file: path.to_path_buf(),
            line: 1,
            detail: "invalid UTF-8".into(),
        }),
    }
}

/// Checks that `bytes` are UTF-8 text without NUL bytes or a UTF-16 byte-order mark. With
/// `partial`, `bytes` are the start of a file and may end inside a character.
fn check_text(bytes: &[u8], path: &Path, partial: bool) -> Result<(), DatasetError> {
    if bytes.starts_with(&[0xff, 0xfe]) || bytes.starts_with(&[0xfe, 0xff]) {
        return Err(DatasetError::Encoding {
            file: path.to_path_buf(),
            line: 1,
            detail: "the file starts with a UTF-16 byte-order mark; save it as UTF-8".into(),
        });
    }
    let locate = |at: usize| {
        let before = &bytes[..at];
        let line = before.iter().filter(|&&b| b == b'\n').count() + 1;
        let line_start = before
            .iter()
            .rposition(|&b| b == b'\n')
            .map_or(0, |i| i + 1);
        (line, at - line_start + 1)
    };
    let invalid = match std::str::from_utf8(bytes) {
        Ok(_) => None,
        Err(e) if partial && e.error_len().is_none() => None,
        Err(e) => Some(e.valid_up_to()),
    };
    let nul = bytes.iter().position(|&b| b == 0);
    match (invalid, nul) {
        (Some(at), nul) if nul.is_none_or(|n| at < n) => {
            let (line, col) = locate(at);
            Err(DatasetError::Encoding {
                file: path.to_path_buf(),
                line,
                detail: format!(
                    "invalid byte 0x{:02x} at byte {col} of the line (byte offset {at} in the file)",
                    bytes[at]
                ),
            })
        }
        (_, Some(at)) => {
            let (line, col) = locate(at);
            Err(DatasetError::Encoding {
                file: path.to_path_buf(),
                line,
                detail: format!(
                    "a NUL byte (0x00) at byte {col} of the line (byte offset {at} in the file): \
                     this is not a text file"
                ),
            })
        }
        _ => Ok(()),
    }
}

/// Where each data row is in the file: rows are consecutive lines except after skipped
/// (blank or comment) lines, recorded as jumps.
struct LineMap {
    /// `(row index, line)` at the first row and wherever a row does not follow the previous
    /// row's line directly; increasing in both.
    jumps: Vec<(usize, usize)>,
}

impl LineMap {
    fn push(&mut self, row: usize, line: usize) {
        match self.jumps.last() {
            Some(&(r, l)) if l + (row - r) == line => {}
            _ => self.jumps.push((row, line)),
        }
    }

    fn line_of(&self, row: usize) -> usize {
        let k = self.jumps.partition_point(|&(r, _)| r <= row);
        match k.checked_sub(1).and_then(|k| self.jumps.get(k)) {
            Some(&(r, l)) => l + (row - r),
            None => 0,
        }
    }
}

/// Parses a record from CSV text (see the [module docs](self) for the format); `path` is
/// used in messages only.
pub fn parse_record(text: &str, path: &Path, kind: RecordKind) -> Result<Record, DatasetError> {
    parse_with_row_limit(text, path, kind, MAX_ROWS)
}

/// [`parse_record`] with a row limit (lowered in tests).
fn parse_with_row_limit(
    text: &str,
    path: &Path,
    kind: RecordKind,
    max_rows: usize,
) -> Result<Record, DatasetError> {
    let file = || path.to_path_buf();
    if text.len() as u64 > MAX_FILE_BYTES {
        return Err(DatasetError::TooLarge {
            file: file(),
            bytes: text.len() as u64,
            limit: MAX_FILE_BYTES,
        });
    }
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut lines = text
        .split('\n')
        .enumerate()
        .map(|(i, l)| (i + 1, l.strip_suffix('\r').unwrap_or(l)));

    // Preamble: comments, metadata, blank lines, then the header.
    let mut metadata = Vec::new();
    let mut warnings = Vec::new();
    let (header_line, header_text) = loop {
        let Some((n, line)) = lines.next() else {
            return Err(DatasetError::Empty {
                file: file(),
                detail: "no header row (the file has only comments or blank lines)".into(),
            });
        };
        if let Some(comment) = line.strip_prefix('#') {
            if let Some((k, v)) = comment.split_once(':') {
                let k = k.trim();
                if !k.is_empty() {
                    metadata.push((k.to_string(), v.trim().to_string()));
                }
            }
        } else if !line.trim().is_empty() {
            break (n, line);
        }
    };

    // Header: map each field to a column slot.
    let header: Vec<String> = header_text
        .split(',')
        .map(|h| unquote(h.trim_matches([' ', '\t'])).to_string())
        .collect();
    let n_fields = header.len();
    let mut slot_of_field: Vec<Option<usize>> = Vec::with_capacity(n_fields);
    let mut field_of_slot: [Option<usize>; COLUMNS.len()] = [None; COLUMNS.len()];
    let mut unknown = Vec::new();
    let mut seen: HashMap<&str, usize> = HashMap::with_capacity(n_fields);
    for (i, name) in header.iter().enumerate() {
        if let Some(&j) = seen.get(name.as_str()) {
            return Err(DatasetError::DuplicateColumn {
                file: file(),
                line: header_line,
                column: name.clone(),
                first: j + 1,
                second: i + 1,
            });
        }
        seen.insert(name, i);
        let slot = COLUMNS.iter().position(|c| c == name);
        match slot {
            Some(s) => field_of_slot[s] = Some(i),
            None => unknown.push(i),
        }
        slot_of_field.push(slot);
    }
    for &i in unknown.iter().take(MAX_UNKNOWN_WARNINGS) {
        warnings.push(format!(
            "line {header_line}: unknown column {} (field {}) ignored; known columns are {}",
            quote(&header[i]),
            i + 1,
            COLUMNS.join(", ")
        ));
    }
    if let Some(more) = unknown
        .len()
        .checked_sub(MAX_UNKNOWN_WARNINGS)
        .filter(|&m| m > 0)
    {
        warnings.push(format!(
            "line {header_line}: {more} more unknown column{} ignored",
            if more == 1 { "" } else { "s" }
        ));
    }
    let has = |c: &str| header.iter().any(|h| h == c);
    let missing = kind
        .required_columns()
        .iter()
        .find(|c| !has(c))
        .map(|c| vec![c.to_string()])
        .or_else(|| {
            let any = kind.one_of_columns();
            (!any.is_empty() && !any.iter().any(|c| has(c)))
                .then(|| any.iter().map(|c| c.to_string()).collect())
        });
    if let Some(columns) = missing {
        return Err(DatasetError::MissingColumn {
            file: file(),
            line: header_line,
            columns,
            kind,
            header,
        });
    }

    // Data rows.
    let header_offset = header_text.as_ptr() as usize - text.as_ptr() as usize;
    let capacity = text
        .get(header_offset..)
        .unwrap_or("")
        .bytes()
        .filter(|&b| b == b'\n')
        .count()
        .min(max_rows);
    let mut cols: [Option<Vec<f64>>; COLUMNS.len()] = Default::default();
    for (s, f) in field_of_slot.iter().enumerate() {
        if f.is_some() {
            cols[s] = Some(Vec::with_capacity(capacity));
        }
    }
    let limits: [f64; COLUMNS.len()] = COLUMNS.map(column_limit);
    let mut map = LineMap { jumps: Vec::new() };
    let mut rows = 0usize;
    let mut late_comments = 0usize;
    let mut first_late_comment = 0usize;
    let mut prev_t = f64::NEG_INFINITY;
    let mut prev_line = 0usize;
    for (n, line) in lines {
        if line.starts_with('#') {
            if late_comments == 0 {
                first_late_comment = n;
            }
            late_comments += 1;
            continue;
        }
        if line.trim().is_empty() {
            continue;
        }
        if rows == max_rows {
            return Err(DatasetError::TooManyRows {
                file: file(),
                line: n,
                limit: max_rows,
            });
        }
        let mut found = 0usize;
        for (i, cell) in line.split(',').enumerate() {
            found = i + 1;
            if i >= n_fields {
                break;
            }
            let Some(slot) = slot_of_field[i] else {
                continue;
            };
            let cell = cell.trim_matches([' ', '\t']);
            let value = parse_cell(cell, limits[slot]).map_err(|reason| DatasetError::Parse {
                file: file(),
                line: n,
                column: COLUMNS[slot].to_string(),
                value: shorten(cell),
                reason: match reason {
                    CellError::Beyond => format!(
                        "is beyond ±{} {}, the bound of column \"{}\" (SI units)",
                        crate::params::fmt_value(limits[slot]),
                        column_unit(COLUMNS[slot]),
                        COLUMNS[slot]
                    ),
                    CellError::Other(r) => r.to_string(),
                },
            })?;
            if slot == T {
                if value <= prev_t {
                    return Err(DatasetError::Time {
                        file: file(),
                        line: n,
                        reason: format!(
                            "t = {} s is not after the previous sample's t = {} s (line {prev_line}); \
                             t must be strictly increasing",
                            fmt_num(value),
                            fmt_num(prev_t)
                        ),
                    });
                }
                prev_t = value;
                prev_line = n;
            }
            if let Some(col) = cols[slot].as_mut() {
                col.push(value);
            }
        }
        if found != n_fields {
            let (found, column) = if found > n_fields {
                (line.split(',').count(), &header[n_fields - 1])
            } else {
                (found, &header[found])
            };
            return Err(DatasetError::FieldCount {
                file: file(),
                line: n,
                column: column.clone(),
                found,
                expected: n_fields,
                header_line,
                row: shorten(line),
            });
        }
        map.push(rows, n);
        rows += 1;
    }
    if late_comments > 0 {
        warnings.push(format!(
            "{late_comments} comment line{} after the header skipped (first at line {first_late_comment}); \
             metadata is read only before the header",
            if late_comments == 1 { "" } else { "s" }
        ));
    }
    if rows == 0 {
        return Err(DatasetError::Empty {
            file: file(),
            detail: format!("no data rows after the header (line {header_line})"),
        });
    }
    let [t, v_in, u, x, xdd, ydd, p1, p2] = cols;
    let t = t.unwrap_or_default();
    if t.len() < 2 {
        return Err(DatasetError::Time {
            file: file(),
            line: map.line_of(0),
            reason: "only one data row; at least two are needed to find the sample rate".into(),
        });
    }

    // Uniform sampling: dt is the median step, every step within tolerance.
    let mut steps: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
    let mid = steps.len() / 2;
    let (_, &mut dt, _) = steps.select_nth_unstable_by(mid, f64::total_cmp);
    drop(steps);
    let tol = DT_REL_TOLERANCE * dt + DT_ABS_TOLERANCE_S;
    if let Some(i) = t.windows(2).position(|w| ((w[1] - w[0]) - dt).abs() > tol) {
        let (a, b) = (t[i], t[i + 1]);
        return Err(DatasetError::Time {
            file: file(),
            line: map.line_of(i + 1),
            reason: format!(
                "the step from t = {} s (line {}) to t = {} s is {} s, but the record's step \
                 (the median) is {} s ± 1 %: the record is not uniformly sampled \
                 (a missing, repeated or shifted sample?)",
                fmt_num(a),
                map.line_of(i),
                fmt_num(b),
                sig(b - a),
                sig(dt)
            ),
        });
    }
    let rate_hz = 1.0 / dt;
    let (min, max) = kind.rate_range_hz();
    if !(rate_hz >= min * (1.0 - RATE_SLACK) && rate_hz <= max * (1.0 + RATE_SLACK)) {
        return Err(DatasetError::SampleRate {
            file: file(),
            rate_hz,
            min,
            max,
            kind,
        });
    }

    // Plausibility warnings.
    let peak = |c: &Option<Vec<f64>>| {
        c.as_ref().and_then(|c| {
            // The first of equal peaks.
            c.iter()
                .enumerate()
                .rev()
                .max_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))
                .map(|(i, v)| (map.line_of(i), *v))
        })
    };
    if let Some((line, v)) = peak(&u).filter(|(_, v)| v.abs() > RIG_HALF_STROKE_M) {
        let hint = if v.abs() > 1.0 {
            ": is it in millimetres instead of metres? (the format is SI)"
        } else {
            ""
        };
        warnings.push(format!(
            "column \"u\" reaches {} m at line {line}, far beyond the rig's stroke of \
             ±{} mm{hint}",
            sig(v),
            fmt_num(RIG_HALF_STROKE_M * 1e3)
        ));
    }
    if let Some((line, v)) = peak(&v_in).filter(|(_, v)| v.abs() > RIG_V_IN_MAX_V) {
        warnings.push(format!(
            "column \"v_in\" reaches {} V at line {line}, beyond the valve's ±{} V \
             (the twin saturates the command there)",
            sig(v),
            fmt_num(RIG_V_IN_MAX_V)
        ));
    }
    if let Some((_, v)) = metadata.iter().find(|(k, _)| k == "sample_rate_hz") {
        match v.parse::<f64>() {
            Ok(declared) if ((declared - rate_hz) / rate_hz).abs() <= DT_REL_TOLERANCE => {}
            _ => warnings.push(format!(
                "metadata sample_rate_hz: {} disagrees with the times, which give {} Hz",
                quote(v),
                sig(rate_hz)
            )),
        }
    }
    Ok(Record {
        path: file(),
        metadata,
        dt,
        t,
        v_in,
        u,
        x,
        xdd,
        ydd,
        p1,
        p2,
        warnings,
    })
}

/// Strips one pair of surrounding double quotes.
fn unquote(s: &str) -> &str {
    s.strip_prefix('"')
        .and_then(|s| s.strip_suffix('"'))
        .unwrap_or(s)
}

/// Why a cell was refused.
enum CellError {
    /// Beyond the column's limit.
    Beyond,
    /// Not a finite number (the reason).
    Other(&'static str),
}

/// Parses a trimmed cell as a finite number within `±limit`, or says why not.
#[inline]
fn parse_cell(cell: &str, limit: f64) -> Result<f64, CellError> {
    let v = match cell.parse::<f64>() {
        Ok(v) => v,
        Err(_) if cell.is_empty() => {
            return Err(CellError::Other("is empty; a number is expected"));
        }
        Err(_) => unquote(cell)
            .parse::<f64>()
            .map_err(|_| CellError::Other("is not a number"))?,
    };
    if !v.is_finite() {
        Err(CellError::Other("is not a finite number"))
    } else if v.abs() > limit {
        Err(CellError::Beyond)
    } else {
        Ok(v)
    }
}

/// Writes a record in the [module's format](self): `# key: value` lines, the header, then one
/// line per row, each number in its shortest text that reads back to the same `f64`.
///
/// Refuses (with [`io::ErrorKind::InvalidInput`]) what could not be read back the same: an
/// empty or repeated header name, a name or key with a comma, colon, `#` start or line
/// break, a row of the wrong length, a non-finite number, a number beyond the
/// [`column_limit`] of a known column.
pub fn write_csv<W: Write>(
    mut w: W,
    header: &[&str],
    comments: &[(String, String)],
    rows: impl Iterator<Item = Vec<f64>>,
) -> io::Result<()> {
    let mut out = CsvWriter::start(&mut w, header, comments)?;
    for row in rows {
        out.row(&mut w, &row)?;
    }
    Ok(())
}

/// A CSV record written row by row (what [`write_csv`] does in one call), for output that is
/// produced as it is written, such as a long simulation: memory does not grow with the rows.
#[derive(Debug)]
pub struct CsvWriter {
    header: Vec<String>,
    limits: Vec<f64>,
    line: String,
    rows: usize,
}

impl CsvWriter {
    /// Checks the header and comments (as [`write_csv`] does) and writes them.
    pub fn start<W: Write + ?Sized>(
        w: &mut W,
        header: &[&str],
        comments: &[(String, String)],
    ) -> io::Result<Self> {
        let breaks = |s: &str| s.contains(['\n', '\r']);
        if header.is_empty() {
            return Err(invalid("the header has no columns".into()));
        }
        for (i, h) in header.iter().enumerate() {
            let bad = h.is_empty()
                || h.trim_matches([' ', '\t']) != *h
                || h.contains([',', '"'])
                || h.starts_with('#')
                || breaks(h);
            if bad {
                return Err(invalid(format!("bad column name {h:?}")));
            }
            if header[..i].contains(h) {
                return Err(invalid(format!("column {h:?} appears twice")));
            }
        }
        for (k, v) in comments {
            if k.trim().is_empty() || k.trim() != k || k.contains(':') || breaks(k) || breaks(v) {
                return Err(invalid(format!("bad metadata entry {k:?}: {v:?}")));
            }
            writeln!(w, "# {k}: {}", v.trim())?;
        }
        writeln!(w, "{}", header.join(","))?;
        Ok(Self {
            header: header.iter().map(|h| h.to_string()).collect(),
            limits: header.iter().map(|h| column_limit(h)).collect(),
            line: String::with_capacity(32 * header.len()),
            rows: 0,
        })
    }

    /// Writes one row; refuses (nothing written) a row of the wrong length, a non-finite
    /// number or one beyond its column's [`column_limit`].
    pub fn row<W: Write + ?Sized>(&mut self, w: &mut W, row: &[f64]) -> io::Result<()> {
        let r = self.rows + 1;
        if row.len() != self.header.len() {
            return Err(invalid(format!(
                "row {r} has {} values, the header has {} columns",
                row.len(),
                self.header.len()
            )));
        }
        self.line.clear();
        for (i, &v) in row.iter().enumerate() {
            if !v.is_finite() {
                return Err(invalid(format!(
                    "row {r}, column {:?}: {v} is not a finite number",
                    self.header[i]
                )));
            }
            if v.abs() > self.limits[i] {
                return Err(invalid(format!(
                    "row {r}, column {:?}: {} is beyond the column's bound ±{}",
                    self.header[i],
                    fmt_num(v),
                    crate::params::fmt_value(self.limits[i])
                )));
            }
            if i > 0 {
                self.line.push(',');
            }
            let _ = write_num(&mut self.line, v);
        }
        self.line.push('\n');
        w.write_all(self.line.as_bytes())?;
        self.rows += 1;
        Ok(())
    }

    /// Rows written so far.
    pub fn rows(&self) -> usize {
        self.rows
    }
}

fn invalid(msg: String) -> io::Error {
    io::Error::new(io::ErrorKind::InvalidInput, msg)
}

/// Writes a record like [`write_csv`] to `path`, atomically
/// ([`crate::fsutil::write_atomic`]): into a temporary file in the same directory, flushed to
/// disk, then renamed over `path`. On any error (including a refused row) `path` is left as it
/// was and the temporary file is removed.
pub fn write_csv_atomic(
    path: &Path,
    header: &[&str],
    comments: &[(String, String)],
    rows: impl Iterator<Item = Vec<f64>>,
) -> io::Result<()> {
    crate::fsutil::write_atomic(path, |w| write_csv(w, header, comments, rows))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p() -> &'static Path {
        Path::new("ride.csv")
    }

    fn err(text: &str, kind: RecordKind) -> DatasetError {
        match parse_record(text, p(), kind) {
            Ok(r) => panic!("expected an error, got a record of {} rows", r.len()),
            Err(e) => e,
        }
    }

    const GOOD: &str = "# experiment: sine 5 Hz 0.72 V\n# sample_rate_hz: 1000\n\
        t,v_in,u,x,xdd,ydd\n\
        0.000,0.72,0,1.83747616e-05,-0.097796809,0.197458573\n\
        0.001,0.72,0.01,1e-5,0.01,0.2\n\
        0.002,0.72,0.02,2e-5,0.02,0.3\n\
        0.003,0.72,0.03,3e-5,0.03,0.4\n";

    #[test]
    fn parses_the_example() {
        let r = parse_record(GOOD, p(), RecordKind::Measured).unwrap();
        assert_eq!(r.len(), 4);
        assert!(!r.is_empty());
        assert!((r.sample_rate_hz() - 1000.0).abs() < 1e-6);
        assert!((r.duration_s() - 0.003).abs() < 1e-12);
        assert_eq!(r.metadata_value("experiment"), Some("sine 5 Hz 0.72 V"));
        assert_eq!(r.metadata_value("sample_rate_hz"), Some("1000"));
        assert_eq!(r.metadata_value("nope"), None);
        assert_eq!(r.x.as_ref().unwrap()[0], 1.83747616e-05);
        assert_eq!(r.ydd.as_ref().unwrap()[3], 0.4);
        assert!(r.p1.is_none() && r.p2.is_none());
        assert!(r.warnings.is_empty(), "{:?}", r.warnings);
        assert_eq!(r.column("u"), Some(&[0.0, 0.01, 0.02, 0.03][..]));
        let e = parse_record(GOOD, p(), RecordKind::Excitation).unwrap();
        assert_eq!(e.len(), 4);
    }

    #[test]
    fn crlf_bom_blank_lines_padding_any_order_and_unknown_columns() {
        let text = "\u{feff}# a: 1\r\n\r\n#plain comment\r\n xdd , t ,foo\r\n\r\n5, 0.5 ,bar\r\n1,0.6,\r\n\r\n# late\r\n2,0.7,x\r\n";
        let r = parse_record(text, p(), RecordKind::Excitation).unwrap();
        assert_eq!(r.t, vec![0.5, 0.6, 0.7]);
        assert_eq!(r.xdd, Some(vec![5.0, 1.0, 2.0]));
        assert_eq!(r.metadata, vec![("a".to_string(), "1".to_string())]);
        assert_eq!(r.warnings.len(), 2, "{:?}", r.warnings);
        assert!(r.warnings[0].contains("unknown column \"foo\" (field 3) ignored"));
        assert!(
            r.warnings[1].contains("1 comment line after the header skipped (first at line 9)")
        );
    }

    #[test]
    fn io_error_names_the_file() {
        let e = read_record(Path::new("/nonexistent/ride.csv"), RecordKind::Measured).unwrap_err();
        assert!(matches!(e, DatasetError::Io { .. }));
        assert!(
            e.to_string()
                .starts_with("/nonexistent/ride.csv: cannot read"),
            "{e}"
        );
    }

    #[test]
    fn empty_files() {
        for text in ["", "\n\n", "# a: b\n# c\n\n"] {
            let e = err(text, RecordKind::Measured);
            assert!(matches!(e, DatasetError::Empty { .. }), "{e}");
            assert_eq!(
                e.to_string(),
                "ride.csv: no header row (the file has only comments or blank lines)"
            );
        }
        let e = err("# a: b\nt,v_in,u\n\n", RecordKind::Measured);
        assert!(matches!(e, DatasetError::Empty { .. }));
        assert_eq!(
            e.to_string(),
            "ride.csv: no data rows after the header (line 2)"
        );
    }

    #[test]
    fn missing_columns() {
        let e = err("# x\nt,v_in,x\n0,0,0\n", RecordKind::Measured);
        assert!(matches!(e, DatasetError::MissingColumn { .. }));
        assert_eq!(
            e.to_string(),
            "ride.csv: line 2: missing column \"u\" (a measured record needs t, v_in and u); \
             the header has \"t\", \"v_in\", \"x\""
        );
        let e = err("t,v_in,u\n0,0,0\n", RecordKind::Excitation);
        assert_eq!(
            e.to_string(),
            "ride.csv: line 1: missing column \"x\" or \"xdd\" (an excitation record needs t and \
             at least one of x, xdd); the header has \"t\", \"v_in\", \"u\""
        );
        let e = err("0,1,2\n1,1,2\n", RecordKind::Excitation);
        assert!(e.to_string().contains("missing column \"t\""), "{e}");
        assert!(e.to_string().contains("is the header row missing?"), "{e}");
    }

    #[test]
    fn duplicate_column() {
        let e = err("# m: 1\nt,x,xdd,x\n0,0,0,0\n", RecordKind::Excitation);
        assert!(matches!(e, DatasetError::DuplicateColumn { .. }));
        assert_eq!(
            e.to_string(),
            "ride.csv: line 2: column \"x\" appears twice in the header (fields 2 and 4)"
        );
        // A very wide header is handled in linear time.
        let wide: Vec<String> = (0..200_000).map(|i| format!("c{i}")).collect();
        let e = err(
            &format!("t,{},c7\n", wide.join(",")),
            RecordKind::Excitation,
        );
        assert!(e.to_string().contains("(fields 9 and 200002)"), "{e}");
        // Unknown names may not repeat either.
        let e = err("t,x,foo,foo\n0,0,0,0\n", RecordKind::Excitation);
        assert!(matches!(e, DatasetError::DuplicateColumn { .. }), "{e}");
    }

    #[test]
    fn parse_errors_name_line_and_column() {
        let mut text = String::from("# a: 1\n\nt,v_in,u,x,xdd,ydd\n");
        for i in 0..10 {
            let ydd = if i == 7 {
                "abc".to_string()
            } else {
                "0.5".into()
            };
            text.push_str(&format!("{}.{:03},1,2,3,4,{ydd}\n", i / 1000, i % 1000));
        }
        let e = err(&text, RecordKind::Measured);
        assert!(matches!(e, DatasetError::Parse { .. }));
        assert_eq!(
            e.to_string(),
            "ride.csv: line 11, column \"ydd\": \"abc\" is not a number"
        );

        let cases = [
            (
                "t,x\n0,1\n0.1,nan\n",
                "line 3, column \"x\": \"nan\" is not a finite number",
            ),
            (
                "t,x\n0,1\n0.1,-inf\n",
                "line 3, column \"x\": \"-inf\" is not a finite number",
            ),
            (
                "t,x\n0,1\n0.1,1e999\n",
                "line 3, column \"x\": \"1e999\" is not a finite number",
            ),
            (
                "t,x\n0,1\n0.1,\n",
                "line 3, column \"x\": \"\" is empty; a number is expected",
            ),
            (
                "t,x\n0,1\n0.1, \n",
                "line 3, column \"x\": \"\" is empty; a number is expected",
            ),
            (
                "t,x\n0,1\nNaN,1\n",
                "line 3, column \"t\": \"NaN\" is not a finite number",
            ),
            (
                "t,x\n0,1\n0.1,2e3\n",
                "line 3, column \"x\": \"2e3\" is beyond ±1000 m, the bound of column \"x\" \
                 (SI units)",
            ),
            (
                "t,x\n0,1\n-1e10,2\n",
                "line 3, column \"t\": \"-1e10\" is beyond ±1e9 s, the bound of column \"t\" \
                 (SI units)",
            ),
        ];
        for (text, msg) in cases {
            let e = err(text, RecordKind::Excitation);
            assert!(matches!(e, DatasetError::Parse { .. }), "{e}");
            assert_eq!(e.to_string(), format!("ride.csv: {msg}"));
        }
        let field_counts = [
            (
                "t,x\n0,1\n0.1,1,2\n",
                "line 3: fields past the last column \"x\" are not expected: the row \"0.1,1,2\" \
                 has 3 fields, the header (line 1) has 2",
            ),
            (
                "t,x\n0,1\n0.1\n",
                "line 3: column \"x\" is missing: the row \"0.1\" has 1 field, the header \
                 (line 1) has 2",
            ),
            (
                "t,x,note\n0,1,a\n0.1,2,b,4,5\n",
                "line 3: fields past the last column \"note\" are not expected: the row \
                 \"0.1,2,b,4,5\" has 5 fields, the header (line 1) has 3",
            ),
        ];
        for (text, msg) in field_counts {
            let e = err(text, RecordKind::Excitation);
            assert!(matches!(e, DatasetError::FieldCount { .. }), "{e}");
            assert_eq!(e.to_string(), format!("ride.csv: {msg}"));
        }
        // Long cells are shortened in the message.
        let long = "z".repeat(10_000);
        let e = err(&format!("t,x\n0,1\n0.1,{long}\n"), RecordKind::Excitation);
        assert!(e.to_string().len() < 200, "{e}");
    }

    #[test]
    fn many_unknown_columns_give_few_warnings() {
        let names: Vec<String> = (0..25).map(|i| format!("c{i}")).collect();
        let text = format!(
            "t,{},x\n0,{z},1\n0.1,{z},2\n",
            names.join(","),
            z = ["0"; 25].join(",")
        );
        let r = parse_record(&text, p(), RecordKind::Excitation).unwrap();
        assert_eq!(r.warnings.len(), 11, "{:?}", r.warnings);
        assert!(r.warnings[9].contains("unknown column \"c9\" (field 11)"));
        assert_eq!(r.warnings[10], "line 1: 15 more unknown columns ignored");
    }

    #[test]
    fn unknown_columns_are_not_read() {
        let r = parse_record("t,note,x\n0,hello,1\n0.1,,2\n", p(), RecordKind::Excitation).unwrap();
        assert_eq!(r.x, Some(vec![1.0, 2.0]));
        assert_eq!(r.warnings.len(), 1);
    }

    #[test]
    fn quoted_cells_are_accepted() {
        let r = parse_record(
            "\"t\",\"x\"\n\"0\",\"1\"\n0.1,2\n",
            p(),
            RecordKind::Excitation,
        )
        .unwrap();
        assert_eq!(r.t, vec![0.0, 0.1]);
        assert_eq!(r.x, Some(vec![1.0, 2.0]));
    }

    #[test]
    fn time_errors() {
        let e = err("t,x\n# c\n0,0\n0.1,0\n0.1,0\n", RecordKind::Excitation);
        assert!(matches!(e, DatasetError::Time { .. }));
        assert_eq!(
            e.to_string(),
            "ride.csv: line 5: t = 0.1 s is not after the previous sample's t = 0.1 s (line 4); \
             t must be strictly increasing"
        );
        let e = err("t,x\n0.2,0\n0.1,0\n", RecordKind::Excitation);
        assert!(
            e.to_string()
                .starts_with("ride.csv: line 3: t = 0.1 s is not after"),
            "{e}"
        );

        // A missing sample: the step from 0.003 to 0.005 at line 8 (blank and comment lines
        // in between are counted).
        let text = "# c\nt,v_in,u\n0.000,0,0\n0.001,0,0\n\n0.002,0,0\n0.003,0,0\n# x\n0.005,0,0\n0.006,0,0\n";
        let e = err(text, RecordKind::Measured);
        assert!(matches!(e, DatasetError::Time { line: 9, .. }), "{e:?}");
        assert_eq!(
            e.to_string(),
            "ride.csv: line 9: the step from t = 0.003 s (line 7) to t = 0.005 s is 0.002 s, \
             but the record's step (the median) is 0.001 s ± 1 %: the record is not uniformly \
             sampled (a missing, repeated or shifted sample?)"
        );
        let e = err("t,x\n0,0\n", RecordKind::Excitation);
        assert_eq!(
            e.to_string(),
            "ride.csv: line 2: only one data row; at least two are needed to find the sample rate"
        );
    }

    #[test]
    fn rounded_times_are_uniform_enough() {
        // 3 kHz printed to 1 µs: steps of 333 and 334 µs (0.3 % apart).
        let mut text = String::from("t,v_in,u\n");
        for i in 0..3000 {
            text.push_str(&format!("{:.6},0,0\n", i as f64 / 3000.0));
        }
        let r = parse_record(&text, p(), RecordKind::Measured).unwrap();
        assert!((r.sample_rate_hz() - 3000.0).abs() < 10.0);
        // 10 kHz printed to 0.1 ms from a large offset: exact enough.
        let mut text = String::from("t,v_in,u\n");
        for i in 0..1000 {
            text.push_str(&format!("{:.4},0,0\n", 1000.0 + i as f64 * 1e-4));
        }
        let r = parse_record(&text, p(), RecordKind::Measured).unwrap();
        assert!((r.sample_rate_hz() - 10_000.0).abs() < 1e-3);
    }

    #[test]
    fn sample_rate_limits() {
        let make = |rate: f64| {
            let mut s = String::from("t,v_in,u,x\n");
            for i in 0..5 {
                s.push_str(&format!("{},0,0,0\n", i as f64 / rate));
            }
            s
        };
        let e = err(&make(100.0), RecordKind::Measured);
        assert!(matches!(e, DatasetError::SampleRate { .. }));
        assert_eq!(
            e.to_string(),
            "ride.csv: sample rate 100 Hz (step 0.01 s) is outside 200 ..= 10000 Hz allowed for \
             a measured record"
        );
        assert!(parse_record(&make(100.0), p(), RecordKind::Excitation).is_ok());
        assert!(parse_record(&make(200.0), p(), RecordKind::Measured).is_ok());
        assert!(parse_record(&make(10_000.0), p(), RecordKind::Measured).is_ok());
        assert!(parse_record(&make(10.0), p(), RecordKind::Excitation).is_ok());
        assert!(parse_record(&make(100_000.0), p(), RecordKind::Excitation).is_ok());
        let e = err(&make(20_000.0), RecordKind::Measured);
        assert!(
            e.to_string()
                .contains("sample rate 20000 Hz (step 0.00005 s)"),
            "{e}"
        );
        let e = err(&make(5.0), RecordKind::Excitation);
        assert!(
            e.to_string()
                .ends_with("outside 10 ..= 100000 Hz allowed for an excitation record"),
            "{e}"
        );
        assert!(matches!(
            err(&make(200_000.0), RecordKind::Excitation),
            DatasetError::SampleRate { .. }
        ));
    }

    #[test]
    fn metadata_rate_mismatch_is_a_warning() {
        let text = "# sample_rate_hz: 500\nt,v_in,u\n0,0,0\n0.001,0,0\n0.002,0,0\n";
        let r = parse_record(text, p(), RecordKind::Measured).unwrap();
        assert_eq!(r.warnings.len(), 1);
        assert!(
            r.warnings[0].contains("sample_rate_hz: \"500\" disagrees"),
            "{:?}",
            r.warnings
        );
    }

    #[test]
    fn encoding_errors() {
        let e =
            parse_record_bytes(b"t,x\n0,1\n0.1,\xff\n", p(), RecordKind::Excitation).unwrap_err();
        assert!(matches!(e, DatasetError::Encoding { line: 3, .. }), "{e:?}");
        assert_eq!(
            e.to_string(),
            "ride.csv: line 3: not UTF-8 text: invalid byte 0xff at byte 5 of the line \
             (byte offset 12 in the file)"
        );
        let e = parse_record_bytes(b"\xff\xfet\x00", p(), RecordKind::Excitation).unwrap_err();
        assert!(e.to_string().contains("UTF-16"), "{e}");
        let e = parse_record_bytes(b"t,x\n0,\x001\n", p(), RecordKind::Excitation).unwrap_err();
        assert_eq!(
            e.to_string(),
            "ride.csv: line 2: not UTF-8 text: a NUL byte (0x00) at byte 3 of the line \
             (byte offset 6 in the file): this is not a text file"
        );
        // Through a real file.
        let dir = tempfile::tempdir().unwrap();
        let f = dir.path().join("bad.csv");
        std::fs::write(&f, b"# caf\xe9\nt,x\n").unwrap();
        let e = read_record(&f, RecordKind::Excitation).unwrap_err();
        assert!(e.to_string().contains("bad.csv: line 1: not UTF-8"), "{e}");
    }

    #[test]
    fn too_large_file_is_refused_before_reading() {
        let dir = tempfile::tempdir().unwrap();
        let f = dir.path().join("huge.csv");
        let file = File::create(&f).unwrap();
        // A sparse file: no disk space used, and never read.
        file.set_len(MAX_FILE_BYTES + 1).unwrap();
        let e = read_record(&f, RecordKind::Measured).unwrap_err();
        assert!(matches!(e, DatasetError::TooLarge { .. }), "{e}");
        assert!(
            e.to_string().ends_with(
                "huge.csv: 536870913 bytes is over the limit of 536870912 bytes (512 MiB)"
            ),
            "{e}"
        );
    }

    #[test]
    fn plausibility_warnings() {
        let text = "t,v_in,u\n0,0,0\n0.001,-12.5,0.02\n0.002,3,-30\n0.003,0,0\n";
        let r = parse_record(text, p(), RecordKind::Measured).unwrap();
        assert_eq!(
            r.warnings,
            vec![
                "column \"u\" reaches -30 m at line 4, far beyond the rig's stroke of ±35 mm: \
                 is it in millimetres instead of metres? (the format is SI)"
                    .to_string(),
                "column \"v_in\" reaches -12.5 V at line 3, beyond the valve's ±10 V (the twin \
                 saturates the command there)"
                    .to_string(),
            ]
        );
        let text = "t,v_in,u\n0,10,0.035\n0.001,-10,-0.035\n";
        let r = parse_record(text, p(), RecordKind::Measured).unwrap();
        assert!(r.warnings.is_empty(), "{:?}", r.warnings);
    }

    #[test]
    fn devices_and_binary_files_fail_after_a_short_read() {
        let e = read_record(Path::new("/dev/zero"), RecordKind::Measured).unwrap_err();
        assert!(
            e.to_string()
                .starts_with("/dev/zero: line 1: not UTF-8 text: a NUL byte"),
            "{e}"
        );
        let e = read_record(Path::new("/dev/urandom"), RecordKind::Measured).unwrap_err();
        assert!(matches!(e, DatasetError::Encoding { .. }), "{e}");
        let e = read_record(Path::new("/"), RecordKind::Measured).unwrap_err();
        assert_eq!(
            e.to_string(),
            "/: cannot read: is a directory, not a CSV file"
        );
    }

    #[test]
    fn too_many_rows() {
        let text = "# a\nt,x\n0,0\n0.1,0\n\n0.2,0\n0.3,0\n";
        assert!(parse_with_row_limit(text, p(), RecordKind::Excitation, 4).is_ok());
        let e = parse_with_row_limit(text, p(), RecordKind::Excitation, 3).unwrap_err();
        assert!(matches!(e, DatasetError::TooManyRows { .. }), "{e}");
        assert_eq!(e.to_string(), "ride.csv: line 7: more than 3 data rows");
    }

    #[test]
    fn line_map() {
        let mut m = LineMap { jumps: Vec::new() };
        for (row, line) in [(0, 5), (1, 6), (2, 8), (3, 9), (4, 12)] {
            m.push(row, line);
        }
        assert_eq!(m.jumps, vec![(0, 5), (2, 8), (4, 12)]);
        let lines: Vec<usize> = (0..5).map(|r| m.line_of(r)).collect();
        assert_eq!(lines, vec![5, 6, 8, 9, 12]);
    }

    #[test]
    fn number_formats() {
        for x in [
            0.0,
            -0.0,
            1.0,
            0.1,
            1e-5,
            9.99e-6,
            1e15,
            123456.789,
            -2.5e-300,
            f64::MAX,
            f64::MIN_POSITIVE,
            5e-324,
        ] {
            let s = fmt_num(x);
            assert_eq!(
                s.parse::<f64>().unwrap().to_bits(),
                x.to_bits(),
                "{x} -> {s}"
            );
            assert!(s.len() < 30, "{s}");
        }
        assert_eq!(sig(0.0015000000000000013), "0.0015");
        assert_eq!(sig(20_000.000000001), "20000");
    }

    #[test]
    fn round_trip_through_write_csv_atomic() {
        let dir = tempfile::tempdir().unwrap();
        let f = dir.path().join("out.csv");
        let header = ["t", "v_in", "u", "x", "xdd", "ydd", "p1", "p2"];
        let comments = vec![
            ("experiment".to_string(), "round trip: a, b".to_string()),
            ("sample_rate_hz".to_string(), "2000".to_string()),
        ];
        let rows: Vec<Vec<f64>> = (0..500)
            .map(|i| {
                let t = i as f64 / 2000.0;
                vec![
                    t,
                    (t * 7.0).sin(),
                    1e-7 * i as f64,
                    -3.3e-20,
                    1.0 / 3.0,
                    1e6,
                    2.0e5 + t,
                    -0.0,
                ]
            })
            .collect();
        write_csv_atomic(&f, &header, &comments, rows.clone().into_iter()).unwrap();
        let r = read_record(&f, RecordKind::Measured).unwrap();
        assert_eq!(r.metadata, comments);
        assert!(r.warnings.is_empty(), "{:?}", r.warnings);
        assert_eq!(r.len(), 500);
        for (j, name) in header.iter().enumerate() {
            let col = r.column(name).unwrap();
            for (i, row) in rows.iter().enumerate() {
                assert_eq!(col[i].to_bits(), row[j].to_bits(), "{name}[{i}]");
            }
        }
        // Only the target file is left in the directory.
        let names: Vec<_> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names, vec![std::ffi::OsString::from("out.csv")]);
    }

    #[test]
    fn write_refuses_what_would_not_read_back_and_leaves_the_old_file() {
        let dir = tempfile::tempdir().unwrap();
        let f = dir.path().join("keep.csv");
        std::fs::write(&f, "old").unwrap();
        let ok_rows = || vec![vec![0.0, 1.0]].into_iter();
        type Case = (Vec<&'static str>, Vec<(String, String)>, Vec<Vec<f64>>);
        let bad: Vec<Case> = vec![
            (vec![], vec![], vec![]),
            (vec!["t", "t"], vec![], vec![]),
            (vec!["t", "a,b"], vec![], vec![]),
            (vec!["t", "#x"], vec![], vec![]),
            (vec!["t", ""], vec![], vec![]),
            (vec!["t", "x"], vec![("a:b".into(), "c".into())], vec![]),
            (vec!["t", "x"], vec![("a".into(), "c\nd".into())], vec![]),
            (vec!["t", "x"], vec![], vec![vec![0.0, 1.0], vec![0.1]]),
            (
                vec!["t", "x"],
                vec![],
                vec![vec![0.0, 1.0], vec![0.1, f64::NAN]],
            ),
            (
                vec!["t", "x"],
                vec![],
                vec![vec![0.0, 1.0], vec![0.1, 1e300]],
            ),
        ];
        for (h, c, rows) in bad {
            let e = write_csv_atomic(&f, &h, &c, rows.into_iter()).unwrap_err();
            assert_eq!(e.kind(), io::ErrorKind::InvalidInput, "{e}");
            assert_eq!(std::fs::read_to_string(&f).unwrap(), "old");
        }
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
        write_csv_atomic(&f, &["t", "x"], &[], ok_rows()).unwrap();
        assert_eq!(std::fs::read_to_string(&f).unwrap(), "t,x\n0,1\n");
        // A missing directory is an error, not a panic.
        assert!(
            write_csv_atomic(Path::new("/nonexistent-dir/x.csv"), &["t"], &[], ok_rows()).is_err()
        );
    }

    #[test]
    fn demo_campaign_files_parse() {
        let dir = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/assets/demo-campaign"));
        if !dir.is_dir() {
            println!(
                "note: {} not found; demo-campaign check skipped",
                dir.display()
            );
            return;
        }
        let expected = [
            ("bump.csv", 6001),
            ("ride.csv", 30001),
            ("sine_01hz_0.72v.csv", 6001),
            ("sine_02hz_2.10v.csv", 3001),
            ("sine_05hz_0.72v.csv", 3001),
            ("sine_05hz_4.50v.csv", 3001),
            ("sine_10hz_1.10v.csv", 3001),
            ("sine_10hz_6.40v.csv", 3001),
            ("sine_15hz_3.00v.csv", 3001),
            ("sine_20hz_0.72v.csv", 3001),
        ];
        for (name, rows) in expected {
            let f = dir.join(name);
            let r = read_record(&f, RecordKind::Measured).unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(r.len(), rows, "{name}");
            assert!(
                (r.sample_rate_hz() - 1000.0).abs() < 1e-6,
                "{name}: {}",
                r.sample_rate_hz()
            );
            assert!(r.warnings.is_empty(), "{name}: {:?}", r.warnings);
            assert_eq!(r.metadata_value("sample_rate_hz"), Some("1000"));
            for c in ["v_in", "u", "x", "xdd", "ydd"] {
                assert_eq!(r.column(c).map(<[f64]>::len), Some(rows), "{name} {c}");
            }
            assert!(r.p1.is_none() && r.p2.is_none());
            let dur: f64 = r.metadata_value("duration_s").unwrap().parse().unwrap();
            assert!((r.duration_s() - dur).abs() < 1e-9, "{name}");
            let x = read_record(&f, RecordKind::Excitation).unwrap_or_else(|e| panic!("{e}"));
            assert!(x.warnings.is_empty(), "{name}: {:?}", x.warnings);
        }
    }

    #[test]
    fn parses_600k_rows_by_7_columns_quickly() {
        // 60 s at 10 kHz; a tenth of it in unoptimised builds, where it is only checked.
        let rate = 10_000.0;
        let n = if cfg!(debug_assertions) {
            60_000
        } else {
            600_000
        };
        let mut text = String::with_capacity(n * 90);
        text.push_str("# sample_rate_hz: 10000\nt,v_in,u,x,xdd,ydd,p1\n");
        for i in 0..n {
            let t = i as f64 / rate;
            let s = (t * 31.4).sin();
            let _ = writeln!(
                text,
                "{:.4},{:.6},{:.6e},{:.6e},{:.6},{:.6},{:.1}",
                t,
                0.72 * s,
                1e-3 * s,
                2e-5 * s,
                0.3 * s,
                1.1 * s,
                2.0e6 + 1e5 * s
            );
        }
        let start = std::time::Instant::now();
        let r = parse_record(&text, p(), RecordKind::Measured).unwrap();
        let took = start.elapsed();
        assert_eq!(r.len(), n);
        assert!((r.duration_s() - (n - 1) as f64 / rate).abs() < 1e-6);
        println!(
            "parsed {} MB, {n} rows x 7 columns in {took:?}",
            text.len() / 1_000_000
        );
        if !cfg!(debug_assertions) {
            assert!(took.as_secs_f64() < 1.0, "took {took:?}");
        }
    }
}
