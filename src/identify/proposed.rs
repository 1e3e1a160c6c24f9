//! Beyond the library (issue 20, item 2): when the library's twin leaves a raw residual above
//! the noise floor, a family of physically meaningful corrections
//! ([`crate::params::CorrectionParams`]) is searched the way the library is: each candidate
//! is fitted on top of the current model with the current knobs but the mass, ranked by ΔBIC
//! on the fit records, and the best is re-fitted with every knob and kept only when it removes
//! at least [`CalibrationOptions::min_relative_gain`] of the residual *and* lowers the
//! weighted error on the held-out records by [`CalibrationOptions::min_validation_gain`].
//! Rounds repeat up to [`CalibrationOptions::max_proposed`] terms, and stop once the twin with
//! the kept terms is at its raw-error floor (the search's own condition to run). Where the
//! twin with them is still above that floor, the library is searched again beside them
//! ([`library_beside`]): an effect of the library that the one it lacks had hidden (a friction
//! under a drifting null) goes into the proposed twin ([`Proposal::beside`]). Then each
//! effect the library added is switched off and the rest fitted again: one that no longer
//! earns its parameters beside the proposed terms (the library had added it to follow the
//! effect it lacks: a supply sag beside a quadratic damping) is left out of the proposed
//! twin ([`Proposal::left_out`]). What is kept is
//! *proposed*: the verdict stays the library's, and the report says in physical words what the
//! terms are and whether they bring every raw channel to its floor.

use super::context::{SearchContext, raw_error_at, validation_rms};
use super::data::Campaign;
use super::effects::{self, Added};
use super::fit::{self, FitResult, Knob};
use super::progress::Stage;
use super::result::{LeftOut, ProposedScore, ProposedTerm};
use super::starts::best_of;
use super::term_form::Agreement;
use super::{CalibrationOptions, EffectId, IdentifyError};
use crate::params::Params;
use rayon::prelude::*;
use serde::Serialize;

/// A correction term beyond the library, one parameter each.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, PartialOrd, Ord)]
#[serde(rename_all = "snake_case")]
pub enum CorrectionId {
    /// Discharge coefficient changing with the spool opening.
    CdOpening,
    /// Flow gain differing between the spool directions.
    FlowDirection,
    /// Flow gain differing between the metering edges to tank and from supply.
    ReturnEdge,
    /// A spring on the body beyond the declared stiffness.
    Spring,
    /// Damping quadratic in the velocity.
    QuadraticDamping,
    /// Leakage across the piston growing with √|Δp|.
    TurbulentLeakage,
    /// A first-order lag of the valve command, beside the delay τ.
    CommandLag,
    /// The valve's null drifting during each record.
    CommandDrift,
}

impl CorrectionId {
    /// Every correction of the family.
    pub const ALL: [CorrectionId; 8] = [
        CorrectionId::CdOpening,
        CorrectionId::FlowDirection,
        CorrectionId::ReturnEdge,
        CorrectionId::Spring,
        CorrectionId::QuadraticDamping,
        CorrectionId::TurbulentLeakage,
        CorrectionId::CommandLag,
        CorrectionId::CommandDrift,
    ];

