//! Residual diagnostics: sensor-noise estimate, whiteness, the residual's spectrum, and its
//! correlation with the signature features of each candidate effect.
//!
//! | feature | signature of |
//! |---|---|
//! | `sign_velocity` — `sign(u̇)` of the twin | `friction` (a force step at each reversal) |
//! | `small_command` — `sign(v)` where `|v| < 10 %` of the file's peak command | `valve_overlap` |
//! | `constant` — a constant 1 (velocity bias, drift of `u`) | `valve_offset` |
//! | `load_pressure` — `p1 − p2` of the twin | `leakage` |
//! | `flow_magnitude` — `Q·|Q|` of the twin | `supply_sag` |
//! | `high_frequency` — residual power above 30 Hz in `ÿ` | `compliance`, mass |

use super::replay::{PreparedRecord, Replay, rms};
use serde::Serialize;

pub use crate::dsp::{noise_rms, spectrum};

/// Whiteness of a residual: its normalised autocorrelation at lags 1..=`max_lag` and the share
/// of lags outside the 95 % band `±1.96/√n` of white noise.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Whiteness {
    /// Lag-1 autocorrelation [-].
    pub lag1: f64,
    /// Share of lags 1..=max_lag outside the 95 % band [-] (≈ 0.05 for white noise).
    pub share_outside: f64,
    /// Ljung–Box statistic over the lags [-] (≈ max_lag for white noise).
    pub ljung_box: f64,
    /// Lags tested.
    pub max_lag: usize,
}

/// Autocorrelation test of `r` (decimated residual of one or more files, concatenated).
pub fn whiteness(r: &[f64], max_lag: usize) -> Whiteness {
    let n = r.len();
    let mean = r.iter().sum::<f64>() / n.max(1) as f64;
    let c0: f64 = r
        .iter()
        .map(|v| (v - mean).powi(2))
        .sum::<f64>()
        .max(1e-300);
    let mut outside = 0usize;
    let mut q = 0.0;
    let mut lag1 = 0.0;
    let band = 1.96 / (n.max(1) as f64).sqrt();
    let lags = max_lag.min(n.saturating_sub(2)).max(1);
    for k in 1..=lags {
        let ck: f64 = (k..n).map(|i| (r[i] - mean) * (r[i - k] - mean)).sum();
        let rho = ck / c0;
        if k == 1 {
            lag1 = rho;
        }
        if rho.abs() > band {
            outside += 1;
        }
        q += rho * rho / (n - k).max(1) as f64;
    }
    Whiteness {
        lag1,
        share_outside: outside as f64 / lags as f64,
        ljung_box: n as f64 * (n as f64 + 2.0) * q,
        max_lag: lags,
    }
}

/// Correlation of the residual with one signature feature.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FeatureCorrelation {
    /// Feature id (see the module table).
    pub feature: String,
    /// The effect it points at.
    pub effect: String,
    /// Correlation coefficient with the velocity residual [-1, 1] (the constant feature
    /// reports mean/RMS of the residual instead).
    pub velocity: f64,
    /// Correlation with the acceleration residual (NaN without `ÿ`).
    pub acceleration: f64,
}

