//! The stability verdict of a closed loop with delays: one function, [`Stability::of`], used by
//! the app's Stable line and banner, `tune`, `transmissibility` and the reports;
//! [`twin_stability`] and [`linear_stability`] give it for a parameter set's twin and G(s).
//!
//! # The verdict: closed-loop eigenvalues with the delays
//! The plant is a model linearised at rest ([`LinearisedModel`]: `ẋ = A·x + b·V(t − τ)`), the
//! controller is the feedback part of a [`ControlLaw`] (the feed-forward from `ẍ` is outside
//! the loop), and every pure delay in the loop (the valve's τ, the Smith predictor's model
//! delay τm) is a transport equation `∂φ/∂t = ∂φ/∂θ` on `θ ∈ [−T, 0]` with `φ(0, t)` the
//! delayed signal's input, discretised by Chebyshev collocation on `order + 1` points
//! ([`DelayBlock`]). The rightmost eigenvalues of the resulting matrix converge spectrally to
//! the characteristic roots of the delay system as the order rises (the infinitesimal-generator
//! method of Breda, Maset and Vermiglio); the verdict computes them at two orders and reports
//! how much the rightmost one moved ([`ClosedLoopModes::order_change`]). A loop is stable when
//! the rightmost real part is negative by more than that change.
//!
//! # The margins: every crossing
//! [`LoopMargins`] reads every gain crossover (|L| = 1, with its phase margin and delay margin)
//! and every phase crossover (L on the negative real axis, with its gain margin) of the loop
//! gain `L(jω)` on a frequency grid that is refined around every lightly damped open-loop pole
//! (known from the plant's Jacobian): a resonance of damping ratio 3e-4 is 0.04 Hz wide at
//! 77 Hz, far narrower than any fixed log grid. Each crossing is then located by bisection on
//! `L` itself. The margins describe; the eigenvalues decide.

mod delay;
mod margins;

pub use delay::{DelayBlock, clenshaw_curtis, eigenvalues};
pub use margins::{GainCrossover, LoopMargins, PhaseCrossover, margin_grid};

use crate::analysis::frequency_response::{
    LinearisedModel, OpenLoop, linearise_linear, linearise_twin,
};
use crate::control::ControlLaw;
use crate::params::{ControllerKind, Params};
use nalgebra::{DMatrix, DVector};
use num_complex::Complex64;
use std::f64::consts::PI;

/// Chebyshev orders of the delay blocks at which the eigenvalues are computed and compared.
pub const ORDERS: [usize; 2] = [28, 40];

/// Highest frequency of the margin grid \[Hz\] (above the valve's and the oil column's modes).
pub const MARGIN_F_MAX_HZ: f64 = 1000.0;

/// The plant as the loop sees it: `ẋ = a·x + b·V(t − τ)`, the stroke `u = u_row·x` and the
/// body acceleration `ÿ = ydd_row·x + ydd_b·V(t − τ)` (platform still), in scaled states.
#[derive(Debug, Clone)]
pub struct LoopPlant {
    a: DMatrix<f64>,
    b: DVector<f64>,
    u_row: DVector<f64>,
    ydd_row: DVector<f64>,
    ydd_b: f64,
    /// Neutral modes taken out: conserved quantities that neither the command nor anything
    /// else moves (the closed chambers' pressure level with the valve at null).
    pub neutral_modes: usize,
}

impl LoopPlant {
    /// The linearised plant in scaled states, with its loop-independent neutral modes removed:
    /// each left null vector `w` of `[A b]` (`wᵀA = 0`, `wᵀb = 0`) is a conserved quantity
    /// `wᵀx` that no controller changes and that does not grow; the plant is projected on the
    /// orthogonal complement of those vectors, which keeps every other eigenvalue.
    pub fn new(plant: &LinearisedModel) -> Self {
        let scales = plant.scales();
        let np = scales.len();
        let a = plant.a();
        let bv = plant.b_v();
        // Scaled plant: x = D·x̃.
        let at = DMatrix::from_fn(np, np, |i, j| a[(i, j)] * scales[j] / scales[i]);
        let bt = DVector::from_fn(np, |i, _| bv[i] / scales[i]);
        let (u_i, du_i) = (0, 1);
        let unit =
            |i: usize, scale: f64| DVector::from_fn(np, |k, _| if k == i { scale } else { 0.0 });
        let u_row = unit(u_i, scales[u_i]);
        let ydd_row = at.row(du_i).transpose() * scales[du_i];
        let ydd_b = bt[du_i] * scales[du_i];
        let mut ab = DMatrix::<f64>::zeros(np, np + 1);
        ab.view_mut((0, 0), (np, np)).copy_from(&at);
        ab.set_column(np, &bt);
        let svd = ab.svd(true, false);
        let sv = svd.singular_values;
        let tol = 1e-9 * sv.max();
        let keep: Vec<usize> = (0..np).filter(|&k| sv[k] > tol).collect();
        let (Some(u), false) = (svd.u, keep.len() == np) else {
            // Nothing to take out (or no basis to take it out with).
            return Self {
                a: at,
                b: bt,
                u_row,
                ydd_row,
                ydd_b,
                neutral_modes: 0,
            };
        };
        let q = u.select_columns(&keep);
        Self {
            a: q.tr_mul(&at) * &q,
            b: q.tr_mul(&bt),
            u_row: q.tr_mul(&u_row),
            ydd_row: q.tr_mul(&ydd_row),
            ydd_b,
            neutral_modes: np - keep.len(),
        }
    }
}

