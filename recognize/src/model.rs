//! Surface recognizers on disk: self-describing JSON, validated on load, and the offline
//! pipeline that trains and evaluates them on labelled captures.
//!
//! A recognizer file names its method (Nakano's SOM over sliding windows, or Sinapov's k-NN
//! over one scratch per capture), the classes in label order, how features are computed (filters,
//! window, hop, sample rate; or the histogram's cell scaling), the trained map or training set
//! with its feature scaling, and a SHA-256 of each training capture and of all of them together.
//! Loading checks the format, the version and every shape, so a truncated or hand-edited file is
//! a typed error naming the file and the field — never a wrong label on the haptic thread.
//!
//! **Labels** come from each capture's metadata: `surface` is the class, and `behaviour` (for
//! scratches) picks which k-NN answers. **Windows** of the SOM start at
//! `lookahead + k · hop` samples (the first sample whose zero-phase filters are complete, then
//! every hop) and only once the tip has travelled [`NakanoWindowing::start_travel_m`] from the
//! capture's first sample, as the thesis starts recognising after 5 mm; a live recognizer fed
//! the same samples makes its decisions on exactly these windows.

use std::borrow::Borrow;
use std::collections::BTreeSet;
use std::io::{self, Read};
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::eval::{ConfusionMatrix, EvalError};
use super::knn::{FusionError, Knn, KnnError, KnnParams, argmax, fuse};
use super::nakano::{FEATURES, NakanoConfig, NakanoError, NakanoSignals};
use super::som::{Som, SomError, SomParams};
use super::spectral::{CellScale, SpectralError, SpectrogramPlan};
use super::svc::{CSearch, Svc, SvcError, SvcParams, select_c};
use capture::{Capture, CaptureError, CaptureKind, write_atomically};
use capture::{CaptureRef, sha256_hex};

mod features;
pub use features::{
    BehaviourSom, FeatureSet, SCRATCH_SOM_NORMALIZATION, WINDOW_SVM_FALLBACK_C, WindowScaling, som_nodes,
    som_params, window_svc_params,
};

/// Format name in every recognizer file.
pub const RECOGNIZER_FORMAT: &str = "palpus-recognizer";
/// Current recognizer file version.
pub const RECOGNIZER_VERSION: u32 = 1;
/// Metadata key of a capture's class.
pub const LABEL_KEY: &str = "surface";
/// Metadata key of a scratch's exploratory behaviour.
pub const BEHAVIOUR_KEY: &str = "behaviour";
/// Metadata key of a scratch's trial: the scratches of one object by several behaviours share
/// its surface and trial (`palpus gen --only sinapov` writes `trial=0…9`).
pub const TRIAL_KEY: &str = "trial";
/// Most folds of the cross-validations run on the training captures of a k-NN or SVM
/// recognizer (reliability weights, the SVM's C); fewer when there are fewer trials.
pub const CV_FOLDS: usize = 5;

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

/// A capture with its class, behaviour and hash, as the recognizer sees it.
#[derive(Debug, Clone)]
pub struct LabelledCapture {
    /// The capture.
    pub capture: Capture,
    /// Its class (metadata `surface`).
    pub label: String,
    /// Its exploratory behaviour (metadata `behaviour`), if any.
    pub behaviour: Option<String>,
    /// Where it was read from, and the SHA-256 of its bytes.
    pub reference: CaptureRef,
}

impl LabelledCapture {
    /// Reads a `rubbing` capture and its label; a capture without a `surface` in its metadata
    /// is an error naming the file.
    pub fn read(path: &Path) -> Result<Self, RecognizerError> {
        let bytes = std::fs::read(path).map_err(|source| RecognizerError::Io {
            path: path.to_owned(),
            source,
        })?;
        let capture = Capture::read_from(bytes.as_slice(), path, Some(CaptureKind::Rubbing))?;
        Self::new(capture, path, sha256_hex(&bytes))
    }

    /// Labels a capture already in memory; `path` and `sha256` identify it in the model.
    pub fn new(capture: Capture, path: &Path, sha256: String) -> Result<Self, RecognizerError> {
        let meta = capture.metadata();
        let label = meta
            .get(LABEL_KEY)
            .filter(|l| !l.is_empty())
            .ok_or_else(|| RecognizerError::UnusableCapture {
                path: path.to_owned(),
                reason: format!("metadata has no `{LABEL_KEY}`: the class of a capture comes from it"),
            })?
            .to_owned();
        let behaviour = meta.get(BEHAVIOUR_KEY).map(str::to_owned);
        Ok(Self {
            capture,
            label,
            behaviour,
            reference: CaptureRef {
                path: path.to_owned(),
                sha256,
            },
        })
    }
}

/// Default decision window of a SOM recognizer, s (15 mm of travel at 5 mm/s).
pub const DECISION_WINDOW_S: f64 = 3.0;
/// Default training window of a SOM recognizer, s (5 mm of travel at 5 mm/s).
pub const TRAINING_WINDOW_S: f64 = 1.0;
/// Default time between a SOM recognizer's decisions, s.
pub const HOP_S: f64 = 0.1;

/// How a rubbing stream is cut into the windows the map decides on.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct NakanoWindowing {
    /// The two zero-phase moving averages.
    pub filters: NakanoConfig,
    /// Samples per decision window.
    pub window_samples: usize,
    /// Samples per window the map was trained on, when not [`NakanoWindowing::window_samples`]
    /// (see [`NakanoWindowing::with_training_window_s`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub training_window_samples: Option<usize>,
    /// Samples between decisions.
    pub hop_samples: usize,
    /// No decision on a window that starts before this travel from the first sample, m.
    pub start_travel_m: f64,
    /// Sample rate the windows are counted at, Hz.
    pub rate_hz: f64,
}

impl NakanoWindowing {
    /// The protocol's windowing: `window_s` and `hop_s` at `rate_hz`, the filters at that rate
    /// ([`NakanoConfig::at_rate`]: the same travel whatever the rate), and decisions from 5 mm
    /// of travel on (thesis Sec. 4.3).
    pub fn new(window_s: f64, hop_s: f64, rate_hz: f64) -> Result<Self, RecognizerError> {
        if !(rate_hz.is_finite() && rate_hz > 0.0 && rate_hz <= 1e6) {
            return Err(RecognizerError::Setting {
                name: "rate_hz",
                value: rate_hz,
                reason: "positive and at most 10^6 Hz",
            });
        }
        let windowing = Self {
            filters: NakanoConfig::at_rate(rate_hz).map_err(|_| RecognizerError::Setting {
                name: "rate_hz",
                value: rate_hz,
                reason: "a rate at which Nakano's filters span whole samples",
            })?,
            window_samples: samples("window_s", window_s, rate_hz)?,
            training_window_samples: None,
            hop_samples: samples("hop_s", hop_s, rate_hz)?,
            start_travel_m: 0.005,
            rate_hz,
        };
        windowing.check().map_err(setting_error)?;
        Ok(windowing)
    }

    /// The defaults at `rate_hz`: [`TRAINING_WINDOW_S`] windows to train on,
    /// [`DECISION_WINDOW_S`] windows to decide on, every [`HOP_S`].
    pub fn protocol(rate_hz: f64) -> Result<Self, RecognizerError> {
        Self::new(DECISION_WINDOW_S, HOP_S, rate_hz)?.with_training_window_s(TRAINING_WINDOW_S)
    }

    /// The same windowing with a decision window of `window_s` instead.
    pub fn with_window_s(self, window_s: f64) -> Result<Self, RecognizerError> {
        let windowing = Self {
            window_samples: samples("window_s", window_s, self.rate_hz)?,
            ..self
        };
        windowing.check().map_err(setting_error)?;
        Ok(windowing)
    }

    /// The same windowing, trained on windows of `training_window_s`.
    ///
    /// Trained on one run per surface, a map learns each surface's spread from that run's
    /// windows only. Short training windows give it many, varied windows (the spread a surface
    /// shows from place to place), while long decision windows average more roughness waves
    /// into each decision: a 1 s training window with a 3 s decision window recognizes every
    /// Nakano surface at ≥ 95 % (`tests/recognition_nakano.rs`) where 1 s / 1 s does not.
    pub fn with_training_window_s(self, training_window_s: f64) -> Result<Self, RecognizerError> {
        let windowing = Self {
            training_window_samples: Some(samples("training_window_s", training_window_s, self.rate_hz)?),
            ..self
        };
        windowing.check().map_err(setting_error)?;
        Ok(windowing)
    }

    /// The windowing the map was trained with.
    pub fn training(&self) -> Self {
        Self {
            window_samples: self.training_window_samples.unwrap_or(self.window_samples),
            training_window_samples: None,
            ..*self
        }
    }

    /// Length of the training windows, s.
    pub fn training_window_s(&self) -> f64 {
        self.training().window_s()
    }

    /// The first setting out of range: its name, its value and what it must be. The bounds
    /// keep a hand-edited recognizer file from sizing buffers past memory or overflowing the
    /// filters' sample arithmetic.
    fn check(&self) -> Result<(), (&'static str, f64, &'static str)> {
        const MAX_HALF_WIDTH: usize = 1_000_000;
        const MAX_WINDOW: usize = 10_000_000;
        let windows = [
            ("window_samples", Some(self.window_samples)),
            ("training_window_samples", self.training_window_samples),
        ];
        for (name, n) in windows {
            if let Some(n) = n
                && !(2..=MAX_WINDOW).contains(&n)
            {
                return Err((name, n as f64, "from 2 to 10^7 samples"));
            }
        }
        if !(1..=MAX_WINDOW).contains(&self.hop_samples) {
            return Err(("hop_samples", self.hop_samples as f64, "from 1 to 10^7 samples"));
        }
        let filters = [
            ("filters.highpass_half_width", self.filters.highpass_half_width, 1),
            (
                "filters.smoothing_half_width",
                self.filters.smoothing_half_width,
                0,
            ),
        ];
        for (name, n, least) in filters {
            if !(least..=MAX_HALF_WIDTH).contains(&n) {
                let reason = if least == 1 {
                    "from 1 to 10^6 samples (the rate is too low for the roughness filter)"
                } else {
                    "at most 10^6 samples"
                };
                return Err((name, n as f64, reason));
            }
        }
        if !(self.start_travel_m.is_finite() && self.start_travel_m >= 0.0) {
            return Err(("start_travel_m", self.start_travel_m, "finite and not negative"));
        }
        if !(self.rate_hz.is_finite() && self.rate_hz > 0.0 && self.rate_hz <= 1e6) {
            return Err(("rate_hz", self.rate_hz, "positive and at most 10^6 Hz"));
        }
        Ok(())
    }

