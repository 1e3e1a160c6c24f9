//! Second-order IIR sections (biquads) and their design from analogue prototypes,
//! Butterworth low-passes of any order, and zero-phase (forward–backward) filtering of whole
//! records.
//!
//! A [`Biquad`] holds the coefficients of `H(z) = (b0 + b1·z⁻¹ + b2·z⁻²) / (1 + a1·z⁻¹ +
//! a2·z⁻²)`. It runs in three ways, each where it fits:
//!
//! * [`BiquadState`], sample by sample from rest, in transposed direct form II: streaming
//!   filters that start at rest (the ISO 2631 Wk weighting of a live signal);
//! * [`SettledCascade`], sample by sample, each section settled at its first input: a data
//!   acquisition's anti-alias filter on the twin's channels during a replay;
//! * [`Biquad::pass`], over a whole slice in place, forward or backward, started in steady
//!   state at the slice's first (or last) value, in direct form I: the building block of the
//!   zero-phase filters, whose ends then carry no start-up transient.
//!
//! Butterworth low-pass sections come from the bilinear transform with the corner pre-warped
//! (`k = tan(π·fc·dt)`), so the digital corner is exactly at `fc`. A zero-phase filter runs a
//! cascade forward and then backward: its gain is `|H|²` and its phase is zero at every
//! frequency.

use num_complex::Complex64;
use std::f64::consts::PI;

/// Coefficients of a second-order IIR section, `a0 = 1`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Biquad {
    /// Numerator `b0, b1, b2`.
    pub b: [f64; 3],
    /// Denominator `a1, a2`.
    pub a: [f64; 2],
}

impl Biquad {
    /// Second-order Butterworth-type low-pass with quality factor `q` at the corner `fc` \[Hz\]
    /// for the sample step `dt` \[s\] (bilinear transform, corner pre-warped). `q = 1/√2` is the
    /// second-order Butterworth filter; the sections of a higher-order Butterworth filter use
    /// `q = 1/(2·cos θᵢ)` ([`butterworth_sections`]).
    pub fn lowpass(dt: f64, fc: f64, q: f64) -> Self {
        let k = (PI * fc * dt).tan();
        let norm = 1.0 / (1.0 + k / q + k * k);
        let b0 = k * k * norm;
        Self {
            b: [b0, 2.0 * b0, b0],
            a: [2.0 * (k * k - 1.0) * norm, (1.0 - k / q + k * k) * norm],
        }
    }

    /// First-order low-pass `1/(1 + s/ωc)` at the corner `fc` \[Hz\] for the sample step `dt`
    /// \[s\] (bilinear transform, corner pre-warped), as a section with `b2 = a2 = 0`: the real
    /// pole of an odd-order Butterworth filter ([`butterworth_sections`]).
    pub fn lowpass_first_order(dt: f64, fc: f64) -> Self {
        let k = (PI * fc * dt).tan();
        let b0 = k / (1.0 + k);
        Self {
            b: [b0, b0, 0.0],
            a: [(k - 1.0) / (k + 1.0), 0.0],
        }
    }

    /// Frequency response `H(e^{jθ})` at the normalised angular frequency `theta` =
    /// `2π·f·dt` [rad/sample].
    pub fn response(&self, theta: f64) -> Complex64 {
        let z1 = Complex64::from_polar(1.0, -theta);
        let z2 = z1 * z1;
        (self.b[0] + self.b[1] * z1 + self.b[2] * z2) / (1.0 + self.a[0] * z1 + self.a[1] * z2)
    }

    /// `|H(e^{jθ})|` at the normalised angular frequency `theta` [rad/sample].
    pub fn gain(&self, theta: f64) -> f64 {
        // Evaluate c0 + c1·e^{-jθ} + c2·e^{-2jθ} as magnitudes (as accurate as the complex
        // quotient, and what the Wk filter's accuracy table was measured with).
        let eval = |c0: f64, c1: f64, c2: f64| {
            let re = c0 + c1 * theta.cos() + c2 * (2.0 * theta).cos();
            let im = -c1 * theta.sin() - c2 * (2.0 * theta).sin();
            re.hypot(im)
        };
        eval(self.b[0], self.b[1], self.b[2]) / eval(1.0, self.a[0], self.a[1])
    }

