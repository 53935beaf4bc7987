//! The recognize crate's integration tests, one binary.

// A failed unwrap is a failed test, reported with its line.
#![allow(clippy::unwrap_used)]

mod both_single_axis;
mod nakano_speed;
mod single_axis;
