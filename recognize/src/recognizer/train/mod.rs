//! Training: one trainer per method ([`SomTrainer`], [`KnnTrainer`], [`SvmTrainer`]) behind
//! one trait ([`Trainer`]), and [`train`], which picks the trainer that [`TrainSettings`] names.
//!
//! Each method has its own features by default (the SOM Nakano's rubbing windows, k-NN and SVM
//! Sinapov's histogram of a whole scratch) and takes any [`FeatureSet`]; see
//! [`crate::features`] for how methods and features cross. On captures that carry the columns
//! of both sets, the command line trains on both unless told otherwise
//! ([`Method::features_for`]).

mod knn;
mod som;
mod svm;
mod warnings;

use std::collections::{BTreeMap, BTreeSet};
use std::time::{Duration, Instant};

pub use knn::KnnTrainer;
pub use som::{
    SCRATCH_SOM_NORMALIZATION, SomTrainer, UnmappedClasses, som_nodes, som_params, window_som_nodes,
};
pub use svm::{SvmTrainer, WINDOW_SVM_FALLBACK_C, window_svc_params};
pub use warnings::{FEW_TRAINING_VECTORS, TrainingWarning};

use super::kept::FeatureNeeds;
use super::labelled::{check_rate, class_index, class_list};
use super::{LabelledCapture, RecognizerBody, RecognizerFile, recording_groups, trial_groups};
use crate::RecognizeError;
use crate::features::nakano::FrictionOverTravel;
use crate::features::spectral::{FEATURE_LEN, Histogram, SpectrogramPlan};
use crate::features::{
    DECISION_WINDOW_S, FeatureSet, HOP_S, NakanoWindowing, TooFastWindows, WindowScaling, WindowlessCapture,
    capture_histogram, histogram_names, window_vectors,
};
use crate::knn::PAPER_K;
use crate::sequential::DEFAULT_MEMORY_S;
use crate::som::Normalization;
#[cfg(doc)]
use crate::svc::SvcParams;
use crate::svc::{CSearch, Progress, no_progress};
use crate::{DataError, SettingError};

/// Which classifier a recognizer trains.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Method {
    /// Nakano's 1-D self-organizing map.
    Som,
    /// k nearest neighbours (Sinapov).
    Knn,
    /// One-vs-one C-SVC with a degree-2 polynomial kernel (Sinapov).
    Svm,
}

impl Method {
    /// Every method.
    pub const ALL: [Method; 3] = [Self::Som, Self::Knn, Self::Svm];

