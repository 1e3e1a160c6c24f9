//! Frequency responses: exact (linear and passive models), by numerical linearisation of the
//! twin at rest (Jacobian → state space → delay applied on jω), and by simulation (sine
//! dwell, first harmonic). Plus the |T| = 1 crossings and the delay from the phase slope.
//!
//! Two responses matter (section 4 and 6 of the paper):
//! * the valve/actuator Bode `u̇/V_in` (G(s) for the linear model), open loop, platform still;
//! * the transmissibility `T = ÿ/ẍ` with the controller `V = Kp·u + (Ki/s)·ẍ` in the loop.

use crate::control::ControlLaw;
use crate::model::linear::{LinearModel, g_of};
use crate::model::passive::PassiveModel;
use crate::model::twin::Twin;
use crate::model::{Inputs, Model};
use crate::params::Params;
use nalgebra::{DMatrix, DVector};
use num_complex::Complex64;
use std::f64::consts::PI;

/// One point of a frequency response.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct FrequencyPoint {
    /// Frequency \[Hz\].
    pub freq_hz: f64,
    /// Complex response (SI ratio, e.g. [m/(s·V)] or [-]).
    pub value: Complex64Ser,
}

/// A serialisable complex number.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Complex64Ser {
    /// Real part.
    pub re: f64,
    /// Imaginary part.
    pub im: f64,
}

impl From<Complex64> for Complex64Ser {
    fn from(c: Complex64) -> Self {
        Self { re: c.re, im: c.im }
    }
}

impl FrequencyPoint {
    /// Builds a point.
    pub fn new(freq_hz: f64, value: Complex64) -> Self {
        Self {
            freq_hz,
            value: value.into(),
        }
    }
    /// The complex value.
    pub fn complex(&self) -> Complex64 {
        Complex64::new(self.value.re, self.value.im)
    }
    /// Magnitude.
    pub fn mag(&self) -> f64 {
        self.complex().norm()
    }
    /// Phase \[rad\] in (−π, π].
    pub fn phase(&self) -> f64 {
        self.complex().arg()
    }
}

/// Unwraps a phase sequence \[rad\] so that consecutive values differ by less than π.
pub fn unwrap_phase(phases: &[f64]) -> Vec<f64> {
    let mut out = Vec::with_capacity(phases.len());
    let mut offset = 0.0;
    for (i, &p) in phases.iter().enumerate() {
        if i > 0 {
            let prev = phases[i - 1];
            let d = p - prev;
            if d > PI {
                offset -= 2.0 * PI;
            } else if d < -PI {
                offset += 2.0 * PI;
            }
        }
        out.push(p + offset);
    }
    out
}

/// Logarithmically spaced frequencies \[Hz\].
pub fn log_space(f_lo: f64, f_hi: f64, n: usize) -> Vec<f64> {
    if n < 2 {
        return vec![f_lo];
    }
    let (a, b) = (f_lo.ln(), f_hi.ln());
    (0..n)
        .map(|i| (a + (b - a) * i as f64 / (n - 1) as f64).exp())
        .collect()
}

/// Transmissibility of the linear model with the controller, exact [-].
pub fn linear_transmissibility(params: &Params, freq_hz: f64) -> Complex64 {
    let w = 2.0 * PI * freq_hz;
    let jw = Complex64::new(0.0, w);
    // G without its delay; u = G/s·V_valve, ü = s·G·V_valve; ÿ = ẍ + ü.
    let mut l = params.linear;
    let tau = l.tau_s;
    l.tau_s = 0.0;
    let g = g_of(&l, w);
    ControlLaw::new(params).transmissibility(
        w,
        tau,
        g / jw,
        Complex64::new(0.0, 0.0),
        g * jw,
        Complex64::new(1.0, 0.0),
    )
}

/// Transmissibility of the passive reference, exact [-].
pub fn passive_transmissibility(params: &Params, freq_hz: f64) -> Complex64 {
    PassiveModel::new(params).transmissibility(2.0 * PI * freq_hz)
}

/// `G(jω)` of the linear model, exact, with its delay [m/(s·V)].
pub fn linear_bode(params: &Params, freq_hz: f64) -> Complex64 {
    LinearModel::new(params).g(2.0 * PI * freq_hz)
}

