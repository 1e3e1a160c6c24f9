//! The seat test on one model: a class's platform motion in closed loop, and its numbers.
//!
//! The "seat" is the suspended body of the rig (the model has no cushion and no occupant
//! model). Statistics cover the steady part of the record (the fades left out). The SEAT value
//! is `100 · a_w,seat / a_w,floor` with ISO 2631-1 Wk weighting ([`metrics::seat_percent`]);
//! the ratio of VDVs is given beside it, for when the crest factor is high.

use crate::analysis::metrics::{self, MetricsError};
use crate::experiments;
use crate::model::ModelKind;
use crate::params::{ParamError, Params};
use crate::scenario::PlatformMotion;
use crate::scenario::class_motion::{
    ClassMotion, Psd, PsdCheck, SignalError, WELCH_SEGMENT, check_psd, welch_psd,
};
use crate::scenario::classes::InputClass;
use crate::simulation::{Drive, SimError, Trace};

/// Default duration of a seat-test record \[s\], fades included (a choice made here: the
/// standards' run length was not read).
pub const DEFAULT_DURATION_S: f64 = 180.0;

/// Output rate of the seat-test trace \[Hz\] (the Wk filter wants ≥ 1 kHz for 0.5 % accuracy).
pub const SEAT_TEST_RATE_HZ: f64 = 1000.0;

/// Crest factor above which ISO 2631-1 (§6.2.1) says the weighted rms may underestimate and
/// the VDV should be used as well.
pub const CREST_FACTOR_LIMIT: f64 = 9.0;

