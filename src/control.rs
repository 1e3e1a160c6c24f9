//! Controllers: one type, [`Controller`], for every structure ([`ControllerKind`]), used by every
//! stepper (the twin's and the exact-hold linear models'), the engine thread, the CLI and
//! presets, and one frequency-domain form, [`ControlLaw`], for transmissibility and margins.
//!
//! # Signals and units
//! The controller runs once per simulation step `h` at the grid times, as a digital controller
//! would. It measures ([`Measurement`]):
//! * `u = y − x` \[m\], the relative displacement (the cylinder's position sensor);
//! * `ẍ` [m/s²], the platform accelerometer, and `∫ẍ dt` over the step just taken [m/s]
//!   (the stepper integrates its own input: Simpson for the twin's RK stages, the trapezoid of
//!   the exact-hold models' linear input);
//! * `ÿ` [m/s²], a body accelerometer (read only by the kinds that need it).
//!
//! It returns the command `V` \[V\] before saturation; the simulation saturates it to ±Vmax,
//! delays it by τ and applies it to the valve. With `u̇ ≈ Kg·V(t − τ)` (the valve and cylinder
//! act as a velocity source, `Kg` ≈ 0.133 m/(s·V)), `Ki·Kg = −1` makes `u̇ = −ẋ` and so keeps the
//! body still; `Kp < 0` pulls the seat back to mid-stroke.
//!
//! # The structures
//! * **paper** (Eq. 16 of the paper): `V = Kp·u + Ki·∫ẍ dt`.
//! * **predictive**: the feed-forward predicts the platform velocity `L = lead_s` ahead by its
//!   first-order Taylor term, band-limited by a first-order low-pass at `fc = lead_cutoff_hz`:
//!   `V = Kp·u + Ki·(∫ẍ dt + L·LP(ẍ))`, i.e. `V_ff = Ki·(1/s + L·ωc/(s + ωc))·ẍ`, which
//!   approximates `Ki·e^(sL)/s` below `fc`. `L` is designed from the delay: τ plus the spool's
//!   lag `2ζ/ωn` (≈ 20.7 ms for the paper's valve).
//! * **skyhook**: the paper's law plus feedback of the absolute body velocity, estimated from
//!   the body accelerometer by a leaky integrator `ẏ̂ = ÿ/(s + ωl)` (ωl = 2π·leak_hz keeps the
//!   accelerometer's offset from winding up) and band-limited by a first-order low-pass at
//!   `ωs = 2π·sky_cutoff_hz`: `V = Kp·u + Ki·∫ẍ dt + Ksky·ωs/(s + ωs)·ẏ̂`. With `Ksky·Kg < 0` the
//!   valve moves the seat against its own velocity, a feedback that does not rely on the plant
//!   gain being known (the feed-forward does). The low-pass matters: above it the loop meets
//!   the valve's lightly damped resonance (G(s): ζ = 0.05 at 80 Hz, |G| = Kg/2ζ there) through
//!   the delay, which caps an unfiltered `|Ksky|` near 0.75 V·s/m.
//! * **smith**: a Smith predictor around the position loop built on the preset's G(s) (its gain
//!   `Kg`, `sp`, `ζ` and delay `τm`): an internal model `M(s) = G0(s)/s` (G(s) without its
//!   delay, integrated to a position) is driven by the command actually sent, and the loop
//!   feeds back `u + ũ(t) − ũ(t − τm)`: `V = Kp·(u + ũ − ũ(t − τm)) + Ki·∫ẍ dt`. When the model
//!   is right, the position loop sees no delay.
//!
//! # Discretisation
//! Filters are first-order sections stepped exactly for an input linear between grid points
//! (first-order hold), so they agree with their transfer functions to round-off at any step.
//! The Smith model is stepped exactly for a command held over the step (zero-order hold) and
//! read `τm` back by the cubic interpolation of a [`DelayLine`].

