//! `seat-twin`: with no subcommand it opens the desktop app (feature `gui`); the subcommands
//! run the same engine headless.

use anyhow::{Context, Result, bail};
use clap::{Parser, Subcommand, ValueEnum};
use seat_twin::analysis::frequency_response as fr;
use seat_twin::dataset::{self, RecordKind};
use seat_twin::experiments;
use seat_twin::identify;
use seat_twin::model::ModelKind;
use seat_twin::params::Params;
use seat_twin::preset;
use seat_twin::scenario::{CommandSignal, Cycloid, PlatformMotion, RandomRide, SampledMotion};
use seat_twin::simulation::{Drive, Trace};
use std::path::{Path, PathBuf};

#[derive(Parser)]
#[command(
    name = "seat-twin",
    version,
    about = "Digital twin and gain-tuning tool for a hydraulic active seat suspension",
    long_about = "Without a subcommand, opens the desktop app (when built with the `gui` feature).\n\
                  The subcommands run the same engine headless; all files are SI unless a column \
                  name says otherwise."
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Clone, Copy, ValueEnum)]
enum ModelArg {
    Twin,
    Linear,
    Passive,
}

impl From<ModelArg> for ModelKind {
    fn from(m: ModelArg) -> Self {
        match m {
            ModelArg::Twin => ModelKind::Twin,
            ModelArg::Linear => ModelKind::Linear,
            ModelArg::Passive => ModelKind::Passive,
        }
    }
}

#[derive(Clone, Copy, ValueEnum)]
enum ScenarioArg {
    /// Cycloidal platform rise (30 mm in 0.5 s by default), closed loop.
    Cycloid,
    /// Band-limited random platform acceleration (0.5–5 Hz, S0 = 0.05), closed loop.
    Random,
    /// Valve sine test, platform still, open loop: V_in = A·cos(2πft).
    Sine,
    /// Valve linear chirp from --f0 to --f1, platform still, open loop.
    Chirp,
}

#[derive(Clone, Copy, ValueEnum)]
enum MethodArg {
    /// Closed form (linear and passive models).
    Exact,
    /// Sine dwell by simulation, first harmonic.
    Simulated,
    /// Numerical linearisation at rest, evaluated on jω (twin).
    Linearised,
}

#[derive(Subcommand)]
enum Command {
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
        #[arg(long, value_enum)]
        model: ModelArg,
        #[arg(long, default_value = "paper")]
        preset: String,
        #[arg(long, value_enum, conflicts_with = "excitation")]
        scenario: Option<ScenarioArg>,
        /// Seed of the random ride.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Duration [s] (default: cycloid 5, random 60, sine max(3 s, 6 periods), chirp 10).
        #[arg(long)]
        duration: Option<f64>,
        /// Sine frequency [Hz].
        #[arg(long, default_value_t = 5.0)]
        freq: f64,
        /// Sine/chirp amplitude [V].
        #[arg(long, default_value_t = 2.1)]
        amp: f64,
        /// Chirp start frequency [Hz].
        #[arg(long, default_value_t = 0.5)]
        f0: f64,
        /// Chirp end frequency [Hz].
        #[arg(long, default_value_t = 20.0)]
        f1: f64,
        /// A platform record (CSV: `t` and `x` and/or `xdd`, SI); runs closed loop on it.
        #[arg(long)]
        excitation: Option<PathBuf>,
        /// Output sample rate [Hz].
        #[arg(long, default_value_t = 1000.0)]
        rate: f64,
        #[arg(long)]
        out: PathBuf,
    },
    /// Bode of u̇/V_in: columns freq_hz, mag_mm_per_s_v, phase_deg.
    Bode {
        #[arg(long, value_enum)]
        model: ModelArg,
        #[arg(long, default_value = "paper")]
        preset: String,
        /// Command amplitude of the sine dwell [V] (twin).
        #[arg(long, default_value_t = 0.72)]
        amp: f64,
        /// Comma-separated frequencies [Hz].
        #[arg(long, value_delimiter = ',', required = true)]
        freqs: Vec<f64>,
        /// Default: simulated for the twin, exact for the linear model.
        #[arg(long, value_enum)]
        method: Option<MethodArg>,
        #[arg(long)]
        out: PathBuf,
    },
    /// Transmissibility ÿ/ẍ with the controller: columns freq_hz, mag, phase_deg.
    Transmissibility {
        #[arg(long, value_enum)]
        model: ModelArg,
        #[arg(long, default_value = "paper")]
        preset: String,
        /// Comma-separated frequencies [Hz].
        #[arg(long, value_delimiter = ',', required = true)]
        freqs: Vec<f64>,
        /// Default: simulated for the twin, exact for linear and passive.
        #[arg(long, value_enum)]
        method: Option<MethodArg>,
        #[arg(long)]
        out: PathBuf,
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
    /// Real-time factors, accuracy against a 10× finer step, and the Table 1 sweep time.
    Bench {
        /// Preset file or shipped preset name.
        #[arg(long, default_value = "paper")]
        preset: String,
    },
}

