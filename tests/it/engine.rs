//! The engine thread driven by commands, as the app drives it: parameters reach the running
//! simulation, pause stops the stream, bad parameters are refused with a message and the
//! thread keeps serving, and all three models stream on the same excitation.

use seat_twin::engine::{self, Command, EngineHandle, Event, Excitation, Speed};
use seat_twin::params::Params;
use std::time::{Duration, Instant};

/// Collects events until `done` says so, or fails after 20 s.
fn until(h: &EngineHandle, mut done: impl FnMut(&Event) -> bool) -> Vec<Event> {
    let t0 = Instant::now();
    let mut seen = Vec::new();
    while t0.elapsed() < Duration::from_secs(20) {
        if let Ok(e) = h.events.recv_timeout(Duration::from_millis(50)) {
            let stop = done(&e);
            seen.push(e);
            if stop {
                return seen;
            }
        }
    }
    panic!(
        "the engine did not answer in 20 s; saw {} events",
        seen.len()
    );
}

#[test]
fn new_gains_reach_the_running_simulation() {
    let h = engine::spawn(Params::paper(), || {});
    h.send(Command::SetSpeed(Speed::Max));
    until(&h, |e| matches!(e, Event::Samples(b) if !b.twin.is_empty()));
    let mut p = Params::paper();
    p.controller.kp_v_per_m = -20.0;
    p.valve.cd = 0.12;
    h.send(Command::SetParams(Box::new(p)));
    until(&h, |e| {
        matches!(e, Event::Status { params, .. }
            if params.controller.kp_v_per_m == -20.0 && params.valve.cd == 0.12)
    });
}

#[test]
fn all_three_models_stream_the_same_instants_and_platform() {
    let h = engine::spawn(Params::paper(), || {});
    h.send(Command::SetSpeed(Speed::Max));
    let events = until(&h, |e| matches!(e, Event::Samples(b) if b.twin.len() > 10));
    let Some(Event::Samples(b)) = events.last() else {
        unreachable!()
    };
    assert_eq!(b.twin.len(), b.linear.len());
    assert_eq!(b.twin.len(), b.passive.len());
    for ((t, l), p) in b.twin.iter().zip(&b.linear).zip(&b.passive) {
        assert_eq!(t.t, l.t);
        assert_eq!(t.t, p.t);
        assert_eq!(t.xdd, l.xdd);
        assert_eq!(t.xdd, p.xdd);
        assert!(t.ydd.is_finite() && l.ydd.is_finite() && p.ydd.is_finite());
    }
}

#[test]
fn pause_stops_the_stream_and_run_resumes_it() {
    let h = engine::spawn(Params::paper(), || {});
    h.send(Command::SetSpeed(Speed::Max));
    until(&h, |e| matches!(e, Event::Samples(_)));
    h.send(Command::Pause);
    until(&h, |e| matches!(e, Event::Status { running: false, .. }));
    // Drain what was in flight, then nothing new may arrive while paused.
    std::thread::sleep(Duration::from_millis(200));
    while h.events.try_recv().is_ok() {}
    std::thread::sleep(Duration::from_millis(300));
    let during_pause: Vec<Event> = h.events.try_iter().collect();
    assert!(
        !during_pause.iter().any(|e| matches!(e, Event::Samples(_))),
        "no samples while paused"
    );
    h.send(Command::Run);
    until(&h, |e| matches!(e, Event::Samples(_)));
}

#[test]
fn invalid_parameters_are_refused_by_name_and_the_engine_keeps_running() {
    let h = engine::spawn(Params::paper(), || {});
    h.send(Command::SetSpeed(Speed::Max));
    let mut p = Params::paper();
    p.body.mass_kg = -1.0;
    h.send(Command::SetParams(Box::new(p)));
    let events = until(&h, |e| matches!(e, Event::Error(_)));
    let Some(Event::Error(msg)) = events.last() else {
        unreachable!()
    };
    assert!(msg.contains("mass_kg"), "{msg}");
    // Still serving, with the old, valid parameters.
    until(
        &h,
        |e| matches!(e, Event::Status { params, running: true, .. } if params.body.mass_kg == 11.7),
    );
    until(&h, |e| matches!(e, Event::Samples(_)));
}

#[test]
fn a_new_excitation_restarts_from_rest() {
    let h = engine::spawn(Params::paper(), || {});
    h.send(Command::SetSpeed(Speed::Max));
    until(&h, |e| matches!(e, Event::Status { t, .. } if *t > 1.0));
    h.send(Command::SetExcitation(Box::new(Excitation::ValveSine {
        amplitude_v: 1.1,
        freq_hz: 5.0,
    })));
    // The first samples after the restart start near t = 0 with the platform still.
    let events = until(
        &h,
        |e| matches!(e, Event::Samples(b) if b.twin.first().is_some_and(|s| s.t < 0.1)),
    );
    let Some(Event::Samples(b)) = events.last() else {
        unreachable!()
    };
    assert!(b.twin.iter().all(|s| s.xdd == 0.0));
}

/// An unstable loop (positive Kp feeds the position back with the wrong sign) makes the
/// linear model grow without bound. The engine reports the divergence by model and state,
/// streams no non-finite sample, stops stepping, and Reset with stable gains brings it back.
#[test]
fn a_divergence_is_reported_and_reset_with_stable_gains_recovers() {
    let mut unstable = Params::paper();
    unstable.controller.kp_v_per_m = 20.0;
    let h = engine::spawn(unstable, || {});
    h.send(Command::SetSpeed(Speed::Max));
    let events = until(&h, |e| matches!(e, Event::Error(_)));
    let Some(Event::Error(msg)) = events.last() else {
        unreachable!()
    };
    assert!(msg.contains("linear model diverged"), "{msg}");
    assert!(msg.contains("Reset"), "{msg}");
    // Motion channels of all three models, and the twin's pressures (the linear and passive
    // models have none: NaN there means "not modelled"), stay finite up to the error.
    let batches: Vec<_> = events
        .iter()
        .filter_map(|e| match e {
            Event::Samples(b) => Some(b),
            _ => None,
        })
        .collect();
    let motion = batches
        .iter()
        .flat_map(|b| b.linear.iter().chain(&b.twin).chain(&b.passive));
    let mut n = 0;
    for s in motion {
        n += 1;
        assert!(
            [s.ydd, s.u, s.du, s.xdd].iter().all(|v| v.is_finite()),
            "a non-finite sample reached the UI: {s:?}"
        );
    }
    assert!(n > 0, "samples before the divergence");
    assert!(
        batches
            .iter()
            .flat_map(|b| &b.twin)
            .all(|s| s.p1.is_finite() && s.p2.is_finite())
    );
    // Stopped: nothing more arrives until Reset.
    std::thread::sleep(Duration::from_millis(300));
    assert!(
        !h.events
            .try_iter()
            .any(|e| matches!(e, Event::Samples(b) if !b.twin.is_empty())),
        "the engine keeps stepping after the error"
    );
    h.send(Command::SetParams(Box::new(Params::paper())));
    h.send(Command::Reset);
    let back = until(
        &h,
        |e| matches!(e, Event::Samples(b) if !b.linear.is_empty()),
    );
    let Some(Event::Samples(b)) = back.last() else {
        unreachable!()
    };
    assert!(
        b.linear[0].t < 1.0,
        "restarted from t = 0: {}",
        b.linear[0].t
    );
    until(
        &h,
        |e| matches!(e, Event::Status { t, running: true, .. } if *t > 2.0),
    );
}
