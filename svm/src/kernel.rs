//! Kernels of the ε-SVR.

use faer::Mat;
use serde::{Deserialize, Serialize};

/// A positive-definite kernel `K(a, b)`, with libsvm's parameterisation so models export to
/// libsvm unchanged.
///
/// Li & Bi write the Gaussian kernel as `exp(−‖a − b‖² / (2σ²))` (their Eq. 3): that is
/// [`Kernel::Rbf`] with `gamma = 1 / (2σ²)`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum Kernel {
    /// `a·b`.
    Linear,
    /// `exp(−γ‖a − b‖²)`.
    Rbf {
        /// γ > 0.
        gamma: f64,
    },
    /// `(γ a·b + coef0)^degree`.
    Polynomial {
        /// γ > 0.
        gamma: f64,
        /// Additive constant.
        coef0: f64,
        /// Degree ≥ 1.
        degree: u32,
    },
}

impl Kernel {
    /// `K(a, b)`; `a` and `b` have the same length.
    #[inline]
    pub fn eval(&self, a: &[f64], b: &[f64]) -> f64 {
        match *self {
            Self::Linear => dot(a, b),
            Self::Rbf { gamma } => {
                clear_upper_simd_state();
                (-gamma * squared_distance(a, b)).exp()
            }
            Self::Polynomial { gamma, coef0, degree } => powi(gamma * dot(a, b) + coef0, degree),
        }
    }

    /// Short name (`linear`, `rbf`, `polynomial`).
    pub fn name(&self) -> &'static str {
        match self {
            Self::Linear => "linear",
            Self::Rbf { .. } => "rbf",
            Self::Polynomial { .. } => "polynomial",
        }
    }
}

/// Clears the upper halves of the AVX registers before a call into the C math library.
///
/// The solvers' dense algebra (faer's AVX kernels) can return with those halves in use, and
/// this crate's own code is built for baseline x86-64 (SSE). A thread left in that state pays
/// a transition on every switch between SSE code and the math library's AVX `exp`: the
/// certificate's `Kβ` at n = 1,000 took 71 ms on two threads against 7.5 ms on one (AMD
/// EPYC), and 4 ms once cleared. `vzeroupper` costs about a cycle; the feature check is a
/// cached load.
#[inline]
fn clear_upper_simd_state() {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx") {
        // SAFETY: the CPU supports AVX, checked just above.
        unsafe { zero_upper() }
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
fn zero_upper() {
    std::arch::x86_64::_mm256_zeroupper();
}

/// Inputs from which a kernel's sum is kept in four partial sums ([`lane_sum`]); below, one
/// running sum. With 130 features a running sum made every kernel value wait on the latency of
/// each addition in turn, most of a C-SVC's fit; with 5 (Friedman #1's RBF ε-SVR) the partial
/// sums' setup made the fit 1.8× slower (2.8 s against 5.1 s at n = 10,000). Below it the sum
/// is the one it always was, so identification's models are unchanged to the bit.
const LANE_SUM_MIN: usize = 16;

/// `Σ term(aₖ, bₖ)` in four partial sums (term k into sum `k mod 4`, in increasing k), combined
/// as `(s₀ + s₁) + (s₂ + s₃)`; a running sum below [`LANE_SUM_MIN`] terms.
#[inline(always)]
pub(crate) fn lane_sum(a: &[f64], b: &[f64], term: impl Fn(f64, f64) -> f64) -> f64 {
    let n = a.len().min(b.len());
    let (a, b) = (&a[..n], &b[..n]);
    if n < LANE_SUM_MIN {
        return a.iter().zip(b).map(|(&x, &y)| term(x, y)).sum();
    }
    // −0 as the empty sum, as the running sum has it: −0 + x is x for every x.
    let mut lanes = [-0.0; 4];
    let (ca, cb) = (a.chunks_exact(4), b.chunks_exact(4));
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        for k in 0..4 {
            lanes[k] += term(x[k], y[k]);
        }
    }
    for (lane, (&x, &y)) in lanes.iter_mut().zip(ra.iter().zip(rb)) {
        *lane += term(x, y);
    }
    (lanes[0] + lanes[1]) + (lanes[2] + lanes[3])
}