    /// The method spelled `name` ([`Method::name`]), if any.
    pub fn named(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|m| m.name() == name)
    }

    /// `som`, `knn` or `svm`, as recognizer files and `--method` spell it.
    pub fn name(self) -> &'static str {
        match self {
            Self::Som => "som",
            Self::Knn => "knn",
            Self::Svm => "svm",
        }
    }

    /// The method's own features: Nakano's rubbing windows for the SOM, Sinapov's histogram of
    /// a whole scratch for k-NN and SVM.
    pub fn default_features(self) -> FeatureSet {
        match self {
            Self::Som => FeatureSet::Nakano,
            Self::Knn | Self::Svm => FeatureSet::Spectral,
        }
    }

    /// The features this method reads from captures shaped like `capture`, in windows of at
    /// least `window_s` (the shorter of the training and decision windows), when none are asked
    /// for: both sets when the capture carries the columns of both (a rig that logs rubbing and
    /// a vibration channel) and a window holds a histogram ([`SpectrogramPlan::min_samples`],
    /// 1.92 s); else the method's own ([`Method::default_features`]), else the other set it
    /// carries, else the method's own (whose missing columns training then names).
    ///
    /// Both sets, because neither alone is enough for a rig we have not seen: Nakano's
    /// features need millimetres of travel to tell rough from smooth, and surfaces built alike
    /// (two floor mats, two papers) differ in friction but not in spectrum, or the reverse. Each
    /// set weighs the same in the combined vector (see [`WindowScaling::fit`]). On the
    /// generated 20-surface multi-stream set (trained on trials 1–5, tested on 6–10) the SOM
    /// named 85.2 % of the test windows over Nakano's features and 97.5 % over both; k-NN over
    /// whole-trial histograms 89.0 % of the trials and 97.1 % of the windows over both; the SVM
    /// 94.0 % and 97.0 %. Captures of one set only (Nakano's protocol, Sinapov's scratches)
    /// get the method's own, as before.
    pub fn features_for(self, capture: &LabelledCapture, window_s: f64) -> FeatureSet {
        let own = self.default_features();
        let other = match own {
            FeatureSet::Nakano => FeatureSet::Spectral,
            FeatureSet::Spectral | FeatureSet::Both | FeatureSet::Vibration | FeatureSet::NakanoSpectrum => {
                FeatureSet::Nakano
            }
        };
        let rate_hz = capture.capture.metadata().rate_hz();
        let holds_a_histogram = SpectrogramPlan::at_rate(rate_hz)
            .is_ok_and(|plan| (window_s * rate_hz).round() >= plan.min_samples() as f64);
        [FeatureSet::Both, own, other]
            .into_iter()
            .filter(|f| *f != FeatureSet::Both || holds_a_histogram)
            .find(|f| f.missing_columns(capture).is_empty())
            .unwrap_or(own)
    }

    /// The method's trainer.
    pub fn trainer(self) -> &'static dyn Trainer {
        match self {
            Self::Som => &SomTrainer,
            Self::Knn => &KnnTrainer,
            Self::Svm => &SvmTrainer,
        }
    }
}

/// Everything that decides how a recognizer is trained, besides the captures.
#[derive(Debug, Clone, PartialEq)]
pub struct TrainSettings {
    /// The classifier.
    pub method: Method,
    /// Its features (by default the method's own, [`Method::default_features`]).
    pub features: FeatureSet,
    /// Windowed features (nakano, both): decision window, s.
    pub window_s: f64,
    /// Windowed features: window of the training vectors, s; `None` for the method's default
    /// ([`TrainSettings::training_window_s`]).
    pub train_window_s: Option<f64>,
    /// Windowed features: time between decisions (and between training windows), s.
    pub hop_s: f64,
    /// Windowed features: decide each window at its last sample
    /// ([`NakanoWindowing::mirrored_end`]); always so for `vibration` and `nakano_spectrum`.
    pub mirrored_end: bool,
    /// Windowed features: filter the friction over travel
    /// ([`NakanoWindowing::friction_over_travel`], at [`FrictionOverTravel::protocol`]'s
    /// wavelength), so that it reads the same at any rubbing speed.
    pub friction_over_travel: bool,
    /// Windowed features: let the roughness filters follow the speed down to this one, m/s,
    /// instead of the protocol's 5 mm/s ([`NakanoWindowing::following_speeds_down_to`]).
    pub slowest_speed_mps: Option<f64>,
    /// Windowed features: windows over travel ([`NakanoWindowing::over_travel`]); needs
    /// [`TrainSettings::mirrored_end`].
    pub windows_over_travel: bool,
    /// Windows over travel: the speed at which a window spans `window_s`, m/s; `None` for
    /// the protocol's 5 mm/s ([`NakanoWindowing::over_travel_at`]).
    pub travel_speed_mps: Option<f64>,
    /// Windows over travel: the fastest stroke whose spectra the windows read, m/s; `None`
    /// for bands of 0–200 Hz at the travel speed ([`NakanoWindowing::reading_spectra_up_to`]).
    pub fastest_speed_mps: Option<f64>,
    /// SOM: seed of the map's initial vectors and presentation order.
    pub seed: u64,
    /// SOM over windows: how features are scaled before the map (a SOM over whole-scratch
    /// histograms uses [`SCRATCH_SOM_NORMALIZATION`]).
    pub normalization: Normalization,
    /// k-NN: neighbours.
    pub k: usize,
    /// SVM: how C is set.
    pub c: SvmC,
    /// The histogram's cell scaling.
    pub histogram: Histogram,
    /// SOM: nodes of each map; `None` for as many as the classes need ([`window_som_nodes`]
    /// over windows, [`som_nodes`] over whole scratches).
    pub som_nodes: Option<usize>,
    /// k-NN or SVM over windows: fit the posterior's weight on recordings held out of
    /// training ([`RecognizerFile::fit_posterior_weight`]) where the captures allow.
    pub fit_posterior_weight: bool,
    /// The posterior's memory that weight is fitted at, s: the one the recognizer will decide
    /// with (a scene's `memory_s`, `eval --memory-s`).
    pub weight_fit_memory_s: f64,
    /// SVM: wall-clock budget of its solves, counted from the instant given
    /// ([`crate::SvcParams::time_budget`]); a fit still running past it fails. The k-NN's and
    /// the SOM's fits are bounded by their sizes and take no budget. `None`: no limit.
    pub time_budget: Option<(Instant, Duration)>,
}

