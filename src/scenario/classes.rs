//! The laboratory input spectral classes of the seat standards, as data.
//!
//! # Source, and how sure each number is
//!
//! The standards themselves (ISO 7096:2000, ISO 5007:2003, EN 13490:2001) are not public text;
//! their class tables could not be read here. Every number below comes from the public source
//! of the **HVLab HRV Toolbox** for MATLAB (Human Factors Research Unit, ISVR, University of
//! Southampton; C. Lewis), which implements the classes in two files:
//!
//! * `hvtestspectrum.m` (issue 1.1, 04/12/09): the **target PSD** of each class as
//!   `G(f) = G0 · |H_hp(f)|² · |H_lp(f)|²`, with Butterworth high- and low-pass sections
//!   (order and corner per class) and the scale `G0`, and the tolerance band
//!   `G(f) ± 0.1 · max G`;
//! * `hvtestsignal.m` (issue 2.1, 14/07/10): the same filters applied to random noise, scaled
//!   to an **rms** measured in 0.89–11.22 Hz or 0.89–17.78 Hz through 8-pole Butterworth
//!   band edges.
//!
//! The two files agree on every filter. For all classes but one, the rms that the target PSD
//! implies (its integral through the same band edges, [`InputClass::target_band_rms`]) is within
//! 0.6 % of the rms `hvtestsignal.m` states — a check in the tests, since the two numbers were
//! typed into two files independently. The exception is **EM7**: its filters and `G0` are those
//! of AG1 (3.0–3.5 Hz, 8th order, 9.25), whose PSD gives 2.26 m/s², but `hvtestsignal.m` scales
//! it to 2.36 m/s². Which one ISO 7096 prints could not be checked; the generator here follows
//! the target PSD (the quantity with a stated tolerance).
//!
//! `G0` is *not* the peak of the PSD: the band-pass product stays below 1 (for AG1 the peak is
//! 5.55, not 9.25 (m/s²)²/Hz). The tolerance is ±10 % of the true peak
//! ([`InputClass::peak`]), as `hvtestspectrum.m` computes it. ISO 5007's public table of
//! contents has a clause "Tolerances on input vibration (see ISO 10326-1:1992, 8.1)"; the
//! ±10 % figure itself is the toolbox's, not read in the standard.
//!
//! Further uncertain points, stated once here and per class in [`InputClass::note`]:
//! * the toolbox cites ISO 7096:2000; the 2020 edition (which adds machines such as crawler
//!   dumpers) may have changed classes;
//! * the mapping of AG1–AG3 to the three tractor classes of ISO 5007 (class 1 ≤ 3 600 kg,
//!   class 2 3 600–6 500 kg, class 3 > 6 500 kg — from the standard's public scope) is
//!   inferred from the numbering;
//! * which machines or truck categories each EM and IT class covers is not stated in the
//!   toolbox and is not given here;
//! * IT2 has the filters, `G0` and rms of EM8, IT3 those of EM4, as the toolbox has them.

/// A Butterworth filter section of the class definition: `|H|² = 1 / (1 + (f/fc)^(±2n))`.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Butterworth {
    /// Order `n` (poles), 1 ..= 8.
    pub order: u8,
    /// Corner frequency `fc` \[Hz\].
    pub corner_hz: f64,
}

impl Butterworth {
    /// Squared magnitude of the high-pass of this order and corner at `f_hz` [-].
    pub fn high_pass_sq(&self, f_hz: f64) -> f64 {
        if f_hz <= 0.0 {
            return 0.0;
        }
        1.0 / (1.0 + (self.corner_hz / f_hz).powi(2 * i32::from(self.order)))
    }

    /// Squared magnitude of the low-pass of this order and corner at `f_hz` [-].
    pub fn low_pass_sq(&self, f_hz: f64) -> f64 {
        1.0 / (1.0 + (f_hz.abs() / self.corner_hz).powi(2 * i32::from(self.order)))
    }
}

/// The seat standard a class belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum Standard {
    /// ISO 7096:2000, earth-moving machinery (classes EM1–EM9).
    Iso7096,
    /// ISO 5007:2003, agricultural wheeled tractors (classes AG1–AG3).
    Iso5007,
    /// EN 13490:2001, industrial trucks (classes IT1–IT4).
    En13490,
}

