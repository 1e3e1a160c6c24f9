//! Corrections beyond the effect library: terms that `seat-twin calibrate` proposes when the
//! library leaves a residual (issue 20, item 2). Each is a physically meaningful term of the
//! twin's equations, zero (off) by default; `calibrated.toml` carries the proposed ones and
//! the twin (replay, simulation, app) applies them.

use serde::{Deserialize, Serialize};

/// Proposed terms of the twin's equations, all zero by default (the paper's twin).
///
/// * Valve flow, Eqs. (12)–(13): the orifice gain `Cd·ka·xv` is multiplied by
///   `(1 + s·(|x|/xv,max − ½))·(1 + a·x/√(x² + w²))·(1 ± e)`: `s` a discharge coefficient
///   that changes from small to full opening, `a` a flow gain that differs between the two
///   spool directions (`+a` for `xv > 0`, supply to chamber 2), built up over a spool travel
///   `w` about null, `e` a flow gain that differs between the metering edges to tank
///   (`1 + e`) and from supply (`1 − e`).
/// * Body force, Eq. (1): `− k_c·u − c_q·u̇·|u̇|` (a spring not in the declared stiffness;
///   a damping quadratic in the velocity, as an orifice or a seat cushion's air gives it).
/// * Chamber flows, Eqs. (4)–(5): a leakage across the piston that grows with the square root
///   of the pressure difference (a turbulent gap), `c_t·sign(Δp)·√|Δp|`.
/// * Valve command, Eq. (10): a first-order lag `T_cmd·v̇ = v_in − v` between the command as
///   sent and the one the valve acts on (a servo amplifier's or a proportional magnet's),
///   beside the pure delay τ; and a null that drifts during each record, `+ r·t` at the
///   valve, after the delay, with `t` from the record's start (a torque motor or an
///   amplifier warming up). Applied by the
///   replay of measured records (`seat-twin replay`, `seat-twin calibrate`: the record's
///   command is filtered, then offset, before it drives the valve, [`Self::acted_command`]);
///   the twin's own closed-loop simulation does not apply them.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields, default)]
pub struct CorrectionParams {
    /// Relative change `s` of the discharge coefficient from small to full spool opening [-], -0.5 ..= 0.5 (0: Cd constant).
    pub cd_opening_slope: f64,
    /// Flow-gain difference `a` between the spool directions [-], -0.5 ..= 0.5; gain `1 + a` for `xv > 0`, `1 − a` for `xv < 0`.
    pub flow_gain_direction: f64,
    /// Spool travel `w` over which the direction difference builds up \[m\], 0 ..= 0.01; the gain is `1 + a·x/√(x² + w²)` (0: a sharp step at null).
    pub flow_gain_direction_width_m: f64,
    /// Flow-gain difference `e` between the metering edges [-], -0.5 ..= 0.5; gain `1 + e` on the edges to tank, `1 − e` on the edges from supply.
    pub flow_gain_return_edge: f64,
    /// Spring `k_c` on the body beyond the declared stiffness [N/m], -1e5 ..= 1e5.
    pub spring_n_per_m: f64,
    /// Quadratic damping `c_q` on the body [N·s²/m²], 0 ..= 1e6.
    pub quadratic_damping_n_s2_per_m2: f64,
    /// Turbulent leakage `c_t` across the piston [m³/(s·√Pa)], 0 ..= 1e-7.
    pub turbulent_leakage_m3_per_s_sqrt_pa: f64,
    /// First-order lag `T_cmd` of the valve command \[s\], 0 ..= 0.05 (0: none).
    pub command_lag_s: f64,
    /// Drift rate `r` of the valve's null during each record [V/s], -0.1 ..= 0.1 (0: none);
    /// the valve acts on its command plus `r·t`, `t` from the record's start.
    pub command_drift_v_per_s: f64,
}

impl CorrectionParams {
    /// Whether any term is non-zero.
    pub fn any(&self) -> bool {
        *self != Self::default()
    }

    /// Whether a valve-flow term is non-zero.
    pub fn valve(&self) -> bool {
        self.cd_opening_slope != 0.0
            || self.flow_gain_direction != 0.0
            || self.flow_gain_return_edge != 0.0
    }

