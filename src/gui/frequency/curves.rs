//! The analytic frequency responses that follow the sliders: |T| and phase of the linear
//! model, the linearised twin and the passive seat, the Bode of `u̇/V_in`, the |T| = 1
//! crossings and the loop margins. The twin's linearisation is cached on its plant
//! parameters, so dragging a gain or τ only re-evaluates the loop.

use super::*;

/// The plant part of the parameters: the linearisation's cache key. The gains and the delay
/// act outside the linearised plant, so dragging Kp, Ki or τ reuses it.
fn plant_key(p: &Params) -> Params {
    let mut k = *p;
    k.controller = ControllerParams::paper(0.0, 0.0);
    k.plant.valve.tau_s = 0.0;
    k.linear.tau_s = 0.0;
    k
}

/// The linearised twin's open-loop responses on the plot grid, and what the stability verdict
/// needs of it (its loop form and the margin grid refined around its resonances).
pub struct PlantCache {
    key: Params,
    /// On the plot frequencies (delay excluded).
    pub points: Vec<OpenLoop>,
    lin0: LinearisedModel,
    grid: MarginGrid,
}

impl PlantCache {
    /// Linearises the twin (delay-free) and evaluates it on both grids.
    pub fn new(params: &Params, freqs: &[f64]) -> Self {
        let key = plant_key(params);
        let lin0 = fr::linearise_twin(&key);
        let points = freqs.iter().map(|&f| lin0.open_loop(f)).collect();
        let grid = MarginGrid::new(&lin0);
        Self {
            key,
            points,
            lin0,
            grid,
        }
    }

    /// The twin's stability verdict for a controller and delay (as [`twin_stability`](crate::analysis::stability::twin_stability)).
    pub fn stability(&self, law: &ControlLaw, tau_s: f64) -> Stability {
        Stability::on_grid(&self.lin0, &self.grid, law, tau_s)
    }

    /// The twin's loop in state-space form (for the remedy's search).
    pub fn loop_plant(&self) -> &LoopPlant {
        &self.grid.loop_plant
    }
}

/// One curve in plot coordinates `(log10 f, value)`.
pub type Curve = Vec<PlotPoint>;

/// The analytic frequency responses for one parameter set.
#[derive(Debug, Clone, Default)]
pub struct Curves {
    /// Parameters they were computed for.
    pub params: Option<Params>,
    /// |T| \[dB\] of linear, twin (linearised), passive.
    pub t_mag: [Curve; 3],
    /// Phase of T [deg] of linear, twin, passive (unwrapped).
    pub t_phase: [Curve; 3],
    /// |u̇/V_in| [dB re 1 (mm/s)/V] of twin (linearised) and G(s).
    pub bode_mag: [Curve; 2],
    /// Phase of `u̇/V_in` [deg] of twin and G(s).
    pub bode_phase: [Curve; 2],
    /// |T| = 1 crossings of linear and twin.
    pub crossings: [Vec<Crossing>; 2],
    /// Stability verdicts (closed-loop eigenvalues and every crossing) of linear and twin.
    pub stability: [Option<Stability>; 2],
    /// What to change when a loop is unstable (empty when both are stable).
    pub remedy: String,
    /// Time the last recomputation took \[ms\].
    pub compute_ms: f64,
}

impl Curves {
    /// Whether either active loop is unstable.
    pub fn unstable(&self) -> bool {
        self.stability.iter().flatten().any(|s| !s.stable())
    }
}

/// Cached analytic curves plus the linearised twin.
#[derive(Default)]
pub struct Analytic {
    curves: Curves,
    plant: Option<PlantCache>,
    freqs: Vec<f64>,
}

impl Analytic {
    /// The current curves.
    pub fn curves(&self) -> &Curves {
        &self.curves
    }

    /// Recomputes if `params` differ from the last call; returns true if it did.
    pub fn update(&mut self, params: &Params) -> bool {
        if self.curves.params.as_ref() == Some(params) {
            return false;
        }
        let t0 = Instant::now();
        if self.freqs.is_empty() {
            self.freqs = fr::log_space(F_RANGE_HZ.0, F_RANGE_HZ.1, N_POINTS);
        }
        let key = plant_key(params);
        if self.plant.as_ref().is_none_or(|c| c.key != key) {
            self.plant = Some(PlantCache::new(params, &self.freqs));
        }
        let Some(plant) = self.plant.as_ref() else {
            return false;
        };
        let tau = params.plant.valve.tau_s;
        let f = &self.freqs;
        let lx: Vec<f64> = f.iter().map(|x| x.log10()).collect();
        let t_lin: Vec<Complex64> = f
            .iter()
            .map(|&x| fr::linear_transmissibility(params, x))
            .collect();
        let t_twin: Vec<Complex64> = plant
            .points
            .iter()
            .map(|p| p.transmissibility(&ControlLaw::new(params), tau))
            .collect();
        let t_pas: Vec<Complex64> = f
            .iter()
            .map(|&x| fr::passive_transmissibility(params, x))
            .collect();
        let b_twin: Vec<Complex64> = plant.points.iter().map(|p| p.bode(tau)).collect();
        let b_g: Vec<Complex64> = f.iter().map(|&x| fr::linear_bode(params, x)).collect();
        let mag = |v: &[Complex64], scale: f64| -> Curve {
            lx.iter()
                .zip(v)
                .map(|(&x, c)| PlotPoint::new(x, db(c.norm() * scale)))
                .filter(|p| p.y.is_finite())
                .collect()
        };
        let phase = |v: &[Complex64]| -> Curve {
            let ph = fr::unwrap_phase(&v.iter().map(|c| c.arg()).collect::<Vec<_>>());
            lx.iter()
                .zip(ph)
                .map(|(&x, p)| PlotPoint::new(x, deg(p)))
                .filter(|p| p.y.is_finite())
                .collect()
        };
        let mags = |v: &[Complex64]| v.iter().map(|c| c.norm()).collect::<Vec<_>>();
        let law = ControlLaw::new(params);
        let g = fr::linearise_linear(params);
        let g_grid = MarginGrid::new(&g);
        let stab_lin = Stability::on_grid(&g, &g_grid, &law, params.linear.tau_s);
        let stab_twin = plant.stability(&law, tau);
        let remedy = if stab_lin.stable() && stab_twin.stable() {
            String::new()
        } else {
            crate::analysis::stability::remedy(
                params,
                &[
                    (&g_grid.loop_plant, params.linear.tau_s),
                    (plant.loop_plant(), tau),
                ],
            )
        };
        self.curves = Curves {
            params: Some(*params),
            t_mag: [mag(&t_lin, 1.0), mag(&t_twin, 1.0), mag(&t_pas, 1.0)],
            t_phase: [phase(&t_lin), phase(&t_twin), phase(&t_pas)],
            bode_mag: [mag(&b_twin, 1e3), mag(&b_g, 1e3)],
            bode_phase: [phase(&b_twin), phase(&b_g)],
            crossings: [
                fr::unity_crossings(f, &mags(&t_lin)),
                fr::unity_crossings(f, &mags(&t_twin)),
            ],
            stability: [Some(stab_lin), Some(stab_twin)],
            remedy,
            compute_ms: 0.0,
        };
        self.curves.compute_ms = t0.elapsed().as_secs_f64() * 1e3;
        true
    }
}
