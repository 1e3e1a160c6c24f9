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
    p.plant.valve.cd = 0.12;
    h.send(Command::SetParams(Box::new(p)));
    until(&h, |e| {
        matches!(e, Event::Status { params, .. }
            if params.controller.kp_v_per_m == -20.0 && params.plant.valve.cd == 0.12)
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
    p.plant.body.mass_kg = -1.0;
    h.send(Command::SetParams(Box::new(p)));
    let events = until(&h, |e| matches!(e, Event::Error(_)));
    let Some(Event::Error(msg)) = events.last() else {
        unreachable!()
    };
    assert!(msg.contains("mass_kg"), "{msg}");
    // Still serving, with the old, valid parameters.
    until(
        &h,
        |e| matches!(e, Event::Status { params, running: true, .. } if params.plant.body.mass_kg == 11.7),
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

/// A short record replayed over and over at full speed: the reported clock keeps counting
/// across the automatic restarts (it is the scopes' time axis), the real-time factor is
/// never negative, and it reads 0 once paused. (Before: the clock fell back to 0 at every
/// restart and the factor, measured on it, went negative.)
#[test]
fn the_clock_counts_across_restarts_and_the_realtime_factor_is_never_negative() {
    let dt = 1e-3;
    let n = 301; // 0.3 s of a gentle platform sine
    let w = 2.0 * std::f64::consts::PI * 5.0;
    let t: Vec<f64> = (0..n).map(|i| i as f64 * dt).collect();
    let x: Vec<f64> = t.iter().map(|t| 1e-3 * (w * t).sin()).collect();
    let xd: Vec<f64> = t.iter().map(|t| 1e-3 * w * (w * t).cos()).collect();
    let xdd: Vec<f64> = t.iter().map(|t| -1e-3 * w * w * (w * t).sin()).collect();
    let record = seat_twin::scenario::SampledMotion::new(dt, x, xd, xdd);
    let h = engine::spawn(Params::paper(), || {});
    h.send(Command::SetExcitation(Box::new(Excitation::Record(record))));
    h.send(Command::SetSpeed(Speed::Max));
    let mut restarts = 0;
    let mut last_t = 0.0;
    let mut rtf_seen = 0.0f64;
    let events = until(&h, |e| {
        if matches!(e, Event::Restarted) {
            restarts += 1;
        }
        if let Event::Status {
            realtime_factor, ..
        } = e
        {
            rtf_seen = rtf_seen.max(*realtime_factor);
        }
        restarts >= 8 && rtf_seen > 0.0
    });
    for e in &events {
        if let Event::Status {
            t, realtime_factor, ..
        } = e
        {
            assert!(
                *realtime_factor >= 0.0,
                "real-time factor {realtime_factor}"
            );
            assert!(*t >= last_t - 1e-9, "the clock went back: {last_t} → {t}");
            last_t = *t;
        }
    }
    assert!(
        last_t > 8.0 * 0.3 - 0.01,
        "8 restarts of a 0.3 s record, clock at {last_t} s"
    );
    h.send(Command::Pause);
    let events = until(&h, |e| matches!(e, Event::Status { running: false, .. }));
    let Some(Event::Status {
        realtime_factor, ..
    }) = events.last()
    else {
        unreachable!()
    };
    assert_eq!(*realtime_factor, 0.0, "paused: no real-time factor");
}

/// A panic inside an engine step (injected by the test-only command) is caught: the engine
/// reports it as an internal error, stops stepping, and Reset starts it again from t = 0.
#[test]
fn an_injected_panic_in_a_step_is_reported_and_reset_recovers() {
    let h = engine::spawn(Params::paper(), || {});
    h.send(Command::SetSpeed(Speed::Max));
    until(&h, |e| matches!(e, Event::Samples(b) if !b.twin.is_empty()));
    h.send(Command::InjectFault);
    let events = until(&h, |e| matches!(e, Event::Error(_)));
    let Some(Event::Error(msg)) = events.last() else {
        unreachable!()
    };
    assert!(msg.contains("internal error"), "{msg}");
    assert!(msg.contains("Reset"), "{msg}");
    until(&h, |e| matches!(e, Event::Status { running: false, .. }));
    h.send(Command::Reset);
    until(
        &h,
        |e| matches!(e, Event::Status { t, running: true, .. } if *t > 1.0),
    );
}
