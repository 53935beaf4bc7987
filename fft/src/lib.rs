//! Real-to-complex FFT plans, generated once for the workspace.
//!
//! realfft's planner is generic over the float type, so its SIMD butterflies are compiled in
//! whichever crate calls `RealFftPlanner::<f64>::new()`, and again for that crate's unit tests:
//! 75 % of `sim`'s generated code and 31 % of `recognize`'s (measured with `cargo llvm-lines`).
//! Planning through the two functions here generates that code in this crate only; callers
//! hold a plan as the trait object realfft returns anyway, so nothing is slower.

use std::sync::Arc;

use realfft::RealFftPlanner;

pub use realfft::num_complex::Complex;
pub use realfft::{ComplexToReal, FftError, RealToComplex};

/// A plan for the forward transform of `len` real samples into `len / 2 + 1` complex bins.
pub fn forward_plan(len: usize) -> Arc<dyn RealToComplex<f64>> {
    RealFftPlanner::<f64>::new().plan_fft_forward(len)
}

/// A plan for the inverse transform of `len / 2 + 1` complex bins into `len` real samples,
/// unnormalized (the forward then the inverse multiply by `len`).
pub fn inverse_plan(len: usize) -> Arc<dyn ComplexToReal<f64>> {
    RealFftPlanner::<f64>::new().plan_fft_inverse(len)
}
