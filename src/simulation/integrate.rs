//! Fixed-step integrators on `[f64; N]`: classical Runge–Kutta (RK4), exponential RK4
//! ([`Etd4`], the twin's default), plus step statistics.
//!
//! Why fixed steps: the twin is not stiff for explicit methods (its fastest modes are the
//! lightly damped hose L–C modes near 5.8e3 rad/s, docs/model.md, correction 9), a fixed step keeps the pure
//! input delay on a uniform grid, and the same step everywhere makes runs reproducible bit for
//! bit. Why the exponential method by default: those hose modes ring with a damping ratio of
//! 6e-4, and RK4 needs ≈ 0.1 ms to follow the ringing to 1e-4 m/s² in ÿ, while [`Etd4`] takes
//! the linear part exactly and reaches the same accuracy at 0.5 ms (see [`Etd4`]). Both orders
//! are verified in `tests/it/integrator.rs`, and the accuracy against a 10× finer run is measured
//! by `seat-twin bench`.

use super::memo;

/// Counters of integrator work, so that a regression shows as work before it shows as time.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
pub struct StepStats {
    /// Steps taken.
    pub steps: u64,
    /// Right-hand-side evaluations.
    pub rhs_evals: u64,
}

/// One RK4 step of size `h` from `(t, y)`, in place. `f(t, y)` returns `dy/dt`.
#[inline(always)]
pub fn rk4_step<const N: usize>(
    t: f64,
    h: f64,
    y: &mut [f64; N],
    mut f: impl FnMut(f64, &[f64; N]) -> [f64; N],
) {
    let k1 = f(t, y);
    let mut tmp = [0.0; N];
    for i in 0..N {
        tmp[i] = y[i] + 0.5 * h * k1[i];
    }
    let k2 = f(t + 0.5 * h, &tmp);
    for i in 0..N {
        tmp[i] = y[i] + 0.5 * h * k2[i];
    }
    let k3 = f(t + 0.5 * h, &tmp);
    for i in 0..N {
        tmp[i] = y[i] + h * k3[i];
    }
    let k4 = f(t + h, &tmp);
    for i in 0..N {
        y[i] += h / 6.0 * (k1[i] + 2.0 * (k2[i] + k3[i]) + k4[i]);
    }
}

/// A fixed-step method for a problem `dy/dt = f(t, y)` on `[f64; N]`: the solver half of a
/// simulation, kept apart from the problem (model, command path, excitation) that supplies
/// `f`, as [`crate::simulation::Simulation`] does ([`Method`] lists the methods it can use). Every method here evaluates `f` at the
/// stage times `t`, `t + h/2` (twice) and `t + h`, so a problem can prepare its inputs at
/// those three times once per step.
pub trait Stepper<const N: usize> {
    /// The step \[s\].
    fn step_size(&self) -> f64;

    /// One step from `(t, y)`, in place; `f(t, y)` returns `dy/dt`.
    fn step(&self, t: f64, y: &mut [f64; N], f: impl FnMut(f64, &[f64; N]) -> [f64; N]);
}

/// Classical RK4 at a fixed step ([`rk4_step`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rk4 {
    /// The step \[s\].
    pub h: f64,
}

impl<const N: usize> Stepper<N> for Rk4 {
    fn step_size(&self) -> f64 {
        self.h
    }

    #[inline(always)]
    fn step(&self, t: f64, y: &mut [f64; N], f: impl FnMut(f64, &[f64; N]) -> [f64; N]) {
        rk4_step(t, self.h, y, f)
    }
}

impl<const N: usize> Stepper<N> for Etd4<N> {
    fn step_size(&self) -> f64 {
        self.h
    }

    #[inline(always)]
    fn step(&self, t: f64, y: &mut [f64; N], f: impl FnMut(f64, &[f64; N]) -> [f64; N]) {
        Etd4::step(self, t, y, f)
    }
}

