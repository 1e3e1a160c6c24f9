//! The reference numbers of the browser test: a_w and max |u| of `seat-twin simulate` CSV
//! files, evaluated exactly as the app's live metrics table (and so the web page's
//! `seatTwin.state()`) evaluates them: the samples at the engine's stream rate
//! ([`STREAM_RATE_HZ`], so run the CLI with `--rate 500`), ISO 2631-1 Wk weighting, the
//! first [`METRICS_SETTLE_S`] left out, max |u| over the same samples.
//!
//! `cargo run --example web_aw -- twin.csv linear.csv passive.csv` prints one JSON object
//! per file: `{"file", "aw", "max_abs_u_m", "t_end_s", "samples"}`.

use anyhow::{Context, Result, bail};
use seat_twin::analysis::metrics::RunningMetrics;
use seat_twin::engine::STREAM_RATE_HZ;
use seat_twin::gui::traces::METRICS_SETTLE_S;

fn main() -> Result<()> {
    for file in std::env::args().skip(1) {
        let text = std::fs::read_to_string(&file).with_context(|| format!("reading {file}"))?;
        let mut lines = text.lines().filter(|l| !l.starts_with('#'));
        let header: Vec<&str> = lines.next().context("no header")?.split(',').collect();
        let col = |name: &str| {
            header
                .iter()
                .position(|h| *h == name)
                .with_context(|| format!("{file}: no `{name}` column"))
        };
        let (it, iydd, iu) = (col("t")?, col("ydd")?, col("u")?);
        let mut metrics = RunningMetrics::with_settle(STREAM_RATE_HZ, METRICS_SETTLE_S)?;
        let (mut max_u, mut t_prev, mut n) = (0.0_f64, None::<f64>, 0usize);
        for (i, line) in lines.enumerate() {
            let v: Vec<f64> = line
                .split(',')
                .map(str::parse)
                .collect::<Result<_, _>>()
                .with_context(|| format!("{file}: data row {}", i + 1))?;
            if let Some(tp) = t_prev
                && ((v[it] - tp) * STREAM_RATE_HZ - 1.0).abs() > 1e-6
            {
                bail!("{file}: not sampled at {STREAM_RATE_HZ} Hz (run the CLI with --rate 500)");
            }
            t_prev = Some(v[it]);
            metrics.push(v[iydd]);
            // As the app's table: |u| counts from the first sample the metrics count.
            if metrics.metrics().duration_s > 0.0 {
                max_u = max_u.max(v[iu].abs());
            }
            n += 1;
        }
        println!(
            "{}",
            serde_json::json!({
                "file": file,
                "aw": metrics.metrics().aw,
                "max_abs_u_m": max_u,
                "t_end_s": t_prev,
                "samples": n,
            })
        );
    }
    Ok(())
}
