//! Auto-tuning of a controller's gains on the **nonlinear twin** (not on G(s)).
//!
//! The problem: minimise an ISO 2631-1 objective of the body's acceleration (Wk-weighted
//! `a_w`, VDV, or the SEAT ratio) averaged over a few random rides, subject to
//! * **stability at every point of the parameter spread** (Cd ±10 %, τ ±3 ms, mass ±20 %:
//!   27 points), from the closed-loop eigenvalues of the twin linearised at rest with the
//!   delay ([`crate::analysis::stability`]) — a hard constraint: a gain set unstable anywhere
//!   in the spread is never feasible, and one unstable where the rides run is not simulated;
//! * no end-stop contact and `max |u| ≤ 30 mm` on every tuning ride;
//! * every closed-loop mode at every point of the spread decays at ≥ 0.2 1/s;
//! * over every crossing of the loop: gain margin ≥ 6 dB, phase margin ≥ 45° and delay margin
//!   ≥ 3 ms (the τ part of the spread) at the nominal plant (at the corners too with `robust`).
//!
//! The soft constraints enter as a penalty that grows with the violation, so the search
//! (Nelder–Mead, from the `argmin` crate) is pulled back into the feasible set rather than
//! walled off. Each evaluation runs the tuning rides in parallel (rayon). With `robust`, the
//! objective is the worst case over the spread's corners and nominal point.
//!
//! The result is then checked where instability shows ([`RobustnessRow`]): at each of the 27
//! points, the eigenvalue verdict, the smallest delay margin, and a settle test at rest after a
//! bump on the nonlinear twin ([`crate::analysis::settle`]), besides the ride objective. The
//! best feasible gains that pass every point are the tuned ones; if none do,
//! [`TuneResult::failures`] says why and no tuned preset should be written.
//!
//! What comes out ([`TuneResult`]): the tuned gains; the objective of the starting gains and
//! of the tuned ones on the tuning rides and on held-out rides (other seeds); the margins and
//! stroke use of the tuned loop; the robustness table; and the Pareto front of objective
//! against stroke use among every feasible evaluation.

pub mod report;
mod robustness;
mod run;

pub use robustness::{RobustnessRow, robustness_table, spread, tau_max_s};
pub use run::TuneRun;

use crate::analysis::frequency_response::LinearisedModel;
use crate::analysis::metrics;
use crate::analysis::stability::{ClosedLoopModes, LoopMargins, LoopPlant, MarginGrid};
use crate::control::ControlLaw;
use crate::experiments;
use crate::model::ModelKind;
use crate::params::{ControllerKind, ControllerParams, Params};
use crate::scenario::InputClass;
use crate::scenario::class_motion::ClassMotion;
use crate::scenario::{PlatformMotion, RandomRide};
use crate::simulation::Drive;
use rayon::prelude::*;
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

/// Largest stroke use allowed on a tuning ride \[m\].
pub const MAX_ABS_U_M: f64 = 0.030;
/// Smallest gain margin allowed \[dB\].
pub const MIN_GAIN_MARGIN_DB: f64 = 6.0;
/// Smallest phase margin allowed \[deg\] (over every gain crossover, in magnitude).
pub const MIN_PHASE_MARGIN_DEG: f64 = 45.0;
/// Smallest delay margin allowed \[s\]: the τ part of the spread.
pub const MIN_DELAY_MARGIN_S: f64 = 0.003;
/// Slowest decay allowed of any closed-loop mode at any point of the spread [1/s] (a time
/// constant of 5 s: a mode rung by a bump is gone well within the settle test's 10 s).
pub const MIN_DECAY_RATE_PER_S: f64 = 0.02;
/// Feasible candidates, best first, put through the robustness check before giving up.
const MAX_CHECKED_CANDIDATES: usize = 12;
/// Start of the ride left out of the metrics (the rides fade in over 2 s) \[s\].
pub const SETTLE_S: f64 = 2.0;
/// Recording rate of the tuning runs [Hz].
const RATE_HZ: f64 = 500.0;

/// What the tuner minimises (of the body's acceleration, ISO 2631-1).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Objective {
    /// Wk-weighted RMS `a_w` [m/s²].
    Aw,
    /// Vibration dose value of the Wk-weighted acceleration [m/s^1.75].
    Vdv,
    /// SEAT: `a_w` of the body over `a_w` of the platform [%].
    Seat,
}