impl TrainSettings {
    /// The defaults of `method`: its own features, [`DECISION_WINDOW_S`] decision windows
    /// every [`HOP_S`] on the method's training windows
    /// ([`TrainSettings::training_window_s`]), seed 0, [`Normalization::LogWithinClass`], k = 3,
    /// C chosen by cross-validation ([`SvmC::auto`]), mean cells, maps sized by their classes, the
    /// posterior's weight fitted where the captures allow, at [`DEFAULT_MEMORY_S`].
    pub fn new(method: Method) -> Self {
        Self {
            method,
            features: method.default_features(),
            window_s: DECISION_WINDOW_S,
            train_window_s: None,
            hop_s: HOP_S,
            mirrored_end: false,
            friction_over_travel: false,
            slowest_speed_mps: None,
            windows_over_travel: false,
            travel_speed_mps: None,
            fastest_speed_mps: None,
            seed: 0,
            normalization: Normalization::LogWithinClass,
            k: PAPER_K,
            c: SvmC::auto(),
            histogram: Histogram::default(),
            som_nodes: None,
            fit_posterior_weight: true,
            weight_fit_memory_s: DEFAULT_MEMORY_S,
            time_budget: None,
        }
    }

    /// The window of the training vectors, s: the one set, else the decision window, for
    /// every method. A classifier compares a decision window with what it learnt from training
    /// windows, and features of another length sit elsewhere in feature space (a variance
    /// over 1 s is not one over 3 s): a map trained on Nakano's 1 s windows
    /// ([`TRAINING_WINDOW_S`](crate::features::TRAINING_WINDOW_S), `--train-window-s 1`) and
    /// deciding on 3 s named 83.2 % of the generated 20-surface multi-stream set's test windows
    /// where 3 s training windows named 85.2 %. The thesis's protocol, one 6 s run per surface,
    /// is the exception: its 1 s windows are more than twice as many.
    pub fn training_window_s(&self) -> f64 {
        self.train_window_s.unwrap_or(self.window_s)
    }

    /// The windowing of windowed features, at the rate of the first capture.
    pub fn windowing(&self, captures: &[LabelledCapture]) -> Result<NakanoWindowing, RecognizeError> {
        let rate_hz = captures
            .first()
            .map(|c| c.capture.metadata().rate_hz())
            .ok_or(RecognizeError::Data(DataError::NoTrainingData))?;
        self.windowing_at(rate_hz)
    }

