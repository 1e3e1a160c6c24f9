//! Standard laboratory seat tests: the input spectral classes of ISO 7096 (EM1–EM9),
//! ISO 5007 (AG1–AG3) and EN 13490 (IT1–IT4) as data ([`classes`]), platform motions that meet
//! a class's target PSD within its tolerance ([`signal`]), and the seat test itself on any
//! model ([`run`]) with its report ([`report`]).
//!
//! ```
//! use seat_twin::seat_test::{classes, signal::ClassMotion};
//! let em6 = classes::find("em6").expect("a class of ISO 7096");
//! let motion = ClassMotion::new(em6, 30.0).generate().expect("a valid duration");
//! // Starts and ends at rest, at the same place: no drift.
//! let (a, b) = (motion.at(0.0), motion.at(motion.duration_s()));
//! assert!(a.x.abs() < 1e-12 && b.x.abs() < 1e-9 && b.xd.abs() < 1e-9);
//! ```
//!
//! A class motion is an ordinary [`crate::scenario::SampledMotion`]; wrap it in
//! [`crate::scenario::PlatformMotion::Sampled`] to run it anywhere a platform motion runs.

pub mod classes;
pub mod report;
pub mod run;
pub mod signal;

pub use classes::{CLASSES, InputClass, find};
pub use run::{SeatTestOptions, SeatTestResult, run_seat_test};
pub use signal::ClassMotion;
