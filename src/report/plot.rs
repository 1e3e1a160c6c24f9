//! Engineering plots for `seat-twin report`: Bode diagrams, transmissibility curves and time
//! histories, written as a PNG and an SVG of the same figure.
//!
//! A [`Figure`] is a title over one or more [`Panel`]s stacked vertically (they share the width
//! and their plot areas are aligned). A panel holds [`Series`] (lines or markers), optional
//! horizontal reference lines (`|T| = 1`, `±35 mm`, …) and shaded x intervals (end-stop contact,
//! …). [`save_figure`] writes `<path>.png` and `<path>.svg`, each atomically (temporary file in
//! the same directory, then rename), so a crash never leaves half a file behind.
//!
//! The look: white background, light grid (decades with 1–9 sub-lines on log axes), 14–16 px
//! text in the embedded Ubuntu Light font (no system font is needed), axis titles, a legend box
//! with a semi-transparent background placed in the corner where it hides the least data, and
//! a PNG rendered at twice the resolution and averaged down, so lines are anti-aliased.
//!
//! Bad data never panics: non-finite points break a line, non-positive values are dropped on a
//! log axis, and a panel with nothing to show is drawn empty with a "no data" note.

use plotters::coord::Shift;
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use plotters::style::{FontStyle, FontTransform};
use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// The embedded font (Ubuntu Font Licence, see `assets/fonts/UFL.txt`).
static FONT_BYTES: &[u8] = include_bytes!("../../assets/fonts/Ubuntu-Light.ttf");

/// Default figure width (px).
pub const DEFAULT_WIDTH: u32 = 1000;
/// Default figure height (px).
pub const DEFAULT_HEIGHT: u32 = 600;

/// Smallest figure side that is drawn (px); smaller requested sizes are enlarged to this.
const MIN_SIDE: u32 = 64;
/// Largest figure side that is drawn (px); larger requested sizes are reduced to this.
const MAX_SIDE: u32 = 8_192;

/// Why a figure could not be written.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// Creating, writing or renaming a file failed.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file or directory concerned.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// The drawing backend, the font or the PNG encoder failed.
    #[error("plot backend: {0}")]
    Backend(String),
}

/// An sRGB colour.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Rgb(pub u8, pub u8, pub u8);

impl Rgb {
    fn to_plotters(self) -> RGBColor {
        RGBColor(self.0, self.1, self.2)
    }
}

/// The `i`-th colour of a ten-colour qualitative palette (matplotlib's "tab10": blue, orange,
/// green, red, purple, brown, pink, grey, olive, cyan); it repeats after ten.
pub fn palette(i: usize) -> Rgb {
    const TAB10: [Rgb; 10] = [
        Rgb(31, 119, 180),
        Rgb(255, 127, 14),
        Rgb(44, 160, 44),
        Rgb(214, 39, 40),
        Rgb(148, 103, 189),
        Rgb(140, 86, 75),
        Rgb(227, 119, 194),
        Rgb(127, 127, 127),
        Rgb(188, 189, 34),
        Rgb(23, 190, 207),
    ];
    TAB10[i % TAB10.len()]
}

/// How an axis maps values to positions.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Scale {
    /// Linear axis, 5 % padding around the data.
    #[default]
    Linear,
    /// Base-10 logarithmic axis: decade grid, labels such as 0.5, 1, 2, 5, 10, 20;
    /// values ≤ 0 are not drawn.
    Log10,
}

/// How a series is drawn.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SeriesStyle {
    /// Points joined by a polyline; a non-finite point (or a value ≤ 0 on a log axis) breaks it.
    Line {
        /// Line colour.
        color: Rgb,
        /// Stroke width (px); 1 is thin, 2 is the usual model line.
        width: u32,
        /// Dashed instead of solid.
        dashed: bool,
    },
    /// One filled circle (with a thin white rim) per point, e.g. measured test points.
    Markers {
        /// Marker colour.
        color: Rgb,
        /// Marker radius (px) (without the rim); 3–4 gives small, unobtrusive markers.
        size: u32,
    },
}

/// One data series of a panel.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Legend text; an empty label leaves the series out of the legend.
    pub label: String,
    /// Abscissae; pairs beyond the shorter of `x` and `y` are ignored.
    pub x: Vec<f64>,
    /// Ordinates.
    pub y: Vec<f64>,
    /// How it is drawn.
    pub style: SeriesStyle,
}

impl Series {
    /// A solid line of width 2 px.
    pub fn line(label: impl Into<String>, x: Vec<f64>, y: Vec<f64>, color: Rgb) -> Self {
        Self {
            label: label.into(),
            x,
            y,
            style: SeriesStyle::Line {
                color,
                width: 2,
                dashed: false,
            },
        }
    }

    /// Markers of radius 3 px.
    pub fn markers(label: impl Into<String>, x: Vec<f64>, y: Vec<f64>, color: Rgb) -> Self {
        Self {
            label: label.into(),
            x,
            y,
            style: SeriesStyle::Markers { color, size: 3 },
        }
    }
}

/// One chart: axes, grid, series, reference lines, shaded intervals and a legend.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Panel {
    /// Title above the plot area (may be empty).
    pub title: String,
    /// X-axis title, with units, e.g. `"frequency [Hz]"`.
    pub x_label: String,
    /// Y-axis title, with units.
    pub y_label: String,
    /// X-axis scale.
    pub x_scale: Scale,
    /// Y-axis scale.
    pub y_scale: Scale,
    /// The data, drawn in order (markers on top of all lines).
    pub series: Vec<Series>,
    /// Fixed y range `(min, max)`; `None` (or an unusable range) fits the data.
    pub y_range: Option<(f64, f64)>,
    /// Fixed x range `(min, max)`; `None` (or an unusable range) fits the data.
    pub x_range: Option<(f64, f64)>,
    /// Horizontal reference lines `(y, label)`, drawn dashed grey with the label at their left
    /// end; a fitted y range includes them.
    pub hlines: Vec<(f64, String)>,
    /// Shaded x intervals `(from, to)`, e.g. end-stop contact; not part of the fitted x range.
    pub vspans: Vec<(f64, f64)>,
}

impl Panel {
    /// An empty panel with linear axes and fitted ranges.
    pub fn new(
        title: impl Into<String>,
        x_label: impl Into<String>,
        y_label: impl Into<String>,
    ) -> Self {
        Self {
            title: title.into(),
            x_label: x_label.into(),
            y_label: y_label.into(),
            ..Self::default()
        }
    }
}

/// A titled figure of panels stacked vertically.
#[derive(Debug, Clone, PartialEq)]
pub struct Figure {
    /// Figure title (may be empty).
    pub title: String,
    /// Panels, top to bottom; they share the height equally.
    pub panels: Vec<Panel>,
    /// Width (px) of the PNG and the SVG (drawn within 64–8192).
    pub width: u32,
    /// Height (px) of the PNG and the SVG (drawn within 64–8192).
    pub height: u32,
}

impl Figure {
    /// A figure of [`DEFAULT_WIDTH`] × [`DEFAULT_HEIGHT`] px.
    pub fn new(title: impl Into<String>, panels: Vec<Panel>) -> Self {
        Self {
            title: title.into(),
            panels,
            width: DEFAULT_WIDTH,
            height: DEFAULT_HEIGHT,
        }
    }
}

