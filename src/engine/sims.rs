//! The engine's simulations: the twin, the linear model and the passive seat (and the A/B reference twin) on the same excitation, stepped together.

use super::*;
use crate::control::ControlLaw;
use crate::experiments::LTI_MAX_STEP_S;
use crate::model::linear::LinearModel;
use crate::model::passive::PassiveModel;
use crate::model::twin::Twin;
use crate::params::ControllerParams;
use crate::params::Params;
use crate::simulation::{Drive, Run, SimError, Simulation, step_for_rate};

pub(super) struct Sims {
    pub(super) twin: Simulation<Twin, 10>,
    /// The linear models stepped as `seat-twin simulate` steps them: exactly at up to
    /// [`LTI_MAX_STEP_S`] (new parameters rebuild the exact hold, the state kept), or by RK4
    /// at the twin's step when the delay is shorter than that.
    pub(super) linear: Simulation<LinearModel, 3>,
    pub(super) passive: Simulation<PassiveModel, 2>,
    /// The A/B reference twin and its controller.
    pub(super) reference: Option<(Simulation<Twin, 10>, ControllerParams)>,
    pub(super) every: u64,
    pub(super) duration: f64,
    pub(super) contacts_seen: usize,
}

/// The parameters of the reference twin: the live plant with the reference controller.
fn with_controller(params: &Params, c: ControllerParams) -> Params {
    Params {
        controller: c,
        ..*params
    }
}

impl Sims {
    pub(super) fn new(
        params: &Params,
        excitation: &Excitation,
        reference: Option<ControllerParams>,
    ) -> Result<Self, String> {
        let (platform, drive, duration) = excitation.build(params)?;
        let h = step_for_rate(params.numerics.max_step_s, STREAM_RATE_HZ);
        let h_lti = step_for_rate(LTI_MAX_STEP_S, STREAM_RATE_HZ);
        let every = ((1.0 / STREAM_RATE_HZ) / h).round() as u64;
        let reference = reference.map(|c| {
            let rp = with_controller(params, c);
            let rdrive = match &drive {
                Drive::ClosedLoop(_) => Drive::ClosedLoop(ControlLaw::new(&rp)),
                open => open.clone(),
            };
            (Simulation::twin(&rp, h, rdrive, platform.clone()), c)
        });
        Ok(Self {
            reference,
            twin: Simulation::twin(params, h, drive.clone(), platform.clone()),
            linear: Simulation::exact_or_rk4(
                LinearModel::new(params),
                h_lti,
                h,
                drive.clone(),
                platform.clone(),
            ),
            passive: Simulation::exact_or_rk4(PassiveModel::new(params), h_lti, h, drive, platform),
            every,
            duration,
            contacts_seen: 0,
        })
    }

    pub(super) fn set_params(&mut self, params: &Params) {
        if let Some((sim, c)) = self.reference.as_mut() {
            let rp = with_controller(params, *c);
            sim.set_model(Twin::new(rp));
            sim.update_gains(&rp);
        }
        self.twin.set_model(Twin::new(*params));
        self.twin.update_gains(params);
        self.linear.set_model(LinearModel::new(params));
        self.linear.update_gains(params);
        self.passive.set_model(PassiveModel::new(params));
        self.passive.update_gains(params);
    }

    pub(super) fn time(&self) -> f64 {
        self.twin.time()
    }

    /// Advances all three until `t_end`, appending streamed samples.
    pub(super) fn advance(&mut self, t_end: f64, batch: &mut Batch) -> Result<(), SimError> {
        let every = self.every;
        self.twin.run_until(t_end, every, |s| batch.twin.push(s))?;
        let every_of = |h: f64| ((1.0 / STREAM_RATE_HZ) / h).round() as u64;
        let linear_every = every_of(self.linear.step_size());
        self.linear
            .run_until(t_end, linear_every, |s| batch.linear.push(s))?;
        let passive_every = every_of(self.passive.step_size());
        self.passive
            .run_until(t_end, passive_every, |s| batch.passive.push(s))?;
        if let Some((sim, _)) = self.reference.as_mut() {
            sim.run_until(t_end, every, |s| batch.reference.push(s))?;
        }
        Ok(())
    }
}

trait DriveTarget {
    fn update_gains(&mut self, params: &Params);
}

impl<M, const N: usize> DriveTarget for Simulation<M, N>
where
    M: crate::model::Model<N> + crate::simulation::CommandPath,
{
    fn update_gains(&mut self, params: &Params) {
        if let Drive::ClosedLoop(_) = self.drive() {
            self.set_drive(Drive::ClosedLoop(ControlLaw::new(params)));
        }
    }
}
