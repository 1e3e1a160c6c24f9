//! Why a record could not be read, and the pieces of its messages (quoted cells, numbers).

use super::columns::RecordKind;
use std::fmt::Write as _;
use std::io;
use std::path::{Path, PathBuf};

/// Longest cell or row text quoted in a message, in characters.
const QUOTE_CHARS: usize = 60;

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
    /// A carriage return with no line feed after it: CR-only (classic Mac) line ends, which
    /// would make the whole file one line.
    #[error(
        "{file}: line {line}: a carriage return (CR) with no line feed after it: the file has \
         CR-only line ends; save it with LF or CR LF line ends"
    )]
    LoneCarriageReturn {
        /// The file.
        file: PathBuf,
        /// 1-based line (counting LF line ends) of the first lone CR.
        line: usize,
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
    /// A cell is not a finite number, or beyond its column's [`column_limit`](super::column_limit).
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
    #[error("{file}: line {line}{}: {reason}", column.map(|c| format!(", column \"{c}\"")).unwrap_or_default())]
    Time {
        /// The file.
        file: PathBuf,
        /// 1-based line of the offending sample.
        line: usize,
        /// The time column's name where the fault is in its values (`t`), else `None`.
        column: Option<&'static str>,
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
    /// The file is larger than [`MAX_FILE_BYTES`](super::MAX_FILE_BYTES); refused before reading.
    #[error("{file}: {bytes} bytes is over the limit of {limit} bytes (512 MiB)")]
    TooLarge {
        /// The file.
        file: PathBuf,
        /// Its size \[bytes\].
        bytes: u64,
        /// The limit \[bytes\].
        limit: u64,
    },
    /// The record has more than [`MAX_ROWS`](super::MAX_ROWS) data rows.
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
pub(super) fn quote(s: &str) -> String {
    format!("{:?}", shorten(s))
}

pub(super) fn shorten(s: &str) -> String {
    match s.char_indices().nth(QUOTE_CHARS) {
        Some((i, _)) => format!("{}…", &s[..i]),
        None => s.to_string(),
    }
}

/// A number with 6 significant digits, printed without trailing noise.
pub(super) fn sig(x: f64) -> String {
    if !x.is_finite() {
        return format!("{x}");
    }
    let rounded: f64 = format!("{x:.5e}").parse().unwrap_or(x);
    fmt_num(rounded)
}

/// Shortest round-trip text of a finite `f64` (the one formatter's [`crate::format::exact`]).
pub(super) use crate::format::{exact as fmt_num, write_exact as write_num};
