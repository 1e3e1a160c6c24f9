//! Issue 12, CLI part: bad input never gets in, nothing wrong is shown. One test (or more) per
//! item; each failed on the code before the issue was worked on (the reason is in its doc).
//! This module: items 1–3 (resources: sample limits, preset sizes, slow runs and signals); items
//! 4–9 (bad values, messages, smaller items) are in `cli_input.rs`.

use crate::support::{
    bin, cli, cli_within, entries_starting, entry_count, measured_record, read_csv, s, signal,
    stderr, stderr_reader, tmp, wait_for,
};

use std::process::{Command, Stdio};
use std::time::Duration;

// ---------------------------------------------------------------------------------------------
// 1. Allocation abort on allowed values.

/// Before: `memory allocation of 403200000224 bytes failed`, exit 134 (SIGABRT).
#[test]
fn a_run_over_the_sample_limit_is_refused_up_front_with_the_count_and_the_limit() {
    let dir = tmp();
    let out = dir.path().join("o.csv");
    for (model, scenario, duration) in [
        ("passive", "cycloid", "36000"),
        ("twin", "random", "3600"),
        ("linear", "sine", "36000"),
    ] {
        let o = cli_within(
            &format!(
                "simulate --model {model} --scenario {scenario} --duration {duration} \
                 --rate 100000 --out {{}}"
            ),
            &[&out],
            Duration::from_secs(60),
        )
        .expect("refused at once, not after a long run");
        assert_eq!(
            o.status.code(),
            Some(1),
            "{model} {scenario}: {}",
            stderr(&o)
        );
        let err = stderr(&o);
        let expected = format!("{}", duration.parse::<u64>().unwrap() * 100_000 + 1);
        assert!(err.contains(&format!("{expected} samples")), "{err}");
        assert!(err.contains("limit of 50000000 samples"), "{err}");
        assert!(!out.exists());
    }
}

/// Before: the whole trace was kept in memory (4 GB reserved up front for 36 000 s at 1 kHz):
/// under a 1 GB address-space limit the run aborted at once. Now samples reach the disk while
/// the run goes on, memory stays small, and SIGTERM removes the unfinished hidden file.
#[cfg(unix)]
#[test]
fn simulate_streams_to_disk_in_bounded_memory_and_sigterm_removes_its_temporary_file() {
    let dir = tmp();
    let out = dir.path().join("long.csv");
    let mut child = Command::new("sh")
        .arg("-c")
        .arg("ulimit -v 1000000 && exec \"$0\" \"$@\"")
        .arg(env!("CARGO_BIN_EXE_seat-twin"))
        .args([
            "simulate",
            "--model",
            "passive",
            "--scenario",
            "cycloid",
            "--duration",
            "36000",
            "--out",
            s(&out),
        ])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the binary starts");
    let err = stderr_reader(&mut child);
    // The hidden temporary file grows past 8 MB while the run goes on.
    let grown = wait_for(Duration::from_secs(120), || {
        if let Ok(Some(_)) = child.try_wait() {
            return Some(None);
        }
        entries_starting(dir.path(), ".long.csv.")
            .into_iter()
            .find(|p| p.metadata().map(|m| m.len() > 8 << 20).unwrap_or(false))
            .map(Some)
    });
    let status_now = child.try_wait().ok().flatten();
    assert!(
        matches!(grown, Some(Some(_))) && status_now.is_none(),
        "the run streams to its temporary file (exited: {status_now:?})"
    );
    let hwm_kb: Option<u64> = std::fs::read_to_string(format!("/proc/{}/status", child.id()))
        .ok()
        .and_then(|st| {
            st.lines()
                .find(|l| l.starts_with("VmHWM:"))
                .and_then(|l| l.split_whitespace().nth(1).and_then(|v| v.parse().ok()))
        });
    signal(&child, "TERM");
    let status = child.wait().unwrap();
    let err = err.join().unwrap();
    assert_eq!(status.code(), Some(128 + 15), "{err}");
    assert!(err.contains("interrupted (SIGTERM)"), "{err}");
    assert_eq!(
        entry_count(dir.path()),
        0,
        "no temporary file and no output are left"
    );
    if let Some(kb) = hwm_kb {
        eprintln!("peak resident memory of the streaming run: {kb} kB");
        assert!(kb < 200_000, "peak resident memory {kb} kB");
    }
}