    /// The id in reports (`cd_opening`, `flow_direction`, …).
    pub fn name(self) -> &'static str {
        match self {
            CorrectionId::CdOpening => "cd_opening",
            CorrectionId::FlowDirection => "flow_direction",
            CorrectionId::ReturnEdge => "return_edge",
            CorrectionId::Spring => "spring",
            CorrectionId::QuadraticDamping => "quadratic_damping",
            CorrectionId::TurbulentLeakage => "turbulent_leakage",
            CorrectionId::CommandLag => "command_lag",
            CorrectionId::CommandDrift => "command_drift",
        }
    }

    /// The parameter that sizes it (the first of [`Self::knobs`]).
    pub fn knob(self) -> Knob {
        self.knobs()[0]
    }

    /// The parameters fitted for it: its size, and for the direction difference the spool
    /// travel it builds up over.
    pub fn knobs(self) -> &'static [Knob] {
        match self {
            CorrectionId::CdOpening => &[Knob::CdSlope],
            CorrectionId::FlowDirection => &[Knob::FlowDirection, Knob::FlowDirectionWidth],
            CorrectionId::ReturnEdge => &[Knob::ReturnEdge],
            CorrectionId::Spring => &[Knob::ExtraSpring],
            CorrectionId::QuadraticDamping => &[Knob::QuadraticDamping],
            CorrectionId::TurbulentLeakage => &[Knob::TurbulentLeakage],
            CorrectionId::CommandLag => &[Knob::CommandLag],
            CorrectionId::CommandDrift => &[Knob::CommandDrift],
        }
    }

    /// Whether its parameter has a sign (else it is `≥ 0`).
    fn signed(self) -> bool {
        !matches!(
            self,
            CorrectionId::QuadraticDamping
                | CorrectionId::TurbulentLeakage
                | CorrectionId::CommandLag
        )
    }

    /// The term in physical words, with its value `v` and 1-σ uncertainty `s` (SI).
    pub fn describe(self, v: f64, s: f64, p: &Params) -> String {
        let pm = |x: f64, dx: f64, d: usize| format!("{x:.d$} ± {dx:.d$}");
        match self {
            CorrectionId::CdOpening => format!(
                "Cd {} {} % from small to full spool opening",
                if v >= 0.0 { "rises" } else { "falls" },
                pm(100.0 * v.abs(), 100.0 * s, 1)
            ),
            CorrectionId::FlowDirection => {
                // Gain ratio (1 + a)/(1 − a) − 1 ≈ 2a.
                let r = (1.0 + v) / (1.0 - v) - 1.0;
                let dr = 2.0 * s / (1.0 - v).powi(2);
                format!(
                    "the valve passes {} % {} flow with the spool opened positive (supply to \
                     chamber 2) than negative, at the same opening and pressure drop",
                    pm(100.0 * r.abs(), 100.0 * dr, 1),
                    if r >= 0.0 { "more" } else { "less" }
                )
            }
            CorrectionId::ReturnEdge => {
                let r = (1.0 + v) / (1.0 - v) - 1.0;
                let dr = 2.0 * s / (1.0 - v).powi(2);
                format!(
                    "the metering edges to tank pass {} % {} flow than the edges from supply \
                     at the same opening and pressure drop",
                    pm(100.0 * r.abs(), 100.0 * dr, 1),
                    if r >= 0.0 { "more" } else { "less" }
                )
            }
            CorrectionId::Spring => format!(
                "a spring of {} N/m acts on the body beyond the declared stiffness ({:+.1} % of \
                 its {:.0} N/m)",
                pm(v, s, 0),
                100.0 * v / p.plant.body.stiffness_n_per_m,
                p.plant.body.stiffness_n_per_m
            ),
            CorrectionId::QuadraticDamping => format!(
                "a damping force quadratic in the velocity, c·u̇·|u̇| with c = {} N·s²/m² \
                 ({:.1} N at 0.1 m/s)",
                pm(v, s, 0),
                v * 0.01
            ),
            CorrectionId::TurbulentLeakage => format!(
                "a leakage across the piston growing with the square root of the pressure \
                 difference: {} L/min at 10 bar",
                pm(6e4 * v * 1e3, 6e4 * s * 1e3, 3)
            ),
            CorrectionId::CommandLag => format!(
                "the valve follows its command through a first-order lag of {} ms beside the \
                 delay τ = {:.2} ms (its gain falls to {:.0} % at 20 Hz)",
                pm(1e3 * v, 1e3 * s, 2),
                1e3 * p.plant.valve.tau_s,
                100.0 / (1.0 + (2.0 * std::f64::consts::PI * 20.0 * v).powi(2)).sqrt()
            ),
            CorrectionId::CommandDrift => format!(
                "the valve's null drifts by {} mV/s during each record: an offset of the command \
                 that grows from the record's start ({:+.1} mV after 10 s), as a torque motor or \
                 an amplifier warming up makes it",
                pm(1e3 * v, 1e3 * s, 3),
                1e4 * v
            ),
        }
    }
}

/// What the search beyond the library found.
#[derive(Debug, Clone)]
pub struct Proposal {
    /// The fit with the kept terms (every knob re-fitted), at the fit step.
    pub fit: FitResult,
    /// Its knobs.
    pub knobs: Vec<Knob>,
    /// The kept terms, in order, with their ΔBIC, gain and held-out error `[before, after]`.
    pub kept: Vec<(CorrectionId, f64, f64, [f64; 2])>,
    /// Effects of the library found only beside the kept terms ([`library_beside`]), in the
    /// order added: the proposed twin carries them, the library's twin does not.
    pub beside: Vec<Added>,
    /// The library's effects the proposed twin leaves out
    /// ([`super::leave_out::leave_out_followers`]).
    pub left_out: Vec<LeftOut>,
}

