//! Placement of what is drawn over the data: a coarse occupancy grid of the plot area records
//! where lines, markers and labels are, the reference-line labels go just above (or below)
//! their line, and the legend goes to the corner where it hides the least.
//!
//! plotters' `SeriesLabelPosition` is a fixed corner or coordinate and does not look at the
//! data, hence this module.

use super::canvas::{
    Ctx, Frame, HAlign, LEGEND_BORDER, LEGEND_PX, NOTE_PX, Rect, TEXT, TEXT_MUTED, TextStyle,
    VAlign, backend, draw_text, fill, text_width,
};
use super::{Panel, PlotError, Series, SeriesStyle};
use plotters::coord::Shift;
use plotters::element::DashedPathElement;
use plotters::prelude::*;

/// Polyline pieces (or one marker set) in backend px.
pub(super) type Pieces = Vec<Vec<(i32, i32)>>;

/// Coarse grid over a plot area counting what is drawn where, to place the legend.
pub(super) struct Occupancy {
    f: Frame,
    cell: i32,
    cols: usize,
    cells: Vec<u32>,
}

impl Occupancy {
    /// An empty grid of `cell` px cells over the plot area `f` (unscaled px).
    pub fn new(f: Frame, cell: i32) -> Self {
        let cols = ((f.r - f.l).max(1) / cell + 1) as usize;
        let rows = ((f.b - f.t).max(1) / cell + 1) as usize;
        Self {
            f,
            cell,
            cols,
            cells: vec![0; cols * rows],
        }
    }
    fn idx(&self, (px, py): (i32, i32)) -> Option<usize> {
        if px < self.f.l || px >= self.f.r || py < self.f.t || py >= self.f.b {
            return None;
        }
        let c = ((px - self.f.l) / self.cell) as usize;
        let r = ((py - self.f.t) / self.cell) as usize;
        Some(r * self.cols + c)
    }
    /// Adds weight `w` at point `p`.
    pub fn mark_point(&mut self, p: (i32, i32), w: u32) {
        if let Some(i) = self.idx(p) {
            self.cells[i] = self.cells[i].saturating_add(w).min(1000);
        }
    }
    /// Marks the cells a segment passes through with weight `w` (once per cell).
    pub fn mark_segment(&mut self, a: (i32, i32), b: (i32, i32), w: u32) {
        let len = f64::from((b.0 - a.0).abs().max((b.1 - a.1).abs()));
        let steps = (2.0 * len / f64::from(self.cell))
            .ceil()
            .clamp(1.0, 10_000.0) as i32;
        for k in 0..=steps {
            let t = f64::from(k) / f64::from(steps);
            let p = (
                (f64::from(a.0) + t * f64::from(b.0 - a.0)).round() as i32,
                (f64::from(a.1) + t * f64::from(b.1 - a.1)).round() as i32,
            );
            if let Some(i) = self.idx(p) {
                // A line counts once per cell, however many of its points fall in it.
                self.cells[i] = self.cells[i].max(w);
            }
        }
    }
    /// Adds weight `w` over a box.
    pub fn mark_rect(&mut self, r: Rect, w: u32) {
        for y in (r.y0..=r.y1).step_by(self.cell as usize) {
            for x in (r.x0..=r.x1).step_by(self.cell as usize) {
                self.mark_point((x, y), w);
            }
        }
    }
    /// Records a drawn series (backend px, `s` backend px per unscaled px); markers weigh
    /// more than lines, as a legend over a measured point hides more than over a curve.
    pub fn mark_series(&mut self, style: SeriesStyle, pieces: &[Vec<(i32, i32)>], s: f64) {
        let markers = matches!(style, SeriesStyle::Markers { .. });
        let weight = if markers { 3 } else { 1 };
        let unscale = |p: (i32, i32)| ((f64::from(p.0) / s) as i32, (f64::from(p.1) / s) as i32);
        for piece in pieces {
            if piece.len() == 1 || markers {
                for &p in piece {
                    self.mark_point(unscale(p), weight);
                }
            } else {
                for w in piece.windows(2) {
                    self.mark_segment(unscale(w[0]), unscale(w[1]), weight);
                }
            }
        }
    }
    fn cost(&self, r: Rect) -> u64 {
        let mut sum = 0u64;
        for y in (r.y0..=r.y1).step_by(self.cell as usize) {
            for x in (r.x0..=r.x1).step_by(self.cell as usize) {
                if let Some(i) = self.idx((x, y)) {
                    sum += u64::from(self.cells[i]);
                }
            }
        }
        sum
    }
}

/// Gap between a legend box and the plot frame (px).
const INSET: i32 = 8;

