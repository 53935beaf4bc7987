//! Decisions: a recognizer's labels on a capture (one per decision window, or one per
//! scratch), and the behaviours' reliabilities and fusion weights.

use super::LabelledCapture;
use super::file::{BehaviourKnn, BehaviourSom, BehaviourSvc, RecognizerBody, RecognizerFile};
use super::labelled::check_rate;
use crate::InputError;
use crate::RecognizeError;
use crate::features::nakano::FEATURES;
use crate::features::spectral::Histogram;
use crate::features::{FeatureSet, NakanoWindowing, capture_histogram, window_vectors, windows};
use crate::knn::Knn;
use crate::som::{Som, SomDecision};
use crate::svc::{CSearch, Svc};

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

/// One decision of the offline pipeline.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Decision {
    /// First sample of the window (0 for a whole-capture decision).
    pub window_start: usize,
    /// The sample at which the decision is available.
    pub decided_at: usize,
    /// Index into [`RecognizerFile::classes`].
    pub label: usize,
    /// Confidence in `[0, 1]` (see [`Som::decide_into`]; k-NN: the vote fraction, calibrated
    /// when the k-NN over windows carries a [`crate::knn::VoteCalibration`]).
    pub confidence: f64,
}

/// One window of a k-NN or SVM over windows: its decision and every class's probability
/// ([`RecognizerFile::window_probabilities`]).
#[derive(Debug, Clone, PartialEq)]
pub struct WindowProbabilities {
    /// The window and its decision, as [`RecognizerFile::decisions`] gives it.
    pub decision: Decision,
    /// Probability of each class, in [`RecognizerFile::classes`]' order; they sum to 1.
    pub probabilities: Vec<f64>,
    /// Its evidence relative to a window of the windowing's nominal length
    /// ([`NakanoWindowing::evidence`]): 1 but for windows over travel, 0 for one in which the
    /// tool never left the play.
    pub evidence_scale: f64,
    /// Whether it covered less than its travel ([`NakanoWindowing::short_of_travel`]): over
    /// travel, rubbed slower than the slowest speed its windows read; of either windowing, a
    /// tool at rest.
    pub short_of_travel: bool,
}

impl RecognizerFile {
    /// For a SOM over Nakano's windows: the winning node of each of `capture`'s decision
    /// windows (`windowing`, else the recognizer's own), in the order of
    /// [`RecognizerFile::decisions`]; `None` for any other recognizer. Reads a capture whose
    /// features were kept for those windows as well as a whole one.
    pub fn som_winners(
        &self,
        capture: &LabelledCapture,
        windowing: Option<&NakanoWindowing>,
    ) -> Result<Option<Vec<usize>>, RecognizeError> {
        let RecognizerBody::Som { windowing: own, som } = &self.body else {
            return Ok(None);
        };
        let decided = som_windows(capture, windowing.unwrap_or(own), som)?;
        Ok(Some(decided.into_iter().map(|(_, d)| d.node).collect()))
    }

    /// The offline pipeline's decisions on one capture (`windowing` overrides the model's, for
    /// a SOM): one per decision window for a SOM, one per capture for a k-NN.
    pub fn decisions(
        &self,
        capture: &LabelledCapture,
        windowing: Option<&NakanoWindowing>,
    ) -> Result<Vec<Decision>, RecognizeError> {
        match &self.body {
            RecognizerBody::Som { windowing: own, som } => {
                let windowing = windowing.unwrap_or(own);
                Ok(som_windows(capture, windowing, som)?
                    .into_iter()
                    .map(|(start, d)| Decision {
                        window_start: start,
                        decided_at: windowing.decided_at(start),
                        label: som.node_labels().get(d.node).copied().unwrap_or(0),
                        confidence: d.confidence,
                    })
                    .collect())
            }
            RecognizerBody::KnnWindows { .. } | RecognizerBody::SvmWindows { .. } => Ok(self
                .window_probabilities(capture, windowing)?
                .unwrap_or_default()
                .into_iter()
                .map(|w| w.decision)
                .collect()),
            RecognizerBody::SomWindows {
                windowing: own,
                histogram,
                som,
            } => {
                let windowing = windowing.unwrap_or(own);
                let mut scratch = vec![0.0; som.dim()];
                self.window_decisions(capture, windowing, FeatureSet::Both, *histogram, |v| {
                    let d = som.decide_into(v, &mut scratch).map_err(RecognizeError::som)?;
                    Ok((som.node_labels().get(d.node).copied().unwrap_or(0), d.confidence))
                })
            }
            RecognizerBody::Knn { .. } | RecognizerBody::Svm { .. } | RecognizerBody::SomScratches { .. } => {
                let (_, label, p) = self.scratch_prediction(capture)?;
                Ok(vec![whole_capture_decision(capture, label, &p)])
            }
        }
    }

