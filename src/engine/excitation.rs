//! What drives the engine's runs: the excitation (a platform motion or a valve test) and how fast simulated time runs against the wall clock.

use crate::control::ControlLaw;
use crate::params::Params;
use crate::scenario::{ClassMotion, InputClass};
use crate::scenario::{CommandSignal, Cycloid, PlatformMotion, RandomRide, SampledMotion};
use crate::simulation::Drive;
use serde::{Deserialize, Serialize};

/// How fast simulated time runs against wall-clock time.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum Speed {
    /// 0.1× real time.
    Slow,
    /// Real time.
    RealTime,
    /// 10× real time.
    Fast,
    /// As fast as the machine allows.
    Max,
}

impl Speed {
    /// Factor of simulated over wall-clock time (∞ for `Max`).
    pub fn factor(self) -> f64 {
        match self {
            Speed::Slow => 0.1,
            Speed::RealTime => 1.0,
            Speed::Fast => 10.0,
            Speed::Max => f64::INFINITY,
        }
    }

    /// Label for the UI.
    pub fn label(self) -> &'static str {
        match self {
            Speed::Slow => "0.1×",
            Speed::RealTime => "1×",
            Speed::Fast => "10×",
            Speed::Max => "max",
        }
    }
}

/// What the platform does in the live simulation.
#[derive(Debug, Clone, PartialEq)]
pub enum Excitation {
    /// Band-limited random ride; a new seed starts when the record ends.
    Random(RandomRide),
    /// A cycloidal bump (repeated every `period_s`, alternating up and down).
    Cycloid {
        /// The bump.
        bump: Cycloid,
        /// Repeat period \[s\].
        period_s: f64,
    },
    /// Platform sine: acceleration amplitude [m/s²] and frequency \[Hz\].
    Sine {
        /// Acceleration amplitude [m/s²].
        accel_m_s2: f64,
        /// Frequency \[Hz\].
        freq_hz: f64,
    },
    /// A loaded platform record (replayed from the start when it ends).
    Record(SampledMotion),
    /// A seat-test input class (ISO 7096 / ISO 5007 / EN 13490) generated as the CLI's
    /// `simulate --scenario class` does; a new seed starts when the record ends.
    Class {
        /// The class.
        class: &'static InputClass,
        /// Record length \[s\], 20 ..= 3600.
        duration_s: f64,
        /// Seed of the phases.
        seed: u64,
    },
    /// Platform still; open-loop valve sine `A·cos(2πft)` on the active models.
    ValveSine {
        /// Amplitude \[V\].
        amplitude_v: f64,
        /// Frequency \[Hz\].
        freq_hz: f64,
    },
}

impl Default for Excitation {
    fn default() -> Self {
        Excitation::Random(RandomRide {
            duration_s: 300.0,
            ..Default::default()
        })
    }
}

impl Excitation {
    /// The platform motion and the drive of the active models, and how long it lasts [s];
    /// an error for a seat-test class whose record cannot be generated (bad duration).
    pub(super) fn build(&self, params: &Params) -> Result<(PlatformMotion, Drive, f64), String> {
        let closed = Drive::ClosedLoop(ControlLaw::new(params));
        Ok(match self {
            Excitation::Random(r) => (PlatformMotion::Sampled(r.generate()), closed, r.duration_s),
            Excitation::Class {
                class,
                duration_s,
                seed,
            } => {
                let motion = ClassMotion {
                    seed: *seed,
                    ..ClassMotion::new(class, *duration_s)
                }
                .generate()
                .map_err(|e| format!("seat-test class {}: {e}", class.name))?;
                let d = motion.duration_s();
                (PlatformMotion::Sampled(motion), closed, d)
            }
            Excitation::Cycloid { bump, period_s } => {
                // Build one up-and-down cycle as a sampled record so it can repeat.
                let period = period_s.max(2.0 * (bump.start_s + bump.rise_time_s));
                let dt = 1e-3;
                let n = (2.0 * period / dt) as usize + 1;
                let down = Cycloid {
                    height_m: -bump.height_m,
                    start_s: bump.start_s + period,
                    ..*bump
                };
                let (mut x, mut xd, mut xdd) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
                for i in 0..n {
                    let t = i as f64 * dt;
                    let (a, b) = (bump.at(t), down.at(t));
                    x[i] = a.x + b.x;
                    xd[i] = a.xd + b.xd;
                    xdd[i] = a.xdd + b.xdd;
                }
                (
                    PlatformMotion::Sampled(SampledMotion::new(dt, x, xd, xdd)),
                    closed,
                    2.0 * period,
                )
            }
            Excitation::Sine {
                accel_m_s2,
                freq_hz,
            } => {
                let w = 2.0 * std::f64::consts::PI * freq_hz;
                (
                    PlatformMotion::Sine(crate::scenario::PlatformSine {
                        amplitude_m: accel_m_s2 / (w * w),
                        freq_hz: *freq_hz,
                        fade_in_s: 1.0,
                    }),
                    closed,
                    f64::INFINITY,
                )
            }
            Excitation::Record(m) => (PlatformMotion::Sampled(m.clone()), closed, m.duration_s()),
            Excitation::ValveSine {
                amplitude_v,
                freq_hz,
            } => (
                PlatformMotion::Still,
                Drive::OpenLoop(CommandSignal::Sine {
                    amplitude_v: *amplitude_v,
                    freq_hz: *freq_hz,
                }),
                f64::INFINITY,
            ),
        })
    }

    /// The same excitation with the next seed (random ride and seat-test class), or as it is.
    pub(super) fn reseeded(&self, bump: u64) -> Excitation {
        match self {
            Excitation::Random(r) => Excitation::Random(RandomRide {
                seed: r.seed.wrapping_add(bump),
                ..*r
            }),
            Excitation::Class {
                class,
                duration_s,
                seed,
            } => Excitation::Class {
                class,
                duration_s: *duration_s,
                seed: seed.wrapping_add(bump),
            },
            other => other.clone(),
        }
    }
}
