//! Features computed ahead, so that a capture's samples can be dropped: training and evaluating
//! on hundreds of high-rate captures then holds one capture's samples at a time, plus every
//! capture's feature vectors (a few per cent of the samples).
//!
//! [`FeatureNeeds`] lists what a training or an evaluation will read (window vectors of given
//! windowings, whole-capture histograms); [`LabelledCapture::keep_features`] computes exactly
//! those, by the same functions the recognizers call on samples, and drops the samples. The
//! recognizers then read the kept vectors, so results are bit-identical to those on the whole
//! captures; asking a capture without samples for anything it did not keep is a typed error,
//! never a computation on missing samples.

use std::sync::Arc;

use super::file::{RecognizerBody, RecognizerFile};
use super::labelled::{KeptFeatures, KeptWindows, LabelledCapture, check_rate};
use crate::RecognizeError;
use crate::features::spectral::{CellScale, Histogram};
use crate::features::{
    FeatureSet, NakanoWindowing, NakanoWindows, PlayedPath, Travel, WindowVectors, capture_histogram,
    window_vectors_from, windows as windows_of,
};
use crate::{InputError, SettingError, UsageError};
use capture::Capture;

/// The features a training or an evaluation reads from each capture: window vectors (of a
/// windowing, a feature set and, for [`FeatureSet::Both`], a cell scaling) and whole-capture
/// histograms (of a cell scaling).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FeatureNeeds {
    pub(super) windows: Vec<(NakanoWindowing, FeatureSet, Histogram)>,
    pub(super) histograms: Vec<Histogram>,
}

impl FeatureNeeds {
    /// Nothing yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// Also the vectors of the windows `windowing` picks, of `features` ([`FeatureSet::Nakano`]
    /// or [`FeatureSet::Both`]; `histogram` scales the latter's histograms).
    pub fn with_windows(
        mut self,
        windowing: NakanoWindowing,
        features: FeatureSet,
        histogram: Histogram,
    ) -> Self {
        let need = (windowing, features, histogram);
        if !self.windows.contains(&need) {
            self.windows.push(need);
        }
        self
    }

    /// Also the spectrotemporal histogram of the whole capture, cells scaled by `histogram`.
    pub fn with_histogram(mut self, histogram: Histogram) -> Self {
        if !self.histograms.contains(&histogram) {
            self.histograms.push(histogram);
        }
        self
    }

    /// What [`RecognizerFile::evaluate`] with each window length of `window_s` (none: the
    /// recognizer's own), [`RecognizerFile::evaluate_fused`] and, for a decision window,
    /// [`RecognizerFile::som_quality`] read with `model`.
    pub fn evaluation(model: &RecognizerFile, window_s: &[f64]) -> Result<Self, RecognizeError> {
        let Some((windowing, features, histogram)) = window_features(&model.body) else {
            return Ok(Self::new().with_histogram(scratch_histogram(&model.body)));
        };
        if window_s.is_empty() {
            return Ok(Self::new().with_windows(*windowing, features, histogram));
        }
        window_s.iter().try_fold(Self::new(), |needs, &s| {
            Ok(needs.with_windows(windowing.with_window_s(s)?, features, histogram))
        })
    }

    /// What [`RecognizerFile::evaluate_sequential`] reads: the windows of
    /// [`RecognizerFile::sequential_windowing`]; refused for a recognizer without window
    /// probabilities.
    pub fn sequential(model: &RecognizerFile) -> Result<Self, RecognizeError> {
        match (model.sequential_windowing(), window_features(&model.body)) {
            (Some(windowing), Some((_, features, histogram))) => {
                Ok(Self::new().with_windows(windowing, features, histogram))
            }
            _ => Err(RecognizeError::Setting(SettingError::NoWindowProbabilities {
                method: model.method(),
                features: model.feature_set().name(),
            })),
        }
    }

    /// What [`RecognizerFile::evaluate_sequential_fused`] reads: every recognizer's
    /// [`FeatureNeeds::sequential`].
    pub fn sequential_fused(
        model: &RecognizerFile,
        others: &[&RecognizerFile],
    ) -> Result<Self, RecognizeError> {
        others.iter().try_fold(Self::sequential(model)?, |needs, other| {
            Ok(Self::sequential(other)?
                .windows
                .into_iter()
                .fold(needs, |needs, (w, f, s)| needs.with_windows(w, f, s)))
        })
    }

    /// Everything either needs.
    pub fn merged(self, other: Self) -> Self {
        let needs = other
            .windows
            .into_iter()
            .fold(self, |needs, (w, f, h)| needs.with_windows(w, f, h));
        other.histograms.into_iter().fold(needs, Self::with_histogram)
    }

