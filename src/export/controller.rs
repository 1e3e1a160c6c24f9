//! The controller at a fixed rate, in Rust ([`SampledController`]) and as portable C99
//! (`seat-twin export controller`, File → Export controller code… through [`write`](fn@write)).
//!
//! # The discrete controller
//! [`SampledController`] is the twin's own [`Controller`] stepped at `h = 1/rate` on sensor
//! samples, as it would run on the rig: at each sample it takes `u` \[m\], `ẍ` [m/s²] and `ÿ`
//! [m/s²]; `∫ẍ dt` grows by the trapezoid `h/2·(ẍₙ₋₁ + ẍₙ)` (the only rule samples allow; the
//! twin's stepper uses Simpson with its mid-step value), the filters step exactly for an
//! input linear between samples, the Smith model exactly for the command held over the step.
//! The command is saturated to ±Vmax, and the saturated command is what the Smith model is
//! driven with — the controller's one anti-windup: its only integrator, `∫ẍ dt`, is the
//! platform's velocity, which the command does not drive, so it is not clamped (as in the
//! twin). The first call starts the controller (no `∫ẍ` yet); each later call steps it.
//!
//! # The C code
//! `seat_controller.h` / `seat_controller.c`: one state struct, `seat_ctrl_init` and
//! `seat_ctrl_step(s, u_m, xdd_m_s2, ydd_m_s2)` returning the saturated command \[V\] before the
//! valve's delay; `_f` names for the float variant. No allocation, no globals, no libm: every
//! coefficient is written as a C99 hexadecimal literal of the Rust value, and the
//! expressions keep Rust's order of operations, so that the double variant, compiled with
//! `-ffp-contract=off`, gives the Rust controller's commands bit for bit
//! (`tests/it/export.rs`). `seat_controller.json` holds the discretised transfer functions.

use crate::control::{ControlLaw, Controller, Measurement};
use crate::format::general as fmt_value;
use crate::params::{ControllerKind, MAX_DELAY_S, Params};
use crate::preset::Preset;
use std::fmt::Write as _;
use std::path::Path;

/// Allowed controller rates \[Hz\].
pub const RATE_RANGE_HZ: (f64, f64) = (50.0, 100_000.0);

/// The twin's controller stepped at a fixed rate on sensor samples (see the module docs).
#[derive(Debug, Clone)]
pub struct SampledController {
    controller: Controller,
    h: f64,
    v_max: f64,
    last_xdd: f64,
    started: bool,
}

impl SampledController {
    /// The preset's controller at `rate_hz` \[Hz\], at rest.
    pub fn new(params: &Params, rate_hz: f64) -> Self {
        let h = 1.0 / rate_hz;
        Self {
            controller: Controller::new(&ControlLaw::new(params), h),
            h,
            v_max: params.plant.valve.v_max_v,
            last_xdd: 0.0,
            started: false,
        }
    }

    /// The command \[V\], saturated to ±Vmax, for the samples `u` \[m\], `ẍ` [m/s²], `ÿ` [m/s²].
    pub fn step(&mut self, u: f64, xdd: f64, ydd: f64) -> f64 {
        let c = &mut self.controller;
        if self.started {
            c.advance(&Measurement {
                u,
                ydd,
                xdd,
                dxd: 0.5 * self.h * (self.last_xdd + xdd),
            });
        } else {
            c.start(&Measurement {
                u,
                ydd,
                xdd,
                dxd: 0.0,
            });
            self.started = true;
        }
        self.last_xdd = xdd;
        let v = c.output(u).clamp(-self.v_max, self.v_max);
        c.sent(v);
        v
    }

    /// The discretisation's numbers.
    pub fn coefficients(&self) -> crate::control::Coefficients {
        self.controller.coefficients()
    }
}

/// A C99 hexadecimal literal of `v` (exact).
pub fn hex_f64(v: f64) -> String {
    let bits = v.to_bits();
    let sign = if bits >> 63 == 1 { "-" } else { "" };
    let exp = ((bits >> 52) & 0x7ff) as i64;
    let man = bits & ((1u64 << 52) - 1);
    match exp {
        0 if man == 0 => format!("{sign}0.0"),
        0 => format!("{sign}0x0.{man:013x}p-1022"),
        _ => format!("{sign}0x1.{man:013x}p{}", exp - 1023),
    }
}

