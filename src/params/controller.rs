//! The controller's structure and gains, and how `[controller]` reads and writes in a preset.

use super::{ParamError, check};
use serde::{Deserialize, Serialize};

/// Which controller structure drives the valve. The equations, signals and units of each are in
/// [`crate::control`]; every kind runs on the twin and on the linear models.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ControllerKind {
    /// The paper's Eq. (16): `V = Kp·u + Ki·∫ẍ dt` (position feedback, platform-velocity
    /// feed-forward).
    #[default]
    Paper,
    /// The paper's structure with the platform velocity predicted `lead_s` ahead:
    /// `V = Kp·u + Ki·(∫ẍ dt + lead_s·LP(ẍ))`.
    Predictive,
    /// The paper's structure plus feedback of the absolute body velocity, estimated from a body
    /// accelerometer by a leaky integrator and band-limited:
    /// `V = Kp·u + Ki·∫ẍ dt + Ksky·ωs/(s + ωs)·ÿ/(s + ωl)`.
    Skyhook,
    /// A Smith predictor on G(s) with its delay around the position loop, plus the paper's
    /// feed-forward.
    Smith,
}

impl ControllerKind {
    /// Every kind, in menu order.
    pub const ALL: [ControllerKind; 4] = [
        ControllerKind::Paper,
        ControllerKind::Predictive,
        ControllerKind::Skyhook,
        ControllerKind::Smith,
    ];

    /// The name used in presets and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            ControllerKind::Paper => "paper",
            ControllerKind::Predictive => "predictive",
            ControllerKind::Skyhook => "skyhook",
            ControllerKind::Smith => "smith",
        }
    }

    /// The preset keys (gains) this kind reads, besides `kind`.
    pub fn keys(self) -> &'static [&'static str] {
        match self {
            ControllerKind::Paper | ControllerKind::Smith => &["kp_v_per_m", "ki_v_s_per_m"],
            ControllerKind::Predictive => {
                &["kp_v_per_m", "ki_v_s_per_m", "lead_s", "lead_cutoff_hz"]
            }
            ControllerKind::Skyhook => &[
                "kp_v_per_m",
                "ki_v_s_per_m",
                "sky_v_s_per_m",
                "leak_hz",
                "sky_cutoff_hz",
            ],
        }
    }
}

impl std::fmt::Display for ControllerKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for ControllerKind {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Self::ALL
            .into_iter()
            .find(|k| k.name() == s)
            .ok_or_else(|| {
                format!("unknown controller kind `{s}` (one of: paper, predictive, skyhook, smith)")
            })
    }
}

/// The controller: its structure and gains. In a preset, `[controller]` holds `kind` (default
/// `"paper"`) and that kind's keys only ([`ControllerKind::keys`]); a key of another kind is an
/// error, as is an unknown key. Gains a kind does not use keep their defaults.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "ControllerTable", into = "ControllerTable")]
pub struct ControllerParams {
    /// Structure.
    pub kind: ControllerKind,
    /// Position gain `Kp` [V/m], -1e4 ..= 1e4. Paper: -5. All kinds.
    pub kp_v_per_m: f64,
    /// Gain on the integral of the platform acceleration `Ki` [V·s/m], -1e3 ..= 1e3. Paper: -7.5.
    /// All kinds.
    pub ki_v_s_per_m: f64,
    /// Prediction horizon of the platform velocity \[s\], 0 ..= 0.1. Default 0.0207 (the valve's
    /// 17.5 ms delay plus the spool's ≈ 3.2 ms lag). `predictive` only.
    pub lead_s: f64,
    /// Corner of the first-order low-pass on the predicted term \[Hz\], 0.5 ..= 200. Default 12.
    /// `predictive` only.
    pub lead_cutoff_hz: f64,
    /// Gain on the estimated absolute body velocity `Ksky` [V·s/m], -1e3 ..= 1e3. Default -3.
    /// `skyhook` only.
    pub sky_v_s_per_m: f64,
    /// Corner of the leaky integrator `ωl/2π` \[Hz\], 0.01 ..= 10. Default 0.3. `skyhook` only.
    pub leak_hz: f64,
    /// Corner of the first-order low-pass on the body-velocity estimate `ωs/2π` \[Hz\],
    /// 0.5 ..= 200. Default 6: keeps the feedback off the valve's lightly damped resonance
    /// (≈ 80 Hz), where the delay turns it positive. `skyhook` only.
    pub sky_cutoff_hz: f64,
}

impl Default for ControllerParams {
    fn default() -> Self {
        Self {
            kind: ControllerKind::Paper,
            kp_v_per_m: -5.0,
            ki_v_s_per_m: -7.5,
            lead_s: 0.0207,
            lead_cutoff_hz: 12.0,
            sky_v_s_per_m: -3.0,
            leak_hz: 0.3,
            sky_cutoff_hz: 6.0,
        }
    }
}

