//! Many k-NN queries at once (a cross-validation's held-out windows), with the exhaustive
//! scan's answer to the bit, on all cores.
//!
//! A query against every training point costs `dim` subtractions, multiplications and
//! additions per point; over the histograms' 130 features and tens of thousands of windows, a
//! k-NN's cross-validations were most of its training. Here a matrix product (faer's, blocked
//! and vectorised) screens the points: `‖p‖² + ‖q‖² − 2 p·q` differs from the scan's computed
//! distance by at most a bound `B` that follows from the dimension and the norms (below), so a
//! point whose screened distance exceeds the k-th smallest screened distance by more than `2B`
//! is strictly farther than the k-th nearest and cannot be among them, not even through a tie.
//! The points left (about k, plus ties) are then ordered by the scan's own distance
//! ([`squared_distance`]) and index, exactly as the scan orders them.

use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, MatRef, Par};
use rayon::prelude::*;

use super::tree::{Best, squared_distance};

/// Queries screened by one matrix product: its `QUERY_BLOCK × points` products take 1 MB per
/// thousand training points, and the blocks are what the cores share.
const QUERY_BLOCK: usize = 128;

/// The factor of `‖p‖² + ‖q‖²` in the bound `B` on `|screened − computed|` for one pair.
/// With `γₙ = n u / (1 − n u)` (Higham's bound on a computed sum of `n` terms, in any order,
/// with or without fused multiply-adds): the dot product errs by at most
/// `γ_dim ‖p‖‖q‖ ≤ γ_dim (‖p‖² + ‖q‖²) / 2`, each norm by `γ_dim` of itself, the three
/// operations that combine them by `6u (‖p‖² + ‖q‖²)`, and the scan's distance (a rounded
/// difference squared per feature, then summed) by `γ_{dim+3} · 2 (‖p‖² + ‖q‖²)`: in all at
/// most `(4 γ_{dim+3} + 6u)`. Doubled, for the rounding of the bound itself and of the norms it
/// is applied to.
fn bound_factor(dim: usize) -> f64 {
    let u = f64::EPSILON / 2.0;
    let n = (dim + 3) as f64;
    let gamma = n * u / (1.0 - n * u);
    2.0 * (4.0 * gamma + 6.0 * u)
}

/// The `k` nearest of `points` (row-major, `dim` per row) to each row of `queries` (the same
/// layout, already scaled as the points are), nearest first under (computed distance, index):
/// for each query, what [`Best`] over every point gives.
pub(super) fn neighbours(points: &[f64], dim: usize, k: usize, queries: &[f64]) -> Vec<Vec<usize>> {
    let n = points.len().checked_div(dim).unwrap_or(0);
    if n == 0 || dim == 0 {
        return vec![Vec::new(); queries.len().checked_div(dim).unwrap_or(0)];
    }
    let norms: Vec<f64> = points
        .chunks_exact(dim)
        .map(|p| p.iter().map(|v| v * v).sum())
        .collect();
    let largest_norm = norms.iter().copied().fold(0.0, f64::max);
    let factor = bound_factor(dim);
    let p = MatRef::from_row_major_slice(points, n, dim);
    queries
        .par_chunks(QUERY_BLOCK * dim)
        .flat_map_iter(|block| {
            let m = block.len() / dim;
            // Column j: query j's dot products with every point, contiguous.
            let mut dots = Mat::<f64>::zeros(n, m);
            let q = MatRef::from_row_major_slice(block, m, dim);
            matmul(dots.as_mut(), Accum::Replace, p, q.transpose(), 1.0, Par::Seq);
            let mut screened = vec![0.0; n];
            let mut found = Vec::with_capacity(m);
            for (j, query) in block.chunks_exact(dim).enumerate() {
                let qn: f64 = query.iter().map(|v| v * v).sum();
                // The screened distances and their k smallest in one pass.
                let mut smallest = KSmallest::new(k);
                for ((s, &pn), &dot) in screened.iter_mut().zip(&norms).zip(dots.col_as_slice(j)) {
                    *s = pn + qn - 2.0 * dot;
                    smallest.offer(*s);
                }
                let kth = smallest.kth();
                let reach = kth + 2.0 * factor * (largest_norm + qn);
                let mut best = Best::new(k);
                for (i, (&s, p)) in screened.iter().zip(points.chunks_exact(dim)).enumerate() {
                    if s <= reach {
                        best.offer(squared_distance(p, query), i);
                    }
                }
                found.push(best.into_indices());
            }
            found
        })
        .collect()
}

