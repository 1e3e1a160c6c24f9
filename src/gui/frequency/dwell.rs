//! The simulated twin's sine dwell in the background: a [`Job`] steps the twin at each dwell
//! frequency, one frequency per step (on the desktop's thread, or in the web's frames), and
//! streams the points back; cancelled when superseded.

use super::*;
use crate::gui::job::{Job, JobCtx, Step, Waker};

/// One simulated dwell frequency, streamed back by the dwell job.
#[derive(Debug, PartialEq)]
pub enum DwellPoint {
    /// The twin's transmissibility there.
    Point {
        /// Frequency \[Hz\].
        freq_hz: f64,
        /// The twin's transmissibility ÿ/ẍ [-] by a sine dwell.
        value: Complex64,
        /// The plant's `u̇/V_in` [m/(s·V)] by an open-loop dwell, up to
        /// [`BODE_DWELL_MAX_HZ`](super::BODE_DWELL_MAX_HZ) (`None` above).
        bode: Option<Complex64>,
    },
    /// The run at that frequency failed.
    Failed {
        /// Frequency \[Hz\].
        freq_hz: f64,
        /// Why, for the user.
        reason: String,
    },
}

/// The dwell sweep of the twin with `p` as job steps: one frequency of `freqs` per step, its
/// point sent as it is done; stops at the next step when cancelled.
pub fn dwell_steps(
    p: Params,
    freqs: Vec<f64>,
) -> impl FnMut(&JobCtx<DwellPoint>) -> Step<()> + Send + 'static {
    let mut left = freqs.into_iter();
    let opt = DwellOptions::default();
    move |ctx| {
        if ctx.cancelled() {
            return Step::Done(Err("cancelled".into()));
        }
        let Some(f) = left.next() else {
            return Step::Done(Ok(()));
        };
        let r = std::panic::catch_unwind(|| {
            let t = sine_dwell::simulated_transmissibility(&p, ModelKind::Twin, f, &opt)?;
            let b = if f <= BODE_DWELL_MAX_HZ {
                Some(sine_dwell::simulated_bode(
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
        let point = match r {
            Ok(Ok((value, bode))) => DwellPoint::Point {
                freq_hz: f,
                value,
                bode,
            },
            Ok(Err(e)) => DwellPoint::Failed {
                freq_hz: f,
                reason: e.to_string(),
            },
            Err(_) => DwellPoint::Failed {
                freq_hz: f,
                reason: "internal error in the simulation".into(),
            },
        };
        if ctx.send(point) {
            Step::More
        } else {
            Step::Done(Err("cancelled".into()))
        }
    }
}

/// A running sine-dwell sweep of the twin (the app's [`Job`]: dropped, it stops after its
/// current point).
struct DwellJob {
    params: Params,
    job: Job<(), DwellPoint>,
    total: usize,
    done: usize,
}

/// The simulated (sine dwell) points of the twin: transmissibility, and u̇/V_in up to
/// [`BODE_DWELL_MAX_HZ`].
pub struct Dwell {
    job: Option<DwellJob>,
    /// Parameters of the shown points.
    shown_for: Option<Params>,
    /// |T| \[dB\] points.
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
    /// Repaints the app when a point arrives.
    waker: Waker,
}

impl Dwell {
    /// No points yet; `waker` repaints the app when a point arrives.
    pub fn new(waker: Waker) -> Self {
        Self {
            job: None,
            shown_for: None,
            mag: Curve::new(),
            phase: Curve::new(),
            bode_mag: Curve::new(),
            bode_phase: Curve::new(),
            failures: Vec::new(),
            pending: None,
            cancelled: false,
            waker,
        }
    }

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
        let p = *params;
        let total = freqs.len();
        let job = Job::spawn_steps("seat-twin-dwell", self.waker.clone(), dwell_steps(p, freqs));
        self.job = Some(DwellJob {
            params: p,
            job,
            total,
            done: 0,
        });
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
        if let Some(job) = self.job.as_mut() {
            // The end first, then the points: every point is sent before the end, so none
            // sent before it is missed.
            let end = job.job.poll();
            for point in job.job.drain() {
                job.done += 1;
                match point {
                    DwellPoint::Point {
                        freq_hz,
                        value,
                        bode,
                    } => {
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
                    DwellPoint::Failed { freq_hz, reason } => {
                        self.failures.push((freq_hz, reason));
                    }
                }
            }
            // An error at the end is a thread that could not start, or ended early.
            let ended = match end {
                Some(Ok(())) => true,
                Some(Err(reason)) => {
                    if job.done < job.total {
                        self.failures.push((0.0, reason));
                    }
                    true
                }
                None => false,
            };
            if ended || job.done >= job.total {
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
