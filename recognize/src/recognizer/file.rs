//! The recognizer file: what a trained recognizer stores (self-describing JSON), how it is
//! written and read, and the checks that make a truncated or hand-edited file a typed error
//! naming the file and the field.

use std::path::Path;

use serde::{Deserialize, Serialize};

use super::LabelledCapture;
use super::choice_table::DefaultChoice;
use super::posterior_weight::PosteriorWeight;
#[cfg(doc)]
use super::{SvmC, trial_groups};
use crate::RecognizeError;
use crate::features::nakano::FEATURES;
use crate::features::spectral::{FEATURE_LEN, Histogram};
use crate::features::{FeatureSet, NakanoWindowing, WindowScaling};
use crate::knn::{Knn, VoteCalibration};
use crate::som::Som;
use crate::svc::{CSearch, Svc};
use capture::json_file;
use capture::{CaptureRef, sha256_hex};

/// Format name in every recognizer file.
pub const RECOGNIZER_FORMAT: &str = "palpus-recognizer";
/// Current recognizer file version. Version 2: the spectrotemporal histogram is defined in
/// seconds and hertz (see [`crate::spectral`]); a version-1 file's histograms were counted in
/// samples and mean something else at any rate but 400 Hz, so such a file is refused, not
/// misread; a version-1 file over Nakano's features alone is read as it was.
pub const RECOGNIZER_VERSION: u32 = 2;

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