    /// Window length, s.
    pub fn window_s(&self) -> f64 {
        self.window_samples as f64 / self.rate_hz
    }

    /// From a window's first sample to the sample that completes it (the window plus the
    /// filters' lookahead), s: how old the oldest sample of a decision is.
    pub fn decision_latency_s(&self) -> f64 {
        (self.window_samples + self.filters.lookahead_samples()) as f64 / self.rate_hz
    }

    /// Whether a window starting at sample `start`, `travel_m` from the first sample, is
    /// decided on.
    pub fn is_decision_window(&self, start: u64, travel_m: f64) -> bool {
        let margin = self.filters.lookahead_samples() as u64;
        start >= margin
            && (start - margin).is_multiple_of(self.hop_samples as u64)
            && travel_m >= self.start_travel_m
    }

    /// The sample at which the window starting at `start` is complete.
    pub fn decided_at(&self, start: usize) -> usize {
        start + self.window_samples - 1 + self.filters.lookahead_samples()
    }
}

fn setting_error((name, value, reason): (&'static str, f64, &'static str)) -> RecognizerError {
    RecognizerError::Setting { name, value, reason }
}

fn samples(name: &'static str, seconds: f64, rate_hz: f64) -> Result<usize, RecognizerError> {
    let n = (seconds * rate_hz).round();
    if !(seconds.is_finite() && seconds > 0.0 && (1.0..=1e7).contains(&n)) {
        return Err(RecognizerError::Setting {
            name,
            value: seconds,
            reason: "positive, at least one sample and at most 10^7 samples",
        });
    }
    Ok(n as usize)
}

/// One behaviour's k-NN.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BehaviourKnn {
    /// The behaviour (metadata `behaviour`); `None` for captures without one.
    pub behaviour: Option<String>,
    /// Its classifier over spectrotemporal histograms.
    pub knn: Knn,
    /// Its accuracy under cross-validation by trial on the training captures (see
    /// [`trial_groups`]): its weight when behaviours are fused. `None` in files written before
    /// weights were stored, and when the training captures could not be cross-validated (fewer
    /// than two trials, or fewer than k scratches outside a fold); see
    /// [`RecognizerFile::fusion_weights`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reliability: Option<f64>,
    /// Folds of that cross-validation.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reliability_folds: Option<usize>,
}

/// One behaviour's SVC.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BehaviourSvc {
    /// The behaviour (metadata `behaviour`); `None` for captures without one.
    pub behaviour: Option<String>,
    /// Its one-vs-one SVC over spectrotemporal histograms, with probabilities.
    pub svc: Svc,
    /// Its accuracy, at its C, under cross-validation by trial on the training captures: its
    /// weight when behaviours are fused (as [`BehaviourKnn::reliability`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reliability: Option<f64>,
    /// How its C was chosen: every candidate's cross-validated accuracy (one candidate when C
    /// was given). `None` in older files and when the training captures could not be
    /// cross-validated (then C is [`SvmC::FALLBACK`] or the one given).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub c_search: Option<CSearch>,
}

/// How an SVM recognizer's C is set.
#[derive(Debug, Clone, PartialEq)]
pub enum SvmC {
    /// Per behaviour, the candidate with the best accuracy under cross-validation by trial on
    /// that behaviour's training captures; ties go to the smaller C.
    Auto(Vec<f64>),
    /// This C for every behaviour.
    Fixed(f64),
}

impl SvmC {
    /// C of a behaviour whose training captures cannot be cross-validated (fewer than two
    /// trials) under [`SvmC::Auto`]: large enough for the hard-margin machine that separable
    /// histograms get (see [`SvcParams::default`]).
    pub const FALLBACK: f64 = 1e4;

    /// [`SvmC::Auto`] over [`super::svc::C_GRID`].
    pub fn auto() -> Self {
        Self::Auto(super::svc::C_GRID.to_vec())
    }
}

/// A behaviour's reliability weight (cross-validated accuracy), as the training summary shows
/// it.
#[derive(Debug, Clone, PartialEq)]
pub struct BehaviourReliability<'a> {
    /// The behaviour.
    pub behaviour: Option<&'a str>,
    /// Its cross-validated accuracy, if any.
    pub reliability: Option<f64>,
    /// Folds of the cross-validation.
    pub folds: Option<usize>,
    /// For an SVM: how C was chosen, and the C in use.
    pub c_search: Option<&'a CSearch>,
    /// For an SVM: the C in use.
    pub c: Option<f64>,
}

/// The trained classifier and how its features are computed.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "method", rename_all = "snake_case")]
// One body per recognizer file, never in a hot collection: the SOM variant carries its map inline.
#[allow(clippy::large_enum_variant)]
pub enum RecognizerBody {
    /// Nakano: five rubbing features over sliding windows, a 1-D SOM (node labels are class
    /// indices).
    Som {
        /// The windows.
        windowing: NakanoWindowing,
        /// The map, with its feature scaling.
        som: Som<usize>,
    },
    /// Sinapov: one spectrotemporal histogram per scratch, one k-NN per behaviour.
    Knn {
        /// The histogram's cell scaling.
        cell_scale: CellScale,
        /// One classifier per behaviour seen in training.
        behaviours: Vec<BehaviourKnn>,
    },
    /// Sinapov: one spectrotemporal histogram per scratch, one SVC (degree-2 polynomial
    /// kernel, pairwise-coupled probabilities) per behaviour.
    Svm {
        /// The histogram's cell scaling.
        cell_scale: CellScale,
        /// One classifier per behaviour seen in training.
        behaviours: Vec<BehaviourSvc>,
    },
    /// k-NN over rubbing windows (`--features nakano|both`), windowed like the SOM.
    KnnWindows {
        /// `nakano` or `both`.
        features: FeatureSet,
        /// The windows.
        windowing: NakanoWindowing,
        /// For `both`: the window histogram's cell scaling.
        #[serde(default)]
        cell_scale: CellScale,
        /// The feature scaling learned from the training windows.
        scaling: WindowScaling,
        /// The classifier over scaled windows.
        knn: Knn,
    },
    /// C-SVC (degree-2 polynomial kernel) over rubbing windows (`--features nakano|both`).
    SvmWindows {
        /// `nakano` or `both`.
        features: FeatureSet,
        /// The windows.
        windowing: NakanoWindowing,
        /// For `both`: the window histogram's cell scaling.
        #[serde(default)]
        cell_scale: CellScale,
        /// The feature scaling learned from the training windows.
        scaling: WindowScaling,
        /// The classifier over scaled windows.
        svc: Svc,
        /// How C was chosen; `None` when the training captures could not be cross-validated.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        c_search: Option<CSearch>,
    },
    /// A SOM over rubbing windows of Nakano's features and the window's histogram
    /// (`--features both`).
    SomWindows {
        /// The windows.
        windowing: NakanoWindowing,
        /// The window histogram's cell scaling.
        #[serde(default)]
        cell_scale: CellScale,
        /// The map, with its feature scaling.
        som: Som<usize>,
    },
    /// One SOM per behaviour over the histograms of whole scratches (`--features spectral`).
    SomScratches {
        /// The histogram's cell scaling.
        cell_scale: CellScale,
        /// One map per behaviour seen in training.
        behaviours: Vec<BehaviourSom>,
    },
}

impl RecognizerBody {
    /// `som`, `knn` or `svm`.
    pub fn method(&self) -> &'static str {
        match self {
            Self::Som { .. } | Self::SomWindows { .. } | Self::SomScratches { .. } => "som",
            Self::Knn { .. } | Self::KnnWindows { .. } => "knn",
            Self::Svm { .. } | Self::SvmWindows { .. } => "svm",
        }
    }

    /// The features the body's classifiers take.
    pub fn feature_set(&self) -> FeatureSet {
        match self {
            Self::Som { .. } => FeatureSet::Nakano,
            Self::Knn { .. } | Self::Svm { .. } | Self::SomScratches { .. } => FeatureSet::Spectral,
            Self::SomWindows { .. } => FeatureSet::Both,
            Self::KnnWindows { features, .. } | Self::SvmWindows { features, .. } => *features,
        }
    }

    /// Whether it classifies whole scratches, one classifier per behaviour (and fuses them).
    fn is_scratch(&self) -> bool {
        matches!(
            self,
            Self::Knn { .. } | Self::Svm { .. } | Self::SomScratches { .. }
        )
    }
}

/// A whole recognizer file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RecognizerFile {
    /// Always [`RECOGNIZER_FORMAT`].
    pub format: String,
    /// Always [`RECOGNIZER_VERSION`] when written by this version.
    pub version: u32,
    /// Class names; labels inside the body index this list.
    pub classes: Vec<String>,
    /// Which features (`nakano`, `spectral`, `both`). Absent in files written before the
    /// choice existed: then the method's own ([`RecognizerBody::feature_set`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub features: Option<FeatureSet>,
    /// Names of the features, in vector order, with units.
    pub feature_names: Vec<String>,
    /// The classifier.
    pub body: RecognizerBody,
    /// What it was trained on.
    pub training: Vec<CaptureRef>,
    /// SHA-256 over the training captures' hashes, in order (one value to compare models by).
    pub training_sha256: String,
    /// Number of training vectors.
    pub n_train: usize,
}

