//! Prediction fast path for the 1 kHz haptic loop.
//!
//! The loop evaluates an identified model once per tick next to the device I/O, the observers
//! and the controller, so a model must cost a small fraction of the 1 ms period and must never
//! allocate. [`SvrModel::predict`] is the general path: it scales the input, walks row-major
//! support vectors through a `match` on the kernel per term and calls libm's `exp` ~100 times.
//! The evaluators here are built once from an [`SvrModel`] and its [`InputScaling`]:
//!
//! * the input dimension `D` is a const generic, so there is no slice length to check and the
//!   distance loop unrolls;
//! * the scaling (and for RBF also `√γ`) is folded into the stored support vectors, so an
//!   evaluation does `D` multiply-adds on the input and no division;
//! * support vectors are stored structure-of-arrays in blocks of [`LANES`]: [`FastSvr`] works
//!   on eight `f32` lanes at once in explicit SIMD (`wide::f32x8`: two SSE2 registers on the
//!   baseline x86-64 target, one AVX register where the build enables AVX), evaluating the
//!   exponential with [`fast_exp2`]'s branch-free range-reduced polynomial instead of a libm
//!   call per support vector;
//! * [`ExactSvr`] keeps the same folding and layout in `f64` with libm's `exp`: the reference
//!   the accuracy cost is measured against, and the choice where `f32` is not enough.
//!
//! Measured with `cargo bench -p svm --bench predict` (RBF, 100 support vectors, 2-D): the
//! `f32` path is several times faster than `SvrModel::predict` (see the benchmark's report).
//!
//! # Accuracy of [`FastSvr`]
//!
//! Support vectors are stored relative to their mean (in folded units), so the `f32` distance
//! is formed from small numbers whatever the raw input's offset. The error of one evaluation is
//! bounded by [`FastSvr::abs_error_bound`], `Σ|βᵢ| · ε_K` with `ε_K` a first-order bound on the
//! error of one `βᵢ·K` term (coefficient rounding, [`FAST_EXP2_MAX_REL_ERROR`], the `f32`
//! distance's rounding propagated through `2^{−r}`, and the per-lane `f32` accumulation). It is
//! relative to `Σ|βᵢ|`, not to `f(x)`: a model whose coefficients cancel (large C) loses
//! correspondingly more. The tests measure the actual error on a grid against [`ExactSvr`]
//! and `SvrModel::predict` and check it stays under the bound.

use std::ops::MulAssign;

use wide::bytemuck::cast;
use wide::{f32x8, u32x8};

use super::error::SvmError;
use super::kernel::Kernel;
use super::model::{InputScaling, SvrModel};

/// Support vectors per block: one AVX register of `f32` (two SSE registers, whose independent
/// dependency chains the CPU overlaps).
pub const LANES: usize = 8;

/// Largest relative error of [`fast_exp2`] over `[−126, 127]`, measured against `f64` `exp2`
/// by the test `fast_exp2_relative_error_is_bounded` (measured 1.0e-7; `f32` rounding alone is
/// 6e-8).
pub const FAST_EXP2_MAX_REL_ERROR: f64 = 1.2e-7;

/// Unit roundoff of `f32`.
const U32: f64 = f32::EPSILON as f64 / 2.0;

/// `2^t` in `f32`, branch-free and without a libm call, so a loop over it vectorises.
///
/// Range reduction `t = k + r` with `k = round(t)`, `r ∈ [−½, ½]` (the rounding uses the
/// `1.5·2²³` trick, which needs no SSE4.1 `round` instruction), then `2^r` by a degree-6
/// polynomial fitted to minimise the relative error on `[−½, ½]` (weighted least squares
/// iterated to the minimax solution, coefficients rounded to `f32`; its `f64` error is 1.9e-9,
/// so the `f32` Horner evaluation's rounding dominates), and `2^k` built directly in the
/// exponent bits. The relative error is at most [`FAST_EXP2_MAX_REL_ERROR`] for
/// `t ∈ [−126, 127]`; outside, `t` is clamped (below −126 the result is `2^−126 ≈ 1.2e−38`
/// instead of a smaller number — an absolute error below `1.2e−38`). NaN propagates.
#[inline(always)]
pub fn fast_exp2(t: f32) -> f32 {
    const MAGIC: f32 = 12_582_912.0; // 1.5 · 2²³: adding it rounds to an integer.
    const C: [f32; 7] = EXP2_POLY;
    let t = if t < -126.0 { -126.0 } else { t };
    let t = if t > 127.0 { 127.0 } else { t };
    let shifted = t + MAGIC;
    let k = shifted - MAGIC;
    let r = t - k;
    let p = ((((((C[6] * r + C[5]) * r + C[4]) * r + C[3]) * r + C[2]) * r + C[1]) * r) + C[0];
    // The low bits of `shifted` hold k in two's complement; k + 127 ∈ [1, 254] is the biased
    // exponent of 2^k.
    let scale = f32::from_bits(shifted.to_bits().wrapping_add(127) << 23);
    p * scale
}