/// The streamed file is the same as the samples of a short run kept in memory would give:
/// one row per sample, both ends, the documented columns.
#[test]
fn a_streamed_trace_has_every_sample() {
    let dir = tmp();
    let out = dir.path().join("t.csv");
    let o = cli(
        "simulate --model linear --scenario sine --duration 1.5 --rate 200 --out {}",
        &[&out],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let (header, rows) = read_csv(&out);
    assert_eq!(header, ["t", "x", "xdd", "u", "ydd", "v_in"]);
    assert_eq!(rows.len(), 301);
    for (i, r) in rows.iter().enumerate() {
        assert!(
            (r[0] - i as f64 / 200.0).abs() < 1e-9,
            "row {i}: t = {}",
            r[0]
        );
    }
}

// ---------------------------------------------------------------------------------------------
// 2. Preset files have no size limit.

/// Before: `/dev/zero` and `/dev/urandom` were read whole (past 4 GB).
#[cfg(unix)]
#[test]
fn presets_from_devices_and_oversized_files_are_refused_at_once() {
    let dir = tmp();
    let out = dir.path().join("x.csv");
    for dev in ["/dev/zero", "/dev/urandom"] {
        let o = cli_within(
            "transmissibility --model linear --preset {} --freqs 1 --out {}",
            &[std::path::Path::new(dev), &out],
            Duration::from_secs(30),
        )
        .unwrap_or_else(|| panic!("--preset {dev} did not fail within 30 s"));
        assert_eq!(o.status.code(), Some(1));
        let err = stderr(&o);
        assert!(err.contains(dev), "{err}");
        assert!(err.contains("limit of 1048576 bytes (1 MiB)"), "{err}");
    }
    // A sparse 2 MiB file: refused by its size before it is read.
    let big = dir.path().join("big.toml");
    std::fs::File::create(&big)
        .unwrap()
        .set_len(2 << 20)
        .unwrap();
    let o = cli(
        "transmissibility --model linear --preset {} --freqs 1 --out {}",
        &[&big, &out],
    );
    let err = stderr(&o);
    assert!(
        err.contains("2097152 bytes is over the limit of 1048576 bytes"),
        "{err}"
    );
    assert!(!out.exists());
}

// ---------------------------------------------------------------------------------------------
// 3. Values in range that run for minutes.

/// Before: no word about the cost, no cleanup on Ctrl-C: the half-written report folder
/// stayed. Now: a note up front, SIGINT ends it with no trace.
#[cfg(unix)]
#[test]
fn a_slow_report_says_so_and_ctrl_c_leaves_nothing() {
    let dir = tmp();
    let preset = dir.path().join("fine.toml");
    std::fs::write(&preset, "[numerics]\nmax_step_s = 1e-6\n").unwrap();
    let out = dir.path().join("r");
    let mut child = bin()
        .args(["report", "--preset", s(&preset), "--out", s(&out)])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let err = stderr_reader(&mut child);
    let started = wait_for(Duration::from_secs(60), || {
        entries_starting(dir.path(), ".r.").into_iter().next()
    });
    assert!(started.is_some(), "the report's temporary folder appears");
    signal(&child, "INT");
    let status = child.wait().unwrap();
    let err = err.join().unwrap();
    assert_eq!(status.code(), Some(128 + 2), "{err}");
    assert!(
        err.contains("numerics.max_step_s = 1e-6 s is 500× finer than the default 0.0005 s"),
        "{err}"
    );
    assert!(err.contains("interrupted (SIGINT)"), "{err}");
    assert!(!out.exists(), "no report folder");
    assert!(
        entries_starting(dir.path(), ".r.").is_empty(),
        "no temporary folder"
    );
}

/// Before: ±1e6 V passed without a word, and Ctrl-C left the output folder's files. Now the
/// record gets a warning, and SIGTERM during the calibration leaves nothing.
#[cfg(unix)]
#[test]
fn calibrating_on_a_megavolt_record_warns_and_sigterm_leaves_nothing() {
    let dir = tmp();
    let rec = dir.path().join("mv.csv");
    measured_record(&rec, 3.0, 1e6, 0.002);
    // A fine step makes the calibration take seconds instead of 0.1 s, so that the signal
    // surely arrives while it runs (with the default step it could end first).
    let preset = dir.path().join("fine.toml");
    std::fs::write(&preset, "[numerics]\nmax_step_s = 1e-6\n").unwrap();
    let out = dir.path().join("cal");
    let mut child = bin()
        .args([
            "calibrate",
            "--preset",
            s(&preset),
            "--data",
            s(&rec),
            "--out",
            s(&out),
        ])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let err = stderr_reader(&mut child);
    let running = wait_for(Duration::from_secs(60), || {
        if let Ok(Some(_)) = child.try_wait() {
            return Some(false);
        }
        (!entries_starting(dir.path(), ".cal.").is_empty()).then_some(true)
    });
    if running == Some(true) {
        signal(&child, "TERM");
    }
    let status = child.wait().unwrap();
    let err = err.join().unwrap();
    assert!(
        err.contains("column \"v_in\" reaches 1000000 V at line 2")
            && err.contains("beyond the valve's ±10 V"),
        "{err}"
    );
    if running == Some(true) {
        assert_eq!(status.code(), Some(128 + 15), "{err}");
        assert!(!out.exists(), "no results folder");
    }
    assert!(
        entries_starting(dir.path(), ".cal.").is_empty(),
        "no temporary folder"
    );
}
