//! The 10-state nonlinear multi-physics twin of section 3.
//!
//! States ([`TwinState`]): relative position and velocity of the body, the two chamber
//! pressures, the two hose flows, the two pressures at the valve ports, spool position and
//! velocity. Equations (numbers as in the paper):
//!
//! ```text
//! (1)  m·ÿ = −k·u − p1·A1 + p2·A2 − F_friction(u̇) − F_stop(u, u̇)        (ü = ÿ − ẍ)
//! (2)  I1·Q̇1 = p1 − p1v − R1·Q1
//! (3)  I2·Q̇2 = p2v − p2 − R2·Q2
//! (4)  C1c·ṗ1 = u̇·A1 − Q1 − Q_leak
//! (5)  C2c·ṗ2 = Q2 − u̇·A2 + Q_leak        (sign corrected: docs/model.md, correction 1)
//! (6)  C1·ṗ1v = Q1 − Q1v
//! (7)  C2·ṗ2v = Q2v − Q2
//! (12) Q1v = Cd·ka·xv·√(2/ρ·(p1v − p0)) for xv > 0, √(2/ρ·(pA − p1v)) otherwise
//! (13) Q2v = Cd·ka·xv·√(2/ρ·(pA − p2v)) for xv > 0, √(2/ρ·(p2v − p0)) otherwise
//! (14) ẍv + 2ζs·ωn·ẋv + ωn²·xv = ωn²·kv·V(t − τ)
//! ```
//!
//! The square roots are signed, with a laminar core of width `laminar_core_pa`
//! (`√Δp ≈ Δp / (Δp² + δ²)^¼`), so the Jacobian stays finite at Δp = 0. The spool is clamped
//! to `±xv,max` by projection after each step; the end stops at `±Lc/2` are a stiff,
//! damped, push-only contact. Friction, overlap, offset, leakage, compliance and supply sag
//! are the optional effects of [`crate::params::EffectsParams`]; the terms a calibration
//! proposes beyond them are [`crate::params::CorrectionParams`] (docs/model.md, 9.3.1).

use super::{Inputs, Model, ModelKind, Outputs};
use crate::params::{Derived, Params, derived};

/// The ten states of the twin, by name.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct TwinState {
    /// Relative position `u = y − x` \[m\].
    pub u: f64,
    /// Relative velocity `u̇` [m/s].
    pub du: f64,
    /// Upper chamber pressure `p1` \[Pa\].
    pub p1: f64,
    /// Lower chamber pressure `p2` \[Pa\].
    pub p2: f64,
    /// Hose-1 flow `Q1`, chamber 1 → valve [m³/s].
    pub q1: f64,
    /// Hose-2 flow `Q2`, valve → chamber 2 [m³/s].
    pub q2: f64,
    /// Pressure at valve port 1 `p1v` \[Pa\].
    pub p1v: f64,
    /// Pressure at valve port 2 `p2v` \[Pa\].
    pub p2v: f64,
    /// Spool position `xv` \[m\].
    pub xv: f64,
    /// Spool velocity `ẋv` [m/s].
    pub dxv: f64,
}

impl TwinState {
    /// Flattens to the integrator's array (order of [`Twin::STATE_NAMES`]).
    pub fn to_array(&self) -> [f64; 10] {
        [
            self.u, self.du, self.p1, self.p2, self.q1, self.q2, self.p1v, self.p2v, self.xv,
            self.dxv,
        ]
    }

    /// Reads the integrator's array.
    pub fn from_array(y: &[f64; 10]) -> Self {
        let [u, du, p1, p2, q1, q2, p1v, p2v, xv, dxv] = *y;
        Self {
            u,
            du,
            p1,
            p2,
            q1,
            q2,
            p1v,
            p2v,
            xv,
            dxv,
        }
    }
}

