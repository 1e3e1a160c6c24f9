//! Engineering plots: Bode diagrams, transmissibility curves and time histories, written as a
//! PNG and an SVG of the same figure. Used by `seat-twin report`, by the measured-data report
//! of `identify`, and by the app's figure export.
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
//!
//! # Layout of the module
//!
//! | file | job |
//! |------|-----|
//! | `mod.rs` | the public types ([`Figure`], [`Panel`], [`Series`], …) and [`save_figure`] |
//! | `output.rs` | the two backends: supersampled PNG (averaged down) and SVG; atomic writes |
//! | `text.rs` | the embedded font's metrics (read with `ttf-parser`) and text layout |
//! | `canvas.rs` | rendering context, colours and sizes, pixel-exact fills, drawing text |
//! | `ticks.rs` | axis ranges and tick generation (1-2-5 steps, log decades), tick labels |
//! | `clip.rs` | data preparation: scale transform, clipping to the plot area, decimation |
//! | `legend.rs` | what is drawn where (occupancy grid), legend and reference-label placement |
//! | `render.rs` | figure layout (margins shared by the panels) and drawing one panel |
//!
//! # What plotters does, and why some drawing is still done here
//!
//! plotters provides the backends (bitmap with its PNG encoder, SVG), the font rasteriser
//! (`ab_glyph`), and the elements that are drawn (paths, dashed paths, circles, rectangles,
//! text). Its chart layer (`ChartBuilder`, `configure_mesh`, `configure_series_labels`) is not
//! used, because for these figures it cannot do what is needed:
//!
//! - **Text.** plotters' `ab_glyph` renderer places each glyph from its ink box and drops the
//!   left side bearing, so letter spacing is uneven; and it has no fallback for characters the
//!   font lacks (`u̇`, `ẍ`, `′`, `→`). Text is therefore laid out here from the font's own
//!   metrics (read with `ttf-parser`, see `text.rs`) and drawn one glyph at a time. The mesh and
//!   the series legend of the chart layer draw their text through that renderer.
//! - **Clipping.** plotters draws a series wherever its points map, also outside the plot area
//!   and over the axes; lines are clipped here (Liang–Barsky) and broken at non-finite points.
//! - **Ticks.** The x tick density is chosen so that neighbouring labels keep a clear gap in
//!   the font actually used, and log axes get 1-2-5 labels with 1–9 sub-lines; the mesh has
//!   no such measurement.
//! - **Legend.** `SeriesLabelPosition` is a fixed corner or coordinate; it does not know where
//!   the data are. The legend here goes to the corner that hides the least data.
//! - **Dense lines.** plotters fills a wide path as one polygon, which leaves holes where a
//!   dense time history doubles back; the PNG draws such paths in runs joined by round dots.

mod canvas;
mod clip;
mod legend;
mod output;
mod render;
mod text;
mod ticks;

#[cfg(test)]
mod tests;

use plotters::prelude::RGBColor;
use std::path::PathBuf;

pub use output::{figure_bytes, figure_svg, save_figure};

/// Default figure width (px).
pub const DEFAULT_WIDTH: u32 = 1000;
/// Default figure height (px).
pub const DEFAULT_HEIGHT: u32 = 600;

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

    /// The panel with `series` as its curves.
    pub fn with_series(mut self, series: Vec<Series>) -> Self {
        self.series = series;
        self
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
