//! Replay of a measured record through the twin, and the error metric.
//!
//! The record's `v_in` drives the valve in open loop (the command as sent, before the valve's
//! delay) and its platform motion (`xdd`, else `x`, else still) drives the base. The twin runs
//! on the record's time grid with the largest RK4 step ≤ `numerics.max_step_s` that divides the
//! sample step.
//!
//! **Conditioning of the measured excitation** ([`EXCITATION_CONDITIONING`]). The recorded
//! platform acceleration is not fed raw: it is low-passed at [`EXCITATION_LOWPASS_HZ`] with a
//! zero-phase 6th-order Butterworth filter (run forward and backward, so
//! `|H|² = 1/(1 + (f/20 Hz)¹²)`: flat to 1 % up to 13 Hz, −87 dB at 46 Hz, −140 dB at
//! 77 Hz). The twin's oil column is a mass on a fluid spring with almost no damping (about
//! 77 Hz, ζ ≈ 3·10⁻⁴ with the paper's parameters; about 46 Hz once a calibration lowers the
//! effective bulk modulus to 0.5 GPa): the accelerometer's white noise has power there, and
//! fed raw it makes the replayed `ÿ` ring at a hundred times the measured one. The cut-off was
//! 30 Hz until 2026-11-27 (flat to 20 Hz, −6 dB at 30 Hz, −44 dB at 46 Hz): the platform
//! accelerometer's noise between 20 and 40 Hz passed into the twin, and a calibrated twin with
//! compliance, its mode at 46 Hz, amplified it and rang there (the demo campaign's bump: the
//! replayed ÿ's content from 20 to 50 Hz 0.037 m/s² nominal, 0.049 calibrated, 0.018 of it
//! at the mode; raw ÿ error 0.094 m/s² calibrated against 0.088 nominal, noise 0.080; with
//! the 20 Hz cut-off 0.080 both). A
//! seat rig's platform motion (the ISO 7096, ISO 5007 and EN 13490 classes, a ride, a bump)
//! lies below 13 Hz, so the filter removes noise, not motion. A record with `x` but no `xdd`
//! is filtered the same way before its double difference. The record is extended at each
//! end by its point reflection over the filter's settling time
//! ([`crate::dsp::zero_phase_odd_padded`]): a platform still moving when the record starts
//! or stops is filtered there as in its middle. Each pass used to start settled at the end
//! value instead, and the twin's `ÿ` then left a quiet accelerometer's over the last tens of
//! milliseconds of a ride, enough for a false `unexplained` at 10 kHz.
//!
//! **Error metric.** Open-loop replay of a flow-controlled cylinder integrates every flow error
//! into a drift of `u`, so position is a poor thing to fit. The metric compares two channels
//! that do not integrate the error:
//!
//! * the relative velocity `u̇`, obtained from the measured `u` and from the twin's `u` by the
//!   *same* linear operator (zero-phase low-pass, then central difference), so quantisation
//!   and noise are smoothed identically on both sides;
//! * the body acceleration `ÿ` (when measured), through the same zero-phase low-pass;
//! * the chamber pressures `p1`, `p2` (only when the record has them), through the same
//!   low-pass. Records give them in Pa gauge, the convention of the twin's pressures (supply
//!   and return pressures of the preset are gauge too). Pressures are what separate effects
//!   that motion alone confounds: supply sag lowers the common-mode pressure `(p1 + p2)/2`
//!   with the drawn flow, friction shifts the load pressure `p1 − p2`, and at steady flow
//!   the two give the same velocity.
//!
//! All are decimated to about `eval_rate_hz`, and each residual is divided by
//! `max(σ_noise, floor·RMS(signal))` of its file and channel, where `σ_noise` is the sensor
//! noise estimated from the measured record itself (see [`crate::dsp::noise_floor`], the raw
//! error measure's estimate too) after the same filter. Until 2026-11-27 the weights used a
//! plain spectral estimate (the top 40 % of the unwindowed spectrum), which a record's drift
//! and start leak into: at 200 Hz it read the body accelerometer's noise 40 times too high
//! and the stroke sensor's 30 times, so the fit weighed `ÿ` and `u̇` at almost nothing and
//! a stroke drift (a valve offset) drove Cd to its bound. A calibration holds a campaign's
//! records against one noise per channel ([`share_sensor_noise`]). The reported error is the
//! RMS of these weighted residuals: 1 means the twin matches the record to the sensor noise.

