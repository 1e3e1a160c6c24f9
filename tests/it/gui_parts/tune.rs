//! `seat_twin::gui::tune`: unit tests kept out of the library (see `gui_parts`).

use super::job::wait_pumping;
use seat_twin::gui::job::{Job, Waker};
use seat_twin::gui::job::{Runner, pump};
use seat_twin::gui::tune::*;
use seat_twin::params::Params;
use seat_twin::tune::{self, TuneOptions, TuneResult};
use std::time::{Duration, Instant};

fn short() -> TuneOptions {
    TuneOptions {
        tune_seeds: vec![1],
        heldout_seeds: vec![101],
        duration_s: 6.0,
        max_evaluations: 12,
        ..TuneOptions::default()
    }
}

fn run_on(runner: Runner) -> (Result<TuneResult, String>, (usize, usize)) {
    let noop: Waker = std::sync::Arc::new(|| {});
    let job = Job::spawn_steps_on(runner, "t", noop, tune_steps(Params::paper(), short()));
    let t0 = Instant::now();
    let mut seen = Vec::new();
    loop {
        if let Some(r) = job.poll() {
            if runner == Runner::Frames {
                // Progress seen advancing between frames, not only at the end.
                assert!(seen.windows(2).any(|w| w[0] < w[1]), "{seen:?}");
            }
            return (r, job.progress());
        }
        assert!(
            t0.elapsed() < Duration::from_secs(300),
            "the tune never ended"
        );
        if pump(Duration::from_millis(8)) {
            seen.push(job.progress().0);
        } else {
            std::thread::sleep(Duration::from_millis(5));
        }
    }
}

/// Tune in the web's frames gives the desktop thread's result bit for bit, with the same
/// progress, and the result is `tune`'s own.
#[test]
fn tune_in_frames_equals_the_threaded_tune() {
    let (threaded, progress_t) = run_on(Runner::Thread);
    let (sliced, progress_f) = run_on(Runner::Frames);
    let json = |r: &TuneResult| serde_json::to_string(r).unwrap();
    let (threaded, sliced) = (threaded.unwrap(), sliced.unwrap());
    assert_eq!(json(&threaded), json(&sliced));
    assert_eq!(progress_t, progress_f);
    let direct = tune::tune(&Params::paper(), &short(), None).unwrap();
    assert_eq!(json(&direct), json(&sliced));
}

#[test]
fn a_tune_in_frames_is_cancelled() {
    let noop: Waker = std::sync::Arc::new(|| {});
    let job = Job::spawn_steps_on(
        Runner::Frames,
        "t",
        noop,
        tune_steps(Params::paper(), short()),
    );
    pump(Duration::ZERO);
    job.cancel();
    let r = wait_pumping(&job, Duration::from_secs(60), "cancel not honoured");
    assert_eq!(r.unwrap_err(), tune::TuneError::Cancelled.to_string());
}
