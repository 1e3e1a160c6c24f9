//! Single cases of the randomised survey (`survey`) that once failed, each calibrated as the
//! survey calibrates it and held to the rig's truth: the verdict, the effects, and the values
//! the failure was about.

use super::rig::calibrate_paper;
use super::survey::{Case, cases, effects_right, records_at, records_of, replayed_above_noise};
use seat_twin::identify::{self, CalibrationReport, EffectId, Verdict};

/// Case 20 of the fresh draw `SURVEY_SEED=2021` (overlap 43 µm, hoses at 0.55 GPa, chambers
/// at 0.9): the fit stopped at chambers 0.60 ± 0.015 GPa, 19σ from the truth, in a valley as
/// deep as the truth's (the records see mostly the total capacitance). The profile of the
/// split finds the other valley: both moduli are reported with 1-σ that span the two, and a
/// note says they trade off.
#[test]
fn a_hose_chamber_split_the_records_cannot_tell_is_reported_as_a_trade_off() {
    let (c, r) = survey_case(2021, 20);
    assert_eq!(c.fx.compliance.map(|(_, chambers)| chambers), Some(0.9e9));
    let compliance = r
        .effects
        .iter()
        .find(|e| e.effect == EffectId::Compliance)
        .expect("compliance found");
    let (hose, chambers) = c.fx.compliance.expect("a compliance rig");
    for (name, truth) in [
        ("effective_bulk_modulus_pa", chambers),
        ("hose_bulk_modulus_pa", hose),
    ] {
        let (v, s) = (compliance.params[name], compliance.uncertainties[name]);
        assert!(
            (v - truth).abs() <= 3.0 * s,
            "{name} = {v:e} ± {s:e}, truth {truth:e}; notes {:?}",
            r.notes
        );
    }
    assert!(
        r.notes.iter().any(|n| n.contains("trade off")),
        "no trade-off note: {:?}",
        r.notes
    );
}

/// Calibrates case `i` of the draw `seed` as the survey does.
fn survey_case(seed: u64, i: usize) -> (Case, CalibrationReport) {
    let c = cases(seed).swap_remove(i);
    let r = calibrate_paper(&records_of(seed, i, &c));
    (c, r)
}

/// Case `i` of the draw `seed`, calibrated, asserted `explained` with the rig's own effects.
fn explained_with_its_effects(seed: u64, i: usize) -> CalibrationReport {
    let (c, r) = survey_case(seed, i);
    let s = super::rig::summary(&r);
    assert!(effects_right(&c, &r), "{s}; {:?}", r.notes);
    assert_eq!(r.verdict, Verdict::Explained, "{s}");
    r
}

/// Case 2 of the draw 2021 (friction 36 N beside a 36 µm overlap): friction removed 39 % of
/// the weighted residual after the overlap, under the 40 % a further effect needs, and was
/// missed (`unexplained`, Cd 4.7σ off) while the raw error stood at 10× its floor; it was then
/// added by a trial on the raw error. Since the fit's weights take the sensor noise from the
/// same estimate as the verdict (2026-11-27; before, the stroke's noise read 10–15 times too
/// high, so the small tests' velocity weighed little), friction clears the bar by itself.
#[test]
fn friction_beside_an_overlap_is_found() {
    let r = explained_with_its_effects(2021, 2);
    let found: Vec<&str> = r.effects.iter().map(|e| e.effect.name()).collect();
    assert_eq!(found, ["valve_overlap", "friction"], "{:?}", r.notes);
}

/// Case 1 of the draw 2024 (friction alone, 47 N): the friction fit stopped in a valley whose
/// raw error left a band at 4.0×, and only a trial of compliance (ended at no size of its
/// own) let the friction move on to the rig's valley. With the fit's weights on the verdict's
/// noise estimate (2026-11-27) the friction fit reaches it directly: `explained` by friction
/// alone.
#[test]
fn friction_alone_of_the_2024_draw_is_explained() {
    let r = explained_with_its_effects(2024, 1);
    assert_eq!(r.effects.len(), 1, "{:?}", r.notes);
}

