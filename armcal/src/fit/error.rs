//! Why a calibration refuses to give a result ([`CalibError`]): each variant says what the
//! data lack or where they disagree with the arm, in words a user can act on.

use crate::fit::lm;

/// Why a calibration refused to give a result.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum CalibError {
    /// Not enough equations for the unknowns.
    #[error(
        "too few rows for the parameters: the data give {equations} equations \
         ({detail}) for {parameters} identifiable parameters; record more rows"
    )]
    TooFewRows {
        /// Equations the data give.
        equations: usize,
        /// Unknowns a well-spread data set of these kinds determines.
        parameters: usize,
        /// Where the equations come from.
        detail: String,
    },
    /// The poses do not exercise the arm enough.
    #[error(
        "degenerate pose set: these poses cannot determine {}, which well-spread poses of \
         the same kinds would; {hint}",
        lost.join(", ")
    )]
    Degenerate {
        /// What is lost, in words.
        lost: Vec<String>,
        /// What to do about it.
        hint: String,
    },
    /// The solver stopped without converging.
    #[error(
        "the fit did not converge: {reason} after {iterations} iterations (RMS residual \
         {rms_mm:.4} mm); the start arm may be too far from the data, or the data inconsistent"
    )]
    NotConverged {
        /// Iterations done.
        iterations: usize,
        /// Why the solver stopped.
        reason: lm::Termination,
        /// RMS residual where it stopped (mm).
        rms_mm: f64,
    },
    /// The data and the arm do not fit together.
    #[error("{0}")]
    Mismatch(String),
    /// The data's kinds cannot fix something the unknowns would change ([`crate::kinds`]).
    #[error("these data cannot fix {what}: {why}")]
    Unfixable {
        /// What is not fixed.
        what: String,
        /// Why, and what to record.
        why: String,
    },
}
