//! `seat-twin report`: the paper's sections 4–6 reproduced — `report.md`, `numbers.json` and
//! PNG + SVG plots (Table 1 Bode, Fig. 12 transmissibility, Figs. 13–14 cycloid,
//! Figs. 15–16 random ride) — with an honest *paper value | this twin | note* table.

use crate::analysis::dwell;
use crate::analysis::frequency_response::{self as fr, FrequencyPoint};
use crate::analysis::metrics;
use crate::control::ControlLaw;
use crate::experiments;
use crate::model::ModelKind;
use crate::output::OutputError;
use crate::params::Params;
use crate::plot::{self, Figure, Panel, Scale, Series, SeriesStyle};
use crate::preset::write_atomic;
use crate::scenario::{Cycloid, PlatformMotion, RandomRide};
use crate::simulation::{Drive, SimError, Trace};
use num_complex::Complex64;
use serde::Serialize;
use std::fmt::Write as _;
use std::path::Path;

/// Why a report could not be written.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    /// A simulation diverged.
    #[error(transparent)]
    Sim(#[from] SimError),
    /// A file (named) or a plot could not be written.
    #[error(transparent)]
    Output(#[from] OutputError),
    /// Metrics could not be computed.
    #[error(transparent)]
    Metrics(#[from] metrics::MetricsError),
}

impl From<plot::PlotError> for ReportError {
    fn from(e: plot::PlotError) -> Self {
        Self::Output(e.into())
    }
}

/// Seeds of the random rides whose spread the report states.
pub const RIDE_SEEDS: [u64; 8] = [1, 2, 3, 4, 5, 6, 7, 8];
/// Duration of each random ride \[s\] (after a 2 s fade-in that the statistics skip).
pub const RIDE_DURATION_S: f64 = 60.0;

/// Mean and sample standard deviation over the seeds.
#[derive(Debug, Clone, Copy, Serialize, PartialEq)]
pub struct Spread {
    /// Mean.
    pub mean: f64,
    /// Sample standard deviation.
    pub std: f64,
    /// Smallest.
    pub min: f64,
    /// Largest.
    pub max: f64,
}

impl Spread {
    /// Statistics of a sample.
    pub fn of(v: &[f64]) -> Self {
        let n = v.len().max(1) as f64;
        let mean = v.iter().sum::<f64>() / n;
        let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0);
        Self {
            mean,
            std: var.sqrt(),
            min: v.iter().copied().fold(f64::INFINITY, f64::min),
            max: v.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        }
    }
}

/// Vibration metrics of one ride on one model.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct RideMetrics {
    /// RMS of the body acceleration [m/s²].
    pub rms_ydd: f64,
    /// ISO 2631-1 Wk-weighted RMS a_w of the body [m/s²].
    pub aw_ydd: f64,
    /// VDV of the body [m/s^1.75].
    pub vdv_ydd: f64,
    /// SEAT [%] = a_w body / a_w platform.
    pub seat_percent: f64,
    /// RMS of the relative displacement \[m\].
    pub rms_u: f64,
    /// Largest |u| \[m\].
    pub max_abs_u: f64,
    /// End-stop contacts (twin) or stroke overruns.
    pub contacts: usize,
}

