//! `seat-twin bench`: real-time factors, accuracy against a 10× finer step and the Table 1
//! sweep time, measured on this machine. (The criterion benches in `benches/` measure the same
//! kernels with statistics.)

use crate::analysis::dwell;
use crate::experiments;
use crate::model::ModelKind;
use crate::params::{Integrator, Params};
use crate::scenario::{PlatformMotion, RandomRide};
use crate::simulation::{Drive, SimError, Trace};
use std::fmt::Write;
use std::time::Instant;

/// RK4's step for the same accuracy as the exponential method at 0.5 ms \[s\].
pub const RK4_STEP_S: f64 = 1e-4;

/// Largest ÿ error against the same run at a 10× finer step that the preset's step must keep
/// [m/s²].
pub const MAX_YDD_ERROR: f64 = 1e-4;

/// Step of the independent RK4 reference run \[s\].
pub const REFERENCE_STEP_S: f64 = 1e-5;

/// Accuracy of a run against the same run at a 10× finer step.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Accuracy {
    /// Step of the run \[s\].
    pub step_s: f64,
    /// Largest |ÿ − ÿ_fine| over the record [m/s²].
    pub max_ydd_error: f64,
    /// RMS of ÿ − ÿ_fine [m/s²].
    pub rms_ydd_error: f64,
    /// Largest |u − u_fine| \[m\].
    pub max_u_error: f64,
}

/// The random ride used by the bench (10 s, seed 1, paper's band and level).
pub fn bench_ride(duration_s: f64) -> PlatformMotion {
    PlatformMotion::Sampled(
        RandomRide {
            duration_s,
            fade_in_s: 1.0,
            ..Default::default()
        }
        .generate(),
    )
}

/// Runs the closed-loop random ride on `kind` with internal step `step_s`, recorded at 1 kHz.
pub fn ride_run(
    params: &Params,
    kind: ModelKind,
    ride: &PlatformMotion,
    duration_s: f64,
    step_s: f64,
) -> Result<Trace, SimError> {
    let mut p = *params;
    p.numerics.max_step_s = step_s;
    experiments::run(
        &p,
        kind,
        Drive::closed_loop(&p),
        ride.clone(),
        duration_s,
        1000.0,
    )
}

/// The internal step a closed-loop run of `kind` recorded at 1 kHz uses \[s\]: the preset's
/// step for the twin, the exact-hold step for the linear and passive models.
pub fn bench_step_s(params: &Params, kind: ModelKind) -> f64 {
    match kind {
        ModelKind::Twin => params.numerics.max_step_s,
        ModelKind::Linear | ModelKind::Passive => experiments::LTI_MAX_STEP_S,
    }
}

/// Compares a run at `step_s` with one at `step_s / 10` (both recorded at 1 kHz).
pub fn accuracy(
    params: &Params,
    ride: &PlatformMotion,
    duration_s: f64,
    step_s: f64,
) -> Result<Accuracy, SimError> {
    let coarse = ride_run(params, ModelKind::Twin, ride, duration_s, step_s)?;
    let fine = ride_run(params, ModelKind::Twin, ride, duration_s, step_s / 10.0)?;
    Ok(accuracy_of(&coarse, &fine, step_s))
}

/// Accuracy of `coarse` (run at `step_s`) against `fine` (the same run at a finer step).
pub fn accuracy_of(coarse: &Trace, fine: &Trace, step_s: f64) -> Accuracy {
    let mut max_e: f64 = 0.0;
    let mut sum2 = 0.0;
    let mut max_u: f64 = 0.0;
    let n = coarse.samples.len().min(fine.samples.len());
    for (a, b) in coarse.samples.iter().zip(&fine.samples) {
        let e = a.ydd - b.ydd;
        max_e = max_e.max(e.abs());
        sum2 += e * e;
        max_u = max_u.max((a.u - b.u).abs());
    }
    Accuracy {
        step_s,
        max_ydd_error: max_e,
        rms_ydd_error: (sum2 / n.max(1) as f64).sqrt(),
        max_u_error: max_u,
    }
}

/// Wall times of repeated runs \[s\].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Timing {
    /// Fastest run: the cost without interference from the rest of the machine.
    pub best_s: f64,
    /// Median run.
    pub median_s: f64,
    /// Number of runs.
    pub runs: usize,
}

/// Times `f` at least `min_runs` times and until `budget_s` \[s\] of runs have passed (at most
/// 1000 runs); returns the timing and the last result. A shared 2-core VM's speed drifts
/// between and within invocations, so one or five runs can land on a slow patch: many runs and
/// their minimum and median say more.
pub fn timed<T>(min_runs: usize, budget_s: f64, mut f: impl FnMut() -> T) -> (Timing, T) {
    let start = Instant::now();
    let mut walls = Vec::new();
    let mut last = None;
    while walls.len() < min_runs.max(1)
        || (start.elapsed().as_secs_f64() < budget_s && walls.len() < 1000)
    {
        let t0 = Instant::now();
        let r = f();
        walls.push(t0.elapsed().as_secs_f64());
        last = Some(r);
    }
    walls.sort_by(f64::total_cmp);
    let timing = Timing {
        best_s: walls[0],
        median_s: walls[walls.len() / 2],
        runs: walls.len(),
    };
    (timing, last.expect("at least one run"))
}

