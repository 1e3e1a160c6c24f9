//! Figure layout and panel drawing: the figure title, panels sharing one set of margins (so
//! their plot areas line up), and for each panel the shaded intervals, grid, reference lines,
//! series, frame, ticks, titles, labels and legend, in that order.

use super::canvas::{
    AXIS, AXIS_TITLE_PX, Ctx, FIG_TITLE_PX, Frame, GAP_TICK_LABEL, GRID, GRID_MINOR, HAlign,
    PANEL_TITLE_PX, REF_LINE, Rect, SPAN, TEXT, TEXT_MUTED, TICK_LEN, TICK_PX, TextStyle, VAlign,
    backend, draw_text, fill, fit_size, text_width,
};
use super::clip::{clip_polyline, decimate, inside, transformed};
use super::legend::{Occupancy, Pieces, draw_legend, draw_ref_labels};
use super::ticks::{Axis, make_axis, resolve_range, tr};
use super::{Figure, Panel, PlotError, Scale, Series, SeriesStyle};
use plotters::coord::Shift;
use plotters::element::DashedPathElement;
use plotters::prelude::*;

/// Where a panel was drawn (unscaled px).
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Drawn {
    /// The plot area.
    pub frame: Frame,
    /// The legend box, if the panel has one.
    pub legend: Option<Rect>,
}

/// Maps drawing-scale values of a panel to pixels.
struct View<'a> {
    f: Frame,
    xa: &'a Axis,
    ya: &'a Axis,
}

impl View<'_> {
    /// Unscaled px (pixel centres at .5).
    fn x(&self, v: f64) -> f64 {
        let t = (v - self.xa.lo) / (self.xa.hi - self.xa.lo);
        f64::from(self.f.l) + 0.5 + t.clamp(-1.0, 2.0) * f64::from(self.f.r - self.f.l - 1)
    }
    fn y(&self, v: f64) -> f64 {
        let t = (v - self.ya.lo) / (self.ya.hi - self.ya.lo);
        f64::from(self.f.b) - 0.5 - t.clamp(-1.0, 2.0) * f64::from(self.f.b - self.f.t - 1)
    }
    /// Backend px of a drawing-scale point.
    fn pt(&self, ctx: &Ctx, (x, y): (f64, f64)) -> (i32, i32) {
        (
            (self.x(x) * ctx.s).round() as i32,
            (self.y(y) * ctx.s).round() as i32,
        )
    }
}

/// Space around the plot areas (unscaled px).
struct Margins {
    left: i32,
    right: i32,
    top: i32,
    bottom: i32,
}

/// Margins that hold the widest y tick label, half the last x label, titles and axis titles.
fn margins(fig: &Figure, axes: &[(Axis, Axis, bool)], ctx: &Ctx) -> Margins {
    let mut tick_w: f64 = 0.0;
    let mut right: f64 = 16.0;
    for (xa, ya, _) in axes {
        for (_, s) in &ya.major {
            tick_w = tick_w.max(text_width(ctx, s, TICK_PX));
        }
        if let Some((_, s)) = xa.major.last() {
            right = right.max(0.5 * text_width(ctx, s, TICK_PX) + 8.0);
        }
    }
    let any_y_label = fig.panels.iter().any(|p| !p.y_label.trim().is_empty());
    let any_title = fig.panels.iter().any(|p| !p.title.trim().is_empty());
    let y_title = if any_y_label {
        ctx.cap(AXIS_TITLE_PX) + ctx.desc(AXIS_TITLE_PX) + 10.0
    } else {
        0.0
    };
    Margins {
        left: (10.0 + y_title + tick_w + GAP_TICK_LABEL + TICK_LEN + 1.0).ceil() as i32,
        right: right.ceil() as i32,
        top: if any_title {
            (ctx.cap(PANEL_TITLE_PX) + ctx.desc(PANEL_TITLE_PX) + 20.0).ceil() as i32
        } else {
            14
        },
        bottom: (1.0
            + TICK_LEN
            + GAP_TICK_LABEL
            + ctx.cap(TICK_PX)
            + 11.0
            + ctx.cap(AXIS_TITLE_PX)
            + ctx.desc(AXIS_TITLE_PX)
            + 8.0)
            .ceil() as i32,
    }
}

