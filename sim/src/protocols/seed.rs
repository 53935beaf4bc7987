//! Seeds: each protocol derives its captures' seeds from the run's seed and a tag of its own.

pub use capture::rng::derive_seed;

/// Tags for [`derive_seed`], one per protocol.
pub(crate) mod tag {
    pub const HARD: u64 = 1;
    pub const SOFT: u64 = 2;
    pub const NEEDLE: u64 = 3;
    pub const NAKANO: u64 = 4;
    pub const MULTISTREAM: u64 = 5;
    /// A multi-stream trial's rig effect, drawn apart from the trial's own stream.
    pub const RIG_EFFECT: u64 = 6;
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
