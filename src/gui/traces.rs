//! The live traces behind the scopes: bounded sliding windows of the engine's sample batches,
//! kept in display units as plot points so the scopes borrow them without copying, plus the
//! end-stop contact intervals and the running vibration metrics.

use super::units::{BAR_PER_PA, LPM_PER_M3_S, MM_PER_M};
use crate::analysis::metrics::{RunningMetrics, VibrationMetrics, seat_percent};
use crate::engine::{Batch, STREAM_RATE_HZ};
use crate::simulation::Sample;
use egui_plot::PlotPoint;

/// Default length of the scrolling window of the scopes, and the span of the rows kept for
/// the CSV export \[s\].
pub const WINDOW_S: f64 = 10.0;

/// Longest scope window offered, and the span of the scope channels kept \[s\].
pub const MAX_WINDOW_S: f64 = 60.0;

/// Samples left out of the running metrics after a reset or a parameter change \[s\].
pub const METRICS_SETTLE_S: f64 = 1.0;

/// One scope channel: a sliding window of points `(t [s], value [display unit])`.
#[derive(Debug, Clone, Default)]
pub struct Channel {
    pts: Vec<PlotPoint>,
    start: usize,
}

impl Channel {
    fn push(&mut self, t: f64, v: f64) {
        if v.is_finite() {
            self.pts.push(PlotPoint::new(t, v));
        }
    }

    /// Drops points before `t_min`; compacts the storage once half of it is stale.
    fn trim(&mut self, t_min: f64) {
        let keep_from = self.pts[self.start..].partition_point(|p| p.x < t_min);
        self.start += keep_from;
        if self.start > 4096 && self.start * 2 > self.pts.len() {
            self.pts.drain(..self.start);
            self.start = 0;
        }
    }

    fn clear(&mut self) {
        self.pts.clear();
        self.start = 0;
    }

    /// The points in the window, oldest first.
    pub fn points(&self) -> &[PlotPoint] {
        &self.pts[self.start..]
    }

    /// The points of the last `span_s` seconds before `t_now`, oldest first.
    pub fn window(&self, t_now: f64, span_s: f64) -> &[PlotPoint] {
        let pts = self.points();
        let from = pts.partition_point(|p| p.x < t_now - span_s);
        &pts[from..]
    }

    /// The newest value, if any.
    pub fn last(&self) -> Option<f64> {
        self.points().last().map(|p| p.y)
    }
}

/// The scope channels, in display units.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Ch {
    /// Platform acceleration ẍ [m/s²].
    PlatformAcc,
    /// Twin body acceleration ÿ [m/s²].
    TwinAcc,
    /// Linear-model body acceleration [m/s²].
    LinearAcc,
    /// Passive body acceleration [m/s²].
    PassiveAcc,
    /// Twin stroke u \[mm\].
    TwinU,
    /// Linear-model stroke \[mm\].
    LinearU,
    /// Passive stroke \[mm\].
    PassiveU,
    /// Twin upper chamber pressure p1 \[bar\].
    P1,
    /// Twin lower chamber pressure p2 \[bar\].
    P2,
    /// Twin hose-1 flow Q1 [L/min].
    Q1,
    /// Twin hose-2 flow Q2 [L/min].
    Q2,
    /// Twin command V_in \[V\].
    TwinVin,
    /// Linear-model command \[V\].
    LinearVin,
    /// Twin spool position x_v \[mm\].
    TwinXv,
    /// A/B reference twin body acceleration [m/s²].
    RefAcc,
    /// A/B reference twin stroke \[mm\].
    RefU,
    /// A/B reference twin command \[V\].
    RefVin,
}

const N_CH: usize = 17;

