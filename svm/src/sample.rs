//! A deterministic needle-sized model, the one the fast path's tests and the prediction
//! benchmark measure, kept in one place so both measure the same thing.

use super::kernel::Kernel;
use super::model::{InputScaling, SvrModel};

/// Deterministic values in [−1, 1) with no lattice structure.
pub(crate) fn wiggle(i: usize, salt: f64) -> f64 {
    (i as f64 * 0.618_033_988_749_894_8 + salt).fract() * 2.0 - 1.0
}

/// A needle-like model: 100 RBF support vectors on [depth, velocity] scaled to the unit box
/// (depth 0–30 mm, velocity ±10 mm/s), coefficients up to `c_max`.
#[doc(hidden)]
pub fn needle_like_model(gamma: f64, c_max: f64) -> (SvrModel, InputScaling) {
    let n = 100;
    let support_vectors = (0..2 * n).map(|i| 0.5 + 0.5 * wiggle(i, 0.3)).collect();
    let coefficients = (0..n).map(|i| c_max * wiggle(i, 0.71)).collect();
    let model = SvrModel {
        kernel: Kernel::Rbf { gamma },
        dim: 2,
        support_vectors,
        coefficients,
        bias: 0.4,
        weights: None,
    };
    let scaling = InputScaling {
        offset: vec![0.0, -0.01],
        scale: vec![0.03, 0.02],
    };
    (model, scaling)
}
