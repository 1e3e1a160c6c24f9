//! The tuning run cut into steps ([`TuneRun`]): the baseline, the optimiser one iteration at a
//! time, the robustness checks one candidate at a time, then the held-out rides. The desktop
//! runs it to its end on a thread ([`tune_observed`](super::tune_observed)); the web app steps
//! it inside its frames.

use super::robustness::{claim_failures, spread_corners};
use super::{
    Evaluation, GainSearch, LOG_KEY, MAX_CHECKED_CANDIDATES, Progress, RobustnessRow, SearchStop,
    TuneError, TuneOptions, TuneResult, check_options, pareto_front, robustness_table, spread,
    tau_max_s, to_search, tuned_keys,
};
use crate::analysis::frequency_response::{self as fr, LinearisedModel};
use crate::analysis::stability::{LoopPlant, MarginGrid};
use crate::params::Params;
use crate::scenario::PlatformMotion;
use argmin::core::{CostFunction, IterState, Problem, Solver, State, TerminationStatus};
use argmin::solver::neldermead::NelderMead;
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

/// The gain search's cost function, owned by argmin's problem while the search runs.
struct SearchCost(GainSearch);

impl CostFunction for SearchCost {
    type Param = Vec<f64>;
    type Output = f64;
    fn cost(&self, x: &Self::Param) -> Result<f64, argmin::core::Error> {
        self.0.search_cost(x)
    }
}

/// The Nelder–Mead state between two iterations.
type SearchState = IterState<Vec<f64>, (), (), (), (), f64>;

/// A tuning run cut into steps, so a caller without threads (the web app, inside its frames)
/// can run it a piece at a time: the baseline evaluation, then one optimiser iteration per
/// step (the start simplex is one step: an evaluation per corner), then one robustness check
/// per candidate, then the held-out rides. [`tune_observed`](super::tune_observed) is this
/// stepped to its end, so both give the same result bit for bit.
pub struct TuneRun {
    opts: TuneOptions,
    nominal: Params,
    rides: Vec<PlatformMotion>,
    stage: RunStage,
}

/// Where a [`TuneRun`] is.
enum RunStage {
    /// Set up; the start's evaluation is next.
    Baseline(Box<GainSearch>),
    /// The optimiser between iterations (`state` is `None` before its start simplex).
    Search {
        problem: Box<Problem<SearchCost>>,
        solver: Box<NelderMead<Vec<f64>, f64>>,
        state: Option<Box<SearchState>>,
        baseline: Box<Evaluation>,
    },
    /// The robustness check of the best candidates, one per step.
    Check {
        search: Box<GainSearch>,
        baseline: Box<Evaluation>,
        log: Vec<Evaluation>,
        stop_reason: String,
        candidates: std::vec::IntoIter<Evaluation>,
    },
    /// Ended (its result was returned).
    Done,
}

impl TuneRun {
    /// Checks the options and sets the search up (linearisations, rides); no simulation yet.
    pub fn new(
        params: &Params,
        opts: &TuneOptions,
        cancel: Option<std::sync::Arc<AtomicBool>>,
        progress: Option<Progress>,
    ) -> Result<Self, TuneError> {
        check_options(opts)?;
        let nominal = {
            let mut p = *params;
            p.controller.kind = opts.kind;
            p
        };
        let spread_plants: Vec<(Params, LoopPlant)> = spread(&nominal)
            .into_iter()
            .map(|p| (p, LoopPlant::new(&fr::linearise_twin(&p))))
            .collect();
        let plants = if opts.robust {
            plants_of(spread_corners(&nominal))
        } else {
            plants_of(vec![nominal])
        };
        let rides = motions(opts, &opts.tune_seeds)?;
        let search = GainSearch {
            plants,
            spread: spread_plants,
            rides: rides.clone(),
            duration_s: opts.duration_s,
            objective: opts.objective,
            kind: opts.kind,
            start: nominal.controller,
            scale: Mutex::new(None),
            log: Mutex::new(Vec::new()),
            count: AtomicUsize::new(0),
            cancel,
            progress,
            budget: opts.max_evaluations,
            starting: AtomicBool::new(false),
        };
        Ok(Self {
            opts: opts.clone(),
            nominal,
            rides,
            stage: RunStage::Baseline(Box::new(search)),
        })
    }

