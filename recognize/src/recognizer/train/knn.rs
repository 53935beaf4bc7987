//! The k-NN's trainer: one classifier per behaviour over whole-scratch histograms (Sinapov), or
//! one over rubbing windows.

use super::{
    CV_FOLDS, Method, ScaledWindows, TrainJob, Trainer, every_class_in_two_groups, histograms_by_behaviour,
    scaled_training_windows,
};
use crate::DataError;
use crate::RecognizeError;
#[cfg(doc)]
use crate::features::WindowScaling;
use crate::features::spectral::Histogram;
use crate::features::{FeatureSet, NakanoWindowing};
use crate::folds::group_folds;
use crate::fusion::cross_validated_accuracy;
use crate::knn::{FeatureScaling, KnnParams, VoteCalibration, held_out_votes};
use crate::recognizer::labelled::class_list;
#[cfg(doc)]
use crate::recognizer::trial_groups;
use crate::recognizer::{BehaviourKnn, LabelledCapture, RecognizerBody, RecognizerFile};

/// Trains k-NN recognizers with `settings.k` neighbours: one classifier per behaviour over
/// whole-scratch histograms ([`RecognizerFile::train_knn`]), or one over rubbing windows
/// ([`RecognizerFile::train_knn_windows`]).
#[derive(Debug, Clone, Copy, Default)]
pub struct KnnTrainer;

impl Trainer for KnnTrainer {
    fn method(&self) -> Method {
        Method::Knn
    }

    fn train(&self, job: TrainJob<'_>) -> Result<RecognizerFile, RecognizeError> {
        let TrainJob {
            captures, settings, ..
        } = job;
        match settings.features {
            FeatureSet::Spectral => {
                RecognizerFile::train_knn(captures, KnnParams::default().k(settings.k), settings.histogram)
            }
            windowed => RecognizerFile::train_knn_windows(
                captures,
                settings.windowing(captures)?,
                windowed,
                settings.k,
                settings.histogram,
            ),
        }
    }
}

impl RecognizerFile {
    /// Trains Sinapov's k-NN on one histogram per capture, one classifier per behaviour.
    pub fn train_knn(
        captures: &[LabelledCapture],
        params: KnnParams,
        histogram: impl Into<Histogram>,
    ) -> Result<Self, RecognizeError> {
        let histogram = histogram.into();
        let classes = class_list(captures);
        let mut behaviours = Vec::new();
        for (name, x, y, groups) in histograms_by_behaviour(captures, &classes, histogram)? {
            let knn = params
                .fit(&x, &y, classes.len())
                .map_err(RecognizeError::knn(name))?;
            // The fit above has checked the data, so a failing cross-validation only means
            // too few trials (or too few scratches outside a fold): no weight, see
            // `fusion_weights`.
            let cv = group_folds(&groups, CV_FOLDS).ok().and_then(|(_, folds)| {
                cross_validated_accuracy(params, &x, &y, &groups, classes.len(), CV_FOLDS)
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
        Self::assemble_scratches(
            classes,
            behaviours.len(),
            RecognizerBody::Knn {
                histogram,
                behaviours,
            },
            captures,
        )
    }

    /// k-NN over rubbing windows (`features` [`FeatureSet::Nakano`] or [`FeatureSet::Both`]):
    /// windowed like the SOM, one classifier over every training window, scaled by
    /// [`WindowScaling`]. When every surface has captures of two runs or trials, its votes are
    /// calibrated on windows held out by run or trial ([`VoteCalibration`]), which also
    /// measures the reliability it is fused by.
    pub fn train_knn_windows(
        captures: &[LabelledCapture],
        windowing: NakanoWindowing,
        features: FeatureSet,
        k: usize,
        histogram: impl Into<Histogram>,
    ) -> Result<Self, RecognizeError> {
        Self::knn_windows(captures, windowing, features, k, histogram.into(), None)
    }

    /// [`RecognizerFile::train_knn_windows`] with its votes calibrated by `calibration`
    /// instead of a cross-validation of its own: the posterior weight's refits. The
    /// calibration is one blend weight, fitted by cross-validation on all the training
    /// captures; fitting it again in each of twenty refits took five k-NN cross-validations a
    /// refit, most of a default training.
    pub(crate) fn refit_knn_windows(
        captures: &[LabelledCapture],
        windowing: NakanoWindowing,
        features: FeatureSet,
        k: usize,
        histogram: Histogram,
        calibration: VoteCalibration,
    ) -> Result<Self, RecognizeError> {
        Self::knn_windows(captures, windowing, features, k, histogram, Some(calibration))
    }

    /// A k-NN over windows, its votes calibrated by `calibration`, else by cross-validation.
    fn knn_windows(
        captures: &[LabelledCapture],
        windowing: NakanoWindowing,
        features: FeatureSet,
        k: usize,
        histogram: Histogram,
        calibration: Option<VoteCalibration>,
    ) -> Result<Self, RecognizeError> {
        let ScaledWindows {
            classes,
            scaling,
            x,
            y,
            groups,
            ..
        } = scaled_training_windows(captures, &windowing, features, histogram)?;
        let params = KnnParams::default().k(k).scaling(FeatureScaling::None);
        let knn = params
            .fit(&x, &y, classes.len())
            .map_err(RecognizeError::knn(None))?;
        let calibration = match calibration {
            Some(given) => Some(given),
            // A fold's training windows can be fewer than k where all of them are not: then
            // nothing can be held out, as with a single run, and the votes stay raw.
            None => match every_class_in_two_groups(&y, &groups)
                .then(|| held_out_votes(params, &x, &y, &groups, classes.len(), CV_FOLDS))
            {
                Some(Ok((votes, folds))) => Some(VoteCalibration::fit(&votes, &y, classes.len(), folds)?),
                None | Some(Err(RecognizeError::Data(DataError::TooFewPoints { .. }))) => None,
                Some(Err(e)) => return Err(e),
            },
        };
        Ok(Self::assemble(
            classes,
            features.feature_names(),
            RecognizerBody::KnnWindows {
                features,
                windowing,
                histogram,
                scaling,
                knn,
                calibration,
            },
            captures,
            x.len(),
        ))
    }
}