    /// For a k-NN or SVM over rubbing windows: each decision window of `capture` (`windowing`,
    /// else the recognizer's own) with its every class's probability, in the order of
    /// [`RecognizerFile::decisions`]; `None` for any other recognizer (a SOM names a node, not
    /// a distribution over the surfaces; a whole-scratch classifier has no windows).
    pub fn window_probabilities(
        &self,
        capture: &LabelledCapture,
        windowing: Option<&NakanoWindowing>,
    ) -> Result<Option<Vec<WindowProbabilities>>, RecognizeError> {
        let (windowing, features, histogram, scaling, classifier, calibration) = match &self.body {
            RecognizerBody::KnnWindows {
                features,
                windowing: own,
                histogram,
                scaling,
                knn,
                calibration,
            } => {
                let knn: &dyn Classifier = knn;
                (
                    windowing.unwrap_or(own),
                    *features,
                    *histogram,
                    scaling,
                    knn,
                    *calibration,
                )
            }
            RecognizerBody::SvmWindows {
                features,
                windowing: own,
                histogram,
                scaling,
                svc,
                ..
            } => {
                let svc: &dyn Classifier = svc;
                (
                    windowing.unwrap_or(own),
                    *features,
                    *histogram,
                    scaling,
                    svc,
                    None,
                )
            }
            _ => return Ok(None),
        };
        features.check_columns(std::slice::from_ref(capture))?;
        check_rate(capture, windowing.rate_hz)?;
        let windows =
            window_vectors(capture, windowing, features, histogram)?.decidable(capture, features)?;
        let scaled: Vec<Vec<f64>> = windows.iter().map(|(_, _, v)| scaling.apply(v)).collect();
        let classified = classifier.classify_many(&scaled)?;
        let mut out = Vec::with_capacity(windows.len());
        for ((start, span, _), (label, mut p)) in windows.into_iter().zip(classified) {
            if let Some(c) = calibration {
                c.apply(&mut p);
            }
            let decision = Decision {
                window_start: start,
                decided_at: windowing.decided_at(start),
                label,
                confidence: p.get(label).copied().unwrap_or(0.0),
            };
            out.push(WindowProbabilities {
                decision,
                probabilities: p,
                evidence_scale: windowing.evidence(span),
                short_of_travel: windowing.short_of_travel(span),
            });
        }
        Ok(Some(out))
    }

