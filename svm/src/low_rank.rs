//! Low-rank kernel matrices: a pivoted incomplete Cholesky factor `K ≈ GGᵀ`, and the interior
//! point's Newton solves on it.
//!
//! Why: a smooth kernel on low-dimensional inputs has a numerically low-rank Gram matrix. The
//! needle's RBF (γ = 30 on two inputs in the unit box) is within 1e-12 of a rank-220 matrix at
//! n = 8,000, and the rank stops growing with n once the inputs fill their box. On `GGᵀ` an
//! interior-point iteration costs O(n r²) instead of the dense O(n³), and memory is n·r instead
//! of n², so the interior point's tens of iterations reach capture sizes that SMO, whose
//! iteration count grows with n and C, takes minutes over. The factor only guides the solve: the
//! returned model is finished and certified on the exact kernel (`crate::fit`).
//!
//! Hand-written because the factorisation must stop at a tolerance on the residual diagonal,
//! evaluating the kernel one pivot column at a time; linear-algebra crates factor a matrix that
//! is already formed.

use faer::linalg::matmul::triangular::{self, BlockStructure};
use faer::linalg::solvers::Solve;
use faer::{Accum, Mat, Par, Side};
use rayon::prelude::*;

use super::ipm::NewtonOperator;
use super::kernel::{Kernel, RowSource};

/// Rows per parallel task.
const CHUNK: usize = 2048;

/// What a fit by this path reports as its solver.
pub(crate) const NAME: &str = "low-rank interior point + exact finish";

/// Samples from which `Solver::Auto` tries the factor: below, the dense interior point's n³ is
/// already small. Measured on the needle capture: at n = 550–950 the factor's path took
/// 0.027–0.036 s where the dense interior point took 0.028–0.119 s, rising as n³; at n = 500
/// the factor stops at its rank limit ([`max_rank`], 125) within milliseconds and the dense
/// path runs (0.027 s).
pub(crate) const MIN_SAMPLES: usize = 500;

/// The tightest factor: its largest residual diagonal entry, relative to the kernel's diagonal.
/// A residual E moves the fitted values by at most `√(Eᵢᵢ · tr E) · ‖β‖ ≤ tolerance · n · C`
/// (Cauchy–Schwarz on the PSD E): at 1e-14, with n = 1e5 samples all at |β| = C = 1e3, that is
/// 1e-6 of a unit target, so the factor's active set is the exact kernel's except for samples
/// that close to the tube, which the exact finish sorts out.
pub(crate) const TOLERANCE: f64 = 1e-14;

/// The first factor's bound on that shift of the fitted values, relative to the targets' scale.
const FIRST_SHIFT: f64 = 1e-4;

/// The loosest first factor: rank, and with it the iteration's n·r², grow slowly as the
/// tolerance tightens (n = 1,000 needle samples: r = 220 at 1e-14), so looser buys little.
const LOOSEST: f64 = 1e-9;

/// The tolerances to factor at, in order: the loosest whose worst-case shift of the fitted
/// values (`tolerance · n · C`) is [`FIRST_SHIFT`] of the targets' scale `y_scale`, within
/// [[`TOLERANCE`], [`LOOSEST`]]; then [`TOLERANCE`], for when the first factor's active set
/// does not finish exactly (the shift bound is a worst case, usually far from reached). On the
/// needle at n = 1,000 the first is 1e-9 and the fit takes 0.09 s instead of 0.13 s at 1e-14
/// (median of five, `palpus bench svr-scale`).
pub(crate) fn tolerances(n: usize, c: f64, y_scale: f64) -> Vec<f64> {
    let first = (FIRST_SHIFT * y_scale / (n as f64 * c)).clamp(TOLERANCE, LOOSEST);
    if first > TOLERANCE {
        vec![first, TOLERANCE]
    } else {
        vec![TOLERANCE]
    }
}

/// Bytes the factor may hold.
const MAX_FACTOR_BYTES: usize = 512 << 20;

