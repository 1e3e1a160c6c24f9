//! The report's figures.

use super::*;
use crate::simulation::Sample;

fn line(label: &str, x: Vec<f64>, y: Vec<f64>, i: usize) -> Series {
    Series {
        label: label.into(),
        x,
        y,
        style: SeriesStyle::Line {
            color: plot::palette(i),
            width: 2,
            dashed: false,
        },
    }
}

fn dashed(label: &str, x: Vec<f64>, y: Vec<f64>, i: usize) -> Series {
    Series {
        label: label.into(),
        x,
        y,
        style: SeriesStyle::Line {
            color: plot::palette(i),
            width: 2,
            dashed: true,
        },
    }
}

fn markers(label: &str, x: Vec<f64>, y: Vec<f64>, i: usize) -> Series {
    Series {
        label: label.into(),
        x,
        y,
        style: SeriesStyle::Markers {
            color: plot::palette(i),
            size: 4,
        },
    }
}

fn panel(title: &str, x_label: &str, y_label: &str, x_scale: Scale, series: Vec<Series>) -> Panel {
    Panel {
        title: title.into(),
        x_label: x_label.into(),
        y_label: y_label.into(),
        x_scale,
        y_scale: Scale::Linear,
        series,
        y_range: None,
        x_range: None,
        hlines: Vec::new(),
        vspans: Vec::new(),
    }
}

fn unwrapped_deg(c: &[Complex64]) -> Vec<f64> {
    fr::unwrap_phase(&c.iter().map(|v| v.arg()).collect::<Vec<_>>())
        .into_iter()
        .map(f64::to_degrees)
        .collect()
}

/// Phase of `c` [deg], each point moved by whole turns to the branch nearest `reference`
/// (so two curves that differ only by 360° across a deep notch are drawn on one branch).
fn aligned_deg(c: &[Complex64], reference: &[f64]) -> Vec<f64> {
    c.iter()
        .zip(reference)
        .map(|(v, r)| {
            let d = v.arg().to_degrees();
            d + 360.0 * ((r - d) / 360.0).round()
        })
        .collect()
}

pub fn table1_bode(
    out: &Path,
    params: &Params,
    table1: &[(f64, f64, f64, f64)],
    lin: &fr::LinearisedModel,
    dense: &[f64],
) -> Result<(), ReportError> {
    let g: Vec<Complex64> = dense.iter().map(|&f| fr::linear_bode(params, f)).collect();
    let tl: Vec<Complex64> = dense.iter().map(|&f| lin.bode(f)).collect();
    let mut mag = vec![
        line(
            "G(s), Eq. (15)",
            dense.to_vec(),
            g.iter().map(|c| c.norm() * 1e3).collect(),
            0,
        ),
        dashed(
            "twin linearised at rest",
            dense.to_vec(),
            tl.iter().map(|c| c.norm() * 1e3).collect(),
            1,
        ),
    ];
    let mut phase = vec![
        line("G(s)", dense.to_vec(), unwrapped_deg(&g), 0),
        dashed("twin linearised", dense.to_vec(), unwrapped_deg(&tl), 1),
    ];
    let mut amps: Vec<f64> = table1.iter().map(|r| r.1).collect();
    amps.dedup();
    amps.sort_by(f64::total_cmp);
    amps.dedup();
    for (i, a) in amps.iter().enumerate() {
        let rows: Vec<_> = table1.iter().filter(|r| r.1 == *a).collect();
        let f: Vec<f64> = rows.iter().map(|r| r.0).collect();
        mag.push(markers(
            &format!("twin {a:.2} V"),
            f.clone(),
            rows.iter().map(|r| r.2 * 1e3).collect(),
            i + 2,
        ));
        // Unwrap the sparse phase against the linearised twin's continuous curve.
        let ph: Vec<f64> = rows
            .iter()
            .map(|r| {
                let reference = lin.bode(r.0);
                let refdeg = unwrapped_deg(&[Complex64::new(1.0, 0.0), reference])[1];
                let mut p = r.3;
                while p - refdeg > 180.0 {
                    p -= 360.0;
                }
                while refdeg - p > 180.0 {
                    p += 360.0;
                }
                p
            })
            .collect();
        phase.push(markers(&format!("twin {a:.2} V"), f, ph, i + 2));
    }
    let fig = Figure {
        title: "u̇/V_in: Table 1 sine tests on the twin vs G(s)".into(),
        panels: vec![
            panel(
                "Magnitude",
                "frequency [Hz]",
                "|u̇/V_in| [mm/(s·V)]",
                Scale::Log10,
                mag,
            ),
            panel(
                "Phase",
                "frequency [Hz]",
                "phase [deg]",
                Scale::Log10,
                phase,
            ),
        ],
        width: 1100,
        height: 900,
    };
    plot::save_figure(&fig, &out.join("table1_bode"))?;
    Ok(())
}