/// `a · b`, in four partial sums from 16 terms on (a running sum below): the kernels' inner
/// product, shared with the other crates' inner products over feature vectors.
#[inline]
pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    lane_sum(a, b, |x, y| x * y)
}

#[inline]
pub(crate) fn squared_distance(a: &[f64], b: &[f64]) -> f64 {
    lane_sum(a, b, |x, y| (x - y) * (x - y))
}

/// Entries of a row [`RbfColumns`] sums in registers at once.
const BLOCK: usize = 16;

/// The samples of an RBF kernel laid out by feature (`dim × n`), from which whole rows are
/// computed in vector loops, [`BLOCK`] entries at a time summed over the features, where a row
/// sample by sample is a short loop per value. Only for inputs whose squared distance
/// [`Kernel::eval`] sums in one running sum (fewer than [`LANE_SUM_MIN`] features): the rows
/// have its squared distances to the bit, and its values within the two ulps by which the
/// vectorised [`crate::exp::exp`] may differ from the C library's (which `eval` keeps: one
/// call at a time, the library's table-driven `exp` is twice as fast).
#[derive(Debug, Clone)]
pub(crate) struct RbfColumns {
    gamma: f64,
    columns: Vec<f64>,
    n: usize,
}

impl RbfColumns {
    /// `x` (`n × dim`, row-major) by feature, when `kernel` is an RBF over fewer than
    /// [`LANE_SUM_MIN`] features; `None` otherwise.
    pub(crate) fn new(kernel: &Kernel, x: &[f64], dim: usize) -> Option<Self> {
        let n = x.len().checked_div(dim)?;
        Self::of(kernel, x, dim, 0..n)
    }

    /// As [`RbfColumns::new`], over the samples `samples` of `x` only, in their order: row
    /// entry `r` is then the kernel with `samples[r]`.
    pub(crate) fn of(
        kernel: &Kernel,
        x: &[f64],
        dim: usize,
        samples: impl ExactSizeIterator<Item = usize>,
    ) -> Option<Self> {
        let Kernel::Rbf { gamma } = *kernel else {
            return None;
        };
        if dim == 0 || dim >= LANE_SUM_MIN {
            return None;
        }
        let n = samples.len();
        let mut columns = vec![0.0; dim * n];
        for (r, i) in samples.enumerate() {
            for (k, &v) in x[i * dim..(i + 1) * dim].iter().enumerate() {
                columns[k * n + r] = v;
            }
        }
        Some(Self { gamma, columns, n })
    }

