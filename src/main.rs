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
    /// A seat-test input spectral class (--class NAME: EM1–EM9, IT1–IT4, AG1–AG3), closed loop.
    Class,
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
        /// Input spectral class of `--scenario class` (EM1–EM9, IT1–IT4, AG1–AG3).
        #[arg(long)]
        class: Option<String>,
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
    Tune {
        /// Preset file or shipped preset name (its plant, and its gains as the start).
        #[arg(long, default_value = "paper")]
        preset: String,
        /// Controller structure: paper, predictive, skyhook or smith (default: the preset's).
        #[arg(long)]
        controller: Option<String>,
        /// Objective: aw (Wk-weighted RMS), vdv or seat.
        #[arg(long, default_value = "aw")]
        objective: String,
        /// Tuning input: `ride` (the paper's random ride).
        #[arg(long, default_value = "ride")]
        excitation: String,
        /// Number of tuning rides (seeds 1..=N); as many held-out rides use seeds 101...
        #[arg(long, default_value_t = 3, allow_negative_numbers = true)]
        seeds: i64,
        /// Duration of each ride [s], 5..=600.
        #[arg(long, default_value_t = 60.0, allow_negative_numbers = true)]
        duration: f64,
        /// Optimise the worst case over Cd ±10 %, τ ±3 ms, mass ±20 %.
        #[arg(long)]
        robust: bool,
        /// Budget of objective evaluations, 10..=10000.
        #[arg(long, default_value_t = 120, allow_negative_numbers = true)]
        evaluations: i64,
        /// Output directory.
        #[arg(long)]
        out: PathBuf,
    },
}

/// Arguments of `seat-twin seat-test`.
#[derive(clap::Args)]
struct SeatTestArgs {
    /// Input spectral class: EM1–EM9 (ISO 7096), IT1–IT4 (EN 13490), AG1–AG3 (ISO 5007).
    #[arg(long)]
    class: String,
    /// Preset file or shipped preset name.
    #[arg(long, default_value = "paper")]
    preset: String,
    #[arg(long, value_enum, default_value = "twin")]
    model: ModelArg,
    /// Suspended mass [kg] (default: the preset's; the paper's rig carries 11.7 kg).
    #[arg(long)]
    mass: Option<f64>,
    /// Record length including 2 s fades at both ends [s].
    #[arg(long, default_value_t = seat_twin::seat_test::run::DEFAULT_DURATION_S)]
    duration: f64,
    /// Seed of the class motion's phases.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Output directory.
    #[arg(long)]
    out: PathBuf,
}

fn find_class(name: &str) -> Result<&'static seat_twin::seat_test::InputClass> {
    seat_twin::seat_test::find(name).with_context(|| {
        format!(
            "unknown input class `{name}`; the classes are {}",
            seat_twin::seat_test::classes::names()
        )
    })
}

