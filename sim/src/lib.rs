//! The simulated world palpus is developed against, and the papers' protocols that measure it.
//!
//! May import `capture` (the data contract), `fft` (the transforms) and `recognize` (the
//! metadata keys its captures carry for the recognizers), each through its door, and no other
//! palpus crate; `haptics` builds its simulated Omega.7 on this crate, and the binary's
//! `palpus gen` runs its protocols.
//!
//! This file is the crate's door: other crates name what they use as `sim::X`, and a paper's
//! protocol as `sim::li_bi::X`, `sim::nakano::X`, `sim::sinapov::X` or `sim::multistream::X`
//! (each paper's settings live in its own namespace). Inside:
//!
//! - `world`: the ground truth: needle tissue, hard and soft contact friction, rubbing
//!   surfaces, scratched surfaces, and the sensors that read them (encoders, force sensors,
//!   accelerometers);
//! - `hand`: the operator's hand as an impedance following scripted waypoints;
//! - `protocols`: the papers' experiments run in that world and written as captures, each
//!   deterministic in its seed;
//! - [`SimError`]: every failure of the above as one type.

mod error;
mod hand;
mod protocols;
mod world;

pub use error::SimError;
pub use hand::{HandImpedance, HandScript, HandTarget, LiveHand, Waypoints};
pub use protocols::{
    CaptureSet, GenSummary, Generated, Split, Variant, derive_seed, generate, generate_variant,
};
pub use protocols::{li_bi, multistream, nakano, sinapov};
pub use world::friction::{HardContact, SoftContact, kgf_to_n};
pub use world::needle::{Membrane, NeedleForce, NeedleSite, NeedleTissue};
pub use world::profile::{Band, Profile};
pub use world::scratch::{
    Adxl345, Behaviour, ScratchRecording, ScratchSurface, household_surfaces, scratch_trial,
};
pub use world::sensor::{Encoder, ForceSensor, LowPass, Noise, round_to};
pub use world::surface::{RubbingSurface, SurfacePatch, nakano_surfaces};