use super::IdentifyError;
use crate::dataset::Record;
use crate::params::Params;
use crate::scenario::{CommandSignal, PlatformMotion, SampledMotion};
use crate::simulation::{Drive, Run, Sample, Simulation, step_for_rate};
use std::path::Path;
use std::sync::Arc;

use crate::dsp::{NoiseFloor, SettledCascade, noise_floor, noise_gain};
pub use crate::dsp::{butterworth_zero_phase, filtered_derivative, lowpass, rms};

mod errors;
mod step;
mod streamed;
pub use errors::{ChannelErrors, RawChannel, RawErrors};
pub use step::StepRule;
pub use streamed::{BeforeEndStop, StreamedErrors, replay_streamed};

/// Cut-off of the zero-phase low-pass applied to the recorded platform motion before it drives
/// the twin \[Hz\] (see the [module docs](self)); at most 0.3 × the sample rate.
pub const EXCITATION_LOWPASS_HZ: f64 = 20.0;

/// How the measured excitation is conditioned, and why (for file headers and reports).
pub const EXCITATION_CONDITIONING: &str = "platform xdd (or x) low-passed before it drives the \
twin: zero-phase 6th-order Butterworth at 20 Hz, run forward and backward (|H|^2 = \
1/(1+(f/20 Hz)^12); flat within 1 % to 13 Hz, -87 dB at 46 Hz, -140 dB at 77 Hz), the record \
extended at each end by its point reflection over the filter's settling time (0.62 s), so that \
a platform still moving when the record starts or stops is filtered there as in its middle; xd \
and x are its trapezoidal integrals. Why: the twin's oil-column mode (about 77 Hz, 46 Hz with an \
effective bulk modulus of 0.5 GPa; damping ratio about 3e-4) is almost undamped, and the \
accelerometer's white noise, fed raw, makes the replayed ydd ring far above the measured one; \
the platform motion of a seat rig lies below 13 Hz. v_in is used as recorded.";

/// The platform acceleration conditioned as the twin's replay uses it (see
/// [`EXCITATION_CONDITIONING`]).
pub fn condition_excitation(xdd: &[f64], dt: f64) -> Vec<f64> {
    let fc = EXCITATION_LOWPASS_HZ.min(0.3 / dt);
    let sections = crate::dsp::butterworth_sections(dt, fc, 6);
    let pad = crate::dsp::butterworth_settling_samples(dt, fc, 6);
    crate::dsp::zero_phase_odd_padded(xdd, &sections, pad)
}

/// Cut-off of the stroke-drift channel of the metric \[Hz\]: the raw error measure's band with
/// DC ([`super::raw_error::BANDS_HZ`]).
pub const DRIFT_LOWPASS_HZ: f64 = 0.5;

/// The resolution part of a band's floor in the raw error measure ([`super::raw_error`]; here
/// also in the stroke-drift channel's weight), relative to the measured channel's own content in
/// that band [-]: 0.1 %. The twin is stepped by RK4 at a fixed step, its delay interpolated
/// and its parameters fitted to finite precision; on the demo campaign's largest sine test
/// (13 mm at 10 Hz) that leaves 7 µm, 0.06 %, against a white-noise floor of 2 µm in the
/// 5–25 Hz band. The floor is `√(white² + (0.001·content)²)`, so a residual must be both
/// above the sensor's noise and above 0.1 % of what was measured in that band. For the band
/// with DC the content is the whole channel's swing about its mean: the open-loop replay of
/// an integrating plant turns a relative flow error at any frequency into drift (the same
/// record's start transient leaves 33 µm there against 9 mm of stroke swing).
pub const RESOLUTION: f64 = 1e-3;

/// Rate at which the stroke-drift channel is kept \[Hz\]: ten samples per period of its
/// cut-off, so that its slow residual does not outweigh the other channels by its count.
pub const DRIFT_EVAL_RATE_HZ: f64 = 5.0;

/// Signal-processing settings of the error metric.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MetricOptions {
    /// Cut-off of the zero-phase low-pass applied to measured and simulated channels \[Hz\].
    pub lowpass_hz: f64,
    /// Rate at which the filtered residual is kept \[Hz\] (decimation).
    pub eval_rate_hz: f64,
    /// Floor of a channel's weight scale, as a fraction of the measured channel's RMS.
    pub floor_fraction: f64,
}

impl Default for MetricOptions {
    fn default() -> Self {
        Self {
            lowpass_hz: 25.0,
            eval_rate_hz: 250.0,
            floor_fraction: 0.01,
        }
    }
}

