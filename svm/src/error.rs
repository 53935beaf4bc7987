//! Why a fit, a libsvm model file or a fast evaluator failed.

use std::io;

/// [`SvmError::NotConverged`]'s measure for an ε-SVR solver's last iterate.
pub(crate) const CERTIFIED_MISS: &str =
    "its last iterate misses the acceptance threshold (1e-6) at a certified relative gap of";
/// [`SvmError::NotConverged`]'s measure for a bare SMO (no certificate).
pub(crate) const KKT_VIOLATION: &str = "its largest KKT violation is";
/// [`SvmError::Budget`]'s measure for the interior point's own iterate.
pub(crate) const RELATIVE_GAP: &str = "its relative duality gap is";
/// [`SvmError::Budget`]'s measure once the last iterate has been certified.
pub(crate) const CERTIFIED_GAP: &str = "its last iterate's certified relative gap is";
/// [`SvmError::NotConverged`]'s measure when no iterate was left to certify.
pub(crate) const NOTHING_TO_CERTIFY: &str = "no iterate was left to certify; gap";

/// Errors of the crate: bad hyperparameters or data are rejected before a fit starts, a solve
/// that cannot reach its tolerance within its budgets says so instead of returning a model, a
/// libsvm model file that cannot be written or read names the line and what is wrong with it,
/// and a model the fast evaluators cannot take names the offending value.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SvmError {
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
    /// A row-major array does not hold `rows × dim` values: training inputs against their
    /// targets, or a model's support vectors against its coefficients.
    #[error("{values} {array} values for {rows} {rows_of} of dimension {dim}")]
    Shape {
        /// The array (`input`, `support-vector`).
        array: &'static str,
        /// Number of values it holds.
        values: usize,
        /// What its rows are counted by (`targets`, `coefficients`).
        rows_of: &'static str,
        /// Number of rows.
        rows: usize,
        /// Input dimension.
        dim: usize,
    },
    /// A model or a scaling has another input dimension than the evaluator built for it.
    #[error("{what} has dimension {found}, the evaluator {expected}")]
    Dimension {
        /// `model`, `model weights`, `scaling.offset` or `scaling.scale`.
        what: &'static str,
        /// Its dimension.
        found: usize,
        /// The evaluator's `D`.
        expected: usize,
    },
    /// A training input or target is NaN or infinite.
    #[error("sample {row}, {what} is not finite")]
    NonFinite {
        /// Sample index.
        row: usize,
        /// `input k` or `target`.
        what: String,
    },
    /// A model value is NaN or infinite, a scale is 0, or a folded value overflows.
    #[error("{what} = {value} is not usable: {reason}")]
    BadValue {
        /// Which value (`scaling.scale[1]`, `coefficient 7`, ...).
        what: String,
        /// Its value.
        value: f64,
        /// Why.
        reason: &'static str,
    },
    /// The iteration budget ran out before the tolerance was met, and where it stopped is not
    /// good enough to return.
    #[error(
        "{solver} did not converge in {iterations} iterations, aiming for {tolerance:.1e}: {measure} {gap:.3e}"
    )]
    NotConverged {
        /// Which solver.
        solver: &'static str,
        /// Iterations done.
        iterations: usize,
        /// What it reached: an ε-SVR's certified relative duality gap of its last iterate
        /// (above [`crate::ACCEPT_GAP`], or the iterate would have been returned); a bare SMO's
        /// ([`crate::solve_smo`], no certificate) largest KKT violation.
        gap: f64,
        /// What `gap` measures, in words.
        measure: &'static str,
        /// The tolerance it aimed for (a relative gap; SMO's, a KKT violation).
        tolerance: f64,
    },
    /// The solver stopped (at its own tolerance or at a limit) with a solution whose certified
    /// relative duality gap misses the acceptance threshold: it is not returned.
    #[error(
        "{solver} stopped ({stopped}) after {iterations} iterations with a certified relative gap of {gap:.3e}, above the acceptance threshold {threshold:.0e}: no model is returned; a tighter tolerance or other C, epsilon or gamma may reach it"
    )]
    Uncertified {
        /// Which solver.
        solver: &'static str,
        /// Why it stopped (no budget ran out: those are [`SvmError::Budget`] and
        /// [`SvmError::NotConverged`]).
        stopped: &'static str,
        /// Iterations done.
        iterations: usize,
        /// Best certified relative gap reached (infinite: the coefficients left their box).
        gap: f64,
        /// The acceptance threshold ([`crate::ACCEPT_GAP`]).
        threshold: f64,
    },
    /// The time budget ran out.
    #[error(
        "{solver} exceeded its time budget of {budget_s} s after {iterations} iterations: {measure} {gap:.3e}"
    )]
    Budget {
        /// Which solver.
        solver: &'static str,
        /// Budget in seconds.
        budget_s: f64,
        /// Iterations done.
        iterations: usize,
        /// What it reached: a relative duality gap (certified where `measure` says so), or
        /// SMO's largest KKT violation.
        gap: f64,
        /// What `gap` measures, in words.
        measure: &'static str,
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
    /// Reading or writing a model file failed. The error is kept as its kind and message so
    /// that this type stays `Clone` and `PartialEq`.
    #[error("I/O error: {message}")]
    Io {
        /// The kind of the I/O error.
        kind: io::ErrorKind,
        /// Its message.
        message: String,
    },
    /// The model cannot be expressed in (or is not consistent enough for) libsvm's format.
    #[error("cannot export the model: {0}")]
    LibsvmExport(String),
    /// A libsvm model file ended before a required part.
    #[error("the model file ends without {0}")]
    LibsvmMissing(&'static str),
    /// A header keyword the libsvm reader does not know.
    #[error("line {line}: unknown header keyword `{key}`")]
    LibsvmUnknownKey {
        /// 1-based line number.
        line: usize,
        /// The keyword.
        key: String,
    },
    /// A header keyword appears twice.
    #[error("line {line}: header keyword `{key}` appears twice")]
    LibsvmDuplicateKey {
        /// 1-based line number of the second one.
        line: usize,
        /// The keyword.
        key: String,
    },
    /// A header keyword without the value(s) it needs.
    #[error("line {line}: `{key}` needs {expected} value(s), found {found}")]
    LibsvmValueCount {
        /// 1-based line number.
        line: usize,
        /// The keyword.
        key: String,
        /// Values expected.
        expected: usize,
        /// Values found.
        found: usize,
    },
    /// A value that is not a number of the right kind.
    #[error("line {line}: {what}: `{text}` is not {expected}")]
    LibsvmBadNumber {
        /// 1-based line number.
        line: usize,
        /// Which value.
        what: String,
        /// The text found.
        text: String,
        /// What it should be.
        expected: &'static str,
    },
    /// Not a regression model.
    #[error("line {line}: svm_type `{svm_type}` is not a regression model (expected epsilon_svr or nu_svr)")]
    LibsvmSvmType {
        /// 1-based line number.
        line: usize,
        /// The type found.
        svm_type: String,
    },
    /// A kernel this crate does not have.
    #[error("line {line}: kernel_type `{kernel}` is not supported (expected linear, polynomial or rbf)")]
    LibsvmKernel {
        /// 1-based line number.
        line: usize,
        /// The kernel found.
        kernel: String,
    },
    /// A header parameter outside its domain.
    #[error("line {line}: {name} = {value}: {reason}")]
    LibsvmParameter {
        /// 1-based line number.
        line: usize,
        /// The parameter.
        name: &'static str,
        /// Its value.
        value: f64,
        /// What it must be.
        reason: &'static str,
    },
    /// A header keyword appears before one it depends on.
    #[error("line {line}: `{key}` must come after `{after}`")]
    LibsvmOrder {
        /// 1-based line number.
        line: usize,
        /// The keyword.
        key: &'static str,
        /// The keyword it needs first.
        after: &'static str,
    },
    /// A required header keyword never appeared before `SV`.
    #[error("line {line}: the header has no `{key}` line")]
    LibsvmMissingKey {
        /// 1-based line number where it was needed (the `SV` or `kernel_type` line).
        line: usize,
        /// The keyword.
        key: &'static str,
    },
    /// A support-vector element is not `index:value`.
    #[error("line {line}: `{text}` is not an index:value pair")]
    LibsvmBadNode {
        /// 1-based line number.
        line: usize,
        /// The element found.
        text: String,
    },
    /// Indices must be ≥ 1 and strictly increasing along a line.
    #[error("line {line}: index {index} after index {previous}: indices must be ≥ 1 and strictly increasing")]
    LibsvmIndexOrder {
        /// 1-based line number.
        line: usize,
        /// The index found.
        index: usize,
        /// The index before it (0 at the start of the line).
        previous: usize,
    },
    /// An index beyond the dimension asked for.
    #[error("line {line}: index {index} exceeds the input dimension {dim}")]
    LibsvmIndexBeyondDim {
        /// 1-based line number.
        line: usize,
        /// The index found.
        index: usize,
        /// The dimension.
        dim: usize,
    },
    /// More support-vector lines than `total_sv` declared.
    #[error("line {line}: more support vectors than total_sv = {declared}")]
    LibsvmTooManySupportVectors {
        /// 1-based line number.
        line: usize,
        /// The declared count.
        declared: usize,
    },
    /// Fewer support-vector lines than `total_sv` declared (reported at the last line).
    #[error("line {line}: {found} support vectors but total_sv = {declared}")]
    LibsvmTooFewSupportVectors {
        /// 1-based line number.
        line: usize,
        /// The declared count.
        declared: usize,
        /// Lines found.
        found: usize,
    },
}

impl From<io::Error> for SvmError {
    fn from(e: io::Error) -> Self {
        Self::Io {
            kind: e.kind(),
            message: e.to_string(),
        }
    }
}

impl SvmError {
    /// [`SvmError::InvalidHyperparameter`].
    pub(crate) fn hyperparameter(name: &'static str, value: f64, reason: &'static str) -> Self {
        Self::InvalidHyperparameter { name, value, reason }
    }

    /// The 1-based line of the libsvm model file the error is about, for a malformed line.
    pub fn line(&self) -> Option<usize> {
        match *self {
            Self::LibsvmUnknownKey { line, .. }
            | Self::LibsvmDuplicateKey { line, .. }
            | Self::LibsvmValueCount { line, .. }
            | Self::LibsvmBadNumber { line, .. }
            | Self::LibsvmSvmType { line, .. }
            | Self::LibsvmKernel { line, .. }
            | Self::LibsvmParameter { line, .. }
            | Self::LibsvmOrder { line, .. }
            | Self::LibsvmMissingKey { line, .. }
            | Self::LibsvmBadNode { line, .. }
            | Self::LibsvmIndexOrder { line, .. }
            | Self::LibsvmIndexBeyondDim { line, .. }
            | Self::LibsvmTooManySupportVectors { line, .. }
            | Self::LibsvmTooFewSupportVectors { line, .. } => Some(line),
            _ => None,
        }
    }
}

/// C, γ and the stopping tolerance must be finite and positive.
pub(crate) fn check_positive(name: &'static str, value: f64) -> Result<(), SvmError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(SvmError::hyperparameter(name, value, "must be finite and > 0"))
    }
}

/// A wall-clock budget of zero could never be met.
pub(crate) fn check_time_budget(budget: std::time::Duration) -> Result<(), SvmError> {
    if budget.is_zero() {
        Err(SvmError::hyperparameter("time_budget", 0.0, "must be > 0"))
    } else {
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_refusal_states_the_acceptance_threshold_the_certificate_is_held_to() {
        assert!(CERTIFIED_MISS.contains(&format!("({:e})", crate::ACCEPT_GAP)));
    }
}
