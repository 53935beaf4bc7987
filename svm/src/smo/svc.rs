//! The binary C-SVC on the crate's SMO: kernel rows cached by position over the active prefix
//! (libsvm's `SVC_Q`), so that a fit with a few dozen active variables computes and reads a
//! few dozen values per row.

use super::solver::{QMatrix, solve};
use super::{NAME, SmoSettings, SmoSolution};
use crate::error::{KKT_VIOLATION, SvmError};
use crate::kernel::Kernel;

/// The signed kernel rows `Qₜₛ = yₜ yₛ K(xₜ, xₛ)` by position, computed when first asked for
/// (as far as asked) and kept within a byte budget, least recently used rows dropped first.
struct PrefixQ<'a> {
    kernel: Kernel,
    /// The training points, n × dim, in the caller's order.
    points: &'a [f64],
    dim: usize,
    /// Point at each position.
    at: Vec<usize>,
    /// Label at each position.
    y: Vec<f64>,
    /// Cached prefix of each position's row (empty: not cached).
    rows: Vec<Vec<f64>>,
    last_used: Vec<u64>,
    clock: u64,
    /// Values cached, and the most to keep.
    held: usize,
    budget: usize,
    /// Ḡ by position, swapped with its positions.
    bar: Vec<f64>,
}

impl PrefixQ<'_> {
    fn point(&self, position: usize) -> &[f64] {
        let t = self.at[position];
        &self.points[t * self.dim..(t + 1) * self.dim]
    }
}

impl QMatrix for PrefixQ<'_> {
    fn diagonal(&self, t: usize) -> f64 {
        let x = self.point(t);
        self.kernel.eval(x, x)
    }

    /// The handle is the position: a row stays until evicted, and the least recently used
    /// other row is never the one fetched just before (the budget holds two whole rows).
    fn fetch(&mut self, i: usize, len: usize) -> usize {
        self.clock += 1;
        self.last_used[i] = self.clock;
        let have = self.rows[i].len();
        if have >= len {
            return i;
        }
        // Room first: drop least recently used rows (never `i`) until the extension fits.
        while self.held + (len - have) > self.budget {
            let victim = (0..self.rows.len())
                .filter(|&r| r != i && !self.rows[r].is_empty())
                .min_by_key(|&r| self.last_used[r]);
            let Some(v) = victim else { break };
            self.held -= self.rows[v].len();
            self.rows[v] = Vec::new();
        }
        let mut row = std::mem::take(&mut self.rows[i]);
        row.reserve_exact(len - have);
        let (xi, yi) = (self.point(i), self.y[i]);
        for s in have..len {
            row.push(yi * self.y[s] * self.kernel.eval(xi, self.point(s)));
        }
        self.held += len - have;
        self.rows[i] = row;
        i
    }

    fn get(&self, handle: usize) -> &[f64] {
        &self.rows[handle]
    }

    fn add_to_bar(&mut self, t: usize, coefficient: f64) {
        let all = self.at.len();
        let h = self.fetch(t, all);
        for (b, q) in self.bar.iter_mut().zip(&self.rows[h][..all]) {
            *b += coefficient * q;
        }
    }

    fn bar(&self, t: usize) -> f64 {
        self.bar[t]
    }

    /// Swaps positions `i < j` in every cached row; a row cached past `i` but not past `j`
    /// is dropped (libsvm's rule: it cannot be swapped in place).
    fn swap(&mut self, i: usize, j: usize) {
        self.rows.swap(i, j);
        self.last_used.swap(i, j);
        self.at.swap(i, j);
        self.y.swap(i, j);
        self.bar.swap(i, j);
        for r in 0..self.rows.len() {
            let len = self.rows[r].len();
            if len > j {
                self.rows[r].swap(i, j);
            } else if len > i {
                self.held -= len;
                self.rows[r] = Vec::new();
            }
        }
    }
}

