//! The binary C-SVC's SMO, laid out as libsvm's `Solver` lays it out, so that an iteration
//! costs what the active set costs.
//!
//! The algorithm is [`svm::solve_smo`]'s (Fan, Chen & Lin's second-order working set, libsvm's
//! pair update, shrinking and ρ), and it stops at the same violation. What differs is the
//! memory layout: [`svm::KernelRows`] hands out rows over every sample in the original order,
//! so each iteration copies two whole rows and reads the active set through an index list. A
//! surface pair at a soft margin needs ~10⁵–10⁶ iterations (scikit-learn's SVC takes as many)
//! while shrinking leaves a few dozen variables active, so those full-length copies were most
//! of the fit. Here, as in libsvm, shrinking swaps the active variables to the front of every
//! array and of every cached row, and an iteration reads two cached prefixes of the rows and
//! the front of the arrays, contiguously.

use svm::{Kernel, PairStep};

/// Curvature floor for non-positive-definite pairs (libsvm's τ).
const TAU: f64 = 1e-12;

/// Independent accumulators in the working-set scans.
const LANES: usize = 4;

/// The solution of one binary C-SVC dual.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct BinarySolution {
    /// α, one per training vector in the order given, in `[0, C]`.
    pub alpha: Vec<f64>,
    /// libsvm's ρ: the decision function is `Σ yₜαₜK(xₜ, x) − ρ`.
    pub rho: f64,
    /// Pair updates made.
    pub iterations: usize,
}

/// The signed kernel rows `Q_ts = y_t y_s K(x_t, x_s)` by position, computed when first asked
/// for (as far as asked) and kept within a byte budget, least recently used rows dropped first.
struct QRows<'a> {
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
}

