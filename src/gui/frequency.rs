//! Frequency plots that follow the sliders: transmissibility |T| and phase (linear active,
//! twin linearised, passive), the Bode of `u̇/V_in` (twin vs G(s)), the |T| = 1 crossings,
//! the loop margins, and the twin's simulated sine-dwell points computed on a background
//! thread with progress and cancel.
//!
//! The analytic curves are recomputed on the frame the parameters change (the twin's
//! linearisation only when a plant parameter changes, not for a gain).

use super::plotkit::{self, LegendItem, Swatch, legend_ui, wrap_deg, y_axis, y_marks};
use super::units::{db, deg};
use crate::analysis::frequency_response::{
    self as fr, Crossing, DwellOptions, LoopMargins, OpenLoop,
};
use crate::control::ControlLaw;
use crate::model::ModelKind;
use crate::params::{ControllerParams, Params};
use egui::{Color32, RichText};
use egui_plot::{Line, LineStyle, MarkerShape, Plot, PlotPoint, PlotPoints, Points, VLine};
use num_complex::Complex64;
use std::collections::BTreeSet;
use std::f64::consts::PI;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, channel};
use std::time::{Duration, Instant};

/// Frequency range of the plots [Hz].
pub const F_RANGE_HZ: (f64, f64) = (0.1, 100.0);
/// Points of the analytic curves.
pub const N_POINTS: usize = 240;
/// Frequencies of the simulated dwell [Hz].
pub const DWELL_RANGE_HZ: (f64, f64) = (0.3, 30.0);
/// Number of dwell points.
pub const N_DWELL: usize = 14;
/// Legend of the simulated u̇/V_in points.
const BODE_DWELL_NAME: &str = "twin simulated (sine dwell, ≤ 1.1 V)";
/// Highest frequency of the simulated u̇/V_in points [Hz] (Table 1's range: above it the
/// phase between neighbouring dwell points could not be unwrapped reliably).
pub const BODE_DWELL_MAX_HZ: f64 = 20.0;
/// Command amplitude of the simulated u̇/V_in point at `freq_hz` [V]: Table 1's 1.1 V where
/// the stroke allows, less at low frequency so that the piston stays within ±15 mm of
/// mid-stroke (at the paper's gain of 133 mm/(s·V), 1.1 V at 0.3 Hz would swing ±78 mm,
/// into the end stops at ±35 mm).
pub fn bode_dwell_amplitude_v(freq_hz: f64) -> f64 {
    const STROKE_AMPLITUDE_M: f64 = 0.015;
    const NOMINAL_GAIN_M_PER_S_V: f64 = 0.133;
    (STROKE_AMPLITUDE_M * 2.0 * PI * freq_hz / NOMINAL_GAIN_M_PER_S_V).clamp(0.05, 1.1)
}
/// Pause after the last parameter change before the dwell restarts.
pub const DWELL_DEBOUNCE: Duration = Duration::from_millis(400);

/// Colours of the three models, shared by scopes and frequency plots.
pub const TWIN: Color32 = Color32::from_rgb(31, 119, 180);
/// Linear model colour.
pub const LINEAR: Color32 = Color32::from_rgb(255, 127, 14);
/// Passive model colour.
pub const PASSIVE: Color32 = Color32::from_rgb(44, 160, 44);
/// Platform colour.
pub const PLATFORM: Color32 = Color32::from_rgb(127, 127, 127);

/// The plant part of the parameters: the linearisation's cache key. The gains and the delay
/// act outside the linearised plant, so dragging Kp, Ki or τ reuses it.
fn plant_key(p: &Params) -> Params {
    let mut k = *p;
    k.controller = ControllerParams::paper(0.0, 0.0);
    k.plant.valve.tau_s = 0.0;
    k.linear.tau_s = 0.0;
    k
}

/// The linearised twin's open-loop responses on the plot grid and the margin grid.
pub struct PlantCache {
    key: Params,
    /// On the plot frequencies (delay excluded).
    pub points: Vec<OpenLoop>,
    margin_freqs: Vec<f64>,
    margin_points: Vec<OpenLoop>,
}

impl PlantCache {
    /// Linearises the twin (delay-free) and evaluates it on both grids.
    pub fn new(params: &Params, freqs: &[f64]) -> Self {
        let key = plant_key(params);
        let lin0 = fr::linearise_twin(&key);
        let points = freqs.iter().map(|&f| lin0.open_loop(f)).collect();
        let margin_freqs = fr::margin_frequencies();
        let margin_points = margin_freqs.iter().map(|&f| lin0.open_loop(f)).collect();
        Self {
            key,
            points,
            margin_freqs,
            margin_points,
        }
    }