impl Objective {
    /// Name as on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Objective::Aw => "aw",
            Objective::Vdv => "vdv",
            Objective::Seat => "seat",
        }
    }

    /// Unit of the objective's value.
    pub fn unit(self) -> &'static str {
        match self {
            Objective::Aw => "m/s²",
            Objective::Vdv => "m/s^1.75",
            Objective::Seat => "%",
        }
    }
}

impl std::str::FromStr for Objective {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "aw" => Ok(Objective::Aw),
            "vdv" => Ok(Objective::Vdv),
            "seat" => Ok(Objective::Seat),
            _ => Err(format!("unknown objective `{s}` (one of: aw, vdv, seat)")),
        }
    }
}

/// The platform motion of the tuning (and held-out) rides.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TuneInput {
    /// The paper's band-limited random ride (section 6).
    Ride,
    /// A seat-test input spectral class ([`crate::seat_test`]), one record per seed.
    Class(&'static InputClass),
}

impl TuneInput {
    /// What the rides are, for reports.
    pub fn describe(&self) -> String {
        match self {
            TuneInput::Ride => "the paper's band-limited random ride".into(),
            TuneInput::Class(c) => format!("seat-test input class {}", c.name),
        }
    }

    /// The motion for one seed and duration \[s\].
    pub fn motion(&self, seed: u64, duration_s: f64) -> Result<PlatformMotion, TuneError> {
        match self {
            TuneInput::Ride => Ok(ride(seed, duration_s)),
            TuneInput::Class(class) => {
                let m = ClassMotion {
                    seed,
                    ..ClassMotion::new(class, duration_s)
                };
                m.validate()
                    .and_then(|()| m.generate())
                    .map(PlatformMotion::Sampled)
                    .map_err(|e| TuneError::Input(e.to_string()))
            }
        }
    }
}

/// How to tune.
#[derive(Debug, Clone)]
pub struct TuneOptions {
    /// Structure to tune; the preset's gains of that structure are the start.
    pub kind: ControllerKind,
    /// What to minimise.
    pub objective: Objective,
    /// The rides' platform motion.
    pub input: TuneInput,
    /// Seeds of the tuning rides.
    pub tune_seeds: Vec<u64>,
    /// Seeds of the held-out rides (confirmation only).
    pub heldout_seeds: Vec<u64>,
    /// Duration of each ride \[s\], ≥ 5.
    pub duration_s: f64,
    /// Optimise the worst case over the parameter spread.
    pub robust: bool,
    /// Budget of objective evaluations (each runs every tuning ride), ≥ 10.
    pub max_evaluations: usize,
}

impl Default for TuneOptions {
    fn default() -> Self {
        Self {
            kind: ControllerKind::Paper,
            objective: Objective::Aw,
            input: TuneInput::Ride,
            tune_seeds: vec![1, 2, 3],
            heldout_seeds: vec![101, 102, 103],
            duration_s: 60.0,
            robust: false,
            max_evaluations: 120,
        }
    }
}

/// Why tuning could not run.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TuneError {
    /// An option outside its range.
    #[error("tune option `{name}` = {value} is outside [{min}, {max}]")]
    Option {
        /// Option name.
        name: &'static str,
        /// Its value.
        value: f64,
        /// Smallest allowed.
        min: f64,
        /// Largest allowed.
        max: f64,
    },
    /// No seeds to tune on.
    #[error("tune needs at least one tuning seed")]
    NoSeeds,
    /// The ride motion could not be made.
    #[error("tuning input: {0}")]
    Input(String),
    /// The optimiser failed.
    #[error("optimiser: {0}")]
    Optimiser(String),
    /// Cancelled by the caller.
    #[error("tuning was cancelled")]
    Cancelled,
}

/// One evaluation of a set of gains.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Evaluation {
    /// The controller evaluated (not in report.json; the app's session file keeps it beside
    /// the evaluation).
    #[serde(skip)]
    pub controller: ControllerParams,
    /// The tuned keys and their values.
    pub gains: Vec<(String, f64)>,
    /// Mean objective over the rides (worst case over the spread when robust); NaN if a ride
    /// diverged.
    pub objective: f64,
    /// Largest |u| over the rides \[m\].
    pub max_abs_u_m: f64,
    /// End-stop contacts over the rides.
    pub contacts: usize,
    /// Gain margin of the linearised loop, the crossing nearest instability \[dB\] (worst over
    /// the corners when robust).
    pub gain_margin_db: f64,
    /// Phase margin of the linearised loop, the crossover nearest instability \[deg\] (worst over
    /// the corners when robust).
    pub phase_margin_deg: f64,
    /// Smallest delay margin over every crossover \[s\] (worst over the corners when robust).
    pub delay_margin_s: f64,
    /// Points of the 27-point spread where the loop linearised at rest is unstable.
    pub unstable_points: usize,
    /// Largest closed-loop growth rate over the spread [1/s] (negative: every mode decays).
    pub worst_growth_rate_per_s: f64,
    /// Every constraint met.
    pub feasible: bool,
}

