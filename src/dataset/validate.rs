//! Checks of a parsed record: uniform sampling, the sample rate its kind allows, and
//! warnings for values that are allowed but far outside what the rig produces.

use super::columns::RecordKind;
use super::error::{DatasetError, fmt_num, quote, sig};
use super::lines::LineMap;
use super::{DT_ABS_TOLERANCE_S, DT_REL_TOLERANCE};
use std::path::Path;

/// Relative slack on the sample-rate limits, for the rounding of printed times.
const RATE_SLACK: f64 = 1e-6;
/// Half the rig's stroke \[m\]: a measured `u` beyond it gives a warning.
pub const RIG_HALF_STROKE_M: f64 = 0.035;
/// The valve's command range \[V\]: a `v_in` beyond ±this gives a warning.
pub const RIG_V_IN_MAX_V: f64 = 10.0;

/// The record's step `dt`: the median of the time steps `t` (at least two samples), every
/// step within `±(DT_REL_TOLERANCE·dt + DT_ABS_TOLERANCE_S)` of it, and the rate `1/dt`
/// within what `kind` allows. Errors name the line (through `map`) and the times.
pub(super) fn sample_step(
    t: &[f64],
    map: &LineMap,
    kind: RecordKind,
    path: &Path,
) -> Result<f64, DatasetError> {
    // Uniform sampling: dt is the median step, every step within tolerance.
    let mut steps: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
    let mid = steps.len() / 2;
    let (_, &mut dt, _) = steps.select_nth_unstable_by(mid, f64::total_cmp);
    drop(steps);
    let tol = DT_REL_TOLERANCE * dt + DT_ABS_TOLERANCE_S;
    if let Some(i) = t.windows(2).position(|w| ((w[1] - w[0]) - dt).abs() > tol) {
        let (a, b) = (t[i], t[i + 1]);
        return Err(DatasetError::Time {
            file: path.to_path_buf(),
            line: map.line_of(i + 1),
            column: Some("t"),
            reason: format!(
                "the step from t = {} s (line {}) to t = {} s is {} s, but the record's step \
                 (the median) is {} s ± 1 %: the record is not uniformly sampled \
                 (a missing, repeated or shifted sample?)",
                fmt_num(a),
                map.line_of(i),
                fmt_num(b),
                sig(b - a),
                sig(dt)
            ),
        });
    }
    let rate_hz = 1.0 / dt;
    let (min, max) = kind.rate_range_hz();
    if !(rate_hz >= min * (1.0 - RATE_SLACK) && rate_hz <= max * (1.0 + RATE_SLACK)) {
        return Err(DatasetError::SampleRate {
            file: path.to_path_buf(),
            rate_hz,
            min,
            max,
            kind,
        });
    }

    Ok(dt)
}

/// Warnings for a stroke `u` beyond the rig's (a record in millimetres?), a command `v_in`
/// beyond the valve's range, and a `sample_rate_hz` metadata value that disagrees with the
/// times (`rate_hz`) by more than 1 %. `u_peak` and `v_in_peak` are the first largest
/// magnitude of each column and its line, found while the rows are read.
pub(super) fn plausibility_warnings(
    u_peak: Option<(usize, f64)>,
    v_in_peak: Option<(usize, f64)>,
    metadata: &[(String, String)],
    rate_hz: f64,
) -> Vec<String> {
    let mut warnings = Vec::new();
    if let Some((line, v)) = u_peak.filter(|(_, v)| v.abs() > RIG_HALF_STROKE_M) {
        let hint = if v.abs() > 1.0 {
            ": is it in millimetres instead of metres? (the format is SI)"
        } else {
            ""
        };
        warnings.push(format!(
            "column \"u\" reaches {} m at line {line}, far beyond the rig's stroke of \
             ±{} mm{hint}",
            sig(v),
            fmt_num(RIG_HALF_STROKE_M * 1e3)
        ));
    }
    if let Some((line, v)) = v_in_peak.filter(|(_, v)| v.abs() > RIG_V_IN_MAX_V) {
        warnings.push(format!(
            "column \"v_in\" reaches {} V at line {line}, beyond the valve's ±{} V \
             (the twin saturates the command there)",
            sig(v),
            fmt_num(RIG_V_IN_MAX_V)
        ));
    }
    if let Some((_, v)) = metadata.iter().find(|(k, _)| k == "sample_rate_hz") {
        match v.parse::<f64>() {
            Ok(declared) if ((declared - rate_hz) / rate_hz).abs() <= DT_REL_TOLERANCE => {}
            _ => warnings.push(format!(
                "metadata sample_rate_hz: {} disagrees with the times, which give {} Hz",
                quote(v),
                sig(rate_hz)
            )),
        }
    }
    warnings
}
