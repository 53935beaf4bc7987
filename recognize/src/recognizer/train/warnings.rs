//! Warnings about the training data, found before training: a class with too few training
//! vectors, features that are the same in every vector, windows left out for a tool at rest.
//! Training still runs; the library returns them as data ([`TrainSettings::data_warnings`]) and
//! the CLI prints them.

use super::{
    CV_FOLDS, LEAST_TRAINING_TRAVEL_SHARE, Method, TrainSettings, histograms_by_behaviour,
    training_windows_left_out,
};
use crate::RecognizeError;
use crate::TRAVEL_PLAY_M;
use crate::features::{FeatureSet, TooFastWindows};
use crate::recognizer::LabelledCapture;
use crate::recognizer::labelled::class_list;

/// Fewer training vectors of a class than this in one classifier draw a warning
/// ([`TrainingWarning::FewVectors`]): the cross-validations that weigh behaviours and choose an
/// SVM's C hold out at most [`CV_FOLDS`] folds, so a class needs a vector for each to be tested
/// in every fold, and a handful of vectors cannot show a class's spread. A k-NN needs at least
/// its k as well, or a query's neighbours always include other classes.
pub const FEW_TRAINING_VECTORS: usize = CV_FOLDS;

/// Something about the training data that weakens a recognizer without stopping its training.
#[derive(Debug, Clone, PartialEq)]
pub enum TrainingWarning {
    /// A class has fewer training vectors than `least` in one classifier.
    FewVectors {
        /// The classifier's behaviour, for one classifier per behaviour; `None` for one
        /// classifier over every capture (windows), or captures without a behaviour.
        behaviour: Option<String>,
        /// The class.
        class: String,
        /// Its training vectors in that classifier.
        vectors: usize,
        /// The fewest without this warning.
        least: usize,
    },
    /// Features with the same value in every training vector of one classifier: they cannot
    /// tell classes apart (a sensor that was stuck, unplugged, or not recorded).
    ConstantFeatures {
        /// The classifier's behaviour, as in [`TrainingWarning::FewVectors`].
        behaviour: Option<String>,
        /// The features, in vector order, and the value each always has.
        features: Vec<(String, f64)>,
        /// Features in a vector.
        of: usize,
        /// Training vectors of the classifier.
        vectors: usize,
    },
    /// Training windows left out for covering less than [`LEAST_TRAINING_TRAVEL_SHARE`] of
    /// their travel: the tool rested, or over travel crawled below the slowest speed the
    /// windows read.
    ShortOfTravel {
        /// Windows left out, and windows in all.
        left_out: usize,
        of: usize,
        /// Over travel, the slowest speed the windows read, m/s; `None` for windows of fixed
        /// length, which leave out only a tool at rest.
        slowest_speed_mps: Option<f64>,
    },
    /// Training windows over travel left out because they slid faster than their bands can be
    /// read at the captures' rate (a rig's position stream at a low rate can read a burst of
    /// speed); training goes on without them.
    TooFast(TooFastWindows),
}

impl std::fmt::Display for TrainingWarning {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let classifier = |b: &Option<String>| match b {
            Some(b) => format!("the classifier of behaviour {b}"),
            None => "the classifier".to_owned(),
        };
        match self {
            Self::FewVectors {
                behaviour,
                class,
                vectors,
                least,
            } => write!(
                f,
                "class {class} has {vectors} training vector{} in {} (fewer than {least}): too few to show its spread or to be cross-validated; more captures of it would help",
                if *vectors == 1 { "" } else { "s" },
                classifier(behaviour)
            ),
            Self::ConstantFeatures {
                behaviour,
                features,
                of,
                vectors,
            } => {
                const SHOWN: usize = 5;
                let mut names: Vec<String> = features
                    .iter()
                    .take(SHOWN)
                    .map(|(name, value)| format!("{name} = {value}"))
                    .collect();
                if features.len() > SHOWN {
                    names.push(format!("and {} more", features.len() - SHOWN));
                }
                write!(
                    f,
                    "{} of {of} features are constant over all {vectors} training vectors of {} ({}): they cannot tell classes apart (a sensor stuck, unplugged or not recorded?)",
                    features.len(),
                    classifier(behaviour),
                    names.join(", ")
                )
            }
            Self::ShortOfTravel {
                left_out,
                of,
                slowest_speed_mps: Some(slowest_speed_mps),
            } => write!(
                f,
                "{left_out} of {of} training windows were left out: each covered less than {:.0} % of its travel, rubbed well below the slowest speed the windows read ({:.1} mm/s), so it holds mostly the tool at rest; if the rig rubs that slowly, a lower --slowest-speed-mps reads it",
                100.0 * LEAST_TRAINING_TRAVEL_SHARE,
                1e3 * slowest_speed_mps
            ),
            Self::TooFast(t) => write!(
                f,
                "{} training window{} left out: slid at up to {:.1} mm/s, faster than the bands over travel can be read at this rate ({:.1} mm/s); if the rig rubs that fast, a higher --fastest-speed-mps reads it with narrower bands",
                t.count,
                if t.count == 1 { " was" } else { "s were" },
                1e3 * t.fastest_mps,
                1e3 * t.readable_up_to_mps
            ),
            Self::ShortOfTravel {
                left_out,
                of,
                slowest_speed_mps: None,
            } => write!(
                f,
                "{left_out} of {of} training windows were left out: in each the tool never left the {:.1} mm play, so it holds the tool at rest",
                1e3 * TRAVEL_PLAY_M
            ),
        }
    }
}

