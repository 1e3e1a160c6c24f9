//! Excitations: platform (seat-base) motions and open-loop valve commands.
//!
//! Platform motions give `x`, `ẋ`, `ẍ` at any time; all start from rest. Commands give
//! `V_in(t)` for open-loop tests (the valve sine tests of Table 1, chirps, replayed records).

pub mod class_motion;
pub mod classes;

pub use class_motion::ClassMotion;
pub use classes::InputClass;

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use realfft::RealFftPlanner;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;
use std::sync::Arc;

/// Platform position, velocity and acceleration at one instant.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PlatformSample {
    /// Position `x` \[m\].
    pub x: f64,
    /// Velocity `ẋ` [m/s].
    pub xd: f64,
    /// Acceleration `ẍ` [m/s²].
    pub xdd: f64,
}

/// Cycloidal rise of the platform (Fig. 13): `height` in `duration`, starting at `start`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Cycloid {
    /// Rise \[m\], −0.2 ..= 0.2. Paper: 0.030.
    pub height_m: f64,
    /// Rise time \[s\], 0.01 ..= 10. Paper: 0.5.
    pub rise_time_s: f64,
    /// Start of the rise \[s\], 0 ..= 1000.
    pub start_s: f64,
}

impl Default for Cycloid {
    fn default() -> Self {
        Self {
            height_m: 0.030,
            rise_time_s: 0.5,
            start_s: 0.5,
        }
    }
}

impl Cycloid {
    /// Motion at time `t` (exact cycloidal law).
    pub fn at(&self, t: f64) -> PlatformSample {
        let (h, tr) = (self.height_m, self.rise_time_s);
        let s = (t - self.start_s) / tr;
        if s <= 0.0 {
            PlatformSample::default()
        } else if s >= 1.0 {
            PlatformSample {
                x: h,
                ..Default::default()
            }
        } else {
            let a = 2.0 * PI * s;
            PlatformSample {
                x: h * (s - a.sin() / (2.0 * PI)),
                xd: h / tr * (1.0 - a.cos()),
                xdd: 2.0 * PI * h / (tr * tr) * a.sin(),
            }
        }
    }
}

/// Band-limited Gaussian white-noise platform acceleration (section 6).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RandomRide {
    /// One-sided PSD level `S0` [(m/s²)²/Hz], 0 ..= 10. Paper: 0.05.
    pub s0: f64,
    /// Lower band edge \[Hz\], 0.05 ..= 100. Paper: 0.5.
    pub f_low_hz: f64,
    /// Upper band edge \[Hz\], > lower, ..= 200. Paper: 5.
    pub f_high_hz: f64,
    /// Duration of the record \[s\], 1 ..= 3600.
    pub duration_s: f64,
    /// Smooth (quintic) fade-in at the start \[s\], 0 ..= duration/2, so that it starts from rest.
    pub fade_in_s: f64,
    /// Seed of the random generator (ChaCha8): same seed, same record, bit for bit.
    pub seed: u64,
}

impl Default for RandomRide {
    fn default() -> Self {
        Self {
            s0: 0.05,
            f_low_hz: 0.5,
            f_high_hz: 5.0,
            duration_s: 60.0,
            fade_in_s: 2.0,
            seed: 1,
        }
    }
}

/// A platform motion sampled on a uniform grid, read with Catmull–Rom cubic interpolation.
#[derive(Debug, Clone, PartialEq)]
pub struct SampledMotion {
    dt: f64,
    x: Arc<Vec<f64>>,
    xd: Arc<Vec<f64>>,
    xdd: Arc<Vec<f64>>,
}

#[inline(always)]
fn catmull_rom(v: &[f64], s: f64) -> f64 {
    let n = v.len();
    if n == 0 {
        return 0.0;
    }
    if s <= 0.0 {
        return v[0];
    }
    // s > 0: truncation is floor (and far cheaper than a libm call on the hot path).
    let i = s as usize;
    if i + 1 >= n {
        return v[n - 1];
    }
    let f = s - i as f64;
    let p0 = v[i.saturating_sub(1)];
    let (p1, p2) = (v[i], v[i + 1]);
    let p3 = v[(i + 2).min(n - 1)];
    p1 + 0.5
        * f
        * (p2 - p0 + f * (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3 + f * (3.0 * (p1 - p2) + p3 - p0)))
}

