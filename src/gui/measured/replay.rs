//! A replay of the selected record, reduced to what the window draws: the errors, the raw
//! error measure, the residual's diagnosis and display-decimated curves.

use super::super::units::MM_PER_M;
use crate::identify;
use crate::identify::diagnose::{self, FeatureCorrelation, Whiteness};
use crate::identify::replay::{ChannelErrors, PreparedRecord, replay_prepared};
use crate::params::Params;

/// Most points drawn per line (the records are decimated for display only).
const MAX_PLOT_POINTS: usize = 3000;
/// Lags of the whiteness test.
const WHITENESS_LAGS: usize = 20;

/// A replay of the selected record, reduced to what the window draws.
pub struct ReplayView {
    /// Index of the record it belongs to.
    pub record: usize,
    /// The parameters it was run with.
    pub params: Params,
    /// Per-channel errors (SI).
    pub errors: ChannelErrors,
    /// RMS of the noise-weighted residual, the fit's metric (1.0 = sensor noise).
    pub weighted_rms: f64,
    /// The raw error measure of this record (every raw channel and band against its noise
    /// floor), as the calibration's verdict and report use it.
    pub raw: identify::raw_error::RawErrorReport,
    /// Whiteness of the relative-velocity residual, decimated to the metric's rate.
    pub whiteness: Whiteness,
    /// Correlation of the residual with the signature features of the library effects.
    pub correlations: Vec<FeatureCorrelation>,
    /// Measured and twin relative velocity du/dt [mm/s] (filtered as in the metric).
    pub(super) du: [Vec<[f64; 2]>; 2],
    /// Measured and twin stroke u [mm].
    pub(super) u: [Vec<[f64; 2]>; 2],
    /// Measured and twin body acceleration [m/s²] (empty without `ydd`).
    pub(super) ydd: [Vec<[f64; 2]>; 2],
    /// Residual of du/dt [mm/s].
    pub(super) residual: Vec<[f64; 2]>,
}

impl ReplayView {
    /// Number of measured-vs-twin points drawn for du/dt.
    pub fn n_points(&self) -> usize {
        self.du[0].len()
    }
}

/// Display-decimated `(t, scale·y)` points.
fn decimated(t: &[f64], y: &[f64], scale: f64) -> Vec<[f64; 2]> {
    let step = (t.len() / MAX_PLOT_POINTS).max(1);
    t.iter()
        .zip(y)
        .step_by(step)
        .filter(|(_, v)| v.is_finite())
        .map(|(t, v)| [*t, v * scale])
        .collect()
}

pub(super) fn replay_view(
    params: &Params,
    rec: &PreparedRecord,
    index: usize,
) -> Result<ReplayView, String> {
    let r = replay_prepared(params, rec).map_err(|e| e.to_string())?;
    let dec: Vec<f64> = r
        .residual_du
        .iter()
        .step_by(rec.decimate.max(1))
        .copied()
        .collect();
    let whiteness = diagnose::whiteness(&dec, WHITENESS_LAGS);
    let mut weighted = Vec::new();
    rec.weighted_residuals(&r.sim, &mut weighted);
    let correlations =
        diagnose::feature_correlations(std::slice::from_ref(rec), std::slice::from_ref(&r));
    let t = &rec.t;
    let ydd = match &r.measured_ydd {
        Some(m) => [decimated(t, m, 1.0), decimated(t, &r.twin_ydd, 1.0)],
        None => [Vec::new(), Vec::new()],
    };
    Ok(ReplayView {
        record: index,
        params: *params,
        errors: r.errors,
        weighted_rms: identify::replay::rms(&weighted),
        raw: identify::raw_error::raw_error_report(
            std::slice::from_ref(rec),
            &[&r.sim],
            identify::raw_error::DEFAULT_LIMIT,
        ),
        whiteness,
        correlations,
        du: [
            decimated(t, &r.measured_du, MM_PER_M),
            decimated(t, &r.twin_du, MM_PER_M),
        ],
        u: [
            decimated(t, &rec.u, MM_PER_M),
            decimated(t, &r.sim.u, MM_PER_M),
        ],
        ydd,
        residual: decimated(t, &r.residual_du, MM_PER_M),
    })
}
