//! Sequential minimal optimisation (Fan, Chen & Lin, "Working set selection using second order
//! information", JMLR 6, 2005 — libsvm's algorithm): one core for the ε-SVR and the C-SVC.
//!
//! Both duals have libsvm's form `min ½ αᵀQα + pᵀα` subject to `yᵀα = 0`, `0 ≤ α ≤ C`, with
//! labels `yₜ = ±1` and `Qₜₛ = yₜ yₛ K(sample(t), sample(s))`:
//! * C-SVC: one variable per sample, its class label, `p = −1`;
//! * ε-SVR: two variables per sample (the split dual), `αₜ` with label +1 and `p = ε − yₜ`, then
//!   `α*ₜ` with label −1 and `p = ε + yₜ`.
//!
//! Each iteration changes two variables analytically, chosen by the second-order rule, so an
//! iteration costs two kernel rows and O(n) gradient updates. That scales to n where the dense
//! interior point's n² memory and n³ factorisations do not; its weakness is the iteration count
//! at large C, which is why [`super::Solver::Auto`] uses it for the ε-SVR only beyond
//! [`super::SvrParams::DENSE_LIMIT`] samples. Kernel rows come from a [`KernelRows`]: a
//! precomputed Gram matrix ([`GramRows`], the C-SVC's pairs of tens of vectors) or a cache of
//! least recently used rows within a memory budget (the ε-SVR).

use std::time::{Duration, Instant};

use super::error::{SvmError, check_positive, check_time_budget};

mod svr;
pub(crate) use svr::{CACHE_BYTES, TARGET_GAP, solve_svr};

/// The solver's name in errors.
pub(crate) const NAME: &str = "SMO";
/// The ε-SVR's SMO when the exact finish on its partition produced the answer.
pub(crate) const NAME_FINISHED: &str = "SMO + exact finish";

/// Curvature floor for non-positive-definite pairs (libsvm's τ).
const TAU: f64 = 1e-12;

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

/// Which curvature the second-order working-set selection divides by when a pair's
/// `Kᵢᵢ + Kₜₜ − 2Kᵢₜ` is at most τ. The pair update itself always uses `max(·, τ)`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SelectionCurvature {
    /// `max(·, τ)`, as in the update.
    #[default]
    Clamped,
    /// libsvm's selection rule: only a non-positive curvature becomes τ.
    NonPositiveToTau,
}

/// Unchecked SMO settings; [`SmoSettingsBuilder::build`] validates them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SmoSettingsBuilder {
    c: f64,
    stop: f64,
    max_iterations: usize,
    shrinking: bool,
    budget: Option<(Instant, Duration)>,
    selection: SelectionCurvature,
}

/// Checked SMO settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SmoSettings {
    c: f64,
    stop: f64,
    max_iterations: usize,
    shrinking: bool,
    budget: Option<(Instant, f64)>,
    selection: SelectionCurvature,
}

impl Default for SmoSettingsBuilder {
    fn default() -> Self {
        Self {
            c: 1.0,
            stop: 1e-3,
            max_iterations: 0,
            shrinking: false,
            budget: None,
            selection: SelectionCurvature::Clamped,
        }
    }
}

impl SmoSettingsBuilder {
    /// Box constraint C > 0.
    pub fn c(mut self, c: f64) -> Self {
        self.c = c;
        self
    }

    /// The solve stops once the maximal KKT violation `max_{I_up} −yₜ∇ₜ + max_{I_low} yₜ∇ₜ`
    /// is below this (> 0; libsvm's ε, in the units of the gradient).
    pub fn stop(mut self, stop: f64) -> Self {
        self.stop = stop;
        self
    }

    /// Iteration budget; 0 picks `max(100 · variables, 10⁷)`.
    pub fn max_iterations(mut self, max_iterations: usize) -> Self {
        self.max_iterations = max_iterations;
        self
    }

    /// libsvm's shrinking heuristic (worth it for thousands of variables; it changes the cost,
    /// never the answer).
    pub fn shrinking(mut self, shrinking: bool) -> Self {
        self.shrinking = shrinking;
        self
    }

