//! The crate's one error type: every way an identification, a baseline, a metric or a model
//! file can fail, each naming the file, the series or the parameter at fault.

use std::path::PathBuf;

/// Why an identification, a baseline, a metric or a model file failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum IdentifyError {
    /// A capture lacks what this model needs, or a model file could not be written, read or
    /// used (capture owns the project's files, so its error names the file, line and field).
    #[error(transparent)]
    Capture(#[from] capture::CaptureError),
    /// The data cannot make this model.
    #[error("{}: {reason}", path.display())]
    Data {
        /// Capture.
        path: PathBuf,
        /// Why.
        reason: String,
    },
    /// A fit failed.
    #[error("fitting {what}: {source}")]
    Svr {
        /// Which SVR.
        what: String,
        /// Why.
        #[source]
        source: svm::SvmError,
    },
    /// A baseline failed.
    #[error("baseline {what}: {source}")]
    Baseline {
        /// Which.
        what: &'static str,
        /// Why (boxed: the error is recursive).
        #[source]
        source: Box<IdentifyError>,
    },
    /// Metrics could not be computed.
    #[error("metrics: {source}")]
    Metrics {
        /// Why (boxed: the error is recursive).
        #[source]
        source: Box<IdentifyError>,
    },
    /// A metric came out infinite or NaN (values so large their squares overflow), so the
    /// model file could not hold it.
    #[error(
        "{}: the {what} is {value}: the capture holds values too large to evaluate a fit on",
        path.display()
    )]
    NonFiniteMetric {
        /// The capture the metric was computed on.
        path: PathBuf,
        /// Which metric of which model on which data.
        what: String,
        /// Its value.
        value: f64,
    },
    /// No samples at all.
    #[error("no samples")]
    Empty,
    /// AISE needs an observed duration, so at least two samples.
    #[error("{found} sample(s): AISE needs at least 2 (a duration to average over)")]
    TooFewSamples {
        /// Samples given.
        found: usize,
    },
    /// A series does not have the length the others imply.
    #[error("{name} has {found} values, expected {expected}")]
    LengthMismatch {
        /// The series.
        name: &'static str,
        /// Its length.
        found: usize,
        /// The expected length.
        expected: usize,
    },
    /// A value is NaN or infinite.
    #[error("{name}[{index}] = {value} is not finite")]
    NonFinite {
        /// The series.
        name: &'static str,
        /// Index in the (row-major) series.
        index: usize,
        /// The value.
        value: f64,
    },
    /// Time does not strictly increase.
    #[error("time_s[{index}] = {time_s} s does not exceed the previous sample's {previous_s} s")]
    TimeNotIncreasing {
        /// Index of the offending sample.
        index: usize,
        /// Its time.
        time_s: f64,
        /// The previous sample's time.
        previous_s: f64,
    },
    /// A parameter is out of its domain.
    #[error("{name} = {value:e}: {reason}")]
    InvalidParameter {
        /// Its name.
        name: &'static str,
        /// Its value.
        value: f64,
        /// What it must be.
        reason: &'static str,
    },
    /// The capture is shorter than the requested observation window.
    #[error("the samples cover {covered_s} s but the observation window needs {needed_s} s")]
    TooShort {
        /// Time covered by the samples.
        covered_s: f64,
        /// Time needed.
        needed_s: f64,
    },
    /// The regressors do not determine the coefficients (e.g. velocity proportional to pressure,
    /// or a constant regressor next to an intercept).
    #[error("{model}: the {columns} regressors have rank {rank}, so the coefficients are not determined")]
    RankDeficient {
        /// Which model.
        model: &'static str,
        /// Rank found.
        rank: usize,
        /// Regressors.
        columns: usize,
    },
    /// The linear-algebra routine failed.
    #[error("least squares failed: {reason}")]
    Numerical {
        /// What went wrong.
        reason: String,
    },
}

/// Rejects a series whose length is not `expected` or that holds a NaN or an infinity.
pub(crate) fn check_series(name: &'static str, values: &[f64], expected: usize) -> Result<(), IdentifyError> {
    if values.len() != expected {
        return Err(IdentifyError::LengthMismatch {
            name,
            found: values.len(),
            expected,
        });
    }
    check_finite(name, values)
}

/// Rejects a series that holds a NaN or an infinity, naming the first.
pub(crate) fn check_finite(name: &'static str, values: &[f64]) -> Result<(), IdentifyError> {
    match values.iter().position(|v| !v.is_finite()) {
        Some(index) => Err(IdentifyError::NonFinite {
            name,
            index,
            value: values[index],
        }),
        None => Ok(()),
    }
}