/// What the search beyond the library tried, whether or not it kept a term.
#[derive(Debug, Clone, Default)]
pub struct Searched {
    /// The kept terms and their fit; `None` when no term cleared the bars.
    pub proposal: Option<Proposal>,
    /// Every candidate's score, per round (report.json's `proposed_candidates`, also where
    /// nothing was kept: the user sees how near the best came).
    pub candidates: Vec<ProposedScore>,
    /// Notes: rejected terms, and why the search stopped.
    pub notes: Vec<String>,
}

/// Coarse start for a correction: its parameter on a small grid (both signs when signed), the
/// best of the grid and zero.
fn multi_start(
    cx: &SearchContext<'_>,
    current: &Params,
    c: CorrectionId,
) -> Result<Params, IdentifyError> {
    let mut grid = vec![0.0];
    // A command lag looks like more delay at low frequency, and the delay τ has already
    // taken it: each lag of the grid starts with τ shortened by as much (1, 2, 4, 8 ms).
    let lag = c == CorrectionId::CommandLag;
    let sizes: &[f64] = if lag {
        &[1.0, 2.0, 4.0, 8.0]
    } else {
        &[0.3, 1.0, 3.0]
    };
    for &g in sizes {
        grid.push(g);
        if c.signed() {
            grid.push(-g);
        }
    }
    let starts: Vec<Params> = grid
        .iter()
        .map(|&g| {
            let mut p = *current;
            c.knob().set(&mut p, g);
            if lag {
                let shorter = p.plant.valve.tau_s - c.knob().value(&p);
                p.plant.valve.tau_s = shorter.max(0.0);
            }
            if c.knobs().len() > 1 {
                // The direction difference starts built up over 50 µm.
                c.knobs()[1].set(&mut p, 0.5);
            }
            p
        })
        .collect();
    Ok(best_of(cx.ev, &starts)?.unwrap_or(*current))
}

