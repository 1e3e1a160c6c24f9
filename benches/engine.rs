//! Criterion benches of the engine kernels: 10 s of closed-loop random ride on each model, the
//! 69 Table 1 sine dwells on the twin, the twin's linearisation + frequency response, and one
//! calibration (two demo sine records, full effect search).
//!
//! Run with `cargo bench --no-default-features --bench engine`. The real-time factor is
//! 10 s divided by the reported time per iteration.

use criterion::{Criterion, criterion_group, criterion_main};
use seat_twin::analysis::dwell;
use seat_twin::analysis::frequency_response as fr;
use seat_twin::bench::{bench_ride, ride_run};
use seat_twin::experiments;
use seat_twin::model::ModelKind;
use seat_twin::params::{Integrator, Params};
use std::hint::black_box;

fn ride_10s(c: &mut Criterion) {
    let params = Params::paper();
    let ride = bench_ride(10.0);
    let mut group = c.benchmark_group("ride_10s");
    group.sample_size(20);
    for kind in [ModelKind::Twin, ModelKind::Linear, ModelKind::Passive] {
        let step = seat_twin::bench::bench_step_s(&params, kind);
        group.bench_function(kind.name(), |b| {
            b.iter(|| {
                let trace = ride_run(black_box(&params), kind, &ride, 10.0, step)
                    .expect("the paper's ride does not diverge");
                black_box(trace.samples.len())
            })
        });
    }
    // The twin with classical RK4 at the step that gives it the same accuracy.
    let mut rk4 = params;
    rk4.numerics.integrator = Integrator::Rk4;
    rk4.numerics.max_step_s = seat_twin::bench::RK4_STEP_S;
    group.bench_function("twin_rk4", |b| {
        b.iter(|| {
            let trace = ride_run(black_box(&rk4), ModelKind::Twin, &ride, 10.0, 1e-4)
                .expect("the paper's ride does not diverge");
            black_box(trace.samples.len())
        })
    });
    group.finish();
}

fn table1_sweep(c: &mut Criterion) {
    let params = Params::paper();
    let tests = experiments::table1();
    let opt = dwell::DwellOptions::default();
    let mut group = c.benchmark_group("table1");
    group.sample_size(10);
    group.bench_function("twin_69_dwells", |b| {
        b.iter(|| {
            let r = dwell::sweep(&tests, |&(f, a)| {
                dwell::simulated_bode(&params, ModelKind::Twin, f, a, &opt)
            });
            black_box(r.len())
        })
    });
    group.finish();
}

fn linearisation(c: &mut Criterion) {
    let params = Params::paper();
    let freqs = fr::log_space(0.3, 30.0, 200);
    c.bench_function("linearise_twin_and_200_point_transmissibility", |b| {
        b.iter(|| {
            let lin = fr::linearise_twin(black_box(&params));
            let t: Vec<_> = freqs
                .iter()
                .map(|&f| lin.transmissibility(&seat_twin::control::ControlLaw::new(&params), f))
                .collect();
            black_box(t)
        })
    });
    // What the app does on a plant-slider frame (Cd, mass, k, supply): re-linearise, the
    // margin grid refined around the resonances, the 240 plot frequencies, and the verdict.
    let plot = fr::log_space(0.1, 100.0, 240);
    c.bench_function("linearise_twin_margin_grid_plot_and_verdict", |b| {
        b.iter(|| {
            let lin = fr::linearise_twin(black_box(&params));
            let grid = seat_twin::analysis::stability::MarginGrid::new(&lin);
            let n = plot.iter().map(|&f| lin.open_loop(f).u_v.re).sum::<f64>();
            let law = seat_twin::control::ControlLaw::new(&params);
            let s = seat_twin::analysis::stability::Stability::on_grid(
                &lin,
                &grid,
                &law,
                params.plant.valve.tau_s,
            );
            black_box((n, s))
        })
    });
    // What a gain-slider frame costs: the verdict on the cached plant.
    let lin = fr::linearise_twin(&params);
    let grid = seat_twin::analysis::stability::MarginGrid::new(&lin);
    c.bench_function("stability_verdict_on_cached_plant", |b| {
        b.iter(|| {
            let law = seat_twin::control::ControlLaw::new(black_box(&params));
            black_box(seat_twin::analysis::stability::Stability::on_grid(
                &lin,
                &grid,
                &law,
                params.plant.valve.tau_s,
            ))
        })
    });
}

fn calibration(c: &mut Criterion) {
    use seat_twin::dataset::{RecordKind, read_record};
    use seat_twin::identify::{CalibrationOptions, calibrate};
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/demo-campaign");
    let records: Vec<_> = ["sine_05hz_4.50v.csv", "sine_10hz_1.10v.csv"]
        .iter()
        .map(|f| read_record(&dir.join(f), RecordKind::Measured).expect("demo record"))
        .collect();
    let params = Params::paper();
    let options = CalibrationOptions::default();
    let mut group = c.benchmark_group("calibration");
    group.sample_size(10);
    group.bench_function("two_demo_sine_records", |b| {
        b.iter(|| {
            let report = calibrate(&params, &records, &options, &|_| true).expect("calibrates");
            black_box(report)
        })
    });
    group.finish();
}

criterion_group!(benches, ride_10s, table1_sweep, linearisation, calibration);
criterion_main!(benches);
