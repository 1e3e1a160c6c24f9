//! The slave's state machine, inputs and serialised state.

use super::state::SavedSlave;
use super::*;

fn stepping() -> Slave {
    let mut s = Slave::new(Params::paper(), ControllerPlacement::Internal);
    s.setup(0.0).unwrap();
    s.enter_initialization().unwrap();
    s.exit_initialization().unwrap();
    s
}

#[test]
fn wrong_calls_are_refused_with_a_reason() {
    let mut s = Slave::new(Params::paper(), ControllerPlacement::Internal);
    assert!(s.do_step(0.0, 1e-3).unwrap_err().contains("not allowed"));
    assert!(s.set(9999, 1.0).unwrap_err().contains("9999"));
    assert!(s.set(VR_XDD, f64::NAN).unwrap_err().contains("range"));
    let kp = VR_PARAMS
        + PARAMS
            .iter()
            .position(|p| p.key == "controller.kp_v_per_m")
            .unwrap() as u32;
    assert!(
        s.set(kp, 1e9)
            .unwrap_err()
            .contains("controller.kp_v_per_m")
    );
    let mut s = stepping();
    let mass = VR_PARAMS + PARAMS.iter().position(|p| p.key == "body.mass_kg").unwrap() as u32;
    assert!(s.set(mass, 12.0).unwrap_err().contains("fixed"));
    assert!(s.do_step(0.0, 0.7e-3).unwrap_err().contains("multiple"));
    assert!(s.do_step(0.5, 1e-3).unwrap_err().contains("time"));
    assert!(s.set(VR_OUTPUTS, 1.0).unwrap_err().contains("output"));
    // A gain of a kind the preset does not have is no variable of the FMU.
    let lead = VR_PARAMS
        + PARAMS
            .iter()
            .position(|p| p.key == "controller.lead_s")
            .unwrap() as u32;
    assert!(s.get(lead).is_err());
}

#[test]
fn input_segment_and_command_stream_read_as_documented() {
    let seg = InputSegment {
        t0: 1.0,
        x: 0.0,
        xdd: [2.0, 3.0, 4.0, 6.0],
    };
    // 2 + 3·d + 4·d²/2 + 6·d³/6 at d = 0.5.
    assert_eq!(seg.xdd_at(1.5), 2.0 + 1.5 + 0.5 + 0.125);
    let mut c = CommandStream::default();
    c.push(0.0, 1.0, 0.1);
    c.push(0.01, 3.0, 0.1);
    assert_eq!(c.at(-1e-9), 0.0);
    assert_eq!(c.at(0.005), 2.0);
    assert_eq!(c.at(0.02), 3.0);
    // Samples older than the window go, except the newest of them.
    c.push(0.5, 5.0, 0.1);
    assert_eq!(c.at(0.45), 3.0 + 0.44 / 0.49 * 2.0);
    assert_eq!(c.at(0.005), 0.0);
}

#[test]
fn external_command_is_saturated_and_reaches_the_valve_tau_later() {
    let p = Params::paper();
    let mut s = Slave::new(p, ControllerPlacement::External);
    s.setup(0.0).unwrap();
    s.enter_initialization().unwrap();
    s.exit_initialization().unwrap();
    s.set(VR_V_IN_EXT, 25.0).unwrap();
    assert_eq!(s.get(VR_OUTPUTS + 7).unwrap(), p.plant.valve.v_max_v);
    // The spool does not move before τ = 17.5 ms, and does after.
    let xv = VR_OUTPUTS + 6;
    for k in 0..35 {
        s.do_step(k as f64 * 5e-4, 5e-4).unwrap();
    }
    assert_eq!(s.get(xv).unwrap(), 0.0);
    for k in 35..40 {
        s.do_step(k as f64 * 5e-4, 5e-4).unwrap();
    }
    assert!(s.get(xv).unwrap() > 0.0);
}

fn vr_of(key: &str) -> u32 {
    VR_PARAMS + PARAMS.iter().position(|p| p.key == key).unwrap() as u32
}

/// One communication step of 1 ms at `k` with a sine input and its slope (and a held
/// external command for that placement).
fn drive(s: &mut Slave, k: u64) {
    let t = k as f64 * 1e-3;
    s.set(VR_XDD, 0.8 * (7.0 * t).sin()).unwrap();
    s.set_derivative(VR_XDD, 1, 5.6 * (7.0 * t).cos()).unwrap();
    if s.placement == ControllerPlacement::External {
        s.set(VR_V_IN_EXT, 2.0 * (3.0 * t).sin()).unwrap();
    }
    s.do_step(t, 1e-3).unwrap();
}

fn outputs(s: &Slave) -> Vec<u64> {
    (0..OUTPUTS.len() as u32)
        .map(|vr| s.get(VR_OUTPUTS + vr).unwrap().to_bits())
        .collect()
}

