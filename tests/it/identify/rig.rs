//! The independent true rig, its campaigns, and helpers to run and judge a calibration.

use rand::SeedableRng;
use rand_distr::{Distribution, Normal};
use seat_twin::dataset::Record;
use seat_twin::identify::{self, CalibrationOptions, CalibrationReport, EffectId, Verdict};
use seat_twin::params::Params;
use seat_twin::preset::Preset;
use std::f64::consts::PI;
use std::path::PathBuf;

#[derive(Clone, Copy, Default)]
pub(super) struct RigEffects {
    /// (Coulomb N, Stribeck extra N, Stribeck velocity m/s, viscous N·s/m)
    pub(super) friction: Option<(f64, f64, f64, f64)>,
    /// overlap m (smooth edge)
    pub(super) overlap: Option<f64>,
    /// width of the overlap's rounded edges [m] (default 1 µm: nearly sharp)
    pub(super) overlap_edge: Option<f64>,
    /// spool null offset m
    pub(super) offset: Option<f64>,
    /// leakage coefficient m³/(s·Pa), grows with |Δp|
    pub(super) leakage: Option<f64>,
    /// (β hose, β chamber) Pa
    pub(super) compliance: Option<(f64, f64)>,
    /// droop Pa/(m³/s), linear in the drawn flow (solved by fixed-point iteration here)
    pub(super) sag: Option<f64>,
    /// Outside the library: a discharge coefficient that depends on the spool position,
    /// `Cd·(1 + a·tanh(x/0.1 mm))` — larger on one side of null than on the other, more so
    /// with the opening (asymmetric metering edges). No library effect has this form: an
    /// offset shifts null but keeps the gain, overlap and sag are symmetric.
    pub(super) cd_spool: Option<f64>,
    /// Outside the library: the valve's null drifts during each test (its torque motor
    /// warming up), as a command-referred bias growing at this rate [V/s] from the test's
    /// start. The stroke drifts slowly, faster and faster; a constant offset can follow its
    /// mean only.
    pub(super) null_drift_v_per_s: Option<f64>,
    /// Outside the library: a discharge coefficient that rises with the opening and levels
    /// off (the jet angle changing), `Cd·(1 + c·(1 − exp(−|x|/0.2 mm)))`.
    pub(super) cd_opening: Option<f64>,
    /// Outside the library: a damping force that grows with the square of the velocity (oil
    /// forced through a gap), `c·u̇·√(u̇² + (5 mm/s)²)` with `c` in N·s²/m².
    pub(super) quadratic_damping: Option<f64>,
    /// Outside the library: a spring the declared stiffness lacks (a seat cushion), slightly
    /// progressive: `k·u·(1 + (u/30 mm)²)` with `k` in N/m.
    pub(super) extra_spring: Option<f64>,
    /// Outside the library: the valve acts on its command through a first-order lag [s] (a
    /// servo amplifier's), integrated at the rig's step by the trapezoidal rule; the record's
    /// `v_in` is the command as sent.
    pub(super) command_lag_s: Option<f64>,
    /// A drift, not an effect: the discharge coefficient grows by this fraction from one test
    /// to the next (oil warming up through the campaign: test i has Cd·(1 + d·i)).
    pub(super) cd_drift_per_test: Option<f64>,
    /// Sensor, not plant: the body accelerometer reads this fraction of the truth.
    pub(super) ydd_scale: Option<f64>,
    /// Sensor, not plant: the body accelerometer's offset [m/s²].
    pub(super) ydd_offset: Option<f64>,
    /// Sensor, not plant: the time constant [s] of the stroke sensor's first-order low-pass,
    /// run by the data acquisition on the samples (`y[n] = a·y[n−1] + (1 − a)·u[n]`,
    /// `a = e^(−Δt/T)`), as a rig's digital filter is.
    pub(super) u_lag_s: Option<f64>,
    /// Sensor, not plant: the data acquisition's analogue anti-alias filter [Hz], a
    /// second-order Butterworth low-pass on every measured channel (u, x, ẍ, ÿ, p1, p2; not
    /// the command, which the controller sends digitally), run at the rig's 20 kHz step
    /// before the channels are sampled.
    pub(super) daq_antialias_hz: Option<f64>,
    /// Sensor: the accelerometers' white noise RMS [m/s²] (default [`ACC_NOISE`], a MEMS
    /// sensor's 0.08 m/s²; a laboratory accelerometer is several times quieter).
    pub(super) acc_noise: Option<f64>,
}