fn run_seat_test_command(a: SeatTestArgs) -> Result<()> {
    use seat_twin::seat_test::{SeatTestOptions, report, run_seat_test};
    let class = find_class(&a.class)?;
    let params = load_params(&a.preset)?;
    if let Some(m) = a.mass {
        check_range("--mass", m, 1.0, 500.0, "kg")?;
    }
    let opts = SeatTestOptions {
        mass_kg: a.mass,
        duration_s: a.duration,
        seed: a.seed,
        ..SeatTestOptions::new(class, a.model.into())
    };
    let result = run_seat_test(&params, &opts).with_context(|| {
        format!(
            "seat test {} on the {} model",
            class.name,
            opts.model.name()
        )
    })?;
    report::write_seat_test(&result, class, &a.preset, &a.out)
        .with_context(|| format!("writing the seat-test report to {}", a.out.display()))?;
    let n = &result.numbers;
    println!(
        "{} on the {} model, {:.1} kg: a_w floor {:.3} m/s², seat {:.3} m/s², SEAT {:.1} %, \
         VDV seat {:.3} m/s^1.75, max |u| {:.1} mm, {} contact(s), PSD error {:.1} % of peak{}",
        n.class,
        n.model,
        n.mass_kg,
        n.aw_floor,
        n.aw_seat,
        n.seat_percent,
        n.vdv_seat,
        n.max_abs_u_mm,
        n.contacts,
        n.psd_error_percent,
        if n.psd_within_tolerance {
            ""
        } else {
            " (outside the ±10 % tolerance)"
        }
    );
    if n.contacts > 0 {
        eprintln!(
            "warning: the seat reached its ±{:.0} mm stops {} time(s)",
            n.half_stroke_mm, n.contacts
        );
    }
    println!("report written to {}", a.out.join("report.md").display());
    Ok(())
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
            class,
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
                (Some(ScenarioArg::Class), None) => {
                    let Some(name) = class.as_deref() else {
                        bail!(
                            "--scenario class needs --class NAME ({})",
                            seat_twin::seat_test::classes::names()
                        );
                    };
                    let class = find_class(name)?;
                    let motion = seat_twin::seat_test::ClassMotion {
                        seed,
                        ..seat_twin::seat_test::ClassMotion::new(
                            class,
                            duration.unwrap_or(seat_twin::seat_test::run::DEFAULT_DURATION_S),
                        )
                    };
                    let sampled = motion.generate()?;
                    let d = sampled.duration_s();
                    (
                        experiments::closed_loop(&params),
                        PlatformMotion::Sampled(sampled),
                        d,
                        format!("seat-test input class {} seed {seed}", class.name),
                    )
                }
                (None, None) => {
                    bail!(
                        "give --scenario cycloid|random|sine|chirp|class or --excitation FILE.csv"
                    )
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
                        .map(|&f| {
                            lin.transmissibility(&seat_twin::control::ControlLaw::new(&params), f)
                        })
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
            for e in &report.effects {
                println!("effect {}: {:?}", e.effect.name(), e.params);
            }
            for v in &report.calibrated {
                println!("{} = {:.6} ± {:.2e}", v.name, v.value, v.std);
            }
            println!(
                "weighted error: nominal {:.3}, before {:.3}, after {:.3}",
                report.error_nominal.value, report.error_before.value, report.error_after.value
            );
            println!(
                "calibrated in {elapsed:.1} s ({} replays); report in {}",
                report.evaluations,
                out.join("report.md").display()
            );
            Ok(())
        }
        Command::SeatTest(args) => run_seat_test_command(args),
        Command::Bench { preset } => {
            let params = load_params(&preset)?;
            let text = seat_twin::bench::run_bench(&params)?;
            println!("{text}");
            Ok(())
        }
        Command::Tune {
            preset,
            controller,
            objective,
            excitation,
            seeds,
            duration,
            robust,
            evaluations,
            out,
        } => run_tune(
            &preset,
            controller.as_deref(),
            &objective,
            &excitation,
            seeds,
            duration,
            robust,
            evaluations,
            &out,
        ),
    }
}

/// `seat-twin tune`.
#[allow(clippy::too_many_arguments)]
fn run_tune(
    preset: &str,
    controller: Option<&str>,
    objective: &str,
    excitation: &str,
    seeds: i64,
    duration: f64,
    robust: bool,
    evaluations: i64,
    out: &Path,
) -> Result<()> {
    use seat_twin::tune;
    let params = load_params(preset)?;
    let kind = match controller {
        Some(k) => k.parse().map_err(anyhow::Error::msg)?,
        None => params.controller.kind,
    };
    let objective: tune::Objective = objective.parse().map_err(anyhow::Error::msg)?;
    if excitation != "ride" {
        bail!(
            "--excitation {excitation}: this build tunes on `ride` (the paper's random ride) only"
        );
    }
    check_range("--seeds", seeds as f64, 1.0, 20.0, "")?;
    check_range("--duration", duration, 5.0, 600.0, "s")?;
    check_range("--evaluations", evaluations as f64, 10.0, 10_000.0, "")?;
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let n = seeds as u64;
    let opts = tune::TuneOptions {
        kind,
        objective,
        tune_seeds: (1..=n).collect(),
        heldout_seeds: (101..101 + n).collect(),
        duration_s: duration,
        robust,
        max_evaluations: evaluations as usize,
    };
    let started = std::time::Instant::now();
    eprintln!(
        "tuning {kind} for {} on {n} ride(s) of {duration:.0} s (held out: {n}){}",
        objective.name(),
        if robust {
            ", worst case over the spread"
        } else {
            ""
        }
    );
    let result = tune::tune(&params, &opts, None)?;
    let wall = started.elapsed().as_secs_f64();
    let mut start = params;
    start.controller.kind = kind;
    let files = tune::report::write_outputs(&result, &start, out, wall)?;
    let unit = objective.unit();
    println!(
        "{}: start {:.4} {unit} -> tuned {:.4} {unit} (held out {:.4} -> {:.4}); {} evaluations in {wall:.1} s",
        objective.name(),
        result.baseline.objective,
        result.tuned.objective,
        result.baseline_heldout.objective,
        result.tuned_heldout.objective,
        result.evaluations
    );
    for (k, v) in &result.tuned.gains {
        println!("  {k} = {v:.4}");
    }
    println!(
        "  GM {:.1} dB, PM {:.1} deg, max |u| {:.1} mm, contacts {}",
        result.tuned.gain_margin_db,
        result.tuned.phase_margin_deg,
        result.tuned.max_abs_u_m * 1e3,
        result.tuned.contacts
    );
    println!("wrote {} files to {}", files.len(), out.display());
    Ok(())
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