fn main() {
    let cli = Cli::parse();
    let result = match cli.command {
        None => open_app(),
        Some(cmd) => run(cmd),
    };
    if let Err(e) = result {
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}

#[cfg(feature = "gui")]
fn open_app() -> Result<()> {
    seat_twin::gui::run_native().map_err(|e| anyhow::anyhow!("the app could not start: {e}"))
}

#[cfg(not(feature = "gui"))]
fn open_app() -> Result<()> {
    use clap::CommandFactory;
    Cli::command().print_help()?;
    println!("\n\n(built without the `gui` feature: use a subcommand)");
    Ok(())
}

fn load_params(name: &str) -> Result<Params> {
    Ok(preset::resolve(name)?.params)
}

fn run(cmd: Command) -> Result<()> {
    match cmd {
        Command::Report { preset, out } => {
            let params = load_params(&preset)?;
            let summary = seat_twin::report::write_report(&params, &preset, &out)?;
            println!("{summary}");
            println!("report written to {}", out.join("report.md").display());
            Ok(())
        }
        Command::Simulate {
            model,
            preset,
            scenario,
            seed,
            duration,
            freq,
            amp,
            f0,
            f1,
            excitation,
            rate,
            out,
        } => {
            let params = load_params(&preset)?;
            if !(rate.is_finite() && (1.0..=100_000.0).contains(&rate)) {
                bail!("--rate {rate} is outside the allowed range [1, 100000] Hz");
            }
            let kind: ModelKind = model.into();
            let (drive, platform, default_duration, label) = match (scenario, &excitation) {
                (_, Some(path)) => {
                    let rec = dataset::read_record(path, RecordKind::Excitation)?;
                    let dt = rec.dt;
                    let motion = match (rec.xdd.clone(), rec.x.clone()) {
                        (Some(xdd), Some(x)) => {
                            // xdd drives the dynamics; x is only reported.
                            SampledMotion::from_acceleration(dt, xdd).with_reported_position(x)
                        }
                        (Some(xdd), None) => SampledMotion::from_acceleration(dt, xdd),
                        (None, Some(x)) => SampledMotion::from_position(dt, x),
                        (None, None) => bail!("{}: no `x` or `xdd` column", path.display()),
                    };
                    let d = motion.duration_s();
                    (
                        experiments::closed_loop(&params),
                        PlatformMotion::Sampled(motion),
                        d,
                        format!("excitation {}", path.display()),
                    )
                }
                (Some(ScenarioArg::Cycloid), None) => (
                    experiments::closed_loop(&params),
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
                        experiments::closed_loop(&params),
                        PlatformMotion::Sampled(ride.generate()),
                        ride.duration_s,
                        format!("random ride seed {seed}"),
                    )
                }
                (Some(ScenarioArg::Sine), None) => {
                    check_range("--freq", freq, 0.01, 1000.0, "Hz")?;
                    check_range("--amp", amp, 0.0, 100.0, "V")?;
                    (
                        Drive::OpenLoop(CommandSignal::Sine {
                            amplitude_v: amp,
                            freq_hz: freq,
                        }),
                        PlatformMotion::Still,
                        (6.0 / freq).max(3.0),
                        format!("valve sine {freq} Hz {amp} V"),
                    )
                }
                (Some(ScenarioArg::Chirp), None) => {
                    check_range("--f0", f0, 0.01, 1000.0, "Hz")?;
                    check_range("--f1", f1, 0.01, 1000.0, "Hz")?;
                    let d = duration.unwrap_or(10.0);
                    (
                        fr::chirp_drive(amp, f0, f1, d),
                        PlatformMotion::Still,
                        d,
                        format!("valve chirp {f0}–{f1} Hz {amp} V"),
                    )
                }
                (None, None) => {
                    bail!("give --scenario cycloid|random|sine|chirp or --excitation FILE.csv")
                }
            };
            let duration = duration.unwrap_or(default_duration);
            check_range("--duration", duration, 1e-3, 36_000.0, "s")?;
            let trace = experiments::run(&params, kind, drive, platform, duration, rate)?;
            write_trace(&out, &trace, &preset, &label)?;
            report_contacts(&trace);
            println!(
                "{} samples of the {} model written to {}",
                trace.samples.len(),
                kind.name(),
                out.display()
            );
            Ok(())
        }
        Command::Bode {
            model,
            preset,
            amp,
            freqs,
            method,
            out,
        } => {
            let params = load_params(&preset)?;
            check_freqs(&freqs)?;
            let kind: ModelKind = model.into();
            let method = method.unwrap_or(match kind {
                ModelKind::Twin => MethodArg::Simulated,
                _ => MethodArg::Exact,
            });
            let values: Vec<num_complex::Complex64> = match (kind, method) {
                (ModelKind::Passive, _) => {
                    bail!("the passive model has no valve: no Bode of u̇/V_in")
                }
                (ModelKind::Linear, MethodArg::Exact) => {
                    freqs.iter().map(|&f| fr::linear_bode(&params, f)).collect()
                }
                (ModelKind::Twin, MethodArg::Linearised) => {
                    let lin = fr::linearise_twin(&params);
                    freqs.iter().map(|&f| lin.bode(f)).collect()
                }
                (_, MethodArg::Simulated) => {
                    let opt = fr::DwellOptions::default();
                    fr::sweep(&freqs, |&f| fr::simulated_bode(&params, kind, f, amp, &opt))
                        .into_iter()
                        .collect::<Result<_, _>>()?
                }
                (k, _) => bail!("method not available for the {} model", k.name()),
            };
            let rows = freqs
                .iter()
                .zip(&values)
                .map(|(f, v)| vec![*f, v.norm() * 1000.0, v.arg().to_degrees()]);
            dataset::write_csv_atomic(
                &out,
                &["freq_hz", "mag_mm_per_s_v", "phase_deg"],
                &[
                    ("model".into(), kind.name().into()),
                    ("preset".into(), preset.clone()),
                    ("amplitude_v".into(), amp.to_string()),
                ],
                rows,
            )
            .with_context(|| format!("writing {}", out.display()))?;
            println!("{} points written to {}", freqs.len(), out.display());
            Ok(())
        }
        Command::Transmissibility {
            model,
            preset,
            freqs,
            method,
            out,
        } => {
            let params = load_params(&preset)?;
            check_freqs(&freqs)?;
            let kind: ModelKind = model.into();
            let method = method.unwrap_or(match kind {
                ModelKind::Twin => MethodArg::Simulated,
                _ => MethodArg::Exact,
            });
            let values: Vec<num_complex::Complex64> = match (kind, method) {
                (ModelKind::Linear, MethodArg::Exact) => freqs
                    .iter()
                    .map(|&f| fr::linear_transmissibility(&params, f))
                    .collect(),
                (ModelKind::Passive, MethodArg::Exact) => freqs
                    .iter()
                    .map(|&f| fr::passive_transmissibility(&params, f))
                    .collect(),
                (ModelKind::Twin, MethodArg::Linearised) => {
                    let lin = fr::linearise_twin(&params);
                    freqs
                        .iter()
                        .map(|&f| lin.transmissibility(&params.controller, f))
                        .collect()
                }
                (_, MethodArg::Simulated) => {
                    let opt = fr::DwellOptions::default();
                    fr::sweep(&freqs, |&f| {
                        fr::simulated_transmissibility(&params, kind, f, &opt)
                    })
                    .into_iter()
                    .collect::<Result<_, _>>()?
                }
                (k, _) => bail!("method not available for the {} model", k.name()),
            };
            let rows = freqs
                .iter()
                .zip(&values)
                .map(|(f, v)| vec![*f, v.norm(), v.arg().to_degrees()]);
            dataset::write_csv_atomic(
                &out,
                &["freq_hz", "mag", "phase_deg"],
                &[
                    ("model".into(), kind.name().into()),
                    ("preset".into(), preset.clone()),
                ],
                rows,
            )
            .with_context(|| format!("writing {}", out.display()))?;
            println!("{} points written to {}", freqs.len(), out.display());
            Ok(())
        }
        Command::Replay { data, preset, out } => {
            let params = load_params(&preset)?;
            let rec = dataset::read_record(&data, RecordKind::Measured)?;
            for w in &rec.warnings {
                eprintln!("warning: {}: {w}", data.display());
            }
            let rep = identify::replay(&params, &rec)?;
            let s = &rep.sim;
            let rows = (0..s.t.len()).map(|i| {
                vec![
                    rec.t[i], s.u[i], s.ydd[i], s.p1[i], s.p2[i], s.xv[i], s.q1[i], s.q2[i],
                ]
            });
            dataset::write_csv_atomic(
                &out,
                &["t", "u", "ydd", "p1", "p2", "xv", "q1", "q2"],
                &[
                    ("model".into(), "twin".into()),
                    ("preset".into(), preset.clone()),
                    ("replayed".into(), data.display().to_string()),
                    (
                        "excitation".into(),
                        identify::replay::EXCITATION_CONDITIONING.into(),
                    ),
                    (
                        "units".into(),
                        "t s, u m, ydd m/s^2, p1 Pa, p2 Pa, xv m, q1 m^3/s, q2 m^3/s".into(),
                    ),
                ],
                rows,
            )
            .with_context(|| format!("writing {}", out.display()))?;
            let e = &rep.errors;
            println!(
                "{} samples replayed to {}; RMS error: du {:.3} mm/s ({:.1} %), u {:.3} mm{}",
                s.t.len(),
                out.display(),
                1e3 * e.du,
                100.0 * e.du_nrmse,
                1e3 * e.u,
                e.ydd
                    .map(|y| format!(", ydd {y:.3} m/s^2"))
                    .unwrap_or_default()
            );
            Ok(())
        }
        Command::Calibrate { data, preset, out } => {
            let params = load_params(&preset)?;
            let records = data
                .iter()
                .map(|p| dataset::read_record(p, RecordKind::Measured))
                .collect::<Result<Vec<_>, _>>()?;
            for r in &records {
                for w in &r.warnings {
                    eprintln!("warning: {}: {w}", r.path.display());
                }
            }
            let started = std::time::Instant::now();
            let last = std::sync::Mutex::new(String::new());
            let report = identify::calibrate(
                &params,
                &records,
                &identify::CalibrationOptions::default(),
                &|p| {
                    if let Ok(mut l) = last.lock()
                        && *l != p.stage
                    {
                        eprintln!("[{:6.1} s] {}", started.elapsed().as_secs_f64(), p.stage);
                        *l = p.stage.clone();
                    }
                    true
                },
            )?;
            let elapsed = started.elapsed().as_secs_f64();
            identify::report::write_all(&report, &out, Some(elapsed))?;
            println!("verdict: {}", report.verdict.name());
            for m in &report.missing {
                println!("missing: {m}");
            }
            for e in &report.effects {
                println!("effect {}: {:?}", e.effect.name(), e.params);
            }
            for v in &report.calibrated {
                println!(
                    "{}",
                    identify::report::format_parameter(&v.name, v.value, v.std)
                );
            }
            println!(
                "weighted error: nominal {:.3}, before {:.3}, after {:.3}",
                report.error_nominal.value, report.error_before.value, report.error_after.value
            );
            if let Some(v) = &report.error_validation {
                println!(
                    "validation (held-out): before {:.3}, after {:.3}",
                    v.before, v.after
                );
            }
            println!(
                "calibrated in {elapsed:.1} s ({} replays); report in {}",
                report.evaluations,
                out.join("report.md").display()
            );
            Ok(())
        }
        Command::Bench { preset } => {
            let params = load_params(&preset)?;
            let text = seat_twin::bench::run_bench(&params)?;
            println!("{text}");
            Ok(())
        }
    }
}

