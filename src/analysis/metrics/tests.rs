//! Tests of the vibration metrics and the Wk weighting against the standard's numbers and
//! analytic results.

use super::wk::wk_sections;
use super::*;
use std::f64::consts::PI;

fn sine(amplitude: f64, freq_hz: f64, fs: f64, n: usize) -> Vec<f64> {
    (0..n)
        .map(|i| amplitude * (2.0 * PI * freq_hz * i as f64 / fs).sin())
        .collect()
}

fn rel(a: f64, b: f64) -> f64 {
    ((a - b) / b).abs()
}

#[test]
fn rms_peak_crest_of_simple_signals() {
    let x = [3.0, -4.0];
    assert!((rms(&x) - (12.5_f64).sqrt()).abs() < 1e-15);
    assert_eq!(peak(&x), 4.0);
    assert!((crest_factor(&x) - 4.0 / 12.5_f64.sqrt()).abs() < 1e-15);

    // A sine over whole periods: RMS = A/√2, crest = √2.
    let s = sine(2.0, 5.0, 1000.0, 1000);
    assert!(rel(rms(&s), 2.0 / 2f64.sqrt()) < 1e-12);
    assert!(rel(peak(&s), 2.0) < 1e-12);
    assert!(rel(crest_factor(&s), 2f64.sqrt()) < 1e-12);
}

#[test]
fn empty_and_zero_signals_give_zero() {
    assert_eq!(rms(&[]), 0.0);
    assert_eq!(peak(&[]), 0.0);
    assert_eq!(crest_factor(&[]), 0.0);
    assert_eq!(crest_factor(&[0.0, 0.0]), 0.0);
    assert_eq!(vdv(&[], 1000.0), 0.0);
    assert_eq!(wk_weight(&[], 1000.0), Ok(Vec::new()));
    assert_eq!(
        vibration_metrics(&[], 1000.0, 0.0),
        Err(MetricsError::EmptySignal)
    );
    let running = RunningMetrics::new(1000.0).expect("valid rate");
    assert_eq!(running.metrics(), VibrationMetrics::default());
}

#[test]
fn nan_propagates() {
    assert!(peak(&[1.0, f64::NAN, 2.0]).is_nan());
    assert!(rms(&[1.0, f64::NAN]).is_nan());
}

/// ISO 2631-1:1997 Table 3, weighting Wk, as factors (the table prints factor × 1000).
const ISO_TABLE_3_WK: [(f64, f64); 16] = [
    (0.1, 0.0312),
    (0.5, 0.418),
    (1.0, 0.482),
    (2.0, 0.531),
    (4.0, 0.967),
    (5.0, 1.039),
    (6.3, 1.054),
    (8.0, 1.036),
    (10.0, 0.988),
    (12.5, 0.902),
    (16.0, 0.768),
    (20.0, 0.636),
    (31.5, 0.405),
    (63.0, 0.186),
    (80.0, 0.132),
    (100.0, 0.0887),
];

#[test]
fn wk_response_matches_iso_2631_table_3() {
    // The table is evaluated at the nominal band frequencies and printed to three
    // significant figures; the analytic filter reproduces it to 0.3 %.
    for (f, expected) in ISO_TABLE_3_WK {
        let (mag, _) = wk_response(f);
        assert!(
            rel(mag, expected) < 0.005,
            "Wk at {f} Hz: {mag:.4}, table {expected}"
        );
    }
}

#[test]
fn wk_response_limits_and_phase() {
    // Flat region shapes: gain → 0 at DC and at high frequency.
    assert_eq!(wk_response(0.0).0, 0.0);
    assert!(wk_response(0.01).0 < 1e-3);
    assert!(wk_response(1000.0).0 < 0.01);
    // Low-frequency phase → +π (second-order high-pass), high → −3π/2.
    assert!((wk_response(1e-4).1 - PI).abs() < 1e-3);
    assert!((wk_response(1e6).1 + 1.5 * PI).abs() < 1e-2);
    // The continuous phase agrees, modulo 2π, with the argument of the product H(jω).
    for f in [0.3, 1.0, 3.0, 8.0, 12.5, 40.0, 150.0] {
        let (_, phase) = wk_response(f);
        let w = 2.0 * PI * f;
        let (re, im) = wk_sections(|o| o).iter().fold((1.0, 0.0), |(r, i), s| {
            let (m, p) = s.response(w);
            let (sr, si) = (m * p.cos(), m * p.sin());
            (r * sr - i * si, r * si + i * sr)
        });
        let diff = (phase - im.atan2(re)).rem_euclid(2.0 * PI);
        assert!(diff < 1e-9 || 2.0 * PI - diff < 1e-9, "f = {f}");
    }
    assert!(wk_response(f64::NAN).0.is_nan());
}

