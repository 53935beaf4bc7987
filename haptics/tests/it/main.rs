//! The haptics crate's integration tests, one binary; `no_alloc.rs` stays its own binary
//! because its counting global allocator must watch the haptic thread alone.

// A failed unwrap is a failed test, reported with its line.
#![allow(clippy::unwrap_used)]

#[path = "../common/mod.rs"]
mod common;

mod acquire;
mod admittance;
mod fake_vendor;
mod loop_safety;
mod needle_phases_tissues;
mod omega7_loader;
mod recorder_kill;
mod recorder_partial;