/// A model linearised at a state: `ẏ = A·y + b_v·V_valve + b_x·ẍ`, prepared for fast
/// frequency responses.
///
/// The solves run on `D⁻¹·A·D` with `D = diag(scales)` (same eigenvalues, entries of similar
/// size; the raw A spans 1e-7…1e14), reduced once to upper Hessenberg form `H = Qᵀ·D⁻¹AD·Q`
/// by orthogonal similarity. Each frequency then costs one O(n²) elimination on `jωI − H`
/// (partial pivoting between neighbouring rows) for both inputs together, instead of a dense
/// O(n³) LU per input.
#[derive(Debug, Clone)]
pub struct LinearisedModel {
    a: DMatrix<f64>,
    b_v: DVector<f64>,
    b_x: DVector<f64>,
    tau_s: f64,
    scales: Vec<f64>,
    /// `Qᵀ·D⁻¹·A·D·Q`, upper Hessenberg.
    h: DMatrix<f64>,
    /// `Qᵀ·D⁻¹·[b_v b_x]`.
    qb: [DVector<f64>; 2],
    /// Output rows `scale_u·Q[u, :]` and `scale_du·Q[du, :]`.
    c_out: [DVector<f64>; 2],
}

/// Open-loop responses of a linearised model at one frequency, the command delay excluded:
/// the plant maps `[V_valve, ẍ]` to `[u, u̇]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OpenLoop {
    /// Angular frequency [rad/s].
    pub omega: f64,
    /// `u/V_valve` [m/V].
    pub u_v: Complex64,
    /// `u/ẍ` \[s²\].
    pub u_x: Complex64,
    /// `u̇/V_valve` [m/(s·V)].
    pub du_v: Complex64,
    /// `u̇/ẍ` \[s\].
    pub du_x: Complex64,
}

impl OpenLoop {
    /// All responses NaN (a singular `jωI − A`).
    fn nan(omega: f64) -> Self {
        let n = Complex64::new(f64::NAN, f64::NAN);
        Self {
            omega,
            u_v: n,
            u_x: n,
            du_v: n,
            du_x: n,
        }
    }

    /// `u̇/V_in` with the command delay `tau_s` [m/(s·V)].
    pub fn bode(&self, tau_s: f64) -> Complex64 {
        self.du_v * Complex64::new(0.0, -self.omega * tau_s).exp()
    }

    /// `ÿ/V_valve` [m/(s²·V)] (ÿ = ü + ẍ and ü = jω·u̇).
    pub fn ydd_v(&self) -> Complex64 {
        Complex64::new(0.0, self.omega) * self.du_v
    }

    /// The loop gain at the valve command with the controller and the delay `tau_s`
    /// ([`ControlLaw::loop_gain`]).
    pub fn loop_gain(&self, law: &ControlLaw, tau_s: f64) -> Complex64 {
        law.loop_gain(self.omega, self.u_v, self.ydd_v(), tau_s)
    }

    /// Closed-loop transmissibility `ÿ/ẍ` with the controller and the delay `tau_s` [-].
    pub fn transmissibility(&self, law: &ControlLaw, tau_s: f64) -> Complex64 {
        let jw = Complex64::new(0.0, self.omega);
        // ÿ = ü + ẍ and ü = jω·u̇.
        law.transmissibility(
            self.omega,
            tau_s,
            self.u_v,
            self.u_x,
            jw * self.du_v,
            jw * self.du_x + 1.0,
        )
    }
}

pub use crate::model::jacobian;

/// Numerical linearisation of a model at state `y0` with zero inputs.
pub fn linearise<M: Model<N>, const N: usize>(
    model: &M,
    y0: &[f64; N],
    scales: &[f64; N],
    tau_s: f64,
) -> LinearisedModel {
    let jac = jacobian(model, y0, scales);
    let a = DMatrix::from_fn(N, N, |i, j| jac[i][j]);
    let column = |make: &dyn Fn(f64) -> Inputs, h: f64| {
        let fp = model.derivatives(0.0, y0, &make(h));
        let fm = model.derivatives(0.0, y0, &make(-h));
        DVector::from_iterator(N, (0..N).map(|i| (fp[i] - fm[i]) / (2.0 * h)))
    };
    let b_v = column(
        &|v| Inputs {
            v_valve: v,
            xdd: 0.0,
        },
        1e-4,
    );
    let b_x = column(
        &|x| Inputs {
            v_valve: 0.0,
            xdd: x,
        },
        1e-4,
    );
    LinearisedModel::new(a, b_v, b_x, scales.to_vec(), tau_s)
}