/// Steady-state gain of the digital filter, measured as the RMS ratio of a sine over
/// whole periods after the transient.
fn measured_gain(fs: f64, f: f64) -> f64 {
    let settle = (30.0 * fs) as usize; // HP at 0.4 Hz: transient ≪ 30 s
    let cycles = (20.0 * f).ceil().max(10.0);
    let window = (cycles * fs / f).round() as usize;
    let x = sine(1.0, f, fs, settle + window);
    let y = wk_weight(&x, fs).expect("valid rate");
    rms(&y[settle..]) / rms(&x[settle..])
}

#[test]
fn digital_filter_gain_matches_analogue_within_1_percent() {
    let fs = 1000.0;
    let filter = WkFilter::new(fs).expect("valid rate");
    // Third-octave centres from 0.5 Hz to 50 Hz.
    let freqs = [
        0.5, 0.63, 0.8, 1.0, 1.25, 1.6, 2.0, 2.5, 3.15, 4.0, 5.0, 6.3, 8.0, 10.0, 12.5, 16.0, 20.0,
        25.0, 31.5, 40.0, 50.0,
    ];
    for f in freqs {
        let (exact, _) = wk_response(f);
        let measured = measured_gain(fs, f);
        assert!(
            rel(measured, exact) < 0.01,
            "{f} Hz: digital {measured:.5}, analogue {exact:.5}"
        );
        // The transfer-function gain agrees with the measured one.
        assert!(rel(filter.gain_at(f), measured) < 1e-3, "{f} Hz");
    }
}

#[test]
fn digital_filter_is_accurate_at_the_characteristic_frequencies() {
    // Pre-warping puts each section's characteristic frequencies where the standard
    // has them, so the cascade follows the analogue filter there even at 250 Hz.
    for fs in [250.0, 500.0, 1000.0, 5000.0] {
        let filter = WkFilter::new(fs).expect("valid rate");
        for f in [0.4, 2.37, 3.35, 12.5] {
            assert!(
                rel(filter.gain_at(f), wk_response(f).0) < 0.01,
                "fs {fs}, f {f}: {} vs {}",
                filter.gain_at(f),
                wk_response(f).0
            );
        }
    }
}

#[test]
fn filter_streaming_reset_and_dc_rejection() {
    let fs = 500.0;
    let x = sine(1.0, 3.0, fs, 2000);
    let batch = wk_weight(&x, fs).expect("valid rate");
    let mut filter = WkFilter::new(fs).expect("valid rate");
    let streamed: Vec<f64> = x.iter().map(|&v| filter.filter(v)).collect();
    assert_eq!(batch, streamed);
    filter.reset();
    let again: Vec<f64> = x.iter().map(|&v| filter.filter(v)).collect();
    assert_eq!(batch, again);
    assert_eq!(filter.sample_rate_hz(), fs);

    // A constant input (gravity offset) is removed by the 0.4 Hz high-pass.
    filter.reset();
    let last = (0..(60.0 * fs) as usize).fold(0.0, |_, _| filter.filter(9.81));
    assert!(last.abs() < 1e-6, "DC residue {last}");
}