    /// Filters `x` in place, forward or (`reverse`) backward, started in steady state at the
    /// first value it meets (so a constant passes unchanged through a section of unit DC
    /// gain). Direct form I.
    pub fn pass(&self, x: &mut [f64], reverse: bool) {
        let n = x.len();
        if n == 0 {
            return;
        }
        let [b0, b1, b2] = self.b;
        let [a1, a2] = self.a;
        let first = if reverse { x[n - 1] } else { x[0] };
        let (mut x1, mut x2, mut y1, mut y2) = (first, first, first, first);
        let mut step = |v: &mut f64| {
            let x0 = *v;
            let y0 = b0 * x0 + b1 * x1 + b2 * x2 - a1 * y1 - a2 * y2;
            x2 = x1;
            x1 = x0;
            y2 = y1;
            y1 = y0;
            *v = y0;
        };
        if reverse {
            x.iter_mut().rev().for_each(&mut step);
        } else {
            x.iter_mut().for_each(&mut step);
        }
    }
}

/// A cascade of [`Biquad`] sections of unit DC gain running sample by sample, started in
/// steady state at its first input (direct form I, as [`Biquad::pass`] starts): an analogue
/// filter that has settled on its input before the record starts.
#[derive(Debug, Clone, PartialEq)]
pub struct SettledCascade {
    sections: Vec<Biquad>,
    /// Each section's last two inputs and outputs; `None` before the first input.
    z: Option<Vec<[f64; 4]>>,
}

impl SettledCascade {
    /// The cascade of `sections`, before its first input.
    pub fn new(sections: Vec<Biquad>) -> Self {
        Self { sections, z: None }
    }

    /// Filters one sample.
    pub fn step(&mut self, x: f64) -> f64 {
        let z = self
            .z
            .get_or_insert_with(|| vec![[x; 4]; self.sections.len()]);
        let mut v = x;
        for (c, z) in self.sections.iter().zip(z.iter_mut()) {
            let [x1, x2, y1, y2] = *z;
            let y = c.b[0] * v + c.b[1] * x1 + c.b[2] * x2 - c.a[0] * y1 - c.a[1] * y2;
            *z = [v, x1, y, y1];
            v = y;
        }
        v
    }
}

/// A [`Biquad`] running sample by sample from rest (transposed direct form II).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BiquadState {
    /// The section's coefficients.
    pub coeffs: Biquad,
    s: [f64; 2],
}

impl BiquadState {
    /// The section at rest.
    pub fn new(coeffs: Biquad) -> Self {
        Self {
            coeffs,
            s: [0.0; 2],
        }
    }

    /// Filters one sample.
    pub fn step(&mut self, x: f64) -> f64 {
        let Biquad { b, a } = self.coeffs;
        let y = b[0] * x + self.s[0];
        self.s[0] = b[1] * x - a[0] * y + self.s[1];
        self.s[1] = b[2] * x - a[1] * y;
        y
    }

    /// Returns the section to rest.
    pub fn reset(&mut self) {
        self.s = [0.0; 2];
    }
}

/// One second-order analogue section `(n0 + n1·s + n2·s²) / (d0 + d1·s + d2·s²)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AnalogSection {
    /// Numerator `n0, n1, n2`.
    pub num: [f64; 3],
    /// Denominator `d0, d1, d2`.
    pub den: [f64; 3],
}