/// Everything the report states, in SI (written as `numbers.json`).
#[derive(Debug, Clone, Serialize)]
pub struct ReportNumbers {
    /// Preset used.
    pub preset: String,
    /// Passive |T| = 1 crossing \[Hz\].
    pub passive_crossing_hz: Option<f64>,
    /// Linear active isolation upper edge \[Hz\].
    pub linear_crossing_hz: Option<f64>,
    /// Twin (linearised) isolation upper edge \[Hz\].
    pub twin_crossing_hz: Option<f64>,
    /// Twin (simulated dwell) isolation upper edge \[Hz\].
    pub twin_crossing_simulated_hz: Option<f64>,
    /// Delay from the phase slope of the twin's u̇/V, 1–20 Hz, at 0.72 V \[s\].
    pub twin_phase_delay_s: f64,
    /// Delay from the phase slope of G(s), 1–20 Hz \[s\].
    pub linear_phase_delay_s: f64,
    /// Twin low-frequency gain u̇/V at 0.5 Hz, 0.72 V [m/(s·V)].
    pub twin_gain_m_per_s_v: f64,
    /// Table 1: (f \[Hz\], A \[V\], |u̇/V| [m/(s·V)], phase \[deg\]) of the twin.
    pub table1: Vec<(f64, f64, f64, f64)>,
    /// Platform RMS acceleration over the seeds [m/s²].
    pub ride_rms_xdd: Spread,
    /// Platform a_w over the seeds [m/s²].
    pub ride_aw_xdd: Spread,
    /// Body RMS, twin [m/s²].
    pub ride_rms_ydd_twin: Spread,
    /// Body RMS, linear model [m/s²].
    pub ride_rms_ydd_linear: Spread,
    /// Body RMS, passive [m/s²].
    pub ride_rms_ydd_passive: Spread,
    /// Metrics of the seed-1 ride per model: twin, linear, passive.
    pub ride_seed1: [RideMetrics; 3],
    /// Rides (of the seeds) in which the twin touched an end stop.
    pub ride_twin_contact_seeds: usize,
    /// Largest |p1 + p2 − (pA + p0)| in the seed-1 twin ride \[Pa\].
    pub ride_pressure_symmetry_pa: f64,
    /// Mean of (p1 + p2)/2 in the seed-1 twin ride \[Pa\].
    pub ride_pressure_mean_pa: f64,
    /// Largest |Q1| in the seed-1 twin ride [m³/s].
    pub ride_max_flow_m3_s: f64,
    /// Cycloid: peak |ÿ| twin, linear, passive [m/s²] and peak |ẍ|.
    pub cycloid_peak_ydd: [f64; 3],
    /// Cycloid: peak platform acceleration [m/s²].
    pub cycloid_peak_xdd: f64,
    /// Cycloid: largest |u| of the twin and of the passive \[m\].
    pub cycloid_max_u: [f64; 2],
    /// Cd that Eq. (12) gives for 20 L/min at full opening with Δp = 70 bar and 100 bar.
    pub cd_from_eq12: [f64; 2],
}

fn crossing_sets(params: &Params, freqs: &[f64]) -> (Vec<f64>, Vec<f64>, Vec<Complex64>) {
    let passive: Vec<f64> = freqs
        .iter()
        .map(|&f| fr::passive_transmissibility(params, f).norm())
        .collect();
    let linear: Vec<f64> = freqs
        .iter()
        .map(|&f| fr::linear_transmissibility(params, f).norm())
        .collect();
    let lin = fr::linearise_twin(params);
    let twin: Vec<Complex64> = freqs
        .iter()
        .map(|&f| lin.transmissibility(&ControlLaw::new(params), f))
        .collect();
    (passive, linear, twin)
}

fn ride_of(seed: u64) -> PlatformMotion {
    PlatformMotion::Sampled(
        RandomRide {
            seed,
            duration_s: RIDE_DURATION_S,
            ..Default::default()
        }
        .generate(),
    )
}

fn ride_metrics(trace: &Trace, settle_s: f64) -> Result<RideMetrics, metrics::MetricsError> {
    let fs = 1.0 / (trace.samples[1].t - trace.samples[0].t);
    let skip = (settle_s * fs) as usize;
    let ydd = trace.channel(|s| s.ydd);
    let xdd = trace.channel(|s| s.xdd);
    let body = metrics::vibration_metrics(&ydd, fs, settle_s)?;
    let platform = metrics::vibration_metrics(&xdd, fs, settle_s)?;
    let u: Vec<f64> = trace.samples[skip..].iter().map(|s| s.u).collect();
    Ok(RideMetrics {
        rms_ydd: body.rms,
        aw_ydd: body.aw,
        vdv_ydd: body.vdv,
        seat_percent: metrics::seat_percent(body.aw, platform.aw),
        rms_u: metrics::rms(&u),
        max_abs_u: metrics::peak(&u),
        contacts: trace.contacts.len(),
    })
}