/// Draws `fig` on `root` (white background first); where each panel went.
pub(super) fn render<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    fig: &Figure,
    ctx: &Ctx,
) -> Result<Vec<Drawn>, PlotError> {
    root.fill(&WHITE).map_err(backend)?;
    let (w, h) = root.dim_in_pixel();
    let w = (f64::from(w) / ctx.s).round() as i32;
    let h = (f64::from(h) / ctx.s).round() as i32;

    let mut top = 6;
    if !fig.title.trim().is_empty() {
        let em = fit_size(ctx, &fig.title, FIG_TITLE_PX, f64::from(w - 20));
        draw_text(
            root,
            ctx,
            &fig.title,
            (ctx.px(f64::from(w) / 2.0), ctx.px(12.0)),
            TextStyle::new(em, TEXT, HAlign::Center, VAlign::Top),
        )?;
        top = (12.0 + ctx.cap(em) + ctx.desc(em) + 8.0).ceil() as i32;
    }
    if fig.panels.is_empty() {
        return Ok(Vec::new());
    }
    let n = fig.panels.len() as i32;
    let panel_h = ((h - top - 2) / n).max(1);

    // Axes and margins depend on each other (tick density ↔ plot size): two passes. All
    // panels share the margins, so their plot areas line up.
    let guess = Margins {
        left: 90,
        right: 20,
        top: 34,
        bottom: 56,
    };
    let plot_size = |m: &Margins| {
        (
            (w - m.left - m.right).max(10),
            (panel_h - m.top - m.bottom).max(10),
        )
    };
    let all_axes = |(pw, ph): (i32, i32)| -> Vec<(Axis, Axis, bool)> {
        fig.panels
            .iter()
            .map(|p| panel_axes(p, pw, ph, ctx))
            .collect()
    };
    let axes = all_axes(plot_size(&guess));
    let axes = all_axes(plot_size(&margins(fig, &axes, ctx)));
    let m = margins(fig, &axes, ctx);

    let mut drawn = Vec::with_capacity(fig.panels.len());
    for (i, (panel, (xa, ya, has_data))) in fig.panels.iter().zip(&axes).enumerate() {
        let y0 = top + i as i32 * panel_h;
        let f = Frame {
            l: m.left,
            t: y0 + m.top,
            r: (w - m.right).max(m.left + 10),
            b: (y0 + panel_h - m.bottom).max(y0 + m.top + 10),
        };
        let view = View { f, xa, ya };
        let legend = draw_panel(root, panel, &view, *has_data, (y0, y0 + panel_h), ctx)?;
        drawn.push(Drawn { frame: f, legend });
    }
    Ok(drawn)
}

/// The panel's axes on the drawing scales, and whether any series has a drawable point.
fn panel_axes(p: &Panel, plot_w: i32, plot_h: i32, ctx: &Ctx) -> (Axis, Axis, bool) {
    let (xs, ys) = (p.x_scale, p.y_scale);
    let pts: Vec<(f64, f64)> = p
        .series
        .iter()
        .flat_map(|s| transformed(s, xs, ys).flatten())
        .collect();
    let has_data = !pts.is_empty();
    let xpad = match xs {
        Scale::Linear => 0.05,
        Scale::Log10 => 0.02,
    };
    let xv: Vec<f64> = pts.iter().map(|q| q.0).collect();
    let xr = resolve_range(xs, p.x_range, &xv, xpad);
    // The fitted y range covers the points inside the x range, and the reference lines.
    let mut yv: Vec<f64> = pts
        .iter()
        .filter(|q| q.0 >= xr.0 && q.0 <= xr.1)
        .map(|q| q.1)
        .collect();
    yv.extend(p.hlines.iter().filter_map(|(y, _)| tr(ys, *y)));
    let yr = resolve_range(ys, p.y_range, &yv, 0.05);
    let y_target = (f64::from(plot_h) / 48.0).round().clamp(2.0, 10.0) as usize;
    // As many x labels as fit with a clear gap between neighbours.
    let mut x_target = (f64::from(plot_w) / 100.0).round().clamp(2.0, 14.0) as usize;
    let xa = loop {
        let xa = make_axis(xs, xr, x_target);
        let fits = xa.major.windows(2).all(|w| {
            let room = (w[1].0 - w[0].0) / (xr.1 - xr.0) * f64::from(plot_w);
            let need =
                0.5 * (text_width(ctx, &w[0].1, TICK_PX) + text_width(ctx, &w[1].1, TICK_PX));
            room >= need + 14.0
        });
        if fits || x_target <= 2 {
            break xa;
        }
        x_target -= 1;
    };
    (xa, make_axis(ys, yr, y_target), has_data)
}