/// The method a [`crate::simulation::Simulation`] steps with, chosen when it is built: the
/// solver, kept apart from the problem (model, command path, excitation) it steps.
#[derive(Debug, Clone)]
pub enum Method<const N: usize> {
    /// Classical RK4.
    Rk4(Rk4),
    /// Exponential RK4 (its coefficients are large, hence boxed).
    Exponential(Box<Etd4<N>>),
    /// The exact transition of a linear model with its inputs held linear over the step
    /// ([`crate::simulation::lti`]).
    ExactHold(Box<crate::simulation::lti::ExactHold<N>>),
}

impl<const N: usize> Method<N> {
    /// The exponential integrator, if this is it.
    pub fn exponential(&self) -> Option<&Etd4<N>> {
        match self {
            Method::Exponential(e) => Some(e),
            Method::Rk4(_) | Method::ExactHold(_) => None,
        }
    }
}

/// Column-major `N×N` matrix: `m[j]` is column `j`.
type Columns<const N: usize> = [[f64; N]; N];

/// `out += Σ_k cols[k]·x[k]`: a dense product with all `N` columns, or one restricted to the
/// remainder's rows.
#[inline(always)]
fn mul_add<const N: usize>(out: &mut [f64; N], cols: &[[f64; N]], x: &[f64]) {
    for (col, &xk) in cols.iter().zip(x) {
        for (o, &c) in out.iter_mut().zip(col) {
            *o += c * xk;
        }
    }
}

/// Most rows of the remainder an [`Etd4`] handles explicitly (the twin needs 4).
const MAX_REMAINDER_ROWS: usize = 8;

/// Exponential fourth-order Runge–Kutta (Cox & Matthews 2002, "ETDRK4") for
/// `y' = A·(y − y_ref) + R(t, y)` with a constant matrix `A` taken exactly, through its
/// matrix exponential and φ-functions, and the remainder `R = f − A·(y − y_ref)` explicitly.
///
/// Why: linearised at rest the twin has two hose/chamber L–C modes near 912 Hz with a damping
/// ratio of 6e-4 (docs/model.md, correction 9). They ring for a quarter of a second after every disturbance,
/// and resolving that ringing to 1e-4 m/s² in ÿ takes RK4 a step of ≈ 0.1 ms: the step is set
/// by phase error on a linear mode, not by the nonlinear physics. With `A` the Jacobian at rest
/// those modes are propagated without phase or amplitude error at any step; what is left
/// explicit (valve orifices, saturations, end stops, friction, the inputs) changes slowly.
///
/// The remainder is non-zero only in the rows of `f` that are not affine in the state (for the
/// twin: body velocity, the two valve-port pressures and the spool velocity). [`Etd4::new`]
/// finds those rows by probing `f` far from `y_ref`, and the step only carries the columns of
/// the φ-matrices for them. With `A = 0` the scheme is classical RK4.
#[derive(Debug, Clone)]
pub struct Etd4<const N: usize> {
    h: f64,
    y_ref: [f64; N],
    /// Rows in which the remainder can be non-zero.
    rows: Vec<usize>,
    /// Column `j` of `A` restricted to `rows` (zero beyond them): the remainder's `A·z` is
    /// then a sum of columns, which runs lanes wide.
    a_cols: [[f64; MAX_REMAINDER_ROWS]; N],
    /// `e^{hA}`.
    e: Columns<N>,
    /// `e^{hA/2}`.
    e2: Columns<N>,
    /// Columns `rows` of `(h/2)·φ1(hA/2)`.
    p2: Vec<[f64; N]>,
    /// Weights of the third stage: columns `rows` of `e^{hA/2}·(h/2)·φ1(hA/2)` (so that the
    /// stage can start from `e^{hA}·z`, which the last stage needs anyway: one dense product
    /// fewer per step), then those of `(h/2)·φ1(hA/2)`.
    c3: Vec<[f64; N]>,
    /// Weights of the update: columns `rows` of `h·(φ1 − 3φ2 + 4φ3)(hA)` (first stage), of
    /// `h·(2φ2 − 4φ3)(hA)` (the two middle stages) and of `h·(4φ3 − φ2)(hA)` (last stage).
    c4: Vec<[f64; N]>,
}

