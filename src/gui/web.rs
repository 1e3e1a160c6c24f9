//! The browser entry (wasm32): eframe's web runner with the glow renderer on a canvas, and
//! the page's JavaScript API (`web/index.html` puts it at `window.seatTwin`).
//!
//! The app is the desktop app: the same [`SeatTwinApp`], its engine stepped in the frames
//! ([`crate::engine::EngineHandle::pump`]). The page's address sets it up:
//!
//! * `#s=…` — a setup link ([`super::share`]); a bad one gives a message and the defaults;
//! * `?seed=N&excitation=random[&duration=T][&speed=max]` — the random ride of
//!   `seat-twin simulate --scenario random --seed N --duration T`, paused at its end.

use super::SeatTwinApp;
use super::share::page_link;
use crate::engine::Speed;
use wasm_bindgen::prelude::*;

/// The value of `key` in a query string `?a=1&b=2`.
fn query_value<'a>(query: &'a str, key: &str) -> Option<&'a str> {
    query
        .trim_start_matches('?')
        .split('&')
        .filter_map(|kv| kv.split_once('='))
        .find(|(k, _)| *k == key)
        .map(|(_, v)| v)
}

/// Sets the app up from the page's query and fragment.
fn set_up_from_address(app: &mut SeatTwinApp, query: &str, hash: &str) {
    if !hash.is_empty() && hash != "#" {
        // A bad link is reported by apply_link (a message) and leaves the defaults.
        let _ = app.apply_link(hash);
    }
    match query_value(query, "excitation") {
        Some("random") => {
            let seed = query_value(query, "seed").unwrap_or("1");
            if let Err(e) = app.apply_query(seed, query_value(query, "duration")) {
                app.show_error(e);
            }
        }
        Some(other) => app.show_error(format!(
            "?excitation={other}: only `random` is read from the address (with seed and \
             duration); use a setup link (#s=…) for the others"
        )),
        None => {}
    }
    if let Some(s) = query_value(query, "speed") {
        match s {
            "max" => app.set_speed(Speed::Max),
            "1x" => app.set_speed(Speed::RealTime),
            "fast" => app.set_speed(Speed::Fast),
            "slow" => app.set_speed(Speed::Slow),
            other => app.show_error(format!("?speed={other}: one of slow, 1x, fast, max")),
        }
    }
}

/// The running app in a page, for JavaScript.
#[wasm_bindgen]
pub struct WebHandle {
    runner: eframe::WebRunner,
}

#[wasm_bindgen]
impl WebHandle {
    /// A handle with no app yet ([`Self::start`] starts it).
    #[wasm_bindgen(constructor)]
    #[allow(clippy::new_without_default)]
    pub fn new() -> Self {
        eframe::WebLogger::init(log::LevelFilter::Warn).ok();
        Self {
            runner: eframe::WebRunner::new(),
        }
    }

    /// Starts the app on `canvas`, set up from the page's address.
    pub async fn start(&self, canvas: web_sys::HtmlCanvasElement) -> Result<(), JsValue> {
        let location = web_sys::window().map(|w| w.location());
        let query = location
            .as_ref()
            .and_then(|l| l.search().ok())
            .unwrap_or_default();
        let hash = location
            .as_ref()
            .and_then(|l| l.hash().ok())
            .unwrap_or_default();
        self.runner
            .start(
                canvas,
                eframe::WebOptions::default(),
                Box::new(move |cc| {
                    let mut app = SeatTwinApp::from_creation_context(cc);
                    set_up_from_address(&mut app, &query, &hash);
                    Ok(Box::new(app))
                }),
            )
            .await
    }

    fn with_app<T>(&self, f: impl FnOnce(&mut SeatTwinApp) -> T) -> Result<T, JsValue> {
        let mut app = self.runner.app_mut::<SeatTwinApp>().ok_or_else(|| {
            JsValue::from_str("the app is not running (not started, or it panicked)")
        })?;
        let out = f(&mut app);
        app.repaint();
        Ok(out)
    }

    /// The state as JSON ([`SeatTwinApp::state_json`]).
    pub fn state(&self) -> Result<String, JsValue> {
        self.with_app(|a| a.state_json())
    }

    /// The page's address with the current setup as `#s=…`.
    pub fn link(&self) -> Result<String, JsValue> {
        self.with_app(|a| page_link(&a.link()))
    }

    /// Restores a setup link (`1;…`, `#s=1;…` or a whole address).
    pub fn restore(&self, link: &str) -> Result<(), JsValue> {
        let fragment = link.split_once('#').map_or(link, |(_, f)| f);
        self.with_app(|a| a.apply_link(fragment))?
            .map_err(|e| JsValue::from_str(&e))
    }

    /// Sets a slider by its label (`Kp`, `Ki`, `lead`, `τ`, …) to a value in its display
    /// unit, through the sliders' own path.
    pub fn set_slider(&self, label: &str, value: f64) -> Result<(), JsValue> {
        self.with_app(|a| a.set_slider(label, value))?
            .map_err(|e| JsValue::from_str(&e))
    }

