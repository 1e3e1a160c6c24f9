//! Fixed-step classical Runge–Kutta (RK4) on `[f64; N]`, plus step statistics.
//!
//! Why RK4 with a fixed step: the twin is not stiff for explicit methods (its fastest modes are
//! the lightly damped hose L–C modes near 5.8e3 rad/s, MODEL_NOTES 9), a fixed step keeps the
//! pure input delay on a uniform grid, and the same step everywhere makes runs reproducible
//! bit for bit. Its 4th order is verified in `tests/integrator.rs` (halving the step divides
//! the error by ≈16) and its accuracy against a 10× finer run is measured by `seat-twin bench`.

/// Counters of integrator work, so that a regression shows as work before it shows as time.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
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

#[cfg(test)]
mod tests {
    use super::*;

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
}
