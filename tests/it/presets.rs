//! Every shipped preset loads, validates and says what it claims (issue 2's three presets).

use seat_twin::params::Params;
use seat_twin::preset::{Preset, resolve};
use std::path::Path;

#[test]
fn every_file_in_presets_loads_and_validates() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("presets");
    let mut n = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "toml") {
            let p = Preset::load(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            p.params
                .validate()
                .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            n += 1;
        }
    }
    assert!(n >= 3, "found {n} presets");
}

#[test]
fn shipped_presets_hold_the_papers_values() {
    let paper = resolve("paper").unwrap().params;
    assert_eq!(paper, Params::paper());
    assert_eq!(paper.plant.valve.cd, 0.1506);
    assert_eq!(paper.plant.valve.tau_s, 0.0175);
    let initial = resolve("paper-initial").unwrap().params;
    assert_eq!(initial.plant.valve.cd, 0.1074);
    let consistent = resolve("consistent-delay").unwrap().params;
    assert!((consistent.plant.valve.tau_s - 0.0143).abs() < 0.0005);
}

#[test]
fn a_preset_survives_a_save_and_load_round_trip() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("round.toml");
    let mut p = Preset::paper();
    p.params.plant.valve.cd = 0.1234;
    p.params.plant.effects.friction.coulomb_n = 12.0;
    p.save(&path).unwrap();
    let back = Preset::load(&path).unwrap();
    assert_eq!(back.params, p.params);
}

/// The tuned presets say what they claim, re-computed here on the held-out ride of seed 101
/// (60 s; the tuning used seeds 1–3): each lowers the body's a_w against the paper's gains on
/// the same ride by at least the stated share, keeps the seat off its end stops and within
/// 30 mm of stroke, and its linearised loop keeps 6 dB and 45° of margin.
#[test]
fn tuned_presets_beat_the_papers_gains_on_a_held_out_ride() {
    use seat_twin::analysis::metrics;
    use seat_twin::analysis::stability;
    use seat_twin::experiments;
    use seat_twin::model::ModelKind;
    use seat_twin::simulation::Drive;
    use seat_twin::tune;

    let ride = |p: &Params| {
        let trace = experiments::run(
            p,
            ModelKind::Twin,
            Drive::closed_loop(p),
            tune::ride(101, 60.0),
            60.0,
            1000.0,
        )
        .unwrap();
        let ydd = trace.channel(|s| s.ydd);
        let aw = metrics::vibration_metrics(&ydd, 1000.0, tune::SETTLE_S)
            .unwrap()
            .aw;
        let max_u = trace.samples.iter().map(|s| s.u.abs()).fold(0.0, f64::max);
        (aw, max_u, trace.contacts.len())
    };
    let (paper_aw, _, _) = ride(&Params::paper());
    // (preset, smallest reduction of a_w against the paper's gains on this ride)
    for (name, least) in [
        ("tuned-paper", 0.0),
        ("tuned-predictive", 0.6),
        ("tuned-predictive-robust", 0.6),
    ] {
        let p = resolve(name).unwrap().params;
        let (aw, max_u, contacts) = ride(&p);
        let cut = 1.0 - aw / paper_aw;
        assert!(
            cut >= least,
            "{name}: a_w {aw:.4} vs paper {paper_aw:.4}: {cut:.3}"
        );
        assert_eq!(contacts, 0, "{name}");
        assert!(max_u <= tune::MAX_ABS_U_M, "{name}: max |u| {max_u}");
        let m = stability::twin_stability(&p);
        assert!(
            m.stable()
                && m.margins.gain_margin_db().abs() >= tune::MIN_GAIN_MARGIN_DB
                && m.margins.phase_margin_deg().abs() >= tune::MIN_PHASE_MARGIN_DEG
                && m.margins.delay_margin_s() >= tune::MIN_DELAY_MARGIN_S,
            "{name}: {m:?}"
        );
        println!(
            "{name}: a_w {aw:.4} m/s² vs paper {paper_aw:.4} ({:.0} %), max |u| {:.1} mm",
            -100.0 * cut,
            max_u * 1e3
        );
    }
}

/// Issue 20: the per-record values of a drift survive a save and a load, a record not
/// listed takes the campaign value, and a value out of range is refused naming its key.
#[test]
fn per_record_values_round_trip_and_are_checked() {
    let mut p = Preset::paper();
    p.per_record.cd.insert("sine_2hz.csv".into(), 0.1431);
    p.per_record.cd.insert("ride.csv".into(), 0.1552);
    let text = p.to_toml();
    assert!(text.contains("[per_record.cd]"), "{text}");
    let back = Preset::from_toml(&text, "c.toml".as_ref()).unwrap();
    assert_eq!(back, p);
    let (q, listed) = back.per_record.params_for(&back.params, "ride.csv");
    assert!(listed && q.plant.valve.cd == 0.1552);
    let (q, listed) = back.per_record.params_for(&back.params, "bump.csv");
    assert!(!listed && q.plant.valve.cd == back.params.plant.valve.cd);
    // Without a drift nothing is written.
    assert!(!Preset::paper().to_toml().contains("per_record"));
    let bad = text.replace("0.1552", "3.0");
    let e = Preset::from_toml(&bad, "c.toml".as_ref())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("per_record.cd.\"ride.csv\"") && e.contains("c.toml"),
        "{e}"
    );
}
