//! A simulation's dynamic state apart from its problem: what an FMU's `fmi2GetFMUstate` saves,
//! and what a simulation of the same problem restores to step on bit for bit.

use super::*;

/// What of a [`Simulation`] changes while it steps ([`Simulation::snapshot`]): the model's
/// state, the steps taken, the command history, the controller's signal states, the
/// platform acceleration now and the work counters. The problem (model, drive, platform,
/// step, stepper) is not in it: a simulation built for the same problem takes it with
/// [`Simulation::restore`] and then steps bit for bit as the original.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SimulationState {
    /// The model's state vector (SI, the model's order).
    pub y: Vec<f64>,
    /// Steps taken and the open end-stop contact.
    pub run: RunStateSnapshot,
    /// The commands sent (the delay line).
    pub history: delay::DelayLineState,
    /// The controller's states, in closed loop.
    pub controller: Option<crate::control::ControllerState>,
    /// Platform acceleration at the current time [m/s²].
    pub xdd_now: f64,
    /// Integrator work so far.
    pub stats: StepStats,
}

impl<M: Model<N> + CommandPath, const N: usize> Simulation<M, N> {
    /// Its dynamic state (bounded: its size does not grow with the steps taken).
    pub fn snapshot(&self) -> SimulationState {
        SimulationState {
            y: self.y.to_vec(),
            run: self.run.snapshot(),
            history: self.history.snapshot(),
            controller: self.controller.as_ref().map(Controller::snapshot),
            xdd_now: self.xdd_now,
            stats: self.stats,
        }
    }

    /// Takes the dynamic state of a simulation of the same problem (same model, drive kind,
    /// step and platform; the platform is set before, with [`Self::set_platform`], since it
    /// resets the acceleration now). Refused, leaving `self` unchanged, when a part's size
    /// differs.
    pub fn restore(&mut self, s: &SimulationState) -> Result<(), RestoreError> {
        let y: [f64; N] =
            s.y.as_slice()
                .try_into()
                .map_err(|_| RestoreError::Mismatch {
                    what: "state vector length",
                    expected: N,
                    found: s.y.len(),
                })?;
        let mut history = self.history.clone();
        history.restore(&s.history)?;
        let mut controller = self.controller.clone();
        match (controller.as_mut(), &s.controller) {
            (Some(c), Some(cs)) => c.restore(cs)?,
            (None, None) => {}
            (mine, theirs) => {
                return Err(RestoreError::Mismatch {
                    what: "number of controllers",
                    expected: mine.is_some() as usize,
                    found: theirs.is_some() as usize,
                });
            }
        }
        self.y = y;
        self.run.restore(&s.run);
        self.history = history;
        self.controller = controller;
        self.xdd_now = s.xdd_now;
        self.stats = s.stats;
        Ok(())
    }
}