/// Why a seat test could not run.
#[derive(Debug, thiserror::Error)]
pub enum SeatTestError {
    /// The generator's settings are out of range.
    #[error(transparent)]
    Signal(#[from] SignalError),
    /// The parameters (with the test mass) are invalid.
    #[error(transparent)]
    Params(#[from] ParamError),
    /// The simulation diverged.
    #[error(transparent)]
    Sim(#[from] SimError),
    /// A metric could not be computed.
    #[error(transparent)]
    Metrics(#[from] MetricsError),
}

/// What to run.
#[derive(Debug, Clone, Copy)]
pub struct SeatTestOptions {
    /// The input class.
    pub class: &'static InputClass,
    /// Which model.
    pub model: ModelKind,
    /// Suspended mass \[kg\]; `None` keeps the preset's (the paper's rig: 11.7 kg).
    pub mass_kg: Option<f64>,
    /// Record length, fades included \[s\].
    pub duration_s: f64,
    /// Seed of the class motion.
    pub seed: u64,
}

impl SeatTestOptions {
    /// The class on `model` with the preset's mass, [`DEFAULT_DURATION_S`] and seed 1.
    pub fn new(class: &'static InputClass, model: ModelKind) -> Self {
        Self {
            class,
            model,
            mass_kg: None,
            duration_s: DEFAULT_DURATION_S,
            seed: 1,
        }
    }
}

/// The numbers of one seat test (SI unless the name says otherwise); `numbers.json`.
#[derive(Debug, Clone, serde::Serialize)]
pub struct SeatTestNumbers {
    /// Class name.
    pub class: String,
    /// Standard of the class.
    pub standard: String,
    /// Model run.
    pub model: String,
    /// Suspended mass used \[kg\].
    pub mass_kg: f64,
    /// Wk-weighted rms of the platform (floor) acceleration [m/s²].
    pub aw_floor: f64,
    /// Wk-weighted rms of the suspended body ("seat") acceleration [m/s²].
    pub aw_seat: f64,
    /// SEAT [%] = 100 · aw_seat / aw_floor.
    pub seat_percent: f64,
    /// VDV of the seat [m/s^1.75] over the evaluated interval.
    pub vdv_seat: f64,
    /// VDV of the floor [m/s^1.75].
    pub vdv_floor: f64,
    /// 100 · VDV_seat / VDV_floor [%].
    pub seat_vdv_percent: f64,
    /// Crest factor of the weighted floor acceleration [-].
    pub crest_factor_floor: f64,
    /// Crest factor of the weighted seat acceleration [-].
    pub crest_factor_seat: f64,
    /// Largest |u| over the whole run \[mm\].
    pub max_abs_u_mm: f64,
    /// Half stroke: the end stops sit at ±this \[mm\].
    pub half_stroke_mm: f64,
    /// Total spring stiffness of the preset \[N/m\].
    pub spring_stiffness_n_per_m: f64,
    /// End-stop contacts (twin) or stroke overruns (linear, passive: no stops modelled).
    pub contacts: usize,
    /// Largest deviation of the platform PSD from the target in the class band [% of peak].
    pub psd_error_percent: f64,
    /// Whether that is within the ±10 % tolerance.
    pub psd_within_tolerance: bool,
    /// Where the largest deviation is \[Hz\].
    pub psd_error_at_hz: f64,
    /// rms of the platform acceleration in the class band [m/s²].
    pub floor_band_rms: f64,
    /// rms the target PSD implies in that band [m/s²].
    pub target_band_rms: f64,
    /// rms the source states for the class [m/s²].
    pub stated_rms: f64,
    /// Largest |x| of the platform: the travel the class needs \[mm\].
    pub platform_max_abs_x_mm: f64,
    /// Peak-to-peak platform displacement \[mm\].
    pub platform_peak_to_peak_mm: f64,
    /// rms platform displacement \[mm\].
    pub platform_rms_x_mm: f64,
    /// Record length \[s\].
    pub duration_s: f64,
    /// Evaluated interval (fades left out) \[s\].
    pub evaluated_s: f64,
    /// Seed of the class motion.
    pub seed: u64,
}

/// A seat test's numbers, trace and spectra.
#[derive(Debug, Clone)]
pub struct SeatTestResult {
    /// The numbers.
    pub numbers: SeatTestNumbers,
    /// The PSD check of the platform acceleration.
    pub psd_check: PsdCheck,
    /// The whole run.
    pub trace: Trace,
    /// Welch PSD of the platform acceleration (evaluated interval).
    pub psd_floor: Psd,
    /// Welch PSD of the seat acceleration (evaluated interval).
    pub psd_seat: Psd,
    /// The motion's settings.
    pub motion: ClassMotion,
}

/// Runs the class's motion on `opts.model` with `params` (mass replaced when given).
pub fn run_seat_test(
    params: &Params,
    opts: &SeatTestOptions,
) -> Result<SeatTestResult, SeatTestError> {
    let mut params = *params;
    if let Some(m) = opts.mass_kg {
        params.plant.body.mass_kg = m;
    }
    params.validate()?;
    let motion = ClassMotion {
        seed: opts.seed,
        ..ClassMotion::new(opts.class, opts.duration_s)
    };
    let sampled = motion.generate()?;
    let duration = sampled.duration_s();
    let trace = experiments::run(
        &params,
        opts.model,
        Drive::closed_loop(&params),
        PlatformMotion::Sampled(sampled),
        duration,
        SEAT_TEST_RATE_HZ,
    )?;
    let fs = SEAT_TEST_RATE_HZ;
    // The trace is sampled on the record's own grid (same rate, from t = 0), so the steady
    // range of the record indexes it directly.
    let range = motion.steady_range();
    let steady: Vec<&crate::simulation::Sample> = trace
        .samples
        .iter()
        .enumerate()
        .filter(|(i, _)| range.contains(i))
        .map(|(_, s)| s)
        .collect();
    let xdd: Vec<f64> = steady.iter().map(|s| s.xdd).collect();
    let ydd: Vec<f64> = steady.iter().map(|s| s.ydd).collect();
    // The Wk filter starts at rest at the first steady sample; its 0.4 Hz high-pass settles
    // within a few seconds, which the weighted statistics leave out.
    let settle = 5.0;
    let floor = metrics::vibration_metrics(&xdd, fs, settle)?;
    let seat = metrics::vibration_metrics(&ydd, fs, settle)?;
    let psd_check = check_psd(opts.class, &xdd, fs)?;
    let psd_floor = welch_psd(&xdd, fs, WELCH_SEGMENT)?;
    let psd_seat = welch_psd(&ydd, fs, WELCH_SEGMENT)?;
    let x: Vec<f64> = trace.samples.iter().map(|s| s.x).collect();
    let x_max = x.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let x_min = x.iter().copied().fold(f64::INFINITY, f64::min);
    let u: Vec<f64> = trace.samples.iter().map(|s| s.u).collect();
    let numbers = SeatTestNumbers {
        class: opts.class.name.to_string(),
        standard: opts.class.standard.citation().to_string(),
        model: opts.model.name().to_string(),
        mass_kg: params.plant.body.mass_kg,
        aw_floor: floor.aw,
        aw_seat: seat.aw,
        seat_percent: metrics::seat_percent(seat.aw, floor.aw),
        vdv_seat: seat.vdv,
        vdv_floor: floor.vdv,
        seat_vdv_percent: 100.0 * seat.vdv / floor.vdv,
        crest_factor_floor: floor.crest_factor,
        crest_factor_seat: seat.crest_factor,
        max_abs_u_mm: 1e3 * metrics::peak(&u),
        half_stroke_mm: 1e3 * params.plant.cylinder.stroke_m / 2.0,
        spring_stiffness_n_per_m: params.plant.body.stiffness_n_per_m,
        contacts: trace.contacts.len(),
        psd_error_percent: 100.0 * psd_check.max_error_of_peak,
        psd_within_tolerance: psd_check.within_tolerance(),
        psd_error_at_hz: psd_check.at_hz,
        floor_band_rms: psd_check.band_rms,
        target_band_rms: psd_check.target_band_rms,
        stated_rms: opts.class.rms_m_s2,
        platform_max_abs_x_mm: 1e3 * metrics::peak(&x),
        platform_peak_to_peak_mm: 1e3 * (x_max - x_min),
        platform_rms_x_mm: 1e3 * metrics::rms(&x),
        duration_s: duration,
        evaluated_s: floor.duration_s,
        seed: opts.seed,
    };
    Ok(SeatTestResult {
        numbers,
        psd_check,
        trace,
        psd_floor,
        psd_seat,
        motion,
    })
}
