//! The command line of `seat-twin`: its subcommands and options (clap), the checks of the
//! options' values that run before any work, and each subcommand's run.
//!
//! One file per subcommand holds its options (a `clap::Args` struct), their checks and its
//! run, through the [`Run`] trait: `simulate`, `report`, `response` (`bode` and
//! `transmissibility`), `replay`, `calibrate`, `seat_test`, `tune`, `bench` and `export`. This module
//! holds what they share: the [`Command`] enum and its one dispatch ([`Command::args`]), the
//! range checks, [`load_params`] and [`Heartbeat`]. Adding a subcommand is a file, a variant
//! and an arm of that dispatch.
//!
//! Numeric options take a value that starts with `-` as their value (`--duration -1`,
//! `--duration -inf`, `--freqs -1,2`), so that a number out of range gets the range message
//! rather than clap's "unexpected argument"; [`validate`] checks every numeric option of a
//! command against its documented range, without reading a file.

// The doc comments of the options are also their `--help` text, which clap prints as written:
// a unit stays `[s]` there rather than rustdoc's escaped `\[s\]`, so rustdoc's link check,
// which would read `[s]` as a link, is off for this module.
#![allow(rustdoc::broken_intra_doc_links)]

mod bench;
mod calibrate;
mod export;
mod replay;
mod report;
mod response;
mod seat_test;
mod simulate;
mod tune;

pub use bench::BenchArgs;
pub use calibrate::CalibrateArgs;
pub use export::{
    ExportArgs, ExportControllerArgs, ExportFmuArgs, ExportWhat, LangArg, PlacementArg,
};
pub use replay::ReplayArgs;
pub use report::ReportArgs;
pub use response::{BodeArgs, SweepArgs, TransmissibilityArgs};
pub use seat_test::SeatTestArgs;
pub use simulate::{ScenarioArg, SimulateArgs};
pub use tune::TuneArgs;

use crate::format::general;
use crate::params::Params;
use clap::Parser;

/// Longest `simulate` run [s] (10 h).
pub const MAX_DURATION_S: f64 = 36_000.0;
/// Longest random ride [s] (1 h).
pub const MAX_RANDOM_DURATION_S: f64 = 3600.0;
/// Largest command amplitude of a sine, chirp or dwell [V] (`--amp`).
pub const MAX_AMP_V: f64 = 100.0;
/// Allowed `--rate` [Hz].
pub const RATE_RANGE_HZ: (f64, f64) = (1.0, 100_000.0);
/// Allowed frequencies of `--freq`, `--f0`, `--f1` and `--freqs` [Hz].
pub const FREQ_RANGE_HZ: (f64, f64) = (0.01, 1000.0);
/// Shortest `--duration` [s].
pub const MIN_DURATION_S: f64 = 1e-3;
/// Most samples `simulate` writes to one file: 10 h at 1 kHz and a bit (about 10 GB of CSV).
pub const MAX_SIMULATE_SAMPLES: u64 = 50_000_000;

/// A command-line option with a value it does not accept.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{0}")]
pub struct OptionError(pub String);

#[derive(Debug, Parser)]
#[command(
    name = "seat-twin",
    version,
    about = "Digital twin and gain-tuning tool for a hydraulic active seat suspension",
    long_about = "Without a subcommand, opens the desktop app (when built with the `gui` feature).\n\
                  The subcommands run the same engine headless; all files are SI unless a column \
                  name says otherwise."
)]
/// The command line.
pub struct Cli {
    /// The subcommand; none opens the desktop app.
    #[command(subcommand)]
    pub command: Option<Command>,
}

