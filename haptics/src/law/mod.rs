//! Force laws: identified models turned into forces on the haptic thread.
//!
//! [`model::ScalarModel`] is what a law needs from an identified model (an allocation-free
//! evaluation and its training box); [`needle`] and [`friction`] are Li & Bi's laws over such
//! models, [`phased`] renders the phase-aware needle model; [`environment`] places them in a virtual world; [`reference`](mod@reference) holds closed-form
//! models of the simulated world's truth with the same interface.

pub mod environment;
pub mod friction;
pub mod identified;
pub mod model;
pub mod needle;
pub mod phased;
pub mod reference;

pub use environment::{Environment, EnvironmentForce, FreeSpace, FrictionSurface, NeedleEnvironment};
pub use friction::{FrictionLaw, Frictionless, HardFriction, SoftFriction};
pub use identified::{SvrForceModel, hard_friction_model, needle_model, soft_friction_models};
pub use model::{Evaluation, FnModel, InputBox, ScalarModel, eval_clamped};
pub use needle::{AxialLaw, NeedleLaw, NeedleLawConfig, NeedleOutput, PunctureState};
pub use phased::PhasedNeedleLaw;
pub use reference::{NeedleQuasiStatic, hard_contact_model, soft_contact_models};
