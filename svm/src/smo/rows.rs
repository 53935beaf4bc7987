//! Kernel rows by sample, and the dual's matrix over them when a sample carries one variable or
//! two (libsvm's `SVR_Q`): the ε-SVR's split dual, and any dual over a [`GramRows`].

use super::solver::QMatrix;

/// Rows of the kernel matrix over the samples, as the solver asks for them.
pub trait KernelRows {
    /// How a row holds its values.
    type Value: RowValue;
    /// Number of samples.
    fn samples(&self) -> usize;
    /// `K(xₛ, xₛ)`.
    fn diagonal(&self, s: usize) -> f64;
    /// Row `s` of K: `K(xₛ, xᵣ)` for every sample `r`.
    fn row(&mut self, s: usize) -> &[Self::Value];
}

/// A kernel value as a row holds it: `f64`, or `f32` where a store of rows gains twice the rows
/// for a rounding of 2⁻²⁴ (libsvm holds its rows so). The solver reads every value as `f64`.
pub trait RowValue: Copy + Default + Send + Sync + 'static {
    /// Whether holding a value rounds it, so that a gradient built from rows is the gradient of
    /// a neighbouring problem, not of the one asked.
    const ROUNDS: bool;
    /// `out[t] = st · sign[t] · row[sample[t]]`.
    fn gather_signed(row: &[Self], sample: &[usize], sign: &[f64], st: f64, out: &mut [f64]);
    /// The row's own storage when it is `f64`, so that a row is computed in place.
    fn as_f64_mut(row: &mut [Self]) -> Option<&mut [f64]>;
    /// Holds `values` in `out`.
    fn store(values: &[f64], out: &mut [Self]);
}

impl RowValue for f64 {
    const ROUNDS: bool = false;

    fn gather_signed(row: &[Self], sample: &[usize], sign: &[f64], st: f64, out: &mut [f64]) {
        gather_signed(row, sample, sign, st, out);
    }

    fn as_f64_mut(row: &mut [Self]) -> Option<&mut [f64]> {
        Some(row)
    }

    fn store(values: &[f64], out: &mut [Self]) {
        out.copy_from_slice(values);
    }
}

impl RowValue for f32 {
    const ROUNDS: bool = true;

    fn gather_signed(row: &[Self], sample: &[usize], sign: &[f64], st: f64, out: &mut [f64]) {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") && row.len() <= i64::MAX as usize {
            // SAFETY: the CPU supports AVX2, checked just above.
            unsafe { gather_signed_f32_avx2(row, sample, sign, st, out) };
            return;
        }
        gather_signed_from(row, sample, sign, st, out, 0);
    }

    fn as_f64_mut(_: &mut [Self]) -> Option<&mut [f64]> {
        None
    }

    fn store(values: &[f64], out: &mut [Self]) {
        for (o, &v) in out.iter_mut().zip(values) {
            *o = v as f32;
        }
    }
}

/// A precomputed, symmetric Gram matrix (row-major, n × n).
#[derive(Debug, Clone, Copy)]
pub struct GramRows<'a> {
    k: &'a [f64],
    n: usize,
}

impl<'a> GramRows<'a> {
    /// Wraps `k`, which must hold `n²` values; `None` if it does not.
    pub fn new(k: &'a [f64], n: usize) -> Option<Self> {
        (n.checked_mul(n) == Some(k.len())).then_some(Self { k, n })
    }
}

impl KernelRows for GramRows<'_> {
    type Value = f64;

    fn samples(&self) -> usize {
        self.n
    }
    fn diagonal(&self, s: usize) -> f64 {
        self.k[s * self.n + s]
    }
    fn row(&mut self, s: usize) -> &[f64] {
        &self.k[s * self.n..(s + 1) * self.n]
    }
}

/// The dual's matrix over variables that each stand for a sample with a sign: a row of Q is
/// gathered, over the positions asked for, from the sample's kernel row (which `R` may cache),
/// into one of two buffers in turn, so the last two stay readable together. Two variables of a
/// split dual share their sample's kernel row; libsvm's `SVR_Q` does the same.
pub(super) struct SampleQ<'r, R> {
    rows: &'r mut R,
    /// Sample of the variable at each position.
    sample: Vec<usize>,
    /// Sign (label) of the variable at each position.
    sign: Vec<f64>,
    buffers: [Vec<f64>; 2],
    next: usize,
}

impl<'r, R: KernelRows> SampleQ<'r, R> {
    /// Variable t is sample `t mod n` with sign `labels[t]`.
    pub(super) fn new(rows: &'r mut R, labels: &[f64]) -> Self {
        let n = rows.samples();
        let m = labels.len();
        Self {
            rows,
            sample: (0..m).map(|t| t % n.max(1)).collect(),
            sign: labels.to_vec(),
            buffers: [vec![0.0; m], vec![0.0; m]],
            next: 0,
        }
    }
}