/// The multi-physics twin with its parameters and precomputed constants.
#[derive(Debug, Clone)]
pub struct Twin {
    params: Params,
    d: Derived,
    /// `Cd·ka·√(2/ρ)` [m^(3/2)·kg^(-1/2)… per m of spool], the orifice gain per metre of spool.
    orifice_gain: f64,
    /// Whether a valve-flow correction ([`crate::params::CorrectionParams`]) is non-zero.
    valve_corrected: bool,
    core_sq: f64,
    /// Reciprocals of m, C_chamber, C_hose and I_hose: the right-hand side multiplies instead
    /// of dividing (divisions share the square-root unit, the twin's bottleneck).
    inv: Reciprocals,
}

#[derive(Debug, Clone, Copy)]
struct Reciprocals {
    mass: f64,
    c_chamber: f64,
    c_hose: f64,
    inertance: f64,
}

/// Valve port flows and the effective opening, for reporting and tests.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ValveFlows {
    /// Flow at port 1, line 1 → valve [m³/s].
    pub q1v: f64,
    /// Flow at port 2, valve → line 2 [m³/s].
    pub q2v: f64,
}

/// Signed square root with a laminar core: `Δ/(Δ² + δ²)^¼`, ≈ sign(Δ)·√|Δ| for |Δ| ≫ δ.
#[inline(always)]
pub fn signed_sqrt(delta: f64, core_sq: f64) -> f64 {
    orifice(1.0, delta, core_sq)
}

/// An orifice's flow `g·Δ/(Δ² + δ²)^¼` for a gain `g`, i.e. `g·`[`signed_sqrt`]`(Δ)`.
///
/// Computed as `(g·Δ/s)·√s` with `s = √(Δ² + δ²)`: the division and the second square root
/// wait only on `s`, so they run side by side, and the gain is applied before them, off the
/// chain. The twin's step is bound by this chain's latency (four stages, each waiting on the
/// flows), not by its count of operations.
#[inline(always)]
pub fn orifice(gain: f64, delta: f64, core_sq: f64) -> f64 {
    let s = (delta * delta + core_sq).sqrt();
    (gain * delta / s) * s.sqrt()
}

/// `r²` from which `exp(−r²)` is exactly 0 in `f64` (`exp(−745.2)` is under half the smallest
/// subnormal, 4.9·10⁻³²⁴).
const STRIBECK_UNDERFLOW: f64 = 746.0;

/// `tanh x` from one `exp`: `sign(x)·(1 − e)/(1 + e)` with `e = exp(−2|x|)`.
///
/// The friction law's smoothing calls it at every stage of every step, and libm's `tanh` (an
/// `expm1` and a division) was a tenth of a calibration's time. Near 0 the subtraction
/// `1 − e` loses relative precision but not absolute: the error stays within a few units of
/// 10⁻¹⁶ of the result's scale (1), so a force of tens of newtons moves by 10⁻¹⁴ N or less
/// (`tanh_by_exp_matches_tanh` checks it). Odd, and exactly ±1 beyond |x| ≈ 19.
#[inline(always)]
pub fn tanh_by_exp(x: f64) -> f64 {
    // Beyond |x| = 20, e < 4.3·10⁻¹⁸ rounds away in both 1 − e and 1 + e: the result is ±1
    // bit for bit, without the `exp` (most of a ride's steps, away from the reversals).
    if x.abs() > 20.0 {
        return 1.0f64.copysign(x);
    }
    let e = (-2.0 * x.abs()).exp();
    ((1.0 - e) / (1.0 + e)).copysign(x)
}

