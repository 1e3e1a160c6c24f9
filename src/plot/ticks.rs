//! Axis ranges and ticks: the drawing scale (log10 for a log axis), the fitted range, and
//! labelled ticks at 1-2-5 steps (linear) or 1-2-5 decades with 1–9 sub-lines (log).

use super::Scale;

/// Largest magnitude accepted as data (keeps every span and step finite).
const HUGE: f64 = 1e250;

/// The value on the axis' drawing scale (log10 for a log axis), or `None` if it can't be drawn.
pub(super) fn tr(scale: Scale, v: f64) -> Option<f64> {
    match scale {
        Scale::Linear => (v.is_finite() && v.abs() <= HUGE).then_some(v),
        Scale::Log10 => (v.is_finite() && v > 0.0 && v <= HUGE).then(|| v.log10()),
    }
}

/// A resolved axis, in drawing-scale units.
pub(super) struct Axis {
    pub lo: f64,
    pub hi: f64,
    /// Labelled ticks: position and text.
    pub major: Vec<(f64, String)>,
    /// Unlabelled grid lines.
    pub minor: Vec<f64>,
}

/// The range on the drawing scale: the fixed range if usable, else the data's, padded.
pub(super) fn resolve_range(
    scale: Scale,
    fixed: Option<(f64, f64)>,
    data: &[f64],
    pad: f64,
) -> (f64, f64) {
    if let Some((a, b)) = fixed
        && let (Some(a), Some(b)) = (tr(scale, a), tr(scale, b))
        && a != b
    {
        return (a.min(b), a.max(b));
    }
    let (mut lo, mut hi) = data
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
            (lo.min(v), hi.max(v))
        });
    if !(lo.is_finite() && hi.is_finite()) {
        return (0.0, 1.0);
    }
    let span = hi - lo;
    let tiny = 1e-9 * lo.abs().max(hi.abs());
    if span <= tiny {
        let d = match scale {
            Scale::Log10 => 0.5,
            Scale::Linear if lo.abs() > 0.0 => 0.1 * lo.abs(),
            Scale::Linear => 1.0,
        };
        lo -= d;
        hi += d;
    } else {
        lo -= pad * span;
        hi += pad * span;
    }
    (lo, hi)
}

/// The 1, 2 or 5 × 10^k step that divides `span` into the number of steps closest to `target`
/// (the larger step on a tie).
fn nice_step(span: f64, target: usize) -> f64 {
    let target = target.max(1) as f64;
    let e = (span / target).log10().floor();
    let mut best = f64::NAN;
    let mut best_err = f64::INFINITY;
    for de in [-1.0, 0.0, 1.0] {
        for m in [1.0, 2.0, 5.0] {
            let step = m * 10f64.powf(e + de);
            let err = (span / step - target).abs();
            if err <= best_err {
                best_err = err;
                best = step;
            }
        }
    }
    best
}

fn minus(s: String) -> String {
    if s.starts_with('-') {
        s.replacen('-', "−", 1)
    } else {
        s
    }
}

/// Formats a tick value whose ticks are `step` apart.
fn fmt_tick(v: f64, step: f64) -> String {
    let mag = v.abs();
    if mag < step * 1e-6 {
        return "0".into();
    }
    let dec = (-step.log10().floor()).max(0.0) as usize;
    if (1e-4..1e6).contains(&mag) && dec <= 6 {
        minus(format!("{v:.dec$}"))
    } else {
        // Significant digits that `step` still resolves.
        let digits = (mag.log10().floor() - step.log10().floor()).clamp(0.0, 6.0) as usize;
        let s = format!("{v:.digits$e}");
        minus(s.replace("e-", "e−"))
    }
}

/// Ticks of a linear axis with about `target` labels (no minor grid: it only adds clutter).
fn linear_ticks(lo: f64, hi: f64, target: usize) -> (Vec<(f64, String)>, Vec<f64>) {
    let step = nice_step(hi - lo, target.max(2));
    if !(step.is_finite() && step > 0.0) {
        return (Vec::new(), Vec::new());
    }
    let k0 = (lo / step).ceil() as i64;
    let k1 = (hi / step).floor() as i64;
    let major = (k0..=k1.min(k0 + 200))
        .map(|k| {
            let v = k as f64 * step;
            (v, fmt_tick(v, step))
        })
        .collect();
    (major, Vec::new())
}

/// Formats `m`·10^`d` for a log axis label.
fn fmt_log(m: u32, d: i32) -> String {
    if (-4..=5).contains(&d) {
        let v = f64::from(m) * 10f64.powi(d);
        let dec = (-d).max(0) as usize;
        format!("{v:.dec$}")
    } else {
        format!("{m}e{}", d.to_string().replace('-', "−"))
    }
}

