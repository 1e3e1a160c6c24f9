//! Data preparation: points on the drawing scales, clipped to the plot area (plotters draws a
//! path wherever its points map, also over the axes), broken at points that cannot be drawn,
//! and thinned where a time history has many more points than the plot has pixel columns.

use super::ticks::tr;
use super::{Scale, Series};

/// Points of a series on the drawing scales; `None` where a point can't be drawn.
pub(super) fn transformed(
    s: &Series,
    xs: Scale,
    ys: Scale,
) -> impl Iterator<Item = Option<(f64, f64)>> {
    s.x.iter()
        .zip(&s.y)
        .map(move |(&x, &y)| Some((tr(xs, x)?, tr(ys, y)?)))
}

/// A box on the drawing scales: `(x0, x1, y0, y1)`.
pub(super) type Bounds = (f64, f64, f64, f64);

/// Whether `p` lies in the box (edges included).
pub(super) fn inside(p: (f64, f64), bx: Bounds) -> bool {
    p.0 >= bx.0 && p.0 <= bx.1 && p.1 >= bx.2 && p.1 <= bx.3
}

/// Liang–Barsky clip of segment `a`–`b` to the box; `None` if it misses.
pub(super) fn clip_segment(
    a: (f64, f64),
    b: (f64, f64),
    (x0, x1, y0, y1): Bounds,
) -> Option<((f64, f64), (f64, f64))> {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let mut t0 = 0.0f64;
    let mut t1 = 1.0f64;
    for (p, q) in [
        (-dx, a.0 - x0),
        (dx, x1 - a.0),
        (-dy, a.1 - y0),
        (dy, y1 - a.1),
    ] {
        if p == 0.0 {
            if q < 0.0 {
                return None;
            }
        } else {
            let r = q / p;
            if p < 0.0 {
                t0 = t0.max(r);
            } else {
                t1 = t1.min(r);
            }
        }
    }
    (t0 <= t1).then_some((
        (a.0 + t0 * dx, a.1 + t0 * dy),
        (a.0 + t1 * dx, a.1 + t1 * dy),
    ))
}

/// Splits a polyline at unusable points and clips it to the box; a piece of one point is a
/// valid point with gaps on both sides.
pub(super) fn clip_polyline(
    pts: impl Iterator<Item = Option<(f64, f64)>>,
    bx: Bounds,
) -> Vec<Vec<(f64, f64)>> {
    let mut pieces: Vec<Vec<(f64, f64)>> = Vec::new();
    let mut cur: Vec<(f64, f64)> = Vec::new();
    let mut prev: Option<(f64, f64)> = None;
    let inside = |p| inside(p, bx);
    for p in pts {
        match (prev, p) {
            (_, None) => {
                // A lone valid point between gaps stays, to be drawn as a dot.
                if !cur.is_empty() {
                    pieces.push(std::mem::take(&mut cur));
                }
            }
            (None, Some(q)) => {
                if inside(q) {
                    cur.push(q);
                }
            }
            (Some(a), Some(b)) => match clip_segment(a, b, bx) {
                None => {
                    if cur.len() > 1 {
                        pieces.push(std::mem::take(&mut cur));
                    }
                    cur.clear();
                }
                Some((ca, cb)) => {
                    if cur.last() != Some(&ca) {
                        if cur.len() > 1 {
                            pieces.push(std::mem::take(&mut cur));
                        }
                        cur.clear();
                        cur.push(ca);
                    }
                    cur.push(cb);
                    if cb != b {
                        // Left the box.
                        pieces.push(std::mem::take(&mut cur));
                    }
                }
            },
        }
        prev = p;
    }
    if !cur.is_empty() {
        pieces.push(cur);
    }
    pieces
}