    /// The windowing of windowed features at `rate_hz`.
    pub fn windowing_at(&self, rate_hz: f64) -> Result<NakanoWindowing, RecognizeError> {
        let windowing = NakanoWindowing::new(self.window_s, self.hop_s, rate_hz)?
            .with_training_window_s(self.training_window_s())?;
        let windowing = match self.slowest_speed_mps {
            Some(slowest) => windowing.following_speeds_down_to(slowest)?,
            None => windowing,
        };
        let windowing = NakanoWindowing {
            // Nothing of a window's spectrum waits for a filter's lookahead, so its windows are
            // decided at their last sample, and live its spectrum is read from the same samples
            // as its Nakano features.
            mirrored_end: self.mirrored_end
                || matches!(self.features, FeatureSet::Vibration | FeatureSet::NakanoSpectrum),
            friction_over_travel: self.friction_over_travel.then(FrictionOverTravel::protocol),
            ..windowing
        }
        .checked()?;
        let windowing = match (self.windows_over_travel, self.travel_speed_mps) {
            (true, Some(speed_mps)) => windowing.over_travel_at(speed_mps)?,
            (true, None) => windowing.over_travel()?,
            (false, _) => windowing,
        };
        match self.fastest_speed_mps {
            Some(fastest) if !matches!(self.features, FeatureSet::Vibration | FeatureSet::NakanoSpectrum) => {
                Err(RecognizeError::Setting(SettingError::Parameter {
                    of: "setting",
                    name: "fastest_speed_mps",
                    value: fastest,
                    reason: "only a spectrum reads it: --features vibration or nakano-spectrum",
                }))
            }
            Some(fastest) => windowing.reading_spectra_up_to(fastest),
            None => Ok(windowing),
        }
    }
}

impl FeatureNeeds {
    /// What training as `settings` say on captures sampled at `rate_hz` reads: the training
    /// windows of windowed features (and a k-NN's or SVM's windows from contact on, which the
    /// fit of its posterior's weight decides on), else each capture's histogram.
    pub fn training(settings: &TrainSettings, rate_hz: f64) -> Result<Self, RecognizeError> {
        let needs = Self::new();
        Ok(match settings.features {
            FeatureSet::Spectral => needs.with_histogram(settings.histogram),
            windowed => {
                let windowing = settings.windowing_at(rate_hz)?;
                let needs = needs.with_windows(windowing.training(), windowed, settings.histogram);
                // Fitting the posterior's weight runs anytime decisions on held-out captures.
                if settings.fit_posterior_weight && settings.method != Method::Som {
                    needs.with_windows(windowing.from_contact(), windowed, settings.histogram)
                } else {
                    needs
                }
            }
        })
    }

    /// What training as `settings` say and then deciding with the trained recognizer read
    /// (a cross-validation's rounds): [`FeatureNeeds::training`] and the decision windows.
    pub fn training_and_decisions(settings: &TrainSettings, rate_hz: f64) -> Result<Self, RecognizeError> {
        let needs = Self::training(settings, rate_hz)?;
        Ok(match settings.features {
            FeatureSet::Spectral => needs,
            windowed => needs.with_windows(settings.windowing_at(rate_hz)?, windowed, settings.histogram),
        })
    }
}

/// What a [`Trainer`] is given: labelled captures (whose columns have been checked against
/// `settings.features`), the settings, and where to report its long steps and what it skipped.
#[derive(Clone, Copy)]
pub struct TrainJob<'a> {
    /// The labelled training captures.
    pub captures: &'a [LabelledCapture],
    /// What to train.
    pub settings: &'a TrainSettings,
    /// Told how far the long steps are; a trainer without long steps reports nothing.
    pub progress: Progress<'a>,
}

impl std::fmt::Debug for TrainJob<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("TrainJob")
            .field("captures", &self.captures.len())
            .field("settings", self.settings)
            .finish_non_exhaustive()
    }
}

/// A method's trainer: trains a recognizer of that method on labelled captures, over the
/// features the settings name.
pub trait Trainer: Sync {
    /// The method it trains.
    fn method(&self) -> Method;