impl QRows<'_> {
    fn point(&self, position: usize) -> &[f64] {
        let t = self.at[position];
        &self.points[t * self.dim..(t + 1) * self.dim]
    }

    /// Makes row `i` cached up to `len` and marks it used.
    fn ensure(&mut self, i: usize, len: usize) {
        self.clock += 1;
        self.last_used[i] = self.clock;
        let have = self.rows[i].len();
        if have >= len {
            return;
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
    }

    /// Swaps positions `i < j` in every cached row; a row cached past `i` but not past `j`
    /// is dropped (libsvm's rule: it cannot be swapped in place).
    fn swap(&mut self, i: usize, j: usize) {
        self.rows.swap(i, j);
        self.last_used.swap(i, j);
        self.at.swap(i, j);
        self.y.swap(i, j);
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

/// Solver state by position (libsvm's arrays; positions below `active` are the active set).
struct State<'a> {
    q: QRows<'a>,
    alpha: Vec<f64>,
    /// Gradient ∇ₜ = (Qα)ₜ − 1.
    grad: Vec<f64>,
    /// `C · Σ_{s at upper bound} Q_ts`: the part of the gradient the bounded variables give,
    /// kept so the gradient of shrunk variables can be rebuilt from the free ones only.
    grad_bar: Vec<f64>,
    /// `Q_tt`.
    diag: Vec<f64>,
    /// Caller's index at each position.
    original: Vec<usize>,
    active: usize,
    c: f64,
    /// The largest KKT violation over the active variables at the last selection.
    violation: f64,
}

impl State<'_> {
    #[inline]
    fn upper(&self, t: usize) -> bool {
        self.alpha[t] >= self.c
    }

    #[inline]
    fn lower(&self, t: usize) -> bool {
        self.alpha[t] <= 0.0
    }

    /// libsvm's `select_working_set`: `Some((i, j))`, or `None` when the maximal violation over
    /// the active set is below `stop`.
    ///
    /// The scans avoid branches on the data where they can (whether a variable may move up or
    /// down is as good as random): this is where a fit spends its time.
    fn select(&mut self, stop: f64) -> Option<(usize, usize)> {
        let (n, c) = (self.active, self.c);
        // The largest −yₜ∇ₜ over I_up, ties to the last such t (libsvm's `>=` scan), kept in
        // independent lanes so the comparisons do not wait on each other.
        let mut lane_v = [f64::NEG_INFINITY; LANES];
        let mut lane_t = [usize::MAX; LANES];
        {
            let (y, alpha, grad) = (&self.q.y[..n], &self.alpha[..n], &self.grad[..n]);
            for (chunk, ((ys, als), gs)) in y
                .chunks(LANES)
                .zip(alpha.chunks(LANES))
                .zip(grad.chunks(LANES))
                .enumerate()
            {
                for k in 0..ys.len() {
                    let (yt, a) = (ys[k], als[k]);
                    // In I_up: −yₜ∇ₜ can grow.
                    let up = if yt > 0.0 { a < c } else { a > 0.0 };
                    let v = -yt * gs[k];
                    if up & (v >= lane_v[k]) {
                        lane_v[k] = v;
                        lane_t[k] = chunk * LANES + k;
                    }
                }
            }
        }
        let mut gmax = f64::NEG_INFINITY;
        let mut i_sel = usize::MAX;
        for (&v, &t) in lane_v.iter().zip(&lane_t) {
            if t != usize::MAX && (i_sel == usize::MAX || v > gmax || (v == gmax && t > i_sel)) {
                gmax = v;
                i_sel = t;
            }
        }
        if i_sel == usize::MAX {
            return None;
        }
        self.q.ensure(i_sel, n);
        let qi = &self.q.rows[i_sel][..n];
        let (y, alpha, grad, diag) = (&self.q.y[..n], &self.alpha[..n], &self.grad[..n], &self.diag[..n]);
        let (yi, di) = (y[i_sel], diag[i_sel]);
        let mut lane_max = [f64::NEG_INFINITY; LANES];
        // The best decrease so far, best_gain / best_quad (0 before any candidate).
        let (mut best_gain, mut best_quad) = (0.0, 1.0);
        let mut j_sel = usize::MAX;
        for t in 0..n {
            let (yt, a) = (y[t], alpha[t]);
            // In I_low: yₜ∇ₜ can shrink.
            let low = if yt > 0.0 { a > 0.0 } else { a < c };
            let v = yt * grad[t];
            let lane = &mut lane_max[t % LANES];
            *lane = lane.max(if low { v } else { f64::NEG_INFINITY });
            let grad_diff = gmax + v;
            if low & (grad_diff > 0.0) {
                // The largest decrease gd²/quad, compared as cross products: a division per
                // candidate was most of a fit's time.
                let quad = di + diag[t] - 2.0 * yi * yt * qi[t];
                let quad = if quad > 0.0 { quad } else { TAU };
                let gain = grad_diff * grad_diff;
                if gain * best_quad >= best_gain * quad {
                    best_gain = gain;
                    best_quad = quad;
                    j_sel = t;
                }
            }
        }
        let gmax2 = lane_max.into_iter().fold(f64::NEG_INFINITY, f64::max);
        self.violation = gmax + gmax2;
        (gmax + gmax2 >= stop && j_sel != usize::MAX).then_some((i_sel, j_sel))
    }

    /// The analytic two-variable step (libsvm's), the gradient update over the active set, and
    /// `grad_bar` for a variable that reached or left the upper bound.
    fn update(&mut self, i: usize, j: usize) {
        let (n, c) = (self.active, self.c);
        self.q.ensure(i, n);
        self.q.ensure(j, n);
        let qij = self.q.rows[i][j];
        let (old_i, old_j) = (self.alpha[i], self.alpha[j]);
        let (was_upper_i, was_upper_j) = (self.upper(i), self.upper(j));
        let [ai, aj] = PairStep {
            same_label: self.q.y[i] == self.q.y[j],
            q: [self.diag[i], self.diag[j], qij],
            grad: [self.grad[i], self.grad[j]],
            alpha: [old_i, old_j],
        }
        .clipped(c);
        self.alpha[i] = ai;
        self.alpha[j] = aj;
        let (di, dj) = (ai - old_i, aj - old_j);
        let (qi, qj) = (&self.q.rows[i][..n], &self.q.rows[j][..n]);
        for ((g, a), b) in self.grad[..n].iter_mut().zip(qi).zip(qj) {
            *g += a * di + b * dj;
        }
        for (t, was_upper) in [(i, was_upper_i), (j, was_upper_j)] {
            if was_upper != self.upper(t) {
                let all = self.alpha.len();
                self.q.ensure(t, all);
                let sign = if was_upper { -c } else { c };
                for (gb, q) in self.grad_bar.iter_mut().zip(&self.q.rows[t]) {
                    *gb += sign * q;
                }
            }
        }
    }

    /// Swaps positions `i < j` in every array.
    fn swap(&mut self, i: usize, j: usize) {
        self.q.swap(i, j);
        self.alpha.swap(i, j);
        self.grad.swap(i, j);
        self.grad_bar.swap(i, j);
        self.diag.swap(i, j);
        self.original.swap(i, j);
    }

    /// libsvm's `reconstruct_gradient`: the exact gradient of the shrunk variables, from
    /// `grad_bar` and the free variables.
    fn reconstruct_gradient(&mut self) {
        let (n, all) = (self.active, self.alpha.len());
        if n == all {
            return;
        }
        for t in n..all {
            self.grad[t] = self.grad_bar[t] - 1.0;
        }
        let free = (0..n).filter(|&t| !self.upper(t) && !self.lower(t)).count();
        if free * all > 2 * n * (all - n) {
            for t in n..all {
                self.q.ensure(t, n);
                let c = self.c;
                let g: f64 = self.q.rows[t][..n]
                    .iter()
                    .zip(&self.alpha[..n])
                    .filter(|&(_, &a)| a > 0.0 && a < c)
                    .map(|(q, a)| a * q)
                    .sum();
                self.grad[t] += g;
            }
        } else {
            for s in 0..n {
                let a = self.alpha[s];
                if a > 0.0 && a < self.c {
                    self.q.ensure(s, all);
                    for (g, q) in self.grad[n..].iter_mut().zip(&self.q.rows[s][n..all]) {
                        *g += a * q;
                    }
                }
            }
        }
    }

    fn be_shrunk(&self, t: usize, gmax1: f64, gmax2: f64) -> bool {
        let (g, positive) = (self.grad[t], self.q.y[t] > 0.0);
        if self.upper(t) {
            if positive { -g > gmax1 } else { -g > gmax2 }
        } else if self.lower(t) {
            if positive { g > gmax2 } else { g > gmax1 }
        } else {
            false
        }
    }

    /// libsvm's `do_shrinking`; `unshrunk` is whether the one full rebuild near the end was
    /// done.
    fn shrink(&mut self, stop: f64, unshrunk: &mut bool) {
        let (mut gmax1, mut gmax2) = (f64::NEG_INFINITY, f64::NEG_INFINITY);
        for t in 0..self.active {
            let g = self.grad[t];
            if self.q.y[t] > 0.0 {
                if !self.upper(t) {
                    gmax1 = gmax1.max(-g);
                }
                if !self.lower(t) {
                    gmax2 = gmax2.max(g);
                }
            } else {
                if !self.upper(t) {
                    gmax2 = gmax2.max(-g);
                }
                if !self.lower(t) {
                    gmax1 = gmax1.max(g);
                }
            }
        }
        if !*unshrunk && gmax1 + gmax2 <= 10.0 * stop {
            *unshrunk = true;
            self.reconstruct_gradient();
            self.active = self.alpha.len();
        }
        let mut t = 0;
        while t < self.active {
            if self.be_shrunk(t, gmax1, gmax2) {
                self.active -= 1;
                while self.active > t {
                    if !self.be_shrunk(self.active, gmax1, gmax2) {
                        self.swap(t, self.active);
                        break;
                    }
                    self.active -= 1;
                }
            }
            t += 1;
        }
    }

    /// libsvm's ρ over the active set ([`svm::libsvm_rho`]).
    fn rho(&self) -> f64 {
        let n = self.active;
        svm::libsvm_rho(&self.alpha[..n], &self.grad[..n], &self.q.y[..n], self.c)
    }
}

