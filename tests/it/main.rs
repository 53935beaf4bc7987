//! Integration tests of the palpus binary and the crates together, gathered into one test
//! binary so that the application is linked once; `tests/run/` (real-time sessions, paced
//! one at a time) is kept apart so that nothing else runs beside its rate checks.

// A failed unwrap is a failed test, reported with its line.
#![allow(clippy::unwrap_used)]

#[path = "../common/mod.rs"]
mod common;

mod architecture;
mod capture_import;
mod cli;
mod cli_haptics;
mod fuzz_parsers;
mod identify_cli_extras;
mod identify_predictions;
mod model_validation;
mod multistream_e2e;
mod quiet_headless;
mod readme;
mod recognition_cli;
mod recognition_kept_features;
mod recognition_live;
mod recognition_nakano;
mod recognition_sequential;
mod recognition_sinapov;
mod recognition_single_axis;
mod recognition_speed;
mod recognizer_rules;
mod recording_kill;
mod scene_budget;
mod scene_meshes;
mod window_xvfb;