    /// Trains on `job.captures` as `job.settings` say.
    fn train(&self, job: TrainJob<'_>) -> Result<RecognizerFile, RecognizeError>;
}

/// Trains the recognizer `settings` describe on `captures`: checks that the captures carry the
/// columns its features need, then hands them to the method's [`Trainer`].
pub fn train(
    captures: &[LabelledCapture],
    settings: &TrainSettings,
) -> Result<RecognizerFile, RecognizeError> {
    settings.train_observed(captures, &no_progress)
}

impl TrainSettings {
    /// [`train`], with `progress` told of the trainer's steps and warnings (an SVM's C search
    /// and machines; see [`Trainer::train`]): the library prints nothing itself.
    pub fn train_observed(
        &self,
        captures: &[LabelledCapture],
        progress: Progress<'_>,
    ) -> Result<RecognizerFile, RecognizeError> {
        self.features.check_columns(captures)?;
        let mut file = self.method.trainer().train(TrainJob {
            captures,
            settings: self,
            progress,
        })?;
        if self.fit_posterior_weight {
            file.posterior_weight =
                file.fit_posterior_weight(captures, self.weight_fit_memory_s, progress)?;
        }
        Ok(file)
    }
}

/// Most folds of the cross-validations run on the training captures of a k-NN or SVM
/// recognizer (reliability weights, the SVM's C); fewer when there are fewer trials.
pub const CV_FOLDS: usize = 5;

/// Windows this far apart, s, stand for all of a recording's windows where a fit is only a
/// means of choosing: the default search's candidates ([`DefaultSearch`](super::DefaultSearch)),
/// the SVM's C and the refits that fit the posterior's weight. Windows every 0.1 s over 3 s
/// share 97 % of their samples, so the windows between these add little the fit does not
/// have; dropping them makes a fifth of the vectors, and an SVM's solves on them ten times
/// faster or more.
pub const SPARSE_HOP_S: f64 = 0.5;

/// Of windows every `hop_s`, every how many are [`SPARSE_HOP_S`] apart (at least 1).
pub(crate) fn sparse_every(hop_s: f64) -> usize {
    let every = (SPARSE_HOP_S / hop_s).round();
    if every.is_finite() && every >= 1.0 {
        every as usize
    } else {
        1
    }
}

/// How an SVM recognizer's C is set.
#[derive(Debug, Clone, PartialEq)]
pub enum SvmC {
    /// Per behaviour, the candidate with the best accuracy under cross-validation by trial on
    /// that behaviour's training captures; ties go to the smaller C.
    Auto(Vec<f64>),
    /// This C for every behaviour.
    Fixed(f64),
    /// This C, not cross-validated: the recognizer keeps no reliability for `eval --fuse` to
    /// weigh it by. For a caller that measures the recognizer's accuracy itself (the default
    /// search's candidates), to whom that cross-validation would be five fits more a fold.
    Unscored(f64),
}

impl SvmC {
    /// C of a behaviour whose training captures cannot be cross-validated (fewer than two
    /// trials) under [`SvmC::Auto`]: large enough for the hard-margin machine that separable
    /// histograms get (see [`SvcParams::default`]).
    pub const FALLBACK: f64 = 1e4;

    /// [`SvmC::Auto`] over [`crate::svc::C_GRID`].
    pub fn auto() -> Self {
        Self::Auto(crate::svc::C_GRID.to_vec())
    }

