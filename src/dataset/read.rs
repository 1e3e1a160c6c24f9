//! Reading a record: file access, the text checks, and parsing of the header and rows.

use super::columns::{COLUMNS, RecordKind, T, column_limit, column_unit};
use super::error::{DatasetError, fmt_num, quote, shorten};
use super::lines::LineMap;
use super::{MAX_FILE_BYTES, MAX_ROWS, Record, validate};
use std::collections::HashMap;
use std::io::{self, Read};
use std::path::Path;

/// Unknown columns warned about one by one; the rest are summed up in one warning.
const MAX_UNKNOWN_WARNINGS: usize = 10;
/// Bytes [`read_record`] reads and checks for text before it reads the rest, so that a device
/// or a binary file fails at once.
const PROBE_BYTES: u64 = 64 * 1024;

/// Reads a record from a CSV file (see the [module docs](super) for the format).
///
/// Files over [`MAX_FILE_BYTES`] are refused before reading; a file that is not text (a
/// binary file, `/dev/zero`, `/dev/urandom`) is refused after its first 64 KiB.
pub fn read_record(path: &Path, kind: RecordKind) -> Result<Record, DatasetError> {
    let io_err = |error| DatasetError::Io {
        file: path.to_path_buf(),
        error,
    };
    let file = crate::fsutil::open_input(path).map_err(io_err)?;
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
    let locate = |at: usize| crate::fsutil::line_column(bytes, at);
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
                    "invalid byte 0x{:02x} at character {col} of the line (byte offset {at} in the file)",
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
                    "a NUL byte (0x00) at character {col} of the line (byte offset {at} in the file): \
                     this is not a text file"
                ),
            })
        }
        _ => Ok(()),
    }
}

/// Byte offset of the first `\r` not followed by `\n`, if any.
fn lone_carriage_return(bytes: &[u8]) -> Option<usize> {
    let mut from = 0;
    while let Some(i) = bytes[from..].iter().position(|&b| b == b'\r') {
        let at = from + i;
        if bytes.get(at + 1) != Some(&b'\n') {
            return Some(at);
        }
        from = at + 1;
    }
    None
}

/// Parses a record from CSV text (see the [module docs](super) for the format); `path` is
/// used in messages only.
pub fn parse_record(text: &str, path: &Path, kind: RecordKind) -> Result<Record, DatasetError> {
    parse_with_row_limit(text, path, kind, MAX_ROWS)
}

/// [`parse_record`] with a row limit (lowered in tests).
pub(super) fn parse_with_row_limit(
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
    if let Some(at) = lone_carriage_return(text.as_bytes()) {
        return Err(DatasetError::LoneCarriageReturn {
            file: file(),
            line: crate::fsutil::line_column(text.as_bytes(), at).0,
        });
    }
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
                        crate::format::general(limits[slot]),
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

    let dt = validate::sample_step(&t, &map, kind, path)?;
    warnings.extend(validate::plausibility_warnings(
        u.as_deref(),
        v_in.as_deref(),
        &metadata,
        1.0 / dt,
        &map,
    ));
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