/// One decision of the offline pipeline.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Decision {
    /// First sample of the window (0 for a whole-capture decision).
    pub window_start: usize,
    /// The sample at which the decision is available.
    pub decided_at: usize,
    /// Index into [`RecognizerFile::classes`].
    pub label: usize,
    /// Confidence in `[0, 1]` (see [`Som::decide_into`]; k-NN: the vote fraction).
    pub confidence: f64,
}

/// One behaviour's scratches classified alone, in a [`FusedEvaluation`].
#[derive(Debug, Clone)]
pub struct BehaviourScore {
    /// The behaviour.
    pub behaviour: Option<String>,
    /// Its weight in the fusion.
    pub weight: f64,
    /// Its scratches, by true and predicted class.
    pub confusion: ConfusionMatrix<String>,
}

/// Result of fusing the behaviours of each trial (Sinapov Sec. IV-C).
///
/// The evaluated captures are grouped by surface and [`TRIAL_KEY`]: a group is one object
/// explored by one or more behaviours; a capture without a trial is a group of its own. Each
/// group gets one decision, the argmax of its scratches' class probabilities averaged with the
/// behaviours' weights ([`RecognizerFile::fusion_weights`], [`fuse`]).
#[derive(Debug, Clone)]
pub struct FusedEvaluation {
    /// One decision per group, by true and predicted class.
    pub confusion: ConfusionMatrix<String>,
    /// Groups (trials) evaluated.
    pub groups: usize,
    /// Groups of more than one scratch.
    pub multi_scratch_groups: usize,
    /// Each behaviour of the recognizer that occurs in the evaluated captures, alone.
    pub per_behaviour: Vec<BehaviourScore>,
}

impl FusedEvaluation {
    /// The best accuracy of a single behaviour alone.
    pub fn best_single_accuracy(&self) -> Option<f64> {
        self.per_behaviour
            .iter()
            .filter_map(|b| b.confusion.accuracy())
            .reduce(f64::max)
    }
}

/// A SOM's fit to a set of windows ([`RecognizerFile::som_quality`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SomQuality {
    /// Mean distance from each scaled window to its winner's reference vector.
    pub quantization_error: f64,
    /// Fraction of windows whose two best nodes are not neighbours on the line.
    pub topographic_error: f64,
    /// Windows measured.
    pub windows: usize,
}

/// Result of evaluating a recognizer on labelled captures.
#[derive(Debug, Clone)]
pub struct Evaluation {
    /// `som` or `knn`.
    pub method: &'static str,
    /// Every decision, by true and predicted class.
    pub confusion: ConfusionMatrix<String>,
    /// Window length, s (k-NN: the mean capture duration, its window is the whole scratch).
    pub window_s: f64,
    /// From a window's first sample to its decision, s (k-NN: the mean capture duration).
    pub decision_latency_s: f64,
    /// Mean over captures with a correct decision of the time from the capture's first sample
    /// to the first correct decision, s.
    pub time_to_first_correct_s: Option<f64>,
    /// Mean over captures whose last decision is correct of the time from the first sample to
    /// the decision that starts the final run of correct decisions, s.
    pub time_to_stable_s: Option<f64>,
    /// Changes of decision per second of decisions (pooled over captures).
    pub flips_per_s: f64,
    /// Captures evaluated.
    pub captures: usize,
    /// Captures never recognized correctly.
    pub never_correct: usize,
    /// Captures whose last decision is wrong.
    pub not_stable: usize,
}

impl RecognizerFile {
    /// Trains Nakano's SOM on the training windows of `captures` (see
    /// [`NakanoWindowing::with_training_window_s`]); it decides on the decision windows.
    pub fn train_som(
        captures: &[LabelledCapture],
        windowing: NakanoWindowing,
        params: SomParams,
    ) -> Result<Self, RecognizerError> {
        let classes = class_list(captures);
        let (mut data, mut labels) = (Vec::new(), Vec::new());
        let training = windowing.training();
        for c in captures {
            check_rate(c, windowing.rate_hz)?;
            let label = class_index(&classes, c)?;
            for (_, features) in windows(c, &training)? {
                data.push(features.to_vec());
                labels.push(label);
            }
        }
        if data.is_empty() {
            return Err(RecognizerError::NoTrainingData);
        }
        let som = Som::train(params, &data, &labels)?;
        Ok(Self::assemble(
            classes,
            super::nakano::FEATURE_NAMES
                .iter()
                .map(|s| (*s).to_owned())
                .collect(),
            RecognizerBody::Som { windowing, som },
            captures,
            data.len(),
        ))
    }

    /// Trains Sinapov's k-NN on one histogram per capture, one classifier per behaviour.
    pub fn train_knn(
        captures: &[LabelledCapture],
        params: KnnParams,
        cell_scale: CellScale,
    ) -> Result<Self, RecognizerError> {
        let classes = class_list(captures);
        let mut behaviours = Vec::new();
        for (name, x, y, groups) in histograms_by_behaviour(captures, &classes, cell_scale)? {
            let knn = params
                .fit(&x, &y, classes.len())
                .map_err(|source| RecognizerError::Knn {
                    behaviour: name.unwrap_or("").to_owned(),
                    source,
                })?;
            // The fit above has checked the data, so a failing cross-validation only means
            // too few trials (or too few scratches outside a fold): no weight, see
            // `fusion_weights`.
            let cv = super::knn::group_folds(&groups, CV_FOLDS)
                .ok()
                .and_then(|(_, folds)| {
                    super::knn::cross_validated_accuracy(params, &x, &y, &groups, classes.len(), CV_FOLDS)
                        .ok()
                        .map(|accuracy| (accuracy, folds))
                });
            behaviours.push(BehaviourKnn {
                behaviour: name.map(str::to_owned),
                knn,
                reliability: cv.map(|(a, _)| a),
                reliability_folds: cv.map(|(_, f)| f),
            });
        }
        if behaviours.is_empty() {
            return Err(RecognizerError::NoTrainingData);
        }
        Ok(Self::assemble(
            classes,
            histogram_names(),
            RecognizerBody::Knn {
                cell_scale,
                behaviours,
            },
            captures,
            captures.len(),
        ))
    }

