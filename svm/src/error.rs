//! Why a fit failed.

/// Errors of the ε-SVR: bad hyperparameters or data are rejected before work starts; a solve
/// that cannot reach its tolerance within its budgets says so instead of returning a model.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SvrError {
    /// A hyperparameter is out of its domain.
    #[error("hyperparameter {name} = {value}: {reason}")]
    InvalidHyperparameter {
        /// Its name.
        name: &'static str,
        /// Its value.
        value: f64,
        /// What it must be.
        reason: &'static str,
    },
    /// No samples.
    #[error("no training samples")]
    NoSamples,
    /// The inputs are not `n × dim` or the targets not `n`.
    #[error("inputs have {inputs} values for {targets} targets of dimension {dim}")]
    Shape {
        /// Number of input values.
        inputs: usize,
        /// Number of targets.
        targets: usize,
        /// Declared input dimension.
        dim: usize,
    },
    /// An input or target is NaN or infinite.
    #[error("sample {row}, {what} is not finite")]
    NonFinite {
        /// Sample index.
        row: usize,
        /// `input k` or `target`.
        what: String,
    },
    /// The iteration budget ran out before the tolerance was met.
    #[error(
        "{solver} did not converge in {iterations} iterations (relative gap {gap:.3e}, tolerance {tolerance:.1e})"
    )]
    NotConverged {
        /// Which solver.
        solver: &'static str,
        /// Iterations done.
        iterations: usize,
        /// Relative optimality gap reached.
        gap: f64,
        /// Tolerance asked for.
        tolerance: f64,
    },
    /// The time budget ran out.
    #[error(
        "{solver} exceeded its time budget of {budget_s} s after {iterations} iterations (relative gap {gap:.3e})"
    )]
    Budget {
        /// Which solver.
        solver: &'static str,
        /// Budget in seconds.
        budget_s: f64,
        /// Iterations done.
        iterations: usize,
        /// Relative gap reached.
        gap: f64,
    },
    /// The problem is numerically beyond the solver (e.g. a kernel matrix that is not positive
    /// semi-definite to working precision).
    #[error("numerical failure in {solver}: {reason}")]
    Numerical {
        /// Which solver.
        solver: &'static str,
        /// What went wrong.
        reason: String,
    },
}

impl SvrError {
    /// [`SvrError::InvalidHyperparameter`].
    pub(crate) fn hyperparameter(name: &'static str, value: f64, reason: &'static str) -> Self {
        Self::InvalidHyperparameter { name, value, reason }
    }
}

/// C, γ and the stopping tolerance must be finite and positive.
pub(crate) fn check_positive(name: &'static str, value: f64) -> Result<(), SvrError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(SvrError::hyperparameter(name, value, "must be finite and > 0"))
    }
}

/// A wall-clock budget of zero could never be met.
pub(crate) fn check_time_budget(budget: std::time::Duration) -> Result<(), SvrError> {
    if budget.is_zero() {
        Err(SvrError::hyperparameter("time_budget", 0.0, "must be > 0"))
    } else {
        Ok(())
    }
}