/// Runs the three models on one ride.
fn ride_traces(params: &Params, seed: u64) -> Result<[Trace; 3], SimError> {
    let ride = ride_of(seed);
    let run = |kind| {
        experiments::run(
            params,
            kind,
            Drive::closed_loop(params),
            ride.clone(),
            RIDE_DURATION_S,
            1000.0,
        )
    };
    Ok([
        run(ModelKind::Twin)?,
        run(ModelKind::Linear)?,
        run(ModelKind::Passive)?,
    ])
}

/// Writes the full report into `out` and returns a short console summary.
pub fn write_report(params: &Params, preset_name: &str, out: &Path) -> Result<String, ReportError> {
    std::fs::create_dir_all(out).map_err(OutputError::io(out))?;
    let settle = RandomRide::default().fade_in_s;

    // --- Section 4: Table 1 on the twin, G(s) and the linearised twin.
    let tests = experiments::table1();
    let opt = dwell::DwellOptions::default();
    let bode_results = dwell::sweep(&tests, |&(f, a)| {
        dwell::simulated_bode(params, ModelKind::Twin, f, a, &opt)
    });
    let mut table1 = Vec::with_capacity(tests.len());
    for (&(f, a), r) in tests.iter().zip(bode_results) {
        let g = r?;
        table1.push((f, a, g.norm(), g.arg().to_degrees()));
    }
    let lin = fr::linearise_twin(params);
    let dense = fr::log_space(0.3, 30.0, 300);
    let slope_freqs: Vec<f64> = (1..=20).map(f64::from).collect();
    let twin_slope_phases: Vec<f64> = table1
        .iter()
        .filter(|r| r.1 == 0.72 && r.0 >= 1.0)
        .map(|r| r.3.to_radians())
        .collect();
    let twin_slope_freqs: Vec<f64> = table1
        .iter()
        .filter(|r| r.1 == 0.72 && r.0 >= 1.0)
        .map(|r| r.0)
        .collect();
    let twin_phase_delay_s = fr::delay_from_phase_slope(&twin_slope_freqs, &twin_slope_phases);
    let lin_phases: Vec<f64> = slope_freqs
        .iter()
        .map(|&f| fr::linear_bode(params, f).arg())
        .collect();
    let linear_phase_delay_s = fr::delay_from_phase_slope(&slope_freqs, &lin_phases);

    // --- Section 6: transmissibility.
    let (passive_t, linear_t, twin_t) = crossing_sets(params, &dense);
    let twin_t_mag: Vec<f64> = twin_t.iter().map(|c| c.norm()).collect();
    let dwell_freqs: Vec<f64> = vec![
        0.5, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0, 10.0, 12.0, 15.0, 20.0,
    ];
    let twin_dwell: Vec<Complex64> = dwell::sweep(&dwell_freqs, |&f| {
        dwell::simulated_transmissibility(params, ModelKind::Twin, f, &opt)
    })
    .into_iter()
    .collect::<Result<_, _>>()?;
    let dwell_mag: Vec<f64> = twin_dwell.iter().map(|c| c.norm()).collect();

    // --- Cycloid.
    let bump = Cycloid::default();
    let cyc: Vec<Trace> = [ModelKind::Twin, ModelKind::Linear, ModelKind::Passive]
        .iter()
        .map(|&k| experiments::cycloid(params, k, &bump, 5.0, 1000.0))
        .collect::<Result<_, _>>()?;
    let peak = |t: &Trace, f: &dyn Fn(&crate::simulation::Sample) -> f64| {
        t.samples.iter().map(|s| f(s).abs()).fold(0.0, f64::max)
    };

    // --- Random rides over several seeds.
    let rides: Vec<[Trace; 3]> = dwell::sweep(&RIDE_SEEDS, |&s| ride_traces(params, s))
        .into_iter()
        .collect::<Result<_, _>>()?;
    let mut rms_x = Vec::new();
    let mut aw_x = Vec::new();
    let mut rms_y = [Vec::new(), Vec::new(), Vec::new()];
    let mut contact_seeds = 0;
    for r in &rides {
        let fs = 1000.0;
        let xdd = r[0].channel(|s| s.xdd);
        let m = metrics::vibration_metrics(&xdd, fs, settle)?;
        rms_x.push(m.rms);
        aw_x.push(m.aw);
        for (i, t) in r.iter().enumerate() {
            rms_y[i].push(ride_metrics(t, settle)?.rms_ydd);
        }
        if !r[0].contacts.is_empty() {
            contact_seeds += 1;
        }
    }
    let seed1 = &rides[0];
    let sum_p = params.plant.supply.supply_pressure_pa + params.plant.supply.return_pressure_pa;
    let numbers = ReportNumbers {
        preset: preset_name.to_string(),
        passive_crossing_hz: fr::isolation_lower_edge(&dense, &passive_t),
        linear_crossing_hz: fr::isolation_upper_edge(&dense, &linear_t),
        twin_crossing_hz: fr::isolation_upper_edge(&dense, &twin_t_mag),
        twin_crossing_simulated_hz: fr::isolation_upper_edge(&dwell_freqs, &dwell_mag),
        twin_phase_delay_s,
        linear_phase_delay_s,
        twin_gain_m_per_s_v: table1[0].2,
        table1: table1.clone(),
        ride_rms_xdd: Spread::of(&rms_x),
        ride_aw_xdd: Spread::of(&aw_x),
        ride_rms_ydd_twin: Spread::of(&rms_y[0]),
        ride_rms_ydd_linear: Spread::of(&rms_y[1]),
        ride_rms_ydd_passive: Spread::of(&rms_y[2]),
        ride_seed1: [
            ride_metrics(&seed1[0], settle)?,
            ride_metrics(&seed1[1], settle)?,
            ride_metrics(&seed1[2], settle)?,
        ],
        ride_twin_contact_seeds: contact_seeds,
        ride_pressure_symmetry_pa: seed1[0]
            .samples
            .iter()
            .map(|s| (s.p1 + s.p2 - sum_p).abs())
            .fold(0.0, f64::max),
        ride_pressure_mean_pa: seed1[0]
            .samples
            .iter()
            .map(|s| 0.5 * (s.p1 + s.p2))
            .sum::<f64>()
            / seed1[0].samples.len() as f64,
        ride_max_flow_m3_s: peak(&seed1[0], &|s| s.q1),
        cycloid_peak_ydd: [
            peak(&cyc[0], &|s| s.ydd),
            peak(&cyc[1], &|s| s.ydd),
            peak(&cyc[2], &|s| s.ydd),
        ],
        cycloid_peak_xdd: peak(&cyc[0], &|s| s.xdd),
        cycloid_max_u: [peak(&cyc[0], &|s| s.u), peak(&cyc[2], &|s| s.u)],
        cd_from_eq12: [cd_eq12(params, 70e5), cd_eq12(params, 100e5)],
    };

    // --- Plots.
    plots::table1_bode(out, params, &table1, &lin, &dense)?;
    let curves = plots::TransmissibilityCurves {
        freqs_hz: &dense,
        passive: &passive_t,
        linear: &linear_t,
        twin: &twin_t,
        dwell_freqs_hz: &dwell_freqs,
        dwell: &twin_dwell,
    };
    plots::transmissibility(out, &curves, params)?;
    plots::cycloid(out, &cyc)?;
    plots::ride(out, &rides[0])?;

    // --- Files.
    let json = serde_json::to_string_pretty(&numbers)
        .unwrap_or_else(|e| format!("{{\"error\": \"{e}\"}}"));
    let json_path = out.join("numbers.json");
    write_atomic(&json_path, json.as_bytes()).map_err(OutputError::io(&json_path))?;
    let md = markdown(&numbers, params);
    let md_path = out.join("report.md");
    write_atomic(&md_path, md.as_bytes()).map_err(OutputError::io(&md_path))?;
    Ok(summary_table(&numbers))
}