/// Draws `fig` into `<path_without_extension>.png` and `<path_without_extension>.svg` and
/// returns the two paths. The extensions are appended (`out/fig.v2` → `out/fig.v2.png`); the
/// directory must exist. Each file is written to a temporary file beside it and renamed.
pub fn save_figure(
    fig: &Figure,
    path_without_extension: &Path,
) -> Result<(PathBuf, PathBuf), PlotError> {
    let m = ensure_font()?;
    let png = with_suffix(path_without_extension, ".png");
    let svg = with_suffix(path_without_extension, ".svg");
    let (w, h) = (
        fig.width.clamp(MIN_SIDE, MAX_SIDE),
        fig.height.clamp(MIN_SIDE, MAX_SIDE),
    );

    // PNG: render at `ss`× into memory, average down, encode through plotters' bitmap encoder.
    let ss: u32 = if u64::from(w) * u64::from(h) <= 8_000_000 {
        2
    } else {
        1
    };
    let (bw, bh) = (w * ss, h * ss);
    let mut big = vec![255u8; bw as usize * bh as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut big, (bw, bh)).into_drawing_area();
        let ctx = Ctx {
            s: f64::from(ss),
            bitmap: true,
            m,
        };
        render(&root, fig, &ctx)?;
        root.present().map_err(backend)?;
    }
    let small = downsample(&big, bw, bh, ss);
    drop(big);
    write_atomic(&png, |tmp| {
        let mut enc = BitMapBackend::new(tmp, (w, h));
        enc.blit_bitmap((0, 0), (w, h), &small)
            .map_err(|e| PlotError::Backend(e.to_string()))?;
        enc.present()
            .map_err(|e| PlotError::Backend(format!("{}: {e}", png.display())))?;
        Ok(())
    })?;

    // SVG: render into a string.
    let mut text = String::new();
    {
        let root = SVGBackend::with_string(&mut text, (w, h)).into_drawing_area();
        let ctx = Ctx {
            s: 1.0,
            bitmap: false,
            m,
        };
        render(&root, fig, &ctx)?;
        root.present().map_err(backend)?;
    }
    write_atomic(&svg, |tmp| {
        std::fs::write(tmp, text.as_bytes()).map_err(|source| PlotError::Io {
            path: tmp.to_path_buf(),
            source,
        })
    })?;
    Ok((png, svg))
}

// ---------------------------------------------------------------------------------------------
// Files, font, errors

fn with_suffix(p: &Path, suffix: &str) -> PathBuf {
    let mut s: OsString = p.as_os_str().to_owned();
    s.push(suffix);
    PathBuf::from(s)
}

/// Creates a temporary file beside `dest` (with the same extension, which the PNG encoder
/// needs), lets `fill` write it by path, syncs it and renames it onto `dest`.
fn write_atomic(
    dest: &Path,
    fill: impl FnOnce(&Path) -> Result<(), PlotError>,
) -> Result<(), PlotError> {
    let dir = match dest.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let ext = dest
        .extension()
        .map(|e| format!(".{}", e.to_string_lossy()))
        .unwrap_or_default();
    let mut builder = tempfile::Builder::new();
    builder.prefix(".plot-").suffix(&ext);
    // Like a file created normally (0666 less the umask), not tempfile's private 0600.
    #[cfg(unix)]
    builder.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o666));
    let tmp = builder
        .tempfile_in(&dir)
        .map_err(|source| PlotError::Io { path: dir, source })?;
    fill(tmp.path())?;
    let io = |source| PlotError::Io {
        path: dest.to_path_buf(),
        source,
    };
    tmp.as_file().sync_all().map_err(io)?;
    tmp.persist(dest).map_err(|e| io(e.error))?;
    Ok(())
}

/// Registers the embedded font with plotters (once) and returns its metrics.
fn ensure_font() -> Result<&'static Metrics, PlotError> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let ok = *REGISTERED.get_or_init(|| {
        plotters::style::register_font("sans-serif", FontStyle::Normal, FONT_BYTES).is_ok()
    });
    match metrics() {
        Some(m) if ok => Ok(m),
        _ => Err(PlotError::Backend(
            "the embedded font could not be loaded".into(),
        )),
    }
}

fn backend<E: std::error::Error + Send + Sync>(e: DrawingAreaErrorKind<E>) -> PlotError {
    PlotError::Backend(e.to_string())
}

/// 2×2 (or `f`×`f`) box filter of an RGB buffer.
fn downsample(src: &[u8], w: u32, h: u32, f: u32) -> Vec<u8> {
    if f == 1 {
        return src.to_vec();
    }
    let (w, h, f) = (w as usize, h as usize, f as usize);
    let (ow, oh) = (w / f, h / f);
    let mut out = vec![0u8; ow * oh * 3];
    let n = (f * f) as u32;
    for oy in 0..oh {
        for ox in 0..ow {
            let mut acc = [0u32; 3];
            for dy in 0..f {
                let row = (oy * f + dy) * w;
                for dx in 0..f {
                    let i = (row + ox * f + dx) * 3;
                    acc[0] += u32::from(src[i]);
                    acc[1] += u32::from(src[i + 1]);
                    acc[2] += u32::from(src[i + 2]);
                }
            }
            let o = (oy * ow + ox) * 3;
            for c in 0..3 {
                out[o + c] = ((acc[c] + n / 2) / n) as u8;
            }
        }
    }
    out
}

// ---------------------------------------------------------------------------------------------
// Font metrics
//
// plotters' ab_glyph renderer draws every glyph from its ink box, dropping the left side
// bearing, which makes letter spacing uneven. So text is laid out here from the embedded
// font's own metrics (cmap, hmtx, glyf bounding boxes) and drawn one glyph at a time.

/// What the layout needs from the embedded TrueType font.
struct Metrics {
    data: &'static [u8],
    upem: f64,
    ascent: f64,
    descent: f64, // positive, below the baseline
    cap: f64,
    x_height: f64,
    num_glyphs: u16,
    num_hmetrics: u16,
    hmtx: usize,
    loca: Option<(usize, bool)>, // offset, long format
    glyf: usize,
    cmap: (usize, u16), // subtable offset, format (4 or 12)
}

fn rd_u16(d: &[u8], at: usize) -> Option<u16> {
    Some(u16::from_be_bytes([*d.get(at)?, *d.get(at + 1)?]))
}
fn rd_i16(d: &[u8], at: usize) -> Option<i16> {
    rd_u16(d, at).map(|v| v as i16)
}
fn rd_u32(d: &[u8], at: usize) -> Option<u32> {
    Some(u32::from_be_bytes([
        *d.get(at)?,
        *d.get(at + 1)?,
        *d.get(at + 2)?,
        *d.get(at + 3)?,
    ]))
}

