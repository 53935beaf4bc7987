//! The identify crate's integration tests, one binary.

// A failed unwrap is a failed test, reported with its line.
#![allow(clippy::unwrap_used)]

mod bounds;
mod identification;
mod needle_baseline_and_domain;
mod needle_corpus;
mod phases;
mod punctures;
mod robustness;