    /// Whether nothing is needed.
    pub fn is_empty(&self) -> bool {
        self.windows.is_empty() && self.histograms.is_empty()
    }
}

/// The vectors of `mean` (windows of `features` with mean cells) with unit-sum cells: the last
/// block (the histogram or spectrum) divided by its total, summed in the order
/// [`crate::features::spectral::cell_means`] sums it, so the result is the same to the bit.
fn unit_sum_of(mean: &WindowVectors, features: FeatureSet) -> WindowVectors {
    let cells = features.blocks().last().copied().unwrap_or(0);
    let vectors = mean
        .vectors
        .iter()
        .map(|(start, span, v)| {
            let mut v = v.clone();
            let at = v.len() - cells;
            let tail = &mut v[at..];
            let total: f64 = tail.iter().sum();
            if total > 0.0 {
                tail.iter_mut().for_each(|x| *x /= total);
            }
            (*start, *span, v)
        })
        .collect();
    WindowVectors {
        vectors,
        too_fast: mean.too_fast,
    }
}

/// The windowing, features and histogram cell scale of a recognizer over rubbing windows;
/// `None` for one over whole scratches.
fn window_features(body: &RecognizerBody) -> Option<(&NakanoWindowing, FeatureSet, Histogram)> {
    match body {
        RecognizerBody::Som { windowing, .. } => Some((windowing, FeatureSet::Nakano, Histogram::default())),
        RecognizerBody::SomWindows {
            windowing, histogram, ..
        } => Some((windowing, FeatureSet::Both, *histogram)),
        RecognizerBody::KnnWindows {
            features,
            windowing,
            histogram,
            ..
        }
        | RecognizerBody::SvmWindows {
            features,
            windowing,
            histogram,
            ..
        } => Some((windowing, *features, *histogram)),
        RecognizerBody::Knn { .. } | RecognizerBody::Svm { .. } | RecognizerBody::SomScratches { .. } => None,
    }
}

/// The histogram cell scale of a recognizer over whole scratches (the mean for any other).
fn scratch_histogram(body: &RecognizerBody) -> Histogram {
    match body {
        RecognizerBody::Knn { histogram, .. }
        | RecognizerBody::Svm { histogram, .. }
        | RecognizerBody::SomScratches { histogram, .. } => *histogram,
        _ => Histogram::default(),
    }
}

impl LabelledCapture {
    /// Computes the features `needs` lists and drops the samples: `capture` keeps its header
    /// and columns but only its first sample, and the recognizers read the kept features
    /// instead (bit-identical to computing them then). A recognizer that asks for features
    /// not kept gets [`UsageError::FeaturesNotKept`]. Errors are those computing the
    /// features raises (a capture at another rate than a windowing's, a missing column, too
    /// short a capture for a histogram).
    pub fn keep_features(self, needs: &FeatureNeeds) -> Result<Self, RecognizeError> {
        if !self.has_samples() {
            return Err(RecognizeError::Usage(UsageError::FeaturesNotKept {
                path: self.reference.path.clone(),
                needed: "new features (its samples were already dropped)".to_owned(),
            }));
        }
        // The columns first, so that a capture lacking one is refused as training refuses it.
        let feature_sets = needs.windows.iter().map(|(_, features, _)| *features);
        let histograms = needs.histograms.iter().map(|_| FeatureSet::Spectral);
        for features in feature_sets.chain(histograms) {
            features.check_columns(std::slice::from_ref(&self))?;
        }
        let mut windows: Vec<KeptWindows> = Vec::with_capacity(needs.windows.len());
        // Feature sets over the same windows share their Nakano features, and a histogram's
        // unit-sum cells are its mean cells over their total: each is computed once.
        let mut nakano: Vec<(NakanoWindowing, NakanoWindows)> = Vec::new();
        for &(windowing, features, histogram) in &needs.windows {
            check_rate(&self, windowing.rate_hz)?;
            let as_mean = Histogram {
                cells: CellScale::Mean,
                ..histogram
            };
            let mean = windows
                .iter()
                .find(|k| k.windowing == windowing && k.features == features && k.histogram == as_mean);
            let vectors = match mean {
                Some(mean) if histogram.cells == CellScale::UnitSum && features != FeatureSet::Nakano => {
                    unit_sum_of(&mean.vectors, features)
                }
                _ => {
                    let memo = match nakano.iter().position(|(w, _)| *w == windowing) {
                        Some(i) => i,
                        None => {
                            nakano.push((windowing, windows_of(&self, &windowing)?));
                            nakano.len() - 1
                        }
                    };
                    window_vectors_from(&self, &windowing, features, histogram, nakano[memo].1.clone())?
                }
            };
            windows.push(KeptWindows {
                windowing,
                features,
                histogram,
                vectors,
            });
        }
        let histograms = needs
            .histograms
            .iter()
            .map(|&scale| Ok((scale, capture_histogram(&self, scale)?)))
            .collect::<Result<_, RecognizeError>>()?;
        // The path at every sample a kept window is decided at, and at a change of surface.
        let path_m = self
            .capture
            .column(capture::kind::TANGENTIAL_POSITION_M)
            .map_or_else(|_| Vec::new(), PlayedPath::series);
        let mut decided: Vec<usize> = windows
            .iter()
            .flat_map(|k| {
                k.vectors
                    .vectors
                    .iter()
                    .map(|(start, ..)| k.windowing.decided_at(*start))
            })
            .chain(
                self.change
                    .as_ref()
                    .map(|c| change_sample(c.at_s, self.capture.metadata().rate_hz())),
            )
            .filter(|&i| i < path_m.len())
            .collect();
        decided.sort_unstable();
        decided.dedup();
        let kept = KeptFeatures {
            samples: self.capture.len(),
            path_m: decided.into_iter().map(|i| (i, path_m[i])).collect(),
            travel: Travel::of(
                &self.capture,
                needs.windows.iter().map(|(w, ..)| w.start_travel_m),
            ),
            windows,
            histograms,
        };
        let first = first_sample(&self.capture)
            .map_err(|e| RecognizeError::Input(InputError::Capture(Box::new(e))))?;
        Ok(Self {
            capture: first,
            kept: Some(Arc::new(kept)),
            ..self
        })
    }