impl Metrics {
    fn parse(data: &'static [u8]) -> Option<Self> {
        let n = rd_u16(data, 4)? as usize;
        let table = |tag: &[u8; 4]| -> Option<usize> {
            (0..n).find_map(|i| {
                let rec = 12 + 16 * i;
                (data.get(rec..rec + 4)? == tag)
                    .then(|| rd_u32(data, rec + 8).map(|o| o as usize))?
            })
        };
        let head = table(b"head")?;
        let hhea = table(b"hhea")?;
        let maxp = table(b"maxp")?;
        let cmap = table(b"cmap")?;
        let upem = f64::from(rd_u16(data, head + 18)?);
        let ascent = f64::from(rd_i16(data, hhea + 4)?);
        let descent = -f64::from(rd_i16(data, hhea + 6)?);
        let (mut cap, mut x_height) = (0.7 * upem, 0.5 * upem);
        if let Some(os2) = table(b"OS/2")
            && rd_u16(data, os2)? >= 2
        {
            x_height = f64::from(rd_i16(data, os2 + 86)?);
            cap = f64::from(rd_i16(data, os2 + 88)?);
        }
        let loca = match (table(b"loca"), rd_i16(data, head + 50)) {
            (Some(l), Some(f)) => Some((l, f == 1)),
            _ => None,
        };
        // Unicode subtable: full repertoire (format 12) if present, else BMP (format 4).
        let mut sub = None;
        for i in 0..rd_u16(data, cmap + 2)? as usize {
            let rec = cmap + 4 + 8 * i;
            let (pid, eid) = (rd_u16(data, rec)?, rd_u16(data, rec + 2)?);
            let off = cmap + rd_u32(data, rec + 4)? as usize;
            let format = rd_u16(data, off)?;
            let unicode = pid == 0 || (pid == 3 && (eid == 1 || eid == 10));
            match format {
                12 if unicode => sub = Some((off, 12)),
                4 if unicode && sub.is_none() => sub = Some((off, 4)),
                _ => {}
            }
        }
        let m = Self {
            data,
            upem,
            ascent,
            descent,
            cap,
            x_height,
            num_glyphs: rd_u16(data, maxp + 4)?,
            num_hmetrics: rd_u16(data, hhea + 34)?,
            hmtx: table(b"hmtx")?,
            loca,
            glyf: table(b"glyf").unwrap_or(0),
            cmap: sub?,
        };
        (m.upem > 0.0 && m.ascent + m.descent > 0.0 && m.num_hmetrics > 0).then_some(m)
    }

    /// Glyph index of `c`, 0 if the font lacks it.
    fn glyph(&self, c: char) -> u16 {
        self.glyph_opt(u32::from(c)).unwrap_or(0)
    }

    fn glyph_opt(&self, c: u32) -> Option<u16> {
        let d = self.data;
        let (t, format) = self.cmap;
        if format == 12 {
            let groups = rd_u32(d, t + 12)? as usize;
            let (mut lo, mut hi) = (0usize, groups);
            while lo < hi {
                let mid = (lo + hi) / 2;
                let g = t + 16 + 12 * mid;
                let (start, end) = (rd_u32(d, g)?, rd_u32(d, g + 4)?);
                if c < start {
                    hi = mid;
                } else if c > end {
                    lo = mid + 1;
                } else {
                    return u16::try_from(rd_u32(d, g + 8)? + (c - start)).ok();
                }
            }
            return Some(0);
        }
        let c = u16::try_from(c).ok()?;
        let seg_x2 = rd_u16(d, t + 6)? as usize;
        let ends = t + 14;
        let starts = ends + seg_x2 + 2;
        let deltas = starts + seg_x2;
        let ranges = deltas + seg_x2;
        for i in 0..seg_x2 / 2 {
            if c > rd_u16(d, ends + 2 * i)? {
                continue;
            }
            let start = rd_u16(d, starts + 2 * i)?;
            if c < start {
                return Some(0);
            }
            let delta = rd_u16(d, deltas + 2 * i)?;
            let ro = rd_u16(d, ranges + 2 * i)? as usize;
            if ro == 0 {
                return Some(c.wrapping_add(delta));
            }
            let g = rd_u16(d, ranges + 2 * i + ro + 2 * (c - start) as usize)?;
            return Some(if g == 0 { 0 } else { g.wrapping_add(delta) });
        }
        Some(0)
    }

    /// Advance width (font units).
    fn advance(&self, g: u16) -> f64 {
        let i = g.min(self.num_hmetrics - 1) as usize;
        f64::from(rd_u16(self.data, self.hmtx + 4 * i).unwrap_or(0))
    }

    /// Horizontal ink extent `(x_min, x_max)` (font units); `None` for an empty glyph.
    fn ink(&self, g: u16) -> Option<(f64, f64)> {
        let (loca, long) = self.loca?;
        if g >= self.num_glyphs {
            return None;
        }
        let g = g as usize;
        let (a, b) = if long {
            (
                rd_u32(self.data, loca + 4 * g)? as usize,
                rd_u32(self.data, loca + 4 * g + 4)? as usize,
            )
        } else {
            (
                2 * rd_u16(self.data, loca + 2 * g)? as usize,
                2 * rd_u16(self.data, loca + 2 * g + 2)? as usize,
            )
        };
        if b <= a {
            return None;
        }
        let at = self.glyf + a;
        Some((
            f64::from(rd_i16(self.data, at + 2)?),
            f64::from(rd_i16(self.data, at + 6)?),
        ))
    }
}

fn metrics() -> Option<&'static Metrics> {
    static M: OnceLock<Option<Metrics>> = OnceLock::new();
    M.get_or_init(|| Metrics::parse(FONT_BYTES)).as_ref()
}

// ---------------------------------------------------------------------------------------------
// Style

const TEXT: RGBColor = RGBColor(25, 25, 25);
const TEXT_MUTED: RGBColor = RGBColor(80, 80, 80);
const AXIS: RGBColor = RGBColor(120, 120, 120);
const GRID: RGBColor = RGBColor(220, 220, 220);
const GRID_MINOR: RGBColor = RGBColor(239, 239, 239);
const REF_LINE: RGBColor = RGBColor(90, 90, 90);
const SPAN: RGBColor = RGBColor(255, 165, 50);

// Text sizes are em sizes in px, as CSS's `font-size`.
const FIG_TITLE_PX: f64 = 19.0;
const PANEL_TITLE_PX: f64 = 16.0;
const AXIS_TITLE_PX: f64 = 15.0;
const TICK_PX: f64 = 14.0;
const LEGEND_PX: f64 = 14.0;
const NOTE_PX: f64 = 13.0;
const TICK_LEN: f64 = 5.0;

/// Rendering context: `s` scales every length (2 for the supersampled PNG); `bitmap` selects
/// glyph-by-glyph text (an SVG keeps whole strings, set in the viewer's sans-serif font).
struct Ctx {
    s: f64,
    bitmap: bool,
    m: &'static Metrics,
}

impl Ctx {
    /// Unscaled px → backend px.
    fn px(&self, v: f64) -> i32 {
        (v * self.s).round() as i32
    }
    /// Stroke width in backend px.
    fn stroke(&self, v: f64) -> u32 {
        (v * self.s).round().max(1.0) as u32
    }
}

/// Where the anchor point is along the text.
#[derive(Clone, Copy, PartialEq)]
enum HAlign {
    Start,
    Center,
    End,
}

/// Where the anchor point is across the text.
#[derive(Clone, Copy, PartialEq)]
enum VAlign {
    /// Top of the capitals.
    Top,
    /// Middle of the capitals.
    Center,
    /// Bottom of the descenders.
    Bottom,
}

/// Spacing forms of the combining accents, drawn over their base letter.
fn spacing_accent(c: char) -> Option<char> {
    Some(match c {
        '\u{300}' => '`',
        '\u{301}' => '´',
        '\u{302}' => 'ˆ',
        '\u{303}' => '˜',
        '\u{304}' => '¯',
        '\u{307}' => '˙',
        '\u{308}' => '¨',
        _ => return None,
    })
}

/// One glyph placed along the text: pen position (px) and lift above the baseline (px).
struct Placed {
    c: char,
    pen: f64,
    lift: f64,
}