    /// Loop margins of the twin for a controller and delay (as [`fr::twin_margins`]).
    pub fn margins(&self, law: &ControlLaw, tau_s: f64) -> LoopMargins {
        fr::law_margins_on(
            &self.margin_freqs,
            self.margin_points.iter().copied(),
            law,
            tau_s,
        )
    }
}

/// One curve in plot coordinates `(log10 f, value)`.
pub type Curve = Vec<PlotPoint>;

/// The analytic frequency responses for one parameter set.
#[derive(Debug, Clone, Default)]
pub struct Curves {
    /// Parameters they were computed for.
    pub params: Option<Params>,
    /// |T| [dB] of linear, twin (linearised), passive.
    pub t_mag: [Curve; 3],
    /// Phase of T [deg] of linear, twin, passive (unwrapped).
    pub t_phase: [Curve; 3],
    /// |u̇/V_in| [dB re 1 (mm/s)/V] of twin (linearised) and G(s).
    pub bode_mag: [Curve; 2],
    /// Phase of `u̇/V_in` [deg] of twin and G(s).
    pub bode_phase: [Curve; 2],
    /// |T| = 1 crossings of linear and twin.
    pub crossings: [Vec<Crossing>; 2],
    /// Position-loop margins of linear and twin.
    pub margins: [Option<LoopMargins>; 2],
    /// Time the last recomputation took [ms].
    pub compute_ms: f64,
}

impl Curves {
    /// Whether either active loop is unstable.
    pub fn unstable(&self) -> bool {
        self.margins.iter().flatten().any(|m| !m.stable())
    }
}

/// Cached analytic curves plus the linearised twin.
#[derive(Default)]
pub struct Analytic {
    curves: Curves,
    plant: Option<PlantCache>,
    freqs: Vec<f64>,
}

impl Analytic {
    /// The current curves.
    pub fn curves(&self) -> &Curves {
        &self.curves
    }

    /// Recomputes if `params` differ from the last call; returns true if it did.
    pub fn update(&mut self, params: &Params) -> bool {
        if self.curves.params.as_ref() == Some(params) {
            return false;
        }
        let t0 = Instant::now();
        if self.freqs.is_empty() {
            self.freqs = fr::log_space(F_RANGE_HZ.0, F_RANGE_HZ.1, N_POINTS);
        }
        let key = plant_key(params);
        if self.plant.as_ref().is_none_or(|c| c.key != key) {
            self.plant = Some(PlantCache::new(params, &self.freqs));
        }
        let Some(plant) = self.plant.as_ref() else {
            return false;
        };
        let tau = params.plant.valve.tau_s;
        let f = &self.freqs;
        let lx: Vec<f64> = f.iter().map(|x| x.log10()).collect();
        let t_lin: Vec<Complex64> = f
            .iter()
            .map(|&x| fr::linear_transmissibility(params, x))
            .collect();
        let t_twin: Vec<Complex64> = plant
            .points
            .iter()
            .map(|p| p.transmissibility(&ControlLaw::new(params), tau))
            .collect();
        let t_pas: Vec<Complex64> = f
            .iter()
            .map(|&x| fr::passive_transmissibility(params, x))
            .collect();
        let b_twin: Vec<Complex64> = plant.points.iter().map(|p| p.bode(tau)).collect();
        let b_g: Vec<Complex64> = f.iter().map(|&x| fr::linear_bode(params, x)).collect();
        let mag = |v: &[Complex64], scale: f64| -> Curve {
            lx.iter()
                .zip(v)
                .map(|(&x, c)| PlotPoint::new(x, db(c.norm() * scale)))
                .filter(|p| p.y.is_finite())
                .collect()
        };
        let phase = |v: &[Complex64]| -> Curve {
            let ph = fr::unwrap_phase(&v.iter().map(|c| c.arg()).collect::<Vec<_>>());
            lx.iter()
                .zip(ph)
                .map(|(&x, p)| PlotPoint::new(x, deg(p)))
                .filter(|p| p.y.is_finite())
                .collect()
        };
        let mags = |v: &[Complex64]| v.iter().map(|c| c.norm()).collect::<Vec<_>>();
        self.curves = Curves {
            params: Some(*params),
            t_mag: [mag(&t_lin, 1.0), mag(&t_twin, 1.0), mag(&t_pas, 1.0)],
            t_phase: [phase(&t_lin), phase(&t_twin), phase(&t_pas)],
            bode_mag: [mag(&b_twin, 1e3), mag(&b_g, 1e3)],
            bode_phase: [phase(&b_twin), phase(&b_g)],
            crossings: [
                fr::unity_crossings(f, &mags(&t_lin)),
                fr::unity_crossings(f, &mags(&t_twin)),
            ],
            margins: [
                Some(fr::linear_margins(params)),
                Some(plant.margins(&ControlLaw::new(params), tau)),
            ],
            compute_ms: 0.0,
        };
        self.curves.compute_ms = t0.elapsed().as_secs_f64() * 1e3;
        true
    }
}

