//! The kit of the CLI tests: run the binary, read what it wrote, check how it refused.
//!
//! A command line is written as one string, `cli("simulate --model twin --out {}", &[&out])`:
//! its words are split at spaces and each `{}` is replaced by the next path, whole, so a path
//! with spaces stays one argument.

use std::ffi::OsString;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

/// The arguments of command line `line`, each `{}` replaced by the next of `paths`.
pub(crate) fn argv(line: &str, paths: &[&Path]) -> Vec<OsString> {
    let mut paths = paths.iter();
    let args: Vec<OsString> = line
        .split_whitespace()
        .map(|w| match w {
            "{}" => paths
                .next()
                .unwrap_or_else(|| panic!("more `{{}}` than paths in {line:?}"))
                .as_os_str()
                .to_owned(),
            w => w.into(),
        })
        .collect();
    assert!(paths.next().is_none(), "more paths than `{{}}` in {line:?}");
    args
}

/// Runs command line `line` (see [`argv`]) to its end.
pub(crate) fn cli(line: &str, paths: &[&Path]) -> Output {
    bin()
        .args(argv(line, paths))
        .output()
        .expect("the binary runs")
}

/// Runs command line `line` (see [`argv`]) and kills it after `limit` (then `None`).
pub(crate) fn cli_within(line: &str, paths: &[&Path], limit: Duration) -> Option<Output> {
    let args = argv(line, paths);
    let args: Vec<&str> = args
        .iter()
        .map(|a| a.to_str().expect("a UTF-8 argument"))
        .collect();
    run_within(&args, limit)
}

pub(crate) fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_seat-twin"))
}

pub(crate) fn run(args: &[&str]) -> Output {
    bin().args(args).output().expect("the binary runs")
}

pub(crate) fn tmp() -> tempfile::TempDir {
    tempfile::tempdir().expect("a temporary directory")
}

/// Header and rows of a CSV written by the CLI (comment lines skipped).
pub(crate) fn read_csv(path: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(path).expect("the output exists");
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let header: Vec<String> = lines
        .next()
        .expect("a header")
        .split(',')
        .map(str::to_owned)
        .collect();
    let rows = lines
        .map(|l| {
            l.split(',')
                .map(|c| c.parse::<f64>().expect("a number"))
                .collect()
        })
        .collect();
    (header, rows)
}

pub(crate) fn column(header: &[String], rows: &[Vec<f64>], name: &str) -> Vec<f64> {
    let i = header
        .iter()
        .position(|h| h == name)
        .unwrap_or_else(|| panic!("column {name} in {header:?}"));
    rows.iter().map(|r| r[i]).collect()
}

pub(crate) fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

pub(crate) fn s(p: &Path) -> &str {
    p.to_str().expect("a UTF-8 path")
}

/// Polls `f` every 20 ms until it returns `Some`, at most `limit`.
pub(crate) fn wait_for<T>(limit: Duration, mut f: impl FnMut() -> Option<T>) -> Option<T> {
    let start = Instant::now();
    loop {
        if let Some(v) = f() {
            return Some(v);
        }
        if start.elapsed() > limit {
            return None;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// Runs the binary and kills it if it has not finished within `limit` (then `None`).
pub(crate) fn run_within(args: &[&str], limit: Duration) -> Option<Output> {
    let mut child = bin()
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the binary starts");
    let done = wait_for(limit, || child.try_wait().ok().flatten());
    if done.is_none() {
        let _ = child.kill();
        let _ = child.wait();
        return None;
    }
    child.wait_with_output().ok()
}

/// Entries of `dir` whose name starts with `prefix`.
pub(crate) fn entries_starting(dir: &Path, prefix: &str) -> Vec<PathBuf> {
    std::fs::read_dir(dir)
        .map(|rd| {
            rd.filter_map(|e| e.ok())
                .filter(|e| e.file_name().to_string_lossy().starts_with(prefix))
                .map(|e| e.path())
                .collect()
        })
        .unwrap_or_default()
}

pub(crate) fn entry_count(dir: &Path) -> usize {
    std::fs::read_dir(dir).map(|rd| rd.count()).unwrap_or(0)
}

#[cfg(unix)]
pub(crate) fn signal(child: &Child, name: &str) {
    let ok = Command::new("kill")
        .args([&format!("-{name}"), &child.id().to_string()])
        .status()
        .expect("kill runs")
        .success();
    assert!(ok, "kill -{name} {}", child.id());
}

/// Collects a child's stderr on a thread (so that a full pipe never blocks it).
pub(crate) fn stderr_reader(child: &mut Child) -> std::thread::JoinHandle<String> {
    let mut err = child.stderr.take().expect("stderr is piped");
    std::thread::spawn(move || {
        let mut s = String::new();
        let _ = err.read_to_string(&mut s);
        s
    })
}

/// The `error: …` line, split at ": " into its messages.
pub(crate) fn error_segments(err: &str) -> Vec<String> {
    let line = err
        .lines()
        .find(|l| l.starts_with("error: "))
        .unwrap_or_else(|| panic!("no error line in {err:?}"));
    line["error: ".len()..]
        .split(": ")
        .map(|s| s.trim().to_string())
        .collect()
}

/// Writes a measured record (`t, v_in, u`) at 1 kHz for `secs` s.
pub(crate) fn measured_record(path: &Path, secs: f64, v_amp: f64, u_amp: f64) {
    let mut text = String::from("t,v_in,u\n");
    let n = (secs * 1000.0) as usize;
    for i in 0..=n {
        let t = i as f64 / 1000.0;
        let w = 2.0 * std::f64::consts::PI * 2.0 * t;
        text.push_str(&format!("{t:.3},{},{}\n", v_amp * w.cos(), u_amp * w.sin()));
    }
    std::fs::write(path, text).unwrap();
}

/// Checks that a run failed with exit code `code` and that its stderr says each of `said`;
/// returns the stderr.
pub(crate) fn refused(o: &Output, code: i32, said: &[&str]) -> String {
    let err = stderr(o);
    assert_eq!(o.status.code(), Some(code), "{err}");
    for s in said {
        assert!(err.contains(s), "{s:?} not in {err}");
    }
    err
}

/// A short excitation record (`t, x`) of `secs` s at 1 kHz, a 2 Hz sine of 5 mm.
pub(crate) fn excitation_record(path: &Path, secs: f64) {
    let mut text = String::from("t,x\n");
    for i in 0..=(secs * 1000.0) as usize {
        let t = i as f64 / 1000.0;
        let x = 0.005 * (2.0 * std::f64::consts::PI * 2.0 * t).sin();
        text.push_str(&format!("{t:.3},{x:.9}\n"));
    }
    std::fs::write(path, text).unwrap();
}
