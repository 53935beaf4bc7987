//! Kernel rows of one binary machine's training vectors, computed when the solver first asks
//! for them and kept within a memory budget.
//!
//! SMO with shrinking touches few rows on an easy pair (a separable pair of surfaces converges
//! in tens of iterations, two rows each), so a precomputed Gram matrix would spend most of the
//! fit on rows nobody reads; on a hard pair it reads most rows many times, so they are kept.
//! libsvm's cache does the same (scikit-learn's `cache_size`, 200 MB by default).

use svm::{Kernel, KernelRows};

/// Memory for one solve's cached rows: with both cores solving, twice this is held.
/// A pair of up to 4,096 training vectors keeps every row.
pub(super) const CACHE_BYTES: usize = 128 << 20;

/// Rows of `kernel` over a subset of the training points, least recently used ones evicted
/// beyond [`CACHE_BYTES`] (at least two rows are kept: a pair update reads two).
pub(super) struct SubsetRows {
    kernel: Kernel,
    /// The subset's points, gathered contiguously (n × dim), so a row reads memory in order.
    x: Vec<f64>,
    dim: usize,
    n: usize,
    diag: Vec<f64>,
    /// Slot of each sample's row, if cached.
    slot_of: Vec<Option<usize>>,
    /// Sample whose row each slot holds.
    owner: Vec<usize>,
    last_used: Vec<u64>,
    /// Slots' storage, grown as slots are first used.
    rows: Vec<f64>,
    slots: usize,
    clock: u64,
}

impl SubsetRows {
    /// Rows over the points `points[t·dim..(t + 1)·dim]` for each `t` in `subset`, in that order.
    pub(super) fn new(
        kernel: Kernel,
        points: &[f64],
        dim: usize,
        subset: impl Iterator<Item = usize>,
    ) -> Self {
        let mut x = Vec::new();
        for t in subset {
            x.extend_from_slice(&points[t * dim..(t + 1) * dim]);
        }
        let n = x.len() / dim.max(1);
        let diag = x.chunks_exact(dim.max(1)).map(|p| kernel.eval(p, p)).collect();
        let slots = (CACHE_BYTES / (size_of::<f64>() * n.max(1))).clamp(2, n.max(2));
        Self {
            kernel,
            x,
            dim,
            n,
            diag,
            slot_of: vec![None; n],
            owner: Vec::new(),
            last_used: Vec::new(),
            rows: Vec::new(),
            slots,
            clock: 0,
        }
    }

    /// The subset's point `s`.
    pub(super) fn point(&self, s: usize) -> &[f64] {
        &self.x[s * self.dim..(s + 1) * self.dim]
    }
}

impl KernelRows for SubsetRows {
    fn samples(&self) -> usize {
        self.n
    }

    fn diagonal(&self, s: usize) -> f64 {
        self.diag[s]
    }

    fn row(&mut self, s: usize) -> &[f64] {
        self.clock += 1;
        let n = self.n;
        let slot = match self.slot_of[s] {
            Some(slot) => slot,
            None => {
                let slot = if self.owner.len() < self.slots {
                    // Storage grows only as far as rows are asked for.
                    self.owner.push(s);
                    self.last_used.push(0);
                    self.rows.resize(self.owner.len() * n, 0.0);
                    self.owner.len() - 1
                } else {
                    let lru = (0..self.slots).min_by_key(|&k| self.last_used[k]).unwrap_or(0);
                    self.slot_of[self.owner[lru]] = None;
                    self.owner[lru] = s;
                    lru
                };
                self.slot_of[s] = Some(slot);
                let (kernel, dim) = (self.kernel, self.dim);
                let xs = &self.x[s * dim..(s + 1) * dim];
                for (out, xr) in self.rows[slot * n..(slot + 1) * n]
                    .iter_mut()
                    .zip(self.x.chunks_exact(dim))
                {
                    *out = kernel.eval(xs, xr);
                }
                slot
            }
        };
        self.last_used[slot] = self.clock;
        &self.rows[slot * n..(slot + 1) * n]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_are_the_kernel_of_the_subset_and_survive_eviction() {
        let kernel = Kernel::Polynomial {
            gamma: 0.5,
            coef0: 1.0,
            degree: 2,
        };
        let points: Vec<f64> = (0..20).map(|v| (v as f64 * 0.37).sin()).collect();
        let subset = [7, 2, 9, 4];
        let mut rows = SubsetRows::new(kernel, &points, 2, subset.iter().copied());
        // Two slots only, so asking for four rows in turn evicts.
        rows.slots = 2;
        for _ in 0..3 {
            for (s, &t) in subset.iter().enumerate() {
                let want: Vec<f64> = subset
                    .iter()
                    .map(|&r| kernel.eval(&points[2 * t..2 * t + 2], &points[2 * r..2 * r + 2]))
                    .collect();
                assert_eq!(rows.row(s), want.as_slice());
                assert_eq!(rows.diagonal(s), want[s]);
            }
        }
        assert_eq!(rows.owner.len(), 2);
        assert_eq!(rows.rows.len(), 2 * subset.len());
        assert_eq!(rows.point(1), &points[4..6]);
    }
}
