//! Where a candidate effect's fit starts: a coarse grid of its first parameter and "off"
//! ([`multi_start`]), with finer grids and their lowest valleys for compliance and friction,
//! whose residuals are rough along their sizes; and the best of a set of starts on the fit
//! records ([`best_of`]).

use super::fit::{self, Evaluator, Knob, Screened};
use super::{EffectId, IdentifyError};
use crate::params::Params;
use rayon::prelude::*;

/// Coarse starts for a candidate effect's fit: its first parameter on a log grid (both signs
/// for a signed one), the others at 0, gives the best of the grid and "off". For compliance
/// a finer grid and its best valleys (`compliance_starts`); for friction a finer grid of
/// the Coulomb force, its best valleys and a Stribeck peak from each (`friction_starts`).
pub fn multi_start(
    ev: &Evaluator<'_>,
    current: &Params,
    e: EffectId,
) -> Result<Vec<Params>, IdentifyError> {
    let mut off = *current;
    for k in e.knobs() {
        // A shape knob starts where the parameters hold it (see `Knob::is_shape`).
        let start = if k.is_shape() { k.theta(current) } else { 0.0 };
        k.set(&mut off, start);
    }
    let signed = matches!(e, EffectId::ValveOffset);
    let mut grid = vec![0.0];
    if e == EffectId::Compliance {
        // The total compliance of one modulus for chambers and hoses, the oil's over 1.04,
        // 1.04², … 1.04⁸⁸ (down to 1/31.5), split as `softer_hoses`: see `compliance_starts`.
        grid.extend((1..=COMPLIANCE_STEPS).map(|k| COMPLIANCE_STEP.powi(k) - 1.0));
    } else {
        for g in [0.1, 0.3, 1.0, 3.0, 10.0] {
            grid.push(g);
            if signed {
                grid.push(-g);
            }
        }
    }
    let starts: Vec<Params> = grid
        .iter()
        .map(|&g| {
            let mut p = off;
            e.knobs()[0].set(&mut p, g);
            p
        })
        .collect();
    if e == EffectId::Compliance {
        let starts: Vec<Params> = starts
            .iter()
            .map(|p| softer_hoses(p).unwrap_or(*p))
            .collect();
        return compliance_starts(ev, &starts);
    }
    let best = best_of(ev, &starts)?.unwrap_or(off);
    if e == EffectId::Friction {
        return friction_starts(ev, &off, best);
    }
    Ok(vec![best])
}

/// How many valleys of the Coulomb force's grid friction's fit starts from.
const FRICTION_VALLEYS: usize = 2;

/// Ratio of neighbouring Coulomb forces on friction's start grid.
const FRICTION_STEP: f64 = 1.5;

/// Friction's starts, from `off` (friction on at its preset shape, all forces 0) and `coarse`
/// (the best of the coarse grid every effect starts from, 0, 1, 3, 10, 30 and 100 N):
/// * `coarse`, and the [`FRICTION_VALLEYS`] lowest local minima of the fit records' residual
///   along the Coulomb force, 1 N to 290 N in steps of [`FRICTION_STEP`] (0 N, friction off,
///   is the grid's first point). Before the fit that residual is rough along the Coulomb force: an
///   open-loop replay turns each change of where the stroke sticks into drift. On case 2 of
///   the 2029 survey draw at 200 Hz (the rig: 48 N Coulomb, 96 N·s/m viscous, a 12 N
///   Stribeck peak, beside a 35 µm overlap) it read 14 599 at 11 N, 17 718 at 38 N, 9938 at
///   58 N and 14 827 at 86 N. The grid 1, 3, 10, 30, 100 N started the fit at 10 N, which
///   ended at 12 N and 0.4 N·s/m having removed a fifth of the residual; from 58 N it ends at
///   55 N and removes 84 %, and its re-fit finds the rig's law. The coarse grid's best stays
///   among the starts: on case 1 of the 2020 draw at 200 Hz (friction alone, 36 N) the
///   valleys alone ended at 18 N with the smoothing at its bound, Cd and τ outside 3σ,
///   where the fit from 30 N finds the rig's law. The grid's last point (290 N) is no
///   valley even where the residual is lower there than at 195 N: there it still falls with
///   more friction, which then stands in for another effect the model lacks, and fits from
///   it are the slowest (a Coulomb force of 290 N needs a replay step five times finer than
///   58 N, see [`Params::friction_resolving_step_s`]). On the 200 Hz test of soft hoses
///   beside an overlap (no friction) they took 12 s of the calibration's 18 (in the first
///   two rounds, ending at 290–545 N and up to 0.8 kN·s/m, then losing to the overlap and
///   the hoses);
/// * from each, a Stribeck peak of half its Coulomb force at the best of a few Stribeck
///   velocities spread over a decade: the Stribeck velocity does nothing while the Stribeck
///   force is 0, so a fit started there leaves it where the parameters hold it, and a law
///   with and without its peak are different valleys of the fit (a peak's start can look
///   worse before the fit and end better, or the other way round).
fn friction_starts(
    ev: &Evaluator<'_>,
    off: &Params,
    coarse: Params,
) -> Result<Vec<Params>, IdentifyError> {
    let grid: Vec<Params> = std::iter::once(0.0)
        .chain((0..15).map(|k| 0.1 * FRICTION_STEP.powi(k)))
        .map(|g| {
            let mut p = *off;
            Knob::FrictionCoulomb.set(&mut p, g);
            p
        })
        .collect();
    let mut out: Vec<Params> = Vec::with_capacity(2 * FRICTION_VALLEYS + 2);
    let mut bases = vec![coarse];
    bases.extend(lowest_valleys(ev, &grid, FRICTION_VALLEYS, GridEnd::Open)?);
    for valley in bases {
        let peaks: Vec<Params> = [0.002, 0.005, 0.01, 0.02]
            .iter()
            .map(|&velocity| {
                let mut p = valley;
                let friction = &mut p.plant.effects.friction;
                friction.stribeck_n = 0.5 * friction.coulomb_n;
                friction.stribeck_velocity_m_s = velocity;
                p
            })
            .collect();
        let peak = best_of(ev, &peaks)?;
        for p in std::iter::once(valley).chain(peak) {
            if !out.contains(&p) {
                out.push(p);
            }
        }
    }
    Ok(out)
}

