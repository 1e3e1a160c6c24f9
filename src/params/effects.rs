//! Physical effects that the paper's model lacks, each off by default.

use serde::{Deserialize, Serialize};

/// Physical effects that the paper's model lacks (issue 4). All off by default; each is a real
/// part of the twin, usable in simulation, the app and presets.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields, default)]
pub struct EffectsParams {
    /// Seal and slide friction.
    pub friction: FrictionEffect,
    /// Spool overlap (dead band) around null.
    pub valve_overlap: OverlapEffect,
    /// Valve null offset, expressed as a command bias.
    pub valve_offset: OffsetEffect,
    /// Internal leakage across the piston.
    pub leakage: LeakageEffect,
    /// Reduced effective bulk modulus (air, hose walls).
    pub compliance: ComplianceEffect,
    /// Supply pressure falling with drawn flow.
    pub supply_sag: SupplySagEffect,
}

/// Coulomb + viscous friction with an optional Stribeck peak, smoothed at zero velocity:
/// `F = (Fc + Fs·exp(−(v/vs)²))·tanh(v/v_eps) + b·v`, opposing the relative velocity `u̇`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FrictionEffect {
    /// Effect active.
    pub enabled: bool,
    /// Coulomb force `Fc` \[N\], 0 ..= 5000.
    pub coulomb_n: f64,
    /// Viscous coefficient `b` [N·s/m], 0 ..= 1e5.
    pub viscous_n_s_per_m: f64,
    /// Extra static (Stribeck) force `Fs` above Coulomb \[N\], 0 ..= 5000.
    pub stribeck_n: f64,
    /// Stribeck velocity `vs` [m/s], 1e-5 ..= 1.
    pub stribeck_velocity_m_s: f64,
    /// Smoothing velocity `v_eps` of the sign function [m/s], 1e-5 ..= 0.1.
    pub smoothing_velocity_m_s: f64,
}

impl Default for FrictionEffect {
    fn default() -> Self {
        Self {
            enabled: false,
            coulomb_n: 0.0,
            viscous_n_s_per_m: 0.0,
            stribeck_n: 0.0,
            stribeck_velocity_m_s: 0.005,
            smoothing_velocity_m_s: 1.0e-3,
        }
    }
}

/// Symmetric spool overlap: the orifices open only once `|xv|` exceeds the overlap. Real
/// lands are rounded: with an edge width `w > 0` the opening leaves zero smoothly, as the
/// hyperbola `½(d + √(d² + w²)) − ½(√(o² + w²) − o)` of `d = |x| − o` (0 at null, `d` well
/// past the edge, never negative); `w = 0` is the sharp edge `max(d, 0)`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct OverlapEffect {
    /// Effect active.
    pub enabled: bool,
    /// Overlap on each side of null \[m\], 0 ..= 0.01.
    pub overlap_m: f64,
    /// Width over which the rounded edges open \[m\], 0 ..= 0.01 (0: sharp edges).
    pub edge_width_m: f64,
}

impl Default for OverlapEffect {
    fn default() -> Self {
        Self {
            enabled: false,
            overlap_m: 0.0,
            edge_width_m: 0.0,
        }
    }
}

impl OverlapEffect {
    /// The opening \[m\] the orifices see at a (clamped) spool position `x` \[m\].
    #[inline(always)]
    pub fn opening(&self, x: f64) -> f64 {
        let d = x.abs() - self.overlap_m;
        let w = self.edge_width_m;
        let open = if w > 0.0 {
            let o = self.overlap_m;
            0.5 * (d + d.hypot(w)) - 0.5 * (o.hypot(w) - o)
        } else {
            d
        };
        x.signum() * open.max(0.0)
    }
}

/// Valve null offset, as a constant bias added to the delayed command at the valve.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct OffsetEffect {
    /// Effect active.
    pub enabled: bool,
    /// Command bias \[V\], -5 ..= 5.
    pub bias_v: f64,
}

impl Default for OffsetEffect {
    fn default() -> Self {
        Self {
            enabled: false,
            bias_v: 0.0,
        }
    }
}