/// The curves of the transmissibility figure.
#[derive(Debug, Clone, Copy)]
pub struct TransmissibilityCurves<'a> {
    /// Frequencies of the dense curves [Hz].
    pub freqs_hz: &'a [f64],
    /// Passive |T| at `freqs_hz`.
    pub passive: &'a [f64],
    /// Linear-model |T| at `freqs_hz`.
    pub linear: &'a [f64],
    /// Linearised twin T at `freqs_hz`.
    pub twin: &'a [Complex64],
    /// Frequencies of the simulated dwells [Hz].
    pub dwell_freqs_hz: &'a [f64],
    /// Twin T from the simulated dwells.
    pub dwell: &'a [Complex64],
}

/// Writes `transmissibility.png` and `.svg`: the three models and the twin's dwells.
pub fn transmissibility(
    out: &Path,
    curves: &TransmissibilityCurves,
    params: &Params,
) -> Result<(), ReportError> {
    let TransmissibilityCurves {
        freqs_hz: dense,
        passive,
        linear,
        twin,
        dwell_freqs_hz: dwell_f,
        dwell,
    } = *curves;
    let lin_c: Vec<Complex64> = dense
        .iter()
        .map(|&f| fr::linear_transmissibility(params, f))
        .collect();
    let pas_c: Vec<Complex64> = dense
        .iter()
        .map(|&f| fr::passive_transmissibility(params, f))
        .collect();
    let mut mag_panel = panel(
        "Transmissibility |ÿ/ẍ|",
        "frequency [Hz]",
        "|T| [-]",
        Scale::Log10,
        vec![
            line("active, G(s)", dense.to_vec(), linear.to_vec(), 0),
            line(
                "active, twin linearised",
                dense.to_vec(),
                twin.iter().map(|c| c.norm()).collect(),
                1,
            ),
            markers(
                "active, twin sine dwell",
                dwell_f.to_vec(),
                dwell.iter().map(|c| c.norm()).collect(),
                1,
            ),
            line("passive ζ = 0.3", dense.to_vec(), passive.to_vec(), 3),
        ],
    );
    mag_panel.y_scale = Scale::Log10;
    mag_panel.hlines.push((1.0, "|T| = 1".into()));
    let lin_deg = unwrapped_deg(&lin_c);
    // Reference branch for the dwell points: G(s)'s unwrapped phase at the nearest
    // dense frequency.
    let dwell_ref: Vec<f64> = dwell_f
        .iter()
        .map(|f| {
            let i = dense
                .iter()
                .enumerate()
                .min_by(|a, b| (a.1 - f).abs().total_cmp(&(b.1 - f).abs()))
                .map_or(0, |(i, _)| i);
            lin_deg.get(i).copied().unwrap_or(0.0)
        })
        .collect();
    let phase_panel = panel(
        "Phase",
        "frequency [Hz]",
        "phase [deg]",
        Scale::Log10,
        vec![
            line("active, G(s)", dense.to_vec(), lin_deg.clone(), 0),
            line(
                "active, twin linearised",
                dense.to_vec(),
                aligned_deg(twin, &lin_deg),
                1,
            ),
            markers(
                "active, twin sine dwell",
                dwell_f.to_vec(),
                aligned_deg(dwell, &dwell_ref),
                1,
            ),
            line("passive", dense.to_vec(), unwrapped_deg(&pas_c), 3),
        ],
    );
    let fig = Figure {
        title: "Fig. 12 — transmissibility, active vs passive".into(),
        panels: vec![mag_panel, phase_panel],
        width: 1100,
        height: 900,
    };
    plot::save_figure(&fig, &out.join("transmissibility"))?;
    Ok(())
}

fn contact_spans(t: &Trace) -> Vec<(f64, f64)> {
    t.contacts
        .iter()
        .map(|c| (c.t_start, c.t_end.max(c.t_start + 0.01)))
        .collect()
}

/// Curves over time of the runs of one scenario (twin, G(s), passive), on the first run's
/// time axis.
struct TimeCurves<'a> {
    t: Vec<f64>,
    runs: &'a [Trace],
}

impl<'a> TimeCurves<'a> {
    fn new(runs: &'a [Trace]) -> Self {
        Self {
            t: runs[0].channel(|s| s.t),
            runs,
        }
    }