impl Standard {
    /// Citation as the toolbox gives it.
    pub fn citation(self) -> &'static str {
        match self {
            Standard::Iso7096 => "ISO 7096:2000 (earth-moving machinery)",
            Standard::Iso5007 => "ISO 5007:2003 (agricultural wheeled tractors)",
            Standard::En13490 => "EN 13490:2001 (industrial trucks)",
        }
    }
}

/// One input spectral class: the target PSD of the vertical platform (seat-base) acceleration.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct InputClass {
    /// Name, e.g. `"EM1"`, `"AG2"` (matched case-insensitively by [`find`]).
    pub name: &'static str,
    /// The standard that defines it.
    pub standard: Standard,
    /// High-pass edge of the band.
    pub high_pass: Butterworth,
    /// Low-pass edge of the band.
    pub low_pass: Butterworth,
    /// Scale `G0` of the target PSD [(m/s²)²/Hz] (not its peak: see [`Self::peak`]).
    pub g0: f64,
    /// Overall rms of the platform acceleration [m/s²] that `hvtestsignal.m` states, measured
    /// in [`Self::rms_band_hz`].
    pub rms_m_s2: f64,
    /// Band of that rms \[Hz\] (8-pole Butterworth edges); also the band over which the
    /// generated PSD is checked.
    pub rms_band_hz: (f64, f64),
    /// What is uncertain about this class in particular (empty if nothing beyond the module's
    /// general notes).
    pub note: &'static str,
}

/// Tolerance on the PSD of the platform acceleration, as a fraction of the target's peak
/// (`hvtestspectrum.m`: `G ± 0.1 · max G`).
pub const PSD_TOLERANCE_OF_PEAK: f64 = 0.10;

/// Band limits of the stated rms \[Hz\]: 0.89–11.22 Hz (1–10 Hz third-octave edges) …
const BAND_11: (f64, f64) = (0.89, 11.22);
/// … or 0.89–17.78 Hz (1–16 Hz third-octave edges).
const BAND_17: (f64, f64) = (0.89, 17.78);

const fn bw(order: u8, corner_hz: f64) -> Butterworth {
    Butterworth { order, corner_hz }
}

#[allow(clippy::too_many_arguments)]
const fn class(
    name: &'static str,
    standard: Standard,
    high_pass: Butterworth,
    low_pass: Butterworth,
    g0: f64,
    rms_m_s2: f64,
    rms_band_hz: (f64, f64),
    note: &'static str,
) -> InputClass {
    InputClass {
        name,
        standard,
        high_pass,
        low_pass,
        g0,
        rms_m_s2,
        rms_band_hz,
        note,
    }
}

use Standard::{En13490, Iso5007, Iso7096};