/// What tuning found.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct TuneResult {
    /// Structure tuned.
    pub kind: ControllerKind,
    /// Objective minimised.
    pub objective: Objective,
    /// What the rides were.
    pub input: String,
    /// The starting controller (the preset's gains) on the tuning rides.
    pub baseline: Evaluation,
    /// The tuned controller on the tuning rides.
    pub tuned: Evaluation,
    /// The starting controller on the held-out rides.
    pub baseline_heldout: Evaluation,
    /// The tuned controller on the held-out rides.
    pub tuned_heldout: Evaluation,
    /// The tuned controller over the parameter spread (on the tuning rides).
    pub robustness: Vec<RobustnessRow>,
    /// Feasible evaluations that no other feasible one beats on both objective and stroke.
    pub pareto: Vec<Evaluation>,
    /// Objective evaluations made by the search.
    pub evaluations: usize,
    /// Seeds and duration used.
    pub tune_seeds: Vec<u64>,
    /// Held-out seeds.
    pub heldout_seeds: Vec<u64>,
    /// Ride duration \[s\].
    pub duration_s: f64,
    /// Whether the worst case over the spread was optimised.
    pub robust: bool,
    /// Why the search stopped.
    pub stop_reason: String,
    /// Why the tuned gains' claim fails (empty when it holds at every point of the spread):
    /// a tuned preset should only be written when this is empty.
    pub failures: Vec<String>,
}

/// The gains a structure tunes, with the scale of one search unit. Corner frequencies stay as
/// the preset sets them (they are design choices, not gains). `Kp` is searched on a log scale
/// of |Kp| with its sign fixed negative (`to_search`): positive position feedback is unstable
/// at any gain, and the stable range of |Kp| spans decades (a few V/m at rest, where the oil
/// column limits it, to tens of V/m on G(s)).
pub fn tuned_keys(kind: ControllerKind) -> &'static [(&'static str, f64)] {
    match kind {
        ControllerKind::Paper | ControllerKind::Smith => {
            &[("kp_v_per_m", 40.0), ("ki_v_s_per_m", 2.0)]
        }
        ControllerKind::Predictive => &[
            ("kp_v_per_m", 40.0),
            ("ki_v_s_per_m", 2.0),
            ("lead_s", 0.01),
        ],
        ControllerKind::Skyhook => &[
            ("kp_v_per_m", 40.0),
            ("ki_v_s_per_m", 2.0),
            ("sky_v_s_per_m", 2.0),
        ],
    }
}

/// The key searched on a log scale (see [`tuned_keys`]).
const LOG_KEY: &str = "kp_v_per_m";

/// A gain in search units: `ln(|Kp| / 1 V/m)` for Kp (a positive start is mirrored to −|Kp|,
/// its stable side), `value / scale` for the others.
fn to_search(key: &str, scale: f64, value: f64) -> f64 {
    if key == LOG_KEY {
        value.abs().max(1e-3).ln()
    } else {
        value / scale
    }
}

/// The inverse of [`to_search`].
fn from_search(key: &str, scale: f64, x: f64) -> f64 {
    if key == LOG_KEY { -x.exp() } else { x * scale }
}

/// The random ride of the paper (section 6) with a seed and duration.
pub fn ride(seed: u64, duration_s: f64) -> PlatformMotion {
    PlatformMotion::Sampled(
        RandomRide {
            seed,
            duration_s,
            ..Default::default()
        }
        .generate(),
    )
}

