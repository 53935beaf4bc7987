//! `--features`: which features a recognizer computes, independently of its classifier.
//!
//! Each method has its own features by default — the SOM Nakano's five rubbing features over
//! sliding windows, k-NN and SVM Sinapov's spectrotemporal histogram of a whole scratch — and
//! [`FeatureSet`] crosses them:
//!
//! - **k-NN / SVM on `nakano`** ([`RecognizerBody::KnnWindows`], [`RecognizerBody::SvmWindows`]):
//!   windowed exactly like the SOM (the same [`NakanoWindowing`]: trained on the training
//!   windows, deciding on the decision windows every hop from 5 mm of travel on), one
//!   classifier over all windows (rubbing has no behaviours), features scaled by
//!   [`WindowScaling`] (the SOM's `LogWithinClass`, without the unit length).
//! - **SOM on `spectral`** ([`RecognizerBody::SomScratches`]): one map per behaviour over the
//!   histograms of whole scratches, one decision per scratch, fused over a trial's behaviours
//!   like k-NN and SVM (reliability from cross-validation by trial).
//! - **`both`** (k-NN, SVM: the window variants; SOM: [`RecognizerBody::SomWindows`]): each
//!   window of a rubbing capture that also has accelerometer columns gets Nakano's five features
//!   followed by the 125 cells of the spectrotemporal histogram of the same window's samples.

use std::collections::{BTreeMap, BTreeSet};

use serde::{Deserialize, Serialize};

use super::super::knn::{FeatureScaling, KnnParams, group_folds};
use super::super::nakano::{COMMAND_FORCE_COLUMN, FRICTION_COLUMN, HEIGHT_COLUMN, POSITION_COLUMN};
use super::super::som::{Normalization, Som, SomParams};
use super::super::spectral::{ACCEL_COLUMNS, CellScale, FEATURE_LEN, SpectrogramPlan};
use super::super::svc::{CSearch, Svc, SvcError, SvcParams, select_c};
use super::{
    BehaviourReliability, CV_FOLDS, LabelledCapture, NakanoWindowing, RecognizerBody, RecognizerError,
    RecognizerFile, SvmC, check_rate, class_index, class_list, histogram_names, windows,
};
use svm::Kernel;

/// Which features a recognizer computes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FeatureSet {
    /// Nakano's five rubbing features over sliding windows (the SOM's default).
    Nakano,
    /// Sinapov's spectrotemporal histogram of a whole scratch (k-NN's and SVM's default).
    Spectral,
    /// Per window of a rubbing capture with accelerometer columns: the five Nakano features
    /// followed by the histogram of the window's acceleration (130 features).
    Both,
}

impl FeatureSet {
    /// `nakano`, `spectral` or `both`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Nakano => "nakano",
            Self::Spectral => "spectral",
            Self::Both => "both",
        }
    }

    /// Length of the feature vector.
    pub fn dim(self) -> usize {
        match self {
            Self::Nakano => super::FEATURES,
            Self::Spectral => FEATURE_LEN,
            Self::Both => super::FEATURES + FEATURE_LEN,
        }
    }

    /// Names of the features, in vector order.
    pub fn feature_names(self) -> Vec<String> {
        let nakano = super::super::nakano::FEATURE_NAMES
            .iter()
            .map(|s| (*s).to_owned());
        match self {
            Self::Nakano => nakano.collect(),
            Self::Spectral => histogram_names(),
            Self::Both => nakano.chain(histogram_names()).collect(),
        }
    }

    /// The columns of `capture` these features need but it lacks (empty when it has them all).
    /// Nakano's friction comes from `friction_force_n` or, without it, from the reaction-force
    /// observer over `tangential_command_force_n`.
    pub fn missing_columns(self, capture: &LabelledCapture) -> Vec<String> {
        let has = |name: &str| capture.capture.columns().iter().any(|c| c == name);
        let mut missing = Vec::new();
        if matches!(self, Self::Nakano | Self::Both) {
            for name in [POSITION_COLUMN, HEIGHT_COLUMN] {
                if !has(name) {
                    missing.push(name.to_owned());
                }
            }
            if !has(FRICTION_COLUMN) && !has(COMMAND_FORCE_COLUMN) {
                missing.push(format!("{FRICTION_COLUMN} (or {COMMAND_FORCE_COLUMN})"));
            }
        }
        if matches!(self, Self::Spectral | Self::Both) {
            missing.extend(ACCEL_COLUMNS.iter().filter(|c| !has(c)).map(|c| (*c).to_owned()));
        }
        missing
    }

    /// A typed error for the first capture that lacks a column these features need.
    pub fn check_columns(self, captures: &[LabelledCapture]) -> Result<(), RecognizerError> {
        for c in captures {
            let missing = self.missing_columns(c);
            if !missing.is_empty() {
                return Err(RecognizerError::MissingColumns {
                    path: c.reference.path.clone(),
                    features: self.name(),
                    missing,
                });
            }
        }
        Ok(())
    }
}

