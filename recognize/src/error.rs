//! The crate's one error type.

use std::io;
use std::path::PathBuf;

use crate::eval::EvalError;
use crate::features::nakano::NakanoError;
use crate::features::spectral::SpectralError;
use crate::knn::KnnError;
use crate::som::SomError;
use crate::svc::SvcError;
use capture::{CaptureError, JsonFileError};

/// Why a recognizer could not be trained, stored, loaded or evaluated.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RecognizerError {
    /// Reading or writing a file failed.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        #[source]
        source: io::Error,
    },
    /// Not valid JSON for a recognizer.
    #[error("{}:{line}: {reason}", path.display())]
    Parse {
        /// The file.
        path: PathBuf,
        /// Line of the error.
        line: usize,
        /// What serde said.
        reason: String,
    },
    /// Parsed, but inconsistent.
    #[error("{}: field `{field}`: {reason}", path.display())]
    Invalid {
        /// The file.
        path: PathBuf,
        /// The field.
        field: String,
        /// Why.
        reason: String,
    },
    /// A capture could not be read.
    #[error("reading capture")]
    Capture(#[from] CaptureError),
    /// A capture cannot be used as it is.
    #[error("{}: {reason}", path.display())]
    UnusableCapture {
        /// The capture.
        path: PathBuf,
        /// Why.
        reason: String,
    },
    /// Nakano's features failed on a capture.
    #[error("{}: Nakano features", path.display())]
    Nakano {
        /// The capture.
        path: PathBuf,
        /// Why.
        #[source]
        source: NakanoError,
    },
    /// Sinapov's features failed on a capture.
    #[error("{}: spectrotemporal features", path.display())]
    Spectral {
        /// The capture.
        path: PathBuf,
        /// Why.
        #[source]
        source: SpectralError,
    },
    /// The map could not be trained or queried.
    #[error("self-organizing map")]
    Som(#[from] SomError),
    /// An SVC could not be fitted or queried.
    #[error("SVC of behaviour `{behaviour}`")]
    Svc {
        /// The behaviour whose classifier failed.
        behaviour: String,
        /// Why.
        #[source]
        source: SvcError,
    },
    /// A k-NN could not be fitted or queried.
    #[error("k-NN of behaviour `{behaviour}`")]
    Knn {
        /// The behaviour whose classifier failed.
        behaviour: String,
        /// Why.
        #[source]
        source: KnnError,
    },
    /// A setting is out of range.
    #[error("invalid setting {name} = {value}: {reason}")]
    Setting {
        /// The setting.
        name: &'static str,
        /// Its value.
        value: f64,
        /// What it must be.
        reason: &'static str,
    },
    /// The captures lack columns the chosen features need.
    #[error("{}: `--features {features}` needs the columns {}, which this capture lacks", path.display(), missing.join(", "))]
    MissingColumns {
        /// The capture.
        path: PathBuf,
        /// The feature set asked for (`nakano`, `spectral`, `both`).
        features: &'static str,
        /// The columns it lacks.
        missing: Vec<String>,
    },
    /// No capture gave a training vector.
    #[error("no training windows: every capture is shorter than one window after the start travel")]
    NoTrainingData,
    /// A label could not be recorded.
    #[error("confusion matrix")]
    Eval(#[from] EvalError),
}

impl RecognizerError {
    /// Wraps a k-NN's error, naming the classifier's behaviour (none for one over windows).
    pub(crate) fn knn(behaviour: Option<&str>) -> impl Fn(KnnError) -> Self + '_ {
        move |source| Self::Knn {
            behaviour: behaviour.unwrap_or_default().to_owned(),
            source,
        }
    }

    /// Wraps an SVC's error, naming the classifier's behaviour (none for one over windows).
    pub(crate) fn svc(behaviour: Option<&str>) -> impl Fn(SvcError) -> Self + '_ {
        move |source| Self::Svc {
            behaviour: behaviour.unwrap_or_default().to_owned(),
            source,
        }
    }
}

/// A recognizer file's failures keep this crate's own variants, with the same messages.
impl From<JsonFileError> for RecognizerError {
    fn from(e: JsonFileError) -> Self {
        match e {
            JsonFileError::Io { path, source } => Self::Io { path, source },
            JsonFileError::Parse { path, line, reason } => Self::Parse { path, line, reason },
            JsonFileError::Invalid { path, field, reason } => Self::Invalid { path, field, reason },
        }
    }
}