/// [`fast_exp2`] on eight lanes whose arguments are ≤ 0 (so only the lower clamp is needed),
/// in explicit SIMD: one instruction per stage on AVX, two on SSE2.
#[inline(always)]
fn exp2_nonpositive_x8(t: f32x8) -> f32x8 {
    let magic = f32x8::splat(12_582_912.0);
    let t = t.fast_max(f32x8::splat(-126.0));
    let shifted = t + magic;
    let r = t - (shifted - magic);
    let mut p = f32x8::splat(EXP2_POLY[6]);
    for &c in EXP2_POLY[..6].iter().rev() {
        p = p * r + f32x8::splat(c);
    }
    let bits: u32x8 = cast(shifted);
    let scale: f32x8 = cast((bits + u32x8::splat(127)) << 23);
    p * scale
}

/// Coefficients of `2^r` on `[−½, ½]`, lowest degree first (see [`fast_exp2`]).
const EXP2_POLY: [f32; 7] = [
    1.0,
    // The fitted coefficient rounds to the same f32 as ln 2.
    std::f32::consts::LN_2,
    0.240_226_46,
    0.055_503_286,
    0.009_618_489,
    0.001_339_993_4,
    0.000_153_458_18,
];

/// One block of [`LANES`] support vectors, structure-of-arrays (the `f64` layout of
/// [`ExactSvr`], and the staging layout [`FastSvr`]'s SIMD blocks are built from).
#[derive(Debug, Clone, Copy)]
#[repr(C, align(32))]
struct Block<T, const D: usize> {
    /// Folded coordinates: `c[k][lane]`.
    c: [[T; LANES]; D],
    /// Coefficients (0 in padding lanes).
    beta: [T; LANES],
}

/// What the kernel expansion reduces to once folded.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Folded {
    /// `Σ βᵢ 2^{−‖u − cᵢ‖²}` (f32) or `Σ βᵢ e^{−‖u − cᵢ‖²}` (f64), with
    /// `u = a ⊙ x − shift`.
    Rbf,
    /// `Σ βᵢ (u·cᵢ + coef0)^degree` with `u = a ⊙ x − shift` the scaled input and `cᵢ = γ sᵢ`.
    Polynomial { coef0: f64, degree: u32 },
    /// `w·x + b` with the scaling folded into `w` and `b`: no support vectors needed.
    Linear,
}

/// The model folded in `f64`: `u = a ⊙ x − shift`, then the kernel against each `cᵢ`.
struct Folding<const D: usize> {
    kind: Folded,
    a: [f64; D],
    shift: [f64; D],
    /// Row-major folded support vectors.
    c: Vec<[f64; D]>,
    beta: Vec<f64>,
    bias: f64,
}

fn bad(what: String, value: f64, reason: &'static str) -> SvmError {
    SvmError::BadValue { what, value, reason }
}