/// A second-order Butterworth low-pass at `fc` [Hz] run every `h` [s] (the bilinear
/// transform, prewarped at `fc`), settled at its first input.
struct Butter2 {
    b: [f64; 3],
    a: [f64; 2],
    /// Last two inputs and outputs; `None` before the first input.
    z: Option<([f64; 2], [f64; 2])>,
}

impl Butter2 {
    fn new(fc: f64, h: f64) -> Self {
        let k = (PI * fc * h).tan();
        let q = std::f64::consts::FRAC_1_SQRT_2;
        let norm = 1.0 / (1.0 + k / q + k * k);
        let b0 = k * k * norm;
        Self {
            b: [b0, 2.0 * b0, b0],
            a: [2.0 * (k * k - 1.0) * norm, (1.0 - k / q + k * k) * norm],
            z: None,
        }
    }

    fn next(&mut self, x: f64) -> f64 {
        let ([x1, x2], [y1, y2]) = self.z.unwrap_or(([x, x], [x, x]));
        let y = self.b[0] * x + self.b[1] * x1 + self.b[2] * x2 - self.a[0] * y1 - self.a[1] * y2;
        self.z = Some(([x, x1], [y, y1]));
        y
    }
}

pub(super) struct Rig {
    pub(super) cd: f64,
    pub(super) tau: f64,
    pub(super) fx: RigEffects,
}

pub(super) enum Test {
    Sine { f: f64, a: f64, dur: f64 },
    Ride { dur: f64 },
}

pub(super) fn ssqrt(dp: f64) -> f64 {
    const D: f64 = 1.0e4;
    if dp.abs() < D {
        dp / D.sqrt()
    } else {
        dp.signum() * dp.abs().sqrt()
    }
}

/// Platform of the ride: three cosines in position, from rest in position and velocity.
pub(super) fn platform(t: f64) -> (f64, f64, f64) {
    let comps = [(1.3, 0.35), (2.7, 0.3), (4.1, 0.25)];
    let (mut x, mut xd, mut xdd) = (0.0, 0.0, 0.0);
    for (f, acc) in comps {
        let w: f64 = 2.0 * PI * f;
        let a = 2.0 * acc / (w * w);
        x += 0.5 * a * (1.0 - (w * t).cos());
        xd += 0.5 * a * w * (w * t).sin();
        xdd += 0.5 * a * w * w * (w * t).cos();
    }
    (x, xd, xdd)
}