impl<R: KernelRows> QMatrix for SampleQ<'_, R> {
    fn diagonal(&self, t: usize) -> f64 {
        self.rows.diagonal(self.sample[t])
    }

    fn fetch(&mut self, t: usize, len: usize) -> usize {
        let h = self.next;
        self.next = 1 - h;
        let (s, st) = (self.sample[t], self.sign[t]);
        let row = self.rows.row(s);
        let out = &mut self.buffers[h][..len];
        R::Value::gather_signed(row, &self.sample[..len], &self.sign[..len], st, out);
        h
    }

    fn get(&self, handle: usize) -> &[f64] {
        &self.buffers[handle]
    }

    fn swap(&mut self, i: usize, j: usize) {
        self.sample.swap(i, j);
        self.sign.swap(i, j);
    }
}

/// `out[t] = st · sign[t] · row[sample[t]]`: a row of Q from its sample's kernel row, in AVX2
/// gathers where the CPU has them (a fifth of a Friedman fit's time at n = 3,000 was this loop;
/// the products by ±1 are exact, so both ways give the same bits).
fn gather_signed(row: &[f64], sample: &[usize], sign: &[f64], st: f64, out: &mut [f64]) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") && row.len() <= i64::MAX as usize {
        // SAFETY: the CPU supports AVX2, checked just above.
        unsafe { gather_signed_avx2(row, sample, sign, st, out) };
        return;
    }
    gather_signed_from(row, sample, sign, st, out, 0);
}

fn gather_signed_from<T: Copy + Into<f64>>(
    row: &[T],
    sample: &[usize],
    sign: &[f64],
    st: f64,
    out: &mut [f64],
    from: usize,
) {
    for ((o, &r), &sr) in out[from..].iter_mut().zip(&sample[from..]).zip(&sign[from..]) {
        *o = st * sr * row[r].into();
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn gather_signed_avx2(row: &[f64], sample: &[usize], sign: &[f64], st: f64, out: &mut [f64]) {
    use std::arch::x86_64::*;
    let n = out.len().min(sample.len()).min(sign.len());
    // Every index is checked once, up front: the gathers below read without bounds checks.
    assert!(
        sample[..n].iter().all(|&r| r < row.len()),
        "a sample outside its kernel row"
    );
    let whole = n / 4 * 4;
    let stv = _mm256_set1_pd(st);
    for start in (0..whole).step_by(4) {
        // SAFETY: start + 4 ≤ n ≤ each slice's length, and every index is below row.len()
        // (checked above), so the gather reads inside `row`.
        unsafe {
            let index = _mm256_loadu_si256(sample.as_ptr().add(start).cast());
            let values = _mm256_i64gather_pd::<8>(row.as_ptr(), index);
            let signs = _mm256_loadu_pd(sign.as_ptr().add(start));
            _mm256_storeu_pd(
                out.as_mut_ptr().add(start),
                _mm256_mul_pd(_mm256_mul_pd(stv, signs), values),
            );
        }
    }
    gather_signed_from(row, sample, sign, st, &mut out[..n], whole);
}

/// [`gather_signed_avx2`] from a row of `f32`, each value widened exactly.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn gather_signed_f32_avx2(row: &[f32], sample: &[usize], sign: &[f64], st: f64, out: &mut [f64]) {
    use std::arch::x86_64::*;
    let n = out.len().min(sample.len()).min(sign.len());
    assert!(
        sample[..n].iter().all(|&r| r < row.len()),
        "a sample outside its kernel row"
    );
    let whole = n / 4 * 4;
    let stv = _mm256_set1_pd(st);
    for start in (0..whole).step_by(4) {
        // SAFETY: as in `gather_signed_avx2`, with 4-byte values.
        unsafe {
            let index = _mm256_loadu_si256(sample.as_ptr().add(start).cast());
            let values = _mm256_cvtps_pd(_mm256_i64gather_ps::<4>(row.as_ptr(), index));
            let signs = _mm256_loadu_pd(sign.as_ptr().add(start));
            _mm256_storeu_pd(
                out.as_mut_ptr().add(start),
                _mm256_mul_pd(_mm256_mul_pd(stv, signs), values),
            );
        }
    }
    gather_signed_from(row, sample, sign, st, &mut out[..n], whole);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_gathered_row_is_the_signed_kernel_row_whatever_the_length() {
        let row: Vec<f64> = (0..37).map(|r| (r as f64 * 0.71).sin()).collect();
        for len in [0, 1, 3, 4, 5, 8, 74] {
            let sample: Vec<usize> = (0..len).map(|t| (t * 13 + 5) % 37).collect();
            let sign: Vec<f64> = (0..len).map(|t| if t % 3 == 0 { -1.0 } else { 1.0 }).collect();
            let narrow: Vec<f32> = row.iter().map(|&v| v as f32).collect();
            for st in [1.0, -1.0] {
                let mut out = vec![f64::NAN; len];
                f64::gather_signed(&row, &sample, &sign, st, &mut out);
                let mut out_f32 = vec![f64::NAN; len];
                f32::gather_signed(&narrow, &sample, &sign, st, &mut out_f32);
                for t in 0..len {
                    assert_eq!(out[t], st * sign[t] * row[sample[t]], "len {len} t {t}");
                    let widened = f64::from(narrow[sample[t]]);
                    assert_eq!(out_f32[t], st * sign[t] * widened, "f32, len {len} t {t}");
                }
            }
        }
    }
}