#[test]
fn sample_rate_errors() {
    let err = WkFilter::new(200.0).expect_err("too slow");
    assert_eq!(
        err,
        MetricsError::SampleRateTooLow {
            sample_rate_hz: 200.0,
            min_hz: MIN_SAMPLE_RATE_HZ
        }
    );
    let msg = err.to_string();
    assert!(
        msg.contains("200") && msg.contains("250") && msg.contains("100 Hz"),
        "{msg}"
    );
    for bad in [0.0, -1000.0, f64::NAN, f64::INFINITY] {
        assert!(matches!(
            WkFilter::new(bad),
            Err(MetricsError::InvalidSampleRate { .. })
        ));
        assert!(vdv(&[1.0], bad).is_nan());
    }
    assert!(WkFilter::new(MIN_SAMPLE_RATE_HZ).is_ok());
    assert!(wk_weight(&[1.0], 100.0).is_err());
    assert!(vibration_metrics(&[1.0], 100.0, 0.0).is_err());
    assert!(RunningMetrics::new(100.0).is_err());
}

#[test]
fn vdv_of_a_sine_matches_the_analytic_integral() {
    // ∫₀ᵀ (A sin ωt)⁴ dt = 3A⁴T/8 over whole periods.
    let (amplitude, f, fs, duration) = (1.7, 4.0, 1000.0, 10.0);
    let x = sine(amplitude, f, fs, (duration * fs) as usize);
    let expected = (3.0 * amplitude.powi(4) * duration / 8.0).powf(0.25);
    assert!(rel(vdv(&x, fs), expected) < 1e-12);
    // A constant: VDV = a·T^(1/4).
    let c = vec![2.0; 4000];
    assert!(rel(vdv(&c, 1000.0), 2.0 * 4f64.powf(0.25)) < 1e-12);
}

#[test]
fn vibration_metrics_of_a_sine() {
    let (amplitude, f, fs): (f64, f64, f64) = (1.0, 6.3, 1000.0);
    let settle: f64 = 20.0;
    let window_s = 100.0 / f; // 100 whole periods
    let n = ((settle + window_s) * fs).round() as usize;
    let x = sine(amplitude, f, fs, n);
    let m = vibration_metrics(&x, fs, settle).expect("valid input");
    let w = wk_response(f).0;
    assert!(rel(m.rms, amplitude / 2f64.sqrt()) < 1e-3);
    assert!(rel(m.peak, amplitude) < 1e-3);
    assert!(rel(m.aw, w * amplitude / 2f64.sqrt()) < 0.01);
    assert!(rel(m.crest_factor, 2f64.sqrt()) < 0.01);
    let expected_vdv = (3.0 * (w * amplitude).powi(4) * window_s / 8.0).powf(0.25);
    assert!(rel(m.vdv, expected_vdv) < 0.01);
    assert!((m.duration_s - (n - (settle * fs) as usize) as f64 / fs).abs() < 1e-12);

    // Without settling, the whole signal is counted.
    let whole = vibration_metrics(&x, fs, 0.0).expect("valid input");
    assert!((whole.duration_s - n as f64 / fs).abs() < 1e-12);
}

#[test]
fn settling_interval_excludes_initial_samples() {
    let fs = 1000.0;
    // A large initial shock then a quiet sine: settling hides the shock from the
    // unweighted statistics.
    let mut x = sine(0.1, 5.0, fs, 5000);
    x[10] = 50.0;
    let m = vibration_metrics(&x, fs, 1.0).expect("valid input");
    assert!(m.peak < 0.11);
    assert!((m.duration_s - 4.0).abs() < 1e-12);
    let all = vibration_metrics(&x, fs, 0.0).expect("valid input");
    assert_eq!(all.peak, 50.0);

    // 0.3 s at 1 kHz skips exactly 300 samples despite 0.3·1000 = 300.00000000000006.
    assert_eq!(settle_samples(0.3, 1000.0), 300);
    assert_eq!(settle_samples(0.0, 1000.0), 0);
    assert_eq!(settle_samples(0.0015, 1000.0), 2);

    assert_eq!(
        vibration_metrics(&x, fs, 5.0),
        Err(MetricsError::SettleTooLong {
            settle_s: 5.0,
            duration_s: 5.0
        })
    );
    for bad in [-1.0, f64::NAN, f64::INFINITY] {
        assert!(matches!(
            vibration_metrics(&x, fs, bad),
            Err(MetricsError::InvalidSettle { .. })
        ));
    }
}