/// Ticks of a log axis spanning `lo..hi` decades (log10 units), with about `target` labels.
fn log_ticks(lo: f64, hi: f64, target: usize) -> (Vec<(f64, String)>, Vec<f64>) {
    let d0 = lo.floor() as i32;
    let d1 = hi.ceil() as i32;
    let inside = |p: f64| p >= lo - 1e-9 && p <= hi + 1e-9;
    let sets: [&[u32]; 4] = [
        &[1, 2, 3, 4, 5, 6, 7, 8, 9],
        &[1, 2, 3, 5],
        &[1, 2, 5],
        &[1],
    ];
    let target = target.max(2);
    let decades = d1.saturating_sub(d0).max(1);
    let stride = if decades as usize > target {
        (decades as usize).div_ceil(target) as i32
    } else {
        1
    };
    let mut major = Vec::new();
    for set in sets {
        major.clear();
        for d in d0..=d1 {
            if (d - d0) % stride != 0 {
                continue;
            }
            for &m in set {
                let p = f64::from(m).log10() + f64::from(d);
                if inside(p) {
                    major.push((p, fmt_log(m, d)));
                }
            }
        }
        if major.len() <= target {
            break;
        }
    }
    if major.len() < 2 {
        // Less than a decade between labels: use linear ticks on the values.
        let (a, b) = (10f64.powf(lo), 10f64.powf(hi));
        let (lin, _) = linear_ticks(a, b, target.min(6));
        let major: Vec<(f64, String)> = lin
            .into_iter()
            .filter(|(v, _)| *v > 0.0)
            .map(|(v, s)| (v.log10(), s))
            .collect();
        return (major, Vec::new());
    }
    let mut minor = Vec::new();
    if stride == 1 && decades <= 12 {
        for d in d0..=d1 {
            for m in 1..=9u32 {
                let p = f64::from(m).log10() + f64::from(d);
                if inside(p) && !major.iter().any(|(q, _)| (q - p).abs() < 1e-9) {
                    minor.push(p);
                }
            }
        }
    } else {
        for d in d0..=d1 {
            let p = f64::from(d);
            if inside(p) && !major.iter().any(|(q, _)| (q - p).abs() < 1e-9) {
                minor.push(p);
            }
        }
    }
    (major, minor)
}

