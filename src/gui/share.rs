//! Shareable setups: the preset, the controller, the excitation and the view as one short,
//! versioned text — the web page's `#s=…` fragment, and the same string pasted into the
//! desktop app (View ▸ Paste setup link).
//!
//! Version 1 is `;`-separated `key=value` fields after the version:
//!
//! ```text
//! 1;preset=paper;kind=paper;controller.kp_v_per_m=-400;exc=random,seed=7,dur=60;speed=max;present=1;lesson=3
//! ```
//!
//! * `preset` — a preset compiled into the app ([`SHIPPED`]); the parameters start from it.
//! * `kind` — the controller structure; any key of the parameter table
//!   ([`crate::params::PARAMS`]) — a value \[SI\] that differs from the preset.
//! * `exc` — the excitation: `random,seed,dur,s0,flo,fhi`, `sine,a,f` (platform, m/s² and
//!   Hz), `valve,a,f` (V, Hz), `cycloid,h,rise,period` (m, s, s), `class,name,dur`.
//! * `speed` (`slow`, `1x`, `fast`, `max`), `present` (0/1), `lesson` (step number, 1-based).
//!
//! A link is read like a preset file: every field is checked (name, range, the parameter set
//! as a whole); a bad one gives an error naming the field and what is allowed, and the app
//! keeps its defaults. Numbers are written in Rust's shortest round-trip form, so a link
//! restores the values bit for bit.

use super::controls::{ExcitationEditor, ExcitationKind};
use crate::engine::Speed;
use crate::params::{ControllerKind, PARAMS, Params};
use crate::preset::Preset;
use std::path::Path;

/// The version this app writes and reads.
pub const VERSION: u32 = 1;

/// The presets compiled into the app (the web build has no `presets/` folder): name, TOML.
pub const SHIPPED: [(&str, &str); 6] = [
    ("paper", include_str!("../../presets/paper.toml")),
    (
        "paper-initial",
        include_str!("../../presets/paper-initial.toml"),
    ),
    (
        "consistent-delay",
        include_str!("../../presets/consistent-delay.toml"),
    ),
    (
        "tuned-paper",
        include_str!("../../presets/tuned-paper.toml"),
    ),
    (
        "tuned-predictive",
        include_str!("../../presets/tuned-predictive.toml"),
    ),
    (
        "tuned-predictive-robust",
        include_str!("../../presets/tuned-predictive-robust.toml"),
    ),
];

/// The compiled-in preset `name`, parsed (an error names it and the allowed names).
pub fn shipped_preset(name: &str) -> Result<Preset, String> {
    let (_, text) = SHIPPED.iter().find(|(n, _)| *n == name).ok_or_else(|| {
        let names: Vec<&str> = SHIPPED.iter().map(|(n, _)| *n).collect();
        format!("unknown preset `{name}` (one of: {})", names.join(", "))
    })?;
    Preset::from_toml(text, Path::new(&format!("presets/{name}.toml"))).map_err(|e| e.to_string())
}

/// One setup: what a link carries.
#[derive(Debug, Clone)]
pub struct Setup {
    /// The compiled-in preset the parameters start from.
    pub preset: String,
    /// The parameters (the preset's, with the link's changes).
    pub params: Params,
    /// The excitation editor's state (kind and the fields of that kind).
    pub excitation: ExcitationEditor,
    /// Simulation speed.
    pub speed: Speed,
    /// Presentation mode (large text, thick lines).
    pub presentation: bool,
    /// The lesson step shown (0-based), if any.
    pub lesson: Option<usize>,
}

impl Setup {
    /// The app's defaults: the paper's preset, the default random ride, real time.
    pub fn defaults() -> Self {
        Self {
            preset: "paper".into(),
            params: shipped_preset("paper").map_or_else(|_| Params::paper(), |p| p.params),
            excitation: ExcitationEditor::default(),
            speed: Speed::RealTime,
            presentation: false,
            lesson: None,
        }
    }

