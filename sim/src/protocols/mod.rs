//! Measurement protocols: the papers' experiments, run in the simulated world and recorded as
//! captures.
//!
//! Each protocol simulates its rig at the rig's control rate, passes every logged quantity
//! through the rig's sensor models ([`super::world::sensor`]) and writes what the rig would have
//! logged, with the ground truth in the capture's metadata. A protocol is deterministic in its
//! seed: same seed, same bytes.

mod columns;
mod generate;
pub mod li_bi;
pub mod multistream;
pub mod nakano;
mod seed;
pub mod sinapov;
mod split;

pub use generate::{CaptureSet, GenSummary, Generated, Variant, generate, generate_variant};
pub use seed::derive_seed;
pub use split::Split;
