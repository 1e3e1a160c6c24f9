//! Reading a record: file access, the text checks, and parsing of the header and rows.
//!
//! A file is read twice, in bounded memory: a first pass checks that it is text (UTF-8, no
//! NUL byte, no lone carriage return) and counts its lines, so that the columns are allocated
//! once at their final size; the second parses it line by line. Only the columns asked for
//! are stored (8 bytes a row each); the file's text is never held whole. In-memory text
//! ([`parse_record`], [`parse_record_bytes`]) goes through the same checks and the same
//! parser.

use super::columns::{COLUMNS, RecordKind, T, column_limit, column_unit};
use super::error::{DatasetError, fmt_num, quote, shorten};
use super::lines::LineMap;
use super::{MAX_FILE_BYTES, MAX_ROWS, Record, validate};
use std::collections::HashMap;
use std::io::{self, BufRead, BufReader, Read, Seek};
use std::path::Path;

/// Unknown columns warned about one by one; the rest are summed up in one warning.
const MAX_UNKNOWN_WARNINGS: usize = 10;
/// Bytes the text check reads at a time, so that a device or a binary file fails after its
/// first 64 KiB.
const SCAN_CHUNK: usize = 64 * 1024;
/// Slot of `v_in` in [`COLUMNS`].
const V_IN: usize = 1;
/// Slot of `u` in [`COLUMNS`].
const U: usize = 2;

/// What to keep of a record and how many rows to allow ([`read_record_with`]).
#[derive(Debug, Clone, Copy)]
pub struct ReadOptions<'a> {
    /// Known columns to store (names from [`COLUMNS`]); `t` is always stored. A column of the
    /// file that is not named here is still parsed and checked (so the errors and warnings are
    /// those of a full read) but left `None` in the record, saving 8 bytes a row.
    pub keep: &'a [&'a str],
    /// Most data rows allowed, ≤ [`MAX_ROWS`]; a row past it is a
    /// [`DatasetError::TooManyRows`] naming its line, met before the columns grow past it.
    pub max_rows: usize,
}

impl Default for ReadOptions<'_> {
    /// Every known column, up to [`MAX_ROWS`] rows.
    fn default() -> Self {
        ReadOptions {
            keep: &COLUMNS,
            max_rows: MAX_ROWS,
        }
    }
}

/// Reads a record from a CSV file (see the [module docs](super) for the format).
///
/// Files over [`MAX_FILE_BYTES`] are refused before reading; a file that is not text (a
/// binary file, `/dev/zero`, `/dev/urandom`) is refused after its first 64 KiB. Memory: 8
/// bytes a row for each known column of the file (and 8 more, briefly, for the median step).
pub fn read_record(path: &Path, kind: RecordKind) -> Result<Record, DatasetError> {
    read_record_with(path, kind, ReadOptions::default())
}

/// [`read_record`] storing only the columns in `options.keep` and refusing more than
/// `options.max_rows` rows: for a job that needs a few columns of a long record.
pub fn read_record_with(
    path: &Path,
    kind: RecordKind,
    options: ReadOptions,
) -> Result<Record, DatasetError> {
    let io_err = |error| DatasetError::Io {
        file: path.to_path_buf(),
        error,
    };
    let mut file = crate::fsutil::open_input(path).map_err(io_err)?;
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
    let scan = scan_text(&mut file, path)?;
    file.rewind().map_err(io_err)?;
    // `take` guards against a file that grows between the two passes.
    let lines = FileLines {
        reader: BufReader::with_capacity(SCAN_CHUNK, file.take(MAX_FILE_BYTES + 1)),
        buf: Vec::new(),
        line: 0,
        path,
    };
    parse_lines(lines, path, kind, options, scan.line_feeds + 1)
}

/// Parses a record from the raw bytes of a file, which must be UTF-8; `path` is used in
/// messages only.
pub fn parse_record_bytes(
    bytes: &[u8],
    path: &Path,
    kind: RecordKind,
) -> Result<Record, DatasetError> {
    check_size(bytes.len(), path)?;
    let scan = scan_text(bytes, path)?;
    match std::str::from_utf8(bytes) {
        Ok(text) => parse_text(text, path, kind, MAX_ROWS, scan),
        // Not reached: the scan has found any invalid byte.
        Err(_) => Err(DatasetError::Encoding {
            file: path.to_path_buf(),
            line: 1,
            detail: "invalid UTF-8".into(),
        }),
    }
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
    check_size(text.len(), path)?;
    let scan = scan_text(text.as_bytes(), path)?;
    parse_text(text, path, kind, max_rows, scan)
}

/// Refuses text over [`MAX_FILE_BYTES`].
fn check_size(len: usize, path: &Path) -> Result<(), DatasetError> {
    if len as u64 > MAX_FILE_BYTES {
        return Err(DatasetError::TooLarge {
            file: path.to_path_buf(),
            bytes: len as u64,
            limit: MAX_FILE_BYTES,
        });
    }
    Ok(())
}