    /// The setup as a link string (without `#s=`).
    pub fn encode(&self) -> String {
        let mut f = vec![VERSION.to_string(), format!("preset={}", self.preset)];
        let base = shipped_preset(&self.preset).map_or_else(|_| Params::paper(), |p| p.params);
        if self.params.controller.kind != base.controller.kind {
            f.push(format!("kind={}", self.params.controller.kind));
        }
        for s in &PARAMS {
            let v = s.get(&self.params);
            if v.to_bits() != s.get(&base).to_bits() {
                f.push(format!("{}={v}", s.key));
            }
        }
        let e = &self.excitation;
        f.push(match e.kind {
            ExcitationKind::Random | ExcitationKind::Record => {
                let r = &e.random;
                format!(
                    "exc=random,{},{},{},{},{}",
                    r.seed, r.duration_s, r.s0, r.f_low_hz, r.f_high_hz
                )
            }
            ExcitationKind::Sine => format!("exc=sine,{},{}", e.sine_accel_m_s2, e.sine_freq_hz),
            ExcitationKind::ValveSine => {
                format!("exc=valve,{},{}", e.valve_amplitude_v, e.valve_freq_hz)
            }
            ExcitationKind::Cycloid => format!(
                "exc=cycloid,{},{},{}",
                e.cycloid.height_m, e.cycloid.rise_time_s, e.cycloid_period_s
            ),
            ExcitationKind::Class => format!("exc=class,{},{}", e.class_name, e.class_duration_s),
        });
        f.push(format!("speed={}", speed_name(self.speed)));
        if self.presentation {
            f.push("present=1".into());
        }
        if let Some(l) = self.lesson {
            f.push(format!("lesson={}", l + 1));
        }
        f.join(";")
    }

    /// Reads a link string (`1;preset=…`, with or without a leading `#s=` or `s=`): every
    /// field is checked; the first bad one is the error, naming it.
    pub fn decode(text: &str) -> Result<Self, String> {
        let text = text.trim();
        let text = text.strip_prefix('#').unwrap_or(text);
        let text = text.strip_prefix("s=").unwrap_or(text);
        let text = percent_decode(text);
        let mut fields = text.split(';');
        let version = fields.next().unwrap_or_default();
        match version.parse::<u32>() {
            Ok(VERSION) => {}
            Ok(v) => {
                return Err(format!(
                    "setup link version {v} is not known: this app reads version {VERSION}"
                ));
            }
            Err(_) => {
                return Err(format!(
                    "not a setup link: it must start with the version `{VERSION};`, not `{version}`"
                ));
            }
        }
        let mut setup = Setup::defaults();
        let mut changes: Vec<(&'static crate::params::ParamSpec, f64)> = Vec::new();
        let mut kind: Option<ControllerKind> = None;
        for (i, field) in fields.enumerate().filter(|(_, f)| !f.is_empty()) {
            let n = i + 2;
            let (key, value) = field
                .split_once('=')
                .ok_or_else(|| format!("setup link field {n} `{field}`: expected key=value"))?;
            let bad = |why: String| format!("setup link field {n} `{field}`: {why}");
            match key {
                "preset" => {
                    let p = shipped_preset(value).map_err(bad)?;
                    setup.preset = value.to_string();
                    setup.params = p.params;
                }
                "kind" => kind = Some(value.parse().map_err(bad)?),
                "exc" => setup.excitation = excitation(value).map_err(bad)?,
                "speed" => setup.speed = parse_speed(value).map_err(bad)?,
                "present" => setup.presentation = flag(value).map_err(bad)?,
                "lesson" => {
                    let l: usize = value
                        .parse()
                        .ok()
                        .filter(|l| (1..=super::lessons::LESSONS.len()).contains(l))
                        .ok_or_else(|| {
                            bad(format!(
                                "a lesson step 1 … {}",
                                super::lessons::LESSONS.len()
                            ))
                        })?;
                    setup.lesson = Some(l - 1);
                }
                key => {
                    let spec = crate::params::spec(key).ok_or_else(|| {
                        bad(
                            "unknown key (preset, kind, exc, speed, present, lesson or a \
                             parameter key such as controller.kp_v_per_m)"
                                .into(),
                        )
                    })?;
                    let v = number(value).map_err(bad)?;
                    spec.check(v).map_err(|e| bad(e.to_string()))?;
                    changes.push((spec, v));
                }
            }
        }
        // The preset first (wherever it stood), then the changes on top of it.
        if let Some(k) = kind {
            setup.params.controller.kind = k;
        }
        for (spec, v) in changes {
            spec.set_unchecked(&mut setup.params, v);
        }
        setup
            .params
            .validate()
            .map_err(|e| format!("setup link: the parameters are not valid together: {e}"))?;
        Ok(setup)
    }
}

fn speed_name(s: Speed) -> &'static str {
    match s {
        Speed::Slow => "slow",
        Speed::RealTime => "1x",
        Speed::Fast => "fast",
        Speed::Max => "max",
    }
}

fn parse_speed(s: &str) -> Result<Speed, String> {
    Ok(match s {
        "slow" => Speed::Slow,
        "1x" => Speed::RealTime,
        "fast" => Speed::Fast,
        "max" => Speed::Max,
        _ => return Err("speed is one of slow, 1x, fast, max".into()),
    })
}

fn flag(s: &str) -> Result<bool, String> {
    match s {
        "0" => Ok(false),
        "1" => Ok(true),
        _ => Err("0 or 1".into()),
    }
}