use crate::params::{ControllerKind, ControllerParams, LinearParams, MAX_DELAY_S, Params};
use crate::simulation::delay::{DelayLine, DelayLineState, RestoreError, Tap};
use nalgebra::{Matrix3, Matrix4, Vector3};
use num_complex::Complex64;
use std::f64::consts::PI;

/// What the controller measures at a grid time (SI).
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct Measurement {
    /// Relative displacement `u = y − x` \[m\].
    pub u: f64,
    /// Body acceleration `ÿ` [m/s²] (read only when [`Controller::needs_body_acceleration`]).
    pub ydd: f64,
    /// Platform acceleration `ẍ` [m/s²].
    pub xdd: f64,
    /// `∫ẍ dt` over the step just taken [m/s] (zero for the first call at t = 0).
    pub dxd: f64,
}

/// A first-order section `ẇ = −a·w + b·x`, stepped exactly for an input linear over the step.
#[derive(Debug, Clone, Copy, PartialEq)]
struct FirstOrder {
    /// State.
    w: f64,
    /// `e^(−a·h)`.
    alpha: f64,
    /// Weights of the input at the step's start and end.
    c0: f64,
    c1: f64,
}

impl FirstOrder {
    fn new(a: f64, b: f64, h: f64) -> Self {
        let ah = a * h;
        let alpha = (-ah).exp();
        // I0 = ∫₀ʰ e^(−a(h−s)) ds and I1 = ∫₀ʰ e^(−a(h−s))·s/h ds; series for small a·h.
        let (i0, i1) = if ah < 1e-4 {
            (
                h * (1.0 - ah / 2.0 + ah * ah / 6.0),
                h * (0.5 - ah / 6.0 + ah * ah / 24.0),
            )
        } else {
            let i0 = (1.0 - alpha) / a;
            (i0, 1.0 / a - i0 / ah)
        };
        Self {
            w: 0.0,
            alpha,
            c0: b * (i0 - i1),
            c1: b * i1,
        }
    }

    #[inline(always)]
    fn step(&mut self, x0: f64, x1: f64) {
        self.w = self.alpha * self.w + self.c0 * x0 + self.c1 * x1;
    }
}

/// The Smith predictor's internal model `M(s) = Kg·sp²/(s·(s² + 2ζ·sp·s + sp²))` and its
/// delayed output.
#[derive(Debug, Clone)]
struct SmithModel {
    /// State `[ũ, w, ẇ]`: model position [m], the second-order section's output [V] and its rate.
    z: Vector3<f64>,
    phi: Matrix3<f64>,
    gamma: Vector3<f64>,
    /// History of ũ on the grid, read `τm` back.
    history: DelayLine,
    tap: Tap,
    /// Grid index of the newest history sample.
    n: u64,
}

impl SmithModel {
    fn new(model: &LinearParams, h: f64) -> Self {
        let (kg, sp, zeta) = (model.kg_m_per_s_v, model.sp_rad_s, model.zeta);
        // Zero-order-hold discretisation from the exponential of the augmented matrix.
        let mut m = Matrix4::<f64>::zeros();
        m[(0, 1)] = kg;
        m[(1, 2)] = 1.0;
        m[(2, 1)] = -sp * sp;
        m[(2, 2)] = -2.0 * zeta * sp;
        m[(2, 3)] = sp * sp;
        let e = (m * h).exp();
        let phi = e.fixed_view::<3, 3>(0, 0).into_owned();
        let gamma = e.fixed_view::<3, 1>(0, 3).into_owned();
        let mut history = DelayLine::new(h, MAX_DELAY_S + h, 0.0);
        history.push(0.0);
        let tap = history.tap(model.tau_s);
        Self {
            z: Vector3::zeros(),
            phi,
            gamma,
            history,
            tap,
            n: 0,
        }
    }

    /// `ũ(t) − ũ(t − τm)` now [m].
    #[inline]
    fn prediction(&self) -> f64 {
        self.z[0] - self.history.value_at_tap(self.n, &self.tap)
    }

