//! The co-simulation slave behind the FMI 2.0 functions, in safe Rust: the twin's
//! [`Simulation`] with the FMU's inputs, parameters and the FMI state machine.
//!
//! # Inputs between communication points
//! At `fmi2DoStep(t, H)` the slave steps the twin `H/h` times at its own step `h` (the
//! preset's `numerics.max_step_s`; `H` must be a whole multiple of it). The platform
//! acceleration over the step is the value set at `t` extended by its derivatives of order
//! 1–3 when the importer gave them (`fmi2SetRealInputDerivatives`, `canInterpolateInputs`),
//! else held. The twin reads it at its grid and mid-step times exactly as `simulate` reads a
//! record: a record linear between communication points, sent with its forward slope, gives
//! the same run to round-off. The external command `v_in_ext` is held from its
//! communication point to the next (a digital controller's output), then saturated and
//! delayed by τ like the internal controller's. Nothing adds a delay: the outputs after a
//! step are the twin's state at its end.
//!
//! # State
//! `fmi2GetFMUstate` copies the slave. The serialised form is its state as it is now, not
//! its history: the FMI phase, the start time, the tunable parameters as set, the inputs and
//! their derivatives, the held external commands of the last `2·MAX_DELAY_S`, and the twin's
//! dynamic state ([`SimulationState`]: the ten states, the steps taken, the delay line of
//! the commands sent, the controller's integrator, filters and Smith model, the platform's
//! input segment and acceleration now, the work counters). What the parameters determine
//! (the model, the exponential integrator's coefficients, the controller's discretisation,
//! the delay taps) is rebuilt from them on deserialising, which then steps bit for bit as
//! the original. The size does not grow with the run: 6.3 kB for the paper preset at its
//! 0.5 ms step with the internal controller (the delay line is 256 values), 12 kB with the
//! external one at 1 ms communication steps (its 0.2 s of held commands), the same after
//! 1000 and 10 000 steps (`serialised_size_is_bounded`). Nothing is kept between
//! serialisations; restoring costs one build of the twin (its exponential integrator's
//! coefficients), whatever the run's length.
//!
//! The bytes are `SEATFMU2`, a format version (u32, little-endian), the FMU's GUID (u16
//! length and its bytes), the state as JSON (f64 written shortest and parsed exactly, so
//! they round-trip bit for bit) and an FNV-1a 64 checksum of everything before it. A state
//! of another format, of another FMU (GUID) or with damaged bytes is refused with the
//! reason, never a panic.

use super::super::fmu::{
    ControllerPlacement, OUTPUTS, V_IN_EXT_RANGE, VR_OUTPUTS, VR_PARAMS, VR_V_IN_EXT, VR_X, VR_XDD,
    X_RANGE, XDD_RANGE, exposes,
};
use crate::format::general as fmt_value;
use crate::model::twin::Twin;
use crate::params::{MAX_DELAY_S, PARAMS, Params};
use crate::scenario::{CommandSignal, CommandStream, InputSegment, PlatformMotion};
use crate::simulation::{Drive, Run, Simulation, SimulationState};
use serde::{Deserialize, Serialize};

mod state;
pub use state::STATE_FORMAT_VERSION;

/// The FMI 2.0 states of a co-simulation slave.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Phase {
    /// After `fmi2Instantiate` (and `fmi2Reset`).
    Instantiated,
    /// Between `fmi2EnterInitializationMode` and `fmi2ExitInitializationMode`.
    Initialization,
    /// Stepping.
    Step,
    /// After `fmi2Terminate`.
    Terminated,
    /// After an error: only reading, `fmi2Reset` and freeing are allowed.
    Error,
}

/// The slave's state (everything `fmi2GetFMUstate` copies).
#[derive(Debug, Clone)]
pub struct Slave {
    placement: ControllerPlacement,
    /// The preset's parameters (what `fmi2Reset` returns to).
    preset: Params,
    /// The parameters as set.
    params: Params,
    phase: Phase,
    start_time: f64,
    /// `ẍ` and its derivatives of order 1–3 at the current communication point.
    xdd: [f64; 4],
    x: f64,
    v_in_ext: f64,
    command: CommandStream,
    sim: Option<Simulation<Twin, 10>>,
    /// The platform input the twin steps with now (set at each communication point).
    segment: InputSegment,
    /// The FMU's GUID (or, outside an FMU, a hash of the preset and placement): a serialised
    /// state names it, and only a slave of the same one takes it.
    guid: String,
}

/// An error with the message the FMU logs.
pub type SlaveResult<T> = Result<T, String>;

impl Slave {
    /// A slave for the preset's parameters with the controller `placement`.
    pub fn new(preset: Params, placement: ControllerPlacement) -> Self {
        Self {
            placement,
            preset,
            params: preset,
            phase: Phase::Instantiated,
            start_time: 0.0,
            xdd: [0.0; 4],
            x: 0.0,
            v_in_ext: 0.0,
            command: CommandStream::default(),
            sim: None,
            segment: InputSegment::default(),
            guid: super::super::fmu::guid(
                &serde_json::to_string(&preset).unwrap_or_default(),
                placement,
            ),
        }
    }