/// A message from the dwell thread.
enum DwellMsg {
    Point {
        freq_hz: f64,
        value: Complex64,
        bode: Option<Complex64>,
    },
    Failed {
        freq_hz: f64,
        reason: String,
    },
    Finished,
}

/// A running sine-dwell sweep of the twin.
struct DwellJob {
    params: Params,
    cancel: Arc<AtomicBool>,
    rx: Receiver<DwellMsg>,
    total: usize,
    done: usize,
}

impl Drop for DwellJob {
    fn drop(&mut self) {
        self.cancel.store(true, Ordering::Relaxed);
    }
}

/// The simulated (sine dwell) points of the twin: transmissibility, and u̇/V_in up to
/// [`BODE_DWELL_MAX_HZ`].
#[derive(Default)]
pub struct Dwell {
    job: Option<DwellJob>,
    /// Parameters of the shown points.
    shown_for: Option<Params>,
    /// |T| [dB] points.
    pub mag: Curve,
    /// Phase [deg] points.
    pub phase: Curve,
    /// |u̇/V_in| [dB re 1 mm/(s·V)] points.
    pub bode_mag: Curve,
    /// Phase of u̇/V_in [deg] points.
    pub bode_phase: Curve,
    /// Points that failed (diverged), with the reason.
    pub failures: Vec<(f64, String)>,
    /// Last parameter change not yet simulated, and when it happened.
    pending: Option<(Params, Instant)>,
    /// Whether the user cancelled the sweep for the current parameters.
    pub cancelled: bool,
}

impl Dwell {
    /// Progress `(done, total)` of a running sweep.
    pub fn progress(&self) -> Option<(usize, usize)> {
        self.job.as_ref().map(|j| (j.done, j.total))
    }

    /// Whether the shown points belong to `params`.
    pub fn is_current(&self, params: &Params) -> bool {
        self.shown_for.as_ref() == Some(params) && self.job.is_none()
    }

    /// Cancels the running sweep (the thread stops after its current point).
    pub fn cancel(&mut self) {
        self.job = None;
        self.pending = None;
        self.cancelled = true;
    }

    /// Starts a sweep now for `params` (also after a cancel).
    pub fn start(&mut self, params: &Params) {
        self.pending = None;
        self.cancelled = false;
        self.mag.clear();
        self.phase.clear();
        self.bode_mag.clear();
        self.bode_phase.clear();
        self.failures.clear();
        self.shown_for = Some(*params);
        let freqs = fr::log_space(DWELL_RANGE_HZ.0, DWELL_RANGE_HZ.1, N_DWELL);
        let cancel = Arc::new(AtomicBool::new(false));
        let (tx, rx) = channel();
        let p = *params;
        let stop = cancel.clone();
        let total = freqs.len();
        let spawned = std::thread::Builder::new()
            .name("seat-twin-dwell".into())
            .spawn(move || {
                let opt = DwellOptions::default();
                for &f in &freqs {
                    if stop.load(Ordering::Relaxed) {
                        return;
                    }
                    let r = std::panic::catch_unwind(|| {
                        let t = fr::simulated_transmissibility(&p, ModelKind::Twin, f, &opt)?;
                        let b = if f <= BODE_DWELL_MAX_HZ {
                            Some(fr::simulated_bode(
                                &p,
                                ModelKind::Twin,
                                f,
                                bode_dwell_amplitude_v(f),
                                &opt,
                            )?)
                        } else {
                            None
                        };
                        Ok::<_, crate::simulation::SimError>((t, b))
                    });
                    let msg = match r {
                        Ok(Ok((value, bode))) => DwellMsg::Point {
                            freq_hz: f,
                            value,
                            bode,
                        },
                        Ok(Err(e)) => DwellMsg::Failed {
                            freq_hz: f,
                            reason: e.to_string(),
                        },
                        Err(_) => DwellMsg::Failed {
                            freq_hz: f,
                            reason: "internal error in the simulation".into(),
                        },
                    };
                    if tx.send(msg).is_err() {
                        return;
                    }
                }
                let _ = tx.send(DwellMsg::Finished);
            });
        match spawned {
            Ok(_) => {
                self.job = Some(DwellJob {
                    params: p,
                    cancel,
                    rx,
                    total,
                    done: 0,
                })
            }
            Err(e) => self
                .failures
                .push((0.0, format!("could not start a thread: {e}"))),
        }
    }

