//! The two outputs of a figure: a PNG rendered at twice the size and averaged down (so lines
//! are anti-aliased), and an SVG whose text is set by the viewer. Each file is written with
//! [`crate::fsutil::write_atomic_bytes`] (a temporary file beside it, renamed).

use super::canvas::Ctx;
use super::render::{Drawn, render};
use super::text::font;
use super::{Figure, PlotError};
use crate::fsutil::write_atomic_bytes;
use image::ImageEncoder;
use plotters::prelude::*;
use std::ffi::OsString;
use std::path::{Path, PathBuf};

/// Smallest figure side that is drawn (px); smaller requested sizes are enlarged to this.
const MIN_SIDE: u32 = 64;
/// Largest figure side that is drawn (px); larger requested sizes are reduced to this.
const MAX_SIDE: u32 = 8_192;

/// Draws `fig` into `<path_without_extension>.png` and `<path_without_extension>.svg` and
/// returns the two paths. The extensions are appended (`out/fig.v2` → `out/fig.v2.png`); the
/// directory must exist. Each file is written to a temporary file beside it and renamed.
pub fn save_figure(
    fig: &Figure,
    path_without_extension: &Path,
) -> Result<(PathBuf, PathBuf), PlotError> {
    let png = with_suffix(path_without_extension, ".png");
    let svg = with_suffix(path_without_extension, ".svg");
    let (encoded, text) =
        figure_bytes(fig).map_err(|e| PlotError::Backend(format!("{}: {e}", png.display())))?;
    let io = |path: &Path| {
        let path = path.to_path_buf();
        move |source| PlotError::Io { path, source }
    };
    write_atomic_bytes(&png, &encoded).map_err(io(&png))?;
    write_atomic_bytes(&svg, text.as_bytes()).map_err(io(&svg))?;
    Ok((png, svg))
}

/// `fig` drawn as the bytes of a PNG file and the text of an SVG file, in memory (what
/// [`save_figure`] writes). Not in the web build (see [`figure_svg`]).
pub fn figure_bytes(fig: &Figure) -> Result<(Vec<u8>, String), PlotError> {
    let (w, h) = size(fig);
    let (rgb, _) = render_rgb(fig)?;
    let mut encoded = Vec::new();
    image::codecs::png::PngEncoder::new(&mut encoded)
        .write_image(&rgb, w, h, image::ExtendedColorType::Rgb8)
        .map_err(|e| PlotError::Backend(e.to_string()))?;
    let (text, _) = render_svg(fig)?;
    Ok((encoded, text))
}

/// `fig` as the text of an SVG file, in memory: what the web app downloads (its text is set
/// by the viewer, so no font rasteriser is needed; the web build draws no PNG).
pub fn figure_svg(fig: &Figure) -> Result<String, PlotError> {
    render_svg(fig).map(|(text, _)| text)
}

/// The drawn size of `fig` (px).
fn size(fig: &Figure) -> (u32, u32) {
    (
        fig.width.clamp(MIN_SIDE, MAX_SIDE),
        fig.height.clamp(MIN_SIDE, MAX_SIDE),
    )
}

/// The figure as 8-bit RGB rows of [`size`], rendered at 2× (up to 8 Mpx) and averaged down;
/// where the panels went.
pub(super) fn render_rgb(fig: &Figure) -> Result<(Vec<u8>, Vec<Drawn>), PlotError> {
    if cfg!(target_arch = "wasm32") {
        // plotters rasterises text with its font registry, which wasm32 lacks: a PNG here
        // would have no text.
        return Err(PlotError::Backend(
            "PNG figures are not drawn in the web build (no font rasteriser); the SVG is".into(),
        ));
    }
    let m = font()?;
    let (w, h) = size(fig);
    let ss: u32 = if u64::from(w) * u64::from(h) <= 8_000_000 {
        2
    } else {
        1
    };
    let (bw, bh) = (w * ss, h * ss);
    let mut big = vec![255u8; bw as usize * bh as usize * 3];
    let drawn = {
        let root = BitMapBackend::with_buffer(&mut big, (bw, bh)).into_drawing_area();
        let ctx = Ctx {
            s: f64::from(ss),
            bitmap: true,
            m,
        };
        let drawn = render(&root, fig, &ctx)?;
        root.present().map_err(super::canvas::backend)?;
        drawn
    };
    Ok((downsample(&big, bw, bh, ss), drawn))
}

/// The figure as SVG text; where the panels went.
pub(super) fn render_svg(fig: &Figure) -> Result<(String, Vec<Drawn>), PlotError> {
    let m = font()?;
    let mut text = String::new();
    let drawn = {
        let root = SVGBackend::with_string(&mut text, size(fig)).into_drawing_area();
        let ctx = Ctx {
            s: 1.0,
            bitmap: false,
            m,
        };
        let drawn = render(&root, fig, &ctx)?;
        root.present().map_err(super::canvas::backend)?;
        drawn
    };
    Ok((text, drawn))
}

fn with_suffix(p: &Path, suffix: &str) -> PathBuf {
    let mut s: OsString = p.as_os_str().to_owned();
    s.push(suffix);
    PathBuf::from(s)
}

/// `f`×`f` box filter of an RGB buffer.
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