/// The twin's channels replayed on a record's time grid (SI).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SimChannels {
    /// Time \[s\].
    pub t: Vec<f64>,
    /// Relative displacement \[m\].
    pub u: Vec<f64>,
    /// Relative velocity [m/s].
    pub du: Vec<f64>,
    /// Body acceleration [m/s²].
    pub ydd: Vec<f64>,
    /// Upper chamber pressure \[Pa\] (absolute model pressure, as the twin holds it).
    pub p1: Vec<f64>,
    /// Lower chamber pressure \[Pa\].
    pub p2: Vec<f64>,
    /// Spool position \[m\].
    pub xv: Vec<f64>,
    /// Hose-1 flow [m³/s].
    pub q1: Vec<f64>,
    /// Hose-2 flow [m³/s].
    pub q2: Vec<f64>,
}

impl SimChannels {
    /// The columns [`Self::write_csv`] writes.
    pub const CSV_COLUMNS: [&'static str; 8] = ["t", "u", "ydd", "p1", "p2", "xv", "q1", "q2"];
    /// Their units, for the `units` comment.
    pub const CSV_UNITS: &'static str =
        "t s, u m, ydd m/s^2, p1 Pa, p2 Pa, xv m, q1 m^3/s, q2 m^3/s";

    /// Writes the channels to `path` in the [dataset format](crate::dataset) with `comments`,
    /// atomically, one row per sample with its time from `t` (the replayed record's own time
    /// column, on whose grid the channels lie).
    pub fn write_csv(
        &self,
        t: &[f64],
        path: &Path,
        comments: &[(String, String)],
    ) -> std::io::Result<()> {
        let rows = (0..self.t.len()).map(|i| {
            vec![
                t[i],
                self.u[i],
                self.ydd[i],
                self.p1[i],
                self.p2[i],
                self.xv[i],
                self.q1[i],
                self.q2[i],
            ]
        });
        crate::dataset::write_csv_atomic(path, &Self::CSV_COLUMNS, comments, rows)
    }
}

/// The platform motion a record drives the twin's base with (its `xdd`, else its `x`,
/// conditioned: see [`EXCITATION_CONDITIONING`]), and whether the platform moved at all.
fn record_platform(record: &Record) -> (PlatformMotion, bool) {
    let dt = record.dt;
    // A platform channel that is indistinguishable from its own sensor noise means the
    // platform was still: replaying that noise would only add noise to the twin.
    let moving = |v: &Vec<f64>| {
        let n = noise_floor(v).rms;
        let mean = v.iter().sum::<f64>() / v.len().max(1) as f64;
        let dev: Vec<f64> = v.iter().map(|x| x - mean).collect();
        rms(&dev) > 3.0 * n.max(1e-15)
    };
    let xdd = record.xdd.as_ref().filter(|v| moving(v));
    let x = record.x.as_ref().filter(|v| moving(v));
    match (xdd, x) {
        (Some(xdd), _) => {
            let m = SampledMotion::from_acceleration(dt, condition_excitation(xdd, dt));
            let m = match &record.x {
                Some(x) => m.with_reported_position(x.clone()),
                None => m,
            };
            (PlatformMotion::Sampled(m), true)
        }
        (None, Some(x)) => (
            PlatformMotion::Sampled(SampledMotion::from_position(
                dt,
                condition_excitation(x, dt),
            )),
            true,
        ),
        (None, None) => (PlatformMotion::Still, false),
    }
}

/// Replays `len` samples at `dt` through the twin: `v_in` drives the valve in open loop and
/// `platform` the base; every sample on the record's grid goes to `sink`, the last repeated
/// (with its own time) if rounding of the last step left the run a sample short.
#[allow(clippy::too_many_arguments)]
fn replay_samples(
    params: &Params,
    rule: StepRule,
    dt: f64,
    v_in: Arc<Vec<f64>>,
    platform: PlatformMotion,
    len: usize,
    name: &str,
    sink: &mut dyn FnMut(Sample),
) -> Result<(), IdentifyError> {
    // Within the method's stability limit, and (but for screening) short enough to resolve
    // the friction.
    let h = step_for_rate(rule.largest_step_s(params), 1.0 / dt);
    // A proposed lag of the valve command filters the command as sent, a proposed drift of
    // the valve's null offsets it.
    let values = match params
        .plant
        .corrections
        .acted_command(&v_in, dt, params.plant.valve.tau_s)
    {
        Some(v) => Arc::new(v),
        None => v_in,
    };
    let drive = Drive::OpenLoop(CommandSignal::Sampled { dt, values });
    // The data acquisition's declared anti-alias filter: on the twin's measured channels,
    // run at every step (the analogue filter before the sampling), with a step of at most a
    // tenth of its corner's period; the platform's measured motion, filtered already,
    // advanced by the filter's delay. A corner above 5 times the sample rate is refused (it
    // is no anti-alias filter, and would ask for more than 50 steps a sample).
    let corner = params.sensors.antialias_hz;
    if corner > 5.0 / dt {
        return Err(IdentifyError::AntialiasAboveRate {
            file: name.to_string(),
            corner_hz: corner,
            rate_hz: 1.0 / dt,
        });
    }
    let acquisition = (corner > 0.0).then(|| {
        let h = step_for_rate(h.min(0.1 / corner), 1.0 / dt);
        let sections = params.sensors.antialias_sections(h).unwrap_or_default();
        (h, sections)
    });
    let (h, platform) = match &acquisition {
        Some((h_aa, _)) => (*h_aa, platform.advanced(params.sensors.antialias_delay_s())),
        None => (h, platform),
    };
    let mut sim = Simulation::twin(params, h, drive, platform);
    let every = (dt / h).round().max(1.0) as u64;
    let t_end = (len.saturating_sub(1)) as f64 * dt;
    let mut done = 0;
    // The state at rest until the run records its first sample (which it always does, at 0).
    let mut last = sim.sample();
    let mut record = |s: Sample| {
        if done < len {
            sink(s);
            last = s;
            done += 1;
        }
    };
    // One stepping loop for both (a second closure type would compile the whole hot loop
    // once more): without the filter it records every `every` steps; with it, it runs the
    // filter at every step and records every `every`-th filtered sample.
    let mut read = acquisition.map(|(_, sections)| Acquisition::new(&sections));
    let (run_every, keep_every) = if read.is_some() {
        (1, every)
    } else {
        (every, 1)
    };
    let mut step = 0u64;
    sim.run_until(t_end, run_every, |s| {
        let s = match &mut read {
            Some(r) => r.sample(s),
            None => s,
        };
        if step.is_multiple_of(keep_every) {
            record(s);
        }
        step += 1;
    })
    .map_err(|e| IdentifyError::Simulation {
        file: name.to_string(),
        source: e,
    })?;
    // Pad (rounding of the last step) so the channels align with the record exactly.
    for i in done..len {
        sink(Sample {
            t: i as f64 * dt,
            ..last
        });
    }
    Ok(())
}

/// The data acquisition's anti-alias filter on the twin's measured channels (u, u̇, ÿ, p1, p2
/// and the platform's x, ẋ, ẍ), sample by sample at the twin's step, each started settled at
/// its first value as a rig's filters are before a test. The valve's spool, the flows and the
/// time are internal and pass unchanged.
struct Acquisition {
    channels: [SettledCascade; 8],
}

impl Acquisition {
    fn new(sections: &[crate::dsp::Biquad]) -> Self {
        Self {
            channels: std::array::from_fn(|_| SettledCascade::new(sections.to_vec())),
        }
    }

