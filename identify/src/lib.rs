//! Identification of haptic dynamics from captures.
//!
//! This crate is pure computation on data: it knows nothing of threads, devices or rendering.
//! Top-down: [`capture`] (the CSV files every recording is stored in, read strictly),
//! [`signal`] (velocity from position), [`svr`] (the ε-SVR: interior point with an exact polish,
//! SMO, the haptic fast path, libsvm export), [`baselines`] and [`metrics`] (what a model is
//! compared with, and how), [`identification`] (Li & Bi's three models), [`search`]
//! (cross-validated hyperparameters) and [`model_file`] (models on disk).

pub mod baselines;
pub mod capture;
pub mod identification;
pub mod metrics;
pub mod model_file;
pub mod recognition;
pub mod search;
pub mod signal;
pub mod svr;

pub use capture::{
    Capture, CaptureError, CaptureErrorKind, CaptureKind, CaptureReader, CaptureWriter, FORMAT_VERSION,
    Metadata, write_atomically,
};