    /// Wall-clock budget counted from `started`; exceeding it is [`SvmError::Budget`].
    pub fn time_budget(mut self, started: Instant, budget: Duration) -> Self {
        self.budget = Some((started, budget));
        self
    }

    /// The selection's curvature floor.
    pub fn selection(mut self, selection: SelectionCurvature) -> Self {
        self.selection = selection;
        self
    }

    /// Validates into [`SmoSettings`].
    pub fn build(self) -> Result<SmoSettings, SvmError> {
        check_positive("C", self.c)?;
        check_positive("stop", self.stop)?;
        if let Some((_, budget)) = self.budget {
            check_time_budget(budget)?;
        }
        Ok(SmoSettings {
            c: self.c,
            stop: self.stop,
            max_iterations: self.max_iterations,
            shrinking: self.shrinking,
            budget: self.budget.map(|(started, b)| (started, b.as_secs_f64())),
            selection: self.selection,
        })
    }
}

impl SmoSettings {
    /// Starts a builder (C = 1, stop 1e-3, default iteration budget, no shrinking, no time
    /// budget, clamped selection curvature).
    pub fn builder() -> SmoSettingsBuilder {
        SmoSettingsBuilder::default()
    }

    /// The iteration budget for `variables` variables.
    pub fn iteration_budget(&self, variables: usize) -> usize {
        if self.max_iterations == 0 {
            (100 * variables).max(10_000_000)
        } else {
            self.max_iterations
        }
    }
}

/// The solution of an SMO solve.
#[derive(Debug, Clone, PartialEq)]
pub struct SmoSolution {
    /// The dual variables α, one per variable, in `[0, C]`.
    pub alpha: Vec<f64>,
    /// libsvm's ρ (the decision function is `Σ yₜαₜK(xₜ, x) − ρ`): the mean of `yₜ∇ₜ` over free
    /// variables, else the middle of the interval the bounded ones allow.
    pub rho: f64,
    /// Pair updates made.
    pub iterations: usize,
    /// The maximal KKT violation at the last selection (below the stop value when converged).
    pub violation: f64,
    /// Whether it met its stop value; `false`: it stopped at its iteration limit, and this is
    /// its last iterate (only [`solve_svr`]'s caller sees one, to certify it).
    pub converged: bool,
    /// The stop value it was aiming for at the end.
    pub stop: f64,
}

/// The labels `yₜ = ±1` of a dual's variables.
trait Labels: Copy {
    fn label(&self, t: usize) -> f64;
}

/// Labels given one by one (the C-SVC's classes).
#[derive(Clone, Copy)]
struct Given<'a>(&'a [f64]);

impl Labels for Given<'_> {
    #[inline]
    fn label(&self, t: usize) -> f64 {
        self.0[t]
    }
}

/// The ε-SVR's split dual: +1 for the first n variables (α), −1 for the rest (α*); computed,
/// so the inner loops read no label array.
#[derive(Clone, Copy)]
struct Split {
    n: usize,
}

impl Labels for Split {
    #[inline]
    fn label(&self, t: usize) -> f64 {
        if t < self.n { 1.0 } else { -1.0 }
    }
}

/// Labels and linear term of the dual's variables, and how they map to samples.
struct Variables<'a, L> {
    labels: L,
    linear: &'a [f64],
    /// Samples: variable t is sample t, or t − n for the second half of a split dual.
    n: usize,
}

/// The largest KKT values over the active set: max over I_up of −yₜ∇ₜ and over I_low of yₜ∇ₜ.
fn extremes(
    active: &[usize],
    alpha: &[f64],
    grad: &[f64],
    label: impl Fn(usize) -> f64,
    in_up: impl Fn(f64, f64) -> bool,
    in_low: impl Fn(f64, f64) -> bool,
) -> (f64, f64) {
    let (mut up, mut low) = (f64::NEG_INFINITY, f64::NEG_INFINITY);
    for &t in active {
        let yt = label(t);
        if in_up(alpha[t], yt) {
            up = up.max(-yt * grad[t]);
        }
        if in_low(alpha[t], yt) {
            low = low.max(yt * grad[t]);
        }
    }
    (up, low)
}

