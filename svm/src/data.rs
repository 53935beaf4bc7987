//! An ε-SVR's training data, checked once before any solver sees it.

use super::error::SvmError;

/// Training data of an ε-SVR, checked once: `x` is `n × dim` row-major, `y` has `n` targets,
/// every value finite.
#[derive(Debug, Clone, Copy)]
pub(crate) struct SvrData<'a> {
    /// Inputs, row-major.
    pub x: &'a [f64],
    /// Input dimension.
    pub dim: usize,
    /// Targets.
    pub y: &'a [f64],
}

impl<'a> SvrData<'a> {
    /// Checks the shapes and values.
    pub fn new(x: &'a [f64], dim: usize, y: &'a [f64]) -> Result<Self, SvmError> {
        let n = y.len();
        if n == 0 {
            return Err(SvmError::NoSamples);
        }
        if dim == 0 || x.len() != n * dim {
            return Err(SvmError::Shape {
                array: "input",
                values: x.len(),
                rows_of: "targets",
                rows: n,
                dim,
            });
        }
        for (row, chunk) in x.chunks_exact(dim).enumerate() {
            if let Some(k) = chunk.iter().position(|v| !v.is_finite()) {
                return Err(SvmError::NonFinite {
                    row,
                    what: format!("input {k}"),
                });
            }
        }
        if let Some(row) = y.iter().position(|v| !v.is_finite()) {
            return Err(SvmError::NonFinite {
                row,
                what: "target".into(),
            });
        }
        Ok(Self { x, dim, y })
    }
}

/// `1 + max|yᵢ|`: the scale the solvers measure residuals and tolerances on, so that they mean
/// the same for targets in newtons or in millinewtons.
pub(crate) fn target_scale(y: &[f64]) -> f64 {
    1.0 + y.iter().fold(0.0f64, |m, v| m.max(v.abs()))
}