impl Rig {
    pub(super) fn rhs(&self, y: &[f64; 10], v_valve: f64, xdd: f64) -> [f64; 10] {
        let (m, k) = (11.7, 3680.0);
        let area = PI * (0.025f64.powi(2) - 0.018f64.powi(2)) / 4.0;
        let (l, dh): (f64, f64) = (0.5, 0.010);
        let (rho, mu) = (840.0, 0.02);
        let (beta_h, beta_c) = self.fx.compliance.unwrap_or((1.2e9, 1.2e9));
        let r = 128.0 * mu * l / (PI * dh.powi(4));
        let inert = 4.0 * rho * l / (PI * dh * dh);
        let ch = PI * l * dh * dh / (4.0 * beta_h);
        let cc = area * 0.035 / beta_c;
        let (pa, p0) = (100e5, 10e5);
        let [u, du, p1, p2, q1, q2, p1v, p2v, xv, dxv] = *y;
        // Friction.
        let ff = match self.fx.friction {
            Some((fc, fs, vs, b)) => {
                (fc + fs * (-(du / vs).powi(2)).exp()) * (du / 2e-3).tanh() + b * du
            }
            None => 0.0,
        };
        let half = 0.035;
        let pen = u.abs() - half;
        let stop = if pen > 0.0 {
            -u.signum() * (5e6 * pen + 5e3 * du * u.signum()).max(0.0)
        } else {
            0.0
        };
        let fq = self
            .fx
            .quadratic_damping
            .map_or(0.0, |c| c * du * (du * du + 25e-6).sqrt());
        let fk = self
            .fx
            .extra_spring
            .map_or(0.0, |ke| ke * u * (1.0 + (u / 0.03).powi(2)));
        let ydd = (-k * u - p1 * area + p2 * area - ff - fq - fk + stop) / m;
        // Valve opening.
        let mut x = xv.clamp(-0.8e-3, 0.8e-3) - self.fx.offset.unwrap_or(0.0);
        if let Some(ov) = self.fx.overlap {
            let d = x.abs() - ov;
            let e = self.fx.overlap_edge.unwrap_or(1e-6);
            let open =
                0.5 * (d + (d * d + e * e).sqrt()) - 0.5 * (ov * ov + e * e).sqrt() + 0.5 * ov;
            x = x.signum() * open.max(0.0);
        }
        let cd = match self.fx.cd_spool {
            Some(a) => self.cd * (1.0 + a * (x / 1e-4).tanh()),
            None => self.cd,
        };
        let cd = match self.fx.cd_opening {
            Some(c) => cd * (1.0 + c * (1.0 - (-x.abs() / 2e-4).exp())),
            None => cd,
        };
        let g = cd * 0.0251 * (2.0 / rho).sqrt() * x;
        let supply = |p_line: f64| -> f64 {
            match self.fx.sag {
                None => pa,
                Some(r2) => {
                    let mut ps = pa;
                    for _ in 0..12 {
                        let q = g.abs() * ssqrt(ps - p_line).max(0.0);
                        ps = pa - r2 * q;
                    }
                    ps
                }
            }
        };
        let (q1v, q2v) = if x > 0.0 {
            (g * ssqrt(p1v - p0), g * ssqrt(supply(p2v) - p2v))
        } else {
            (g * ssqrt(supply(p1v) - p1v), g * ssqrt(p2v - p0))
        };
        let ql = match self.fx.leakage {
            Some(cl) => cl * (p1 - p2) * (1.0 + (p1 - p2).abs() / 2e7),
            None => 0.0,
        };
        let wn = 691.0;
        let target = 8e-5 * v_valve;
        [
            du,
            ydd - xdd,
            (du * area - q1 - ql) / cc,
            (q2 - du * area + ql) / cc,
            (p1 - p1v - r * q1) / inert,
            (p2v - p2 - r * q2) / inert,
            (q1 - q1v) / ch,
            (q2v - q2) / ch,
            dxv,
            wn * wn * (target - xv) - 2.0 * 1.1 * wn * dxv,
        ]
    }

    pub(super) fn body_acc(&self, y: &[f64; 10], xdd: f64) -> f64 {
        self.rhs(y, 0.0, xdd)[1] + xdd
    }

    /// Simulates one test and returns a measured record (1 kHz, noisy, quantised); with
    /// `pressures`, the chamber pressures too (Pa gauge, 0.2 bar noise, 12-bit on 250 bar).
    pub(super) fn record(&self, test: &Test, seed: u64, pressures: bool) -> Record {
        self.record_at(test, seed, pressures, 1000.0)
    }

