//! A run's samples as a CSV file in the [dataset format](crate::dataset): the `# key: value`
//! comments, then the columns `t,x,xdd,u,ydd`, `v_in` for a model with a valve command and
//! `xv,p1,p2,q1,q2` for the twin's hydraulics (the columns a model lacks are left out), SI.
//!
//! [`Trace::write_csv`] writes a recorded trace, [`write_csv_streamed`] the samples of a run
//! as they are made (memory does not grow with the duration). Both write atomically
//! ([`crate::fsutil::write_atomic`]): on any error, and on SIGINT/SIGTERM while writing, the
//! target is left as it was and the temporary file is removed.

use super::{RunSummary, Sample, SimError, Trace};
use crate::dataset::CsvWriter;
use crate::model::ModelKind;
use std::io;
use std::path::Path;

/// The `units` comment of a sample file: every column's unit.
pub const SAMPLE_UNITS: &str =
    "t s, x m, xdd m/s^2, u m, ydd m/s^2, v_in V, xv m, p1 Pa, p2 Pa, q1 m^3/s, q2 m^3/s";

/// The columns a model's samples are written with.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SampleColumns {
    /// `v_in`: the model has a valve command.
    command: bool,
    /// `xv,p1,p2,q1,q2`: the model has hydraulics.
    hydraulics: bool,
}

impl SampleColumns {
    /// The columns of `kind`'s samples.
    pub fn of(kind: ModelKind) -> Self {
        Self {
            command: kind.has_command(),
            hydraulics: kind.has_hydraulics(),
        }
    }

    /// The header: `t,x,xdd,u,ydd`, then `v_in`, then `xv,p1,p2,q1,q2` when the model has them.
    pub fn header(self) -> Vec<&'static str> {
        let mut header = vec!["t", "x", "xdd", "u", "ydd"];
        if self.command {
            header.push("v_in");
        }
        if self.hydraulics {
            header.extend(["xv", "p1", "p2", "q1", "q2"]);
        }
        header
    }

    /// `s`'s values in the order of [`Self::header`], into `row` (cleared first).
    pub fn fill(self, s: &Sample, row: &mut Vec<f64>) {
        row.clear();
        row.extend([s.t, s.x, s.xdd, s.u, s.ydd]);
        if self.command {
            row.push(s.v_in);
        }
        if self.hydraulics {
            row.extend([s.xv, s.p1, s.p2, s.q1, s.q2]);
        }
    }
}