/// Validates `model` and `scaling` for dimension `D` and folds them. `rbf_base_e` is false for
/// the `f32` path, which evaluates `2^{−r}` and so folds `log₂e` into the coordinates.
fn fold<const D: usize>(
    model: &SvrModel,
    scaling: &InputScaling,
    rbf_base_e: bool,
) -> Result<Folding<D>, SvmError> {
    for (what, found) in [
        ("model", model.dim),
        ("scaling.offset", scaling.offset.len()),
        ("scaling.scale", scaling.scale.len()),
    ] {
        if found != D {
            return Err(SvmError::Dimension {
                what,
                found,
                expected: D,
            });
        }
    }
    if model.support_vectors.len() != model.n_sv() * D {
        return Err(SvmError::Shape {
            array: "support-vector",
            values: model.support_vectors.len(),
            rows_of: "coefficients",
            rows: model.n_sv(),
            dim: D,
        });
    }
    let mut inv_scale = [0.0; D];
    for (k, inv) in inv_scale.iter_mut().enumerate() {
        let (o, s) = (scaling.offset[k], scaling.scale[k]);
        if !o.is_finite() {
            return Err(bad(format!("scaling.offset[{k}]"), o, "not finite"));
        }
        if !(s.is_finite() && s != 0.0) {
            return Err(bad(
                format!("scaling.scale[{k}]"),
                s,
                "must be finite and non-zero",
            ));
        }
        *inv = 1.0 / s;
    }
    if !model.bias.is_finite() {
        return Err(bad("bias".to_owned(), model.bias, "not finite"));
    }
    if let Some(i) = model.coefficients.iter().position(|b| !b.is_finite()) {
        return Err(bad(
            format!("coefficient {i}"),
            model.coefficients[i],
            "not finite",
        ));
    }
    if let Some(i) = model.support_vectors.iter().position(|v| !v.is_finite()) {
        return Err(bad(
            format!("support vector {} element {}", i / D, i % D),
            model.support_vectors[i],
            "not finite",
        ));
    }
    let rows = || model.support_vectors.chunks_exact(D);

    match model.kernel {
        Kernel::Linear => {
            let w = model.linear_weights().unwrap_or_default();
            if w.len() != D {
                return Err(SvmError::Dimension {
                    what: "model weights",
                    found: w.len(),
                    expected: D,
                });
            }
            // f(x) = Σ wₖ (xₖ − oₖ)/sₖ + b = Σ (wₖ/sₖ) xₖ + (b − Σ wₖ oₖ/sₖ).
            let a: [f64; D] = std::array::from_fn(|k| w[k] * inv_scale[k]);
            let bias = model.bias - (0..D).map(|k| a[k] * scaling.offset[k]).sum::<f64>();
            if let Some(k) = (0..D).find(|&k| !a[k].is_finite()) {
                return Err(bad(format!("folded weight {k}"), a[k], "overflows"));
            }
            Ok(Folding {
                kind: Folded::Linear,
                a,
                shift: [0.0; D],
                c: Vec::new(),
                beta: Vec::new(),
                bias,
            })
        }
        Kernel::Rbf { gamma } => {
            if !(gamma.is_finite() && gamma > 0.0) {
                return Err(bad("gamma".to_owned(), gamma, "must be finite and positive"));
            }
            // γ‖(x − o)/s − sv‖² = ‖g(x − o)/s − g sv‖² with g = √γ (times √log₂e for 2^{−r}).
            let g = if rbf_base_e {
                gamma.sqrt()
            } else {
                (gamma * std::f64::consts::LOG2_E).sqrt()
            };
            let c: Vec<[f64; D]> = rows().map(|sv| std::array::from_fn(|k| g * sv[k])).collect();
            // Centre the folded support vectors so f32 differences are formed from small numbers.
            let n = c.len().max(1) as f64;
            let mean: [f64; D] = std::array::from_fn(|k| c.iter().map(|ci| ci[k]).sum::<f64>() / n);
            let c = c
                .iter()
                .map(|ci| std::array::from_fn(|k| ci[k] - mean[k]))
                .collect();
            let a: [f64; D] = std::array::from_fn(|k| g * inv_scale[k]);
            let shift: [f64; D] = std::array::from_fn(|k| a[k] * scaling.offset[k] + mean[k]);
            Ok(Folding {
                kind: Folded::Rbf,
                a,
                shift,
                c,
                beta: model.coefficients.clone(),
                bias: model.bias,
            })
        }
        Kernel::Polynomial { gamma, coef0, degree } => {
            if !gamma.is_finite() {
                return Err(bad("gamma".to_owned(), gamma, "not finite"));
            }
            if !coef0.is_finite() {
                return Err(bad("coef0".to_owned(), coef0, "not finite"));
            }
            let c = rows().map(|sv| std::array::from_fn(|k| gamma * sv[k])).collect();
            let a = inv_scale;
            let shift: [f64; D] = std::array::from_fn(|k| inv_scale[k] * scaling.offset[k]);
            Ok(Folding {
                kind: Folded::Polynomial { coef0, degree },
                a,
                shift,
                c,
                beta: model.coefficients.clone(),
                bias: model.bias,
            })
        }
    }
}