    /// Advances the model one step with the command `v` [V] held over it.
    #[inline]
    fn step(&mut self, v: f64) {
        self.z = self.phi * self.z + self.gamma * v;
        self.history.push(self.z[0]);
        self.n += 1;
    }
}

/// A controller with its state, stepped once per grid step.
#[derive(Debug, Clone)]
pub struct Controller {
    params: ControllerParams,
    h: f64,
    /// `∫ẍ dt` since the start [m/s].
    xd: f64,
    /// Low-passed ẍ (predictive) [m/s²].
    lead: FirstOrder,
    /// Leaky integral of ÿ, the body-velocity estimate (skyhook) [m/s].
    sky: FirstOrder,
    /// The estimate low-passed (skyhook) [m/s].
    sky_lp: FirstOrder,
    smith: Option<SmithModel>,
    /// The previous measurement (the first-order hold's start).
    last: Measurement,
    /// The command last sent, after saturation [V] (the Smith model's input).
    sent: f64,
}

impl Controller {
    /// A controller at rest for a control law, stepped every `h` \[s\].
    pub fn new(law: &ControlLaw, h: f64) -> Self {
        let c = law.params;
        let wc = 2.0 * PI * c.lead_cutoff_hz;
        let wl = 2.0 * PI * c.leak_hz;
        Self {
            params: c,
            h,
            xd: 0.0,
            lead: FirstOrder::new(wc, wc, h),
            sky: FirstOrder::new(wl, 1.0, h),
            sky_lp: FirstOrder::new(2.0 * PI * c.sky_cutoff_hz, 2.0 * PI * c.sky_cutoff_hz, h),
            smith: (c.kind == ControllerKind::Smith).then(|| SmithModel::new(&law.model, h)),
            last: Measurement::default(),
            sent: 0.0,
        }
    }

    /// The structure and gains.
    pub fn params(&self) -> &ControllerParams {
        &self.params
    }

    /// New gains (a slider) keeping the signal states (`∫ẍ`, filters, model) when the structure
    /// is the same, so that a retune does not kick the seat; a new structure starts at rest
    /// except for `∫ẍ`, which is the platform's velocity whatever the structure.
    pub fn retune(&mut self, law: &ControlLaw) {
        let mut next = Controller::new(law, self.h);
        next.xd = self.xd;
        next.last = self.last;
        next.sent = self.sent;
        if next.params.kind == self.params.kind {
            next.lead.w = self.lead.w;
            next.sky.w = self.sky.w;
            next.sky_lp.w = self.sky_lp.w;
            if let (Some(new), Some(old)) = (next.smith.as_mut(), self.smith.take())
                && new.tap == old.tap
                && new.phi == old.phi
                && new.gamma == old.gamma
            {
                *new = old;
            }
        }
        *self = next;
    }

    /// Whether the controller reads the body acceleration (the stepper then evaluates it).
    pub fn needs_body_acceleration(&self) -> bool {
        self.params.kind == ControllerKind::Skyhook
    }

    /// Advances the controller's states by one step to the measurement `m` at the step's end
    /// (call it once per step, after the plant; at t = 0 use [`Self::start`]).
    ///
    /// Inlined into the stepping loop: called out of line, the measurement the loop had just
    /// stored went through memory, and reading it back stalled (a third of the exact hold's
    /// step for the linear models).
    #[inline(always)]
    pub fn advance(&mut self, m: &Measurement) {
        self.xd += m.dxd;
        match self.params.kind {
            ControllerKind::Paper => {}
            ControllerKind::Predictive => self.lead.step(self.last.xdd, m.xdd),
            ControllerKind::Skyhook => {
                let q0 = self.sky.w;
                self.sky.step(self.last.ydd, m.ydd);
                self.sky_lp.step(q0, self.sky.w);
            }
            ControllerKind::Smith => {
                if let Some(s) = self.smith.as_mut() {
                    s.step(self.sent);
                }
            }
        }
        self.last = *m;
    }

