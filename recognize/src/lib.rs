//! Surface recognition from rubbing and scratching: Nakano's roughness and friction features
//! with a 1-D self-organizing map, and Sinapov's spectrotemporal features with k-NN and a
//! one-vs-one SVC; recognizer files ([`RecognizerFile`]) train, store and evaluate either.
//!
//! May import `capture` (the data contract) and `svm` (the solvers), no other palpus crate.
//!
//! This file is the crate's door: other crates name what they use as `recognize::X`, or, for
//! the three modules that are namespaces of their own, `recognize::nakano::X` (Nakano's rubbing
//! features), `recognize::spectral::X` (Sinapov's spectrotemporal histogram) and
//! `recognize::protocol::X` (the papers' cross-validations).
//!
//! Inside: `features` (those two feature sets, the vibration spectrum and how a capture is cut
//! into windows), the classifiers `som`, `knn` and `svc`, `recognizer` (the recognizer file, its
//! training, decisions and evaluation), `sequential` (anytime decisions), `fusion`, `category`
//! (surface categories) and `eval` (confusion matrices and decision timing).
mod category;
mod error;
mod eval;
mod features;
mod folds;
mod fusion;
mod knn;
pub mod protocol;
mod recognizer;
mod sequential;
mod som;
mod svc;
mod vectors;

pub use category::{
    CategoryTree, StopRule, classical_mds, distances_from_similarity, isomap, recursive_ncut,
    similarity_from_confusion,
};
pub use error::{DataError, InputError, RecognizeError, SettingError, SolverError, UsageError};
pub use eval::{ConfusionMatrix, DecisionTiming, NamedDecision, natural_cmp, stable_right_from};
pub use features::nakano::{self, FEATURES, NakanoConfig, NakanoSignals, NakanoStream};
pub use features::spectral::{self, CellScale, FEATURE_LEN, Histogram, HistogramBand, SpectrogramPlan};
pub use features::window_spectrum::{SPECTRUM_LEN, SpectrumScratch, WindowSpectrumPlan};
pub use features::{
    DECISION_WINDOW_S, FeatureSet, HOP_S, NakanoWindowing, PlayedPath, TRAINING_WINDOW_S, TRAVEL_PLAY_M,
    TooFastWindows, TravelWindows, WindowScaling, WindowSpan, WindowlessCapture,
};
pub use fusion::{BehaviourData, ReliabilityFusion, argmax, fuse, fused_label};
pub use knn::{FeatureScaling, Knn, KnnParams};
pub use protocol::{ProtocolResult, SINAPOV_FOLDS, Split, surface_confusion};
pub use recognizer::{
    BEHAVIOUR_KEY, BehaviourKnn, BehaviourReliability, BehaviourScore, BehaviourSom, BehaviourSvc, CV_FOLDS,
    Decision, Evaluation, FEW_TRAINING_VECTORS, FeatureNeeds, FusedEvaluation, HeldOutDecisions, KnnTrainer,
    LABEL_KEY, LEAST_TRAINING_TRAVEL_SHARE, LabelledCapture, Method, PosteriorWeight, RECOGNIZER_FORMAT,
    RECOGNIZER_VERSION, RecognizerBody, RecognizerFile, SCRATCH_SOM_NORMALIZATION, SomQuality, SomTrainer,
    SvmC, SvmTrainer, TRIAL_KEY, TrainJob, TrainSettings, Trainer, TrainingWarning, UnmappedClasses,
    WINDOW_SVM_FALLBACK_C, WindowProbabilities, recording_groups, som_nodes, som_params, train, trial_groups,
    window_som_nodes, window_svc_params,
};
pub use recognizer::{
    CLEAR_MARGIN_Z, Candidate, CandidateScore, DefaultChoice, DefaultSearch, Named, Outcome, SEARCH_BUDGET_S,
    SEARCH_FOLDS, SHORT_WINDOW_S, SPARSE_HOP_S,
};
pub use recognizer::{
    Calibration, FusionMember, ReliabilityBin, SURFACE_AFTER_KEY, SURFACE_CHANGE_S_KEY, SequentialEvaluation,
    SequentialRow, SurfaceChange, SurfaceWait, WindowClassifier,
};
pub use sequential::{
    DEFAULT_CHANGE_ODDS, DEFAULT_FLOOR, DEFAULT_MEMORY_S, DEFAULT_THRESHOLD, SequentialParams,
    SequentialParamsBuilder, SequentialState, SequentialStep,
};
pub use som::{Normalization, Som, SomParams};
pub use svc::{CSearch, CvPoint, FitEvent, Progress, Svc, SvcParams, TrainingVectors};