/// Where a `w` × `h` box inset in a corner of the plot area hides the least; on ties upper
/// right, upper left, lower right, lower left, in that order.
pub(super) fn place_box(occ: &Occupancy, w: i32, h: i32) -> Rect {
    let f = occ.f;
    let (left, right) = (f.l + INSET, f.r - INSET - w);
    let (top, bottom) = (f.t + INSET, f.b - INSET - h);
    let mut best = None;
    let mut best_cost = u64::MAX;
    for (x, y) in [(right, top), (left, top), (right, bottom), (left, bottom)] {
        let r = Rect::new(x, y, x + w, y + h);
        let cost = occ.cost(r);
        if cost < best_cost || best.is_none() {
            best_cost = cost;
            best = Some(r);
        }
    }
    best.unwrap_or(Rect::new(right, top, right + w, top + h))
}

/// Draws the labels of the reference lines `(y px, text)` just above each line at its left
/// end (below it if there is no room, left out if neither fits), and marks them as occupied.
pub(super) fn draw_ref_labels<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    ctx: &Ctx,
    labels: &[(f64, &str)],
    occ: &mut Occupancy,
) -> Result<(), PlotError> {
    let f = occ.f;
    let mut placed: Vec<(f64, f64)> = Vec::new();
    for &(py, text) in labels {
        if text.trim().is_empty() {
            continue;
        }
        let tw = text_width(ctx, text, NOTE_PX);
        let th = ctx.cap(NOTE_PX) + ctx.desc(NOTE_PX);
        let pad = 3.0;
        let x0 = f64::from(f.l) + 6.0;
        let x1 = x0 + tw + 2.0 * pad;
        let h = th + 2.0 * pad;
        let free = |y0: f64| {
            y0 >= f64::from(f.t)
                && y0 + h <= f64::from(f.b)
                && placed.iter().all(|&(a, b)| y0 + h <= a || y0 >= b)
        };
        let Some(y_top) = [py - h - 2.0, py + 2.0].into_iter().find(|&y| free(y)) else {
            continue;
        };
        let y_bot = y_top + h;
        placed.push((y_top, y_bot));
        root.draw(&Rectangle::new(
            [(ctx.px(x0), ctx.px(y_top)), (ctx.px(x1), ctx.px(y_bot))],
            WHITE.mix(0.8).filled(),
        ))
        .map_err(backend)?;
        draw_text(
            root,
            ctx,
            text,
            (ctx.px(x0 + pad), ctx.px(y_bot - pad)),
            TextStyle::new(NOTE_PX, TEXT_MUTED, HAlign::Start, VAlign::Bottom),
        )?;
        let r = Rect::new(
            x0 as i32,
            y_top as i32,
            x1.ceil() as i32,
            y_bot.ceil() as i32,
        );
        occ.mark_rect(r, 50);
    }
    Ok(())
}

/// Draws the legend of `panel`'s labelled series where it hides the least of what `occ`
/// records; returns its box (unscaled px), `None` if no series has a label.
pub(super) fn draw_legend<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    panel: &Panel,
    occ: &Occupancy,
    ctx: &Ctx,
) -> Result<Option<Rect>, PlotError> {
    let entries: Vec<&Series> = panel
        .series
        .iter()
        .filter(|s| !s.label.trim().is_empty())
        .collect();
    if entries.is_empty() {
        return Ok(None);
    }
    let f = occ.f;
    let (pad, glyph_w, gap, col_gap) = (8, 28, 7, 16);
    // As many rows as fit in the plot's height, then more columns.
    let row_h = (LEGEND_PX * 1.4).round() as i32;
    let avail_h = (f.b - f.t) - 2 * INSET - 2 * pad;
    let rows = ((avail_h / row_h).max(1) as usize).min(entries.len());
    let ncols = entries.len().div_ceil(rows);
    let mut col_w = vec![0i32; ncols];
    for (i, s) in entries.iter().enumerate() {
        let w = text_width(ctx, &s.label, LEGEND_PX).ceil() as i32;
        col_w[i / rows] = col_w[i / rows].max(glyph_w + gap + w);
    }
    let box_w = col_w.iter().sum::<i32>() + col_gap * (ncols as i32 - 1) + 2 * pad;
    let box_h = rows as i32 * row_h + 2 * pad - 4;
    let b = place_box(occ, box_w, box_h);

    let corner = |x: i32, y: i32| (ctx.px(f64::from(x)), ctx.px(f64::from(y)));
    root.draw(&Rectangle::new(
        [corner(b.x0, b.y0), corner(b.x1, b.y1)],
        WHITE.mix(0.85).filled(),
    ))
    .map_err(backend)?;
    fill(root, ctx, b.edges(), LEGEND_BORDER.into())?;

    let mut x = b.x0 + pad;
    for (c, chunk) in entries.chunks(rows).enumerate() {
        for (r, s) in chunk.iter().enumerate() {
            let cy = f64::from(b.y0 + pad + r as i32 * row_h) + f64::from(row_h) / 2.0 - 2.0;
            let (x0, x1, y) = (
                ctx.px(f64::from(x)),
                ctx.px(f64::from(x + glyph_w)),
                ctx.px(cy),
            );
            draw_key(root, ctx, s.style, (x0, x1), y)?;
            draw_text(
                root,
                ctx,
                &s.label,
                (ctx.px(f64::from(x + glyph_w + gap)), y),
                TextStyle::new(LEGEND_PX, TEXT, HAlign::Start, VAlign::Center),
            )?;
        }
        x += col_w[c] + col_gap;
    }
    Ok(Some(b))
}

