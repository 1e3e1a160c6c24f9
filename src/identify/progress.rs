//! Progress, cancellation and stop reasons of a calibration.
//!
//! A calibration runs in [`Stage`]s. A [`CalibrationObserver`] (any `Fn(&Progress) + Sync`)
//! hears of every stage entered, every unit of work done in it and every replay of the
//! campaign; one cancel flag (an [`AtomicBool`], usually shared as an `Arc`) stops the run at
//! the next replay with [`super::IdentifyError::Cancelled`]. The [`Monitor`] holds both for
//! the stages and the fits. Why a Levenberg–Marquardt fit stopped is a [`StopReason`].

use super::memo::ResidualMemo;
use super::{EffectId, IdentifyError};
use std::fmt;
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

/// A stage of the calibration, in the order they run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stage {
    /// Replaying every record with the nominal parameters.
    Nominal,
    /// The paper's section-4 calibration from the open-loop sine tests.
    PaperBaseline,
    /// Levenberg–Marquardt on the declared parameters (Cd, τ and, if identifiable, the mass).
    DeclaredFit,
    /// Fitting every remaining candidate effect on top of the current model and ranking them.
    Candidates {
        /// Round (1 = first).
        round: usize,
    },
    /// Re-fitting all parameters with the best candidate, then validating it on the held-out
    /// records.
    Refit {
        /// Round (1 = first).
        round: usize,
        /// The effect tried.
        effect: EffectId,
    },
    /// Beyond the library: fitting and ranking the corrections of
    /// [`super::proposed::CorrectionId`], re-fitting and validating the best (only when the
    /// library leaves a raw residual above the floor).
    Proposed {
        /// Round (1 = first).
        round: usize,
    },
    /// An effect the library added, switched off beside the proposed terms and the rest
    /// fitted again ([`super::proposed::LeftOut`]).
    LeftOut {
        /// The effect.
        effect: EffectId,
    },
    /// Every drift candidate fitted on each record alone ([`super::drift`]).
    Drifts,
    /// The mass or the oil's stiffness searched again for the oil column's ringing
    /// ([`super::ringing`]; only when the calibrated twin rings out of time with the records).
    Ringing,
    /// The search's fits again on every sample, for records the search read at a lower rate
    /// ([`super::search_rate`]).
    RecordRate,
    /// Final replays at the preset's step, errors, diagnostics and the verdict.
    Report,
}

impl Stage {
    /// Whether the Jacobians of the stage's fits count as its work (`done`).
    fn counts_jacobians(self) -> bool {
        matches!(
            self,
            Stage::DeclaredFit | Stage::Refit { .. } | Stage::LeftOut { .. } | Stage::RecordRate
        )
    }
}

impl fmt::Display for Stage {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Stage::Nominal => f.write_str("nominal replay"),
            Stage::PaperBaseline => f.write_str("paper's section-4 calibration"),
            Stage::DeclaredFit => f.write_str("declared parameters (Cd, τ, mass)"),
            Stage::Candidates { round } => write!(f, "candidate effects (round {round})"),
            Stage::Refit { effect, .. } => write!(f, "re-fit with {}", effect.name()),
            Stage::Proposed { round } => {
                write!(f, "corrections beyond the library (round {round})")
            }
            Stage::LeftOut { effect } => write!(
                f,
                "{} switched off beside the proposed terms",
                effect.name()
            ),
            Stage::Drifts => f.write_str("parameters record by record (drifts)"),
            Stage::Ringing => {
                f.write_str("the mass or the oil's stiffness against the oil column's ringing")
            }
            Stage::RecordRate => f.write_str("the fits again on every sample of the records"),
            Stage::Report => f.write_str("diagnostics"),
        }
    }
}

/// Where a calibration is.
///
/// `done` of `total` counts the stage's units of work: the nominal replay and the paper's
/// method are one unit each; the declared fit and a re-fit count Jacobians against their
/// budget (a fit that converges early leaves the stage before `done` reaches `total`), the
/// re-fit's validation one more; the candidate stage counts candidate fits; the report
/// counts its seven replay sets.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Progress {
    /// The stage running.
    pub stage: Stage,
    /// Units of the stage done.
    pub done: usize,
    /// Units the stage has (at most).
    pub total: usize,
    /// Replays of the whole (fit part of the) campaign so far, all stages together.
    pub evaluations: usize,
}

/// Hears the progress of a calibration. Called from worker threads, so it must be `Sync`;
/// any `Fn(&Progress) + Sync` closure is one.
pub trait CalibrationObserver: Sync {
    /// A stage was entered, a unit of work done or a replay made.
    fn progress(&self, progress: &Progress);
}

