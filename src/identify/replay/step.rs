//! How short a replay's step is ([`StepRule`]): the report's replays resolve a friction's
//! reversals, the effect search's screening keeps only the integrator's stability limit.

use crate::params::Params;

/// How short a replay's step is, beyond the preset's largest step and the integrator's
/// stability limit (which every replay keeps).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum StepRule {
    /// Short enough to resolve the smoothed friction's sign change at a reversal
    /// ([`Params::friction_resolving_step_s`]): every fit, error and replay the report shows.
    #[default]
    Resolving,
    /// Only the stability limit: the effect search's screening (its start grids and its
    /// short fits on top of the current model, which rank the candidates; the one tried is
    /// then fitted again at [`StepRule::Resolving`]). With a friction that asks for a finer
    /// step (a 2 kHz record's 0.5 ms halved), a screening replay takes half the steps. The
    /// reversals it smears leave a residual of their own, so the current model is fitted
    /// again at this step and the candidates are ranked against that fit
    /// ([`crate::identify::effects::rank_candidates`]).
    Screening,
}

impl StepRule {
    /// The largest step this rule allows for `params` \[s\] (before it is fitted to a
    /// record's sample step).
    pub fn largest_step_s(self, params: &Params) -> f64 {
        let stable = params.numerics.max_step_s.min(0.9 * params.step_limit_s());
        match self {
            StepRule::Resolving => stable.min(params.friction_resolving_step_s()),
            StepRule::Screening => stable,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::identify::replay::{MetricOptions, PreparedRecord, rms};
    use crate::simulation::step_for_rate;

    /// The screening step is the integrator's limit alone: with the timing campaigns' friction
    /// (40 N Coulomb, 15 N Stribeck at 10 mm/s, 2 mm/s smoothing, 80 N·s/m) a 1 kHz record is
    /// replayed at 0.5 ms instead of the 1/3 ms that resolves the friction's reversals, and
    /// without friction both rules give the preset's 0.5 ms. The coarser replay stays close
    /// to the finer one on the whole record (4 s of a 3 Hz + 9 Hz command): the stroke within
    /// 4.4·10⁻⁵ of its swing, the seat's acceleration within 1.7 % of its RMS (not bit for
    /// bit: the reversals are smeared, which is why only the search's screening uses it).
    #[test]
    fn the_screening_step_drops_only_the_friction_resolving_limit() {
        let dt = 1e-3;
        let steps = |p: &Params| {
            [StepRule::Resolving, StepRule::Screening]
                .map(|rule| step_for_rate(rule.largest_step_s(p), 1.0 / dt))
        };
        let plain = crate::identify::testdata::true_params();
        assert_eq!(steps(&plain), [5e-4, 5e-4]);
        let mut rig = plain;
        let f = &mut rig.plant.effects.friction;
        f.enabled = true;
        f.coulomb_n = 40.0;
        f.stribeck_n = 15.0;
        f.stribeck_velocity_m_s = 0.01;
        f.smoothing_velocity_m_s = 0.002;
        f.viscous_n_s_per_m = 80.0;
        let [fine, coarse] = steps(&rig);
        assert!(
            (fine - dt / 3.0).abs() < 1e-12 && coarse == 5e-4,
            "{fine} {coarse}"
        );

        let record = crate::identify::testdata::twin_record(&rig, 4.0, "friction.csv").unwrap();
        let rec = PreparedRecord::new(&record, &MetricOptions::default()).unwrap();
        let a = rec.simulate(&rig).unwrap();
        let b = rec.simulate_with(&rig, StepRule::Screening).unwrap();
        let swing = |v: &[f64]| {
            v.iter().cloned().fold(f64::MIN, f64::max) - v.iter().cloned().fold(f64::MAX, f64::min)
        };
        let worst = |x: &[f64], y: &[f64]| {
            x.iter()
                .zip(y)
                .map(|(p, q)| (p - q).abs())
                .fold(0.0, f64::max)
        };
        let du = worst(&a.u, &b.u) / swing(&a.u);
        let dy = rms(&a
            .ydd
            .iter()
            .zip(&b.ydd)
            .map(|(p, q)| p - q)
            .collect::<Vec<_>>())
            / rms(&a.ydd);
        assert!(du > 0.0, "the two steps gave the same replay");
        assert!(du < 5e-4 && dy < 0.03, "stroke {du}, ÿ {dy}");
    }
}
