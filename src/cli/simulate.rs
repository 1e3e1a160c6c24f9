//! `seat-twin simulate`: one model on one scenario, streamed into one CSV file.

use super::{
    FREQ_RANGE_HZ, Heartbeat, MAX_AMP_V, MAX_DURATION_S, MAX_RANDOM_DURATION_S, MIN_DURATION_S,
    OptionError, Outcome, RATE_RANGE_HZ, Run, check_output_is_not_an_input, check_range,
    check_sample_count, find_class, load_params, preset_file,
};
use crate::analysis::dwell;
use crate::dataset::{self, RecordKind};
use crate::experiments::RunSpec;
use crate::format::general;
use crate::model::ModelKind;
use crate::scenario::{CommandSignal, Cycloid, PlatformMotion, RandomRide, SampledMotion};
use crate::simulation::{
    ContactEvent, CsvRunError, Drive, SAMPLE_UNITS, sample_count, step_for_rate,
};
use anyhow::{Context, Result, bail};
use clap::ValueEnum;
use std::path::PathBuf;

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

/// Options of `seat-twin simulate`.
#[derive(Debug, clap::Args)]
pub struct SimulateArgs {
    /// Which model.
    #[arg(long, value_enum)]
    pub model: ModelKind,
    /// Preset file or shipped preset name.
    #[arg(long, default_value = "paper", value_parser = super::preset_parser())]
    pub preset: String,
    /// The platform or valve scenario (or give --excitation).
    #[arg(long, value_enum, conflicts_with = "excitation")]
    pub scenario: Option<ScenarioArg>,
    /// Seed of the random ride or the class motion, 0..=2^64−1 (default 1).
    #[arg(long, allow_hyphen_values = true, value_parser = super::parse_seed)]
    pub seed: Option<u64>,
    /// Duration [s] (default: cycloid 5, random 60, sine max(3 s, 6 periods), chirp 10).
    #[arg(long, allow_hyphen_values = true)]
    pub duration: Option<f64>,
    /// Sine frequency [Hz] (default 5).
    #[arg(long, allow_hyphen_values = true)]
    pub freq: Option<f64>,
    /// Sine/chirp amplitude [V] (default 2.1).
    #[arg(long, allow_hyphen_values = true)]
    pub amp: Option<f64>,
    /// Chirp start frequency [Hz] (default 0.5).
    #[arg(long, allow_hyphen_values = true)]
    pub f0: Option<f64>,
    /// Chirp end frequency [Hz] (default 20).
    #[arg(long, allow_hyphen_values = true)]
    pub f1: Option<f64>,
    /// A platform record (CSV: `t` and `x` and/or `xdd`, SI); runs closed loop on it.
    #[arg(long)]
    pub excitation: Option<PathBuf>,
    /// Input spectral class of `--scenario class` (EM1–EM9, IT1–IT4, AG1–AG3).
    #[arg(long)]
    pub class: Option<String>,
    /// Output sample rate [Hz].
    #[arg(long, default_value_t = 1000.0, allow_hyphen_values = true)]
    pub rate: f64,
    /// Output file (CSV).
    #[arg(long)]
    pub out: PathBuf,
}

/// Defaults of the scenario options.
const DEFAULT_SEED: u64 = 1;
const DEFAULT_FREQ_HZ: f64 = 5.0;
const DEFAULT_AMP_V: f64 = 2.1;
const DEFAULT_F0_HZ: f64 = 0.5;
const DEFAULT_F1_HZ: f64 = 20.0;

impl SimulateArgs {
    /// The scenario options given, each with the scenarios that use it.
    fn scenario_options(&self) -> [(&'static str, bool, &'static [ScenarioArg]); 6] {
        use ScenarioArg::{Chirp, Class, Random, Sine};
        [
            ("--seed", self.seed.is_some(), &[Random, Class]),
            ("--freq", self.freq.is_some(), &[Sine]),
            ("--amp", self.amp.is_some(), &[Sine, Chirp]),
            ("--f0", self.f0.is_some(), &[Chirp]),
            ("--f1", self.f1.is_some(), &[Chirp]),
            ("--class", self.class.is_some(), &[Class]),
        ]
    }
}

