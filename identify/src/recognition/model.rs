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

use std::collections::BTreeSet;
use std::io::{self, Read};
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::eval::{ConfusionMatrix, EvalError};
use super::knn::{Knn, KnnError, KnnParams};
use super::nakano::{FEATURES, NakanoConfig, NakanoError, NakanoSignals};
use super::som::{Som, SomError, SomParams};
use super::spectral::{CellScale, SpectralError, SpectrogramPlan};
use super::svc::{Svc, SvcError, SvcParams};
use crate::capture::{Capture, CaptureError, CaptureKind, write_atomically};
use crate::model_file::{CaptureRef, sha256_hex};

/// Format name in every recognizer file.
pub const RECOGNIZER_FORMAT: &str = "palpus-recognizer";
/// Current recognizer file version.
pub const RECOGNIZER_VERSION: u32 = 1;
/// Metadata key of a capture's class.
pub const LABEL_KEY: &str = "surface";
/// Metadata key of a scratch's exploratory behaviour.
pub const BEHAVIOUR_KEY: &str = "behaviour";

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

/// How a rubbing stream is cut into the windows the map decides on.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct NakanoWindowing {
    /// The two zero-phase moving averages.
    pub filters: NakanoConfig,
    /// Samples per window.
    pub window_samples: usize,
    /// Samples between decisions.
    pub hop_samples: usize,
    /// No decision on a window that starts before this travel from the first sample, m.
    pub start_travel_m: f64,
    /// Sample rate the windows are counted at, Hz.
    pub rate_hz: f64,
}

impl NakanoWindowing {
    /// The protocol's windowing: `window_s` and `hop_s` at `rate_hz`, the default filters, and
    /// decisions from 5 mm of travel on (thesis Sec. 4.3).
    pub fn new(window_s: f64, hop_s: f64, rate_hz: f64) -> Result<Self, RecognizerError> {
        let windowing = Self {
            filters: NakanoConfig::default(),
            window_samples: samples("window_s", window_s, rate_hz)?,
            hop_samples: samples("hop_s", hop_s, rate_hz)?,
            start_travel_m: 0.005,
            rate_hz,
        };
        windowing
            .check()
            .map_err(|(name, reason)| RecognizerError::Setting {
                name,
                value: f64::NAN,
                reason,
            })?;
        Ok(windowing)
    }

    /// The same windowing with a window of `window_s` instead.
    pub fn with_window_s(self, window_s: f64) -> Result<Self, RecognizerError> {
        Ok(Self {
            window_samples: samples("window_s", window_s, self.rate_hz)?,
            ..self
        })
    }

