//! The mass against the oil column's ringing: the last step of a calibration whose twin rings
//! as much as the records but not in time with them.
//!
//! The fits see the channels below [`OIL_COLUMN_BAND_HZ`]. There the seat follows the valve's
//! flow and a mass a few per cent off barely shows: its 1-σ is typically 3 % of the mass.
//! The mass does show in the oil column's mode (near 77 Hz on the paper's seat), which every
//! command step rings; a mass 2 % off mistimes that ringing by about 1 % in frequency, and on
//! records sampled at 200 Hz the mistimed ringing is most of the replay's raw ÿ error.
//!
//! So, only when the raw error measure flags such a ringing ([`RawErrorReport::ringing`]),
//! the mass is searched again within ±2 of its own 1-σ (and ±10 %) for the smallest residual
//! above [`OIL_COLUMN_BAND_HZ`], sample by sample, each channel against its noise. The value
//! is kept only if that residual falls by at least a third. Everything else stays as fitted,
//! and the mass keeps the fit's 1-σ: the bound keeps the value inside what the channels below
//! 25 Hz allow, and the ringing alone cannot tell the mass from the oil's stiffness (its
//! frequency fixes their ratio), so it is trusted only within that bound.

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
pub struct MassRefined {
    /// The fit's mass [kg].
    pub from_kg: f64,
    /// The mass kept [kg].
    pub to_kg: f64,
    /// The fit's 1-σ of the mass [kg].
    pub std_kg: f64,
    /// The ringing residual's energy at the fit's mass and at the kept one, relative to the
    /// first (1 and below).
    pub energy_ratio: f64,
}

impl MassRefined {
    /// The note in the report.
    pub fn note(&self) -> String {
        format!(
            "the calibrated twin rang as much as the records above {OIL_COLUMN_BAND_HZ:.0} Hz \
             but not in time with them (the oil column's mode, rung by each command step): \
             the mass, searched again within 2σ of the fit for that ringing, moves from {} \
             to {} (the residual above {OIL_COLUMN_BAND_HZ:.0} Hz falls to {:.0} % of its \
             energy); its 1-σ stays the fit's, since the ringing's frequency fixes the mass \
             over the oil's stiffness, not the mass alone",
            units::format_parameter(Knob::Mass.name(), self.from_kg, self.std_kg),
            units::format_parameter(Knob::Mass.name(), self.to_kg, self.std_kg),
            100.0 * self.energy_ratio
        )
    }
}

/// Searches `fit`'s mass again when `first` (the raw error measure of `recs` replayed with
/// `fit.params`) flags a ringing; sets it in `fit` and returns the new replays and measure
/// when it is kept. `limit` is the measure's limit.
pub fn refine_mass(
    fit: &mut FitResult,
    recs: &[PreparedRecord],
    first: &RawErrorReport,
    limit: f64,
    monitor: &Monitor<'_>,
) -> Result<Option<(MassRefined, Vec<Replay>, RawErrorReport)>, IdentifyError> {
    if first.ringing.is_empty() {
        return Ok(None);
    }
    let Some(slot) = fit.values.iter().position(|v| v.knob == Knob::Mass) else {
        return Ok(None);
    };
    let (m0, std) = (fit.values[slot].value, fit.values[slot].std);
    let Some(e0) = ringing_energy(first, recs) else {
        return Ok(None);
    };
    if !(std.is_finite() && std > 0.0 && e0 > 0.0) {
        return Ok(None);
    }
    monitor.enter(Stage::Ringing, GRID + REFINE);
    let half = (2.0 * std).min(0.1 * m0);
    let (lo, hi) = (m0 - half, m0 + half);
    let base = fit.params;
    // One evaluation: every record replayed with mass `m`; a replay that diverges counts as
    // no better (the search stays where the twin runs).
    let evaluate = |m: f64| -> Result<Evaluated, IdentifyError> {
        monitor.check()?;
        let mut p = base;
        p.plant.body.mass_kg = m;
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
    let mut best = (m0, e0, None);
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
    for (m, e, run) in [(c, ec, rc), (d, ed, rd)] {
        if e < best.1 {
            best = (m, e, run);
        }
    }
    for _ in 2..REFINE {
        // The minimum lies left of `d` (a new inner point `c`) or right of `c` (a new `d`).
        let left = ec < ed;
        let m = if left {
            (b, d, ed) = (d, c, ec);
            c = b - g * (b - a);
            c
        } else {
            (a, c, ec) = (c, d, ed);
            d = a + g * (b - a);
            d
        };
        let (e, run) = evaluate(m)?;
        if left {
            ec = e;
        } else {
            ed = e;
        }
        if e < best.1 {
            best = (m, e, run);
        }
    }
    let (m, e, run) = best;
    match run {
        Some((reps, report)) if e <= (1.0 - LEAST_GAIN) * e0 => {
            fit.params.plant.body.mass_kg = m;
            fit.values[slot].value = m;
            let refined = MassRefined {
                from_kg: m0,
                to_kg: m,
                std_kg: std,
                energy_ratio: e / e0,
            };
            Ok(Some((refined, reps, report)))
        }
        _ => Ok(None),
    }
}