/// The largest rank worth factoring for n samples: a third of n, where an iteration's n·r² is
/// a third of the dense Cholesky's n³/3 (at a quarter, the needle log at varying speed, whose
/// factor needs more than a quarter of n at n = 555–754, fell back to the dense interior point:
/// 44–52 ms there, against 43 ms at 879; with a third, 22–34 ms); at most 2,000 (the r × r
/// capacitance matrix's r³ per iteration), and within [`MAX_FACTOR_BYTES`].
pub(crate) fn max_rank(n: usize) -> usize {
    (n / 3).min(2000).min(MAX_FACTOR_BYTES / 8 / n.max(1))
}

/// `K ≈ GGᵀ`, `G` n × r kept as its r columns.
#[derive(Debug, Clone)]
pub(crate) struct LowRank {
    columns: Vec<Vec<f64>>,
    n: usize,
}

impl LowRank {
    /// The rank r.
    pub fn rank(&self) -> usize {
        self.columns.len()
    }
}

/// Why [`pivoted_cholesky`] gave no factor.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum FactorMiss {
    /// It reached `max_rank` columns with its residual still falling fast enough to reach the
    /// tolerance later: the kernel is low-rank, just not within the rank allowed at this n.
    RankLimit,
    /// Its residual's fall slowed too much to reach the tolerance by `max_rank`
    /// ([`out_of_reach`]): the kernel is far from low-rank.
    SlowFall,
    /// A kernel value was not finite.
    NotFinite,
}

/// Pivoted incomplete Cholesky of the kernel matrix of the `n = x.len() / dim` inputs: greedy
/// pivots on the largest residual diagonal until every residual diagonal entry is at most
/// `tolerance` times the largest kernel diagonal; a [`FactorMiss`] when that would take more
/// than `max_rank` columns (the matrix is not low-rank enough for the factor to pay) or a value
/// is not finite.
pub(crate) fn pivoted_cholesky(
    kernel: &Kernel,
    x: &[f64],
    dim: usize,
    tolerance: f64,
    max_rank: usize,
) -> Result<LowRank, FactorMiss> {
    factor_up_to(kernel, x, dim, tolerance, max_rank, max_rank, Projection::Hopeful)
}

/// Columns [`numerically_full_rank`] factors: its third checkpoint (16, 32, 64), the first at
/// which the residual's fall has a trend.
pub(crate) const PROBE_COLUMNS: usize = 64;

/// Whether the kernel matrix of the inputs is numerically full-rank at `tolerance`: after
/// [`PROBE_COLUMNS`] columns of [`pivoted_cholesky`], the residual's fall, projected as it
/// has been changing ([`Projection::AsMeasured`]), would still miss the tolerance with as many
/// columns as samples. It costs those columns, a small part of a dense solve where it is asked
/// (below [`MIN_SAMPLES`]); `false` below twice as many samples, where nothing is measured.
/// On 350–476 samples of Friedman #1 (5 or 10 uniform inputs, γ = 1) the largest residual was
/// still above half the diagonal at rank 64, falling at 0.010 per column at ranks 16–64 (the
/// tolerance 1e-9 would take some 2,000 columns); on the needle capture's two inputs (γ = 30)
/// it was 3.6e-3 and falling faster each doubling (0.084, then 0.127 per column).
pub(crate) fn numerically_full_rank(kernel: &Kernel, x: &[f64], dim: usize, tolerance: f64) -> bool {
    let n = x.len() / dim.max(1);
    n >= 2 * PROBE_COLUMNS
        && matches!(
            factor_up_to(
                kernel,
                x,
                dim,
                tolerance,
                n,
                PROBE_COLUMNS,
                Projection::AsMeasured
            ),
            Err(FactorMiss::SlowFall)
        )
}

