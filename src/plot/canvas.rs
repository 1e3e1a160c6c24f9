//! The drawing surface: the rendering context (scale, PNG or SVG, font), the colours and sizes
//! of the look, pixel-exact fills and text drawing.

use super::PlotError;
use super::text::{Font, layout};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use plotters::style::{FontStyle, FontTransform};

pub(super) const TEXT: RGBColor = RGBColor(25, 25, 25);
pub(super) const TEXT_MUTED: RGBColor = RGBColor(80, 80, 80);
pub(super) const AXIS: RGBColor = RGBColor(120, 120, 120);
pub(super) const GRID: RGBColor = RGBColor(220, 220, 220);
pub(super) const GRID_MINOR: RGBColor = RGBColor(239, 239, 239);
pub(super) const REF_LINE: RGBColor = RGBColor(90, 90, 90);
pub(super) const SPAN: RGBColor = RGBColor(255, 165, 50);
pub(super) const LEGEND_BORDER: RGBColor = RGBColor(200, 200, 200);

// Text sizes are em sizes in px, as CSS's `font-size`.
pub(super) const FIG_TITLE_PX: f64 = 19.0;
pub(super) const PANEL_TITLE_PX: f64 = 16.0;
pub(super) const AXIS_TITLE_PX: f64 = 15.0;
pub(super) const TICK_PX: f64 = 14.0;
pub(super) const LEGEND_PX: f64 = 14.0;
pub(super) const NOTE_PX: f64 = 13.0;
pub(super) const TICK_LEN: f64 = 5.0;
pub(super) const GAP_TICK_LABEL: f64 = 5.0;

/// How much wider than Ubuntu Light an SVG viewer's sans-serif may set text (DejaVu Sans).
const SVG_WIDTH_SLACK: f64 = 1.15;

/// `font-family` of SVG text.
const SVG_FONT_FAMILY: &str = "Ubuntu, sans-serif";

/// Rendering context: `s` scales every length (2 for the supersampled PNG); `bitmap` selects
/// glyph-by-glyph text (an SVG keeps whole strings, set in the viewer's sans-serif font).
pub(super) struct Ctx {
    pub s: f64,
    pub bitmap: bool,
    pub m: &'static Font,
}

impl Ctx {
    /// Unscaled px → backend px.
    pub fn px(&self, v: f64) -> i32 {
        (v * self.s).round() as i32
    }
    /// Stroke width in backend px.
    pub fn stroke(&self, v: f64) -> u32 {
        (v * self.s).round().max(1.0) as u32
    }
    /// Height of the capitals at `em` px.
    pub fn cap(&self, em: f64) -> f64 {
        self.m.cap * self.m.k(em)
    }
    /// Depth of the descenders at `em` px.
    pub fn desc(&self, em: f64) -> f64 {
        self.m.descent * self.m.k(em)
    }
}

/// A plotters drawing error as a [`PlotError`].
pub(super) fn backend<E: std::error::Error + Send + Sync>(e: DrawingAreaErrorKind<E>) -> PlotError {
    PlotError::Backend(e.to_string())
}

/// A plot area in unscaled px: interior columns `l..r`, rows `t..b`; the frame is drawn just
/// outside it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Frame {
    pub l: i32,
    pub t: i32,
    pub r: i32,
    pub b: i32,
}

/// A box in unscaled px: columns `x0..x1`, rows `y0..y1`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Rect {
    pub x0: i32,
    pub y0: i32,
    pub x1: i32,
    pub y1: i32,
}

impl Rect {
    /// Columns `x0..x1`, rows `y0..y1`.
    pub const fn new(x0: i32, y0: i32, x1: i32, y1: i32) -> Self {
        Self { x0, y0, x1, y1 }
    }

    /// Whether the two boxes share any pixel.
    #[cfg(test)]
    pub fn intersects(&self, o: &Rect) -> bool {
        self.x0 < o.x1 && o.x0 < self.x1 && self.y0 < o.y1 && o.y0 < self.y1
    }

    /// The box's one-pixel edges (top, bottom, left, right): its outline, to [`fill`].
    pub fn edges(self) -> [Rect; 4] {
        let Rect { x0, y0, x1, y1 } = self;
        [
            Rect::new(x0, y0, x1, y0 + 1),
            Rect::new(x0, y1 - 1, x1, y1),
            Rect::new(x0, y0, x0 + 1, y1),
            Rect::new(x1 - 1, y0, x1, y1),
        ]
    }
}

/// Fills each box of `boxes` (an empty one draws nothing): crisp one-pixel lines in both
/// outputs.
pub(super) fn fill<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    ctx: &Ctx,
    boxes: impl IntoIterator<Item = Rect>,
    style: ShapeStyle,
) -> Result<(), PlotError> {
    for Rect { x0, y0, x1, y1 } in boxes {
        if x1 <= x0 || y1 <= y0 {
            continue;
        }
        root.draw(&Rectangle::new(
            [
                (ctx.px(f64::from(x0)), ctx.px(f64::from(y0))),
                (ctx.px(f64::from(x1)), ctx.px(f64::from(y1))),
            ],
            style.filled(),
        ))
        .map_err(backend)?;
    }
    Ok(())
}