    /// Sets the first measurement (t = 0) without stepping.
    pub fn start(&mut self, m: &Measurement) {
        self.last = *m;
    }

    /// The command for position `u` \[m\] with the states as they are \[V\], before saturation.
    #[inline(always)]
    pub fn output(&self, u: f64) -> f64 {
        self.output_with(u, 0.0)
    }

    /// The command for position `u` \[m\] with `dxd` [m/s] more of `∫ẍ` than integrated so far
    /// (a stage inside a step, for delays shorter than a step); other states as they are.
    #[inline(always)]
    pub fn output_with(&self, u: f64, dxd: f64) -> f64 {
        let c = &self.params;
        let xd = self.xd + dxd;
        match c.kind {
            ControllerKind::Paper => c.kp_v_per_m * u + c.ki_v_s_per_m * xd,
            ControllerKind::Predictive => {
                c.kp_v_per_m * u + c.ki_v_s_per_m * (xd + c.lead_s * self.lead.w)
            }
            ControllerKind::Skyhook => {
                c.kp_v_per_m * u + c.ki_v_s_per_m * xd + c.sky_v_s_per_m * self.sky_lp.w
            }
            ControllerKind::Smith => {
                let p = self.smith.as_ref().map_or(0.0, SmithModel::prediction);
                c.kp_v_per_m * (u + p) + c.ki_v_s_per_m * xd
            }
        }
    }

    /// Records the command actually sent after saturation \[V\] (the Smith model's input).
    #[inline(always)]
    pub fn sent(&mut self, v: f64) {
        self.sent = v;
    }

    /// `∫ẍ dt` so far [m/s].
    pub fn platform_velocity(&self) -> f64 {
        self.xd
    }

    /// The numbers of its discretisation at its step, for a port of the controller to
    /// another language ([`crate::export::controller`]).
    pub fn coefficients(&self) -> Coefficients {
        let section = |f: &FirstOrder| [f.alpha, f.c0, f.c1];
        Coefficients {
            lead: section(&self.lead),
            sky: section(&self.sky),
            sky_lp: section(&self.sky_lp),
            smith: self.smith.as_ref().map(|m| {
                let phi = std::array::from_fn(|i| std::array::from_fn(|j| m.phi[(i, j)]));
                (phi, [m.gamma[0], m.gamma[1], m.gamma[2]])
            }),
        }
    }
}

/// The paper law's changing states held apart from its [`Controller`] by a stepping loop, so
/// that they can stay in registers ([`Controller::paper_law`]): the same arithmetic as
/// [`Controller::advance`] and [`Controller::output`] for [`ControllerKind::Paper`].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(crate) struct PaperLaw {
    /// `Kp` [V/m].
    kp: f64,
    /// `Ki` [V·s/m].
    ki: f64,
    /// `∫ẍ dt` since the start [m/s].
    xd: f64,
    /// The previous measurement.
    last: Measurement,
    /// The command last sent, after saturation [V].
    sent: f64,
}

impl PaperLaw {
    /// `∫ẍ dt` since the start [m/s].
    #[inline(always)]
    pub(crate) fn platform_velocity(&self) -> f64 {
        self.xd
    }

    /// The law as steps of [`Controller::advance`] and [`Controller::sent`] leave it, from a
    /// loop that kept `∫ẍ` as `xd` [m/s] itself (`xd += m.dxd` a step): the last step's
    /// measurement `last` and command `sent` [V]. The same values as those calls give,
    /// without a store of the measurement at every step.
    #[inline(always)]
    pub(crate) fn stepped(&self, xd: f64, last: Measurement, sent: f64) -> Self {
        Self {
            xd,
            last,
            sent,
            ..*self
        }
    }

    /// [`Controller::output`] of the paper law [V], before saturation, with `∫ẍ` given as
    /// `xd` [m/s] (the loop's own, see [`Self::stepped`]).
    #[inline(always)]
    pub(crate) fn output_at(&self, u: f64, xd: f64) -> f64 {
        // `+ 0.0` as `output_with(u, 0.0)` adds it (it turns −0 into +0).
        let xd = xd + 0.0;
        self.kp * u + self.ki * xd
    }
}