    /// [`Self::record`] sampled at `rate_hz` (a divisor of the rig's 20 kHz step rate,
    /// 200 Hz … 10 kHz), with the same sensor noise per sample.
    pub(super) fn record_at(
        &self,
        test: &Test,
        seed: u64,
        pressures: bool,
        rate_hz: f64,
    ) -> Record {
        let h = 5e-5;
        let per_sample = (1.0 / (rate_hz * h)).round() as usize;
        let dt_s = per_sample as f64 * h;
        let dur = match test {
            Test::Sine { dur, .. } | Test::Ride { dur } => *dur,
        };
        let n = (dur / dt_s).round() as usize + 1;
        let mut y = [0.0; 10];
        for i in [2, 3, 6, 7] {
            y[i] = 55e5;
        }
        let mut hist: Vec<f64> = Vec::with_capacity(n * per_sample + 1);
        let (kp, ki) = (-5.0, -7.5);
        let cmd = |t: f64, y: &[f64; 10]| -> f64 {
            match test {
                Test::Sine { f, a, .. } => a * (2.0 * PI * f * t).cos(),
                Test::Ride { .. } => (kp * y[0] + ki * platform(t).1).clamp(-10.0, 10.0),
            }
        };
        let plat = |t: f64| match test {
            Test::Sine { .. } => (0.0, 0.0, 0.0),
            Test::Ride { .. } => platform(t),
        };
        let delayed = |hist: &[f64], t: f64| -> f64 {
            let s = (t - self.tau) / h;
            if s < 0.0 {
                return 0.0;
            }
            let i = s.floor() as usize;
            let f = s - i as f64;
            match (hist.get(i), hist.get(i + 1)) {
                (Some(a), Some(b)) => a + f * (b - a),
                (Some(a), None) => *a,
                _ => *hist.last().unwrap_or(&0.0),
            }
        };
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let acc_noise = Normal::new(0.0, self.fx.acc_noise.unwrap_or(ACC_NOISE)).unwrap();
        let pos_noise = Normal::new(0.0, 1e-5).unwrap();
        let lsb = 0.075 / 4096.0;
        let p_noise = Normal::new(0.0, 2e4).unwrap();
        let p_lsb = 250e5 / 4096.0;
        let (mut t_col, mut v_col, mut u_col, mut x_col, mut xdd_col, mut ydd_col) =
            (vec![], vec![], vec![], vec![], vec![], vec![]);
        let (mut p1_col, mut p2_col) = (vec![], vec![]);
        let mut t = 0.0;
        // The measured channels' true values (u, x, ẍ, ÿ, p1, p2), and the anti-alias
        // filters they pass through first when the rig has them.
        let truths = |t: f64, y: &[f64; 10]| {
            let (x, _, xdd) = plat(t);
            [y[0], x, xdd, self.body_acc(y, xdd), y[2], y[3]]
        };
        let mut aa: Option<[Butter2; 6]> = self
            .fx
            .daq_antialias_hz
            .map(|fc| std::array::from_fn(|_| Butter2::new(fc, h)));
        let mut filtered = [0.0; 6];
        if let Some(f) = &mut aa {
            let v = truths(0.0, &y);
            for i in 0..6 {
                filtered[i] = f[i].next(v[i]);
            }
        }
        let mut u_sensed = 0.0;
        // What the valve acts on (before its delay): the command, or its lag from rest.
        let mut valve_hist: Vec<f64> = Vec::with_capacity(n * per_sample + 1);
        let mut lagged = 0.0;
        hist.push(cmd(0.0, &y));
        valve_hist.push(if self.fx.command_lag_s.is_some() {
            lagged
        } else {
            hist[0]
        });
        for s in 0..n {
            let [u_in, x, xdd, ydd, p1, p2] = if aa.is_some() {
                filtered
            } else {
                truths(t, &y)
            };
            t_col.push(s as f64 * dt_s);
            v_col.push(hist[hist.len() - 1]);
            let u_true = match self.fx.u_lag_s {
                Some(lag) if s > 0 => {
                    let a = (-dt_s / lag).exp();
                    u_sensed = a * u_sensed + (1.0 - a) * u_in;
                    u_sensed
                }
                Some(_) => {
                    u_sensed = u_in;
                    u_sensed
                }
                None => u_in,
            };
            let un = u_true + pos_noise.sample(&mut rng);
            u_col.push(lsb * ((un + 0.0375) / lsb).round() - 0.0375);
            x_col.push(x + pos_noise.sample(&mut rng));
            xdd_col.push(xdd + acc_noise.sample(&mut rng));
            ydd_col.push(
                self.fx.ydd_scale.unwrap_or(1.0) * ydd
                    + self.fx.ydd_offset.unwrap_or(0.0)
                    + acc_noise.sample(&mut rng),
            );
            if pressures {
                for (col, p) in [(&mut p1_col, p1), (&mut p2_col, p2)] {
                    col.push(p_lsb * ((p + p_noise.sample(&mut rng)) / p_lsb).round());
                }
            }
            if s + 1 == n {
                break;
            }
            for _ in 0..per_sample {
                let drift = |tt: f64| self.fx.null_drift_v_per_s.map_or(0.0, |r| r * tt);
                let f = |tt: f64, yy: &[f64; 10]| {
                    self.rhs(yy, delayed(&valve_hist, tt) + drift(tt), plat(tt).2)
                };
                let k1 = f(t, &y);
                let mut tmp = [0.0; 10];
                for i in 0..10 {
                    tmp[i] = y[i] + 0.5 * h * k1[i];
                }
                let k2 = f(t + 0.5 * h, &tmp);
                for i in 0..10 {
                    tmp[i] = y[i] + 0.5 * h * k2[i];
                }
                let k3 = f(t + 0.5 * h, &tmp);
                for i in 0..10 {
                    tmp[i] = y[i] + h * k3[i];
                }
                let k4 = f(t + h, &tmp);
                for i in 0..10 {
                    y[i] += h / 6.0 * (k1[i] + 2.0 * (k2[i] + k3[i]) + k4[i]);
                }
                y[8] = y[8].clamp(-0.8e-3, 0.8e-3);
                t += h;
                if let Some(f) = &mut aa {
                    let v = truths(t, &y);
                    for i in 0..6 {
                        filtered[i] = f[i].next(v[i]);
                    }
                }
                let c = cmd(t, &y);
                if let Some(lag) = self.fx.command_lag_s {
                    let k = h / (2.0 * lag);
                    lagged = ((1.0 - k) * lagged + k * (hist[hist.len() - 1] + c)) / (1.0 + k);
                }
                hist.push(c);
                valve_hist.push(if self.fx.command_lag_s.is_some() {
                    lagged
                } else {
                    c
                });
            }
        }
        let ride = matches!(test, Test::Ride { .. });
        Record {
            path: PathBuf::from(match test {
                Test::Sine { f, a, .. } => format!("sine_{f}hz_{a}v.csv"),
                Test::Ride { .. } => "ride.csv".into(),
            }),
            metadata: vec![],
            dt: dt_s,
            t: t_col,
            v_in: Some(v_col),
            u: Some(u_col),
            x: ride.then_some(x_col),
            xdd: ride.then_some(xdd_col),
            ydd: Some(ydd_col),
            p1: pressures.then_some(p1_col),
            p2: pressures.then_some(p2_col),
            warnings: vec![],
        }
    }
}