    /// `K(xi, x_r)` for `r` in `start..start + out.len()`, into `out`: [`Kernel::eval`]'s
    /// values to two ulps.
    pub(crate) fn row(&self, xi: &[f64], start: usize, out: &mut [f64]) {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU supports AVX2, checked just above.
            return unsafe { self.row_avx2(xi, start, out) };
        }
        self.blocks(xi, start, out, exp_f64_block);
    }

    /// [`RbfColumns::row`] for a row held as f32: the same squared distances, scaled by −γ in
    /// f64, rounded to f32 and exponentiated in f32 ([`crate::exp::exp_f32`]). Each value is
    /// within 2⁻²³ of the exact kernel: the exponent's rounding moves eᵗ by at most
    /// |t| eᵗ 2⁻²⁴ ≤ 2⁻²⁴/e, and the f32 `exp` by an ulp of a value at most 1. Over 10,000
    /// samples such a row took 1.0 ns an entry on 2 inputs and 2.0 ns on 10, against 2.3 and
    /// 3.2 ns for [`RbfColumns::row`].
    pub(crate) fn row_f32(&self, xi: &[f64], start: usize, out: &mut [f32]) {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU supports AVX2, checked just above.
            return unsafe { self.row_f32_avx2(xi, start, out) };
        }
        self.blocks(xi, start, out, exp_f32_block);
    }

    /// [`RbfColumns::row`] in four-wide vectors. Without fused multiply-adds (Rust never
    /// contracts), every operation rounds as the two-wide build's does: the same bits.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn row_avx2(&self, xi: &[f64], start: usize, out: &mut [f64]) {
        self.blocks(xi, start, out, exp_f64_block);
    }

    /// [`RbfColumns::row_f32`] in vectors, the same bits as [`RbfColumns::row_avx2`] gives
    /// [`RbfColumns::row`].
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn row_f32_avx2(&self, xi: &[f64], start: usize, out: &mut [f32]) {
        self.blocks(xi, start, out, exp_f32_block);
    }

    /// `out[r] = value(−γ · ‖xi − x_{start+r}‖²)`, [`BLOCK`] entries at a time, their sums held
    /// in registers across the features and exponentiated there: a row of 30,000 over 10
    /// features otherwise read and wrote its partial sums once per feature. `values` maps a
    /// block's exponents to its entries. The last, partial block is summed as a whole one is,
    /// so every entry gets the same operations in the same order.
    #[inline(always)]
    fn blocks<O>(&self, xi: &[f64], start: usize, out: &mut [O], values: impl Fn(&[f64], &mut [O])) {
        let scaled = |sum: [f64; BLOCK]| sum.map(|s| -self.gamma * s);
        let blocked = out.len() / BLOCK * BLOCK;
        let (head, tail) = out.split_at_mut(blocked);
        for (b, chunk) in head.chunks_exact_mut(BLOCK).enumerate() {
            values(&scaled(self.block_sums(xi, start + b * BLOCK)), chunk);
        }
        if !tail.is_empty() {
            let from = start + blocked;
            // A whole block's sums, of which the entries before the tail are not read:
            // summed from the last BLOCK entries where the row has them, else one by one.
            if from + tail.len() >= BLOCK {
                let skipped = BLOCK - tail.len();
                values(&scaled(self.block_sums(xi, from - skipped))[skipped..], tail);
            } else {
                for (r, o) in (from..).zip(tail.chunks_exact_mut(1)) {
                    values(&[-self.gamma * self.block_sums::<1>(xi, r)[0]], o);
                }
            }
        }
    }

    /// `‖xi − x_r‖²` for `r` in `from..from + W`, summed feature by feature from the first.
    #[inline(always)]
    fn block_sums<const W: usize>(&self, xi: &[f64], from: usize) -> [f64; W] {
        let mut sum = [0.0f64; W];
        let first = &self.columns[from..from + W];
        // The first feature's term is the sum so far (0 + t is t for t ≥ 0).
        for (s, &v) in sum.iter_mut().zip(first) {
            *s = (xi[0] - v) * (xi[0] - v);
        }
        for (k, &a) in xi.iter().enumerate().skip(1) {
            let column = &self.columns[k * self.n + from..k * self.n + from + W];
            for (s, &v) in sum.iter_mut().zip(column) {
                *s += (a - v) * (a - v);
            }
        }
        sum
    }
}

/// `out[r] = eᵗ` for the exponents `t` of a row's block.
#[inline(always)]
fn exp_f64_block(exponents: &[f64], out: &mut [f64]) {
    for (o, &t) in out.iter_mut().zip(exponents) {
        *o = crate::exp::exp(t);
    }
}

/// [`exp_f64_block`] in f32: the exponents are rounded to f32 first, all of them, so that the
/// exponentials run eight to a vector rather than four (as the f64 sums come).
#[inline(always)]
fn exp_f32_block(exponents: &[f64], out: &mut [f32]) {
    let mut rounded = [0.0f32; BLOCK];
    for (r, &t) in rounded.iter_mut().zip(exponents) {
        *r = t as f32;
    }
    for (o, &t) in out.iter_mut().zip(&rounded) {
        *o = crate::exp::exp_f32(t);
    }
}