/// Objective, max |u| and contacts of the twin on one ride; `None` if it diverged.
fn ride_score(
    params: &Params,
    ride: &PlatformMotion,
    duration_s: f64,
    objective: Objective,
) -> Option<(f64, f64, usize)> {
    let trace = experiments::run(
        params,
        ModelKind::Twin,
        Drive::closed_loop(params),
        ride.clone(),
        duration_s,
        RATE_HZ,
    )
    .ok()?;
    let ydd = trace.channel(|s| s.ydd);
    let body = metrics::vibration_metrics(&ydd, RATE_HZ, SETTLE_S).ok()?;
    let value = match objective {
        Objective::Aw => body.aw,
        Objective::Vdv => body.vdv,
        Objective::Seat => {
            let xdd = trace.channel(|s| s.xdd);
            let floor = metrics::vibration_metrics(&xdd, RATE_HZ, SETTLE_S).ok()?;
            metrics::seat_percent(body.aw, floor.aw)
        }
    };
    let max_u = trace.samples.iter().map(|s| s.u.abs()).fold(0.0, f64::max);
    value
        .is_finite()
        .then_some((value, max_u, trace.contacts.len()))
}

/// Mean objective, max |u| and contacts over rides (in parallel); objective NaN if any ride
/// diverged.
fn score_rides(
    params: &Params,
    rides: &[PlatformMotion],
    duration_s: f64,
    objective: Objective,
) -> (f64, f64, usize) {
    let scores: Vec<Option<(f64, f64, usize)>> = rides
        .par_iter()
        .map(|r| ride_score(params, r, duration_s, objective))
        .collect();
    if scores.iter().any(Option::is_none) {
        return (f64::NAN, f64::NAN, 0);
    }
    let scores: Vec<(f64, f64, usize)> = scores.into_iter().flatten().collect();
    let mean = scores.iter().map(|s| s.0).sum::<f64>() / scores.len() as f64;
    let max_u = scores.iter().map(|s| s.1).fold(0.0, f64::max);
    let contacts = scores.iter().map(|s| s.2).sum();
    (mean, max_u, contacts)
}

/// Why the gain search stopped before the optimiser's own termination: carried through
/// argmin's error as a type, and read back by downcasting, not by matching its text.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
enum SearchStop {
    /// The caller set the cancel flag.
    #[error("tuning was cancelled")]
    Cancelled,
    /// The search asked for an evaluation past [`TuneOptions::max_evaluations`].
    #[error("budget of evaluations used")]
    BudgetUsed,
}

impl SearchStop {
    /// The stop reason an optimiser's error carries, if it is one of these.
    fn of(e: &argmin::core::Error) -> Option<Self> {
        e.downcast_ref::<SearchStop>().copied()
    }
}

/// The gain search: the cost of a controller's gains on a plant (or its spread), rides and an
/// objective, with the evaluation log, the budget and the cancel flag.
struct GainSearch {
    /// Plants whose rides and margins are evaluated: the nominal alone, or the spread's
    /// corners and nominal when robust.
    plants: Vec<(Params, LinearisedModel, MarginGrid)>,
    /// Every point of the spread, for the stability constraint.
    spread: Vec<(Params, LoopPlant)>,
    rides: Vec<PlatformMotion>,
    duration_s: f64,
    objective: Objective,
    kind: ControllerKind,
    start: ControllerParams,
    /// Objective of the start, the penalty's scale.
    scale: Mutex<Option<f64>>,
    log: Mutex<Vec<Evaluation>>,
    count: AtomicUsize,
    cancel: Option<std::sync::Arc<AtomicBool>>,
    /// Told `(evaluations done, budget)` after each search evaluation.
    progress: Option<Progress>,
    /// Most search evaluations ([`TuneOptions::max_evaluations`]).
    budget: usize,
    /// The optimiser is evaluating its start simplex (no stop then).
    starting: AtomicBool,
}

/// A progress observer: called with `(evaluations done, budget)` from the tuning thread.
pub type Progress = std::sync::Arc<dyn Fn(usize, usize) + Send + Sync>;

impl GainSearch {
    /// Whether the caller set the cancel flag.
    fn cancelled(&self) -> bool {
        self.cancel
            .as_ref()
            .is_some_and(|c| c.load(Ordering::Relaxed))
    }

    fn controller_at(&self, x: &[f64]) -> ControllerParams {
        let mut c = self.start;
        c.kind = self.kind;
        for ((key, scale), xi) in tuned_keys(self.kind).iter().zip(x) {
            let (min, max, _) = ControllerParams::range(key).unwrap_or((-1e4, 1e4, ""));
            c.set(key, from_search(key, *scale, *xi).clamp(min, max));
        }
        c
    }

