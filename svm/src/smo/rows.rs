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
    /// Row `s` of K: `K(xₛ, xᵣ)` for every sample `r`, or, while narrowed
    /// ([`KernelRows::narrow`]), for the window's samples only, in the window's order.
    fn row(&mut self, s: usize) -> &[Self::Value];
    /// From now on, [`KernelRows::row`] runs over the samples `window` only (entry `r` is the
    /// kernel with `window[r]`), until the next `narrow` or [`KernelRows::widen`]; `false` (and
    /// rows stay whole) where this source cannot narrow.
    fn narrow(&mut self, window: &[u32]) -> bool {
        let _ = window;
        false
    }
    /// Rows over every sample again.
    fn widen(&mut self) {}
    /// Row `s` over every sample, narrowed or not.
    fn whole_row(&mut self, s: usize) -> &[Self::Value] {
        self.row(s)
    }
}

/// A kernel value as a row holds it: `f64`, or `f32` where a store of rows gains twice the rows
/// for a rounding of 2⁻²⁴ (libsvm holds its rows so). The solver reads every value as `f64`.
pub trait RowValue: sealed::Sealed + Copy + Default + Into<f64> + Send + Sync + 'static {
    /// Whether holding a value rounds it, so that a gradient built from rows is the gradient of
    /// a neighbouring problem, not of the one asked.
    const ROUNDS: bool;
    /// The row's own storage, by type, so that a row is computed in place and in the
    /// arithmetic its values are held to.
    fn storage(row: &mut [Self]) -> RowStorage<'_>;
}

/// A row's storage as [`RowValue::storage`] hands it out.
#[derive(Debug)]
pub enum RowStorage<'a> {
    /// Values held as computed.
    Exact(&'a mut [f64]),
    /// Values held rounded to f32.
    Rounded(&'a mut [f32]),
}

mod sealed {
    /// Only the row values the gathers are written for: what differs between them is how four
    /// values are gathered and widened.
    pub trait Sealed: Sized {
        /// `row[index[k]]` for k < 4, as doubles.
        ///
        /// # Safety
        /// Every index is below the row's length and the CPU supports AVX2.
        #[cfg(target_arch = "x86_64")]
        unsafe fn four(row: *const Self, index: std::arch::x86_64::__m128i) -> std::arch::x86_64::__m256d;
    }

    impl Sealed for f64 {
        #[cfg(target_arch = "x86_64")]
        #[inline(always)]
        unsafe fn four(row: *const Self, index: std::arch::x86_64::__m128i) -> std::arch::x86_64::__m256d {
            // SAFETY: as the caller promised.
            unsafe { std::arch::x86_64::_mm256_i32gather_pd::<8>(row, index) }
        }
    }

    impl Sealed for f32 {
        #[cfg(target_arch = "x86_64")]
        #[inline(always)]
        unsafe fn four(row: *const Self, index: std::arch::x86_64::__m128i) -> std::arch::x86_64::__m256d {
            use std::arch::x86_64::*;
            // SAFETY: as the caller promised; widening is exact.
            unsafe { _mm256_cvtps_pd(_mm_i32gather_ps::<4>(row, index)) }
        }
    }
}

impl RowValue for f64 {
    const ROUNDS: bool = false;

    fn storage(row: &mut [Self]) -> RowStorage<'_> {
        RowStorage::Exact(row)
    }
}

impl RowValue for f32 {
    const ROUNDS: bool = true;

