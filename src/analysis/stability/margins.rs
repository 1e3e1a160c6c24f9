//! Every crossing of a loop gain: gain crossovers with their phase and delay margins, phase
//! crossovers with their gain margins, found on a grid refined around every lightly damped
//! pole and located by bisection on the loop gain itself.

use super::{MARGIN_F_MAX_HZ, MarginGrid, controller_poles};
use crate::analysis::frequency_response::{LinearisedModel, OpenLoop, log_space};
use crate::control::ControlLaw;
use num_complex::Complex64;
use std::f64::consts::PI;

/// A gain crossover, `|L(jω)| = 1`.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct GainCrossover {
    /// Frequency \[Hz\].
    pub freq_hz: f64,
    /// Phase margin `180° + ∠L` wrapped to (−180°, 180°] \[deg\].
    pub phase_margin_deg: f64,
    /// The extra delay that would put a closed-loop pole on the imaginary axis here \[s\].
    pub delay_margin_s: f64,
    /// |L| falls through 1 here: added delay moves the pole on the axis into the right half
    /// plane (destabilising). Where |L| rises through 1 the pole crosses the other way
    /// (Re ds/dδ = −ω·(d ln|L|/dω)/|…|², for `1 + L(s)·e^(−sδ) = 0`).
    pub destabilising: bool,
}

/// A phase crossover, `L(jω)` on the negative real axis.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct PhaseCrossover {
    /// Frequency \[Hz\].
    pub freq_hz: f64,
    /// Gain margin `−20·log10 |L|` \[dB\] (positive: the gain may rise by that much here;
    /// negative: lowering the gain by that much puts a pole on the axis).
    pub gain_margin_db: f64,
}

/// Every crossing of a loop gain `L` (negative-feedback form: `1 + L` in the closed loop's
/// denominator), in ascending frequency.
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize)]
pub struct LoopMargins {
    /// Every `|L| = 1` crossing.
    pub gain_crossovers: Vec<GainCrossover>,
    /// Every `∠L = −180°` crossing.
    pub phase_crossovers: Vec<PhaseCrossover>,
}

impl LoopMargins {
    /// The phase crossover closest to instability in gain (smallest |GM| in dB); `None` when
    /// the phase never reaches −180° (an infinite gain margin).
    pub fn worst_gain(&self) -> Option<PhaseCrossover> {
        self.phase_crossovers
            .iter()
            .copied()
            .min_by(|a, b| a.gain_margin_db.abs().total_cmp(&b.gain_margin_db.abs()))
    }

    /// The gain crossover closest to −1 in angle (smallest |phase margin|: a loop that pokes
    /// above |L| = 1 inside a resonance can cross with a negative margin and stay stable, and
    /// is then that many degrees of phase *lead* away from instability); `None` when |L|
    /// never reaches 1.
    pub fn worst_phase(&self) -> Option<GainCrossover> {
        self.gain_crossovers.iter().copied().min_by(|a, b| {
            a.phase_margin_deg
                .abs()
                .total_cmp(&b.phase_margin_deg.abs())
        })
    }

    /// The delay margin \[s\]: the smallest extra delay that makes the loop unstable, over the
    /// destabilising gain crossovers ([`GainCrossover::destabilising`]); ∞ without one.
    pub fn delay_margin_s(&self) -> f64 {
        self.gain_crossovers
            .iter()
            .filter(|c| c.destabilising)
            .map(|c| c.delay_margin_s)
            .fold(f64::INFINITY, f64::min)
    }

    /// The gain margin of [`Self::worst_gain`] \[dB\] (signed); ∞ without a phase crossover.
    pub fn gain_margin_db(&self) -> f64 {
        self.worst_gain()
            .map_or(f64::INFINITY, |c| c.gain_margin_db)
    }

    /// The phase margin of [`Self::worst_phase`] \[deg\]; ∞ without a gain crossover.
    pub fn phase_margin_deg(&self) -> f64 {
        self.worst_phase()
            .map_or(f64::INFINITY, |c| c.phase_margin_deg)
    }