impl ControllerParams {
    /// The paper's controller with gains `kp` [V/m] and `ki` [V·s/m].
    pub fn paper(kp_v_per_m: f64, ki_v_s_per_m: f64) -> Self {
        Self {
            kp_v_per_m,
            ki_v_s_per_m,
            ..Self::default()
        }
    }

    /// Value of a gain by its preset key, `None` for an unknown key.
    pub fn get(&self, key: &str) -> Option<f64> {
        Some(match key {
            "kp_v_per_m" => self.kp_v_per_m,
            "ki_v_s_per_m" => self.ki_v_s_per_m,
            "lead_s" => self.lead_s,
            "lead_cutoff_hz" => self.lead_cutoff_hz,
            "sky_v_s_per_m" => self.sky_v_s_per_m,
            "leak_hz" => self.leak_hz,
            "sky_cutoff_hz" => self.sky_cutoff_hz,
            _ => return None,
        })
    }

    /// Sets a gain by its preset key; `false` for an unknown key.
    pub fn set(&mut self, key: &str, value: f64) -> bool {
        let slot = match key {
            "kp_v_per_m" => &mut self.kp_v_per_m,
            "ki_v_s_per_m" => &mut self.ki_v_s_per_m,
            "lead_s" => &mut self.lead_s,
            "lead_cutoff_hz" => &mut self.lead_cutoff_hz,
            "sky_v_s_per_m" => &mut self.sky_v_s_per_m,
            "leak_hz" => &mut self.leak_hz,
            "sky_cutoff_hz" => &mut self.sky_cutoff_hz,
            _ => return false,
        };
        *slot = value;
        true
    }

    /// Allowed range `(min, max, unit)` of a gain by its preset key (from [`super::PARAMS`]).
    pub fn range(key: &str) -> Option<(f64, f64, &'static str)> {
        let s = super::spec(&format!("controller.{key}"))?;
        Some((s.min, s.max, s.unit))
    }

    /// Checks every gain of this kind against its range.
    pub fn validate(&self) -> Result<(), ParamError> {
        for key in self.kind.keys() {
            let s = super::spec(&format!("controller.{key}")).expect("every kind's key is listed");
            let value = self.get(key).expect("every kind's key is a field");
            check(s.key, value, s.min, s.max, s.unit)?;
        }
        Ok(())
    }
}

/// `[controller]` as written in a preset: `kind` and the gains that kind reads.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct ControllerTable {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    kind: Option<ControllerKind>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    kp_v_per_m: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    ki_v_s_per_m: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    lead_s: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    lead_cutoff_hz: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    sky_v_s_per_m: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    leak_hz: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    sky_cutoff_hz: Option<f64>,
}

impl TryFrom<ControllerTable> for ControllerParams {
    type Error = String;
    fn try_from(t: ControllerTable) -> Result<Self, String> {
        let kind = t.kind.unwrap_or_default();
        let mut c = ControllerParams {
            kind,
            ..ControllerParams::default()
        };
        let given = [
            ("kp_v_per_m", t.kp_v_per_m),
            ("ki_v_s_per_m", t.ki_v_s_per_m),
            ("lead_s", t.lead_s),
            ("lead_cutoff_hz", t.lead_cutoff_hz),
            ("sky_v_s_per_m", t.sky_v_s_per_m),
            ("leak_hz", t.leak_hz),
            ("sky_cutoff_hz", t.sky_cutoff_hz),
        ];
        for (key, value) in given {
            let Some(value) = value else { continue };
            if !kind.keys().contains(&key) {
                return Err(format!(
                    "`{key}` is not a gain of controller kind `{kind}` (its keys: kind, {})",
                    kind.keys().join(", ")
                ));
            }
            c.set(key, value);
        }
        Ok(c)
    }
}

impl From<ControllerParams> for ControllerTable {
    fn from(c: ControllerParams) -> Self {
        let mut t = ControllerTable {
            kind: Some(c.kind),
            ..Default::default()
        };
        for key in c.kind.keys() {
            let value = c.get(key);
            match *key {
                "kp_v_per_m" => t.kp_v_per_m = value,
                "ki_v_s_per_m" => t.ki_v_s_per_m = value,
                "lead_s" => t.lead_s = value,
                "lead_cutoff_hz" => t.lead_cutoff_hz = value,
                "sky_v_s_per_m" => t.sky_v_s_per_m = value,
                "leak_hz" => t.leak_hz = value,
                "sky_cutoff_hz" => t.sky_cutoff_hz = value,
                _ => {}
            }
        }
        t
    }
}