/// Draws one panel; its legend box.
fn draw_panel<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    panel: &Panel,
    v: &View<'_>,
    has_data: bool,
    area: (i32, i32),
    ctx: &Ctx,
) -> Result<Option<Rect>, PlotError> {
    draw_background(root, panel, v, ctx)?;
    let ref_labels = draw_ref_lines(root, panel, v, ctx)?;
    let prepared = prepare_series(panel, v, ctx);
    draw_series(root, &prepared, ctx)?;
    draw_axes(root, v, ctx)?;
    draw_titles(root, panel, v.f, area, ctx)?;

    let mut occ = Occupancy::new(v.f, 6);
    draw_ref_labels(root, ctx, &ref_labels, &mut occ)?;
    if !has_data {
        draw_no_data(root, v.f, ctx)?;
    }
    for (s, pieces) in &prepared {
        occ.mark_series(s.style, pieces, ctx.s);
    }
    draw_legend(root, panel, &occ, ctx)
}

/// Shaded intervals and the grid (minor, then major lines), behind everything.
fn draw_background<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    panel: &Panel,
    v: &View<'_>,
    ctx: &Ctx,
) -> Result<(), PlotError> {
    let (f, xa, ya) = (v.f, v.xa, v.ya);
    for &(a, b) in &panel.vspans {
        let (Some(a), Some(b)) = (tr(panel.x_scale, a), tr(panel.x_scale, b)) else {
            continue;
        };
        let (a, b) = (a.min(b).max(xa.lo), a.max(b).min(xa.hi));
        if a >= b {
            continue;
        }
        let (x0, x1) = (v.x(a).round() as i32, v.x(b).round() as i32);
        let shade = SPAN.mix(0.2).into();
        fill(root, ctx, [Rect::new(x0, f.t, x1.max(x0 + 1), f.b)], shade)?;
    }
    let majors = |a: &Axis| a.major.iter().map(|t| t.0).collect::<Vec<_>>();
    for (vals, color) in [(xa.minor.clone(), GRID_MINOR), (majors(xa), GRID)] {
        for x in vals {
            let c = v.x(x).floor() as i32;
            fill(root, ctx, [Rect::new(c, f.t, c + 1, f.b)], color.into())?;
        }
    }
    for (vals, color) in [(ya.minor.clone(), GRID_MINOR), (majors(ya), GRID)] {
        for y in vals {
            let r = v.y(y).floor() as i32;
            fill(root, ctx, [Rect::new(f.l, r, f.r, r + 1)], color.into())?;
        }
    }
    Ok(())
}

/// Dashed horizontal reference lines; their labels `(y px, text)` for later placement.
fn draw_ref_lines<'p, DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    panel: &'p Panel,
    v: &View<'_>,
    ctx: &Ctx,
) -> Result<Vec<(f64, &'p str)>, PlotError> {
    let mut labels = Vec::new();
    for (y, text) in &panel.hlines {
        let Some(yv) = tr(panel.y_scale, *y) else {
            continue;
        };
        if yv < v.ya.lo || yv > v.ya.hi {
            continue;
        }
        let (p0, p1) = (v.pt(ctx, (v.xa.lo, yv)), v.pt(ctx, (v.xa.hi, yv)));
        root.draw(&DashedPathElement::new(
            vec![p0, p1],
            ctx.px(7.0),
            ctx.px(4.0),
            REF_LINE.stroke_width(ctx.stroke(1.25)),
        ))
        .map_err(backend)?;
        labels.push((v.y(yv), text.as_str()));
    }
    Ok(labels)
}