/// Internal leakage from the upper to the lower chamber across the piston:
/// `Ql = Cl·Δp·(1 + g·|Δp|)` with `Δp = p1 − p2`. The flow through the piston's clearance is
/// laminar (`g = 0`: a fixed gap); on real pistons the gap widens with the pressure across it
/// (the seal lifts, the bore and piston deform), so the coefficient grows with `|Δp|`: `g` is
/// that growth, the fraction by which `Cl` rises per pascal.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LeakageEffect {
    /// Effect active.
    pub enabled: bool,
    /// Leakage coefficient `Cl` at small `|Δp|` [m³/(s·Pa)], 0 ..= 1e-9.
    pub coefficient_m3_per_s_pa: f64,
    /// Growth `g` of the coefficient with `|Δp|` [1/Pa], 0 ..= 1e-6 (0: a fixed gap; 5e-8
    /// doubles the leakage coefficient at 200 bar).
    pub growth_per_pa: f64,
}

impl Default for LeakageEffect {
    fn default() -> Self {
        Self {
            enabled: false,
            coefficient_m3_per_s_pa: 0.0,
            growth_per_pa: 0.0,
        }
    }
}

impl LeakageEffect {
    /// The leakage flow [m³/s] from chamber 1 to chamber 2 at `dp = p1 − p2` \[Pa\] (0 when
    /// the effect is off).
    #[inline(always)]
    pub fn flow(&self, dp: f64) -> f64 {
        if !self.enabled {
            0.0
        } else if self.growth_per_pa == 0.0 {
            self.coefficient_m3_per_s_pa * dp
        } else {
            self.coefficient_m3_per_s_pa * dp * (1.0 + self.growth_per_pa * dp.abs())
        }
    }
}

/// Reduced effective bulk modulus of the oil (entrained air, elastic walls) in chambers and
/// hoses. A hose's wall stretches far more than a steel cylinder's, so the hoses may have a
/// softer modulus of their own (`hose_bulk_modulus_pa`; 0: the chambers' for both).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ComplianceEffect {
    /// Effect active.
    pub enabled: bool,
    /// Effective bulk modulus \[Pa\] of the chambers (and of the hoses when
    /// `hose_bulk_modulus_pa` is 0), 1e6 ..= 1e10 (replaces `fluid.bulk_modulus_pa`).
    pub effective_bulk_modulus_pa: f64,
    /// Effective bulk modulus of the hoses \[Pa\], 0 ..= 1e10 (0 means as the chambers; any
    /// other value must be at least 1e6, as `effective_bulk_modulus_pa`).
    pub hose_bulk_modulus_pa: f64,
}

impl Default for ComplianceEffect {
    fn default() -> Self {
        Self {
            enabled: false,
            effective_bulk_modulus_pa: 1.2e9,
            hose_bulk_modulus_pa: 0.0,
        }
    }
}

/// Supply pressure drooping linearly with the flow drawn from it: `pA,eff = pA − r·Q`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SupplySagEffect {
    /// Effect active.
    pub enabled: bool,
    /// Droop `r` [Pa/(m³/s)], 0 ..= 1e12 (1e10 ≈ 1.7 bar per L/min).
    pub droop_pa_per_m3_s: f64,
}

impl Default for SupplySagEffect {
    fn default() -> Self {
        Self {
            enabled: false,
            droop_pa_per_m3_s: 0.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The rounded edge: zero at null, the sharp law far past the edge, never negative,
    /// monotonic, odd; with zero width, exactly the sharp law.
    #[test]
    fn rounded_overlap_opens_smoothly_and_tends_to_the_sharp_edge() {
        let sharp = OverlapEffect {
            enabled: true,
            overlap_m: 40e-6,
            edge_width_m: 0.0,
        };
        let round = OverlapEffect {
            edge_width_m: 20e-6,
            ..sharp
        };
        for x in [0.0, 10e-6, 40e-6, 60e-6, 300e-6] {
            assert_eq!(sharp.opening(x), (x - 40e-6f64).max(0.0));
            assert_eq!(sharp.opening(-x), -sharp.opening(x));
            assert_eq!(round.opening(-x), -round.opening(x));
        }
        assert_eq!(round.opening(0.0), 0.0);
        // Far past the edge: the sharp opening less the constant ½(√(o² + w²) − o) that keeps
        // the rounded opening at zero at null (2.36 µm here), to within w²/(4d).
        let far = round.opening(800e-6) - sharp.opening(800e-6);
        let shift = 0.5 * (40e-6f64.hypot(20e-6) - 40e-6);
        assert!((far + shift).abs() < 0.2e-6, "{far} {shift}");
        // Open already at the edge (the sharp one is still shut): a rounded land.
        assert!(round.opening(40e-6) > 5e-6);
        let mut last = 0.0;
        for k in 0..=200 {
            let o = round.opening(k as f64 * 1e-6);
            assert!(o >= last && o >= 0.0, "{k}");
            last = o;
        }
    }
}