    /// Follows the parameters (debounced restart) and collects finished points. Returns
    /// true while work is under way (the caller keeps repainting).
    pub fn poll(&mut self, params: &Params, auto: bool) -> bool {
        let stale = self.shown_for.as_ref() != Some(params);
        if stale && auto {
            match &self.pending {
                Some((p, _)) if p == params => {}
                _ => {
                    self.pending = Some((*params, Instant::now()));
                    self.cancelled = false;
                }
            }
        }
        if let Some((p, since)) = self.pending
            && since.elapsed() >= DWELL_DEBOUNCE
        {
            self.start(&p);
        }
        let mut finished = false;
        if let Some(job) = self.job.as_mut() {
            for msg in job.rx.try_iter() {
                match msg {
                    DwellMsg::Point {
                        freq_hz,
                        value,
                        bode,
                    } => {
                        job.done += 1;
                        let x = freq_hz.log10();
                        if value.norm().is_finite() {
                            self.mag.push(PlotPoint::new(x, db(value.norm())));
                            self.phase.push(PlotPoint::new(x, deg(value.arg())));
                        }
                        if let Some(b) = bode.filter(|b| b.norm().is_finite()) {
                            self.bode_mag.push(PlotPoint::new(x, db(b.norm() * 1e3)));
                            self.bode_phase.push(PlotPoint::new(x, deg(b.arg())));
                        }
                    }
                    DwellMsg::Failed { freq_hz, reason } => {
                        job.done += 1;
                        self.failures.push((freq_hz, reason));
                    }
                    DwellMsg::Finished => finished = true,
                }
            }
            if finished || job.done >= job.total {
                self.shown_for = Some(job.params);
                self.job = None;
                self.unwrap_phase_points();
            }
        }
        self.job.is_some() || self.pending.is_some()
    }

    /// Puts the dwell phases on the same branch as a continuous curve (each point is an
    /// independent `arg` in (−180°, 180°]).
    fn unwrap_phase_points(&mut self) {
        for curve in [&mut self.phase, &mut self.bode_phase] {
            let ph: Vec<f64> = curve.iter().map(|p| p.y.to_radians()).collect();
            for (p, u) in curve.iter_mut().zip(fr::unwrap_phase(&ph)) {
                p.y = u.to_degrees();
            }
        }
    }
}

/// Formats a log10-frequency axis mark as Hz.
fn hz_axis(mark: egui_plot::GridMark, _range: &std::ops::RangeInclusive<f64>) -> String {
    let f = 10f64.powf(mark.value);
    if (mark.value - mark.value.round()).abs() > 1e-6 {
        // Only label decades and 2, 5 multiples.
        let lead = f / 10f64.powf(mark.value.floor());
        if (lead - 2.0).abs() > 0.05 && (lead - 5.0).abs() > 0.05 {
            return String::new();
        }
    }
    if f >= 1.0 {
        format!("{f:.0}")
    } else {
        format!("{f:.1}")
    }
}

/// Grid marks at decades (strong) and 2…9 within each decade (faint).
fn log_grid(input: egui_plot::GridInput) -> Vec<egui_plot::GridMark> {
    let (lo, hi) = input.bounds;
    let mut out = Vec::new();
    let mut d = lo.floor() as i32 - 1;
    while (d as f64) <= hi + 1.0 {
        for k in 1..10 {
            let v = d as f64 + (k as f64).log10();
            if v >= lo && v <= hi {
                out.push(egui_plot::GridMark {
                    value: v,
                    step_size: if k == 1 { 1.0 } else { 0.1 },
                });
            }
        }
        d += 1;
    }
    out
}