/// Where the anchor point is along the text.
#[derive(Clone, Copy, PartialEq)]
pub(super) enum HAlign {
    Start,
    Center,
    End,
}

/// Where the anchor point is across the text.
#[derive(Clone, Copy, PartialEq)]
pub(super) enum VAlign {
    /// Top of the capitals.
    Top,
    /// Middle of the capitals.
    Center,
    /// Bottom of the descenders.
    Bottom,
}

/// How a line of text is set: size, colour, alignment and direction.
#[derive(Clone, Copy)]
pub(super) struct TextStyle {
    pub em: f64,
    pub color: RGBColor,
    pub h: HAlign,
    pub v: VAlign,
    /// Rotated to read upwards (then "top" is towards the left).
    pub vertical: bool,
}

impl TextStyle {
    pub fn new(em: f64, color: RGBColor, h: HAlign, v: VAlign) -> Self {
        Self {
            em,
            color,
            h,
            v,
            vertical: false,
        }
    }
}

/// Advance width of `text` at `em` px (unscaled), in unscaled px. For the SVG, whose text
/// is set in the viewer's font, with room for a wider face than Ubuntu Light.
pub(super) fn text_width(ctx: &Ctx, text: &str, em: f64) -> f64 {
    let w = layout(ctx.m, text, em).1;
    if ctx.bitmap { w } else { w * SVG_WIDTH_SLACK }
}

/// `em`, shrunk until `text` fits in `avail` unscaled px (not below 70 %).
pub(super) fn fit_size(ctx: &Ctx, text: &str, em: f64, avail: f64) -> f64 {
    let w = text_width(ctx, text, em);
    if w <= avail || w <= 0.0 {
        em
    } else {
        (em * avail.max(1.0) / w).max(em * 0.7)
    }
}

/// Draws one line of text at `anchor` (backend px).
pub(super) fn draw_text<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    ctx: &Ctx,
    text: &str,
    anchor: (i32, i32),
    st: TextStyle,
) -> Result<(), PlotError> {
    if text.trim().is_empty() {
        return Ok(());
    }
    let m = ctx.m;
    let em_s = st.em * ctx.s;
    let k = m.k(em_s);
    // Baseline offset below the anchor, across the text.
    let base = match st.v {
        VAlign::Top => m.cap * k,
        VAlign::Center => 0.5 * m.cap * k,
        VAlign::Bottom => -m.descent * k,
    };
    // Text frame (along, down) → screen.
    let to_screen = |a: f64, d: f64| -> (i32, i32) {
        let (dx, dy) = if st.vertical { (d, -a) } else { (a, d) };
        (anchor.0 + dx.round() as i32, anchor.1 + dy.round() as i32)
    };
    let trans = if st.vertical {
        FontTransform::Rotate270
    } else {
        FontTransform::None
    };
    if !ctx.bitmap {
        // SVG: one <text>; the viewer's font does the layout. plotters writes
        // font-size = size / 1.24 and puts the baseline 0.76 em below y for VPos::Top.
        let hp = match st.h {
            HAlign::Start => HPos::Left,
            HAlign::Center => HPos::Center,
            HAlign::End => HPos::Right,
        };
        let style = FontDesc::new(
            FontFamily::Name(SVG_FONT_FAMILY),
            em_s * 1.24,
            FontStyle::Normal,
        )
        .transform(trans)
        .color(&st.color)
        .pos(Pos::new(hp, VPos::Top));
        return root
            .draw(&Text::new(
                text.to_string(),
                to_screen(0.0, base - 0.76 * em_s),
                style,
            ))
            .map_err(backend);
    }
    // Bitmap: glyph by glyph. plotters' ab_glyph size is the ascent-to-descent height, its
    // baseline lies size/2 below the given point, and ink starts at the point.
    let size = em_s * (m.ascent + m.descent) / m.upem;
    let style = FontDesc::new(FontFamily::SansSerif, size, FontStyle::Normal)
        .transform(trans)
        .color(&st.color)
        .pos(Pos::new(HPos::Left, VPos::Top));
    let (glyphs, width) = layout(m, text, em_s);
    let start = match st.h {
        HAlign::Start => 0.0,
        HAlign::Center => -0.5 * width,
        HAlign::End => -width,
    };
    let mut buf = [0u8; 4];
    for g in glyphs {
        let x_min = m.ink(m.glyph(g.c)).map_or(0.0, |i| i.0);
        let along = (start + g.pen).round() + (x_min * k).floor();
        let down = (base - g.lift).round() - size / 2.0;
        let s: &str = g.c.encode_utf8(&mut buf);
        root.draw(&Text::new(s, to_screen(along, down), style.clone()))
            .map_err(backend)?;
    }
    Ok(())
}