fn check_range(name: &str, v: f64, min: f64, max: f64, unit: &str) -> Result<()> {
    if v.is_finite() && v >= min && v <= max {
        Ok(())
    } else {
        bail!("{name} {v} is outside the allowed range [{min}, {max}] {unit}")
    }
}

fn check_freqs(freqs: &[f64]) -> Result<()> {
    if freqs.is_empty() {
        bail!("--freqs needs at least one frequency");
    }
    for &f in freqs {
        check_range("--freqs value", f, 0.01, 1000.0, "Hz")?;
    }
    Ok(())
}

/// Writes a trace with the columns its model has.
fn write_trace(out: &Path, trace: &Trace, preset: &str, label: &str) -> Result<()> {
    let hyd = trace.model.has_hydraulics();
    let cmd = trace.model.has_command();
    let mut header = vec!["t", "x", "xdd", "u", "ydd"];
    if cmd {
        header.push("v_in");
    }
    if hyd {
        header.extend(["xv", "p1", "p2", "q1", "q2"]);
    }
    let rows = trace.samples.iter().map(|s| {
        let mut r = vec![s.t, s.x, s.xdd, s.u, s.ydd];
        if cmd {
            r.push(s.v_in);
        }
        if hyd {
            r.extend([s.xv, s.p1, s.p2, s.q1, s.q2]);
        }
        r
    });
    let comments = vec![
        ("model".to_string(), trace.model.name().to_string()),
        ("preset".to_string(), preset.to_string()),
        ("scenario".to_string(), label.to_string()),
        (
            "end_stop_contacts".to_string(),
            trace.contacts.len().to_string(),
        ),
        (
            "units".to_string(),
            "t s, x m, xdd m/s^2, u m, ydd m/s^2, v_in V, xv m, p1 Pa, p2 Pa, q1 m^3/s, q2 m^3/s"
                .to_string(),
        ),
    ];
    dataset::write_csv_atomic(out, &header, &comments, rows)
        .with_context(|| format!("writing {}", out.display()))
}

fn report_contacts(trace: &Trace) {
    if trace.contacts.is_empty() {
        return;
    }
    let what = if trace.model.has_hydraulics() {
        "end-stop contact"
    } else {
        "stroke overrun (this model has no end stops)"
    };
    eprintln!(
        "warning: {} {what} event(s); first at t = {:.3} s",
        trace.contacts.len(),
        trace.contacts[0].t_start
    );
}
