//! Measurement protocols: the papers' experiments, run in the simulated world and recorded as
//! captures.
//!
//! Each protocol simulates its rig at the rig's control rate, passes every logged quantity
//! through the rig's sensor models ([`super::world::sensor`]) and writes what the rig would have
//! logged, with the ground truth in the capture's metadata. A protocol is deterministic in its
//! seed: same seed, same bytes.

mod columns;
pub mod generate;
pub mod li_bi;
pub mod nakano;
pub mod sinapov;

pub use generate::{CaptureSet, GenError, GenSummary, Generated, generate};

/// Which half of a train/test pair a capture is. The test half uses another seed *and* another
/// trajectory (other speeds, other load profile), so held-out evaluation is not interpolation
/// between training samples.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Split {
    /// Data to identify from.
    Train,
    /// Held-out data to evaluate on.
    Test,
}

impl Split {
    /// `train` or `test`.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Train => "train",
            Self::Test => "test",
        }
    }
}

pub use capture::rng::derive_seed;

/// Tags for [`derive_seed`], one per protocol.
pub(crate) mod tag {
    pub const HARD: u64 = 1;
    pub const SOFT: u64 = 2;
    pub const NEEDLE: u64 = 3;
    pub const NAKANO: u64 = 4;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn derived_seeds_differ_by_tag_and_path() {
        let a = derive_seed(1, &[tag::HARD, 0]);
        assert_eq!(a, derive_seed(1, &[tag::HARD, 0]));
        assert_ne!(a, derive_seed(1, &[tag::HARD, 1]));
        assert_ne!(a, derive_seed(2, &[tag::HARD, 0]));
        assert_ne!(derive_seed(1, &[1, 2]), derive_seed(1, &[2, 1]));
    }
}