impl<F: Fn(&Progress) + Sync> CalibrationObserver for F {
    fn progress(&self, progress: &Progress) {
        self(progress)
    }
}

/// The progress of a calibration as text, for [`super::calibrate`]'s callback.
#[derive(Debug, Clone, PartialEq)]
pub struct ProgressText {
    /// The stage, in words (`Display` of [`Stage`]).
    pub stage: String,
    /// Replays of the whole campaign so far.
    pub evaluations: usize,
}

#[derive(Debug, Clone, Copy)]
struct StageState {
    stage: Stage,
    done: usize,
    total: usize,
}

/// The cancel flag, the observer, the replay count and the kept replays
/// ([`ResidualMemo`]) of one running calibration, shared by its stages and fits.
pub struct Monitor<'a> {
    cancel: &'a AtomicBool,
    observer: &'a dyn CalibrationObserver,
    evaluations: AtomicUsize,
    state: Mutex<StageState>,
    /// The weighted residuals of the last replays, for the fits' evaluators.
    pub(super) residuals: ResidualMemo,
}

impl<'a> Monitor<'a> {
    /// A monitor at the start of the [`Stage::Nominal`] stage.
    pub fn new(cancel: &'a AtomicBool, observer: &'a dyn CalibrationObserver) -> Self {
        Self {
            cancel,
            observer,
            evaluations: AtomicUsize::new(0),
            state: Mutex::new(StageState {
                stage: Stage::Nominal,
                done: 0,
                total: 1,
            }),
            residuals: ResidualMemo::default(),
        }
    }

    /// Enters `stage`, which has `total` units of work, and tells the observer.
    pub fn enter(&self, stage: Stage, total: usize) {
        if let Ok(mut s) = self.state.lock() {
            *s = StageState {
                stage,
                done: 0,
                total,
            };
        }
        self.notify();
    }

    /// One unit of the stage's work is done.
    pub fn advance(&self) {
        if let Ok(mut s) = self.state.lock() {
            s.done = (s.done + 1).min(s.total);
        }
        self.notify();
    }

    /// A fit computed a Jacobian (work of the declared fit and the re-fits).
    pub fn jacobian(&self) {
        let counts = self
            .state
            .lock()
            .map(|s| s.stage.counts_jacobians())
            .unwrap_or(false);
        if counts {
            self.advance();
        }
    }

    /// A replay of the campaign was made: counts it and tells the observer. Returns the count.
    pub fn evaluated(&self) -> usize {
        let n = self.evaluations.fetch_add(1, Ordering::Relaxed) + 1;
        self.notify();
        n
    }

    /// Replays of the campaign so far.
    pub fn evaluations(&self) -> usize {
        self.evaluations.load(Ordering::Relaxed)
    }

    /// Whether the caller has cancelled.
    pub fn is_cancelled(&self) -> bool {
        self.cancel.load(Ordering::Relaxed)
    }

    /// `Err(Cancelled)` once the caller has cancelled.
    pub fn check(&self) -> Result<(), IdentifyError> {
        if self.is_cancelled() {
            Err(IdentifyError::Cancelled)
        } else {
            Ok(())
        }
    }

    fn notify(&self) {
        let Ok(s) = self.state.lock().map(|s| *s) else {
            return;
        };
        self.observer.progress(&Progress {
            stage: s.stage,
            done: s.done,
            total: s.total,
            evaluations: self.evaluations(),
        });
    }
}

/// Why a Levenberg–Marquardt fit stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StopReason {
    /// The relative change of the cost (`ftol`) and/or of the parameters (`xtol`) fell below
    /// the tolerance.
    Converged {
        /// The cost criterion was met.
        ftol: bool,
        /// The parameter criterion was met.
        xtol: bool,
    },
    /// The residual is orthogonal to the Jacobian's columns (a stationary point).
    Orthogonal,
    /// The residual is exactly zero.
    ResidualsZero,
    /// The fit used its budget of Jacobians.
    JacobianBudget,
    /// The optimiser's evaluation limit was hit.
    LostPatience,
    /// No step improves the cost at machine precision.
    NoImprovementPossible,
    /// A residual or Jacobian was not finite.
    NotFinite,
    /// Nothing to fit (no parameter or no residual) or inconsistent dimensions.
    Degenerate,
}

impl StopReason {
    /// Whether the fit reached a minimum by its own criteria (not a budget or failure).
    pub fn converged(self) -> bool {
        matches!(
            self,
            StopReason::Converged { .. } | StopReason::Orthogonal | StopReason::ResidualsZero
        )
    }
}

