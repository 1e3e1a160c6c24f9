//! Profile checks of the uncertainties where the fit's local picture can be overconfident.
//!
//! A fit's 1-σ comes from the Jacobian at its end point: the curvature of the residual there.
//! Where two parameters trade off along a curved valley, that curvature can be steep across
//! the valley's floor at the end point and yet the floor rise only slowly along it, so the
//! local 1-σ is far smaller than the records warrant. The hoses' and the chambers' bulk
//! moduli are such a pair: the records see mostly their total capacitance (the hoses hold
//! about five times the chambers' oil), the split only through the line's own mode.
//!
//! The check is the profile of the criterion (as in a profile likelihood): the chambers'
//! modulus is moved to each side (×1.5 and ÷1.5) with the total capacitance kept, everything
//! else fitted again, and the rise of the residual read in units of its own noise,
//! `Δχ² = ΔRSS/s²` with the fit's `s²` (per effective residual). A parabolic profile has
//! `Δχ² = (Δβ/σ)²`, so each side gives `σ = |Δβ|/√Δχ²`; the reported 1-σ is the largest of
//! the local one and the two sides', for both moduli (the hoses' from the refitted value).
//! A side within `Δχ² ≤ 1` — another valley as deep as the fit's, or nearly — stays within
//! 1-σ; one deeper than the fit's is fitted again in full and becomes the result.

use super::IdentifyError;
use super::fit::{self, Evaluator, FitResult, Knob};
use crate::params::derived;

/// Factor by which the chambers' modulus is moved to each side of the fit.
const STEP: f64 = 1.5;

/// Ratio of the profile's 1-σ to the local one above which the report says the two moduli
/// trade off.
const WIDENED: f64 = 1.5;

/// One side of the profile: the chambers' and hoses' moduli refitted with the chambers fixed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProfilePoint {
    /// Chambers' modulus, held \[Pa\].
    pub chambers_pa: f64,
    /// Hoses' modulus, refitted \[Pa\].
    pub hoses_pa: f64,
    /// Rise of the residual over the fit's, in units of its noise (`ΔRSS/s²`) [-].
    pub delta_chi2: f64,
}

/// What the profile of the hose/chamber split found. The points are relative to the end
/// point: [`Self::fit`] where the profile found a deeper valley, else the fit profiled.
#[derive(Debug, Clone)]
pub struct SplitProfile {
    /// The two sides (those whose start was physical).
    pub points: Vec<ProfilePoint>,
    /// Local 1-σ of the chambers' and the hoses' moduli \[Pa\].
    pub local: [f64; 2],
    /// 1-σ after the profile \[Pa\].
    pub widened: [f64; 2],
    /// The fit done again in full from a side that fitted better than the fit itself
    /// (another valley); the points are then relative to it.
    pub fit: Option<FitResult>,
}