/// [`orifice`] of two ports at once. The twin's right-hand side is dominated by these fourth
/// roots; on x86-64 the two ports share one packed square root (SSE2, part of the x86-64
/// baseline), elsewhere it is two scalar calls. Bit-identical to the scalar form (IEEE square
/// roots and divisions are correctly rounded either way).
#[inline(always)]
pub fn orifice_pair(gains: (f64, f64), d1: f64, d2: f64, core_sq: f64) -> (f64, f64) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{
            _mm_add_pd, _mm_div_pd, _mm_mul_pd, _mm_set_pd, _mm_set1_pd, _mm_sqrt_pd, _mm_storeu_pd,
        };
        // SAFETY: SSE2 is always present on x86-64; the intrinsics only touch registers and
        // the local array written by `_mm_storeu_pd`.
        unsafe {
            let d = _mm_set_pd(d2, d1);
            let g = _mm_set_pd(gains.1, gains.0);
            let s = _mm_sqrt_pd(_mm_add_pd(_mm_mul_pd(d, d), _mm_set1_pd(core_sq)));
            let q = _mm_mul_pd(_mm_div_pd(_mm_mul_pd(g, d), s), _mm_sqrt_pd(s));
            let mut out = [0.0f64; 2];
            _mm_storeu_pd(out.as_mut_ptr(), q);
            (out[0], out[1])
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        (orifice(gains.0, d1, core_sq), orifice(gains.1, d2, core_sq))
    }
}

impl Twin {
    /// Builds the twin. The parameters should have been validated.
    pub fn new(params: Params) -> Self {
        let d = derived(&params);
        let orifice_gain = params.plant.valve.cd
            * params.plant.valve.ka_m
            * (2.0 / params.plant.fluid.density_kg_m3).sqrt();
        Self {
            params,
            d,
            orifice_gain,
            valve_corrected: params.plant.corrections.valve(),
            core_sq: params.plant.valve.laminar_core_pa.powi(2),
            inv: Reciprocals {
                mass: 1.0 / params.plant.body.mass_kg,
                c_chamber: 1.0 / d.c_chamber,
                c_hose: 1.0 / d.c_hose,
                inertance: 1.0 / d.inertance,
            },
        }
    }

    /// The parameters in use.
    pub fn params(&self) -> &Params {
        &self.params
    }

    /// Lumped hydraulic quantities in use.
    pub fn derived(&self) -> &Derived {
        &self.d
    }

    /// Valve opening seen by the orifices [m]: spool clamped to its travel, minus overlap.
    #[inline(always)]
    fn opening(&self, xv: f64) -> f64 {
        let xmax = self.params.plant.valve.xv_max_m;
        let x = xv.clamp(-xmax, xmax);
        let ov = &self.params.plant.effects.valve_overlap;
        if ov.enabled { ov.opening(x) } else { x }
    }

    /// Supply pressure seen by the metering edge [Pa] when a flow is drawn through an
    /// orifice of gain `a = g·|x|` from a line at `p_line` (supply-sag effect).
    #[inline(always)]
    fn supply_pressure(&self, a: f64, p_line: f64) -> f64 {
        let pa = self.params.plant.supply.supply_pressure_pa;
        let sag = &self.params.plant.effects.supply_sag;
        if !sag.enabled || sag.droop_pa_per_m3_s == 0.0 {
            return pa;
        }
        let dp = pa - p_line;
        if dp <= 0.0 || a == 0.0 {
            return pa;
        }
        // Q = a·√(pA − r·Q − p)  ⇒  Q² + a²r·Q − a²Δp = 0.
        let r = sag.droop_pa_per_m3_s;
        let a2 = a * a;
        let q = 0.5 * (-a2 * r + (a2 * a2 * r * r + 4.0 * a2 * dp).sqrt());
        pa - r * q
    }

    /// Valve port flows, Eqs. (12)–(13), for a spool position and the two port pressures.
    pub fn valve_flows(&self, xv: f64, p1v: f64, p2v: f64) -> ValveFlows {
        let (q1v, q2v) = self.port_flows(xv, p1v, p2v, 1.0);
        ValveFlows { q1v, q2v }
    }

