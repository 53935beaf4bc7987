//! The SOM's trainer: Nakano's map over rubbing windows, a map over windows of both feature
//! sets, and one map per behaviour over whole-scratch histograms.

use rayon::prelude::*;

use super::{
    BehaviourHistograms, CV_FOLDS, Method, TrainJob, Trainer, every_class_has_windows,
    every_class_in_two_groups, histograms_by_behaviour, training_windows,
};
use crate::RecognizeError;
use crate::features::nakano::FEATURE_NAMES;
use crate::features::spectral::Histogram;
use crate::features::{FeatureSet, NakanoWindowing, windows};
use crate::folds::{group_folds, held_out_correct};
use crate::recognizer::labelled::{check_rate, class_index, class_list};
use crate::recognizer::{BehaviourSom, LabelledCapture, RecognizerBody, RecognizerFile};
use crate::som::{Normalization, Som, SomParams};
use crate::svc::{Progress, no_progress};
use crate::{DataError, SettingError};

/// Trains SOM recognizers: over Nakano's windows ([`RecognizerFile::train_som`]), over windows
/// of both feature sets ([`RecognizerFile::train_som_windows`]), or one map per behaviour over
/// whole-scratch histograms ([`RecognizerFile::train_som_scratches`], scaled by
/// [`SCRATCH_SOM_NORMALIZATION`], [`som_nodes`] nodes).
#[derive(Debug, Clone, Copy, Default)]
pub struct SomTrainer;

impl Trainer for SomTrainer {
    fn method(&self) -> Method {
        Method::Som
    }

    fn train(&self, job: TrainJob<'_>) -> Result<RecognizerFile, RecognizeError> {
        let (captures, settings, progress) = (job.captures, job.settings, job.progress);
        let classes = class_list(captures).len();
        let params = |vectors| {
            let nodes = settings.som_nodes.unwrap_or(window_som_nodes(classes, vectors));
            SomParams {
                nodes,
                iterations: som_iterations(nodes),
                seed: settings.seed,
                normalization: settings.normalization,
                ..SomParams::default()
            }
        };
        match settings.features {
            FeatureSet::Nakano => {
                RecognizerFile::train_som_sized(captures, settings.windowing(captures)?, params, progress)
            }
            FeatureSet::Both => RecognizerFile::train_som_windows_sized(
                captures,
                settings.windowing(captures)?,
                params,
                settings.histogram,
                progress,
            ),
            FeatureSet::Spectral => {
                let params = SomParams {
                    nodes: settings.som_nodes.unwrap_or(som_nodes(classes)),
                    normalization: SCRATCH_SOM_NORMALIZATION,
                    ..som_params(classes, settings.seed)
                };
                RecognizerFile::train_som_scratches(captures, params, settings.histogram)
            }
            FeatureSet::Vibration => Err(RecognizeError::Setting(SettingError::Config {
                of: "training",
                reason: "`--features vibration` trains a k-NN or an SVM (whose window \
                         probabilities are fused with a Nakano classifier's); a SOM names a node, \
                         not a distribution over the surfaces",
            })),
            FeatureSet::NakanoSpectrum => Err(RecognizeError::Setting(SettingError::Config {
                of: "training",
                reason: "`--features nakano-spectrum` trains a k-NN or an SVM over windows, whose \
                         probabilities accumulate into the anytime posterior; a SOM over windows \
                         reads `nakano` or `both`",
            })),
        }
    }
}

/// Nodes of a SOM over `classes` classes: the thesis's 12, or three per class when there are
/// more than four classes (a node answers one class, and Sinapov's 21 surfaces need room for a
/// class's spread and for the boundaries between classes along the line).
pub fn som_nodes(classes: usize) -> usize {
    12.max(3 * classes)
}

/// Surfaces of Nakano's protocol (thesis Table 3.3's map of 12 nodes was sized for them).
const PAPER_SURFACES: usize = 7;

/// Nodes of a SOM over `vectors` rubbing windows of `classes` classes: the thesis's 12 for up
/// to its seven surfaces (so Nakano's protocol is unchanged); beyond, the SOM Toolbox's
/// default map size `⌈5·N^0.54321⌉` for `N` training vectors (Vesanto et al., `som_topol_struct`),
/// and never fewer than two per class.
///
/// A node answers one class, so a map with fewer nodes than classes can never name some of
/// them (with twelve nodes for twenty surfaces, nine or ten own no node), and two per class
/// leave room for a class's spread and a boundary on each side along the line. Past that the
/// data decide: a map is a quantiser of the training windows, and one that has far fewer nodes
/// than the windows have distinct places averages neighbouring surfaces into one node. On the
/// generated 20-surface multi-stream set (1,300 training windows) two per class (40 nodes)
/// named 76.8 % of the test windows, the Toolbox's 246 nodes 85.2 %.
pub fn window_som_nodes(classes: usize, vectors: usize) -> usize {
    let paper = SomParams::default().nodes;
    if classes <= PAPER_SURFACES {
        paper
    } else {
        let toolbox = (5.0 * (vectors as f64).powf(0.54321)).ceil() as usize;
        paper.max(2 * classes).max(toolbox)
    }
}