/// Case 20 of the draw 2025 (a 39 µm overlap beside hoses at 0.68 GPa): after the overlap,
/// compliance's screening fit started from the chambers' modulus on a grid of ×3 steps and
/// stopped in a valley of the hydraulic mode on the wrong side of the 20 Hz test (ΔBIC +7.2):
/// compliance was missed, τ read 4.1σ off and the replay rang at 34× its floor. On a grid of
/// ×1.2 steps its best start lies in the rig's valley (69 % of the residual): `explained`,
/// with both moduli within 3σ of the rig's.
#[test]
fn softer_hoses_beside_an_overlap_are_found_on_a_fine_modulus_grid() {
    let r = explained_with_its_effects(2025, 20);
    let (hose, chambers) = cases(2025)
        .swap_remove(20)
        .fx
        .compliance
        .expect("a compliance rig");
    let compliance = r
        .effects
        .iter()
        .find(|e| e.effect == EffectId::Compliance)
        .expect("compliance added");
    for (name, truth) in [
        ("hose_bulk_modulus_pa", hose),
        ("effective_bulk_modulus_pa", chambers),
    ] {
        let (value, std) = (compliance.params[name], compliance.uncertainties[name]);
        assert!((value - truth).abs() < 3.0 * std, "{name}: {compliance:?}");
    }
}

/// Case 20 of the development draw at 200 Hz (a 39 µm overlap beside hoses at 0.61 GPa, the
/// chambers as declared). On compliance's two-dimensional start grid it removed 36 % of the
/// residual after the overlap, under the 40 % bar, and was tried on the raw error (worst band
/// 10.8× its floor → 2.2×); it was then refused as "of no size", because that rule read only
/// the chambers' modulus, which the re-fit rightly left at the oil's (fixed: either modulus
/// is compliance's size). Since the grid runs along the total compliance (2026-11-29) its
/// screening fit clears the bar by itself, so this case no longer takes the raw-error path.
/// It now takes the hoses' own search for the oil column's ringing (the fit's hoses, 0.593
/// GPa, mistime it): `explained`, the hoses within 2 % and 3σ of the rig's.
#[test]
fn soft_hoses_beside_an_overlap_at_200_hz_are_found_and_their_ringing_timed() {
    let (seed, i) = (2020, 20);
    let c = cases(seed).swap_remove(i);
    let r = calibrate_paper(&records_at(seed, i, &c, 200.0));
    let s = super::rig::summary(&r);
    assert!(effects_right(&c, &r), "{s}; {:?}", r.notes);
    assert_eq!(r.verdict, Verdict::Explained, "{s}; {:?}", r.notes);
    assert!(
        r.notes
            .iter()
            .any(|n| n.contains("hoses' bulk modulus, searched again")),
        "{:?}",
        r.notes
    );
    let (hose, _) = c.fx.compliance.expect("a compliance rig");
    let compliance = r
        .effects
        .iter()
        .find(|e| e.effect == EffectId::Compliance)
        .expect("compliance added");
    let (value, std) = (
        compliance.params["hose_bulk_modulus_pa"],
        compliance.uncertainties["hose_bulk_modulus_pa"],
    );
    assert!((value / hose - 1.0).abs() < 0.02, "{compliance:?}");
    assert!((value - hose).abs() < 3.0 * std, "{compliance:?}");
}

/// Case 26 of the 2026 draw (a valve offset of 3.4 µm beside a leakage of 2.9e-12 m³/(s·Pa)
/// that grows by |Δp|/200 bar): the leakage's re-fit took its growth to the bound (1e-6 /Pa)
/// with the coefficient near zero, a law all quadratic in Δp; the plain law was kept and u of
/// the 10 Hz / 4 V test stayed 4.1× its floor in 0–0.5 Hz (`unexplained`). The re-fit now also
/// starts from growths over two decades (the leakage at 5 MPa kept): `explained`, the growth
/// and the coefficient within 3σ of the rig's.
#[test]
fn a_growing_leakage_beside_an_offset_is_refitted_from_several_growths() {
    let r = explained_with_its_effects(2026, 26);
    assert_leakage_on_the_rigs(2026, 26, &r);
}