/// Profiles the chambers'/hoses' split of `fit` (of `knobs`) when both moduli are fitted;
/// `None` otherwise. Two fits of all other knobs (in parallel), each with at most
/// `max_jacobians` Jacobians; `n_eff_ratio` as for [`fit::fit`].
pub fn hose_split(
    ev: &Evaluator<'_>,
    fit: &FitResult,
    knobs: &[Knob],
    max_jacobians: usize,
    n_eff_ratio: f64,
) -> Result<Option<SplitProfile>, IdentifyError> {
    let index = |k: Knob| knobs.iter().position(|&x| x == k);
    let (Some(ic), Some(ih)) = (index(Knob::Compliance), index(Knob::HoseCompliance)) else {
        return Ok(None);
    };
    let p0 = fit.params;
    let (beta_c, beta_h) = (p0.effective_bulk_modulus_pa(), p0.hose_bulk_modulus_pa());
    if p0.plant.effects.compliance.hose_bulk_modulus_pa <= 0.0 {
        return Ok(None);
    }
    let d = derived(&p0);
    let total = d.c_chamber + d.c_hose;
    let others: Vec<Knob> = knobs
        .iter()
        .copied()
        .filter(|&k| k != Knob::Compliance)
        .collect();
    let starts: Vec<_> = [STEP, 1.0 / STEP]
        .iter()
        .filter_map(|&f| {
            // The chambers' capacitance scales as 1/β; the hoses take the rest of the total.
            let chambers = beta_c * f;
            let c_hose = total - d.c_chamber / f;
            let hoses = beta_h * d.c_hose / c_hose;
            let spec = Knob::Compliance.spec();
            let in_range = |b: f64| (spec.min..=spec.max).contains(&b);
            (c_hose > 0.1 * d.c_hose && in_range(chambers) && in_range(hoses)).then(|| {
                let mut p = p0;
                p.plant.effects.compliance.effective_bulk_modulus_pa = chambers;
                p.plant.effects.compliance.hose_bulk_modulus_pa = hoses;
                p
            })
        })
        .collect();
    let fits: Vec<Result<FitResult, IdentifyError>> = {
        use rayon::prelude::*;
        starts
            .par_iter()
            .map(|p| fit::fit(ev, p, &others, max_jacobians, n_eff_ratio))
            .collect()
    };
    let s2 = fit::residual_variance(fit.rss, fit.n, knobs.len(), n_eff_ratio);
    let mut sides = fits.into_iter().collect::<Result<Vec<_>, _>>()?;
    // A side at least as deep as the fit is another valley: the fit is done again in full
    // from the deepest, and the first end point becomes one of the profile's points.
    let deepest = sides
        .iter()
        .filter(|s| s.rss < fit.rss)
        .min_by(|a, b| a.rss.total_cmp(&b.rss));
    let (end, moved) = match deepest {
        Some(d) => {
            let refit = fit::fit(ev, &d.params, knobs, max_jacobians, n_eff_ratio)?;
            if refit.rss < fit.rss {
                sides.push(fit.clone());
                (refit, true)
            } else {
                (fit.clone(), false)
            }
        }
        None => (fit.clone(), false),
    };
    let (beta_c, beta_h) = (
        end.params.effective_bulk_modulus_pa(),
        end.params.hose_bulk_modulus_pa(),
    );
    let local = [end.values[ic].std, end.values[ih].std];
    let mut widened = local;
    let mut points = Vec::new();
    for side in &sides {
        let point = ProfilePoint {
            chambers_pa: side.params.effective_bulk_modulus_pa(),
            hoses_pa: side.params.hose_bulk_modulus_pa(),
            delta_chi2: (side.rss - end.rss) / s2,
        };
        // σ = |Δβ|/√Δχ² on a parabolic profile; a point within Δχ² ≤ 1 (another valley as
        // deep, or nearly) is kept within 1-σ.
        let root = point.delta_chi2.max(1.0).sqrt();
        widened[0] = widened[0].max((point.chambers_pa - beta_c).abs() / root);
        widened[1] = widened[1].max((point.hoses_pa - beta_h).abs() / root);
        points.push(point);
    }
    Ok(Some(SplitProfile {
        points,
        local,
        widened,
        fit: moved.then_some(end),
    }))
}

/// The note for the report when the fit's own 1-σ of either modulus is over half its value
/// (the profile then has nothing to widen): the records do not separate them.
pub fn undetermined_note(fit: &FitResult) -> Option<String> {
    let value = |k: Knob| fit.values.iter().find(|v| v.knob == k);
    let (c, h) = (value(Knob::Compliance)?, value(Knob::HoseCompliance)?);
    if c.is_determined() && h.is_determined() {
        return None;
    }
    let gpa =
        |v: &super::fit::FittedValue| format!("{:.3} ± {:.3} GPa", 1e-9 * v.value, 1e-9 * v.std);
    Some(format!(
        "`compliance`: these records do not separate the chambers' bulk modulus ({}) from the \
         hoses' ({}): they see mostly the total capacitance, and the split is left uncertain. \
         Pressures at the valve ports, or a test that excites the line's own mode, would \
         separate them.",
        gpa(c),
        gpa(h)
    ))
}

impl SplitProfile {
    /// Whether the profile widened either 1-σ by more than half.
    pub fn trades_off(&self) -> bool {
        self.widened[0] > WIDENED * self.local[0] || self.widened[1] > WIDENED * self.local[1]
    }

    /// The note for the report when [`Self::trades_off`]: the points that fit nearly as well.
    pub fn note(&self, end: &FitResult) -> String {
        let gpa = |v: f64| format!("{:.3} GPa", 1e-9 * v);
        let near: Vec<String> = self
            .points
            .iter()
            .map(|q| {
                format!(
                    "chambers {} with hoses {} (Δχ² {:+.1})",
                    gpa(q.chambers_pa),
                    gpa(q.hoses_pa),
                    q.delta_chi2
                )
            })
            .collect();
        format!(
            "`compliance`: the chambers' and the hoses' bulk moduli trade off (the records see \
             mostly their total capacitance). Fitted: chambers {} with hoses {}; the profile \
             (chambers' modulus held ×1.5 and ÷1.5 with the total capacitance kept, everything \
             else fitted again; Δχ² is the rise of the residual in units of its noise): {}. The \
             1-σ are widened from the local {} and {} to {} and {} to cover it. Pressures at the \
             valve ports, or a test that excites the line's own mode, would separate them.",
            gpa(end.params.effective_bulk_modulus_pa()),
            gpa(end.params.hose_bulk_modulus_pa()),
            near.join("; "),
            gpa(self.local[0]),
            gpa(self.local[1]),
            gpa(self.widened[0]),
            gpa(self.widened[1]),
        )
    }

    /// Sets the widened 1-σ into `fit`'s values of the two moduli.
    pub fn apply(&self, fit: &mut FitResult) {
        for v in &mut fit.values {
            match v.knob {
                Knob::Compliance => v.std = self.widened[0],
                Knob::HoseCompliance => v.std = self.widened[1],
                _ => {}
            }
        }
    }
}

