//! Display units of the app: the one place where SI values become mm, bar, ms, L/min, dB, deg.

/// Metres → millimetres.
pub const MM_PER_M: f64 = 1e3;
/// Seconds → milliseconds.
pub const MS_PER_S: f64 = 1e3;
/// Pascal → bar.
pub const BAR_PER_PA: f64 = 1e-5;
/// m³/s → L/min.
pub const LPM_PER_M3_S: f64 = 60_000.0;
/// N/m → kN/m.
pub const KN_PER_N: f64 = 1e-3;

/// Magnitude → decibels (`20·log10|x|`); −∞ dB for 0, NaN stays NaN.
pub fn db(mag: f64) -> f64 {
    20.0 * mag.log10()
}

/// Radians → degrees.
pub fn deg(rad: f64) -> f64 {
    rad.to_degrees()
}