/// The leakage of `r`, the calibration of case `i` of the draw `seed`: its coefficient and its
/// growth within 3σ of the rig's.
fn assert_leakage_on_the_rigs(seed: u64, i: usize, r: &CalibrationReport) {
    let leakage = r
        .effects
        .iter()
        .find(|e| e.effect == EffectId::Leakage)
        .expect("leakage added");
    let truth = cases(seed)
        .swap_remove(i)
        .fx
        .leakage
        .expect("a leakage rig");
    for (name, truth) in [("coefficient_m3_per_s_pa", truth), ("growth_per_pa", 5e-8)] {
        let (value, std) = (leakage.params[name], leakage.uncertainties[name]);
        assert!((value - truth).abs() < 3.0 * std, "{name}: {leakage:?}");
    }
}

/// Case 12 of the 2026 draw at 200 Hz (no hidden effect): the fits, which see the channels
/// below 25 Hz, left the mass at 11.93 ± 0.32 kg against the rig's 11.7, inside its 1-σ, and
/// the oil column's ringing after each command step ran 1 % off in frequency. The replayed ÿ
/// was then further from the records than the nominal preset's (0.093 → 0.212 m/s² above the
/// noise). The mass is now searched again, within 2σ, for that ringing
/// (`identify::ringing`): it lands on the rig's mass and the calibrated.toml, replayed,
/// halves the nominal error on u and ÿ; the verdict stays `no_missing_effect`.
#[test]
fn a_mistimed_ringing_at_200_hz_puts_the_mass_on_the_rigs() {
    let (_, recs, r) = calibrated_at_200_hz(2026, 12);
    let s = super::rig::summary(&r);
    assert_eq!(r.verdict, Verdict::NoMissingEffect, "{s}");
    assert!(
        r.notes.iter().any(|n| n.contains("searched again")),
        "{:?}",
        r.notes
    );
    let mass = r
        .calibrated
        .iter()
        .find(|v| v.knob == identify::fit::Knob::Mass)
        .expect("the mass is fitted");
    let truth = seat_twin::params::Params::paper().plant.body.mass_kg;
    assert!((mass.value / truth - 1.0).abs() < 0.005, "{mass:?}");
    assert!((mass.value - truth).abs() < 3.0 * mass.std, "{mass:?}");
    assert_replay_halves(&r, &recs);
}

/// Case 20 of the 2024 draw at 200 Hz (a 37 µm overlap beside hoses at 0.61 GPa, chambers
/// at 0.9): `explained` with both effects and every band at its floor, but the calibrated
/// hoses once read 0.642 GPa (inside their 1-σ of 0.056), so the oil column's ringing after
/// each command step ran out of time with the records: sample by sample 220× the noise above
/// 25 Hz, and the replayed ÿ 6.0 m/s² above the noise against 9.6 nominal. The moduli are
/// searched again for that ringing (`identify::ringing`). The records see the total
/// compliance of hoses and chambers, not its split (the report says the two trade off), so
/// the test holds the total against the rig's: the oil column's stiffness within 2 %, each
/// modulus within 3σ, and the calibrated.toml, replayed, halves the nominal error.
#[test]
fn a_mistimed_ringing_at_200_hz_puts_the_oil_stiffness_on_the_rigs() {
    let (c, recs, r) = calibrated_at_200_hz(2024, 20);
    let s = super::rig::summary(&r);
    assert!(effects_right(&c, &r), "{s}");
    assert_eq!(r.verdict, Verdict::Explained, "{s}");
    assert!(
        r.notes.iter().any(|n| n.contains("searched again")),
        "{:?}",
        r.notes
    );
    let (hoses, chambers) = c.fx.compliance.expect("a compliance rig");
    let mut rig = seat_twin::params::Params::paper();
    let compliance = &mut rig.plant.effects.compliance;
    compliance.enabled = true;
    compliance.effective_bulk_modulus_pa = chambers;
    compliance.hose_bulk_modulus_pa = hoses;
    let total = |p: &seat_twin::params::Params| {
        let d = seat_twin::params::derived(p);
        d.c_chamber + d.c_hose
    };
    let ratio = total(&r.params) / total(&rig);
    assert!(
        (ratio - 1.0).abs() < 0.02,
        "total compliance {ratio} of the rig's; {s}"
    );
    let fitted = r
        .effects
        .iter()
        .find(|e| e.effect == EffectId::Compliance)
        .expect("compliance found");
    for (name, truth) in [
        ("effective_bulk_modulus_pa", chambers),
        ("hose_bulk_modulus_pa", hoses),
    ] {
        let (value, std) = (fitted.params[name], fitted.uncertainties[name]);
        assert!((value - truth).abs() < 3.0 * std, "{name}: {fitted:?}");
    }
    assert_replay_halves(&r, &recs);
}