/// How [`out_of_reach`] projects a residual's fall whose rate has grown.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Projection {
    /// A growing rate may grow on without bound: never out of reach (the factor itself, which
    /// would rather spend columns than give up on a low-rank kernel).
    Hopeful,
    /// A growing rate grows on by the ratio measured, as a shrinking one shrinks on.
    AsMeasured,
}

/// [`pivoted_cholesky`], stopping with [`FactorMiss::RankLimit`] at `columns_at_most` columns
/// while judging the residual's fall against `max_rank`, projected as `projection` says.
fn factor_up_to(
    kernel: &Kernel,
    x: &[f64],
    dim: usize,
    tolerance: f64,
    max_rank: usize,
    columns_at_most: usize,
    projection: Projection,
) -> Result<LowRank, FactorMiss> {
    let n = x.len() / dim;
    let row = |i: usize| &x[i * dim..(i + 1) * dim];
    let mut diag: Vec<f64> = (0..n).map(|i| kernel.eval(row(i), row(i))).collect();
    if diag.iter().any(|d| !d.is_finite()) {
        return Err(FactorMiss::NotFinite);
    }
    let scale = diag.iter().fold(0.0f64, |m, d| m.max(d.abs()));
    let stop = tolerance * scale.max(f64::MIN_POSITIVE);
    let mut columns: Vec<Vec<f64>> = Vec::new();
    // Each new column is a kernel row: an RBF's come a feature at a time, in vector loops.
    let source = RowSource::new(kernel, x, dim);
    // The largest residual at the checkpoint ranks (16, 32, 64, …) so far.
    let mut checkpoints: Vec<(usize, f64)> = Vec::new();
    loop {
        let (pivot, largest) =
            diag.iter().enumerate().fold(
                (0, f64::NEG_INFINITY),
                |best, (i, &d)| if d > best.1 { (i, d) } else { best },
            );
        if largest <= stop {
            return Ok(LowRank { columns, n });
        }
        let rank = columns.len();
        if rank >= max_rank {
            return Err(FactorMiss::RankLimit);
        }
        if rank >= 16 && rank.is_power_of_two() {
            checkpoints.push((rank, largest));
            if out_of_reach(&checkpoints, max_rank, stop, projection) {
                return Err(FactorMiss::SlowFall);
            }
        }
        if rank >= columns_at_most {
            return Err(FactorMiss::RankLimit);
        }
        let pivot_row: Vec<f64> = columns.iter().map(|g| g[pivot]).collect();
        let xp = row(pivot);
        let inv = 1.0 / largest.sqrt();
        let mut column = vec![0.0; n];
        column.par_chunks_mut(CHUNK).enumerate().for_each(|(chunk, out)| {
            let start = chunk * CHUNK;
            let end = start + out.len();
            source.row(xp, start, out);
            for (g, &gp) in columns.iter().zip(&pivot_row) {
                for (v, gi) in out.iter_mut().zip(&g[start..end]) {
                    *v -= gi * gp;
                }
            }
            for v in out.iter_mut() {
                *v *= inv;
            }
        });
        if column.iter().any(|v| !v.is_finite()) {
            return Err(FactorMiss::NotFinite);
        }
        for (d, v) in diag.iter_mut().zip(&column) {
            *d -= v * v;
        }
        // The pivot's own residual is 0 by construction; rounding must not let it be chosen
        // again.
        diag[pivot] = 0.0;
        columns.push(column);
    }
}