    /// A solid curve of run `k`'s channel `f` in palette colour `i`.
    fn line(&self, label: &str, k: usize, f: impl Fn(&Sample) -> f64, i: usize) -> Series {
        line(label, self.t.clone(), self.runs[k].channel(f), i)
    }

    /// [`Self::line`] dashed.
    fn dashed(&self, label: &str, k: usize, f: impl Fn(&Sample) -> f64, i: usize) -> Series {
        dashed(label, self.t.clone(), self.runs[k].channel(f), i)
    }

    /// The "Accelerations" panel: the platform's ẍ (first run), then the `body` curves.
    fn accelerations(&self, body: Vec<Series>) -> Panel {
        let mut series = vec![self.line("platform ẍ", 0, |s| s.xdd, 7)];
        series.extend(body);
        time_panel("Accelerations", "acceleration [m/s²]", series)
    }
}

/// A panel over time [s].
fn time_panel(title: &str, y_label: &str, series: Vec<Series>) -> Panel {
    panel(title, "time [s]", y_label, Scale::Linear, series)
}

pub fn cycloid(out: &Path, cyc: &[Trace]) -> Result<(), ReportError> {
    let c = TimeCurves::new(cyc);
    let acc = c.accelerations(vec![
        c.line("body ÿ twin", 0, |s| s.ydd, 1),
        c.dashed("body ÿ G(s)", 1, |s| s.ydd, 0),
        c.line("body ÿ passive", 2, |s| s.ydd, 3),
    ]);
    let pos = time_panel(
        "Displacements",
        "displacement [mm]",
        vec![
            c.line("platform x", 0, |s| s.x * 1e3, 7),
            c.line("u twin", 0, |s| s.u * 1e3, 1),
            c.line("y twin", 0, |s| (s.x + s.u) * 1e3, 2),
            c.line("u passive", 2, |s| s.u * 1e3, 3),
            c.dashed("y passive", 2, |s| (s.x + s.u) * 1e3, 3),
        ],
    );
    let mut valve = time_panel(
        "Fig. 14 — command and spool (twin)",
        "V_in [V] · x_v [×0.1 mm]",
        vec![
            c.line("V_in [V]", 0, |s| s.v_in, 0),
            c.line("x_v [0.1 mm]", 0, |s| s.xv * 1e4, 1),
        ],
    );
    valve.vspans = contact_spans(&cyc[0]);
    let fig = Figure {
        title: "Figs. 13–14 — cycloidal platform rise 30 mm in 0.5 s".into(),
        panels: vec![acc, pos, valve],
        width: 1100,
        height: 1100,
    };
    plot::save_figure(&fig, &out.join("cycloid"))?;
    Ok(())
}

pub fn ride(out: &Path, r: &[Trace; 3]) -> Result<(), ReportError> {
    let c = TimeCurves::new(r);
    let acc = c.accelerations(vec![
        c.line("body ÿ passive", 2, |s| s.ydd, 3),
        c.line("body ÿ twin", 0, |s| s.ydd, 1),
    ]);
    let mut disp = time_panel(
        "Relative displacement",
        "u [mm]",
        vec![
            c.line("u twin", 0, |s| s.u * 1e3, 1),
            c.dashed("u G(s)", 1, |s| s.u * 1e3, 0),
            c.line("u passive", 2, |s| s.u * 1e3, 3),
        ],
    );
    disp.hlines = vec![(35.0, "+Lc/2".into()), (-35.0, "−Lc/2".into())];
    disp.vspans = contact_spans(&r[0]);
    let press = time_panel(
        "Fig. 16 — chamber pressures (twin)",
        "pressure [bar]",
        vec![
            c.line("p1", 0, |s| s.p1 / 1e5, 0),
            c.line("p2", 0, |s| s.p2 / 1e5, 3),
        ],
    );
    let flow = time_panel(
        "Flows (twin)",
        "flow [L/min]",
        vec![
            c.line("Q1", 0, |s| s.q1 * 60_000.0, 0),
            c.dashed("Q2", 0, |s| s.q2 * 60_000.0, 3),
        ],
    );
    let fig = Figure {
        title: "Figs. 15–16 — random ride, 0.5–5 Hz, S0 = 0.05 (m/s²)²/Hz, seed 1".into(),
        panels: vec![acc, disp, press, flow],
        width: 1200,
        height: 1400,
    };
    plot::save_figure(&fig, &out.join("ride"))?;
    Ok(())
}
