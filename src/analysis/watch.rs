//! The running twin watches itself: a self-excited oscillation or sustained growth of the body
//! acceleration, and chamber pressures below zero, found in the samples as they stream. A
//! linear verdict at rest can say "stable" while the running twin rings: a calibrated plant
//! with more compliance, a state far from rest, a limit cycle. This catches what the twin does.
//!
//! # How
//! `ÿ` and `ẍ` are high-passed (second-order, [`HIGHPASS_HZ`]: above the ride band, below the
//! oil-column and valve modes, ≈ 45–90 Hz) and their RMS taken over windows of
//! [`WINDOW_S`]. A window is *self-excited* when the high-passed `ÿ` exceeds
//! [`FLOOR_M_S2`] and [`AMPLIFICATION`] times the high-passed `ẍ` (the platform does not
//! drive it). [`SUSTAINED_WINDOWS`] self-excited windows in a row are a limit cycle;
//! a high-passed RMS that rises window on window over as many windows, by [`GROWTH_FACTOR`]
//! overall, is growth. Either is reported once, with the frequency counted from the zero
//! crossings of `ÿ` high-passed at [`FREQ_HIGHPASS_HZ`] (so that a slower, saturated
//! oscillation is not read at a harmonic), until [`Watch::reset`].

use crate::dsp::{Biquad, BiquadState};

/// High-pass corner \[Hz\].
pub const HIGHPASS_HZ: f64 = 30.0;
/// High-pass corner of the signal whose zero crossings give the frequency \[Hz\].
pub const FREQ_HIGHPASS_HZ: f64 = 8.0;
/// Window length \[s\].
pub const WINDOW_S: f64 = 0.5;
/// Smallest high-passed ÿ RMS that counts [m/s²].
pub const FLOOR_M_S2: f64 = 0.5;
/// High-passed ÿ over high-passed ẍ above which the twin drives itself [-].
pub const AMPLIFICATION: f64 = 10.0;
/// Windows in a row (2 s).
pub const SUSTAINED_WINDOWS: usize = 4;
/// Overall rise over those windows that counts as growth [-].
pub const GROWTH_FACTOR: f64 = 2.0;
/// Smallest high-passed ÿ RMS at the end of a growth [m/s²].
pub const GROWTH_FLOOR_M_S2: f64 = 0.05;

/// What the watch found.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub enum Finding {
    /// A self-excited oscillation that does not decay.
    LimitCycle {
        /// Frequency \[Hz\].
        freq_hz: f64,
        /// RMS of the high-passed ÿ over the last window [m/s²].
        rms_m_s2: f64,
        /// Time \[s\].
        t: f64,
    },
    /// The oscillation grows window on window.
    Growth {
        /// Frequency \[Hz\].
        freq_hz: f64,
        /// Rise of the high-passed ÿ RMS over the windows [-].
        factor: f64,
        /// RMS of the high-passed ÿ over the last window [m/s²].
        rms_m_s2: f64,
        /// Time \[s\].
        t: f64,
    },
    /// A chamber pressure below zero: outside the model (it has no cavitation).
    NegativePressure {
        /// Which chamber (1 or 2).
        chamber: u8,
        /// The pressure \[Pa\].
        p_pa: f64,
        /// Time \[s\].
        t: f64,
    },
}

impl std::fmt::Display for Finding {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            Finding::LimitCycle {
                freq_hz,
                rms_m_s2,
                t,
            } => write!(
                f,
                "the running twin oscillates at {freq_hz:.1} Hz and does not decay (ÿ {rms_m_s2:.2} \
                 m/s² RMS above {HIGHPASS_HZ:.0} Hz, not driven by the platform; since t = {:.1} s)",
                t - WINDOW_S * SUSTAINED_WINDOWS as f64
            ),
            Finding::Growth {
                freq_hz,
                factor,
                rms_m_s2,
                t,
            } => write!(
                f,
                "the running twin's oscillation at {freq_hz:.1} Hz grows (×{factor:.1} in {:.1} s, \
                 now ÿ {rms_m_s2:.2} m/s² RMS above {HIGHPASS_HZ:.0} Hz; t = {t:.1} s)",
                WINDOW_S * SUSTAINED_WINDOWS as f64
            ),
            Finding::NegativePressure { chamber, p_pa, t } => write!(
                f,
                "chamber {chamber} pressure fell to {:.1} bar at t = {t:.2} s: below zero the \
                 model is outside its range (it has no cavitation)",
                p_pa / 1e5
            ),
        }
    }
}