/// How many valleys of the modulus' grid compliance's fit starts from.
const COMPLIANCE_VALLEYS: usize = 3;

/// Ratio of neighbouring moduli on compliance's start grid.
const COMPLIANCE_STEP: f64 = 1.04;

/// Steps of [`COMPLIANCE_STEP`] on compliance's start grid below the oil's modulus.
const COMPLIANCE_STEPS: i32 = 88;

/// Compliance's starts: the [`COMPLIANCE_VALLEYS`] lowest local minima of the fit records'
/// residual along the total compliance of hoses and chambers (`grid`, in steps of
/// [`COMPLIANCE_STEP`] of one modulus, split by [`softer_hoses`]). The lightly damped oil
/// column's mode makes the residual rise and fall as its frequency passes the test
/// frequencies and their harmonics: the valleys are narrow (on the 2027 survey draw's case 20,
/// ±2 % of the compliance wide, with a peak three times as high 9 % away), and a valley's
/// depth before the fit says little about its depth after it (there 6252 against 6344
/// before, 5215 against 6025 after). Each step of 4 % moves the mode's frequency by 2 %.
/// What sets the mode is the total compliance, to which the hoses (about five times the
/// chambers' oil) contribute most; how it splits between hoses and chambers moves the
/// residual far less (under 2 % along the same valley), so the split is left to the fit.
/// The grid had been two-dimensional (the chambers' modulus in steps of 1.2 times five hose
/// ratios, 70 points), whose total compliance stepped by up to 20 % and missed that valley.
fn compliance_starts(ev: &Evaluator<'_>, grid: &[Params]) -> Result<Vec<Params>, IdentifyError> {
    lowest_valleys(ev, grid, COMPLIANCE_VALLEYS, GridEnd::Closed)
}

/// Whether the last point of a start grid can be a valley.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum GridEnd {
    /// It can (compliance's grid, whose last point, 31.5 times softer than the oil, has
    /// always been one of its starts).
    Closed,
    /// It cannot: the residual may fall on beyond it, so a minimum there is a slope.
    Open,
}

/// The `k` lowest local minima of the fit records' residual along `grid` (a line of
/// parameter sets), lowest first; its last point is one only if `end` is
/// [`GridEnd::Closed`].
fn lowest_valleys(
    ev: &Evaluator<'_>,
    grid: &[Params],
    k: usize,
    end: GridEnd,
) -> Result<Vec<Params>, IdentifyError> {
    let costs = costs_of(ev, grid)?;
    Ok(valley_indices(&costs, k, end)
        .into_iter()
        .map(|i| grid[i])
        .collect())
}

