//! The command line of `seat-twin`: its subcommands and options (clap), and the checks of the
//! options' values that run before any work.
//!
//! Numeric options take a value that starts with `-` as their value (`--duration -1`,
//! `--duration -inf`, `--freqs -1,2`), so that a number out of range gets the range message
//! rather than clap's "unexpected argument"; [`validate`] checks every numeric option of a
//! command against its documented range, without reading a file.

use crate::analysis::response::Method;
use crate::model::ModelKind;
use crate::params::fmt_value;
use clap::{Parser, Subcommand, ValueEnum};
use std::path::PathBuf;

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

/// `--scenario`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ScenarioArg {
    /// Cycloidal platform rise (30 mm in 0.5 s by default), closed loop.
    Cycloid,
    /// Band-limited random platform acceleration (0.5–5 Hz, S0 = 0.05), closed loop.
    Random,
    /// Valve sine test, platform still, open loop: V_in = A·cos(2πft).
    Sine,
    /// Valve linear chirp from --f0 to --f1, platform still, open loop.
    Chirp,
    /// A seat-test input spectral class (--class NAME: EM1–EM9, IT1–IT4, AG1–AG3), closed loop.
    Class,
}

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Reproduce the paper's sections 4–6: report.md, numbers.json and PNG+SVG plots.
    Report {
        /// Preset file or shipped preset name.
        #[arg(long, default_value = "paper")]
        preset: String,
        /// Output directory.
        #[arg(long, default_value = "out/report")]
        out: PathBuf,
    },
    /// Simulate one model on one scenario and write a CSV trace (SI columns).
    Simulate {
        /// Which model.
        #[arg(long, value_enum)]
        model: ModelKind,
        /// Preset file or shipped preset name.
        #[arg(long, default_value = "paper")]
        preset: String,
        /// The platform or valve scenario (or give --excitation).
        #[arg(long, value_enum, conflicts_with = "excitation")]
        scenario: Option<ScenarioArg>,
        /// Seed of the random ride.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Duration [s] (default: cycloid 5, random 60, sine max(3 s, 6 periods), chirp 10).
        #[arg(long, allow_hyphen_values = true)]
        duration: Option<f64>,
        /// Sine frequency [Hz].
        #[arg(long, default_value_t = 5.0, allow_hyphen_values = true)]
        freq: f64,
        /// Sine/chirp amplitude [V].
        #[arg(long, default_value_t = 2.1, allow_hyphen_values = true)]
        amp: f64,
        /// Chirp start frequency [Hz].
        #[arg(long, default_value_t = 0.5, allow_hyphen_values = true)]
        f0: f64,
        /// Chirp end frequency [Hz].
        #[arg(long, default_value_t = 20.0, allow_hyphen_values = true)]
        f1: f64,
        /// A platform record (CSV: `t` and `x` and/or `xdd`, SI); runs closed loop on it.
        #[arg(long)]
        excitation: Option<PathBuf>,
        /// Input spectral class of `--scenario class` (EM1–EM9, IT1–IT4, AG1–AG3).
        #[arg(long)]
        class: Option<String>,
        /// Output sample rate [Hz].
        #[arg(long, default_value_t = 1000.0, allow_hyphen_values = true)]
        rate: f64,
        /// Output file (CSV).
        #[arg(long)]
        out: PathBuf,
    },
    /// Bode of u̇/V_in: columns freq_hz, mag_mm_per_s_v, phase_deg.
    Bode {
        /// Which model.
        #[arg(long, value_enum)]
        model: ModelKind,
        /// Preset file or shipped preset name.
        #[arg(long, default_value = "paper")]
        preset: String,
        /// Command amplitude of the sine dwell [V] (twin).
        #[arg(long, default_value_t = 0.72, allow_hyphen_values = true)]
        amp: f64,
        /// Frequencies, method and output file.
        #[command(flatten)]
        sweep: SweepArgs,
    },
    /// Transmissibility ÿ/ẍ with the controller: columns freq_hz, mag, phase_deg.
    Transmissibility {
        /// Which model.
        #[arg(long, value_enum)]
        model: ModelKind,
        /// Preset file or shipped preset name.
        #[arg(long, default_value = "paper")]
        preset: String,
        /// Frequencies, method and output file.
        #[command(flatten)]
        sweep: SweepArgs,
    },
    /// Replay a measured record through the twin (its v_in and platform motion, open loop):
    /// columns t,u,ydd,p1,p2,xv,q1,q2 on the record's time grid (SI).
    Replay {
        /// Measured record (CSV: t, v_in, u; optional x, xdd, ydd, p1, p2).
        #[arg(long)]
        data: PathBuf,
        /// Preset file or shipped preset name.
        #[arg(long, default_value = "paper")]
        preset: String,
        /// Output file (CSV).
        #[arg(long)]
        out: PathBuf,
    },
    /// Calibrate the twin on measured records: Cd, τ (and the mass), then trace the residual
    /// to a missing effect; writes report.md, report.json, calibrated.toml and plots to DIR.
    Calibrate {
        /// Measured records (one or more CSV files).
        #[arg(long, num_args = 1.., required = true)]
        data: Vec<PathBuf>,
        /// Preset file or shipped preset name to start from.
        #[arg(long, default_value = "paper")]
        preset: String,
        /// Output directory.
        #[arg(long)]
        out: PathBuf,
    },
    /// A standard laboratory seat test: a seat-test input class on the platform, closed loop;
    /// writes report.md, numbers.json and PNG+SVG plots to DIR.
    SeatTest(SeatTestArgs),
    /// Real-time factors, accuracy against a 10× finer step, and the Table 1 sweep time.
    Bench {
        /// Preset file or shipped preset name.
        #[arg(long, default_value = "paper")]
        preset: String,
    },
    /// Tune a controller's gains on the nonlinear twin (ISO 2631-1 objective of the body,
    /// no end-stop contact, max |u| ≤ 30 mm, GM ≥ 6 dB, PM ≥ 45°); writes tuned.toml,
    /// report.md, report.json and plots to DIR.
    Tune(TuneArgs),
}