    /// Trains one SVC per behaviour on one histogram per capture, with `params` but the C of
    /// `c`; each behaviour's C and reliability weight come from cross-validation by trial on
    /// its training captures (see [`trial_groups`]).
    ///
    /// C is chosen per behaviour: each behaviour has its own classifier over its own
    /// histograms (a fast lateral scratch and a slow poke differ in level and spread), and
    /// its reliability weight is the same cross-validation's accuracy at the chosen C. A
    /// behaviour with fewer than two trials cannot be cross-validated: it gets
    /// [`SvmC::FALLBACK`] (or the fixed C) and no weight.
    pub fn train_svm(
        captures: &[LabelledCapture],
        params: SvcParams,
        c: &SvmC,
        cell_scale: CellScale,
    ) -> Result<Self, RecognizerError> {
        let classes = class_list(captures);
        let data = histograms_by_behaviour(captures, &classes, cell_scale)?;
        // One behaviour per thread, as many as the machine has cores.
        let threads = std::thread::available_parallelism()
            .map_or(1, usize::from)
            .clamp(1, data.len().max(1));
        let fit_one =
            |(name, x, y, groups): &BehaviourHistograms<'_>| -> Result<BehaviourSvc, RecognizerError> {
                let svc_error = |source| RecognizerError::Svc {
                    behaviour: name.unwrap_or("").to_owned(),
                    source,
                };
                let grid = match c {
                    SvmC::Auto(grid) => grid.clone(),
                    SvmC::Fixed(c) => vec![*c],
                };
                let search = match select_c(params, &grid, x, y, groups, classes.len(), CV_FOLDS) {
                    Ok(search) => Some(search),
                    Err(SvcError::TooFewGroups { .. }) => None,
                    Err(e) => return Err(svc_error(e)),
                };
                let chosen = match (&search, c) {
                    (Some(s), _) => s.chosen_c,
                    (None, SvmC::Fixed(c)) => *c,
                    (None, SvmC::Auto(_)) => SvmC::FALLBACK,
                };
                let svc =
                    Svc::fit(SvcParams { c: chosen, ..params }, x, y, classes.len()).map_err(svc_error)?;
                Ok(BehaviourSvc {
                    behaviour: name.map(str::to_owned),
                    svc,
                    reliability: search.as_ref().and_then(CSearch::accuracy),
                    c_search: search,
                })
            };
        let mut behaviours = Vec::with_capacity(data.len());
        std::thread::scope(|scope| -> Result<(), RecognizerError> {
            let workers: Vec<_> = (0..threads)
                .map(|t| {
                    let (data, fit_one) = (&data, &fit_one);
                    scope.spawn(move || {
                        data.iter()
                            .enumerate()
                            .filter(|(i, _)| i % threads == t)
                            .map(|(i, d)| fit_one(d).map(|b| (i, b)))
                            .collect::<Result<Vec<_>, _>>()
                    })
                })
                .collect();
            let mut fitted = Vec::with_capacity(data.len());
            for w in workers {
                fitted.extend(
                    w.join()
                        .unwrap_or_else(|panic| std::panic::resume_unwind(panic))?,
                );
            }
            fitted.sort_by_key(|(i, _)| *i);
            behaviours.extend(fitted.into_iter().map(|(_, b)| b));
            Ok(())
        })?;
        if behaviours.is_empty() {
            return Err(RecognizerError::NoTrainingData);
        }
        Ok(Self::assemble(
            classes,
            histogram_names(),
            RecognizerBody::Svm {
                cell_scale,
                behaviours,
            },
            captures,
            captures.len(),
        ))
    }

    fn assemble(
        classes: Vec<String>,
        feature_names: Vec<String>,
        body: RecognizerBody,
        captures: &[LabelledCapture],
        n_train: usize,
    ) -> Self {
        let training: Vec<CaptureRef> = captures.iter().map(|c| c.reference.clone()).collect();
        let joined: String = training.iter().map(|r| r.sha256.as_str()).collect();
        Self {
            format: RECOGNIZER_FORMAT.to_owned(),
            version: RECOGNIZER_VERSION,
            classes,
            features: Some(body.feature_set()),
            feature_names,
            body,
            training,
            training_sha256: sha256_hex(joined.as_bytes()),
            n_train,
        }
    }

    /// `som`, `knn` or `svm`.
    pub fn method(&self) -> &'static str {
        self.body.method()
    }

    /// The features its classifiers take (see [`RecognizerFile::features`]).
    pub fn feature_set(&self) -> FeatureSet {
        self.features.unwrap_or_else(|| self.body.feature_set())
    }

    /// The windowing, for a recognizer over rubbing windows.
    pub fn windowing(&self) -> Option<&NakanoWindowing> {
        match &self.body {
            RecognizerBody::Som { windowing, .. }
            | RecognizerBody::KnnWindows { windowing, .. }
            | RecognizerBody::SvmWindows { windowing, .. }
            | RecognizerBody::SomWindows { windowing, .. } => Some(windowing),
            RecognizerBody::Knn { .. } | RecognizerBody::Svm { .. } | RecognizerBody::SomScratches { .. } => {
                None
            }
        }
    }

    /// The offline pipeline's decisions on one capture (`windowing` overrides the model's, for
    /// a SOM): one per decision window for a SOM, one per capture for a k-NN.
    pub fn decisions(
        &self,
        capture: &LabelledCapture,
        windowing: Option<&NakanoWindowing>,
    ) -> Result<Vec<Decision>, RecognizerError> {
        match &self.body {
            RecognizerBody::Som { windowing: own, som } => {
                let windowing = windowing.unwrap_or(own);
                check_rate(capture, windowing.rate_hz)?;
                let mut scratch = [0.0; FEATURES];
                windows(capture, windowing)?
                    .into_iter()
                    .map(|(start, features)| {
                        let d = som.decide_into(&features, &mut scratch)?;
                        Ok(Decision {
                            window_start: start,
                            decided_at: windowing.decided_at(start),
                            label: som.node_labels().get(d.node).copied().unwrap_or(0),
                            confidence: d.confidence,
                        })
                    })
                    .collect()
            }
            RecognizerBody::KnnWindows {
                features,
                windowing: own,
                cell_scale,
                scaling,
                knn,
            } => {
                let windowing = windowing.unwrap_or(own);
                self.window_decisions(capture, windowing, *features, *cell_scale, |v| {
                    let v = scaling.apply(v);
                    let knn_error = |source| RecognizerError::Knn {
                        behaviour: String::new(),
                        source,
                    };
                    let label = knn.predict(&v).map_err(knn_error)?;
                    let p = knn.predict_proba(&v).map_err(knn_error)?;
                    Ok((label, p.get(label).copied().unwrap_or(0.0)))
                })
            }
            RecognizerBody::SvmWindows {
                features,
                windowing: own,
                cell_scale,
                scaling,
                svc,
                ..
            } => {
                let windowing = windowing.unwrap_or(own);
                self.window_decisions(capture, windowing, *features, *cell_scale, |v| {
                    let v = scaling.apply(v);
                    let svc_error = |source| RecognizerError::Svc {
                        behaviour: String::new(),
                        source,
                    };
                    let label = svc.predict(&v).map_err(svc_error)?;
                    let p = svc.predict_proba(&v).map_err(svc_error)?;
                    Ok((label, p.get(label).copied().unwrap_or(0.0)))
                })
            }
            RecognizerBody::SomWindows {
                windowing: own,
                cell_scale,
                som,
            } => {
                let windowing = windowing.unwrap_or(own);
                let mut scratch = vec![0.0; som.dim()];
                self.window_decisions(capture, windowing, FeatureSet::Both, *cell_scale, |v| {
                    let d = som.decide_into(v, &mut scratch)?;
                    Ok((som.node_labels().get(d.node).copied().unwrap_or(0), d.confidence))
                })
            }
            RecognizerBody::Knn { .. } | RecognizerBody::Svm { .. } | RecognizerBody::SomScratches { .. } => {
                let (_, label, p) = self.scratch_prediction(capture, &SpectrogramPlan::new())?;
                Ok(vec![whole_capture_decision(capture, label, &p)])
            }
        }
    }

    /// Decisions of a classifier over rubbing windows: `classify` maps a window's raw features
    /// to a label and a confidence.
    fn window_decisions(
        &self,
        capture: &LabelledCapture,
        windowing: &NakanoWindowing,
        features: FeatureSet,
        cell_scale: CellScale,
        mut classify: impl FnMut(&[f64]) -> Result<(usize, f64), RecognizerError>,
    ) -> Result<Vec<Decision>, RecognizerError> {
        features.check_columns(std::slice::from_ref(capture))?;
        check_rate(capture, windowing.rate_hz)?;
        let plan = SpectrogramPlan::new();
        features::window_vectors(capture, windowing, features, cell_scale, &plan)?
            .into_iter()
            .map(|(start, v)| {
                let (label, confidence) = classify(&v)?;
                Ok(Decision {
                    window_start: start,
                    decided_at: windowing.decided_at(start),
                    label,
                    confidence,
                })
            })
            .collect()
    }

    /// For a k-NN or SVM recognizer: the index of the capture's behaviour among
    /// [`RecognizerFile::behaviour_names`], its classifier's label and class probabilities.
    fn scratch_prediction(
        &self,
        capture: &LabelledCapture,
        plan: &SpectrogramPlan,
    ) -> Result<(usize, usize, Vec<f64>), RecognizerError> {
        match &self.body {
            RecognizerBody::Som { .. }
            | RecognizerBody::SomWindows { .. }
            | RecognizerBody::KnnWindows { .. }
            | RecognizerBody::SvmWindows { .. } => Err(RecognizerError::UnusableCapture {
                path: capture.reference.path.clone(),
                reason: "a recognizer over rubbing windows does not classify whole scratches".into(),
            }),
            RecognizerBody::SomScratches {
                cell_scale,
                behaviours,
            } => {
                let b = behaviour_index(behaviours, |b| &b.behaviour, capture)?;
                let features = spectral(plan, capture, *cell_scale)?;
                let label = *behaviours[b].som.classify(&features)?;
                // A map answers one class: its "probabilities" are that class's indicator, so a
                // trial's fusion is a vote weighted by the behaviours' reliabilities.
                let mut p = vec![0.0; self.classes.len()];
                if let Some(slot) = p.get_mut(label) {
                    *slot = 1.0;
                }
                Ok((b, label, p))
            }
            RecognizerBody::Knn {
                cell_scale,
                behaviours,
            } => {
                let b = behaviour_index(behaviours, |b| &b.behaviour, capture)?;
                let features = spectral(plan, capture, *cell_scale)?;
                let knn_error = |source| RecognizerError::Knn {
                    behaviour: capture.behaviour.clone().unwrap_or_default(),
                    source,
                };
                let knn = &behaviours[b].knn;
                let label = knn.predict(&features).map_err(knn_error)?;
                Ok((b, label, knn.predict_proba(&features).map_err(knn_error)?))
            }
            RecognizerBody::Svm {
                cell_scale,
                behaviours,
            } => {
                let b = behaviour_index(behaviours, |b| &b.behaviour, capture)?;
                let features = spectral(plan, capture, *cell_scale)?;
                let svc_error = |source| RecognizerError::Svc {
                    behaviour: capture.behaviour.clone().unwrap_or_default(),
                    source,
                };
                let svc = &behaviours[b].svc;
                let label = svc.predict(&features).map_err(svc_error)?;
                Ok((b, label, svc.predict_proba(&features).map_err(svc_error)?))
            }
        }
    }

    /// The behaviours of a k-NN or SVM recognizer, in its classifiers' order (empty for a SOM).
    pub fn behaviour_names(&self) -> Vec<Option<&str>> {
        self.reliabilities().into_iter().map(|r| r.behaviour).collect()
    }

    /// Each behaviour's stored reliability (and, for an SVM, its C and how it was chosen), in
    /// the classifiers' order; empty for a SOM.
    pub fn reliabilities(&self) -> Vec<BehaviourReliability<'_>> {
        match &self.body {
            RecognizerBody::Som { .. }
            | RecognizerBody::SomWindows { .. }
            | RecognizerBody::KnnWindows { .. }
            | RecognizerBody::SvmWindows { .. } => Vec::new(),
            RecognizerBody::SomScratches { behaviours, .. } => features::som_reliabilities(behaviours),
            RecognizerBody::Knn { behaviours, .. } => behaviours
                .iter()
                .map(|b| BehaviourReliability {
                    behaviour: b.behaviour.as_deref(),
                    reliability: b.reliability,
                    folds: b.reliability_folds,
                    c_search: None,
                    c: None,
                })
                .collect(),
            RecognizerBody::Svm { behaviours, .. } => behaviours
                .iter()
                .map(|b| BehaviourReliability {
                    behaviour: b.behaviour.as_deref(),
                    reliability: b.reliability,
                    folds: b.c_search.as_ref().map(|s| s.folds),
                    c_search: b.c_search.as_ref(),
                    c: Some(b.svc.params().c),
                })
                .collect(),
        }
    }

    /// The weight of each behaviour (in [`RecognizerFile::behaviour_names`] order) when a
    /// trial's behaviours are fused: its stored reliability, or, where it has none (a file
    /// written before weights were stored, or a behaviour with too few trials to
    /// cross-validate), the mean of the others' stored reliabilities, or 1 when none has one
    /// (every behaviour weighs the same).
    pub fn fusion_weights(&self) -> Vec<f64> {
        let stored: Vec<Option<f64>> = self.reliabilities().iter().map(|r| r.reliability).collect();
        let known: Vec<f64> = stored.iter().flatten().copied().collect();
        let fallback = if known.is_empty() {
            1.0
        } else {
            known.iter().sum::<f64>() / known.len() as f64
        };
        stored.into_iter().map(|w| w.unwrap_or(fallback)).collect()
    }

    /// Fuses the behaviours of each trial of `captures` (see [`FusedEvaluation`]); `None` for a
    /// SOM recognizer.
    ///
    /// Groups whose behaviours all weigh 0 (each never classified a held-out trial right)
    /// are fused with equal weights instead.
    pub fn evaluate_fused<C: Borrow<LabelledCapture>>(
        &self,
        captures: &[C],
    ) -> Result<Option<FusedEvaluation>, RecognizerError> {
        if !self.body.is_scratch() {
            return Ok(None);
        }
        let names = self.behaviour_names();
        let weights = self.fusion_weights();
        let mut alone: Vec<Option<ConfusionMatrix<String>>> = vec![None; names.len()];
        let plan = SpectrogramPlan::new();
        // (surface, trial) → the group's (behaviour, probabilities); trial-less captures alone.
        let mut trials: std::collections::BTreeMap<(usize, String), TrialScratches> =
            std::collections::BTreeMap::new();
        let mut singles: Vec<(usize, TrialScratches)> = Vec::new();
        for c in captures {
            let c = c.borrow();
            let truth = class_index(&self.classes, c)?;
            let (b, label, p) = self.scratch_prediction(c, &plan)?;
            let matrix = match &mut alone[b] {
                Some(m) => m,
                slot => slot.insert(ConfusionMatrix::new(self.classes.clone())?),
            };
            matrix.add(&self.classes[truth], &self.classes[label])?;
            match trial_of(c) {
                Some(trial) => trials.entry((truth, trial.to_owned())).or_default().push((b, p)),
                None => singles.push((truth, vec![(b, p)])),
            }
        }
        let mut confusion = ConfusionMatrix::new(self.classes.clone())?;
        let mut multi_scratch_groups = 0;
        let groups: Vec<(usize, TrialScratches)> = trials
            .into_iter()
            .map(|((truth, _), members)| (truth, members))
            .chain(singles)
            .collect();
        for (truth, members) in &groups {
            multi_scratch_groups += usize::from(members.len() > 1);
            let p: Vec<&[f64]> = members.iter().map(|(_, p)| p.as_slice()).collect();
            let w: Vec<f64> = members.iter().map(|(b, _)| weights[*b]).collect();
            let fused = match fuse(&p, &w) {
                Err(FusionError::ZeroTotalWeight) => fuse(&p, &vec![1.0; p.len()]),
                other => other,
            }
            .map_err(|e| RecognizerError::UnusableCapture {
                path: PathBuf::from(&self.classes[*truth]),
                reason: format!("fusing a trial's behaviours: {e}"),
            })?;
            let label = argmax(&fused).unwrap_or(0);
            confusion.add(&self.classes[*truth], &self.classes[label])?;
        }
        let per_behaviour = alone
            .into_iter()
            .enumerate()
            .filter_map(|(b, m)| {
                m.map(|confusion| BehaviourScore {
                    behaviour: names[b].map(str::to_owned),
                    weight: weights[b],
                    confusion,
                })
            })
            .collect();
        Ok(Some(FusedEvaluation {
            confusion,
            groups: groups.len(),
            multi_scratch_groups,
            per_behaviour,
        }))
    }

    /// Evaluates on `captures`; `window_s` overrides a SOM's window length.
    pub fn evaluate<C: Borrow<LabelledCapture>>(
        &self,
        captures: &[C],
        window_s: Option<f64>,
    ) -> Result<Evaluation, RecognizerError> {
        let windowing = match (self.windowing(), window_s) {
            (Some(w), Some(s)) => Some(w.with_window_s(s)?),
            (w, _) => w.copied(),
        };
        let mut confusion = ConfusionMatrix::new(self.classes.clone())?;
        let (mut first, mut stable) = (Vec::new(), Vec::new());
        let (mut flips, mut span_s, mut duration_s) = (0usize, 0.0, 0.0);
        for c in captures {
            let c = c.borrow();
            let truth = class_index(&self.classes, c)?;
            let rate_hz = c.capture.metadata().rate_hz();
            duration_s += c.capture.len() as f64 / rate_hz;
            let decisions = self.decisions(c, windowing.as_ref())?;
            for d in &decisions {
                confusion.add(&self.classes[truth], &self.classes[d.label])?;
            }
            let at_s = |d: &Decision| d.decided_at as f64 / rate_hz;
            if let Some(d) = decisions.iter().find(|d| d.label == truth) {
                first.push(at_s(d));
            }
            if decisions.last().is_some_and(|d| d.label == truth) {
                let wrong = decisions.iter().rposition(|d| d.label != truth);
                stable.push(at_s(&decisions[wrong.map_or(0, |w| w + 1)]));
            }
            flips += decisions.windows(2).filter(|p| p[0].label != p[1].label).count();
            if let (Some(a), Some(b)) = (decisions.first(), decisions.last()) {
                span_s += at_s(b) - at_s(a);
            }
        }
        let mean = |v: &[f64]| (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64);
        let (window_s, decision_latency_s) = match &windowing {
            Some(w) => (w.window_s(), w.decision_latency_s()),
            None => {
                let mean_s = duration_s / captures.len().max(1) as f64;
                (mean_s, mean_s)
            }
        };
        Ok(Evaluation {
            method: self.method(),
            confusion,
            window_s,
            decision_latency_s,
            time_to_first_correct_s: mean(&first),
            time_to_stable_s: mean(&stable),
            flips_per_s: if span_s > 0.0 { flips as f64 / span_s } else { 0.0 },
            captures: captures.len(),
            never_correct: captures.len() - first.len(),
            not_stable: captures.len() - stable.len(),
        })
    }

    /// How well a SOM recognizer's map fits the windows of `captures` — its training windows
    /// when `training`, else its decision windows (of `window_s` when given, as
    /// [`RecognizerFile::evaluate`] takes them): the quantization and topographic errors
    /// (Kohonen's measures of fit and of order). `None` for other recognizers, or when no
    /// capture is long enough for a window.
    pub fn som_quality<C: Borrow<LabelledCapture>>(
        &self,
        captures: &[C],
        training: bool,
        window_s: Option<f64>,
    ) -> Result<Option<SomQuality>, RecognizerError> {
        let RecognizerBody::Som { windowing, som } = &self.body else {
            return Ok(None);
        };
        let windowing = match (training, window_s) {
            (true, _) => windowing.training(),
            (false, Some(s)) => windowing.with_window_s(s)?,
            (false, None) => *windowing,
        };
        let mut data = Vec::new();
        for c in captures {
            let c = c.borrow();
            check_rate(c, windowing.rate_hz)?;
            data.extend(windows(c, &windowing)?.into_iter().map(|(_, f)| f.to_vec()));
        }
        if data.is_empty() {
            return Ok(None);
        }
        Ok(Some(SomQuality {
            quantization_error: som.quantization_error(&data)?,
            topographic_error: som.topographic_error(&data)?,
            windows: data.len(),
        }))
    }

    /// Writes the recognizer atomically as pretty JSON.
    pub fn save(&self, path: &Path) -> Result<(), RecognizerError> {
        write_atomically(path, |w| {
            serde_json::to_writer_pretty(&mut *w, self).map_err(io::Error::other)
        })
        .map_err(|source| RecognizerError::Io {
            path: path.to_owned(),
            source,
        })
    }

    /// Reads and validates a recognizer file.
    pub fn load(path: &Path) -> Result<Self, RecognizerError> {
        let mut text = String::new();
        std::fs::File::open(path)
            .and_then(|mut f| f.read_to_string(&mut text))
            .map_err(|source| RecognizerError::Io {
                path: path.to_owned(),
                source,
            })?;
        Self::from_json(&text, path)
    }

    /// Parses and validates a recognizer; `path` names it in errors.
    pub fn from_json(text: &str, path: &Path) -> Result<Self, RecognizerError> {
        let model: Self = serde_json::from_str(text).map_err(|e| RecognizerError::Parse {
            path: path.to_owned(),
            line: e.line(),
            reason: e.to_string(),
        })?;
        model
            .validate()
            .map_err(|(field, reason)| RecognizerError::Invalid {
                path: path.to_owned(),
                field,
                reason,
            })?;
        Ok(model)
    }

    /// Checks format, version and shapes; `Err((field, reason))`.
    pub fn validate(&self) -> Result<(), (String, String)> {
        let bad = |field: &str, reason: String| Err((field.to_owned(), reason));
        if self.format != RECOGNIZER_FORMAT {
            return bad(
                "format",
                format!("`{}` is not `{RECOGNIZER_FORMAT}`", self.format),
            );
        }
        if self.version != RECOGNIZER_VERSION {
            return bad(
                "version",
                format!(
                    "{} is not supported (this build reads {RECOGNIZER_VERSION})",
                    self.version
                ),
            );
        }
        if self.classes.is_empty() {
            return bad("classes", "no classes".into());
        }
        if let Some(i) = (1..self.classes.len()).find(|&i| self.classes[..i].contains(&self.classes[i])) {
            return bad("classes", format!("`{}` given twice", self.classes[i]));
        }
        match &self.body {
            RecognizerBody::Som { windowing, som } => {
                windowing
                    .check()
                    .map_err(|(f, v, r)| (format!("body.windowing.{f}"), format!("{v} is not {r}")))?;
                som.check_shape(self.classes.len())
                    .map_err(|(f, r)| (format!("body.som.{f}"), r))?;
                if som.dim() != FEATURES || self.feature_names.len() != FEATURES {
                    return bad(
                        "body.som.scaling",
                        format!("a Nakano map has {FEATURES} features, not {}", som.dim()),
                    );
                }
            }
            RecognizerBody::Knn { behaviours, .. } => {
                if behaviours.is_empty() {
                    return bad("body.behaviours", "no classifier".into());
                }
                for (i, b) in behaviours.iter().enumerate() {
                    b.knn
                        .check_shape()
                        .map_err(|(f, r)| (format!("body.behaviours[{i}].knn.{f}"), r))?;
                    if b.knn.classes() != self.classes.len() {
                        return bad(
                            &format!("body.behaviours[{i}].knn.classes"),
                            format!(
                                "{} classes, the file names {}",
                                b.knn.classes(),
                                self.classes.len()
                            ),
                        );
                    }
                    if b.knn.dim() != super::spectral::FEATURE_LEN {
                        return bad(
                            &format!("body.behaviours[{i}].knn.dim"),
                            format!("histograms have {} cells", super::spectral::FEATURE_LEN),
                        );
                    }
                    check_reliability(b.reliability)
                        .map_err(|r| (format!("body.behaviours[{i}].reliability"), r))?;
                }
            }
            RecognizerBody::Svm { behaviours, .. } => {
                if behaviours.is_empty() {
                    return bad("body.behaviours", "no classifier".into());
                }
                for (i, b) in behaviours.iter().enumerate() {
                    b.svc
                        .check_shape()
                        .map_err(|(f, r)| (format!("body.behaviours[{i}].svc.{f}"), r))?;
                    if b.svc.classes() != self.classes.len() || b.svc.dim() != super::spectral::FEATURE_LEN {
                        return bad(
                            &format!("body.behaviours[{i}].svc"),
                            format!(
                                "{} classes over {} features; the file names {} classes over {}",
                                b.svc.classes(),
                                b.svc.dim(),
                                self.classes.len(),
                                super::spectral::FEATURE_LEN
                            ),
                        );
                    }
                    check_reliability(b.reliability)
                        .map_err(|r| (format!("body.behaviours[{i}].reliability"), r))?;
                    if let Some(search) = &b.c_search {
                        search
                            .check()
                            .map_err(|(f, r)| (format!("body.behaviours[{i}].c_search.{f}"), r))?;
                        if search.chosen_c != b.svc.params().c {
                            return bad(
                                &format!("body.behaviours[{i}].c_search.chosen_c"),
                                format!(
                                    "{} is not the classifier's C {}",
                                    search.chosen_c,
                                    b.svc.params().c
                                ),
                            );
                        }
                    }
                }
            }
            RecognizerBody::KnnWindows {
                features,
                windowing,
                scaling,
                knn,
                ..
            } => {
                check_window_body(*features, windowing, scaling)?;
                knn.check_shape().map_err(|(f, r)| (format!("body.knn.{f}"), r))?;
                if knn.classes() != self.classes.len() || knn.dim() != features.dim() {
                    return bad(
                        "body.knn",
                        format!(
                            "{} classes over {} features; the file names {} classes over {} ({features})",
                            knn.classes(),
                            knn.dim(),
                            self.classes.len(),
                            features.dim()
                        ),
                    );
                }
            }
            RecognizerBody::SvmWindows {
                features,
                windowing,
                scaling,
                svc,
                c_search,
                ..
            } => {
                check_window_body(*features, windowing, scaling)?;
                svc.check_shape().map_err(|(f, r)| (format!("body.svc.{f}"), r))?;
                if svc.classes() != self.classes.len() || svc.dim() != features.dim() {
                    return bad(
                        "body.svc",
                        format!(
                            "{} classes over {} features; the file names {} classes over {} ({features})",
                            svc.classes(),
                            svc.dim(),
                            self.classes.len(),
                            features.dim()
                        ),
                    );
                }
                features::check_c_search(c_search.as_ref(), svc.params().c)?;
            }
            RecognizerBody::SomWindows { windowing, som, .. } => {
                windowing
                    .check()
                    .map_err(|(f, v, r)| (format!("body.windowing.{f}"), format!("{v} is not {r}")))?;
                som.check_shape(self.classes.len())
                    .map_err(|(f, r)| (format!("body.som.{f}"), r))?;
                if som.dim() != FeatureSet::Both.dim() {
                    return bad(
                        "body.som.scaling",
                        format!(
                            "a map over both feature sets has {} features, not {}",
                            FeatureSet::Both.dim(),
                            som.dim()
                        ),
                    );
                }
            }
            RecognizerBody::SomScratches { behaviours, .. } => {
                if behaviours.is_empty() {
                    return bad("body.behaviours", "no classifier".into());
                }
                for (i, b) in behaviours.iter().enumerate() {
                    b.som
                        .check_shape(self.classes.len())
                        .map_err(|(f, r)| (format!("body.behaviours[{i}].som.{f}"), r))?;
                    if b.som.dim() != super::spectral::FEATURE_LEN {
                        return bad(
                            &format!("body.behaviours[{i}].som.scaling"),
                            format!("histograms have {} cells", super::spectral::FEATURE_LEN),
                        );
                    }
                    check_reliability(b.reliability)
                        .map_err(|r| (format!("body.behaviours[{i}].reliability"), r))?;
                }
            }
        }
        if let Some(features) = self.features
            && features != self.body.feature_set()
        {
            return bad(
                "features",
                format!(
                    "`{features}`, but the body is a {} over `{}` features",
                    self.method(),
                    self.body.feature_set()
                ),
            );
        }
        if self.feature_names.len() != self.feature_set().dim() {
            return bad(
                "feature_names",
                format!(
                    "{} names for {} features",
                    self.feature_names.len(),
                    self.feature_set().dim()
                ),
            );
        }
        Ok(())
    }
}