fn freq_plot<'a>(id: &str, y_label: &str, unit: &'static str, height: f32) -> Plot<'a> {
    Plot::new(id)
        .height(height)
        .x_axis_label("frequency [Hz]")
        .custom_y_axes(vec![y_axis(y_label)])
        .x_axis_formatter(hz_axis)
        .x_grid_spacer(log_grid)
        .y_grid_spacer(move |input| y_marks(input, height))
        .label_formatter(move |pos| {
            Some(match pos {
                egui_plot::HoverPosition::NearDataPoint {
                    plot_name,
                    position,
                    ..
                } => format!(
                    "{plot_name}\n{:.2} Hz\n{:.1} {unit}",
                    10f64.powf(position.x),
                    position.y
                ),
                egui_plot::HoverPosition::Elsewhere { position } => {
                    format!("{:.2} Hz\n{:.1} {unit}", 10f64.powf(position.x), position.y)
                }
            })
        })
        .default_x_bounds(F_RANGE_HZ.0.log10(), F_RANGE_HZ.1.log10())
        .allow_scroll(false)
        .link_axis(egui::Id::unique("freq"), [true, false])
}

/// Colour of the simulated (sine dwell) points: the theme's strongest text colour (white on
/// dark, black on light), so points on the twin's blue line stay visible in either theme.
pub fn dwell_color(ui: &egui::Ui) -> Color32 {
    ui.visuals().strong_text_color()
}

/// What the frequency panel asks the app to do.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FreqAction {
    /// Nothing.
    None,
    /// Put back the last gains with which both loops were stable.
    ResetToStableGains,
}

/// View options of the frequency panel.
pub struct FreqView<'a> {
    /// Unwrapped phase (else wrapped into ±180°, the default).
    pub phase_unwrapped: &'a mut bool,
    /// Curves hidden in the legends.
    pub hidden: &'a mut BTreeSet<String>,
    /// The last stable gains, if they differ from the current ones.
    pub last_stable: Option<ControllerParams>,
}

/// The phase curve as shown: wrapped into ±180° (default) or unwrapped. Wrapping breaks the
/// line where it jumps, so no vertical stroke crosses the plot.
pub fn shown_phase(c: &[PlotPoint], unwrapped: bool) -> Vec<Vec<PlotPoint>> {
    if unwrapped {
        return vec![c.to_vec()];
    }
    let mut out: Vec<Vec<PlotPoint>> = vec![Vec::new()];
    let mut prev: Option<f64> = None;
    for p in c {
        let y = wrap_deg(p.y);
        if prev.is_some_and(|q| (y - q).abs() > 180.0) {
            out.push(Vec::new());
        }
        if let Some(seg) = out.last_mut() {
            seg.push(PlotPoint::new(p.x, y));
        }
        prev = Some(y);
    }
    out
}