    /// The valve's port flows (port 1 → valve, valve → port 2), each times `scale`: the
    /// right-hand side asks for them over the hose capacitance, a factor folded into the
    /// orifices' gains ahead of their square roots, off the step's critical path.
    #[inline(always)]
    fn port_flows(&self, xv: f64, p1v: f64, p2v: f64, scale: f64) -> (f64, f64) {
        let x = self.opening(xv);
        let p0 = self.params.plant.supply.return_pressure_pa;
        let g = self.orifice_gain * x;
        // Supply-edge and return-edge gains (equal unless a proposed correction says not).
        let (gs, gr) = if self.valve_corrected {
            let (s, r) = self
                .params
                .plant
                .corrections
                .edge_gains(x, self.params.plant.valve.xv_max_m);
            (g * s, g * r)
        } else {
            (g, g)
        };
        if x > 0.0 {
            let d2 = self.supply_pressure(gs, p2v) - p2v;
            orifice_pair((gr * scale, gs * scale), p1v - p0, d2, self.core_sq)
        } else {
            let d1 = self.supply_pressure(-gs, p1v) - p1v;
            orifice_pair((gs * scale, gr * scale), d1, p2v - p0, self.core_sq)
        }
    }

    /// Friction force on the body, opposing `du` \[N\] (0 unless the effect is enabled).
    #[inline(always)]
    pub fn friction_force(&self, du: f64) -> f64 {
        let f = &self.params.plant.effects.friction;
        if !f.enabled {
            return 0.0;
        }
        let r = du / f.stribeck_velocity_m_s;
        // exp(−r²) is exactly 0 below −745.2 (under the smallest subnormal), and libm reaches
        // that 0 through its slow underflow path: a few per cent of a calibration's time.
        let peak = if r * r < STRIBECK_UNDERFLOW {
            (-r * r).exp()
        } else {
            0.0
        };
        (f.coulomb_n + f.stribeck_n * peak) * tanh_by_exp(du / f.smoothing_velocity_m_s)
            + f.viscous_n_s_per_m * du
    }

    /// End-stop force on the body \[N\]: push-only spring–damper beyond ±Lc/2.
    #[inline(always)]
    pub fn end_stop_force(&self, u: f64, du: f64) -> f64 {
        let c = &self.params.plant.cylinder;
        let pen = u.abs() - 0.5 * c.stroke_m;
        if pen <= 0.0 {
            return 0.0;
        }
        let s = u.signum();
        let push = c.end_stop_stiffness_n_per_m * pen + c.end_stop_damping_n_s_per_m * du * s;
        -s * push.max(0.0)
    }

    /// Net force on the body [N] (springs, pistons, friction, end stops).
    #[inline(always)]
    fn body_force(&self, s: &TwinState) -> f64 {
        let a = self.d.area;
        -self.params.plant.body.stiffness_n_per_m * s.u - s.p1 * a + s.p2 * a
            - self.friction_force(s.du)
            + self.end_stop_force(s.u, s.du)
            + self.params.plant.corrections.body_force(s.u, s.du)
    }

    /// Internal leakage flow chamber 1 → chamber 2 [m³/s].
    #[inline(always)]
    fn leakage(&self, s: &TwinState) -> f64 {
        let laminar = self.params.plant.effects.leakage.flow(s.p1 - s.p2);
        let c_t = self
            .params
            .plant
            .corrections
            .turbulent_leakage_m3_per_s_sqrt_pa;
        if c_t == 0.0 {
            laminar
        } else {
            laminar + c_t * signed_sqrt(s.p1 - s.p2, self.core_sq)
        }
    }

    /// Command at the spool after the offset effect [V].
    #[inline(always)]
    fn spool_command(&self, v_valve: f64) -> f64 {
        let o = &self.params.plant.effects.valve_offset;
        if o.enabled {
            v_valve + o.bias_v
        } else {
            v_valve
        }
    }
}

impl Model<10> for Twin {
    const KIND: ModelKind = ModelKind::Twin;
    const STATE_NAMES: [&'static str; 10] = [
        "u [m]",
        "du [m/s]",
        "p1 [Pa]",
        "p2 [Pa]",
        "Q1 [m3/s]",
        "Q2 [m3/s]",
        "p1v [Pa]",
        "p2v [Pa]",
        "xv [m]",
        "dxv [m/s]",
    ];