pub(super) fn campaign(fx: RigEffects, seed: u64, pressures: bool) -> Vec<Record> {
    campaign_at(fx, seed, pressures, 1000.0)
}

/// The five tests of [`campaign`] sampled at `rate_hz`.
pub(super) fn campaign_at(fx: RigEffects, seed: u64, pressures: bool, rate_hz: f64) -> Vec<Record> {
    campaign_of(0.95 * 0.1506, 0.0175 + 0.0015, fx, seed, pressures, rate_hz)
}

/// The five tests of [`campaign`] on a rig of discharge coefficient `cd` and valve delay
/// `tau` [s], sampled at `rate_hz`.
pub(super) fn campaign_of(
    cd: f64,
    tau: f64,
    fx: RigEffects,
    seed: u64,
    pressures: bool,
    rate_hz: f64,
) -> Vec<Record> {
    let rig = |i: usize| Rig {
        cd: cd * (1.0 + fx.cd_drift_per_test.unwrap_or(0.0) * i as f64),
        tau,
        fx,
    };
    let tests = [
        Test::Sine {
            f: 2.0,
            a: 2.1,
            dur: 2.5,
        },
        Test::Sine {
            f: 5.0,
            a: 0.72,
            dur: 2.0,
        },
        Test::Sine {
            f: 10.0,
            a: 4.0,
            dur: 2.0,
        },
        Test::Sine {
            f: 20.0,
            a: 0.72,
            dur: 1.5,
        },
        Test::Ride { dur: 5.0 },
    ];
    tests
        .iter()
        .enumerate()
        .map(|(i, t)| rig(i).record_at(t, seed * 100 + i as u64, pressures, rate_hz))
        .collect()
}

pub(super) fn run(fx: RigEffects, seed: u64) -> CalibrationReport {
    run_with(fx, seed, false)
}

pub(super) fn run_with(fx: RigEffects, seed: u64, pressures: bool) -> CalibrationReport {
    calibrate_paper(&campaign(fx, seed, pressures))
}

/// Calibrates `recs` from the paper preset with the default options.
pub(super) fn calibrate_paper(recs: &[Record]) -> CalibrationReport {
    calibrate_from(&Params::paper(), recs)
}

/// Calibrates `recs` from `start` with the default options.
pub(super) fn calibrate_from(start: &Params, recs: &[Record]) -> CalibrationReport {
    identify::calibrate(start, recs, &CalibrationOptions::default(), &|_| true)
        .expect("calibration runs")
}

