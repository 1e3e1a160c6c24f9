//! The three plant models, all stepped by the same [`crate::simulation::Simulation`] loop:
//!
//! * [`twin::Twin`] — the 10-state nonlinear multi-physics twin (Eqs. 1–14, Eq. 5 corrected),
//! * [`linear::LinearModel`] — the simplified model G(s) of Eq. (15) in state space,
//! * [`passive::PassiveModel`] — the passive reference (same m and k, viscous damper).
//!
//! A model is a pure function `derivatives(t, state, inputs)`; the delay of the command and the
//! controller live in the simulation, the integrator in [`crate::simulation::integrate`].

pub mod linear;
pub mod passive;
pub mod twin;

use serde::{Deserialize, Serialize};

/// Inputs a model sees at one instant.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Inputs {
    /// Command arriving at the valve, i.e. already delayed by τ and saturated \[V\].
    pub v_valve: f64,
    /// Platform (seat-base) acceleration `ẍ` [m/s²].
    pub xdd: f64,
}

/// Quantities a model reports at one instant (NaN where a model lacks the quantity).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Outputs {
    /// Relative displacement `u = y − x` \[m\], positive up, 0 at mid-stroke.
    pub u: f64,
    /// Relative velocity `u̇` [m/s].
    pub du: f64,
    /// Body acceleration `ÿ` [m/s²].
    pub ydd: f64,
    /// Spool position `xv` \[m\].
    pub xv: f64,
    /// Upper chamber pressure `p1` \[Pa\].
    pub p1: f64,
    /// Lower chamber pressure `p2` \[Pa\].
    pub p2: f64,
    /// Flow out of the upper chamber towards the valve `Q1` [m³/s].
    pub q1: f64,
    /// Flow from the valve into the lower chamber `Q2` [m³/s].
    pub q2: f64,
    /// Force of the end stops on the body \[N\] (0 when not in contact).
    pub end_stop_force: f64,
}

impl Outputs {
    /// Outputs of a model without hydraulics (linear, passive): the hydraulic quantities NaN.
    pub fn mechanical(u: f64, du: f64, ydd: f64) -> Self {
        Outputs {
            u,
            du,
            ydd,
            xv: f64::NAN,
            p1: f64::NAN,
            p2: f64::NAN,
            q1: f64::NAN,
            q2: f64::NAN,
            end_stop_force: 0.0,
        }
    }
}

/// Which model a trace came from; decides which CSV columns exist.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[cfg_attr(not(target_arch = "wasm32"), derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum ModelKind {
    /// The nonlinear digital twin.
    Twin,
    /// The paper's linear model G(s) with the controller.
    Linear,
    /// The passive seat (spring and damper).
    Passive,
}

impl ModelKind {
    /// Lower-case name as used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            ModelKind::Twin => "twin",
            ModelKind::Linear => "linear",
            ModelKind::Passive => "passive",
        }
    }

    /// Whether the model has a valve and hydraulics (spool, pressures, flows).
    pub const fn has_hydraulics(self) -> bool {
        matches!(self, ModelKind::Twin)
    }

    /// Whether the model takes a valve command (the passive one does not).
    pub const fn has_command(self) -> bool {
        !matches!(self, ModelKind::Passive)
    }
}

impl std::str::FromStr for ModelKind {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "twin" => Ok(ModelKind::Twin),
            "linear" => Ok(ModelKind::Linear),
            "passive" => Ok(ModelKind::Passive),
            other => Err(format!(
                "unknown model `{other}` (expected twin, linear or passive)"
            )),
        }
    }
}

/// A plant with `N` states, written as a pure right-hand side.
pub trait Model<const N: usize>: Clone + Send + Sync {
    /// Which model this is.
    const KIND: ModelKind;
    /// Names of the states, in array order (for error messages and linearisation).
    const STATE_NAMES: [&'static str; N];

    /// State derivatives `dy/dt` at time `t` [SI per second].
    fn derivatives(&self, t: f64, y: &[f64; N], inputs: &Inputs) -> [f64; N];

    /// The rest state (body at mid-stroke, everything still).
    fn rest_state(&self) -> [f64; N];

    /// Outputs at a state.
    fn outputs(&self, y: &[f64; N], inputs: &Inputs) -> Outputs;

    /// Relative displacement `u` \[m\] at a state (what the controller measures).
    fn relative_position(&self, y: &[f64; N]) -> f64;

    /// Projection after each step (e.g. the spool's travel limit). Default: none.
    fn project(&self, _y: &mut [f64; N]) {}

    /// Half the stroke \[m\]: |u| beyond it is end-stop contact (or, for models without end
    /// stops, a stroke overrun that is flagged).
    fn half_stroke(&self) -> f64;

    /// Largest magnitude a state may reach before the run is declared diverged.
    fn state_bound(&self, index: usize) -> f64;

    /// Characteristic size of each state (finite-difference steps, matrix balancing).
    fn state_scales(&self) -> [f64; N] {
        [1.0; N]
    }
}

/// Command delay and saturation a model sees: `(τ [s], Vmax [V])`. The simulation reads the
/// controller's command back `τ` late and clamps it to `±Vmax` before the model gets it.
pub trait CommandPath {
    /// Pure delay of the command \[s\].
    fn command_delay(&self) -> f64;
    /// Saturation of the command \[V\] (0 for a model without a valve).
    fn command_limit(&self) -> f64;
}

impl CommandPath for twin::Twin {
    fn command_delay(&self) -> f64 {
        self.params().plant.valve.tau_s
    }
    fn command_limit(&self) -> f64 {
        self.params().plant.valve.v_max_v
    }
}

/// Numerical Jacobian `∂f/∂y` (central differences, step 1e-6 of each state's scale) of a
/// model at state `y0` with zero inputs; `a[i][j] = ∂f_i/∂y_j`.
pub fn jacobian<M: Model<N>, const N: usize>(
    model: &M,
    y0: &[f64; N],
    scales: &[f64; N],
) -> [[f64; N]; N] {
    let inputs = Inputs::default();
    let mut a = [[0.0; N]; N];
    for j in 0..N {
        let h = 1e-6 * scales[j];
        let mut yp = *y0;
        let mut ym = *y0;
        yp[j] += h;
        ym[j] -= h;
        let fp = model.derivatives(0.0, &yp, &inputs);
        let fm = model.derivatives(0.0, &ym, &inputs);
        for i in 0..N {
            a[i][j] = (fp[i] - fm[i]) / (2.0 * h);
        }
    }
    a
}