/// Rows of any kernel over a set of samples: by feature ([`RbfColumns`]) where it applies, else
/// value by value with [`Kernel::eval`] (which gives the same bits either way round, every
/// kernel being a function of `a·b` or `‖a − b‖²`).
pub(crate) struct RowSource<'a> {
    kernel: &'a Kernel,
    x: &'a [f64],
    dim: usize,
    /// The samples a row runs over, in order; `None`: every sample of `x`.
    samples: Option<Vec<usize>>,
    by_feature: Option<RbfColumns>,
}

impl<'a> RowSource<'a> {
    /// Rows over every sample of `x` (`n × dim`, row-major).
    pub(crate) fn new(kernel: &'a Kernel, x: &'a [f64], dim: usize) -> Self {
        Self {
            kernel,
            x,
            dim,
            samples: None,
            by_feature: RbfColumns::new(kernel, x, dim),
        }
    }

    /// Rows over the samples `samples` of `x` only, in their order: row entry `r` is then the
    /// kernel with `samples[r]`.
    pub(crate) fn of(kernel: &'a Kernel, x: &'a [f64], dim: usize, samples: &[usize]) -> Self {
        let by_feature = RbfColumns::of(kernel, x, dim, samples.iter().copied());
        Self {
            kernel,
            x,
            dim,
            samples: by_feature.is_none().then(|| samples.to_vec()),
            by_feature,
        }
    }

    /// `K(xi, x_r)` for the row's entries `r` in `start..start + out.len()`, into `out`.
    pub(crate) fn row(&self, xi: &[f64], start: usize, out: &mut [f64]) {
        if let Some(by_feature) = &self.by_feature {
            return by_feature.row(xi, start, out);
        }
        self.each(xi, start, out, |v| v);
    }

    /// [`RowSource::row`] for a row held as f32: within 2⁻²³ of the kernel's values for an
    /// RBF ([`RbfColumns::row_f32`]), else [`Kernel::eval`]'s values rounded.
    pub(crate) fn row_f32(&self, xi: &[f64], start: usize, out: &mut [f32]) {
        if let Some(by_feature) = &self.by_feature {
            return by_feature.row_f32(xi, start, out);
        }
        self.each(xi, start, out, |v| v as f32);
    }

    /// `out[r] = held(K(xi, x_{start+r}))`, value by value.
    fn each<O>(&self, xi: &[f64], start: usize, out: &mut [O], held: impl Fn(f64) -> O) {
        let (x, dim) = (self.x, self.dim);
        for (r, o) in (start..).zip(out.iter_mut()) {
            let j = self.samples.as_ref().map_or(r, |samples| samples[r]);
            *o = held(self.kernel.eval(xi, &x[j * dim..(j + 1) * dim]));
        }
    }
}

/// The dense kernel matrix, or `None` if a value overflows. The lower triangle is filled down
/// each column (contiguous in faer's column-major storage), then mirrored. One core: at the
/// sizes this matrix is built for, waking a second one cost more than it saved (measured at
/// n = 350: 2.1 ms on two threads, 1.3 ms on one).
pub(crate) fn kernel_matrix(kernel: &Kernel, x: &[f64], dim: usize) -> Option<Mat<f64>> {
    let n = x.len() / dim;
    let row = |i: usize| &x[i * dim..(i + 1) * dim];
    let mut k = Mat::<f64>::zeros(n, n);
    // An RBF's columns come a feature at a time, in vector loops (the same bits).
    let source = RowSource::new(kernel, x, dim);
    let mut column = vec![0.0; n];
    for j in 0..n {
        let below = &mut column[..n - j];
        source.row(row(j), j, below);
        for (&v, i) in below.iter().zip(j..) {
            if !v.is_finite() {
                return None;
            }
            k[(i, j)] = v;
        }
    }
    for j in 1..n {
        for i in 0..j {
            k[(i, j)] = k[(j, i)];
        }
    }
    Some(k)
}