impl SampledMotion {
    /// The motion sampled at step `dt` \[s\] from `x`, `ẋ`, `ẍ` (SI, equal lengths), each
    /// instant passed through `shape(t, sample)` (a fade in, or in and out).
    pub fn shaped(
        dt: f64,
        x: &[f64],
        xd: &[f64],
        xdd: &[f64],
        shape: impl Fn(f64, PlatformSample) -> PlatformSample,
    ) -> Self {
        let n = x.len().min(xd.len()).min(xdd.len());
        let (mut fx, mut fxd, mut fxdd) = (
            Vec::with_capacity(n),
            Vec::with_capacity(n),
            Vec::with_capacity(n),
        );
        for i in 0..n {
            let m = shape(
                i as f64 * dt,
                PlatformSample {
                    x: x[i],
                    xd: xd[i],
                    xdd: xdd[i],
                },
            );
            fx.push(m.x);
            fxd.push(m.xd);
            fxdd.push(m.xdd);
        }
        SampledMotion::new(dt, fx, fxd, fxdd)
    }

    /// From uniformly sampled `x`, `ẋ`, `ẍ` (equal lengths, ≥ 2 samples) with step `dt` \[s\].
    pub fn new(dt: f64, x: Vec<f64>, xd: Vec<f64>, xdd: Vec<f64>) -> Self {
        Self {
            dt,
            x: Arc::new(x),
            xd: Arc::new(xd),
            xdd: Arc::new(xdd),
        }
    }

    /// The platform motion of a record (measured or excitation CSV): its `xdd` column drives
    /// the dynamics when there is one (an `x` column beside it is only reported), else its
    /// `x` column does; `None` for a record with neither.
    pub fn from_record(rec: &crate::dataset::Record) -> Option<Self> {
        let dt = rec.dt;
        Some(match (rec.xdd.clone(), rec.x.clone()) {
            (Some(xdd), Some(x)) => Self::from_acceleration(dt, xdd).with_reported_position(x),
            (Some(xdd), None) => Self::from_acceleration(dt, xdd),
            (None, Some(x)) => Self::from_position(dt, x),
            (None, None) => return None,
        })
    }

    /// From a sampled acceleration only: velocity and position by trapezoidal integration
    /// from rest.
    pub fn from_acceleration(dt: f64, xdd: Vec<f64>) -> Self {
        let mut xd = vec![0.0; xdd.len()];
        let mut x = vec![0.0; xdd.len()];
        for i in 1..xdd.len() {
            xd[i] = xd[i - 1] + 0.5 * dt * (xdd[i - 1] + xdd[i]);
            x[i] = x[i - 1] + 0.5 * dt * (xd[i - 1] + xd[i]);
        }
        Self::new(dt, x, xd, xdd)
    }

    /// From a sampled position only: velocity and acceleration by central differences.
    pub fn from_position(dt: f64, x: Vec<f64>) -> Self {
        let n = x.len();
        let diff = |v: &[f64]| -> Vec<f64> {
            (0..n)
                .map(|i| {
                    let (a, b) = (i.saturating_sub(1), (i + 1).min(n - 1));
                    if b > a {
                        (v[b] - v[a]) / ((b - a) as f64 * dt)
                    } else {
                        0.0
                    }
                })
                .collect()
        };
        let xd = diff(&x);
        let xdd = diff(&xd);
        Self::new(dt, x, xd, xdd)
    }

    /// Replaces the position channel by a measured one (reported only: the dynamics and the
    /// controller use the acceleration). Lengths must match; otherwise the record is kept.
    pub fn with_reported_position(mut self, x: Vec<f64>) -> Self {
        if x.len() == self.x.len() {
            self.x = Arc::new(x);
        }
        self
    }

    /// The motion `by` \[s\] earlier on the same grid: sample i reads the motion at
    /// `i·dt + by` between the samples as [`Self::at`] does, held at the last. Undoes a
    /// measurement's delay `by` (a data acquisition's anti-alias filter delays the slow
    /// platform motion by its group delay, with its gain at 1).
    pub fn advanced(&self, by: f64) -> Self {
        let shift = |v: &[f64]| -> Vec<f64> {
            (0..v.len())
                .map(|i| catmull_rom(v, i as f64 + by / self.dt))
                .collect()
        };
        Self::new(self.dt, shift(&self.x), shift(&self.xd), shift(&self.xdd))
    }

