//! The numerics under the verdict: a pure delay as a Chebyshev-collocated transport equation,
//! Clenshaw–Curtis weights on the same nodes, and balanced eigenvalues.

use nalgebra::{DMatrix, DVector, Schur};
use num_complex::Complex64;
use std::f64::consts::PI;

/// A pure delay `T` of one scalar signal, as the Chebyshev collocation of the transport
/// equation: states `φ(θ_j)` at `θ_j = T·(cos(jπ/n) − 1)/2`, `j = 1..=n` (the input sits at
/// `j = 0`, `θ = 0`; the output is the last state, `θ = −T`). `φ̇ = a·φ + b·input`.
#[derive(Debug, Clone)]
pub struct DelayBlock {
    /// State matrix (n × n) [1/s].
    pub a: DMatrix<f64>,
    /// Input column (n) [1/s].
    pub b: DVector<f64>,
}

impl DelayBlock {
    /// The block for a delay `delay_s` > 0 \[s\] with `n` ≥ 2 collocation states.
    pub fn new(delay_s: f64, n: usize) -> Self {
        let x: Vec<f64> = (0..=n).map(|j| (PI * j as f64 / n as f64).cos()).collect();
        let c = |j: usize| if j == 0 || j == n { 2.0 } else { 1.0 };
        let mut d = DMatrix::<f64>::zeros(n + 1, n + 1);
        for i in 0..=n {
            for j in 0..=n {
                if i != j {
                    let sign = if (i + j) % 2 == 0 { 1.0 } else { -1.0 };
                    d[(i, j)] = c(i) / c(j) * sign / (x[i] - x[j]);
                }
            }
        }
        for i in 0..=n {
            let off: f64 = (0..=n).filter(|&j| j != i).map(|j| d[(i, j)]).sum();
            d[(i, i)] = -off;
        }
        // d/dθ = (2/T)·d/dx.
        let scale = 2.0 / delay_s;
        Self {
            a: d.view((1, 1), (n, n)) * scale,
            b: d.view((1, 0), (n, 1)).column(0) * scale,
        }
    }

    /// The block's transfer function at `omega` [rad/s] (≈ `e^(−jωT)`), for checking.
    pub fn response(&self, omega: f64) -> Complex64 {
        let n = self.a.nrows();
        let m = DMatrix::from_fn(n, n, |i, j| {
            Complex64::new(-self.a[(i, j)], if i == j { omega } else { 0.0 })
        });
        let rhs = self.b.map(|v| Complex64::new(v, 0.0));
        m.lu()
            .solve(&rhs)
            .map_or(Complex64::new(f64::NAN, f64::NAN), |z| z[n - 1])
    }
}

/// Clenshaw–Curtis weights on `[−1, 1]` at the Chebyshev points `cos(jπ/n)`, `j = 0..=n`
/// (they sum to 2 and integrate polynomials of degree ≤ n exactly).
pub fn clenshaw_curtis(n: usize) -> Vec<f64> {
    let nf = n as f64;
    let mut w = vec![0.0; n + 1];
    if n == 0 {
        w[0] = 2.0;
        return w;
    }
    let ends = if n.is_multiple_of(2) {
        1.0 / (nf * nf - 1.0)
    } else {
        1.0 / (nf * nf)
    };
    w[0] = ends;
    w[n] = ends;
    for (j, wj) in w.iter_mut().enumerate().take(n).skip(1) {
        let theta = PI * j as f64 / nf;
        let mut v = 1.0;
        for k in 1..=(n - 1) / 2 {
            let kf = k as f64;
            v -= 2.0 * (2.0 * kf * theta).cos() / (4.0 * kf * kf - 1.0);
        }
        if n.is_multiple_of(2) {
            v -= (nf * theta).cos() / (nf * nf - 1.0);
        }
        *wj = 2.0 * v / nf;
    }
    w
}

/// Balances a matrix by diagonal similarity with powers of two (rows and columns of equal
/// norm), as LAPACK's `gebal` does before an eigenvalue solve: the eigenvalues are the same and
/// their rounding errors much smaller for a matrix whose entries span many decades.
fn balance(m: &mut DMatrix<f64>) {
    let n = m.nrows();
    for _sweep in 0..100 {
        let mut changed = false;
        for i in 0..n {
            let c: f64 = (0..n).filter(|&j| j != i).map(|j| m[(j, i)].abs()).sum();
            let r: f64 = (0..n).filter(|&j| j != i).map(|j| m[(i, j)].abs()).sum();
            if c == 0.0 || r == 0.0 {
                continue;
            }
            let mut f = 1.0;
            let (mut cc, mut rr) = (c, r);
            while cc < rr / 2.0 {
                cc *= 2.0;
                rr /= 2.0;
                f *= 2.0;
            }
            while cc >= rr * 2.0 {
                cc /= 2.0;
                rr *= 2.0;
                f /= 2.0;
            }
            if (cc + rr) < 0.95 * (c + r) {
                changed = true;
                for j in 0..n {
                    m[(i, j)] /= f;
                    m[(j, i)] *= f;
                }
            }
        }
        if !changed {
            break;
        }
    }
}

/// Eigenvalues of a real matrix, balanced first; `None` if the QR iteration does not converge.
pub fn eigenvalues(m: &DMatrix<f64>) -> Option<Vec<Complex64>> {
    let mut b = m.clone();
    balance(&mut b);
    Schur::try_new(b, 1e-15, 100_000).map(|s| s.complex_eigenvalues().iter().copied().collect())
}
