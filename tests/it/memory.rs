//! Memory per record row (issue 21, item 7): the bytes a job allocates for each row of its
//! record, counted by this binary's global allocator on the test's own thread and taken as
//! the slope between two record lengths, so that fixed costs (buffers, plans) drop out.

use seat_twin::dataset::{self, ReadOptions, RecordKind};
use seat_twin::identify::replay::{MetricOptions, replay_streamed};
use seat_twin::params::Params;
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// The system allocator, counting the bytes each thread holds and the most it held.
struct Counting;

thread_local! {
    static LIVE: Cell<isize> = const { Cell::new(0) };
    static PEAK: Cell<isize> = const { Cell::new(0) };
}

fn count(delta: isize) {
    // `try_with`: a thread being torn down no longer counts (nothing to measure there).
    let _ = LIVE.try_with(|live| {
        let now = live.get() + delta;
        live.set(now);
        let _ = PEAK.try_with(|peak| peak.set(peak.get().max(now)));
    });
}

// SAFETY: every call goes to the system allocator unchanged; the counting touches only
// constant-initialised thread-locals, which never allocate.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        // SAFETY: the caller's contract, passed on.
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            count(layout.size() as isize);
        }
        p
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        // SAFETY: the caller's contract, passed on.
        let p = unsafe { System.alloc_zeroed(layout) };
        if !p.is_null() {
            count(layout.size() as isize);
        }
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: the caller's contract, passed on.
        unsafe { System.dealloc(ptr, layout) };
        count(-(layout.size() as isize));
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        // SAFETY: the caller's contract, passed on.
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if !p.is_null() {
            count(new_size as isize - layout.size() as isize);
        }
        p
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

/// `f`'s result and the most bytes this thread held during it beyond what it held before.
fn peak_during<T>(f: impl FnOnce() -> T) -> (T, usize) {
    let before = LIVE.with(Cell::get);
    PEAK.with(|p| p.set(before));
    let out = f();
    (out, (PEAK.with(Cell::get) - before).max(0) as usize)
}

/// A measured record of `rows` rows at 1 kHz with all eight columns, as the rig writes them
/// (about 80 bytes a row of text).
fn eight_column_record(dir: &Path, rows: usize) -> PathBuf {
    let mut text = String::from("# sample_rate_hz: 1000\nt,v_in,u,x,xdd,ydd,p1,p2\n");
    for i in 0..rows {
        let t = i as f64 / 1000.0;
        let w = (2.0 * std::f64::consts::PI * 2.0 * t).sin();
        let _ = writeln!(
            text,
            "{t:.3},{:.4},{:.6},{:.3e},{:.4},{:.4},{:.0},{:.0}",
            0.5 * w,
            0.001 * w,
            1e-5 * w,
            0.01 * w,
            0.2 * w,
            2e6 + 1e5 * w,
            2e6 - 1e5 * w
        );
    }
    let path = dir.join(format!("rec{rows}.csv"));
    std::fs::write(&path, text).unwrap();
    path
}

/// Bytes a row that `job` allocates at its peak on a record of `n` rows: the slope between
/// `n` and `2n` rows.
fn bytes_per_row(dir: &Path, n: usize, job: impl Fn(&Path)) -> f64 {
    let small = eight_column_record(dir, n);
    let large = eight_column_record(dir, 2 * n);
    let ((), a) = peak_during(|| job(&small));
    let ((), b) = peak_during(|| job(&large));
    (b as f64 - a as f64) / n as f64
}

/// Before: the reader held the file's whole text beside the columns it parsed, 150 bytes a
/// row for this 8-column record (80 of text, 64 of columns, 8 for the median step). Now it
/// reads line by line: 8 bytes a row for each column it stores, and 8 for the median step.
#[test]
fn reading_a_record_holds_its_columns_not_its_text() {
    let dir = tempfile::tempdir().unwrap();
    let all = bytes_per_row(dir.path(), 50_000, |p| {
        let r = dataset::read_record(p, RecordKind::Measured).unwrap();
        assert!(r.p2.is_some());
    });
    assert!((71.0..=73.0).contains(&all), "{all} bytes a row");
    let three = bytes_per_row(dir.path(), 50_000, |p| {
        let options = ReadOptions {
            keep: &["t", "v_in", "u"],
            ..Default::default()
        };
        let r = dataset::read_record_with(p, RecordKind::Measured, options).unwrap();
        assert!(r.u.is_some() && r.x.is_none() && r.p2.is_none());
        assert!(r.warnings.is_empty(), "{:?}", r.warnings);
    });
    assert!((31.0..=33.0).contains(&three), "{three} bytes a row");
}

/// `seat-twin replay`'s job (the record read with the replayed columns, the twin's samples
/// handed on as they are made) holds at most 100 bytes a record row, on a record of all eight
/// columns whose platform moves. Before: 156 bytes a row (the reader's text).
#[test]
fn a_replay_holds_at_most_100_bytes_a_record_row() {
    let dir = tempfile::tempdir().unwrap();
    let params = Params::paper();
    let per_row = bytes_per_row(dir.path(), 10_000, |p| {
        let options = ReadOptions {
            keep: &["t", "v_in", "u", "x", "xdd", "ydd"],
            ..Default::default()
        };
        let rec = dataset::read_record_with(p, RecordKind::Measured, options).unwrap();
        let mut samples = 0;
        let e =
            replay_streamed(&params, rec, &MetricOptions::default(), |_, _| samples += 1).unwrap();
        assert_eq!(e.samples, samples);
    });
    assert!(per_row <= 100.0, "{per_row} bytes a row");
}

/// Before: a record calibrate could not hold aborted it part-way ("memory allocation of …
/// bytes failed", exit 134) and left its hidden `.cal.*.tmp` folder. Now a record over
/// calibrate's 2 000 000 rows is refused before it is read, naming the file, its rows, the
/// limit and what to do, and nothing is created beside `--out`.
#[test]
fn calibrate_refuses_a_record_over_its_row_limit_up_front_and_leaves_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let rec = dir.path().join("long.csv");
    let rows = 2_100_000;
    let mut text = String::with_capacity(rows * 16);
    text.push_str("t,v_in,u\n");
    for i in 0..rows {
        let _ = writeln!(text, "{}.{:03},0.5,0", i / 1000, i % 1000);
    }
    std::fs::write(&rec, text).unwrap();
    let out = dir.path().join("cal");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_seat-twin"))
        .args(["calibrate", "--data"])
        .arg(&rec)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains(&format!("calibrate: {}: about 2", rec.display()))
            && err.contains("data rows (from its size), over the limit of 2000000 rows")
            && err.contains("decimate the record"),
        "{err}"
    );
    let left: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(left, [std::ffi::OsString::from("long.csv")], "{err}");
}