    /// Every crossing of `loop_gain` sampled on `freqs_hz` (ascending), each located by
    /// bisection on `eval` (the same loop gain at any frequency).
    pub fn from_loop(
        freqs_hz: &[f64],
        loop_gain: &[Complex64],
        eval: impl Fn(f64) -> Complex64,
    ) -> Self {
        let mut out = Self::default();
        let n = freqs_hz.len().min(loop_gain.len());
        let finite = |c: &Complex64| c.re.is_finite() && c.im.is_finite() && c.norm() > 0.0;
        for i in 1..n {
            let (fa, fb) = (freqs_hz[i - 1], freqs_hz[i]);
            let (la, lb) = (loop_gain[i - 1], loop_gain[i]);
            if !(finite(&la) && finite(&lb)) {
                continue;
            }
            // |L| through 1.
            let ga = la.norm().ln();
            if ga * lb.norm().ln() <= 0.0 && !(ga == 0.0 && i > 1) {
                let f = bisect(fa, fb, |f| eval(f).norm().ln(), ga);
                let l = eval(f);
                let pm = wrap_deg(180.0 + l.arg().to_degrees());
                let w = 2.0 * PI * f;
                out.gain_crossovers.push(GainCrossover {
                    freq_hz: f,
                    phase_margin_deg: pm,
                    delay_margin_s: pm.rem_euclid(360.0).to_radians() / w,
                    destabilising: lb.norm() < la.norm(),
                });
            }
            // L through the negative real axis: Im L changes sign with Re L < 0 between.
            if la.im * lb.im <= 0.0 && !(la.im == 0.0 && i > 1) && (la.re < 0.0 || lb.re < 0.0) {
                let f = bisect(fa, fb, |f| eval(f).im, la.im);
                let l = eval(f);
                if l.re < 0.0 {
                    out.phase_crossovers.push(PhaseCrossover {
                        freq_hz: f,
                        gain_margin_db: -20.0 * l.norm().log10(),
                    });
                }
            }
        }
        out
    }
}

/// Wraps an angle to (−180°, 180°] [deg].
fn wrap_deg(a: f64) -> f64 {
    let w = (a + 180.0).rem_euclid(360.0) - 180.0;
    if w == -180.0 { 180.0 } else { w }
}

/// A zero of `g` between `a` and `b` (Hz, bisection on log f; `ga` = g(a)).
fn bisect(a: f64, b: f64, g: impl Fn(f64) -> f64, ga: f64) -> f64 {
    let (mut lo, mut hi, mut glo) = (a.ln(), b.ln(), ga);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        let gm = g(mid.exp());
        if !gm.is_finite() {
            break;
        }
        if glo * gm <= 0.0 {
            hi = mid;
        } else {
            lo = mid;
            glo = gm;
        }
        if hi - lo < 1e-13 {
            break;
        }
    }
    (0.5 * (lo + hi)).exp()
}

/// The margin grid \[Hz\]: 3000 log points from 0.01 Hz to [`MARGIN_F_MAX_HZ`], plus, around
/// every pole with damping ratio below 0.3 in that range, points `|σ|/8` apart over `±40·|σ|`
/// of its damped frequency (σ its real part), so that a resonance of any sharpness is sampled
/// across its width.
pub fn margin_grid(poles: &[Complex64]) -> Vec<f64> {
    let mut f = log_space(0.01, MARGIN_F_MAX_HZ, 3000);
    let (w_lo, w_hi) = (2.0 * PI * 0.01, 2.0 * PI * MARGIN_F_MAX_HZ);
    for p in poles {
        let wd = p.im.abs();
        let sigma = p.re.abs().max(1e-9 * wd);
        if !(wd > w_lo && wd < w_hi) || sigma > 0.3 * p.norm() {
            continue;
        }
        for k in -320..=320 {
            let w = wd + sigma * k as f64 / 8.0;
            if w > w_lo && w < w_hi {
                f.push(w / (2.0 * PI));
            }
        }
    }
    f.sort_by(f64::total_cmp);
    f.dedup_by(|a, b| (*a - *b).abs() <= 1e-12 * b.abs());
    f
}

impl LoopMargins {
    /// Every crossing of the loop of `plant` (delay excluded; `grid` evaluated on it) with
    /// `law` and the command delay `tau_s`.
    pub fn on_grid(
        plant: &LinearisedModel,
        grid: &MarginGrid,
        law: &ControlLaw,
        tau_s: f64,
    ) -> Self {
        let extra = controller_poles(law);
        // The plant's cached grid, borrowed; a grid of its own only when the controller adds
        // poles (the Smith predictor's inner loop).
        let refined: (Vec<f64>, Vec<OpenLoop>);
        let (freqs, points) = if extra.is_empty() {
            (&grid.freqs_hz, &grid.points)
        } else {
            let mut f = grid.freqs_hz.clone();
            f.extend(margin_grid(&extra));
            f.sort_by(f64::total_cmp);
            f.dedup();
            let p = f.iter().map(|&x| plant.open_loop(x)).collect();
            refined = (f, p);
            (&refined.0, &refined.1)
        };
        let loop_gain: Vec<Complex64> = points.iter().map(|p| p.loop_gain(law, tau_s)).collect();
        Self::from_loop(freqs, &loop_gain, |f| {
            plant.open_loop(f).loop_gain(law, tau_s)
        })
    }
}