    /// Does the next piece of work; the result once the run has ended (then `None` again).
    pub fn step(&mut self) -> Option<Result<TuneResult, TuneError>> {
        let stage = std::mem::replace(&mut self.stage, RunStage::Done);
        match self.advance(stage) {
            Ok(RunStage::Done) => None,
            Ok(next) => {
                self.stage = next;
                None
            }
            Err(Ended(result)) => Some(*result),
        }
    }

    /// The stage after `stage`, or the run's end.
    fn advance(&self, stage: RunStage) -> Result<RunStage, Ended> {
        let opts = &self.opts;
        match stage {
            RunStage::Baseline(search) => {
                let baseline = search.evaluate(self.nominal.controller);
                let scale = if baseline.objective.is_finite() {
                    baseline.objective
                } else {
                    1.0
                };
                if let Ok(mut s) = search.scale.lock() {
                    *s = Some(scale);
                }
                // Start simplex: the preset's gains and one step along each axis: |Kp| ×
                // 0.6, half a search unit towards zero for the others.
                let keys = tuned_keys(opts.kind);
                let x0: Vec<f64> = keys
                    .iter()
                    .map(|(k, s)| to_search(k, *s, self.nominal.controller.get(k).unwrap_or(0.0)))
                    .collect();
                let mut simplex = vec![x0.clone()];
                for (i, (key, _)) in keys.iter().enumerate() {
                    let mut v = x0.clone();
                    if *key == LOG_KEY {
                        v[i] -= 0.5;
                    } else {
                        v[i] += if v[i] > 0.0 { -0.5 } else { 0.5 } * v[i].abs().max(1.0);
                    }
                    simplex.push(v);
                }
                let solver = NelderMead::new(simplex)
                    .with_sd_tolerance(1e-4)
                    .map_err(|e| end(Err(TuneError::Optimiser(e.to_string()))))?;
                Ok(RunStage::Search {
                    problem: Box::new(Problem::new(SearchCost(*search))),
                    solver: Box::new(solver),
                    state: None,
                    baseline: Box::new(baseline),
                })
            }
            RunStage::Search {
                mut problem,
                mut solver,
                state,
                baseline,
            } => {
                // As argmin's `Executor::run` does it: the start simplex (init), then per
                // iteration the termination test, one iteration, the update. Every iteration
                // evaluates at least once, so the evaluation budget bounds the iterations; the
                // budget itself is enforced in `cost`.
                let cancelled =
                    |p: &Problem<SearchCost>| p.problem.as_ref().is_some_and(|c| c.0.cancelled());
                let starting = |p: &Problem<SearchCost>, on: bool| {
                    if let Some(c) = &p.problem {
                        c.0.starting.store(on, Ordering::Relaxed);
                    }
                };
                let next = match state {
                    None => {
                        if cancelled(&problem) {
                            return Err(end(Err(TuneError::Cancelled)));
                        }
                        starting(&problem, true);
                        let started = solver.init(
                            &mut *problem,
                            SearchState::new().max_iters(opts.max_evaluations as u64),
                        );
                        starting(&problem, false);
                        if cancelled(&problem) {
                            return Err(end(Err(TuneError::Cancelled)));
                        }
                        started.map(|(mut s, _)| {
                            s.update();
                            s
                        })
                    }
                    Some(s) => {
                        let s = *s;
                        let s = if s.terminated() {
                            s
                        } else {
                            match Solver::<SearchCost, _>::terminate_internal(&mut *solver, &s) {
                                TerminationStatus::Terminated(reason) => s.terminate_with(reason),
                                TerminationStatus::NotTerminated => s,
                            }
                        };
                        if s.terminated() {
                            let stop_reason = s.get_termination_reason().map_or_else(
                                || "budget of iterations used".to_string(),
                                |t| t.text().to_string(),
                            );
                            return self.search_ended(*problem, *baseline, stop_reason);
                        }
                        solver.next_iter(&mut *problem, s).map(|(mut s, _)| {
                            s.update();
                            s.increment_iter();
                            s
                        })
                    }
                };
                match next {
                    Ok(s) => Ok(RunStage::Search {
                        problem,
                        solver,
                        state: Some(Box::new(s)),
                        baseline,
                    }),
                    Err(e) => match SearchStop::of(&e) {
                        Some(SearchStop::BudgetUsed) => self.search_ended(
                            *problem,
                            *baseline,
                            SearchStop::BudgetUsed.to_string(),
                        ),
                        Some(SearchStop::Cancelled) => Err(end(Err(TuneError::Cancelled))),
                        None => Err(end(Err(TuneError::Optimiser(e.to_string())))),
                    },
                }
            }
            RunStage::Check {
                search,
                baseline,
                log,
                stop_reason,
                mut candidates,
            } => {
                if let Some(cancel) = &search.cancel
                    && cancel.load(Ordering::Relaxed)
                {
                    return Err(end(Err(TuneError::Cancelled)));
                }
                let checked = match candidates.next() {
                    Some(e) => {
                        let table =
                            robustness_table(&self.nominal, e.controller, &self.rides, opts);
                        let top = tau_max_s(&table);
                        if !table.iter().all(|r| r.passes(top)) {
                            return Ok(RunStage::Check {
                                search,
                                baseline,
                                log,
                                stop_reason,
                                candidates,
                            });
                        }
                        (e, table)
                    }
                    None => {
                        let table =
                            robustness_table(&self.nominal, baseline.controller, &self.rides, opts);
                        ((*baseline).clone(), table)
                    }
                };
                Err(end(self.finish(
                    *search,
                    *baseline,
                    log,
                    stop_reason,
                    checked,
                )))
            }
            RunStage::Done => Ok(RunStage::Done),
        }
    }