pub(super) fn first_ranked(r: &CalibrationReport) -> EffectId {
    r.candidates
        .iter()
        .filter(|c| c.round == 1)
        .min_by(|a, b| a.score.total_cmp(&b.score))
        .expect("candidates scored")
        .effect
}

/// The sensor property of `channel` and `kind` that `r` reports; the test fails, naming what
/// was reported, if there is none.
pub(super) fn reported_sensor<'a>(
    r: &'a CalibrationReport,
    channel: &str,
    kind: &str,
) -> &'a identify::result::SensorEstimate {
    r.sensors
        .iter()
        .find(|e| e.channel == channel && e.kind == kind)
        .unwrap_or_else(|| {
            panic!(
                "{channel} {kind} not reported: {:?}; {}",
                r.sensors,
                summary(r)
            )
        })
}

/// The names of the library effects `r` lists (its library's twin).
pub(super) fn effect_names(r: &CalibrationReport) -> Vec<&'static str> {
    r.effects.iter().map(|e| e.effect.name()).collect()
}

/// The proposed terms of `r` in words.
pub(super) fn proposed_words(r: &CalibrationReport) -> Vec<&str> {
    r.proposed.iter().map(|t| t.description.as_str()).collect()
}

pub(super) fn summary(r: &CalibrationReport) -> String {
    let c: Vec<String> = r
        .candidates
        .iter()
        .map(|c| {
            format!(
                "r{} {} {:.1} ({:.1} %)",
                c.round,
                c.effect.name(),
                c.score,
                100.0 * c.relative_gain
            )
        })
        .collect();
    let worst = r
        .error_after
        .files
        .iter()
        .map(|(f, e)| {
            let w = [
                Some(e.weighted_du),
                e.weighted_ydd,
                e.weighted_p1,
                e.weighted_p2,
            ]
            .into_iter()
            .flatten()
            .fold(0.0, f64::max);
            (f.clone(), w)
        })
        .max_by(|a, b| a.1.total_cmp(&b.1));
    format!(
        "verdict {:?} (raw: {}), worst record channel after {worst:?}, effects {:?}, errors nominal {:.3} before {:.3} after {:.3}, cd {:.5} tau {:.5}; {}",
        r.verdict,
        r.raw_error_after.summary(),
        r.effects
            .iter()
            .map(|e| e.effect.name())
            .collect::<Vec<_>>(),
        r.error_nominal.value,
        r.error_before.value,
        r.error_after.value,
        r.params.plant.valve.cd,
        r.params.plant.valve.tau_s,
        c.join("; ")
    )
}

/// Weighted error of a correct model on these records: the null case (no hidden effect) ends
/// at 0.715, i.e. the sensor noise and quantisation alone.
pub(super) const NOISE_FLOOR: f64 = 0.70;

/// The effect removes at least 30 % of the error, or — for a weak effect whose error before is
/// already within 50 % of the noise floor (leakage: 0.985) — brings it down to that floor.
pub(super) fn assert_reduced_to_noise(r: &CalibrationReport, s: &str) {
    let (before, after) = (r.error_before.value, r.error_after.value);
    assert!(
        after < 0.7 * before || (before < 1.5 * NOISE_FLOOR && after < 1.02 * NOISE_FLOOR),
        "{s}"
    );
}

pub(super) fn check_single(fx: RigEffects, expected: EffectId, seed: u64) -> CalibrationReport {
    check_single_with(fx, expected, seed, false)
}

/// A friction rig: friction is ranked first and added, Cd and τ are found, and — since
/// issue 20 fits the friction law's shape (the Stribeck velocity and the velocity over which
/// the force changes sign) beside its sizes — the verdict is `explained`, every raw band at
/// its floor. The rig's law is the library's form with its own values (sign smoothed over
/// 2 mm/s, Stribeck velocity 10 mm/s, against the preset's 1 and 5 mm/s); before, with the
/// shape fixed at the preset's, u and ÿ stayed 3–7× above the floor and the verdict read
/// `unexplained`.
pub(super) fn check_friction(fx: RigEffects, seed: u64, pressures: bool) -> CalibrationReport {
    let r = run_with(fx, seed, pressures);
    let s = summary(&r);
    eprintln!("friction: {s}; effects {:?}", r.effects);
    let friction = r
        .effects
        .iter()
        .find(|e| e.effect == EffectId::Friction)
        .unwrap_or_else(|| panic!("friction not found: {s}"));
    assert_eq!(r.verdict, Verdict::Explained, "{s}");
    assert!(
        friction.params.contains_key("stribeck_velocity_m_s"),
        "{friction:?}"
    );
    assert!(
        (r.params.plant.valve.cd / (0.95 * 0.1506) - 1.0).abs() < 0.03,
        "{s}"
    );
    assert!((r.params.plant.valve.tau_s - 0.019).abs() < 1.0e-3, "{s}");
    r
}