/// Per-feature correlation over all records (feature and residual pooled across files).
pub fn feature_correlations(
    records: &[PreparedRecord],
    replays: &[Replay],
) -> Vec<FeatureCorrelation> {
    type Feat = fn(&PreparedRecord, &Replay, usize, f64) -> f64;
    let feats: [(&str, &str, Feat); 5] = [
        ("sign_velocity", "friction", |_, r, i, _| {
            r.twin_du[i].signum()
        }),
        ("small_command", "valve_overlap", |p, _, i, vpk| {
            let v = p.v_in[i];
            if v.abs() < 0.1 * vpk { v.signum() } else { 0.0 }
        }),
        ("load_pressure", "leakage", |_, r, i, _| {
            r.sim.p1[i] - r.sim.p2[i]
        }),
        ("flow_magnitude", "supply_sag", |_, r, i, _| {
            r.sim.q2[i] * r.sim.q2[i].abs()
        }),
        ("constant", "valve_offset", |_, _, _, _| 1.0),
    ];
    let mut out = Vec::new();
    for (name, effect, f) in feats {
        let mut v_pairs = Vec::new();
        let mut a_pairs = Vec::new();
        for (p, r) in records.iter().zip(replays) {
            let vpk = p.v_in.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let sd = rms(&p.du_meas_f).max(1e-12);
            // The acceleration residual and its measured channel's RMS, once per record.
            let acc = match (&r.residual_ydd, &p.ydd_meas_f) {
                (Some(ra), Some(ym)) => Some((ra, rms(ym).max(1e-12))),
                _ => None,
            };
            for i in (0..p.len).step_by(p.decimate) {
                let x = f(p, r, i, vpk);
                v_pairs.push((x, r.residual_du[i] / sd));
                if let Some((ra, sa)) = acc {
                    a_pairs.push((x, ra[i] / sa));
                }
            }
        }
        let constant = name == "constant";
        out.push(FeatureCorrelation {
            feature: name.into(),
            effect: effect.into(),
            velocity: if constant {
                mean_over_rms(&v_pairs)
            } else {
                correlation(&v_pairs)
            },
            acceleration: if a_pairs.is_empty() {
                f64::NAN
            } else if constant {
                mean_over_rms(&a_pairs)
            } else {
                correlation(&a_pairs)
            },
        });
    }
    out
}

fn mean_over_rms(p: &[(f64, f64)]) -> f64 {
    let n = p.len().max(1) as f64;
    let m = p.iter().map(|(_, y)| y).sum::<f64>() / n;
    let r = (p.iter().map(|(_, y)| y * y).sum::<f64>() / n).sqrt();
    if r > 0.0 { m / r } else { 0.0 }
}

/// Pearson correlation of pairs (0 when either side is constant).
pub fn correlation(p: &[(f64, f64)]) -> f64 {
    let n = p.len() as f64;
    if n < 2.0 {
        return 0.0;
    }
    let mx = p.iter().map(|(x, _)| x).sum::<f64>() / n;
    let my = p.iter().map(|(_, y)| y).sum::<f64>() / n;
    let (mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0);
    for (x, y) in p {
        sxy += (x - mx) * (y - my);
        sxx += (x - mx) * (x - mx);
        syy += (y - my) * (y - my);
    }
    if sxx <= 0.0 || syy <= 0.0 {
        0.0
    } else {
        sxy / (sxx * syy).sqrt()
    }
}

/// Share of the acceleration residual's power above `f_hz` (raw, unfiltered twin vs measured
/// `ÿ`), pooled over files: the high-frequency signature.
pub fn high_frequency_share(records: &[PreparedRecord], replays: &[Replay], f_hz: f64) -> f64 {
    let (mut hi, mut all) = (0.0, 0.0);
    for (p, r) in records.iter().zip(replays) {
        let Some(ym) = &p.ydd else { continue };
        let e: Vec<f64> = r.sim.ydd.iter().zip(ym).map(|(a, b)| a - b).collect();
        let (f, a) = spectrum(&e, p.dt);
        for (fk, ak) in f.iter().zip(&a) {
            let pk = ak * ak;
            all += pk;
            if *fk > f_hz {
                hi += pk;
            }
        }
    }
    if all > 0.0 { hi / all } else { 0.0 }
}

/// One record's channel whose residual stays above the noise.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LeftChannel {
    /// Record (file) name.
    pub file: String,
    /// Channel: `du`, `ydd`, `p1` or `p2`.
    pub channel: String,
    /// Its weighted RMS residual (1 = noise level).
    pub weighted_rms: f64,
}