/// Why [`Etd4::new`] could not build its coefficients.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Etd4Error {
    /// A matrix exponential overflowed (a step far too long for the matrix).
    #[error("the matrix exponential of h·A is not finite (step {h} s)")]
    NotFinite {
        /// Step \[s\].
        h: f64,
    },
    /// More rows of the right-hand side are nonlinear than the scheme carries.
    #[error("{rows} rows of the right-hand side are nonlinear (at most {MAX_REMAINDER_ROWS})")]
    TooManyNonlinearRows {
        /// Rows found nonlinear.
        rows: usize,
    },
}

impl<const N: usize> Etd4<N> {
    /// Coefficients for step `h` \[s\], matrix `A` (`a[i][j] = A_ij`), reference state `y_ref`,
    /// per-state scales (the exponentials are taken of `D⁻¹·A·D`, `D = diag(scales)`, whose
    /// entries are of similar size) and the right-hand side `f(y)` to probe for its nonlinear
    /// rows, which must include every row an input enters.
    ///
    /// The coefficients are a pure function of `(h, A, y_ref, scales)` and the nonlinear rows,
    /// and their two matrix exponentials (of 4N × 4N and 2N × 2N matrices) cost as much as
    /// a few percent of a 10 s run of the twin: the last few built in this process are kept
    /// and a run of the same plant at the same step (every run after the first of a tuning
    /// search, a sweep of sine dwells, a bench) takes a copy, bit for bit what building them
    /// gives.
    pub fn new(
        h: f64,
        a: &[[f64; N]; N],
        y_ref: [f64; N],
        scales: &[f64; N],
        probe: impl Fn(&[f64; N]) -> [f64; N],
    ) -> Result<Self, Etd4Error> {
        let rows = nonlinear_rows(a, &y_ref, scales, probe);
        let key: Vec<u64> = [h]
            .iter()
            .chain(a.as_flattened())
            .chain(&y_ref)
            .chain(scales)
            .map(|v| v.to_bits())
            .chain(rows.iter().map(|&r| r as u64))
            .collect();
        if let Some(built) = memo::get::<Self>(&key) {
            return Ok(built);
        }
        let built = Self::build(h, a, y_ref, scales, rows)?;
        memo::put(key, built.clone());
        Ok(built)
    }

    /// [`Self::new`] without the kept coefficients, the nonlinear rows found.
    fn build(
        h: f64,
        a: &[[f64; N]; N],
        y_ref: [f64; N],
        scales: &[f64; N],
        rows: Vec<usize>,
    ) -> Result<Self, Etd4Error> {
        use nalgebra::DMatrix;
        let scaled = |i: usize, j: usize| a[i][j] * scales[j] / scales[i];
        // exp([[hÃ, I, 0, 0], [0, 0, I, 0], [0, 0, 0, I], [0, 0, 0, 0]]) has φ0..φ3(hÃ) on its
        // first block row; the 2-block version with hÃ/2 gives e^{hÃ/2} and φ1(hÃ/2).
        let augmented = |blocks: usize, step: f64| {
            let mut m = DMatrix::<f64>::zeros(blocks * N, blocks * N);
            for i in 0..N {
                for j in 0..N {
                    m[(i, j)] = step * scaled(i, j);
                }
                for b in 1..blocks {
                    m[((b - 1) * N + i, b * N + i)] = 1.0;
                }
            }
            m.exp()
        };
        let full = augmented(4, h);
        let half = augmented(2, 0.5 * h);
        if full.iter().chain(half.iter()).any(|v| !v.is_finite()) {
            return Err(Etd4Error::NotFinite { h });
        }
        if rows.len() > MAX_REMAINDER_ROWS {
            return Err(Etd4Error::TooManyNonlinearRows { rows: rows.len() });
        }
        // Column j of a weighted sum of blocks of the first block row, unscaled (D·Φ̃·D⁻¹).
        let column = |m: &DMatrix<f64>, w: &[(usize, f64)], j: usize| {
            let mut col = [0.0; N];
            for (i, v) in col.iter_mut().enumerate() {
                let sum: f64 = w.iter().map(|&(k, c)| c * m[(i, k * N + j)]).sum();
                *v = sum * scales[i] / scales[j];
            }
            col
        };
        let all = |m: &DMatrix<f64>| {
            let mut out = [[0.0; N]; N];
            for (j, col) in out.iter_mut().enumerate() {
                *col = column(m, &[(0, 1.0)], j);
            }
            out
        };
        let cols = |m: &DMatrix<f64>, w: &[(usize, f64)]| -> Vec<[f64; N]> {
            rows.iter().map(|&j| column(m, w, j)).collect()
        };
        let e2 = all(&half);
        let p2 = cols(&half, &[(1, 0.5 * h)]);
        let mut c3: Vec<[f64; N]> = p2
            .iter()
            .map(|c| {
                let mut out = [0.0; N];
                mul_add(&mut out, &e2, c);
                out
            })
            .collect();
        c3.extend_from_slice(&p2);
        let mut c4 = cols(&full, &[(1, h), (2, -3.0 * h), (3, 4.0 * h)]);
        c4.extend(cols(&full, &[(2, 2.0 * h), (3, -4.0 * h)]));
        c4.extend(cols(&full, &[(2, -h), (3, 4.0 * h)]));
        Ok(Self {
            h,
            y_ref,
            a_cols: std::array::from_fn(|j| {
                let mut col = [0.0; MAX_REMAINDER_ROWS];
                for (c, &i) in col.iter_mut().zip(&rows) {
                    *c = a[i][j];
                }
                col
            }),
            e: all(&full),
            e2,
            p2,
            c3,
            c4,
            rows,
        })
    }