/// The twin linearised at rest.
pub fn linearise_twin(params: &Params) -> LinearisedModel {
    let twin = Twin::new(*params);
    let y0 = twin.rest_state();
    linearise(&twin, &y0, &twin.state_scales(), params.plant.valve.tau_s)
}

impl LinearisedModel {
    /// Prepares `ẏ = A·y + b_v·V_valve + b_x·ẍ` (state order: `u`, `u̇`, …) with the state
    /// scales `scales` and the command delay `tau_s` \[s\].
    pub fn new(
        a: DMatrix<f64>,
        b_v: DVector<f64>,
        b_x: DVector<f64>,
        scales: Vec<f64>,
        tau_s: f64,
    ) -> Self {
        let n = a.nrows();
        let scaled = DMatrix::from_fn(n, n, |i, j| a[(i, j)] * scales[j] / scales[i]);
        let (q, h) = scaled.hessenberg().unpack();
        let scale_in = |b: &DVector<f64>| {
            q.tr_mul(&DVector::from_iterator(n, (0..n).map(|i| b[i] / scales[i])))
        };
        let qb = [scale_in(&b_v), scale_in(&b_x)];
        let (u_index, du_index) = (0, 1);
        let out_row = |i: usize| q.row(i).transpose() * scales[i];
        let c_out = [out_row(u_index), out_row(du_index)];
        Self {
            a,
            b_v,
            b_x,
            tau_s,
            scales,
            h,
            qb,
            c_out,
        }
    }

    /// State matrix A [SI, per state].
    pub fn a(&self) -> &DMatrix<f64> {
        &self.a
    }

    /// Input column of the (delayed) valve command.
    pub fn b_v(&self) -> &DVector<f64> {
        &self.b_v
    }

    /// Input column of the platform acceleration.
    pub fn b_x(&self) -> &DVector<f64> {
        &self.b_x
    }

    /// Pure delay of the command \[s\].
    pub fn tau_s(&self) -> f64 {
        self.tau_s
    }

    /// Characteristic scale of each state (SI units of that state).
    pub fn scales(&self) -> &[f64] {
        &self.scales
    }

    /// The open-loop responses at `freq_hz` \[Hz\], delay excluded: one elimination on the
    /// Hessenberg form for both inputs. NaN if `jωI − A` is singular.
    pub fn open_loop(&self, freq_hz: f64) -> OpenLoop {
        let omega = 2.0 * PI * freq_hz;
        self.open_loop_at(omega).unwrap_or(OpenLoop::nan(omega))
    }

    fn open_loop_at(&self, omega: f64) -> Option<OpenLoop> {
        let n = self.h.nrows();
        let zero = Complex64::new(0.0, 0.0);
        // Row-major jωI − H, then the two right-hand sides.
        let mut m: Vec<Complex64> = (0..n * n)
            .map(|k| {
                let (i, j) = (k / n, k % n);
                let d = if i == j { omega } else { 0.0 };
                Complex64::new(-self.h[(i, j)], d)
            })
            .collect();
        let mut z: [Vec<Complex64>; 2] = self
            .qb
            .clone()
            .map(|b| b.iter().map(|&x| Complex64::new(x, 0.0)).collect());
        for k in 0..n.saturating_sub(1) {
            if m[(k + 1) * n + k].norm_sqr() > m[k * n + k].norm_sqr() {
                for j in k..n {
                    m.swap(k * n + j, (k + 1) * n + j);
                }
                for zc in &mut z {
                    zc.swap(k, k + 1);
                }
            }
            let pivot = m[k * n + k];
            if pivot == zero {
                return None;
            }
            let l = m[(k + 1) * n + k] / pivot;
            if l != zero {
                for j in k + 1..n {
                    let mkj = m[k * n + j];
                    m[(k + 1) * n + j] -= l * mkj;
                }
                for zc in &mut z {
                    let zk = zc[k];
                    zc[k + 1] -= l * zk;
                }
            }
        }
        for i in (0..n).rev() {
            let d = m[i * n + i];
            if d == zero {
                return None;
            }
            for zc in &mut z {
                let mut acc = zc[i];
                for j in i + 1..n {
                    acc -= m[i * n + j] * zc[j];
                }
                zc[i] = acc / d;
            }
        }
        let out = |c: &DVector<f64>, zc: &[Complex64]| -> Complex64 {
            c.iter().zip(zc).map(|(&ci, &zi)| zi * ci).sum()
        };
        let r = OpenLoop {
            omega,
            u_v: out(&self.c_out[0], &z[0]),
            u_x: out(&self.c_out[0], &z[1]),
            du_v: out(&self.c_out[1], &z[0]),
            du_x: out(&self.c_out[1], &z[1]),
        };
        let finite = |c: Complex64| c.re.is_finite() && c.im.is_finite();
        [r.u_v, r.u_x, r.du_v, r.du_x]
            .into_iter()
            .all(finite)
            .then_some(r)
    }

