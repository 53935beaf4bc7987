//! The simulated world palpus is developed against, and the papers' protocols that measure it.
//!
//! May import `capture` (the data contract) and `recognize` (the metadata keys its captures
//! carry for the recognizers), each through its door, and no other palpus crate; `haptics`
//! builds its simulated Omega.7 on this crate, and the binary's `palpus gen` runs its protocols.
//!
//! - [`world`]: the ground truth: needle tissue, hard and soft contact friction, rubbing
//!   surfaces, and the sensors that read them (encoders, force sensors, accelerometers);
//! - [`hand`]: the operator's hand as an impedance following scripted waypoints;
//! - [`protocols`]: the papers' experiments run in that world and written as captures, each
//!   deterministic in its seed;
//! - [`SimError`]: every failure of the above as one type.

mod error;
pub mod hand;
pub mod protocols;
pub mod world;

pub use error::SimError;
