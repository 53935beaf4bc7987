//! Hyperparameters, validated once into a checked type (the linfa convention): a value that
//! could make the solver misbehave is a typed error before any work is done.

use std::time::{Duration, Instant};

use super::error::{SvmError, check_positive, check_time_budget};
use super::kernel::Kernel;

/// Which optimiser solves the dual.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Solver {
    /// A linear kernel in few dimensions exactly in the primal; other kernels on the low-rank
    /// interior point from 500 samples on where the kernel matrix is
    /// numerically low-rank; otherwise the dense interior point for up to
    /// [`SvrParams::DENSE_LIMIT`] samples, SMO beyond.
    #[default]
    Auto,
    /// Dense primal–dual interior point (Mehrotra), then an exact active-set polish: tens of
    /// iterations whatever C is, O(n³) per iteration.
    InteriorPoint,
    /// Sequential minimal optimisation with second-order working-set selection (libsvm's
    /// algorithm): O(n) per iteration, scales to large n, slow when C is large.
    Smo,
    /// The interior point on a pivoted incomplete Cholesky factor `GGᵀ` of the kernel matrix,
    /// its active set then finished exactly on the kernel: O(n r²) per iteration, for smooth
    /// kernels on few inputs, whose matrices are numerically low-rank. A typed error where the
    /// matrix is not.
    LowRank,
}

/// Unchecked hyperparameters; [`SvrParamsBuilder::build`] validates them into the
/// [`SvrParams`] it holds (linfa's builder-over-checked-type pattern).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SvrParamsBuilder(SvrParams);

/// Checked hyperparameters of an ε-SVR.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SvrParams {
    c: f64,
    epsilon: f64,
    kernel: Kernel,
    solver: Solver,
    tolerance: f64,
    max_iterations: usize,
    time_budget: Duration,
    max_sv: Option<usize>,
}

impl Default for SvrParamsBuilder {
    fn default() -> Self {
        Self(SvrParams {
            c: 1.0,
            epsilon: 0.1,
            kernel: Kernel::Rbf { gamma: 1.0 },
            solver: Solver::Auto,
            tolerance: 1e-10,
            max_iterations: 0,
            time_budget: Duration::from_secs(60),
            max_sv: None,
        })
    }
}

impl SvrParamsBuilder {
    /// Regularisation constant C > 0 (the weight of the ε-insensitive loss against ½‖w‖²).
    pub fn c(mut self, c: f64) -> Self {
        self.0.c = c;
        self
    }

    /// Width ε ≥ 0 of the insensitive tube, in the units of the targets.
    pub fn epsilon(mut self, epsilon: f64) -> Self {
        self.0.epsilon = epsilon;
        self
    }

    /// The kernel.
    pub fn kernel(mut self, kernel: Kernel) -> Self {
        self.0.kernel = kernel;
        self
    }

    /// The optimiser.
    pub fn solver(mut self, solver: Solver) -> Self {
        self.0.solver = solver;
        self
    }

    /// Relative optimality tolerance (duality gap for the interior point, KKT violation for SMO).
    pub fn tolerance(mut self, tolerance: f64) -> Self {
        self.0.tolerance = tolerance;
        self
    }

    /// Iteration budget; 0 picks the solver's default (200 interior-point iterations;
    /// 100 000 · n SMO iterations).
    pub fn max_iterations(mut self, max_iterations: usize) -> Self {
        self.0.max_iterations = max_iterations;
        self
    }

    /// Wall-clock budget; a fit that exceeds it stops with [`SvmError::Budget`].
    pub fn time_budget(mut self, budget: Duration) -> Self {
        self.0.time_budget = budget;
        self
    }

    /// At most this many support vectors in the returned model: a larger solution is reduced
    /// ([`crate::reduce_support`]) and the fit says how far the reduced model is from the
    /// certified one ([`crate::SvrFit::reduction`]). None (the default): no budget.
    pub fn max_sv(mut self, max_sv: Option<usize>) -> Self {
        self.0.max_sv = max_sv;
        self
    }

    /// Validates into [`SvrParams`].
    pub fn build(self) -> Result<SvrParams, SvmError> {
        let bad = SvmError::hyperparameter;
        check_positive("C", self.0.c)?;
        if !(self.0.epsilon.is_finite() && self.0.epsilon >= 0.0) {
            return Err(bad("epsilon", self.0.epsilon, "must be finite and >= 0"));
        }
        match self.0.kernel {
            Kernel::Linear => {}
            Kernel::Rbf { gamma } => {
                check_positive("gamma", gamma)?;
            }
            Kernel::Polynomial { gamma, coef0, degree } => {
                check_positive("gamma", gamma)?;
                if !coef0.is_finite() {
                    return Err(bad("coef0", coef0, "must be finite"));
                }
                if degree == 0 || degree > 10 {
                    return Err(bad("degree", f64::from(degree), "must be in 1..=10"));
                }
            }
        }
        if !(self.0.tolerance.is_finite() && self.0.tolerance > 0.0 && self.0.tolerance < 1.0) {
            return Err(bad("tolerance", self.0.tolerance, "must be in (0, 1)"));
        }
        check_time_budget(self.0.time_budget)?;
        if self.0.max_sv == Some(0) {
            return Err(bad("max_sv", 0.0, "at least one support vector"));
        }
        Ok(self.0)
    }
}

impl SvrParams {
    /// Samples above which [`Solver::Auto`] switches from the interior point to SMO: the dense
    /// kernel matrix (n² doubles) and its O(n³) factorisations stop paying off there.
    pub const DENSE_LIMIT: usize = 3000;

    /// Starts a builder (C = 1, ε = 0.1, RBF γ = 1, automatic solver, tolerance 1e-10).
    pub fn builder() -> SvrParamsBuilder {
        SvrParamsBuilder::default()
    }