impl AnalogSection {
    /// Magnitude [-] and phase \[rad\] at the angular frequency `w` [rad/s].
    pub fn response(&self, w: f64) -> (f64, f64) {
        let eval = |c: &[f64; 3]| (c[0] - c[2] * w * w, c[1] * w);
        let (nr, ni) = eval(&self.num);
        let (dr, di) = eval(&self.den);
        (nr.hypot(ni) / dr.hypot(di), ni.atan2(nr) - di.atan2(dr))
    }

    /// Digital section by the bilinear transform `s = k·(1 − z⁻¹)/(1 + z⁻¹)` (`k = 2·fs`;
    /// pre-warp the section's frequencies beforehand to place them exactly).
    pub fn bilinear(&self, k: f64) -> Biquad {
        let map = |c: &[f64; 3]| {
            [
                c[0] + c[1] * k + c[2] * k * k,
                2.0 * (c[0] - c[2] * k * k),
                c[0] - c[1] * k + c[2] * k * k,
            ]
        };
        let b = map(&self.num);
        let a = map(&self.den);
        Biquad {
            b: [b[0] / a[0], b[1] / a[0], b[2] / a[0]],
            a: [a[1] / a[0], a[2] / a[0]],
        }
    }
}

/// The angles θᵢ \[rad\] of a Butterworth low-pass's complex pole pairs from the negative
/// real axis, smallest first: `θᵢ = (2i − 1 + n mod 2)·π/(2n)`, i = 1 … ⌊n/2⌋ (an odd order
/// has a real pole besides, at θ = 0). Each pair is a second-order section of quality factor
/// `1/(2·cos θᵢ)`.
fn butterworth_pair_angles(order: usize) -> impl Iterator<Item = f64> {
    (1..=order / 2).map(move |i| (2 * i - 1 + order % 2) as f64 * PI / (2 * order) as f64)
}

/// The sections of a Butterworth low-pass of order `order` ≥ 1 at `fc` \[Hz\] for the step
/// `dt` \[s\]: a second-order section for each pole pair (`butterworth_pair_angles`), and a
/// first-order section last for the real pole of an odd order. `|H|² = 1/(1 + (f/fc)^(2n))`,
/// exactly at `fc` and closely below it when `fc·dt` is small (the bilinear transform warps
/// frequencies towards Nyquist).
pub fn butterworth_sections(dt: f64, fc: f64, order: usize) -> Vec<Biquad> {
    let mut sections: Vec<Biquad> = butterworth_pair_angles(order)
        .map(|theta| Biquad::lowpass(dt, fc, 1.0 / (2.0 * theta.cos())))
        .collect();
    if order % 2 == 1 {
        sections.push(Biquad::lowpass_first_order(dt, fc));
    }
    sections
}

/// The low-frequency group delay \[s\] of a Butterworth low-pass of order `order` at `fc`
/// \[Hz\]: `(1/ωc)·Σ 1/Qₖ` over its sections (a first-order section counts 1), √2/ωc for the
/// second order, 2.613/ωc for the fourth.
pub fn butterworth_delay_s(fc: f64, order: usize) -> f64 {
    let sum_inv_q: f64 = butterworth_pair_angles(order)
        .map(|t| 2.0 * t.cos())
        .sum::<f64>()
        + (order % 2) as f64;
    sum_inv_q / (2.0 * PI * fc)
}

/// Runs `sections` over `x` forward, then backward ([`Biquad::pass`]): gain `|H|²`, zero
/// phase.
pub fn zero_phase(x: &[f64], sections: &[Biquad]) -> Vec<f64> {
    let mut y = x.to_vec();
    for c in sections {
        c.pass(&mut y, false);
    }
    for c in sections {
        c.pass(&mut y, true);
    }
    y
}