/// Each series in backend px, clipped to the axes, lines decimated to ~4 points per backend
/// pixel column (2 per px in the SVG, for zooming).
fn prepare_series<'p>(panel: &'p Panel, v: &View<'_>, ctx: &Ctx) -> Vec<(&'p Series, Pieces)> {
    let (xs, ys) = (panel.x_scale, panel.y_scale);
    let bx = (v.xa.lo, v.xa.hi, v.ya.lo, v.ya.hi);
    let columns = ((v.f.r - v.f.l).max(1) as f64 * ctx.s.max(2.0)) as usize;
    panel
        .series
        .iter()
        .map(|s| {
            let pieces: Vec<Vec<(f64, f64)>> = match s.style {
                SeriesStyle::Line { .. } => clip_polyline(transformed(s, xs, ys), bx)
                    .into_iter()
                    .map(|p| decimate(p, v.xa.lo, v.xa.hi, columns))
                    .collect(),
                SeriesStyle::Markers { .. } => vec![
                    transformed(s, xs, ys)
                        .flatten()
                        .filter(|&p| inside(p, bx))
                        .collect(),
                ],
            };
            let px = pieces
                .into_iter()
                .map(|p| p.into_iter().map(|q| v.pt(ctx, q)).collect())
                .collect();
            (s, px)
        })
        .collect()
}

/// Lines first (a lone point as a dot), then markers with a white rim on top.
fn draw_series<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    prepared: &[(&Series, Pieces)],
    ctx: &Ctx,
) -> Result<(), PlotError> {
    for (s, pieces) in prepared {
        let SeriesStyle::Line {
            color,
            width,
            dashed,
        } = s.style
        else {
            continue;
        };
        let wf = f64::from(width.max(1));
        let style = color.to_plotters().stroke_width(ctx.stroke(wf));
        for piece in pieces {
            let Some(&first) = piece.first() else {
                continue;
            };
            if piece.iter().all(|&p| p == first) {
                let r = (ctx.s * (0.75 * wf + 1.0)).round() as i32;
                root.draw(&Circle::new(first, r, style.filled()))
                    .map_err(backend)?;
            } else if dashed {
                root.draw(&DashedPathElement::new(
                    piece.iter().copied(),
                    ctx.px(3.0 * wf + 4.0),
                    ctx.px(2.0 * wf + 2.0),
                    style,
                ))
                .map_err(backend)?;
            } else {
                draw_polyline(root, ctx, piece, style)?;
            }
        }
    }
    for (s, pieces) in prepared {
        let SeriesStyle::Markers { color, size } = s.style else {
            continue;
        };
        let r = ctx.px(f64::from(size.max(1))).max(1);
        let rim = r + ctx.px(1.0).max(1);
        let c = color.to_plotters();
        for &p in pieces.iter().flatten() {
            root.draw(&Circle::new(p, rim, WHITE.filled()))
                .map_err(backend)?;
            root.draw(&Circle::new(p, r, c.filled())).map_err(backend)?;
        }
    }
    Ok(())
}

/// The frame, tick marks and tick labels.
fn draw_axes<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    v: &View<'_>,
    ctx: &Ctx,
) -> Result<(), PlotError> {
    let f = v.f;
    let axis: ShapeStyle = AXIS.into();
    let frame = Rect::new(f.l - 1, f.t - 1, f.r + 1, f.b + 1);
    fill(root, ctx, frame.edges(), axis)?;
    let tick = TICK_LEN as i32;
    for (x, label) in &v.xa.major {
        let c = v.x(*x).floor() as i32;
        fill(
            root,
            ctx,
            [Rect::new(c, f.b + 1, c + 1, f.b + 1 + tick)],
            axis,
        )?;
        let at = (
            ctx.px(f64::from(c) + 0.5),
            ctx.px(f64::from(f.b + 1 + tick) + GAP_TICK_LABEL),
        );
        let st = TextStyle::new(TICK_PX, TEXT_MUTED, HAlign::Center, VAlign::Top);
        draw_text(root, ctx, label, at, st)?;
    }
    for (y, label) in &v.ya.major {
        let r = v.y(*y).floor() as i32;
        fill(
            root,
            ctx,
            [Rect::new(f.l - 1 - tick, r, f.l - 1, r + 1)],
            axis,
        )?;
        let at = (
            ctx.px(f64::from(f.l - 1 - tick) - GAP_TICK_LABEL),
            ctx.px(f64::from(r) + 0.5),
        );
        let st = TextStyle::new(TICK_PX, TEXT_MUTED, HAlign::End, VAlign::Center);
        draw_text(root, ctx, label, at, st)?;
    }
    Ok(())
}