/// Every class, in the toolbox's order (HVLab `hvtestspectrum.m` / `hvtestsignal.m`).
pub const CLASSES: [InputClass; 16] = [
    class(
        "EM1",
        Iso7096,
        bw(4, 1.5),
        bw(4, 2.5),
        2.82,
        1.71,
        BAND_11,
        "",
    ),
    class(
        "EM2",
        Iso7096,
        bw(4, 1.5),
        bw(4, 3.0),
        2.72,
        2.05,
        BAND_11,
        "",
    ),
    class(
        "EM3",
        Iso7096,
        bw(4, 1.5),
        bw(4, 3.0),
        1.93,
        1.73,
        BAND_11,
        "",
    ),
    class(
        "EM4",
        Iso7096,
        bw(4, 1.5),
        bw(4, 3.0),
        0.60,
        0.96,
        BAND_11,
        "",
    ),
    class(
        "EM5",
        Iso7096,
        bw(4, 1.5),
        bw(1, 3.5),
        1.11,
        1.94,
        BAND_17,
        "first-order low-pass: a slow 1/f² tail; 4 % of the peak is still present at 20 Hz",
    ),
    class(
        "EM6",
        Iso7096,
        bw(2, 6.5),
        bw(2, 9.0),
        0.79,
        1.65,
        BAND_17,
        "",
    ),
    class(
        "EM7",
        Iso7096,
        bw(8, 3.0),
        bw(8, 3.5),
        9.25,
        2.36,
        BAND_11,
        "the toolbox's rms (2.36 m/s²) disagrees with its own target PSD (2.26 m/s², the same \
         filters and G0 as AG1); the generator follows the PSD",
    ),
    class(
        "EM8",
        Iso7096,
        bw(4, 3.0),
        bw(2, 3.0),
        1.45,
        1.05,
        BAND_17,
        "",
    ),
    class(
        "EM9",
        Iso7096,
        bw(4, 3.5),
        bw(2, 4.0),
        2.10,
        1.63,
        BAND_17,
        "",
    ),
    class(
        "IT1",
        En13490,
        bw(4, 4.5),
        bw(2, 5.0),
        1.66,
        1.58,
        BAND_17,
        "",
    ),
    class(
        "IT2",
        En13490,
        bw(4, 3.0),
        bw(2, 3.0),
        1.45,
        1.05,
        BAND_17,
        "identical to EM8 in the toolbox",
    ),
    class(
        "IT3",
        En13490,
        bw(4, 1.5),
        bw(4, 3.0),
        0.60,
        0.96,
        BAND_11,
        "identical to EM4 in the toolbox",
    ),
    class(
        "IT4",
        En13490,
        bw(4, 1.5),
        bw(4, 3.0),
        1.64,
        1.59,
        BAND_17,
        "",
    ),
    class(
        "AG1",
        Iso5007,
        bw(8, 3.0),
        bw(8, 3.5),
        9.25,
        2.26,
        BAND_11,
        "read as ISO 5007 class 1 (tractors ≤ 3 600 kg); the toolbox corrected AG1's corner \
         frequencies in Dec 2009",
    ),
    class(
        "AG2",
        Iso5007,
        bw(8, 2.1),
        bw(8, 2.6),
        7.22,
        1.94,
        BAND_11,
        "read as ISO 5007 class 2 (tractors 3 600–6 500 kg)",
    ),
    class(
        "AG3",
        Iso5007,
        bw(8, 1.95),
        bw(8, 2.45),
        5.85,
        1.74,
        BAND_11,
        "read as ISO 5007 class 3 (tractors > 6 500 kg)",
    ),
];

/// The class named `name` (case-insensitive), if any.
pub fn find(name: &str) -> Option<&'static InputClass> {
    CLASSES.iter().find(|c| c.name.eq_ignore_ascii_case(name))
}

/// The names of all classes, comma-separated (for error messages and help).
pub fn names() -> String {
    CLASSES
        .iter()
        .map(|c| c.name)
        .collect::<Vec<_>>()
        .join(", ")
}

/// Squared magnitude of the 8-pole Butterworth band edges through which an rms is measured
/// (`bandrms` in `hvtestsignal.m`) at `f_hz`.
pub fn rms_band_weight_sq(band_hz: (f64, f64), f_hz: f64) -> f64 {
    bw(8, band_hz.0).high_pass_sq(f_hz) * bw(8, band_hz.1).low_pass_sq(f_hz)
}

impl InputClass {
    /// Target one-sided PSD of the platform acceleration at `f_hz` [(m/s²)²/Hz].
    pub fn target_psd(&self, f_hz: f64) -> f64 {
        self.g0 * self.high_pass.high_pass_sq(f_hz) * self.low_pass.low_pass_sq(f_hz)
    }

    /// Peak of the target PSD: `(frequency \[Hz\], value [(m/s²)²/Hz])`, found on a 1 mHz grid
    /// from 0.1 to 50 Hz and refined by golden-section search.
    pub fn peak(&self) -> (f64, f64) {
        let df = 1e-3;
        let (mut fb, mut gb) = (0.1, 0.0);
        let mut f = 0.1;
        while f <= 50.0 {
            let g = self.target_psd(f);
            if g > gb {
                (fb, gb) = (f, g);
            }
            f += df;
        }
        // Golden-section refinement on [fb − df, fb + df] (the PSD is unimodal there).
        let (mut a, mut b) = (fb - df, fb + df);
        let r = 0.5 * (5f64.sqrt() - 1.0);
        for _ in 0..40 {
            let (c, d) = (b - r * (b - a), a + r * (b - a));
            if self.target_psd(c) > self.target_psd(d) {
                b = d;
            } else {
                a = c;
            }
        }
        let f = 0.5 * (a + b);
        (f, self.target_psd(f))
    }