impl From<&levenberg_marquardt::TerminationReason> for StopReason {
    fn from(t: &levenberg_marquardt::TerminationReason) -> Self {
        use levenberg_marquardt::TerminationReason as T;
        match t {
            // The problem returns no Jacobian once its budget is spent (a cancel is caught
            // before the stop reason is read).
            T::User(_) => StopReason::JacobianBudget,
            T::Numerical(_) => StopReason::NotFinite,
            T::ResidualsZero => StopReason::ResidualsZero,
            T::Orthogonal => StopReason::Orthogonal,
            T::Converged { ftol, xtol } => StopReason::Converged {
                ftol: *ftol,
                xtol: *xtol,
            },
            T::NoImprovementPossible(_) => StopReason::NoImprovementPossible,
            T::LostPatience => StopReason::LostPatience,
            T::NoParameters | T::NoResiduals | T::WrongDimensions(_) => StopReason::Degenerate,
        }
    }
}

impl fmt::Display for StopReason {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            StopReason::Converged { ftol, xtol } => {
                let what = match (ftol, xtol) {
                    (true, true) => "cost and parameters",
                    (true, false) => "cost",
                    (false, true) => "parameters",
                    (false, false) => "tolerance",
                };
                write!(f, "converged ({what} settled)")
            }
            StopReason::Orthogonal => f.write_str("converged (gradient vanished)"),
            StopReason::ResidualsZero => f.write_str("converged (residual zero)"),
            StopReason::JacobianBudget => f.write_str("Jacobian budget used up"),
            StopReason::LostPatience => f.write_str("evaluation limit reached"),
            StopReason::NoImprovementPossible => {
                f.write_str("no further improvement at machine precision")
            }
            StopReason::NotFinite => f.write_str("residual not finite"),
            StopReason::Degenerate => f.write_str("nothing to fit"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stages_read_as_the_cli_prints_them() {
        assert_eq!(Stage::Nominal.to_string(), "nominal replay");
        assert_eq!(
            Stage::Candidates { round: 2 }.to_string(),
            "candidate effects (round 2)"
        );
        assert_eq!(
            Stage::Refit {
                round: 1,
                effect: EffectId::ValveOverlap
            }
            .to_string(),
            "re-fit with valve_overlap"
        );
    }

    #[test]
    fn stop_reasons_come_from_the_optimiser_and_read_as_words() {
        use levenberg_marquardt::TerminationReason as T;
        let r = StopReason::from(&T::User("jacobian"));
        assert_eq!(r, StopReason::JacobianBudget);
        assert_eq!(r.to_string(), "Jacobian budget used up");
        assert!(!r.converged());
        let c = StopReason::from(&T::Converged {
            ftol: true,
            xtol: false,
        });
        assert_eq!(c.to_string(), "converged (cost settled)");
        assert!(c.converged());
        assert_eq!(StopReason::from(&T::NoResiduals), StopReason::Degenerate);
        // Never the Debug form of the optimiser's enum.
        for r in [r, c, StopReason::from(&T::Numerical("nan"))] {
            let s = r.to_string();
            assert!(!s.contains('{') && !s.contains('"'), "{s}");
        }
    }

    #[test]
    fn monitor_counts_stage_work_replays_and_cancels() {
        let cancel = AtomicBool::new(false);
        let seen = Mutex::new(Vec::new());
        let obs = |p: &Progress| seen.lock().unwrap().push(p.clone());
        {
            let m = Monitor::new(&cancel, &obs);
            m.enter(Stage::DeclaredFit, 3);
            m.jacobian();
            m.evaluated();
            m.enter(Stage::Candidates { round: 1 }, 2);
            m.jacobian(); // not the candidate stage's unit
            m.advance();
            m.advance();
            m.advance(); // never beyond the total
            assert!(m.check().is_ok());
            cancel.store(true, Ordering::Relaxed);
            assert!(matches!(m.check(), Err(IdentifyError::Cancelled)));
            assert_eq!(m.evaluations(), 1);
        }
        let seen = seen.into_inner().unwrap();
        let at = |i: usize| {
            (
                seen[i].stage,
                seen[i].done,
                seen[i].total,
                seen[i].evaluations,
            )
        };
        assert_eq!(at(0), (Stage::DeclaredFit, 0, 3, 0));
        assert_eq!(at(1), (Stage::DeclaredFit, 1, 3, 0));
        assert_eq!(at(2), (Stage::DeclaredFit, 1, 3, 1));
        let round1 = Stage::Candidates { round: 1 };
        assert_eq!(at(3), (round1, 0, 2, 1));
        assert_eq!(at(4), (round1, 1, 2, 1));
        assert_eq!(at(5), (round1, 2, 2, 1));
        assert_eq!(at(6), (round1, 2, 2, 1));
        assert_eq!(seen.len(), 7);
    }
}
