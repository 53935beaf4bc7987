//! A k-NN's or SVM's window classifier that allocates nothing per window, for a thread that
//! must not (the haptic loop's): every buffer it needs is made once, when it is built.
//!
//! Its probabilities are those of [`RecognizerFile::window_probabilities`] to the bit: the
//! same scaling and the same classifier arithmetic, on buffers kept between windows.

use super::file::{RecognizerBody, RecognizerFile};
use crate::RecognizeError;
use crate::features::spectral::{CellScale, Histogram};
use crate::features::{FeatureSet, NakanoWindowing, WindowScaling};
use crate::knn::{Knn, KnnScratch, VoteCalibration};
use crate::svc::{Svc, SvcScratch};
use crate::{SettingError, UsageError};

/// A classifier and the buffers it works on.
#[derive(Debug)]
enum Scratched {
    Knn(Box<Knn>, KnnScratch, Option<VoteCalibration>),
    Svc(Box<Svc>, SvcScratch),
}

/// The window classifier of a k-NN or SVM recognizer over rubbing windows, with its feature
/// scaling and buffers.
#[derive(Debug)]
pub struct WindowClassifier {
    classifier: Scratched,
    scaling: WindowScaling,
    features: FeatureSet,
    windowing: NakanoWindowing,
    scaled: Vec<f64>,
    classes: usize,
    histogram: Histogram,
}

impl Clone for WindowClassifier {
    /// A copy with its own buffers (the search tree of a k-NN built for it too).
    fn clone(&self) -> Self {
        let classifier = match &self.classifier {
            Scratched::Knn(knn, _, calibration) => {
                let knn = knn.clone();
                let scratch = knn.scratch();
                Scratched::Knn(knn, scratch, *calibration)
            }
            Scratched::Svc(svc, _) => {
                let svc = svc.clone();
                let scratch = svc.scratch();
                Scratched::Svc(svc, scratch)
            }
        };
        Self {
            classifier,
            scaling: self.scaling.clone(),
            features: self.features,
            windowing: self.windowing,
            scaled: vec![0.0; self.scaled.len()],
            classes: self.classes,
            histogram: self.histogram,
        }
    }
}

impl WindowClassifier {
    /// The classifier of `model`, which must be a k-NN or SVM over windows (any other gives no
    /// per-window probabilities, and is refused saying so).
    pub fn new(model: &RecognizerFile) -> Result<Self, RecognizeError> {
        let (classifier, scaling, features, dim, histogram) = match &model.body {
            RecognizerBody::KnnWindows {
                knn,
                scaling,
                features,
                calibration,
                histogram,
                ..
            } => {
                let knn = Box::new(knn.clone());
                let scratch = knn.scratch();
                let dim = knn.dim();
                (
                    Scratched::Knn(knn, scratch, *calibration),
                    scaling,
                    *features,
                    dim,
                    *histogram,
                )
            }
            RecognizerBody::SvmWindows {
                svc,
                scaling,
                features,
                histogram,
                ..
            } => {
                let svc = Box::new(svc.clone());
                let scratch = svc.scratch();
                let dim = svc.dim();
                (Scratched::Svc(svc, scratch), scaling, *features, dim, *histogram)
            }
            body => {
                return Err(RecognizeError::Setting(SettingError::NoWindowProbabilities {
                    method: body.method(),
                    features: body.feature_set().name(),
                }));
            }
        };
        let windowing = model.sequential_windowing().ok_or(RecognizeError::Setting(
            SettingError::NoWindowProbabilities {
                method: model.method(),
                features: features.name(),
            },
        ))?;
        Ok(Self {
            classifier,
            scaling: scaling.clone(),
            features,
            windowing,
            scaled: vec![0.0; dim],
            classes: model.classes.len(),
            histogram,
        })
    }

    /// The features it takes.
    pub fn features(&self) -> FeatureSet {
        self.features
    }

    /// How its windows' histogram or spectrum cells are scaled.
    pub fn cell_scale(&self) -> CellScale {
        self.histogram.cells
    }

    /// The windows it classifies, from contact on
    /// ([`RecognizerFile::sequential_windowing`]).
    pub fn windowing(&self) -> &NakanoWindowing {
        &self.windowing
    }

    /// Number of classes, the length of every probability vector.
    pub fn classes(&self) -> usize {
        self.classes
    }

    /// Every class's probability for one window's raw features, into `p`: no allocation.
    pub fn probabilities_into(&mut self, features: &[f64], p: &mut [f64]) -> Result<(), RecognizeError> {
        if features.len() != self.scaled.len() {
            return Err(RecognizeError::Usage(UsageError::Dimension {
                index: 0,
                got: features.len(),
                expected: self.scaled.len(),
            }));
        }
        self.scaling.apply_into(features, &mut self.scaled);
        match &mut self.classifier {
            Scratched::Knn(knn, scratch, calibration) => {
                knn.predict_proba_into(&self.scaled, scratch, p)?;
                if let Some(c) = calibration {
                    c.apply(p);
                }
                Ok(())
            }
            Scratched::Svc(svc, scratch) => svc.predict_proba_into(&self.scaled, scratch, p),
        }
    }
}