    /// The optimiser has stopped: the candidates for the robustness check.
    fn search_ended(
        &self,
        mut problem: Problem<SearchCost>,
        baseline: Evaluation,
        stop_reason: String,
    ) -> Result<RunStage, Ended> {
        let Some(SearchCost(search)) = problem.take_problem() else {
            return Err(end(Err(TuneError::Optimiser(
                "the optimiser lost its cost function".into(),
            ))));
        };
        let log = search.log.lock().map(|l| l.clone()).unwrap_or_default();
        // The best feasible evaluation that passes the robustness check at every point of
        // the spread (eigenvalues, settle at rest); the start if none beats it.
        let mut candidates: Vec<Evaluation> = log
            .iter()
            .filter(|e| e.feasible)
            .filter(|e| !baseline.feasible || e.objective < baseline.objective)
            .cloned()
            .collect();
        candidates.sort_by(|a, b| a.objective.total_cmp(&b.objective));
        candidates.dedup_by(|a, b| a.gains == b.gains);
        candidates.truncate(MAX_CHECKED_CANDIDATES);
        Ok(RunStage::Check {
            search: Box::new(search),
            baseline: Box::new(baseline),
            log,
            stop_reason,
            candidates: candidates.into_iter(),
        })
    }

    /// The held-out rides of the start and the tuned gains, and the result.
    fn finish(
        &self,
        search: GainSearch,
        baseline: Evaluation,
        log: Vec<Evaluation>,
        stop_reason: String,
        (tuned, robustness): (Evaluation, Vec<RobustnessRow>),
    ) -> Result<TuneResult, TuneError> {
        let opts = &self.opts;
        let failures = claim_failures(&tuned, &robustness);
        let heldout = motions(opts, &opts.heldout_seeds)?;
        let heldout_search = GainSearch {
            plants: plants_of(vec![self.nominal]),
            rides: heldout,
            progress: None,
            ..search
        };
        let baseline_heldout = heldout_search.evaluate(self.nominal.controller);
        let tuned_heldout = heldout_search.evaluate(tuned.controller);
        Ok(TuneResult {
            kind: opts.kind,
            objective: opts.objective,
            input: opts.input.describe(),
            pareto: pareto_front(&log),
            evaluations: heldout_search.count.load(Ordering::Relaxed),
            baseline,
            tuned,
            baseline_heldout,
            tuned_heldout,
            robustness,
            tune_seeds: opts.tune_seeds.clone(),
            heldout_seeds: opts.heldout_seeds.clone(),
            duration_s: opts.duration_s,
            robust: opts.robust,
            stop_reason,
            failures,
        })
    }
}