/// Checks the windows, features and scaling of a k-NN or SVM over rubbing windows.
fn check_window_body(
    features: FeatureSet,
    windowing: &NakanoWindowing,
    scaling: &WindowScaling,
) -> Result<(), (String, String)> {
    windowing
        .check()
        .map_err(|(f, v, r)| (format!("body.windowing.{f}"), format!("{v} is not {r}")))?;
    if features == FeatureSet::Spectral {
        return Err((
            "body.features".into(),
            "windows carry `nakano` or `both` features".into(),
        ));
    }
    scaling
        .check(features.dim())
        .map_err(|r| ("body.scaling".to_owned(), r))
}

/// Names of the spectrotemporal histogram's cells, time-major.
fn histogram_names() -> Vec<String> {
    (0..super::spectral::FEATURE_LEN)
        .map(|i| {
            format!(
                "histogram_t{}_f{}",
                i / super::spectral::FREQUENCY_BINS,
                i % super::spectral::FREQUENCY_BINS
            )
        })
        .collect()
}

/// The sorted distinct labels of `captures`.
fn class_list(captures: &[LabelledCapture]) -> Vec<String> {
    let set: BTreeSet<&str> = captures.iter().map(|c| c.label.as_str()).collect();
    set.into_iter().map(str::to_owned).collect()
}