/// Solves the C-SVC dual `min ½ αᵀQα − eᵀα`, `yᵀα = 0`, `0 ≤ α ≤ c` over the points
/// `points[t·dim..]` for `t` in `subset` with labels `y` (±1), until the maximal KKT violation
/// is below `stop`, with libsvm's shrinking and at most `cache_bytes` of kernel rows; if
/// `max_iterations` pass first, the largest KKT violation it had reached (over the variables
/// still active) as the error.
#[allow(clippy::too_many_arguments)]
pub(super) fn solve_binary(
    kernel: Kernel,
    points: &[f64],
    dim: usize,
    subset: &[usize],
    y: &[f64],
    c: f64,
    stop: f64,
    max_iterations: usize,
    cache_bytes: usize,
) -> Result<BinarySolution, f64> {
    let n = subset.len();
    let q = QRows {
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
    };
    let diag = (0..n).map(|t| kernel.eval(q.point(t), q.point(t))).collect();
    let mut s = State {
        q,
        alpha: vec![0.0; n],
        grad: vec![-1.0; n],
        grad_bar: vec![0.0; n],
        diag,
        original: (0..n).collect(),
        active: n,
        c,
        violation: f64::INFINITY,
    };
    let mut counter = n.min(1000) + 1;
    let mut unshrunk = false;
    let mut iterations = 0;
    loop {
        if iterations >= max_iterations {
            return Err(s.violation);
        }
        counter -= 1;
        if counter == 0 {
            counter = n.min(1000);
            s.shrink(stop, &mut unshrunk);
        }
        let (i, j) = match s.select(stop) {
            Some(pair) => pair,
            None => {
                // Converged on the active set: every variable again, with exact gradients.
                s.reconstruct_gradient();
                s.active = n;
                match s.select(stop) {
                    Some(pair) => {
                        counter = 1;
                        pair
                    }
                    None => break,
                }
            }
        };
        iterations += 1;
        s.update(i, j);
    }
    let rho = s.rho();
    let mut alpha = vec![0.0; n];
    for (t, &a) in s.original.iter().zip(&s.alpha) {
        alpha[*t] = a;
    }
    Ok(BinarySolution {
        alpha,
        rho,
        iterations,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use capture::rng::SplitMix64;
    use svm::{GramRows, SelectionCurvature, SmoSettings};

    /// Two overlapping classes in 3-D, so that a soft margin leaves vectors free, at both
    /// bounds, and shrinking has something to shrink.
    fn problem(n: usize) -> (Vec<f64>, Vec<f64>) {
        let mut rng = SplitMix64::new(11);
        let mut points = Vec::with_capacity(3 * n);
        let mut y = Vec::with_capacity(n);
        for t in 0..n {
            let label = if t % 3 == 0 { -1.0 } else { 1.0 };
            for d in 0..3 {
                let centre = if d == 0 { 0.4 * label } else { 0.0 };
                points.push(centre + rng.next_f64() - 0.5);
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

    #[test]
    fn agrees_with_the_svm_crates_smo() {
        let (points, y) = problem(300);
        let n = y.len();
        // The subset in a scrambled order, so positions and the caller's order differ.
        let subset: Vec<usize> = (0..n).map(|t| (t * 7) % n).collect();
        let ys: Vec<f64> = subset.iter().map(|&t| y[t]).collect();
        let (c, stop) = (5.0, 1e-9);
        let ours =
            solve_binary(KERNEL, &points, 3, &subset, &ys, c, stop, 10_000_000, 64 << 20).expect("converges");
        let mut gram = vec![0.0; n * n];
        for a in 0..n {
            for b in 0..n {
                let (pa, pb) = (subset[a], subset[b]);
                gram[a * n + b] = KERNEL.eval(&points[3 * pa..3 * pa + 3], &points[3 * pb..3 * pb + 3]);
            }
        }
        let settings = SmoSettings::builder()
            .c(c)
            .stop(stop)
            .selection(SelectionCurvature::NonPositiveToTau)
            .build()
            .expect("settings");
        let mut rows = GramRows::new(&gram, n).expect("square");
        let theirs = svm::solve_smo(&mut rows, &ys, &vec![-1.0; n], &settings).expect("converges");
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
        let solve = |bytes| solve_binary(KERNEL, &points, 3, &subset, &y, 5.0, 1e-3, 10_000_000, bytes);
        let roomy = solve(64 << 20).expect("converges");
        // Rows dropped and recomputed (and dropped by swaps) change the cost, not the path.
        let tight = solve(0).expect("converges");
        assert_eq!(roomy, tight);
        assert!(roomy.iterations > 50, "{}", roomy.iterations);
        // Too few iterations is no answer, but the violation it reached.
        let short = solve_binary(KERNEL, &points, 3, &subset, &y, 5.0, 1e-3, 10, 64 << 20);
        assert!(matches!(short, Err(v) if v > 1e-3 && v.is_finite()), "{short:?}");
    }
}