/// Why a run written to CSV ([`write_csv_streamed`]) stopped.
#[derive(Debug, thiserror::Error)]
pub enum CsvRunError {
    /// The model diverged.
    #[error(transparent)]
    Sim(#[from] SimError),
    /// The file could not be written.
    #[error(transparent)]
    Io(#[from] io::Error),
}

impl Trace {
    /// Writes the trace's samples to `path` with `comments`, in the
    /// [dataset format](crate::dataset).
    pub fn write_csv(&self, path: &Path, comments: &[(String, String)]) -> io::Result<()> {
        write_samples(path, self.model, comments, |record| {
            for s in &self.samples {
                if !record(*s) {
                    break;
                }
            }
            Ok(())
        })
    }
}

/// Runs `run` and writes each sample it passes to its recorder to `path` as it is made, with
/// `comments`, in the columns of `kind` (in the [dataset format](crate::dataset)). `run` is a
/// streamed run such as `|record| sim.run_streaming(t_end, rate_hz, record)`; the recorder
/// returns `false` once a row could not be written, which should stop the run.
pub fn write_csv_streamed(
    path: &Path,
    kind: ModelKind,
    comments: &[(String, String)],
    run: impl FnOnce(&mut dyn FnMut(Sample) -> bool) -> Result<RunSummary, SimError>,
) -> Result<RunSummary, CsvRunError> {
    write_samples(path, kind, comments, |record| Ok(run(record)?))
}

/// The writer of both: `make` passes samples to the recorder it is given (which returns
/// `false` once a row failed) and returns what it made, or its error.
fn write_samples<T, E: From<io::Error>>(
    path: &Path,
    kind: ModelKind,
    comments: &[(String, String)],
    make: impl FnOnce(&mut dyn FnMut(Sample) -> bool) -> Result<T, E>,
) -> Result<T, E> {
    let columns = SampleColumns::of(kind);
    let header = columns.header();
    let mut made = None;
    crate::fsutil::write_atomic(path, |w| -> Result<(), E> {
        let mut csv = CsvWriter::start(w, &header, comments)?;
        let mut failed = None;
        let mut row = Vec::with_capacity(header.len());
        let out = make(&mut |s| {
            columns.fill(&s, &mut row);
            match csv.row(&mut *w, &row) {
                Ok(()) => true,
                Err(e) => {
                    failed = Some(e);
                    false
                }
            }
        })?;
        if let Some(e) = failed {
            return Err(e.into());
        }
        made = Some(out);
        Ok(())
    })?;
    made.ok_or_else(|| io::Error::other("the run recorded nothing").into())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::linear::LinearModel;
    use crate::model::passive::PassiveModel;
    use crate::params::Params;
    use crate::scenario::{Cycloid, PlatformMotion};
    use crate::simulation::{Drive, Run, Simulation};

    fn comments() -> Vec<(String, String)> {
        vec![
            ("model".to_string(), "test".to_string()),
            ("units".to_string(), SAMPLE_UNITS.to_string()),
        ]
    }

    /// The comment lines, the header and the rows of numbers of a written file.
    fn read_back(path: &Path) -> (Vec<String>, Vec<String>, Vec<Vec<f64>>) {
        let text = std::fs::read_to_string(path).unwrap();
        let (comments, rest): (Vec<&str>, Vec<&str>) =
            text.lines().partition(|l| l.starts_with('#'));
        let header = rest[0].split(',').map(String::from).collect();
        let rows = rest[1..]
            .iter()
            .map(|l| l.split(',').map(|c| c.parse().unwrap()).collect())
            .collect();
        (
            comments.into_iter().map(String::from).collect(),
            header,
            rows,
        )
    }

    fn twin_bump(params: &Params) -> Simulation<crate::model::twin::Twin, 10> {
        let platform = PlatformMotion::Cycloid(Cycloid::default());
        Simulation::twin(params, 1e-4, Drive::closed_loop(params), platform)
    }

    /// Every number of a written trace reads back as the sample's own value, bit for bit, in
    /// the documented column order; the passive seat's file leaves out the valve and the
    /// hydraulics (its samples hold NaN there, which a file refuses).
    #[test]
    fn a_trace_reads_back_number_for_number() {
        let params = Params::paper();
        let dir = tempfile::tempdir().unwrap();
        let passive = Simulation::new(
            PassiveModel::new(&params),
            1e-4,
            Drive::closed_loop(&params),
            PlatformMotion::Cycloid(Cycloid::default()),
        );
        let traces = [
            twin_bump(&params).run_trace(1.0, 200.0).unwrap(),
            passive.clone().run_trace(1.0, 200.0).unwrap(),
        ];
        for trace in &traces {
            let path = dir.path().join(format!("{}.csv", trace.model.name()));
            trace.write_csv(&path, &comments()).unwrap();
            let (comment_lines, header, rows) = read_back(&path);
            assert_eq!(
                comment_lines,
                ["# model: test", &format!("# units: {SAMPLE_UNITS}")]
            );
            assert_eq!(rows.len(), 201);
            assert_eq!(rows.len(), trace.samples.len());
            let twin = trace.model == ModelKind::Twin;
            let expected_header: &[&str] = if twin {
                &[
                    "t", "x", "xdd", "u", "ydd", "v_in", "xv", "p1", "p2", "q1", "q2",
                ]
            } else {
                &["t", "x", "xdd", "u", "ydd"]
            };
            assert_eq!(header, expected_header);
            for (row, s) in rows.iter().zip(&trace.samples) {
                let mut expected = vec![s.t, s.x, s.xdd, s.u, s.ydd];
                if twin {
                    expected.extend([s.v_in, s.xv, s.p1, s.p2, s.q1, s.q2]);
                }
                assert_eq!(row, &expected, "t = {}", s.t);
            }
            // The bump moves the platform 30 mm and the seat with it: the file holds the run.
            let x_end = rows.last().unwrap()[1];
            assert!(
                (x_end - 0.030).abs() < 1e-9,
                "platform x at the end {x_end}"
            );
            let peak_xdd = rows.iter().map(|r| r[2].abs()).fold(0.0, f64::max);
            assert!((peak_xdd - 0.754).abs() < 0.01, "peak ẍ {peak_xdd}");
        }
    }

    /// The streamed writer writes the file of the trace, byte for byte, and returns the run's
    /// summary.
    #[test]
    fn a_streamed_run_writes_the_file_of_its_trace() {
        let params = Params::paper();
        let dir = tempfile::tempdir().unwrap();
        let (whole, streamed) = (
            dir.path().join("whole.csv"),
            dir.path().join("streamed.csv"),
        );
        let trace = twin_bump(&params).run_trace(1.0, 200.0).unwrap();
        trace.write_csv(&whole, &comments()).unwrap();
        let mut sim = twin_bump(&params);
        let summary = write_csv_streamed(&streamed, ModelKind::Twin, &comments(), |record| {
            sim.run_streaming(1.0, 200.0, record)
        })
        .unwrap();
        assert_eq!(summary.samples, 201);
        assert!(!summary.stopped);
        assert_eq!(summary.contacts, trace.contacts);
        assert_eq!(
            std::fs::read(&streamed).unwrap(),
            std::fs::read(&whole).unwrap()
        );
    }

    /// A run that diverges leaves no file and no temporary file behind, and says which model
    /// diverged when.
    #[test]
    fn a_diverging_run_leaves_nothing() {
        let mut params = Params::paper();
        // Positive feedback: the linear model grows without bound.
        params.controller.kp_v_per_m = 20.0;
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("diverged.csv");
        let mut sim = Simulation::new(
            LinearModel::new(&params),
            1e-4,
            Drive::closed_loop(&params),
            PlatformMotion::Cycloid(Cycloid::default()),
        );
        let e = write_csv_streamed(&path, ModelKind::Linear, &comments(), |record| {
            sim.run_streaming(10.0, 100.0, record)
        })
        .unwrap_err();
        match e {
            CsvRunError::Sim(SimError::Diverged { model, t, .. }) => {
                assert_eq!(model, "linear");
                assert!(t > 0.0 && t < 10.0, "diverged at t = {t}");
            }
            e => panic!("expected a divergence, got {e}"),
        }
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    }
}