    /// `u̇/V_in` including the delay [m/(s·V)].
    pub fn bode(&self, freq_hz: f64) -> Complex64 {
        self.open_loop(freq_hz).bode(self.tau_s)
    }

    /// Closed-loop transmissibility `ÿ/ẍ` with the controller [-].
    pub fn transmissibility(&self, law: &ControlLaw, freq_hz: f64) -> Complex64 {
        self.open_loop(freq_hz).transmissibility(law, self.tau_s)
    }

    /// Eigenvalues of A [1/s] (computed from the Hessenberg form, which has the same).
    pub fn eigenvalues(&self) -> Vec<Complex64> {
        self.h.complex_eigenvalues().iter().copied().collect()
    }
}

/// First harmonic `(2/T)·∫ s(t)·e^(−jωt) dt` of uniformly sampled data over an integer number
/// of periods ending at the last sample (trapezoidal rule).
pub fn first_harmonic(values: &[f64], dt: f64, t0: f64, freq_hz: f64, periods: usize) -> Complex64 {
    let w = 2.0 * PI * freq_hz;
    let t_window = periods as f64 / freq_hz;
    let n_window = (t_window / dt).round() as usize;
    if values.len() < n_window + 1 || n_window == 0 {
        return Complex64::new(f64::NAN, f64::NAN);
    }
    let start = values.len() - 1 - n_window;
    let mut acc = Complex64::new(0.0, 0.0);
    for (k, v) in values[start..].iter().enumerate() {
        let t = t0 + (start + k) as f64 * dt;
        let weight = if k == 0 || k == n_window { 0.5 } else { 1.0 };
        acc += weight * v * Complex64::new(0.0, -w * t).exp();
    }
    acc * 2.0 * dt / (n_window as f64 * dt)
}

/// A frequency where |T| crosses 1.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Crossing {
    /// Frequency \[Hz\] (log-linear interpolation between the bracketing points).
    pub freq_hz: f64,
    /// True where |T| rises through 1 (the end of an isolation band).
    pub rising: bool,
}

/// All |T| = 1 crossings of a sampled magnitude curve.
pub fn unity_crossings(freqs_hz: &[f64], mags: &[f64]) -> Vec<Crossing> {
    let mut out = Vec::new();
    for i in 1..freqs_hz.len().min(mags.len()) {
        let (a, b) = (mags[i - 1].ln(), mags[i].ln());
        if !(a.is_finite() && b.is_finite()) {
            continue;
        }
        if (a < 0.0) != (b < 0.0) {
            let (fa, fb) = (freqs_hz[i - 1].ln(), freqs_hz[i].ln());
            let f = fa + (fb - fa) * (0.0 - a) / (b - a);
            out.push(Crossing {
                freq_hz: f.exp(),
                rising: b > a,
            });
        }
    }
    out
}

/// The upper edge of the first isolation band (|T| < 1) of an active suspension: the first
/// rising crossing. `None` if |T| never rises back through 1 in the range.
pub fn isolation_upper_edge(freqs_hz: &[f64], mags: &[f64]) -> Option<f64> {
    unity_crossings(freqs_hz, mags)
        .into_iter()
        .find(|c| c.rising)
        .map(|c| c.freq_hz)
}

/// The start of isolation of a passive suspension: the first falling crossing.
pub fn isolation_lower_edge(freqs_hz: &[f64], mags: &[f64]) -> Option<f64> {
    unity_crossings(freqs_hz, mags)
        .into_iter()
        .find(|c| !c.rising)
        .map(|c| c.freq_hz)
}