/// The subcommands.
#[derive(Debug, clap::Subcommand)]
pub enum Command {
    /// Reproduce the paper's sections 4–6: report.md, numbers.json and PNG+SVG plots.
    Report(ReportArgs),
    /// Simulate one model on one scenario and write a CSV trace (SI columns).
    Simulate(SimulateArgs),
    /// Bode of u̇/V_in: columns freq_hz, mag_mm_per_s_v, phase_deg.
    Bode(BodeArgs),
    /// Transmissibility ÿ/ẍ with the controller: columns freq_hz, mag, phase_deg.
    Transmissibility(TransmissibilityArgs),
    /// Replay a measured record through the twin (its v_in and platform motion, open loop):
    /// columns t,u,ydd,p1,p2,xv,q1,q2 on the record's time grid (SI).
    Replay(ReplayArgs),
    /// Calibrate the twin on measured records: Cd, τ (and the mass), then trace the residual
    /// to a missing effect; writes report.md, report.json, calibrated.toml and plots to DIR.
    Calibrate(CalibrateArgs),
    /// A standard laboratory seat test: a seat-test input class on the platform, closed loop;
    /// writes report.md, numbers.json and PNG+SVG plots to DIR.
    SeatTest(SeatTestArgs),
    /// Real-time factors, accuracy against a 10× finer step, and the Table 1 sweep time.
    Bench(BenchArgs),
    /// Tune a controller's gains on the nonlinear twin (ISO 2631-1 objective of the body;
    /// stable at rest over Cd ±10 %, τ ±3 ms, mass ±20 %, no end-stop contact, max |u| ≤
    /// 30 mm, GM ≥ 6 dB, PM ≥ 45°, delay margin ≥ 3 ms; checked by a settle test at every
    /// point); writes report.md, report.json, plots and — when the claim holds — tuned.toml
    /// to DIR.
    Tune(TuneArgs),
    /// Export the twin as an FMI 2.0 co-simulation FMU (`export fmu`) or the controller as
    /// portable C99 (`export controller`).
    Export(ExportArgs),
}

/// Exit code of an error: bad input, a failed run, an output that could not be written
/// (nothing is written then, or the old output is left as it was).
pub const EXIT_ERROR: i32 = 1;
/// Exit code of a command line clap refuses (unknown option, missing value).
pub const EXIT_USAGE: i32 = 2;
/// Exit code of a run that ended and wrote its report but claims no result: `calibrate` with
/// the verdict `insufficient_data` (report.md and report.json written, no calibrated.toml).
pub const EXIT_NO_RESULT: i32 = 3;

/// How a subcommand that ran to its end ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Outcome {
    /// It did what it was asked: exit code 0.
    Done,
    /// It wrote its report, which claims no result ([`EXIT_NO_RESULT`]).
    NoResult,
}

impl Outcome {
    /// The process's exit code.
    pub fn exit_code(self) -> i32 {
        match self {
            Outcome::Done => 0,
            Outcome::NoResult => EXIT_NO_RESULT,
        }
    }
}

/// What every subcommand's options do: check their values, then run.
pub trait Run {
    /// Checks the options' values against their documented ranges, reading no file (the
    /// preset and the records are checked when read). The default accepts everything.
    fn validate(&self) -> Result<(), OptionError> {
        Ok(())
    }

    /// Runs the subcommand: reads its inputs, computes, writes its outputs, prints a summary.
    fn run(&self) -> anyhow::Result<Outcome>;
}

impl Command {
    /// The subcommand's options, which know how to check themselves and run.
    pub fn args(&self) -> &dyn Run {
        match self {
            Command::Report(a) => a,
            Command::Simulate(a) => a,
            Command::Bode(a) => a,
            Command::Transmissibility(a) => a,
            Command::Replay(a) => a,
            Command::Calibrate(a) => a,
            Command::SeatTest(a) => a,
            Command::Bench(a) => a,
            Command::Tune(a) => a,
            Command::Export(a) => a,
        }
    }
}

/// Checks every numeric option of `cmd` against its range, whether the command's scenario
/// or method uses it or not. Reads no file: the preset and the records are checked when read.
pub fn validate(cmd: &Command) -> Result<(), OptionError> {
    cmd.args().validate()
}