    /// Sample step \[s\].
    pub fn dt(&self) -> f64 {
        self.dt
    }

    /// Duration covered \[s\].
    pub fn duration_s(&self) -> f64 {
        (self.xdd.len().saturating_sub(1)) as f64 * self.dt
    }

    /// Motion at `t` (held at the last sample after the end).
    #[inline]
    pub fn at(&self, t: f64) -> PlatformSample {
        let s = t / self.dt;
        PlatformSample {
            x: catmull_rom(&self.x, s),
            xd: catmull_rom(&self.xd, s),
            xdd: catmull_rom(&self.xdd, s),
        }
    }

    /// Acceleration only (the hot path of the simulation).
    #[inline(always)]
    pub fn xdd_at(&self, t: f64) -> f64 {
        catmull_rom(&self.xdd, t / self.dt)
    }

    /// Motion at sample `i` (held at the last sample after the end): what [`Self::at`] gives
    /// at `t = i·dt`, without interpolating.
    #[inline(always)]
    pub fn at_sample(&self, i: usize) -> PlatformSample {
        let i = i.min(self.xdd.len().saturating_sub(1));
        PlatformSample {
            x: self.x.get(i).copied().unwrap_or(0.0),
            xd: self.xd.get(i).copied().unwrap_or(0.0),
            xdd: self.xdd.get(i).copied().unwrap_or(0.0),
        }
    }

    /// The samples of `x` [m], `ẋ` [m/s] and `ẍ` [m/s²], for a loop that reads them in place
    /// as [`Self::at_sample`] does.
    pub(crate) fn channels(&self) -> (&[f64], &[f64], &[f64]) {
        (&self.x, &self.xd, &self.xdd)
    }

    /// Acceleration at sample `i` (held after the end).
    #[inline(always)]
    pub fn xdd_at_sample(&self, i: usize) -> f64 {
        let i = i.min(self.xdd.len().saturating_sub(1));
        self.xdd.get(i).copied().unwrap_or(0.0)
    }
}

/// A platform sine dwell `x = X·sin(ωt)` under a quintic fade-in, for transmissibility.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlatformSine {
    /// Position amplitude \[m\].
    pub amplitude_m: f64,
    /// Frequency \[Hz\].
    pub freq_hz: f64,
    /// Fade-in duration \[s\].
    pub fade_in_s: f64,
}

/// Quintic smooth step `w(t)` on `[0, T]` and its first two derivatives (w, w', w'' = 0 at 0).
pub(crate) fn smoothstep(t: f64, t_fade: f64) -> (f64, f64, f64) {
    if t_fade <= 0.0 || t >= t_fade {
        return (1.0, 0.0, 0.0);
    }
    if t <= 0.0 {
        return (0.0, 0.0, 0.0);
    }
    let s = t / t_fade;
    let w = s * s * s * (10.0 - 15.0 * s + 6.0 * s * s);
    let w1 = 30.0 * s * s * (1.0 - s) * (1.0 - s) / t_fade;
    let w2 = 60.0 * s * (1.0 - s) * (1.0 - 2.0 * s) / (t_fade * t_fade);
    (w, w1, w2)
}

/// Applies a fade-in window to a motion by the product rule, so x, ẋ, ẍ stay consistent.
fn faded(t: f64, t_fade: f64, m: PlatformSample) -> PlatformSample {
    let (w, w1, w2) = smoothstep(t, t_fade);
    PlatformSample {
        x: w * m.x,
        xd: w1 * m.x + w * m.xd,
        xdd: w2 * m.x + 2.0 * w1 * m.xd + w * m.xdd,
    }
}

impl PlatformSine {
    /// Motion at `t`.
    pub fn at(&self, t: f64) -> PlatformSample {
        let w = 2.0 * PI * self.freq_hz;
        let a = self.amplitude_m;
        let (s, c) = (w * t).sin_cos();
        faded(
            t,
            self.fade_in_s,
            PlatformSample {
                x: a * s,
                xd: a * w * c,
                xdd: -a * w * w * s,
            },
        )
    }
}