/// A C99 hexadecimal `float` literal of `v` rounded to single precision.
pub fn hex_f32(v: f64) -> String {
    let bits = (v as f32).to_bits();
    let sign = if bits >> 31 == 1 { "-" } else { "" };
    let exp = ((bits >> 23) & 0xff) as i64;
    let man = (bits & ((1u32 << 23) - 1)) << 1;
    match exp {
        0 if man == 0 => format!("{sign}0.0f"),
        0 => format!("{sign}0x0.{man:06x}p-126f"),
        _ => format!("{sign}0x1.{man:06x}p{}f", exp - 127),
    }
}

/// The Smith model's read of its history `τm` back: whole steps back, fraction, cubic
/// Lagrange weights, and the ring's length — the numbers [`crate::simulation::delay::DelayLine`] uses
/// for a delay line of step `h` with room for [`MAX_DELAY_S`] + `h`.
fn smith_tap(tau_s: f64, h: f64) -> (i64, f64, [f64; 4], usize) {
    let inv_h = 1.0 / h;
    let d = tau_s * inv_h;
    let back = d.ceil();
    let f = back - d;
    let (fm1, fm2, fp1) = (f - 1.0, f - 2.0, f + 1.0);
    let w = [
        -f * fm1 * fm2 / 6.0,
        fp1 * fm1 * fm2 / 2.0,
        -fp1 * f * fm2 / 2.0,
        fp1 * f * fm1 / 6.0,
    ];
    let size = (((MAX_DELAY_S + h) / h).ceil() as usize + 8).next_power_of_two();
    (back as i64, f, w, size)
}

/// What the C header says about where the controller comes from.
#[derive(Debug, Clone)]
pub struct Provenance {
    /// Preset name or file.
    pub preset: String,
    /// Gain margin \[dB\], phase margin \[deg\] and delay margin \[s\] of the twin linearised at
    /// rest with this law (continuous time), if the loop is stable.
    pub margins: Option<(f64, f64, f64)>,
}

impl Provenance {
    /// The provenance of `params` from the preset `name`, with the margins of its loop.
    pub fn of(name: &str, params: &Params) -> Self {
        let s = crate::analysis::stability::twin_stability(params);
        let m = &s.margins;
        Self {
            preset: name.to_string(),
            margins: s
                .stable()
                .then(|| (m.gain_margin_db(), m.phase_margin_deg(), m.delay_margin_s())),
        }
    }
}

/// One variant of the C code: its type, suffix and literal writer.
struct Variant {
    ty: &'static str,
    suffix: &'static str,
    lit: fn(f64) -> String,
}

const DOUBLE: Variant = Variant {
    ty: "double",
    suffix: "",
    lit: hex_f64,
};
const FLOAT: Variant = Variant {
    ty: "float",
    suffix: "_f",
    lit: hex_f32,
};

