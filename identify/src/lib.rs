//! Identification of haptic dynamics from captures.
//!
//! This crate is pure computation on data: it knows nothing of devices or rendering, and its
//! only concurrency is rayon's pool (cross-validation folds side by side).
//! It may import `capture` (the data contract) and `svm` (the solvers), no other palpus crate.
//! Top-down: `baselines` and `metrics` (what a model is compared with, and how),
//! `identification` (what Li & Bi's three models share), `contact_identification` and
//! `needle_identification` (the models), `punctures` (puncture events and layers
//! read from insertion data), `phases` (the phase-aware needle model built on them), `search` (cross-validated hyperparameters)
//! and `model_file` (models on disk). Every failure of any of them is one [`IdentifyError`]
//! (`error`), which wraps `capture`'s and `svm`'s errors. This file is the crate's door:
//! everything public is re-exported here, so callers write `identify::ModelFile`,
//! `identify::identify`.

mod baselines;
mod bounds;
mod by_kind;
mod contact_identification;
mod error;
mod grid_spec;
mod identification;
mod metrics;
mod model_file;
mod needle_identification;
mod outliers;
mod phase_identification;
mod phase_parts;
mod phases;
mod plausibility;
mod punctures;
mod search;

pub use baselines::{CentrePlacement, CoulombViscous, CoulombViscousStiffness, RbfNetwork, RbfNetworkParams};
pub use bounds::{BoundViolation, CHECK_WORK, DeviceEnvelope, ForceCertificate, SIGN_TOLERANCE_N};
pub use by_kind::{PLAUSIBLE_RANGE_MARGIN, identify, identify_with};
pub use error::IdentifyError;
pub use grid_spec::{GridSpecError, MAX_GRID_VALUES};
pub use identification::{
    BaselineNotFitted, BaselinePunctures, ComparedMetrics, DEFAULT_MAX_FIT_SAMPLES, DOMAIN_MARGIN, FitLimits,
    Identified, IdentifyOptions, MAX_SEGMENT_SAMPLES, OutOfDomain, Report, model_column, model_rows,
    out_of_domain,
};
pub use metrics::{
    Metrics, PAPER_DURATION_S, PAPER_STEP_S, aise, aise_paper, aise_trapezoid, error_bound, errors, rmse,
};
pub use model_file::{
    Hyperparameters, MODEL_FORMAT, MODEL_VERSION, ModelBody, ModelFile, ModelKind, Quantity, ScaledSvr,
    SvrHyper,
};
pub use needle_identification::{NEEDLE_C, NEEDLE_EPSILON_N, NEEDLE_GAMMA, NEEDLE_SAMPLES};
pub use outliers::{Outlier, OutlierScreen, force_noise_n};
pub use phase_identification::{PhaseForm, identify_phases};
pub use phase_parts::PartComparison;
pub use phases::{
    Domain, HOLD_JITTER_MPS, LayerModel, Loading, MAX_LAYERS, PartSvr, Phase, PhaseExit, PhaseModel,
    PhaseState, PhaseStep, REVERSAL_MPS, Rupture, ShaftLaw, TIP_CONTACT_M, Threshold, WithdrawalSource,
};
pub use plausibility::Plausibility;
pub use punctures::{
    Layer, PunctureComparison, PunctureDetection, PunctureEvent, PunctureParams, compare_punctures,
    detect_punctures, group_layers,
};
pub use search::{
    PREDICT_TIMING_PASSES, SearchGrid, SearchPoint, best, search, search_with, timed_predictions,
};
