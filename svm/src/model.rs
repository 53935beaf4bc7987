//! A fitted ε-SVR: `f(x) = Σ βᵢ K(xᵢ, x) + b` over its support vectors (Li & Bi Eq. 10).

use serde::{Deserialize, Serialize};

use super::kernel::Kernel;

/// A fitted ε-SVR in the space it was trained in (inputs already scaled by the caller, see
/// [`super::InputScaling`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SvrModel {
    /// The kernel and its parameters.
    pub kernel: Kernel,
    /// Input dimension.
    pub dim: usize,
    /// Support vectors, `n_sv × dim`, row-major.
    pub support_vectors: Vec<f64>,
    /// Their coefficients `βᵢ = αᵢ − αᵢ*`, one per support vector.
    pub coefficients: Vec<f64>,
    /// Bias `b` (libsvm's `−rho`).
    pub bias: f64,
    /// For a linear kernel, the primal weights `w` (so `f(x) = w·x + b`), solved for directly:
    /// at large C, `Σ βᵢ xᵢ` sums terms ~C that cancel to ~w and keeps only a few digits.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub weights: Option<Vec<f64>>,
}

impl SvrModel {
    /// Number of support vectors.
    pub fn n_sv(&self) -> usize {
        self.coefficients.len()
    }

    /// The `i`-th support vector.
    pub fn support_vector(&self, i: usize) -> &[f64] {
        &self.support_vectors[i * self.dim..(i + 1) * self.dim]
    }

    /// `f(x)`. `x` must have `dim` elements (this is the general path; the haptic loop uses
    /// a fixed-dimension, allocation-free evaluator).
    pub fn predict(&self, x: &[f64]) -> f64 {
        if let Some(w) = &self.weights {
            return self.bias + w.iter().zip(x).map(|(a, b)| a * b).sum::<f64>();
        }
        let mut sum = self.bias;
        for (i, beta) in self.coefficients.iter().enumerate() {
            sum += beta * self.kernel.eval(self.support_vector(i), x);
        }
        sum
    }

    /// For a linear kernel, the weight vector `w = Σ βᵢ xᵢ` (so `f(x) = w·x + b`).
    pub fn linear_weights(&self) -> Option<Vec<f64>> {
        if self.kernel != Kernel::Linear {
            return None;
        }
        if let Some(w) = &self.weights {
            return Some(w.clone());
        }
        let mut w = vec![0.0; self.dim];
        for (i, beta) in self.coefficients.iter().enumerate() {
            for (wk, xk) in w.iter_mut().zip(self.support_vector(i)) {
                *wk += beta * xk;
            }
        }
        Some(w)
    }
}

/// Affine input scaling `x_scaled = (x − offset) / scale`, fitted on training data so that
/// RBF widths mean the same thing whatever the units (depth in metres, speed in m/s).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct InputScaling {
    /// Subtracted from each input.
    pub offset: Vec<f64>,
    /// Each input is divided by this (never 0).
    pub scale: Vec<f64>,
}

impl InputScaling {
    /// Maps each of the `dim` inputs of the row-major `x` onto [0, 1] over the data's range
    /// (constant inputs get scale 1).
    pub fn min_max(x: &[f64], dim: usize) -> Self {
        let mut lo = vec![f64::INFINITY; dim];
        let mut hi = vec![f64::NEG_INFINITY; dim];
        for row in x.chunks_exact(dim) {
            for k in 0..dim {
                lo[k] = lo[k].min(row[k]);
                hi[k] = hi[k].max(row[k]);
            }
        }
        let scale = lo
            .iter()
            .zip(&hi)
            // An input that does not vary (one speed: a digitized curve's velocity is the stated
            // speed, up to rounding) keeps unit scale; 1/rounding error would blow its noise
            // up to the whole [0, 1] range.
            .map(|(l, h)| {
                if h - l > 1e-9 * l.abs().max(h.abs()) {
                    h - l
                } else {
                    1.0
                }
            })
            .collect();
        Self { offset: lo, scale }
    }

    /// The identity scaling.
    pub fn identity(dim: usize) -> Self {
        Self {
            offset: vec![0.0; dim],
            scale: vec![1.0; dim],
        }
    }

    /// Scales one input vector into `out`.
    pub fn apply_into(&self, x: &[f64], out: &mut [f64]) {
        for (k, o) in out.iter_mut().enumerate() {
            *o = (x[k] - self.offset[k]) / self.scale[k];
        }
    }

    /// Scales a row-major block of inputs.
    pub fn apply(&self, x: &[f64]) -> Vec<f64> {
        let dim = self.offset.len();
        let mut out = vec![0.0; x.len()];
        for (row, o) in x.chunks_exact(dim).zip(out.chunks_exact_mut(dim)) {
            self.apply_into(row, o);
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn predict_is_the_kernel_expansion_and_linear_weights_agree() {
        let m = SvrModel {
            kernel: Kernel::Linear,
            dim: 2,
            support_vectors: vec![1.0, 0.0, 0.0, 2.0],
            coefficients: vec![0.5, -0.25],
            bias: 0.1,
            weights: None,
        };
        let x = [3.0, 4.0];
        assert!((m.predict(&x) - (0.5 * 3.0 - 0.25 * 8.0 + 0.1)).abs() < 1e-15);
        assert_eq!(m.linear_weights().unwrap(), vec![0.5, -0.5]);
    }

    #[test]
    fn min_max_scaling_maps_the_range_onto_the_unit_box() {
        let x = [0.0, 10.0, 0.02, 30.0, 0.01, 20.0];
        let s = InputScaling::min_max(&x, 2);
        assert_eq!(s.apply(&x), vec![0.0, 0.0, 1.0, 1.0, 0.5, 0.5]);
        let c = InputScaling::min_max(&[5.0, 5.0], 1);
        assert_eq!(c.scale, vec![1.0]);
    }
}
