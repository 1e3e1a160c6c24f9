//! The mass or the oil's stiffness against the oil column's ringing: the last step of a
//! calibration whose twin rings as much as the records but not in time with them.
//!
//! The fits see the channels below [`OIL_COLUMN_BAND_HZ`]. There the seat follows the valve's
//! flow and a mass a few per cent off barely shows: its 1-σ is typically 3 % of the mass.
//! The mass does show in the oil column's mode (near 77 Hz on the paper's seat), which every
//! command step rings; a mass 2 % off mistimes that ringing by about 1 % in frequency, and on
//! records sampled at 200 Hz the mistimed ringing is most of the replay's raw ÿ error. The
//! oil's stiffness sets the same mode: with soft hoses (a compliance whose hoses have a
//! modulus of their own) the fit below 25 Hz sees mostly the total capacitance, and a hose
//! modulus 5 % off, within its 1-σ, mistimes the ringing as badly.
//!
//! So, only when the raw error measure flags such a ringing ([`RawErrorReport::ringing`]),
//! each fitted parameter of [`MODE_KNOBS`] is searched again, alone, within ±2 of its own 1-σ
//! (and ±10 %) for the smallest residual above [`OIL_COLUMN_BAND_HZ`], sample by sample,
//! each channel against its noise. The best of them is kept only if that residual falls by at
//! least a third. Everything else stays as fitted, and the parameter keeps the fit's 1-σ: the
//! bound keeps the value inside what the channels below 25 Hz allow, and the ringing alone
//! cannot tell the mass from the oil's stiffness (its frequency fixes their ratio), so it is
//! trusted only within that bound.

use super::evaluate::replay_all;
use super::fit::{FitResult, Knob};
use super::progress::{Monitor, Stage};
use super::raw_error::{OIL_COLUMN_BAND_HZ, RawErrorReport, raw_error_report};
use super::replay::{PreparedRecord, Replay};
use super::{IdentifyError, units};

/// Points of the first, coarse pass over the mass's interval (the middle one is the fit's).
const GRID: usize = 9;
/// Golden-section steps after the grid, between the best grid point's neighbours.
const REFINE: usize = 6;
/// Least relative fall of the ringing residual for the new mass to be kept.
const LEAST_GAIN: f64 = 1.0 / 3.0;

/// Residual energy above [`OIL_COLUMN_BAND_HZ`] of `report`: per record and channel, the
/// band's sample-by-sample ratio to its noise floor, squared and counted by the record's
/// samples. `None` when no channel has that band (a record sampled under 50 Hz).
fn ringing_energy(report: &RawErrorReport, recs: &[PreparedRecord]) -> Option<f64> {
    let mut total = None;
    for (r, rec) in report.records.iter().zip(recs) {
        let n = rec.window.len() as f64;
        for c in &r.channels {
            for b in &c.bands {
                if b.band_hz[0] >= OIL_COLUMN_BAND_HZ
                    && let Some(ratio) = b.residual_ratio
                {
                    *total.get_or_insert(0.0) += n * ratio * ratio;
                }
            }
        }
    }
    total
}

/// One evaluation of the search: the ringing residual's energy, with the replays and their
/// measure (none when a replay diverged).
type Evaluated = (f64, Option<(Vec<Replay>, RawErrorReport)>);

/// What the search did, for the report's notes.
#[derive(Debug, Clone, PartialEq)]
pub struct RingingRefined {
    /// The parameter searched again ([`MODE_KNOBS`]).
    pub knob: Knob,
    /// The fit's value \[SI\].
    pub from: f64,
    /// The value kept \[SI\].
    pub to: f64,
    /// The fit's 1-σ \[SI\].
    pub std: f64,
    /// The ringing residual's energy at the fit's value and at the kept one, relative to the
    /// first (1 and below).
    pub energy_ratio: f64,
}

/// The parameters that set the oil column's mode and that the channels below
/// [`OIL_COLUMN_BAND_HZ`] leave least sure: the mass, and the oil's stiffness through the
/// compliance's moduli (the chambers', and the hoses' when they have their own).
pub const MODE_KNOBS: [Knob; 3] = [Knob::Mass, Knob::HoseCompliance, Knob::Compliance];