/// The watch over one twin's streamed samples.
#[derive(Debug, Clone)]
pub struct Watch {
    dt: f64,
    hp_y: BiquadState,
    hp_x: BiquadState,
    /// ÿ high-passed at [`FREQ_HIGHPASS_HZ`], whose zero crossings give the frequency (the
    /// detection high-pass would count a slower oscillation's harmonics instead).
    hp_f: BiquadState,
    last_f: f64,
    per_window: usize,
    n: usize,
    sum_y: f64,
    sum_x: f64,
    crossings: usize,
    /// High-passed ÿ RMS and self-excited flag of the recent windows.
    history: Vec<(f64, bool, f64)>,
    pressure_reported: bool,
    oscillation_reported: bool,
}

/// A second-order high-pass (`x − low-pass(x)` has a first-order tail; this is the bilinear
/// high-pass of the same corner and Q).
fn highpass(dt: f64, fc: f64) -> Biquad {
    let lp = Biquad::lowpass(dt, fc, std::f64::consts::FRAC_1_SQRT_2);
    let k = (std::f64::consts::PI * fc * dt).tan();
    // Same denominator; numerator (1, −2, 1)·norm with norm = b0_lp / k².
    let norm = lp.b[0] / (k * k);
    Biquad {
        b: [norm, -2.0 * norm, norm],
        a: lp.a,
    }
}

impl Watch {
    /// A watch for samples `dt` \[s\] apart.
    pub fn new(dt: f64) -> Self {
        let hp = highpass(dt, HIGHPASS_HZ);
        Self {
            dt,
            hp_y: BiquadState::new(hp),
            hp_x: BiquadState::new(hp),
            hp_f: BiquadState::new(highpass(dt, FREQ_HIGHPASS_HZ)),
            last_f: 0.0,
            per_window: ((WINDOW_S / dt).round() as usize).max(8),
            n: 0,
            sum_y: 0.0,
            sum_x: 0.0,
            crossings: 0,
            history: Vec::new(),
            pressure_reported: false,
            oscillation_reported: false,
        }
    }

    /// Forgets everything (a reset, new gains or a new excitation).
    pub fn reset(&mut self) {
        *self = Self::new(self.dt);
    }

