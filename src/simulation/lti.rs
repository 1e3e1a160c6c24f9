//! Exact discretisation of the linear models (G(s) and the passive seat) for fast runs.
//!
//! The linear model and the passive reference are linear time-invariant, so instead of RK4 at
//! the twin's 0.1 ms step they are advanced at the output interval with the exact transition
//! of a first-order hold: over one step `[t_k, t_k + h]` the inputs `w = (V_valve, ẍ)` are
//! taken as linear between their sampled values, and
//!
//! ```text
//! x_{k+1} = Φ·x_k + Γa·w_k + Γb·(w_{k+1} − w_k)/h,
//! exp([[A, B, 0], [0, 0, I], [0, 0, 0]]·h) = [[Φ, Γa, Γb], [0, I, h·I], [0, 0, I]]
//! ```
//!
//! (one matrix exponential, computed once per run). The only approximation is the hold of
//! the inputs between samples, O(h²) in their curvature; `tests/it/physics.rs` checks the result
//! against the closed-form transmissibility and this module's tests against a fine RK4 run.
//! `A` and `B` are read off the model's own [`Model::derivatives`] (exact for a linear model),
//! so there is one definition of each model.
//!
//! [`ExactHold`] is one more stepper of the same problem as RK4 and the exponential method: a
//! [`Simulation`](super::Simulation) built with
//! [`Simulation::exact_hold`](super::Simulation::exact_hold) keeps its controller, saturation,
//! pure delay and excitation, and only the step itself differs: it reads the inputs at the
//! step's two ends instead of evaluating the right-hand side at stages. The delayed command at
//! the step's end must be known before the step, so this needs `τ ≥ h` (or no command at all);
//! otherwise `exact_hold` returns `None` and the caller keeps RK4.

use crate::model::{Inputs, Model};
use crate::simulation::memo;
use nalgebra::{DMatrix, SMatrix};

/// First word of an [`ExactHold`]'s key among the kept coefficients (no step's bits: a NaN).
const KEY_TAG: u64 = 0x7ff8_e4ac_7401_d000;

/// Marker for models whose derivatives are linear in state and inputs.
pub trait LinearTimeInvariant {}

impl LinearTimeInvariant for crate::model::linear::LinearModel {}
impl LinearTimeInvariant for crate::model::passive::PassiveModel {}

/// The exact transition of a linear model over one step with its inputs
/// `w = (V_valve [V], ẍ [m/s²])` linear between the step's ends (first-order hold).
#[derive(Debug, Clone, PartialEq)]
pub struct ExactHold<const N: usize> {
    /// Rows of Φ.
    phi: [[f64; N]; N],
    /// Rows of `Γa − Γb/h`, applied to the inputs at the start of a step.
    g0: [[f64; 2]; N],
    /// Rows of `Γb/h`, applied to the inputs at the end of a step.
    g1: [[f64; 2]; N],
}

impl<const N: usize> ExactHold<N> {
    /// The transition of `model` (linear: its `A` and `B` are read off its derivatives) over a
    /// step `h` \[s\].
    ///
    /// A pure function of `A`, `B` and `h`, whose matrix exponential costs about 45 000
    /// instructions, some 2 % of a 10 s run of the linear model at 1 ms: the last few built in
    /// this process are kept with the exponential method's coefficients, and a run of the same
    /// model at the same step (the bench's repeated runs, a sweep, a tuning search) takes a
    /// copy, bit for bit what building gives.
    pub fn new<M: Model<N>>(model: &M, h: f64) -> Self {
        let (a, b) = state_space(model);
        // Tagged, so that no key of the exponential method's coefficients (which start with
        // the bits of a step) is taken for one of these.
        let key: Vec<u64> = [KEY_TAG, N as u64, h.to_bits()]
            .into_iter()
            .chain(a.iter().chain(b.iter()).map(|v| v.to_bits()))
            .collect();
        if let Some(kept) = memo::get::<Self>(&key) {
            return kept;
        }
        let built = Self::build(&a, &b, h);
        memo::put(key, built.clone());
        built
    }