impl RingingRefined {
    /// The note in the report.
    pub fn note(&self) -> String {
        let (what, why) = match self.knob {
            Knob::Mass => (
                "the mass",
                "the mass over the oil's stiffness, not the mass alone",
            ),
            Knob::HoseCompliance => (
                "the hoses' bulk modulus",
                "the oil's stiffness over the mass, not the stiffness alone",
            ),
            _ => (
                "the oil's bulk modulus",
                "the oil's stiffness over the mass, not the stiffness alone",
            ),
        };
        let name = self.knob.name();
        format!(
            "the calibrated twin rang as much as the records above {OIL_COLUMN_BAND_HZ:.0} Hz \
             but not in time with them (the oil column's mode, rung by each command step): \
             {what}, searched again within 2σ of the fit for that ringing, moves from {} \
             to {} (the residual above {OIL_COLUMN_BAND_HZ:.0} Hz falls to {} of its \
             energy); its 1-σ stays the fit's, since the ringing's frequency fixes {why}",
            units::format_parameter(name, self.from, self.std),
            units::format_parameter(name, self.to, self.std),
            percent(self.energy_ratio)
        )
    }
}

/// A ratio as a percentage, to two significant digits below 10 % ("0.12 %", "3.4 %", "45 %").
fn percent(ratio: f64) -> String {
    let p = 100.0 * ratio;
    let decimals = if p >= 10.0 {
        0
    } else if p > 0.0 {
        (1.0 - p.log10().floor()).clamp(1.0, 4.0) as usize
    } else {
        1
    };
    format!("{p:.decimals$} %")
}

/// The replays and the raw error measure of a kept search.
type Kept = (RingingRefined, Vec<Replay>, RawErrorReport);

/// When `first` (the raw error measure of `recs` replayed with `fit.params`) flags a
/// ringing, searches each fitted parameter of [`MODE_KNOBS`] again, alone, within 2σ of
/// its fit (and ±10 %) for that ringing; keeps the one whose search lowers the ringing
/// residual most, if by at least `LEAST_GAIN`, sets it in `fit` and returns the new replays
/// and measure. The others stay as fitted: the ringing's frequency fixes the oil's stiffness
/// over the mass, so one of them at a time is all it can tell. `limit` is the measure's limit.
pub fn refine_for_ringing(
    fit: &mut FitResult,
    recs: &[PreparedRecord],
    first: &RawErrorReport,
    limit: f64,
    monitor: &Monitor<'_>,
) -> Result<Option<Kept>, IdentifyError> {
    if first.ringing.is_empty() {
        return Ok(None);
    }
    let Some(e0) = ringing_energy(first, recs) else {
        return Ok(None);
    };
    if e0.is_nan() || e0 <= 0.0 {
        return Ok(None);
    }
    let slots: Vec<usize> = MODE_KNOBS
        .iter()
        .filter_map(|k| fit.values.iter().position(|v| v.knob == *k))
        .filter(|&i| {
            let v = &fit.values[i];
            v.std.is_finite() && v.std > 0.0 && v.value > 0.0
        })
        .collect();
    if slots.is_empty() {
        return Ok(None);
    }
    monitor.enter(Stage::Ringing, slots.len() * (GRID - 1 + REFINE));
    let mut best: Option<(usize, Kept)> = None;
    for slot in slots {
        let found = search(fit, slot, recs, e0, limit, monitor)?;
        if let Some(k) = found
            && best
                .as_ref()
                .is_none_or(|(_, b)| k.0.energy_ratio < b.0.energy_ratio)
        {
            best = Some((slot, k));
        }
    }
    Ok(best.map(|(slot, kept)| {
        kept.0.knob.spec().set_unchecked(&mut fit.params, kept.0.to);
        fit.values[slot].value = kept.0.to;
        kept
    }))
}