    /// `slow`, `1x`, `fast` or `max`.
    pub fn set_speed(&self, speed: &str) -> Result<(), JsValue> {
        let s = match speed {
            "slow" => Speed::Slow,
            "1x" => Speed::RealTime,
            "fast" => Speed::Fast,
            "max" => Speed::Max,
            other => return Err(JsValue::from_str(&format!("unknown speed `{other}`"))),
        };
        self.with_app(|a| a.set_speed(s))
    }

    /// Back to rest at t = 0 (clears a divergence).
    pub fn reset(&self) -> Result<(), JsValue> {
        self.with_app(|a| a.reset())
    }

    /// Back to the last gains that were stable, then from rest.
    pub fn reset_to_last_stable_gains(&self) -> Result<(), JsValue> {
        self.with_app(|a| a.reset_to_last_stable_gains())
    }

    /// Starts lesson step `n` (1-based).
    pub fn start_lesson(&self, n: usize) -> Result<(), JsValue> {
        self.with_app(|a| a.start_lesson(n.saturating_sub(1)))
    }

    /// Presentation mode on or off.
    pub fn set_presentation(&self, on: bool) -> Result<(), JsValue> {
        self.with_app(|a| a.set_presentation(on))
    }

    /// The twin's real-time factor in this browser, as `seat-twin bench` measures it
    /// natively: the best of `runs` runs of its 10 s closed-loop random ride, recorded at
    /// 1 kHz, at the paper preset's step (exponential RK4, 0.5 ms). It blocks the page
    /// while it runs (about 10 s / factor per run).
    pub fn bench_twin(&self, runs: u32) -> Result<f64, JsValue> {
        use crate::bench::{bench_ride, bench_step_s, ride_run};
        use crate::model::ModelKind;
        let params = crate::params::Params::paper();
        let (duration_s, ride) = (10.0, bench_ride(10.0));
        let step = bench_step_s(&params, ModelKind::Twin);
        let mut best = f64::INFINITY;
        for _ in 0..runs.max(1) {
            let t0 = web_time::Instant::now();
            ride_run(&params, ModelKind::Twin, &ride, duration_s, step)
                .map_err(|e| JsValue::from_str(&e.to_string()))?;
            best = best.min(t0.elapsed().as_secs_f64());
        }
        Ok(duration_s / best)
    }

    /// File ▸ Open preset: the browser's file picker, then the preset read from the file.
    pub fn open_preset(&self) -> Result<(), JsValue> {
        self.with_app(|a| a.request_file_by_api(super::files::Purpose::OpenPreset))
    }

    /// Excitation ▸ CSV record: the browser's file picker, then the platform record.
    pub fn open_record(&self) -> Result<(), JsValue> {
        self.with_app(|a| a.request_file_by_api(super::files::Purpose::LoadRecord))
    }

    /// File ▸ Export CSV: the scopes' traces as a download, `traces.csv`.
    pub fn export_csv(&self) -> Result<(), JsValue> {
        self.with_app(|a| a.request_file_by_api(super::files::Purpose::ExportCsv))
    }

    /// File ▸ Export PNG: every plot as a `plots-<plot>.svg` download (the web build draws
    /// no PNG: plotters has no font rasteriser on wasm32).
    pub fn export_png(&self) -> Result<(), JsValue> {
        self.with_app(|a| a.request_file_by_api(super::files::Purpose::ExportPng))
    }

    /// File ▸ Save preset as: the parameters on screen as a `<preset>.toml` download.
    pub fn save_preset(&self) -> Result<(), JsValue> {
        self.with_app(|a| a.request_file_by_api(super::files::Purpose::SavePreset))
    }

    /// Background jobs as JSON ([`SeatTwinApp::jobs_json`]): the sine dwell and Tune, with
    /// progress.
    pub fn jobs(&self) -> Result<String, JsValue> {
        self.with_app(|a| a.jobs_json())
    }

    /// Tunes the live controller as the Tune panel's button does, with rides of
    /// `duration_s` and at most `max_evaluations` evaluations (the panel's: 20 s, 40). It
    /// runs in slices inside the frames; follow it with [`Self::jobs`].
    pub fn start_tune(&self, duration_s: f64, max_evaluations: usize) -> Result<(), JsValue> {
        self.with_app(|a| {
            let opts = crate::tune::TuneOptions {
                duration_s,
                max_evaluations,
                ..super::tune::interactive_options(a.params())
            };
            a.start_tune(opts)
        })
    }

    /// Cancels a running Tune, as its Cancel button does.
    pub fn cancel_tune(&self) -> Result<(), JsValue> {
        self.with_app(|a| a.tune_panel().cancel())
    }

    /// Starts the twin's sine dwell now (in slices inside the frames).
    pub fn start_dwell(&self) -> Result<(), JsValue> {
        self.with_app(|a| a.start_dwell())
    }

    /// Forgets the frame times so far: `state()`'s `ui_ms_*` then cover the frames from now
    /// (at most the last 120).
    pub fn reset_frame_stats(&self) -> Result<(), JsValue> {
        self.with_app(|a| a.reset_frame_stats())
    }

    /// Cancels the running sine dwell.
    pub fn cancel_dwell(&self) -> Result<(), JsValue> {
        self.with_app(|a| a.cancel_dwell())
    }

    /// Whether the app has panicked (then the page shows the message).
    pub fn has_panicked(&self) -> bool {
        self.runner.has_panicked()
    }
}