    /// Gains of the supply and the return edge for an opening `x` of a valve of travel
    /// `xv_max` \[m\], relative to the uncorrected gain: `(supply, return)`.
    #[inline(always)]
    pub fn edge_gains(&self, x: f64, xv_max: f64) -> (f64, f64) {
        let w = self.flow_gain_direction_width_m;
        let sign = if w > 0.0 {
            x / (x * x + w * w).sqrt()
        } else {
            x.signum()
        };
        let m = (1.0 + self.cd_opening_slope * (x.abs() / xv_max - 0.5))
            * (1.0 + self.flow_gain_direction * sign);
        (
            m * (1.0 - self.flow_gain_return_edge),
            m * (1.0 + self.flow_gain_return_edge),
        )
    }

    /// The command \[V\] that drives the valve's delay `delay_s` \[s\] (τ), sampled every `dt`
    /// \[s\], for the command as sent `v_in` sampled at the same instants:
    /// [`Self::lagged_command`], plus the null's drift taken `delay_s` ahead, `r·(t + τ)`, so
    /// that the valve, acting on this command τ later, sees its null at `r·t` from the
    /// record's start (the null is the valve's own, after the delay; from the first sample on
    /// with a drift of `r·τ` at most in the first τ, where the valve acts on the command held
    /// before the record). `None` when neither term is on (the valve acts on `v_in`).
    pub fn acted_command(&self, v_in: &[f64], dt: f64, delay_s: f64) -> Option<Vec<f64>> {
        let r = self.command_drift_v_per_s;
        if self.command_lag_s <= 0.0 && r == 0.0 {
            return None;
        }
        let mut v = self.lagged_command(v_in, dt);
        if r != 0.0 {
            for (i, x) in v.iter_mut().enumerate() {
                *x += r * (i as f64 * dt + delay_s);
            }
        }
        Some(v)
    }

    /// The command `v` \[V\] the valve acts on, sampled every `dt` \[s\], for the command as sent
    /// `v_in` sampled at the same instants and linearly interpolated between them (as a replay
    /// reads a record): the exact solution of `T_cmd·v̇ = v_in − v` from `v = 0` before the
    /// first sample (the valve at rest). Returns `v_in` itself without a lag.
    pub fn lagged_command(&self, v_in: &[f64], dt: f64) -> Vec<f64> {
        let t = self.command_lag_s;
        if t <= 0.0 || v_in.is_empty() {
            return v_in.to_vec();
        }
        // Over one step the input is linear between its samples; the lag's response is exact.
        let a = (-dt / t).exp();
        let mut out = Vec::with_capacity(v_in.len());
        // The first sample is reached by a step from rest at t = 0.
        let mut v = 0.0;
        out.push(v);
        for w in v_in.windows(2) {
            v = lag_step(v, w[0], w[1], dt, t, a);
            out.push(v);
        }
        out
    }

    /// Force of the body terms \[N\] at relative position `u` \[m\] and velocity `du` [m/s],
    /// acting on the body (negative = downward).
    #[inline(always)]
    pub fn body_force(&self, u: f64, du: f64) -> f64 {
        -self.spring_n_per_m * u - self.quadratic_damping_n_s2_per_m2 * du * du.abs()
    }
}