/// Presentations to train a map of `nodes` nodes: the thesis's 10 000, or for a larger map
/// Kohonen's rule of thumb that the steps number at least 500 times the map's units (his
/// practical advice in *Self-Organizing Maps*), so that a map sized by its data is not left
/// half-trained: with 10 000 presentations each of 187 nodes would see about 50.
pub fn som_iterations(nodes: usize) -> usize {
    SomParams::default().iterations.max(500 * nodes)
}

/// The default SOM parameters for `classes` classes with `seed`: Table 3.3's, with
/// [`som_nodes`] nodes.
pub fn som_params(classes: usize, seed: u64) -> SomParams {
    SomParams {
        nodes: som_nodes(classes),
        seed,
        ..SomParams::default()
    }
}

/// The scaling of the CLI's SOMs over whole-scratch histograms: the rubbing map's
/// [`Normalization::LogWithinClass`] (cells are mean magnitudes, positive: log scale, centred,
/// divided by the pooled within-surface spread, then unit length). Chosen over
/// [`Normalization::Standardize`] by the maps' cross-validation by trial on the training
/// captures of `palpus gen --only sinapov` (trials 0–6): 0.84–0.96 per behaviour against
/// 0.74–0.93.
pub const SCRATCH_SOM_NORMALIZATION: Normalization = Normalization::LogWithinClass;

/// Classes that label no node of one map of a SOM recognizer
/// ([`RecognizerFile::classes_without_nodes`]): the map can never answer them.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct UnmappedClasses<'a> {
    /// The map's behaviour, for one map per behaviour; `None` for a map over windows.
    pub behaviour: Option<&'a str>,
    /// Nodes of the map.
    pub nodes: usize,
    /// The classes, in the recognizer's order.
    pub classes: Vec<&'a str>,
}

