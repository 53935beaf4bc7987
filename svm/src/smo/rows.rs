//! Kernel rows by sample, and the dual's matrix over them when a sample carries one variable or
//! two (libsvm's `SVR_Q`): the ε-SVR's split dual, and any dual over a [`GramRows`].

use super::solver::QMatrix;

/// Rows of the kernel matrix over the samples, as the solver asks for them.
pub trait KernelRows {
    /// Number of samples.
    fn samples(&self) -> usize;
    /// `K(xₛ, xₛ)`.
    fn diagonal(&self, s: usize) -> f64;
    /// Row `s` of K: `K(xₛ, xᵣ)` for every sample `r`.
    fn row(&mut self, s: usize) -> &[f64];
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
        for ((o, &r), &sr) in out.iter_mut().zip(&self.sample[..len]).zip(&self.sign[..len]) {
            *o = st * sr * row[r];
        }
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