/// What the platform does.
#[derive(Debug, Clone, PartialEq)]
pub enum PlatformMotion {
    /// Platform still (valve tests).
    Still,
    /// Cycloidal bump.
    Cycloid(Cycloid),
    /// Sine dwell (transmissibility by simulation).
    Sine(PlatformSine),
    /// Sampled record (random ride, CSV excitation).
    Sampled(SampledMotion),
    /// The acceleration given at one instant with its time derivatives, extrapolated by its
    /// Taylor polynomial (an FMU's input over a communication step).
    Extrapolated(InputSegment),
}

impl PlatformMotion {
    /// A sampled motion `by` \[s\] earlier ([`SampledMotion::advanced`]); any other motion,
    /// known at every instant rather than measured, as it is.
    pub fn advanced(self, by: f64) -> Self {
        match self {
            PlatformMotion::Sampled(m) if by != 0.0 => PlatformMotion::Sampled(m.advanced(by)),
            other => other,
        }
    }
}

/// A platform acceleration known at `t0` with its first three time derivatives, read at
/// `t ≥ t0` as `ẍ(t) = Σ dᵢ·(t − t0)ⁱ/i!` (a held value when the derivatives are zero). The
/// position is reported as given; the velocity is not known (NaN).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct InputSegment {
    /// Time the values are given at \[s\].
    pub t0: f64,
    /// Platform position at `t0` \[m\] (reported only).
    pub x: f64,
    /// `ẍ(t0)` [m/s²] and its derivatives of order 1, 2, 3 [m/s³, m/s⁴, m/s⁵].
    pub xdd: [f64; 4],
}

impl InputSegment {
    /// Acceleration at `t` [m/s²].
    #[inline(always)]
    pub fn xdd_at(&self, t: f64) -> f64 {
        let d = t - self.t0;
        let [a0, a1, a2, a3] = self.xdd;
        if a1 == 0.0 && a2 == 0.0 && a3 == 0.0 {
            return a0;
        }
        a0 + d * (a1 + d * (a2 / 2.0 + d * (a3 / 6.0)))
    }
}

impl PlatformMotion {
    /// Motion at time `t`.
    #[inline]
    pub fn at(&self, t: f64) -> PlatformSample {
        match self {
            PlatformMotion::Still => PlatformSample::default(),
            PlatformMotion::Cycloid(c) => c.at(t),
            PlatformMotion::Sine(s) => s.at(t),
            PlatformMotion::Sampled(s) => s.at(t),
            PlatformMotion::Extrapolated(e) => PlatformSample {
                x: e.x,
                xd: f64::NAN,
                xdd: e.xdd_at(t),
            },
        }
    }

    /// Acceleration at time `t` (hot path).
    #[inline(always)]
    pub fn xdd_at(&self, t: f64) -> f64 {
        match self {
            PlatformMotion::Still => 0.0,
            PlatformMotion::Sampled(s) => s.xdd_at(t),
            PlatformMotion::Extrapolated(e) => e.xdd_at(t),
            other => other.at(t).xdd,
        }
    }

    /// Record samples per step `h` \[s\] when this is a record sampled on a grid that the
    /// step lands on exactly (`h` a whole multiple of its sample step): then grid times can be
    /// read from the samples themselves ([`Self::at_grid`]).
    pub fn grid_stride(&self, h: f64) -> Option<usize> {
        match self {
            PlatformMotion::Sampled(s) => {
                let k = h / s.dt();
                let r = k.round();
                (r >= 1.0 && (k - r).abs() < 1e-9 * r).then_some(r as usize)
            }
            _ => None,
        }
    }

    /// Motion at the grid time `n·h` \[s\]; with `stride` from [`Self::grid_stride`] a record's
    /// own samples (what the interpolation gives there, without its cost).
    #[inline(always)]
    pub fn at_grid(&self, n: u64, h: f64, stride: Option<usize>) -> PlatformSample {
        match (self, stride) {
            (PlatformMotion::Sampled(s), Some(k)) => s.at_sample(n as usize * k),
            _ => self.at(n as f64 * h),
        }
    }

    /// Acceleration at the grid time `n·h` \[s\] (see [`Self::at_grid`]).
    #[inline(always)]
    pub fn xdd_at_grid(&self, n: u64, h: f64, stride: Option<usize>) -> f64 {
        match (self, stride) {
            (PlatformMotion::Sampled(s), Some(k)) => s.xdd_at_sample(n as usize * k),
            _ => self.xdd_at(n as f64 * h),
        }
    }
}