/// The closed loop's state matrix: the plant ([`LoopPlant`]), the controller's feedback states,
/// and a [`DelayBlock`] of `order` states for each delay in the loop. `tau_s` is the command
/// delay (the plant's own `tau_s` is not read, so a delay-free linearisation can be reused).
pub fn closed_loop_matrix(
    plant: &LoopPlant,
    law: &ControlLaw,
    tau_s: f64,
    order: usize,
) -> DMatrix<f64> {
    let c = law.params();
    let np = plant.a.nrows();
    let model = law.model();
    // Without a model delay the Smith prediction `ũ − ũ(t − τm)` is zero: no states.
    let smith_delay = c.kind == ControllerKind::Smith && model.tau_s > 0.0;
    let nc = match c.kind {
        ControllerKind::Paper | ControllerKind::Predictive => 0,
        ControllerKind::Skyhook => 2,
        ControllerKind::Smith => 2 * usize::from(smith_delay),
    };
    let plant_delay = tau_s > 0.0;
    let c0 = np;
    let d0 = c0 + nc;
    let m0 = d0 + if plant_delay { order } else { 0 };
    let n = m0 + if smith_delay { order } else { 0 };
    let mut m = DMatrix::<f64>::zeros(n, n);
    // The controller's output V as a row over the states.
    let mut v_row = DVector::<f64>::zeros(n);
    for j in 0..np {
        v_row[j] += c.kp_v_per_m * plant.u_row[j];
    }
    match c.kind {
        ControllerKind::Paper | ControllerKind::Predictive => {}
        ControllerKind::Skyhook => v_row[c0 + 1] += c.sky_v_s_per_m,
        ControllerKind::Smith => {
            if smith_delay {
                // The prediction `ũ(t) − ũ(t − τm) = Kg·∫ w` over the last τm, by
                // Clenshaw–Curtis quadrature on the delay block's nodes (node 0 is w now).
                let q = clenshaw_curtis(order);
                let half = 0.5 * model.tau_s * model.kg_m_per_s_v * c.kp_v_per_m;
                v_row[c0] += half * q[0];
                for j in 1..=order {
                    v_row[m0 + j - 1] += half * q[j];
                }
            }
        }
    }
    // The command the valve sees: V delayed by τ, or V itself.
    let vd_row = if plant_delay {
        let mut r = DVector::<f64>::zeros(n);
        r[m0 - 1] = 1.0;
        r
    } else {
        v_row.clone()
    };
    m.view_mut((0, 0), (np, np)).copy_from(&plant.a);
    for i in 0..np {
        for j in 0..n {
            m[(i, j)] += plant.b[i] * vd_row[j];
        }
    }
    match c.kind {
        ControllerKind::Skyhook => {
            // q̇ = −ωl·q + ÿ (ÿ = ü with the platform still), ṙ = −ωs·r + ωs·q.
            let (wl, ws) = (2.0 * PI * c.leak_hz, 2.0 * PI * c.sky_cutoff_hz);
            let (q, r) = (c0, c0 + 1);
            for j in 0..n {
                let plant_part = if j < np { plant.ydd_row[j] } else { 0.0 };
                m[(q, j)] += plant_part + plant.ydd_b * vd_row[j];
            }
            m[(q, q)] -= wl;
            m[(r, q)] += ws;
            m[(r, r)] -= ws;
        }
        ControllerKind::Smith if smith_delay => {
            // The model's second-order section [w, ẇ]: ẅ + 2ζ·sp·ẇ + sp²·w = sp²·V, and
            // ũ̇ = Kg·w. ũ itself is not a state: only its change over τm reaches V (carrying
            // it would add a neutral mode, its level).
            let sp2 = model.sp_rad_s * model.sp_rad_s;
            m[(c0, c0 + 1)] = 1.0;
            m[(c0 + 1, c0)] = -sp2;
            m[(c0 + 1, c0 + 1)] = -2.0 * model.zeta * model.sp_rad_s;
            for j in 0..n {
                m[(c0 + 1, j)] += sp2 * v_row[j];
            }
        }
        _ => {}
    }
    if plant_delay {
        let block = DelayBlock::new(tau_s, order);
        m.view_mut((d0, d0), (order, order)).copy_from(&block.a);
        for i in 0..order {
            for j in 0..n {
                m[(d0 + i, j)] += block.b[i] * v_row[j];
            }
        }
    }
    if smith_delay {
        let block = DelayBlock::new(model.tau_s, order);
        m.view_mut((m0, m0), (order, order)).copy_from(&block.a);
        for i in 0..order {
            m[(m0 + i, c0)] += block.b[i];
        }
    }
    m
}