/// The options `bode` and `transmissibility` end with: the frequencies, the method, the file.
#[derive(Debug, clap::Args)]
pub struct SweepArgs {
    /// Comma-separated frequencies [Hz].
    #[arg(
        long,
        value_delimiter = ',',
        required = true,
        allow_hyphen_values = true
    )]
    pub freqs: Vec<f64>,
    /// Default: simulated for the twin, exact for linear and passive.
    #[arg(long, value_enum)]
    pub method: Option<Method>,
    /// Output file (CSV).
    #[arg(long)]
    pub out: PathBuf,
}

/// Arguments of `seat-twin tune`.
#[derive(Debug, clap::Args)]
pub struct TuneArgs {
    /// Preset file or shipped preset name (its plant, and its gains as the start).
    #[arg(long, default_value = "paper")]
    pub preset: String,
    /// Controller structure: paper, predictive, skyhook or smith (default: the preset's).
    #[arg(long)]
    pub controller: Option<String>,
    /// Objective: aw (Wk-weighted RMS), vdv or seat.
    #[arg(long, default_value = "aw")]
    pub objective: String,
    /// Tuning input: `ride` (the paper's random ride) or `class:NAME` (a seat-test input class).
    #[arg(long, default_value = "ride")]
    pub excitation: String,
    /// Number of tuning rides (seeds 1..=N); as many held-out rides use seeds 101...
    #[arg(long, default_value_t = 3, allow_negative_numbers = true)]
    pub seeds: i64,
    /// Duration of each ride [s], 5..=600.
    #[arg(long, default_value_t = 60.0, allow_negative_numbers = true)]
    pub duration: f64,
    /// Optimise the worst case over Cd ±10 %, τ ±3 ms, mass ±20 %.
    #[arg(long)]
    pub robust: bool,
    /// Budget of objective evaluations, 10..=10000.
    #[arg(long, default_value_t = 120, allow_negative_numbers = true)]
    pub evaluations: i64,
    /// Output directory.
    #[arg(long)]
    pub out: PathBuf,
}