    /// Absolute PSD tolerance [(m/s²)²/Hz]: ±[`PSD_TOLERANCE_OF_PEAK`] of the peak.
    pub fn tolerance(&self) -> f64 {
        PSD_TOLERANCE_OF_PEAK * self.peak().1
    }

    /// The rms [m/s²] that the target PSD implies in [`Self::rms_band_hz`], through the same
    /// 8-pole band edges as the stated rms: `√∫ G(f)·|B(f)|² df` (Simpson's rule, 0.01–200 Hz
    /// on a logarithmic grid).
    pub fn target_band_rms(&self) -> f64 {
        self.integrate(|f| self.target_psd(f) * rms_band_weight_sq(self.rms_band_hz, f))
            .sqrt()
    }

    /// The rms [m/s²] of the whole target PSD, without band edges.
    pub fn target_total_rms(&self) -> f64 {
        self.integrate(|f| self.target_psd(f)).sqrt()
    }

    /// `∫ g(f) df` over 0.01–200 Hz: Simpson's rule in `ln f` (`df = f·d ln f`).
    fn integrate(&self, g: impl Fn(f64) -> f64) -> f64 {
        let (a, b) = (0.01f64.ln(), 200f64.ln());
        let n = 20_000; // even
        let h = (b - a) / n as f64;
        let mut sum = 0.0;
        for i in 0..=n {
            let f = (a + i as f64 * h).exp();
            let w = if i == 0 || i == n {
                1.0
            } else if i % 2 == 1 {
                4.0
            } else {
                2.0
            };
            sum += w * g(f) * f;
        }
        sum * h / 3.0
    }

    /// `[low, high]` frequencies \[Hz\] where the target PSD is at least `fraction` of its peak.
    pub fn band_above(&self, fraction: f64) -> (f64, f64) {
        let (fp, gp) = self.peak();
        let level = fraction * gp;
        let edge = |mut lo: f64, mut hi: f64, rising: bool| {
            for _ in 0..60 {
                let mid = 0.5 * (lo + hi);
                if (self.target_psd(mid) >= level) == rising {
                    hi = mid;
                } else {
                    lo = mid;
                }
            }
            0.5 * (lo + hi)
        };
        (edge(1e-3, fp, true), edge(fp, 1e3, false))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn butterworth_is_half_power_at_its_corner() {
        for order in [1u8, 2, 4, 8] {
            let b = bw(order, 3.0);
            assert!((b.high_pass_sq(3.0) - 0.5).abs() < 1e-15);
            assert!((b.low_pass_sq(3.0) - 0.5).abs() < 1e-15);
            // Roll-off: 6n dB per octave far from the corner.
            let r = b.low_pass_sq(300.0) / b.low_pass_sq(150.0);
            assert!((r - 0.5f64.powi(2 * i32::from(order))).abs() < 1e-3 * r);
        }
        assert_eq!(bw(2, 1.0).high_pass_sq(0.0), 0.0);
    }

    #[test]
    fn names_are_unique_and_found_case_insensitively() {
        for c in &CLASSES {
            assert_eq!(find(&c.name.to_lowercase()).map(|f| f.name), Some(c.name));
            assert_eq!(CLASSES.iter().filter(|d| d.name == c.name).count(), 1);
        }
        assert!(find("EM10").is_none());
        assert!(names().starts_with("EM1, EM2"));
    }

    #[test]
    fn peak_of_ag1_is_below_its_scale() {
        // 8th-order edges at 3.0 and 3.5 Hz overlap: at the geometric centre √(3·3.5) the
        // product is 1/(1 + (9/10.5)^8)² = 1/1.291357² = 0.59966, so the peak (there, by
        // symmetry of the two equal-order edges) is 9.25·0.59966 = 5.547, well below G0.
        let c = find("AG1").expect("AG1");
        let (f, g) = c.peak();
        let centre = (3.0f64 * 3.5).sqrt();
        assert!((f - centre).abs() < 0.01, "{f}");
        assert!((g - 5.547).abs() < 0.002, "{g}");
    }
}