/// [`zero_phase`] of `x` extended at each end by its point reflection over `pad` samples
/// (at most `x.len() − 1`): `2·x₀ − x_k` before the first sample, `2·x_{n−1} − x_{n−1−k}`
/// after the last, as scipy's `filtfilt` pads (`padtype="odd"`). Value and slope then run on
/// through both ends, so a signal still moving when the record starts or stops is filtered
/// there as in its middle; without the extension each pass starts settled at a constant and
/// its start-up transient lies on the record's first (forward) and last (backward) samples.
/// With `pad` at least the filter's settling ([`butterworth_settling_samples`]) a straight
/// line passes unchanged.
pub fn zero_phase_odd_padded(x: &[f64], sections: &[Biquad], pad: usize) -> Vec<f64> {
    let n = x.len();
    if n < 2 || pad == 0 {
        return zero_phase(x, sections);
    }
    let pad = pad.min(n - 1);
    let (first, last) = (x[0], x[n - 1]);
    let mut ext = Vec::with_capacity(n + 2 * pad);
    ext.extend((1..=pad).rev().map(|k| 2.0 * first - x[k]));
    ext.extend_from_slice(x);
    ext.extend((1..=pad).map(|k| 2.0 * last - x[n - 1 - k]));
    let y = zero_phase(&ext, sections);
    y[pad..pad + n].to_vec()
}

/// Samples at step `dt` \[s\] over which the start-up transient of a Butterworth low-pass of
/// order `order` at `fc` \[Hz\] has died out: 20 time constants (e⁻²⁰ = 2·10⁻⁹) of its
/// slowest pole, whose decay rate is `ωc·sin(π/(2·order))` (0.26·ωc for the 6th order: 0.62 s
/// at 20 Hz).
pub fn butterworth_settling_samples(dt: f64, fc: f64, order: usize) -> usize {
    let sigma = 2.0 * PI * fc * (PI / (2 * order.max(1)) as f64).sin();
    let samples = 20.0 / (sigma * dt);
    if samples.is_finite() && samples > 0.0 {
        samples.ceil() as usize
    } else {
        0
    }
}

/// Zero-phase Butterworth low-pass of order `order`, run forward and backward:
/// `|H|² = 1/(1 + (f/fc)^(2·order))`, no phase shift. Each pass starts in steady state at the
/// end value it starts from.
pub fn butterworth_zero_phase(x: &[f64], dt: f64, fc: f64, order: usize) -> Vec<f64> {
    zero_phase(x, &butterworth_sections(dt, fc, order))
}

/// Zero-phase low-pass of the error metric: a second-order Butterworth run forward and
/// backward twice (`|H|⁴` of the section: −12 dB at `fc`, about −49 dB at `2·fc`).
pub fn lowpass(x: &[f64], dt: f64, fc: f64) -> Vec<f64> {
    let c = Biquad::lowpass(dt, fc, std::f64::consts::FRAC_1_SQRT_2);
    let mut y = x.to_vec();
    for _ in 0..2 {
        c.pass(&mut y, false);
        c.pass(&mut y, true);
    }
    y
}