/// The search of [`refine_for_ringing`] for `fit.values[slot]` alone, from the ringing energy
/// `e0` at the fit: a grid of [`GRID`] points, then [`REFINE`] golden-section steps between
/// the best point's neighbours. `None` unless the best point lowers the energy by at least
/// [`LEAST_GAIN`]. `fit` is not changed.
fn search(
    fit: &FitResult,
    slot: usize,
    recs: &[PreparedRecord],
    e0: f64,
    limit: f64,
    monitor: &Monitor<'_>,
) -> Result<Option<Kept>, IdentifyError> {
    let (knob, v0, std) = (
        fit.values[slot].knob,
        fit.values[slot].value,
        fit.values[slot].std,
    );
    let half = (2.0 * std).min(0.1 * v0);
    let (lo, hi) = (v0 - half, v0 + half);
    let base = fit.params;
    // One evaluation: every record replayed with the parameter at `v`; a replay that diverges
    // counts as no better (the search stays where the twin runs).
    let evaluate = |v: f64| -> Result<Evaluated, IdentifyError> {
        monitor.check()?;
        let mut p = base;
        knob.spec().set_unchecked(&mut p, v);
        let out = match replay_all(&p, recs) {
            Ok(reps) => {
                let sims: Vec<_> = reps.iter().map(|r| &r.sim).collect();
                let report = raw_error_report(recs, &sims, limit);
                let e = ringing_energy(&report, recs).unwrap_or(f64::INFINITY);
                (e, Some((reps, report)))
            }
            Err(IdentifyError::Simulation { .. }) => (f64::INFINITY, None),
            Err(e) => return Err(e),
        };
        monitor.advance();
        Ok(out)
    };
    let at = |k: usize| lo + (hi - lo) * k as f64 / (GRID - 1) as f64;
    let mut best = (v0, e0, None);
    let mut grid = [e0; GRID];
    for (k, g) in grid.iter_mut().enumerate() {
        if k == GRID / 2 {
            continue;
        }
        let (e, run) = evaluate(at(k))?;
        *g = e;
        if e < best.1 {
            best = (at(k), e, run);
        }
    }
    // Golden section between the best grid point's neighbours.
    let k = grid
        .iter()
        .enumerate()
        .min_by(|a, b| a.1.total_cmp(b.1))
        .map_or(GRID / 2, |(k, _)| k);
    let (mut a, mut b) = (at(k.saturating_sub(1)), at((k + 1).min(GRID - 1)));
    let g = 0.5 * (5f64.sqrt() - 1.0);
    let (mut c, mut d) = (b - g * (b - a), a + g * (b - a));
    let (mut ec, rc) = evaluate(c)?;
    let (mut ed, rd) = evaluate(d)?;
    for (v, e, run) in [(c, ec, rc), (d, ed, rd)] {
        if e < best.1 {
            best = (v, e, run);
        }
    }
    for _ in 2..REFINE {
        // The minimum lies left of `d` (a new inner point `c`) or right of `c` (a new `d`).
        let left = ec < ed;
        let v = if left {
            (b, d, ed) = (d, c, ec);
            c = b - g * (b - a);
            c
        } else {
            (a, c, ec) = (c, d, ed);
            d = a + g * (b - a);
            d
        };
        let (e, run) = evaluate(v)?;
        if left {
            ec = e;
        } else {
            ed = e;
        }
        if e < best.1 {
            best = (v, e, run);
        }
    }
    let (v, e, run) = best;
    Ok(match run {
        Some((reps, report)) if e <= (1.0 - LEAST_GAIN) * e0 => {
            let refined = RingingRefined {
                knob,
                from: v0,
                to: v,
                std,
                energy_ratio: e / e0,
            };
            Some((refined, reps, report))
        }
        _ => None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_ratio_reads_to_two_significant_digits_below_ten_percent() {
        assert_eq!(percent(0.45), "45 %");
        assert_eq!(percent(0.034), "3.4 %");
        assert_eq!(percent(0.0012), "0.12 %");
        assert_eq!(percent(0.000_012_3), "0.0012 %");
        assert_eq!(percent(0.0), "0.0 %");
    }
}