/// Whether a factor whose largest residual was `checkpoints` (rank, residual) at ranks 16, 32,
/// 64, … cannot reach `stop` by `max_rank`: its kernel is not low-rank enough, and the columns
/// it would add before giving up at its limit cost n·rank² for nothing. The residual's log falls
/// at a rate per column that changes from one doubling of the rank to the next; while the rate
/// grows the factor goes on ([`Projection::Hopeful`]), and where it shrinks, the rate is
/// projected to go on shrinking by the same ratio each doubling, and the factor gives up if that
/// projected fall misses `stop` ([`Projection::AsMeasured`] projects a growing rate so too).
/// On the needle's 2-D inputs the rate grows (the residual fell by 28 from rank 32 to 64 and by
/// 1.5e5 from 64 to 128 at n = 3,000); on Friedman #1's five uniform inputs it shrinks by about
/// 0.65 per doubling, and the factor went to its limit before it failed: 1,000 columns, 1.3 s,
/// at n = 4,000; 2,000 columns, 21 s, at n = 10,000, where the projection from rank 512 said
/// its residual would still be 1e-5 at 2,000 (from 1024 it was 1.6e-6, the tolerance 1e-9).
fn out_of_reach(checkpoints: &[(usize, f64)], max_rank: usize, stop: f64, projection: Projection) -> bool {
    let [.., (r0, l0), (r1, l1), (r2, l2)] = *checkpoints else {
        return false;
    };
    if !(l0 > 0.0 && l1 > 0.0 && l2 > 0.0 && stop > 0.0) {
        return false;
    }
    let rate_before = (l0 / l1).ln() / (r1 - r0) as f64;
    let rate = (l1 / l2).ln() / (r2 - r1) as f64;
    if !(rate_before > 0.0 && rate > 0.0) || (rate >= rate_before && projection == Projection::Hopeful) {
        return false;
    }
    let change = rate / rate_before;
    let (mut at, mut step_rate, mut fall) = (r2, rate, 0.0);
    while at < max_rank {
        step_rate *= change;
        let next = (2 * at).min(max_rank);
        fall += step_rate * (next - at) as f64;
        at = next;
    }
    fall < (l2 / stop).ln()
}

/// `K + diag(h)` for `K = GGᵀ`, by the Woodbury identity: `D⁻¹ − D⁻¹G (I + GᵀD⁻¹G)⁻¹ GᵀD⁻¹`.
#[derive(Debug)]
pub(crate) struct LowRankFactor {
    h_inv: Vec<f64>,
    capacitance: faer::linalg::solvers::Llt<f64>,
}

impl LowRank {
    /// `φ(G)ᵀ v`, with `φ` applied to each entry of G (identity, or `abs` for a bound).
    fn transpose_times(&self, v: &[f64], phi: impl Fn(f64) -> f64 + Sync) -> Vec<f64> {
        // In partial sums: one running sum waits on each addition's latency in turn. With this
        // and the factor's W built over slices, the needle's low-rank fits at n = 555–3,000
        // took 14–23 % less time (the fastest of 20 fits, one thread, against the build before).
        self.columns
            .par_iter()
            .map(|g| crate::kernel::lane_sum(g, v, |a, b| phi(a) * b))
            .collect()
    }

    /// `out = φ(G) t`.
    fn times(&self, t: &[f64], out: &mut [f64], phi: impl Fn(f64) -> f64 + Sync) {
        out.par_chunks_mut(CHUNK).enumerate().for_each(|(chunk, out)| {
            let start = chunk * CHUNK;
            let end = start + out.len();
            out.fill(0.0);
            for (g, &tk) in self.columns.iter().zip(t) {
                for (o, gi) in out.iter_mut().zip(&g[start..end]) {
                    *o += phi(*gi) * tk;
                }
            }
        });
    }
}

fn identity(v: f64) -> f64 {
    v
}

impl NewtonOperator for LowRank {
    type Factor = LowRankFactor;
    /// An iteration costs n·r², far less than an exact finish's attempt (its rows of the exact
    /// kernel and its bordered solves). Counted in instructions (callgrind) on the three needle
    /// problems' training sets at n = 555, 647, 734: offered from 1e-7 instead, the fits took
    /// the same iterations and up to 31 % more instructions (5–11 % at n = 555).
    const OFFER_BELOW: f64 = 1e-8;