/// Kernel rows as the solver reads them: two at a time (the pair's), by handle, so a cache can
/// hand out its own storage instead of copies.
trait PairRows {
    /// `K(xₛ, xₛ)`.
    fn diagonal(&self, s: usize) -> f64;
    /// Makes row `s` available and returns its handle, valid until the fetch after the next.
    fn fetch(&mut self, s: usize) -> usize;
    /// The row behind a handle from [`PairRows::fetch`].
    fn get(&self, handle: usize) -> &[f64];
}

/// Any [`KernelRows`] as [`PairRows`]: each fetched row is copied into one of two buffers, in
/// turn, so the last two stay readable together.
struct Copied<'r, R> {
    rows: &'r mut R,
    buffers: [Vec<f64>; 2],
    next: usize,
}

impl<'r, R: KernelRows> Copied<'r, R> {
    fn new(rows: &'r mut R) -> Self {
        let n = rows.samples();
        Self {
            rows,
            buffers: [vec![0.0; n], vec![0.0; n]],
            next: 0,
        }
    }
}

impl<R: KernelRows> PairRows for Copied<'_, R> {
    fn diagonal(&self, s: usize) -> f64 {
        self.rows.diagonal(s)
    }
    fn fetch(&mut self, s: usize) -> usize {
        let h = self.next;
        self.next = 1 - h;
        self.buffers[h].copy_from_slice(self.rows.row(s));
        h
    }
    fn get(&self, handle: usize) -> &[f64] {
        &self.buffers[handle]
    }
}

/// Recomputes the gradient of every variable outside `active` from scratch,
/// `∇ₜ = pₜ + Σⱼ yₜ yⱼ K(sₜ, sⱼ) αⱼ`, over the non-zero α only.
fn rebuild_gradient<R: PairRows, L: Labels>(
    grad: &mut [f64],
    alpha: &[f64],
    active: &[usize],
    rows: &mut R,
    vars: &Variables<'_, L>,
) {
    let m = grad.len();
    let mut inactive = vec![true; m];
    for &t in active {
        inactive[t] = false;
    }
    let outside: Vec<usize> = (0..m).filter(|&t| inactive[t]).collect();
    if outside.is_empty() {
        return;
    }
    for &t in &outside {
        grad[t] = vars.linear[t];
    }
    let (labels, n) = (vars.labels, vars.n);
    let sample = |t: usize| if t < n { t } else { t - n };
    for (j, &aj) in alpha.iter().enumerate() {
        if aj == 0.0 {
            continue;
        }
        let (yj, sj) = (labels.label(j), sample(j));
        let h = rows.fetch(sj);
        let row = rows.get(h);
        for &t in &outside {
            let (yt, st) = (labels.label(t), sample(t));
            grad[t] += yt * yj * row[st] * aj;
        }
    }
}

/// Solves `min ½ αᵀQα + pᵀα`, `yᵀα = 0`, `0 ≤ α ≤ C` (see the module doc) for `labels` (±1)
/// and `linear` (p), one entry per variable; there are as many variables as samples in `rows`,
/// or twice as many (a split dual).
///
/// # Panics
/// If `labels` and `linear` differ in length or do not cover the samples once or twice.
pub fn solve_smo<R: KernelRows>(
    rows: &mut R,
    labels: &[f64],
    linear: &[f64],
    settings: &SmoSettings,
) -> Result<SmoSolution, SvmError> {
    let n = rows.samples();
    let m = labels.len();
    assert!(
        linear.len() == m && (m == n || m == 2 * n),
        "SMO: {m} labels and {} linear terms for {n} samples",
        linear.len()
    );
    let vars = Variables {
        labels: Given(labels),
        linear,
        n,
    };
    let sol = solve(&mut Copied::new(rows), &vars, settings, &mut |_, _, _| None)?;
    if !sol.converged {
        // No certificate here (a C-SVC has none): the KKT violation is what it reached.
        return Err(SvmError::NotConverged {
            solver: NAME,
            iterations: sol.iterations,
            gap: sol.violation,
            measure: crate::error::KKT_VIOLATION,
            tolerance: sol.stop,
        });
    }
    Ok(sol)
}