impl Controller {
    /// Its states as a [`PaperLaw`], for the paper structure (`None` for the others).
    pub(crate) fn paper_law(&self) -> Option<PaperLaw> {
        (self.params.kind == ControllerKind::Paper).then_some(PaperLaw {
            kp: self.params.kp_v_per_m,
            ki: self.params.ki_v_s_per_m,
            xd: self.xd,
            last: self.last,
            sent: self.sent,
        })
    }

    /// Takes back the states of a [`PaperLaw`] from [`Self::paper_law`].
    pub(crate) fn set_paper_law(&mut self, law: &PaperLaw) {
        self.xd = law.xd;
        self.last = law.last;
        self.sent = law.sent;
    }
}

/// A controller's signal states ([`Controller::snapshot`]); its gains and discretisation are
/// rebuilt from the parameters.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ControllerState {
    /// `∫ẍ dt` since the start [m/s].
    pub xd: f64,
    /// The predictive kind's low-passed ẍ [m/s²].
    pub lead: f64,
    /// The skyhook kind's body-velocity estimate [m/s].
    pub sky: f64,
    /// The skyhook kind's low-passed estimate [m/s].
    pub sky_lp: f64,
    /// The previous measurement.
    pub last: Measurement,
    /// The command last sent \[V\].
    pub sent: f64,
    /// The Smith model's state `[ũ, w, ẇ]`, its history of ũ and the grid index of the
    /// newest sample.
    pub smith: Option<([f64; 3], DelayLineState, u64)>,
}

impl Controller {
    /// Its signal states.
    pub fn snapshot(&self) -> ControllerState {
        ControllerState {
            xd: self.xd,
            lead: self.lead.w,
            sky: self.sky.w,
            sky_lp: self.sky_lp.w,
            last: self.last,
            sent: self.sent,
            smith: self
                .smith
                .as_ref()
                .map(|m| ([m.z[0], m.z[1], m.z[2]], m.history.snapshot(), m.n)),
        }
    }

    /// Takes the signal states of a controller of the same structure and step; refused,
    /// leaving `self` unchanged, for another structure or history size.
    pub fn restore(&mut self, s: &ControllerState) -> Result<(), RestoreError> {
        let mut smith = self.smith.clone();
        match (smith.as_mut(), &s.smith) {
            (Some(m), Some((z, history, n))) => {
                m.history.restore(history)?;
                m.z = Vector3::from(*z);
                m.n = *n;
            }
            (None, None) => {}
            (mine, theirs) => {
                return Err(RestoreError::Mismatch {
                    what: "number of Smith models",
                    expected: mine.is_some() as usize,
                    found: theirs.is_some() as usize,
                });
            }
        }
        self.smith = smith;
        self.xd = s.xd;
        self.lead.w = s.lead;
        self.sky.w = s.sky;
        self.sky_lp.w = s.sky_lp;
        self.last = s.last;
        self.sent = s.sent;
        Ok(())
    }
}

/// A controller's discretisation ([`Controller::coefficients`]). Each first-order section is
/// `[α, c0, c1]`, stepped as `w ← α·w + c0·x0 + c1·x1` (evaluated in that order) from its input
/// at the step's start `x0` and end `x1`; the Smith model is `z ← Φ·z + Γ·V` with `z = [ũ, w, ẇ]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Coefficients {
    /// The predictive kind's low-pass on ẍ (input ẍ).
    pub lead: [f64; 3],
    /// The skyhook kind's leaky integrator (input ÿ).
    pub sky: [f64; 3],
    /// The skyhook kind's low-pass on the velocity estimate (input: the leaky integrator).
    pub sky_lp: [f64; 3],
    /// The Smith model's `(Φ, Γ)` (row-major Φ), for the `smith` kind.
    pub smith: Option<([[f64; 3]; 3], [f64; 3])>,
}