/// Rounds of ranking and re-fitting corrections from the library's final fit `start` (of
/// `knobs`, with the effects `library` added), as described in the [module docs](self): the
/// raw error is taken on `campaign`'s records at `preset`'s step. Its proposal is `None`
/// when nothing was kept; the candidates' scores and the notes are there either way.
pub fn search(
    cx: &SearchContext<'_>,
    campaign: &Campaign,
    preset: &Params,
    start: &FitResult,
    knobs: &[Knob],
    (library, partners): (&[EffectId], &[EffectId]),
) -> Result<Searched, IdentifyError> {
    let (ev, options): (_, &CalibrationOptions) = (cx.ev, cx.options);
    let mut current = start.clone();
    let mut knobs = knobs.to_vec();
    let mut current_val = validation_rms(&current.params, cx.validation)?;
    let mut remaining = CorrectionId::ALL.to_vec();
    let (mut kept, mut candidates, mut notes) = (Vec::new(), Vec::new(), Vec::new());
    // The raw error of `current` once a term is kept: the leaving-out starts from it.
    let mut current_raw = None;
    // Library effects kept together with a term ([`super::pair`]).
    let mut paired: Vec<Added> = Vec::new();
    let mut round = 0;
    while !remaining.is_empty() && kept.len() < options.max_proposed && round < 6 {
        round += 1;
        ev.monitor
            .enter(Stage::Proposed { round }, remaining.len() + 1);
        let screen: Vec<Knob> = knobs.iter().copied().filter(|k| *k != Knob::Mass).collect();
        let fits: Vec<Result<(CorrectionId, fit::Screened), IdentifyError>> = remaining
            .par_iter()
            .map(|&c| {
                let mut ks = screen.clone();
                ks.extend_from_slice(c.knobs());
                let p0 = multi_start(cx, &current.params, c)?;
                let f = fit::screen(ev, &p0, &ks, options.screen_iterations)?;
                ev.monitor.advance();
                Ok((c, f))
            })
            .collect();
        ev.monitor.check()?;
        let mut ranked = Vec::new();
        for f in fits {
            let (c, f) = f?;
            let k = c.knobs().len();
            let score =
                cx.bic.value(f.rss, knobs.len() + k) - cx.bic.value(current.rss, knobs.len());
            let gain = 1.0 - f.rss / current.rss;
            candidates.push(ProposedScore {
                name: c.name().into(),
                round,
                score,
                relative_gain: gain,
                value: c.knob().value(&f.params),
            });
            ranked.push((c, f, score, gain));
        }
        ranked.sort_by(|a, b| a.2.total_cmp(&b.2));
        let Some((c, screened, score, gain)) = ranked.into_iter().next() else {
            break;
        };
        // Only before any term is kept: the partners are what the library's last round
        // favoured against the library's own twin, and once a term takes its residual the
        // library is searched again beside it ([`library_beside`]).
        let mut pair = None;
        if kept.is_empty()
            && score < 0.0
            && gain < options.min_relative_gain
            && !partners.is_empty()
        {
            let (found, pair_notes) = super::pair::try_pairs(
                cx,
                (&current, &knobs, current_val),
                (c, &screened),
                partners,
            )?;
            notes.extend(pair_notes);
            pair = found;
        }
        // The term kept (its evidence, fit and knobs): with its pair's library effect, or
        // alone where it clears the bars and the held-out records.
        let (entry, refit, trial_knobs) = match pair {
            Some(pair) => {
                remaining.retain(|r| *r != c);
                paired.push(pair.effect);
                (pair.term, pair.fit, pair.knobs)
            }
            None => {
                if !(score < 0.0 && gain >= options.min_relative_gain) {
                    notes.push(format!(
                        "proposed round {round}: no term clears the bars (ΔBIC < 0 and {:.0} % \
                         of the residual); the criterion's best, `{}`, has ΔBIC {score:.1} and \
                         removes {:.1} %",
                        100.0 * options.min_relative_gain,
                        c.name(),
                        100.0 * gain
                    ));
                    break;
                }
                remaining.retain(|r| *r != c);
                let mut trial_knobs = knobs.clone();
                trial_knobs.extend_from_slice(c.knobs());
                let refit = fit::fit(
                    ev,
                    &screened.params,
                    &trial_knobs,
                    options.max_iterations,
                    cx.bic.ratio(),
                )?;
                let val = validation_rms(&refit.params, cx.validation)?;
                ev.monitor.advance();
                // A NaN held-out error does not improve it either.
                let improves = val < (1.0 - options.min_validation_gain) * current_val;
                if !improves {
                    notes.push(format!(
                        "proposed round {round}: `{}` improved the fit records (ΔBIC \
                         {score:.1}, {:.1} % of the residual) but not the held-out ones \
                         (validation weighted RMS {current_val:.3} → {val:.3}): not proposed",
                        c.name(),
                        100.0 * gain
                    ));
                    continue;
                }
                ((c, score, gain, [current_val, val]), refit, trial_knobs)
            }
        };
        kept.push(entry);
        knobs = trial_knobs;
        current = refit;
        current_val = entry.3[1];
        // The search runs because the library's twin is above its raw-error floor; once the
        // kept terms bring it there, a further round has nothing left to explain.
        let raw = raw_error_at(cx, campaign, preset, &current.params)?;
        let at_floor = raw.at_floor();
        if at_floor && !remaining.is_empty() && kept.len() < options.max_proposed {
            notes.push(format!(
                "proposed round {round}: with `{}` every raw channel of every record is at its \
                 noise floor ({}): no further round",
                c.name(),
                raw.summary()
            ));
        }
        current_raw = Some(raw);
        if at_floor {
            break;
        }
    }
    if kept.is_empty() {
        return Ok(Searched {
            proposal: None,
            candidates,
            notes,
        });
    }
    let (found_beside, beside_notes) = library_beside(
        cx,
        campaign,
        preset,
        library,
        (&mut current, &mut knobs, &mut current_val),
        &mut current_raw,
    )?;
    notes.extend(beside_notes);
    let beside = paired.into_iter().chain(found_beside).collect();
    let left_out = super::leave_out::leave_out_followers(
        cx,
        campaign,
        preset,
        library,
        (&mut current, &mut knobs, &mut current_val),
        current_raw,
    )?;
    Ok(Searched {
        proposal: Some(Proposal {
            fit: current,
            knobs,
            kept,
            beside,
            left_out,
        }),
        candidates,
        notes,
    })
}