impl Run for SimulateArgs {
    fn validate(&self) -> Result<(), OptionError> {
        let (flo, fhi) = FREQ_RANGE_HZ;
        check_range("--rate", self.rate, RATE_RANGE_HZ.0, RATE_RANGE_HZ.1, "Hz")?;
        if let Some(d) = self.duration {
            let max = if self.scenario == Some(ScenarioArg::Random) {
                MAX_RANDOM_DURATION_S
            } else {
                MAX_DURATION_S
            };
            check_range("--duration", d, MIN_DURATION_S, max, "s")?;
        }
        let given = |v: Option<f64>, default| v.unwrap_or(default);
        check_range("--freq", given(self.freq, DEFAULT_FREQ_HZ), flo, fhi, "Hz")?;
        check_range("--amp", given(self.amp, DEFAULT_AMP_V), 0.0, MAX_AMP_V, "V")?;
        check_range("--f0", given(self.f0, DEFAULT_F0_HZ), flo, fhi, "Hz")?;
        check_range("--f1", given(self.f1, DEFAULT_F1_HZ), flo, fhi, "Hz")?;
        // An option the chosen scenario does not use is refused, not silently ignored.
        let (used_by, name) = match (&self.excitation, self.scenario) {
            (Some(_), _) => (None, "--excitation".to_string()),
            (None, Some(s)) => (Some(s), format!("--scenario {}", scenario_name(s))),
            (None, None) => return Ok(()),
        };
        for (option, is_given, scenarios) in self.scenario_options() {
            if is_given && !used_by.is_some_and(|s| scenarios.contains(&s)) {
                let names: Vec<&str> = scenarios.iter().map(|&s| scenario_name(s)).collect();
                return Err(OptionError(format!(
                    "{option} is not used with {name}: it applies to --scenario {} only",
                    names.join(" or ")
                )));
            }
        }
        Ok(())
    }

    fn run(&self) -> Result<Outcome> {
        let SimulateArgs {
            model: kind,
            preset,
            scenario,
            seed,
            duration,
            freq,
            amp,
            f0,
            f1,
            excitation,
            class,
            rate,
            out,
        } = self;
        let (kind, rate) = (*kind, *rate);
        let seed = seed.unwrap_or(DEFAULT_SEED);
        let freq = freq.unwrap_or(DEFAULT_FREQ_HZ);
        let amp = amp.unwrap_or(DEFAULT_AMP_V);
        let (f0, f1) = (f0.unwrap_or(DEFAULT_F0_HZ), f1.unwrap_or(DEFAULT_F1_HZ));
        // Every numeric option has been checked by validate; no input is overwritten.
        let mut inputs: Vec<(&str, &std::path::Path)> = Vec::new();
        inputs.extend(excitation.as_deref().map(|p| ("--excitation", p)));
        let preset_file = preset_file(preset);
        inputs.extend(preset_file.as_deref().map(|p| ("--preset", p)));
        check_output_is_not_an_input(out, &inputs)?;
        let params = load_params(preset)?;
        let mut warnings: Vec<String> = Vec::new();
        let mut peak_input: Option<String> = None;
        let (drive, platform, default_duration, label) = match (scenario, excitation) {
            (_, Some(path)) => {
                // Only the platform's columns drive the run.
                let rec = dataset::read_record_with(
                    path,
                    RecordKind::Excitation,
                    dataset::ReadOptions {
                        keep: &["t", "x", "xdd"],
                        ..Default::default()
                    },
                )?;
                for w in &rec.warnings {
                    eprintln!("warning: {}: {w}", path.display());
                    warnings.push(w.clone());
                }
                peak_input = record_peak(&rec);
                let Some(motion) = SampledMotion::from_record(&rec) else {
                    bail!("{}: no `x` or `xdd` column", path.display())
                };
                let d = motion.duration_s();
                (
                    Drive::closed_loop(&params),
                    PlatformMotion::Sampled(motion),
                    d,
                    format!("excitation {}", path.display()),
                )
            }
            (Some(ScenarioArg::Cycloid), None) => (
                Drive::closed_loop(&params),
                PlatformMotion::Cycloid(Cycloid::default()),
                5.0,
                "cycloid 30 mm in 0.5 s".to_string(),
            ),
            (Some(ScenarioArg::Random), None) => {
                let duration_s = duration.unwrap_or(60.0);
                let ride = RandomRide {
                    seed,
                    duration_s,
                    // The paper's 2 s fade-in, shortened for short runs.
                    fade_in_s: (duration_s / 4.0).min(2.0),
                    ..Default::default()
                };
                ride.validate()?;
                (
                    Drive::closed_loop(&params),
                    PlatformMotion::Sampled(ride.generate()),
                    ride.duration_s,
                    format!("random ride seed {seed}"),
                )
            }
            (Some(ScenarioArg::Sine), None) => (
                Drive::OpenLoop(CommandSignal::Sine {
                    amplitude_v: amp,
                    freq_hz: freq,
                }),
                PlatformMotion::Still,
                (6.0 / freq).max(3.0),
                format!("valve sine {} Hz {} V", general(freq), general(amp)),
            ),
            (Some(ScenarioArg::Chirp), None) => {
                let d = duration.unwrap_or(10.0);
                (
                    dwell::chirp_drive(amp, f0, f1, d),
                    PlatformMotion::Still,
                    d,
                    format!(
                        "valve chirp {}–{} Hz {} V",
                        general(f0),
                        general(f1),
                        general(amp)
                    ),
                )
            }
            (Some(ScenarioArg::Class), None) => {
                let Some(name) = class.as_deref() else {
                    bail!(
                        "--scenario class needs --class NAME ({})",
                        crate::scenario::classes::names()
                    );
                };
                let class = find_class(name)?;
                let motion = crate::scenario::ClassMotion {
                    seed,
                    ..crate::scenario::ClassMotion::new(
                        class,
                        duration.unwrap_or(crate::seat_test::run::DEFAULT_DURATION_S),
                    )
                };
                let sampled = motion.generate()?;
                let d = sampled.duration_s();
                (
                    Drive::closed_loop(&params),
                    PlatformMotion::Sampled(sampled),
                    d,
                    format!("seat-test input class {} seed {seed}", class.name),
                )
            }
            (None, None) => {
                bail!("give --scenario cycloid|random|sine|chirp|class or --excitation FILE.csv")
            }
        };
        let duration = match duration {
            Some(d) => *d,
            None => {
                check_range(
                    "the scenario's duration (set --duration)",
                    default_duration,
                    1e-3,
                    MAX_DURATION_S,
                    "s",
                )?;
                default_duration
            }
        };
        let h = step_for_rate(params.numerics.max_step_s, rate);
        let samples = sample_count(duration, rate, h);
        check_sample_count(samples, duration, rate)?;
        let mut comments = vec![
            ("model".to_string(), kind.name().to_string()),
            ("preset".to_string(), preset.clone()),
            ("scenario".to_string(), label.clone()),
            ("units".to_string(), SAMPLE_UNITS.to_string()),
        ];
        comments.extend(warnings.into_iter().map(|w| ("warning".to_string(), w)));
        let spec = RunSpec {
            params: &params,
            kind,
            drive,
            platform,
            duration_s: duration,
            rate_hz: rate,
        };
        let heartbeat = (samples > 2_000_000).then(|| {
            Heartbeat::start(
                format!("simulating {samples} samples"),
                std::time::Duration::from_secs(10),
            )
        });
        let summary =
            match spec.write_csv(out, &comments) {
                Ok(s) => s,
                Err(CsvRunError::Sim(e)) => {
                    return Err(
                        anyhow::Error::new(e).context(match (excitation, peak_input) {
                            (Some(path), Some(peak)) => format!(
                                "the run on the excitation record {} diverged; {peak}: is the \
                             record in SI units (m, m/s²)?",
                                path.display()
                            ),
                            (Some(path), None) => format!(
                                "the run on the excitation record {} diverged",
                                path.display()
                            ),
                            (None, _) => format!(
                                "the {label} run diverged (preset {preset}, --rate {})",
                                general(rate)
                            ),
                        }),
                    );
                }
                // A value beyond what a record holds (the writer's bounds) comes from the run's
                // input, not from the output file.
                Err(CsvRunError::Io(e)) if e.kind() == std::io::ErrorKind::InvalidInput => {
                    return Err(anyhow::Error::new(e).context(match (excitation, peak_input) {
                    (Some(path), Some(peak)) => format!(
                        "the run on the excitation record {} left the range a record holds, \
                         so nothing was written; {peak}: is the record in SI units (m, m/s²)?",
                        path.display()
                    ),
                    _ => format!(
                        "the {label} run left the range a record holds, so nothing was \
                         written (preset {preset})"
                    ),
                }));
                }
                Err(CsvRunError::Io(e)) => {
                    return Err(anyhow::Error::new(e))
                        .with_context(|| format!("writing {}", out.display()));
                }
            };
        drop(heartbeat);
        report_contacts(kind, &summary.contacts);
        println!(
            "{} samples of the {} model written to {}",
            summary.samples,
            kind.name(),
            out.display()
        );
        Ok(Outcome::Done)
    }
}

