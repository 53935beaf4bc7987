//! The crate's one error type.
//!
//! Every part of the crate (features, classifiers, confusion matrices, protocols, categories,
//! recognizer files) fails with [`RecognizeError`], whose variants say what the user can do
//! about it: [`InputError`] (fix or replace a file or capture), [`SettingError`] (change an
//! option), [`DataError`] (bring more recordings, classes or windows), [`SolverError`] (let a
//! solver go further or choose other hyperparameters) and [`UsageError`] (a caller of the
//! library passed arguments that do not fit together). Failures that one part passes up from
//! another keep the outer part's context in a wrapping variant whose source is the inner
//! failure, boxed: one enum cannot hold itself by value, and a box keeps the common variants
//! small while the chain of `source()`s still reads outer to inner.

use std::io;
use std::path::PathBuf;

use capture::{CaptureError, CaptureErrorKind};

use crate::features::WindowlessCapture;

/// Why surface recognition failed, grouped by what the user can do about it: fix an input,
/// change a setting, bring more data, let a solver go further, or fix a caller; or one of those
/// with the context it happened in (which features, classifier or fold), whose source is the
/// inner failure.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RecognizeError {
    /// A file or capture cannot be used as it is: fix, replace or re-record it.
    #[error(transparent)]
    Input(#[from] InputError),
    /// An option is out of its range or does not fit the data: change it.
    #[error(transparent)]
    Setting(#[from] SettingError),
    /// The training or test data cannot support what was asked: more recordings, classes,
    /// windows or travel.
    #[error(transparent)]
    Data(#[from] DataError),
    /// A solver stopped short of an answer: raise its limit, or choose other hyperparameters.
    #[error(transparent)]
    Solver(#[from] SolverError),
    /// Arguments that do not fit together, passed through the library: a bug in the caller,
    /// not in the data.
    #[error(transparent)]
    Usage(#[from] UsageError),
    // --- Context around an inner failure ---
    /// A feature set failed on a capture.
    #[error("{}: {features} features", path.display())]
    Features {
        /// The capture.
        path: PathBuf,
        /// The feature set (`Nakano`, `spectrotemporal`).
        features: &'static str,
        /// Why.
        #[source]
        source: Box<RecognizeError>,
    },
    /// The self-organizing map could not be trained or queried.
    #[error("self-organizing map")]
    Som(#[source] Box<RecognizeError>),
    /// A behaviour's classifier could not be fitted or queried.
    #[error("{classifier} of behaviour `{behaviour}`")]
    Classifier {
        /// The classifier (`SVC`, `k-NN`).
        classifier: &'static str,
        /// The behaviour whose classifier failed (empty for one over windows).
        behaviour: String,
        /// Why.
        #[source]
        source: Box<RecognizeError>,
    },
    /// Fitting or querying one fused behaviour's k-NN failed.
    #[error("behaviour {behaviour}")]
    FusedBehaviour {
        /// Index of the behaviour.
        behaviour: usize,
        /// What went wrong.
        #[source]
        source: Box<RecognizeError>,
    },
    /// A fold's recognizer could not be trained or evaluated.
    #[error("fold {fold} of {folds} (seed {seed})")]
    Fold {
        /// The fold held out (or trained on, for train-on-one).
        fold: usize,
        /// Folds in all.
        folds: usize,
        /// The seed of this round.
        seed: u64,
        /// Why.
        #[source]
        source: Box<RecognizeError>,
    },
}

/// A file or capture cannot be used as it is: fix, replace or re-record it.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum InputError {
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
    Capture(#[source] Box<CaptureError>),
    /// A capture cannot be used as it is.
    #[error("{}: {reason}", path.display())]
    UnusableCapture {
        /// The capture.
        path: PathBuf,
        /// Why.
        reason: String,
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
    /// The capture lacks a column Nakano's features need.
    #[error("capture lacks a column Nakano's features need")]
    NakanoColumn(#[source] Box<CaptureError>),
    /// A capture's metadata value cannot be used.
    #[error("metadata `{key}` = {value:?}: {reason}")]
    Metadata {
        /// The key.
        key: &'static str,
        /// Its value.
        value: String,
        /// What it must be.
        reason: &'static str,
    },
    /// The velocity for the reaction-force observer could not be derived from position.
    #[error("cannot derive velocity for the reaction-force observer")]
    Velocity(#[source] Box<CaptureError>),
    /// The capture lacks an accelerometer column.
    #[error("capture has no accelerometer data")]
    NoAccelerometer(#[source] Box<CaptureError>),
    /// Too few samples for one frame per time bin.
    #[error("recording has {samples} samples; the spectrotemporal histogram needs at least {needed}")]
    TooShort {
        /// Samples given.
        samples: usize,
        /// Samples needed.
        needed: usize,
    },
    /// A sample is NaN or infinite.
    #[error("sample {index} is not finite")]
    NonFiniteSample {
        /// Index of the first bad sample.
        index: usize,
    },
    /// A feature is NaN or infinite.
    #[error("vector {index} has a value that is not finite")]
    NonFinite {
        /// Index of the vector (0 for a query).
        index: usize,
    },
    /// The three axes do not have the same number of samples.
    #[error("accelerometer axes differ in length: x {x}, y {y}, z {z} samples")]
    AxisLengths {
        /// Samples on x.
        x: usize,
        /// Samples on y.
        y: usize,
        /// Samples on z.
        z: usize,
    },
    /// A recognizer fused over time carries no measured reliability to weigh its evidence by.
    #[error(
        "recognizer {index} ({method} over {features} windows) has no cross-validated accuracy to weigh \
         its evidence by: train it (a k-NN or SVM over windows) on captures of at least two runs or trials \
         of every surface (its windows are then cross-validated with whole runs or trials held out)"
    )]
    NoReliability {
        /// Index of the recognizer among those fused.
        index: usize,
        /// Its method.
        method: &'static str,
        /// Its features.
        features: &'static str,
    },
    /// Recognizers fused over time name different surfaces, or the same in another order.
    #[error("recognizer {index} names the surfaces {}, the first {}: fused recognizers must be trained on the same surfaces", got.join(", "), expected.join(", "))]
    FusionSurfaces {
        /// Index of the recognizer among those fused.
        index: usize,
        /// The first recognizer's surfaces.
        expected: Vec<String>,
        /// This one's.
        got: Vec<String>,
    },
}

/// An option is out of its range or does not fit the data: change it.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SettingError {
    /// A setting or hyperparameter is out of range.
    #[error("invalid {of} {name} = {value}: {reason}")]
    Parameter {
        /// Whose setting (`setting`, `SVC parameter`, `SOM parameter`).
        of: &'static str,
        /// The setting.
        name: &'static str,
        /// Its value.
        value: f64,
        /// What it must be.
        reason: &'static str,
    },
    /// A configuration is not usable, for a reason that names no single value.
    #[error("invalid {of}: {reason}")]
    Config {
        /// Whose configuration (`Nakano configuration`, `category parameter`).
        of: &'static str,
        /// Why.
        reason: &'static str,
    },
    /// `k` must be at least one.
    #[error("k must be at least 1")]
    ZeroK,
    /// A window over travel slid so fast that its vibration bands pass the Nyquist frequency.
    #[error(
        "a window slid at {speed_mps:.4} m/s: its spectrum's bands over travel pass the Nyquist frequency of {rate_hz} Hz above {max_speed_mps:.4} m/s (train with a higher --fastest-speed-mps, or record at a higher rate)"
    )]
    TooFastForBands {
        /// The window's speed, m/s.
        speed_mps: f64,
        /// The fastest window the bands can be read at, at this rate, m/s.
        max_speed_mps: f64,
        /// The capture's rate, Hz.
        rate_hz: f64,
    },
    /// A window needs at least two samples (a variance and a travel).
    #[error("window of {len} samples: at least 2 needed")]
    WindowTooShort {
        /// Samples asked for.
        len: usize,
    },
    /// Anytime decisions asked of a recognizer that gives no probability per window.
    #[error(
        "anytime decisions need each window's probability of every surface, which a k-NN or SVM over \
         windows gives; this is a {method} recognizer over {features} features"
    )]
    NoWindowProbabilities {
        /// Its method.
        method: &'static str,
        /// Its features.
        features: &'static str,
    },
    /// Probabilities were asked of a classifier fitted without them.
    #[error("the classifier was fitted without probability estimates")]
    NoProbability,
    /// At least one seed is needed.
    #[error("at least one seed is needed")]
    NoSeeds,
    /// The fold asked for alone does not exist.
    #[error("fold {fold} asked for, but there are {folds} folds (numbered from 1)")]
    NoSuchFold {
        /// The fold asked for (from 1).
        fold: usize,
        /// Folds in all.
        folds: usize,
    },
    /// The k-nearest-neighbour graph has more than one component, so some geodesic distances
    /// do not exist.
    #[error("the {k}-nearest-neighbour graph is disconnected (point {from} cannot reach point {to})")]
    Disconnected {
        /// Neighbours per point.
        k: usize,
        /// A point.
        from: usize,
        /// A point it cannot reach.
        to: usize,
    },
    /// A recognizer fused over time was no better than chance under cross-validation.
    #[error("recognizer {index} named {:.1} % of its held-out windows right, no better than chance: its evidence would weigh nothing", 100.0 * accuracy)]
    Unreliable {
        /// Index of the recognizer among those fused.
        index: usize,
        /// Its cross-validated accuracy per window.
        accuracy: f64,
    },
    /// Two recognizers fused over time read the same evidence.
    #[error(
        "recognizers {first} and {second} read the same evidence ({} and {} features): fused, it would \
         count twice; fuse recognizers over different senses, such as nakano and vibration",
        features[0],
        features[1]
    )]
    FusionOverlap {
        /// Index of the first of the two among the recognizers fused.
        first: usize,
        /// Index of the second.
        second: usize,
        /// Their feature sets.
        features: [&'static str; 2],
    },
}

/// The training or test data cannot support what was asked: more recordings, classes,
/// windows or travel.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum DataError {
    #[error("no training windows: every capture is shorter than one window after the start travel")]
    NoTrainingData,
    /// A class's captures gave no training window, so the recognizer could never answer it.
    #[error("class `{class}` has no training vector: {}", windowless_list(captures))]
    ClassWithoutWindows {
        /// The class.
        class: String,
        /// Each of its captures, and why it gave no window.
        captures: Vec<WindowlessCapture>,
    },
    /// No evaluated capture gave a decision, so there is nothing to score.
    #[error("no decisions to evaluate: {}", if captures.is_empty() { "no captures given".to_owned() } else { windowless_list(captures) })]
    NoDecisions {
        /// Each capture evaluated, and why it gave no window.
        captures: Vec<WindowlessCapture>,
    },
    /// No training points.
    #[error("no training points")]
    Empty,
    /// Fewer training points than neighbours.
    #[error("k = {k} neighbours asked for, only {points} training points")]
    TooFewPoints {
        /// Neighbours asked for.
        k: usize,
        /// Training points available.
        points: usize,
    },
    /// Cross-validation needs at least two groups (recordings, trials) and two folds.
    #[error("cross-validation needs at least 2 groups and 2 folds, got {groups} groups, {folds} folds")]
    TooFewGroups {
        /// Distinct groups.
        groups: usize,
        /// Folds asked for.
        folds: usize,
    },
    /// A class has no training vector.
    #[error("class {class} has no training vector")]
    EmptyClass {
        /// The class.
        class: usize,
    },
    /// Fewer recordings than folds, or fewer than two folds.
    #[error(
        "{recordings} recordings (distinct `trial` or `run` in the metadata, else captures) cannot \
         be split into {folds} folds: at least 2 folds, and at least one recording per fold"
    )]
    Folds {
        /// Recordings found.
        recordings: usize,
        /// Folds asked for.
        folds: usize,
    },
    /// Leaving one surface out needs at least three (two to train on).
    #[error("{surfaces} surfaces: leaving one out needs at least 3")]
    Surfaces {
        /// Surfaces found.
        surfaces: usize,
    },
    /// The folds' recognizers know different classes (a surface missing from some training
    /// folds), so their decisions cannot be pooled.
    #[error(
        "fold {fold}'s recognizer knows the classes [{}] but fold 1's knows [{}]: every surface \
         must have recordings in every training fold",
        got.join(", "),
        expected.join(", ")
    )]
    FoldClasses {
        /// The fold whose classes differ.
        fold: usize,
        /// Its classes.
        got: Vec<String>,
        /// The first fold's classes.
        expected: Vec<String>,
    },
    /// All weights are zero: no classifier is reliable, so there is nothing to trust.
    #[error("all weights are zero")]
    ZeroTotalWeight,
}