/// The library searched again beside the kept terms ([`effects::search`], the library's
/// effects `library` already on), where the twin with them is still above its raw-error
/// floor: an effect the library has may not earn its parameters under the residual of the
/// one it lacks (a friction beside a drifting null screens at ΔBIC +26 under the drift) and
/// earn them once a proposed term takes that residual. What it adds goes into the proposed
/// twin only; the library's twin and its verdict are left as they are. Only the criterion's
/// bars admit an effect here, never the raw error's ([`effects::search`]). Returns the effects
/// added and the search's notes; `current_raw` (the raw error of `current`) is kept where
/// nothing was added.
fn library_beside(
    cx: &SearchContext<'_>,
    campaign: &Campaign,
    preset: &Params,
    library: &[EffectId],
    (current, knobs, current_val): (&mut FitResult, &mut Vec<Knob>, &mut f64),
    current_raw: &mut Option<super::raw_error::RawErrorReport>,
) -> Result<(Vec<Added>, Vec<String>), IdentifyError> {
    let raw = match current_raw.take() {
        Some(r) => r,
        None => raw_error_at(cx, campaign, preset, &current.params)?,
    };
    let mut options = cx.options.clone();
    options.max_effects = options.max_effects.saturating_sub(library.len());
    if raw.at_floor() || options.max_effects == 0 {
        *current_raw = Some(raw);
        return Ok((Vec::new(), Vec::new()));
    }
    let beside_cx = SearchContext {
        options: &options,
        ..*cx
    };
    let found = effects::search(
        &beside_cx,
        campaign,
        preset,
        (current, knobs),
        (library, false),
    )?;
    let notes = found
        .notes
        .iter()
        .map(|n| format!("beside the proposed terms, the library again: {n}"))
        .collect();
    if found.added.is_empty() {
        *current_raw = Some(raw);
    } else {
        *current_val = validation_rms(&found.current.params, cx.validation)?;
        (*current, *knobs) = (found.current, found.knobs);
    }
    Ok((found.added, notes))
}

