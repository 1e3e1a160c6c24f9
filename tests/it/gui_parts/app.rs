//! `seat_twin::gui::app`: unit tests kept out of the library (see `gui_parts`).

use seat_twin::gui::SeatTwinApp;
use seat_twin::gui::files::Purpose;
use seat_twin::gui::settings::Settings;
use seat_twin::preset::Preset;
use std::path::Path;

/// What the web app downloads is what the desktop writes: the preset's TOML reads back
/// as the parameters on screen, each plot is a PNG and an SVG, and nothing is made
/// where there is nothing to save.
#[test]
fn download_files_hold_what_the_desktop_writes() {
    let mut app = SeatTwinApp::new(Settings::default(), || {});
    let mut gains = app.params().controller;
    gains.kp_v_per_m = -21.5;
    app.apply_tuned(gains);
    assert_eq!(app.params().controller.kp_v_per_m, -21.5);
    let files = app
        .download_files(Purpose::SavePreset, "mine.toml")
        .unwrap();
    assert_eq!(files.len(), 1);
    let (name, bytes, mime) = &files[0];
    assert_eq!((name.as_str(), *mime), ("mine.toml", "application/toml"));
    let back = Preset::from_bytes(bytes, Path::new(name)).unwrap();
    assert_eq!(back.params, *app.params());
    assert_eq!(back.meta.name, "mine");

    let plots = app.download_files(Purpose::ExportPng, "plots.png").unwrap();
    let figures = app.plot_figures();
    assert_eq!(plots.len(), 2 * figures.len());
    for ((suffix, _), pair) in figures.iter().zip(plots.chunks(2)) {
        assert_eq!(pair[0].0, format!("plots-{suffix}.png"));
        assert!(pair[0].1.starts_with(b"\x89PNG\r\n\x1a\n"));
        assert_eq!(pair[1].0, format!("plots-{suffix}.svg"));
        assert!(pair[1].1.starts_with(b"<svg"));
    }

    let none = app.download_files(Purpose::ExportCsv, "traces.csv");
    assert!(none.unwrap_err().contains("nothing to export"));
    let refused = app.download_files(Purpose::ExportReport, "calibration");
    assert!(refused.unwrap_err().contains("not in the web build"));
}