/// Zero-phase low-pass ([`lowpass`]) followed by a central difference (one-sided at the
/// ends): a smoothed derivative [unit of `x` per s].
pub fn filtered_derivative(x: &[f64], dt: f64, fc: f64) -> Vec<f64> {
    let y = lowpass(x, dt, fc);
    let n = y.len();
    (0..n)
        .map(|i| {
            let (a, b) = (i.saturating_sub(1), (i + 1).min(n.saturating_sub(1)));
            if b > a {
                (y[b] - y[a]) / ((b - a) as f64 * dt)
            } else {
                0.0
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dsp::rms;
    use crate::dsp::tests::sine;

    /// A Butterworth low-pass of every order 1 … 8, from its sections: gain `1/√2` at the
    /// corner, `1/√(1 + (f/fc)^(2n))` below and above it (analytic; the bilinear transform's
    /// warping is negligible at `fc·dt` = 0.0008), and the low-frequency group delay of the
    /// analogue prototype, `(1/ωc)·Σ 1/Qₖ` over its sections (a first-order section counts
    /// 1): √2/ωc for the second order, 2.613/ωc for the fourth.
    #[test]
    fn butterworth_of_any_order_has_the_analytic_gain_and_delay() {
        let (dt, fc) = (1e-5, 80.0);
        let wc = 2.0 * PI * fc;
        for n in 1..=8usize {
            let sections = butterworth_sections(dt, fc, n);
            assert_eq!(sections.len(), n.div_ceil(2));
            let h = |f: f64| {
                sections
                    .iter()
                    .map(|c| c.response(2.0 * PI * f * dt))
                    .product::<Complex64>()
            };
            for f in [0.0, 20.0, 80.0, 160.0] {
                let want = 1.0 / (1.0 + (f / fc).powi(2 * n as i32)).sqrt();
                let got = h(f).norm();
                assert!(
                    (got - want).abs() < 2e-3 * want,
                    "order {n}, {f} Hz: {got} vs {want}"
                );
            }
            let sum_inv_q: f64 = (1..=n / 2)
                .map(|k| 2.0 * (PI * (n - 2 * k + 1) as f64 / (2 * n) as f64).cos())
                .sum::<f64>()
                + if n % 2 == 1 { 1.0 } else { 0.0 };
            let f = 0.5;
            let delay = -h(f).arg() / (2.0 * PI * f);
            assert!(
                (delay - sum_inv_q / wc).abs() < 1e-3 * sum_inv_q / wc,
                "order {n}: {delay} s vs {} s",
                sum_inv_q / wc
            );
            if n == 2 {
                assert!((sum_inv_q - 2f64.sqrt()).abs() < 1e-12);
            }
            if n == 4 {
                assert!((sum_inv_q - 2.6131).abs() < 1e-4, "{sum_inv_q}");
            }
        }
    }

    /// A settled cascade gives what the sections' whole-slice passes give one after the other
    /// (each started settled at its first input), sample by sample; a constant passes
    /// unchanged from the first sample on.
    #[test]
    fn settled_cascade_streams_the_forward_passes() {
        let (dt, fc) = (1e-3, 40.0);
        let sections = butterworth_sections(dt, fc, 5);
        let x: Vec<f64> = (0..400)
            .map(|i| 3.0 + (0.07 * i as f64).sin() + if i > 200 { 1.5 } else { 0.0 })
            .collect();
        let mut whole = x.clone();
        for c in &sections {
            c.pass(&mut whole, false);
        }
        let mut stream = SettledCascade::new(sections.clone());
        for (i, (&v, &w)) in x.iter().zip(&whole).enumerate() {
            let y = stream.step(v);
            assert!((y - w).abs() < 1e-12, "sample {i}: {y} vs {w}");
        }
        let mut still = SettledCascade::new(sections);
        for _ in 0..50 {
            assert!((still.step(5.5e6) - 5.5e6).abs() < 1e-6);
        }
    }

    /// The designed section's response equals the analogue Butterworth prototype at the
    /// pre-warped frequency: `H(jΩ) = 1/(1 − Ω² + jΩ/q)` with `Ω = tan(πf·dt)/tan(πfc·dt)`,
    /// in gain and in phase; and it is what the section does to a sine in steady state.
    #[test]
    fn biquad_response_matches_its_transfer_function() {
        let (dt, fc) = (1e-3, 40.0);
        for q in [std::f64::consts::FRAC_1_SQRT_2, 0.54, 1.3] {
            let c = Biquad::lowpass(dt, fc, q);
            for f in [1.0, 10.0, 40.0, 120.0, 400.0] {
                let omega = (PI * f * dt).tan() / (PI * fc * dt).tan();
                let h_ref = 1.0 / Complex64::new(1.0 - omega * omega, omega / q);
                let h = c.response(2.0 * PI * f * dt);
                assert!((h - h_ref).norm() < 1e-12, "q {q} f {f}: {h} vs {h_ref}");
                assert!((c.gain(2.0 * PI * f * dt) - h_ref.norm()).abs() < 1e-12);
            }
            // Exactly −3 dB at the corner only for q = 1/√2 (the Butterworth case).
            if q == std::f64::consts::FRAC_1_SQRT_2 {
                assert!((c.gain(2.0 * PI * fc * dt) - 0.5f64.sqrt()).abs() < 1e-12);
            }
        }
        // Steady state of a 10 Hz sine streamed from rest: amplitude |H| and phase arg H.
        let c = Biquad::lowpass(dt, fc, 0.9);
        let f = 10.0;
        let n = 4000;
        let x = sine(1.0, f, dt, n, 0.0);
        let mut st = BiquadState::new(c);
        let y: Vec<f64> = x.iter().map(|&v| st.step(v)).collect();
        let h = c.response(2.0 * PI * f * dt);
        let expect = sine(h.norm(), f, dt, n, h.arg());
        for i in n / 2..n {
            assert!(
                (y[i] - expect[i]).abs() < 1e-9,
                "{i}: {} vs {}",
                y[i],
                expect[i]
            );
        }
        // The in-place pass (other form, steady-state start) gives the same steady state.
        let mut z = x.clone();
        c.pass(&mut z, false);
        for i in n / 2..n {
            assert!((z[i] - expect[i]).abs() < 1e-9);
        }
        // Reset returns to rest: the same output again.
        st.reset();
        assert_eq!(st.step(x[0]), y[0]);
    }

    /// The bilinear transform of an analogue second-order low-pass with its corner pre-warped
    /// is the same section as [`Biquad::lowpass`].
    #[test]
    fn bilinear_of_prewarped_prototype_equals_the_direct_design() {
        let (dt, fc, q) = (5e-4, 25.0, 0.8);
        let k = 2.0 / dt;
        let w = k * (PI * fc * dt).tan();
        let analog = AnalogSection {
            num: [1.0, 0.0, 0.0],
            den: [1.0, 1.0 / (w * q), 1.0 / (w * w)],
        };
        let d = analog.bilinear(k);
        let l = Biquad::lowpass(dt, fc, q);
        for i in 0..3 {
            assert!((d.b[i] - l.b[i]).abs() < 1e-12, "{d:?} vs {l:?}");
        }
        for i in 0..2 {
            assert!((d.a[i] - l.a[i]).abs() < 1e-12, "{d:?} vs {l:?}");
        }
        // Analogue response at the corner: |H| = q, phase −π/2.
        let (m, p) = analog.response(w);
        assert!((m - q).abs() < 1e-12 && (p + PI / 2.0).abs() < 1e-12);
    }

    /// A sine in the passband comes through a zero-phase filter unchanged in amplitude and
    /// with zero lag (its cross-correlation peaks at lag 0 and the residual is tiny); a sine
    /// far in the stopband is removed.
    #[test]
    fn zero_phase_filters_keep_passband_sines_without_lag() {
        let (dt, n) = (1e-3, 8000);
        let x = sine(1.5, 4.0, dt, n, 0.7);
        let mid = n / 4..3 * n / 4;
        let lag_of = |y: &[f64]| {
            (-20i64..=20)
                .max_by(|&a, &b| {
                    let c = |l: i64| -> f64 {
                        mid.clone().map(|i| x[i] * y[(i as i64 + l) as usize]).sum()
                    };
                    c(a).total_cmp(&c(b))
                })
                .unwrap_or(99)
        };
        for (name, y, tol) in [
            (
                "butterworth 6th order, 30 Hz",
                butterworth_zero_phase(&x, dt, 30.0, 6),
                1e-6,
            ),
            ("metric low-pass, 25 Hz", lowpass(&x, dt, 25.0), 2e-3),
        ] {
            let e: Vec<f64> = mid.clone().map(|i| y[i] - x[i]).collect();
            assert!(rms(&e) < tol * 1.5, "{name}: residual {}", rms(&e));
            assert_eq!(lag_of(&y), 0, "{name}");
        }
        // |H|² of the digital 6th-order Butterworth at 60 Hz = 2·fc: 1/(1 + Ω¹²) with the
        // bilinear transform's warped frequency Ω = tan(πf·dt)/tan(πfc·dt).
        let fast = sine(1.0, 60.0, dt, n, 0.0);
        let g = rms(&butterworth_zero_phase(&fast, dt, 30.0, 6)[mid.clone()]) / rms(&fast[mid]);
        let omega = (PI * 60.0 * dt).tan() / (PI * 30.0 * dt).tan();
        let expect = 1.0 / (1.0 + omega.powi(12));
        assert!((g - expect).abs() < 0.01 * expect, "{g} vs {expect}");
        // A constant passes unchanged (steady-state start, unit DC gain).
        let c = vec![2.5; 100];
        assert!(
            lowpass(&c, dt, 25.0)
                .iter()
                .all(|v| (v - 2.5).abs() < 1e-12)
        );
        assert!(zero_phase(&[], &butterworth_sections(dt, 30.0, 6)).is_empty());
    }

    /// A slow sine still moving at the ends of the record, through the 6th-order 20 Hz
    /// Butterworth run forward and backward, should come out as the sine times |H(2 Hz)|²
    /// (analytic: 1 − 10⁻¹²) on every sample. Padded by its point reflection it does to 10⁻⁹
    /// of its amplitude where the record starts and ends at its steepest (the reflection then
    /// continues the sine; measured 8·10⁻¹¹), and to 2·10⁻³ where it starts and ends 0.4 rad
    /// later (the reflection turns its curvature over; measured 1.0·10⁻³). Started settled at
    /// its end values, as before the padding, the filter is off by 0.38 of the amplitude near
    /// the ends in both. A straight line passes the padded filter unchanged.
    #[test]
    fn an_odd_padded_zero_phase_filter_has_no_edge_transients() {
        let (dt, f) = (1e-3, 2.0);
        let sections = butterworth_sections(dt, 20.0, 6);
        let pad = butterworth_settling_samples(dt, 20.0, 6);
        assert_eq!(pad, 615);
        // Ends at its steepest (3 s: six periods), and at another phase (0.4 rad later).
        for (n, phase, tol) in [(3001, 0.0, 1e-9), (3001, 0.4, 2e-3)] {
            let x: Vec<f64> = (0..n)
                .map(|i| (2.0 * PI * f * i as f64 * dt + phase).sin())
                .collect();
            let worst = |y: &[f64]| {
                y.iter()
                    .zip(&x)
                    .map(|(a, b)| (a - b).abs())
                    .fold(0.0, f64::max)
            };
            let padded = worst(&zero_phase_odd_padded(&x, &sections, pad));
            let settled = worst(&zero_phase(&x, &sections));
            assert!(padded < tol, "phase {phase}: padded {padded}");
            assert!(
                settled > 0.3,
                "phase {phase}: settled {settled}, padded {padded}"
            );
        }
        let line: Vec<f64> = (0..3000).map(|i| 0.5 - 1e-3 * i as f64).collect();
        let y = zero_phase_odd_padded(&line, &sections, pad);
        assert!(y.iter().zip(&line).all(|(a, b)| (a - b).abs() < 1e-6));
        let one = zero_phase_odd_padded(&[1.5], &sections, pad);
        assert!(one.len() == 1 && (one[0] - 1.5).abs() < 1e-12, "{one:?}");
    }

    #[test]
    fn filtered_derivative_of_a_ramp_is_its_slope() {
        let dt = 1e-3;
        let x: Vec<f64> = (0..2000).map(|i| 0.3 * i as f64 * dt).collect();
        let d = filtered_derivative(&x, dt, 40.0);
        for v in &d[300..1700] {
            assert!((v - 0.3).abs() < 1e-6, "{v}");
        }
        assert!(filtered_derivative(&[1.0], dt, 40.0) == vec![0.0]);
    }
}