    fn check(&self) -> Result<(), (&'static str, &'static str)> {
        if self.window_samples < 2 {
            return Err(("window_samples", "at least 2"));
        }
        if self.hop_samples == 0 {
            return Err(("hop_samples", "at least 1"));
        }
        if !(self.start_travel_m.is_finite() && self.start_travel_m >= 0.0) {
            return Err(("start_travel_m", "finite and not negative"));
        }
        if !(self.rate_hz.is_finite() && self.rate_hz > 0.0) {
            return Err(("rate_hz", "positive and finite"));
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

fn samples(name: &'static str, seconds: f64, rate_hz: f64) -> Result<usize, RecognizerError> {
    let n = (seconds * rate_hz).round();
    if !(seconds.is_finite() && seconds > 0.0 && (1.0..=1e8).contains(&n)) {
        return Err(RecognizerError::Setting {
            name,
            value: seconds,
            reason: "positive, at least one sample and at most 10^8 samples",
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
}

/// One behaviour's SVC.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BehaviourSvc {
    /// The behaviour (metadata `behaviour`); `None` for captures without one.
    pub behaviour: Option<String>,
    /// Its one-vs-one SVC over spectrotemporal histograms, with probabilities.
    pub svc: Svc,
}

/// The trained classifier and how its features are computed.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "method", rename_all = "snake_case")]
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
}

impl RecognizerBody {
    /// `som`, `knn` or `svm`.
    pub fn method(&self) -> &'static str {
        match self {
            Self::Som { .. } => "som",
            Self::Knn { .. } => "knn",
            Self::Svm { .. } => "svm",
        }
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
    /// Trains Nakano's SOM on the windows of `captures`.
    pub fn train_som(
        captures: &[LabelledCapture],
        windowing: NakanoWindowing,
        params: SomParams,
    ) -> Result<Self, RecognizerError> {
        let classes = class_list(captures);
        let (mut data, mut labels) = (Vec::new(), Vec::new());
        for c in captures {
            check_rate(c, windowing.rate_hz)?;
            let label = class_index(&classes, c)?;
            for (_, features) in windows(c, &windowing)? {
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
        for (name, x, y) in histograms_by_behaviour(captures, &classes, cell_scale)? {
            let knn = params
                .fit(&x, &y, classes.len())
                .map_err(|source| RecognizerError::Knn {
                    behaviour: name.unwrap_or("").to_owned(),
                    source,
                })?;
            behaviours.push(BehaviourKnn {
                behaviour: name.map(str::to_owned),
                knn,
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

    /// Trains one SVC per behaviour on one histogram per capture.
    pub fn train_svm(
        captures: &[LabelledCapture],
        params: SvcParams,
        cell_scale: CellScale,
    ) -> Result<Self, RecognizerError> {
        let classes = class_list(captures);
        let mut behaviours = Vec::new();
        for (name, x, y) in histograms_by_behaviour(captures, &classes, cell_scale)? {
            let svc = Svc::fit(params, &x, &y, classes.len()).map_err(|source| RecognizerError::Svc {
                behaviour: name.unwrap_or("").to_owned(),
                source,
            })?;
            behaviours.push(BehaviourSvc {
                behaviour: name.map(str::to_owned),
                svc,
            });
        }
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

    /// The windowing, for a SOM recognizer.
    pub fn windowing(&self) -> Option<&NakanoWindowing> {
        match &self.body {
            RecognizerBody::Som { windowing, .. } => Some(windowing),
            RecognizerBody::Knn { .. } | RecognizerBody::Svm { .. } => None,
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
            RecognizerBody::Knn {
                cell_scale,
                behaviours,
            } => {
                let model = for_behaviour(behaviours, |b| &b.behaviour, capture)?;
                let features = spectral(&SpectrogramPlan::new(), capture, *cell_scale)?;
                let knn_error = |source| RecognizerError::Knn {
                    behaviour: capture.behaviour.clone().unwrap_or_default(),
                    source,
                };
                let label = model.knn.predict(&features).map_err(knn_error)?;
                let p = model.knn.predict_proba(&features).map_err(knn_error)?;
                Ok(vec![whole_capture_decision(capture, label, &p)])
            }
            RecognizerBody::Svm {
                cell_scale,
                behaviours,
            } => {
                let model = for_behaviour(behaviours, |b| &b.behaviour, capture)?;
                let features = spectral(&SpectrogramPlan::new(), capture, *cell_scale)?;
                let svc_error = |source| RecognizerError::Svc {
                    behaviour: capture.behaviour.clone().unwrap_or_default(),
                    source,
                };
                let label = model.svc.predict(&features).map_err(svc_error)?;
                let p = model.svc.predict_proba(&features).map_err(svc_error)?;
                Ok(vec![whole_capture_decision(capture, label, &p)])
            }
        }
    }

    /// Evaluates on `captures`; `window_s` overrides a SOM's window length.
    pub fn evaluate(
        &self,
        captures: &[LabelledCapture],
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
                    .map_err(|(f, r)| (format!("body.windowing.{f}"), r.to_owned()))?;
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
                }
            }
        }
        Ok(())
    }
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

/// Sinapov's histogram of each capture with its class index, grouped by behaviour (k-NN and SVM
/// recognizers keep one classifier per behaviour).
#[allow(clippy::type_complexity)] // one use, read in place
fn histograms_by_behaviour<'a>(
    captures: &'a [LabelledCapture],
    classes: &[String],
    cell_scale: CellScale,
) -> Result<
    Vec<(
        Option<&'a str>,
        Vec<[f64; super::spectral::FEATURE_LEN]>,
        Vec<usize>,
    )>,
    RecognizerError,
> {
    let plan = SpectrogramPlan::new();
    let names: BTreeSet<Option<&str>> = captures.iter().map(|c| c.behaviour.as_deref()).collect();
    let mut out = Vec::new();
    for name in names {
        let (mut x, mut y) = (Vec::new(), Vec::new());
        for c in captures.iter().filter(|c| c.behaviour.as_deref() == name) {
            x.push(spectral(&plan, c, cell_scale)?);
            y.push(class_index(classes, c)?);
        }
        out.push((name, x, y));
    }
    Ok(out)
}

/// The classifier of the capture's behaviour (k-NN and SVM recognizers keep one per behaviour).
fn for_behaviour<'a, T>(
    behaviours: &'a [T],
    name: impl Fn(&T) -> &Option<String>,
    capture: &LabelledCapture,
) -> Result<&'a T, RecognizerError> {
    behaviours
        .iter()
        .find(|b| *name(b) == capture.behaviour)
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
    use crate::capture::Metadata;

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
        let err = RecognizerFile::from_json("{\"format\": 1", Path::new("r.json")).expect_err("parse");
        assert!(matches!(err, RecognizerError::Parse { line: 1, .. }), "{err}");
        // A capture of a surface the map does not know.
        let unknown = rubbing("glass", 1e-6, 1e-3, 0.1, 3.0);
        let err = model.evaluate(&[unknown], None).expect_err("unknown surface");
        assert!(err.to_string().contains("surface `glass`"), "{err}");
    }
}