    fn sample(&mut self, s: Sample) -> Sample {
        let [u, du, ydd, p1, p2, x, xd, xdd] = &mut self.channels;
        Sample {
            u: u.step(s.u),
            du: du.step(s.du),
            ydd: ydd.step(s.ydd),
            p1: p1.step(s.p1),
            p2: p2.step(s.p2),
            x: x.step(s.x),
            xd: xd.step(s.xd),
            xdd: xdd.step(s.xdd),
            ..s
        }
    }
}

/// A record made ready for repeated replays: inputs, filtered measured channels, weights.
#[derive(Debug, Clone)]
pub struct PreparedRecord {
    /// File name (for reports).
    pub name: String,
    /// Sample step \[s\].
    pub dt: f64,
    /// Number of samples.
    pub len: usize,
    /// Time \[s\].
    pub t: Vec<f64>,
    /// Command as sent \[V\].
    pub v_in: Arc<Vec<f64>>,
    /// Measured relative displacement \[m\].
    pub u: Vec<f64>,
    /// Measured body acceleration [m/s²], if recorded.
    pub ydd: Option<Vec<f64>>,
    /// Platform motion driving the base.
    pub platform: PlatformMotion,
    /// Whether the platform moved (an `x` or `xdd` column above its own noise).
    pub platform_moves: bool,
    /// Decimation factor of the metric.
    pub decimate: usize,
    /// Filtered, differentiated measured `u` at every sample [m/s].
    pub du_meas_f: Vec<f64>,
    /// Filtered measured `ÿ` at every sample [m/s²].
    pub ydd_meas_f: Option<Vec<f64>>,
    /// Weight scale of the velocity channel [m/s].
    pub scale_du: f64,
    /// Weight scale of the acceleration channel [m/s²].
    pub scale_ydd: f64,
    /// Estimated noise RMS of the raw `u` \[m\].
    pub noise_u: f64,
    /// Estimated noise RMS of the raw `ÿ` [m/s²] (0 without the channel).
    pub noise_ydd: f64,
    /// Filtered measured chamber pressures `p1`, `p2` [Pa gauge], each if recorded.
    pub p_meas_f: [Option<Vec<f64>>; 2],
    /// Weight scales of the pressure channels \[Pa\] (1 without the channel).
    pub scale_p: [f64; 2],
    /// Estimated noise RMS of the raw pressures \[Pa\] (0 without the channel).
    pub noise_p: [f64; 2],
    /// Noise floor of the raw `u` (the raw error measure, [`super::raw_error`]).
    pub floor_u: NoiseFloor,
    /// Noise floor of the raw `ÿ` (zero without the channel).
    pub floor_ydd: NoiseFloor,
    /// Noise floors of the raw `p1`, `p2` (zero without the channel).
    pub floor_p: [NoiseFloor; 2],
    /// Measured `u` through the zero-phase drift low-pass ([`DRIFT_LOWPASS_HZ`]) \[m\].
    pub u_drift_meas: Vec<f64>,
    /// Weight scale of the stroke-drift channel \[m\]: the raw error measure's floor of `u` in
    /// its band with DC (noise `σ_u` with 0.1 % of the stroke's swing,
    /// [`RESOLUTION`]).
    pub scale_u_drift: f64,
    /// Decimation of the stroke-drift channel (to about [`DRIFT_EVAL_RATE_HZ`]).
    pub drift_decimate: usize,
    /// Low-pass cut-off used \[Hz\].
    pub lowpass_hz: f64,
    /// Raw measured chamber pressures `p1`, `p2` [Pa gauge], each if recorded.
    pub p_raw: [Option<Vec<f64>>; 2],
    /// The samples whose residuals count (the whole record unless the record is split in
    /// time for validation, see [`Self::windowed`]); the replay always covers the whole record.
    pub window: std::ops::Range<usize>,
    /// The record's discharge coefficient relative to the campaign's [-]: 1, unless a drift of
    /// Cd through the campaign was established ([`super::drift`]); then the record's own value
    /// over the campaign value, so that every replay of the record (fits, verdict, report)
    /// uses its own Cd while the fitted `valve.cd` stays the campaign value.
    pub cd_factor: f64,
}

/// Holds the fit's residuals of a campaign's records against one sensor noise per channel
/// and sample rate: the smallest of the records' own estimates. The same stroke sensor,
/// accelerometer and pressure transducers record every test of a campaign, and a record's
/// estimate ([`noise_floor`]) can only be raised by its signal, never lowered: at 200 Hz the
/// 10 and 20 Hz tests' ÿ harmonics fill the top of the band and their own estimates read 7–12
/// times the accelerometer's noise, which weighed their ÿ (and an accelerometer's scale
/// error) at almost nothing. Records at different rates keep their own (a sensor's noise per
/// sample depends on its filter and the rate). The verdict's floors stay each record's own.
pub fn share_sensor_noise(records: &mut [PreparedRecord], opt: &MetricOptions) {
    let smallest = |of: &dyn Fn(&PreparedRecord) -> f64, dt: f64, recs: &[PreparedRecord]| {
        recs.iter()
            .filter(|r| (r.dt / dt - 1.0).abs() < 1e-6)
            .map(of)
            .filter(|n| *n > 0.0)
            .fold(f64::INFINITY, f64::min)
    };
    let shared: Vec<(f64, f64, [f64; 2])> = records
        .iter()
        .map(|r| {
            let keep = |own: f64, campaign: f64| if campaign.is_finite() { campaign } else { own };
            (
                keep(r.noise_u, smallest(&|q| q.noise_u, r.dt, records)),
                keep(r.noise_ydd, smallest(&|q| q.noise_ydd, r.dt, records)),
                [0, 1].map(|i| keep(r.noise_p[i], smallest(&|q| q.noise_p[i], r.dt, records))),
            )
        })
        .collect();
    for (r, (u, ydd, p)) in records.iter_mut().zip(shared) {
        r.noise_u = u;
        if r.noise_ydd > 0.0 {
            r.noise_ydd = ydd;
        }
        for (own, campaign) in r.noise_p.iter_mut().zip(p) {
            if *own > 0.0 {
                *own = campaign;
            }
        }
        r.weigh(opt.floor_fraction);
    }
}

impl PreparedRecord {
    /// Prepares a record (which must have `v_in` and `u`).
    pub fn new(record: &Record, opt: &MetricOptions) -> Result<Self, IdentifyError> {
        let name = record
            .path
            .file_name()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| record.path.display().to_string());
        let missing = |col: &str| IdentifyError::MissingColumn {
            file: record.path.clone(),
            column: col.to_string(),
        };
        let v_in = record.v_in.clone().ok_or_else(|| missing("v_in"))?;
        let u = record.u.clone().ok_or_else(|| missing("u"))?;
        let dt = record.dt;
        let (platform, platform_moves) = record_platform(record);
        let fs = 1.0 / dt;
        let lowpass_hz = opt.lowpass_hz.min(0.4 * fs);
        let decimate = ((fs / opt.eval_rate_hz).round() as usize).max(1);
        let du_meas_f = filtered_derivative(&u, dt, lowpass_hz);
        let ydd_meas_f = record.ydd.as_ref().map(|y| lowpass(y, dt, lowpass_hz));
        let floor_u = noise_floor(&u);
        let noise_u = floor_u.rms;
        let u_drift_meas = butterworth_zero_phase(&u, dt, DRIFT_LOWPASS_HZ.min(0.3 / dt), 2);
        let u_mean = u.iter().sum::<f64>() / u.len().max(1) as f64;
        let u_swing = rms(&u.iter().map(|v| v - u_mean).collect::<Vec<_>>());
        let scale_u_drift = floor_u.rms.hypot(RESOLUTION * u_swing).max(1e-9);
        let drift_decimate = ((fs / DRIFT_EVAL_RATE_HZ).round() as usize).max(1);
        let floor_ydd = record.ydd.as_deref().map(noise_floor).unwrap_or_default();
        let noise_ydd = floor_ydd.rms;
        let mut p_meas_f = [None, None];
        let p_raw = [record.p1.clone(), record.p2.clone()];
        let floor_p = p_raw
            .each_ref()
            .map(|p| p.as_deref().map(noise_floor).unwrap_or_default());
        for (f, raw) in p_meas_f.iter_mut().zip(&p_raw) {
            *f = raw.as_ref().map(|p| lowpass(p, dt, lowpass_hz));
        }
        let mut prepared = Self {
            name,
            dt,
            len: record.len(),
            t: record.t.iter().map(|t| t - record.t[0]).collect(),
            v_in: Arc::new(v_in),
            u,
            ydd: record.ydd.clone(),
            platform,
            platform_moves,
            decimate,
            du_meas_f,
            ydd_meas_f,
            scale_du: 1.0,
            scale_ydd: 1.0,
            noise_u,
            noise_ydd,
            p_meas_f,
            scale_p: [1.0; 2],
            noise_p: floor_p.map(|f| f.rms),
            floor_u,
            u_drift_meas,
            scale_u_drift,
            drift_decimate,
            floor_ydd,
            floor_p,
            lowpass_hz,
            p_raw,
            window: 0..record.len(),
            cd_factor: 1.0,
        };
        prepared.weigh(opt.floor_fraction);
        Ok(prepared)
    }