    /// The slave with the FMU's GUID (what a serialised state is checked against).
    pub fn with_guid(mut self, guid: &str) -> Self {
        self.guid = guid.to_string();
        self
    }

    /// The FMI state.
    pub fn phase(&self) -> Phase {
        self.phase
    }

    /// Marks the slave as failed (after an error in a call).
    pub fn fail(&mut self) {
        self.phase = Phase::Error;
    }

    fn require(&self, allowed: &[Phase], call: &str) -> SlaveResult<()> {
        if allowed.contains(&self.phase) {
            Ok(())
        } else {
            Err(format!(
                "{call} is not allowed in the state {:?} (allowed in: {:?})",
                self.phase, allowed
            ))
        }
    }

    /// `fmi2SetupExperiment`.
    pub fn setup(&mut self, start_time: f64) -> SlaveResult<()> {
        self.require(&[Phase::Instantiated], "fmi2SetupExperiment")?;
        if !start_time.is_finite() {
            return Err(format!("startTime {start_time} is not a finite number"));
        }
        self.start_time = start_time;
        Ok(())
    }

    /// `fmi2EnterInitializationMode`.
    pub fn enter_initialization(&mut self) -> SlaveResult<()> {
        self.require(&[Phase::Instantiated], "fmi2EnterInitializationMode")?;
        self.phase = Phase::Initialization;
        Ok(())
    }

    /// `fmi2ExitInitializationMode`: checks the parameters together and builds the twin.
    pub fn exit_initialization(&mut self) -> SlaveResult<()> {
        self.require(&[Phase::Initialization], "fmi2ExitInitializationMode")?;
        self.sim = Some(self.build()?);
        self.phase = Phase::Step;
        Ok(())
    }

    /// The twin at rest for the parameters and inputs as set, at t = 0.
    fn build(&mut self) -> SlaveResult<Simulation<Twin, 10>> {
        self.params
            .validate()
            .map_err(|e| format!("the parameters as set are not valid together: {e}"))?;
        let h = self.params.numerics.max_step_s;
        let drive = match self.placement {
            ControllerPlacement::Internal => Drive::closed_loop(&self.params),
            ControllerPlacement::External => {
                self.command = CommandStream::default();
                self.command.push(0.0, self.v_in_ext, self.keep_s());
                Drive::OpenLoop(CommandSignal::Streamed(self.command.clone()))
            }
        };
        self.segment = InputSegment {
            t0: 0.0,
            x: self.x,
            xdd: [self.xdd[0], 0.0, 0.0, 0.0],
        };
        let platform = PlatformMotion::Extrapolated(self.segment);
        Ok(Simulation::twin(&self.params, h, drive, platform))
    }

    /// How long the held command's history must reach back [s].
    fn keep_s(&self) -> f64 {
        2.0 * MAX_DELAY_S
    }

    /// `fmi2Terminate`.
    pub fn terminate(&mut self) -> SlaveResult<()> {
        self.require(&[Phase::Step], "fmi2Terminate")?;
        self.phase = Phase::Terminated;
        Ok(())
    }

    /// `fmi2Reset`: back to the state after instantiation.
    pub fn reset(&mut self) {
        let guid = std::mem::take(&mut self.guid);
        *self = Slave::new(self.preset, self.placement).with_guid(&guid);
    }

    /// The table index of a parameter's value reference, if the FMU has it.
    fn param_index(&self, vr: u32) -> Option<usize> {
        let i = vr.checked_sub(VR_PARAMS)? as usize;
        let spec = PARAMS.get(i)?;
        exposes(spec, &self.preset, self.placement).then_some(i)
    }

    /// `fmi2GetReal` of one variable.
    pub fn get(&self, vr: u32) -> SlaveResult<f64> {
        if let Some(i) = self.param_index(vr) {
            return Ok(PARAMS[i].get(&self.params));
        }
        match vr {
            VR_XDD => return Ok(self.xdd[0]),
            VR_X => return Ok(self.x),
            VR_V_IN_EXT if self.placement == ControllerPlacement::External => {
                return Ok(self.v_in_ext);
            }
            _ => {}
        }
        let k = vr.wrapping_sub(VR_OUTPUTS) as usize;
        if k >= OUTPUTS.len() {
            return Err(format!("no variable has the value reference {vr}"));
        }
        let sample = match (&self.sim, self.phase) {
            (Some(sim), _) => sim.sample(),
            (None, Phase::Initialization) => {
                let mut probe = self.clone();
                probe.build()?.sample()
            }
            _ => {
                return Err(format!(
                    "the output {} is computed from fmi2EnterInitializationMode on",
                    OUTPUTS[k].0
                ));
            }
        };
        let v_max = self.params.plant.valve.v_max_v;
        Ok(match OUTPUTS[k].0 {
            "u" => sample.u,
            "ydd" => sample.ydd,
            "p1" => sample.p1,
            "p2" => sample.p2,
            "q1" => sample.q1,
            "q2" => sample.q2,
            "xv" => sample.xv,
            _ => match self.placement {
                ControllerPlacement::Internal => sample.v_in,
                ControllerPlacement::External => self.v_in_ext.clamp(-v_max, v_max),
            },
        })
    }

