//! Identification of haptic dynamics from captures.
//!
//! This crate is pure computation on data: it knows nothing of threads, devices or rendering.
//! It may import `capture` (the data contract) and `svm` (the solvers), no other palpus crate.
//! Top-down: [`baselines`] and [`metrics`] (what a model is compared with, and how),
//! [`identification`] (Li & Bi's three models), [`search`] (cross-validated hyperparameters)
//! and [`model_file`] (models on disk).

pub mod baselines;
pub mod identification;
pub mod metrics;
pub mod model_file;
pub mod search;