    /// Rows of the right-hand side handled explicitly.
    pub fn nonlinear_rows(&self) -> &[usize] {
        &self.rows
    }

    /// One step from `(t, y)`, in place; `f(t, y)` returns `dy/dt`. Stage times are `t`,
    /// `t + h/2` (twice) and `t + h`, as in RK4.
    ///
    /// The number of nonlinear rows is fixed when the coefficients are built, so the step is
    /// dispatched once to a form with that number known at compile time: every product is
    /// then unrolled over fixed-size columns and kept in registers (the twin's 4 rows: about
    /// half the instructions of the loop over a run-time count).
    #[inline(always)]
    pub fn step(&self, t: f64, y: &mut [f64; N], f: impl FnMut(f64, &[f64; N]) -> [f64; N]) {
        match self.rows.len() {
            1 => self.step_k::<1>(t, y, f),
            2 => self.step_k::<2>(t, y, f),
            3 => self.step_k::<3>(t, y, f),
            4 => self.step_k::<4>(t, y, f),
            5 => self.step_k::<5>(t, y, f),
            6 => self.step_k::<6>(t, y, f),
            7 => self.step_k::<7>(t, y, f),
            8 => self.step_k::<8>(t, y, f),
            // No nonlinear row (a linear problem without inputs): the exponential alone.
            _ => {
                let mut z = *y;
                for (v, r) in z.iter_mut().zip(&self.y_ref) {
                    *v -= r;
                }
                let mut ez = [0.0; N];
                mul_add(&mut ez, &self.e, &z);
                for (v, (e, r)) in y.iter_mut().zip(ez.iter().zip(&self.y_ref)) {
                    *v = e + r;
                }
            }
        }
    }

    /// The remainder `R = f − A·z` on the `K` nonlinear `rows`, for `fy = f(y)`.
    #[inline(always)]
    fn remainder<const K: usize>(
        &self,
        rows: &[usize; K],
        fy: &[f64; N],
        z: &[f64; N],
    ) -> [f64; K] {
        let mut az = [0.0; K];
        for (col, zj) in self.a_cols.iter().zip(z) {
            for (s, c) in az.iter_mut().zip(col) {
                *s += c * zj;
            }
        }
        let mut r = [0.0; K];
        for ((r, &i), s) in r.iter_mut().zip(rows).zip(&az) {
            *r = fy[i] - s;
        }
        r
    }