impl TuneRun {
    /// The run to its end with argmin's own `Executor` driving the optimiser in one call
    /// (what [`tune_observed`](super::tune_observed) did before it was cut into steps): the
    /// reference the stepped search ([`Self::step`]) is tested against, evaluation for
    /// evaluation.
    pub fn finish_with_executor(mut self) -> Result<TuneResult, TuneError> {
        use argmin::core::Executor;
        while matches!(self.stage, RunStage::Baseline(_)) {
            if let Some(r) = self.step() {
                return r;
            }
        }
        let RunStage::Search {
            mut problem,
            solver,
            state: None,
            baseline,
        } = std::mem::replace(&mut self.stage, RunStage::Done)
        else {
            unreachable!("the baseline step leads to the search's start");
        };
        /// The search borrowed, as the one-call run had it.
        struct Borrowed<'a>(&'a GainSearch);
        impl CostFunction for Borrowed<'_> {
            type Param = Vec<f64>;
            type Output = f64;
            fn cost(&self, x: &Self::Param) -> Result<f64, argmin::core::Error> {
                self.0.search_cost(x)
            }
        }
        let cost = problem.take_problem().expect("the cost function");
        let max_iters = self.opts.max_evaluations as u64;
        let res = Executor::new(Borrowed(&cost.0), *solver)
            .configure(|state| state.max_iters(max_iters))
            .run();
        let stop_reason = match res {
            Ok(r) => r.state().get_termination_reason().map_or_else(
                || "budget of iterations used".to_string(),
                |t| t.text().to_string(),
            ),
            Err(e) => match SearchStop::of(&e) {
                Some(SearchStop::BudgetUsed) => SearchStop::BudgetUsed.to_string(),
                Some(SearchStop::Cancelled) => return Err(TuneError::Cancelled),
                None => return Err(TuneError::Optimiser(e.to_string())),
            },
        };
        self.stage = self
            .search_ended(Problem::new(cost), *baseline, stop_reason)
            .unwrap_or(RunStage::Done);
        loop {
            if let Some(r) = self.step() {
                return r;
            }
        }
    }
}

/// A [`TuneRun`]'s end, carried out of a step.
struct Ended(Box<Result<TuneResult, TuneError>>);

/// The run's end with `result`.
fn end(result: Result<TuneResult, TuneError>) -> Ended {
    Ended(Box::new(result))
}

/// The plants with their linearisation and margin grid.
fn plants_of(ps: Vec<Params>) -> Vec<(Params, LinearisedModel, MarginGrid)> {
    ps.into_iter()
        .map(|p| {
            let lin = fr::linearise_twin(&p);
            let grid = MarginGrid::new(&lin);
            (p, lin, grid)
        })
        .collect()
}

/// The platform motions of `seeds`.
fn motions(opts: &TuneOptions, seeds: &[u64]) -> Result<Vec<PlatformMotion>, TuneError> {
    seeds
        .iter()
        .map(|&s| opts.input.motion(s, opts.duration_s))
        .collect()
}