/// The closed loop's rightmost mode, at two delay orders.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct ClosedLoopModes {
    /// Growth rate of the rightmost mode, its real part [1/s] (negative: it decays).
    pub growth_rate_per_s: f64,
    /// Its frequency `|Im λ|/2π` \[Hz\].
    pub freq_hz: f64,
    /// Delay order of the reported eigenvalue (the higher of [`ORDERS`]).
    pub order: usize,
    /// How far the rightmost eigenvalue moved between the two orders [1/s].
    pub order_change: f64,
    /// Neutral modes of the plant outside the loop, left out ([`LoopPlant::neutral_modes`]).
    pub neutral_modes: usize,
}

impl ClosedLoopModes {
    /// The rightmost closed-loop mode of `plant` with `law` and the command delay `tau_s`;
    /// `None` if an eigenvalue solve did not converge.
    pub fn of(plant: &LoopPlant, law: &ControlLaw, tau_s: f64) -> Option<Self> {
        let rightmost = |order| -> Option<Complex64> {
            let eig = eigenvalues(&closed_loop_matrix(plant, law, tau_s, order))?;
            eig.into_iter()
                .filter(|l| l.re.is_finite() && l.im.is_finite())
                .max_by(|a, b| a.re.total_cmp(&b.re))
        };
        let lo = rightmost(ORDERS[0])?;
        let hi = rightmost(ORDERS[1])?;
        Some(Self {
            growth_rate_per_s: hi.re,
            freq_hz: hi.im.abs() / (2.0 * PI),
            order: ORDERS[1],
            order_change: (hi - lo).norm(),
            neutral_modes: plant.neutral_modes,
        })
    }

    /// The decay rate must beat the discretisation's own uncertainty (and 1e-6 1/s): a mode
    /// that does not decay, such as an uncontrolled integrator (`Kp = 0`), is not stable.
    pub fn stable(&self) -> bool {
        self.growth_rate_per_s < -(1e-6_f64).max(10.0 * self.order_change)
    }
}

/// The poles of the controller's feedback part (the Smith predictor's inner loop; the skyhook
/// filters' real poles), for the margin grid.
pub(super) fn controller_poles(law: &ControlLaw) -> Vec<Complex64> {
    let c = law.params();
    match c.kind {
        ControllerKind::Smith => {
            // The inner loop alone: no plant, only the model and its delay.
            let none = LoopPlant {
                a: DMatrix::zeros(0, 0),
                b: DVector::zeros(0),
                u_row: DVector::zeros(0),
                ydd_row: DVector::zeros(0),
                ydd_b: 0.0,
                neutral_modes: 0,
            };
            let m = closed_loop_matrix(&none, law, 0.0, ORDERS[0]);
            eigenvalues(&m).unwrap_or_default()
        }
        _ => Vec::new(),
    }
}

/// What the verdict needs of a plant, for any controller and delay: the loop's state-space
/// form and the open-loop responses on the margin grid (delay excluded). The app keeps one per
/// plant, so dragging a gain or τ only closes the loop again.
#[derive(Debug, Clone)]
pub struct MarginGrid {
    /// The plant for the eigenvalues.
    pub loop_plant: LoopPlant,
    /// Frequencies \[Hz\].
    pub freqs_hz: Vec<f64>,
    /// The plant's responses there.
    pub points: Vec<OpenLoop>,
}