    /// Sets the channels' weight scales from the noise estimates the record holds: each is
    /// `max(noise through the metric's filter, floor_fraction · RMS of the filtered channel)`
    /// (for the pressures, of its swing about the mean: the mean pressure, tens of bar, says
    /// nothing about how well the twin follows it).
    fn weigh(&mut self, floor_fraction: f64) {
        let (dt, fc) = (self.dt, self.lowpass_hz);
        let gain_du = noise_gain(self.len, |x| filtered_derivative(x, dt, fc));
        let gain_y = noise_gain(self.len, |x| lowpass(x, dt, fc));
        self.scale_du = (self.noise_u * gain_du)
            .max(floor_fraction * rms(&self.du_meas_f))
            .max(1e-9);
        self.scale_ydd = self
            .ydd_meas_f
            .as_ref()
            .map(|y| {
                (self.noise_ydd * gain_y)
                    .max(floor_fraction * rms(y))
                    .max(1e-6)
            })
            .unwrap_or(1.0);
        for ((scale, f), noise) in self
            .scale_p
            .iter_mut()
            .zip(&self.p_meas_f)
            .zip(self.noise_p)
        {
            *scale = f.as_ref().map_or(1.0, |f| {
                let mean = f.iter().sum::<f64>() / f.len().max(1) as f64;
                let swing = (f.iter().map(|v| (v - mean).powi(2)).sum::<f64>()
                    / f.len().max(1) as f64)
                    .sqrt();
                (noise * gain_y).max(floor_fraction * swing).max(1.0)
            });
        }
    }