/// The kept terms of `proposal` as reported, with the values of its final fit `fit` and, for
/// each, the records' agreement on its size (`agreements`, in the order of the kept terms;
/// [`super::term_form`]): where they disagree beyond their noise, its 1-σ is scaled and the
/// description says why.
pub fn terms(
    proposal: &Proposal,
    fit: &FitResult,
    agreements: &[Option<Agreement>],
) -> Vec<ProposedTerm> {
    proposal
        .kept
        .iter()
        .zip(agreements.iter().chain(std::iter::repeat(&None)))
        .map(|(&(c, score, gain, [v0, v1]), agreement)| {
            let scaled = agreement.as_ref().filter(|a| a.scale > 1.0);
            let value = |k: Knob| {
                let scale = scaled.filter(|_| k == c.knob()).map_or(1.0, |a| a.scale);
                fit.values
                    .iter()
                    .find(|x| x.knob == k)
                    .map_or((k.value(&fit.params), f64::NAN), |x| {
                        (x.value, scale * x.std)
                    })
            };
            let (v, s) = value(c.knob());
            let mut description = c.describe(v, s, &fit.params);
            if c == CorrectionId::FlowDirection {
                let (w, sw) = value(Knob::FlowDirectionWidth);
                description.push_str(&format!(
                    ", building up over {:.0} ± {:.0} µm of spool travel about null",
                    1e6 * w,
                    1e6 * sw
                ));
            }
            if let Some(a) = scaled {
                let (lo, hi) = a.range();
                let unit = super::units::format_value;
                description.push_str(&format!(
                    "; fitted on each record alone it ranges from {} to {} (χ²/dof = {:.1} over \
                     {} records): the records disagree on its size beyond their noise, so its \
                     form is not quite the rig's effect's, and its uncertainty is scaled by \
                     √(χ²/dof) = {:.1}",
                    unit(c.knob().name(), lo),
                    unit(c.knob().name(), hi),
                    a.chi2_per_dof,
                    a.per_record.len(),
                    a.scale,
                ));
            }
            ProposedTerm {
                name: c.name().into(),
                description,
                per_record: agreement
                    .as_ref()
                    .map(|a| a.per_record.clone())
                    .unwrap_or_default(),
                uncertainty_scale: agreement.as_ref().map_or(1.0, |a| a.scale),
                params: c
                    .knobs()
                    .iter()
                    .map(|k| (k.name().to_string(), value(*k).0))
                    .collect(),
                uncertainties: c
                    .knobs()
                    .iter()
                    .map(|k| (k.name().to_string(), value(*k).1))
                    .collect(),
                evidence: format!(
                    "ΔBIC = {score:.1} when added; removed {:.1} % of the remaining weighted \
                     residual sum of squares on the fit records; validation weighted RMS \
                     {v0:.3} → {v1:.3} on the held-out records",
                    100.0 * gain
                ),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// calibrated.toml carries the proposed terms (`[corrections]`, read back exactly), and
    /// the twin a replay builds from it applies them: at rest pressures and 1 cm of stroke, a
    /// spring of 500 N/m changes the body acceleration by −500·0.01/m; a 10 % flow gain for
    /// a positive spool raises the supply-edge flow by 10 %.
    #[test]
    fn calibrated_toml_carries_the_terms_and_the_twin_applies_them() {
        use crate::model::{Inputs, Model, twin::Twin};
        use crate::preset::{Preset, PresetMeta};
        let mut p = Params::paper();
        p.plant.corrections.spring_n_per_m = 500.0;
        p.plant.corrections.flow_gain_direction = 0.1;
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("calibrated.toml");
        Preset {
            meta: PresetMeta::default(),
            params: p,
            per_record: Default::default(),
        }
        .save(&path)
        .unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(text.contains("[corrections]"), "{text}");
        let loaded = Preset::load(&path).unwrap().params;
        assert_eq!(loaded.plant.corrections, p.plant.corrections);
        let (plain, corrected) = (Twin::new(Params::paper()), Twin::new(loaded));
        let mut y = plain.rest_state();
        y[0] = 0.01;
        let inputs = Inputs {
            v_valve: 0.0,
            xdd: 0.0,
        };
        let (a0, a1) = (
            plain.derivatives(0.0, &y, &inputs)[1],
            corrected.derivatives(0.0, &y, &inputs)[1],
        );
        let m = p.plant.body.mass_kg;
        assert!((a1 - a0 + 500.0 * 0.01 / m).abs() < 1e-9, "{a0} {a1}");
        let x = 4e-4;
        let (f0, f1) = (
            plain.valve_flows(x, 50e5, 50e5),
            corrected.valve_flows(x, 50e5, 50e5),
        );
        assert!((f1.q2v / f0.q2v - 1.1).abs() < 1e-12, "{f0:?} {f1:?}");
        assert!((f1.q1v / f0.q1v - 1.1).abs() < 1e-12);
    }

    #[test]
    fn corrections_have_distinct_knobs_and_words() {
        let p = Params::paper();
        let mut knobs: Vec<Knob> = CorrectionId::ALL
            .iter()
            .flat_map(|c| c.knobs().to_vec())
            .collect();
        let n = knobs.len();
        knobs.dedup();
        assert_eq!(knobs.len(), n);
        assert_eq!(
            CorrectionId::CdOpening.describe(0.05, 0.004, &p),
            "Cd rises 5.0 ± 0.4 % from small to full spool opening"
        );
        let d = CorrectionId::CommandLag.describe(4e-3, 2e-4, &p);
        // 1/√(1 + (2π·20·0.004)²) = 0.893.
        assert!(
            d.contains("lag of 4.00 ± 0.20 ms") && d.contains("89 % at 20 Hz"),
            "{d}"
        );
        let d = CorrectionId::Spring.describe(-368.0, 12.0, &p);
        assert!(d.contains("-368 ± 12 N/m") && d.contains("-10.0 %"), "{d}");
        // A flow gain 1.05 one way and 0.95 the other: 10.5 % more flow.
        let d = CorrectionId::FlowDirection.describe(0.05, 0.001, &p);
        assert!(
            d.starts_with("the valve passes 10.5 ± 0.2 % more flow"),
            "{d}"
        );
        // The parameter round-trips through its knob.
        for c in CorrectionId::ALL {
            let mut q = p;
            c.knob().set(&mut q, 0.7);
            assert!((c.knob().theta(&q) - 0.7).abs() < 1e-12, "{}", c.name());
            q.validate().unwrap();
        }
    }
}