fn class_index(classes: &[String], c: &LabelledCapture) -> Result<usize, RecognizerError> {
    classes
        .iter()
        .position(|l| *l == c.label)
        .ok_or_else(|| RecognizerError::UnusableCapture {
            path: c.reference.path.clone(),
            reason: format!("surface `{}` is not one the recognizer was trained on", c.label),
        })
}

fn check_rate(c: &LabelledCapture, rate_hz: f64) -> Result<(), RecognizerError> {
    let found = c.capture.metadata().rate_hz();
    if (found - rate_hz).abs() > 1e-9 * rate_hz {
        return Err(RecognizerError::UnusableCapture {
            path: c.reference.path.clone(),
            reason: format!("sampled at {found} Hz; the recognizer's windows are counted at {rate_hz} Hz"),
        });
    }
    Ok(())
}

/// Start and features of every decision window of a capture.
fn windows(
    c: &LabelledCapture,
    windowing: &NakanoWindowing,
) -> Result<Vec<(usize, [f64; FEATURES])>, RecognizerError> {
    let nakano = |source| RecognizerError::Nakano {
        path: c.reference.path.clone(),
        source,
    };
    let signals = NakanoSignals::from_capture(&c.capture).map_err(nakano)?;
    let x = signals.position_m();
    let Some(&x0) = x.first() else {
        return Ok(Vec::new());
    };
    let margin = windowing.filters.lookahead_samples();
    let len = windowing.window_samples;
    (margin..)
        .step_by(windowing.hop_samples)
        .take_while(|s| s + len + margin <= signals.len())
        .filter(|&s| windowing.is_decision_window(s as u64, (x[s] - x0).abs()))
        .map(|s| Ok((s, signals.features(s, len, &windowing.filters).map_err(nakano)?)))
        .collect()
}

fn spectral(
    plan: &SpectrogramPlan,
    c: &LabelledCapture,
    scale: CellScale,
) -> Result<[f64; super::spectral::FEATURE_LEN], RecognizerError> {
    plan.capture_features(&c.capture, scale)
        .map_err(|source| RecognizerError::Spectral {
            path: c.reference.path.clone(),
            source,
        })
}

/// One behaviour's training data: its name, a histogram per capture, their class indices and
/// cross-validation groups ([`trial_groups`]).
type BehaviourHistograms<'a> = (
    Option<&'a str>,
    Vec<[f64; super::spectral::FEATURE_LEN]>,
    Vec<usize>,
    Vec<u64>,
);

