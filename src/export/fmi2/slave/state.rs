//! The slave's serialised state (`fmi2SerializeFMUstate`): the bytes, their checks and the
//! restore (see the [module docs](super)).

use super::*;

pub(super) const MAGIC: &[u8; 8] = b"SEATFMU2";
/// Version of the serialised form.
pub const STATE_FORMAT_VERSION: u32 = 2;

/// The serialised slave (see the module docs).
#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct SavedSlave {
    pub(super) phase: Phase,
    pub(super) start_time: f64,
    /// The values of the FMU's parameters, in table order.
    pub(super) params: Vec<f64>,
    pub(super) xdd: [f64; 4],
    pub(super) x: f64,
    pub(super) v_in_ext: f64,
    pub(super) command: CommandStream,
    pub(super) segment: InputSegment,
    pub(super) sim: Option<SimulationState>,
}

/// FNV-1a 64 of `bytes`.
pub(super) fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01B3)
    })
}

impl Slave {
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
    pub(super) fn restore(&self, saved: SavedSlave) -> SlaveResult<Self> {
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