/// Draws the stability banner (if needed), the four frequency plots and the dwell progress.
pub fn frequency_ui(
    ui: &mut egui::Ui,
    curves: &Curves,
    dwell: &mut Dwell,
    params: &Params,
    view: FreqView<'_>,
) -> FreqAction {
    let action = stability_ui(ui, curves, view.last_stable);
    let unstable = curves.unstable();
    ui.horizontal(|ui| {
        ui.label(RichText::new("Simulated twin (sine dwell):").strong());
        match dwell.progress() {
            _ if unstable => {
                ui.label("not shown: the closed loop is unstable");
            }
            Some((done, total)) => {
                ui.add(
                    egui::ProgressBar::new(done as f32 / total.max(1) as f32)
                        .desired_width(120.0)
                        .text(format!("{done}/{total}")),
                );
                if ui.button("Cancel").clicked() {
                    dwell.cancel();
                }
            }
            None if dwell.is_current(params) => {
                ui.label(format!("{} points, up to date", dwell.mag.len()));
            }
            None if dwell.cancelled => {
                ui.label("cancelled");
                if ui.button("Recompute").clicked() {
                    dwell.start(params);
                }
            }
            None => {
                ui.label("waiting for the sliders to settle…");
            }
        }
        if !unstable && !dwell.failures.is_empty() {
            ui.colored_label(
                Color32::from_rgb(200, 60, 40),
                format!("{} point(s) diverged", dwell.failures.len()),
            )
            .on_hover_text(
                dwell
                    .failures
                    .iter()
                    .map(|(f, r)| format!("{f:.2} Hz: {r}"))
                    .collect::<Vec<_>>()
                    .join("\n"),
            );
        }
        ui.separator();
        ui.checkbox(&mut *view.phase_unwrapped, "unwrapped phase")
            .on_hover_text("Off: phase wrapped into ±180°. On: continuous (unwrapped) phase.");
    });
    // Points simulated for other parameters, or for an unstable loop, are not shown.
    let show_dwell = !unstable && (dwell.is_current(params) || dwell.progress().is_some());
    let hidden = view.hidden;
    let unwrapped = *view.phase_unwrapped;
    let legend_h = 18.0 + ui.spacing().item_spacing.y;
    let h = ((ui.available_height() - 12.0 - 4.0 * legend_h) / 4.0).max(80.0);
    let crossings = curves.crossings.clone();
    // Unstable: the active curves are faint (not a steady state).
    let active = |c: Color32| if unstable { c.gamma_multiply(0.45) } else { c };
    let names = ["linear active", "twin active (linearised)", "passive"];
    let colors = [active(LINEAR), active(TWIN), PASSIVE];
    let styles = [
        (1.8, LineStyle::dashed_dense()),
        (2.4, LineStyle::Solid),
        (1.6, LineStyle::dotted_dense()),
    ];
    let dwell_name = "twin simulated (dwell)";
    let dwell_c = dwell_color(ui);
    let t_items = |ui: &mut egui::Ui, id: &str, hidden: &mut BTreeSet<String>| {
        let mut items: Vec<LegendItem<'_>> = (0..3)
            .map(|i| LegendItem {
                name: names[i],
                color: colors[i],
                swatch: Swatch::Line(styles[i].0, styles[i].1),
            })
            .collect();
        if show_dwell {
            items.push(LegendItem {
                name: dwell_name,
                color: dwell_c,
                swatch: Swatch::Marker,
            });
        }
        legend_ui(ui, id, &items, hidden);
    };

    t_items(ui, "t_mag", hidden);
    let hid = hidden.clone();
    freq_plot("t_mag", "|T| [dB]", "dB", h).show(ui, |pu| {
        pu.hline(
            egui_plot::HLine::new("|T| = 1", 0.0)
                .color(Color32::GRAY)
                .style(LineStyle::dashed_dense()),
        );
        for (i, c) in curves.t_mag.iter().enumerate() {
            if plotkit::hidden(&hid, "t_mag", names[i]) {
                continue;
            }
            pu.line(
                Line::new(names[i], c.as_slice())
                    .color(colors[i])
                    .width(styles[i].0)
                    .style(styles[i].1),
            );
        }
        if show_dwell && !plotkit::hidden(&hid, "t_mag", dwell_name) {
            pu.points(
                Points::new(dwell_name, dwell.mag.as_slice())
                    .color(dwell_c)
                    .shape(MarkerShape::Diamond)
                    .radius(5.0)
                    .filled(true),
            );
        }
        if unstable {
            // The |T| = 1 crossings of an unstable loop mean nothing.
            return;
        }
        // |T| = 1 crossings (end of the isolation band): a dotted line and a label.
        let top = curves.t_mag[0]
            .iter()
            .chain(&curves.t_mag[1])
            .map(|p| p.y)
            .fold(f64::NEG_INFINITY, f64::max)
            .max(0.0);
        for (i, cs) in crossings.iter().enumerate() {
            for c in cs.iter().filter(|c| c.rising).take(1) {
                let x = c.freq_hz.log10();
                pu.vline(
                    VLine::new("", x)
                        .color(colors[i].gamma_multiply(0.8))
                        .style(LineStyle::dotted_dense()),
                );
                pu.text(
                    egui_plot::Text::new(
                        "",
                        PlotPoint::new(x, top),
                        RichText::new(if i == 0 {
                            format!(" |T|=1 @ {:.2} Hz", c.freq_hz)
                        } else {
                            format!("|T|=1 @ {:.2} Hz ", c.freq_hz)
                        })
                        .color(colors[i])
                        .small(),
                    )
                    // Linear to the right of its line, twin to the left.
                    .anchor(if i == 0 {
                        egui::Align2::LEFT_TOP
                    } else {
                        egui::Align2::RIGHT_TOP
                    }),
                );
            }
        }
    });
    t_items(ui, "t_phase", hidden);
    let hid = hidden.clone();
    freq_plot("t_phase", "phase T [deg]", "°", h).show(ui, |pu| {
        for (i, c) in curves.t_phase.iter().enumerate() {
            if plotkit::hidden(&hid, "t_phase", names[i]) {
                continue;
            }
            for seg in shown_phase(c, unwrapped) {
                pu.line(
                    Line::new(names[i], PlotPoints::Owned(seg))
                        .color(colors[i])
                        .width(styles[i].0)
                        .style(styles[i].1),
                );
            }
        }
        if show_dwell && !plotkit::hidden(&hid, "t_phase", dwell_name) {
            let pts: Vec<PlotPoint> = shown_phase(&dwell.phase, unwrapped).concat();
            pu.points(
                Points::new(dwell_name, PlotPoints::Owned(pts))
                    .color(dwell_c)
                    .shape(MarkerShape::Diamond)
                    .radius(5.0)
                    .filled(true),
            );
        }
    });
    let b_names = ["twin (linearised)", "G(s)", BODE_DWELL_NAME];
    let b_items = |ui: &mut egui::Ui, id: &str, hidden: &mut BTreeSet<String>| {
        let mut items = vec![
            LegendItem {
                name: b_names[0],
                color: TWIN,
                swatch: Swatch::Line(2.4, LineStyle::Solid),
            },
            LegendItem {
                name: b_names[1],
                color: LINEAR,
                swatch: Swatch::Line(1.8, LineStyle::dashed_dense()),
            },
        ];
        if show_dwell {
            items.push(LegendItem {
                name: b_names[2],
                color: dwell_c,
                swatch: Swatch::Marker,
            });
        }
        legend_ui(ui, id, &items, hidden);
    };
    let bode = |ui: &mut egui::Ui,
                id: &str,
                y_label: &str,
                unit: &'static str,
                lines: &[Curve; 2],
                points: &[PlotPoint],
                phase: bool,
                hid: &BTreeSet<String>| {
        freq_plot(id, y_label, unit, h).show(ui, |pu| {
            let seg = |c: &[PlotPoint]| {
                if phase {
                    shown_phase(c, unwrapped)
                } else {
                    vec![c.to_vec()]
                }
            };
            if !plotkit::hidden(hid, id, b_names[0]) {
                for s in seg(&lines[0]) {
                    pu.line(
                        Line::new(b_names[0], PlotPoints::Owned(s))
                            .color(TWIN)
                            .width(2.4),
                    );
                }
            }
            if !plotkit::hidden(hid, id, b_names[1]) {
                for s in seg(&lines[1]) {
                    pu.line(
                        Line::new(b_names[1], PlotPoints::Owned(s))
                            .color(LINEAR)
                            .width(1.8)
                            .style(LineStyle::dashed_dense()),
                    );
                }
            }
            if show_dwell && !plotkit::hidden(hid, id, b_names[2]) {
                pu.points(
                    Points::new(b_names[2], PlotPoints::Owned(seg(points).concat()))
                        .color(dwell_c)
                        .shape(MarkerShape::Diamond)
                        .radius(5.0)
                        .filled(true),
                );
            }
        });
    };
    b_items(ui, "bode_mag", hidden);
    let hid = hidden.clone();
    bode(
        ui,
        "bode_mag",
        "|du/dt / V_in| [dB]",
        "dB re (mm/s)/V",
        &curves.bode_mag,
        &dwell.bode_mag,
        false,
        &hid,
    );
    b_items(ui, "bode_phase", hidden);
    let hid = hidden.clone();
    bode(
        ui,
        "bode_phase",
        "phase [deg]",
        "°",
        &curves.bode_phase,
        &dwell.bode_phase,
        true,
        &hid,
    );
    action
}