    /// Decisions of a classifier over rubbing windows: `classify` maps a window's raw features
    /// to a label and a confidence.
    fn window_decisions(
        &self,
        capture: &LabelledCapture,
        windowing: &NakanoWindowing,
        features: FeatureSet,
        histogram: Histogram,
        mut classify: impl FnMut(&[f64]) -> Result<(usize, f64), RecognizeError>,
    ) -> Result<Vec<Decision>, RecognizeError> {
        features.check_columns(std::slice::from_ref(capture))?;
        check_rate(capture, windowing.rate_hz)?;
        window_vectors(capture, windowing, features, histogram)?
            .decidable(capture, features)?
            .into_iter()
            .map(|(start, _, v)| {
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
    pub(crate) fn scratch_prediction(
        &self,
        capture: &LabelledCapture,
    ) -> Result<(usize, usize, Vec<f64>), RecognizeError> {
        match &self.body {
            RecognizerBody::Som { .. }
            | RecognizerBody::SomWindows { .. }
            | RecognizerBody::KnnWindows { .. }
            | RecognizerBody::SvmWindows { .. } => Err(RecognizeError::Input(InputError::UnusableCapture {
                path: capture.reference.path.clone(),
                reason: "a recognizer over rubbing windows does not classify whole scratches".into(),
            })),
            RecognizerBody::SomScratches {
                histogram,
                behaviours,
            } => self.scratch_prediction_by(behaviours, capture, *histogram),
            RecognizerBody::Knn {
                histogram,
                behaviours,
            } => self.scratch_prediction_by(behaviours, capture, *histogram),
            RecognizerBody::Svm {
                histogram,
                behaviours,
            } => self.scratch_prediction_by(behaviours, capture, *histogram),
        }
    }

    /// [`RecognizerFile::scratch_prediction`] by the classifier of the capture's behaviour among
    /// `behaviours`, over the capture's histogram.
    fn scratch_prediction_by(
        &self,
        behaviours: &[impl BehaviourClassifier],
        capture: &LabelledCapture,
        histogram: Histogram,
    ) -> Result<(usize, usize, Vec<f64>), RecognizeError> {
        let b = behaviour_index(behaviours, capture)?;
        let features = capture_histogram(capture, histogram)?;
        let (label, p) = behaviours[b].classify(&features, self.classes.len())?;
        Ok((b, label, p))
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
            RecognizerBody::SomScratches { behaviours, .. } => {
                behaviours.iter().map(BehaviourClassifier::reliability).collect()
            }
            RecognizerBody::Knn { behaviours, .. } => {
                behaviours.iter().map(BehaviourClassifier::reliability).collect()
            }
            RecognizerBody::Svm { behaviours, .. } => {
                behaviours.iter().map(BehaviourClassifier::reliability).collect()
            }
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
}

/// A classifier of one feature vector with class probabilities: a k-NN or an SVC.
trait Classifier {
    /// The label of `v` and every class's probability; a failure names `behaviour` (none for
    /// a classifier over windows).
    fn classify(&self, v: &[f64], behaviour: Option<&str>) -> Result<(usize, Vec<f64>), RecognizeError>;

    /// [`Classifier::classify`] of each of a classifier over windows' vectors, in order.
    fn classify_many(&self, vs: &[Vec<f64>]) -> Result<Vec<(usize, Vec<f64>)>, RecognizeError> {
        vs.iter().map(|v| self.classify(v, None)).collect()
    }
}

impl Classifier for Knn {
    fn classify(&self, v: &[f64], behaviour: Option<&str>) -> Result<(usize, Vec<f64>), RecognizeError> {
        self.predict_with_proba(v).map_err(RecognizeError::knn(behaviour))
    }

    /// All at once: the same answers, screened by one matrix product ([`Knn::predict_with_proba_many`]).
    fn classify_many(&self, vs: &[Vec<f64>]) -> Result<Vec<(usize, Vec<f64>)>, RecognizeError> {
        self.predict_with_proba_many(vs)
            .map_err(RecognizeError::knn(None))
    }
}

impl Classifier for Svc {
    fn classify(&self, v: &[f64], behaviour: Option<&str>) -> Result<(usize, Vec<f64>), RecognizeError> {
        let error = RecognizeError::svc(behaviour);
        Ok((
            self.predict(v).map_err(&error)?,
            self.predict_proba(v).map_err(error)?,
        ))
    }
}

/// One behaviour's classifier of whole-scratch histograms, as a recognizer stores it.
trait BehaviourClassifier {
    /// The behaviour it classifies.
    fn behaviour(&self) -> &Option<String>;

    /// The label of a histogram and the probabilities of the `classes` classes.
    fn classify(&self, histogram: &[f64], classes: usize) -> Result<(usize, Vec<f64>), RecognizeError>;

    /// Its stored reliability, for [`RecognizerFile::reliabilities`].
    fn reliability(&self) -> BehaviourReliability<'_>;
}

impl BehaviourClassifier for BehaviourKnn {
    fn behaviour(&self) -> &Option<String> {
        &self.behaviour
    }

    fn classify(&self, histogram: &[f64], _: usize) -> Result<(usize, Vec<f64>), RecognizeError> {
        Classifier::classify(&self.knn, histogram, self.behaviour.as_deref())
    }

    fn reliability(&self) -> BehaviourReliability<'_> {
        without_c(&self.behaviour, self.reliability, self.reliability_folds)
    }
}

impl BehaviourClassifier for BehaviourSvc {
    fn behaviour(&self) -> &Option<String> {
        &self.behaviour
    }

    fn classify(&self, histogram: &[f64], _: usize) -> Result<(usize, Vec<f64>), RecognizeError> {
        Classifier::classify(&self.svc, histogram, self.behaviour.as_deref())
    }

    fn reliability(&self) -> BehaviourReliability<'_> {
        BehaviourReliability {
            behaviour: self.behaviour.as_deref(),
            reliability: self.reliability,
            folds: self.c_search.as_ref().map(|s| s.folds),
            c_search: self.c_search.as_ref(),
            c: Some(self.svc.params().c),
        }
    }
}

impl BehaviourClassifier for BehaviourSom {
    fn behaviour(&self) -> &Option<String> {
        &self.behaviour
    }

    /// A map answers one class: its "probabilities" are that class's indicator, so a trial's
    /// fusion is a vote weighted by the behaviours' reliabilities.
    fn classify(&self, histogram: &[f64], classes: usize) -> Result<(usize, Vec<f64>), RecognizeError> {
        let label = *self.som.classify(histogram).map_err(RecognizeError::som)?;
        let mut p = vec![0.0; classes];
        if let Some(slot) = p.get_mut(label) {
            *slot = 1.0;
        }
        Ok((label, p))
    }

    fn reliability(&self) -> BehaviourReliability<'_> {
        without_c(&self.behaviour, self.reliability, self.reliability_folds)
    }
}

/// The reliability of a behaviour whose classifier has no C (k-NN, SOM).
fn without_c(
    behaviour: &Option<String>,
    reliability: Option<f64>,
    folds: Option<usize>,
) -> BehaviourReliability<'_> {
    BehaviourReliability {
        behaviour: behaviour.as_deref(),
        reliability,
        folds,
        c_search: None,
        c: None,
    }
}