    /// The C to use: the best of the candidates (the grid, or the C given) under `search`, a
    /// cross-validation of them (`None` when the training data cannot be cross-validated);
    /// without one, the C given, or `fallback`.
    pub(crate) fn choose(
        &self,
        fallback: f64,
        search: impl FnOnce(&[f64]) -> Option<Result<CSearch, RecognizeError>>,
    ) -> Result<ChosenC, RecognizeError> {
        let grid = match self {
            Self::Auto(grid) => grid.clone(),
            Self::Fixed(c) => vec![*c],
            Self::Unscored(c) => return Ok(ChosenC { c: *c, search: None }),
        };
        let search = match search(&grid) {
            Some(Ok(search)) => Some(search),
            Some(Err(RecognizeError::Data(DataError::TooFewGroups { .. }))) | None => None,
            Some(Err(e)) => return Err(e),
        };
        let c = match (&search, self) {
            (Some(s), _) => s.chosen_c,
            (None, Self::Fixed(c) | Self::Unscored(c)) => *c,
            (None, Self::Auto(_)) => fallback,
        };
        Ok(ChosenC { c, search })
    }
}

/// An SVM's C, and how it was chosen ([`SvmC::choose`]).
pub(crate) struct ChosenC {
    /// The C.
    pub c: f64,
    /// The cross-validation that chose it; `None` when there was none.
    pub search: Option<CSearch>,
}

/// One behaviour's training data: its name, a histogram per capture, their class indices and
/// cross-validation groups ([`trial_groups`]).
pub(crate) type BehaviourHistograms<'a> = (Option<&'a str>, Vec<[f64; FEATURE_LEN]>, Vec<usize>, Vec<u64>);

/// Sinapov's histogram of each capture with its class index and cross-validation group,
/// grouped by behaviour (k-NN and SVM recognizers keep one classifier per behaviour).
pub(crate) fn histograms_by_behaviour<'a>(
    captures: &'a [LabelledCapture],
    classes: &[String],
    histogram: Histogram,
) -> Result<Vec<BehaviourHistograms<'a>>, RecognizeError> {
    let names: BTreeSet<Option<&str>> = captures.iter().map(|c| c.behaviour.as_deref()).collect();
    let mut out = Vec::new();
    for name in names {
        let (mut x, mut y, mut members) = (Vec::new(), Vec::new(), Vec::new());
        for c in captures.iter().filter(|c| c.behaviour.as_deref() == name) {
            x.push(capture_histogram(c, histogram)?);
            y.push(class_index(classes, c)?);
            members.push(c);
        }
        out.push((name, x, y, trial_groups(&members)));
    }
    Ok(out)
}

/// Training windows of every capture: vectors, class indices, and the cross-validation group
/// of each window (its capture's, see [`recording_groups`]).
pub(crate) type WindowData = (Vec<Vec<f64>>, Vec<usize>, Vec<u64>);

pub(crate) fn training_windows(
    captures: &[LabelledCapture],
    classes: &[String],
    windowing: &NakanoWindowing,
    features: FeatureSet,
    histogram: Histogram,
) -> Result<WindowData, RecognizeError> {
    training_windows_left_out(captures, classes, windowing, features, histogram).map(|(data, ..)| data)
}

/// A training window that covers less than this share of its travel
/// ([`NakanoWindowing::travel_share`]) is left out: over travel it holds mostly a tool at rest,
/// one spot of the surface rather than its texture, and one of fixed length that covers none
/// held the tool within the play throughout. One that covers more reads the texture, if less of
/// it than the others.
pub const LEAST_TRAINING_TRAVEL_SHARE: f64 = 0.5;

/// [`training_windows`], and how many windows were left out for covering less than
/// [`LEAST_TRAINING_TRAVEL_SHARE`] of their travel, of how many, and those left out because
/// they slid too fast for their bands (not counted in the "of how many").
pub(crate) fn training_windows_left_out(
    captures: &[LabelledCapture],
    classes: &[String],
    windowing: &NakanoWindowing,
    features: FeatureSet,
    histogram: Histogram,
) -> Result<(WindowData, usize, usize, TooFastWindows), RecognizeError> {
    let w = read_training_windows(captures, classes, windowing, features, histogram)?;
    Ok(((w.x, w.y, w.groups), w.left_out, w.of, w.too_fast))
}

/// What [`read_training_windows`] read.
struct TrainingWindowRead {
    x: Vec<Vec<f64>>,
    y: Vec<usize>,
    groups: Vec<u64>,
    /// Each window's place among its capture's windows (those left out counted), so that
    /// windows `k` places apart are `k` hops apart.
    place: Vec<usize>,
    left_out: usize,
    of: usize,
    too_fast: TooFastWindows,
}