/// `seat_controller.h` and `seat_controller.c` for `params`' controller at `rate_hz`.
pub fn c_source(params: &Params, rate_hz: f64, provenance: &Provenance) -> (String, String) {
    let sc = SampledController::new(params, rate_hz);
    let k = sc.coefficients();
    let c = &params.controller;
    let kind = c.kind;
    let h = 1.0 / rate_hz;
    let v_max = params.plant.valve.v_max_v;
    let tap = smith_tap(params.linear.tau_s, h);

    let mut comment = String::new();
    let _ = writeln!(comment, "/*");
    let _ = writeln!(
        comment,
        " * seat-twin {} controller, exported by seat-twin {} (`seat-twin export controller`).",
        kind.name(),
        env!("CARGO_PKG_VERSION")
    );
    let _ = writeln!(comment, " * Preset: {}", provenance.preset);
    let _ = writeln!(
        comment,
        " * Rate: {} Hz (step {} s). Call seat_ctrl_step once per sample, in order.",
        fmt_value(rate_hz),
        fmt_value(h)
    );
    let _ = writeln!(comment, " * Gains (SI):");
    for key in kind.keys() {
        let _ = writeln!(
            comment,
            " *   controller.{key} = {}",
            fmt_value(c.get(key).unwrap_or(f64::NAN))
        );
    }
    if kind == ControllerKind::Smith {
        let l = &params.linear;
        let _ = writeln!(
            comment,
            " *   Smith model G(s): Kg = {} m/(s.V), sp = {} rad/s, zeta = {}, tau_m = {} s",
            fmt_value(l.kg_m_per_s_v),
            fmt_value(l.sp_rad_s),
            fmt_value(l.zeta),
            fmt_value(l.tau_s)
        );
    }
    let _ = writeln!(
        comment,
        " * Saturation: +-{} V (valve.v_max_v); the Smith model, when there is one, is driven by the",
        fmt_value(v_max)
    );
    let _ = writeln!(
        comment,
        " * saturated command (anti-windup); the integral of xdd is the platform velocity and is"
    );
    let _ = writeln!(comment, " * not clamped, as in the twin.");
    match provenance.margins {
        Some((gm, pm, dm)) => {
            let _ = writeln!(
                comment,
                " * Tuned for (twin linearised at rest, continuous-time law, valve delay {} s):",
                fmt_value(params.plant.valve.tau_s)
            );
            let _ = writeln!(
                comment,
                " *   gain margin {} dB, phase margin {} deg, delay margin {} ms.",
                fmt_value((gm * 10.0).round() / 10.0),
                fmt_value((pm * 10.0).round() / 10.0),
                fmt_value((dm * 1e4).round() / 10.0)
            );
            let _ = writeln!(
                comment,
                " *   Sampling at this rate adds about half a step ({} ms) of delay to the loop.",
                fmt_value(h * 500.0)
            );
        }
        None => {
            let _ = writeln!(
                comment,
                " * WARNING: the loop of this preset is not stable on the twin linearised at rest."
            );
        }
    }
    let _ = writeln!(
        comment,
        " * Inputs: u_m = y - x [m] (stroke), xdd_m_s2 [m/s^2] (platform accelerometer),"
    );
    let _ = writeln!(
        comment,
        " * ydd_m_s2 [m/s^2] (body accelerometer{}). Output: command [V], before the valve's delay.",
        if kind == ControllerKind::Skyhook {
            ""
        } else {
            "; not read by this kind"
        }
    );
    let _ = writeln!(
        comment,
        " * The double variant equals the Rust controller bit for bit when compiled with\n * -ffp-contract=off (no fused multiply-add); the float variant (_f) is the same code in single\n * precision. C99, no allocation, no globals, no libm."
    );
    let _ = writeln!(comment, " */");

    let mut hdr = comment.clone();
    let _ = writeln!(
        hdr,
        "#ifndef SEAT_CONTROLLER_H\n#define SEAT_CONTROLLER_H\n"
    );
    let _ = writeln!(
        hdr,
        "/* Samples per second the controller was discretised for. */\n#define SEAT_CTRL_RATE_HZ {}",
        fmt_value(rate_hz)
    );
    if kind == ControllerKind::Smith {
        let _ = writeln!(
            hdr,
            "/* Length of the Smith model's history (a power of two). */\n#define SEAT_CTRL_HISTORY {}",
            tap.3
        );
    }
    let _ = writeln!(hdr);
    for v in [&DOUBLE, &FLOAT] {
        let t = v.ty;
        let _ = writeln!(
            hdr,
            "/* The controller's state ({t}); set it up with seat_ctrl_init{}. */",
            v.suffix
        );
        let _ = writeln!(hdr, "typedef struct {{");
        let _ = writeln!(hdr, "    int started;      /* 0 until the first sample */");
        let _ = writeln!(hdr, "    {t} xd;            /* integral of xdd [m/s] */");
        let _ = writeln!(hdr, "    {t} last_xdd;      /* previous xdd [m/s^2] */");
        let _ = writeln!(hdr, "    {t} last_ydd;      /* previous ydd [m/s^2] */");
        match kind {
            ControllerKind::Paper => {}
            ControllerKind::Predictive => {
                let _ = writeln!(hdr, "    {t} lead;          /* low-passed xdd [m/s^2] */");
            }
            ControllerKind::Skyhook => {
                let _ = writeln!(
                    hdr,
                    "    {t} sky;           /* leaky integral of ydd [m/s] */"
                );
                let _ = writeln!(hdr, "    {t} sky_lp;        /* its low-pass [m/s] */");
            }
            ControllerKind::Smith => {
                let _ = writeln!(
                    hdr,
                    "    {t} z[3];          /* Smith model: position [m], section output and rate */"
                );
                let _ = writeln!(hdr, "    {t} sent;          /* command last sent [V] */");
                let _ = writeln!(
                    hdr,
                    "    {t} hist[SEAT_CTRL_HISTORY]; /* model positions, ring */"
                );
                let _ = writeln!(hdr, "    unsigned long len; /* samples pushed to hist */");
            }
        }
        let _ = writeln!(hdr, "}} seat_ctrl_state{};\n", v.suffix);
    }
    for v in [&DOUBLE, &FLOAT] {
        let (t, s) = (v.ty, v.suffix);
        let _ = writeln!(hdr, "/* Puts the controller at rest. */");
        let _ = writeln!(hdr, "void seat_ctrl_init{s}(seat_ctrl_state{s} *s);");
        let _ = writeln!(
            hdr,
            "/* One sample: the saturated command [V] for u [m], xdd [m/s^2], ydd [m/s^2]. */"
        );
        let _ = writeln!(
            hdr,
            "{t} seat_ctrl_step{s}(seat_ctrl_state{s} *s, {t} u_m, {t} xdd_m_s2, {t} ydd_m_s2);\n"
        );
    }
    let _ = writeln!(hdr, "#endif /* SEAT_CONTROLLER_H */");

    let mut src = comment;
    let _ = writeln!(src, "#include \"seat_controller.h\"\n");
    for v in [&DOUBLE, &FLOAT] {
        let (t, s, l) = (v.ty, v.suffix, v.lit);
        let _ = writeln!(src, "void seat_ctrl_init{s}(seat_ctrl_state{s} *s)\n{{");
        let _ = writeln!(src, "    s->started = 0;");
        let _ = writeln!(
            src,
            "    s->xd = 0;\n    s->last_xdd = 0;\n    s->last_ydd = 0;"
        );
        match kind {
            ControllerKind::Paper => {}
            ControllerKind::Predictive => {
                let _ = writeln!(src, "    s->lead = 0;");
            }
            ControllerKind::Skyhook => {
                let _ = writeln!(src, "    s->sky = 0;\n    s->sky_lp = 0;");
            }
            ControllerKind::Smith => {
                let _ = writeln!(
                    src,
                    "    {{\n        unsigned long i;\n        for (i = 0; i < SEAT_CTRL_HISTORY; i++) {{\n            s->hist[i] = 0;\n        }}\n    }}"
                );
                let _ = writeln!(
                    src,
                    "    s->z[0] = 0;\n    s->z[1] = 0;\n    s->z[2] = 0;\n    s->sent = 0;"
                );
                let _ = writeln!(src, "    s->len = 1; /* the rest value at t = 0 */");
            }
        }
        let _ = writeln!(src, "}}\n");
        if kind == ControllerKind::Smith {
            let _ = writeln!(
                src,
                "/* The model position pushed as sample n (clamped to the samples kept; 0 before 0). */\n\
                 static {t} history_at{s}(const seat_ctrl_state{s} *s, long n)\n{{\n    \
                 long newest = (long)s->len - 1;\n    \
                 long oldest = (long)s->len - SEAT_CTRL_HISTORY;\n    \
                 if (n < 0 || newest < 0) {{\n        return 0;\n    }}\n    \
                 if (oldest < 0) {{\n        oldest = 0;\n    }}\n    \
                 if (n < oldest) {{\n        n = oldest;\n    }}\n    \
                 if (n > newest) {{\n        n = newest;\n    }}\n    \
                 return s->hist[(unsigned long)n & (SEAT_CTRL_HISTORY - 1)];\n}}\n"
            );
            let w = tap.2;
            let _ = writeln!(
                src,
                "/* The model position tau_m ago: cubic Lagrange interpolation of the history. */\n\
                 static {t} delayed_model{s}(const seat_ctrl_state{s} *s)\n{{\n    \
                 const {t} w0 = {}, w1 = {}, w2 = {}, w3 = {};\n    \
                 const {t} f = {};\n    \
                 long newest = (long)s->len - 1;\n    \
                 long oldest = (long)s->len - SEAT_CTRL_HISTORY;\n    \
                 long base = newest - {};\n    \
                 if (base < 0) {{\n        return 0;\n    }}\n    \
                 if (base >= 1 && base > oldest && base + 2 <= newest) {{\n        \
                 return w0 * s->hist[(unsigned long)(base - 1) & (SEAT_CTRL_HISTORY - 1)]\n            \
                 + w1 * s->hist[(unsigned long)base & (SEAT_CTRL_HISTORY - 1)]\n            \
                 + w2 * s->hist[(unsigned long)(base + 1) & (SEAT_CTRL_HISTORY - 1)]\n            \
                 + w3 * s->hist[(unsigned long)(base + 2) & (SEAT_CTRL_HISTORY - 1)];\n    }}\n    \
                 if (base + 2 <= newest) {{\n        \
                 return w0 * history_at{s}(s, base - 1) + w1 * history_at{s}(s, base)\n            \
                 + w2 * history_at{s}(s, base + 1) + w3 * history_at{s}(s, base + 2);\n    }}\n    \
                 {{\n        {t} b = history_at{s}(s, base), c = history_at{s}(s, base + 1);\n        \
                 return b + f * (c - b);\n    }}\n}}\n",
                l(w[0]),
                l(w[1]),
                l(w[2]),
                l(w[3]),
                l(tap.1),
                tap.0
            );
        }
        let _ = writeln!(
            src,
            "{t} seat_ctrl_step{s}(seat_ctrl_state{s} *s, {t} u_m, {t} xdd_m_s2, {t} ydd_m_s2)\n{{"
        );
        let _ = writeln!(src, "    const {t} kp = {}; /* V/m */", l(c.kp_v_per_m));
        let _ = writeln!(src, "    const {t} ki = {}; /* V.s/m */", l(c.ki_v_s_per_m));
        let _ = writeln!(src, "    const {t} half_h = {}; /* s */", l(0.5 * h));
        let _ = writeln!(src, "    const {t} v_max = {}; /* V */", l(v_max));
        let _ = writeln!(src, "    {t} xd, v;");
        let _ = writeln!(src, "    if (s->started) {{");
        let _ = writeln!(
            src,
            "        s->xd = s->xd + half_h * (s->last_xdd + xdd_m_s2);"
        );
        let section = |src: &mut String, name: &str, sec: [f64; 3], x0: &str, x1: &str| {
            let _ = writeln!(
                src,
                "        s->{name} = {} * s->{name} + {} * {x0} + {} * {x1};",
                l(sec[0]),
                l(sec[1]),
                l(sec[2])
            );
        };
        match kind {
            ControllerKind::Paper => {}
            ControllerKind::Predictive => {
                section(&mut src, "lead", k.lead, "s->last_xdd", "xdd_m_s2");
            }
            ControllerKind::Skyhook => {
                let _ = writeln!(src, "        {t} q0 = s->sky;");
                section(&mut src, "sky", k.sky, "s->last_ydd", "ydd_m_s2");
                section(&mut src, "sky_lp", k.sky_lp, "q0", "s->sky");
            }
            ControllerKind::Smith => {
                let (phi, gamma) = k.smith.unwrap_or_default();
                let _ = writeln!(src, "        {t} z0 = s->z[0], z1 = s->z[1], z2 = s->z[2];");
                for i in 0..3 {
                    let _ = writeln!(
                        src,
                        "        s->z[{i}] = {} * z0 + {} * z1 + {} * z2 + {} * s->sent;",
                        l(phi[i][0]),
                        l(phi[i][1]),
                        l(phi[i][2]),
                        l(gamma[i])
                    );
                }
                let _ = writeln!(
                    src,
                    "        s->hist[s->len & (SEAT_CTRL_HISTORY - 1)] = s->z[0];\n        s->len++;"
                );
            }
        }
        let _ = writeln!(src, "    }} else {{\n        s->started = 1;\n    }}");
        let _ = writeln!(
            src,
            "    s->last_xdd = xdd_m_s2;\n    s->last_ydd = ydd_m_s2;"
        );
        // Rust's output reads ∫ẍ as `xd + 0.0` (its stage form with nothing more integrated).
        let _ = writeln!(src, "    xd = s->xd + 0;");
        let out = match kind {
            ControllerKind::Paper => "kp * u_m + ki * xd".to_string(),
            ControllerKind::Predictive => {
                format!("kp * u_m + ki * (xd + {} * s->lead)", l(c.lead_s))
            }
            ControllerKind::Skyhook => {
                format!("kp * u_m + ki * xd + {} * s->sky_lp", l(c.sky_v_s_per_m))
            }
            ControllerKind::Smith => {
                format!("kp * (u_m + (s->z[0] - delayed_model{s}(s))) + ki * xd")
            }
        };
        let _ = writeln!(src, "    v = {out};");
        let _ = writeln!(
            src,
            "    if (v < -v_max) {{\n        v = -v_max;\n    }}\n    if (v > v_max) {{\n        v = v_max;\n    }}"
        );
        if kind == ControllerKind::Smith {
            let _ = writeln!(src, "    s->sent = v;");
        }
        let _ = writeln!(src, "    return v;\n}}\n");
    }
    (hdr, src)
}