/// What a solve asks, each time it has converged on every variable, of whoever called it:
/// `(α, ∇, stop)` → a smaller stop value to go on to, or `None` to finish.
type Refine<'a> = dyn FnMut(&[f64], &[f64], f64) -> Option<f64> + 'a;

/// [`solve_smo`] for any labelling, with the selection's curvature rule fixed at compile time.
fn solve<R: PairRows, L: Labels>(
    rows: &mut R,
    vars: &Variables<'_, L>,
    settings: &SmoSettings,
    refine: &mut Refine<'_>,
) -> Result<SmoSolution, SvmError> {
    match settings.selection {
        SelectionCurvature::Clamped => solve_with::<R, L, false>(rows, vars, settings, refine),
        SelectionCurvature::NonPositiveToTau => solve_with::<R, L, true>(rows, vars, settings, refine),
    }
}

/// libsvm's ρ at (α, ∇) for labels `y` (±1) and box `[0, c]`: the mean of `yₜ∇ₜ` over free
/// variables, else the middle of the interval the bounded ones allow. Every SMO here (the
/// ε-SVR's, the C-SVC's) reads its ρ from this one function.
///
/// # Panics
/// If the three slices differ in length.
pub fn libsvm_rho(alpha: &[f64], grad: &[f64], y: &[f64], c: f64) -> f64 {
    assert!(
        alpha.len() == grad.len() && grad.len() == y.len(),
        "ρ: slices of different lengths"
    );
    rho(alpha, grad, Given(y), c)
}

/// [`libsvm_rho`] for any labelling.
fn rho<L: Labels>(alpha: &[f64], grad: &[f64], labels: L, c: f64) -> f64 {
    let (mut ub, mut lb, mut sum_free, mut n_free) = (f64::INFINITY, f64::NEG_INFINITY, 0.0, 0usize);
    for (t, (&a, &g)) in alpha.iter().zip(grad).enumerate() {
        let yt = labels.label(t);
        let yg = yt * g;
        if a >= c {
            if yt < 0.0 {
                ub = ub.min(yg)
            } else {
                lb = lb.max(yg)
            }
        } else if a <= 0.0 {
            if yt > 0.0 {
                ub = ub.min(yg)
            } else {
                lb = lb.max(yg)
            }
        } else {
            n_free += 1;
            sum_free += yg;
        }
    }
    if n_free > 0 {
        sum_free / n_free as f64
    } else {
        0.5 * (ub + lb)
    }
}

