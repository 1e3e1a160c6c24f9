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

const MAGIC: &[u8; 8] = b"SEATFMU2";
/// Version of the serialised form.
pub const STATE_FORMAT_VERSION: u32 = 2;

/// The serialised slave (see the module docs).
#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct SavedSlave {
    phase: Phase,
    start_time: f64,
    /// The values of the FMU's parameters, in table order.
    params: Vec<f64>,
    xdd: [f64; 4],
    x: f64,
    v_in_ext: f64,
    command: CommandStream,
    segment: InputSegment,
    sim: Option<SimulationState>,
}

/// FNV-1a 64 of `bytes`.
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01B3)
    })
}

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

    /// Current time [s].
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

    /// The serialised state (see the module docs; its size does not grow with the run).
    pub fn serialize(&self) -> Vec<u8> {
        let saved = SavedSlave {
            phase: self.phase,
            start_time: self.start_time,
            params: PARAMS.iter().map(|p| p.get(&self.params)).collect(),
            xdd: self.xdd,
            x: self.x,
            v_in_ext: self.v_in_ext,
            command: self.command.clone(),
            segment: self.segment,
            sim: self.sim.as_ref().map(Simulation::snapshot),
        };
        let mut out = MAGIC.to_vec();
        out.extend_from_slice(&STATE_FORMAT_VERSION.to_le_bytes());
        let guid = &self.guid.as_bytes()[..self.guid.len().min(u16::MAX as usize)];
        out.extend_from_slice(&(guid.len() as u16).to_le_bytes());
        out.extend_from_slice(guid);
        // Plain numbers, strings and structs: writing JSON cannot fail.
        out.extend(serde_json::to_vec(&saved).unwrap_or_default());
        let sum = fnv1a(&out);
        out.extend_from_slice(&sum.to_le_bytes());
        out
    }

    /// The slave a serialised state describes, for this slave's FMU (its preset, placement
    /// and GUID); `self` is not changed.
    pub fn deserialize(&self, bytes: &[u8]) -> SlaveResult<Self> {
        let damaged = |why: String| format!("the serialised FMU state is damaged: {why}");
        if bytes.len() < MAGIC.len() || &bytes[..MAGIC.len()] != MAGIC {
            return Err("the bytes are not a serialised state of a seat-twin FMU".into());
        }
        let rest = &bytes[MAGIC.len()..];
        let version = rest
            .get(..4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .ok_or_else(|| damaged("it ends in its header".into()))?;
        if version != STATE_FORMAT_VERSION {
            return Err(format!(
                "the serialised state has format version {version}; this FMU reads version \
                 {STATE_FORMAT_VERSION}"
            ));
        }
        let n = rest
            .get(4..6)
            .map(|b| u16::from_le_bytes([b[0], b[1]]) as usize)
            .ok_or_else(|| damaged("it ends in its header".into()))?;
        let guid = rest
            .get(6..6 + n)
            .ok_or_else(|| damaged("it ends in its GUID".into()))?;
        if guid != self.guid.as_bytes() {
            return Err(format!(
                "the serialised state is of another FMU (GUID {}); this FMU's is {}",
                String::from_utf8_lossy(guid),
                self.guid
            ));
        }
        let body_end = bytes
            .len()
            .checked_sub(8)
            .filter(|&e| e >= MAGIC.len() + 6 + n)
            .ok_or_else(|| damaged("it has no checksum".into()))?;
        let mut sum = [0; 8];
        sum.copy_from_slice(&bytes[body_end..]);
        if u64::from_le_bytes(sum) != fnv1a(&bytes[..body_end]) {
            return Err(damaged("its checksum does not match".into()));
        }
        let saved: SavedSlave = serde_json::from_slice(&bytes[MAGIC.len() + 6 + n..body_end])
            .map_err(|e| damaged(e.to_string()))?;
        self.restore(saved)
            .map_err(|e| format!("the serialised state does not fit this FMU: {e}"))
    }

    /// A fresh slave of this FMU with the state `saved`.
    fn restore(&self, saved: SavedSlave) -> SlaveResult<Self> {
        let mut s = Slave::new(self.preset, self.placement).with_guid(&self.guid);
        if saved.params.len() != PARAMS.len() {
            return Err(format!(
                "{} parameter values, this FMU has {}",
                saved.params.len(),
                PARAMS.len()
            ));
        }
        for (i, (spec, &v)) in PARAMS.iter().zip(&saved.params).enumerate() {
            if self.param_index(VR_PARAMS + i as u32).is_some() {
                spec.check(v).map_err(|e| e.to_string())?;
                spec.set_unchecked(&mut s.params, v);
            } else if v.to_bits() != spec.get(&self.preset).to_bits() {
                return Err(format!("{} is not a variable of this FMU", spec.key));
            }
        }
        s.phase = saved.phase;
        s.start_time = saved.start_time;
        s.xdd = saved.xdd;
        s.x = saved.x;
        s.v_in_ext = saved.v_in_ext;
        s.command = saved.command;
        s.segment = saved.segment;
        match (saved.sim, saved.phase) {
            (Some(state), _) => {
                s.params
                    .validate()
                    .map_err(|e| format!("the parameters are not valid together: {e}"))?;
                let drive = match s.placement {
                    ControllerPlacement::Internal => Drive::closed_loop(&s.params),
                    ControllerPlacement::External => {
                        Drive::OpenLoop(CommandSignal::Streamed(s.command.clone()))
                    }
                };
                let h = s.params.numerics.max_step_s;
                let platform = PlatformMotion::Extrapolated(s.segment);
                let mut sim = Simulation::twin(&s.params, h, drive, platform);
                sim.restore(&state).map_err(|e| e.to_string())?;
                s.sim = Some(sim);
            }
            (None, Phase::Step | Phase::Terminated) => {
                return Err(format!(
                    "the phase {:?} needs the model's state",
                    saved.phase
                ));
            }
            (None, _) => {}
        }
        Ok(s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn stepping() -> Slave {
        let mut s = Slave::new(Params::paper(), ControllerPlacement::Internal);
        s.setup(0.0).unwrap();
        s.enter_initialization().unwrap();
        s.exit_initialization().unwrap();
        s
    }

    #[test]
    fn wrong_calls_are_refused_with_a_reason() {
        let mut s = Slave::new(Params::paper(), ControllerPlacement::Internal);
        assert!(s.do_step(0.0, 1e-3).unwrap_err().contains("not allowed"));
        assert!(s.set(9999, 1.0).unwrap_err().contains("9999"));
        assert!(s.set(VR_XDD, f64::NAN).unwrap_err().contains("range"));
        let kp = VR_PARAMS
            + PARAMS
                .iter()
                .position(|p| p.key == "controller.kp_v_per_m")
                .unwrap() as u32;
        assert!(
            s.set(kp, 1e9)
                .unwrap_err()
                .contains("controller.kp_v_per_m")
        );
        let mut s = stepping();
        let mass = VR_PARAMS + PARAMS.iter().position(|p| p.key == "body.mass_kg").unwrap() as u32;
        assert!(s.set(mass, 12.0).unwrap_err().contains("fixed"));
        assert!(s.do_step(0.0, 0.7e-3).unwrap_err().contains("multiple"));
        assert!(s.do_step(0.5, 1e-3).unwrap_err().contains("time"));
        assert!(s.set(VR_OUTPUTS, 1.0).unwrap_err().contains("output"));
        // A gain of a kind the preset does not have is no variable of the FMU.
        let lead = VR_PARAMS
            + PARAMS
                .iter()
                .position(|p| p.key == "controller.lead_s")
                .unwrap() as u32;
        assert!(s.get(lead).is_err());
    }

    #[test]
    fn input_segment_and_command_stream_read_as_documented() {
        let seg = InputSegment {
            t0: 1.0,
            x: 0.0,
            xdd: [2.0, 3.0, 4.0, 6.0],
        };
        // 2 + 3·d + 4·d²/2 + 6·d³/6 at d = 0.5.
        assert_eq!(seg.xdd_at(1.5), 2.0 + 1.5 + 0.5 + 0.125);
        let mut c = CommandStream::default();
        c.push(0.0, 1.0, 0.1);
        c.push(0.01, 3.0, 0.1);
        assert_eq!(c.at(-1e-9), 0.0);
        assert_eq!(c.at(0.005), 2.0);
        assert_eq!(c.at(0.02), 3.0);
        // Samples older than the window go, except the newest of them.
        c.push(0.5, 5.0, 0.1);
        assert_eq!(c.at(0.45), 3.0 + 0.44 / 0.49 * 2.0);
        assert_eq!(c.at(0.005), 0.0);
    }

    #[test]
    fn external_command_is_saturated_and_reaches_the_valve_tau_later() {
        let p = Params::paper();
        let mut s = Slave::new(p, ControllerPlacement::External);
        s.setup(0.0).unwrap();
        s.enter_initialization().unwrap();
        s.exit_initialization().unwrap();
        s.set(VR_V_IN_EXT, 25.0).unwrap();
        assert_eq!(s.get(VR_OUTPUTS + 7).unwrap(), p.plant.valve.v_max_v);
        // The spool does not move before τ = 17.5 ms, and does after.
        let xv = VR_OUTPUTS + 6;
        for k in 0..35 {
            s.do_step(k as f64 * 5e-4, 5e-4).unwrap();
        }
        assert_eq!(s.get(xv).unwrap(), 0.0);
        for k in 35..40 {
            s.do_step(k as f64 * 5e-4, 5e-4).unwrap();
        }
        assert!(s.get(xv).unwrap() > 0.0);
    }

    fn vr_of(key: &str) -> u32 {
        VR_PARAMS + PARAMS.iter().position(|p| p.key == key).unwrap() as u32
    }

    /// One communication step of 1 ms at `k` with a sine input and its slope (and a held
    /// external command for that placement).
    fn drive(s: &mut Slave, k: u64) {
        let t = k as f64 * 1e-3;
        s.set(VR_XDD, 0.8 * (7.0 * t).sin()).unwrap();
        s.set_derivative(VR_XDD, 1, 5.6 * (7.0 * t).cos()).unwrap();
        if s.placement == ControllerPlacement::External {
            s.set(VR_V_IN_EXT, 2.0 * (3.0 * t).sin()).unwrap();
        }
        s.do_step(t, 1e-3).unwrap();
    }

    fn outputs(s: &Slave) -> Vec<u64> {
        (0..OUTPUTS.len() as u32)
            .map(|vr| s.get(VR_OUTPUTS + vr).unwrap().to_bits())
            .collect()
    }

    /// The regression test of the log-based state: a slave restored from bytes serialised
    /// mid-run (after a gain change and with an input derivative set) steps bit for bit as
    /// the original, for every controller kind and the external placement.
    #[test]
    fn restored_slave_steps_bit_for_bit_as_the_original() {
        use crate::params::ControllerKind;
        let kinds = [
            ControllerKind::Paper,
            ControllerKind::Predictive,
            ControllerKind::Skyhook,
            ControllerKind::Smith,
        ];
        let cases = kinds
            .iter()
            .map(|&k| (k, ControllerPlacement::Internal))
            .chain([(ControllerKind::Paper, ControllerPlacement::External)]);
        for (kind, placement) in cases {
            let mut p = Params::paper();
            p.controller.kind = kind;
            let mut s = Slave::new(p, placement);
            s.setup(0.0).unwrap();
            s.enter_initialization().unwrap();
            s.exit_initialization().unwrap();
            for k in 0..300 {
                drive(&mut s, k);
            }
            if placement == ControllerPlacement::Internal {
                s.set(vr_of("controller.kp_v_per_m"), -8.0).unwrap();
            }
            s.set(VR_XDD, 0.3).unwrap();
            s.set_derivative(VR_XDD, 1, 40.0).unwrap();
            s.set_derivative(VR_XDD, 2, -900.0).unwrap();
            let bytes = s.serialize();
            let mut r = Slave::new(p, placement).deserialize(&bytes).unwrap();
            assert_eq!(r.serialize(), bytes, "{kind:?} {placement:?}");
            let (t, u_before) = (s.time(), s.get(VR_OUTPUTS).unwrap());
            s.do_step(0.3, 1e-3).unwrap();
            r.do_step(0.3, 1e-3).unwrap();
            assert_eq!(
                outputs(&s),
                outputs(&r),
                "{kind:?} {placement:?} first step"
            );
            for k in 301..800 {
                drive(&mut s, k);
                drive(&mut r, k);
                assert_eq!(outputs(&s), outputs(&r), "{kind:?} {placement:?} step {k}");
            }
            assert_eq!(r.time(), s.time());
            // The run went on (the comparison is not of a slave at rest).
            assert!(s.time() > t && s.get(VR_OUTPUTS).unwrap() != u_before);
        }
    }

    /// The serialised size does not grow with the run (the old log grew by 43 bytes a step).
    #[test]
    fn serialised_size_is_bounded() {
        for placement in [ControllerPlacement::Internal, ControllerPlacement::External] {
            let mut s = Slave::new(Params::paper(), placement);
            s.setup(0.0).unwrap();
            s.enter_initialization().unwrap();
            s.exit_initialization().unwrap();
            let mut sizes = Vec::new();
            for k in 0..10_000 {
                drive(&mut s, k);
                if k == 9 || k == 999 || k == 9_999 {
                    sizes.push(s.serialize().len());
                }
            }
            // Room for the digits of the numbers to differ; the command window fills in 0.2 s.
            let (lo, hi) = (sizes[1].min(sizes[2]), sizes[1].max(sizes[2]));
            assert!(hi - lo < 300, "{placement:?}: {sizes:?}");
            assert!(sizes[0] < 10_000 && hi < 20_000, "{placement:?}: {sizes:?}");
            eprintln!("{placement:?}: serialised sizes after 10, 1000, 10 000 steps: {sizes:?}");
        }
    }

    #[test]
    fn states_of_other_fmus_or_damaged_are_refused_without_panic() {
        let mut s = stepping();
        for k in 0..40 {
            drive(&mut s, k);
        }
        let bytes = s.serialize();
        let fresh = Slave::new(Params::paper(), ControllerPlacement::Internal);
        assert!(fresh.deserialize(&bytes).is_ok());
        // Another FMU: another GUID, another placement, another preset.
        let e = fresh
            .clone()
            .with_guid("{other}")
            .deserialize(&bytes)
            .unwrap_err();
        assert!(e.contains("another FMU"), "{e}");
        let e = Slave::new(Params::paper(), ControllerPlacement::External)
            .deserialize(&bytes)
            .unwrap_err();
        assert!(e.contains("another FMU"), "{e}");
        let mut other = Params::paper();
        other.plant.body.mass_kg += 1.0;
        assert!(
            Slave::new(other, ControllerPlacement::Internal)
                .deserialize(&bytes)
                .is_err()
        );
        // Another format version.
        let mut v = bytes.clone();
        v[8] = 1;
        assert!(fresh.deserialize(&v).unwrap_err().contains("version"));
        // Every truncation and every single flipped byte.
        for n in 0..bytes.len() {
            assert!(fresh.deserialize(&bytes[..n]).is_err(), "cut at {n}");
            let mut d = bytes.clone();
            d[n] ^= 0x20;
            assert!(fresh.deserialize(&d).is_err(), "byte {n} flipped");
        }
        // A consistent state whose content does not fit (a delay line of another size).
        let mut saved = SavedSlave {
            phase: s.phase,
            start_time: 0.0,
            params: PARAMS.iter().map(|p| p.get(&s.params)).collect(),
            xdd: s.xdd,
            x: s.x,
            v_in_ext: 0.0,
            command: CommandStream::default(),
            segment: s.segment,
            sim: s.sim.as_ref().map(Simulation::snapshot),
        };
        if let Some(sim) = saved.sim.as_mut() {
            sim.history.ring.pop();
        }
        let e = fresh.restore(saved).unwrap_err();
        assert!(e.contains("delay line"), "{e}");
    }

    #[test]
    fn state_before_initialization_and_after_reset_round_trips() {
        let mut s = Slave::new(Params::paper(), ControllerPlacement::Internal);
        s.setup(0.25).unwrap();
        s.set(VR_XDD, 1.5).unwrap();
        let r = s.deserialize(&s.serialize()).unwrap();
        assert_eq!(r.phase(), Phase::Instantiated);
        assert_eq!(r.get(VR_XDD).unwrap(), 1.5);
        let mut r = r;
        r.enter_initialization().unwrap();
        r.exit_initialization().unwrap();
        assert_eq!(r.time(), 0.25);
        r.reset();
        let back = r.deserialize(&r.serialize()).unwrap();
        assert_eq!(back.phase(), Phase::Instantiated);
        assert_eq!(back.get(VR_XDD).unwrap(), 0.0);
    }
}