/// Lays `text` out at `em` px: the glyphs and the advance width. Characters the font lacks
/// fall back: accents (combining, or precomposed `ẋ ẏ ẍ ṗ`) go over their letter, primes
/// become apostrophes, arrows `->`, …
fn layout(m: &Metrics, text: &str, em: f64) -> (Vec<Placed>, f64) {
    let k = em / m.upem;
    let mut out: Vec<Placed> = Vec::with_capacity(text.len());
    let mut pen = 0.0;
    let mut last_base: Option<usize> = None;
    let glyph = |c: char, out: &mut Vec<Placed>, pen: &mut f64, last: &mut Option<usize>| {
        if c != ' ' {
            *last = Some(out.len());
            out.push(Placed {
                c,
                pen: *pen,
                lift: 0.0,
            });
        }
        *pen += m.advance(m.glyph(c)) * k;
    };
    let accent = |a: char, base: Option<usize>, out: &mut Vec<Placed>| {
        let Some(b) = base else { return };
        let (bc, bpen) = (out[b].c, out[b].pen);
        let gb = m.glyph(bc);
        let (x0, x1) = m.ink(gb).unwrap_or((0.0, m.advance(gb)));
        let ga = m.glyph(a);
        let (a0, a1) = m.ink(ga).unwrap_or((0.0, m.advance(ga)));
        let tall = bc.is_uppercase() || bc.is_ascii_digit() || "bdfhklt".contains(bc);
        out.push(Placed {
            c: a,
            pen: bpen + 0.5 * (x0 + x1) * k - 0.5 * (a0 + a1) * k,
            lift: if tall { (m.cap - m.x_height) * k } else { 0.0 },
        });
    };
    for c in text.chars() {
        if c == '\n' || c == '\t' {
            glyph(' ', &mut out, &mut pen, &mut last_base);
            continue;
        }
        if c == ' ' || m.glyph(c) != 0 {
            glyph(c, &mut out, &mut pen, &mut last_base);
            continue;
        }
        if let Some(a) = spacing_accent(c) {
            accent(a, last_base, &mut out);
            continue;
        }
        if ('\u{300}'..='\u{36f}').contains(&c) {
            continue; // an accent we have no spacing form for: leave the letter bare
        }
        let (base, acc): (&str, Option<char>) = match c {
            'ẋ' => ("x", Some('˙')),
            'ẏ' => ("y", Some('˙')),
            'ṗ' => ("p", Some('˙')),
            'ẍ' => ("x", Some('¨')),
            'Ẋ' => ("X", Some('˙')),
            'Ẏ' => ("Y", Some('˙')),
            '′' => ("'", None),
            '″' => ("\"", None),
            '⁻' => ("-", None),
            '⁺' => ("+", None),
            '⋅' => ("·", None),
            'ₙ' => ("n", None),
            '→' => ("->", None),
            '←' => ("<-", None),
            '↔' => ("<->", None),
            _ => ("", None),
        };
        if base.is_empty() {
            glyph(c, &mut out, &mut pen, &mut last_base); // the font's "missing" box
            continue;
        }
        for b in base.chars() {
            glyph(b, &mut out, &mut pen, &mut last_base);
        }
        if let Some(a) = acc {
            accent(a, last_base, &mut out);
        }
    }
    (out, pen)
}

/// Advance width of `text` at `em` px (unscaled), in unscaled px. For the SVG, whose text
/// is set in the viewer's font, with room for a wider face than Ubuntu Light.
fn text_width(ctx: &Ctx, text: &str, em: f64) -> f64 {
    let w = layout(ctx.m, text, em).1;
    if ctx.bitmap { w } else { w * SVG_WIDTH_SLACK }
}

/// How much wider than Ubuntu Light an SVG viewer's sans-serif may set text (DejaVu Sans).
const SVG_WIDTH_SLACK: f64 = 1.15;

/// `font-family` of SVG text.
const SVG_FONT_FAMILY: &str = "Ubuntu, sans-serif";