/// The scenario's name as on the command line.
fn scenario_name(s: ScenarioArg) -> &'static str {
    match s {
        ScenarioArg::Cycloid => "cycloid",
        ScenarioArg::Random => "random",
        ScenarioArg::Sine => "sine",
        ScenarioArg::Chirp => "chirp",
        ScenarioArg::Class => "class",
    }
}

/// "column "xdd" peaks at 9e5 m/s² at t = 1.2 s (sample 1201)": the largest driving value of
/// an excitation record, to name when a run on it diverges.
fn record_peak(rec: &dataset::Record) -> Option<String> {
    let (name, unit, col) = match (&rec.xdd, &rec.x) {
        (Some(xdd), _) => ("xdd", "m/s²", xdd),
        (None, Some(x)) => ("x", "m", x),
        (None, None) => return None,
    };
    // The first of equal peaks.
    let (i, v) = col
        .iter()
        .enumerate()
        .rev()
        .max_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))?;
    Some(format!(
        "its column \"{name}\" peaks at {} {unit} at t = {} s (data row {})",
        general(*v),
        general(rec.t[i]),
        i + 1
    ))
}

fn report_contacts(kind: ModelKind, contacts: &[ContactEvent]) {
    let Some(first) = contacts.first() else {
        return;
    };
    let what = if kind.has_hydraulics() {
        "end-stop contact"
    } else {
        "stroke overrun (this model has no end stops)"
    };
    eprintln!(
        "warning: {} {what} event(s); first at t = {:.3} s",
        contacts.len(),
        first.t_start
    );
}