    fn storage(row: &mut [Self]) -> RowStorage<'_> {
        RowStorage::Rounded(row)
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

/// Rows narrow to the active samples once these are at most this fraction (numerator,
/// denominator) of the samples rows run over.
const NARROW_BELOW: (usize, usize) = (1, 2);

/// The dual's matrix over variables that each stand for a sample with a sign: a row of Q is
/// gathered, over the positions asked for, from the sample's kernel row (which `R` may cache),
/// into one of two buffers in turn, so the last two stay readable together. Two variables of a
/// split dual share their sample's kernel row; libsvm's `SVR_Q` does the same, and as libsvm's,
/// the sample and sign of a position take 5 bytes, which the gather reads for every position of
/// every row (with 16 bytes it was a quarter of a Friedman fit at n = 2,208).
///
/// Once shrinking has left few samples active ([`NARROW_BELOW`]), their rows are computed over the
/// active samples only ([`KernelRows::narrow`]), as libsvm's C-SVC computes its rows over the
/// active set only (its `SVR_Q` computes every row whole): at n = 30,000 on Friedman #1 the
/// active set is a tenth of the variables after the first 60,000 of 239,000 iterations.
pub(super) struct SampleQ<'r, R> {
    rows: &'r mut R,
    /// Samples; every entry of `sample` is below it.
    n: usize,
    /// Sample of the variable at each position.
    sample: Vec<u32>,
    /// Sign (label) of the variable at each position.
    sign: Vec<i8>,
    /// Entry of each position's sample in the narrowed rows (the sample itself while rows are
    /// whole); below [`SampleQ::covered`], every entry is below the window's length.
    entry: Vec<u32>,
    /// Positions below it have their samples in the window (every position while whole).
    covered: usize,
    /// The samples rows run over while narrowed; empty while whole.
    window: Vec<u32>,
    /// Each sample's entry in the window (`u32::MAX` outside it, and while whole).
    entry_of: Vec<u32>,
    /// Scratch: a mark per sample.
    seen: Vec<bool>,
    /// Ḡ by sample, unsigned: `Ḡₜ = sign[t] · bar[sample[t]]`, since every row of Q is its
    /// sample's kernel row signed. A variable reaching its bound adds its kernel row as it is
    /// held, n values in order, where a row of Q was gathered over all 2n positions and added
    /// there: that was a seventh of a Friedman #1 fit's time at n = 30,000 on 5 inputs, which
    /// now takes 11.6 s instead of 12.9 (one thread, fastest of three).
    bar: Vec<f64>,
    buffers: [Vec<f64>; 2],
    next: usize,
}

impl<'r, R: KernelRows> SampleQ<'r, R> {
    /// Variable t is sample `t mod n` with sign `labels[t]`.
    ///
    /// # Panics
    /// If a label is not ±1, or there are 2³¹ samples or more (the gathers' indices are 32-bit).
    pub(super) fn new(rows: &'r mut R, labels: &[f64]) -> Self {
        let n = rows.samples();
        let m = labels.len();
        assert!(
            i32::try_from(n).is_ok(),
            "SMO: {n} samples; at most 2³¹ − 1 are indexed"
        );
        let sign = labels
            .iter()
            .map(|&l| match l {
                1.0 => 1,
                -1.0 => -1,
                _ => panic!("SMO: a label {l}, not ±1"),
            })
            .collect();
        let sample: Vec<u32> = (0..m).map(|t| (t % n.max(1)) as u32).collect();
        Self {
            rows,
            n,
            entry: sample.clone(),
            sample,
            sign,
            covered: m,
            window: Vec::new(),
            entry_of: vec![u32::MAX; n],
            seen: vec![false; n],
            bar: vec![0.0; n],
            buffers: [vec![0.0; m], vec![0.0; m]],
            next: 0,
        }
    }

    /// Rows over every sample again.
    fn widen(&mut self) {
        if !self.window.is_empty() {
            self.rows.widen();
            for &s in &self.window {
                self.entry_of[s as usize] = u32::MAX;
            }
            self.window.clear();
            self.entry.copy_from_slice(&self.sample);
        }
        self.covered = self.sample.len();
    }
}