/// The solve; `NON_POSITIVE_TO_TAU` is [`SelectionCurvature::NonPositiveToTau`].
fn solve_with<R: PairRows, L: Labels, const NON_POSITIVE_TO_TAU: bool>(
    rows: &mut R,
    vars: &Variables<'_, L>,
    settings: &SmoSettings,
    refine: &mut Refine<'_>,
) -> Result<SmoSolution, SvmError> {
    let (n, m, linear) = (vars.n, vars.linear.len(), vars.linear);
    let c = settings.c;
    let mut stop = settings.stop;
    let max_iterations = settings.iteration_budget(m);
    // Copies, so the hot loops keep them in registers rather than reloading them through a
    // reference after every store to the gradient.
    let labels = vars.labels;
    let label = |t: usize| labels.label(t);
    let sample = |t: usize| if t < n { t } else { t - n };
    let mut alpha = vec![0.0; m];
    let mut grad: Vec<f64> = linear.to_vec();
    let diag: Vec<f64> = (0..n).map(|s| rows.diagonal(s)).collect();
    let in_up = |a: f64, yt: f64| (yt > 0.0 && a < c) || (yt < 0.0 && a > 0.0);
    let in_low = |a: f64, yt: f64| (yt > 0.0 && a > 0.0) || (yt < 0.0 && a < c);

    // Shrinking (libsvm's heuristic): variables at a bound whose gradient says they will stay
    // there leave the active set, so selection and gradient updates skip them; near the end
    // their gradients are rebuilt and every variable is checked again, so shrinking changes
    // the cost, never the answer.
    let shrink_every = m.min(1000);
    let mut counter = shrink_every;
    let mut active: Vec<usize> = (0..m).collect();
    let mut unshrunk = false;
    let mut iterations = 0;
    let mut violation = f64::INFINITY;
    while iterations < max_iterations {
        if let Some((started, budget_s)) = settings.budget
            && iterations % 1000 == 0
            && started.elapsed().as_secs_f64() > budget_s
        {
            return Err(SvmError::Budget {
                solver: NAME,
                budget_s,
                iterations,
                gap: violation,
            });
        }
        if settings.shrinking {
            counter -= 1;
            if counter == 0 {
                counter = shrink_every;
                let (g_up, g_low) = extremes(&active, &alpha, &grad, label, in_up, in_low);
                if !unshrunk && g_up + g_low <= 10.0 * stop {
                    // Close to the end: bring everything back once, with exact gradients.
                    unshrunk = true;
                    rebuild_gradient(&mut grad, &alpha, &active, rows, vars);
                    active = (0..m).collect();
                }
                active.retain(|&t| {
                    let (a, yt, g) = (alpha[t], label(t), grad[t]);
                    let at_upper = a >= c;
                    let at_lower = a <= 0.0;
                    !((at_upper && yt > 0.0 && -g > g_up)
                        || (at_upper && yt < 0.0 && -g > g_low)
                        || (at_lower && yt > 0.0 && g > g_low)
                        || (at_lower && yt < 0.0 && g > g_up))
                });
            }
        }
        // i: the most violating variable from I_up.
        let mut gmax = f64::NEG_INFINITY;
        let mut i_sel = usize::MAX;
        for &t in &active {
            let yt = label(t);
            if in_up(alpha[t], yt) && -yt * grad[t] >= gmax {
                gmax = -yt * grad[t];
                i_sel = t;
            }
        }
        let mut gmax2 = f64::NEG_INFINITY;
        let mut best = f64::INFINITY;
        let mut j_sel = usize::MAX;
        let mut hi = usize::MAX;
        if i_sel != usize::MAX {
            let si = sample(i_sel);
            hi = rows.fetch(si);
            let ki = rows.get(hi);
            // j: the largest second-order decrease among I_low.
            for &t in &active {
                let yt = label(t);
                if !in_low(alpha[t], yt) {
                    continue;
                }
                gmax2 = gmax2.max(yt * grad[t]);
                let b = gmax + yt * grad[t];
                if b > 0.0 {
                    let st = sample(t);
                    let a = diag[si] + diag[st] - 2.0 * ki[st];
                    let a = if NON_POSITIVE_TO_TAU {
                        if a > 0.0 { a } else { TAU }
                    } else {
                        a.max(TAU)
                    };
                    let decrease = -b * b / a;
                    if decrease <= best {
                        best = decrease;
                        j_sel = t;
                    }
                }
            }
        }
        violation = gmax + gmax2;
        if i_sel == usize::MAX || violation < stop || j_sel == usize::MAX {
            if active.len() < m {
                // Converged on the active set: check everything with exact gradients.
                rebuild_gradient(&mut grad, &alpha, &active, rows, vars);
                active = (0..m).collect();
                counter = shrink_every;
                continue;
            }
            match refine(&alpha, &grad, stop) {
                Some(tighter) if tighter < stop && i_sel != usize::MAX && j_sel != usize::MAX => {
                    stop = tighter;
                    unshrunk = false;
                    counter = shrink_every;
                    continue;
                }
                _ => break,
            }
        }
        let yi = label(i_sel);
        let si = sample(i_sel);
        let yj = label(j_sel);
        let sj = sample(j_sel);
        let hj = rows.fetch(sj);
        let (ki, kj) = (rows.get(hi), rows.get(hj));
        // Analytic two-variable step, clipped to the box (libsvm's update).
        let qii = diag[si];
        let qjj = diag[sj];
        let qij = yi * yj * ki[sj];
        let (old_i, old_j) = (alpha[i_sel], alpha[j_sel]);
        [alpha[i_sel], alpha[j_sel]] = PairStep {
            same_label: yi == yj,
            q: [qii, qjj, qij],
            grad: [grad[i_sel], grad[j_sel]],
            alpha: [old_i, old_j],
        }
        .clipped(c);
        let (di, dj) = (yi * (alpha[i_sel] - old_i), yj * (alpha[j_sel] - old_j));
        for &t in &active {
            let st = sample(t);
            grad[t] += label(t) * (ki[st] * di + kj[st] * dj);
        }
        iterations += 1;
    }
    let rho = rho(&alpha, &grad, labels, c);
    Ok(SmoSolution {
        alpha,
        rho,
        iterations,
        violation,
        converged: !(violation >= stop && iterations >= max_iterations),
        stop,
    })
}

