//! `seat_twin::gui::frequency::dwell`: unit tests kept out of the library (see `gui_parts`).

use super::job::wait_pumping;
use seat_twin::analysis::dwell::{self as sine_dwell, DwellOptions};
use seat_twin::gui::frequency::{DwellPoint, dwell_steps};
use seat_twin::gui::job::{Job, Runner, Waker};
use seat_twin::model::ModelKind;
use seat_twin::params::Params;
use std::sync::Arc;
use std::time::Duration;

fn run_on(runner: Runner, freqs: Vec<f64>) -> (Result<(), String>, Vec<DwellPoint>) {
    let noop: Waker = Arc::new(|| {});
    let job = Job::spawn_steps_on(runner, "t", noop, dwell_steps(Params::paper(), freqs));
    let end = wait_pumping(&job, Duration::from_secs(60), "the dwell never ended");
    (end, job.drain().collect())
}

/// The dwell in slices (the web's frames) gives the thread's points bit for bit, and each
/// point is the library's sine dwell at that frequency.
#[test]
fn dwell_in_frames_equals_the_threaded_dwell() {
    let freqs = vec![0.8, 2.5, 9.0];
    let (end_t, threaded) = run_on(Runner::Thread, freqs.clone());
    let (end_f, sliced) = run_on(Runner::Frames, freqs.clone());
    assert_eq!(end_t, Ok(()));
    assert_eq!(end_f, Ok(()));
    assert_eq!(threaded.len(), 3);
    assert_eq!(threaded, sliced);
    let reference = sine_dwell::simulated_transmissibility(
        &Params::paper(),
        ModelKind::Twin,
        2.5,
        &DwellOptions::default(),
    )
    .unwrap();
    assert!(
        matches!(sliced[1], DwellPoint::Point { value, .. } if value == reference),
        "{:?}",
        sliced[1]
    );
}
