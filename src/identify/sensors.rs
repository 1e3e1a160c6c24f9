//! The sensor properties a calibration reports: those more than 3σ from exact, and those
//! within 3σ that the calibrated twin's raw error needs.

use super::IdentifyError;
use super::evaluate::replay_all;
use super::fit::{FitResult, FittedValue};
use super::raw_error::{RawErrorReport, raw_error_report};
use super::replay::{PreparedRecord, Replay};
use super::result::SensorEstimate;
use crate::params::Params;

/// Sensor properties of `fit` within 3σ of exact are exact: set back in its parameters, not
/// applied, not listed. Returns the others, as reported, and a note for each one set back
/// (its estimate, so that a property near the limit of detection is not silently lost).
/// The report stage keeps them as estimated after all where, set back, they leave the
/// calibrated twin's raw error above its floor and, as estimated, they do not (survey draw
/// 2020, case 4: an accelerometer scale of 1.005 estimated at 1.0050 ± 0.0024).
pub(super) fn set_back_exact_sensors(fit: &mut FitResult) -> (Vec<SensorEstimate>, Vec<String>) {
    let mut sensors = Vec::new();
    let mut notes = Vec::new();
    for v in &fit.values {
        if let Some((channel, kind, exact)) = v.knob.sensor() {
            if (v.value - exact).abs() > 3.0 * v.std && v.std.is_finite() {
                sensors.extend(estimate_of(v));
            } else {
                if v.std.is_finite() {
                    // In the parameter table's display unit (a lag in ms).
                    let name = v.knob.name();
                    notes.push(format!(
                        "sensor {channel} {kind}: estimated {}, {:.1}σ from exact ({}), \
                         within 3σ: not reported, the replays take it as exact",
                        super::units::format_parameter(name, v.value, v.std),
                        (v.value - exact).abs() / v.std,
                        super::units::format_value(name, exact),
                    ));
                }
                v.knob.spec().set_unchecked(&mut fit.params, exact);
            }
        }
    }
    (sensors, notes)
}

/// The calibrated twin with the sensor properties within 3σ of exact that its raw error
/// needs kept as estimated.
pub(super) struct KeptSensors {
    pub fit: FitResult,
    pub replays: Vec<Replay>,
    pub raw: RawErrorReport,
    pub sensors: Vec<SensorEstimate>,
    pub note: String,
}

/// Where setting the sensor properties within 3σ of exact back to exact left the calibrated
/// twin's raw error above its floor (`set_back`), whether keeping them as estimated
/// (`estimated`: every property with a finite uncertainty as the fit found it) brings it
/// there. Then each is tried exact again, nearest to exact first, and set back where the twin
/// stays at its floor without it: only the properties the raw error needs are kept (a stroke
/// lag of 0.17 ± 0.42 ms on a rig without one went along with an accelerometer scale of
/// 1.0072 ± 0.0025 until this step; survey draw 2021, case 10). `None` when keeping them
/// does not bring the twin to its floor.
pub(super) fn keep_needed_sensors(
    estimated: &FitResult,
    set_back: &RawErrorReport,
    all: &[PreparedRecord],
    limit: f64,
) -> Result<Option<KeptSensors>, IdentifyError> {
    let raw_of = |params: &Params| -> Result<(Vec<Replay>, RawErrorReport), IdentifyError> {
        let replays = replay_all(params, all)?;
        let sims: Vec<_> = replays.iter().map(|r| &r.sim).collect();
        let raw = raw_error_report(all, &sims, limit);
        Ok((replays, raw))
    };
    let (mut replays, mut raw) = raw_of(&estimated.params)?;
    if !raw.at_floor() {
        return Ok(None);
    }
    let mut within: Vec<(&FittedValue, f64, f64)> = estimated
        .values
        .iter()
        .filter_map(|v| {
            let (_, _, exact) = v.knob.sensor()?;
            let z = (v.value - exact).abs() / v.std;
            (v.std.is_finite() && z <= 3.0).then_some((v, exact, z))
        })
        .collect();
    within.sort_by(|a, b| a.2.total_cmp(&b.2));
    let mut fit = estimated.clone();
    let mut back = Vec::new();
    for (v, exact, _) in &within {
        let mut trial = fit.params;
        v.knob.spec().set_unchecked(&mut trial, *exact);
        let (r, w) = raw_of(&trial)?;
        if w.at_floor() {
            fit.params = trial;
            (replays, raw) = (r, w);
            back.push(v.knob);
        }
    }
    let listed = |keep: bool| {
        within
            .iter()
            .filter(|(v, _, _)| back.contains(&v.knob) != keep)
            .map(|(v, _, _)| super::units::format_parameter(v.knob.name(), v.value, v.std))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let mut note = format!(
        "sensor properties within 3σ of exact kept as estimated ({}): with them exact the \
         calibrated twin leaves {}; as estimated, {}",
        listed(true),
        set_back.summary(),
        raw.summary()
    );
    if !back.is_empty() {
        note.push_str(&format!(
            "; set back to exact, since the twin stays at its floor without them: {}",
            listed(false)
        ));
    }
    let sensors = sensor_estimates(estimated)
        .into_iter()
        .filter(|e| {
            !within.iter().any(|(v, _, _)| {
                back.contains(&v.knob)
                    && v.knob
                        .sensor()
                        .is_some_and(|(c, k, _)| c == e.channel && k == e.kind)
            })
        })
        .collect();
    Ok(Some(KeptSensors {
        fit,
        replays,
        raw,
        sensors,
        note,
    }))
}

/// Every sensor property of `fit` with a finite uncertainty, as estimated.
fn sensor_estimates(fit: &FitResult) -> Vec<SensorEstimate> {
    fit.values
        .iter()
        .filter(|v| v.std.is_finite())
        .filter_map(estimate_of)
        .collect()
}

/// `v` as a sensor estimate, if it is a sensor property.
fn estimate_of(v: &FittedValue) -> Option<SensorEstimate> {
    v.knob.sensor().map(|(channel, kind, _)| SensorEstimate {
        channel: channel.into(),
        kind: kind.into(),
        value: v.value,
        uncertainty: v.std,
    })
}

/// `fit` with every sensor property it could size (a finite uncertainty) as estimated and
/// the others exact: the twin [`keep_needed_sensors`] tries.
pub(super) fn with_sized_sensors(fit: &FitResult) -> FitResult {
    let mut sized = fit.clone();
    for v in &fit.values {
        if let Some((_, _, exact)) = v.knob.sensor().filter(|_| !v.std.is_finite()) {
            v.knob.spec().set_unchecked(&mut sized.params, exact);
        }
    }
    sized
}