/// Running metrics of the platform and the three bodies.
#[derive(Debug, Clone)]
pub struct LiveMetrics {
    /// Platform acceleration.
    pub platform: RunningMetrics,
    /// Twin body acceleration.
    pub twin: RunningMetrics,
    /// Linear-model body acceleration.
    pub linear: RunningMetrics,
    /// Passive body acceleration.
    pub passive: RunningMetrics,
    /// A/B reference twin body acceleration.
    pub reference: RunningMetrics,
    /// Largest |u| of the live twin since the last metrics reset \[m\].
    pub max_u_twin: f64,
    /// Largest |u| of the reference twin since the last metrics reset \[m\].
    pub max_u_reference: f64,
}

impl LiveMetrics {
    fn new() -> Self {
        // The stream rate is a fixed, valid rate; the settle time is a valid constant.
        let m = RunningMetrics::with_settle(STREAM_RATE_HZ, METRICS_SETTLE_S)
            .unwrap_or_else(|e| panic!("stream rate {STREAM_RATE_HZ} Hz refused: {e}"));
        Self {
            platform: m.clone(),
            twin: m.clone(),
            linear: m.clone(),
            passive: m.clone(),
            reference: m,
            max_u_twin: 0.0,
            max_u_reference: 0.0,
        }
    }

    fn reset(&mut self) {
        for m in [
            &mut self.platform,
            &mut self.twin,
            &mut self.linear,
            &mut self.passive,
            &mut self.reference,
        ] {
            m.reset();
        }
        self.max_u_twin = 0.0;
        self.max_u_reference = 0.0;
    }

    /// The A/B comparison: live twin (A) against the reference twin (B), `None` before the
    /// reference has counted any data.
    pub fn ab(&self) -> Option<AbMetrics> {
        let (a, b) = (self.twin.metrics(), self.reference.metrics());
        (b.duration_s > 0.0).then_some(AbMetrics {
            a,
            b,
            max_u_a: self.max_u_twin,
            max_u_b: self.max_u_reference,
        })
    }