    /// Takes one sample (time \[s\], ẍ, ÿ [m/s²], p1, p2 \[Pa\]); returns a finding once.
    pub fn push(&mut self, t: f64, xdd: f64, ydd: f64, p1: f64, p2: f64) -> Option<Finding> {
        if !self.pressure_reported {
            for (chamber, p) in [(1, p1), (2, p2)] {
                if p < 0.0 {
                    self.pressure_reported = true;
                    return Some(Finding::NegativePressure {
                        chamber,
                        p_pa: p,
                        t,
                    });
                }
            }
        }
        let y = self.hp_y.step(ydd);
        let x = self.hp_x.step(xdd);
        let yf = self.hp_f.step(ydd);
        if !(y.is_finite() && x.is_finite() && yf.is_finite()) {
            return None;
        }
        self.sum_y += y * y;
        self.sum_x += x * x;
        if (yf > 0.0) != (self.last_f > 0.0) && self.n > 0 {
            self.crossings += 1;
        }
        self.last_f = yf;
        self.n += 1;
        if self.n < self.per_window {
            return None;
        }
        let rms_y = (self.sum_y / self.n as f64).sqrt();
        let rms_x = (self.sum_x / self.n as f64).sqrt();
        let freq = self.crossings as f64 / 2.0 / (self.n as f64 * self.dt);
        let excited = rms_y > FLOOR_M_S2 && rms_y > AMPLIFICATION * rms_x;
        self.n = 0;
        self.sum_y = 0.0;
        self.sum_x = 0.0;
        self.crossings = 0;
        self.history.push((rms_y, excited, freq));
        if self.history.len() > SUSTAINED_WINDOWS {
            self.history.remove(0);
        }
        if self.oscillation_reported || self.history.len() < SUSTAINED_WINDOWS {
            return None;
        }
        let first = self.history[0].0;
        let rising = self.history.windows(2).all(|w| w[1].0 > w[0].0);
        let factor = rms_y / first.max(f64::MIN_POSITIVE);
        let driven_by_platform = rms_y <= AMPLIFICATION * rms_x;
        if rising && factor >= GROWTH_FACTOR && rms_y > GROWTH_FLOOR_M_S2 && !driven_by_platform {
            self.oscillation_reported = true;
            return Some(Finding::Growth {
                freq_hz: freq,
                factor,
                rms_m_s2: rms_y,
                t,
            });
        }
        let decaying = rms_y < 0.7 * first;
        if self.history.iter().all(|h| h.1) && !decaying {
            self.oscillation_reported = true;
            return Some(Finding::LimitCycle {
                freq_hz: freq,
                rms_m_s2: rms_y,
                t,
            });
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    const DT: f64 = 1.0 / 500.0;

    fn run(f: impl Fn(f64) -> (f64, f64), seconds: f64) -> Option<Finding> {
        let mut w = Watch::new(DT);
        let mut found = None;
        for k in 0..(seconds / DT) as usize {
            let t = k as f64 * DT;
            let (x, y) = f(t);
            if let Some(fnd) = w.push(t, x, y, 5e6, 5e6) {
                found.get_or_insert(fnd);
            }
        }
        found
    }

    /// An 85 Hz oscillation of constant amplitude with the platform still is a limit cycle at
    /// 85 Hz; growing at 0.5 1/s it is growth; decaying, or driven by the platform, nothing.
    #[test]
    fn finds_limit_cycles_and_growth_and_nothing_else() {
        let osc =
            |a: f64, s: f64| move |t: f64| (0.0, a * (s * t).exp() * (2.0 * PI * 85.0 * t).sin());
        match run(osc(5.0, 0.0), 4.0) {
            Some(Finding::LimitCycle { freq_hz, .. }) => assert!((freq_hz - 85.0).abs() < 2.0),
            other => panic!("{other:?}"),
        }
        match run(osc(0.05, 0.6), 5.0) {
            Some(Finding::Growth { freq_hz, .. }) => assert!((freq_hz - 85.0).abs() < 2.0),
            other => panic!("{other:?}"),
        }
        assert_eq!(run(osc(5.0, -1.0), 6.0), None);
        // A large saturated (square) oscillation at 15 Hz is read at 15 Hz, not at a harmonic.
        let square = |t: f64| (0.0, 80.0 * (2.0 * PI * 15.0 * t).sin().signum());
        match run(square, 4.0) {
            Some(Finding::LimitCycle { freq_hz, .. }) => {
                assert!((freq_hz - 15.0).abs() < 1.0, "{freq_hz}")
            }
            other => panic!("{other:?}"),
        }
        // The platform shakes at 60 Hz and the seat follows it: not self-excited.
        let driven = |t: f64| {
            let s = (2.0 * PI * 60.0 * t).sin();
            (3.0 * s, 4.0 * s)
        };
        assert_eq!(run(driven, 4.0), None);
        // A ride's band (≤ 20 Hz) at 3 m/s² does not pass the high-pass.
        let ride = |t: f64| {
            (
                0.0,
                3.0 * (2.0 * PI * 4.0 * t).sin() + (2.0 * PI * 15.0 * t).sin(),
            )
        };
        assert_eq!(run(ride, 4.0), None);
    }

    #[test]
    fn negative_pressure_is_reported_once() {
        let mut w = Watch::new(DT);
        assert!(matches!(
            w.push(0.1, 0.0, 0.0, -2e4, 5e6),
            Some(Finding::NegativePressure { chamber: 1, .. })
        ));
        assert_eq!(w.push(0.2, 0.0, 0.0, -3e4, 5e6), None);
    }
}
