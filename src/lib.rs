//! The `palpus` application: the command line and the wiring between the crates.
//!
//! `identify` (models from captures) and `haptics` (the simulated world, devices, the haptic
//! loop) know nothing of each other's threads or files; this crate is the only place that joins
//! them: scenes say what a session contains ([`scene`]), [`models`] loads or identifies exactly
//! the models a scene needs, [`session`] runs them on the haptic thread and reports, and
//! [`plots`] draws every figure.

pub mod attempt;
pub mod cli;
pub mod exit;
pub mod fit_files;
pub mod history;
pub mod models;
pub mod plots;
pub mod recognizer;
mod scale_sets;
pub mod scene;
pub mod session;
mod tables;
pub mod trade;
pub mod training;
pub mod view;
pub mod window;