    /// `(name, metrics, SEAT %)` for twin, linear and passive, and the platform's metrics.
    pub fn rows(&self) -> ([(&'static str, VibrationMetrics, f64); 3], VibrationMetrics) {
        let p = self.platform.metrics();
        let row = |name, m: &RunningMetrics| {
            let v = m.metrics();
            (name, v, seat_percent(v.aw, p.aw))
        };
        (
            [
                row("twin", &self.twin),
                row("linear", &self.linear),
                row("passive", &self.passive),
            ],
            p,
        )
    }

    /// Seconds of data counted in the statistics.
    pub fn counted_s(&self) -> f64 {
        self.platform.metrics().duration_s
    }
}

/// Metrics of the live twin (A) and the A/B reference twin (B) over the same samples.
#[derive(Debug, Clone, Copy)]
pub struct AbMetrics {
    /// Live twin body acceleration.
    pub a: VibrationMetrics,
    /// Reference twin body acceleration.
    pub b: VibrationMetrics,
    /// Largest |u| of A \[m\].
    pub max_u_a: f64,
    /// Largest |u| of B \[m\].
    pub max_u_b: f64,
}

/// `(a − b)/b` in percent (NaN when `b` is 0).
pub fn difference_percent(a: f64, b: f64) -> f64 {
    if b == 0.0 {
        f64::NAN
    } else {
        100.0 * (a - b) / b
    }
}

/// Time-aligned samples of the three models (for CSV export and the schematic).
#[derive(Debug, Clone, Copy)]
pub struct Row {
    /// Display time \[s\] (continues across excitation restarts).
    pub t: f64,
    /// Twin sample.
    pub twin: Sample,
    /// Linear-model sample.
    pub linear: Sample,
    /// Passive sample.
    pub passive: Sample,
}

/// Everything the scopes show.
#[derive(Debug, Clone)]
pub struct Traces {
    channels: Vec<Channel>,
    rows: Vec<Row>,
    rows_start: usize,
    /// Contact intervals of the twin `(from, to)` in display time [s].
    contacts: Vec<(f64, f64)>,
    in_contact: bool,
    /// Offset added to engine time so the display time keeps increasing across restarts.
    epoch_offset: f64,
    restart_pending: bool,
    /// Latest display time [s].
    t_now: f64,
    /// Running metrics.
    pub metrics: LiveMetrics,
    /// Number of end-stop contacts reported by the engine since the last reset or
    /// parameter change (counted over the same window as the metrics).
    pub contact_count: usize,
    /// Display times of the parameter changes that restarted the metrics [s] (the last
    /// [`MAX_CHANGES`], marked in the scopes).
    changes: Vec<f64>,
}

/// Change markers kept.
const MAX_CHANGES: usize = 32;

impl Default for Traces {
    fn default() -> Self {
        Self::new()
    }
}

impl Traces {
    /// Empty traces.
    pub fn new() -> Self {
        Self {
            channels: vec![Channel::default(); N_CH],
            rows: Vec::new(),
            rows_start: 0,
            contacts: Vec::new(),
            in_contact: false,
            epoch_offset: 0.0,
            restart_pending: false,
            t_now: 0.0,
            metrics: LiveMetrics::new(),
            contact_count: 0,
            changes: Vec::new(),
        }
    }

    /// Forgets everything (reset, new excitation).
    pub fn clear(&mut self) {
        for c in &mut self.channels {
            c.clear();
        }
        self.rows.clear();
        self.rows_start = 0;
        self.contacts.clear();
        self.in_contact = false;
        self.epoch_offset = 0.0;
        self.restart_pending = false;
        self.t_now = 0.0;
        self.metrics.reset();
        self.contact_count = 0;
        self.changes.clear();
    }

    /// The excitation restarted from rest: the next samples continue the display time.
    pub fn mark_restart(&mut self) {
        self.restart_pending = true;
    }

    /// Restarts the running metrics and the contact count (after a parameter change) and
    /// marks the moment in the scopes: the numbers then describe the new parameters only,
    /// and the transient of the change shows where it came from. A drag that changes a
    /// value every frame leaves one marker, at its last change.
    pub fn reset_metrics(&mut self) {
        self.metrics.reset();
        self.contact_count = 0;
        match self.changes.last_mut() {
            Some(t) if self.t_now - *t < 0.5 => *t = self.t_now,
            _ => self.changes.push(self.t_now),
        }
        if self.changes.len() > MAX_CHANGES {
            self.changes.remove(0);
        }
    }

    /// Display times of the last parameter changes \[s\].
    pub fn changes(&self) -> &[f64] {
        &self.changes
    }

    /// The channel `ch`.
    pub fn channel(&self, ch: Ch) -> &Channel {
        &self.channels[ch as usize]
    }

    /// Twin contact intervals in the window \[s\].
    pub fn contacts(&self) -> &[(f64, f64)] {
        &self.contacts
    }

    /// The lowest and highest chamber pressure (both chambers) in the window \[Pa\].
    pub fn pressure_range_pa(&self) -> Option<(f64, f64)> {
        let pts = self.channel(Ch::P1).points().iter();
        let all = pts.chain(self.channel(Ch::P2).points());
        let (lo, hi) = all.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(p.y), hi.max(p.y))
        });
        (lo <= hi).then_some((lo / BAR_PER_PA, hi / BAR_PER_PA))
    }

    /// Latest display time \[s\].
    pub fn t_now(&self) -> f64 {
        self.t_now
    }

    /// The rows in the window, oldest first.
    pub fn rows(&self) -> &[Row] {
        &self.rows[self.rows_start..]
    }

    /// The newest row.
    pub fn last_row(&self) -> Option<&Row> {
        self.rows().last()
    }

    /// Appends a batch from the engine and trims the window.
    pub fn push_batch(&mut self, batch: &Batch) {
        let Some(first) = batch.twin.first() else {
            return;
        };
        if first.t + self.epoch_offset < self.t_now - 1e-9 {
            if self.restart_pending {
                self.epoch_offset = self.t_now;
            } else {
                // Samples from before a reset: start afresh.
                self.clear();
            }
        }
        self.restart_pending = false;
        let n = batch
            .twin
            .len()
            .min(batch.linear.len())
            .min(batch.passive.len());
        for i in 0..n {
            let (tw, li, pa) = (&batch.twin[i], &batch.linear[i], &batch.passive[i]);
            let t = tw.t + self.epoch_offset;
            let c = &mut self.channels;
            c[Ch::PlatformAcc as usize].push(t, tw.xdd);
            c[Ch::TwinAcc as usize].push(t, tw.ydd);
            c[Ch::LinearAcc as usize].push(t, li.ydd);
            c[Ch::PassiveAcc as usize].push(t, pa.ydd);
            c[Ch::TwinU as usize].push(t, tw.u * MM_PER_M);
            c[Ch::LinearU as usize].push(t, li.u * MM_PER_M);
            c[Ch::PassiveU as usize].push(t, pa.u * MM_PER_M);
            c[Ch::P1 as usize].push(t, tw.p1 * BAR_PER_PA);
            c[Ch::P2 as usize].push(t, tw.p2 * BAR_PER_PA);
            c[Ch::Q1 as usize].push(t, tw.q1 * LPM_PER_M3_S);
            c[Ch::Q2 as usize].push(t, tw.q2 * LPM_PER_M3_S);
            c[Ch::TwinVin as usize].push(t, tw.v_in);
            c[Ch::LinearVin as usize].push(t, li.v_in);
            c[Ch::TwinXv as usize].push(t, tw.xv * MM_PER_M);
            if tw.contact {
                match (self.in_contact, self.contacts.last_mut()) {
                    (true, Some(last)) => last.1 = t,
                    _ => self.contacts.push((t, t)),
                }
            }
            self.in_contact = tw.contact;
            for (m, v) in [
                (&mut self.metrics.platform, tw.xdd),
                (&mut self.metrics.twin, tw.ydd),
                (&mut self.metrics.linear, li.ydd),
                (&mut self.metrics.passive, pa.ydd),
            ] {
                if v.is_finite() {
                    m.push(v);
                }
            }
            // Same settling as the running metrics: nothing counted before it.
            if self.metrics.twin.metrics().duration_s > 0.0 && tw.u.is_finite() {
                self.metrics.max_u_twin = self.metrics.max_u_twin.max(tw.u.abs());
            }
            if let Some(r) = batch.reference.get(i) {
                c[Ch::RefAcc as usize].push(t, r.ydd);
                c[Ch::RefU as usize].push(t, r.u * MM_PER_M);
                c[Ch::RefVin as usize].push(t, r.v_in);
                if r.ydd.is_finite() {
                    self.metrics.reference.push(r.ydd);
                }
                if self.metrics.reference.metrics().duration_s > 0.0 && r.u.is_finite() {
                    self.metrics.max_u_reference = self.metrics.max_u_reference.max(r.u.abs());
                }
            }
            // A restarted run's first sample (at rest) falls on the instant of the last one
            // (the display time, like the toolbar's clock, continues without a gap): the
            // scopes draw both, the rows (an exported traces.csv, whose time must increase
            // strictly to be read back) keep the one already there.
            if self.rows().last().is_none_or(|r| t > r.t) {
                self.rows.push(Row {
                    t,
                    twin: *tw,
                    linear: *li,
                    passive: *pa,
                });
            }
            self.t_now = t;
        }
        self.trim();
    }

    fn trim(&mut self) {
        let t_channels = self.t_now - MAX_WINDOW_S;
        for c in &mut self.channels {
            c.trim(t_channels);
        }
        let t_min = self.t_now - WINDOW_S;
        let keep_from = self.rows[self.rows_start..].partition_point(|r| r.t < t_min);
        self.rows_start += keep_from;
        if self.rows_start > 4096 && self.rows_start * 2 > self.rows.len() {
            self.rows.drain(..self.rows_start);
            self.rows_start = 0;
        }
        self.contacts.retain(|&(_, b)| b >= t_channels);
    }
}