/// What a twin still misses: where the residual above the noise is, in which frequency band,
/// and what it correlates with.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ResidualLeft {
    /// The whole finding, in one paragraph.
    pub summary: String,
    /// Record channels above the per-record noise level, worst first (the worst three when
    /// only the pooled error is above it).
    pub channels: Vec<LeftChannel>,
    /// Share of the weighted residual power of those channels per band `[lo, hi)` Hz.
    pub bands: Vec<([f64; 2], f64)>,
    /// The band with most of that power.
    pub main_band_hz: [f64; 2],
    /// Correlation of the residual of those channels with candidate explanatory signals,
    /// strongest first: `(signal, channel, r)`.
    pub correlations: Vec<(String, String, f64)>,
}

/// Finds what is left in the residual of `replays` (see [`ResidualLeft`]).
pub fn residual_left(
    records: &[PreparedRecord],
    replays: &[Replay],
    threshold: f64,
) -> ResidualLeft {
    let mut all: Vec<(usize, &'static str, f64)> = Vec::new();
    for (i, r) in replays.iter().enumerate() {
        let e = &r.errors;
        for (c, v) in [
            ("du", Some(e.weighted_du)),
            ("ydd", e.weighted_ydd),
            ("p1", e.weighted_p1),
            ("p2", e.weighted_p2),
        ] {
            if let Some(v) = v.filter(|v| v.is_finite()) {
                all.push((i, c, v));
            }
        }
    }
    all.sort_by(|a, b| b.2.total_cmp(&a.2));
    let mut flagged: Vec<(usize, &'static str, f64)> =
        all.iter().copied().filter(|x| x.2 > threshold).collect();
    if flagged.is_empty() {
        flagged = all.iter().copied().take(3).collect();
    }
    let edges = [0.0, 0.5, 2.0, 5.0, 10.0, 20.0, f64::INFINITY];
    let mut power = vec![0.0; edges.len() - 1];
    // Residual of a flagged channel (filtered as in the metric) on its window, in units of its
    // weight scale.
    let residual = |i: usize, c: &str| -> Option<Vec<f64>> {
        let (p, r) = (&records[i], &replays[i]);
        let w = p.window.clone();
        match c {
            "du" => Some(r.residual_du[w].iter().map(|v| v / p.scale_du).collect()),
            "ydd" => r
                .residual_ydd
                .as_ref()
                .map(|v| v[w].iter().map(|v| v / p.scale_ydd).collect()),
            _ => None,
        }
    };
    for &(i, c, _) in &flagged {
        let Some(e) = residual(i, c) else { continue };
        let (f, a) = spectrum(&e, records[i].dt);
        for (fk, ak) in f.iter().zip(&a) {
            if let Some(b) = (0..power.len()).find(|&b| *fk >= edges[b] && *fk < edges[b + 1]) {
                power[b] += ak * ak;
            }
        }
    }
    let total: f64 = power.iter().sum();
    let bands: Vec<([f64; 2], f64)> = (0..power.len())
        .map(|b| {
            let hi = if edges[b + 1].is_finite() {
                edges[b + 1]
            } else {
                records.first().map(|r| 0.5 / r.dt).unwrap_or(500.0)
            };
            (
                [edges[b], hi],
                if total > 0.0 { power[b] / total } else { 0.0 },
            )
        })
        .collect();
    let main = bands
        .iter()
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .map(|b| (b.0, b.1))
        .unwrap_or(([0.0, 0.0], 0.0));
    // Correlations with signals that an effect outside the library could depend on.
    type Sig = fn(&PreparedRecord, &Replay, usize) -> f64;
    let signals: [(&str, Sig); 10] = [
        ("spool position xv", |_, r, k| r.sim.xv[k]),
        ("spool opening |xv|", |_, r, k| r.sim.xv[k].abs()),
        ("command v_in", |p, _, k| p.v_in[k]),
        ("twin velocity du/dt", |_, r, k| r.twin_du[k]),
        ("sign of velocity", |_, r, k| r.twin_du[k].signum()),
        ("twin body acceleration", |_, r, k| r.twin_ydd[k]),
        ("stroke u", |_, r, k| r.sim.u[k]),
        ("load pressure p1 − p2", |_, r, k| {
            r.sim.p1[k] - r.sim.p2[k]
        }),
        ("flow |Q|·Q", |_, r, k| r.sim.q2[k] * r.sim.q2[k].abs()),
        ("time in the record", |p, _, k| k as f64 * p.dt),
    ];
    let mut correlations = Vec::new();
    for ch in ["du", "ydd"] {
        let rows: Vec<usize> = flagged.iter().filter(|x| x.1 == ch).map(|x| x.0).collect();
        if rows.is_empty() {
            continue;
        }
        for (name, f) in signals {
            let mut pairs = Vec::new();
            for &i in &rows {
                let (p, r) = (&records[i], &replays[i]);
                let res = if ch == "du" {
                    Some(&r.residual_du)
                } else {
                    r.residual_ydd.as_ref()
                };
                let Some(res) = res else { continue };
                let scale = if ch == "du" { p.scale_du } else { p.scale_ydd };
                for k in p.window.clone().step_by(p.decimate.max(1)) {
                    pairs.push((f(p, r, k), res[k] / scale));
                }
            }
            let c = correlation(&pairs);
            if c.is_finite() {
                correlations.push((name.to_string(), ch.to_string(), c));
            }
        }
    }
    correlations.sort_by(|a, b| b.2.abs().total_cmp(&a.2.abs()));
    correlations.truncate(4);
    let channels: Vec<LeftChannel> = flagged
        .iter()
        .map(|&(i, c, v)| LeftChannel {
            file: records[i].name.clone(),
            channel: c.to_string(),
            weighted_rms: v,
        })
        .collect();
    let list: Vec<String> = channels
        .iter()
        .take(6)
        .map(|c| format!("{} {} ({:.2})", c.file, c.channel, c.weighted_rms))
        .collect();
    let corr: Vec<String> = correlations
        .iter()
        .map(|(s, c, r)| format!("{s} ({c} residual, r = {r:+.2})"))
        .collect();
    let summary = format!(
        "Left above the noise (weighted RMS, 1 = noise; limit {threshold:.1} per record and \
         channel): {}{}. {:.0} % of that residual's power lies in {:.1}–{:.1} Hz. It correlates \
         most with: {}.",
        list.join(", "),
        if channels.len() > 6 {
            format!(" and {} more", channels.len() - 6)
        } else {
            String::new()
        },
        100.0 * main.1,
        main.0[0],
        main.0[1],
        if corr.is_empty() {
            "nothing tested".to_string()
        } else {
            corr.join(", ")
        }
    );
    ResidualLeft {
        summary,
        channels,
        bands,
        main_band_hz: main.0,
        correlations,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};

    #[test]
    fn noise_estimate_sees_white_noise_under_a_slow_signal() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let nd = Normal::new(0.0, 0.08).unwrap();
        let dt = 1e-3;
        let x: Vec<f64> = (0..5000)
            .map(|i| {
                30.0 * (2.0 * std::f64::consts::PI * 10.0 * i as f64 * dt).sin()
                    + nd.sample(&mut rng)
            })
            .collect();
        let s = noise_rms(&x, dt);
        assert!((s / 0.08 - 1.0).abs() < 0.1, "{s}");
    }

    #[test]
    fn white_noise_is_white_and_a_sine_is_not() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(4);
        let nd = Normal::new(0.0, 1.0).unwrap();
        let w: Vec<f64> = (0..4000).map(|_| nd.sample(&mut rng)).collect();
        assert!(whiteness(&w, 20).share_outside < 0.2);
        let s: Vec<f64> = (0..4000).map(|i| (i as f64 * 0.05).sin()).collect();
        let ws = whiteness(&s, 20);
        assert!(ws.share_outside > 0.9 && ws.lag1 > 0.9);
    }
}