/// Checks `cmd`'s options ([`validate`]), then runs it.
pub fn run(cmd: &Command) -> anyhow::Result<Outcome> {
    let args = cmd.args();
    args.validate()?;
    args.run()
}

/// The parameters of a preset given as a file or a shipped preset's name.
pub fn load_params(name: &str) -> anyhow::Result<Params> {
    Ok(load_preset(name)?.params)
}

/// The data acquisition's anti-alias filter, declared on the command line (it overrides the
/// preset's `[sensors]` values).
#[derive(Debug, Clone, Copy, Default, clap::Args)]
pub struct AcquisitionArgs {
    /// Corner [Hz] of the data acquisition's anti-alias filter on every measured channel (a
    /// Butterworth low-pass; 0: none). The replay reads the twin's measured channels through
    /// it; undeclared, its delay reads as a longer valve delay τ.
    #[arg(long, value_name = "HZ", allow_negative_numbers = true)]
    pub antialias_hz: Option<f64>,
    /// Order of that filter, 1 to 8 [default: the preset's, 2 in the shipped presets].
    #[arg(long, value_name = "N")]
    pub antialias_order: Option<u8>,
}

impl AcquisitionArgs {
    /// `params` with the declared filter, validated; the error names the option, its value
    /// and the allowed range.
    pub fn apply(&self, mut params: Params) -> anyhow::Result<Params> {
        if let Some(hz) = self.antialias_hz {
            params.sensors.antialias_hz = hz;
        }
        if let Some(n) = self.antialias_order {
            params.sensors.antialias_order = f64::from(n);
        }
        let specs = [
            ("--antialias-hz", "sensors.antialias_hz", self.antialias_hz),
            (
                "--antialias-order",
                "sensors.antialias_order",
                self.antialias_order.map(f64::from),
            ),
        ];
        for (flag, key, given) in specs {
            if let (Some(v), Some(spec)) = (given, crate::params::spec(key))
                && let Err(e) = spec.check(v)
            {
                anyhow::bail!("{flag} {v}: {e}");
            }
        }
        Ok(params)
    }
}

/// The preset `--preset` names (a file or a shipped preset's name), whole: its parameters and
/// its per-record values.
pub fn load_preset(name: &str) -> anyhow::Result<crate::preset::Preset> {
    if name.trim().is_empty() {
        anyhow::bail!(
            "--preset is empty: give a preset file or the name of a shipped preset ({})",
            shipped_names()
        );
    }
    Ok(crate::preset::resolve(name)?)
}

/// "paper, paper-initial, …": the shipped presets' names.
fn shipped_names() -> String {
    let mut names: Vec<String> = crate::preset::shipped_presets()
        .into_iter()
        .map(|(n, _)| n)
        .collect();
    if names.is_empty() {
        names.push("paper".into());
    }
    names.join(", ")
}

/// The value parser of `--preset`: a path or a name as text. A path that is not valid UTF-8
/// is refused naming the option (clap's own message for it names none).
pub fn preset_parser() -> impl clap::builder::TypedValueParser<Value = String> {
    use clap::builder::TypedValueParser;
    clap::builder::OsStringValueParser::new().try_map(|os| {
        os.into_string().map_err(|os| {
            format!(
                "the path {:?} is not valid UTF-8: rename the file (or link to it) with a \
                 UTF-8 name",
                os.to_string_lossy()
            )
        })
    })
}

/// The value parser of `--seed`: a whole number in [0, 2^64 − 1]; a negative or fractional
/// one gets the range, not clap's "unexpected argument".
pub fn parse_seed(text: &str) -> Result<u64, String> {
    text.trim().parse::<u64>().map_err(|_| {
        format!(
            "{text} is not a whole number in the allowed range [0, {}]",
            u64::MAX
        )
    })
}