impl<R: KernelRows> QMatrix for SampleQ<'_, R> {
    fn diagonal(&self, t: usize) -> f64 {
        self.rows.diagonal(self.sample[t] as usize)
    }

    fn fetch(&mut self, t: usize, len: usize) -> usize {
        let h = self.next;
        self.next = 1 - h;
        let (s, st) = (self.sample[t] as usize, f64::from(self.sign[t]));
        let (row, index) = if len <= self.covered {
            let entries = if self.window.is_empty() {
                self.n
            } else {
                self.window.len()
            };
            let row = self.rows.row(s);
            assert!(row.len() >= entries, "a kernel row shorter than its samples");
            (row, &self.entry)
        } else {
            let row = self.rows.whole_row(s);
            assert!(row.len() >= self.n, "a kernel row shorter than its samples");
            (row, &self.sample)
        };
        let out = &mut self.buffers[h][..len];
        // SAFETY: `index` and `sign` hold a position per variable, as many as `out` at most.
        // Every sample is below `n` (made so, then only swapped) and `n ≤ row.len()`; below
        // `covered`, every entry is below the window's length (`focus` made it so, and no
        // position has moved since) and that is at most `row.len()`.
        unsafe { gather_signed(row, &index[..len], &self.sign[..len], st, out) };
        h
    }

    fn focus(&mut self, active: usize) {
        let mut samples = Vec::new();
        let mut outside = false;
        for &s in &self.sample[..active] {
            if !std::mem::replace(&mut self.seen[s as usize], true) {
                samples.push(s);
                outside |= !self.window.is_empty() && self.entry_of[s as usize] == u32::MAX;
            }
        }
        for &s in &samples {
            self.seen[s as usize] = false;
        }
        let now = if self.window.is_empty() {
            self.n
        } else {
            self.window.len()
        };
        if !outside && NARROW_BELOW.1 * samples.len() > NARROW_BELOW.0 * now {
            // Still over the active samples, and not enough fewer of them to narrow to.
            self.covered = if self.window.is_empty() {
                self.sample.len()
            } else {
                active
            };
            return;
        }
        if NARROW_BELOW.1 * samples.len() > NARROW_BELOW.0 * self.n || !self.rows.narrow(&samples) {
            self.widen();
            return;
        }
        // Entries by sample, then by position (positions outside the window get 0: they are
        // at or above `covered`, so never gathered through `entry`).
        for &s in &self.window {
            self.entry_of[s as usize] = u32::MAX;
        }
        for (r, &s) in samples.iter().enumerate() {
            self.entry_of[s as usize] = r as u32;
        }
        for (e, &s) in self.entry.iter_mut().zip(&self.sample) {
            let r = self.entry_of[s as usize];
            *e = if r == u32::MAX { 0 } else { r };
        }
        self.window = samples;
        self.covered = active;
    }

    fn get(&self, handle: usize) -> &[f64] {
        &self.buffers[handle]
    }

    /// The same sums, to the bit, as adding Q's row by position: each term is the position's
    /// sign (±1, exact) times this one.
    fn add_to_bar(&mut self, t: usize, coefficient: f64) {
        let (s, st) = (self.sample[t] as usize, f64::from(self.sign[t]));
        let row = self.rows.whole_row(s);
        assert!(row.len() >= self.n, "a kernel row shorter than its samples");
        for (b, &v) in self.bar.iter_mut().zip(&row[..self.n]) {
            *b += coefficient * (st * v.into());
        }
    }

    fn bar(&self, t: usize) -> f64 {
        f64::from(self.sign[t]) * self.bar[self.sample[t] as usize]
    }

    fn swap(&mut self, i: usize, j: usize) {
        self.sample.swap(i, j);
        self.sign.swap(i, j);
        self.entry.swap(i, j);
    }
}

/// `out[t] = st · sign[t] · row[sample[t]]` for every `t < out.len()`: a row of Q from its
/// sample's kernel row, in AVX2 gathers where the CPU has them (a fifth of a Friedman fit's time
/// at n = 3,000 was this loop; the products by ±1 and the widening are exact, so both ways give
/// the same bits).
///
/// # Safety
/// `sample` and `sign` are at least as long as `out`, and each of the first `out.len()` samples
/// is below `row.len()`: the gathers read `row` without bounds checks.
unsafe fn gather_signed<T: RowValue>(row: &[T], sample: &[u32], sign: &[i8], st: f64, out: &mut [f64]) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU supports AVX2, checked just above; the indices as the caller
        // promised.
        unsafe { gather_signed_avx2(row, sample, sign, st, out) };
        return;
    }
    gather_signed_from(row, sample, sign, st, out, 0);
}

fn gather_signed_from<T: RowValue>(
    row: &[T],
    sample: &[u32],
    sign: &[i8],
    st: f64,
    out: &mut [f64],
    from: usize,
) {
    for ((o, &r), &sr) in out[from..].iter_mut().zip(&sample[from..]).zip(&sign[from..]) {
        *o = st * f64::from(sr) * row[r as usize].into();
    }
}