/// Packs folded support vectors into blocks of [`LANES`] (padding lanes have β = 0).
fn blocks<T: Copy + Default, const D: usize>(
    c: &[[f64; D]],
    beta: &[f64],
    convert: impl Fn(f64) -> T,
) -> Vec<Block<T, D>> {
    c.chunks(LANES)
        .zip(beta.chunks(LANES))
        .map(|(cs, bs)| {
            let mut block = Block {
                c: [[T::default(); LANES]; D],
                beta: [T::default(); LANES],
            };
            for (lane, (ci, &bi)) in cs.iter().zip(bs).enumerate() {
                for (column, &v) in block.c.iter_mut().zip(ci) {
                    column[lane] = convert(v);
                }
                block.beta[lane] = convert(bi);
            }
            block
        })
        .collect()
}

/// `base^degree` by squaring (libsvm's `powi`): `⌈log₂ degree⌉` rounds whatever the base, so
/// every lane of a SIMD base takes the same path. `one` is the multiplicative identity.
#[inline(always)]
fn powi_by_squaring<T: Copy + MulAssign>(mut base: T, one: T, degree: u32) -> T {
    let mut result = one;
    let mut e = degree;
    while e > 0 {
        if e & 1 == 1 {
            result *= base;
        }
        e >>= 1;
        if e > 0 {
            base *= base;
        }
    }
    result
}

/// Fixed-dimension, allocation-free `f32` evaluator of an ε-SVR, for the haptic loop.
///
/// Accuracy: see the module documentation and [`FastSvr::abs_error_bound`]. Linear models are
/// folded to `w·x + b` and evaluated exactly in `f64`.
#[derive(Debug, Clone)]
pub struct FastSvr<const D: usize> {
    kind: Folded,
    a: [f64; D],
    shift: [f64; D],
    blocks: Vec<SimdBlock<D>>,
    bias: f64,
    n_sv: usize,
    abs_error_bound: f64,
}

impl<const D: usize> FastSvr<D> {
    /// Builds the evaluator of `model` for raw inputs that `scaling` maps into the model's
    /// training space.
    pub fn new(model: &SvrModel, scaling: &InputScaling) -> Result<Self, SvmError> {
        let folding = fold::<D>(model, scaling, false)?;
        let mut max_c: f64 = 0.0;
        for (i, ci) in folding.c.iter().enumerate() {
            for (k, &v) in ci.iter().enumerate() {
                if !((v as f32).is_finite()) {
                    return Err(bad(
                        format!("folded support vector {i} element {k}"),
                        v,
                        "overflows f32",
                    ));
                }
                max_c = max_c.max(v.abs());
            }
        }
        if let Some(i) = folding.beta.iter().position(|b| !(*b as f32).is_finite()) {
            return Err(bad(format!("coefficient {i}"), folding.beta[i], "overflows f32"));
        }
        let blocks: Vec<SimdBlock<D>> = blocks(&folding.c, &folding.beta, |v| v as f32)
            .into_iter()
            .map(|b| SimdBlock {
                c: b.c.map(f32x8::new),
                beta: f32x8::new(b.beta),
            })
            .collect();
        let sum_abs_beta: f64 = folding.beta.iter().map(|b| b.abs()).sum();
        let abs_error_bound = match folding.kind {
            Folded::Linear => 0.0,
            Folded::Rbf => sum_abs_beta * rbf_term_error(max_c, D, blocks.len()),
            // (u·c + coef0)^d has no bounded kernel value; there is no useful a-priori bound.
            Folded::Polynomial { .. } => f64::INFINITY,
        };
        Ok(Self {
            kind: folding.kind,
            a: folding.a,
            shift: folding.shift,
            blocks,
            bias: folding.bias,
            n_sv: folding.beta.len(),
            abs_error_bound,
        })
    }

    /// Number of support vectors (0 for a linear model folded to `w·x + b`).
    pub fn n_sv(&self) -> usize {
        self.n_sv
    }

    /// A bound on `|eval(x) − f(x)|` for every input `x`, in the target's unit (first-order in
    /// the `f32` unit roundoff; 0 for linear models; infinite for polynomial kernels, whose
    /// kernel values are unbounded). See the module documentation.
    pub fn abs_error_bound(&self) -> f64 {
        self.abs_error_bound
    }

