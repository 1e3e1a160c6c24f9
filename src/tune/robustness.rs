//! The robustness check of a tuned controller: the parameter spread (Cd ±10 %, τ ±3 ms,
//! mass ±20 %), and at each of its 27 points the eigenvalue verdict, the delay margin, the
//! settle test after a bump on the nonlinear twin and the ride objective; and why a claim
//! fails.

use super::{Evaluation, MIN_DECAY_RATE_PER_S, TuneOptions, score_rides};
use crate::analysis::settle::{Settle, settle_after_bump};
use crate::analysis::stability::twin_stability;
use crate::params::{ControllerParams, Params};
use crate::scenario::PlatformMotion;

/// One row of the robustness table.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RobustnessRow {
    /// Discharge coefficient [-].
    pub cd: f64,
    /// Valve delay \[s\].
    pub tau_s: f64,
    /// Body mass \[kg\].
    pub mass_kg: f64,
    /// Mean objective over the tuning rides.
    pub objective: f64,
    /// End-stop contacts over the tuning rides.
    pub contacts: usize,
    /// Largest |u| \[m\].
    pub max_abs_u_m: f64,
    /// Closed-loop eigenvalue verdict of the loop linearised at rest.
    pub stable: bool,
    /// Growth rate of the rightmost closed-loop mode [1/s].
    pub growth_rate_per_s: f64,
    /// Smallest delay margin over every crossover \[s\].
    pub delay_margin_s: f64,
    /// The settle test at rest after a bump on the nonlinear twin (`None`: it diverged).
    pub settle: Option<Settle>,
}

impl RobustnessRow {
    /// Stable by the eigenvalues, settled on the twin, and — with `tau_max_s` the spread's
    /// largest delay — a delay margin that reaches it, so the loop stays stable for every τ
    /// between this point's and the top of the spread (stability can switch on and off as
    /// the delay grows past a lightly damped mode: three levels of τ alone can miss a window).
    pub fn passes(&self, tau_max_s: f64) -> bool {
        self.stable
            && self.settle.is_some_and(|s| s.settled())
            && self.delay_margin_s >= tau_max_s - self.tau_s - 1e-12
    }
}

/// The largest delay of a robustness table \[s\].
pub fn tau_max_s(table: &[RobustnessRow]) -> f64 {
    table.iter().map(|r| r.tau_s).fold(0.0, f64::max)
}

/// The parameter spread of the robustness table: Cd ±10 %, τ ±3 ms, mass ±20 % (3 levels
/// each, nominal included).
pub fn spread(params: &Params) -> Vec<Params> {
    let mut out = Vec::with_capacity(27);
    for dc in [-0.1, 0.0, 0.1] {
        for dt in [-0.003, 0.0, 0.003] {
            for dm in [-0.2, 0.0, 0.2] {
                let mut p = *params;
                p.plant.valve.cd *= 1.0 + dc;
                p.plant.valve.tau_s = (p.plant.valve.tau_s + dt).max(0.0);
                p.plant.body.mass_kg *= 1.0 + dm;
                out.push(p);
            }
        }
    }
    out
}

/// The corners of the spread and the nominal point (what `robust` optimises over).
pub(super) fn spread_corners(params: &Params) -> Vec<Params> {
    spread(params)
        .into_iter()
        .enumerate()
        .filter(|(i, _)| {
            let (a, b, c) = (i / 9, (i / 3) % 3, i % 3);
            (a != 1 && b != 1 && c != 1) || (a == 1 && b == 1 && c == 1)
        })
        .map(|(_, p)| p)
        .collect()
}

/// Why the claim of a tuned controller fails: a constraint at the nominal plant, or a point of
/// the spread where the loop is unstable or the twin does not settle. Empty when it holds.
pub(super) fn claim_failures(tuned: &Evaluation, table: &[RobustnessRow]) -> Vec<String> {
    let mut out = Vec::new();
    if !tuned.feasible {
        out.push(format!(
            "the gains do not meet the constraints (unstable at {} of 27 spread points, \
             slowest mode {:.3} 1/s against ≤ −{MIN_DECAY_RATE_PER_S}; GM {:.1} dB, PM {:.0}°, \
             delay margin {:.1} ms; {})",
            tuned.unstable_points,
            tuned.worst_growth_rate_per_s,
            tuned.gain_margin_db,
            tuned.phase_margin_deg,
            tuned.delay_margin_s * 1e3,
            if tuned.max_abs_u_m.is_finite() {
                format!(
                    "max |u| {:.1} mm, {} contact(s)",
                    tuned.max_abs_u_m * 1e3,
                    tuned.contacts
                )
            } else {
                "rides not simulated".into()
            }
        ));
    }
    let top = tau_max_s(table);
    for row in table.iter().filter(|r| !r.passes(top)) {
        let at = format!(
            "Cd {:.4}, τ {:.1} ms, mass {:.1} kg",
            row.cd,
            row.tau_s * 1e3,
            row.mass_kg
        );
        if !row.stable {
            out.push(format!(
                "{at}: unstable at rest (a mode grows at {:.3} 1/s)",
                row.growth_rate_per_s
            ));
        } else if row.delay_margin_s < top - row.tau_s - 1e-12 {
            out.push(format!(
                "{at}: the delay margin {:.2} ms does not reach the spread's τ = {:.1} ms (the \
                 loop goes unstable between the τ levels)",
                row.delay_margin_s * 1e3,
                top * 1e3
            ));
        }
        match row.settle {
            None => out.push(format!("{at}: the twin diverged after the bump")),
            Some(s) if !s.settled() => out.push(format!(
                "{at}: the twin does not settle after the bump (ÿ RMS {:.3} m/s² over the last \
                 2 s, ×{:.2} from one second to the next, ≈ {:.1} Hz)",
                s.rms_last_2s_m_s2, s.growth_ratio, s.freq_hz
            )),
            Some(_) => {}
        }
    }
    out
}

/// The tuned controller over the whole spread (3 levels of Cd, τ and mass): the objective on
/// the tuning rides, the eigenvalue verdict and delay margin of the loop linearised at rest,
/// and the settle test after a bump on the nonlinear twin.
pub fn robustness_table(
    nominal: &Params,
    c: ControllerParams,
    rides: &[PlatformMotion],
    opts: &TuneOptions,
) -> Vec<RobustnessRow> {
    spread(nominal)
        .into_iter()
        .map(|mut p| {
            p.controller = c;
            let stability = twin_stability(&p);
            let settle = settle_after_bump(&p).ok();
            let (objective, max_u, contacts) =
                score_rides(&p, rides, opts.duration_s, opts.objective);
            RobustnessRow {
                cd: p.plant.valve.cd,
                tau_s: p.plant.valve.tau_s,
                mass_kg: p.plant.body.mass_kg,
                objective,
                contacts,
                max_abs_u_m: max_u,
                stable: stability.stable(),
                growth_rate_per_s: stability
                    .modes
                    .map_or(f64::INFINITY, |m| m.growth_rate_per_s),
                delay_margin_s: stability.margins.delay_margin_s(),
                settle,
            }
        })
        .collect()
}
