//! Decisions: a recognizer's labels on a capture (one per decision window, or one per
//! scratch), and the behaviours' reliabilities and fusion weights.

use super::LabelledCapture;
use super::file::{BehaviourSom, RecognizerBody, RecognizerFile};
use super::labelled::check_rate;
use crate::RecognizerError;
use crate::features::nakano::FEATURES;
use crate::features::spectral::{CellScale, SpectrogramPlan};
use crate::features::{FeatureSet, NakanoWindowing, capture_histogram, window_vectors, windows};
#[cfg(doc)]
use crate::som::Som;
use crate::svc::CSearch;

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
    /// Confidence in `[0, 1]` (see [`Som::decide_into`]; k-NN: the vote fraction).
    pub confidence: f64,
}

impl RecognizerFile {
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
        window_vectors(capture, windowing, features, cell_scale, &plan)?
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
    pub(crate) fn scratch_prediction(
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
                let features = capture_histogram(plan, capture, *cell_scale)?;
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
                let features = capture_histogram(plan, capture, *cell_scale)?;
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
                let features = capture_histogram(plan, capture, *cell_scale)?;
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
            RecognizerBody::SomScratches { behaviours, .. } => som_reliabilities(behaviours),
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
}

/// Reliabilities of a [`RecognizerBody::SomScratches`], for
/// [`RecognizerFile::reliabilities`].
fn som_reliabilities(behaviours: &[BehaviourSom]) -> Vec<BehaviourReliability<'_>> {
    behaviours
        .iter()
        .map(|b| BehaviourReliability {
            behaviour: b.behaviour.as_deref(),
            reliability: b.reliability,
            folds: b.reliability_folds,
            c_search: None,
            c: None,
        })
        .collect()
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
