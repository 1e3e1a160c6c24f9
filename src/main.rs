//! `seat-twin`: with no subcommand it opens the desktop app (feature `gui`); the subcommands
//! run the same engine headless.

use anyhow::{Context, Result, bail};
use clap::Parser;
use seat_twin::analysis::dwell;
use seat_twin::analysis::response::{Method, Response, ResponseError, response};
use seat_twin::cli::{self, Cli, Command, MAX_DURATION_S, ScenarioArg, SweepArgs, check_range};
use seat_twin::dataset::{self, RecordKind};
use seat_twin::experiments::RunSpec;
use seat_twin::fsutil::{self, OutputDir};
use seat_twin::identify;
use seat_twin::model::ModelKind;
use seat_twin::params::Params;
use seat_twin::params::fmt_value;
use seat_twin::preset;
use seat_twin::scenario::{CommandSignal, Cycloid, PlatformMotion, RandomRide, SampledMotion};
use seat_twin::simulation::{
    ContactEvent, CsvRunError, Drive, SAMPLE_UNITS, sample_count, step_for_rate,
};

mod commands;
use commands::{find_class, run_seat_test_command, run_tune};

fn main() {
    let cli = Cli::parse();
    let result = match cli.command {
        None => open_app(),
        Some(cmd) => {
            clean_up_on_signals();
            run(cmd)
        }
    };
    if let Err(e) = result {
        eprintln!("error: {}", error_text(&e));
        std::process::exit(1);
    }
}

/// The error and its chain of causes, each message once: a cause whose text an outer message
/// already includes (`file: cause` over `cause`) is not repeated.
fn error_text(e: &anyhow::Error) -> String {
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

/// On SIGINT, SIGTERM or SIGHUP: removes the temporary files and folders of the output being
/// written ([`fsutil::remove_pending`]), says so, and exits with 128 + the signal's number.
#[cfg(unix)]
fn clean_up_on_signals() {
    use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
    let Ok(mut signals) = signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGHUP]) else {
        return;
    };
    std::thread::spawn(move || {
        if let Some(sig) = signals.forever().next() {
            let removed = fsutil::remove_pending();
            let name = match sig {
                SIGINT => "SIGINT",
                SIGTERM => "SIGTERM",
                _ => "SIGHUP",
            };
            eprintln!(
                "\ninterrupted ({name}): stopped{}",
                if removed > 0 {
                    "; the unfinished output was removed"
                } else {
                    ""
                }
            );
            std::process::exit(128 + sig);
        }
    });
}

#[cfg(not(unix))]
fn clean_up_on_signals() {}