    fn mat_vec_with_abs(&self, v: &[f64], out: &mut [f64], out_abs: &mut [f64]) {
        self.mat_vec(v, out);
        // |GGᵀ| ≤ |G||G|ᵀ elementwise.
        let abs_v: Vec<f64> = v.iter().map(|x| x.abs()).collect();
        let t = self.transpose_times(&abs_v, f64::abs);
        self.times(&t, out_abs, f64::abs);
    }

    fn diag_max(&self) -> f64 {
        (0..self.n)
            .map(|i| self.columns.iter().map(|g| g[i] * g[i]).sum::<f64>())
            .fold(0.0, f64::max)
    }

    fn factor(&self, h: &[f64], _spare: Option<LowRankFactor>) -> Option<LowRankFactor> {
        let r = self.rank();
        let h_inv: Vec<f64> = h.iter().map(|v| 1.0 / v).collect();
        if h_inv.iter().any(|v| !v.is_finite() || *v <= 0.0) {
            return None;
        }
        // I + GᵀD⁻¹G = I + WᵀW with W = D^{-1/2}G: the iteration's main cost (n r² flops), so
        // only its lower half (all the Cholesky reads), summed over one row block per core.
        let block = self.n.div_ceil(rayon::current_num_threads()).max(256);
        let gram = (0..self.n.div_ceil(block))
            .into_par_iter()
            .map(|chunk| {
                let start = chunk * block;
                let rows = block.min(self.n - start);
                let scale: Vec<f64> = h_inv[start..start + rows].iter().map(|v| v.sqrt()).collect();
                // Column by column over slices, not an element-wise `from_fn` that indexes G's
                // columns for every entry.
                let mut w = Mat::<f64>::zeros(rows, r);
                for (k, g) in self.columns.iter().enumerate() {
                    let g = &g[start..start + rows];
                    for ((w, g), s) in w.col_as_slice_mut(k).iter_mut().zip(g).zip(&scale) {
                        *w = g * s;
                    }
                }
                let mut part = Mat::<f64>::zeros(r, r);
                triangular::matmul(
                    part.as_mut(),
                    BlockStructure::TriangularLower,
                    Accum::Replace,
                    w.transpose(),
                    BlockStructure::Rectangular,
                    w.as_ref(),
                    BlockStructure::Rectangular,
                    1.0,
                    Par::Seq,
                );
                part
            })
            .reduce(|| Mat::<f64>::zeros(r, r), |a, b| a + b);
        let mut capacitance = gram;
        for k in 0..r {
            capacitance[(k, k)] += 1.0;
        }
        let capacitance = capacitance.llt(Side::Lower).ok()?;
        Some(LowRankFactor { h_inv, capacitance })
    }

    fn solve_columns(&self, factor: &LowRankFactor, columns: &mut [f64]) {
        for column in columns.chunks_mut(self.n.max(1)) {
            let x = self.solve(factor, column);
            column.copy_from_slice(&x);
        }
    }
}

impl LowRank {
    /// `out = GGᵀ v`.
    fn mat_vec(&self, v: &[f64], out: &mut [f64]) {
        let t = self.transpose_times(v, identity);
        self.times(&t, out, identity);
    }

    /// `(D + GGᵀ)⁻¹ rhs` by Woodbury, through the capacitance factor.
    fn solve(&self, factor: &LowRankFactor, rhs: &[f64]) -> Vec<f64> {
        let u: Vec<f64> = rhs.iter().zip(&factor.h_inv).map(|(b, d)| b * d).collect();
        let t = self.transpose_times(&u, identity);
        let t = Mat::<f64>::from_fn(t.len(), 1, |k, _| t[k]);
        let s = factor.capacitance.solve(&t);
        let s: Vec<f64> = (0..s.nrows()).map(|k| s[(k, 0)]).collect();
        let mut gs = vec![0.0; self.n];
        self.times(&s, &mut gs, identity);
        u.iter()
            .zip(&gs)
            .zip(&factor.h_inv)
            .map(|((ui, gi), d)| ui - d * gi)
            .collect()
    }
}