fn number(s: &str) -> Result<f64, String> {
    s.parse::<f64>()
        .ok()
        .filter(|v| v.is_finite())
        .ok_or_else(|| format!("`{s}` is not a finite number"))
}

/// `%XX` escapes (a browser may escape characters of a pasted fragment) back to bytes.
fn percent_decode(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        let hex = |c: u8| (c as char).to_digit(16);
        if b[i] == b'%'
            && i + 2 < b.len()
            && let (Some(h), Some(l)) = (hex(b[i + 1]), hex(b[i + 2]))
        {
            out.push((h * 16 + l) as u8);
            i += 3;
        } else {
            out.push(b[i]);
            i += 1;
        }
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// The excitation of an `exc=` value, each number checked against its range.
fn excitation(value: &str) -> Result<ExcitationEditor, String> {
    let mut parts = value.split(',');
    let kind = parts.next().unwrap_or_default();
    let rest: Vec<&str> = parts.collect();
    let mut e = ExcitationEditor::default();
    let num = |i: usize, name: &str, lo: f64, hi: f64, unit: &str| -> Result<f64, String> {
        let s = rest
            .get(i)
            .ok_or_else(|| format!("exc={kind} needs {name} as value {}", i + 2))?;
        let v = number(s)?;
        if (lo..=hi).contains(&v) {
            Ok(v)
        } else {
            Err(format!("{name} = {v} {unit} is outside {lo} … {hi} {unit}"))
        }
    };
    let count = |n: usize| {
        if rest.len() > n {
            Err(format!("exc={kind} takes {n} values, got {}", rest.len()))
        } else {
            Ok(())
        }
    };
    match kind {
        "random" => {
            count(5)?;
            e.kind = ExcitationKind::Random;
            let seed = rest.first().ok_or("exc=random needs a seed")?;
            e.random.seed = seed
                .parse()
                .map_err(|_| format!("seed `{seed}` is not a whole number 0 … 2^64−1"))?;
            if rest.len() > 1 {
                e.random.duration_s = num(1, "duration", 1.0, 3600.0, "s")?;
            }
            if rest.len() > 2 {
                e.random.s0 = num(2, "S0", 0.0, 10.0, "(m/s²)²/Hz")?;
            }
            if rest.len() > 3 {
                e.random.f_low_hz = num(3, "lower band edge", 0.05, 100.0, "Hz")?;
            }
            if rest.len() > 4 {
                e.random.f_high_hz = num(4, "upper band edge", 0.05, 200.0, "Hz")?;
            }
            e.random.validate().map_err(|e| e.to_string())?;
        }
        "sine" => {
            count(2)?;
            e.kind = ExcitationKind::Sine;
            e.sine_accel_m_s2 = num(0, "acceleration", 0.0, 20.0, "m/s²")?;
            e.sine_freq_hz = num(1, "frequency", 0.1, 100.0, "Hz")?;
        }
        "valve" => {
            count(2)?;
            e.kind = ExcitationKind::ValveSine;
            e.valve_amplitude_v = num(0, "amplitude", 0.0, 10.0, "V")?;
            e.valve_freq_hz = num(1, "frequency", 0.1, 100.0, "Hz")?;
        }
        "cycloid" => {
            count(3)?;
            e.kind = ExcitationKind::Cycloid;
            e.cycloid.height_m = num(0, "height", -0.2, 0.2, "m")?;
            e.cycloid.rise_time_s = num(1, "rise time", 0.01, 10.0, "s")?;
            e.cycloid_period_s = num(2, "period", 0.1, 60.0, "s")?;
        }
        "class" => {
            count(2)?;
            e.kind = ExcitationKind::Class;
            let name = rest.first().ok_or("exc=class needs a class name")?;
            if crate::seat_test::find(name).is_none() {
                return Err(format!(
                    "unknown seat-test class `{name}` ({})",
                    crate::scenario::classes::names()
                ));
            }
            e.class_name = (*name).to_string();
            if rest.len() > 1 {
                e.class_duration_s = num(1, "duration", 20.0, 3600.0, "s")?;
            }
        }
        other => {
            return Err(format!(
                "unknown excitation `{other}` (random, sine, valve, cycloid, class)"
            ));
        }
    }
    Ok(e)
}

/// The page's address without its fragment, plus `#s=link` (web): the link as the web page
/// shares it.
#[cfg(target_arch = "wasm32")]
pub fn page_link(link: &str) -> String {
    let base = web_sys::window()
        .and_then(|w| w.location().href().ok())
        .unwrap_or_default();
    let base = base.split('#').next().unwrap_or_default().to_string();
    format!("{base}#s={link}")
}