/// Cd of Eq. (12) for the valve's nominal 20 L/min at full opening and a pressure drop `dp`.
pub fn cd_eq12(params: &Params, dp_pa: f64) -> f64 {
    let q = 20.0 / 60_000.0;
    q / (params.plant.valve.ka_m
        * params.plant.valve.xv_max_m
        * (2.0 * dp_pa / params.plant.fluid.density_kg_m3).sqrt())
}

fn fmt_opt(v: Option<f64>, digits: usize) -> String {
    v.map_or("none in range".to_string(), |x| {
        crate::format::fixed(x, digits)
    })
}

fn spread_cell(s: &Spread, scale: f64, digits: usize) -> String {
    format!(
        "{:.d$} ± {:.d$} ({:.d$}–{:.d$})",
        s.mean * scale,
        s.std * scale,
        s.min * scale,
        s.max * scale,
        d = digits
    )
}

/// The *paper value | this twin | note* rows: (quantity, paper, twin, note).
pub fn comparison_rows(n: &ReportNumbers) -> Vec<[String; 4]> {
    let seeds = RIDE_SEEDS.len();
    vec![
        [
            "Cd from Eq. (12), 20 L/min at full opening".into(),
            "0.1074 (stated for Δp = 70 bar)".into(),
            format!(
                "{:.4} at 70 bar, {:.4} at 100 bar",
                n.cd_from_eq12[0], n.cd_from_eq12[1]
            ),
            "The paper's 0.1074 follows from Δp = 100 bar (pA), not 70 bar (docs/model.md, correction 4).".into(),
        ],
        [
            "Gain of u̇/V_in at low frequency".into(),
            "Kg = 133.25 mm/(s·V) (G(s))".into(),
            format!(
                "{:.2} mm/(s·V) at 0.5 Hz, 0.72 V",
                n.twin_gain_m_per_s_v * 1e3
            ),
            "Reproduces: the adjusted Cd = 0.1506 gives the measured gain.".into(),
        ],
        [
            "Delay from the phase slope of u̇/V_in (1–20 Hz)".into(),
            "17.5 ms (measured, section 4.1)".into(),
            format!(
                "{:.1} ms (G(s): {:.1} ms)",
                n.twin_phase_delay_s * 1e3,
                n.linear_phase_delay_s * 1e3
            ),
            "Does not reproduce by design: the paper puts the measured *total* 17.5 ms into the \
             spool equation, whose own lag adds ≈ 2ζs/ωn = 3.2 ms (docs/model.md, correction 6). The \
             `consistent-delay` preset (τ = 14.3 ms) restores 17.5 ms."
                .into(),
        ],
        [
            "Passive |T| = 1 crossing".into(),
            "≈ 4 Hz".into(),
            format!("{} Hz", fmt_opt(n.passive_crossing_hz, 2)),
            "√2·fn with k = 3680 N/m in total (docs/model.md, correction 3).".into(),
        ],
        [
            "Active |T| = 1 crossing (end of isolation)".into(),
            "9 Hz (G(s), Fig. 12)".into(),
            format!(
                "G(s): {} Hz; twin: {} Hz linearised, {} Hz simulated",
                fmt_opt(n.linear_crossing_hz, 2),
                fmt_opt(n.twin_crossing_hz, 2),
                fmt_opt(n.twin_crossing_simulated_hz, 1)
            ),
            "G(s) reproduces 9 Hz; the twin as written crosses earlier because of its ≈ 3 ms \
             longer total delay."
                .into(),
        ],
        [
            "Random ride: RMS platform ẍ".into(),
            "0.48 m/s²".into(),
            format!(
                "{} m/s² ({seeds} seeds × 60 s)",
                spread_cell(&n.ride_rms_xdd, 1.0, 3)
            ),
            "√(S0·B) = √(0.05·4.5) = 0.474 m/s²; single 60 s Gaussian records spread a few %."
                .into(),
        ],
        [
            "Random ride: RMS body ÿ, equivalent model G(s)".into(),
            "0.15 m/s²".into(),
            format!("{} m/s²", spread_cell(&n.ride_rms_ydd_linear, 1.0, 3)),
            "Same controller, same band; the value scales with the realisation.".into(),
        ],
        [
            "Random ride: RMS body ÿ, multi-physics twin".into(),
            "0.16 m/s²".into(),
            format!("{} m/s²", spread_cell(&n.ride_rms_ydd_twin, 1.0, 3)),
            "Above the paper's value: the longer total delay leaves more residual \
             acceleration (docs/model.md, correction 6)."
                .into(),
        ],
        [
            "Random ride: RMS body ÿ, passive (ζ = 0.3)".into(),
            "0.67 m/s²".into(),
            format!("{} m/s²", spread_cell(&n.ride_rms_ydd_passive, 1.0, 3)),
            "The passive seat amplifies the 0.5–4 Hz band around its 2.8 Hz resonance.".into(),
        ],
        [
            "Chamber pressures oscillate symmetrically around 55 bar".into(),
            "yes (Fig. 16)".into(),
            format!(
                "mean {:.2} bar, max |p1 + p2 − 110 bar| = {:.1e} bar",
                n.ride_pressure_mean_pa / 1e5,
                n.ride_pressure_symmetry_pa / 1e5
            ),
            "Exact symmetry of the corrected model (docs/model.md, correction 11).".into(),
        ],
        [
            "Flows Q1 = Q2 within the valve's 20 L/min".into(),
            "yes (Fig. 16)".into(),
            format!("max |Q1| = {:.2} L/min", n.ride_max_flow_m3_s * 60_000.0),
            "".into(),
        ],
        [
            "End-stop contact in the random ride".into(),
            "not modelled; u stated within limits".into(),
            format!(
                "twin touched a stop in {} of {seeds} seeds",
                n.ride_twin_contact_seeds
            ),
            "The platform RMS displacement is ≈ 9 mm; some realisations exceed ±35 mm \
             (docs/model.md, correction 8). Contacts are flagged, not hidden."
                .into(),
        ],
        [
            "Cycloid: active body acceleration below the platform's".into(),
            "yes (Fig. 13)".into(),
            format!(
                "peak ẍ {:.3}; peak ÿ twin {:.3}, G(s) {:.3}, passive {:.3} m/s²",
                n.cycloid_peak_xdd,
                n.cycloid_peak_ydd[0],
                n.cycloid_peak_ydd[1],
                n.cycloid_peak_ydd[2]
            ),
            "The active seat reacts after the delay τ, as the paper notes.".into(),
        ],
    ]
}