/// The sample of a series in the legend, between backend x `x0..x1` at backend y `y`.
fn draw_key<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    ctx: &Ctx,
    style: SeriesStyle,
    (x0, x1): (i32, i32),
    y: i32,
) -> Result<(), PlotError> {
    match style {
        SeriesStyle::Line {
            color,
            width,
            dashed,
        } => {
            let wf = f64::from(width.max(1));
            let style = color.to_plotters().stroke_width(ctx.stroke(wf));
            if dashed {
                root.draw(&DashedPathElement::new(
                    vec![(x0, y), (x1, y)],
                    ctx.px(1.5 * wf + 4.0),
                    ctx.px(wf + 2.0),
                    style,
                ))
            } else {
                root.draw(&PathElement::new(vec![(x0, y), (x1, y)], style))
            }
            .map_err(backend)
        }
        SeriesStyle::Markers { color, size } => {
            let r = ctx.px(f64::from(size.max(1))).max(1);
            root.draw(&Circle::new(
                ((x0 + x1) / 2, y),
                r,
                color.to_plotters().filled(),
            ))
            .map_err(backend)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const F: Frame = Frame {
        l: 100,
        t: 50,
        r: 900,
        b: 450,
    };

    /// Bounding box of a set of points.
    fn bbox(pts: &[(i32, i32)]) -> Rect {
        Rect {
            x0: pts.iter().map(|p| p.0).min().unwrap(),
            y0: pts.iter().map(|p| p.1).min().unwrap(),
            x1: pts.iter().map(|p| p.0).max().unwrap() + 1,
            y1: pts.iter().map(|p| p.1).max().unwrap() + 1,
        }
    }

    /// A zig-zag line filling the box `r`.
    fn zigzag(r: Rect) -> Vec<(i32, i32)> {
        (0..=20)
            .map(|i| {
                let x = r.x0 + (r.x1 - 1 - r.x0) * i / 20;
                (x, if i % 2 == 0 { r.y0 } else { r.y1 - 1 })
            })
            .collect()
    }

    #[test]
    fn the_legend_avoids_the_data() {
        let (w, h) = (180, 90);
        // Data in the upper-right quadrant (the preferred corner), then the whole upper half.
        let upper_right = Rect::new(500, 50, 900, 250);
        let upper_left = Rect::new(100, 50, 500, 250);
        let mut occ = Occupancy::new(F, 6);
        let line = SeriesStyle::Line {
            color: super::super::palette(0),
            width: 2,
            dashed: false,
        };
        let a = zigzag(upper_right);
        occ.mark_series(line, std::slice::from_ref(&a), 1.0);
        let b = place_box(&occ, w, h);
        assert!(!b.intersects(&bbox(&a)), "{b:?} over {:?}", bbox(&a));
        assert_eq!(
            (b.x0, b.y0),
            (F.l + INSET, F.t + INSET),
            "upper left is free"
        );

        let c = zigzag(upper_left);
        occ.mark_series(line, std::slice::from_ref(&c), 1.0);
        let b = place_box(&occ, w, h);
        for data in [bbox(&a), bbox(&c)] {
            assert!(!b.intersects(&data), "{b:?} over {data:?}");
        }
        assert_eq!(
            (b.x1, b.y1),
            (F.r - INSET, F.b - INSET),
            "lower right is free"
        );

        // Markers (backend px at 2×) in three corners leave the fourth.
        let mut occ = Occupancy::new(F, 6);
        let dots = SeriesStyle::Markers {
            color: super::super::palette(1),
            size: 3,
        };
        let corners = [(880, 60), (120, 60), (880, 440)];
        let pts: Vec<(i32, i32)> = corners
            .iter()
            .flat_map(|&(x, y)| (0..5).map(move |k| (2 * (x + 3 * k - 6), 2 * y)))
            .collect();
        occ.mark_series(dots, &[pts], 2.0);
        let b = place_box(&occ, w, h);
        assert_eq!((b.x0, b.y1), (F.l + INSET, F.b - INSET));
    }

    #[test]
    fn boxes_intersect_only_when_they_overlap() {
        let a = Rect::new(0, 0, 10, 10);
        let touching = Rect::new(10, 0, 20, 10);
        let overlapping = Rect::new(9, 9, 20, 20);
        assert!(!a.intersects(&touching) && a.intersects(&overlapping));
        assert!(overlapping.intersects(&a));
    }
}