/// The discretised transfer functions as JSON: each section's continuous form, the
/// discretisation method (as python-control's `sample_system` names it) and the discrete
/// coefficients the controller uses (highest power of z first).
pub fn coefficients_json(params: &Params, rate_hz: f64) -> serde_json::Value {
    use serde_json::json;
    let h = 1.0 / rate_hz;
    let c = &params.controller;
    let k = SampledController::new(params, rate_hz).coefficients();
    let two_pi = 2.0 * std::f64::consts::PI;
    let first_order = |name: &str, input: &str, a: f64, b: f64, sec: [f64; 3]| {
        json!({
            "name": name,
            "input": input,
            "continuous": { "num": [b], "den": [1.0, a] },
            "method": "foh",
            "discrete": { "num": [sec[2], sec[1]], "den": [1.0, -sec[0]] },
        })
    };
    let mut sections = vec![json!({
        "name": "xdd_integral",
        "input": "xdd",
        "continuous": { "num": [1.0], "den": [1.0, 0.0] },
        "method": "tustin",
        "discrete": { "num": [0.5 * h, 0.5 * h], "den": [1.0, -1.0] },
    })];
    let mut smith = serde_json::Value::Null;
    match c.kind {
        ControllerKind::Paper => {}
        ControllerKind::Predictive => {
            let wc = two_pi * c.lead_cutoff_hz;
            sections.push(first_order("lead", "xdd", wc, wc, k.lead));
        }
        ControllerKind::Skyhook => {
            let wl = two_pi * c.leak_hz;
            let ws = two_pi * c.sky_cutoff_hz;
            sections.push(first_order("sky", "ydd", wl, 1.0, k.sky));
            sections.push(first_order("sky_lp", "sky", ws, ws, k.sky_lp));
        }
        ControllerKind::Smith => {
            let l = &params.linear;
            let sp2 = l.sp_rad_s * l.sp_rad_s;
            let (phi, gamma) = k.smith.unwrap_or_default();
            smith = json!({
                "state": ["model position [m]", "section output [V]", "section rate [V/s]"],
                "continuous": {
                    "A": [[0.0, l.kg_m_per_s_v, 0.0], [0.0, 0.0, 1.0],
                          [0.0, -sp2, -2.0 * l.zeta * l.sp_rad_s]],
                    "B": [0.0, 0.0, sp2],
                },
                "method": "zoh",
                "discrete": { "A": phi, "B": gamma },
                "delay_s": l.tau_s,
            });
        }
    }
    json!({
        "kind": c.kind.name(),
        "rate_hz": rate_hz,
        "step_s": h,
        "gains": c.kind.keys().iter().map(|key| (key.to_string(), json!(c.get(key))))
            .collect::<serde_json::Map<_, _>>(),
        "v_max_v": params.plant.valve.v_max_v,
        "sections": sections,
        "smith_model": smith,
    })
}