fn margin_text(m: &LoopMargins) -> String {
    let gm = if m.gain_margin.is_finite() && m.gain_margin <= 0.0 {
        // No gain keeps it stable (positive feedback).
        "−∞ dB".into()
    } else if m.gain_margin.is_finite() {
        format!("{:.1} dB", db(m.gain_margin))
    } else {
        "∞".into()
    };
    let pm = if m.phase_margin_deg.is_finite() {
        format!("{:.0}°", m.phase_margin_deg)
    } else if m.phase_margin_deg > 0.0 {
        "∞".into()
    } else {
        "−∞".into()
    };
    format!("GM {gm}, PM {pm}")
}

/// What to change to make the loop stable, from the stability condition itself: a positive
/// Kp is positive feedback at any gain (the margins are those of `V = Kp·u` with
/// `Kp < 0`); otherwise the smallest gain margin says how far |Kp| must come down.
pub fn remedy(curves: &Curves) -> String {
    let Some(p) = curves.params else {
        return String::new();
    };
    let kp = p.controller.kp_v_per_m;
    if kp > 0.0 {
        return format!(
            "Kp = {kp:.1} V/m feeds the stroke back with the wrong sign (positive feedback, \
             unstable at any gain): use a negative Kp."
        );
    }
    let unstable: Vec<&LoopMargins> = curves
        .margins
        .iter()
        .flatten()
        .filter(|m| !m.stable())
        .collect();
    let gm = unstable
        .iter()
        .map(|m| m.gain_margin)
        .filter(|g| g.is_finite() && *g > 0.0)
        .fold(f64::INFINITY, f64::min);
    if gm < 1.0 {
        let limit = kp.abs() * gm;
        format!(
            "|Kp| = {:.1} V/m is above the stability limit: keep Kp between −{limit:.1} and 0 V/m \
             (less |Kp| or a shorter τ).",
            kp.abs()
        )
    } else {
        "The phase margin is negative: reduce |Kp| or τ.".into()
    }
}