    /// `f(x)` for one raw input. A NaN input gives NaN (the kernel's clamp would otherwise
    /// turn it into a plausible force).
    #[inline]
    pub fn eval(&self, x: &[f64; D]) -> f64 {
        let u: [f64; D] = std::array::from_fn(|k| self.a[k] * x[k] - self.shift[k]);
        if u.iter().any(|v| v.is_nan()) {
            return f64::NAN;
        }
        match self.kind {
            Folded::Linear => self.bias + u.iter().sum::<f64>(),
            Folded::Rbf => self.bias + self.rbf(&u.map(|v| v as f32)),
            Folded::Polynomial { coef0, degree } => {
                self.bias + self.polynomial(&u.map(|v| v as f32), coef0 as f32, degree)
            }
        }
    }

    #[inline]
    fn rbf(&self, u: &[f32; D]) -> f64 {
        let u = u.map(f32x8::splat);
        let mut acc = f32x8::ZERO;
        for block in &self.blocks {
            let mut t = f32x8::ZERO;
            for (&uk, &ck) in u.iter().zip(&block.c) {
                let d = uk - ck;
                t -= d * d;
            }
            acc += block.beta * exp2_nonpositive_x8(t);
        }
        acc.to_array().iter().map(|&v| f64::from(v)).sum()
    }

    #[inline]
    fn polynomial(&self, u: &[f32; D], coef0: f32, degree: u32) -> f64 {
        let u = u.map(f32x8::splat);
        let mut acc = f32x8::ZERO;
        for block in &self.blocks {
            let mut t = f32x8::splat(coef0);
            for (&uk, &ck) in u.iter().zip(&block.c) {
                t += uk * ck;
            }
            acc += block.beta * powi_by_squaring(t, f32x8::ONE, degree);
        }
        acc.to_array().iter().map(|&v| f64::from(v)).sum()
    }
}

/// Eight `f32` lanes of [`LANES`] support vectors, structure-of-arrays, for [`FastSvr`].
#[derive(Debug, Clone, Copy)]
struct SimdBlock<const D: usize> {
    c: [f32x8; D],
    beta: f32x8,
}

/// First-order bound on the error of one `β·K` term of the `f32` RBF path, per unit `|β|`.
///
/// With `r = Σₖ dₖ²`, `dₖ = uₖ − cₖ` and `K = 2^{−r}`: rounding `u`, `c` and the difference
/// perturbs `dₖ` by at most `u₃₂(|uₖ| + |cₖ| + |dₖ|) ≤ 2u₃₂(C + |dₖ|)` (`|uₖ| ≤ |cₖ| + |dₖ|`,
/// `C = max|c|`); squaring and summing add `(D + 1)u₃₂ r`. So `|Δr| ≤ u₃₂(4C√(D r) + (D + 5) r)`,
/// and `K|Δr| ln 2` is largest where `√r 2^{−r}` (≤ 0.5152) and `r 2^{−r}` (≤ 0.5307) peak.
/// Add the exponential's own error, the rounding of β and of the product, and the worst-case
/// growth of a lane's running sum over `blocks` additions; then a 10 % margin for second-order
/// terms.
fn rbf_term_error(max_c: f64, dim: usize, blocks: usize) -> f64 {
    let d = dim as f64;
    let distance = std::f64::consts::LN_2 * (4.0 * max_c * d.sqrt() * 0.5152 + (d + 5.0) * 0.5307);
    1.1 * (FAST_EXP2_MAX_REL_ERROR + U32 * (2.0 + blocks as f64 + distance))
}

/// The same layout and folding as [`FastSvr`] in `f64` with libm's `exp`: the reference for
/// the accuracy [`FastSvr`] gives up, and what to use where `f32` is not enough.
#[derive(Debug, Clone)]
pub struct ExactSvr<const D: usize> {
    kind: Folded,
    a: [f64; D],
    shift: [f64; D],
    blocks: Vec<Block<f64, D>>,
    bias: f64,
}

impl<const D: usize> ExactSvr<D> {
    /// Builds the evaluator of `model` for raw inputs that `scaling` maps into the model's
    /// training space.
    pub fn new(model: &SvrModel, scaling: &InputScaling) -> Result<Self, SvmError> {
        let folding = fold::<D>(model, scaling, true)?;
        Ok(Self {
            kind: folding.kind,
            a: folding.a,
            shift: folding.shift,
            blocks: blocks(&folding.c, &folding.beta, |v| v),
            bias: folding.bias,
        })
    }

