//! The `palpus` application: the command line and the wiring between the crates.
//!
//! `identify` (models from captures) and `haptics` (the simulated world, devices, the haptic
//! loop) know nothing of each other's threads or files; this crate is the only place that joins
//! them.

pub mod cli;
