//! `seat-twin bode` and `seat-twin transmissibility`: a frequency response into one CSV file.

use super::{
    OptionError, Outcome, Run, announce, check_dwell_amp, check_freqs,
    check_output_is_not_an_input, estimate_wall_s, load_params, preset_file,
};
use crate::analysis::dwell::{self, DwellOptions};
use crate::analysis::response::{Method, Response, ResponseError, response};
use crate::dataset;
use crate::format::general;
use crate::model::ModelKind;
use anyhow::{Context, Result, bail};
use std::path::PathBuf;

/// The options `bode` and `transmissibility` end with: the frequencies, the method, the file.
#[derive(Debug, clap::Args)]
pub struct SweepArgs {
    /// Comma-separated frequencies [Hz].
    #[arg(
        long,
        value_delimiter = ',',
        required = true,
        allow_hyphen_values = true
    )]
    pub freqs: Vec<f64>,
    /// Default: simulated for the twin, exact for linear and passive.
    #[arg(long, value_enum)]
    pub method: Option<Method>,
    /// Output file (CSV).
    #[arg(long)]
    pub out: PathBuf,
}

/// Options of `seat-twin bode`.
#[derive(Debug, clap::Args)]
pub struct BodeArgs {
    /// Which model.
    #[arg(long, value_enum)]
    pub model: ModelKind,
    /// Preset file or shipped preset name.
    #[arg(long, default_value = "paper", value_parser = super::preset_parser())]
    pub preset: String,
    /// Command amplitude of the sine dwell [V] (twin).
    #[arg(long, default_value_t = 0.72, allow_hyphen_values = true)]
    pub amp: f64,
    /// Frequencies, method and output file.
    #[command(flatten)]
    pub sweep: SweepArgs,
}

/// Options of `seat-twin transmissibility`.
#[derive(Debug, clap::Args)]
pub struct TransmissibilityArgs {
    /// Which model.
    #[arg(long, value_enum)]
    pub model: ModelKind,
    /// Preset file or shipped preset name.
    #[arg(long, default_value = "paper", value_parser = super::preset_parser())]
    pub preset: String,
    /// Frequencies, method and output file.
    #[command(flatten)]
    pub sweep: SweepArgs,
}

impl Run for BodeArgs {
    fn validate(&self) -> Result<(), OptionError> {
        check_freqs(&self.sweep.freqs)?;
        check_dwell_amp(self.amp)
    }

    fn run(&self) -> Result<Outcome> {
        let what = Response::Bode {
            amplitude_v: self.amp,
        };
        write_response(&self.preset, self.model, what, &self.sweep)
    }
}

impl Run for TransmissibilityArgs {
    fn validate(&self) -> Result<(), OptionError> {
        check_freqs(&self.sweep.freqs)
    }

    fn run(&self) -> Result<Outcome> {
        write_response(
            &self.preset,
            self.model,
            Response::Transmissibility,
            &self.sweep,
        )
    }
}

/// The response by its entry point, then one CSV file. A non-finite point is refused naming
/// the frequency and the input it came from.
fn write_response(
    preset: &str,
    kind: ModelKind,
    what: Response,
    sweep: &SweepArgs,
) -> Result<Outcome> {
    let SweepArgs { freqs, method, out } = sweep;
    if let Some(file) = preset_file(preset) {
        check_output_is_not_an_input(out, &[("--preset", &file)])?;
    }
    let params = load_params(preset)?;
    // What a non-finite point is traced back to, and the input's own comment line.
    let (input, extra) = match what {
        Response::Bode { amplitude_v } => (
            format!("--amp {} V", general(amplitude_v)),
            vec![("amplitude_v".to_string(), general(amplitude_v))],
        ),
        Response::Transmissibility => (format!("preset {preset}"), Vec::new()),
    };
    let method = method.unwrap_or(Method::default_for(kind));
    let heartbeat = (method == Method::Simulated).then(|| {
        let opt = DwellOptions::default();
        let simulated: f64 = freqs
            .iter()
            .map(|&f| match what {
                Response::Bode { .. } => dwell::bode_dwell_s(f, &opt),
                Response::Transmissibility => dwell::transmissibility_dwell_s(f, &opt),
            })
            .sum();
        let command = match what {
            Response::Bode { .. } => "bode",
            Response::Transmissibility => "transmissibility",
        };
        announce(
            command,
            &format!(
                "{} sine dwells, {} s simulated in all on the {} model",
                freqs.len(),
                general(simulated.round()),
                kind.name()
            ),
            estimate_wall_s(kind, simulated, params.numerics.max_step_s),
        )
    });
    if let Response::Transmissibility = what {
        check_loop_stable(&params, kind, preset)?;
    }
    let values = match response(&params, kind, what, method, freqs) {
        Err(e @ ResponseError::NotFinite { .. }) => {
            bail!("{e}; nothing was written. Check {input}")
        }
        r => r?,
    };
    drop(heartbeat);
    let mut comments = vec![
        ("model".to_string(), kind.name().to_string()),
        ("preset".to_string(), preset.to_string()),
    ];
    comments.extend(extra);
    let rows = freqs.iter().zip(&values).map(|(&f, &v)| what.row(f, v));
    dataset::write_csv_atomic(out, &what.columns(), &comments, rows)
        .with_context(|| format!("writing {}", out.display()))?;
    println!("{} points written to {}", freqs.len(), out.display());
    Ok(Outcome::Done)
}

/// Refuses a closed loop that the stability verdict calls unstable: its transmissibility is
/// not a steady state (|T| of an unstable loop is a number, not a response).
fn check_loop_stable(params: &crate::params::Params, kind: ModelKind, preset: &str) -> Result<()> {
    use crate::analysis::frequency_response as fr;
    use crate::analysis::stability::{LoopPlant, Stability, remedy};
    let (lin, tau) = match kind {
        ModelKind::Twin => (fr::linearise_twin(params), params.plant.valve.tau_s),
        ModelKind::Linear => (fr::linearise_linear(params), params.linear.tau_s),
        ModelKind::Passive => return Ok(()),
    };
    let law = crate::control::ControlLaw::new(params);
    let s = Stability::of(&lin, &law, tau);
    if s.stable() {
        return Ok(());
    }
    let plant = LoopPlant::new(&lin);
    bail!(
        "the closed loop of preset {preset} on the {} is unstable: {} (closed-loop eigenvalues \
         of the loop linearised at rest, with the delay). {} Nothing was written.",
        kind.name(),
        s.mode_text(),
        remedy(params, &[(&plant, tau)])
    )
}