impl RecognizerFile {
    /// For each map of a SOM recognizer, the classes no node answers (none listed when every
    /// class owns a node; always empty for other recognizers). A node takes the majority class
    /// of the training vectors it wins, so a class whose vectors all lose to other classes'
    /// nodes is never decided, however close a query comes to it.
    pub fn classes_without_nodes(&self) -> Vec<UnmappedClasses<'_>> {
        fn unmapped<'a>(
            classes: &'a [String],
            behaviour: Option<&'a str>,
            som: &Som<usize>,
        ) -> UnmappedClasses<'a> {
            UnmappedClasses {
                behaviour,
                nodes: som.node_labels().len(),
                classes: classes
                    .iter()
                    .enumerate()
                    .filter(|(i, _)| !som.node_labels().contains(i))
                    .map(|(_, c)| c.as_str())
                    .collect(),
            }
        }
        let maps = match &self.body {
            RecognizerBody::Som { som, .. } | RecognizerBody::SomWindows { som, .. } => {
                vec![unmapped(&self.classes, None, som)]
            }
            RecognizerBody::SomScratches { behaviours, .. } => behaviours
                .iter()
                .map(|b| unmapped(&self.classes, b.behaviour.as_deref(), &b.som))
                .collect(),
            RecognizerBody::Knn { .. }
            | RecognizerBody::Svm { .. }
            | RecognizerBody::KnnWindows { .. }
            | RecognizerBody::SvmWindows { .. } => Vec::new(),
        };
        maps.into_iter().filter(|m| !m.classes.is_empty()).collect()
    }

    /// Trains Nakano's SOM on the training windows of `captures` (see
    /// [`NakanoWindowing::with_training_window_s`]); it decides on the decision windows.
    pub fn train_som(
        captures: &[LabelledCapture],
        windowing: NakanoWindowing,
        params: SomParams,
    ) -> Result<Self, RecognizeError> {
        Self::train_som_sized(captures, windowing, |_| params, &no_progress)
    }

    /// [`RecognizerFile::train_som`] with the parameters chosen once the number of training
    /// windows is known (`params(vectors)`), so that a map can be sized by its data, telling
    /// `progress` of the map's training ([`Som::train_observed`]).
    pub fn train_som_sized(
        captures: &[LabelledCapture],
        windowing: NakanoWindowing,
        params: impl FnOnce(usize) -> SomParams,
        progress: Progress<'_>,
    ) -> Result<Self, RecognizeError> {
        let classes = class_list(captures);
        let (mut data, mut labels) = (Vec::new(), Vec::new());
        let training = windowing.training();
        for c in captures {
            check_rate(c, windowing.rate_hz)?;
            let label = class_index(&classes, c)?;
            for (_, _, features) in windows(c, &training)? {
                data.push(features.to_vec());
                labels.push(label);
            }
        }
        every_class_has_windows(captures, &classes, &labels, &training, &[])?;
        if data.is_empty() {
            return Err(RecognizeError::Data(DataError::NoTrainingData));
        }
        let som =
            Som::train_observed(params(data.len()), &data, &labels, progress).map_err(RecognizeError::som)?;
        Ok(Self::assemble(
            classes,
            FEATURE_NAMES.iter().map(|s| (*s).to_owned()).collect(),
            RecognizerBody::Som { windowing, som },
            captures,
            data.len(),
        ))
    }

    /// A SOM over windows of Nakano's features and the window's histogram together
    /// ([`FeatureSet::Both`]), trained and deciding like Nakano's SOM, its scaling
    /// `params.normalization` (default: [`Normalization::LogWithinClass`]).
    pub fn train_som_windows(
        captures: &[LabelledCapture],
        windowing: NakanoWindowing,
        params: SomParams,
        histogram: impl Into<Histogram>,
    ) -> Result<Self, RecognizeError> {
        let histogram = histogram.into();
        Self::train_som_windows_sized(captures, windowing, |_| params, histogram, &no_progress)
    }

    /// [`RecognizerFile::train_som_windows`] with the parameters chosen once the number of
    /// training windows is known (`params(vectors)`), telling `progress` of the map's training.
    pub fn train_som_windows_sized(
        captures: &[LabelledCapture],
        windowing: NakanoWindowing,
        params: impl FnOnce(usize) -> SomParams,
        histogram: impl Into<Histogram>,
        progress: Progress<'_>,
    ) -> Result<Self, RecognizeError> {
        let histogram = histogram.into();
        let classes = class_list(captures);
        let (x, y, _) = training_windows(captures, &classes, &windowing, FeatureSet::Both, histogram)?;
        let som = Som::train_observed(params(x.len()), &x, &y, progress)?;
        Ok(Self::assemble(
            classes,
            FeatureSet::Both.feature_names(),
            RecognizerBody::SomWindows {
                windowing,
                histogram,
                som,
            },
            captures,
            x.len(),
        ))
    }

    /// One SOM per behaviour over the spectrotemporal histograms of whole scratches (one vector
    /// each), each with its reliability weight from cross-validation by trial (as k-NN's); the
    /// maps' own scaling is `params.normalization` (the CLI's is [`SCRATCH_SOM_NORMALIZATION`]).
    pub fn train_som_scratches(
        captures: &[LabelledCapture],
        params: SomParams,
        histogram: impl Into<Histogram>,
    ) -> Result<Self, RecognizeError> {
        let histogram = histogram.into();
        FeatureSet::Spectral.check_columns(captures)?;
        let classes = class_list(captures);
        let data = histograms_by_behaviour(captures, &classes, histogram)?;
        let fit_one =
            |(name, x, y, groups): &BehaviourHistograms<'_>| -> Result<BehaviourSom, RecognizeError> {
                let x: Vec<Vec<f64>> = x.iter().map(|v| v.to_vec()).collect();
                let som = Som::train(params, &x, y)?;
                let cv = match group_folds(groups, CV_FOLDS) {
                    Ok((fold, folds)) if every_class_in_two_groups(y, groups) => {
                        let correct = held_out_correct(
                            &x,
                            y,
                            &fold,
                            folds,
                            |tx, ty| {
                                let tx: Vec<Vec<f64>> = tx.iter().map(|v| (*v).clone()).collect();
                                Som::train(params, &tx, ty)
                            },
                            |map, v| map.classify(v).copied(),
                        )?;
                        Some((correct as f64 / x.len() as f64, folds))
                    }
                    _ => None,
                };
                Ok(BehaviourSom {
                    behaviour: name.map(str::to_owned),
                    som,
                    reliability: cv.map(|(a, _)| a),
                    reliability_folds: cv.map(|(_, f)| f),
                })
            };
        // One behaviour per task; collected in the behaviours' order.
        let behaviours: Vec<BehaviourSom> = data.par_iter().map(fit_one).collect::<Result<_, _>>()?;
        Self::assemble_scratches(
            classes,
            behaviours.len(),
            RecognizerBody::SomScratches {
                histogram,
                behaviours,
            },
            captures,
        )
    }
}
