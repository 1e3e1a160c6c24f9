//! `seat_twin::gui::job`: unit tests kept out of the library (see `gui_parts`).

use seat_twin::gui::job::*;
use std::sync::Arc;
use std::time::{Duration, Instant};

fn wait<T, P>(job: &Job<T, P>) -> Result<T, String> {
    wait_pumping(job, Duration::from_secs(10), "job never ended")
}

/// Work in steps: the sum of squares of 0..n, one term per step, reporting progress and
/// streaming each term; stops when cancelled.
fn squares(n: usize) -> impl FnMut(&JobCtx<usize>) -> Step<usize> + Send + 'static {
    let (mut i, mut sum) = (0, 0);
    move |ctx| {
        if ctx.cancelled() {
            return Step::Done(Err("cancelled".into()));
        }
        if i == n {
            return Step::Done(Ok(sum));
        }
        sum += i * i;
        ctx.send(i * i);
        i += 1;
        ctx.report(i, n);
        Step::More
    }
}

#[test]
fn result_progress_cancel_and_panic() {
    for runner in [Runner::Thread, Runner::Frames] {
        let noop: Waker = Arc::new(|| {});
        let mut once = Some(7);
        let ok: Job<i32> = Job::spawn_steps_on(runner, "t", noop.clone(), move |ctx| {
            ctx.report(3, 4);
            Step::Done(once.take().ok_or_else(|| "twice".to_string()))
        });
        assert_eq!(wait(&ok), Ok(7), "{runner:?}");
        assert_eq!(ok.progress(), (3, 4));
        assert!(ok.poll().is_none(), "the result comes once");

        let stop: Job<()> = Job::spawn_steps_on(runner, "t", noop.clone(), |ctx| {
            if ctx.cancelled() {
                Step::Done(Err("cancelled".into()))
            } else {
                std::thread::sleep(Duration::from_millis(1));
                Step::More
            }
        });
        pump(Duration::from_millis(5));
        assert!(stop.poll().is_none(), "{runner:?}: it runs until cancelled");
        stop.cancel();
        assert_eq!(wait(&stop), Err("cancelled".into()), "{runner:?}");

        let boom: Job<()> =
            Job::spawn_steps_on(runner, "t", noop, |_| -> Step<()> { panic!("kaboom") });
        let e = wait(&boom).unwrap_err();
        assert!(e.contains("kaboom"), "{runner:?}: {e}");
    }
}

/// The same work in slices inside "frames" (as in a browser) and on a thread: the same
/// parts, progress and result; in the frames, each pump runs a bounded part of it.
#[test]
fn frames_runner_gives_what_the_thread_gives() {
    let noop: Waker = Arc::new(|| {});
    let n = 200;
    let threaded: Job<usize, usize> =
        Job::spawn_steps_on(Runner::Thread, "t", noop.clone(), squares(n));
    let sliced: Job<usize, usize> = Job::spawn_steps_on(Runner::Frames, "t", noop, squares(n));
    // A zero budget: one step per pump, so progress is seen advancing a step at a time.
    assert!(pump(Duration::ZERO));
    assert_eq!(sliced.progress(), (1, n));
    assert!(pump(Duration::ZERO));
    assert_eq!(sliced.progress(), (2, n));
    let r_sliced = wait(&sliced);
    let r_threaded = wait(&threaded);
    assert_eq!(r_sliced, Ok((0..n).map(|i| i * i).sum()));
    assert_eq!(r_sliced, r_threaded);
    assert_eq!(sliced.progress(), threaded.progress());
    assert_eq!(
        sliced.drain().collect::<Vec<_>>(),
        threaded.drain().collect::<Vec<_>>()
    );
    assert!(!pump(Duration::ZERO), "nothing left to run");
}

#[test]
fn a_long_step_is_not_cut_but_a_budget_stops_the_next() {
    let noop: Waker = Arc::new(|| {});
    let job: Job<(), ()> = Job::spawn_steps_on(Runner::Frames, "t", noop, {
        let mut i = 0;
        move |ctx| {
            std::thread::sleep(Duration::from_millis(20));
            i += 1;
            ctx.report(i, 3);
            if i == 3 {
                Step::Done(Ok(()))
            } else {
                Step::More
            }
        }
    });
    // 10 ms of budget: the first 20 ms step runs whole, the second waits for the next
    // frame.
    assert!(pump(Duration::from_millis(10)));
    assert_eq!(job.progress(), (1, 3));
    assert_eq!(wait(&job), Ok(()));
}

#[test]
fn partial_results_arrive_in_order_and_a_dropped_job_is_cancelled() {
    for runner in [Runner::Thread, Runner::Frames] {
        let noop: Waker = Arc::new(|| {});
        let job: Job<usize, usize> = Job::spawn_steps_on(runner, "t", noop.clone(), squares(5));
        assert_eq!(wait(&job), Ok(30));
        assert_eq!(job.drain().collect::<Vec<_>>(), vec![0, 1, 4, 9, 16]);
        assert_eq!(job.drain().count(), 0, "each part comes once");

        // A job nobody holds stops: its work sees the cancel flag.
        let (tx, rx) = std::sync::mpsc::channel();
        let t0 = Instant::now();
        let dropped: Job<(), ()> = Job::spawn_steps_on(runner, "t", noop, move |ctx| {
            if ctx.cancelled() {
                let _ = tx.send(true);
                Step::Done(Ok(()))
            } else if t0.elapsed() > Duration::from_secs(10) {
                let _ = tx.send(false);
                Step::Done(Ok(()))
            } else {
                std::thread::sleep(Duration::from_millis(1));
                Step::More
            }
        });
        drop(dropped);
        pump(Duration::from_millis(5));
        assert_eq!(
            rx.recv_timeout(Duration::from_secs(20)),
            Ok(true),
            "{runner:?}"
        );
    }
}

#[test]
fn a_one_call_job_runs_whole_in_one_slice() {
    let noop: Waker = Arc::new(|| {});
    let job: Job<i32> = Job::spawn("t", noop, |_| Ok(5));
    assert_eq!(wait(&job), Ok(5));
}

/// Test helper: `job`'s end, running this thread's Frames jobs meanwhile (nothing to run for
/// a Thread job); fails the test with `what` if it has not ended within `limit`.
pub(crate) fn wait_pumping<T, P>(
    job: &Job<T, P>,
    limit: std::time::Duration,
    what: &str,
) -> Result<T, String> {
    let t0 = std::time::Instant::now();
    loop {
        if let Some(r) = job.poll() {
            return r;
        }
        assert!(t0.elapsed() < limit, "{what}");
        if !pump(std::time::Duration::from_millis(2)) {
            std::thread::sleep(std::time::Duration::from_millis(5));
        }
    }
}
