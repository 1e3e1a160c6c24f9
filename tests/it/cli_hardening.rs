//! Issue 12, CLI part: bad input never gets in, nothing wrong is shown. One test (or more) per
//! item; each failed on the code before the issue was worked on (the reason is in its doc).

use crate::cli::{bin, read_csv, run, stderr, tmp};
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

fn s(p: &Path) -> &str {
    p.to_str().expect("a UTF-8 path")
}

/// Polls `f` every 20 ms until it returns `Some`, at most `limit`.
fn wait_for<T>(limit: Duration, mut f: impl FnMut() -> Option<T>) -> Option<T> {
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
fn run_within(args: &[&str], limit: Duration) -> Option<Output> {
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
fn entries_starting(dir: &Path, prefix: &str) -> Vec<PathBuf> {
    std::fs::read_dir(dir)
        .map(|rd| {
            rd.filter_map(|e| e.ok())
                .filter(|e| e.file_name().to_string_lossy().starts_with(prefix))
                .map(|e| e.path())
                .collect()
        })
        .unwrap_or_default()
}

fn entry_count(dir: &Path) -> usize {
    std::fs::read_dir(dir).map(|rd| rd.count()).unwrap_or(0)
}

#[cfg(unix)]
fn signal(child: &Child, name: &str) {
    let ok = Command::new("kill")
        .args([&format!("-{name}"), &child.id().to_string()])
        .status()
        .expect("kill runs")
        .success();
    assert!(ok, "kill -{name} {}", child.id());
}

/// Collects a child's stderr on a thread (so that a full pipe never blocks it).
fn stderr_reader(child: &mut Child) -> std::thread::JoinHandle<String> {
    let mut err = child.stderr.take().expect("stderr is piped");
    std::thread::spawn(move || {
        let mut s = String::new();
        let _ = err.read_to_string(&mut s);
        s
    })
}

/// The `error: …` line, split at ": " into its messages.
fn error_segments(err: &str) -> Vec<String> {
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
fn measured_record(path: &Path, secs: f64, v_amp: f64, u_amp: f64) {
    let mut text = String::from("t,v_in,u\n");
    let n = (secs * 1000.0) as usize;
    for i in 0..=n {
        let t = i as f64 / 1000.0;
        let w = 2.0 * std::f64::consts::PI * 2.0 * t;
        text.push_str(&format!("{t:.3},{},{}\n", v_amp * w.cos(), u_amp * w.sin()));
    }
    std::fs::write(path, text).unwrap();
}

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
        let o = run_within(
            &[
                "simulate",
                "--model",
                model,
                "--scenario",
                scenario,
                "--duration",
                duration,
                "--rate",
                "100000",
                "--out",
                s(&out),
            ],
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
    let o = run(&[
        "simulate",
        "--model",
        "linear",
        "--scenario",
        "sine",
        "--duration",
        "1.5",
        "--rate",
        "200",
        "--out",
        s(&out),
    ]);
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
        let o = run_within(
            &[
                "transmissibility",
                "--model",
                "linear",
                "--preset",
                dev,
                "--freqs",
                "1",
                "--out",
                s(&out),
            ],
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
    let o = run(&[
        "transmissibility",
        "--model",
        "linear",
        "--preset",
        s(&big),
        "--freqs",
        "1",
        "--out",
        s(&out),
    ]);
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
    let out = dir.path().join("cal");
    let mut child = bin()
        .args(["calibrate", "--data", s(&rec), "--out", s(&out)])
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

// ---------------------------------------------------------------------------------------------
// 4. Exit 0 on bad input.

/// Before: all four were accepted (exit 0).
#[test]
fn amp_is_checked_for_bode_and_chirp_as_for_sine() {
    let dir = tmp();
    let out = dir.path().join("o.csv");
    let cases: [&[&str]; 6] = [
        &["bode", "--model", "linear", "--freqs", "1", "--amp", "1e9"],
        &["bode", "--model", "linear", "--freqs", "1", "--amp=-1"],
        &[
            "simulate",
            "--model",
            "linear",
            "--scenario",
            "chirp",
            "--amp",
            "1e9",
        ],
        &[
            "simulate",
            "--model",
            "linear",
            "--scenario",
            "chirp",
            "--amp=-5",
        ],
        &[
            "simulate",
            "--model",
            "linear",
            "--scenario",
            "sine",
            "--amp",
            "1e9",
        ],
        &[
            "simulate",
            "--model",
            "linear",
            "--scenario",
            "sine",
            "--amp",
            "nan",
        ],
    ];
    for args in cases {
        let mut a = args.to_vec();
        a.extend(["--out", s(&out)]);
        let o = run(&a);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {err}");
        assert!(
            err.contains("--amp") && err.contains("is outside the allowed range"),
            "{args:?}: {err}"
        );
        assert!(err.contains("100] V"), "{args:?}: {err}");
        assert!(!out.exists());
    }
}

/// Before: "du inf mm/s (NaN %)" and an output full of NaN.
#[test]
fn an_absurd_value_in_a_record_is_an_error_naming_file_line_and_column() {
    let dir = tmp();
    let rec = dir.path().join("huge.csv");
    std::fs::write(
        &rec,
        "t,v_in,u\n0,0,0\n0.001,0.1,0\n0.002,0.2,1e308\n0.003,0.3,0\n",
    )
    .unwrap();
    let out = dir.path().join("r.csv");
    let o = run(&["replay", "--data", s(&rec), "--out", s(&out)]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("huge.csv: line 4, column \"u\""), "{err}");
    assert!(err.contains("is beyond ±1000 m"), "{err}");
    assert!(!err.contains("NaN") && !err.contains("inf"), "{err}");
    assert!(!out.exists());
}

/// Before: a record in millimetres, or with a ±1e6 V command, passed without a word. Now a
/// warning on stderr, and in the output's comments where the output is a CSV of the run.
#[test]
fn channels_far_outside_the_rig_give_a_warning() {
    let dir = tmp();
    let mm = dir.path().join("mm.csv");
    measured_record(&mm, 1.0, 1.0, 20.0);
    let out = dir.path().join("r.csv");
    let o = run(&["replay", "--data", s(&mm), "--out", s(&out)]);
    let err = stderr(&o);
    assert!(
        err.contains("mm.csv: column \"u\" reaches ") && err.contains("20 m at line"),
        "{err}"
    );
    assert!(err.contains("millimetres instead of metres"), "{err}");

    let exc = dir.path().join("exc.csv");
    let mut text = String::from("t,xdd,v_in\n");
    for i in 0..=500 {
        text.push_str(&format!(
            "{},0,{}\n",
            i as f64 / 1000.0,
            if i == 7 { 24.0 } else { 0.0 }
        ));
    }
    std::fs::write(&exc, text).unwrap();
    let out = dir.path().join("s.csv");
    let o = run(&[
        "simulate",
        "--model",
        "passive",
        "--excitation",
        s(&exc),
        "--out",
        s(&out),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let warning = "column \"v_in\" reaches 24 V at line 9, beyond the valve's ±10 V";
    assert!(stderr(&o).contains(warning), "{}", stderr(&o));
    let written = std::fs::read_to_string(&out).unwrap();
    assert!(
        written
            .lines()
            .any(|l| l.starts_with("# warning: ") && l.contains(warning)),
        "{}",
        &written[..400.min(written.len())]
    );
}

// ---------------------------------------------------------------------------------------------
// 5. Negative values.

/// Before: clap's "unexpected argument '-1' found".
#[test]
fn negative_values_get_the_range_message() {
    let dir = tmp();
    let out = dir.path().join("o.csv");
    let cases: [(&[&str], &str); 5] = [
        (
            &[
                "simulate",
                "--model",
                "twin",
                "--scenario",
                "cycloid",
                "--duration",
                "-1",
            ],
            "--duration -1 is outside the allowed range [0.001, 36000] s",
        ),
        (
            &[
                "simulate",
                "--model",
                "twin",
                "--scenario",
                "cycloid",
                "--rate",
                "-1",
            ],
            "--rate -1 is outside the allowed range [1, 100000] Hz",
        ),
        (
            &[
                "simulate",
                "--model",
                "twin",
                "--scenario",
                "sine",
                "--freq",
                "-2",
            ],
            "--freq -2 is outside the allowed range [0.01, 1000] Hz",
        ),
        (
            &["bode", "--model", "linear", "--freqs", "-1,2"],
            "--freqs value -1 is outside the allowed range [0.01, 1000] Hz",
        ),
        (
            &["transmissibility", "--model", "linear", "--freqs", "2,-0.5"],
            "--freqs value -0.5 is outside the allowed range [0.01, 1000] Hz",
        ),
    ];
    for (args, msg) in cases {
        let mut a = args.to_vec();
        a.extend(["--out", s(&out)]);
        let o = run(&a);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {err}");
        assert!(err.contains(msg), "{args:?}: {err}");
    }
}

// ---------------------------------------------------------------------------------------------
// 6. Divergence that blames the wrong thing.

/// Before: "twin model diverged … check the gains … or reduce numerics.max_step_s" for an
/// excitation with xdd = 1e300 and for `--amp nan`; `bode --amp 0` blamed the output file.
#[test]
fn a_bad_input_is_named_not_the_gains_or_the_output_file() {
    let dir = tmp();
    let exc = dir.path().join("spike.csv");
    std::fs::write(&exc, "t,xdd\n0,0\n0.001,0\n0.002,1e300\n0.003,0\n").unwrap();
    let out = dir.path().join("o.csv");
    let o = run(&[
        "simulate",
        "--model",
        "twin",
        "--excitation",
        s(&exc),
        "--out",
        s(&out),
    ]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("spike.csv: line 4, column \"xdd\""), "{err}");
    assert!(!err.contains("gains"), "{err}");

    let o = run(&[
        "simulate",
        "--model",
        "twin",
        "--scenario",
        "chirp",
        "--amp",
        "nan",
        "--out",
        s(&out),
    ]);
    let err = stderr(&o);
    assert!(
        err.contains("--amp NaN is outside the allowed range"),
        "{err}"
    );
    assert!(!err.contains("diverged"), "{err}");

    for method in ["exact", "simulated"] {
        let model = if method == "exact" { "linear" } else { "twin" };
        let o = run(&[
            "bode",
            "--model",
            model,
            "--method",
            method,
            "--amp",
            "0",
            "--freqs",
            "5",
            "--out",
            s(&out),
        ]);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{err}");
        assert!(
            err.contains("--amp 0 is outside the allowed range (0, 100] V"),
            "{err}"
        );
        assert!(!err.contains("writing"), "{err}");
        assert!(!out.exists());
    }
}

/// A record within the cell bounds that still makes the run diverge: the message names the
/// record, its driving column and where it peaks.
#[test]
fn a_divergence_on_an_excitation_names_the_record_and_its_peak() {
    let dir = tmp();
    let exc = dir.path().join("hammer.csv");
    let mut text = String::from("t,xdd\n");
    for i in 0..=2000 {
        let v = if (1000..1010).contains(&i) {
            9.0e5
        } else {
            0.0
        };
        text.push_str(&format!("{},{v}\n", i as f64 / 1000.0));
    }
    std::fs::write(&exc, text).unwrap();
    let out = dir.path().join("o.csv");
    let o = run(&[
        "simulate",
        "--model",
        "twin",
        "--excitation",
        s(&exc),
        "--out",
        s(&out),
    ]);
    let err = stderr(&o);
    if o.status.success() {
        // The twin absorbed it (end stops); then there is nothing to blame.
        return;
    }
    assert!(err.contains("hammer.csv"), "{err}");
    assert!(
        err.contains("its column \"xdd\" peaks at 900000 m/s² at t = 1 s (data row 1001)"),
        "{err}"
    );
    assert!(!out.exists());
}

// ---------------------------------------------------------------------------------------------
// 7. Every message is printed twice.

/// Before: 145 of 484 cases printed a message twice, e.g. "parameter `body.mass_kg` = 0 …:
/// parameter `body.mass_kg` = 0 …" and "Is a directory (os error 21): Is a directory (os
/// error 21)".
#[test]
fn every_error_message_is_printed_once() {
    let dir = tmp();
    let d = dir.path();
    let file = |name: &str, text: &str| {
        let p = d.join(name);
        std::fs::write(&p, text).unwrap();
        p.to_str().unwrap().to_string()
    };
    let sub = d.join("sub");
    std::fs::create_dir(&sub).unwrap();
    let sub = s(&sub).to_string();
    let missing = s(&d.join("missing.csv")).to_string();
    let out = s(&d.join("o.csv")).to_string();
    let zero_mass = file("zero.toml", "[body]\nmass_kg = 0\n");
    let typed = file("typed.toml", "[body]\nmass_kg = { a = 1 }\n");
    let unknown = file("unknown.toml", "[valve]\ntua_s = 0.01\n");
    let version = file("v2.toml", "[preset]\nformat_version = 2\n");
    let bad_cell = file("bad.csv", "t,xdd\n0,0\n0.001,abc\n");
    let short_row = file("short.csv", "t,x,xdd\n0,0,0\n0.001,0\n");
    let measured = file("m.csv", "t,v_in,u\n0,0,0\n0.001,0,0\n0.002,0,0\n");
    let a_file = file("plain.txt", "x");
    let under_file = format!("{a_file}/x");
    let sim = |extra: &[&str]| {
        let mut v: Vec<String> = ["simulate", "--model", "twin"]
            .iter()
            .map(|s| s.to_string())
            .collect();
        v.extend(extra.iter().map(|s| s.to_string()));
        v
    };
    let own = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
    let cases: Vec<Vec<String>> = vec![
        sim(&["--preset", &sub, "--scenario", "cycloid", "--out", &out]),
        sim(&["--preset", &missing, "--scenario", "cycloid", "--out", &out]),
        sim(&[
            "--preset",
            &zero_mass,
            "--scenario",
            "cycloid",
            "--out",
            &out,
        ]),
        sim(&["--preset", &typed, "--scenario", "cycloid", "--out", &out]),
        sim(&["--preset", &unknown, "--scenario", "cycloid", "--out", &out]),
        sim(&["--preset", &version, "--scenario", "cycloid", "--out", &out]),
        sim(&["--scenario", "cycloid", "--duration", "0.01", "--out", &sub]),
        sim(&[
            "--scenario",
            "cycloid",
            "--duration",
            "0.01",
            "--out",
            &under_file,
        ]),
        sim(&["--excitation", &sub, "--out", &out]),
        sim(&["--excitation", &missing, "--out", &out]),
        sim(&["--excitation", &bad_cell, "--out", &out]),
        sim(&["--excitation", &short_row, "--out", &out]),
        sim(&["--scenario", "cycloid", "--duration=-1", "--out", &out]),
        sim(&["--scenario", "random", "--duration", "7200", "--out", &out]),
        own(&["bode", "--model", "linear", "--freqs", "1", "--out", &sub]),
        own(&[
            "bode", "--model", "linear", "--freqs", "1", "--amp", "0", "--out", &out,
        ]),
        own(&["bode", "--model", "passive", "--freqs", "1", "--out", &out]),
        own(&[
            "transmissibility",
            "--model",
            "linear",
            "--freqs",
            "1",
            "--out",
            &under_file,
        ]),
        own(&["replay", "--data", &sub, "--out", &out]),
        own(&["replay", "--data", &missing, "--out", &out]),
        own(&[
            "replay", "--data", &measured, "--preset", &zero_mass, "--out", &out,
        ]),
        own(&["calibrate", "--data", &sub, "--out", &sub]),
        own(&["calibrate", "--data", &measured, "--out", &under_file]),
        own(&["report", "--out", &a_file]),
        own(&["report", "--preset", &sub, "--out", &out]),
        own(&["bench", "--preset", &missing]),
    ];
    for args in &cases {
        let a: Vec<&str> = args.iter().map(String::as_str).collect();
        let o = run_within(&a, Duration::from_secs(60)).expect("fails within a minute");
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{args:?}: {err}");
        let segments = error_segments(&err);
        for (i, a) in segments.iter().enumerate() {
            for b in &segments[i + 1..] {
                assert!(
                    a.len() < 4 || a != b,
                    "{args:?}: {a:?} is printed twice in {err}"
                );
            }
        }
        assert!(
            !err.contains("(os error 21): Is a directory"),
            "{args:?}: {err}"
        );
    }
}

// ---------------------------------------------------------------------------------------------
// 8. Half-written result sets.

/// Before: `calibrate` ran the whole calibration, then failed to write, leaving files behind.
/// Now the output folder is checked first: it fails before any calibration stage.
#[test]
fn calibrate_checks_its_output_folder_before_it_starts() {
    let dir = tmp();
    let rec = dir.path().join("m.csv");
    measured_record(&rec, 2.0, 1.0, 0.002);
    let blocker = dir.path().join("blocker");
    std::fs::write(&blocker, "a file").unwrap();
    let out = blocker.join("cal");
    let o = run_within(
        &["calibrate", "--data", s(&rec), "--out", s(&out)],
        Duration::from_secs(60),
    )
    .expect("fails at once");
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("cannot write the results into"), "{err}");
    assert!(
        !err.lines().any(|l| l.starts_with('[')),
        "no calibration stage ran: {err}"
    );
    // Onto an existing file: refused the same way.
    let o = run(&["calibrate", "--data", s(&rec), "--out", s(&blocker)]);
    let err = stderr(&o);
    assert!(err.contains("exists and is not a directory"), "{err}");
    assert_eq!(std::fs::read_to_string(&blocker).unwrap(), "a file");
}

// ---------------------------------------------------------------------------------------------
// 9. Smaller items.

/// Before: outputs were created with mode 0600 whatever the umask.
#[cfg(unix)]
#[test]
fn outputs_honour_the_umask() {
    use std::os::unix::fs::PermissionsExt;
    let dir = tmp();
    for (umask, mode) in [("022", 0o644), ("027", 0o640)] {
        let out = dir.path().join(format!("u{umask}.csv"));
        let o = Command::new("sh")
            .arg("-c")
            .arg(format!("umask {umask} && exec \"$0\" \"$@\""))
            .arg(env!("CARGO_BIN_EXE_seat-twin"))
            .args([
                "bode",
                "--model",
                "linear",
                "--freqs",
                "1",
                "--out",
                s(&out),
            ])
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", stderr(&o));
        let m = out.metadata().unwrap().permissions().mode() & 0o777;
        assert_eq!(m, mode, "umask {umask}: mode {m:o}");
    }
}

/// Before: `--duration 1e300` printed 301 digits; a preset value of 1e300 too.
#[test]
fn huge_and_tiny_numbers_are_printed_short() {
    let dir = tmp();
    let out = dir.path().join("o.csv");
    let o = run(&[
        "simulate",
        "--model",
        "twin",
        "--scenario",
        "cycloid",
        "--duration",
        "1e300",
        "--out",
        s(&out),
    ]);
    let err = stderr(&o);
    assert!(err.contains("--duration 1e300 is outside"), "{err}");
    assert!(err.len() < 200, "{err}");
    let o = run(&[
        "simulate",
        "--model",
        "twin",
        "--scenario",
        "sine",
        "--freq",
        "1e-300",
        "--out",
        s(&out),
    ]);
    let err = stderr(&o);
    assert!(err.contains("--freq 1e-300 is outside"), "{err}");
    assert!(err.len() < 200, "{err}");
    let preset = dir.path().join("p.toml");
    std::fs::write(&preset, "[body]\nmass_kg = 1e300\n").unwrap();
    let o = run(&[
        "simulate",
        "--model",
        "twin",
        "--preset",
        s(&preset),
        "--scenario",
        "cycloid",
        "--out",
        s(&out),
    ]);
    let err = stderr(&o);
    assert!(
        err.contains("parameter `body.mass_kg` = 1e300 is outside the allowed range [1, 500] kg"),
        "{err}"
    );
    assert!(err.len() < 250, "{err}");
}

/// Before: `column "-"`.
#[test]
fn a_row_with_the_wrong_field_count_names_a_real_column() {
    let dir = tmp();
    let exc = dir.path().join("rows.csv");
    let out = dir.path().join("o.csv");
    for (text, expected) in [
        (
            "t,x,xdd\n0,0,0\n0.001,0\n",
            "rows.csv: line 3: column \"xdd\" is missing: the row \"0.001,0\" has 2 fields, \
             the header (line 1) has 3",
        ),
        (
            "t,x,xdd\n0,0,0\n0.001,0,0,7\n",
            "rows.csv: line 3: fields past the last column \"xdd\" are not expected: the row \
             \"0.001,0,0,7\" has 4 fields, the header (line 1) has 3",
        ),
    ] {
        std::fs::write(&exc, text).unwrap();
        let o = run(&[
            "simulate",
            "--model",
            "passive",
            "--excitation",
            s(&exc),
            "--out",
            s(&out),
        ]);
        let err = stderr(&o);
        assert!(err.contains(expected), "{err}");
        assert!(!err.contains("column \"-\""), "{err}");
    }
}

/// Before: "invalid type: map, expected f64" without the key.
#[test]
fn a_preset_type_error_names_the_key() {
    let dir = tmp();
    let out = dir.path().join("o.csv");
    for (text, expected) in [
        (
            "[body]\nmass_kg = { a = 1 }\n",
            "line 2, column 11: `body.mass_kg`: invalid type: map, expected f64",
        ),
        (
            "[valve]\ncd = \"0.15\"\n",
            "line 2, column 6: `valve.cd`: invalid type: string \"0.15\", expected f64",
        ),
        (
            "[effects.friction]\nenabled = 1\n",
            "`effects.friction.enabled`: invalid type: integer `1`, expected a boolean",
        ),
        (
            "numerics = { integrator = \"euler\" }\n",
            "`numerics.integrator`: unknown variant `euler`",
        ),
    ] {
        let preset = dir.path().join("t.toml");
        std::fs::write(&preset, text).unwrap();
        let o = run(&[
            "transmissibility",
            "--model",
            "linear",
            "--preset",
            s(&preset),
            "--freqs",
            "1",
            "--out",
            s(&out),
        ]);
        let err = stderr(&o);
        assert!(err.contains(expected), "{text}: {err}");
    }
}

/// Before: the plots were written into the target one by one, so when `report.md` could not
/// be written the new plots were left beside the old report. Now the set is written in a
/// temporary folder and moved only when every file can be: the target is left as it was.
#[test]
fn a_report_that_cannot_be_moved_into_place_leaves_the_old_set_untouched() {
    let dir = tmp();
    let out = dir.path().join("rep");
    std::fs::create_dir_all(out.join("report.md")).unwrap();
    std::fs::write(out.join("cycloid.png"), "old").unwrap();
    let o = run(&["report", "--out", s(&out)]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("moving the report into"), "{err}");
    assert!(
        err.contains("report.md is a directory; nothing was moved"),
        "{err}"
    );
    assert_eq!(
        std::fs::read_to_string(out.join("cycloid.png")).unwrap(),
        "old",
        "the old plot is untouched"
    );
    assert_eq!(entry_count(&out), 2, "nothing new in the target");
    assert!(
        entries_starting(dir.path(), ".rep.").is_empty(),
        "no temporary folder left"
    );
}