/// The scratches of one trial: each one's behaviour index and class probabilities.
type TrialScratches = Vec<(usize, Vec<f64>)>;

/// Sinapov's histogram of each capture with its class index and cross-validation group,
/// grouped by behaviour (k-NN and SVM recognizers keep one classifier per behaviour).
fn histograms_by_behaviour<'a>(
    captures: &'a [LabelledCapture],
    classes: &[String],
    cell_scale: CellScale,
) -> Result<Vec<BehaviourHistograms<'a>>, RecognizerError> {
    let plan = SpectrogramPlan::new();
    let names: BTreeSet<Option<&str>> = captures.iter().map(|c| c.behaviour.as_deref()).collect();
    let mut out = Vec::new();
    for name in names {
        let (mut x, mut y, mut members) = (Vec::new(), Vec::new(), Vec::new());
        for c in captures.iter().filter(|c| c.behaviour.as_deref() == name) {
            x.push(spectral(&plan, c, cell_scale)?);
            y.push(class_index(classes, c)?);
            members.push(c);
        }
        out.push((name, x, y, trial_groups(&members)));
    }
    Ok(out)
}

/// A capture's trial (metadata [`TRIAL_KEY`]), if it has a non-empty one.
fn trial_of(c: &LabelledCapture) -> Option<&str> {
    c.capture.metadata().get(TRIAL_KEY).filter(|t| !t.is_empty())
}

/// Cross-validation group of each capture inside training: its trial, so that the folds of
/// [`super::knn::group_folds`] hold out trial `t` of every surface together — a scratch is
/// never on both sides of a split, and every fold keeps about the same share of each surface.
/// Groups are numbered in the trials' numeric order (shorter strings first); captures without
/// a trial are a group each, after them.
pub fn trial_groups(captures: &[&LabelledCapture]) -> Vec<u64> {
    groups_by(captures, trial_of)
}

/// Recording of each capture: its `trial`, else its `run` (both in numeric order), else a
/// recording of its own — numbered densely from 0 — so that all windows of one recording, and
/// all recordings of one run or trial, are held out together.
pub fn recording_groups(captures: &[LabelledCapture]) -> Vec<u64> {
    groups_by(captures, recording_of)
}

/// A capture's recording: its trial, else its `run`.
fn recording_of(c: &LabelledCapture) -> Option<&str> {
    trial_of(c).or_else(|| c.capture.metadata().get("run").filter(|r| !r.is_empty()))
}

/// Numbers captures by `key`, densely from 0 in the keys' numeric order (shorter strings
/// first, so trial 10 follows 9); a capture without a key is a group of its own, after them.
fn groups_by<C: Borrow<LabelledCapture>>(
    captures: &[C],
    key: fn(&LabelledCapture) -> Option<&str>,
) -> Vec<u64> {
    let keys: BTreeSet<(usize, &str)> = captures
        .iter()
        .filter_map(|c| key(c.borrow()))
        .map(|k| (k.len(), k))
        .collect();
    let keys: Vec<(usize, &str)> = keys.into_iter().collect();
    let mut alone = keys.len() as u64;
    captures
        .iter()
        .map(|c| match key(c.borrow()) {
            Some(k) => keys.binary_search(&(k.len(), k)).map_or(0, |r| r as u64),
            None => {
                alone += 1;
                alone - 1
            }
        })
        .collect()
}

/// A stored reliability must be a finite accuracy in `[0, 1]`.
fn check_reliability(r: Option<f64>) -> Result<(), String> {
    match r {
        Some(r) if !(r.is_finite() && (0.0..=1.0).contains(&r)) => {
            Err(format!("{r} is not an accuracy in [0, 1]"))
        }
        _ => Ok(()),
    }
}

/// Index of the classifier of the capture's behaviour (k-NN and SVM recognizers keep one per
/// behaviour).
fn behaviour_index<T>(
    behaviours: &[T],
    name: impl Fn(&T) -> &Option<String>,
    capture: &LabelledCapture,
) -> Result<usize, RecognizerError> {
    behaviours
        .iter()
        .position(|b| *name(b) == capture.behaviour)
        .ok_or_else(|| RecognizerError::UnusableCapture {
            path: capture.reference.path.clone(),
            reason: format!(
                "behaviour {:?}: the recognizer was trained on {:?}",
                capture.behaviour,
                behaviours.iter().map(&name).collect::<Vec<_>>()
            ),
        })
}