/// One behaviour's SOM over spectrotemporal histograms.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BehaviourSom {
    /// The behaviour (metadata `behaviour`); `None` for captures without one.
    pub behaviour: Option<String>,
    /// Its map (node labels are class indices), with its feature scaling.
    pub som: Som<usize>,
    /// Its accuracy under cross-validation by trial on the training captures: its weight when
    /// behaviours are fused (as [`BehaviourKnn::reliability`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reliability: Option<f64>,
    /// Folds of that cross-validation.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reliability_folds: Option<usize>,
}

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
        /// The histogram's definition: its cell scaling (`cell_scale`) and band
        /// (`band`, absent for the paper's).
        #[serde(flatten)]
        histogram: Histogram,
        /// One classifier per behaviour seen in training.
        behaviours: Vec<BehaviourKnn>,
    },
    /// Sinapov: one spectrotemporal histogram per scratch, one SVC (degree-2 polynomial
    /// kernel, pairwise-coupled probabilities) per behaviour.
    Svm {
        /// The histogram's definition: its cell scaling (`cell_scale`) and band
        /// (`band`, absent for the paper's).
        #[serde(flatten)]
        histogram: Histogram,
        /// One classifier per behaviour seen in training.
        behaviours: Vec<BehaviourSvc>,
    },
    /// k-NN over rubbing windows (`--features nakano|both`), windowed like the SOM.
    KnnWindows {
        /// `nakano` or `both`.
        features: FeatureSet,
        /// The windows.
        windowing: NakanoWindowing,
        /// For `both`: the window histogram's definition: its cell scaling (`cell_scale`) and band
        /// (`band`, absent for the paper's).
        #[serde(flatten)]
        histogram: Histogram,
        /// The feature scaling learned from the training windows.
        scaling: WindowScaling,
        /// The classifier over scaled windows.
        knn: Knn,
        /// How its votes become window probabilities, fitted under cross-validation by run or
        /// trial; `None` (raw vote fractions, and no reliability to be fused by) when the
        /// training captures could not be cross-validated, or the file predates it.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        calibration: Option<VoteCalibration>,
    },
    /// C-SVC (degree-2 polynomial kernel) over rubbing windows (`--features nakano|both`).
    SvmWindows {
        /// `nakano` or `both`.
        features: FeatureSet,
        /// The windows.
        windowing: NakanoWindowing,
        /// For `both`: the window histogram's definition: its cell scaling (`cell_scale`) and band
        /// (`band`, absent for the paper's).
        #[serde(flatten)]
        histogram: Histogram,
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
        /// The window histogram's definition: its cell scaling (`cell_scale`) and band
        /// (`band`, absent for the paper's).
        #[serde(flatten)]
        histogram: Histogram,
        /// The map, with its feature scaling.
        som: Som<usize>,
    },
    /// One SOM per behaviour over the histograms of whole scratches (`--features spectral`).
    SomScratches {
        /// The histogram's definition: its cell scaling (`cell_scale`) and band
        /// (`band`, absent for the paper's).
        #[serde(flatten)]
        histogram: Histogram,
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
    pub(crate) fn is_scratch(&self) -> bool {
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
    /// A k-NN's or SVM's posterior weight fitted on recordings held out of its training
    /// ([`RecognizerFile::fit_posterior_weight`]); `None` where its captures could not be
    /// cross-validated, or the file predates the fit: then windows weigh `hop / window`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub posterior_weight: Option<PosteriorWeight>,
    /// The table its features, histogram and window were chosen from by cross-validation on
    /// its training captures ([`super::DefaultSearch`]); `None` when the user named them all,
    /// or the file predates the search.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub default_choice: Option<DefaultChoice>,
}

impl RecognizerFile {
    /// A recognizer file around a trained `body`, with the hashes of its training captures.
    pub(crate) fn assemble(
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
            posterior_weight: None,
            default_choice: None,
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

    /// Writes the recognizer atomically as pretty JSON.
    pub fn save(&self, path: &Path) -> Result<(), RecognizeError> {
        json_file::save_pretty(path, self).map_err(RecognizeError::from_json_file)
    }

    /// Reads and validates a recognizer file.
    pub fn load(path: &Path) -> Result<Self, RecognizeError> {
        json_file::load(path, Self::validate).map_err(RecognizeError::from_json_file)
    }

    /// Parses and validates a recognizer; `path` names it in errors.
    pub fn from_json(text: &str, path: &Path) -> Result<Self, RecognizeError> {
        json_file::parse(text.as_bytes(), path, Self::validate).map_err(RecognizeError::from_json_file)
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
        // Version 1 differs only in the histogram's definition, so a version-1 recognizer over
        // Nakano's features alone reads the same under both and stays usable.
        let same_in_both = self.version == 1 && self.feature_set() == FeatureSet::Nakano;
        if self.version != RECOGNIZER_VERSION && !same_in_both {
            return bad(
                "version",
                if self.version == 1 {
                    format!(
                        "1 is not supported for {} features (this build reads 2, whose \
                         spectrotemporal histograms are defined in seconds and hertz): train the \
                         recognizer again",
                        self.feature_set()
                    )
                } else {
                    format!(
                        "{} is not supported (this build reads {RECOGNIZER_VERSION})",
                        self.version
                    )
                },
            );
        }
        if self.classes.is_empty() {
            return bad("classes", "no classes".into());
        }
        // A surface is named by its class in every report and overlay.
        if let Some(i) = self.classes.iter().position(|c| c.trim().is_empty()) {
            return bad(&format!("classes[{i}]"), "an empty name".into());
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
                    if b.knn.dim() != FEATURE_LEN {
                        return bad(
                            &format!("body.behaviours[{i}].knn.dim"),
                            format!("histograms have {} cells", FEATURE_LEN),
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
                    if b.svc.classes() != self.classes.len() || b.svc.dim() != FEATURE_LEN {
                        return bad(
                            &format!("body.behaviours[{i}].svc"),
                            format!(
                                "{} classes over {} features; the file names {} classes over {}",
                                b.svc.classes(),
                                b.svc.dim(),
                                self.classes.len(),
                                FEATURE_LEN
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
                calibration,
                ..
            } => {
                check_window_body(*features, windowing, scaling)?;
                knn.check_shape().map_err(|(f, r)| (format!("body.knn.{f}"), r))?;
                if let Some(c) = calibration {
                    let in_unit = |v: f64| (0.0..=1.0).contains(&v);
                    if !(in_unit(c.votes_weight) && in_unit(c.accuracy) && in_unit(c.unvoted)) {
                        return bad(
                            "body.calibration",
                            format!(
                                "votes weight {}, accuracy {} and unvoted share {} must each lie in [0, 1]",
                                c.votes_weight, c.accuracy, c.unvoted
                            ),
                        );
                    }
                }
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
                check_probabilities(svc).map_err(|r| ("body.svc.params.probability".to_owned(), r))?;
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
                check_c_search(c_search.as_ref(), svc.params().c)?;
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
                    if b.som.dim() != FEATURE_LEN {
                        return bad(
                            &format!("body.behaviours[{i}].som.scaling"),
                            format!("histograms have {} cells", FEATURE_LEN),
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
        if let Some(p) = &self.posterior_weight {
            if self.hop_weight().is_none() {
                return bad(
                    "posterior_weight",
                    format!(
                        "a {} over `{}` gives no window probabilities to weigh",
                        self.method(),
                        self.feature_set()
                    ),
                );
            }
            p.check().map_err(|(f, r)| (format!("posterior_weight.{f}"), r))?;
        }
        if let Some(choice) = &self.default_choice {
            choice.validate()?;
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
            "windows carry `nakano`, `both` or `vibration` features".into(),
        ));
    }
    scaling
        .check(features.dim())
        .map_err(|r| ("body.scaling".to_owned(), r))
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

/// An SVM over windows decides by class probabilities in every reader (evaluation, anytime
/// posteriors, the live recognizer), so one fitted without them is refused on reading rather
/// than by whichever reader first asks. (A whole-scratch SVM without them votes instead.)
fn check_probabilities(svc: &Svc) -> Result<(), String> {
    if svc.params().probability || svc.classes() < 2 {
        return Ok(());
    }
    Err("false: an SVM over windows decides by class probabilities; train it again".into())
}

/// The search of a window SVM must name its C, from its grid.
fn check_c_search(search: Option<&CSearch>, c: f64) -> Result<(), (String, String)> {
    if let Some(search) = search {
        search
            .check()
            .map_err(|(f, r)| (format!("body.c_search.{f}"), r))?;
        if search.chosen_c != c {
            return Err((
                "body.c_search.chosen_c".into(),
                format!("{} is not the classifier's C {c}", search.chosen_c),
            ));
        }
    }
    Ok(())
}
