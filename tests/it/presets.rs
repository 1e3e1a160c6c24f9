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