/// Keeps first, lowest, highest and last point of every pixel column when a piece has many
/// more points than columns and x increases (time histories); the drawn envelope is unchanged.
pub(super) fn decimate(
    piece: Vec<(f64, f64)>,
    x0: f64,
    x1: f64,
    columns: usize,
) -> Vec<(f64, f64)> {
    if piece.len() <= 4 * columns || columns == 0 || piece.windows(2).any(|w| w[1].0 < w[0].0) {
        return piece;
    }
    let col = |x: f64| (((x - x0) / (x1 - x0)) * columns as f64).floor() as i64;
    let mut out = Vec::with_capacity(4 * columns + 4);
    let mut i = 0;
    while i < piece.len() {
        let c = col(piece[i].0);
        let mut j = i;
        let (mut lo, mut hi) = (i, i);
        while j < piece.len() && col(piece[j].0) == c {
            if piece[j].1 < piece[lo].1 {
                lo = j;
            }
            if piece[j].1 > piece[hi].1 {
                hi = j;
            }
            j += 1;
        }
        let mut keep = [i, lo.min(hi), lo.max(hi), j - 1];
        keep.sort_unstable();
        let mut last = usize::MAX;
        for k in keep {
            if k != last {
                out.push(piece[k]);
                last = k;
            }
        }
        i = j;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plot::palette;

    const UNIT: Bounds = (0.0, 1.0, 0.0, 1.0);

    #[test]
    fn non_finite_points_break_the_line_and_are_not_drawn() {
        let nan = f64::NAN;
        let s = Series::line(
            "",
            vec![0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7],
            vec![0.1, 0.2, nan, 0.4, 0.5, f64::INFINITY, 0.7, 0.8],
            palette(0),
        );
        let pieces = clip_polyline(transformed(&s, Scale::Linear, Scale::Linear), UNIT);
        let xs: Vec<Vec<f64>> = pieces
            .iter()
            .map(|p| p.iter().map(|q| q.0).collect())
            .collect();
        assert_eq!(xs, [vec![0.0, 0.1], vec![0.3, 0.4], vec![0.6, 0.7]]);
        assert!(
            pieces
                .iter()
                .flatten()
                .all(|p| p.0.is_finite() && p.1.is_finite())
        );
        // On a log axis, values ≤ 0 are gaps too; a lone drawable point stays (as a dot).
        let s = Series::line("", vec![1.0, 2.0, 3.0], vec![-1.0, 10.0, 0.0], palette(0));
        let pieces = clip_polyline(
            transformed(&s, Scale::Log10, Scale::Log10),
            (0.0, 1.0, 0.0, 2.0),
        );
        assert_eq!(pieces.len(), 1);
        assert_eq!(pieces[0].len(), 1);
        assert!((pieces[0][0].0 - 2f64.log10()).abs() < 1e-12 && pieces[0][0].1 == 1.0);
    }

    #[test]
    fn lines_are_clipped_at_the_box_edges() {
        // A diagonal from outside to outside crosses the box from (0, 0.5) to (0.5, 1).
        let (a, b) = clip_segment((-0.5, 0.0), (1.0, 1.5), UNIT).unwrap();
        assert!(
            (a.0 - 0.0).abs() < 1e-12 && (a.1 - 0.5).abs() < 1e-12,
            "{a:?}"
        );
        assert!(
            (b.0 - 0.5).abs() < 1e-12 && (b.1 - 1.0).abs() < 1e-12,
            "{b:?}"
        );
        assert!(clip_segment((2.0, 0.0), (3.0, 1.0), UNIT).is_none());
        // A polyline that leaves and re-enters gives two pieces, all inside.
        let pts = [(0.5, 0.5), (0.5, 2.0), (0.8, 0.5)].map(Some);
        let pieces = clip_polyline(pts.into_iter(), UNIT);
        assert_eq!(pieces.len(), 2, "{pieces:?}");
        let near = |p: (f64, f64)| inside(p, (-1e-12, 1.0 + 1e-12, -1e-12, 1.0 + 1e-12));
        assert!(pieces.iter().flatten().all(|&p| near(p)), "{pieces:?}");
        assert_eq!(pieces[0], [(0.5, 0.5), (0.5, 1.0)]);
    }

    #[test]
    fn decimation_keeps_each_columns_extremes() {
        let n = 10_000;
        let piece: Vec<(f64, f64)> = (0..n)
            .map(|i| {
                let t = i as f64 / n as f64;
                (t, (t * 300.0).sin() + if i == 4321 { 5.0 } else { 0.0 })
            })
            .collect();
        let thin = decimate(piece.clone(), 0.0, 1.0, 100);
        assert!(
            thin.len() <= 4 * 100 + 4 && thin.len() > 100,
            "{}",
            thin.len()
        );
        for c in 0..100 {
            let col = |p: &&(f64, f64)| (p.0 * 100.0).floor() as usize == c;
            let ext = |v: Vec<f64>| {
                (
                    v.iter().copied().fold(f64::INFINITY, f64::min),
                    v.iter().copied().fold(f64::NEG_INFINITY, f64::max),
                )
            };
            let full = ext(piece.iter().filter(col).map(|p| p.1).collect());
            let kept = ext(thin.iter().filter(col).map(|p| p.1).collect());
            assert_eq!(full, kept, "column {c}");
        }
        // Few points, or x not increasing: unchanged.
        let back: Vec<(f64, f64)> = vec![(1.0, 0.0), (0.0, 1.0)];
        assert_eq!(decimate(back.clone(), 0.0, 1.0, 0), back);
    }
}