    /// [`Self::step`] with `K` = the number of nonlinear rows.
    #[inline(always)]
    fn step_k<const K: usize>(
        &self,
        t: f64,
        y: &mut [f64; N],
        mut f: impl FnMut(f64, &[f64; N]) -> [f64; N],
    ) {
        let h = self.h;
        fn fixed<const N: usize, const K: usize>(v: &[[f64; N]], from: usize) -> &[[f64; N]; K] {
            v[from..from + K].try_into().expect("K columns per block")
        }
        let rows: &[usize; K] = self.rows[..K].try_into().expect("K rows");
        let p2 = fixed::<N, K>(&self.p2, 0);
        let (c3a, c3b) = (fixed::<N, K>(&self.c3, 0), fixed::<N, K>(&self.c3, K));
        let (c4a, c4b, c4c) = (
            fixed::<N, K>(&self.c4, 0),
            fixed::<N, K>(&self.c4, K),
            fixed::<N, K>(&self.c4, 2 * K),
        );
        let shift = |z: &[f64; N]| {
            let mut y = *z;
            for (v, r) in y.iter_mut().zip(&self.y_ref) {
                *v += r;
            }
            y
        };
        let mut z = *y;
        for (v, r) in z.iter_mut().zip(&self.y_ref) {
            *v -= r;
        }
        let nu = self.remainder::<K>(rows, &f(t, y), &z);
        let mut e2z = [0.0; N];
        mul_add(&mut e2z, &self.e2, &z);
        let mut ez = [0.0; N];
        mul_add(&mut ez, &self.e, &z);
        let mut za = e2z;
        mul_add(&mut za, p2, &nu);
        let na = self.remainder::<K>(rows, &f(t + 0.5 * h, &shift(&za)), &za);
        let mut zb = e2z;
        mul_add(&mut zb, p2, &na);
        let nb = self.remainder::<K>(rows, &f(t + 0.5 * h, &shift(&zb)), &zb);
        // e^{hA/2}·za = e^{hA}·z + e^{hA/2}·(h/2)·φ1(hA/2)·nu.
        let mut zc = ez;
        mul_add(&mut zc, c3a, &nu);
        let mut w = [0.0; K];
        for ((w, &b), &u) in w.iter_mut().zip(&nb).zip(&nu) {
            *w = 2.0 * b - u;
        }
        mul_add(&mut zc, c3b, &w);
        let nc = self.remainder::<K>(rows, &f(t + h, &shift(&zc)), &zc);
        let mut out = ez;
        mul_add(&mut out, c4a, &nu);
        for ((w, &a), &b) in w.iter_mut().zip(&na).zip(&nb) {
            *w = a + b;
        }
        mul_add(&mut out, c4b, &w);
        mul_add(&mut out, c4c, &nc);
        *y = shift(&out);
    }
}