/// `Kβ` on the exact kernel, over the samples whose β is not 0, on every core.
pub(crate) fn kernel_times(kernel: &Kernel, x: &[f64], dim: usize, beta: &[f64]) -> Vec<f64> {
    let n = beta.len();
    let row = |i: usize| &x[i * dim..(i + 1) * dim];
    let samples: Vec<usize> = (0..n).filter(|&j| beta[j] != 0.0).collect();
    let support: Vec<f64> = samples.iter().map(|&j| beta[j]).collect();
    let source = RowSource::of(kernel, x, dim, &samples);
    let mut out = vec![0.0; n];
    out.par_chunks_mut(CHUNK / 8).enumerate().for_each_init(
        || vec![0.0; support.len()],
        |values, (chunk, out)| {
            let start = chunk * (CHUNK / 8);
            for (o, v) in out.iter_mut().enumerate() {
                source.row(row(start + o), 0, values);
                *v = crate::kernel::dot(values, &support);
            }
        },
    );
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_factor_gives_up_early_only_where_its_residual_falls_ever_slower() {
        // The needle's residuals at ranks 16, 32, 64, 128 (n = 3,000): the fall quickens.
        let needle = [(16, 0.796), (32, 0.277), (64, 9.93e-3), (128, 6.41e-8)];
        for k in 1..=needle.len() {
            assert!(
                !out_of_reach(&needle[..k], 750, 9.1e-10, Projection::Hopeful),
                "needle at {k}"
            );
        }
        // Friedman #1's (n = 4,000): the fall slows by about 0.6 each doubling.
        let friedman = [(16, 0.506), (32, 0.178), (64, 5.13e-2), (128, 8.69e-3)];
        for projection in [Projection::Hopeful, Projection::AsMeasured] {
            assert!(
                !out_of_reach(&friedman[..2], 1000, 1e-9, projection),
                "two points say nothing of a trend"
            );
            assert!(out_of_reach(&friedman[..3], 1000, 1e-9, projection));
            // The same slowing fall, but a target it reaches in time.
            assert!(!out_of_reach(&friedman[..3], 1000, 1e-3, projection));
        }
    }

    #[test]
    fn a_growing_rate_is_out_of_reach_only_where_projected_as_measured() {
        // Friedman #1 with 10 inputs at n = 350: the rate barely grows (0.0103, then 0.0104
        // per column), some 3 of the 20 the tolerance needs by rank 350.
        let flat = [(16, 0.856), (32, 0.726), (64, 0.520)];
        assert!(!out_of_reach(&flat, 350, 1e-9, Projection::Hopeful));
        assert!(out_of_reach(&flat, 350, 1e-9, Projection::AsMeasured));
        // The needle capture at n = 350: the rate grows by half each doubling and reaches
        // the tolerance well before rank 350, but not by 116 (the factor's limit there).
        let needle = [(16, 0.786), (32, 0.206), (64, 3.56e-3)];
        assert!(!out_of_reach(&needle, 350, 1e-9, Projection::AsMeasured));
        assert!(out_of_reach(&needle, 116, 1e-9, Projection::AsMeasured));
    }

    #[test]
    fn full_rank_is_told_from_low_rank_in_the_probes_columns() {
        // Five uniform inputs at γ = 1, as Friedman #1, against two at γ = 30, as the needle.
        let n = 400;
        let mut rng = capture::rng::SplitMix64::new(5);
        let uniform5: Vec<f64> = (0..n * 5).map(|_| rng.next_f64()).collect();
        assert!(numerically_full_rank(
            &Kernel::Rbf { gamma: 1.0 },
            &uniform5,
            5,
            1e-9
        ));
        assert!(!numerically_full_rank(
            &Kernel::Rbf { gamma: 30.0 },
            &inputs(n),
            2,
            1e-9
        ));
        // Too few samples to measure a trend: not called full rank.
        assert!(!numerically_full_rank(
            &Kernel::Rbf { gamma: 1.0 },
            &uniform5[..100 * 5],
            5,
            1e-9
        ));
    }

    fn inputs(n: usize) -> Vec<f64> {
        // Deterministic points filling the unit square.
        (0..n)
            .flat_map(|i| {
                let t = i as f64;
                [(t * 0.618_033_988_75).fract(), (t * 0.754_877_666_2).fract()]
            })
            .collect()
    }

    #[test]
    fn the_first_factor_is_as_loose_as_its_shift_bound_allows_and_the_tightest_follows() {
        // 1e-4 · 2.7 / (1e3 · 1e2) = 2.7e-9, beyond the loosest allowed.
        assert_eq!(tolerances(1_000, 100.0, 2.7), vec![LOOSEST, TOLERANCE]);
        // 1e-4 · 2 / (1e5 · 1e2) = 2e-11: the bound itself.
        let t = tolerances(100_000, 100.0, 2.0);
        assert_eq!(t.len(), 2);
        assert!((t[0] - 2e-11).abs() < 1e-24, "{t:?}");
        // At C = 1e11 the bound asks for less than the tightest: only the tightest.
        assert_eq!(tolerances(1_000, 1e11, 2.0), vec![TOLERANCE]);
    }

    #[test]
    fn the_factor_meets_its_tolerance_on_every_entry() {
        let n = 600;
        let x = inputs(n);
        let kernel = Kernel::Rbf { gamma: 10.0 };
        let lr = pivoted_cholesky(&kernel, &x, 2, 1e-10, n).unwrap();
        assert!(lr.rank() < n / 2, "rank {}", lr.rank());
        let mut worst: f64 = 0.0;
        for i in 0..n {
            for j in 0..n {
                let approx: f64 = lr.columns.iter().map(|g| g[i] * g[j]).sum();
                worst = worst.max((approx - kernel.eval(&x[2 * i..2 * i + 2], &x[2 * j..2 * j + 2])).abs());
            }
        }
        // A PSD residual's entries are bounded by its largest diagonal entry.
        assert!(worst <= 1e-10 * (1.0 + 1e-6), "worst entry error {worst:e}");
    }

    #[test]
    fn a_rank_budget_too_small_is_refused() {
        let x = inputs(300);
        assert!(pivoted_cholesky(&Kernel::Rbf { gamma: 1e4 }, &x, 2, 1e-12, 50).is_err());
    }

    #[test]
    fn woodbury_solves_match_the_dense_solve() {
        let x = inputs(300);
        let kernel = Kernel::Rbf { gamma: 5.0 };
        let lr = pivoted_cholesky(&kernel, &x, 2, 1e-14, 300).unwrap();
        let n = 300;
        let h: Vec<f64> = (0..n).map(|i| 10f64.powi((i % 9) as i32 - 6)).collect();
        let rhs: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin()).collect();
        let factor = lr.factor(&h, None).unwrap();
        let sol = lr.solve(&factor, &rhs);
        // Residual of (GGᵀ + diag h) sol = rhs, on the factor itself.
        let mut k_sol = vec![0.0; n];
        lr.mat_vec(&sol, &mut k_sol);
        // Relative to the terms it balances: the capacitance matrix's condition grows with
        // the spread of h (here 1e8), and so does the solve's relative error.
        let worst = (0..n)
            .map(|i| {
                (k_sol[i] + h[i] * sol[i] - rhs[i]).abs() / (k_sol[i].abs() + (h[i] * sol[i]).abs() + 1.0)
            })
            .fold(0.0, f64::max);
        assert!(worst < 1e-6, "residual {worst:e}");
        let exact = kernel_times(&kernel, &x, 2, &sol);
        let off = (0..n).map(|i| (exact[i] - k_sol[i]).abs()).fold(0.0, f64::max);
        let norm: f64 = sol.iter().map(|v| v * v).sum::<f64>().sqrt();
        assert!(off <= 1e-14 * norm * n as f64, "GGᵀ vs K: {off:e}");
    }
}