    /// Whether the capture still has its samples (not since
    /// [`LabelledCapture::keep_features`]).
    pub fn has_samples(&self) -> bool {
        self.kept.is_none()
    }

    /// Samples of the capture, also after its samples were dropped.
    pub fn samples(&self) -> usize {
        self.kept.as_ref().map_or(self.capture.len(), |k| k.samples())
    }

    /// The tool's path from the first sample, read through the play ([`PlayedPath`]): at
    /// every sample, or after [`LabelledCapture::keep_features`] at those its kept windows are
    /// decided at and its change of surface; none for a capture without a position column.
    pub(crate) fn played_path(&self) -> PathOfCapture<'_> {
        match (
            &self.kept,
            self.capture.column(capture::kind::TANGENTIAL_POSITION_M),
        ) {
            (Some(k), _) => PathOfCapture::Kept(&k.path_m),
            (None, Ok(x)) => PathOfCapture::Every(PlayedPath::series(x)),
            (None, Err(_)) => PathOfCapture::Every(Vec::new()),
        }
    }

    /// The features kept when the samples were dropped.
    pub(crate) fn kept(&self) -> Option<&KeptFeatures> {
        self.kept.as_deref()
    }

    /// The error for features `needed` that a capture without samples did not keep.
    pub(crate) fn not_kept(&self, needed: String) -> RecognizeError {
        RecognizeError::Usage(UsageError::FeaturesNotKept {
            path: self.reference.path.clone(),
            needed,
        })
    }
}

/// `capture`'s header and columns with its first sample only.
fn first_sample(capture: &Capture) -> Result<Capture, capture::CaptureError> {
    let data = capture.data().iter().map(|column| column[..1].to_vec()).collect();
    Capture::new(capture.metadata().clone(), capture.columns().to_vec(), data)
}

/// A capture's path through the play ([`LabelledCapture::played_path`]), m.
pub(crate) enum PathOfCapture<'a> {
    /// At every sample (none without a position column).
    Every(Vec<f64>),
    /// Kept at some samples: each sample and the path there, in order of sample.
    Kept(&'a [(usize, f64)]),
}

impl PathOfCapture<'_> {
    /// The path at `sample`, m; `None` where it was neither measured nor kept.
    pub(crate) fn at(&self, sample: usize) -> Option<f64> {
        match self {
            Self::Every(path_m) => path_m.get(sample).copied(),
            Self::Kept(kept) => kept
                .binary_search_by_key(&sample, |&(i, _)| i)
                .ok()
                .map(|k| kept[k].1),
        }
    }
}

/// The sample a change of surface `at_s` into a capture at `rate_hz` falls on.
pub(crate) fn change_sample(at_s: f64, rate_hz: f64) -> usize {
    (at_s * rate_hz).round() as usize
}
