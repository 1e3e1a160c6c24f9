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
//! `fmi2GetFMUstate` copies the slave. The serialised form is the log of the calls that
//! changed it since instantiation (the slave is deterministic): deserialising replays them
//! on a fresh slave. The log is kept in memory and grows by 13 bytes per `fmi2SetReal` value
//! and 17 per `fmi2DoStep`: 43 bytes per communication step when the importer sets `xdd` and
//! its slope each step (about 150 MB per simulated hour at 1 ms).

use super::super::fmu::{
    ControllerPlacement, OUTPUTS, V_IN_EXT_RANGE, VR_OUTPUTS, VR_PARAMS, VR_V_IN_EXT, VR_X, VR_XDD,
    X_RANGE, XDD_RANGE, exposes,
};
use crate::model::twin::Twin;
use crate::params::{MAX_DELAY_S, PARAMS, Params, fmt_value};
use crate::scenario::{CommandSignal, CommandStream, InputSegment, PlatformMotion};
use crate::simulation::{Drive, Run, Simulation};

/// The FMI 2.0 states of a co-simulation slave.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
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

/// A call that changed the slave (the serialised state is the list of them).
#[derive(Debug, Clone, Copy, PartialEq)]
enum Call {
    Setup(f64),
    Enter,
    Exit,
    SetReal(u32, f64),
    SetDerivative(u32, u8, f64),
    DoStep(f64, f64),
    Terminate,
    Reset,
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
    log: Vec<Call>,
}

/// An error with the message the FMU logs.
pub type SlaveResult<T> = Result<T, String>;

const MAGIC: &[u8; 8] = b"STFMU2S1";

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
            log: Vec::new(),
        }
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
        self.log.push(Call::Setup(start_time));
        Ok(())
    }

    /// `fmi2EnterInitializationMode`.
    pub fn enter_initialization(&mut self) -> SlaveResult<()> {
        self.require(&[Phase::Instantiated], "fmi2EnterInitializationMode")?;
        self.phase = Phase::Initialization;
        self.log.push(Call::Enter);
        Ok(())
    }

    /// `fmi2ExitInitializationMode`: checks the parameters together and builds the twin.
    pub fn exit_initialization(&mut self) -> SlaveResult<()> {
        self.require(&[Phase::Initialization], "fmi2ExitInitializationMode")?;
        self.sim = Some(self.build()?);
        self.phase = Phase::Step;
        self.log.push(Call::Exit);
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
        let platform = PlatformMotion::Extrapolated(InputSegment {
            t0: 0.0,
            x: self.x,
            xdd: [self.xdd[0], 0.0, 0.0, 0.0],
        });
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
        self.log.push(Call::Terminate);
        Ok(())
    }

    /// `fmi2Reset`: back to the state after instantiation.
    pub fn reset(&mut self) {
        let log = std::mem::take(&mut self.log);
        *self = Slave::new(self.preset, self.placement);
        self.log = log;
        self.log.push(Call::Reset);
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
        self.log.push(Call::SetReal(vr, value));
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
        self.log.push(Call::SetDerivative(vr, order as u8, value));
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
        sim.set_platform(PlatformMotion::Extrapolated(InputSegment {
            t0: t_sim,
            x: self.x,
            xdd: self.xdd,
        }));
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
        self.log.push(Call::DoStep(t, step));
        Ok(())
    }

    /// The serialised state: the calls since instantiation.
    pub fn serialize(&self) -> Vec<u8> {
        let mut out = MAGIC.to_vec();
        for c in &self.log {
            let (tag, a, b, c2): (u8, u32, f64, f64) = match *c {
                Call::Setup(t) => (1, 0, t, 0.0),
                Call::Enter => (2, 0, 0.0, 0.0),
                Call::Exit => (3, 0, 0.0, 0.0),
                Call::SetReal(vr, v) => (4, vr, v, 0.0),
                Call::SetDerivative(vr, o, v) => (5, vr | (o as u32) << 28, v, 0.0),
                Call::DoStep(t, h) => (6, 0, t, h),
                Call::Terminate => (7, 0, 0.0, 0.0),
                Call::Reset => (8, 0, 0.0, 0.0),
            };
            out.push(tag);
            match tag {
                4 | 5 => {
                    out.extend_from_slice(&a.to_le_bytes());
                    out.extend_from_slice(&b.to_le_bytes());
                }
                1 => out.extend_from_slice(&b.to_le_bytes()),
                6 => {
                    out.extend_from_slice(&b.to_le_bytes());
                    out.extend_from_slice(&c2.to_le_bytes());
                }
                _ => {}
            }
        }
        out
    }

    /// The slave a serialised state describes, replayed on a fresh slave of the same preset.
    pub fn deserialize(
        preset: Params,
        placement: ControllerPlacement,
        bytes: &[u8],
    ) -> SlaveResult<Self> {
        let bad = |at: usize| format!("the serialised FMU state is damaged at byte {at}");
        if bytes.len() < MAGIC.len() || &bytes[..MAGIC.len()] != MAGIC {
            return Err("the bytes are not a serialised state of this FMU".into());
        }
        let mut s = Slave::new(preset, placement);
        let mut i = MAGIC.len();
        let f64_at = |i: usize| -> SlaveResult<f64> {
            bytes
                .get(i..i + 8)
                .map(|b| f64::from_le_bytes(b.try_into().unwrap_or([0; 8])))
                .ok_or_else(|| bad(i))
        };
        let u32_at = |i: usize| -> SlaveResult<u32> {
            bytes
                .get(i..i + 4)
                .map(|b| u32::from_le_bytes(b.try_into().unwrap_or([0; 4])))
                .ok_or_else(|| bad(i))
        };
        while i < bytes.len() {
            let tag = bytes[i];
            i += 1;
            let replayed = match tag {
                1 => {
                    let t = f64_at(i)?;
                    i += 8;
                    s.setup(t)
                }
                2 => s.enter_initialization(),
                3 => s.exit_initialization(),
                4 => {
                    let (vr, v) = (u32_at(i)?, f64_at(i + 4)?);
                    i += 12;
                    s.set(vr, v)
                }
                5 => {
                    let (a, v) = (u32_at(i)?, f64_at(i + 4)?);
                    i += 12;
                    s.set_derivative(a & 0x0fff_ffff, (a >> 28) as i32, v)
                }
                6 => {
                    let (t, h) = (f64_at(i)?, f64_at(i + 8)?);
                    i += 16;
                    s.do_step(t, h)
                }
                7 => s.terminate(),
                8 => {
                    s.reset();
                    Ok(())
                }
                _ => Err(bad(i - 1)),
            };
            replayed.map_err(|e| format!("replaying the serialised state: {e}"))?;
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

    #[test]
    fn serialised_state_replays_bit_for_bit() {
        let mut s = stepping();
        for k in 0..40 {
            let t = k as f64 * 1e-3;
            s.set(VR_XDD, (7.0 * t).sin()).unwrap();
            s.set_derivative(VR_XDD, 1, 7.0 * (7.0 * t).cos()).unwrap();
            s.do_step(t, 1e-3).unwrap();
        }
        let bytes = s.serialize();
        let r = Slave::deserialize(Params::paper(), ControllerPlacement::Internal, &bytes).unwrap();
        for vr in 0..OUTPUTS.len() as u32 {
            assert_eq!(s.get(vr).unwrap().to_bits(), r.get(vr).unwrap().to_bits());
        }
        assert!(
            Slave::deserialize(Params::paper(), ControllerPlacement::Internal, &bytes[..20])
                .is_err()
        );
    }
}