/// A controller's transfer functions at one frequency: `V = c_u·u + c_y·ÿ + c_x·ẍ`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ControllerResponse {
    /// From the relative displacement [V/m].
    pub c_u: Complex64,
    /// From the body acceleration [V·s²/m].
    pub c_y: Complex64,
    /// From the platform acceleration [V·s²/m].
    pub c_x: Complex64,
}

/// The controller in the frequency domain (its LTI form; every kind has one).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ControlLaw {
    params: ControllerParams,
    /// G(s) of the Smith predictor's model.
    model: LinearParams,
}

impl ControlLaw {
    /// The parameters' controller (and, for `smith`, its model G(s) from `params.linear`).
    pub fn new(params: &Params) -> Self {
        Self {
            params: params.controller,
            model: params.linear,
        }
    }

    /// The structure and gains.
    pub fn params(&self) -> &ControllerParams {
        &self.params
    }

    /// G(s) of the Smith predictor's model (read only by `smith`).
    pub fn model(&self) -> &LinearParams {
        &self.model
    }

    /// The law with other gains (same structure or not), the same model.
    pub fn with_params(&self, params: ControllerParams) -> Self {
        Self { params, ..*self }
    }

    /// Whether the position feedback is positive at low frequency (`c_u(0) > 0`): around the
    /// integrating plant that is unstable at any gain.
    pub fn positive_position_feedback(&self) -> bool {
        self.response(1e-9).c_u.re > 0.0
    }

    /// Transfer functions at angular frequency `omega` [rad/s].
    pub fn response(&self, omega: f64) -> ControllerResponse {
        let c = &self.params;
        let s = Complex64::new(0.0, omega);
        let zero = Complex64::new(0.0, 0.0);
        let kp = Complex64::new(c.kp_v_per_m, 0.0);
        let ff = c.ki_v_s_per_m / s;
        match c.kind {
            ControllerKind::Paper => ControllerResponse {
                c_u: kp,
                c_y: zero,
                c_x: ff,
            },
            ControllerKind::Predictive => {
                let wc = 2.0 * PI * c.lead_cutoff_hz;
                ControllerResponse {
                    c_u: kp,
                    c_y: zero,
                    c_x: ff + c.ki_v_s_per_m * c.lead_s * wc / (s + wc),
                }
            }
            ControllerKind::Skyhook => {
                let wl = 2.0 * PI * c.leak_hz;
                let ws = 2.0 * PI * c.sky_cutoff_hz;
                ControllerResponse {
                    c_u: kp,
                    c_y: c.sky_v_s_per_m / (s + wl) * ws / (s + ws),
                    c_x: ff,
                }
            }
            ControllerKind::Smith => {
                // V = Kp·(u + M·(1 − e^(−sτm))·V) + Ki/s·ẍ  ⇒  V = (Kp·u + Ki/s·ẍ)/Q.
                let m = &self.model;
                let sp2 = m.sp_rad_s * m.sp_rad_s;
                let g0 = m.kg_m_per_s_v * sp2 / (s * s + 2.0 * m.zeta * m.sp_rad_s * s + sp2);
                let q = 1.0 - kp * g0 / s * (1.0 - (-s * m.tau_s).exp());
                ControllerResponse {
                    c_u: kp / q,
                    c_y: zero,
                    c_x: ff / q,
                }
            }
        }
    }

    /// The loop gain at the valve command, `L = −e^(−jωτ)·(c_u·u/V + c_y·ÿ/V)`, for the plant's
    /// open-loop `u/V_valve` and `ÿ/V_valve` (delay excluded) and the command delay `tau_s`.
    /// The loop is `V = −L·V + …`; margins are read from `L` as for negative feedback.
    pub fn loop_gain(&self, omega: f64, u_v: Complex64, y_v: Complex64, tau_s: f64) -> Complex64 {
        let r = self.response(omega);
        let e = Complex64::new(0.0, -omega * tau_s).exp();
        -e * (r.c_u * u_v + r.c_y * y_v)
    }