/// [`gather_signed`] four positions at a time.
///
/// # Safety
/// As [`gather_signed`], on a CPU with AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn gather_signed_avx2<T: RowValue>(row: &[T], sample: &[u32], sign: &[i8], st: f64, out: &mut [f64]) {
    use std::arch::x86_64::*;
    let n = out.len();
    let whole = n / 4 * 4;
    let stv = _mm256_set1_pd(st);
    for start in (0..whole).step_by(4) {
        // SAFETY: start + 4 ≤ n ≤ each slice's length; every index is below row.len() (the
        // caller's promise) and below 2³¹, so the signed 32-bit gather reads inside `row`.
        unsafe {
            let index = _mm_loadu_si128(sample.as_ptr().add(start).cast());
            let values = T::four(row.as_ptr(), index);
            // Four signs (±1 bytes) as doubles.
            let bytes = sign.as_ptr().add(start).cast::<i32>().read_unaligned();
            let signs = _mm256_cvtepi32_pd(_mm_cvtepi8_epi32(_mm_cvtsi32_si128(bytes)));
            _mm256_storeu_pd(
                out.as_mut_ptr().add(start),
                _mm256_mul_pd(_mm256_mul_pd(stv, signs), values),
            );
        }
    }
    gather_signed_from(row, sample, sign, st, out, whole);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_gathered_row_is_the_signed_kernel_row_whatever_the_length() {
        let row: Vec<f64> = (0..37).map(|r| (r as f64 * 0.71).sin()).collect();
        for len in [0, 1, 3, 4, 5, 8, 74] {
            let sample: Vec<u32> = (0..len).map(|t| ((t * 13 + 5) % 37) as u32).collect();
            let sign: Vec<i8> = (0..len).map(|t| if t % 3 == 0 { -1 } else { 1 }).collect();
            let narrow: Vec<f32> = row.iter().map(|&v| v as f32).collect();
            for st in [1.0, -1.0] {
                let mut out = vec![f64::NAN; len];
                let mut out_f32 = vec![f64::NAN; len];
                // SAFETY: every sample is below 37, the rows' length.
                unsafe {
                    gather_signed(&row, &sample, &sign, st, &mut out);
                    gather_signed(&narrow, &sample, &sign, st, &mut out_f32);
                }
                for t in 0..len {
                    let (r, sr) = (sample[t] as usize, f64::from(sign[t]));
                    assert_eq!(out[t], st * sr * row[r], "len {len} t {t}");
                    let widened = f64::from(narrow[r]);
                    assert_eq!(out_f32[t], st * sr * widened, "f32, len {len} t {t}");
                }
            }
        }
    }

    #[test]
    fn the_bar_by_sample_is_the_bar_by_position_to_the_bit() {
        // A split dual's 2n variables over n samples, moved about as shrinking moves them, and
        // rows added as variables reach or leave their upper bound, with the matrix's rows
        // narrowed to some samples part of the way.
        let n = 23;
        let k: Vec<f64> = (0..n * n)
            .map(|e| {
                let (i, j) = (e / n, e % n);
                (-((i as f64 - j as f64) * 0.37).powi(2)).exp() * (1.0 + 1e-3 * ((i * j) as f64).sin())
            })
            .collect();
        let labels: Vec<f64> = (0..2 * n).map(|t| if t < n { 1.0 } else { -1.0 }).collect();
        let mut rows = GramRows::new(&k, n).unwrap();
        let mut q = SampleQ::new(&mut rows, &labels);
        let mut by_position = vec![0.0; 2 * n];
        let mut rng = capture::rng::SplitMix64::new(5);
        for step in 0..200 {
            let (i, j) = (rng.below(2 * n), rng.below(2 * n));
            if i < j {
                q.swap(i, j);
                by_position.swap(i, j);
            }
            if step == 120 {
                q.focus(n / 2);
            }
            let t = rng.below(2 * n);
            let coefficient = if rng.below(2) == 0 { 3.7 } else { -3.7 } * (1.0 + step as f64);
            let h = q.fetch(t, 2 * n);
            let row = q.get(h)[..2 * n].to_vec();
            for (b, q) in by_position.iter_mut().zip(&row) {
                *b += coefficient * q;
            }
            q.add_to_bar(t, coefficient);
        }
        for (t, expected) in by_position.iter().enumerate() {
            assert_eq!(q.bar(t).to_bits(), expected.to_bits(), "position {t}");
        }
    }
}
