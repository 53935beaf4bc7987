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
//! [`super::SvrParams::DENSE_LIMIT`] samples.
//!
//! There is one solver (`solver.rs`, libsvm's `Solver` with its layout by position) and three
//! ways to read the dual's matrix: rows cached by position over the active prefix
//! ([`solve_svc`], libsvm's `SVC_Q`, for recognition's pairwise C-SVCs), the ε-SVR's kernel
//! rows cached by sample and shared by a sample's two variables (`svr.rs`, libsvm's `SVR_Q`),
//! and any [`KernelRows`], e.g. a precomputed [`GramRows`] ([`solve_smo`]).

use std::time::{Duration, Instant};

use super::error::{SvmError, check_positive, check_time_budget};

mod rows;
mod solver;
mod svc;
mod svr;
pub use rows::{GramRows, KernelRows, RowStorage, RowValue};
pub use svc::solve_svc;
pub(crate) use svr::{CACHE_BYTES, TARGET_GAP, solve_svr};

/// The solver's name in errors.
pub(crate) const NAME: &str = "SMO";
/// The ε-SVR's SMO when the exact finish on its partition produced the answer.
pub(crate) const NAME_FINISHED: &str = "SMO + exact finish";

/// Curvature floor for non-positive-definite pairs (libsvm's τ).
const TAU: f64 = 1e-12;

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

/// Solves `min ½ αᵀQα + pᵀα`, `yᵀα = 0`, `0 ≤ α ≤ C` (see the module doc) for `labels` (±1)
/// and `linear` (p), one entry per variable; there are as many variables as samples in `rows`,
/// or twice as many (a split dual: variable t is sample `t mod n`).
///
/// # Panics
/// If `labels` and `linear` differ in length or do not cover the samples once or twice, or a
/// label is not ±1.
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
    let mut q = rows::SampleQ::new(rows, labels);
    let sol = solver::solve(&mut q, labels, linear, settings, &mut |_, _, _| None)?;
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
    let (mut ub, mut lb, mut sum_free, mut n_free) = (f64::INFINITY, f64::NEG_INFINITY, 0.0, 0usize);
    for ((&a, &g), &yt) in alpha.iter().zip(grad).zip(y) {
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