/// Draws one line of text at `anchor` (backend px). `vertical` rotates it to read upwards
/// (then "top" is towards the left).
#[allow(clippy::too_many_arguments)]
fn draw_text<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    ctx: &Ctx,
    text: &str,
    anchor: (i32, i32),
    em: f64,
    color: &RGBColor,
    h: HAlign,
    v: VAlign,
    vertical: bool,
) -> Result<(), PlotError> {
    if text.trim().is_empty() {
        return Ok(());
    }
    let m = ctx.m;
    let em_s = em * ctx.s;
    let k = em_s / m.upem;
    // Baseline offset below the anchor, across the text.
    let base = match v {
        VAlign::Top => m.cap * k,
        VAlign::Center => 0.5 * m.cap * k,
        VAlign::Bottom => -m.descent * k,
    };
    // Text frame (along, down) → screen.
    let to_screen = |a: f64, d: f64| -> (i32, i32) {
        let (dx, dy) = if vertical { (d, -a) } else { (a, d) };
        (anchor.0 + dx.round() as i32, anchor.1 + dy.round() as i32)
    };
    let trans = if vertical {
        FontTransform::Rotate270
    } else {
        FontTransform::None
    };
    if !ctx.bitmap {
        // SVG: one <text>; the viewer's font does the layout. plotters writes
        // font-size = size / 1.24 and puts the baseline 0.76 em below y for VPos::Top.
        let hp = match h {
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
        .color(color)
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
        .color(color)
        .pos(Pos::new(HPos::Left, VPos::Top));
    let (glyphs, width) = layout(m, text, em_s);
    let start = match h {
        HAlign::Start => 0.0,
        HAlign::Center => -0.5 * width,
        HAlign::End => -width,
    };
    let mut buf = [0u8; 4];
    for g in glyphs {
        let gid = m.glyph(g.c);
        let x_min = m.ink(gid).map_or(0.0, |i| i.0);
        let along = (start + g.pen).round() + (x_min * k).floor();
        let down = (base - g.lift).round() - size / 2.0;
        let s: &str = g.c.encode_utf8(&mut buf);
        root.draw(&Text::new(s, to_screen(along, down), style.clone()))
            .map_err(backend)?;
    }
    Ok(())
}

/// `em`, shrunk until `text` fits in `avail` unscaled px (not below 70 %).
fn fit_size(ctx: &Ctx, text: &str, em: f64, avail: f64) -> f64 {
    let w = text_width(ctx, text, em);
    if w <= avail || w <= 0.0 {
        em
    } else {
        (em * avail.max(1.0) / w).max(em * 0.7)
    }
}

// ---------------------------------------------------------------------------------------------
// Axes

/// Largest magnitude accepted as data (keeps every span and step finite).
const HUGE: f64 = 1e250;

/// The value on the axis' drawing scale (log10 for a log axis), or `None` if it can't be drawn.
fn tr(scale: Scale, v: f64) -> Option<f64> {
    match scale {
        Scale::Linear => (v.is_finite() && v.abs() <= HUGE).then_some(v),
        Scale::Log10 => (v.is_finite() && v > 0.0 && v <= HUGE).then(|| v.log10()),
    }
}

/// A resolved axis, in drawing-scale units.
struct Axis {
    lo: f64,
    hi: f64,
    /// Labelled ticks: position and text.
    major: Vec<(f64, String)>,
    /// Unlabelled grid lines.
    minor: Vec<f64>,
}

/// The range on the drawing scale: the fixed range if usable, else the data's, padded.
fn resolve_range(scale: Scale, fixed: Option<(f64, f64)>, data: &[f64], pad: f64) -> (f64, f64) {
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

fn make_axis(scale: Scale, (lo, hi): (f64, f64), target: usize) -> Axis {
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

// ---------------------------------------------------------------------------------------------
// Data preparation

/// Points of a series on the drawing scales; `None` where a point can't be drawn.
fn transformed(s: &Series, xs: Scale, ys: Scale) -> impl Iterator<Item = Option<(f64, f64)>> {
    s.x.iter()
        .zip(&s.y)
        .map(move |(&x, &y)| Some((tr(xs, x)?, tr(ys, y)?)))
}

/// Liang–Barsky clip of segment `a`–`b` to the box; `None` if it misses.
fn clip_segment(
    a: (f64, f64),
    b: (f64, f64),
    (x0, x1, y0, y1): (f64, f64, f64, f64),
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
fn clip_polyline(
    pts: impl Iterator<Item = Option<(f64, f64)>>,
    bx: (f64, f64, f64, f64),
) -> Vec<Vec<(f64, f64)>> {
    let mut pieces: Vec<Vec<(f64, f64)>> = Vec::new();
    let mut cur: Vec<(f64, f64)> = Vec::new();
    let mut prev: Option<(f64, f64)> = None;
    let inside = |p: (f64, f64)| p.0 >= bx.0 && p.0 <= bx.1 && p.1 >= bx.2 && p.1 <= bx.3;
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
fn decimate(piece: Vec<(f64, f64)>, x0: f64, x1: f64, columns: usize) -> Vec<(f64, f64)> {
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

// ---------------------------------------------------------------------------------------------
// Rendering

/// A plot area in unscaled px: interior columns `l..r`, rows `t..b`; the frame is drawn just
/// outside it.
#[derive(Clone, Copy, Debug)]
struct Frame {
    l: i32,
    t: i32,
    r: i32,
    b: i32,
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

/// Fills unscaled px `x0..x1` × `y0..y1`: crisp one-pixel lines in both outputs.
fn fill<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    ctx: &Ctx,
    (x0, y0): (i32, i32),
    (x1, y1): (i32, i32),
    style: ShapeStyle,
) -> Result<(), PlotError> {
    if x1 <= x0 || y1 <= y0 {
        return Ok(());
    }
    root.draw(&Rectangle::new(
        [
            (ctx.px(f64::from(x0)), ctx.px(f64::from(y0))),
            (ctx.px(f64::from(x1)), ctx.px(f64::from(y1))),
        ],
        style.filled(),
    ))
    .map_err(backend)
}

/// Space around the plot areas (unscaled px).
struct Margins {
    left: i32,
    right: i32,
    top: i32,
    bottom: i32,
}

const GAP_TICK_LABEL: f64 = 5.0;

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
    let m = ctx.m;
    let cap = |em: f64| m.cap / m.upem * em;
    let desc = |em: f64| m.descent / m.upem * em;
    let any_y_label = fig.panels.iter().any(|p| !p.y_label.trim().is_empty());
    let any_title = fig.panels.iter().any(|p| !p.title.trim().is_empty());
    let y_title = if any_y_label {
        cap(AXIS_TITLE_PX) + desc(AXIS_TITLE_PX) + 10.0
    } else {
        0.0
    };
    Margins {
        left: (10.0 + y_title + tick_w + GAP_TICK_LABEL + TICK_LEN + 1.0).ceil() as i32,
        right: right.ceil() as i32,
        top: if any_title {
            (cap(PANEL_TITLE_PX) + desc(PANEL_TITLE_PX) + 20.0).ceil() as i32
        } else {
            14
        },
        bottom: (1.0
            + TICK_LEN
            + GAP_TICK_LABEL
            + cap(TICK_PX)
            + 11.0
            + cap(AXIS_TITLE_PX)
            + desc(AXIS_TITLE_PX)
            + 8.0)
            .ceil() as i32,
    }
}

fn render<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    fig: &Figure,
    ctx: &Ctx,
) -> Result<(), PlotError> {
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
            em,
            &TEXT,
            HAlign::Center,
            VAlign::Top,
            false,
        )?;
        top = (12.0 + em * (ctx.m.cap + ctx.m.descent) / ctx.m.upem + 8.0).ceil() as i32;
    }
    if fig.panels.is_empty() {
        return Ok(());
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
    let (pw, ph) = plot_size(&guess);
    let axes: Vec<_> = fig
        .panels
        .iter()
        .map(|p| panel_axes(p, pw, ph, ctx))
        .collect();
    let m1 = margins(fig, &axes, ctx);
    let (pw, ph) = plot_size(&m1);
    let axes: Vec<_> = fig
        .panels
        .iter()
        .map(|p| panel_axes(p, pw, ph, ctx))
        .collect();
    let m = margins(fig, &axes, ctx);

    for (i, (panel, (xa, ya, has_data))) in fig.panels.iter().zip(&axes).enumerate() {
        let y0 = top + i as i32 * panel_h;
        let f = Frame {
            l: m.left,
            t: y0 + m.top,
            r: (w - m.right).max(m.left + 10),
            b: (y0 + panel_h - m.bottom).max(y0 + m.top + 10),
        };
        let view = View { f, xa, ya };
        draw_panel(root, panel, &view, *has_data, (y0, y0 + panel_h), ctx)?;
    }
    Ok(())
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

fn draw_panel<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    panel: &Panel,
    v: &View<'_>,
    has_data: bool,
    (area_top, area_bottom): (i32, i32),
    ctx: &Ctx,
) -> Result<(), PlotError> {
    let f = v.f;
    let (xa, ya) = (v.xa, v.ya);
    let (xs, ys) = (panel.x_scale, panel.y_scale);
    let m = ctx.m;
    let cap = |em: f64| m.cap / m.upem * em;

    // Shaded intervals, behind everything.
    for &(a, b) in &panel.vspans {
        let (Some(a), Some(b)) = (tr(xs, a), tr(xs, b)) else {
            continue;
        };
        let (a, b) = (a.min(b).max(xa.lo), a.max(b).min(xa.hi));
        if a >= b {
            continue;
        }
        let (x0, x1) = (v.x(a).round() as i32, v.x(b).round() as i32);
        fill(
            root,
            ctx,
            (x0, f.t),
            (x1.max(x0 + 1), f.b),
            SPAN.mix(0.2).into(),
        )?;
    }

    // Grid: minor, then major lines.
    for (vals, color) in [
        (&xa.minor, GRID_MINOR),
        (&xa.major.iter().map(|t| t.0).collect(), GRID),
    ] {
        for &x in vals.iter() {
            let c = v.x(x).floor() as i32;
            fill(root, ctx, (c, f.t), (c + 1, f.b), color.into())?;
        }
    }
    for (vals, color) in [
        (&ya.minor, GRID_MINOR),
        (&ya.major.iter().map(|t| t.0).collect(), GRID),
    ] {
        for &y in vals.iter() {
            let r = v.y(y).floor() as i32;
            fill(root, ctx, (f.l, r), (f.r, r + 1), color.into())?;
        }
    }

    // Reference lines.
    let mut ref_labels = Vec::new();
    for (y, text) in &panel.hlines {
        let Some(yv) = tr(ys, *y) else { continue };
        if yv < ya.lo || yv > ya.hi {
            continue;
        }
        let (p0, p1) = (v.pt(ctx, (xa.lo, yv)), v.pt(ctx, (xa.hi, yv)));
        root.draw(&DashedPathElement::new(
            vec![p0, p1],
            ctx.px(7.0),
            ctx.px(4.0),
            REF_LINE.stroke_width(ctx.stroke(1.25)),
        ))
        .map_err(backend)?;
        ref_labels.push((yv, text.as_str()));
    }

    // Series: clipped to the axes; lines first, then markers on top.
    let bx = (xa.lo, xa.hi, ya.lo, ya.hi);
    // Decimation keeps ~4 points per backend pixel column (2 per px in the SVG, for zooming).
    let columns = ((f.r - f.l).max(1) as f64 * ctx.s.max(2.0)) as usize;
    let prepared: Vec<(&Series, Pieces)> = panel
        .series
        .iter()
        .map(|s| {
            let pieces: Vec<Vec<(f64, f64)>> = match s.style {
                SeriesStyle::Line { .. } => clip_polyline(transformed(s, xs, ys), bx)
                    .into_iter()
                    .map(|p| decimate(p, xa.lo, xa.hi, columns))
                    .collect(),
                SeriesStyle::Markers { .. } => vec![
                    transformed(s, xs, ys)
                        .flatten()
                        .filter(|p| p.0 >= bx.0 && p.0 <= bx.1 && p.1 >= bx.2 && p.1 <= bx.3)
                        .collect(),
                ],
            };
            let px = pieces
                .into_iter()
                .map(|p| p.into_iter().map(|q| v.pt(ctx, q)).collect())
                .collect();
            (s, px)
        })
        .collect();
    for (s, pieces) in &prepared {
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
    for (s, pieces) in &prepared {
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

    // Frame and tick marks.
    let axis: ShapeStyle = AXIS.into();
    fill(root, ctx, (f.l - 1, f.t - 1), (f.r + 1, f.t), axis)?;
    fill(root, ctx, (f.l - 1, f.b), (f.r + 1, f.b + 1), axis)?;
    fill(root, ctx, (f.l - 1, f.t), (f.l, f.b), axis)?;
    fill(root, ctx, (f.r, f.t), (f.r + 1, f.b), axis)?;
    let tick = TICK_LEN as i32;
    for (x, label) in &xa.major {
        let c = v.x(*x).floor() as i32;
        fill(root, ctx, (c, f.b + 1), (c + 1, f.b + 1 + tick), axis)?;
        draw_text(
            root,
            ctx,
            label,
            (
                ctx.px(f64::from(c) + 0.5),
                ctx.px(f64::from(f.b + 1 + tick) + GAP_TICK_LABEL),
            ),
            TICK_PX,
            &TEXT_MUTED,
            HAlign::Center,
            VAlign::Top,
            false,
        )?;
    }
    for (y, label) in &ya.major {
        let r = v.y(*y).floor() as i32;
        fill(root, ctx, (f.l - 1 - tick, r), (f.l - 1, r + 1), axis)?;
        draw_text(
            root,
            ctx,
            label,
            (
                ctx.px(f64::from(f.l - 1 - tick) - GAP_TICK_LABEL),
                ctx.px(f64::from(r) + 0.5),
            ),
            TICK_PX,
            &TEXT_MUTED,
            HAlign::End,
            VAlign::Center,
            false,
        )?;
    }

    // Titles.
    let (plot_w, plot_h) = (f64::from(f.r - f.l), f64::from(f.b - f.t));
    let cx = f64::from(f.l + f.r) / 2.0;
    let em = fit_size(ctx, &panel.title, PANEL_TITLE_PX, plot_w);
    draw_text(
        root,
        ctx,
        &panel.title,
        (ctx.px(cx), ctx.px(f64::from(f.t) - 10.0)),
        em,
        &TEXT,
        HAlign::Center,
        VAlign::Bottom,
        false,
    )?;
    let em = fit_size(ctx, &panel.x_label, AXIS_TITLE_PX, plot_w);
    let x_title_top = f64::from(f.b + 1 + tick) + GAP_TICK_LABEL + cap(TICK_PX) + 11.0;
    draw_text(
        root,
        ctx,
        &panel.x_label,
        (
            ctx.px(cx),
            ctx.px(x_title_top.min(f64::from(area_bottom) - cap(em) - 4.0)),
        ),
        em,
        &TEXT,
        HAlign::Center,
        VAlign::Top,
        false,
    )?;
    let em = fit_size(
        ctx,
        &panel.y_label,
        AXIS_TITLE_PX,
        plot_h + f64::from(f.t - area_top) * 0.5,
    );
    draw_text(
        root,
        ctx,
        &panel.y_label,
        (ctx.px(10.0), ctx.px(f64::from(f.t + f.b) / 2.0)),
        em,
        &TEXT,
        HAlign::Center,
        VAlign::Top,
        true,
    )?;

    // Reference-line labels, just above each line at its left end.
    let mut occ = Occupancy::new(f, 6);
    let mut placed: Vec<(f64, f64)> = Vec::new();
    for (yv, text) in &ref_labels {
        if text.trim().is_empty() {
            continue;
        }
        let py = v.y(*yv);
        let tw = text_width(ctx, text, NOTE_PX);
        let th = cap(NOTE_PX) + m.descent / m.upem * NOTE_PX;
        let pad = 3.0;
        let x0 = f64::from(f.l) + 6.0;
        let x1 = x0 + tw + 2.0 * pad;
        let h = th + 2.0 * pad;
        // Above the line, else below it, else leave the label out.
        let free = |y0: f64| {
            y0 >= f64::from(f.t)
                && y0 + h <= f64::from(f.b)
                && placed
                    .iter()
                    .all(|&(a, b): &(f64, f64)| y0 + h <= a || y0 >= b)
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
            NOTE_PX,
            &TEXT_MUTED,
            HAlign::Start,
            VAlign::Bottom,
            false,
        )?;
        occ.mark_rect(
            (x0 as i32, y_top as i32),
            (x1.ceil() as i32, y_bot.ceil() as i32),
            50,
        );
    }

    if !has_data {
        let note = "no data";
        let tw = text_width(ctx, note, 16.0);
        let (cx, cy) = (cx, f64::from(f.t + f.b) / 2.0);
        let (hw, hh) = (tw / 2.0 + 8.0, cap(16.0) / 2.0 + 8.0);
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
            16.0,
            &TEXT_MUTED,
            HAlign::Center,
            VAlign::Center,
            false,
        )?;
    }

    // Legend in the corner that hides the least.
    for (s, pieces) in &prepared {
        let weight = match s.style {
            SeriesStyle::Markers { .. } => 3,
            SeriesStyle::Line { .. } => 1,
        };
        let unscale = |p: (i32, i32)| {
            (
                (f64::from(p.0) / ctx.s) as i32,
                (f64::from(p.1) / ctx.s) as i32,
            )
        };
        for piece in pieces {
            if piece.len() == 1 || matches!(s.style, SeriesStyle::Markers { .. }) {
                for &p in piece {
                    occ.mark_point(unscale(p), weight);
                }
            } else {
                for w in piece.windows(2) {
                    occ.mark_segment(unscale(w[0]), unscale(w[1]), weight);
                }
            }
        }
    }
    draw_legend(root, panel, &occ, ctx)
}

/// Polyline pieces (or one marker set) in backend px.
type Pieces = Vec<Vec<(i32, i32)>>;

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

/// Coarse grid over a plot area counting what is drawn where, to place the legend.
struct Occupancy {
    f: Frame,
    cell: i32,
    cols: usize,
    cells: Vec<u32>,
}

impl Occupancy {
    fn new(f: Frame, cell: i32) -> Self {
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
    fn mark_point(&mut self, p: (i32, i32), w: u32) {
        if let Some(i) = self.idx(p) {
            self.cells[i] = self.cells[i].saturating_add(w).min(1000);
        }
    }
    fn mark_segment(&mut self, a: (i32, i32), b: (i32, i32), w: u32) {
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
    fn mark_rect(&mut self, a: (i32, i32), b: (i32, i32), w: u32) {
        for y in (a.1..=b.1).step_by(self.cell as usize) {
            for x in (a.0..=b.0).step_by(self.cell as usize) {
                self.mark_point((x, y), w);
            }
        }
    }
    fn cost(&self, a: (i32, i32), b: (i32, i32)) -> u64 {
        let mut sum = 0u64;
        for y in (a.1..=b.1).step_by(self.cell as usize) {
            for x in (a.0..=b.0).step_by(self.cell as usize) {
                if let Some(i) = self.idx((x, y)) {
                    sum += u64::from(self.cells[i]);
                }
            }
        }
        sum
    }
}

fn draw_legend<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    panel: &Panel,
    occ: &Occupancy,
    ctx: &Ctx,
) -> Result<(), PlotError> {
    let entries: Vec<&Series> = panel
        .series
        .iter()
        .filter(|s| !s.label.trim().is_empty())
        .collect();
    if entries.is_empty() {
        return Ok(());
    }
    let f = occ.f;
    let (pad, inset, glyph_w, gap, col_gap) = (8, 8, 28, 7, 16);
    let row_h = (LEGEND_PX * 1.4).round() as i32;
    let avail_h = (f.b - f.t) - 2 * inset - 2 * pad;
    let rows = ((avail_h / row_h).max(1) as usize).min(entries.len());
    let ncols = entries.len().div_ceil(rows);
    let mut col_w = vec![0i32; ncols];
    for (i, s) in entries.iter().enumerate() {
        let w = text_width(ctx, &s.label, LEGEND_PX).ceil() as i32;
        col_w[i / rows] = col_w[i / rows].max(glyph_w + gap + w);
    }
    let box_w = col_w.iter().sum::<i32>() + col_gap * (ncols as i32 - 1) + 2 * pad;
    let box_h = rows as i32 * row_h + 2 * pad - 4;

    let (left, right) = (f.l + inset, f.r - inset - box_w);
    let (top, bottom) = (f.t + inset, f.b - inset - box_h);
    // Preference order on ties: upper right, upper left, lower right, lower left.
    let mut best = (right, top);
    let mut best_cost = u64::MAX;
    for c in [(right, top), (left, top), (right, bottom), (left, bottom)] {
        let cost = occ.cost(c, (c.0 + box_w, c.1 + box_h));
        if cost < best_cost {
            best_cost = cost;
            best = c;
        }
    }
    let (bx, by) = best;
    let corner = |x: i32, y: i32| (ctx.px(f64::from(x)), ctx.px(f64::from(y)));
    root.draw(&Rectangle::new(
        [corner(bx, by), corner(bx + box_w, by + box_h)],
        WHITE.mix(0.85).filled(),
    ))
    .map_err(backend)?;
    let border: ShapeStyle = RGBColor(200, 200, 200).into();
    fill(root, ctx, (bx, by), (bx + box_w, by + 1), border)?;
    fill(
        root,
        ctx,
        (bx, by + box_h - 1),
        (bx + box_w, by + box_h),
        border,
    )?;
    fill(root, ctx, (bx, by), (bx + 1, by + box_h), border)?;
    fill(
        root,
        ctx,
        (bx + box_w - 1, by),
        (bx + box_w, by + box_h),
        border,
    )?;

    let mut x = bx + pad;
    for (c, chunk) in entries.chunks(rows).enumerate() {
        for (r, s) in chunk.iter().enumerate() {
            let cy = f64::from(by + pad + r as i32 * row_h) + f64::from(row_h) / 2.0 - 2.0;
            let (x0, x1, y) = (
                ctx.px(f64::from(x)),
                ctx.px(f64::from(x + glyph_w)),
                ctx.px(cy),
            );
            match s.style {
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
                    .map_err(backend)?;
                }
                SeriesStyle::Markers { color, size } => {
                    let r = ctx.px(f64::from(size.max(1))).max(1);
                    root.draw(&Circle::new(
                        ((x0 + x1) / 2, y),
                        r,
                        color.to_plotters().filled(),
                    ))
                    .map_err(backend)?;
                }
            }
            draw_text(
                root,
                ctx,
                &s.label,
                (ctx.px(f64::from(x + glyph_w + gap)), y),
                LEGEND_PX,
                &TEXT,
                HAlign::Start,
                VAlign::Center,
                false,
            )?;
        }
        x += col_w[c] + col_gap;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read_png_size(bytes: &[u8]) -> (u32, u32) {
        assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "PNG magic");
        assert_eq!(&bytes[12..16], b"IHDR");
        let be = |b: &[u8]| u32::from_be_bytes([b[0], b[1], b[2], b[3]]);
        (be(&bytes[16..20]), be(&bytes[20..24]))
    }

    fn line(label: &str, x: Vec<f64>, y: Vec<f64>, i: usize, width: u32, dashed: bool) -> Series {
        Series {
            label: label.into(),
            x,
            y,
            style: SeriesStyle::Line {
                color: palette(i),
                width,
                dashed,
            },
        }
    }

    /// A Bode-like panel over a linear time panel.
    pub(super) fn sample_figure() -> Figure {
        let f: Vec<f64> = (0..300)
            .map(|i| 0.1 * 10f64.powf(f64::from(i) / 299.0 * 2.5))
            .collect();
        let resp = |fn_hz: f64, z: f64| -> Vec<f64> {
            f.iter()
                .map(|&fr| {
                    let r = fr / fn_hz;
                    ((1.0 + (2.0 * z * r).powi(2))
                        / ((1.0 - r * r).powi(2) + (2.0 * z * r).powi(2)))
                    .sqrt()
                })
                .collect()
        };
        let test_f: Vec<f64> = vec![0.3, 0.5, 0.8, 1.0, 1.5, 2.0, 3.0, 5.0, 8.0];
        let test_t: Vec<f64> = test_f
            .iter()
            .enumerate()
            .map(|(i, &fr)| {
                let r = fr / 1.6;
                let z = 0.3;
                ((1.0 + (2.0 * z * r).powi(2)) / ((1.0 - r * r).powi(2) + (2.0 * z * r).powi(2)))
                    .sqrt()
                    * (1.0 + 0.06 * if i % 2 == 0 { 1.0 } else { -1.0 })
            })
            .collect();
        let mut bode = Panel::new("Magnitude", "frequency [Hz]", "|T| [-]");
        bode.x_scale = Scale::Log10;
        bode.y_scale = Scale::Log10;
        bode.series = vec![
            line("passive ζ = 0.3", f.clone(), resp(1.6, 0.3), 3, 2, false),
            line("active, G(s)", f.clone(), resp(0.8, 0.7), 0, 2, false),
            line(
                "active, twin linearised",
                f.clone(),
                resp(0.85, 0.6),
                1,
                1,
                true,
            ),
            Series::markers("measured u̇/V_in", test_f, test_t, palette(2)),
        ];
        bode.hlines = vec![(1.0, "|T| = 1".into())];

        let t: Vec<f64> = (0..6000).map(|i| f64::from(i) * 0.001).collect();
        let x: Vec<f64> = t
            .iter()
            .map(|&t| 30.0 * (t * 1.3).sin() + 8.0 * (t * 17.0).sin() + 3.0 * (t * 190.0).sin())
            .collect();
        let u: Vec<f64> = t.iter().map(|&t| 38.0 * (t * 1.1 + 0.4).sin()).collect();
        let mut time = Panel::new("Relative displacement", "time [s]", "u [mm]");
        time.series = vec![
            line("platform ẍ", t.clone(), x, 7, 1, false),
            line("u twin", t.clone(), u.clone(), 1, 2, false),
            line(
                "u G(s)",
                t.clone(),
                u.iter().map(|v| v * 0.9).collect(),
                0,
                2,
                true,
            ),
        ];
        time.hlines = vec![(35.0, "+Lc/2".into()), (-35.0, "−Lc/2".into())];
        time.vspans = vec![(0.9, 1.6), (3.8, 4.4)];
        Figure {
            title: "Fig. 12 — transmissibility, active vs passive (test figure)".into(),
            panels: vec![bode, time],
            width: 1000,
            height: 800,
        }
    }

    #[test]
    fn writes_png_and_svg_of_requested_size() {
        let dir = tempfile::tempdir().unwrap();
        let fig = sample_figure();
        let (png, svg) = save_figure(&fig, &dir.path().join("bode")).unwrap();
        assert_eq!(png, dir.path().join("bode.png"));
        assert_eq!(svg, dir.path().join("bode.svg"));
        let bytes = std::fs::read(&png).unwrap();
        assert_eq!(read_png_size(&bytes), (1000, 800));
        let text = std::fs::read_to_string(&svg).unwrap();
        assert!(text.starts_with("<svg"), "{}", &text[..40.min(text.len())]);
        for label in [
            "frequency [Hz]",
            "time [s]",
            "u [mm]",
            "|T| = 1",
            "passive ζ = 0.3",
        ] {
            assert!(text.contains(label), "SVG lacks {label:?}");
        }
        // No temporary file is left behind.
        let names: Vec<_> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        assert_eq!(names.len(), 2, "{names:?}");
        if let Ok(keep) = std::env::var("PLOT_SAMPLE_DIR") {
            std::fs::copy(&png, Path::new(&keep).join("sample.png")).unwrap();
            std::fs::copy(&svg, Path::new(&keep).join("sample.svg")).unwrap();
        }
    }

    #[test]
    fn bad_data_never_panics() {
        let dir = tempfile::tempdir().unwrap();
        let nan = f64::NAN;
        let mut log = Panel::new("all negative on log axes", "f [Hz]", "|G| [-]");
        log.x_scale = Scale::Log10;
        log.y_scale = Scale::Log10;
        log.series = vec![
            line(
                "negative",
                vec![-1.0, -2.0, 0.0],
                vec![-1.0, -5.0, -3.0],
                0,
                2,
                false,
            ),
            line("empty", vec![], vec![], 1, 2, false),
            Series::markers("nan", vec![nan, 1.0], vec![1.0, nan], palette(2)),
        ];
        log.hlines = vec![(-1.0, "invisible".into())];
        log.vspans = vec![(-1.0, 0.0), (nan, 3.0)];
        let mut mixed = Panel::new("NaN gaps, mismatched lengths", "t [s]", "y [m]");
        mixed.series = vec![
            line(
                "gappy",
                vec![0.0, 1.0, 2.0, 3.0, 4.0, 5.0],
                vec![0.0, 1.0, nan, 3.0, f64::INFINITY, 2.0, 9.0],
                0,
                2,
                true,
            ),
            line("one point", vec![2.0], vec![2.0], 1, 2, false),
        ];
        mixed.y_range = Some((nan, 1.0)); // unusable → fitted
        mixed.x_range = Some((1.5, 3.5));
        let mut flat = Panel::new("", "", "");
        flat.series = vec![line("", vec![1.0, 1.0], vec![5.0, 5.0], 0, 2, false)];
        let fig = Figure {
            title: String::new(),
            panels: vec![log, mixed, flat, Panel::default()],
            width: 700,
            height: 900,
        };
        let (png, svg) = save_figure(&fig, &dir.path().join("bad.data")).unwrap();
        assert!(png.ends_with("bad.data.png") && svg.ends_with("bad.data.svg"));
        assert_eq!(read_png_size(&std::fs::read(&png).unwrap()), (700, 900));
        assert!(std::fs::read_to_string(&svg).unwrap().contains("no data"));
        if let Ok(keep) = std::env::var("PLOT_SAMPLE_DIR") {
            std::fs::copy(&png, Path::new(&keep).join("bad_data.png")).unwrap();
        }

        // Degenerate figures, and one too large to supersample.
        let mut big = Figure::new("big", vec![Panel::new("p", "x", "y")]);
        big.panels[0].series = vec![Series::line(
            "l",
            vec![0.0, 1.0],
            vec![1.0, 0.0],
            palette(0),
        )];
        (big.width, big.height) = (3000, 2700);
        for fig in [
            big,
            Figure::new("no panels", vec![]),
            Figure {
                title: "tiny".into(),
                panels: vec![Panel::new("p", "x", "y")],
                width: 0,
                height: 1,
            },
        ] {
            let (png, _) = save_figure(&fig, &dir.path().join("degenerate")).unwrap();
            let (w, h) = read_png_size(&std::fs::read(&png).unwrap());
            assert!(w >= fig.width && h >= fig.height);
        }
    }

    #[test]
    fn missing_directory_is_an_io_error() {
        let dir = tempfile::tempdir().unwrap();
        let err = save_figure(
            &Figure::new("x", vec![]),
            &dir.path().join("missing").join("fig"),
        )
        .unwrap_err();
        assert!(matches!(err, PlotError::Io { .. }), "{err}");
        assert!(err.to_string().contains("missing"), "{err}");
    }

    #[test]
    fn ticks_are_readable() {
        let (major, minor) = log_ticks(0.3f64.log10(), 30f64.log10(), 6);
        let labels: Vec<&str> = major.iter().map(|t| t.1.as_str()).collect();
        assert_eq!(labels, ["0.5", "1", "2", "5", "10", "20"]);
        assert!(minor.len() > 10);
        let (major, _) = log_ticks(-7.2, 3.1, 6);
        let labels: Vec<&str> = major.iter().map(|t| t.1.as_str()).collect();
        assert_eq!(labels, ["1e−6", "0.0001", "0.01", "1", "100"]);
        let (major, _) = linear_ticks(-0.37, 0.52, 6);
        let labels: Vec<&str> = major.iter().map(|t| t.1.as_str()).collect();
        assert_eq!(labels, ["−0.2", "0", "0.2", "0.4"]);
        assert_eq!(fmt_tick(1.5e-6, 5e-7), "1.5e−6");
        assert_eq!(fmt_tick(2000.0, 500.0), "2000");
        assert_eq!(fmt_tick(-35.0, 5.0), "−35");
    }

    #[test]
    fn text_layout_matches_the_font() {
        let m = ensure_font().unwrap();
        // Same advance widths as plotters' own (ab_glyph) measurement, which has no kerning
        // between digits.
        let text = "0123456789";
        let (_, ours) = layout(m, text, 100.0);
        let size = 100.0 * (m.ascent + m.descent) / m.upem;
        let theirs = FontDesc::new(FontFamily::SansSerif, size, FontStyle::Normal)
            .box_size(text)
            .unwrap()
            .0;
        assert!(
            (ours - f64::from(theirs)).abs() <= 2.0,
            "{ours} vs {theirs}"
        );
        // Missing glyphs fall back: the dot of u̇ goes over the u, ẍ becomes x + ¨.
        let (g, _) = layout(m, "u\u{307}/V", 20.0);
        let chars: String = g.iter().map(|p| p.c).collect();
        assert_eq!(chars, "u˙/V");
        assert!(g[1].pen > g[0].pen && g[1].pen < g[2].pen);
        let (g, _) = layout(m, "ẍ → y′", 20.0);
        let chars: String = g.iter().map(|p| p.c).collect();
        assert_eq!(chars, "x¨->y'");
        for c in "|T| = 1 ζ ± ² · − —".chars() {
            assert!(c == ' ' || m.glyph(c) != 0, "{c:?}");
        }
    }
}