    /// [`Self::new`] without the kept transitions, from `A`, `B` and `h` [s].
    fn build(a: &SMatrix<f64, N, N>, b: &SMatrix<f64, N, 2>, h: f64) -> Self {
        let (phi, gamma_a, gamma_b) = foh(a, b, h);
        // x_{k+1} = Φ·x_k + (Γa − Γb/h)·w_k + (Γb/h)·w_{k+1}, by rows.
        let g1 = gamma_b / h;
        let g0 = gamma_a - g1;
        let rows2 = |m: SMatrix<f64, N, 2>| std::array::from_fn(|i| [m[(i, 0)], m[(i, 1)]]);
        Self {
            phi: std::array::from_fn(|i| std::array::from_fn(|j| phi[(i, j)])),
            g0: rows2(g0),
            g1: rows2(g1),
        }
    }

    /// One step of `y` in place, the inputs `(V_valve, ẍ)` being `w0` at its start and `w1` at
    /// its end.
    #[inline(always)]
    pub fn step(&self, y: &mut [f64; N], w0: [f64; 2], w1: [f64; 2]) {
        let y0 = *y;
        for (i, yi) in y.iter_mut().enumerate() {
            let (g0, g1) = (self.g0[i], self.g1[i]);
            let mut acc = g0[0] * w0[0] + g0[1] * w0[1] + g1[0] * w1[0] + g1[1] * w1[1];
            for (p, yj) in self.phi[i].iter().zip(&y0) {
                acc += p * yj;
            }
            *yi = acc;
        }
    }
}

/// `A` and `B = [b_v, b_ẍ]` of a linear model, read off its derivatives at rest.
fn state_space<M: Model<N>, const N: usize>(model: &M) -> (SMatrix<f64, N, N>, SMatrix<f64, N, 2>) {
    let zero = [0.0; N];
    let f = |y: &[f64; N], v: f64, xdd: f64| model.derivatives(0.0, y, &Inputs { v_valve: v, xdd });
    let f0 = f(&zero, 0.0, 0.0);
    let mut a = SMatrix::<f64, N, N>::zeros();
    for j in 0..N {
        let mut e = zero;
        e[j] = 1.0;
        let fj = f(&e, 0.0, 0.0);
        for i in 0..N {
            a[(i, j)] = fj[i] - f0[i];
        }
    }
    let mut b = SMatrix::<f64, N, 2>::zeros();
    let (fv, fx) = (f(&zero, 1.0, 0.0), f(&zero, 0.0, 1.0));
    for i in 0..N {
        b[(i, 0)] = fv[i] - f0[i];
        b[(i, 1)] = fx[i] - f0[i];
    }
    (a, b)
}