    /// `fmi2SetReal` of one variable.
    pub fn set(&mut self, vr: u32, value: f64) -> SlaveResult<()> {
        self.require(
            &[Phase::Instantiated, Phase::Initialization, Phase::Step],
            "fmi2SetReal",
        )?;
        let check = |name: &str, (lo, hi): (f64, f64), unit: &str| {
            if value.is_finite() && value >= lo && value <= hi {
                Ok(())
            } else {
                Err(format!(
                    "{name} = {} is outside the allowed range [{}, {}] {unit}",
                    fmt_value(value),
                    fmt_value(lo),
                    fmt_value(hi)
                ))
            }
        };
        if let Some(i) = self.param_index(vr) {
            let spec = &PARAMS[i];
            let tunable = spec.controller_key().is_some();
            if self.phase == Phase::Step && !tunable {
                return Err(format!(
                    "{} is a fixed parameter: set it before fmi2ExitInitializationMode",
                    spec.key
                ));
            }
            spec.check(value).map_err(|e| e.to_string())?;
            let mut next = self.params;
            spec.set_unchecked(&mut next, value);
            if let Some(sim) = self.sim.as_mut() {
                next.validate()
                    .map_err(|e| format!("{} = {}: {e}", spec.key, fmt_value(value)))?;
                sim.set_drive(Drive::closed_loop(&next));
            }
            self.params = next;
        } else {
            match vr {
                VR_XDD => {
                    check("xdd", XDD_RANGE, "m/s^2")?;
                    self.xdd[0] = value;
                }
                VR_X => {
                    check("x", X_RANGE, "m")?;
                    self.x = value;
                }
                VR_V_IN_EXT if self.placement == ControllerPlacement::External => {
                    check("v_in_ext", V_IN_EXT_RANGE, "V")?;
                    self.v_in_ext = value;
                }
                vr if (vr.wrapping_sub(VR_OUTPUTS) as usize) < OUTPUTS.len() => {
                    return Err(format!(
                        "{} is an output: it cannot be set",
                        OUTPUTS[(vr - VR_OUTPUTS) as usize].0
                    ));
                }
                _ => return Err(format!("no variable has the value reference {vr}")),
            }
        }
        Ok(())
    }

    /// `fmi2SetRealInputDerivatives` of one input: the derivative of order `order` (1–3).
    pub fn set_derivative(&mut self, vr: u32, order: i32, value: f64) -> SlaveResult<()> {
        self.require(
            &[Phase::Instantiated, Phase::Initialization, Phase::Step],
            "fmi2SetRealInputDerivatives",
        )?;
        if !(1..=3).contains(&order) {
            return Err(format!(
                "derivative order {order} is not supported (1 to 3 are)"
            ));
        }
        if !value.is_finite() {
            return Err(format!("the derivative {value} is not a finite number"));
        }
        match vr {
            VR_XDD => self.xdd[order as usize] = value,
            // x enters no equation; its derivatives are accepted and not used.
            VR_X => {}
            _ => {
                return Err(format!(
                    "value reference {vr} is not a continuous input (xdd, x): no derivatives"
                ));
            }
        }
        Ok(())
    }

    /// Current time \[s\].
    pub fn time(&self) -> f64 {
        self.start_time + self.sim.as_ref().map_or(0.0, |s| s.time())
    }

    /// `fmi2DoStep(t, H)`.
    pub fn do_step(&mut self, t: f64, step: f64) -> SlaveResult<()> {
        self.require(&[Phase::Step], "fmi2DoStep")?;
        let keep = self.keep_s();
        let Some(sim) = self.sim.as_mut() else {
            return Err("the slave has no model (internal error)".into());
        };
        let h = sim.step_size();
        let now = self.start_time + sim.time();
        if !t.is_finite() || (t - now).abs() > 1e-6 * h {
            return Err(format!(
                "currentCommunicationPoint {t} s is not the FMU's time {now} s"
            ));
        }
        let n = (step / h).round();
        if !step.is_finite() || n < 1.0 || (step - n * h).abs() > 1e-6 * h || n > 1e9 {
            return Err(format!(
                "communicationStepSize {step} s is not a whole multiple of the internal \
                 step {} s",
                fmt_value(h)
            ));
        }
        let t_sim = sim.time();
        self.segment = InputSegment {
            t0: t_sim,
            x: self.x,
            xdd: self.xdd,
        };
        sim.set_platform(PlatformMotion::Extrapolated(self.segment));
        if self.placement == ControllerPlacement::External {
            self.command.push(t_sim, self.v_in_ext, keep);
            sim.set_drive(Drive::OpenLoop(CommandSignal::Streamed(
                self.command.clone(),
            )));
        }
        for _ in 0..n as u64 {
            if let Err(e) = sim.step() {
                self.phase = Phase::Error;
                return Err(e.to_string());
            }
        }
        // Derivatives hold for one communication step.
        self.xdd[1..].fill(0.0);
        Ok(())
    }
}

#[cfg(test)]
mod tests;