    /// C.
    pub fn c(&self) -> f64 {
        self.c
    }
    /// ε.
    pub fn epsilon(&self) -> f64 {
        self.epsilon
    }
    /// The kernel.
    pub fn kernel(&self) -> Kernel {
        self.kernel
    }
    /// The optimiser asked for.
    pub fn solver(&self) -> Solver {
        self.solver
    }
    /// Relative tolerance.
    pub fn tolerance(&self) -> f64 {
        self.tolerance
    }
    /// Iteration budget (0: the solver's default).
    pub fn max_iterations(&self) -> usize {
        self.max_iterations
    }
    /// Wall-clock budget.
    pub fn time_budget(&self) -> Duration {
        self.time_budget
    }
    /// Support-vector budget of the returned model.
    pub fn max_sv(&self) -> Option<usize> {
        self.max_sv
    }
}

/// Where a running fit stands, shown to the observer of [`crate::fit_observed`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FitProgress {
    /// The solver running.
    pub solver: &'static str,
    /// Its iterations so far.
    pub iterations: usize,
    /// The relative gap of its current iterate (the interior point's complementarity gap;
    /// infinite where the solver has none until it stops).
    pub gap: f64,
    /// Seconds since the fit started.
    pub elapsed_s: f64,
}

/// Seconds per `m³` of factorising an `m × m` active-set system, measured: LU with full
/// pivoting of a 3,001 × 3,001 bordered system took 113.6 s in the test profile on the 2-core
/// machine (4.2e-9 s per `m³`), the thin SVD that follows when it leaves a residual 17.8 s
/// more. Release builds are faster, so this overestimates there: a round it skips would only
/// have sped the fit up.
pub(crate) const SECONDS_PER_CUBED_FACTOR: f64 = 5e-9;

/// What the dual solvers of one fit need, taken once from checked [`SvrParams`]: the box, the
/// tube, the tolerance and the budgets, with the instant the fit started (budgets count from
/// it).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct DualSettings {
    /// C.
    pub c: f64,
    /// ε, in the units of the targets.
    pub epsilon: f64,
    /// Relative tolerance of the solver.
    pub tolerance: f64,
    /// Iteration budget (0: the solver's default).
    pub max_iterations: usize,
    /// When the fit started.
    pub started: Instant,
    /// Wall-clock budget of the whole fit.
    pub time_budget: Duration,
}

impl DualSettings {
    /// The time budget in seconds.
    pub fn budget_s(&self) -> f64 {
        self.time_budget.as_secs_f64()
    }

    /// Whether the time budget has run out.
    pub fn over_budget(&self) -> bool {
        self.started.elapsed().as_secs_f64() > self.budget_s()
    }

    /// Whether a factorisation of an `m × m` system by LU with full pivoting, which cannot be
    /// interrupted, can end within the time budget left (by [`SECONDS_PER_CUBED_FACTOR`]).
    pub fn has_time_to_factor(&self, m: usize) -> bool {
        let left_s = self.budget_s() - self.started.elapsed().as_secs_f64();
        SECONDS_PER_CUBED_FACTOR * (m as f64).powi(3) <= left_s
    }
}

impl SvrParams {
    /// The solvers' settings for a fit that started at `started`.
    pub(crate) fn dual_settings(&self, started: Instant) -> DualSettings {
        DualSettings {
            c: self.c,
            epsilon: self.epsilon,
            tolerance: self.tolerance,
            max_iterations: self.max_iterations,
            started,
            time_budget: self.time_budget,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A factorisation is begun only when its estimate fits in the budget left: hundreds of
    /// free samples in seconds, not 3,000 (about two minutes by the estimate) in 5 s, and
    /// nothing once the budget is spent.
    #[test]
    fn a_factorisation_is_begun_only_when_it_can_end_within_the_budget() {
        let settings = |budget_s: u64, spent_s: u64| {
            SvrParams::builder()
                .time_budget(Duration::from_secs(budget_s))
                .build()
                .expect("valid")
                .dual_settings(Instant::now() - Duration::from_secs(spent_s))
        };
        assert!(settings(5, 0).has_time_to_factor(400));
        assert!(!settings(5, 0).has_time_to_factor(3001));
        assert!(settings(600, 0).has_time_to_factor(3001));
        assert!(!settings(600, 500).has_time_to_factor(3001));
        assert!(!settings(5, 10).has_time_to_factor(2));
    }

    #[test]
    fn invalid_values_are_typed_errors() {
        let cases = [
            SvrParams::builder().c(0.0),
            SvrParams::builder().c(f64::INFINITY),
            SvrParams::builder().c(f64::NAN),
            SvrParams::builder().epsilon(-1e-9),
            SvrParams::builder().kernel(Kernel::Rbf { gamma: 0.0 }),
            SvrParams::builder().kernel(Kernel::Rbf { gamma: f64::NAN }),
            SvrParams::builder().kernel(Kernel::Polynomial {
                gamma: 1.0,
                coef0: 0.0,
                degree: 0,
            }),
            SvrParams::builder().tolerance(0.0),
            SvrParams::builder().time_budget(Duration::ZERO),
            SvrParams::builder().max_sv(Some(0)),
        ];
        for b in cases {
            let err = b.build().unwrap_err();
            assert!(matches!(err, SvmError::InvalidHyperparameter { .. }), "{err}");
        }
        let p = SvrParams::builder()
            .c(1e11)
            .epsilon(0.0)
            .kernel(Kernel::Linear)
            .build()
            .unwrap();
        assert_eq!((p.c(), p.epsilon(), p.kernel()), (1e11, 0.0, Kernel::Linear));
    }
}