impl std::fmt::Display for FeatureSet {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Feature scaling of the k-NN and SVM over windows, learned from the training windows: the
/// SOM's [`Normalization::LogWithinClass`] without its last step. A feature positive over all
/// training windows (amplitudes, variances, wavelengths, mean friction, histogram cells) is
/// replaced by its logarithm (values below a thousandth of the smallest training value are taken
/// as that floor); every feature is centred on the training mean and divided by its pooled
/// within-class standard deviation (a constant feature is left unscaled).
///
/// Unlike the SOM, vectors are *not* normalised to unit length: the map's winner is an inner
/// product of unit vectors, whereas k-NN's Euclidean distance and the SVM's polynomial kernel
/// use the whole vector, and a window's distance from the mean is information (a surface far
/// from all others on every feature). The classifiers themselves then scale nothing
/// ([`FeatureScaling::None`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct WindowScaling {
    /// Per feature: `Some(floor)` where the feature is taken on a log scale.
    pub log_floor: Vec<Option<f64>>,
    /// Per feature: the training mean (after the log).
    pub offset: Vec<f64>,
    /// Per feature: the pooled within-class standard deviation (after the log).
    pub scale: Vec<f64>,
}

impl WindowScaling {
    /// Learns the scaling from `data` (non-empty, equal dimensions, finite) and its labels.
    pub fn fit(data: &[Vec<f64>], labels: &[usize]) -> Self {
        let dim = data.first().map_or(0, Vec::len);
        let n = data.len().max(1) as f64;
        let log_floor: Vec<Option<f64>> = (0..dim)
            .map(|j| {
                let min = data.iter().map(|v| v[j]).fold(f64::INFINITY, f64::min);
                (min > 0.0 && min.is_finite()).then_some(min * 1e-3)
            })
            .collect();
        let value = |j: usize, x: f64| match log_floor[j] {
            Some(floor) => x.max(floor).ln(),
            None => x,
        };
        let mut offset = vec![0.0; dim];
        let mut scale = vec![1.0; dim];
        for j in 0..dim {
            let mut by_class: BTreeMap<usize, (f64, f64)> = BTreeMap::new();
            let mut total = 0.0;
            for (v, &l) in data.iter().zip(labels) {
                let x = value(j, v[j]);
                total += x;
                let e = by_class.entry(l).or_default();
                e.0 += 1.0;
                e.1 += x;
            }
            let within: f64 = data
                .iter()
                .zip(labels)
                .map(|(v, l)| {
                    let (count, sum) = by_class[l];
                    (value(j, v[j]) - sum / count).powi(2)
                })
                .sum();
            let s = (within / n).sqrt();
            offset[j] = total / n;
            scale[j] = if s > 0.0 && s.is_finite() { s } else { 1.0 };
        }
        Self {
            log_floor,
            offset,
            scale,
        }
    }

    /// The scaled vector.
    pub fn apply(&self, features: &[f64]) -> Vec<f64> {
        features
            .iter()
            .zip(self.log_floor.iter().zip(self.offset.iter().zip(&self.scale)))
            .map(|(&x, (floor, (o, s)))| {
                let x = match floor {
                    Some(floor) => x.max(*floor).ln(),
                    None => x,
                };
                (x - o) / s
            })
            .collect()
    }

    /// Number of features.
    pub fn dim(&self) -> usize {
        self.offset.len()
    }

    /// Checks a scaling read from a file against `dim` features: `Err(reason)`.
    pub fn check(&self, dim: usize) -> Result<(), String> {
        if self.offset.len() != dim || self.scale.len() != dim || self.log_floor.len() != dim {
            return Err(format!("expected {dim} log floors, offsets and scales"));
        }
        let ok = self.offset.iter().all(|o| o.is_finite())
            && self.scale.iter().all(|s| s.is_finite() && *s > 0.0)
            && self.log_floor.iter().flatten().all(|f| f.is_finite() && *f > 0.0);
        if ok {
            Ok(())
        } else {
            Err(
                "a non-finite offset, a scale that is not positive or a log floor that is not positive"
                    .into(),
            )
        }
    }
}