/// Generation rate of the random ride \[Hz\] (the band is ≤ 200 Hz; interpolation is cubic).
pub const RANDOM_RIDE_RATE_HZ: f64 = 1000.0;

impl RandomRide {
    /// Checks the ride's fields.
    pub fn validate(&self) -> Result<(), crate::params::ParamError> {
        use crate::params::check;
        check("random.s0", self.s0, 0.0, 10.0, "(m/s²)²/Hz")?;
        check("random.f_low_hz", self.f_low_hz, 0.05, 100.0, "Hz")?;
        check(
            "random.f_high_hz",
            self.f_high_hz,
            self.f_low_hz + 1e-3,
            200.0,
            "Hz",
        )?;
        check("random.duration_s", self.duration_s, 1.0, 3600.0, "s")?;
        check(
            "random.fade_in_s",
            self.fade_in_s,
            0.0,
            self.duration_s / 2.0,
            "s",
        )?;
        Ok(())
    }

    /// Generates the record: Gaussian Fourier coefficients on the record's frequency grid
    /// within the band (one-sided PSD `S0`), exact spectral integration to velocity and
    /// position, then a quintic fade-in applied by the product rule so the platform starts
    /// at rest with consistent x, ẋ, ẍ.
    pub fn generate(&self) -> SampledMotion {
        let fs = RANDOM_RIDE_RATE_HZ;
        let n = ((self.duration_s * fs).ceil() as usize + 4).max(16);
        let n = n + (n % 2); // even length for the real FFT
        let df = fs / n as f64;
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed);
        let mut planner = RealFftPlanner::<f64>::new();
        let c2r = planner.plan_fft_inverse(n);
        let mut spec_a = c2r.make_input_vec();
        let mut spec_v = c2r.make_input_vec();
        let mut spec_x = c2r.make_input_vec();
        let sigma = (self.s0 * df).sqrt();
        for (k, ((a, v), x)) in spec_a
            .iter_mut()
            .zip(spec_v.iter_mut())
            .zip(spec_x.iter_mut())
            .enumerate()
        {
            let f = k as f64 * df;
            // Draw for every bin so that the band edges do not shift the random stream.
            let ca: f64 = StandardNormal.sample(&mut rng);
            let cb: f64 = StandardNormal.sample(&mut rng);
            if f < self.f_low_hz || f > self.f_high_hz || k == 0 || 2 * k == n {
                continue;
            }
            // term = a·cos + b·sin with a, b ~ N(0, σ²) ⇒ X_k = (a − i b)/2.
            let xk = num_complex::Complex64::new(ca * sigma / 2.0, -cb * sigma / 2.0);
            let w = 2.0 * PI * f;
            let jw = num_complex::Complex64::new(0.0, w);
            *a = xk;
            *v = xk / jw;
            *x = xk / (jw * jw);
        }
        let inverse = |spec: &mut Vec<num_complex::Complex64>| -> Vec<f64> {
            let mut out = c2r.make_output_vec();
            // The spectrum is valid by construction (zero DC and Nyquist), so this cannot fail.
            if c2r.process(spec, &mut out).is_err() {
                out.iter_mut().for_each(|v| *v = 0.0);
            }
            out
        };
        let xdd = inverse(&mut spec_a);
        let xd = inverse(&mut spec_v);
        let x = inverse(&mut spec_x);
        let dt = 1.0 / fs;
        SampledMotion::shaped(dt, &x, &xd, &xdd, |t, m| faded(t, self.fade_in_s, m))
    }
}

/// An open-loop valve command `V_in(t)` \[V\]; zero before t = 0.
#[derive(Debug, Clone, PartialEq)]
pub enum CommandSignal {
    /// No command.
    Zero,
    /// `A·cos(2πft)` from t = 0 (the sine tests; cosine so the stroke stays centred).
    Sine {
        /// Amplitude \[V\].
        amplitude_v: f64,
        /// Frequency \[Hz\].
        freq_hz: f64,
    },
    /// Linear chirp `A·cos(2π(f0·t + (f1 − f0)·t²/(2T)))` for `0 ≤ t ≤ T`, then zero.
    Chirp {
        /// Amplitude \[V\].
        amplitude_v: f64,
        /// Start frequency \[Hz\].
        f0_hz: f64,
        /// End frequency \[Hz\].
        f1_hz: f64,
        /// Sweep duration \[s\].
        duration_s: f64,
    },
    /// A sampled command (replayed records), read between its samples by the same cubic
    /// (Catmull–Rom) interpolation as sampled platform motion, held after the last. Why not
    /// linear: a rig's command is smooth between its samples (a cosine computed at the
    /// controller's rate, a filtered drive), and at 200 Hz a linear read of a 20 Hz sine test
    /// loses 3.3 % of its amplitude (Catmull–Rom 0.2 %), which a fit then blames on the plant.
    Sampled {
        /// Sample step \[s\].
        dt: f64,
        /// Samples from t = 0 \[V\].
        values: Arc<Vec<f64>>,
    },
    /// A command received sample by sample (an FMU's command input), linearly interpolated
    /// between its samples and held after the newest: the valve reads it τ late, as it reads
    /// the internal controller's command from its history.
    Streamed(CommandStream),
}