/// The `k` smallest values offered so far, in order.
struct KSmallest {
    k: usize,
    values: Vec<f64>,
}

impl KSmallest {
    fn new(k: usize) -> Self {
        Self {
            k,
            values: Vec::with_capacity(k + 1),
        }
    }

    #[inline]
    fn offer(&mut self, v: f64) {
        if self.values.len() == self.k && self.values.last().is_some_and(|&w| v >= w) {
            return;
        }
        let at = self.values.partition_point(|&w| w <= v);
        self.values.insert(at, v);
        self.values.truncate(self.k);
    }

    /// The `k`-th smallest (the largest if fewer were offered), or +∞ for none.
    fn kth(&self) -> f64 {
        self.values.last().copied().unwrap_or(f64::INFINITY)
    }
}

/// The `k`-th smallest of `values` ([`KSmallest::kth`]).
#[cfg(test)]
fn kth_smallest(values: &[f64], k: usize) -> f64 {
    let mut smallest = KSmallest::new(k);
    values.iter().for_each(|&v| smallest.offer(v));
    smallest.kth()
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::strategy::Strategy;

    /// The exhaustive scan, for reference.
    fn scan(points: &[f64], dim: usize, k: usize, q: &[f64]) -> Vec<usize> {
        let mut best = Best::new(k);
        for (i, p) in points.chunks_exact(dim).enumerate() {
            best.offer(squared_distance(p, q), i);
        }
        best.into_indices()
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(64))]

        /// Coordinates from a handful of values make duplicates and equal distances (where only
        /// the index decides); wide ones make norms large beside the gaps, where a screen
        /// without its bound would misorder near neighbours.
        #[test]
        fn the_screened_search_returns_the_scans_neighbours(
            dim in 1usize..40,
            k in 1usize..6,
            cells in proptest::collection::vec(proptest::prop_oneof![
                4 => (0i32..3).prop_map(f64::from),
                1 => -1e4f64..1e4,
                1 => (0i32..3).prop_map(|v| 1e6 + f64::from(v) * 1e-6),
            ], 1..3000),
            queries in proptest::collection::vec(proptest::prop_oneof![
                3 => (-1i32..4).prop_map(|v| f64::from(v) * 0.5),
                1 => -1e4f64..1e4,
                1 => (0i32..3).prop_map(|v| 1e6 + f64::from(v) * 1e-6),
            ], 1..400),
        ) {
            use proptest::prelude::{prop_assert_eq, prop_assume};
            let n = cells.len() / dim;
            prop_assume!(n >= k);
            let points = &cells[..n * dim];
            let queries = &queries[..queries.len() / dim * dim];
            let found = neighbours(points, dim, k, queries);
            prop_assert_eq!(found.len(), queries.len() / dim);
            for (q, got) in queries.chunks_exact(dim).zip(&found) {
                prop_assert_eq!(got, &scan(points, dim, k, q));
            }
        }
    }

    #[test]
    fn the_kth_smallest_counts_repeats() {
        assert_eq!(kth_smallest(&[3.0, 1.0, 1.0, 2.0], 2), 1.0);
        assert_eq!(kth_smallest(&[3.0, 1.0, 1.0, 2.0], 3), 2.0);
        assert_eq!(kth_smallest(&[3.0], 2), 3.0);
        assert_eq!(kth_smallest(&[], 2), f64::INFINITY);
    }
}