/// The stability line: margins, and a red banner with the remedy when a loop is unstable.
/// Returns the button the user pressed.
pub fn stability_ui(
    ui: &mut egui::Ui,
    curves: &Curves,
    last_stable: Option<ControllerParams>,
) -> FreqAction {
    let mut action = FreqAction::None;
    let [lin, twin] = &curves.margins;
    let (Some(lin), Some(twin)) = (lin, twin) else {
        return action;
    };
    if curves.unstable() {
        egui::Frame::new()
            .fill(Color32::from_rgb(180, 30, 30))
            .inner_margin(6.0)
            .corner_radius(4.0)
            .show(ui, |ui| {
                ui.set_width(ui.available_width());
                ui.label(
                    RichText::new(format!(
                        "UNSTABLE closed loop — twin: {}; linear: {}. {} The faint active \
                         curves are not a steady state.",
                        margin_text(twin),
                        margin_text(lin),
                        remedy(curves),
                    ))
                    .color(Color32::WHITE)
                    .strong(),
                );
                if let Some(g) = last_stable
                    && ui
                        .button("Reset to last stable gains")
                        .on_hover_text(format!(
                            "Kp = {:.2} V/m, Ki = {:.2} V·s/m, and the simulation from rest",
                            g.kp_v_per_m, g.ki_v_s_per_m
                        ))
                        .clicked()
                {
                    action = FreqAction::ResetToStableGains;
                }
            });
    } else {
        let edge = |cs: &[Crossing]| {
            cs.iter()
                .find(|c| c.rising)
                .map(|c| format!("{:.2} Hz", c.freq_hz))
                .unwrap_or_else(|| "none".into())
        };
        ui.label(format!(
            "Stable. Twin {}, isolation up to {}; linear {}, up to {}.",
            margin_text(twin),
            edge(&curves.crossings[1]),
            margin_text(lin),
            edge(&curves.crossings[0]),
        ));
    }
    action
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The cached plant responses reproduce the engine's linearised-twin responses for any
    /// gains and delay (the fast path used while dragging Kp, Ki, τ).
    #[test]
    fn cached_plant_matches_the_linearised_twin() {
        let mut p = Params::paper();
        p.controller.kp_v_per_m = -37.0;
        p.controller.ki_v_s_per_m = -3.0;
        p.plant.valve.tau_s = 0.021;
        let freqs = fr::log_space(0.2, 50.0, 9);
        let cache = PlantCache::new(&p, &freqs);
        let lin = fr::linearise_twin(&p);
        for (pt, &f) in cache.points.iter().zip(&freqs) {
            let (a, b) = (
                pt.transmissibility(&ControlLaw::new(&p), 0.021),
                lin.transmissibility(&ControlLaw::new(&p), f),
            );
            assert!(
                (a - b).norm() <= 1e-6 * b.norm().max(1e-3),
                "T at {f} Hz: {a} vs {b}"
            );
            let (a, b) = (pt.bode(0.021), lin.bode(f));
            assert!(
                (a - b).norm() <= 1e-6 * b.norm(),
                "bode at {f} Hz: {a} vs {b}"
            );
        }
        let law = ControlLaw::new(&p);
        let (a, b) = (cache.margins(&law, 0.021), fr::twin_margins(&lin, &law));
        assert!(
            (a.gain_margin - b.gain_margin).abs() <= 1e-6 * b.gain_margin.abs(),
            "{a:?} {b:?}"
        );
        assert!(
            (a.phase_margin_deg - b.phase_margin_deg).abs() < 1e-6,
            "{a:?} {b:?}"
        );
    }
}