/// The indices of the `k` lowest local minima of `costs` (a NaN is none), lowest first; its
/// last index is one only if `end` is [`GridEnd::Closed`].
fn valley_indices(costs: &[f64], k: usize, end: GridEnd) -> Vec<usize> {
    let n = costs.len();
    let mut minima: Vec<usize> = (0..n)
        .filter(|&i| {
            costs[i].is_finite()
                && (i == 0 || costs[i - 1] >= costs[i])
                && if i + 1 == n {
                    end == GridEnd::Closed
                } else {
                    costs[i + 1] >= costs[i]
                }
        })
        .collect();
    minima.sort_by(|&a, &b| costs[a].total_cmp(&costs[b]));
    minima.truncate(k);
    minima
}

/// `p` (one modulus for hoses and chambers) with the hoses softer than the chambers by
/// [`SPLIT_START`] and the total compliance kept; `None` where the chambers would then be
/// stiffer than the oil (the grid's stiffest points, which keep one modulus). Hoses are
/// softer than a cylinder's steel walls, and the fit moves along the split only slowly: on
/// the 2027 draw's case 20 at 200 Hz (rig: hoses 0.64 GPa, chambers 0.9) the fit from one
/// modulus stopped where compliance removed too little to be added, and from this split it
/// is found.
fn softer_hoses(p: &Params) -> Option<Params> {
    let d = crate::params::derived(p);
    let one = p.effective_bulk_modulus_pa();
    let chambers = one * (d.c_chamber + SPLIT_START * d.c_hose) / (d.c_chamber + d.c_hose);
    (chambers <= p.plant.fluid.bulk_modulus_pa).then(|| {
        let mut q = *p;
        let c = &mut q.plant.effects.compliance;
        c.enabled = true;
        c.effective_bulk_modulus_pa = chambers;
        c.hose_bulk_modulus_pa = chambers / SPLIT_START;
        q
    })
}

/// The hoses' modulus below the chambers' in compliance's split start ([`softer_hoses`]).
const SPLIT_START: f64 = 1.5;

/// The residual sum of squares of each of `starts` on the fit records (replayed in
/// parallel).
fn costs_of(ev: &Evaluator<'_>, starts: &[Params]) -> Result<Vec<f64>, IdentifyError> {
    starts
        .par_iter()
        .map(|p| {
            ev.residuals(p)
                .map(|r| r.iter().map(|v| v * v).sum::<f64>())
        })
        .collect::<Option<Vec<f64>>>()
        .ok_or(IdentifyError::Cancelled)
}

/// The parameter set of `starts` with the smallest residual sum of squares on the fit
/// records (replayed in parallel); `None` for no starts.
pub fn best_of(ev: &Evaluator<'_>, starts: &[Params]) -> Result<Option<Params>, IdentifyError> {
    let costs = costs_of(ev, starts)?;
    Ok((0..starts.len())
        .min_by(|&a, &b| costs[a].total_cmp(&costs[b]))
        .map(|i| starts[i]))
}

/// `e`'s starts from `current` ([`multi_start`]), each screened on `knobs`
/// ([`fit::screen`], `iterations` Jacobians at most); the fit with the smallest residual
/// (`None` for no starts).
pub fn best_screened(
    ev: &Evaluator<'_>,
    current: &Params,
    e: EffectId,
    knobs: &[Knob],
    iterations: usize,
) -> Result<Option<Screened>, IdentifyError> {
    let mut best: Option<Screened> = None;
    for p0 in multi_start(ev, current, e)? {
        let f = fit::screen(ev, &p0, knobs, iterations)?;
        if best.as_ref().is_none_or(|b| f.rss < b.rss) {
            best = Some(f);
        }
    }
    Ok(best)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Friction's residual before the fit on the 200 Hz test of soft hoses beside an
    /// overlap (shape only): rough along the Coulomb force, and lowest at the grid's last
    /// point, where it still falls.
    #[test]
    fn an_open_grid_end_is_no_valley_and_a_closed_one_is() {
        let costs = [5.0, 4.0, 6.0, 3.5, 7.0, 5.5, 2.0];
        assert_eq!(valley_indices(&costs, 2, GridEnd::Closed), vec![6, 3]);
        assert_eq!(valley_indices(&costs, 2, GridEnd::Open), vec![3, 1]);
        // The first point (the effect off) is a valley at either end's setting.
        let rising = [1.0, 2.0, 3.0];
        assert_eq!(valley_indices(&rising, 3, GridEnd::Open), vec![0]);
        // A NaN (a replay that blew up) is no valley, and neither is a point beside it: its
        // cost there is not known to be higher.
        let gap = [3.0, f64::NAN, 2.0, 4.0, 1.0, 5.0];
        assert_eq!(valley_indices(&gap, 3, GridEnd::Open), vec![4]);
    }
}
