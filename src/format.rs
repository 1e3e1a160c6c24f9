//! Numbers for people: the one place that decides how a value reads in a message, a report or
//! a widget. Values arrive already in their display unit (SI inside, display units only at
//! the edges, see [`crate::params::PARAMS`]); this module only chooses digits.
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

/// [`exact`] into a writer.
///
/// The text is std's `{}` (plain) or `{:e}` (exponent form) of `x`, byte for byte; the
/// shortest digits come from `zmij` (already in the tree through `serde_json`), and only their
/// layout is std's: several times faster than std's formatting machinery, which a CSV of
/// 11 columns × 65 000 rows notices (`tests`: the same bytes as std on a million random
/// values, and each reads back to the same `f64`).
pub fn write_exact<W: std::fmt::Write>(w: &mut W, x: f64) -> std::fmt::Result {
    let a = x.abs();
    if !a.is_finite() {
        return write!(w, "{x}");
    }
    if a == 0.0 {
        return w.write_str(if x.is_sign_negative() { "-0" } else { "0" });
    }
    let mut zmij = zmij::Buffer::new();
    let text = zmij.format_finite(x);
    let plain = (1e-5..1e15).contains(&a);
    match (plain, text.bytes().position(|b| b == b'e')) {
        // zmij's plain form is std's but for the `.0` of a whole number.
        (true, None) => w.write_str(text.strip_suffix(".0").unwrap_or(text)),
        // Its exponent form is std's but for the exponent's `+` and leading zero (`e+07`).
        (false, Some(e)) => {
            let exp = &text[e + 1..];
            let (minus, exp) = match exp.strip_prefix('-') {
                Some(m) => (true, m),
                None => (false, exp.strip_prefix('+').unwrap_or(exp)),
            };
            let exp = exp.trim_start_matches('0');
            w.write_str(&text[..e])?;
            w.write_str(if minus { "e-" } else { "e" })?;
            w.write_str(if exp.is_empty() { "0" } else { exp })
        }
        // Where zmij switches form elsewhere than std: its digits laid out as std does.
        _ => write_digits(w, x < 0.0, plain, text),
    }
}