impl MarginGrid {
    /// Evaluates `plant` on the grid refined around its lightly damped poles.
    pub fn new(plant: &LinearisedModel) -> Self {
        let freqs_hz = margin_grid(&plant.eigenvalues());
        let points = freqs_hz.iter().map(|&f| plant.open_loop(f)).collect();
        Self {
            loop_plant: LoopPlant::new(plant),
            freqs_hz,
            points,
        }
    }
}

/// The stability of one closed loop: the eigenvalue verdict and every crossing.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Stability {
    /// The rightmost closed-loop mode (`None`: the eigenvalue solve failed; not stable).
    pub modes: Option<ClosedLoopModes>,
    /// Every crossing of the loop gain.
    pub margins: LoopMargins,
}

impl Stability {
    /// The verdict for `plant` (linearised, its own delay not read) with `law` and the command
    /// delay `tau_s`.
    pub fn of(plant: &LinearisedModel, law: &ControlLaw, tau_s: f64) -> Self {
        Self::on_grid(plant, &MarginGrid::new(plant), law, tau_s)
    }

    /// [`Self::of`] with the plant's margin grid already evaluated.
    pub fn on_grid(
        plant: &LinearisedModel,
        grid: &MarginGrid,
        law: &ControlLaw,
        tau_s: f64,
    ) -> Self {
        Self {
            modes: ClosedLoopModes::of(&grid.loop_plant, law, tau_s),
            margins: LoopMargins::on_grid(plant, grid, law, tau_s),
        }
    }

    /// Stable: every closed-loop mode decays.
    pub fn stable(&self) -> bool {
        self.modes.is_some_and(|m| m.stable())
    }

    /// The verdict in words: the slowest decay, or the growing mode.
    pub fn mode_text(&self) -> String {
        match self.modes {
            Some(m) if m.stable() => format!(
                "stable (slowest mode decays at {:.2} 1/s)",
                -m.growth_rate_per_s
            ),
            Some(m) if m.freq_hz > 0.0 => format!(
                "a mode at {:.1} Hz grows at {:.3} 1/s",
                m.freq_hz, m.growth_rate_per_s
            ),
            Some(m) if m.growth_rate_per_s > 1e-6 => format!(
                "a non-oscillating mode grows at {:.3} 1/s",
                m.growth_rate_per_s
            ),
            Some(_) => "a mode does not decay (the stroke drifts)".into(),
            None => "the eigenvalue solve failed".into(),
        }
    }
}

/// The stability verdict of the twin linearised at rest with the parameters' controller.
pub fn twin_stability(params: &Params) -> Stability {
    Stability::of(
        &linearise_twin(params),
        &ControlLaw::new(params),
        params.plant.valve.tau_s,
    )
}

/// The stability verdict of G(s) with the parameters' controller.
pub fn linear_stability(params: &Params) -> Stability {
    Stability::of(
        &linearise_linear(params),
        &ControlLaw::new(params),
        params.linear.tau_s,
    )
}