/// One behaviour's SOM over spectrotemporal histograms.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BehaviourSom {
    /// The behaviour (metadata `behaviour`); `None` for captures without one.
    pub behaviour: Option<String>,
    /// Its map (node labels are class indices), with its feature scaling.
    pub som: Som<usize>,
    /// Its accuracy under cross-validation by trial on the training captures: its weight when
    /// behaviours are fused (as [`super::BehaviourKnn::reliability`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reliability: Option<f64>,
    /// Folds of that cross-validation.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reliability_folds: Option<usize>,
}

/// Nodes of a SOM over `classes` classes: the thesis's 12, or three per class when there are
/// more than four classes (a node answers one class, and Sinapov's 21 surfaces need room for a
/// class's spread and for the boundaries between classes along the line).
pub fn som_nodes(classes: usize) -> usize {
    12.max(3 * classes)
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

/// The SVC of a k-NN/SVM over windows: degree-2 polynomial `(γ a·b + 1)²` with γ = 1/dim (1/5
/// for Nakano's features, 1/130 for both), as the scratch SVM's γ = 1/125 for its 125 cells: the
/// scaled features are O(1) each, so `γ a·b` is O(1) too. No scaling inside (the windows arrive
/// scaled by [`WindowScaling`]).
pub fn window_svc_params(dim: usize) -> SvcParams {
    SvcParams {
        kernel: Kernel::Polynomial {
            gamma: 1.0 / dim.max(1) as f64,
            coef0: 1.0,
            degree: 2,
        },
        scaling: FeatureScaling::None,
        ..SvcParams::default()
    }
}

/// C of an SVM over windows whose training captures cannot be cross-validated (each surface
/// needs captures in at least two runs or trials, e.g. not when trained on run 0 alone): 10, a
/// soft margin. Windows of different surfaces overlap (a 1 s window of one surface can look like
/// another's), so the hard-margin machine of the scratch SVM's fallback (10⁴) would bend its
/// boundaries around single windows; with every feature in units of its within-surface spread,
/// a moderate C keeps the margin wide. `--c` overrides it.
pub const WINDOW_SVM_FALLBACK_C: f64 = 10.0;

/// The feature vectors of the windows of `c` that `windowing` picks: Nakano's five features,
/// followed for [`FeatureSet::Both`] by the spectrotemporal histogram of the window's own
/// accelerometer samples (`start .. start + window_samples`, all before the decision).
pub(super) fn window_vectors(
    c: &LabelledCapture,
    windowing: &NakanoWindowing,
    features: FeatureSet,
    cell_scale: CellScale,
    plan: &SpectrogramPlan,
) -> Result<Vec<(usize, Vec<f64>)>, RecognizerError> {
    let nakano = windows(c, windowing)?;
    if features != FeatureSet::Both {
        return Ok(nakano.into_iter().map(|(s, f)| (s, f.to_vec())).collect());
    }
    let spectral = |source| RecognizerError::Spectral {
        path: c.reference.path.clone(),
        source,
    };
    let [x, y, z] = ACCEL_COLUMNS.map(|name| c.capture.column(name));
    let (x, y, z) = (
        x.map_err(|e| spectral(e.into()))?,
        y.map_err(|e| spectral(e.into()))?,
        z.map_err(|e| spectral(e.into()))?,
    );
    let len = windowing.window_samples;
    nakano
        .into_iter()
        .map(|(s, f)| {
            let range = s..(s + len).min(x.len());
            let h = plan
                .features(&x[range.clone()], &y[range.clone()], &z[range], cell_scale)
                .map_err(spectral)?;
            Ok((s, f.iter().copied().chain(h).collect()))
        })
        .collect()
}

/// Training windows of every capture: vectors, class indices, and the cross-validation group
/// of each window (its capture's, see [`super::recording_groups`]).
type WindowData = (Vec<Vec<f64>>, Vec<usize>, Vec<u64>);

fn training_windows(
    captures: &[LabelledCapture],
    classes: &[String],
    windowing: &NakanoWindowing,
    features: FeatureSet,
    cell_scale: CellScale,
) -> Result<WindowData, RecognizerError> {
    features.check_columns(captures)?;
    let plan = SpectrogramPlan::new();
    let groups = super::recording_groups(captures);
    let training = windowing.training();
    let (mut x, mut y, mut g) = (Vec::new(), Vec::new(), Vec::new());
    for (c, &group) in captures.iter().zip(&groups) {
        check_rate(c, windowing.rate_hz)?;
        let label = class_index(classes, c)?;
        for (_, v) in window_vectors(c, &training, features, cell_scale, &plan)? {
            x.push(v);
            y.push(label);
            g.push(group);
        }
    }
    if x.is_empty() {
        return Err(RecognizerError::NoTrainingData);
    }
    Ok((x, y, g))
}

/// Whether every class has windows in at least two groups, so that no fold of a
/// cross-validation by group holds out a whole class.
fn every_class_in_two_groups(labels: &[usize], groups: &[u64]) -> bool {
    let mut by_class: BTreeMap<usize, BTreeSet<u64>> = BTreeMap::new();
    for (&l, &g) in labels.iter().zip(groups) {
        by_class.entry(l).or_default().insert(g);
    }
    by_class.values().all(|g| g.len() >= 2)
}

fn window_check(features: FeatureSet) -> Result<(), RecognizerError> {
    if features == FeatureSet::Spectral {
        return Err(RecognizerError::Setting {
            name: "features",
            value: f64::NAN,
            reason: "windows carry `nakano` or `both` features; `spectral` is one histogram per scratch",
        });
    }
    Ok(())
}

impl RecognizerFile {
    /// k-NN over rubbing windows (`features` [`FeatureSet::Nakano`] or [`FeatureSet::Both`]):
    /// windowed like the SOM, one classifier over every training window, scaled by
    /// [`WindowScaling`].
    pub fn train_knn_windows(
        captures: &[LabelledCapture],
        windowing: NakanoWindowing,
        features: FeatureSet,
        k: usize,
        cell_scale: CellScale,
    ) -> Result<Self, RecognizerError> {
        window_check(features)?;
        let classes = class_list(captures);
        let (x, y, _) = training_windows(captures, &classes, &windowing, features, cell_scale)?;
        let scaling = WindowScaling::fit(&x, &y);
        let scaled: Vec<Vec<f64>> = x.iter().map(|v| scaling.apply(v)).collect();
        let knn = KnnParams::default()
            .k(k)
            .scaling(FeatureScaling::None)
            .fit(&scaled, &y, classes.len())
            .map_err(|source| RecognizerError::Knn {
                behaviour: String::new(),
                source,
            })?;
        Ok(Self::assemble(
            classes,
            features.feature_names(),
            RecognizerBody::KnnWindows {
                features,
                windowing,
                cell_scale,
                scaling,
                knn,
            },
            captures,
            x.len(),
        ))
    }

    /// C-SVC over rubbing windows (see [`RecognizerFile::train_knn_windows`] and
    /// [`window_svc_params`]). With [`SvmC::Auto`], C is chosen by cross-validation grouped by
    /// run (or trial; the windows of one capture never straddle folds) when every surface has
    /// captures in at least two runs; otherwise C is [`WINDOW_SVM_FALLBACK_C`].
    pub fn train_svm_windows(
        captures: &[LabelledCapture],
        windowing: NakanoWindowing,
        features: FeatureSet,
        c: &SvmC,
        cell_scale: CellScale,
    ) -> Result<Self, RecognizerError> {
        window_check(features)?;
        let classes = class_list(captures);
        let (x, y, groups) = training_windows(captures, &classes, &windowing, features, cell_scale)?;
        let scaling = WindowScaling::fit(&x, &y);
        let scaled: Vec<Vec<f64>> = x.iter().map(|v| scaling.apply(v)).collect();
        let params = window_svc_params(features.dim());
        let svc_error = |source| RecognizerError::Svc {
            behaviour: String::new(),
            source,
        };
        let grid = match c {
            SvmC::Auto(grid) => grid.clone(),
            SvmC::Fixed(c) => vec![*c],
        };
        let search = if every_class_in_two_groups(&y, &groups) {
            match select_c(params, &grid, &scaled, &y, &groups, classes.len(), CV_FOLDS) {
                Ok(search) => Some(search),
                Err(SvcError::TooFewGroups { .. }) => None,
                Err(e) => return Err(svc_error(e)),
            }
        } else {
            None
        };
        let chosen = match (&search, c) {
            (Some(s), _) => s.chosen_c,
            (None, SvmC::Fixed(c)) => *c,
            (None, SvmC::Auto(_)) => WINDOW_SVM_FALLBACK_C,
        };
        let svc =
            Svc::fit(SvcParams { c: chosen, ..params }, &scaled, &y, classes.len()).map_err(svc_error)?;
        Ok(Self::assemble(
            classes,
            features.feature_names(),
            RecognizerBody::SvmWindows {
                features,
                windowing,
                cell_scale,
                scaling,
                svc,
                c_search: search,
            },
            captures,
            x.len(),
        ))
    }

    /// A SOM over windows of Nakano's features and the window's histogram together
    /// ([`FeatureSet::Both`]), trained and deciding like Nakano's SOM, its scaling
    /// `params.normalization` (default: [`Normalization::LogWithinClass`]).
    pub fn train_som_windows(
        captures: &[LabelledCapture],
        windowing: NakanoWindowing,
        params: SomParams,
        cell_scale: CellScale,
    ) -> Result<Self, RecognizerError> {
        let classes = class_list(captures);
        let (x, y, _) = training_windows(captures, &classes, &windowing, FeatureSet::Both, cell_scale)?;
        let som = Som::train(params, &x, &y)?;
        Ok(Self::assemble(
            classes,
            FeatureSet::Both.feature_names(),
            RecognizerBody::SomWindows {
                windowing,
                cell_scale,
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
        cell_scale: CellScale,
    ) -> Result<Self, RecognizerError> {
        FeatureSet::Spectral.check_columns(captures)?;
        let classes = class_list(captures);
        let data = super::histograms_by_behaviour(captures, &classes, cell_scale)?;
        let fit_one =
            |(name, x, y, groups): &super::BehaviourHistograms<'_>| -> Result<BehaviourSom, RecognizerError> {
                let x: Vec<Vec<f64>> = x.iter().map(|v| v.to_vec()).collect();
                let som = Som::train(params, &x, y)?;
                let cv = match group_folds(groups, CV_FOLDS) {
                    Ok((fold, folds)) if every_class_in_two_groups(y, groups) => {
                        let mut correct = 0usize;
                        for f in 0..folds {
                            let (tx, ty): (Vec<Vec<f64>>, Vec<usize>) = x
                                .iter()
                                .zip(y)
                                .zip(&fold)
                                .filter(|&(_, &g)| g != f)
                                .map(|((v, &l), _)| (v.clone(), l))
                                .unzip();
                            let map = Som::train(params, &tx, &ty)?;
                            for ((v, &l), _) in x.iter().zip(y).zip(&fold).filter(|&(_, &g)| g == f) {
                                correct += usize::from(*map.classify(v)? == l);
                            }
                        }
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
        // One behaviour per thread, as many as the machine has cores.
        let threads = std::thread::available_parallelism()
            .map_or(1, usize::from)
            .clamp(1, data.len().max(1));
        let mut fitted: Vec<(usize, BehaviourSom)> = Vec::with_capacity(data.len());
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
            for w in workers {
                fitted.extend(
                    w.join()
                        .unwrap_or_else(|panic| std::panic::resume_unwind(panic))?,
                );
            }
            Ok(())
        })?;
        fitted.sort_by_key(|(i, _)| *i);
        let behaviours: Vec<BehaviourSom> = fitted.into_iter().map(|(_, b)| b).collect();
        if behaviours.is_empty() {
            return Err(RecognizerError::NoTrainingData);
        }
        Ok(Self::assemble(
            classes,
            histogram_names(),
            RecognizerBody::SomScratches {
                cell_scale,
                behaviours,
            },
            captures,
            captures.len(),
        ))
    }
}

/// Reliabilities of a [`RecognizerBody::SomScratches`], for
/// [`RecognizerFile::reliabilities`].
pub(super) fn som_reliabilities(behaviours: &[BehaviourSom]) -> Vec<BehaviourReliability<'_>> {
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

/// The search of a window SVM must name its C, from its grid.
pub(super) fn check_c_search(search: Option<&CSearch>, c: f64) -> Result<(), (String, String)> {
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

/// The scaling of the CLI's SOMs over whole-scratch histograms: the rubbing map's
/// [`Normalization::LogWithinClass`] (cells are mean magnitudes, positive: log scale, centred,
/// divided by the pooled within-surface spread, then unit length). Chosen over
/// [`Normalization::Standardize`] by the maps' cross-validation by trial on the training
/// captures of `palpus gen --only sinapov` (trials 0–6): 0.84–0.96 per behaviour against
/// 0.74–0.93.
pub const SCRATCH_SOM_NORMALIZATION: Normalization = Normalization::LogWithinClass;
