//! Simulation: the ground-truth world, the protocols that measure it, and the operator's hand.

pub mod hand;
pub mod protocols;
pub mod world;