/// The recent samples of a command received as it goes, oldest first (see
/// [`CommandSignal::Streamed`]).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct CommandStream {
    samples: std::collections::VecDeque<(f64, f64)>,
}

impl CommandStream {
    /// Appends the sample `v` \[V\] at `t` \[s\] (after every earlier sample; one at the same
    /// time replaces it), forgetting the samples older than `keep_s` \[s\] before `t` except the
    /// newest of them.
    pub fn push(&mut self, t: f64, v: f64, keep_s: f64) {
        while self.samples.len() >= 2 && self.samples[1].0 <= t - keep_s {
            self.samples.pop_front();
        }
        if self.samples.back().is_some_and(|s| s.0 >= t) {
            self.samples.pop_back();
        }
        self.samples.push_back((t, v));
    }

    /// The command at `t` \[V\]: zero before the first sample, held after the newest.
    pub fn at(&self, t: f64) -> f64 {
        let Some(i) = self.samples.iter().rposition(|s| s.0 <= t) else {
            return 0.0;
        };
        let (t0, v0) = self.samples[i];
        match self.samples.get(i + 1) {
            Some(&(t1, v1)) => v0 + (t - t0) / (t1 - t0) * (v1 - v0),
            None => v0,
        }
    }
}

impl CommandSignal {
    /// Command at `t` \[V\].
    ///
    /// A sampled command (every replay of a record) is read here, inlined into the stepping
    /// loop, which reads it at every stage; the other kinds are read out of line.
    #[inline(always)]
    pub fn at(&self, t: f64) -> f64 {
        if t < 0.0 {
            return 0.0;
        }
        match self {
            CommandSignal::Sampled { dt, values } => catmull_rom(values, t / dt),
            other => other.at_formula(t),
        }
    }