/// Solves the binary C-SVC dual `min ½ αᵀQα − eᵀα`, `yᵀα = 0`, `0 ≤ α ≤ C` over the points
/// `points[t·dim..]` for `t` in `subset`, labelled `y` (±1), with `settings` (C, stop,
/// shrinking, selection rule, iteration budget), keeping at most `cache_bytes` of kernel rows
/// (two whole rows at least). α comes back in `subset`'s order. At the iteration limit:
/// [`SvmError::NotConverged`] with the KKT violation reached (a C-SVC has no certificate).
///
/// # Panics
/// If `y` and `subset` differ in length, `dim` is 0 or a subset index is past the points.
pub fn solve_svc(
    kernel: Kernel,
    points: &[f64],
    dim: usize,
    subset: &[usize],
    y: &[f64],
    settings: &SmoSettings,
    cache_bytes: usize,
) -> Result<SmoSolution, SvmError> {
    let n = subset.len();
    assert!(
        y.len() == n && dim > 0 && subset.iter().all(|&t| (t + 1) * dim <= points.len()),
        "C-SVC: {} labels for {n} vectors of dimension {dim} among {} values",
        y.len(),
        points.len()
    );
    let mut q = PrefixQ {
        kernel,
        points,
        dim,
        at: subset.to_vec(),
        y: y.to_vec(),
        rows: vec![Vec::new(); n],
        last_used: vec![0; n],
        clock: 0,
        held: 0,
        // Two whole rows at least: an update reads a pair's.
        budget: (cache_bytes / size_of::<f64>()).max(2 * n),
        bar: vec![0.0; n],
    };
    let sol = solve(&mut q, y, &vec![-1.0; n], settings, &mut |_, _, _| None)?;
    if !sol.converged {
        return Err(SvmError::NotConverged {
            solver: NAME,
            iterations: sol.iterations,
            gap: sol.violation,
            measure: KKT_VIOLATION,
            tolerance: sol.stop,
        });
    }
    Ok(sol)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{GramRows, SelectionCurvature, solve_smo};

    /// Two overlapping classes in 3-D, so that a soft margin leaves vectors free, at both
    /// bounds, and shrinking has something to shrink (a deterministic scramble, no RNG crate).
    fn problem(n: usize) -> (Vec<f64>, Vec<f64>) {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut points = Vec::with_capacity(3 * n);
        let mut y = Vec::with_capacity(n);
        for t in 0..n {
            let label = if t % 3 == 0 { -1.0 } else { 1.0 };
            for d in 0..3 {
                let centre = if d == 0 { 0.4 * label } else { 0.0 };
                points.push(centre + next() - 0.5);
            }
            y.push(label);
        }
        (points, y)
    }

    const KERNEL: Kernel = Kernel::Polynomial {
        gamma: 0.5,
        coef0: 1.0,
        degree: 2,
    };

    fn settings(c: f64, stop: f64, max_iterations: usize) -> SmoSettings {
        SmoSettings::builder()
            .c(c)
            .stop(stop)
            .selection(SelectionCurvature::NonPositiveToTau)
            .shrinking(true)
            .max_iterations(max_iterations)
            .build()
            .expect("settings")
    }

    #[test]
    fn the_prefix_cache_and_a_gram_matrix_give_the_same_machine() {
        let (points, y) = problem(300);
        let n = y.len();
        // The subset in a scrambled order, so positions and the caller's order differ.
        let subset: Vec<usize> = (0..n).map(|t| (t * 7) % n).collect();
        let ys: Vec<f64> = subset.iter().map(|&t| y[t]).collect();
        let (c, stop) = (5.0, 1e-9);
        let ours =
            solve_svc(KERNEL, &points, 3, &subset, &ys, &settings(c, stop, 0), 64 << 20).expect("converges");
        let mut gram = vec![0.0; n * n];
        for a in 0..n {
            for b in 0..n {
                let (pa, pb) = (subset[a], subset[b]);
                gram[a * n + b] = KERNEL.eval(&points[3 * pa..3 * pa + 3], &points[3 * pb..3 * pb + 3]);
            }
        }
        // Without shrinking, through whole Gram rows: a different path to the same optimum.
        let plain = SmoSettings::builder()
            .c(c)
            .stop(stop)
            .selection(SelectionCurvature::NonPositiveToTau)
            .build()
            .expect("settings");
        let mut rows = GramRows::new(&gram, n).expect("square");
        let theirs = solve_smo(&mut rows, &ys, &vec![-1.0; n], &plain).expect("converges");
        let worst = ours
            .alpha
            .iter()
            .zip(&theirs.alpha)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(worst < 1e-6 * c, "largest α difference {worst}");
        assert!(
            (ours.rho - theirs.rho).abs() < 1e-6,
            "{} vs {}",
            ours.rho,
            theirs.rho
        );
        let bounded = ours.alpha.iter().filter(|&&a| a >= c).count();
        let free = ours.alpha.iter().filter(|&&a| a > 0.0 && a < c).count();
        assert!(bounded > 10 && free > 3, "{bounded} at C, {free} free");
        // Feasible: in the box, and yᵀα = 0.
        assert!(ours.alpha.iter().all(|a| (0.0..=c).contains(a)));
        let balance: f64 = ours.alpha.iter().zip(&ys).map(|(a, y)| a * y).sum();
        assert!(balance.abs() < 1e-9, "{balance}");
    }

    #[test]
    fn a_cache_of_two_rows_gives_the_same_solution() {
        let (points, y) = problem(200);
        let subset: Vec<usize> = (0..y.len()).collect();
        let solve = |bytes, max| solve_svc(KERNEL, &points, 3, &subset, &y, &settings(5.0, 1e-3, max), bytes);
        let roomy = solve(64 << 20, 0).expect("converges");
        // Rows dropped and recomputed (and dropped by swaps) change the cost, not the path.
        let tight = solve(0, 0).expect("converges");
        assert_eq!(roomy, tight);
        assert!(roomy.iterations > 50, "{}", roomy.iterations);
        // Too few iterations is no answer, but the violation it reached.
        let short = solve(64 << 20, 10);
        assert!(
            matches!(short, Err(SvmError::NotConverged { gap, measure, .. }) if gap > 1e-3 && gap.is_finite() && measure == KKT_VIOLATION),
            "{short:?}"
        );
    }
}