    /// Closed-loop transmissibility `T = ÿ/ẍ` from the plant's open-loop responses at one
    /// frequency (delay excluded: `u = u_v·V_valve + u_x·ẍ`, `ÿ = y_v·V_valve + y_x·ẍ`,
    /// `V_valve = e^(−jωτ)·V`).
    pub fn transmissibility(
        &self,
        omega: f64,
        tau_s: f64,
        u_v: Complex64,
        u_x: Complex64,
        y_v: Complex64,
        y_x: Complex64,
    ) -> Complex64 {
        let r = self.response(omega);
        let e = Complex64::new(0.0, -omega * tau_s).exp();
        let v_per_x = (r.c_u * u_x + r.c_y * y_x + r.c_x) / (1.0 - e * (r.c_u * u_v + r.c_y * y_v));
        y_v * e * v_per_x + y_x
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn first_order_section_matches_its_exact_step_response() {
        // ẇ = −a·w + a·x with x a unit step at t = 0⁺ held: w(t) = 1 − e^(−a·t). With a linear
        // input x = t the exact solution is w = t − (1 − e^(−a·t))/a.
        let (a, h) = (2.0 * PI * 12.0, 5e-4);
        let mut f = FirstOrder::new(a, a, h);
        for n in 0..400 {
            let (t0, t1) = (n as f64 * h, (n + 1) as f64 * h);
            f.step(t0, t1);
        }
        let t = 400.0 * h;
        let exact = t - (1.0 - (-a * t).exp()) / a;
        assert!((f.w - exact).abs() < 1e-12, "{} vs {exact}", f.w);
        // a → 0: the trapezoid of an integrator.
        let mut g = FirstOrder::new(0.0, 1.0, h);
        g.step(1.0, 3.0);
        assert!((g.w - 2.0 * h).abs() < 1e-18);
    }

    #[test]
    fn paper_law_is_eq16() {
        let p = Params::paper();
        let law = ControlLaw::new(&p);
        let w = 2.0 * PI * 3.0;
        let r = law.response(w);
        assert_eq!(r.c_u, Complex64::new(-5.0, 0.0));
        assert!((r.c_x - Complex64::new(0.0, 7.5 / w)).norm() < 1e-12);
        let mut c = Controller::new(&law, 1e-3);
        c.advance(&Measurement {
            u: 0.01,
            dxd: 0.2,
            ..Default::default()
        });
        assert!((c.output(0.01) - (-5.0 * 0.01 - 7.5 * 0.2)).abs() < 1e-15);
    }

    #[test]
    fn smith_with_no_model_delay_is_plain_position_feedback() {
        let mut p = Params::paper();
        p.controller.kind = ControllerKind::Smith;
        p.linear.tau_s = 0.0;
        let r = ControlLaw::new(&p).response(2.0 * PI * 5.0);
        assert!((r.c_u - Complex64::new(-5.0, 0.0)).norm() < 1e-12);
    }

    #[test]
    fn smith_model_steps_like_its_transfer_function() {
        // A held unit command: the model's position ramps at Kg after the second-order
        // section settles, ũ(t) → Kg·(t − 2ζ/sp).
        let p = Params::paper();
        let h = 1e-3;
        let mut m = SmithModel::new(&p.linear, h);
        for _ in 0..2000 {
            m.step(1.0);
        }
        let l = &p.linear;
        let t = 2.0;
        let expected = l.kg_m_per_s_v * (t - 2.0 * l.zeta / l.sp_rad_s);
        assert!((m.z[0] - expected).abs() < 1e-9 * expected.abs().max(1.0));
        // And the prediction is the model's motion over the last τm: ≈ Kg·τm.
        assert!((m.prediction() - l.kg_m_per_s_v * l.tau_s).abs() < 1e-6);
    }
}