    fn evaluate(&self, c: ControllerParams) -> Evaluation {
        let law = |p: &Params| {
            let mut q = *p;
            q.controller = c;
            ControlLaw::new(&q)
        };
        // Stability at every point of the spread first. The rides are simulated only where
        // the loop is stable at the plants they run on (the nominal, or the corners when
        // robust); a gain set unstable elsewhere in the spread is simulated there but can
        // never be feasible.
        let (mut unstable, mut growth, mut ride_plants_stable) = (0, f64::NEG_INFINITY, true);
        for (p, plant) in &self.spread {
            let stable = match ClosedLoopModes::of(plant, &law(p), p.plant.valve.tau_s) {
                Some(m) => {
                    growth = growth.max(m.growth_rate_per_s);
                    m.stable()
                }
                None => {
                    growth = f64::INFINITY;
                    false
                }
            };
            if !stable {
                unstable += 1;
                ride_plants_stable &= !self.plants.iter().any(|(q, _, _)| q == p);
            }
        }
        let (mut gm, mut pm, mut dm) = (f64::INFINITY, f64::INFINITY, f64::INFINITY);
        for (p, lin, grid) in &self.plants {
            let m = LoopMargins::on_grid(lin, grid, &law(p), p.plant.valve.tau_s);
            gm = gm.min(m.gain_margin_db().abs());
            pm = pm.min(m.phase_margin_deg().abs());
            dm = dm.min(m.delay_margin_s());
        }
        let gains = tuned_keys(self.kind)
            .iter()
            .map(|(k, _)| (k.to_string(), c.get(k).unwrap_or(f64::NAN)))
            .collect();
        let margins_ok =
            gm >= MIN_GAIN_MARGIN_DB && pm >= MIN_PHASE_MARGIN_DEG && dm >= MIN_DELAY_MARGIN_S;
        let (mut objective, mut max_u, mut contacts) = (f64::NAN, f64::NAN, 0);
        if ride_plants_stable {
            objective = f64::NEG_INFINITY;
            max_u = 0.0;
            for (p, _, _) in &self.plants {
                let mut q = *p;
                q.controller = c;
                let (o, u, n) = score_rides(&q, &self.rides, self.duration_s, self.objective);
                objective = objective.max(o);
                max_u = f64::max(max_u, u);
                contacts += n;
                if !o.is_finite() {
                    objective = f64::NAN;
                    break;
                }
            }
        }
        let feasible = unstable == 0
            && growth <= -MIN_DECAY_RATE_PER_S
            && margins_ok
            && objective.is_finite()
            && contacts == 0
            && max_u <= MAX_ABS_U_M;
        Evaluation {
            controller: c,
            gains,
            objective,
            max_abs_u_m: max_u,
            contacts,
            gain_margin_db: gm,
            phase_margin_deg: pm,
            delay_margin_s: dm,
            unstable_points: unstable,
            worst_growth_rate_per_s: growth,
            feasible,
        }
    }

    /// The penalised cost of an evaluation.
    fn cost(&self, e: &Evaluation) -> f64 {
        let scale = self.scale.lock().map(|s| s.unwrap_or(1.0)).unwrap_or(1.0);
        let mut violation = 0.0;
        violation += (MIN_GAIN_MARGIN_DB - e.gain_margin_db).max(0.0) / MIN_GAIN_MARGIN_DB;
        violation += (MIN_PHASE_MARGIN_DEG - e.phase_margin_deg).max(0.0) / MIN_PHASE_MARGIN_DEG;
        violation += (MIN_DELAY_MARGIN_S - e.delay_margin_s).max(0.0) / MIN_DELAY_MARGIN_S;
        // Unstable points, and a continuous pull towards decay (the growth rate varies
        // smoothly with the gains, so the search finds its way out of an unstable start).
        violation += e.unstable_points as f64;
        if e.worst_growth_rate_per_s.is_finite() {
            violation +=
                (e.worst_growth_rate_per_s + MIN_DECAY_RATE_PER_S).max(0.0) / MIN_DECAY_RATE_PER_S;
        } else {
            violation += 100.0;
        }
        if e.max_abs_u_m.is_finite() {
            violation += (e.max_abs_u_m / MAX_ABS_U_M - 1.0).max(0.0);
        }
        violation += e.contacts as f64;
        if e.objective.is_finite() {
            e.objective + scale * 10.0 * violation
        } else {
            // Not simulated (unstable where the rides run) or diverged: worse than any
            // simulated point.
            scale * (20.0 + 10.0 * violation)
        }
    }
}