/// Refuses, before any work, an output file that is one of the inputs (`inputs`: the option
/// and the file it names): writing it would destroy the input.
pub fn check_output_is_not_an_input(
    out: &std::path::Path,
    inputs: &[(&str, &std::path::Path)],
) -> Result<(), OptionError> {
    for (option, input) in inputs {
        if crate::fsutil::same_file(input, out) {
            return Err(OptionError(format!(
                "--out {} is the same file as {option} {}: writing it would destroy the \
                 input; give another --out",
                out.display(),
                input.display()
            )));
        }
    }
    Ok(())
}

/// The file `--preset NAME` reads, for [`check_output_is_not_an_input`] (none for the
/// built-in paper preset).
pub fn preset_file(name: &str) -> Option<std::path::PathBuf> {
    crate::preset::locate(name)
}

/// Simulated seconds per wall-clock second and core of the twin at the default step, the
/// basis of the cost estimates (measured by `seat-twin bench` on the development machine:
/// about 2000× real time at 0.5 ms).
const TWIN_REAL_TIME_FACTOR: f64 = 2000.0;
/// The same for the linear and passive models (60 000–80 000× measured).
const LTI_REAL_TIME_FACTOR: f64 = 50_000.0;

/// Estimated wall time [s] of simulating `simulated_s` seconds of `kind` at step `step_s`
/// on `cores` cores in parallel.
pub fn estimate_wall_s(kind: crate::model::ModelKind, simulated_s: f64, step_s: f64) -> f64 {
    let default_step = crate::params::NumericsParams::default().max_step_s;
    let factor = match kind {
        crate::model::ModelKind::Twin => TWIN_REAL_TIME_FACTOR,
        _ => LTI_REAL_TIME_FACTOR,
    } * (step_s / default_step);
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get()) as f64;
    simulated_s / factor / cores
}

/// "40 s", "12 min", "3.5 h": a duration for people.
pub fn fmt_duration(s: f64) -> String {
    if s < 90.0 {
        format!("{} s", general(s.ceil()))
    } else if s < 5400.0 {
        format!("{} min", general((s / 60.0).round()))
    } else {
        format!("{} h", general((s / 360.0).round() / 10.0))
    }
}

/// Prints the up-front cost of a long job on stderr (when it is over 10 s) and starts a
/// [`Heartbeat`] that tells its progress every 10 s: `what` names the job, `cost` says what
/// it computes, `wall_s` is the estimate.
pub fn announce(what: &str, cost: &str, wall_s: f64) -> Heartbeat {
    if wall_s > 10.0 {
        eprintln!(
            "note: {what}: {cost}; estimated about {} on this machine",
            fmt_duration(wall_s)
        );
    }
    Heartbeat::start(what.to_string(), std::time::Duration::from_secs(10))
}

/// The seat-test input class called `name`, or an error listing the classes.
pub fn find_class(name: &str) -> anyhow::Result<&'static crate::scenario::InputClass> {
    use anyhow::Context;
    crate::seat_test::find(name).with_context(|| {
        format!(
            "unknown input class `{name}`; the classes are {}",
            crate::scenario::classes::names()
        )
    })
}

/// The error and its chain of causes, each message once: a cause whose text an outer message
/// already includes (`file: cause` over `cause`) is not repeated.
pub fn error_text(e: &anyhow::Error) -> String {
    let mut text = String::new();
    for cause in e.chain() {
        let msg = cause.to_string();
        let msg = msg.trim();
        if msg.is_empty() || text.contains(msg) {
            continue;
        }
        if !text.is_empty() {
            text.push_str(": ");
        }
        text.push_str(msg);
    }
    text
}

