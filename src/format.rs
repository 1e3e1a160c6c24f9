//! Numbers for people: the one place that decides how a value reads in a message, a report or
//! a widget. Values arrive already in their display unit (SI inside, display units only at
//! the edges, see [`crate::params::table`]); this module only chooses digits.
//!
//! | function | for | example |
//! |---|---|---|
//! | [`general`] | parameters and values in messages (6 significant digits) | `0.0175`, `2.5e-11` |
//! | [`exact`] | a value read from a file, shown as it was read | `0.30000000000000004` |
//! | [`fixed`] | a table column with a fixed number of decimals | `0.142` |
//! | [`fixed_or`] | the same, with words for a missing (non-finite) value | `n/a` |
//! | [`compact`] | a widget's label: about 4 significant digits, no trailing zeros | `−7.5` |
//! | [`value_pm`] | `value ± std` to about 4 significant digits of the value | `17.50 ± 0.01` |
//! | [`uncertain`] | `value ± std` to 2 significant digits of the uncertainty | `0.596 ± 0.012` |
//! | [`by_magnitude`] | a value alone, decimals by its size (1, 3 or 4) | `0.5960` |
//!
//! [`compact`] and [`value_pm`] write the minus sign as `−` (U+2212), as a typeset number;
//! the others write `-`, which Markdown, CSV and a shell read back.

/// Significant digits of [`general`].
pub const GENERAL_DIGITS: usize = 6;

/// `x` to [`GENERAL_DIGITS`] significant digits, plain between 1e-4 and 1e7, in exponent form
/// outside (`2.5e-11`), `0` for zero and `NaN`/`inf`/`-inf` as such.
pub fn general(x: f64) -> String {
    if !x.is_finite() {
        return format!("{x}");
    }
    let r: f64 = format!("{x:.prec$e}", prec = GENERAL_DIGITS - 1)
        .parse()
        .unwrap_or(x);
    let a = r.abs();
    if a == 0.0 {
        "0".into()
    } else if (1e-4..1e7).contains(&a) {
        format!("{r}")
    } else {
        format!("{r:e}")
    }
}

/// `x` exactly as stored (the shortest text that reads back to the same `f64`), plain between
/// 1e-5 and 1e15 and for zero, in exponent form outside.
pub fn exact(x: f64) -> String {
    let mut s = String::new();
    let _ = write_exact(&mut s, x);
    s
}

/// [`exact`] into a writer (no allocation).
pub fn write_exact<W: std::fmt::Write>(w: &mut W, x: f64) -> std::fmt::Result {
    let a = x.abs();
    if a == 0.0 || (1e-5..1e15).contains(&a) {
        write!(w, "{x}")
    } else {
        write!(w, "{x:e}")
    }
}

/// `x` with `decimals` decimals; a non-finite value as `NaN`/`inf`.
pub fn fixed(x: f64, decimals: usize) -> String {
    format!("{x:.decimals$}")
}

/// [`fixed`], or `missing` when `x` is not finite (a run that diverged, a quantity with no
/// value in range).
pub fn fixed_or(x: f64, decimals: usize, missing: &str) -> String {
    if x.is_finite() {
        fixed(x, decimals)
    } else {
        missing.to_string()
    }
}

/// Decimals that show `v` to `digits` significant digits, at most `max` (2 for zero and
/// non-finite values).
pub fn decimals_for(v: f64, digits: usize, max: usize) -> usize {
    if !(v.is_finite() && v != 0.0) {
        return 2.min(max);
    }
    let d = digits as f64 - 1.0 - v.abs().log10().floor();
    d.clamp(0.0, max as f64) as usize
}

/// `v` to about 4 significant digits (at most 6 decimals), trailing zeros and a trailing
/// point removed, with a typographic minus: `−7.5`, `0.1074`, `1333`.
pub fn compact(v: f64) -> String {
    let s = format!("{v:.prec$}", prec = decimals_for(v, 4, 6));
    let s = if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    };
    typographic_minus(s)
}

/// `value ± std` with the decimals of about 4 significant digits of the value (at most 6),
/// typographic minus; `± <0.01` when the uncertainty is below the last shown digit, and the
/// value alone when the uncertainty is unknown (NaN) or zero.
pub fn value_pm(value: f64, std: f64) -> String {
    let d = decimals_for(value, 4, 6);
    let v = typographic_minus(format!("{value:.d$}"));
    if std.is_finite() && std > 0.0 {
        let shown = format!("{std:.d$}");
        if shown.trim_start_matches(['0', '.']).is_empty() {
            let unit = 10f64.powi(-(d as i32));
            format!("{v} ± <{unit:.d$}")
        } else {
            format!("{v} ± {shown}")
        }
    } else {
        v
    }
}