/// Panel title above the plot area, x title below the tick labels, y title along the left
/// edge; each shrunk (to 70 % at most) to fit.
fn draw_titles<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    panel: &Panel,
    f: Frame,
    (area_top, area_bottom): (i32, i32),
    ctx: &Ctx,
) -> Result<(), PlotError> {
    let (plot_w, plot_h) = (f64::from(f.r - f.l), f64::from(f.b - f.t));
    let cx = f64::from(f.l + f.r) / 2.0;
    let em = fit_size(ctx, &panel.title, PANEL_TITLE_PX, plot_w);
    draw_text(
        root,
        ctx,
        &panel.title,
        (ctx.px(cx), ctx.px(f64::from(f.t) - 10.0)),
        TextStyle::new(em, TEXT, HAlign::Center, VAlign::Bottom),
    )?;
    let em = fit_size(ctx, &panel.x_label, AXIS_TITLE_PX, plot_w);
    let x_title_top = f64::from(f.b + 1) + TICK_LEN + GAP_TICK_LABEL + ctx.cap(TICK_PX) + 11.0;
    let y = x_title_top.min(f64::from(area_bottom) - ctx.cap(em) - 4.0);
    draw_text(
        root,
        ctx,
        &panel.x_label,
        (ctx.px(cx), ctx.px(y)),
        TextStyle::new(em, TEXT, HAlign::Center, VAlign::Top),
    )?;
    let avail = plot_h + f64::from(f.t - area_top) * 0.5;
    let em = fit_size(ctx, &panel.y_label, AXIS_TITLE_PX, avail);
    let st = TextStyle {
        vertical: true,
        ..TextStyle::new(em, TEXT, HAlign::Center, VAlign::Top)
    };
    let at = (ctx.px(10.0), ctx.px(f64::from(f.t + f.b) / 2.0));
    draw_text(root, ctx, &panel.y_label, at, st)
}

/// "no data" in a white box in the middle of the plot area.
fn draw_no_data<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    f: Frame,
    ctx: &Ctx,
) -> Result<(), PlotError> {
    let note = "no data";
    let tw = text_width(ctx, note, 16.0);
    let (cx, cy) = (f64::from(f.l + f.r) / 2.0, f64::from(f.t + f.b) / 2.0);
    let (hw, hh) = (tw / 2.0 + 8.0, ctx.cap(16.0) / 2.0 + 8.0);
    root.draw(&Rectangle::new(
        [
            (ctx.px(cx - hw), ctx.px(cy - hh)),
            (ctx.px(cx + hw), ctx.px(cy + hh)),
        ],
        WHITE.filled(),
    ))
    .map_err(backend)?;
    draw_text(
        root,
        ctx,
        note,
        (ctx.px(cx), ctx.px(cy)),
        TextStyle::new(16.0, TEXT_MUTED, HAlign::Center, VAlign::Center),
    )
}

/// Draws a solid polyline (backend px). plotters fills a wide path as one polygon, which
/// leaves holes where the path doubles back (dense time histories): in the PNG the path is
/// drawn in gently turning runs instead, joined by round dots (an SVG stroke needs no help).
fn draw_polyline<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    ctx: &Ctx,
    pts: &[(i32, i32)],
    style: ShapeStyle,
) -> Result<(), PlotError> {
    let mut pts: Vec<(i32, i32)> = pts.to_vec();
    pts.dedup();
    if pts.len() < 2 {
        return Ok(());
    }
    if style.stroke_width <= 1 || !ctx.bitmap {
        return root.draw(&PathElement::new(pts, style)).map_err(backend);
    }
    let r = (style.stroke_width / 2).max(1) as i32;
    let dot = ShapeStyle {
        color: style.color,
        filled: true,
        stroke_width: 0,
    };
    let sharp = |a: (i32, i32), b: (i32, i32), c: (i32, i32)| {
        let (ux, uy) = (f64::from(b.0 - a.0), f64::from(b.1 - a.1));
        let (vx, vy) = (f64::from(c.0 - b.0), f64::from(c.1 - b.1));
        ux * vx + uy * vy < 0.64 * ux.hypot(uy) * vx.hypot(vy) // turns by more than ~50°
    };
    let mut start = 0;
    for i in 1..pts.len() {
        let end = i + 1 == pts.len();
        if end || i - start >= 48 || sharp(pts[i - 1], pts[i], pts[i + 1]) {
            root.draw(&PathElement::new(pts[start..=i].to_vec(), style))
                .map_err(backend)?;
            if !end {
                root.draw(&Circle::new(pts[i], r, dot)).map_err(backend)?;
            }
            start = i;
        }
    }
    Ok(())
}