fn read_training_windows(
    captures: &[LabelledCapture],
    classes: &[String],
    windowing: &NakanoWindowing,
    features: FeatureSet,
    histogram: Histogram,
) -> Result<TrainingWindowRead, RecognizeError> {
    features.check_columns(captures)?;
    let groups = recording_groups(captures);
    let training = windowing.training();
    let (mut x, mut y, mut g, mut place) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let mut left_out = vec![0; captures.len()];
    let mut of = 0;
    let mut too_fast = TooFastWindows::default();
    for ((c, &group), left_out) in captures.iter().zip(&groups).zip(&mut left_out) {
        check_rate(c, windowing.rate_hz)?;
        let label = class_index(classes, c)?;
        let windows = window_vectors(c, &training, features, histogram)?;
        too_fast.merge(windows.too_fast);
        for (i, (_, span, v)) in windows.vectors.into_iter().enumerate() {
            of += 1;
            if training.travel_share(span) < LEAST_TRAINING_TRAVEL_SHARE {
                *left_out += 1;
                continue;
            }
            x.push(v);
            y.push(label);
            g.push(group);
            place.push(i);
        }
    }
    every_class_has_windows(captures, classes, &y, &training, &left_out)?;
    if x.is_empty() {
        return Err(RecognizeError::Data(DataError::NoTrainingData));
    }
    Ok(TrainingWindowRead {
        x,
        y,
        groups: g,
        place,
        left_out: left_out.iter().sum(),
        of,
        too_fast,
    })
}

/// Refuses training when a class of `classes` has no vector among `labels` (the class index of
/// each training window of `captures`, cut by the training windowing `training`): a recognizer
/// would list that class but could never answer it. `left_out` is, per capture, how many of
/// its windows were left out for covering too little of their travel (all 0 where none are).
/// The error names the class and why each of its captures gave no window.
pub(crate) fn every_class_has_windows(
    captures: &[LabelledCapture],
    classes: &[String],
    labels: &[usize],
    training: &NakanoWindowing,
    left_out: &[usize],
) -> Result<(), RecognizeError> {
    let mut counts = vec![0usize; classes.len()];
    for &l in labels {
        if let Some(n) = counts.get_mut(l) {
            *n += 1;
        }
    }
    let Some(empty) = counts.iter().position(|&n| n == 0) else {
        return Ok(());
    };
    let class = classes[empty].clone();
    let captures = captures
        .iter()
        .zip(left_out.iter().copied().chain(std::iter::repeat(0)))
        .filter(|(c, _)| c.label == class)
        .map(|(c, left_out)| match left_out {
            0 => WindowlessCapture::of(c, training, "training"),
            n => all_short_of_travel(c, training, n),
        })
        .collect();
    Err(RecognizeError::Data(DataError::ClassWithoutWindows {
        class,
        captures,
    }))
}

/// Why capture `c`, whose `left_out` training windows were all left out for covering less than
/// [`LEAST_TRAINING_TRAVEL_SHARE`] of their travel, gave none.
fn all_short_of_travel(
    c: &LabelledCapture,
    training: &NakanoWindowing,
    left_out: usize,
) -> WindowlessCapture {
    let why = match training.slowest_speed_mps() {
        Some(v) => format!(
            "each covered less than {:.0} % of its travel, so its tool rested or moved slower than the \
             slowest speed the windows read ({:.1} mm/s); if the rig rubs that slowly, a lower \
             --slowest-speed-mps reads it",
            100.0 * LEAST_TRAINING_TRAVEL_SHARE,
            1e3 * v
        ),
        None => format!(
            "in each the tool never left the {:.1} mm play, so it rested",
            1e3 * crate::TRAVEL_PLAY_M
        ),
    };
    WindowlessCapture {
        path: c.reference.path.clone(),
        reason: format!("gave {left_out} training windows, all left out: {why}"),
    }
}

