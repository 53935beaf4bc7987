//! Simulation: the ground-truth world and the protocols that measure it.

pub mod protocols;
pub mod world;