    #[inline]
    fn derivatives(&self, _t: f64, y: &[f64; 10], inputs: &Inputs) -> [f64; 10] {
        let s = TwinState::from_array(y);
        let d = &self.d;
        let a = d.area;
        let inv = &self.inv;
        let ydd = self.body_force(&s) * inv.mass;
        // The port flows over the hoses' capacitance [Pa/s].
        let (q1v_c, q2v_c) = self.port_flows(s.xv, s.p1v, s.p2v, inv.c_hose);
        let q_leak = self.leakage(&s);
        let v = &self.params.plant.valve;
        let wn = v.omega_n_rad_s;
        let target = v.kv_m_per_v * self.spool_command(inputs.v_valve);
        TwinState {
            u: s.du,
            du: ydd - inputs.xdd,
            p1: (s.du * a - s.q1 - q_leak) * inv.c_chamber,
            p2: (s.q2 - s.du * a + q_leak) * inv.c_chamber,
            q1: (s.p1 - s.p1v - d.resistance * s.q1) * inv.inertance,
            q2: (s.p2v - s.p2 - d.resistance * s.q2) * inv.inertance,
            p1v: s.q1 * inv.c_hose - q1v_c,
            p2v: q2v_c - s.q2 * inv.c_hose,
            xv: s.dxv,
            dxv: wn * wn * (target - s.xv) - 2.0 * v.zeta * wn * s.dxv,
        }
        .to_array()
    }

    fn rest_state(&self) -> [f64; 10] {
        let p_mid = 0.5
            * (self.params.plant.supply.supply_pressure_pa
                + self.params.plant.supply.return_pressure_pa);
        TwinState {
            p1: p_mid,
            p2: p_mid,
            p1v: p_mid,
            p2v: p_mid,
            ..TwinState::default()
        }
        .to_array()
    }

    fn outputs(&self, y: &[f64; 10], _inputs: &Inputs) -> Outputs {
        let s = TwinState::from_array(y);
        Outputs {
            u: s.u,
            du: s.du,
            ydd: self.body_force(&s) / self.params.plant.body.mass_kg,
            xv: s.xv,
            p1: s.p1,
            p2: s.p2,
            q1: s.q1,
            q2: s.q2,
            end_stop_force: self.end_stop_force(s.u, s.du),
        }
    }

    #[inline(always)]
    fn relative_position(&self, y: &[f64; 10]) -> f64 {
        y[0]
    }

    #[inline(always)]
    fn project(&self, y: &mut [f64; 10]) {
        let xmax = self.params.plant.valve.xv_max_m;
        if y[8] > xmax {
            y[8] = xmax;
            y[9] = y[9].min(0.0);
        } else if y[8] < -xmax {
            y[8] = -xmax;
            y[9] = y[9].max(0.0);
        }
    }

    fn half_stroke(&self) -> f64 {
        0.5 * self.params.plant.cylinder.stroke_m
    }

    #[inline(always)]
    fn state_bound(&self, index: usize) -> f64 {
        const BOUNDS: [f64; 10] = [1.0, 100.0, 1.0e9, 1.0e9, 1.0, 1.0, 1.0e9, 1.0e9, 1.0, 1.0e4];
        BOUNDS[index]
    }