fn powi(x: f64, degree: u32) -> f64 {
    x.powi(i32::try_from(degree).unwrap_or(i32::MAX))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kernels_match_their_formulas() {
        let a = [1.0, 2.0];
        let b = [0.5, -1.0];
        assert_eq!(Kernel::Linear.eval(&a, &b), 0.5 - 2.0);
        let k = Kernel::Rbf { gamma: 0.3 }.eval(&a, &b);
        assert!((k - (-0.3f64 * (0.25 + 9.0)).exp()).abs() < 1e-15);
        let p = Kernel::Polynomial {
            gamma: 2.0,
            coef0: 1.0,
            degree: 2,
        }
        .eval(&a, &b);
        assert!((p - (2.0f64 * -1.5 + 1.0).powi(2)).abs() < 1e-15);
    }

    #[test]
    fn rbf_rows_by_feature_are_the_kernels_values_to_two_ulps() {
        for dim in 1..LANE_SUM_MIN {
            let n = 37;
            let x: Vec<f64> = (0..n * dim)
                .map(|i| ((i * 7919) % 1000) as f64 / 997.0 - 0.3)
                .collect();
            let kernel = Kernel::Rbf { gamma: 2.7 };
            let columns = RbfColumns::new(&kernel, &x, dim).unwrap();
            // Whole blocks only, blocks and a tail, a tail only (from a last whole block and
            // from no whole block, in a row shorter than a block).
            for (i, start, len) in [(0, 5, 32), (11, 3, 34), (n - 1, 30, 7), (20, 0, 37), (6, 4, 9)] {
                let mut out = vec![0.0; len];
                let mut out_f32 = vec![0.0f32; len];
                let xi = &x[i * dim..(i + 1) * dim];
                columns.row(xi, start, &mut out);
                columns.row_f32(xi, start, &mut out_f32);
                for ((o, o32), r) in out.iter().zip(&out_f32).zip(start..) {
                    let xr = &x[r * dim..(r + 1) * dim];
                    let exact = kernel.eval(xi, xr);
                    assert!(o.to_bits().abs_diff(exact.to_bits()) <= 2, "dim {dim} ({i}, {r})");
                    let exponent = -2.7 * squared_distance(xi, xr);
                    assert_eq!(*o, crate::exp::exp(exponent), "dim {dim} ({i}, {r})");
                    // The f32 row: its own exp on the rounded exponent, within 2⁻²³ of exact.
                    assert_eq!(
                        *o32,
                        crate::exp::exp_f32(exponent as f32),
                        "f32, dim {dim} ({i}, {r})"
                    );
                    assert!(
                        (f64::from(*o32) - exact).abs() <= f64::from(f32::EPSILON) / 2.0,
                        "f32, dim {dim} ({i}, {r})"
                    );
                }
            }
        }
        let wide = vec![0.5; 4 * LANE_SUM_MIN];
        assert!(RbfColumns::new(&Kernel::Rbf { gamma: 1.0 }, &wide, LANE_SUM_MIN).is_none());
        assert!(RbfColumns::new(&Kernel::Linear, &wide, 2).is_none());
    }

    #[test]
    fn the_inner_product_sums_every_term_once() {
        // Small integers sum exactly in any order: every term, in the lanes (from 16 terms on)
        // and in the remainder after them, counts once.
        for len in [0, 1, 3, 4, 7, 8, 13, 16, 17, 19, 40] {
            let row: Vec<f64> = (0..len).map(|i| (i + 1) as f64).collect();
            let coefficients: Vec<f64> = (0..len + 2).map(|i| (3 * i) as f64 - 4.0).collect();
            let expected: f64 = (0..len).map(|i| row[i] * coefficients[i]).sum();
            assert_eq!(dot(&row, &coefficients), expected, "len {len}");
        }
    }

    #[test]
    fn serialises_with_a_type_tag() {
        let json = serde_json::to_string(&Kernel::Rbf { gamma: 10.0 }).unwrap();
        assert_eq!(json, r#"{"type":"rbf","gamma":10.0}"#);
        let back: Kernel = serde_json::from_str(&json).unwrap();
        assert_eq!(back, Kernel::Rbf { gamma: 10.0 });
    }
}