/// Largest |ÿ − ÿ_ref| between two traces on the same grid [m/s²].
pub fn max_ydd_difference(a: &Trace, b: &Trace) -> f64 {
    a.samples
        .iter()
        .zip(&b.samples)
        .map(|(x, y)| (x.ydd - y.ydd).abs())
        .fold(0.0, f64::max)
}

/// Runs the benchmark and returns a Markdown summary.
pub fn run_bench(params: &Params) -> Result<String, SimError> {
    let mut out = String::new();
    let duration = 10.0;
    let ride = bench_ride(duration);
    let h = params.numerics.max_step_s;
    let mut rk4 = *params;
    rk4.numerics.integrator = Integrator::Rk4;
    rk4.numerics.max_step_s = RK4_STEP_S.min(params.rk4_step_limit_s());
    let _ = writeln!(
        out,
        "# seat-twin bench\n\nmachine: {} logical cores, stepping loop {}; preset integrator {} \
         at {:.1e} s; ride 10 s (closed loop, paper controller), recorded at 1 kHz; each timed \
         over ≥ 1 s of repeated runs (fastest and median run)\n",
        std::thread::available_parallelism().map_or(1, |n| n.get()),
        if crate::simulation::wide_simd() {
            "AVX"
        } else {
            "baseline SIMD"
        },
        params.numerics.integrator.name(),
        h
    );
    let _ = writeln!(
        out,
        "| model | method | step | wall for 10 s simulated, fastest (median) | real-time factor, fastest (median) | runs | steps | RHS evaluations |\n|---|---|---|---|---|---|---|---|"
    );
    let mut rows = vec![(ModelKind::Twin, *params)];
    if params.numerics.integrator != Integrator::Rk4 {
        rows.push((ModelKind::Twin, rk4));
    }
    rows.push((ModelKind::Linear, *params));
    rows.push((ModelKind::Passive, *params));
    for (kind, p) in rows {
        let step = p.numerics.max_step_s;
        let (wall, trace) = timed(5, 1.0, || ride_run(&p, kind, &ride, duration, step));
        let trace = trace?;
        let method = match kind {
            ModelKind::Twin => p.numerics.integrator.name(),
            ModelKind::Linear | ModelKind::Passive => "exact hold",
        };
        let _ = writeln!(
            out,
            "| {} | {} | {:.1e} s | {:.3} ({:.3}) ms | {:.0}× ({:.0}×) | {} | {} | {} |",
            kind.name(),
            method,
            duration / trace.stats.steps.max(1) as f64,
            wall.best_s * 1e3,
            wall.median_s * 1e3,
            duration / wall.best_s,
            duration / wall.median_s,
            wall.runs,
            trace.stats.steps,
            trace.stats.rhs_evals
        );
    }
    // An independent reference for both methods: RK4 at 10 µs.
    let mut reference = rk4;
    reference.numerics.max_step_s = REFERENCE_STEP_S;
    let truth = ride_run(
        &reference,
        ModelKind::Twin,
        &ride,
        duration,
        REFERENCE_STEP_S,
    )?;
    let _ = writeln!(
        out,
        "\n## Accuracy of the twin (same ride)\n\nAgainst the same method at a 10× finer step \
         (the requirement: ≤ {MAX_YDD_ERROR:.0e} m/s² at the preset's step) and against RK4 at {REFERENCE_STEP_S:.0e} s.\n\n\
         | method | step | max abs ÿ error | within {MAX_YDD_ERROR:.0e} m/s² | RMS ÿ error | max abs u error | max abs ÿ error vs RK4 at {REFERENCE_STEP_S:.0e} s |\n|---|---|---|---|---|---|---|"
    );
    let mut cases = vec![(*params, h), (*params, 2.0 * h)];
    if params.numerics.integrator != Integrator::Rk4 {
        let r = rk4.numerics.max_step_s;
        cases.extend([(rk4, r), (rk4, 2.0 * r)]);
    }
    for (p, step) in cases {
        if step > p.step_limit_s() {
            continue;
        }
        let run = ride_run(&p, ModelKind::Twin, &ride, duration, step)?;
        let fine = ride_run(&p, ModelKind::Twin, &ride, duration, step / 10.0)?;
        let a = accuracy_of(&run, &fine, step);
        let _ = writeln!(
            out,
            "| {} | {:.1e} s | {:.2e} m/s² | {} | {:.2e} m/s² | {:.2e} m | {:.2e} m/s² |",
            p.numerics.integrator.name(),
            a.step_s,
            a.max_ydd_error,
            if a.max_ydd_error <= MAX_YDD_ERROR {
                "yes"
            } else {
                "no"
            },
            a.rms_ydd_error,
            a.max_u_error,
            max_ydd_difference(&run, &truth)
        );
    }
    let tests = experiments::table1();
    let opt = dwell::DwellOptions::default();
    let (wall, results) = timed(3, 1.0, || {
        dwell::sweep(&tests, |&(f, a)| {
            dwell::simulated_bode(params, ModelKind::Twin, f, a, &opt)
        })
    });
    let failures = results.iter().filter(|r| r.is_err()).count();
    let _ = writeln!(
        out,
        "\n## Table 1 sweep on the twin\n\n69 sine dwells (settle {:.2} s + ≥ {:.1} s of whole \
         periods each), parallel with rayon: **{:.3} s** wall, fastest of {} runs (median {:.3} s; \
         {} failed)",
        opt.settle_s, opt.min_window_s, wall.best_s, wall.runs, wall.median_s, failures
    );
    Ok(out)
}
