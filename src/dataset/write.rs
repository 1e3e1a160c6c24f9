//! Writing a record in the module's format, whole or row by row, atomically to a file.

use super::columns::column_limit;
use super::error::{fmt_num, write_num};
use std::io::{self, Write};
use std::path::Path;

/// Writes a record in the [module's format](super): `# key: value` lines, the header, then one
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
                    crate::format::general(self.limits[i])
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
