//! The interface between identified models and the haptic thread.
//!
//! A force law does not care whether its model is an ε-SVR, an RBF network or a closed-form
//! reference: it needs a scalar function of a few inputs that it can evaluate every tick
//! without allocating, and the box of inputs the model was trained on, so that it clamps
//! instead of extrapolating.

use crate::error::HapticsError;

/// The box of inputs a model was identified on: `lo[i] ≤ x[i] ≤ hi[i]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InputBox<const N: usize> {
    /// Lower corner.
    pub lo: [f64; N],
    /// Upper corner.
    pub hi: [f64; N],
}

impl<const N: usize> InputBox<N> {
    /// A box, checked: every bound finite, `lo ≤ hi`.
    pub fn new(lo: [f64; N], hi: [f64; N]) -> Result<Self, HapticsError> {
        for dimension in 0..N {
            let (l, h) = (lo[dimension], hi[dimension]);
            if !(l.is_finite() && h.is_finite() && l <= h) {
                return Err(HapticsError::BadInputBox {
                    dimension,
                    lo: l,
                    hi: h,
                });
            }
        }
        Ok(Self { lo, hi })
    }

    /// `x` moved into the box, and whether it had to move. A NaN input goes to the box's
    /// centre (and counts as moved).
    pub fn clamp(&self, x: &[f64; N]) -> ([f64; N], bool) {
        let mut out = *x;
        let mut moved = false;
        for i in 0..N {
            let v = x[i];
            let c = if v.is_nan() {
                0.5 * (self.lo[i] + self.hi[i])
            } else {
                v.clamp(self.lo[i], self.hi[i])
            };
            if c != v || v.is_nan() {
                moved = true;
            }
            out[i] = c;
        }
        (out, moved)
    }

    /// Whether `x` lies inside (bounds included).
    pub fn contains(&self, x: &[f64; N]) -> bool {
        (0..N).all(|i| x[i] >= self.lo[i] && x[i] <= self.hi[i])
    }
}

/// A scalar model of `N` inputs, evaluated on the haptic thread.
///
/// `eval` must not allocate, lock or do I/O, and should take microseconds: it runs once or a
/// few times per 1 ms tick. It may return anything (NaN, ±∞); the force laws treat a
/// non-finite value as zero force and flag it.
pub trait ScalarModel<const N: usize>: Send + Sync {
    /// The model's value at `x` (a point inside [`ScalarModel::input_box`]).
    fn eval(&self, x: &[f64; N]) -> f64;

    /// The inputs the model was identified on.
    fn input_box(&self) -> InputBox<N>;
}

impl<const N: usize, M: ScalarModel<N> + ?Sized> ScalarModel<N> for Box<M> {
    fn eval(&self, x: &[f64; N]) -> f64 {
        (**self).eval(x)
    }
    fn input_box(&self) -> InputBox<N> {
        (**self).input_box()
    }
}

impl<const N: usize, M: ScalarModel<N> + ?Sized> ScalarModel<N> for std::sync::Arc<M> {
    fn eval(&self, x: &[f64; N]) -> f64 {
        (**self).eval(x)
    }
    fn input_box(&self) -> InputBox<N> {
        (**self).input_box()
    }
}

/// A model evaluated with its inputs clamped to its box.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Evaluation {
    /// The value; 0 when the model returned a non-finite number.
    pub value: f64,
    /// [`crate::safety::flag`] bits: `MODEL_INPUT_CLAMPED`, `MODEL_OUTPUT_NOT_FINITE`.
    pub flags: u32,
}

/// Evaluates `model` at `x` clamped into its training box; flags the clamp and a non-finite
/// output (which becomes 0).
pub fn eval_clamped<const N: usize, M: ScalarModel<N> + ?Sized>(model: &M, x: &[f64; N]) -> Evaluation {
    use crate::safety::flag;
    let (inside, moved) = model.input_box().clamp(x);
    let raw = model.eval(&inside);
    let mut flags = if moved { flag::MODEL_INPUT_CLAMPED } else { 0 };
    let value = if raw.is_finite() {
        raw
    } else {
        flags |= flag::MODEL_OUTPUT_NOT_FINITE;
        0.0
    };
    Evaluation { value, flags }
}

/// A model made of a closure and a box: reference laws, test doubles.
#[derive(Clone, Copy)]
pub struct FnModel<F, const N: usize> {
    f: F,
    input_box: InputBox<N>,
}

impl<F, const N: usize> FnModel<F, N>
where
    F: Fn(&[f64; N]) -> f64 + Send + Sync,
{
    /// Wraps `f`, identified on `input_box`.
    pub fn new(input_box: InputBox<N>, f: F) -> Self {
        Self { f, input_box }
    }
}

impl<F, const N: usize> std::fmt::Debug for FnModel<F, N> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("FnModel")
            .field("input_box", &self.input_box)
            .finish_non_exhaustive()
    }
}

impl<F, const N: usize> ScalarModel<N> for FnModel<F, N>
where
    F: Fn(&[f64; N]) -> f64 + Send + Sync,
{
    fn eval(&self, x: &[f64; N]) -> f64 {
        (self.f)(x)
    }
    fn input_box(&self) -> InputBox<N> {
        self.input_box
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::safety::flag;

    #[test]
    fn boxes_are_checked_and_clamp_with_a_flag() {
        assert!(InputBox::new([0.0, 1.0], [1.0, 0.0]).is_err());
        assert!(InputBox::new([f64::NAN], [1.0]).is_err());
        let b = InputBox::new([0.0, -1.0], [1.0, 1.0]).unwrap();
        assert_eq!(b.clamp(&[0.5, 0.0]), ([0.5, 0.0], false));
        assert_eq!(b.clamp(&[2.0, -5.0]), ([1.0, -1.0], true));
        assert_eq!(b.clamp(&[f64::NAN, 0.0]), ([0.5, 0.0], true));
        assert!(b.contains(&[1.0, 1.0]) && !b.contains(&[1.1, 0.0]));
    }

    #[test]
    fn evaluation_clamps_inputs_and_zeroes_non_finite_outputs() {
        let b = InputBox::new([0.0], [1.0]).unwrap();
        let square = FnModel::new(b, |x: &[f64; 1]| x[0] * x[0]);
        assert_eq!(eval_clamped(&square, &[0.5]).value, 0.25);
        // Outside the box: the value at the edge, not the extrapolation 100.
        let e = eval_clamped(&square, &[10.0]);
        assert_eq!((e.value, e.flags), (1.0, flag::MODEL_INPUT_CLAMPED));
        let broken = FnModel::new(b, |_: &[f64; 1]| f64::NAN);
        let e = eval_clamped(&broken, &[0.5]);
        assert_eq!((e.value, e.flags), (0.0, flag::MODEL_OUTPUT_NOT_FINITE));
    }
}