/// Case `i` of the draw `seed`, its records sampled at 200 Hz, and their calibration.
fn calibrated_at_200_hz(
    seed: u64,
    i: usize,
) -> (Case, Vec<seat_twin::dataset::Record>, CalibrationReport) {
    let c = cases(seed).swap_remove(i);
    let recs = records_at(seed, i, &c, 200.0);
    let r = calibrate_paper(&recs);
    (c, recs, r)
}

/// `r`'s calibrated.toml, replayed on `recs`, leaves at most half the nominal error above the
/// noise on u and ÿ.
fn assert_replay_halves(r: &CalibrationReport, recs: &[seat_twin::dataset::Record]) {
    let (nominal, after) = replayed_above_noise(r, recs);
    assert!(
        (0..2).all(|k| after[k] <= 0.5 * nominal[k]),
        "above the noise, u and ÿ: nominal {nominal:?}, calibrated {after:?}"
    );
}

/// Case 8 of the 2028 draw (a leakage of 3.4e-12 m³/(s·Pa) that grows by |Δp|/200 bar,
/// beside hoses at 0.49 GPa): the leakage was added first, and its growth weighed then, while
/// the hoses' compliance was still missing from the model: left out (11.6 ± 99.7 % per
/// 100 bar). After both effects, u of the 10 Hz / 4 V test stayed 3.1× its floor in 0.5–5 Hz,
/// so the verdict read `unexplained`. A refinement left out is now fitted again once every
/// effect is in place (`identify::refine::revisit`): the growth reads 51 ± 27 % per 100 bar
/// (the rig's 50), the worst band 1.4×, `explained`. The same pair failed at 10 kHz on the
/// 2020 and 2021 draws' case 8 and now reads right there too.
#[test]
fn a_leakage_growth_hidden_by_soft_hoses_is_fitted_again_after_the_search() {
    let r = explained_with_its_effects(2028, 8);
    assert!(
        r.notes
            .iter()
            .any(|n| n.contains("fitted again with every effect in place") && n.ends_with("kept")),
        "{:?}",
        r.notes
    );
    assert_leakage_on_the_rigs(2028, 8, &r);
}

/// Case 4 of the draw 2020 (no plant effect; the accelerometer reads 0.5 % high, with an
/// offset of 0.22 m/s²): the scale came out 1.0050 ± 0.0024, 2.1σ from exact, and was set
/// back to 1, which left the 10 Hz test's ÿ at 3.9× its floor in 5–25 Hz. The verdict was
/// then judged on the twin before the set-back (`no_missing_effect`) while the twin
/// calibrated.toml carried was above its floor. Judged on the delivered twin (2026-11-30), the
/// case read `unexplained`; a sensor property the raw error needs is now kept as estimated,
/// reported, and the delivered twin is at its floor.
#[test]
fn an_accelerometer_scale_the_raw_error_needs_is_kept_though_within_3_sigma() {
    let (c, r) = survey_case(2020, 4);
    let s = super::rig::summary(&r);
    assert_eq!(r.verdict, Verdict::NoMissingEffect, "{s}; {:?}", r.notes);
    assert!(
        r.raw_error_after.at_floor(),
        "{}",
        r.raw_error_after.summary()
    );
    assert!(effects_right(&c, &r), "{s}; sensors {:?}", r.sensors);
    let truth = c.fx.ydd_scale.expect("a scale error");
    let scale = r
        .sensors
        .iter()
        .find(|e| e.channel == "ydd" && e.kind == "scale")
        .expect("the scale reported");
    assert!(
        (scale.value - truth).abs() <= 3.0 * scale.uncertainty,
        "scale {} ± {}, truth {truth}",
        scale.value,
        scale.uncertainty
    );
    assert!(
        r.notes.iter().any(|n| n.contains("kept as estimated")),
        "{:?}",
        r.notes
    );
    // Only what the raw error needs: no stroke lag on a rig without one.
    assert!(
        c.fx.u_lag_s.is_some() || !r.sensors.iter().any(|e| e.kind == "lag"),
        "{:?}",
        r.sensors
    );
}