/// A solver stopped short of an answer: raise its limit, or choose other hyperparameters.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SolverError {
    /// The SVM solvers rejected a problem or a setting.
    #[error("SVM solver")]
    Svm(#[from] svm::SvmError),
    /// The solver did not converge within its iteration limit.
    #[error(
        "SMO did not converge in {iterations} iterations at C = {c:e} (classes {first}, {second}): its largest KKT violation was {violation:.3e}, over its stop {stop:.1e}"
    )]
    NotConverged {
        /// Iterations run.
        iterations: usize,
        /// The box constraint of the failed fit.
        c: f64,
        /// First class of the pair.
        first: usize,
        /// Second class of the pair.
        second: usize,
        /// The largest KKT violation over the variables still active at the last selection.
        violation: f64,
        /// The violation it had to get below.
        stop: f64,
    },
    /// [`SolverError::NotConverged`] with the classes by name, as a recognizer knows them.
    #[error(
        "SMO did not converge in {iterations} iterations at C = {c:e} (classes `{first}` and `{second}`): its largest KKT violation was {violation:.3e}, over its stop {stop:.1e}"
    )]
    PairNotConverged {
        /// Iterations run.
        iterations: usize,
        /// The box constraint of the failed fit.
        c: f64,
        /// First class of the pair.
        first: String,
        /// Second class of the pair.
        second: String,
        /// The largest KKT violation over the variables still active at the last selection.
        violation: f64,
        /// The violation it had to get below.
        stop: f64,
    },
    /// No candidate of a C search could be fitted.
    #[error("every candidate C failed: {}", c_failures(failures))]
    EveryCFailed {
        /// Each candidate and why its fit failed.
        failures: Vec<(f64, RecognizeError)>,
    },
}

