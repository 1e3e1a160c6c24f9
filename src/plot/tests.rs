//! End-to-end tests of the plot module: files, sizes, pixels, SVG content, bad data, legend.

use super::output::{render_rgb, render_svg};
use super::*;
use std::path::Path;

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

/// SVG colour of palette entry `i`, as plotters writes it.
fn svg_color(i: usize) -> String {
    let Rgb(r, g, b) = palette(i);
    format!("#{r:02X}{g:02X}{b:02X}")
}

/// The text contents of an SVG written by plotters (each on its own line inside `<text>`).
fn svg_texts(svg: &str) -> Vec<&str> {
    svg.lines().filter(|l| !l.starts_with('<')).collect()
}

/// The SVG elements `<{tag}` whose attribute `attr` is palette entry `i`'s colour.
fn svg_elements<'a>(svg: &'a str, tag: &str, attr: &str, i: usize) -> Vec<&'a str> {
    let (start, colour) = (format!("<{tag}"), format!("{attr}=\"{}\"", svg_color(i)));
    svg.lines()
        .filter(|l| l.starts_with(&start) && l.contains(&colour))
        .collect()
}

/// A Bode-like panel over a linear time panel.
fn sample_figure() -> Figure {
    let f: Vec<f64> = (0..300)
        .map(|i| 0.1 * 10f64.powf(f64::from(i) / 299.0 * 2.5))
        .collect();
    let resp = |fn_hz: f64, z: f64| -> Vec<f64> {
        f.iter()
            .map(|&fr| {
                let r = fr / fn_hz;
                ((1.0 + (2.0 * z * r).powi(2)) / ((1.0 - r * r).powi(2) + (2.0 * z * r).powi(2)))
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
            ((1.0 + (2.0 * z * r).powi(2)) / ((1.0 - r * r).powi(2) + (2.0 * z * r).powi(2))).sqrt()
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

/// Pixels of `img` inside `f` whose colour is saturated (a series colour, not text, grid or
/// background, which are all grey).
fn coloured_pixels(img: &image::RgbImage, f: &canvas::Frame) -> usize {
    let mut n = 0;
    for y in f.t..f.b {
        for x in f.l..f.r {
            let p = img.get_pixel(x as u32, y as u32).0;
            let (hi, lo) = (p.iter().max().unwrap(), p.iter().min().unwrap());
            if hi - lo > 60 {
                n += 1;
            }
        }
    }
    n
}

#[test]
fn writes_png_and_svg_of_requested_size_with_the_data_drawn() {
    let dir = tempfile::tempdir().unwrap();
    let fig = sample_figure();
    let (png, svg) = save_figure(&fig, &dir.path().join("bode")).unwrap();
    assert_eq!(png, dir.path().join("bode.png"));
    assert_eq!(svg, dir.path().join("bode.svg"));
    let img = image::open(&png).unwrap().to_rgb8();
    assert_eq!(img.dimensions(), (1000, 800));

    // The series are drawn inside each plot area, and not in the margins.
    let (_, drawn) = render_rgb(&fig).unwrap();
    assert_eq!(drawn.len(), 2);
    for d in &drawn {
        let f = d.frame;
        assert!(f.l > 40 && f.r < 1000 && f.t > 20 && f.b < 800, "{f:?}");
        let n = coloured_pixels(&img, &f);
        let area = ((f.r - f.l) * (f.b - f.t)) as usize;
        assert!(n > area / 100, "{n} coloured px of {area} in {f:?}");
    }
    let left_margin = canvas::Frame {
        l: 0,
        t: 0,
        r: drawn[0].frame.l - 2,
        b: 800,
    };
    assert_eq!(coloured_pixels(&img, &left_margin), 0);
    // An empty panel of the same size has no coloured pixel in its plot area.
    let mut empty = fig.clone();
    for p in &mut empty.panels {
        p.series.clear();
        p.vspans.clear();
    }
    let path = dir.path().join("empty");
    let (png, _) = save_figure(&empty, &path).unwrap();
    let img = image::open(&png).unwrap().to_rgb8();
    let (_, drawn) = render_rgb(&empty).unwrap();
    assert_eq!(coloured_pixels(&img, &drawn[0].frame), 0);

    // No temporary file is left behind.
    let names: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names.len(), 4, "{names:?}");
    if let Ok(keep) = std::env::var("PLOT_SAMPLE_DIR") {
        std::fs::copy(
            dir.path().join("bode.png"),
            Path::new(&keep).join("sample.png"),
        )
        .unwrap();
        std::fs::copy(&svg, Path::new(&keep).join("sample.svg")).unwrap();
    }
}

#[test]
fn svg_holds_the_series_and_the_labels() {
    let fig = sample_figure();
    let (text, _) = render_svg(&fig).unwrap();
    assert!(text.starts_with("<svg"), "{}", &text[..40.min(text.len())]);
    let texts = svg_texts(&text);
    for label in [
        "Fig. 12 — transmissibility",
        "Magnitude",
        "frequency [Hz]",
        "|T| [-]",
        "time [s]",
        "u [mm]",
        "|T| = 1",
        "passive ζ = 0.3",
        "active, twin linearised",
        "measured u̇/V_in",
        "u G(s)",
    ] {
        assert!(
            texts.iter().any(|t| t.starts_with(label)),
            "SVG lacks {label:?}"
        );
    }
    // Tick labels of the log frequency axis and of the linear time axis.
    for tick in ["0.1", "1", "10", "0", "2", "4"] {
        assert!(texts.contains(&tick), "SVG lacks tick {tick}: {texts:?}");
    }
    // Every line series is drawn in its colour; the markers as circles in theirs.
    for i in [3, 0, 1, 7] {
        let c = svg_color(i);
        assert!(
            text.contains(&format!("stroke=\"{c}\"")),
            "no line in {c} (palette {i})"
        );
    }
    let dots = svg_elements(&text, "circle", "fill", 2).len();
    assert_eq!(dots, 9 + 1, "nine markers and the legend's sample");
}

#[test]
fn non_finite_values_are_skipped_not_drawn() {
    let nan = f64::NAN;
    let mut p = Panel::new("gaps", "t [s]", "y [m]");
    let x: Vec<f64> = (0..9).map(f64::from).collect();
    let y = vec![0.0, 1.0, 0.5, nan, 2.0, 1.0, f64::INFINITY, 1.5, 1.0];
    p.series = vec![line("gappy", x.clone(), y.clone(), 3, 2, false)];
    p.series.push(Series::markers("dots", x, y, palette(2)));
    let fig = Figure::new("", vec![p]);
    let (text, drawn) = render_svg(&fig).unwrap();
    assert!(!text.contains("NaN") && !text.contains("inf"), "{text}");
    // Three polylines of the series' colour (0–2, 4–5, 7–8) and one in the legend.
    let polylines = svg_elements(&text, "polyline", "stroke", 3);
    assert_eq!(polylines.len(), 4, "{polylines:#?}");
    // All of them inside the plot area.
    let f = drawn[0].frame;
    for l in &polylines {
        let pts = l
            .split("points=\"")
            .nth(1)
            .unwrap()
            .split('"')
            .next()
            .unwrap();
        for xy in pts.split_whitespace() {
            let (x, y) = xy.split_once(',').unwrap();
            let (x, y): (i32, i32) = (x.parse().unwrap(), y.parse().unwrap());
            assert!(
                x >= f.l && x <= f.r && y >= f.t && y <= f.b,
                "{xy} outside {f:?}"
            );
        }
    }
    // Seven markers (and the legend's), none for the two non-finite values.
    let dots = svg_elements(&text, "circle", "fill", 2).len();
    assert_eq!(dots, 7 + 1);
    // The fitted y range comes from the finite values only: 0 … 2 plus 5 % padding.
    let texts = svg_texts(&text);
    assert!(
        texts.contains(&"2.0") && !texts.contains(&"2.2"),
        "{texts:?}"
    );
}

#[test]
fn legend_keeps_off_the_data_in_the_figure() {
    // Data fill the upper-right quarter of fixed unit ranges; three labelled series.
    let mut p = Panel::new("corner", "x [-]", "y [-]");
    p.x_range = Some((0.0, 1.0));
    p.y_range = Some((0.0, 1.0));
    for k in 0..3usize {
        let x: Vec<f64> = (0..=40).map(|i| 0.5 + 0.5 * f64::from(i) / 40.0).collect();
        let y: Vec<f64> = (0..=40)
            .map(|i: i32| 0.5 + 0.45 * f64::from((i + k as i32) % 2) + 0.02 * k as f64)
            .collect();
        p.series
            .push(line(&format!("series {k}"), x, y, k, 2, false));
    }
    let fig = Figure::new("", vec![p]);
    for drawn in [render_rgb(&fig).unwrap().1, render_svg(&fig).unwrap().1] {
        let f = drawn[0].frame;
        let legend = drawn[0].legend.expect("labelled series have a legend");
        // Pixel box of the data, as the renderer maps x, y ∈ [0.5, 1].
        let px = |t: f64, a: i32, b: i32| f64::from(a) + 0.5 + t * f64::from(b - a - 1);
        let data = canvas::Rect {
            x0: px(0.5, f.l, f.r).floor() as i32 - 2,
            x1: f.r,
            y0: f.t,
            y1: (f64::from(f.b) - (px(0.5, f.t, f.b) - f64::from(f.t))).ceil() as i32 + 2,
        };
        assert!(
            !legend.intersects(&data),
            "legend {legend:?} over data {data:?}"
        );
        assert!(legend.x0 >= f.l && legend.x1 <= f.r && legend.y0 >= f.t && legend.y1 <= f.b);
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
    assert_eq!(
        image::open(&png).unwrap().to_rgb8().dimensions(),
        (700, 900)
    );
    let text = std::fs::read_to_string(&svg).unwrap();
    let notes = svg_texts(&text).iter().filter(|t| **t == "no data").count();
    assert_eq!(notes, 2, "the log panel and the empty one");
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
        let img = image::open(&png).unwrap().to_rgb8();
        let expect = (fig.width.clamp(64, 8192), fig.height.clamp(64, 8192));
        assert_eq!(img.dimensions(), expect);
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