/// Why the controller code could not be written.
#[derive(Debug, thiserror::Error)]
pub enum ControllerExportError {
    /// The rate is outside [`RATE_RANGE_HZ`].
    #[error("the rate {} Hz is outside the allowed range [{}, {}] Hz", fmt_value(*.0), fmt_value(RATE_RANGE_HZ.0), fmt_value(RATE_RANGE_HZ.1))]
    Rate(f64),
    /// Writing the files failed.
    #[error("{}: {error}", .dir.display())]
    Io {
        /// The output directory.
        dir: std::path::PathBuf,
        /// What failed.
        error: std::io::Error,
    },
}

/// The files [`write`](fn@write) makes in its directory.
pub const FILES: [&str; 3] = [
    "seat_controller.h",
    "seat_controller.c",
    "seat_controller.json",
];

/// Writes `seat_controller.h`, `seat_controller.c` and `seat_controller.json` for the
/// preset's controller at `rate_hz` into the directory `out`, all or none (staged in a
/// hidden folder, then moved). `preset_name` goes into the header; `progress(fraction,
/// stage)` is called as the work goes.
pub fn write(
    preset: &Preset,
    preset_name: &str,
    rate_hz: f64,
    out: &Path,
    progress: &mut dyn FnMut(f64, &str),
) -> Result<(), ControllerExportError> {
    if !(rate_hz.is_finite() && (RATE_RANGE_HZ.0..=RATE_RANGE_HZ.1).contains(&rate_hz)) {
        return Err(ControllerExportError::Rate(rate_hz));
    }
    let io = |error| ControllerExportError::Io {
        dir: out.to_path_buf(),
        error,
    };
    progress(0.0, "stability margins");
    let provenance = Provenance::of(preset_name, &preset.params);
    progress(0.5, "C code");
    let (h, c) = c_source(&preset.params, rate_hz, &provenance);
    let json = coefficients_json(&preset.params, rate_hz);
    let json = serde_json::to_string_pretty(&json).unwrap_or_default() + "\n";
    progress(0.8, "writing");
    let dir = crate::fsutil::OutputDir::create(out).map_err(io)?;
    for (name, text) in FILES.iter().zip([h, c, json]) {
        std::fs::write(dir.path().join(name), text).map_err(io)?;
    }
    dir.commit().map_err(io)?;
    progress(1.0, "done");
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hex_literals_are_exact() {
        assert_eq!(hex_f64(1.0), "0x1.0000000000000p0");
        assert_eq!(hex_f64(-0.75), "-0x1.8000000000000p-1");
        assert_eq!(hex_f64(0.0), "0.0");
        assert_eq!(hex_f64(-0.0), "-0.0");
        assert_eq!(hex_f32(1.0), "0x1.000000p0f");
        assert_eq!(hex_f32(0.1), "0x1.99999ap-4f");
    }

    #[test]
    fn paper_law_sampled_is_eq16_with_the_trapezoid() {
        let p = Params::paper();
        let mut c = SampledController::new(&p, 1000.0);
        assert_eq!(c.step(0.01, 2.0, 0.0), -5.0 * 0.01);
        // ∫ẍ = 1 ms/2·(2 + 4) = 3 mm/s.
        let v = c.step(0.02, 4.0, 0.0);
        assert!((v - (-5.0 * 0.02 - 7.5 * 0.003)).abs() < 1e-15);
        // Saturation at ±Vmax.
        assert_eq!(c.step(-10.0, 0.0, 0.0), 10.0);
    }
}