/// Decimals that show 2 significant digits of an uncertainty `std`, at least `min`, at most 9
/// (`min` when `std` is unknown or zero).
pub fn decimals_for_uncertainty(std: f64, min: usize) -> usize {
    if !(std.is_finite() && std > 0.0) {
        return min;
    }
    let d = 1 - std.log10().floor() as i64;
    d.clamp(min as i64, 9.max(min as i64)) as usize
}

/// `value ± std`, both with the decimals of 2 significant digits of `std` (at least
/// `min_decimals`), or the value alone when `std` is not finite; a non-finite value as `—`.
pub fn uncertain(value: f64, std: f64, min_decimals: usize) -> String {
    let d = decimals_for_uncertainty(std, min_decimals);
    if std.is_finite() {
        format!("{} ± {}", fixed_or(value, d, "—"), fixed_or(std, d, "—"))
    } else {
        fixed_or(value, d, "—")
    }
}

/// `v` with decimals by its size: 1 from 100 up, 3 from 1, 4 below; `—` when not finite.
pub fn by_magnitude(v: f64) -> String {
    let d = if v.abs() >= 100.0 {
        1
    } else if v.abs() >= 1.0 {
        3
    } else {
        4
    };
    fixed_or(v, d, "—")
}

/// The first ASCII minus of `s` as a typographic one (U+2212).
pub fn typographic_minus(s: String) -> String {
    if s.contains('-') {
        s.replacen('-', "−", 1)
    } else {
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn general_rounds_to_six_digits_and_switches_to_exponents_outside_the_plain_range() {
        assert_eq!(general(0.0175), "0.0175");
        assert_eq!(general(1.0 / 3.0), "0.333333");
        assert_eq!(general(-1234567.89), "-1234570");
        assert_eq!(general(2.5e-11), "2.5e-11");
        assert_eq!(general(1.5e9), "1.5e9");
        assert_eq!(general(0.0), "0");
        assert_eq!(general(f64::NAN), "NaN");
        assert_eq!(general(f64::NEG_INFINITY), "-inf");
        // 0.1 + 0.2 is not shown with its round-off.
        assert_eq!(general(0.1 + 0.2), "0.3");
    }

    #[test]
    fn exact_reads_back_to_the_same_value() {
        for x in [0.1 + 0.2, 1e-7, -3.25e20, 123.456, 0.0] {
            assert_eq!(exact(x).parse::<f64>().unwrap().to_bits(), x.to_bits());
        }
        assert_eq!(exact(0.1 + 0.2), "0.30000000000000004");
        assert_eq!(exact(1e-7), "1e-7");
    }

    #[test]
    fn fixed_and_its_words_for_missing_values() {
        assert_eq!(fixed(0.14159, 3), "0.142");
        assert_eq!(fixed_or(f64::INFINITY, 2, "none in range"), "none in range");
        assert_eq!(fixed_or(-2.0, 1, "n/a"), "-2.0");
    }

    #[test]
    fn compact_keeps_four_significant_digits_without_trailing_zeros() {
        assert_eq!(compact(-7.5), "−7.5");
        assert_eq!(compact(0.10740001), "0.1074");
        assert_eq!(compact(1333.3), "1333");
        assert_eq!(compact(250.0), "250");
        assert_eq!(compact(0.0), "0");
        assert_eq!(compact(2.5e-9), "0");
    }

    #[test]
    fn value_pm_shows_the_value_to_four_digits_and_a_tiny_uncertainty_as_a_bound() {
        assert_eq!(value_pm(17.5, 0.01), "17.50 ± 0.01");
        assert_eq!(value_pm(17.5, 0.0001), "17.50 ± <0.01");
        assert_eq!(value_pm(-0.596, f64::NAN), "−0.5960");
    }

    #[test]
    fn uncertain_shows_two_digits_of_the_uncertainty() {
        assert_eq!(uncertain(0.59612, 0.01234, 2), "0.596 ± 0.012");
        assert_eq!(uncertain(150.3, 2.7, 0), "150.3 ± 2.7");
        assert_eq!(uncertain(0.5, f64::NAN, 2), "0.50");
        assert_eq!(uncertain(f64::NAN, 0.1, 2), "— ± 0.10");
    }

    #[test]
    fn by_magnitude_chooses_decimals_by_size() {
        assert_eq!(by_magnitude(596.04), "596.0");
        assert_eq!(by_magnitude(1.23456), "1.235");
        assert_eq!(by_magnitude(0.596), "0.5960");
        assert_eq!(by_magnitude(f64::NAN), "—");
    }
}