impl GainSearch {
    /// The optimiser's cost of search point `x`: an evaluation, logged and counted, or the
    /// typed stop when cancelled or past the budget.
    fn search_cost(&self, x: &[f64]) -> Result<f64, argmin::core::Error> {
        // Not while the optimiser evaluates its start simplex: argmin's Nelder–Mead unwraps
        // those costs (a stop there would panic); the cancel is seen right after it.
        if !self.starting.load(Ordering::Relaxed) && self.cancelled() {
            return Err(SearchStop::Cancelled.into());
        }
        // The budget is a hard maximum (issue 21): the evaluation past it stops the search.
        if self.count.load(Ordering::Relaxed) >= self.budget {
            return Err(SearchStop::BudgetUsed.into());
        }
        let e = self.evaluate(self.controller_at(x));
        let done = self.count.fetch_add(1, Ordering::Relaxed) + 1;
        if let Some(p) = &self.progress {
            p(done, self.budget);
        }
        let cost = GainSearch::cost(self, &e);
        if let Ok(mut log) = self.log.lock() {
            log.push(e);
        }
        Ok(cost)
    }
}

/// Feasible evaluations not dominated on (objective, max |u|), sorted by stroke use.
pub fn pareto_front(evals: &[Evaluation]) -> Vec<Evaluation> {
    let feasible: Vec<&Evaluation> = evals.iter().filter(|e| e.feasible).collect();
    let mut front: Vec<Evaluation> = feasible
        .iter()
        .filter(|e| {
            !feasible.iter().any(|o| {
                o.objective <= e.objective
                    && o.max_abs_u_m <= e.max_abs_u_m
                    && (o.objective < e.objective || o.max_abs_u_m < e.max_abs_u_m)
            })
        })
        .map(|e| (*e).clone())
        .collect();
    front.sort_by(|a, b| a.max_abs_u_m.total_cmp(&b.max_abs_u_m));
    front.dedup_by(|a, b| a.gains == b.gains);
    front
}

/// Tunes the preset's controller of `opts.kind` on the twin; setting `cancel` stops at the
/// next evaluation.
pub fn tune(
    params: &Params,
    opts: &TuneOptions,
    cancel: Option<std::sync::Arc<AtomicBool>>,
) -> Result<TuneResult, TuneError> {
    tune_observed(params, opts, cancel, None)
}

/// [`tune`] with a progress observer: `progress(done, budget)` after each search evaluation
/// (`budget` = `opts.max_evaluations`; the search may stop earlier, on its tolerance).
/// It is [`TuneRun`] stepped to its end.
pub fn tune_observed(
    params: &Params,
    opts: &TuneOptions,
    cancel: Option<std::sync::Arc<AtomicBool>>,
    progress: Option<Progress>,
) -> Result<TuneResult, TuneError> {
    let mut run = TuneRun::new(params, opts, cancel, progress)?;
    loop {
        if let Some(result) = run.step() {
            return result;
        }
    }
}

fn check_options(o: &TuneOptions) -> Result<(), TuneError> {
    if o.tune_seeds.is_empty() {
        return Err(TuneError::NoSeeds);
    }
    if !(o.duration_s.is_finite() && (5.0..=600.0).contains(&o.duration_s)) {
        return Err(TuneError::Option {
            name: "duration_s",
            value: o.duration_s,
            min: 5.0,
            max: 600.0,
        });
    }
    if !(10..=10_000).contains(&o.max_evaluations) {
        return Err(TuneError::Option {
            name: "max_evaluations",
            value: o.max_evaluations as f64,
            min: 10.0,
            max: 10_000.0,
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_cancelled_stepped_tune_stops_with_the_typed_reason() {
        let opts = TuneOptions {
            duration_s: 6.0,
            max_evaluations: 14,
            ..TuneOptions::default()
        };
        let cancel = std::sync::Arc::new(AtomicBool::new(false));
        let mut run = TuneRun::new(&Params::paper(), &opts, Some(cancel.clone()), None).unwrap();
        assert!(run.step().is_none(), "the baseline is one step");
        cancel.store(true, Ordering::Relaxed);
        assert!(matches!(run.step(), Some(Err(TuneError::Cancelled))));
        assert!(run.step().is_none(), "the result comes once");
    }
}
