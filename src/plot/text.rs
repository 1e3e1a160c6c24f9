//! The embedded font and text layout.
//!
//! plotters' `ab_glyph` renderer draws every glyph from its ink box, dropping the left side
//! bearing, which makes letter spacing uneven. So text is laid out here from the font's own
//! metrics (advance widths, ink boxes, cap and x heights, read with `ttf-parser`) and drawn one
//! glyph at a time (`canvas::draw_text`). Characters the font lacks fall back to what it has.

use super::PlotError;
#[cfg(not(target_arch = "wasm32"))]
use plotters::style::FontStyle;
use std::sync::OnceLock;
use ttf_parser::{Face, GlyphId};

/// The embedded font (Ubuntu Font Licence, see `assets/fonts/UFL.txt`).
static FONT_BYTES: &[u8] = include_bytes!("../../assets/fonts/Ubuntu-Light.ttf");

/// What the layout needs from the embedded TrueType font. Lengths are in font units.
pub(super) struct Font {
    face: Face<'static>,
    /// Units per em.
    pub upem: f64,
    /// Ascent above the baseline (`hhea`).
    pub ascent: f64,
    /// Descent below the baseline, positive (`hhea`).
    pub descent: f64,
    /// Height of the capitals.
    pub cap: f64,
    /// Height of the lower-case letters.
    pub x_height: f64,
}

impl Font {
    fn parse(data: &'static [u8]) -> Result<Self, String> {
        let face = Face::parse(data, 0).map_err(|e| e.to_string())?;
        let upem = f64::from(face.units_per_em());
        let hhea = face.tables().hhea;
        let font = Self {
            upem,
            ascent: f64::from(hhea.ascender),
            descent: -f64::from(hhea.descender),
            cap: face.capital_height().map_or(0.7 * upem, f64::from),
            x_height: face.x_height().map_or(0.5 * upem, f64::from),
            face,
        };
        if font.upem > 0.0 && font.ascent + font.descent > 0.0 && font.has(' ') {
            Ok(font)
        } else {
            Err("the font has no usable metrics".into())
        }
    }

    /// Glyph of `c`; glyph 0 (the "missing" box) if the font lacks it.
    pub fn glyph(&self, c: char) -> GlyphId {
        self.face.glyph_index(c).unwrap_or(GlyphId(0))
    }

    /// Whether the font has a glyph for `c`.
    pub fn has(&self, c: char) -> bool {
        self.glyph(c).0 != 0
    }

    /// Advance width.
    pub fn advance(&self, g: GlyphId) -> f64 {
        f64::from(self.face.glyph_hor_advance(g).unwrap_or(0))
    }

    /// Horizontal ink extent `(x_min, x_max)`; `None` for an empty glyph.
    pub fn ink(&self, g: GlyphId) -> Option<(f64, f64)> {
        self.face
            .glyph_bounding_box(g)
            .map(|r| (f64::from(r.x_min), f64::from(r.x_max)))
    }

    /// Scale from font units to px at `em` px.
    pub fn k(&self, em: f64) -> f64 {
        em / self.upem
    }
}

/// Parses the embedded font and registers it with plotters (once); the font's metrics.
pub(super) fn font() -> Result<&'static Font, PlotError> {
    static FONT: OnceLock<Result<Font, String>> = OnceLock::new();
    let parsed = FONT.get_or_init(|| {
        // plotters has no font registry on wasm32: the metrics serve the SVG there (its
        // text is set by the viewer); no PNG is drawn (see `output::render_rgb`).
        let font = Font::parse(FONT_BYTES)?;
        #[cfg(not(target_arch = "wasm32"))]
        plotters::style::register_font("sans-serif", FontStyle::Normal, FONT_BYTES)
            .map_err(|_| "plotters did not accept the font".to_string())?;
        Ok(font)
    });
    parsed
        .as_ref()
        .map_err(|e| PlotError::Backend(format!("the embedded font could not be loaded: {e}")))
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

/// What a character the font lacks is drawn as: base letters and an optional accent over the
/// last of them. An empty base means "no substitute".
fn substitute(c: char) -> (&'static str, Option<char>) {
    match c {
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
    }
}

/// One glyph placed along the text: pen position (px) and lift above the baseline (px).
pub(super) struct Placed {
    pub c: char,
    pub pen: f64,
    pub lift: f64,
}

/// Lays `text` out at `em` px: the glyphs and the advance width. Characters the font lacks
/// fall back: accents (combining, or precomposed `ẋ ẏ ẍ ṗ`) go over their letter, primes
/// become apostrophes, arrows `->`, …
pub(super) fn layout(m: &Font, text: &str, em: f64) -> (Vec<Placed>, f64) {
    let k = m.k(em);
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
        if c == ' ' || m.has(c) {
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
        let (base, acc) = substitute(c);
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

#[cfg(test)]
mod tests {
    use super::*;
    use plotters::style::{FontDesc, FontFamily};

    #[test]
    fn metrics_are_those_of_ubuntu_light() {
        let m = font().unwrap();
        // Read from the file's bytes by hand: head.unitsPerEm 1000, hhea ascender 932 /
        // descender −189, OS/2 (version 3) sxHeight 517, sCapHeight 693.
        assert_eq!(m.upem, 1000.0);
        assert_eq!((m.ascent, m.descent), (932.0, 189.0));
        assert_eq!((m.x_height, m.cap), (517.0, 693.0));
    }

    #[test]
    fn layout_matches_the_font() {
        let m = font().unwrap();
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
            assert!(c == ' ' || m.has(c), "{c:?}");
        }
        // An accent over a capital is lifted by the difference of cap and x height.
        let (g, _) = layout(m, "Ẋ", 20.0);
        assert!((g[1].lift - (m.cap - m.x_height) * m.k(20.0)).abs() < 1e-9);
    }
}