pub(super) fn check_single_with(
    fx: RigEffects,
    expected: EffectId,
    seed: u64,
    pressures: bool,
) -> CalibrationReport {
    let r = run_with(fx, seed, pressures);
    let s = summary(&r);
    eprintln!("{}: {s}", expected.name());
    assert_eq!(first_ranked(&r), expected, "{s}");
    assert_eq!(r.verdict, Verdict::Explained, "{s}");
    assert_eq!(r.effects[0].effect, expected, "{s}");
    assert_reduced_to_noise(&r, &s);
    // The declared mismatch is found: Cd −5 %, τ +1.5 ms.
    assert!(
        (r.params.plant.valve.cd / (0.95 * 0.1506) - 1.0).abs() < 0.03,
        "{s}"
    );
    assert!((r.params.plant.valve.tau_s - 0.019).abs() < 1.0e-3, "{s}");
    r
}

/// The rig's true declared parameters (Cd −5 %, τ +1.5 ms) on the paper preset: with no
/// hidden effect, this is the right model of the rig.
pub(super) fn true_params() -> Params {
    let mut p = Params::paper();
    p.plant.valve.cd = 0.95 * 0.1506;
    p.plant.valve.tau_s = 0.0175 + 0.0015;
    p
}

pub(super) fn rms_diff(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len()).max(1);
    (a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum::<f64>() / n as f64).sqrt()
}

/// Sensor noise of the rig's records (noise and quantisation, as the rig adds them).
pub(super) const U_NOISE: f64 = 1.13e-5; // √(10 µm² + (18.3 µm)²/12)
pub(super) const ACC_NOISE: f64 = 0.08;
pub(super) const P_NOISE: f64 = 2.0e4; // 0.2 bar; the 6.1 kPa LSB adds 1 %

pub(super) fn check_pair(
    fx: RigEffects,
    pair: [EffectId; 2],
    seed: u64,
    pressures: bool,
) -> CalibrationReport {
    let r = run_with(fx, seed, pressures);
    let s = summary(&r);
    eprintln!(
        "pair {}+{}: {s}; notes {:?}",
        pair[0].name(),
        pair[1].name(),
        r.notes
    );
    let found: Vec<EffectId> = r.effects.iter().map(|e| e.effect).collect();
    assert!(found.contains(&pair[0]) && found.contains(&pair[1]), "{s}");
    assert_eq!(r.verdict, Verdict::Explained, "{s}");
    assert!(r.error_after.value < 0.7 * r.error_before.value, "{s}");
    let v = r.error_validation.as_ref().expect("validation");
    assert!(v.after < v.before, "{s}");
    r
}

/// RMS above the sensor noise of the raw `u` and `ÿ`, pooled over `recs`, replayed with
/// `preset` as `seat-twin replay --preset` replays them (a record listed in the preset's
/// `[per_record]` with its own values).
pub(super) fn above_noise(preset: &Preset, recs: &[Record]) -> [f64; 2] {
    let (mut eu, mut ey, mut n) = (0.0, 0.0, 0.0);
    for rec in recs {
        let file = rec.path.file_name().expect("file name").to_string_lossy();
        let (params, _) = preset.per_record.params_for(&preset.params, &file);
        let rep = identify::replay(&params, rec).expect("replay");
        let raw = &rep.errors.raw;
        let k = rep.errors.samples as f64;
        eu += k * raw.u.rms_error.powi(2);
        ey += k * raw.ydd.map_or(0.0, |c| c.rms_error.powi(2));
        n += k;
    }
    [
        (eu / n - U_NOISE * U_NOISE).max(0.0).sqrt(),
        (ey / n - ACC_NOISE * ACC_NOISE).max(0.0).sqrt(),
    ]
}