    /// The same record with only the samples in `window` counted in its residuals and errors.
    pub fn windowed(&self, window: std::ops::Range<usize>) -> Self {
        let mut r = self.clone();
        r.window = window.start.min(self.len)..window.end.min(self.len);
        r
    }

    /// Sample indices of the decimated residual (within the window).
    fn eval_indices(&self) -> std::iter::StepBy<std::ops::Range<usize>> {
        self.window.clone().step_by(self.decimate.max(1))
    }

    /// Duration \[s\].
    pub fn duration_s(&self) -> f64 {
        (self.len.saturating_sub(1)) as f64 * self.dt
    }

    /// Number of weighted residuals this record contributes.
    pub fn residual_len(&self) -> usize {
        let k = self.window.len().div_ceil(self.decimate.max(1));
        let channels = 1
            + usize::from(self.ydd_meas_f.is_some())
            + self.p_meas_f.iter().filter(|p| p.is_some()).count();
        channels * k + self.window.len().div_ceil(self.drift_decimate.max(1))
    }

    /// Replays the record through the twin with `params`.
    pub fn simulate(&self, params: &Params) -> Result<SimChannels, IdentifyError> {
        self.simulate_with(params, StepRule::Resolving)
    }

    /// Replays the record through the twin with `params`, at the step `rule` allows.
    pub fn simulate_with(
        &self,
        params: &Params,
        rule: StepRule,
    ) -> Result<SimChannels, IdentifyError> {
        let n = self.len;
        let mut out = SimChannels {
            t: Vec::with_capacity(n),
            u: Vec::with_capacity(n),
            du: Vec::with_capacity(n),
            ydd: Vec::with_capacity(n),
            p1: Vec::with_capacity(n),
            p2: Vec::with_capacity(n),
            xv: Vec::with_capacity(n),
            q1: Vec::with_capacity(n),
            q2: Vec::with_capacity(n),
        };
        let (v_in, platform) = (self.v_in.clone(), self.platform.clone());
        let mut own = *params;
        own.plant.valve.cd *= self.cd_factor;
        replay_samples(
            &own,
            rule,
            self.dt,
            v_in,
            platform,
            n,
            &self.name,
            &mut |s| {
                out.t.push(s.t);
                out.u.push(s.u);
                out.du.push(s.du);
                out.ydd.push(s.ydd);
                out.p1.push(s.p1);
                out.p2.push(s.p2);
                out.xv.push(s.xv);
                out.q1.push(s.q1);
                out.q2.push(s.q2);
            },
        )?;
        // Read u and ÿ through the calibrated sensors.
        params.sensors.read_u(&mut out.u, self.dt);
        params.sensors.read_ydd(&mut out.ydd);
        Ok(out)
    }
}

