//! Criterion bench of the `tune` command's work: a default tuning run (3 tuning + 3 held-out
//! random rides of 60 s on the nonlinear twin, Nelder–Mead within 120 evaluations, the
//! 27-point robustness table and the Pareto front) for the paper's controller and for the
//! predictive one. The requirement is ≤ 120 s per default run on the 2-core machine.
//!
//! Run with `cargo bench --no-default-features --bench tune` (about 5 min: criterion's
//! minimum of 10 runs per case).

use criterion::{Criterion, criterion_group, criterion_main};
use seat_twin::params::{ControllerKind, Params};
use seat_twin::tune::{TuneOptions, tune};
use std::hint::black_box;
use std::time::Duration;

fn default_tune(c: &mut Criterion) {
    let params = Params::paper();
    let mut group = c.benchmark_group("tune_default");
    group.sample_size(10);
    group.measurement_time(Duration::from_secs(60));
    for kind in [ControllerKind::Paper, ControllerKind::Predictive] {
        let options = TuneOptions {
            kind,
            ..TuneOptions::default()
        };
        group.bench_function(kind.name(), |b| {
            b.iter(|| black_box(tune(&params, &options, None).expect("tunes")))
        });
    }
    group.finish();
}

criterion_group!(benches, default_tune);
criterion_main!(benches);