/// Arguments that do not fit together, passed through the library: a bug in the caller,
/// not in the data.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum UsageError {
    /// Feature vectors have no values.
    #[error("feature vectors are empty")]
    ZeroDimension,
    /// Features and labels (or groups) differ in count, or there are none.
    #[error("{features} feature vectors and {labels} labels: need equal, non-zero counts")]
    Counts {
        /// Feature vectors given.
        features: usize,
        /// Labels (or groups) given.
        labels: usize,
    },
    /// A caller's buffer does not fit the classifier it is used with (made for another one).
    #[error("the {what} buffer holds {got} values, expected {expected}: it was made for another classifier")]
    Buffer {
        /// Which buffer.
        what: &'static str,
        /// Its length.
        got: usize,
        /// The classifier's.
        expected: usize,
    },
    /// A vector has the wrong dimension.
    #[error("vector {index} has {got} values, expected {expected}")]
    Dimension {
        /// Index of the vector (0 for a query).
        index: usize,
        /// Dimension of the training data (or the map).
        expected: usize,
        /// Dimension found.
        got: usize,
    },
    /// A label is not below the class count.
    #[error("label {label} of point {index} is not below the class count {classes}")]
    LabelOutOfRange {
        /// Index of the point.
        index: usize,
        /// The label.
        label: usize,
        /// Number of classes.
        classes: usize,
    },
    /// Nothing to fuse.
    #[error("no classifiers to fuse")]
    NothingToFuse,
    /// Probability vectors and weights differ in count.
    #[error("{probabilities} probability vectors but {weights} weights")]
    WeightCount {
        /// Probability vectors.
        probabilities: usize,
        /// Weights.
        weights: usize,
    },
    /// Probability vectors and decisions differ in count.
    #[error("{probabilities} probability vectors but {labels} decisions")]
    LabelCount {
        /// Probability vectors.
        probabilities: usize,
        /// Decisions.
        labels: usize,
    },
    /// Probability vectors differ in length.
    #[error("classifier {index} gives {got} class probabilities, expected {expected}")]
    FusionClasses {
        /// Index of the classifier.
        index: usize,
        /// Classes of the first classifier.
        expected: usize,
        /// Classes of this one.
        got: usize,
    },
    /// A weight is negative or not finite.
    #[error("weight {index} is {weight}; weights must be finite and non-negative")]
    BadWeight {
        /// Index of the classifier.
        index: usize,
        /// The weight.
        weight: f64,
    },
    /// A query gives a feature vector per behaviour; this one has the wrong count.
    #[error("{queries} queries for {behaviours} behaviours")]
    QueryCount {
        /// Queries given.
        queries: usize,
        /// Behaviours fitted.
        behaviours: usize,
    },
    /// The signals passed in differ in length.
    #[error("signals differ in length: position {position}, height {height}, friction {friction}")]
    SignalLengths {
        /// Samples of position.
        position: usize,
        /// Samples of height.
        height: usize,
        /// Samples of friction.
        friction: usize,
    },
    /// A window (with the filter's margin each side) does not fit in the signal.
    #[error(
        "window of {len} samples at {start} needs samples {start}-{margin}..{start}+{len}+{margin} \
         (filter margin {margin}), but the signal has {samples}"
    )]
    WindowOutOfRange {
        /// First sample of the window.
        start: usize,
        /// Samples in the window.
        len: usize,
        /// Filter margin needed on each side.
        margin: usize,
        /// Samples available.
        samples: usize,
    },
    /// A label is not one of the confusion matrix's classes.
    #[error("confusion matrix: label {0} is not one of the classes")]
    UnknownLabel(String),
    /// Two confusion matrices over different classes cannot be merged.
    #[error("confusion matrices over different classes")]
    MatrixClasses,
    /// The same class was given twice to a confusion matrix.
    #[error("confusion matrix: class {0} given twice")]
    DuplicateClass(String),
    /// A matrix has no rows, or there are no indices to cut.
    #[error("empty matrix or index set")]
    EmptyMatrix,
    /// Row `row` has `len` entries instead of `n`.
    #[error("matrix is not square: row {row} has {len} entries, expected {n}")]
    NotSquare {
        /// The row.
        row: usize,
        /// Its entries.
        len: usize,
        /// Rows of the matrix.
        n: usize,
    },
    /// A matrix entry is NaN or infinite.
    #[error("entry ({row}, {col}) is not finite")]
    NonFiniteEntry {
        /// Row of the entry.
        row: usize,
        /// Column of the entry.
        col: usize,
    },
    /// A similarity or distance is negative.
    #[error("entry ({row}, {col}) is negative: {value}")]
    Negative {
        /// Row of the entry.
        row: usize,
        /// Column of the entry.
        col: usize,
        /// The entry.
        value: f64,
    },
    /// `m[i][j]` and `m[j][i]` differ.
    #[error("matrix is not symmetric at ({row}, {col})")]
    Asymmetric {
        /// Row of the entry.
        row: usize,
        /// Column of the entry.
        col: usize,
    },
    /// An index to cut is out of range or repeated.
    #[error("index {index} is out of range or repeated (matrix has {n} rows)")]
    BadIndex {
        /// The index.
        index: usize,
        /// Rows of the matrix.
        n: usize,
    },
    /// No capture gave a training vector.
    /// A capture whose samples were dropped ([`crate::LabelledCapture::keep_features`]) was
    /// asked for features it did not keep.
    #[error("{}: its samples were dropped after computing its features, and {needed} were not among them", path.display())]
    FeaturesNotKept {
        /// The capture.
        path: PathBuf,
        /// The features asked for.
        needed: String,
    },
    /// The FFT library rejected a buffer (a bug here, not bad input).
    #[error("FFT failed")]
    Fft(#[from] fft::FftError),
}