    /// [`Self::at`] for every kind but a sampled one, at `t ≥ 0`.
    #[inline(never)]
    fn at_formula(&self, t: f64) -> f64 {
        match self {
            CommandSignal::Zero => 0.0,
            CommandSignal::Sine {
                amplitude_v,
                freq_hz,
            } => amplitude_v * (2.0 * PI * freq_hz * t).cos(),
            CommandSignal::Chirp {
                amplitude_v,
                f0_hz,
                f1_hz,
                duration_s,
            } => {
                if t > *duration_s {
                    0.0
                } else {
                    let phase = f0_hz * t + (f1_hz - f0_hz) * t * t / (2.0 * duration_s);
                    amplitude_v * (2.0 * PI * phase).cos()
                }
            }
            CommandSignal::Sampled { dt, values } => catmull_rom(values, t / dt),
            CommandSignal::Streamed(c) => c.at(t),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A sampled sine advanced by 2.8 ms reads the sine 2.8 ms later (the cubic read between
    /// samples, a 4 Hz motion at 200 Hz), held at the last sample at the end; a still platform
    /// or a zero advance is unchanged.
    #[test]
    fn an_advanced_motion_reads_the_motion_later() {
        let (dt, f, by) = (5e-3, 4.0, 2.8e-3);
        let w = 2.0 * PI * f;
        let n = 200;
        let at = |t: f64| ((w * t).sin(), w * (w * t).cos(), -w * w * (w * t).sin());
        let (x, xd, xdd): (Vec<f64>, Vec<f64>, Vec<f64>) = {
            let s: Vec<_> = (0..n).map(|i| at(i as f64 * dt)).collect();
            (
                s.iter().map(|v| v.0).collect(),
                s.iter().map(|v| v.1).collect(),
                s.iter().map(|v| v.2).collect(),
            )
        };
        let m = SampledMotion::new(dt, x, xd, xdd).advanced(by);
        for i in 1..n - 3 {
            let (want, _, want_dd) = at(i as f64 * dt + by);
            let got = m.at_sample(i);
            assert!((got.x - want).abs() < 2e-4, "{i}: {} vs {want}", got.x);
            assert!((got.xdd - want_dd).abs() < 2e-4 * w * w, "{i}");
        }
        let last = m.at_sample(n - 1);
        assert!((last.x - at((n - 1) as f64 * dt).0).abs() < 1e-12);
        assert!(matches!(
            PlatformMotion::Still.advanced(by),
            PlatformMotion::Still
        ));
    }

    #[test]
    fn grid_reads_are_the_interpolated_values_at_grid_times() {
        let m = PlatformMotion::Sampled(
            RandomRide {
                duration_s: 2.0,
                fade_in_s: 0.5,
                ..Default::default()
            }
            .generate(),
        );
        assert_eq!(m.grid_stride(1e-3), Some(1));
        assert_eq!(m.grid_stride(2e-3), Some(2));
        assert_eq!(m.grid_stride(5e-4), None);
        assert_eq!(PlatformMotion::Still.grid_stride(1e-3), None);
        for (h, stride) in [(1e-3, Some(1)), (2e-3, Some(2)), (5e-4, None)] {
            // Past the end (n·h > 2 s) both hold the last sample.
            for n in [0u64, 1, 7, 333, 999, 1000, 1001, 4000] {
                let (a, b) = (m.at_grid(n, h, stride), m.at(n as f64 * h));
                let tol = 1e-9 * (1.0 + b.xdd.abs());
                assert!(
                    (a.x - b.x).abs() < tol && (a.xd - b.xd).abs() < tol,
                    "n {n} h {h}"
                );
                assert!(
                    (a.xdd - b.xdd).abs() < tol,
                    "n {n} h {h}: {} vs {}",
                    a.xdd,
                    b.xdd
                );
                assert_eq!(m.xdd_at_grid(n, h, stride), a.xdd);
            }
        }
    }

    #[test]
    fn cycloid_is_consistent_and_reaches_height() {
        let c = Cycloid::default();
        assert_eq!(c.at(0.4), PlatformSample::default());
        assert!((c.at(1.2).x - 0.03).abs() < 1e-15);
        // Peak acceleration 2πH/T² at mid-rise.
        assert!((c.at(0.625).xdd - 2.0 * PI * 0.03 / 0.25).abs() < 1e-12);
        // ẋ is the derivative of x.
        let (t, h) = (0.7, 1e-6);
        let num = (c.at(t + h).x - c.at(t - h).x) / (2.0 * h);
        assert!((num - c.at(t).xd).abs() < 1e-8);
    }

    #[test]
    fn random_ride_has_the_requested_rms_and_starts_at_rest() {
        let ride = RandomRide {
            duration_s: 200.0,
            ..Default::default()
        };
        let m = ride.generate();
        let p0 = m.at(0.0);
        assert!(p0.x.abs() < 1e-12 && p0.xd.abs() < 1e-12 && p0.xdd.abs() < 1e-12);
        let fs = RANDOM_RIDE_RATE_HZ;
        let start = (ride.fade_in_s * fs) as usize;
        let a = &m.xdd[start..(ride.duration_s * fs) as usize];
        let rms = (a.iter().map(|v| v * v).sum::<f64>() / a.len() as f64).sqrt();
        // √(S0·B) = √(0.05·4.5) = 0.474 m/s²; a 200 s Gaussian record is within a few %.
        assert!((rms / 0.4743 - 1.0).abs() < 0.06, "rms {rms}");
        // Velocity is the integral of acceleration (spectral integration is exact).
        let i = 50_000;
        let num = (m.xd[i + 1] - m.xd[i - 1]) * fs / 2.0;
        assert!((num - m.xdd[i]).abs() < 1e-3, "{num} vs {}", m.xdd[i]);
    }

    #[test]
    fn same_seed_same_record() {
        let r = RandomRide {
            duration_s: 5.0,
            ..Default::default()
        };
        assert_eq!(r.generate(), r.generate());
        let other = RandomRide { seed: 2, ..r }.generate();
        assert_ne!(r.generate(), other);
    }
}