/// Prints "still running" with the elapsed time on stderr every `every` until dropped.
pub struct Heartbeat {
    stop: Option<std::sync::mpsc::Sender<()>>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl Heartbeat {
    /// Starts the thread that prints `what: still running` every `every`.
    pub fn start(what: String, every: std::time::Duration) -> Self {
        let (stop, rx) = std::sync::mpsc::channel::<()>();
        let started = std::time::Instant::now();
        let thread = std::thread::spawn(move || {
            while let Err(std::sync::mpsc::RecvTimeoutError::Timeout) = rx.recv_timeout(every) {
                eprintln!(
                    "[{:6.0} s] {what}: still running (Ctrl-C stops it and leaves nothing behind)",
                    started.elapsed().as_secs_f64()
                );
            }
        });
        Self {
            stop: Some(stop),
            thread: Some(thread),
        }
    }
}

impl Drop for Heartbeat {
    fn drop(&mut self) {
        drop(self.stop.take());
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// Checks `min <= v <= max` (and finiteness) of the option `name`.
pub fn check_range(name: &str, v: f64, min: f64, max: f64, unit: &str) -> Result<(), OptionError> {
    if v.is_finite() && v >= min && v <= max {
        Ok(())
    } else {
        Err(OptionError(format!(
            "{name} {} is outside the allowed range [{}, {}] {unit}",
            general(v),
            general(min),
            general(max)
        )))
    }
}

/// Checks `--freqs`: at least one, each within [`FREQ_RANGE_HZ`].
pub fn check_freqs(freqs: &[f64]) -> Result<(), OptionError> {
    if freqs.is_empty() {
        return Err(OptionError("--freqs needs at least one frequency".into()));
    }
    let (lo, hi) = FREQ_RANGE_HZ;
    for &f in freqs {
        check_range("--freqs value", f, lo, hi, "Hz")?;
    }
    Ok(())
}

/// Checks a dwell's `--amp`: in (0, [`MAX_AMP_V`]] (a dwell divides by it).
pub fn check_dwell_amp(amp: f64) -> Result<(), OptionError> {
    if amp.is_nan() || amp <= 0.0 {
        return Err(OptionError(format!(
            "--amp {} is outside the allowed range (0, {}] V: the sine dwell needs a command",
            general(amp),
            general(MAX_AMP_V)
        )));
    }
    check_range("--amp", amp, 0.0, MAX_AMP_V, "V")
}

/// Checks that a `simulate` run of `samples` samples (`duration` [s] at `rate` [Hz]) is within
/// [`MAX_SIMULATE_SAMPLES`].
pub fn check_sample_count(samples: u64, duration: f64, rate: f64) -> Result<(), OptionError> {
    if samples > MAX_SIMULATE_SAMPLES {
        return Err(OptionError(format!(
            "{} s at --rate {} Hz is {samples} samples, over the limit of \
             {MAX_SIMULATE_SAMPLES} samples per file; lower --duration or --rate",
            general(duration),
            general(rate)
        )));
    }
    Ok(())
}

/// The most memory this process may use [bytes] and what sets it: the smallest of the
/// address-space limit (`ulimit -v`), the cgroup's memory limit and the memory available on
/// the machine (Linux); `None` when none is known.
pub fn memory_limit() -> Option<(u64, &'static str)> {
    let mut limits: Vec<(u64, &'static str)> = Vec::new();
    #[cfg(unix)]
    {
        let mut r = libc::rlimit {
            rlim_cur: 0,
            rlim_max: 0,
        };
        // SAFETY: getrlimit writes into the struct it is given and reads nothing else.
        if unsafe { libc::getrlimit(libc::RLIMIT_AS, &mut r) } == 0
            && r.rlim_cur != libc::RLIM_INFINITY
        {
            // `rlim_t` is u64 on Linux and the BSDs.
            #[allow(clippy::useless_conversion)]
            let cur = u64::from(r.rlim_cur);
            limits.push((cur, "the address-space limit (ulimit -v)"));
        }
    }
    let read = |p: &str| std::fs::read_to_string(p).ok();
    if let Some(v) = read("/sys/fs/cgroup/memory.max").and_then(|t| t.trim().parse().ok()) {
        limits.push((v, "the cgroup's memory.max"));
    }
    if let Some(kb) = read("/proc/meminfo").and_then(|t| {
        t.lines()
            .find_map(|l| l.strip_prefix("MemAvailable:"))
            .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<u64>().ok())
    }) {
        limits.push((kb * 1024, "the memory available on this machine"));
    }
    limits.into_iter().min_by_key(|l| l.0)
}

/// Data rows of a record file and its header's fields, estimated from the file's size and
/// the mean length of its first and its last lines (times get longer towards the end of a
/// long record: from its first lines alone, a 20-million-row record looked 24 million).
pub(super) fn estimated_rows(path: &std::path::Path) -> Option<(u64, u64)> {
    use std::io::{Read, Seek};
    const SAMPLE: u64 = 64 * 1024;
    let size = std::fs::metadata(path).ok()?.len();
    let mut file = crate::fsutil::open_input(path).ok()?;
    let mut head = Vec::new();
    (&mut file).take(SAMPLE).read_to_end(&mut head).ok()?;
    let lines: Vec<&[u8]> = head
        .split(|&b| b == b'\n')
        .filter(|l| !l.is_empty() && l[0] != b'#')
        .collect();
    let fields = lines.first()?.iter().filter(|&&b| b == b',').count() as u64 + 1;
    // Mean bytes of the whole lines among `lines` (the last piece may be cut), from `skip` on.
    let mean = |lines: &[&[u8]], skip: usize| {
        let whole = lines.len().saturating_sub(1 + skip);
        let bytes: usize = lines
            .iter()
            .skip(skip)
            .take(whole)
            .map(|l| l.len() + 1)
            .sum();
        (whole > 0).then(|| bytes as f64 / whole as f64)
    };
    // The header is not a row.
    let head_mean = mean(&lines, 1).unwrap_or(1.0);
    let mut tail = Vec::new();
    let tail_mean = if size > 2 * SAMPLE
        && file.seek(std::io::SeekFrom::Start(size - SAMPLE)).is_ok()
        && file.take(SAMPLE).read_to_end(&mut tail).is_ok()
    {
        // The first piece may be cut, and so may the last.
        let lines: Vec<&[u8]> = tail.split(|&b| b == b'\n').skip(1).collect();
        mean(&lines, 0)
    } else {
        None
    };
    let per_row = tail_mean.map_or(head_mean, |t| 0.5 * (head_mean + t));
    Some(((size as f64 / per_row.max(1.0)) as u64, fields))
}

/// Memory a job holds per record row [bytes]: `row` plus `column` for each of the header's
/// fields (measured peaks, see the README's CLI section).
#[derive(Debug, Clone, Copy)]
pub struct RowCost {
    /// Bytes a row whatever its columns.
    pub row: u64,
    /// Bytes a row for each column.
    pub column: u64,
}

/// Refuses up front a job on records whose rows would need more memory than this process may
/// use ([`memory_limit`]): the message states the rows, the estimate and the limit, instead
/// of an allocation failure part-way through.
pub fn check_record_memory(
    what: &str,
    files: &[&std::path::Path],
    cost: RowCost,
) -> Result<(), OptionError> {
    let Some((limit, source)) = memory_limit() else {
        return Ok(());
    };
    let (mut rows, mut need) = (0, BASE_MEMORY_BYTES);
    for (r, fields) in files.iter().filter_map(|f| estimated_rows(f)) {
        rows += r;
        need += r * (cost.row + cost.column * fields);
    }
    if need > limit {
        let mb = |b: u64| general((b as f64 / 1e6).round());
        return Err(OptionError(format!(
            "{what} on about {} thousand record rows would need about {} MB, over the {} MB \
             of {source}; split the record or shorten it",
            general((rows as f64 / 1e3).round()),
            mb(need),
            mb(limit)
        )));
    }
    Ok(())
}

/// Memory of the process before any record is read [bytes] (the binary, the threads).
const BASE_MEMORY_BYTES: u64 = 50_000_000;
