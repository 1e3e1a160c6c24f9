//! Standard laboratory seat tests: the seat test itself on any model ([`run`]) with its
//! report ([`report`]). The input spectral classes of ISO 7096 (EM1–EM9), ISO 5007 (AG1–AG3)
//! and EN 13490 (IT1–IT4) ([`crate::scenario::classes`]) and the platform motions that meet a
//! class's target PSD within its tolerance ([`crate::scenario::class_motion`]) live with the
//! other platform motions in [`crate::scenario`].
//!
//! ```
//! use seat_twin::scenario::{classes, class_motion::ClassMotion};
//! let em6 = classes::find("em6").expect("a class of ISO 7096");
//! let motion = ClassMotion::new(em6, 30.0).generate().expect("a valid duration");
//! // Starts and ends at rest, at the same place: no drift.
//! let (a, b) = (motion.at(0.0), motion.at(motion.duration_s()));
//! assert!(a.x.abs() < 1e-12 && b.x.abs() < 1e-9 && b.xd.abs() < 1e-9);
//! ```
//!
//! A class motion is an ordinary [`crate::scenario::SampledMotion`]; wrap it in
//! [`crate::scenario::PlatformMotion::Sampled`] to run it anywhere a platform motion runs.

pub mod report;
pub mod run;

pub use crate::scenario::classes::{CLASSES, InputClass, find};
pub use run::{SeatTestOptions, SeatTestResult, run_seat_test};