/// A record's name, with the part when it is windowed.
pub(super) fn part_name(r: &PreparedRecord) -> String {
    if r.window.len() == r.len {
        r.name.clone()
    } else {
        format!(
            "{} [{:.3}–{:.3} s]",
            r.name,
            r.window.start as f64 * r.dt,
            r.window.end.saturating_sub(1) as f64 * r.dt
        )
    }
}

/// One record replayed through the twin: the simulated channels aligned with the record and
/// the residuals (twin − measured).
#[derive(Debug, Clone)]
pub struct Replay {
    /// The twin's channels on the record's grid.
    pub sim: SimChannels,
    /// Residual of `u` \[m\] at every sample.
    pub residual_u: Vec<f64>,
    /// Residual of the filtered relative velocity [m/s] at every sample.
    pub residual_du: Vec<f64>,
    /// Residual of the filtered body acceleration [m/s²] at every sample, if measured.
    pub residual_ydd: Option<Vec<f64>>,
    /// Measured filtered velocity [m/s] (for plots).
    pub measured_du: Vec<f64>,
    /// Measured filtered body acceleration [m/s²] (for plots).
    pub measured_ydd: Option<Vec<f64>>,
    /// Twin's filtered velocity [m/s].
    pub twin_du: Vec<f64>,
    /// Twin's filtered body acceleration [m/s²].
    pub twin_ydd: Vec<f64>,
    /// RMS errors per channel.
    pub errors: ChannelErrors,
}