/// Pure delay estimated from the phase slope, as in section 4.1: least-squares fit of the
/// unwrapped phase \[rad\] against ω, `τ = −dφ/dω` \[s\].
pub fn delay_from_phase_slope(freqs_hz: &[f64], phases_rad: &[f64]) -> f64 {
    let ph = unwrap_phase(phases_rad);
    let n = freqs_hz.len().min(ph.len()) as f64;
    if n < 2.0 {
        return f64::NAN;
    }
    let w: Vec<f64> = freqs_hz.iter().map(|f| 2.0 * PI * f).collect();
    let mw = w.iter().sum::<f64>() / n;
    let mp = ph.iter().sum::<f64>() / n;
    let sxy: f64 = w.iter().zip(&ph).map(|(a, b)| (a - mw) * (b - mp)).sum();
    let sxx: f64 = w.iter().map(|a| (a - mw).powi(2)).sum();
    -sxy / sxx
}

/// G(s) as a linearised model (exact: the model is linear), its delay `params.linear.tau_s`.
pub fn linearise_linear(params: &Params) -> LinearisedModel {
    let model = LinearModel::new(params);
    linearise(
        &model,
        &model.rest_state(),
        &[1e-2, 1e-1, 1e1],
        params.linear.tau_s,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Reference: `(jωI − A)⁻¹·b` by a dense complex LU of the unscaled, unreduced A, read at
    /// the state `i`.
    fn dense_response(lin: &LinearisedModel, b: &DVector<f64>, omega: f64, i: usize) -> Complex64 {
        let n = lin.a().nrows();
        let m = DMatrix::from_fn(n, n, |r, c| {
            let d = if r == c { omega } else { 0.0 };
            Complex64::new(-lin.a()[(r, c)], d)
        });
        let rhs = DVector::from_iterator(n, b.iter().map(|&x| Complex64::new(x, 0.0)));
        m.lu().solve(&rhs).expect("jωI − A is regular here")[i]
    }

    /// The Hessenberg elimination gives the dense LU's responses, for both inputs and both
    /// outputs, from 0.01 Hz to 200 Hz (the raw A spans 1e-7…1e14, so the reference solves
    /// the badly scaled system; the agreement bound allows for that).
    #[test]
    fn hessenberg_responses_match_a_dense_solve() {
        let lin = linearise_twin(&Params::paper());
        for f in log_space(0.01, 200.0, 23) {
            let w = 2.0 * PI * f;
            let r = lin.open_loop(f);
            let pairs = [
                (r.u_v, dense_response(&lin, lin.b_v(), w, 0)),
                (r.u_x, dense_response(&lin, lin.b_x(), w, 0)),
                (r.du_v, dense_response(&lin, lin.b_v(), w, 1)),
                (r.du_x, dense_response(&lin, lin.b_x(), w, 1)),
            ];
            for (k, (fast, reference)) in pairs.into_iter().enumerate() {
                assert!(
                    (fast - reference).norm() <= 1e-7 * reference.norm(),
                    "response {k} at {f:.3} Hz: {fast} vs {reference}"
                );
            }
            // u̇ is the derivative of u: the two outputs differ by jω exactly.
            let jw = Complex64::new(0.0, w);
            assert!((r.du_v - jw * r.u_v).norm() <= 1e-9 * r.du_v.norm());
        }
    }

    /// A singular `jωI − A` (a pure integrator at ω = 0) gives NaN, not infinity or a panic.
    #[test]
    fn a_singular_frequency_gives_nan() {
        let a = DMatrix::from_row_slice(2, 2, &[0.0, 1.0, 0.0, -3.0]);
        let b = DVector::from_row_slice(&[0.0, 1.0]);
        let lin = LinearisedModel::new(a, b.clone(), b, vec![1.0, 1.0], 0.0);
        assert!(lin.open_loop(0.0).u_v.re.is_nan());
        // Away from ω = 0: u/V = 1/(jω·(jω + 3)).
        let f = 1.0;
        let jw = Complex64::new(0.0, 2.0 * PI * f);
        let exact = 1.0 / (jw * (jw + 3.0));
        assert!((lin.open_loop(f).u_v - exact).norm() <= 1e-14 * exact.norm());
    }
}
