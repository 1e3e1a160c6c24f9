//! What the writers of a command's output set share (the calibration's
//! `identify::report`, the tuning's `tune::report`): one error type for a
//! file that could not be written, and JSON numbers that are never NaN.

use crate::plot::PlotError;
use crate::preset::PresetError;
use serde_json::{Value, json};
use std::path::{Path, PathBuf};

/// Why an output set (reports, plots, a preset) could not be written.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// A file could not be written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The error.
        source: std::io::Error,
    },
    /// A plot failed.
    #[error(transparent)]
    Plot(#[from] PlotError),
    /// The preset failed.
    #[error(transparent)]
    Preset(#[from] PresetError),
}

impl OutputError {
    /// Maps an I/O error on `path` into [`OutputError::Io`] (for `map_err`).
    pub fn io(path: &Path) -> impl FnOnce(std::io::Error) -> OutputError + use<> {
        let path = path.to_path_buf();
        move |source| OutputError::Io { path, source }
    }
}

/// A JSON number, or `null` for a value that is not finite: a report never holds NaN.
pub fn json_number(v: f64) -> Value {
    if v.is_finite() { json!(v) } else { Value::Null }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn non_finite_numbers_become_null() {
        assert_eq!(json_number(1.5), json!(1.5));
        assert_eq!(json_number(-0.0), json!(-0.0));
        for v in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            assert_eq!(json_number(v), Value::Null);
        }
    }

    #[test]
    fn io_errors_name_the_file() {
        let e = OutputError::io(Path::new("/some/dir/report.md"))(std::io::Error::new(
            std::io::ErrorKind::PermissionDenied,
            "denied",
        ));
        assert_eq!(e.to_string(), "/some/dir/report.md: denied");
    }
}