/// Each failed C and its reason, one after the other.
fn c_failures(failures: &[(f64, RecognizeError)]) -> String {
    failures
        .iter()
        .map(|(c, e)| format!("C = {c:e}: {e}"))
        .collect::<Vec<_>>()
        .join("; ")
}

/// The captures and their reasons, one after the other.
fn windowless_list(captures: &[WindowlessCapture]) -> String {
    captures
        .iter()
        .map(ToString::to_string)
        .collect::<Vec<_>>()
        .join("; ")
}

// The lower crates' errors convert into the group they belong to, so that `?` works on them
// wherever this crate returns a `RecognizeError`.
impl From<CaptureError> for RecognizeError {
    fn from(e: CaptureError) -> Self {
        Self::Input(InputError::Capture(Box::new(e)))
    }
}

impl From<svm::SvmError> for RecognizeError {
    fn from(e: svm::SvmError) -> Self {
        Self::Solver(SolverError::Svm(e))
    }
}

impl From<fft::FftError> for RecognizeError {
    fn from(e: fft::FftError) -> Self {
        Self::Usage(UsageError::Fft(e))
    }
}

impl RecognizeError {
    /// The error and its sources, outer to inner, on one line, as the command line prints
    /// them.
    pub fn chain(&self) -> String {
        let mut text = self.to_string();
        let mut source = std::error::Error::source(self);
        while let Some(s) = source {
            text.push_str(": ");
            text.push_str(&s.to_string());
            source = s.source();
        }
        text
    }