/// The significant digits of `text` (a number written by `zmij`) laid out as std's `{}`
/// (`plain`) or `{:e}` would write them, with a minus sign when `negative`.
fn write_digits<W: std::fmt::Write>(
    w: &mut W,
    negative: bool,
    plain: bool,
    text: &str,
) -> std::fmt::Result {
    let (mantissa, exp) = match text.split_once('e') {
        Some((m, e)) => (m, e.parse::<i32>().map_err(|_| std::fmt::Error)?),
        None => (text, 0),
    };
    let int_len = mantissa.find('.').unwrap_or(mantissa.len()) as i32 - i32::from(negative);
    let all: String = mantissa.chars().filter(char::is_ascii_digit).collect();
    let leading = all.len() - all.trim_start_matches('0').len();
    let digits = all.trim_start_matches('0').trim_end_matches('0');
    let digits = if digits.is_empty() { "0" } else { digits };
    let n = digits.len() as i32;
    // The value is d₁.d₂…dₙ × 10^e.
    let e = int_len - 1 - leading as i32 + exp;
    let zeros = |k: i32| "0".repeat(k.max(0) as usize);
    if negative {
        w.write_str("-")?;
    }
    if !plain {
        let (first, rest) = digits.split_at(1);
        let point = if rest.is_empty() { "" } else { "." };
        return write!(w, "{first}{point}{rest}e{e}");
    }
    if e >= n - 1 {
        write!(w, "{digits}{}", zeros(e + 1 - n))
    } else if e >= 0 {
        let (int, frac) = digits.split_at((e + 1) as usize);
        write!(w, "{int}.{frac}")
    } else {
        write!(w, "0.{}{digits}", zeros(-e - 1))
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

    /// Whether `ours` is std's text `std`, or, where the value lies exactly halfway between
    /// two shortest texts, the other one: the same length, one digit apart in the last place
    /// (std rounds that tie up, zmij to even; both read back to the same value, checked
    /// apart).
    fn same_or_tie(ours: &str, std: &str) -> bool {
        let (a, b) = (ours.as_bytes(), std.as_bytes());
        if a == b {
            return true;
        }
        let differ: Vec<usize> = (0..a.len().max(b.len()))
            .filter(|&i| a.get(i) != b.get(i))
            .collect();
        // The last digit is the last byte, or the byte before the exponent.
        let last_digit = |t: &[u8]| t.iter().position(|&c| c == b'e').unwrap_or(t.len()) - 1;
        a.len() == b.len()
            && differ.len() == 1
            && differ[0] == last_digit(a)
            && a[differ[0]].is_ascii_digit()
            && b[differ[0]].is_ascii_digit()
            && a[differ[0]].abs_diff(b[differ[0]]) == 1
    }

    /// What `write_exact` wrote before it laid out `zmij`'s digits itself: std's formatting.
    fn exact_by_std(x: f64) -> String {
        let a = x.abs();
        if a == 0.0 || (1e-5..1e15).contains(&a) {
            format!("{x}")
        } else {
            format!("{x:e}")
        }
    }

    #[test]
    fn exact_writes_std_s_bytes_and_reads_back_on_random_and_edge_values() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(23);
        let mut edges = vec![
            0.0,
            -0.0,
            1e-5,
            1e15,
            9.999999999999999e14,
            1e-5 * (1.0 - f64::EPSILON),
            f64::MIN_POSITIVE,
            5e-324,
            f64::MAX,
            1.0,
            10.0,
            0.1,
            123456789012345.6,
            1e100,
            1e-100,
            2.5e-9,
        ];
        edges.extend(edges.clone().iter().map(|x| -x));
        let mut values = edges;
        values.extend((0..400_000).map(|_| f64::from_bits(rng.random::<u64>())));
        // Values of the sizes a record holds (SI: 1e-9 m³/s … 1e7 Pa), at full precision.
        values.extend(
            (0..400_000)
                .map(|_| rng.random_range(-1.0..1.0) * 10f64.powi(rng.random_range(-12..9))),
        );
        // Short decimals, where the shortest digits and their trailing zeros matter.
        values.extend((0..200_000).map(|_| rng.random_range(-100_000i64..100_000) as f64 * 1e-3));
        let (mut ties, count) = (0, values.len());
        for x in values {
            let text = exact(x);
            if x.is_finite() {
                assert_eq!(
                    text.parse::<f64>().unwrap().to_bits(),
                    x.to_bits(),
                    "{text}"
                );
            }
            let std = exact_by_std(x);
            assert!(same_or_tie(&text, &std), "{text} against std's {std}");
            ties += usize::from(text != std);
        }
        // Ties are values exactly halfway between two 17-digit texts: rare.
        assert!(ties * 1000 < count, "{ties} of {count} differ from std");
        // One such value: 127114649481159.625 exactly, between …159.62 and …159.63.
        let tie = 127114649481159.0 + 0.625;
        assert_eq!(exact(tie), "127114649481159.62");
        assert_eq!(exact_by_std(tie), "127114649481159.63");
    }

    #[test]
    fn zmij_s_digits_laid_out_in_either_form_are_std_s() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let mut values = vec![
            1e-5,
            1e15,
            1e16,
            1e-7,
            5e-324,
            f64::MAX,
            0.1,
            123.0,
            -2.5e-9,
        ];
        values.extend((0..20_000).map(|_| f64::from_bits(rng.random::<u64>() >> 1)));
        values.extend(
            (0..20_000).map(|_| rng.random_range(-1e3..1e3) * 10f64.powi(rng.random_range(-9..18))),
        );
        for x in values.into_iter().filter(|x| x.is_finite() && *x != 0.0) {
            let mut z = zmij::Buffer::new();
            let text = z.format_finite(x);
            for plain in [true, false] {
                let mut out = String::new();
                write_digits(&mut out, x < 0.0, plain, text).unwrap();
                let std = if plain {
                    format!("{x}")
                } else {
                    format!("{x:e}")
                };
                assert!(same_or_tie(&out, &std), "{out} against std's {std}");
                assert_eq!(out.parse::<f64>().unwrap().to_bits(), x.to_bits(), "{out}");
            }
        }
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