/// The regression test of the log-based state: a slave restored from bytes serialised
/// mid-run (after a gain change and with an input derivative set) steps bit for bit as
/// the original, for every controller kind and the external placement.
#[test]
fn restored_slave_steps_bit_for_bit_as_the_original() {
    use crate::params::ControllerKind;
    let kinds = [
        ControllerKind::Paper,
        ControllerKind::Predictive,
        ControllerKind::Skyhook,
        ControllerKind::Smith,
    ];
    let cases = kinds
        .iter()
        .map(|&k| (k, ControllerPlacement::Internal))
        .chain([(ControllerKind::Paper, ControllerPlacement::External)]);
    for (kind, placement) in cases {
        let mut p = Params::paper();
        p.controller.kind = kind;
        let mut s = Slave::new(p, placement);
        s.setup(0.0).unwrap();
        s.enter_initialization().unwrap();
        s.exit_initialization().unwrap();
        for k in 0..300 {
            drive(&mut s, k);
        }
        if placement == ControllerPlacement::Internal {
            s.set(vr_of("controller.kp_v_per_m"), -8.0).unwrap();
        }
        s.set(VR_XDD, 0.3).unwrap();
        s.set_derivative(VR_XDD, 1, 40.0).unwrap();
        s.set_derivative(VR_XDD, 2, -900.0).unwrap();
        let bytes = s.serialize();
        let mut r = Slave::new(p, placement).deserialize(&bytes).unwrap();
        assert_eq!(r.serialize(), bytes, "{kind:?} {placement:?}");
        let (t, u_before) = (s.time(), s.get(VR_OUTPUTS).unwrap());
        s.do_step(0.3, 1e-3).unwrap();
        r.do_step(0.3, 1e-3).unwrap();
        assert_eq!(
            outputs(&s),
            outputs(&r),
            "{kind:?} {placement:?} first step"
        );
        for k in 301..800 {
            drive(&mut s, k);
            drive(&mut r, k);
            assert_eq!(outputs(&s), outputs(&r), "{kind:?} {placement:?} step {k}");
        }
        assert_eq!(r.time(), s.time());
        // The run went on (the comparison is not of a slave at rest).
        assert!(s.time() > t && s.get(VR_OUTPUTS).unwrap() != u_before);
    }
}

/// The serialised size does not grow with the run (the old log grew by 43 bytes a step).
#[test]
fn serialised_size_is_bounded() {
    for placement in [ControllerPlacement::Internal, ControllerPlacement::External] {
        let mut s = Slave::new(Params::paper(), placement);
        s.setup(0.0).unwrap();
        s.enter_initialization().unwrap();
        s.exit_initialization().unwrap();
        let mut sizes = Vec::new();
        for k in 0..10_000 {
            drive(&mut s, k);
            if k == 9 || k == 999 || k == 9_999 {
                sizes.push(s.serialize().len());
            }
        }
        // Room for the digits of the numbers to differ; the command window fills in 0.2 s.
        let (lo, hi) = (sizes[1].min(sizes[2]), sizes[1].max(sizes[2]));
        assert!(hi - lo < 300, "{placement:?}: {sizes:?}");
        assert!(sizes[0] < 10_000 && hi < 20_000, "{placement:?}: {sizes:?}");
        eprintln!("{placement:?}: serialised sizes after 10, 1000, 10 000 steps: {sizes:?}");
    }
}

#[test]
fn states_of_other_fmus_or_damaged_are_refused_without_panic() {
    let mut s = stepping();
    for k in 0..40 {
        drive(&mut s, k);
    }
    let bytes = s.serialize();
    let fresh = Slave::new(Params::paper(), ControllerPlacement::Internal);
    assert!(fresh.deserialize(&bytes).is_ok());
    // Another FMU: another GUID, another placement, another preset.
    let e = fresh
        .clone()
        .with_guid("{other}")
        .deserialize(&bytes)
        .unwrap_err();
    assert!(e.contains("another FMU"), "{e}");
    let e = Slave::new(Params::paper(), ControllerPlacement::External)
        .deserialize(&bytes)
        .unwrap_err();
    assert!(e.contains("another FMU"), "{e}");
    let mut other = Params::paper();
    other.plant.body.mass_kg += 1.0;
    assert!(
        Slave::new(other, ControllerPlacement::Internal)
            .deserialize(&bytes)
            .is_err()
    );
    // Another format version.
    let mut v = bytes.clone();
    v[8] = 1;
    assert!(fresh.deserialize(&v).unwrap_err().contains("version"));
    // Every truncation and every single flipped byte.
    for n in 0..bytes.len() {
        assert!(fresh.deserialize(&bytes[..n]).is_err(), "cut at {n}");
        let mut d = bytes.clone();
        d[n] ^= 0x20;
        assert!(fresh.deserialize(&d).is_err(), "byte {n} flipped");
    }
    // A consistent state whose content does not fit (a delay line of another size).
    let mut saved = SavedSlave {
        phase: s.phase,
        start_time: 0.0,
        params: PARAMS.iter().map(|p| p.get(&s.params)).collect(),
        xdd: s.xdd,
        x: s.x,
        v_in_ext: 0.0,
        command: CommandStream::default(),
        segment: s.segment,
        sim: s.sim.as_ref().map(Simulation::snapshot),
    };
    if let Some(sim) = saved.sim.as_mut() {
        sim.history.ring.pop();
    }
    let e = fresh.restore(saved).unwrap_err();
    assert!(e.contains("delay line"), "{e}");
}

#[test]
fn state_before_initialization_and_after_reset_round_trips() {
    let mut s = Slave::new(Params::paper(), ControllerPlacement::Internal);
    s.setup(0.25).unwrap();
    s.set(VR_XDD, 1.5).unwrap();
    let r = s.deserialize(&s.serialize()).unwrap();
    assert_eq!(r.phase(), Phase::Instantiated);
    assert_eq!(r.get(VR_XDD).unwrap(), 1.5);
    let mut r = r;
    r.enter_initialization().unwrap();
    r.exit_initialization().unwrap();
    assert_eq!(r.time(), 0.25);
    r.reset();
    let back = r.deserialize(&r.serialize()).unwrap();
    assert_eq!(back.phase(), Phase::Instantiated);
    assert_eq!(back.get(VR_XDD).unwrap(), 0.0);
}