/// How far the mass is moved to each side of the fit in its profile, in its local 1-σ.
const MASS_SIGMAS: f64 = 3.0;

/// Largest move of the mass in its profile, relative to its value [-].
const MASS_MAX_MOVE: f64 = 0.25;

/// What the profile of the mass found, where the oil's stiffness was fitted beside it.
#[derive(Debug, Clone, PartialEq)]
pub struct MassProfile {
    /// The two sides: the mass held \[kg\] and the rise of the residual (`ΔRSS/s²`) [-].
    pub points: Vec<(f64, f64)>,
    /// Local 1-σ of the mass \[kg\].
    pub local: f64,
    /// 1-σ after the profile \[kg\].
    pub widened: f64,
}

/// Profiles the mass of `fit` (of `knobs`) where it was fitted beside a bulk modulus of the
/// oil (chambers' or hoses'): the oil column's mode, which the records see sharply, fixes
/// the ratio of the oil's stiffness to the mass better than either, so the fit's local 1-σ
/// of the mass can be far too small (a survey rig with soft hoses at 200 Hz: 10.84 ± 0.26 kg
/// against the rig's 11.7, the hoses 8 % soft). The mass is held at
/// [`MASS_SIGMAS`] local 1-σ to each side (at most [`MASS_MAX_MOVE`] of it), everything else
/// fitted again (two fits, in parallel), and the 1-σ widened as [`hose_split`] widens the
/// moduli'. A side deeper than the fit is kept within 1-σ, not adopted. `None` where the
/// mass or no modulus was fitted, or its local 1-σ is not finite.
pub fn mass_trade(
    ev: &Evaluator<'_>,
    fit: &FitResult,
    knobs: &[Knob],
    max_jacobians: usize,
    n_eff_ratio: f64,
) -> Result<Option<MassProfile>, IdentifyError> {
    let Some(im) = knobs.iter().position(|&k| k == Knob::Mass) else {
        return Ok(None);
    };
    if !knobs
        .iter()
        .any(|k| matches!(k, Knob::Compliance | Knob::HoseCompliance))
    {
        return Ok(None);
    }
    let (mass, local) = (fit.params.plant.body.mass_kg, fit.values[im].std);
    if !(local.is_finite() && local > 0.0) {
        return Ok(None);
    }
    let step = (MASS_SIGMAS * local).min(MASS_MAX_MOVE * mass);
    let others: Vec<Knob> = knobs.iter().copied().filter(|&k| k != Knob::Mass).collect();
    let held = |m: f64| {
        let mut p = fit.params;
        p.plant.body.mass_kg = m;
        fit::fit(ev, &p, &others, max_jacobians, n_eff_ratio)
    };
    let (up, down) = rayon::join(|| held(mass + step), || held(mass - step));
    let s2 = fit::residual_variance(fit.rss, fit.n, knobs.len(), n_eff_ratio);
    let mut widened = local;
    let mut points = Vec::with_capacity(2);
    for side in [up?, down?] {
        let delta_chi2 = (side.rss - fit.rss) / s2;
        // σ = |Δm|/√Δχ² on a parabolic profile; within Δχ² ≤ 1 the side stays within 1-σ.
        widened = widened.max(step / delta_chi2.max(1.0).sqrt());
        points.push((side.params.plant.body.mass_kg, delta_chi2));
    }
    Ok(Some(MassProfile {
        points,
        local,
        widened,
    }))
}

impl MassProfile {
    /// Whether the profile widened the 1-σ by more than half.
    pub fn trades_off(&self) -> bool {
        self.widened > WIDENED * self.local
    }

    /// The note for the report when [`Self::trades_off`].
    pub fn note(&self, fit: &FitResult) -> String {
        let sides: Vec<String> = self
            .points
            .iter()
            .map(|(m, chi2)| format!("{m:.2} kg (Δχ² {chi2:+.1})"))
            .collect();
        format!(
            "mass: the mass and the oil's stiffness trade off (the oil column's mode, which \
             the records see sharply, fixes their ratio better than either). Fitted: {:.2} kg; \
             the mass held at {}, everything else fitted again (Δχ² is the rise of the \
             residual in units of its noise). Its 1-σ is widened from the local {:.2} kg to \
             {:.2} kg to cover it. Records with a known mass added to the seat (the mode's \
             shift then weighs the mass), or the chamber pressures, would separate them.",
            fit.params.plant.body.mass_kg,
            sides.join(" and "),
            self.local,
            self.widened,
        )
    }

    /// Sets the widened 1-σ into `fit`'s value of the mass.
    pub fn apply(&self, fit: &mut FitResult) {
        for v in fit.values.iter_mut().filter(|v| v.knob == Knob::Mass) {
            v.std = self.widened;
        }
    }
}