    /// Whether it is, or was caused by, a solver's time budget running out
    /// ([`svm::SvmError::Budget`]).
    pub fn ran_out_of_time(&self) -> bool {
        let mut source: Option<&(dyn std::error::Error + 'static)> = Some(self);
        while let Some(s) = source {
            if let Some(svm::SvmError::Budget { .. }) = s.downcast_ref::<svm::SvmError>() {
                return true;
            }
            source = s.source();
        }
        false
    }

    /// Wraps a k-NN's error, naming the classifier's behaviour (none for one over windows).
    pub(crate) fn knn(behaviour: Option<&str>) -> impl Fn(Self) -> Self + '_ {
        Self::classifier("k-NN", behaviour)
    }

    /// Wraps an SVC's error, naming the classifier's behaviour (none for one over windows).
    pub(crate) fn svc(behaviour: Option<&str>) -> impl Fn(Self) -> Self + '_ {
        Self::classifier("SVC", behaviour)
    }

    /// Puts class names on the classes that `self` (or a failure it lists) gives by index into
    /// `classes`; anything else unchanged.
    pub(crate) fn with_class_names(self, classes: &[String]) -> Self {
        let name = |i: usize| classes.get(i).cloned().unwrap_or_else(|| format!("#{i}"));
        match self {
            Self::Solver(SolverError::NotConverged {
                iterations,
                c,
                first,
                second,
                violation,
                stop,
            }) => Self::Solver(SolverError::PairNotConverged {
                iterations,
                c,
                first: name(first),
                second: name(second),
                violation,
                stop,
            }),
            Self::Solver(SolverError::EveryCFailed { failures }) => Self::Solver(SolverError::EveryCFailed {
                failures: failures
                    .into_iter()
                    .map(|(c, e)| (c, e.with_class_names(classes)))
                    .collect(),
            }),
            e => e,
        }
    }

    fn classifier<'a>(classifier: &'static str, behaviour: Option<&'a str>) -> impl Fn(Self) -> Self + 'a {
        move |source| Self::Classifier {
            classifier,
            behaviour: behaviour.unwrap_or_default().to_owned(),
            source: Box::new(source),
        }
    }

    /// A Nakano configuration that cannot be used.
    pub(crate) fn nakano_config(reason: &'static str) -> Self {
        Self::Setting(SettingError::Config {
            of: "Nakano configuration",
            reason,
        })
    }

    /// A category computation's parameter that cannot be used.
    pub(crate) fn category_config(reason: &'static str) -> Self {
        Self::Setting(SettingError::Config {
            of: "category parameter",
            reason,
        })
    }

    /// Wraps the self-organizing map's error.
    pub(crate) fn som(source: Self) -> Self {
        Self::Som(Box::new(source))
    }

    /// A recognizer file's failures keep this crate's own variants, with the same messages;
    /// anything else the JSON reader reports stays a capture-crate error.
    pub(crate) fn from_json_file(e: CaptureError) -> Self {
        let path = e.file.clone().unwrap_or_default();
        match e.kind {
            CaptureErrorKind::Io(source) => Self::Input(InputError::Io { path, source }),
            CaptureErrorKind::Json(reason) => Self::Input(InputError::Parse {
                path,
                line: e.line.unwrap_or_default(),
                reason,
            }),
            CaptureErrorKind::Invalid { field, reason } => {
                Self::Input(InputError::Invalid { path, field, reason })
            }
            kind => Self::Input(InputError::Capture(Box::new(CaptureError { kind, ..e }))),
        }
    }
}