/// One pair `(i, j)` of a dual `min ½ αᵀQα + pᵀα`, `yᵀα = Δ`, `0 ≤ α ≤ C` at an SMO step.
#[derive(Debug, Clone, Copy)]
pub struct PairStep {
    /// `yᵢ = yⱼ`.
    pub same_label: bool,
    /// `[Qᵢᵢ, Qⱼⱼ, Qᵢⱼ]`, with `Qᵢⱼ = yᵢyⱼK(xᵢ, xⱼ)`.
    pub q: [f64; 3],
    /// `[∇ᵢ, ∇ⱼ]`.
    pub grad: [f64; 2],
    /// `[αᵢ, αⱼ]` before the step.
    pub alpha: [f64; 2],
}

impl PairStep {
    /// libsvm's analytic two-variable step, clipped to the box `[0, c]²` along the line
    /// `yᵀα` keeps constant: the new `[αᵢ, αⱼ]`. Every SMO here (the ε-SVR's, the C-SVC's)
    /// takes its step through this one function.
    #[inline(always)]
    pub fn clipped(self, c: f64) -> [f64; 2] {
        let [qii, qjj, qij] = self.q;
        let [gi, gj] = self.grad;
        let [old_i, old_j] = self.alpha;
        // libsvm: a non-positive curvature (a kernel that is not positive definite) is τ.
        let curvature = |quad: f64| if quad > 0.0 { quad } else { TAU };
        if self.same_label {
            let delta = (gi - gj) / curvature(qii + qjj - 2.0 * qij);
            let sum = old_i + old_j;
            let (mut ai, mut aj) = (old_i - delta, old_j + delta);
            clip_equal_labels(&mut ai, &mut aj, sum, c);
            clip_equal_labels(&mut aj, &mut ai, sum, c);
            [ai, aj]
        } else {
            let delta = (-gi - gj) / curvature(qii + qjj + 2.0 * qij);
            let diff = old_i - old_j;
            let (mut ai, mut aj) = (old_i + delta, old_j + delta);
            if diff > 0.0 {
                if aj < 0.0 {
                    aj = 0.0;
                    ai = diff;
                }
            } else if ai < 0.0 {
                ai = 0.0;
                aj = -diff;
            }
            if diff > 0.0 {
                if ai > c {
                    ai = c;
                    aj = c - diff;
                }
            } else if aj > c {
                aj = c;
                ai = c + diff;
            }
            [ai, aj]
        }
    }
}

/// libsvm's clipping of a same-label pair to the box `[0, c]²` on the line `a + b = sum`, for
/// `a` above `c` or `b` below 0; called again with the pair swapped for the other two sides.
#[inline(always)]
fn clip_equal_labels(a: &mut f64, b: &mut f64, sum: f64, c: f64) {
    if sum > c {
        if *a > c {
            *a = c;
            *b = sum - c;
        }
    } else if *b < 0.0 {
        *b = 0.0;
        *a = sum;
    }
}