/// Training windows for a k-NN or SVM over windows, scaled by the [`WindowScaling`] fitted to
/// them.
pub(crate) struct ScaledWindows {
    /// The classes, in the recognizer's order.
    pub classes: Vec<String>,
    /// The scaling, as the recognizer stores it.
    pub scaling: WindowScaling,
    /// The scaled vectors.
    pub x: Vec<Vec<f64>>,
    /// Their class indices.
    pub y: Vec<usize>,
    /// Their cross-validation groups (see [`training_windows`]).
    pub groups: Vec<u64>,
    /// Each one's place among its capture's windows: windows `k` places apart are `k` hops
    /// apart ([`ScaledWindows::sparse`]).
    pub place: Vec<usize>,
}

impl ScaledWindows {
    /// Which windows are every `every`-th of their capture (from its first): windows
    /// [`SPARSE_HOP_S`] apart stand for all of a recording's where a fit is only a means of
    /// choosing (C, the posterior's weight). All of them when `every` is 1, or when one of the
    /// `classes` classes would be left without a window.
    pub fn sparse(&self, every: usize, classes: usize) -> Vec<bool> {
        let every = every.max(1);
        let kept: Vec<bool> = self.place.iter().map(|p| p.is_multiple_of(every)).collect();
        let mut seen = vec![false; classes];
        for (&y, _) in self.y.iter().zip(&kept).filter(|(_, k)| **k) {
            if let Some(s) = seen.get_mut(y) {
                *s = true;
            }
        }
        if seen.iter().all(|&s| s) {
            kept
        } else {
            vec![true; self.x.len()]
        }
    }
}

/// The scaled training windows of `captures` (`features` [`FeatureSet::Nakano`] or
/// [`FeatureSet::Both`]).
pub(crate) fn scaled_training_windows(
    captures: &[LabelledCapture],
    windowing: &NakanoWindowing,
    features: FeatureSet,
    histogram: Histogram,
) -> Result<ScaledWindows, RecognizeError> {
    window_check(features)?;
    let classes = class_list(captures);
    let TrainingWindowRead {
        x, y, groups, place, ..
    } = read_training_windows(captures, &classes, windowing, features, histogram)?;
    let scaling = WindowScaling::fit(&x, &y, features.blocks());
    let x = x.iter().map(|v| scaling.apply(v)).collect();
    Ok(ScaledWindows {
        classes,
        scaling,
        x,
        y,
        groups,
        place,
    })
}

impl RecognizerFile {
    /// A recognizer of whole scratches, one classifier per behaviour (`behaviours` of them in
    /// `body`), over Sinapov's histograms; no behaviour means no training data.
    pub(crate) fn assemble_scratches(
        classes: Vec<String>,
        behaviours: usize,
        body: RecognizerBody,
        captures: &[LabelledCapture],
    ) -> Result<Self, RecognizeError> {
        if behaviours == 0 {
            return Err(RecognizeError::Data(DataError::NoTrainingData));
        }
        Ok(Self::assemble(
            classes,
            histogram_names(),
            body,
            captures,
            captures.len(),
        ))
    }
}

/// Whether every class has windows in at least two groups, so that no fold of a
/// cross-validation by group holds out a whole class.
pub(crate) fn every_class_in_two_groups(labels: &[usize], groups: &[u64]) -> bool {
    let mut by_class: BTreeMap<usize, BTreeSet<u64>> = BTreeMap::new();
    for (&l, &g) in labels.iter().zip(groups) {
        by_class.entry(l).or_default().insert(g);
    }
    by_class.values().all(|g| g.len() >= 2)
}

/// Windows carry `nakano` or `both` features, not `spectral`.
pub(crate) fn window_check(features: FeatureSet) -> Result<(), RecognizeError> {
    if features == FeatureSet::Spectral {
        return Err(RecognizeError::Setting(SettingError::Parameter {
            of: "setting",
            name: "features",
            value: f64::NAN,
            reason: "windows carry `nakano` or `both` features; `spectral` is one histogram per scratch",
        }));
    }
    Ok(())
}