/// Prints "still running" with the elapsed time on stderr every `every` until dropped.
struct Heartbeat {
    stop: Option<std::sync::mpsc::Sender<()>>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl Heartbeat {
    fn start(what: String, every: std::time::Duration) -> Self {
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
    cli::validate(&cmd)?;
    match cmd {
        Command::Report { preset, out } => {
            let params = load_params(&preset)?;
            // The whole set goes into a temporary folder beside --out and is moved into place
            // at the end: a failure or Ctrl-C leaves --out as it was.
            let dir = OutputDir::create(&out)
                .with_context(|| format!("cannot write the report into {}", out.display()))?;
            let default_step = seat_twin::params::NumericsParams::default().max_step_s;
            let factor = default_step / params.numerics.max_step_s;
            if factor > 4.0 {
                eprintln!(
                    "note: numerics.max_step_s = {} s is {}× finer than the default {} s: the \
                     twin's runs take about {}× as long as usual (minutes, not seconds)",
                    fmt_value(params.numerics.max_step_s),
                    fmt_value(factor.round()),
                    fmt_value(default_step),
                    fmt_value(factor.round())
                );
            }
            let heartbeat = Heartbeat::start("report".into(), std::time::Duration::from_secs(10));
            let summary = seat_twin::report::write_report(&params, &preset, dir.path())?;
            drop(heartbeat);
            dir.commit()
                .with_context(|| format!("moving the report into {}", out.display()))?;
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
            // Every numeric option has been checked by cli::validate.
            let params = load_params(&preset)?;
            let kind = model;
            let mut warnings: Vec<String> = Vec::new();
            let mut peak_input: Option<String> = None;
            let (drive, platform, default_duration, label) = match (scenario, &excitation) {
                (_, Some(path)) => {
                    let rec = dataset::read_record(path, RecordKind::Excitation)?;
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
                    format!("valve sine {} Hz {} V", fmt_value(freq), fmt_value(amp)),
                ),
                (Some(ScenarioArg::Chirp), None) => {
                    let d = duration.unwrap_or(10.0);
                    (
                        dwell::chirp_drive(amp, f0, f1, d),
                        PlatformMotion::Still,
                        d,
                        format!(
                            "valve chirp {}–{} Hz {} V",
                            fmt_value(f0),
                            fmt_value(f1),
                            fmt_value(amp)
                        ),
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
                        Drive::closed_loop(&params),
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
            let duration = match duration {
                Some(d) => d,
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
            cli::check_sample_count(samples, duration, rate)?;
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
            let summary = match spec.write_csv(&out, &comments) {
                Ok(s) => s,
                Err(CsvRunError::Sim(e)) => {
                    return Err(
                        anyhow::Error::new(e).context(match (&excitation, peak_input) {
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
                                fmt_value(rate)
                            ),
                        }),
                    );
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
            Ok(())
        }
        Command::Bode {
            model,
            preset,
            amp,
            sweep,
        } => {
            let what = Response::Bode { amplitude_v: amp };
            write_response(&preset, model, what, &sweep)
        }
        Command::Transmissibility {
            model,
            preset,
            sweep,
        } => write_response(&preset, model, Response::Transmissibility, &sweep),
        Command::Replay { data, preset, out } => {
            let params = load_params(&preset)?;
            let rec = dataset::read_record(&data, RecordKind::Measured)?;
            for w in &rec.warnings {
                eprintln!("warning: {}: {w}", data.display());
            }
            let rep = identify::replay(&params, &rec)?;
            let s = &rep.sim;
            let comments = [
                ("model".into(), "twin".into()),
                ("preset".into(), preset.clone()),
                ("replayed".into(), data.display().to_string()),
                (
                    "excitation".into(),
                    identify::replay::EXCITATION_CONDITIONING.into(),
                ),
                ("units".into(), identify::SimChannels::CSV_UNITS.into()),
            ];
            s.write_csv(&rec.t, &out, &comments)
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
            // Issue 12: the output set is written whole into a temporary folder beside --out and
            // moved into place at the end; creating it now checks --out is writable before the
            // long calibration starts.
            let out_dir = OutputDir::create(&out)
                .with_context(|| format!("cannot write the results into {}", out.display()))?;
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
            identify::report::write_all(&report, out_dir.path(), Some(elapsed))?;
            out_dir
                .commit()
                .with_context(|| format!("moving the results into {}", out.display()))?;
            println!("verdict: {}", report.verdict.name());
            for m in &report.missing {
                println!("missing: {m}");
            }
            for e in &report.effects {
                let params: Vec<String> = e
                    .params
                    .iter()
                    .map(|(k, v)| format!("{k} = {}", identify::report::format_value(k, *v)))
                    .collect();
                println!("effect {}: {}", e.effect.name(), params.join(", "));
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
        Command::SeatTest(args) => run_seat_test_command(args),
        Command::Bench { preset } => {
            let params = load_params(&preset)?;
            let text = seat_twin::bench::run_bench(&params)?;
            println!("{text}");
            Ok(())
        }
        Command::Tune(args) => run_tune(&args),
    }
}

/// `bode` and `transmissibility`: the response by its entry point, then one CSV file. A
/// non-finite point is refused naming the frequency and the input it came from.
fn write_response(preset: &str, kind: ModelKind, what: Response, sweep: &SweepArgs) -> Result<()> {
    let SweepArgs { freqs, method, out } = sweep;
    let params = load_params(preset)?;
    // What a non-finite point is traced back to, and the input's own comment line.
    let (input, extra) = match what {
        Response::Bode { amplitude_v } => (
            format!("--amp {} V", fmt_value(amplitude_v)),
            vec![("amplitude_v".to_string(), fmt_value(amplitude_v))],
        ),
        Response::Transmissibility => (format!("preset {preset}"), Vec::new()),
    };
    let method = method.unwrap_or(Method::default_for(kind));
    if let Response::Transmissibility = what {
        check_loop_stable(&params, kind, preset)?;
    }
    let values = match response(&params, kind, what, method, freqs) {
        Err(e @ ResponseError::NotFinite { .. }) => {
            bail!("{e}; nothing was written. Check {input}")
        }
        r => r?,
    };
    let mut comments = vec![
        ("model".to_string(), kind.name().to_string()),
        ("preset".to_string(), preset.to_string()),
    ];
    comments.extend(extra);
    let rows = freqs.iter().zip(&values).map(|(&f, &v)| what.row(f, v));
    dataset::write_csv_atomic(out, &what.columns(), &comments, rows)
        .with_context(|| format!("writing {}", out.display()))?;
    println!("{} points written to {}", freqs.len(), out.display());
    Ok(())
}

/// Refuses a closed loop that the stability verdict calls unstable: its transmissibility is
/// not a steady state (|T| of an unstable loop is a number, not a response).
fn check_loop_stable(params: &Params, kind: ModelKind, preset: &str) -> Result<()> {
    use seat_twin::analysis::frequency_response as fr;
    use seat_twin::analysis::stability::{LoopPlant, remedy};
    let (lin, tau) = match kind {
        ModelKind::Twin => (fr::linearise_twin(params), params.plant.valve.tau_s),
        ModelKind::Linear => (fr::linearise_linear(params), params.linear.tau_s),
        ModelKind::Passive => return Ok(()),
    };
    let law = seat_twin::control::ControlLaw::new(params);
    let s = seat_twin::analysis::stability::Stability::of(&lin, &law, tau);
    if s.stable() {
        return Ok(());
    }
    let plant = LoopPlant::new(&lin);
    bail!(
        "the closed loop of preset {preset} on the {} is unstable: {} (closed-loop eigenvalues \
         of the loop linearised at rest, with the delay). {} Nothing was written.",
        kind.name(),
        s.mode_text(),
        remedy(params, &[(&plant, tau)])
    )
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
        fmt_value(*v),
        fmt_value(rec.t[i]),
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