/// One decision over a whole capture (a scratch is classified once), with its probability as
/// the confidence.
fn whole_capture_decision(capture: &LabelledCapture, label: usize, probabilities: &[f64]) -> Decision {
    Decision {
        window_start: 0,
        decided_at: capture.capture.len().saturating_sub(1),
        label,
        confidence: probabilities.get(label).copied().unwrap_or(0.0),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use capture::Metadata;

    /// A rubbing capture of a sine roughness of `amplitude_m` and `wavelength_m` with friction
    /// `friction_n`, 5 mm/s at 1 kHz for `seconds`.
    fn rubbing(
        surface: &str,
        amplitude_m: f64,
        wavelength_m: f64,
        friction_n: f64,
        seconds: f64,
    ) -> LabelledCapture {
        let n = (seconds * 1000.0) as usize;
        let t: Vec<f64> = (0..n).map(|k| k as f64 * 1e-3).collect();
        let x: Vec<f64> = t.iter().map(|t| 5e-3 * t).collect();
        let z: Vec<f64> = x
            .iter()
            .map(|x| amplitude_m * (x * std::f64::consts::TAU / wavelength_m).sin())
            .collect();
        let f: Vec<f64> = (0..n)
            .map(|k| friction_n * (1.0 + 0.05 * ((k * 7919) % 13) as f64 / 13.0))
            .collect();
        let meta = Metadata::new(CaptureKind::Rubbing, "test", 1000.0).with(LABEL_KEY, surface);
        let columns = [
            "time_s",
            "tangential_position_m",
            "normal_position_m",
            "normal_force_n",
            "friction_force_n",
        ]
        .map(String::from)
        .to_vec();
        let capture = Capture::new(meta, columns, vec![t, x, z, vec![0.3; n], f]).expect("valid capture");
        LabelledCapture::new(capture, Path::new(surface), "00".into()).expect("labelled")
    }

    fn three_surfaces(seconds: f64) -> Vec<LabelledCapture> {
        vec![
            rubbing("fine", 5e-6, 0.3e-3, 0.10, seconds),
            rubbing("coarse", 30e-6, 1.5e-3, 0.20, seconds),
            rubbing("smooth", 1e-6, 0.8e-3, 0.05, seconds),
        ]
    }

    #[test]
    fn a_som_recognizer_round_trips_and_recognizes_distinct_surfaces() {
        let train = three_surfaces(4.0);
        let windowing = NakanoWindowing::new(0.5, 0.1, 1000.0).expect("valid");
        let model = RecognizerFile::train_som(&train, windowing, SomParams::default()).expect("train");
        assert_eq!(model.classes, ["coarse", "fine", "smooth"]);
        let text = serde_json::to_string(&model).expect("serialize");
        let back = RecognizerFile::from_json(&text, Path::new("m.json")).expect("valid");
        assert_eq!(back, model);
        let eval = back.evaluate(&three_surfaces(3.0), None).expect("evaluate");
        assert_eq!(eval.confusion.accuracy(), Some(1.0));
        assert_eq!((eval.never_correct, eval.not_stable), (0, 0));
        // The first decision window starts at 270 + 8 × 100 samples, the first hop after 5 mm
        // (1 s) of travel, and is decided 500 + 270 − 1 samples later.
        assert!((eval.decision_latency_s - 0.77).abs() < 1e-12);
        let first = eval.time_to_first_correct_s.expect("correct decisions");
        assert!((first - 1.839).abs() < 1e-9, "{first}");
        assert_eq!(eval.flips_per_s, 0.0);
    }

    /// A k-NN and an SVM recognizer over two behaviours of three classes, built without
    /// captures: `poke` has a reliability weight, `rub` (as in a file written before weights
    /// were stored, or with too few trials) has none.
    fn sinapov_recognizers() -> [RecognizerFile; 2] {
        use super::super::svc::CvPoint;
        let x: Vec<Vec<f64>> = (0..6)
            .map(|i| {
                (0..super::super::spectral::FEATURE_LEN)
                    .map(|j| (i / 2) as f64 + 0.01 * ((i * 31 + j * 7) % 11) as f64)
                    .collect()
            })
            .collect();
        let y = [0, 0, 1, 1, 2, 2];
        let knn = KnnParams::default().fit(&x, &y, 3).expect("k-NN");
        let params = SvcParams {
            c: 10.0,
            probability: false,
            ..SvcParams::default()
        };
        let svc = Svc::fit(params, &x, &y, 3).expect("SVC");
        let classes: Vec<String> = ["a", "b", "c"].map(String::from).to_vec();
        let knn_body = RecognizerBody::Knn {
            cell_scale: CellScale::Mean,
            behaviours: ["poke", "rub"]
                .iter()
                .map(|b| BehaviourKnn {
                    behaviour: Some((*b).to_owned()),
                    knn: knn.clone(),
                    reliability: (*b == "poke").then_some(0.8),
                    reliability_folds: (*b == "poke").then_some(5),
                })
                .collect(),
        };
        let search = CSearch {
            folds: 5,
            grid: vec![
                CvPoint {
                    c: 1.0,
                    accuracy: 0.5,
                },
                CvPoint {
                    c: 10.0,
                    accuracy: 0.8,
                },
            ],
            chosen_c: 10.0,
        };
        let svm_body = RecognizerBody::Svm {
            cell_scale: CellScale::Mean,
            behaviours: ["poke", "rub"]
                .iter()
                .map(|b| BehaviourSvc {
                    behaviour: Some((*b).to_owned()),
                    svc: svc.clone(),
                    reliability: (*b == "poke").then_some(0.8),
                    c_search: (*b == "poke").then(|| search.clone()),
                })
                .collect(),
        };
        [knn_body, svm_body]
            .map(|body| RecognizerFile::assemble(classes.clone(), histogram_names(), body, &[], 6))
    }

    #[test]
    fn reliability_weights_round_trip_and_older_files_without_them_still_load() {
        for model in sinapov_recognizers() {
            let method = model.method();
            let json = serde_json::to_value(&model).expect("serialize");
            assert_eq!(json["body"]["behaviours"][0]["reliability"], 0.8, "{method}");
            assert!(
                json["body"]["behaviours"][1].get("reliability").is_none(),
                "{method}"
            );
            let back = RecognizerFile::from_json(&json.to_string(), Path::new("m.json")).expect("valid");
            assert_eq!(back, model);
            // `rub` has no weight of its own: it gets the mean of the others' (here `poke`'s).
            assert_eq!(back.fusion_weights(), [0.8, 0.8], "{method}");
            assert_eq!(back.behaviour_names(), [Some("poke"), Some("rub")]);

            // A file from before weights were stored: no `reliability`, `reliability_folds`,
            // `c_search` anywhere. It loads, and every behaviour weighs the same.
            let mut old = json.clone();
            for b in old["body"]["behaviours"].as_array_mut().expect("behaviours") {
                let b = b.as_object_mut().expect("behaviour");
                for key in ["reliability", "reliability_folds", "c_search"] {
                    b.remove(key);
                }
            }
            let old = RecognizerFile::from_json(&old.to_string(), Path::new("old.json")).expect("old file");
            assert!(
                old.reliabilities()
                    .iter()
                    .all(|r| r.reliability.is_none() && r.c_search.is_none())
            );
            assert_eq!(old.fusion_weights(), [1.0, 1.0], "{method}");

            // Weights are accuracies.
            for bad in [serde_json::json!(1.5), serde_json::json!(-0.1)] {
                let mut edited = json.clone();
                edited["body"]["behaviours"][0]["reliability"] = bad;
                let err =
                    RecognizerFile::from_json(&edited.to_string(), Path::new("r.json")).expect_err("range");
                assert!(
                    err.to_string()
                        .contains("r.json: field `body.behaviours[0].reliability`"),
                    "{err}"
                );
            }
        }
        // The SVM's search must name the classifier's C, from its grid.
        let json = serde_json::to_value(&sinapov_recognizers()[1]).expect("serialize");
        let mut edited = json.clone();
        edited["body"]["behaviours"][0]["c_search"]["chosen_c"] = 1.0.into();
        let err = RecognizerFile::from_json(&edited.to_string(), Path::new("r.json")).expect_err("C");
        assert!(
            err.to_string()
                .contains("field `body.behaviours[0].c_search.chosen_c`: 1 is not the classifier's C 10"),
            "{err}"
        );
        let mut edited = json;
        edited["body"]["behaviours"][0]["c_search"]["chosen_c"] = 100.0.into();
        let err = RecognizerFile::from_json(&edited.to_string(), Path::new("r.json")).expect_err("grid");
        assert!(
            err.to_string()
                .contains("c_search.chosen_c`: 100 is not in the grid"),
            "{err}"
        );
    }

    #[test]
    fn trials_group_captures_in_numeric_order_and_trial_less_captures_stand_alone() {
        let with_trial = |trial: Option<&str>| {
            let mut c = rubbing("fine", 5e-6, 0.3e-3, 0.1, 0.1);
            let mut meta = c.capture.metadata().clone();
            if let Some(t) = trial {
                meta = meta.with(TRIAL_KEY, t);
            }
            c.capture =
                Capture::new(meta, c.capture.columns().to_vec(), c.capture.data().to_vec()).expect("capture");
            c
        };
        let captures: Vec<LabelledCapture> = [Some("10"), Some("2"), None, Some("2"), Some("0"), None]
            .into_iter()
            .map(with_trial)
            .collect();
        let refs: Vec<&LabelledCapture> = captures.iter().collect();
        assert_eq!(trial_groups(&refs), [2, 1, 3, 1, 0, 4]);
    }

    #[test]
    fn window_classifiers_round_trip_and_recognize_distinct_surfaces() {
        let train = three_surfaces(4.0);
        let windowing = NakanoWindowing::new(0.5, 0.1, 1000.0).expect("valid");
        let knn =
            RecognizerFile::train_knn_windows(&train, windowing, FeatureSet::Nakano, 3, CellScale::Mean)
                .expect("k-NN");
        let svm = RecognizerFile::train_svm_windows(
            &train,
            windowing,
            FeatureSet::Nakano,
            &SvmC::auto(),
            CellScale::Mean,
        )
        .expect("SVM");
        for model in [knn, svm] {
            assert_eq!(model.feature_set(), FeatureSet::Nakano);
            assert_eq!(model.windowing(), Some(&windowing));
            let json = serde_json::to_value(&model).expect("serialize");
            assert_eq!(json["features"], "nakano");
            let back = RecognizerFile::from_json(&json.to_string(), Path::new("m.json")).expect("valid");
            assert_eq!(back, model);
            let eval = back.evaluate(&three_surfaces(3.0), None).expect("evaluate");
            assert_eq!(eval.confusion.accuracy(), Some(1.0), "{}", model.method());
            // The SOM's windows: the same latency.
            assert!((eval.decision_latency_s - 0.77).abs() < 1e-12);
            assert!(
                back.evaluate_fused(&three_surfaces(3.0))
                    .expect("fused")
                    .is_none()
            );
            // Shapes are checked on load.
            let mut edited = json.clone();
            edited["body"]["scaling"]["scale"][0] = (-1.0).into();
            let err = RecognizerFile::from_json(&edited.to_string(), Path::new("r.json")).expect_err("scale");
            assert!(err.to_string().contains("field `body.scaling`"), "{err}");
            let mut edited = json;
            edited["features"] = "both".into();
            let err =
                RecognizerFile::from_json(&edited.to_string(), Path::new("r.json")).expect_err("features");
            assert!(err.to_string().contains("field `features`"), "{err}");
        }
        // No accelerometer in these captures: `both` names the capture and the columns.
        let err = RecognizerFile::train_knn_windows(&train, windowing, FeatureSet::Both, 3, CellScale::Mean)
            .expect_err("no accelerometer");
        assert!(
            matches!(&err, RecognizerError::MissingColumns { missing, .. } if missing.len() == 3),
            "{err}"
        );
        assert!(
            err.to_string()
                .starts_with("fine: `--features both` needs the columns accel_x_mps2"),
            "{err}"
        );
    }

    #[test]
    fn a_bad_file_names_the_field() {
        let windowing = NakanoWindowing::new(0.5, 0.1, 1000.0).expect("valid");
        let model =
            RecognizerFile::train_som(&three_surfaces(3.0), windowing, SomParams::default()).expect("train");
        let mut json = serde_json::to_value(&model).expect("serialize");
        json["version"] = 7.into();
        let err = RecognizerFile::from_json(&json.to_string(), Path::new("r.json")).expect_err("version");
        assert!(err.to_string().contains("r.json: field `version`"), "{err}");
        let mut json = serde_json::to_value(&model).expect("serialize");
        json["body"]["som"]["labels"][3] = 9.into();
        let err = RecognizerFile::from_json(&json.to_string(), Path::new("r.json")).expect_err("label");
        assert!(err.to_string().contains("field `body.som.labels`"), "{err}");
        let mut json = serde_json::to_value(&model).expect("serialize");
        json["body"]["som"]["reference"][0] = serde_json::json!([1.0, 0.0]);
        let err = RecognizerFile::from_json(&json.to_string(), Path::new("r.json")).expect_err("shape");
        assert!(err.to_string().contains("field `body.som.reference`"), "{err}");
        // Sizes past memory or past the filters' sample arithmetic are refused on load, with
        // the value, not allocated or overflowed.
        for (field, value, message) in [
            (
                "highpass_half_width",
                1e18,
                "body.windowing.filters.highpass_half_width`: 1000000000000000000 is not from 1 to 10^6",
            ),
            (
                "smoothing_half_width",
                2e6,
                "body.windowing.filters.smoothing_half_width`: 2000000 is not at most 10^6",
            ),
        ] {
            let mut json = serde_json::to_value(&model).expect("serialize");
            json["body"]["windowing"]["filters"][field] = (value as u64).into();
            let err = RecognizerFile::from_json(&json.to_string(), Path::new("r.json")).expect_err(field);
            assert!(err.to_string().contains(message), "{err}");
        }
        let mut json = serde_json::to_value(&model).expect("serialize");
        json["body"]["windowing"]["window_samples"] = 100_000_000.into();
        let err = RecognizerFile::from_json(&json.to_string(), Path::new("r.json")).expect_err("window");
        assert!(
            err.to_string()
                .contains("`body.windowing.window_samples`: 100000000 is not from 2 to 10^7"),
            "{err}"
        );
        let err = NakanoWindowing::new(0.5, 0.1, 1000.0)
            .and_then(|w| w.with_training_window_s(0.001))
            .expect_err("one sample");
        assert!(
            err.to_string()
                .contains("training_window_samples = 1: from 2 to 10^7"),
            "{err}"
        );
        let err = RecognizerFile::from_json("{\"format\": 1", Path::new("r.json")).expect_err("parse");
        assert!(matches!(err, RecognizerError::Parse { line: 1, .. }), "{err}");
        // A capture of a surface the map does not know.
        let unknown = rubbing("glass", 1e-6, 1e-3, 0.1, 3.0);
        let err = model.evaluate(&[unknown], None).expect_err("unknown surface");
        assert!(err.to_string().contains("surface `glass`"), "{err}");
    }
}