/// The axis of `scale` over `lo..hi` (drawing scale) with about `target` labels.
pub(super) fn make_axis(scale: Scale, (lo, hi): (f64, f64), target: usize) -> Axis {
    let (major, minor) = match scale {
        Scale::Linear => linear_ticks(lo, hi, target),
        Scale::Log10 => log_ticks(lo, hi, target),
    };
    Axis {
        lo,
        hi,
        major,
        minor,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A label read back as a number (labels use the typographic minus).
    fn value(label: &str) -> f64 {
        label.replace('−', "-").parse().unwrap()
    }

    /// Splits a positive step into mantissa and exponent: `step = m · 10^e`.
    fn mantissa(step: f64) -> f64 {
        step / 10f64.powf(step.log10().floor())
    }

    #[test]
    fn steps_are_nice_numbers_near_the_target_count() {
        for span in [1e-7, 3.3e-3, 0.89, 1.0, 7.0, 9.99, 42.0, 1234.5, 6.02e23] {
            for target in 2..=10 {
                let step = nice_step(span, target);
                let m = mantissa(step);
                assert!(
                    [1.0, 2.0, 5.0].iter().any(|n| (m - n).abs() < 1e-9),
                    "span {span}, target {target}: step {step}"
                );
                let n = span / step;
                let t = target as f64;
                assert!(
                    n >= t / 2.5 && n <= t * 2.5,
                    "{span}/{step} = {n} steps for {t}"
                );
            }
        }
    }

    #[test]
    fn linear_ticks_cover_the_range_evenly() {
        let ranges = [
            (-0.37, 0.52),
            (0.0, 1.0),
            (-35.0, 35.0),
            (1013.0, 1017.5),
            (-2.5e-6, 7.5e-6),
            (12.0, 6000.0),
        ];
        for (lo, hi) in ranges {
            for target in [3, 6, 10] {
                let (major, minor) = linear_ticks(lo, hi, target);
                assert!(minor.is_empty());
                assert!(major.len() >= 2, "{lo}..{hi}: {major:?}");
                let step = major[1].0 - major[0].0;
                for w in major.windows(2) {
                    assert!(((w[1].0 - w[0].0) - step).abs() <= 1e-9 * step);
                }
                // Inside the range, and no gap of a whole step at either end.
                let (first, last) = (major[0].0, major[major.len() - 1].0);
                assert!(first >= lo && last <= hi, "{lo}..{hi}: {major:?}");
                assert!(
                    first - lo < step && hi - last < step,
                    "{lo}..{hi}: {major:?}"
                );
                for (v, label) in &major {
                    assert!(
                        (v / step - (v / step).round()).abs() < 1e-6,
                        "{v} off the grid"
                    );
                    assert!((value(label) - v).abs() <= 1e-6 * step, "{label} ≠ {v}");
                }
            }
        }
        let (major, _) = linear_ticks(-0.37, 0.52, 6);
        let labels: Vec<&str> = major.iter().map(|t| t.1.as_str()).collect();
        assert_eq!(labels, ["−0.2", "0", "0.2", "0.4"]);
    }

    #[test]
    fn log_ticks_sit_on_their_values() {
        // 0.3 … 30: 1-2-5 labels, every other integer multiple as a sub-line.
        let (major, minor) = log_ticks(0.3f64.log10(), 30f64.log10(), 6);
        let labels: Vec<&str> = major.iter().map(|t| t.1.as_str()).collect();
        assert_eq!(labels, ["0.5", "1", "2", "5", "10", "20"]);
        for (p, label) in &major {
            assert!((value(label).log10() - p).abs() < 1e-12, "{label} at {p}");
        }
        let mut subs: Vec<f64> = minor.iter().map(|p| 10f64.powf(*p)).collect();
        subs.sort_by(f64::total_cmp);
        let expect = [
            0.3, 0.4, 0.6, 0.7, 0.8, 0.9, 3.0, 4.0, 6.0, 7.0, 8.0, 9.0, 30.0,
        ];
        assert_eq!(subs.len(), expect.len(), "{subs:?}");
        for (a, b) in subs.iter().zip(expect) {
            assert!((a - b).abs() < 1e-9 * b, "{subs:?}");
        }
        // Eleven decades, six labels at most: every other decade, decade sub-lines.
        let (major, minor) = log_ticks(-7.2, 3.1, 6);
        let labels: Vec<&str> = major.iter().map(|t| t.1.as_str()).collect();
        assert_eq!(labels, ["1e−6", "0.0001", "0.01", "1", "100"]);
        assert!(minor.iter().all(|p| (p - p.round()).abs() < 1e-12));
        // Less than a decade: linear ticks on the values, still placed at their logarithm.
        let (major, _) = log_ticks(2f64.log10(), 2.8f64.log10(), 6);
        assert!(major.len() >= 3, "{major:?}");
        for (p, label) in &major {
            let v = value(label);
            assert!((2.0..=2.8).contains(&v) && (v.log10() - p).abs() < 1e-9);
        }
    }

    #[test]
    fn tick_labels_are_short() {
        assert_eq!(fmt_tick(1.5e-6, 5e-7), "1.5e−6");
        assert_eq!(fmt_tick(2000.0, 500.0), "2000");
        assert_eq!(fmt_tick(-35.0, 5.0), "−35");
        assert_eq!(fmt_tick(1e-17, 0.1), "0");
        assert_eq!(fmt_log(2, -3), "0.002");
        assert_eq!(fmt_log(5, 7), "5e7");
    }

    #[test]
    fn ranges_fit_the_data_or_take_the_fixed_range() {
        assert_eq!(
            resolve_range(Scale::Linear, Some((3.0, -1.0)), &[], 0.05),
            (-1.0, 3.0)
        );
        // An unusable fixed range falls back to the data, padded by 5 % of the span.
        let (lo, hi) = resolve_range(Scale::Linear, Some((f64::NAN, 1.0)), &[0.0, 10.0], 0.05);
        assert!((lo + 0.5).abs() < 1e-12 && (hi - 10.5).abs() < 1e-12);
        assert!(resolve_range(Scale::Log10, Some((-1.0, 10.0)), &[0.0, 1.0], 0.0) == (0.0, 1.0));
        // Flat data get a span; no data a unit range.
        assert_eq!(
            resolve_range(Scale::Linear, None, &[5.0, 5.0], 0.05),
            (4.5, 5.5)
        );
        assert_eq!(resolve_range(Scale::Log10, None, &[1.0], 0.05), (0.5, 1.5));
        assert_eq!(resolve_range(Scale::Linear, None, &[], 0.05), (0.0, 1.0));
        // The drawing scale drops what cannot be drawn.
        assert_eq!(tr(Scale::Log10, 100.0), Some(2.0));
        for v in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert_eq!(tr(Scale::Log10, v), None, "{v}");
        }
        assert_eq!(tr(Scale::Linear, f64::NEG_INFINITY), None);
        assert_eq!(tr(Scale::Linear, -3.0), Some(-3.0));
    }
}
