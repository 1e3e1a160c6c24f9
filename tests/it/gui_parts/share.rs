//! `seat_twin::gui::share`: unit tests kept out of the library (see `gui_parts`).

use seat_twin::engine::Speed;
use seat_twin::gui::share::*;

#[test]
fn every_compiled_in_preset_parses() {
    for (name, _) in SHIPPED {
        assert!(shipped_preset(name).is_ok(), "{name}");
    }
}

#[test]
fn a_setup_survives_its_link_bit_for_bit() {
    let mut s = Setup::defaults();
    s.preset = "tuned-predictive".into();
    s.params = shipped_preset("tuned-predictive").unwrap().params;
    s.params.controller.kp_v_per_m = -123.456_789_012_345;
    s.excitation.random.seed = 42;
    s.excitation.random.duration_s = 20.0;
    s.speed = Speed::Max;
    s.presentation = true;
    s.lesson = Some(2);
    let back = Setup::decode(&s.encode()).unwrap();
    assert_eq!(back.params, s.params);
    assert_eq!(back.preset, "tuned-predictive");
    assert_eq!(back.excitation.random, s.excitation.random);
    assert_eq!(back.speed, Speed::Max);
    assert!(back.presentation);
    assert_eq!(back.lesson, Some(2));
    // Only what differs from the preset travels.
    assert!(
        s.encode()
            .contains("controller.kp_v_per_m=-123.456789012345")
    );
    assert!(!s.encode().contains("valve.cd"));
}

#[test]
fn bad_links_name_the_field_and_what_is_allowed() {
    let err = |t: &str| Setup::decode(t).unwrap_err();
    assert!(err("2;preset=paper").contains("version 2"));
    assert!(err("hello").contains("not a setup link"));
    assert!(err("1;preset=nope").contains("unknown preset `nope`"));
    assert!(err("1;controller.kp_v_per_m=abc").contains("not a finite number"));
    assert!(err("1;valve.cd=7").contains("valve.cd"));
    assert!(err("1;colour=red").contains("unknown key"));
    assert!(err("1;exc=random,1,0.1").contains("duration"));
    assert!(err("1;exc=warp,1").contains("unknown excitation"));
    assert!(err("1;lesson=99").contains("lesson step"));
    assert!(err("1;speed=warp").contains("slow, 1x, fast, max"));
}

#[test]
fn an_escaped_fragment_reads_like_the_plain_one() {
    let plain = Setup::decode("#s=1;preset=paper;exc=sine,0.5,6").unwrap();
    let escaped = Setup::decode("#s=1%3Bpreset=paper%3Bexc=sine,0.5,6").unwrap();
    assert_eq!(plain.excitation.sine_freq_hz, 6.0);
    assert_eq!(escaped.excitation.sine_freq_hz, 6.0);
}