fn markdown(n: &ReportNumbers, params: &Params) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "# seat-twin report — preset `{}`\n", n.preset);
    let _ = writeln!(
        s,
        "Reproduction of sections 4–6 of *Development of a Digital Twin for a Hydraulic, Active \
         Seat Suspension System* with the corrections of seat-twin's `docs/model.md` (Eq. 5 sign, μ/β names, \
         k in total). Parameters: Cd = {}, τ = {:.1} ms, Kp = {} V/m, Ki = {} V·s/m. Random-ride \
         statistics are over {} seeds of {:.0} s (the first 2 s fade-in excluded); they are \
         mean ± standard deviation (min–max).\n",
        params.plant.valve.cd,
        params.plant.valve.tau_s * 1e3,
        params.controller.kp_v_per_m,
        params.controller.ki_v_s_per_m,
        RIDE_SEEDS.len(),
        RIDE_DURATION_S
    );
    let _ = writeln!(
        s,
        "## Paper vs this twin\n\n| quantity | paper value | this twin | note |\n|---|---|---|---|"
    );
    for r in comparison_rows(n) {
        let _ = writeln!(s, "| {} | {} | {} | {} |", r[0], r[1], r[2], r[3]);
    }
    let m = &n.ride_seed1;
    let _ = writeln!(
        s,
        "\n## Ride comfort, seed 1 (ISO 2631-1 Wk, Directive 2002/44/EC)\n\n\
         | model | RMS ÿ [m/s²] | a_w [m/s²] | VDV [m/s^1.75] | SEAT [%] | A(8) for 8 h [m/s²] | RMS u [mm] | max abs u [mm] | contacts |\n|---|---|---|---|---|---|---|---|---|"
    );
    for (name, r) in ["twin", "G(s)", "passive"].iter().zip(m.iter()) {
        let _ = writeln!(
            s,
            "| {name} | {:.3} | {:.3} | {:.3} | {:.0} | {:.3} ({}) | {:.1} | {:.1} | {} |",
            r.rms_ydd,
            r.aw_ydd,
            r.vdv_ydd,
            r.seat_percent,
            metrics::a8(r.aw_ydd, 8.0),
            match metrics::exposure_verdict(metrics::a8(r.aw_ydd, 8.0)) {
                metrics::ExposureVerdict::BelowAction => "below action value",
                metrics::ExposureVerdict::AboveAction => "above action value",
                metrics::ExposureVerdict::AboveLimit => "above limit value",
            },
            r.rms_u * 1e3,
            r.max_abs_u * 1e3,
            r.contacts
        );
    }
    let _ = writeln!(
        s,
        "\n## Plots\n\n\
         ![Table 1 Bode](table1_bode.png)\n\n*Bode of u̇/V_in: the 69 sine tests of Table 1 on \
         the twin (markers, one colour per amplitude), the twin linearised at rest, and G(s).*\n\n\
         ![Transmissibility](transmissibility.png)\n\n*Fig. 12: transmissibility of the active \
         suspension (G(s), twin linearised, twin by sine dwell) and of the passive one.*\n\n\
         ![Cycloid](cycloid.png)\n\n*Figs. 13–14: cycloidal platform rise of 30 mm in 0.5 s.*\n\n\
         ![Random ride](ride.png)\n\n*Figs. 15–16: random ride (seed 1), accelerations, \
         displacements, chamber pressures and flows of the twin.*\n"
    );
    let _ = writeln!(
        s,
        "## Table 1 on the twin\n\n| f [Hz] | A [V] | abs(u̇/V) [mm/(s·V)] | phase [deg] |\n|---|---|---|---|"
    );
    for r in &n.table1 {
        let _ = writeln!(
            s,
            "| {} | {:.2} | {:.2} | {:.1} |",
            r.0,
            r.1,
            r.2 * 1e3,
            r.3
        );
    }
    s
}

fn summary_table(n: &ReportNumbers) -> String {
    let mut s = String::from("paper vs this twin:\n");
    for r in comparison_rows(n) {
        let _ = writeln!(s, "  {}: paper {} | twin {}", r[0], r[1], r[2]);
    }
    s
}

/// A point set for plotting a complex response.
pub fn mag_phase(points: &[FrequencyPoint]) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    (
        points.iter().map(|p| p.freq_hz).collect(),
        points.iter().map(|p| p.mag()).collect(),
        points.iter().map(|p| p.phase().to_degrees()).collect(),
    )
}

mod plots;

#[cfg(test)]
mod tests;