/// One step of a first-order lag `T·ẏ = x − y` of time constant `lag_s` [s] over `dt` [s],
/// exact for an input linear from `prev` to `x` over the step: `y` the output at its start,
/// `a = e^(−dt/T)`: the valve command's lag ([`CorrectionParams::lagged_command`]), a
/// continuous-time servo filter.
#[inline]
fn lag_step(y: f64, prev: f64, x: f64, dt: f64, lag_s: f64, a: f64) -> f64 {
    let slope = (x - prev) / dt;
    a * y + (1.0 - a) * prev + slope * (dt - lag_s * (1.0 - a))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The documented laws at hand-computed points.
    #[test]
    fn corrections_follow_their_documented_laws() {
        let c = CorrectionParams {
            cd_opening_slope: 0.1,
            flow_gain_direction: 0.05,
            flow_gain_return_edge: 0.02,
            flow_gain_direction_width_m: 0.0,
            spring_n_per_m: 500.0,
            quadratic_damping_n_s2_per_m2: 2000.0,
            turbulent_leakage_m3_per_s_sqrt_pa: 0.0,
            command_lag_s: 0.0,
            command_drift_v_per_s: 0.0,
        };
        // Full opening, positive: (1 + 0.05)·(1.05) and the edges ∓2 %.
        let (s, r) = c.edge_gains(8e-4, 8e-4);
        assert!((s - 1.05 * 1.05 * 0.98).abs() < 1e-12);
        assert!((r - 1.05 * 1.05 * 1.02).abs() < 1e-12);
        // Small opening, negative: (1 − 0.05)·(1 − 0.05).
        let (s, _) = c.edge_gains(-1e-9, 8e-4);
        assert!((s - 0.95 * 0.95 * 0.98).abs() < 1e-6);
        // Cd rises by s from small to full opening (direction and edge terms off).
        let only_s = CorrectionParams {
            cd_opening_slope: 0.1,
            ..Default::default()
        };
        let (full, _) = only_s.edge_gains(8e-4, 8e-4);
        let (small, _) = only_s.edge_gains(1e-12, 8e-4);
        assert!((full - small - 0.1).abs() < 1e-9);
        assert!((c.body_force(0.01, -0.1) - (-5.0 + 20.0)).abs() < 1e-12);
        assert!(!CorrectionParams::default().any() && c.any() && c.valve());
    }

    /// The lagged command against the analytic response of a first-order lag: to a ramp
    /// `v_in = r·t` from rest, `v = r·(t − T·(1 − e^(−t/T)))`; to a sine, the steady gain
    /// `1/√(1 + (ωT)²)`.
    #[test]
    fn the_command_lag_is_the_exact_first_order_response() {
        let c = CorrectionParams {
            command_lag_s: 4e-3,
            ..Default::default()
        };
        let dt = 1e-3;
        let ramp: Vec<f64> = (0..200).map(|i| 2.0 * i as f64 * dt).collect();
        let v = c.lagged_command(&ramp, dt);
        for (i, vi) in v.iter().enumerate() {
            let t = i as f64 * dt;
            let exact = 2.0 * (t - 4e-3 * (1.0 - (-t / 4e-3).exp()));
            assert!((vi - exact).abs() < 1e-12, "{i}: {vi} vs {exact}");
        }
        let w = 2.0 * std::f64::consts::PI * 20.0;
        let sine: Vec<f64> = (0..4000).map(|i| (w * i as f64 * dt).sin()).collect();
        let v = c.lagged_command(&sine, dt);
        let amp = v[2000..].iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let gain = 1.0 / (1.0 + (w * 4e-3).powi(2)).sqrt();
        // Linear interpolation between samples and the sampled peak at 50 samples per
        // period: within 0.5 %.
        assert!((amp / gain - 1.0).abs() < 5e-3, "{amp} vs {gain}");
        assert_eq!(CorrectionParams::default().lagged_command(&sine, dt), sine);
    }

    /// The command that drives the valve's delay: none without a term; the drift alone adds
    /// `r·(t + τ)`, so that τ later the valve's null is at `r·t` from the record's start;
    /// with the lag too, the lagged command plus the same ramp.
    #[test]
    fn a_drifting_null_adds_its_ramp_to_the_command() {
        let (dt, tau) = (1e-3, 0.019);
        let v_in: Vec<f64> = (0..500).map(|i| (0.05 * i as f64).sin()).collect();
        assert_eq!(
            CorrectionParams::default().acted_command(&v_in, dt, tau),
            None
        );
        let drift = CorrectionParams {
            command_drift_v_per_s: 2e-3,
            ..Default::default()
        };
        let v = drift.acted_command(&v_in, dt, tau).expect("a drift");
        // The valve acts on sample i at t = i·dt + τ, its null then at r·(i·dt + τ).
        for (i, (a, b)) in v.iter().zip(&v_in).enumerate() {
            assert!((a - b - 2e-3 * (i as f64 * dt + tau)).abs() < 1e-15, "{i}");
        }
        let both = CorrectionParams {
            command_lag_s: 4e-3,
            ..drift
        };
        let lagged = both.lagged_command(&v_in, dt);
        let v = both
            .acted_command(&v_in, dt, tau)
            .expect("a lag and a drift");
        for (i, (a, b)) in v.iter().zip(&lagged).enumerate() {
            assert!((a - b - 2e-3 * (i as f64 * dt + tau)).abs() < 1e-15, "{i}");
        }
    }
}
