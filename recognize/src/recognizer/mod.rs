//! Surface recognizers on disk: self-describing JSON, validated on load, and the offline
//! pipeline that trains and evaluates them on labelled captures.
//!
//! A recognizer file names its method (Nakano's SOM over sliding windows, or Sinapov's k-NN
//! over one scratch per capture), the classes in label order, how features are computed (filters,
//! window, hop, sample rate; or the histogram's cell scaling), the trained map or training set
//! with its feature scaling, and a SHA-256 of each training capture and of all of them together.
//! Loading checks the format, the version and every shape, so a truncated or hand-edited file is
//! a typed error naming the file and the field — never a wrong label on the haptic thread.
//!
//! **Labels** come from each capture's metadata: `surface` is the class, and `behaviour` (for
//! scratches) picks which k-NN answers. **Windows** of the SOM start at
//! `lookahead + k · hop` samples (the first sample whose zero-phase filters are complete, then
//! every hop) and only once the tip has travelled
//! [`NakanoWindowing::start_travel_m`](crate::NakanoWindowing::start_travel_m) from the capture's
//! first sample, as the thesis starts recognising after 5 mm; a live recognizer fed the same
//! samples makes its decisions on exactly these windows.

mod choice;
mod choice_table;
mod decide;
mod evaluate;
mod file;
mod grouping;
mod kept;
pub(crate) mod labelled;
mod posterior_weight;
mod sequential_eval;
mod train;
mod weight_fit;
mod window_classifier;

pub use choice::{CLEAR_MARGIN_Z, DefaultSearch, Named, SEARCH_BUDGET_S, SEARCH_FOLDS, SHORT_WINDOW_S};
pub use choice_table::{Candidate, CandidateScore, DefaultChoice, Outcome};
pub use decide::{BehaviourReliability, Decision, WindowProbabilities};
pub use evaluate::{BehaviourScore, Evaluation, FusedEvaluation, SomQuality};
pub use file::{
    BehaviourKnn, BehaviourSom, BehaviourSvc, RECOGNIZER_FORMAT, RECOGNIZER_VERSION, RecognizerBody,
    RecognizerFile,
};
pub use grouping::{TRIAL_KEY, recording_groups, trial_groups};
pub use kept::FeatureNeeds;
pub use labelled::{
    BEHAVIOUR_KEY, LABEL_KEY, LabelledCapture, SURFACE_AFTER_KEY, SURFACE_CHANGE_S_KEY, SurfaceChange,
};
pub use posterior_weight::{HeldOutDecisions, PosteriorWeight};
pub use sequential_eval::{
    Calibration, FusionMember, ReliabilityBin, SequentialEvaluation, SequentialRow, SurfaceWait,
};
pub use train::{
    CV_FOLDS, FEW_TRAINING_VECTORS, KnnTrainer, LEAST_TRAINING_TRAVEL_SHARE, Method,
    SCRATCH_SOM_NORMALIZATION, SPARSE_HOP_S, SomTrainer, SvmC, SvmTrainer, TrainJob, TrainSettings, Trainer,
    TrainingWarning, UnmappedClasses, WINDOW_SVM_FALLBACK_C, som_nodes, som_params, train, window_som_nodes,
    window_svc_params,
};
pub use window_classifier::WindowClassifier;

#[cfg(test)]
mod tests;
