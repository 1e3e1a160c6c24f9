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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn conversions_at_known_points() {
        assert_eq!(0.035 * MM_PER_M, 35.0);
        assert!((100e5 * BAR_PER_PA - 100.0).abs() < 1e-12);
        assert!((1e-3 / 60.0 * LPM_PER_M3_S - 1.0).abs() < 1e-12);
        assert!((db(10.0) - 20.0).abs() < 1e-12);
        assert!((deg(std::f64::consts::PI) - 180.0).abs() < 1e-12);
    }
}