fn pseudo_random_ride(n: usize, fs: f64) -> Vec<f64> {
    // Deterministic broadband-ish signal: a few sines plus an LCG noise.
    let mut state: u64 = 0x2545_f491_4f6c_dd1d;
    (0..n)
        .map(|i| {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            let noise = (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
            let t = i as f64 / fs;
            0.8 * (2.0 * PI * 1.3 * t).sin() + 0.5 * (2.0 * PI * 4.7 * t).sin() + noise
        })
        .collect()
}

#[test]
fn running_metrics_equal_batch_metrics() {
    let fs = 1000.0;
    let x = pseudo_random_ride(12_345, fs);
    let batch = vibration_metrics(&x, fs, 0.0).expect("valid input");
    let mut running = RunningMetrics::new(fs).expect("valid rate");
    for &v in &x {
        running.push(v);
    }
    let live = running.metrics();
    for (a, b) in [
        (live.rms, batch.rms),
        (live.peak, batch.peak),
        (live.aw, batch.aw),
        (live.vdv, batch.vdv),
        (live.crest_factor, batch.crest_factor),
        (live.duration_s, batch.duration_s),
    ] {
        assert!(rel(a, b) < 1e-9, "{a} vs {b}");
    }
    assert_eq!(running.samples_pushed(), x.len());

    // Batch statistics agree with the free functions.
    let y = wk_weight(&x, fs).expect("valid rate");
    assert!(rel(batch.rms, rms(&x)) < 1e-9);
    assert!(rel(batch.peak, peak(&x)) < 1e-12);
    assert!(rel(batch.aw, rms(&y)) < 1e-9);
    assert!(rel(batch.vdv, vdv(&y, fs)) < 1e-9);
    assert!(rel(batch.crest_factor, crest_factor(&y)) < 1e-9);

    // With a settling interval too.
    let settled = vibration_metrics(&x, fs, 2.5).expect("valid input");
    let mut running = RunningMetrics::with_settle(fs, 2.5).expect("valid input");
    x.iter().for_each(|&v| running.push(v));
    assert_eq!(running.metrics(), settled);

    // Reset starts over.
    running.reset();
    assert_eq!(running.metrics(), VibrationMetrics::default());
    assert_eq!(running.samples_pushed(), 0);
    x.iter().for_each(|&v| running.push(v));
    assert_eq!(running.metrics(), settled);
}

#[test]
fn seat_value() {
    assert!((seat_percent(0.4, 0.8) - 50.0).abs() < 1e-12);
    assert!((seat_percent(1.0, 1.0) - 100.0).abs() < 1e-12);
    assert!(!seat_percent(1.0, 0.0).is_finite());
}

#[test]
fn daily_exposure() {
    assert!((a8(1.0, 8.0) - 1.0).abs() < 1e-15);
    assert!((a8(1.0, 2.0) - 0.5).abs() < 1e-15);
    assert!((a8(0.6, 4.5) - 0.6 * (4.5f64 / 8.0).sqrt()).abs() < 1e-15);
    assert!(a8(1.0, -1.0).is_nan());

    assert_eq!(exposure_verdict(0.3), ExposureVerdict::BelowAction);
    assert_eq!(exposure_verdict(0.5), ExposureVerdict::BelowAction);
    assert_eq!(exposure_verdict(0.51), ExposureVerdict::AboveAction);
    assert_eq!(exposure_verdict(1.15), ExposureVerdict::AboveAction);
    assert_eq!(exposure_verdict(1.2), ExposureVerdict::AboveLimit);
    assert_eq!(exposure_verdict(f64::NAN), ExposureVerdict::AboveLimit);
    assert_eq!(
        ExposureVerdict::AboveAction.to_string(),
        "above the action value"
    );

    // time_to_reach inverts a8.
    let aw = 0.7;
    let t_action = time_to_reach(aw, EU_ACTION_VALUE_A8);
    assert!((a8(aw, t_action) - EU_ACTION_VALUE_A8).abs() < 1e-12);
    let t_limit = time_to_reach(aw, EU_LIMIT_VALUE_A8);
    assert!((a8(aw, t_limit) - EU_LIMIT_VALUE_A8).abs() < 1e-12);
    assert!((time_to_reach(0.5, 0.5) - 8.0).abs() < 1e-12);
    assert_eq!(time_to_reach(0.0, 0.5), f64::INFINITY);
}
