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

/// Derives an independent stream seed from a user seed and a path of tags (splitmix64 over
/// the sequence), so that adding a protocol or a trial never shifts another one's noise.
pub fn derive_seed(seed: u64, tags: &[u64]) -> u64 {
    let mut state = seed;
    for &tag in tags {
        state = splitmix64(state ^ splitmix64(tag));
    }
    splitmix64(state)
}

fn splitmix64(mut x: u64) -> u64 {
    x = x.wrapping_add(0x9e37_79b9_7f4a_7c15);
    x = (x ^ (x >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    x ^ (x >> 31)
}

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
