//! `seat_twin::gui::traces`: unit tests kept out of the library (see `gui_parts`).

use seat_twin::engine::{Batch, STREAM_RATE_HZ};
use seat_twin::gui::traces::*;
use seat_twin::simulation::Sample;

fn sample(t: f64, u: f64, contact: bool) -> Sample {
    Sample {
        t,
        x: 0.0,
        xd: 0.0,
        xdd: 0.1,
        u,
        du: 0.0,
        ydd: 0.05,
        v_in: 1.0,
        xv: 1e-4,
        p1: 55e5,
        p2: 55e5,
        q1: 0.0,
        q2: 0.0,
        contact,
    }
}

fn batch(t0: f64, n: usize, contact: impl Fn(usize) -> bool) -> Batch {
    let s: Vec<Sample> = (0..n)
        .map(|i| sample(t0 + i as f64 / STREAM_RATE_HZ, 0.01, contact(i)))
        .collect();
    Batch {
        twin: s.clone(),
        linear: s.clone(),
        passive: s,
        reference: Vec::new(),
    }
}

#[test]
fn window_keeps_a_minute_of_channels_and_ten_seconds_of_rows_in_display_units() {
    let mut tr = Traces::new();
    for k in 0..90 {
        tr.push_batch(&batch(k as f64, 500, |_| false));
    }
    let pts = tr.channel(Ch::TwinU).points();
    let span = pts.last().unwrap().x - pts[0].x;
    assert!((span - MAX_WINDOW_S).abs() < 0.01, "span {span}");
    let rows = tr.rows();
    let row_span = rows.last().unwrap().t - rows[0].t;
    assert!((row_span - WINDOW_S).abs() < 0.01, "rows span {row_span}");
    // The points of the last `WINDOW_S`, for a scope of that length.
    let shown = tr.channel(Ch::TwinU).window(tr.t_now(), WINDOW_S);
    assert!((shown[0].x - (tr.t_now() - WINDOW_S)).abs() < 0.01);
    assert!((pts[0].y - 10.0).abs() < 1e-12, "u in mm");
    assert!((tr.channel(Ch::P1).last().unwrap() - 55.0).abs() < 1e-9);
}

#[test]
fn restart_continues_the_time_axis_and_reset_clears() {
    let mut tr = Traces::new();
    tr.push_batch(&batch(0.0, 1000, |_| false));
    let t_end = tr.t_now();
    tr.mark_restart();
    tr.push_batch(&batch(0.0, 10, |_| false));
    assert!(tr.t_now() > t_end);
    // The restarted run's first sample falls on the last one's instant: the rows (an
    // exported traces.csv) keep one row there and stay strictly increasing in time, and the
    // restarted run's other nine follow it.
    let rows = tr.rows();
    assert!(
        rows.windows(2).all(|w| w[1].t > w[0].t),
        "time not increasing"
    );
    assert_eq!(rows.iter().filter(|r| r.t > t_end + 1e-12).count(), 9);
    assert_eq!(
        rows.iter().filter(|r| (r.t - t_end).abs() < 1e-12).count(),
        1
    );
    // Time going backwards without a restart: stale data before a reset.
    tr.push_batch(&batch(0.0, 10, |_| false));
    assert!(tr.t_now() < 0.1);
    assert_eq!(tr.rows().len(), 10);
}

/// Issue 22, item 7: a parameter change restarts the metrics *and* the end-stop
/// contact count (they describe the same window), and leaves one marker in the scopes,
/// even when a drag changes the value every frame.
#[test]
fn a_parameter_change_restarts_metrics_and_contacts_with_one_marker() {
    let mut tr = Traces::new();
    tr.push_batch(&batch(0.0, 2000, |_| false));
    tr.contact_count = 3;
    assert!(tr.metrics.counted_s() > 1.0);
    tr.reset_metrics();
    assert_eq!(tr.contact_count, 0);
    assert_eq!(tr.metrics.counted_s(), 0.0);
    let t1 = tr.t_now();
    assert_eq!(tr.changes(), &[t1]);
    // A drag: more changes within half a second move the marker, not add one.
    let dt = 1.0 / STREAM_RATE_HZ;
    tr.push_batch(&batch(t1 + dt, 20, |_| false));
    tr.reset_metrics();
    assert_eq!(tr.changes(), &[tr.t_now()]);
    // A later change is a second marker.
    tr.push_batch(&batch(tr.t_now() + dt, 500, |_| false));
    tr.reset_metrics();
    assert_eq!(tr.changes().len(), 2);
    tr.clear();
    assert!(tr.changes().is_empty());
}

#[test]
fn contact_intervals_follow_the_flag() {
    let mut tr = Traces::new();
    tr.push_batch(&batch(0.0, 500, |i| (100..200).contains(&i) || i >= 400));
    let c = tr.contacts();
    assert_eq!(c.len(), 2);
    assert!((c[0].0 - 0.2).abs() < 1e-9 && (c[0].1 - 0.398).abs() < 1e-9);
}