    /// `f(x)` for one raw input.
    #[inline]
    pub fn eval(&self, x: &[f64; D]) -> f64 {
        let u: [f64; D] = std::array::from_fn(|k| self.a[k] * x[k] - self.shift[k]);
        match self.kind {
            Folded::Linear => self.bias + u.iter().sum::<f64>(),
            Folded::Rbf => {
                let mut acc = [0.0f64; LANES];
                for block in &self.blocks {
                    let mut r = [0.0f64; LANES];
                    for (&uk, column) in u.iter().zip(&block.c) {
                        for (rl, &cl) in r.iter_mut().zip(column) {
                            let d = uk - cl;
                            *rl += d * d;
                        }
                    }
                    for ((a, &b), &rl) in acc.iter_mut().zip(&block.beta).zip(&r) {
                        *a += b * (-rl).exp();
                    }
                }
                self.bias + acc.iter().sum::<f64>()
            }
            Folded::Polynomial { coef0, degree } => {
                let mut acc = [0.0f64; LANES];
                for block in &self.blocks {
                    let mut t = [coef0; LANES];
                    for (&uk, column) in u.iter().zip(&block.c) {
                        for (tl, &cl) in t.iter_mut().zip(column) {
                            *tl += uk * cl;
                        }
                    }
                    for ((a, &b), &tl) in acc.iter_mut().zip(&block.beta).zip(&t) {
                        *a += b * powi_by_squaring(tl, 1.0, degree);
                    }
                }
                self.bias + acc.iter().sum::<f64>()
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::sample::{needle_like_model as needle_like, wiggle};

    fn plain(model: &SvrModel, scaling: &InputScaling, x: &[f64]) -> f64 {
        model.predict(&scaling.apply(x))
    }

    /// Inputs over the training box and 20 % beyond it on every side.
    fn grid(n: usize) -> impl Iterator<Item = [f64; 2]> {
        (0..n * n).map(move |i| {
            let a = (i % n) as f64 / (n - 1) as f64 * 1.4 - 0.2;
            let b = (i / n) as f64 / (n - 1) as f64 * 1.4 - 0.2;
            [0.03 * a, -0.01 + 0.02 * b]
        })
    }

    #[test]
    fn fast_exp2_relative_error_is_bounded() {
        let mut worst: f64 = 0.0;
        let n = 2_000_000;
        for i in 0..=n {
            let t = (-126.0 + 253.0 * i as f64 / n as f64) as f32;
            let exact = f64::from(t).exp2();
            let rel = (f64::from(fast_exp2(t)) / exact - 1.0).abs();
            worst = worst.max(rel);
        }
        // Dense near 0, where the kernel values that matter live.
        for i in 0..=n {
            let t = -(8.0 * i as f64 / n as f64) as f32;
            worst = worst.max((f64::from(fast_exp2(t)) / f64::from(t).exp2() - 1.0).abs());
        }
        eprintln!("fast_exp2 max relative error {worst:.3e}");
        assert!(worst <= FAST_EXP2_MAX_REL_ERROR, "{worst:e}");
        // It is not trivially loose either: the polynomial is within 2× of f32 rounding.
        assert!(worst > 3e-8, "{worst:e}");
        assert_eq!(fast_exp2(0.0), 1.0);
        assert_eq!(fast_exp2(-1.0), 0.5);
        assert_eq!(fast_exp2(-300.0), f32::from_bits(1 << 23));
        assert!(fast_exp2(f32::NAN).is_nan());
        // The eight-lane kernel form agrees with the scalar one bit for bit.
        let t: [f32; LANES] = std::array::from_fn(|l| -0.37 * l as f32 - 0.011);
        assert_eq!(exp2_nonpositive_x8(f32x8::new(t)).to_array(), t.map(fast_exp2));
        assert_eq!(
            exp2_nonpositive_x8(f32x8::splat(-1e9)).to_array(),
            [fast_exp2(-126.0); LANES]
        );
    }

    #[test]
    fn nan_inputs_give_nan_and_infinite_inputs_the_bias() {
        let (model, scaling) = needle_like(10.0, 100.0);
        let fast = FastSvr::<2>::new(&model, &scaling).unwrap();
        let exact = ExactSvr::<2>::new(&model, &scaling).unwrap();
        assert!(fast.eval(&[f64::NAN, 0.0]).is_nan());
        assert!(exact.eval(&[0.01, f64::NAN]).is_nan());
        // Infinitely far from every support vector, only the bias is left.
        assert_eq!(fast.eval(&[f64::INFINITY, 0.0]), model.bias);
    }

    #[test]
    fn exact_path_equals_the_plain_prediction() {
        let (model, scaling) = needle_like(10.0, 100.0);
        let exact = ExactSvr::<2>::new(&model, &scaling).unwrap();
        let scale: f64 = model.coefficients.iter().map(|b| b.abs()).sum();
        let mut worst: f64 = 0.0;
        for x in grid(60) {
            worst = worst.max((exact.eval(&x) - plain(&model, &scaling, &x)).abs());
        }
        // Folding reorders a handful of roundings per term.
        assert!(worst <= 1e-14 * scale, "{worst:e} (Σ|β| = {scale})");
    }

    #[test]
    fn f32_path_error_is_within_its_bound_and_small() {
        for (gamma, c_max) in [(1.0, 10.0), (10.0, 100.0), (50.0, 1000.0)] {
            let (model, scaling) = needle_like(gamma, c_max);
            let fast = FastSvr::<2>::new(&model, &scaling).unwrap();
            let exact = ExactSvr::<2>::new(&model, &scaling).unwrap();
            let sum_abs_beta: f64 = model.coefficients.iter().map(|b| b.abs()).sum();
            let (mut worst_abs, mut worst_rel_to_range): (f64, f64) = (0.0, 0.0);
            let values: Vec<(f64, f64)> = grid(200).map(|x| (fast.eval(&x), exact.eval(&x))).collect();
            let range = values.iter().map(|v| v.1).fold(f64::NEG_INFINITY, f64::max)
                - values.iter().map(|v| v.1).fold(f64::INFINITY, f64::min);
            for (f, e) in values {
                worst_abs = worst_abs.max((f - e).abs());
                worst_rel_to_range = worst_rel_to_range.max((f - e).abs() / range);
            }
            let bound = fast.abs_error_bound();
            eprintln!(
                "γ={gamma} C={c_max}: max |f32 − f64| = {worst_abs:.3e} ({:.2e} of Σ|β| = {sum_abs_beta:.1}, \
                 {worst_rel_to_range:.2e} of the output range {range:.3}); bound {bound:.3e}",
                worst_abs / sum_abs_beta
            );
            assert!(worst_abs <= bound, "γ={gamma}: {worst_abs:e} > bound {bound:e}");
            // The bound itself is tight enough to be useful: a few millionths of Σ|β|.
            assert!(bound <= 5e-6 * sum_abs_beta, "bound {bound:e}");
        }
    }

    #[test]
    fn large_raw_offsets_do_not_cost_f32_precision() {
        // Inputs around 1e6 (an unscaled encoder count, say): centring keeps the f32 distances
        // small, so the error stays at the level of the scaled case.
        let (model, _) = needle_like(10.0, 100.0);
        let scaling = InputScaling {
            offset: vec![1e6, -1e6],
            scale: vec![0.03, 0.02],
        };
        let fast = FastSvr::<2>::new(&model, &scaling).unwrap();
        let exact = ExactSvr::<2>::new(&model, &scaling).unwrap();
        let worst = grid(50)
            .map(|x| [x[0] + 1e6, x[1] - 1e6 + 0.01])
            .map(|x| (fast.eval(&x) - exact.eval(&x)).abs())
            .fold(0.0, f64::max);
        assert!(
            worst <= fast.abs_error_bound(),
            "{worst:e} > {:e}",
            fast.abs_error_bound()
        );
    }

    #[test]
    fn polynomial_and_linear_kernels_fold_correctly() {
        let scaling = InputScaling {
            offset: vec![0.5, -2.0, 10.0],
            scale: vec![2.0, 0.5, 4.0],
        };
        let poly = SvrModel {
            kernel: Kernel::Polynomial {
                gamma: 0.3,
                coef0: 1.5,
                degree: 3,
            },
            dim: 3,
            support_vectors: (0..30).map(|i| wiggle(i, 0.2)).collect(),
            coefficients: (0..10).map(|i| wiggle(i, 0.9)).collect(),
            bias: -0.25,
            weights: None,
        };
        let exact = ExactSvr::<3>::new(&poly, &scaling).unwrap();
        let fast = FastSvr::<3>::new(&poly, &scaling).unwrap();
        for i in 0..50 {
            let x = [
                1.0 + wiggle(3 * i, 0.1),
                -2.0 + wiggle(3 * i + 1, 0.1),
                10.0 + 3.0 * wiggle(3 * i + 2, 0.1),
            ];
            let reference = plain(&poly, &scaling, &x);
            assert!(
                (exact.eval(&x) - reference).abs() < 1e-13,
                "{}",
                exact.eval(&x) - reference
            );
            assert!(
                (fast.eval(&x) - reference).abs() < 1e-5,
                "{}",
                fast.eval(&x) - reference
            );
        }
        assert!(fast.abs_error_bound().is_infinite());

        let linear = SvrModel {
            kernel: Kernel::Linear,
            ..poly.clone()
        };
        let fast = FastSvr::<3>::new(&linear, &scaling).unwrap();
        assert_eq!(fast.n_sv(), 0);
        assert_eq!(fast.abs_error_bound(), 0.0);
        let x = [0.3, 1.7, -4.0];
        assert!((fast.eval(&x) - plain(&linear, &scaling, &x)).abs() < 1e-14);
        // Primal weights win over the support-vector sum, as in SvrModel::predict.
        let primal = SvrModel {
            weights: Some(vec![1.0, -2.0, 0.5]),
            ..linear
        };
        let fast = FastSvr::<3>::new(&primal, &scaling).unwrap();
        assert!((fast.eval(&x) - plain(&primal, &scaling, &x)).abs() < 1e-14);
    }

    #[test]
    fn padding_and_empty_models_contribute_nothing() {
        for n in [0, 1, 7, 8, 9, 17] {
            let model = SvrModel {
                kernel: Kernel::Rbf { gamma: 2.0 },
                dim: 1,
                support_vectors: (0..n).map(|i| wiggle(i, 0.4)).collect(),
                coefficients: (0..n).map(|i| wiggle(i, 0.8)).collect(),
                bias: 1.5,
                weights: None,
            };
            let scaling = InputScaling::identity(1);
            let exact = ExactSvr::<1>::new(&model, &scaling).unwrap();
            let fast = FastSvr::<1>::new(&model, &scaling).unwrap();
            for x in [-2.0, 0.0, 0.3, 5.0] {
                let reference = model.predict(&[x]);
                assert!((exact.eval(&[x]) - reference).abs() < 1e-14, "n={n}");
                assert!(
                    (fast.eval(&[x]) - reference).abs() <= fast.abs_error_bound().max(1e-15),
                    "n={n}"
                );
            }
            assert_eq!(fast.n_sv(), n);
        }
    }

    #[test]
    fn unusable_models_are_typed_errors() {
        let (model, scaling) = needle_like(10.0, 1.0);
        assert_eq!(
            FastSvr::<3>::new(&model, &scaling).unwrap_err(),
            SvmError::Dimension {
                what: "model",
                found: 2,
                expected: 3
            }
        );
        let short = InputScaling {
            offset: vec![0.0],
            ..scaling.clone()
        };
        assert!(matches!(
            ExactSvr::<2>::new(&model, &short),
            Err(SvmError::Dimension {
                what: "scaling.offset",
                ..
            })
        ));
        let zero = InputScaling {
            scale: vec![0.03, 0.0],
            ..scaling.clone()
        };
        let err = FastSvr::<2>::new(&model, &zero).unwrap_err();
        assert!(err.to_string().contains("scaling.scale[1]"), "{err}");
        let mut nan = model.clone();
        nan.support_vectors[5] = f64::NAN;
        let err = FastSvr::<2>::new(&nan, &scaling).unwrap_err();
        assert!(err.to_string().contains("support vector 2 element 1"), "{err}");
        let mut huge = model.clone();
        huge.coefficients[0] = 1e300;
        assert!(matches!(
            FastSvr::<2>::new(&huge, &scaling),
            Err(SvmError::BadValue { .. })
        ));
        let mut ragged = model;
        ragged.support_vectors.pop();
        assert!(matches!(
            FastSvr::<2>::new(&ragged, &scaling),
            Err(SvmError::Shape { .. })
        ));
    }
}
