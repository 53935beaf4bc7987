//! The render crate's integration tests, one binary.

// A failed unwrap is a failed test, reported with its line.
#![allow(clippy::unwrap_used)]

mod assets;
mod gltf_files;
mod golden;
mod headless;
mod interior;
mod no_adapter;
mod shader_branches;
mod window;