impl TrainSettings {
    /// What weakens a recognizer trained as these settings say on `captures`, without stopping
    /// its training: classes with fewer vectors than [`FEW_TRAINING_VECTORS`] (a k-NN's k, if
    /// more) in a classifier, and features constant over a classifier's vectors. Classifiers
    /// are one per behaviour over whole-scratch histograms, one over all windows otherwise.
    /// The vectors are those training computes; its errors (a class without windows, a
    /// missing column) are returned as training would return them.
    pub fn data_warnings(
        &self,
        captures: &[LabelledCapture],
    ) -> Result<Vec<TrainingWarning>, RecognizeError> {
        self.features.check_columns(captures)?;
        let classes = class_list(captures);
        let least = match self.method {
            Method::Knn => FEW_TRAINING_VECTORS.max(self.k),
            Method::Som | Method::Svm => FEW_TRAINING_VECTORS,
        };
        let names = self.features.feature_names();
        let mut warnings = Vec::new();
        let mut check = |behaviour: Option<&str>, x: &[&[f64]], y: &[usize]| {
            let behaviour = behaviour.map(str::to_owned);
            let mut counts = vec![0usize; classes.len()];
            for &l in y {
                counts[l] += 1;
            }
            for (class, &vectors) in classes.iter().zip(&counts) {
                if vectors < least {
                    warnings.push(TrainingWarning::FewVectors {
                        behaviour: behaviour.clone(),
                        class: class.clone(),
                        vectors,
                        least,
                    });
                }
            }
            let constant = constant_features(x);
            if x.len() > 1 && !constant.is_empty() {
                warnings.push(TrainingWarning::ConstantFeatures {
                    behaviour,
                    features: constant.into_iter().map(|(j, v)| (names[j].clone(), v)).collect(),
                    of: names.len(),
                    vectors: x.len(),
                });
            }
        };
        match self.features {
            FeatureSet::Spectral => {
                for (behaviour, x, y, _) in histograms_by_behaviour(captures, &classes, self.histogram)? {
                    let x: Vec<&[f64]> = x.iter().map(|v| v.as_slice()).collect();
                    check(behaviour, &x, &y);
                }
            }
            windowed => {
                let windowing = self.windowing(captures)?;
                let ((x, y, _), left_out, of, too_fast) =
                    training_windows_left_out(captures, &classes, &windowing, windowed, self.histogram)?;
                let x: Vec<&[f64]> = x.iter().map(Vec::as_slice).collect();
                check(None, &x, &y);
                if too_fast.count > 0 {
                    warnings.push(TrainingWarning::TooFast(too_fast));
                }
                if left_out > 0 {
                    warnings.push(TrainingWarning::ShortOfTravel {
                        left_out,
                        of,
                        slowest_speed_mps: windowing.training().slowest_speed_mps(),
                    });
                }
            }
        }
        Ok(warnings)
    }
}

/// The features (index, value) that have one value in every vector of `x`.
fn constant_features(x: &[&[f64]]) -> Vec<(usize, f64)> {
    let Some(first) = x.first() else {
        return Vec::new();
    };
    first
        .iter()
        .enumerate()
        .filter(|&(j, &v)| x.iter().all(|row| row[j] == v))
        .map(|(j, &v)| (j, v))
        .collect()
}