/// What to change to make both loops stable (`plants`: each loop's plant and command delay),
/// from the eigenvalue verdict itself: a positive Kp is positive feedback at any gain; else
/// the largest |Kp| that keeps both loops stable, found by bisection, when lowering |Kp|
/// alone is enough.
pub fn remedy(params: &crate::params::Params, plants: &[(&LoopPlant, f64)]) -> String {
    let kp = params.controller.kp_v_per_m;
    if kp > 0.0 {
        return format!(
            "Kp = {kp:.1} V/m feeds the stroke back with the wrong sign (positive feedback, \
             unstable at any gain): use a negative Kp."
        );
    }
    if kp == 0.0 {
        return "Kp = 0 leaves the stroke uncontrolled (it drifts): use a negative Kp.".into();
    }
    let law = ControlLaw::new(params);
    let stable_at = |k: f64| {
        let mut c = params.controller;
        c.kp_v_per_m = -k;
        let l = law.with_params(c);
        plants
            .iter()
            .all(|(p, tau)| ClosedLoopModes::of(p, &l, *tau).is_some_and(|m| m.stable()))
    };
    let (mut lo, mut hi) = (kp.abs() * 1e-3, kp.abs());
    if !stable_at(lo) {
        return "Lowering |Kp| alone does not stabilise the loop: shorten τ or lower the other \
                feedback gains."
            .into();
    }
    for _ in 0..24 {
        let mid = (lo * hi).sqrt();
        if stable_at(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    format!(
        "|Kp| = {:.1} V/m is above the stability limit: keep Kp between −{lo:.1} and 0 V/m \
         (less |Kp| or a shorter τ).",
        kp.abs()
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The Chebyshev delay block reproduces `e^(−jωT)` to 1e-9 up to ωT = 20 at order 40, and
    /// every one of its own modes decays.
    #[test]
    fn delay_block_is_a_delay() {
        let t = 0.0205;
        let block = DelayBlock::new(t, ORDERS[1]);
        for k in 0..=100 {
            let w = 20.0 / t * k as f64 / 100.0;
            let exact = Complex64::new(0.0, -w * t).exp();
            let err = (block.response(w) - exact).norm();
            assert!(err < 1e-9, "ωT = {:.2}: error {err:e}", w * t);
        }
        let eig = eigenvalues(&block.a).expect("converges");
        assert!(eig.iter().all(|l| l.re < 0.0));
    }

    /// Clenshaw–Curtis integrates `e^x` on [−1, 1] to round-off at order 28, and the weights
    /// sum to 2.
    #[test]
    fn clenshaw_curtis_integrates() {
        for n in [5, 8, ORDERS[0], ORDERS[1]] {
            let w = clenshaw_curtis(n);
            assert!((w.iter().sum::<f64>() - 2.0).abs() < 1e-13);
            let x = (0..=n).map(|j| (PI * j as f64 / n as f64).cos());
            let approx: f64 = w.iter().zip(x).map(|(w, x)| w * x.exp()).sum();
            let exact = 1f64.exp() - (-1f64).exp();
            if n >= 20 {
                assert!((approx - exact).abs() < 1e-14, "{n}: {approx} vs {exact}");
            }
        }
    }

    /// The Smith predictor's loop on G(s) with an exact model has the delay-free position loop's
    /// poles (the prediction cancels the delay): `Kg·sp²/(s(s² + 2ζ·sp·s + sp²))` closed by
    /// `−Kp` is stable up to `|Kp|·Kg = 2ζ·sp` (Routh), whatever τ.
    #[test]
    fn smith_with_an_exact_model_removes_the_delay_from_the_limit() {
        let mut p = crate::params::Params::paper();
        p.controller.kind = ControllerKind::Smith;
        p.controller.ki_v_s_per_m = 0.0;
        let l = p.linear;
        let limit = 2.0 * l.zeta * l.sp_rad_s / l.kg_m_per_s_v;
        let plant = crate::analysis::frequency_response::linearise_linear(&p);
        for (k, stable) in [(0.95 * limit, true), (1.05 * limit, false)] {
            p.controller.kp_v_per_m = -k;
            let s = Stability::of(&plant, &ControlLaw::new(&p), l.tau_s);
            assert_eq!(s.stable(), stable, "Kp = −{k}: {:?}", s.modes);
        }
    }

    /// `u̇ = V` (and a decoupled, decaying second state where the loop reads `u̇`).
    fn integrator() -> LinearisedModel {
        let a = DMatrix::from_row_slice(2, 2, &[0.0, 0.0, 0.0, -1e3]);
        let b = DVector::from_row_slice(&[1.0, 0.0]);
        LinearisedModel::new(a, b.clone(), b * 0.0, vec![1.0, 1.0], 0.0)
    }

    /// The paper's law with `Kp = kp` and no feed-forward.
    fn position(kp: f64) -> ControlLaw {
        let mut p = crate::params::Params::paper();
        p.controller.kp_v_per_m = kp;
        p.controller.ki_v_s_per_m = 0.0;
        ControlLaw::new(&p)
    }

    /// An integrator with delayed feedback, `ẋ = −K·x(t − τ)`, is stable exactly for
    /// `K·τ < π/2` (a classical result): the verdict flips at that gain, and at it the
    /// rightmost root sits on the axis at `ω = K`.
    #[test]
    fn delayed_integrator_limit_is_pi_over_two() {
        let tau = 0.02;
        let k_crit = PI / 2.0 / tau;
        for (k, stable) in [(0.97 * k_crit, true), (1.03 * k_crit, false)] {
            let plant = integrator();
            let law = position(-k);
            let s = Stability::of(&plant, &law, tau);
            assert_eq!(s.stable(), stable, "K = {k}: {:?}", s.modes);
        }
        let s = Stability::of(&integrator(), &position(-k_crit), tau);
        let m = s.modes.expect("solves");
        assert!(m.growth_rate_per_s.abs() < 1e-7, "{m:?}");
        assert!((m.freq_hz * 2.0 * PI / k_crit - 1.0).abs() < 1e-9);
        // The margins agree: one gain crossover at ω = K with PM = 90° − K·τ·180/π = 0.
        let c = s.margins.worst_phase().expect("crossover");
        assert!(c.phase_margin_deg.abs() < 1e-6, "{c:?}");
    }
}