/// Parses text that [`scan_text`] has passed.
fn parse_text(
    text: &str,
    path: &Path,
    kind: RecordKind,
    max_rows: usize,
    scan: Scan,
) -> Result<Record, DatasetError> {
    let lines = TextLines {
        rest: Some(text.strip_prefix('\u{feff}').unwrap_or(text)),
        line: 0,
    };
    let options = ReadOptions {
        max_rows,
        ..ReadOptions::default()
    };
    parse_lines(lines, path, kind, options, scan.line_feeds + 1)
}

/// What the text check of a whole file found.
struct Scan {
    /// Line feeds in the file.
    line_feeds: usize,
}

/// Reads `reader` to its end (at most [`MAX_FILE_BYTES`] + 1 bytes), [`SCAN_CHUNK`] bytes at
/// a time, and checks that it is text: UTF-8 without a UTF-16 byte-order mark or a NUL byte
/// (the first bad byte in the file is named by line, character and byte offset), not over
/// [`MAX_FILE_BYTES`], and with no carriage return that has no line feed after it.
fn scan_text(reader: impl Read, path: &Path) -> Result<Scan, DatasetError> {
    let encoding = |line, detail| DatasetError::Encoding {
        file: path.to_path_buf(),
        line,
        detail,
    };
    let mut reader = reader.take(MAX_FILE_BYTES + 1);
    // The chunk, after up to 3 bytes of a character cut by the previous chunk's end.
    let mut buf = vec![0u8; SCAN_CHUNK + 3];
    let mut carry = 0;
    // File offset, line and characters into that line at `buf[0]`.
    let (mut offset, mut line, mut line_chars) = (0u64, 1usize, 0usize);
    let mut line_feeds = 0;
    let mut lone_cr: Option<usize> = None;
    // The previous chunk ended with a CR on this line.
    let mut cr_at_end: Option<usize> = None;
    loop {
        let n = fill(&mut reader, &mut buf[carry..]).map_err(|error| DatasetError::Io {
            file: path.to_path_buf(),
            error,
        })?;
        let end = carry + n;
        let eof = end < buf.len();
        let data = &buf[..end];
        if offset == 0 && (data.starts_with(&[0xff, 0xfe]) || data.starts_with(&[0xfe, 0xff])) {
            return Err(encoding(
                1,
                "the file starts with a UTF-16 byte-order mark; save it as UTF-8".into(),
            ));
        }
        let (valid, invalid) = match std::str::from_utf8(data) {
            Ok(_) => (end, false),
            // A character cut by the chunk's end: carried into the next chunk.
            Err(e) if e.error_len().is_none() && !eof => (e.valid_up_to(), false),
            Err(e) => (e.valid_up_to(), true),
        };
        let nul = data[..valid].iter().position(|&b| b == 0);
        if let Some(at) = nul.or(invalid.then_some(valid)) {
            let (l, col) = position(line, line_chars, &data[..at], data[at]);
            let at = offset + at as u64;
            return Err(encoding(
                l,
                if nul.is_some() {
                    format!(
                        "a NUL byte (0x00) at character {col} of the line (byte offset {at} in \
                         the file): this is not a text file"
                    )
                } else {
                    format!(
                        "invalid byte 0x{:02x} at character {col} of the line (byte offset \
                         {at} in the file)",
                        data[at as usize - offset as usize]
                    )
                },
            ));
        }
        if offset + end as u64 > MAX_FILE_BYTES {
            return Err(DatasetError::TooLarge {
                file: path.to_path_buf(),
                bytes: offset + end as u64,
                limit: MAX_FILE_BYTES,
            });
        }
        if let Some(l) = cr_at_end.take()
            && data.first() != Some(&b'\n')
        {
            lone_cr.get_or_insert(l);
        }
        let text = &data[..valid];
        let mut last_lf = None;
        for (i, &b) in text.iter().enumerate() {
            if b == b'\n' {
                line_feeds += 1;
                last_lf = Some(i);
            } else if b == b'\r' && lone_cr.is_none() {
                let l = line + text[..i].iter().filter(|&&b| b == b'\n').count();
                match data.get(i + 1) {
                    Some(b'\n') => {}
                    None if !eof => cr_at_end = Some(l),
                    _ => lone_cr = Some(l),
                }
            }
        }
        line = line_feeds + 1;
        line_chars = match last_lf {
            Some(i) => char_starts(&text[i + 1..]),
            None => line_chars + char_starts(text),
        };
        if eof {
            break;
        }
        offset += valid as u64;
        buf.copy_within(valid..end, 0);
        carry = end - valid;
    }
    if let Some(line) = lone_cr {
        return Err(DatasetError::LoneCarriageReturn {
            file: path.to_path_buf(),
            line,
        });
    }
    Ok(Scan { line_feeds })
}