/// First-order-hold transition matrices `(Φ, Γa, Γb)` for step `h`.
#[allow(clippy::type_complexity)]
fn foh<const N: usize>(
    a: &SMatrix<f64, N, N>,
    b: &SMatrix<f64, N, 2>,
    h: f64,
) -> (SMatrix<f64, N, N>, SMatrix<f64, N, 2>, SMatrix<f64, N, 2>) {
    let size = N + 4;
    let mut m = DMatrix::<f64>::zeros(size, size);
    for i in 0..N {
        for j in 0..N {
            m[(i, j)] = a[(i, j)] * h;
        }
        for j in 0..2 {
            m[(i, N + j)] = b[(i, j)] * h;
        }
    }
    for j in 0..2 {
        m[(N + j, N + 2 + j)] = h;
    }
    let e = m.exp();
    let phi = SMatrix::<f64, N, N>::from_fn(|i, j| e[(i, j)]);
    let gamma_a = SMatrix::<f64, N, 2>::from_fn(|i, j| e[(i, N + j)]);
    let gamma_b = SMatrix::<f64, N, 2>::from_fn(|i, j| e[(i, N + 2 + j)]);
    (phi, gamma_a, gamma_b)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::linear::LinearModel;
    use crate::model::passive::PassiveModel;
    use crate::params::Params;
    use crate::scenario::{CommandSignal, PlatformMotion, RandomRide};
    use crate::simulation::{CommandPath, Drive, Run, Simulation};

    /// Largest difference of ÿ and u between the exact-hold run at 1 ms and RK4 at 10 µs.
    fn compare<M: Model<N> + CommandPath + LinearTimeInvariant + Clone, const N: usize>(
        model: M,
        drive: Drive,
        platform: PlatformMotion,
        t_from: f64,
    ) -> (f64, f64, f64) {
        let fast = Simulation::exact_hold(model.clone(), 1e-3, drive.clone(), platform.clone())
            .expect("τ ≥ h")
            .run_trace(4.0, 1000.0)
            .unwrap();
        let fine = Simulation::new(model, 1e-5, drive, platform)
            .run_trace(4.0, 1000.0)
            .unwrap();
        assert_eq!(fast.samples.len(), fine.samples.len());
        let mut e_ydd: f64 = 0.0;
        let mut e_u: f64 = 0.0;
        let mut peak: f64 = 0.0;
        for (a, b) in fast.samples.iter().zip(&fine.samples) {
            assert!((a.t - b.t).abs() < 1e-9);
            if a.t < t_from {
                continue;
            }
            e_ydd = e_ydd.max((a.ydd - b.ydd).abs());
            e_u = e_u.max((a.u - b.u).abs());
            peak = peak.max(b.ydd.abs());
        }
        (e_ydd, e_u, peak)
    }

    fn ride() -> PlatformMotion {
        PlatformMotion::Sampled(
            RandomRide {
                duration_s: 4.0,
                fade_in_s: 1.0,
                seed: 3,
                ..Default::default()
            }
            .generate(),
        )
    }

    /// On the closed-loop ride the exact hold is within 0.2 % of the peak ÿ and 1 µm of u of
    /// fine RK4.
    fn assert_exact_on_the_ride<M, const N: usize>(model: M)
    where
        M: Model<N> + CommandPath + LinearTimeInvariant + Clone,
    {
        let p = Params::paper();
        let (e_ydd, e_u, peak) = compare(model, Drive::closed_loop(&p), ride(), 0.0);
        assert!(e_ydd < 2e-3 * peak, "ÿ error {e_ydd} of peak {peak}");
        assert!(e_u < 1e-6, "u error {e_u}");
    }

    #[test]
    fn exact_hold_matches_fine_rk4_on_the_closed_loop_ride() {
        assert_exact_on_the_ride(LinearModel::new(&Params::paper()));
    }

    #[test]
    fn exact_hold_matches_fine_rk4_on_an_open_loop_sine_and_the_passive_seat() {
        let p = Params::paper();
        let drive = Drive::OpenLoop(CommandSignal::Sine {
            amplitude_v: 1.1,
            freq_hz: 10.0,
        });
        // The sine test's command jumps to A at t = τ (17.5 ms, between grid points of 1 ms):
        // the hold smears that jump, so compare once its 80 Hz ring has died out.
        let (e_ydd, _, peak) = compare(LinearModel::new(&p), drive, PlatformMotion::Still, 0.5);
        assert!(e_ydd < 5e-3 * peak, "ÿ error {e_ydd} of peak {peak}");
        assert_exact_on_the_ride(PassiveModel::new(&p));
    }

    #[test]
    fn a_kept_transition_is_the_built_one_of_the_same_model_and_step() {
        let mut p = Params::paper();
        p.linear.zeta = 0.0731;
        let model = LinearModel::new(&p);
        let (a, b) = state_space(&model);
        let built = ExactHold::build(&a, &b, 1e-3);
        assert_eq!(ExactHold::new(&model, 1e-3), built);
        assert_eq!(ExactHold::new(&model, 1e-3), built);
        // Another step or another model is another transition.
        assert_ne!(ExactHold::new(&model, 5e-4), built);
        p.linear.zeta = 0.0732;
        assert_ne!(ExactHold::new(&LinearModel::new(&p), 1e-3), built);
    }

    #[test]
    fn a_delay_shorter_than_the_step_is_refused() {
        let mut p = Params::paper();
        p.linear.tau_s = 5e-4;
        let sim = Simulation::exact_hold(
            LinearModel::new(&p),
            1e-3,
            Drive::closed_loop(&p),
            PlatformMotion::Still,
        );
        assert!(sim.is_none());
    }
}
