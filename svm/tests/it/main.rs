//! The svm crate's integration tests, one binary.

// A failed unwrap is a failed test, reported with its line.
#![allow(clippy::unwrap_used)]

#[path = "../common/mod.rs"]
mod common;

mod at_limit;
mod linear_extremes;
mod svr_exact;
mod svr_extremes;
mod svr_libsvm;
mod svr_low_rank;
mod svr_rbf_extremes;
mod svr_smo_finish;
