//! `seat-twin bench`: real-time factors and accuracy on this machine.

use super::{Outcome, Run, load_params};
use super::{announce, estimate_wall_s};
use crate::format::general;
use crate::model::ModelKind;
use crate::params::{Integrator, Params};
use anyhow::{Context, Result};

/// Twin seconds the bench simulates one after the other, in units of its 10 s ride at the
/// step being timed: ≥ 5 timed runs, then the accuracy runs at that step (1), 10× finer (10),
/// twice the step (0.5) and 5× finer (5).
const SEQUENTIAL_RIDES: f64 = 21.5;
/// Twin seconds of the Table 1 sweeps (69 dwells, timed ≥ 3 times), run in parallel.
const TABLE1_SWEEP_S: f64 = 3.0 * 69.0 * 1.0;

/// What the bench computes, for the up-front note.
fn cost(params: &Params) -> String {
    format!(
        "about {} s of the twin simulated at a {} s step and its finer references",
        general(10.0 * SEQUENTIAL_RIDES + TABLE1_SWEEP_S),
        general(params.numerics.max_step_s)
    )
}

/// Estimated wall time of [`crate::bench::run_bench`] [s]: the sequential rides on one core,
/// the sweeps on all, at the preset's step (and RK4's, when the preset's method is another).
fn wall_estimate_s(params: &Params) -> f64 {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get()) as f64;
    let sequential =
        |step: f64| estimate_wall_s(ModelKind::Twin, 10.0 * SEQUENTIAL_RIDES, step) * cores;
    let h = params.numerics.max_step_s;
    let mut wall = sequential(h) + estimate_wall_s(ModelKind::Twin, TABLE1_SWEEP_S, h);
    if params.numerics.integrator != Integrator::Rk4 {
        wall += sequential(crate::bench::RK4_STEP_S.min(params.rk4_step_limit_s()));
    }
    wall
}

/// Options of `seat-twin bench`.
#[derive(Debug, clap::Args)]
pub struct BenchArgs {
    /// Preset file or shipped preset name.
    #[arg(long, default_value = "paper", value_parser = super::preset_parser())]
    pub preset: String,
}

impl Run for BenchArgs {
    fn run(&self) -> Result<Outcome> {
        let preset = &self.preset;
        let params = load_params(preset)?;
        let heartbeat = announce("bench", &cost(&params), wall_estimate_s(&params));
        let text = crate::bench::run_bench(&params)
            .with_context(|| format!("the bench's 10 s closed-loop ride on preset {preset}"))?;
        drop(heartbeat);
        println!("{text}");
        Ok(Outcome::Done)
    }
}