/// Reads into `buf` until it is full or the reader ends; the bytes read.
fn fill(reader: &mut impl Read, buf: &mut [u8]) -> io::Result<usize> {
    let mut n = 0;
    while n < buf.len() {
        match reader.read(&mut buf[n..]) {
            Ok(0) => break,
            Ok(k) => n += k,
            Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(n)
}

/// Bytes that start a character (not UTF-8 continuation bytes 10xxxxxx).
fn char_starts(bytes: &[u8]) -> usize {
    bytes.iter().filter(|&&b| b & 0xC0 != 0x80).count()
}

/// 1-based line and character of the byte `at` that follows `before`, where `before` starts
/// on line `line` after `line_chars` characters of it: [`crate::fsutil::line_column`] for a
/// file read in chunks (an offset inside a character points at that character).
fn position(line: usize, line_chars: usize, before: &[u8], at: u8) -> (usize, usize) {
    let line = line + before.iter().filter(|&&b| b == b'\n').count();
    let starts = match before.iter().rposition(|&b| b == b'\n') {
        Some(i) => char_starts(&before[i + 1..]),
        None => line_chars + char_starts(before),
    };
    let inside = at & 0xC0 == 0x80 && starts > 0;
    (line, starts + 1 - usize::from(inside))
}

/// The lines of a record, one at a time: borrowed from the text, or read from a file into one
/// reused buffer.
trait LineSource {
    /// The next line's 1-based number and its text without the line end (`\n` or `\r\n`);
    /// `None` after the last.
    fn next_line(&mut self) -> Result<Option<(usize, &str)>, DatasetError>;
}

/// The lines of text in memory (a byte-order mark already stripped).
struct TextLines<'a> {
    rest: Option<&'a str>,
    line: usize,
}

impl LineSource for TextLines<'_> {
    fn next_line(&mut self) -> Result<Option<(usize, &str)>, DatasetError> {
        let Some(rest) = self.rest else {
            return Ok(None);
        };
        let (l, rest) = match rest.split_once('\n') {
            Some((l, r)) => (l, Some(r)),
            None => (rest, None),
        };
        self.rest = rest;
        self.line += 1;
        Ok(Some((self.line, l.strip_suffix('\r').unwrap_or(l))))
    }
}

/// The lines of a file that [`scan_text`] has passed, read one at a time.
struct FileLines<'p, R> {
    reader: R,
    buf: Vec<u8>,
    line: usize,
    path: &'p Path,
}

impl<R: BufRead> LineSource for FileLines<'_, R> {
    fn next_line(&mut self) -> Result<Option<(usize, &str)>, DatasetError> {
        self.buf.clear();
        let n = self
            .reader
            .read_until(b'\n', &mut self.buf)
            .map_err(|error| DatasetError::Io {
                file: self.path.to_path_buf(),
                error,
            })?;
        if n == 0 {
            return Ok(None);
        }
        self.line += 1;
        let mut bytes = self.buf.as_slice();
        bytes = bytes.strip_suffix(b"\n").unwrap_or(bytes);
        bytes = bytes.strip_suffix(b"\r").unwrap_or(bytes);
        if self.line == 1 {
            bytes = bytes.strip_prefix("\u{feff}".as_bytes()).unwrap_or(bytes);
        }
        match std::str::from_utf8(bytes) {
            Ok(text) => Ok(Some((self.line, text))),
            Err(_) => Err(DatasetError::Encoding {
                file: self.path.to_path_buf(),
                line: self.line,
                detail: "invalid UTF-8 (the file changed while it was read)".into(),
            }),
        }
    }
}

/// Parses a record line by line (see the [module docs](super) for the format), storing the
/// columns `options` asks for; `lines_hint` (the file's lines) sizes the columns.
fn parse_lines(
    mut lines: impl LineSource,
    path: &Path,
    kind: RecordKind,
    options: ReadOptions,
    lines_hint: usize,
) -> Result<Record, DatasetError> {
    let file = || path.to_path_buf();
    let max_rows = options.max_rows;

    // Preamble: comments, metadata, blank lines, then the header.
    let mut metadata = Vec::new();
    let mut warnings = Vec::new();
    let (header_line, header_text) = loop {
        let Some((n, line)) = lines.next_line()? else {
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
            break (n, line.to_string());
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
    let capacity = lines_hint.min(max_rows);
    let mut cols: [Option<Vec<f64>>; COLUMNS.len()] = Default::default();
    for (s, f) in field_of_slot.iter().enumerate() {
        if f.is_some() && (s == T || options.keep.contains(&COLUMNS[s])) {
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
    // The largest |u| and |v_in| and their lines, for the plausibility warnings: the first of
    // equal peaks.
    let mut peaks: [Option<(usize, f64)>; 2] = [None, None];
    while let Some((n, line)) = lines.next_line()? {
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
                        column: Some("t"),
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
            } else if slot == V_IN || slot == U {
                let peak = &mut peaks[usize::from(slot == U)];
                if peak.is_none_or(|(_, p)| value.abs() > p.abs()) {
                    *peak = Some((n, value));
                }
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
            column: None,
            reason: "only one data row; at least two are needed to find the sample rate".into(),
        });
    }

    let dt = validate::sample_step(&t, &map, kind, path)?;
    warnings.extend(validate::plausibility_warnings(
        peaks[1],
        peaks[0],
        &metadata,
        1.0 / dt,
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