/// Rows `i` where `f_i(y) − A_i·(y − y_ref)` is not ≈ 0 for states from 0.3 to 30 scales away
/// from `y_ref` (far enough to reach saturations and end stops), i.e. the rows that are not
/// affine with matrix `A` and an equilibrium at `y_ref`.
fn nonlinear_rows<const N: usize>(
    a: &[[f64; N]; N],
    y_ref: &[f64; N],
    scales: &[f64; N],
    f: impl Fn(&[f64; N]) -> [f64; N],
) -> Vec<usize> {
    let mut nonlinear = [false; N];
    // A fixed, irregular pattern of signs and sizes per state (no RNG: reproducible).
    let pattern = [
        0.83, -0.41, 0.67, -0.97, 0.29, -0.55, 0.76, -0.18, 0.92, -0.63,
    ];
    for (p, amplitude) in [0.3, 3.0, 30.0].into_iter().enumerate() {
        for flip in [1.0, -1.0] {
            let mut z = [0.0; N];
            for (j, v) in z.iter_mut().enumerate() {
                *v = flip * amplitude * pattern[(j + 3 * p) % pattern.len()] * scales[j];
            }
            let mut y = *y_ref;
            for (v, dz) in y.iter_mut().zip(&z) {
                *v += dz;
            }
            let fy = f(&y);
            for i in 0..N {
                let linear: f64 = (0..N).map(|j| a[i][j] * z[j]).sum();
                let size: f64 = (0..N).map(|j| (a[i][j] * z[j]).abs()).sum::<f64>() + fy[i].abs();
                if (fy[i] - linear).abs() > 1e-9 * size.max(f64::MIN_POSITIVE) {
                    nonlinear[i] = true;
                }
            }
        }
    }
    (0..N).filter(|&i| nonlinear[i]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// What [`Etd4::new`] gives, built afresh or a kept copy, is what building gives, and a
    /// problem that differs in its step only gets its own coefficients.
    #[test]
    fn kept_coefficients_are_the_built_ones_of_the_same_problem() {
        let a = [[-3.0, 1.0], [0.5, -40.0]];
        let f = |y: &[f64; 2]| {
            [
                a[0][0] * y[0] + a[0][1] * y[1] + y[0].powi(3),
                a[1][0] * y[0] + a[1][1] * y[1],
            ]
        };
        let (y_ref, scales) = ([0.0, 0.0], [1.0, 2.0]);
        let rows = nonlinear_rows(&a, &y_ref, &scales, f);
        assert_eq!(rows, [0]);
        let built = format!("{:?}", Etd4::build(1e-2, &a, y_ref, &scales, rows).unwrap());
        for _ in 0..2 {
            let given = Etd4::new(1e-2, &a, y_ref, &scales, f).unwrap();
            assert_eq!(format!("{given:?}"), built);
        }
        let other = Etd4::new(2e-2, &a, y_ref, &scales, f).unwrap();
        assert_ne!(format!("{other:?}"), built);
        assert_eq!(
            format!("{other:?}"),
            format!(
                "{:?}",
                Etd4::build(2e-2, &a, y_ref, &scales, vec![0]).unwrap()
            )
        );
    }

    /// y' = −y, y(0) = 1: the error at t = 1 falls 16× per halving of the step.
    #[test]
    fn fourth_order_on_exponential_decay() {
        let err = |n: usize| {
            let h = 1.0 / n as f64;
            let mut y = [1.0];
            for i in 0..n {
                rk4_step(i as f64 * h, h, &mut y, |_, y| [-y[0]]);
            }
            (y[0] - (-1.0f64).exp()).abs()
        };
        let ratio = err(20) / err(40);
        assert!((ratio - 16.0).abs() < 1.0, "ratio {ratio}");
    }

    /// A lightly damped oscillator with a nonlinear forcing: ETD4 with its A equal to the
    /// oscillator is 4th order; with A = 0 it is RK4 (to round-off).
    #[test]
    fn etd4_is_fourth_order_and_reduces_to_rk4() {
        let w = 50.0;
        let f = |t: f64, y: &[f64; 2]| {
            [
                y[1],
                -w * w * y[0] - 0.2 * y[1] + (t.sin() + 30.0 * y[0] * y[0]),
            ]
        };
        let a = [[0.0, 1.0], [-w * w, -0.2]];
        let run = |n: usize, a: &[[f64; 2]; 2]| {
            let h = 1.0 / n as f64;
            let etd = Etd4::new(h, a, [0.0; 2], &[1.0, w], |y| f(0.0, y)).unwrap();
            assert_eq!(etd.nonlinear_rows(), &[1]);
            let mut y = [0.01, 0.0];
            for i in 0..n {
                etd.step(i as f64 * h, &mut y, f);
            }
            y[0]
        };
        let exact = run(20_000, &a);
        let e1 = (run(100, &a) - exact).abs();
        let e2 = (run(200, &a) - exact).abs();
        assert!((e1 / e2 - 16.0).abs() < 3.0, "ratio {}", e1 / e2);
        // At h·ω = 0.5 RK4 is far off; ETD4 with the linear part exact is not.
        let h = 1.0 / 100.0;
        let etd0 = Etd4::new(h, &[[0.0; 2]; 2], [0.0; 2], &[1.0, w], |y| f(0.0, y)).unwrap();
        assert_eq!(etd0.nonlinear_rows(), &[0, 1]);
        let (mut y, mut yr) = ([0.01, 0.0], [0.01, 0.0]);
        for i in 0..100 {
            let t = i as f64 * h;
            etd0.step(t, &mut y, f);
            rk4_step(t, h, &mut yr, f);
        }
        assert!((y[0] - yr[0]).abs() <= 1e-12 * yr[0].abs().max(1e-3));
        assert!(
            (yr[0] - exact).abs() > 100.0 * e1,
            "rk4 {} etd {e1}",
            (yr[0] - exact).abs()
        );
    }
}