/// Replays one prepared record and computes its residuals.
pub fn replay_prepared(params: &Params, rec: &PreparedRecord) -> Result<Replay, IdentifyError> {
    let sim = rec.simulate(params)?;
    let twin_du = filtered_derivative(&sim.u, rec.dt, rec.lowpass_hz);
    let twin_ydd = lowpass(&sim.ydd, rec.dt, rec.lowpass_hz);
    let residual_du = twin_du
        .iter()
        .zip(&rec.du_meas_f)
        .map(|(a, b)| a - b)
        .collect();
    let residual_ydd = rec
        .ydd_meas_f
        .as_ref()
        .map(|ym| twin_ydd.iter().zip(ym).map(|(a, b)| a - b).collect());
    let residual_u = sim.u.iter().zip(&rec.u).map(|(a, b)| a - b).collect();
    let errors = rec.channel_errors(&sim);
    Ok(Replay {
        residual_u,
        residual_du,
        residual_ydd,
        measured_du: rec.du_meas_f.clone(),
        measured_ydd: rec.ydd_meas_f.clone(),
        twin_du,
        twin_ydd,
        errors,
        sim,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The written replay holds the record's times and the twin's channels, number for
    /// number, in the documented columns.
    #[test]
    fn a_replay_written_to_csv_reads_back_number_for_number() {
        let n = 50;
        let ch = |k: f64| {
            (0..n)
                .map(|i| k * (i as f64 + 0.5).sin())
                .collect::<Vec<f64>>()
        };
        let sim = SimChannels {
            t: (0..n).map(|i| i as f64 * 1e-3).collect(),
            u: ch(0.01),
            du: ch(0.2),
            ydd: ch(3.0),
            p1: ch(55e5),
            p2: ch(-54e5),
            xv: ch(1e-4),
            q1: ch(3e-4),
            q2: ch(-3e-4),
        };
        // The record's own times (printed rounded in a file) are the ones written.
        let t: Vec<f64> = (0..n).map(|i| 0.5 + i as f64 * 1.0001e-3).collect();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("replay.csv");
        sim.write_csv(&t, &path, &[("model".into(), "twin".into())])
            .unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        let mut lines = text.lines();
        assert_eq!(lines.next(), Some("# model: twin"));
        assert_eq!(lines.next(), Some("t,u,ydd,p1,p2,xv,q1,q2"));
        let rows: Vec<Vec<f64>> = lines
            .map(|l| l.split(',').map(|c| c.parse().unwrap()).collect())
            .collect();
        assert_eq!(rows.len(), n);
        for (i, row) in rows.iter().enumerate() {
            let expected = [
                t[i], sim.u[i], sim.ydd[i], sim.p1[i], sim.p2[i], sim.xv[i], sim.q1[i], sim.q2[i],
            ];
            assert_eq!(row.as_slice(), expected.as_slice(), "row {i}");
        }
    }

    /// The excitation filter does what its documentation states: flat within 1 % to 13 Hz,
    /// −6 dB at 20 Hz (the combined gain of both passes, |H|²), −87 dB at the 46 Hz mode of a
    /// twin with compliance, −140 dB at the paper twin's 77 Hz mode.
    #[test]
    fn excitation_filter_passes_the_rig_band_and_kills_the_oil_column_mode() {
        let dt = 1e-3;
        let n = 20_000;
        let gain = |f: f64| {
            let x: Vec<f64> = (0..n)
                .map(|i| (2.0 * std::f64::consts::PI * f * i as f64 * dt).sin())
                .collect();
            let y = condition_excitation(&x, dt);
            let mid = n / 4..3 * n / 4;
            rms(&y[mid.clone()]) / rms(&x[mid])
        };
        assert!((gain(5.0) - 1.0).abs() < 1e-3, "{}", gain(5.0));
        assert!((gain(13.0) - 1.0).abs() < 0.01, "{}", gain(13.0));
        assert!((gain(20.0) - 0.5).abs() < 0.01, "{}", gain(20.0));
        assert!(gain(46.0) < 1e-4, "{}", gain(46.0));
        assert!(gain(77.0) < 1e-6, "{}", gain(77.0));
    }
}
