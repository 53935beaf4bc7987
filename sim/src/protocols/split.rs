//! Train and test halves of a protocol's captures.

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