/// Index of the classifier of the capture's behaviour (k-NN, SVM and scratch-SOM recognizers
/// keep one per behaviour).
fn behaviour_index(
    behaviours: &[impl BehaviourClassifier],
    capture: &LabelledCapture,
) -> Result<usize, RecognizeError> {
    behaviours
        .iter()
        .position(|b| *b.behaviour() == capture.behaviour)
        .ok_or_else(|| {
            RecognizeError::Input(InputError::UnusableCapture {
                path: capture.reference.path.clone(),
                reason: format!(
                    "behaviour {:?}: the recognizer was trained on {:?}",
                    capture.behaviour,
                    behaviours
                        .iter()
                        .map(BehaviourClassifier::behaviour)
                        .collect::<Vec<_>>()
                ),
            })
        })
}

/// One decision over a whole capture (a scratch is classified once), with its probability as
/// the confidence.
fn whole_capture_decision(capture: &LabelledCapture, label: usize, probabilities: &[f64]) -> Decision {
    Decision {
        window_start: 0,
        decided_at: capture.samples().saturating_sub(1),
        label,
        confidence: probabilities.get(label).copied().unwrap_or(0.0),
    }
}

/// The map's decision on each of `capture`'s decision windows under `windowing`, with the
/// window's first sample: what both a SOM's decisions and its winners are read from.
fn som_windows(
    capture: &LabelledCapture,
    windowing: &NakanoWindowing,
    som: &Som<usize>,
) -> Result<Vec<(usize, SomDecision)>, RecognizeError> {
    check_rate(capture, windowing.rate_hz)?;
    let mut scratch = [0.0; FEATURES];
    windows(capture, windowing)?
        .into_iter()
        .map(|(start, _, features)| {
            let d = som
                .decide_into(&features, &mut scratch)
                .map_err(RecognizeError::som)?;
            Ok((start, d))
        })
        .collect()
}