    fn state_scales(&self) -> [f64; 10] {
        [1e-2, 1e-1, 1e6, 1e6, 1e-4, 1e-4, 1e6, 1e6, 1e-4, 1e-1]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn packed_pair_equals_the_scalar_form_bit_for_bit() {
        let core = 1e4_f64.powi(2);
        for (a, b) in [(4.5e6, -3.0e5), (0.0, 1e3), (-9e6, 2.5e-3), (1e-300, -7.0)] {
            let gains = (3.1e-7, -2.2e-6);
            let (x, y) = orifice_pair(gains, a, b, core);
            assert_eq!(x.to_bits(), orifice(gains.0, a, core).to_bits());
            assert_eq!(y.to_bits(), orifice(gains.1, b, core).to_bits());
        }
    }

    /// The two short cuts past the `exp` give what the formulas give, bit for bit: `tanh` past
    /// |x| = 20 and the Stribeck peak `exp(−r²)` past r² = 746, on a fine grid across both.
    #[test]
    fn the_short_cuts_past_exp_change_no_bit() {
        let formula = |x: f64| {
            let e = (-2.0 * x.abs()).exp();
            ((1.0 - e) / (1.0 + e)).copysign(x)
        };
        for k in 0..40_000 {
            let x = 15.0 + 1e-3 * f64::from(k);
            for x in [x, -x] {
                assert_eq!(tanh_by_exp(x).to_bits(), formula(x).to_bits(), "x = {x}");
            }
            let r2 = 700.0 + 5e-3 * f64::from(k);
            if r2 >= STRIBECK_UNDERFLOW {
                assert_eq!((-r2).exp(), 0.0, "r² = {r2}");
            }
        }
    }

    /// The friction's `tanh` from one `exp` against libm's: within 4·10⁻¹⁶ absolute over
    /// the whole range (the smoothing's argument runs from 0 to thousands), odd, and ±1
    /// exactly far out; NaN stays NaN.
    #[test]
    fn tanh_by_exp_matches_tanh() {
        let mut worst: f64 = 0.0;
        for k in 0..200_000 {
            let x = 1e-9 * 1.0002f64.powi(k);
            if x > 50.0 {
                break;
            }
            for x in [x, -x] {
                worst = worst.max((tanh_by_exp(x) - x.tanh()).abs());
            }
        }
        assert!(worst < 4e-16, "worst {worst:e}");
        assert_eq!(tanh_by_exp(0.0), 0.0);
        assert_eq!(tanh_by_exp(30.0), 1.0);
        assert_eq!(tanh_by_exp(-30.0), -1.0);
        assert_eq!(tanh_by_exp(f64::INFINITY), 1.0);
        assert!(tanh_by_exp(f64::NAN).is_nan());
        // Small arguments: the relative error stays small where tanh x ≈ x.
        assert!((tanh_by_exp(1e-6) / 1e-6 - 1.0).abs() < 1e-9);
    }

    #[test]
    fn signed_sqrt_matches_sqrt_away_from_core() {
        let core = 1e4_f64.powi(2);
        for dp in [1e6, 4.5e6, 9e6] {
            assert!((signed_sqrt(dp, core) / dp.sqrt() - 1.0).abs() < 1e-4);
            assert!((signed_sqrt(-dp, core) / -(dp.sqrt()) - 1.0).abs() < 1e-4);
        }
        assert_eq!(signed_sqrt(0.0, core), 0.0);
    }

    #[test]
    fn rest_is_an_equilibrium() {
        let twin = Twin::new(Params::paper());
        let y = twin.rest_state();
        let dy = twin.derivatives(0.0, &y, &Inputs::default());
        for (i, v) in dy.iter().enumerate() {
            assert!(
                v.abs() < 1e-9,
                "state {} drifts at rest: {v}",
                Twin::STATE_NAMES[i]
            );
        }
    }

    #[test]
    fn full_opening_flow_matches_eq12_hand_value() {
        // Cd = 0.1074 at full opening and Δp = 100 bar gives the valve's 20 L/min (docs/model.md, correction 4).
        let mut p = Params::paper();
        p.plant.valve.cd = 0.1074;
        p.plant.supply.return_pressure_pa = 0.0;
        let twin = Twin::new(p);
        // xv < 0 connects supply to line 1: drop pA − p1v = 100 bar with p1v = 0.
        let f = twin.valve_flows(-p.plant.valve.xv_max_m, 0.0, 0.0);
        let l_per_min = -f.q1v * 60_000.0;
        assert!((l_per_min - 20.0).abs() < 0.1, "{l_per_min} L/min");
    }

    #[test]
    fn end_stop_pushes_back_only() {
        let twin = Twin::new(Params::paper());
        assert_eq!(twin.end_stop_force(0.0349, 0.0), 0.0);
        assert!(twin.end_stop_force(0.036, 0.0) < 0.0);
        assert!(twin.end_stop_force(-0.036, 0.0) > 0.0);
        // Leaving the stop fast: the damper would pull, the contact does not.
        assert_eq!(twin.end_stop_force(0.0351, -10.0), 0.0);
    }
}