/// Arguments of `seat-twin seat-test`.
#[derive(Debug, clap::Args)]
pub struct SeatTestArgs {
    /// Input spectral class: EM1–EM9 (ISO 7096), IT1–IT4 (EN 13490), AG1–AG3 (ISO 5007).
    #[arg(long)]
    pub class: String,
    /// Preset file or shipped preset name.
    #[arg(long, default_value = "paper")]
    pub preset: String,
    /// Which model.
    #[arg(long, value_enum, default_value = "twin")]
    pub model: ModelKind,
    /// Suspended mass [kg] (default: the preset's; the paper's rig carries 11.7 kg).
    #[arg(long, allow_hyphen_values = true)]
    pub mass: Option<f64>,
    /// Record length including 2 s fades at both ends [s].
    #[arg(long, default_value_t = crate::seat_test::run::DEFAULT_DURATION_S, allow_hyphen_values = true)]
    pub duration: f64,
    /// Seed of the class motion's phases.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Output directory.
    #[arg(long)]
    pub out: PathBuf,
}

/// Checks `min <= v <= max` (and finiteness) of the option `name`.
pub fn check_range(name: &str, v: f64, min: f64, max: f64, unit: &str) -> Result<(), OptionError> {
    if v.is_finite() && v >= min && v <= max {
        Ok(())
    } else {
        Err(OptionError(format!(
            "{name} {} is outside the allowed range [{}, {}] {unit}",
            fmt_value(v),
            fmt_value(min),
            fmt_value(max)
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
            fmt_value(amp),
            fmt_value(MAX_AMP_V)
        )));
    }
    check_range("--amp", amp, 0.0, MAX_AMP_V, "V")
}

/// Checks every numeric option of `cmd` against its range, whether the command's scenario
/// or method uses it or not. Reads no file: the preset and the records are checked when read.
pub fn validate(cmd: &Command) -> Result<(), OptionError> {
    let (flo, fhi) = FREQ_RANGE_HZ;
    match cmd {
        Command::Simulate {
            scenario,
            duration,
            freq,
            amp,
            f0,
            f1,
            rate,
            ..
        } => {
            check_range("--rate", *rate, RATE_RANGE_HZ.0, RATE_RANGE_HZ.1, "Hz")?;
            if let Some(d) = duration {
                let max = if *scenario == Some(ScenarioArg::Random) {
                    MAX_RANDOM_DURATION_S
                } else {
                    MAX_DURATION_S
                };
                check_range("--duration", *d, MIN_DURATION_S, max, "s")?;
            }
            check_range("--freq", *freq, flo, fhi, "Hz")?;
            check_range("--amp", *amp, 0.0, MAX_AMP_V, "V")?;
            check_range("--f0", *f0, flo, fhi, "Hz")?;
            check_range("--f1", *f1, flo, fhi, "Hz")?;
            Ok(())
        }
        Command::Bode { amp, sweep, .. } => {
            check_freqs(&sweep.freqs)?;
            check_dwell_amp(*amp)
        }
        Command::Transmissibility { sweep, .. } => check_freqs(&sweep.freqs),
        // Checked by their own runs (`seat-test`, `tune`), or no numeric option.
        Command::Report { .. }
        | Command::Replay { .. }
        | Command::Calibrate { .. }
        | Command::SeatTest(_)
        | Command::Bench { .. }
        | Command::Tune(_) => Ok(()),
    }
}

/// Checks that a `simulate` run of `samples` samples (`duration` [s] at `rate` [Hz]) is within
/// [`MAX_SIMULATE_SAMPLES`].
pub fn check_sample_count(samples: u64, duration: f64, rate: f64) -> Result<(), OptionError> {
    if samples > MAX_SIMULATE_SAMPLES {
        return Err(OptionError(format!(
            "{} s at --rate {} Hz is {samples} samples, over the limit of \
             {MAX_SIMULATE_SAMPLES} samples per file; lower --duration or --rate",
            fmt_value(duration),
            fmt_value(rate)
        )));
    }
    Ok(())
}
