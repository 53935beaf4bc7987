//! Fitting: validate, solve the dual, polish, and package the model with its objectives.

use std::time::Instant;

use faer::Mat;

use super::data::SvrData;
use super::error::SvmError;
use super::ipm;
use super::kernel::Kernel;
use super::model::SvrModel;
use super::params::{DualSettings, Solver, SvrParams};
use super::polish::{self, Side};
use super::smo;

/// Active-set moves allowed to a polish tried during the interior point's run.
const EARLY_POLISH_ROUNDS: usize = 5;

/// Relative duality gap above which a fit is an error rather than a model.
pub const ACCEPT_GAP: f64 = 1e-6;

/// Largest |K(xᵢ, xᵢ)|: the scale of kernel values, for rounding bounds.
fn kernel_scale(kernel: &Kernel, x: &[f64], dim: usize) -> f64 {
    x.chunks_exact(dim)
        .map(|r| kernel.eval(r, r).abs())
        .fold(1.0, f64::max)
}

/// A fitted model and what it took.
#[derive(Debug, Clone, PartialEq)]
pub struct SvrFit {
    /// The model.
    pub model: SvrModel,
    /// Dual objective `½βᵀKβ + εΣ|β| − yᵀβ` at the solution (libsvm's `obj`).
    pub dual_objective: f64,
    /// Primal objective `½‖w‖² + C Σ max(0, |yᵢ − f(xᵢ)| − ε)` at the solution.
    pub primal_objective: f64,
    /// Which solver produced it.
    pub solver: &'static str,
    /// Iterations of that solver.
    pub iterations: usize,
    /// Whether the exact active-set polish succeeded.
    pub polished: bool,
    /// Support vectors at the bound |β| = C.
    pub n_bounded_sv: usize,
    /// Wall-clock seconds of the whole fit.
    pub fit_seconds: f64,
}

impl SvrFit {
    /// Relative duality gap `|P + D| / max(1, |P|)`: 0 at the exact optimum (strong duality
    /// makes the primal minimum equal minus the dual minimum).
    pub fn relative_gap(&self) -> f64 {
        (self.primal_objective + self.dual_objective).abs() / self.primal_objective.abs().max(1.0)
    }
}

/// A solved dual, before its certificate: what the solvers hand to [`fit`]'s final check.
#[derive(Debug, Clone)]
struct DualSolution {
    /// `β = α − α*`, one per sample.
    beta: Vec<f64>,
    /// The bias b.
    bias: f64,
    /// Which solver produced it.
    solver: &'static str,
    /// Iterations of that solver.
    iterations: usize,
    /// Whether the exact active-set polish produced it.
    polished: bool,
    /// The dense kernel matrix, where the solver built one.
    kernel_matrix: Option<Mat<f64>>,
    /// Exact primal weights (linear kernel, polished).
    weights: Option<Vec<f64>>,
}

/// Fits an ε-SVR to `n` samples: `x` is `n × dim` row-major, `y` has `n` targets.
pub fn fit(params: &SvrParams, x: &[f64], dim: usize, y: &[f64]) -> Result<SvrFit, SvmError> {
    let started = Instant::now();
    let data = SvrData::new(x, dim, y)?;
    let settings = params.dual_settings(started);
    let kernel = params.kernel();
    let use_smo = match params.solver() {
        Solver::Smo => true,
        Solver::InteriorPoint => false,
        Solver::Auto => y.len() > SvrParams::DENSE_LIMIT,
    };
    let solution = if use_smo {
        let sol = smo::solve_svr(&kernel, &data, &settings)?;
        DualSolution {
            beta: sol.beta,
            bias: sol.bias,
            solver: smo::NAME,
            iterations: sol.iterations,
            polished: false,
            kernel_matrix: None,
            weights: None,
        }
    } else {
        solve_dense(&kernel, &data, &settings)?
    };
    let mut fit = certify(&kernel, &data, &settings, solution)?;
    fit.fit_seconds = started.elapsed().as_secs_f64();
    Ok(fit)
}

/// The interior point on the dense kernel matrix, with the polish tried on its late iterates.
fn solve_dense(
    kernel: &Kernel,
    data: &SvrData<'_>,
    settings: &DualSettings,
) -> Result<DualSolution, SvmError> {
    let (x, dim, y) = (data.x, data.dim, data.y);
    let k = kernel_matrix(kernel, x, dim).ok_or_else(|| SvmError::Numerical {
        solver: "kernel",
        reason: "kernel values overflow; scale the inputs or lower gamma/degree".into(),
    })?;
    // Accept a polished iterate only when its own duality gap certifies it.
    let certify_below = (10.0 * settings.tolerance).max(1e-12);
    let mut certified: Option<polish::Polished> = None;
    let linear = *kernel == Kernel::Linear;
    let run_polish = |sides: Vec<Side>, rounds: usize| {
        if linear {
            polish::polish_linear(data, settings, sides, rounds)
        } else {
            polish::polish(&k, y, settings, sides, rounds)
        }
    };
    // Early attempts are cheap ones: a few active-set moves, and only once the gap has
    // shrunk tenfold since the last attempt (each round is a dense solve).
    let mut last_attempt_gap = f64::INFINITY;
    let mut accept = |sol: &ipm::IpmSolution| {
        if sol.gap > 0.1 * last_attempt_gap {
            return false;
        }
        last_attempt_gap = sol.gap;
        let rounds = if linear { usize::MAX } else { EARLY_POLISH_ROUNDS };
        let Some(p) = run_polish(classify(sol), rounds) else {
            return false;
        };
        let ok = certified_optimal(&k, data, settings, &p, certify_below);
        if ok {
            certified = Some(p);
        }
        ok
    };
    let sol = ipm::solve(&k, y, settings, &mut accept)?;
    let iterations = sol.iterations;
    let polished = certified.or_else(|| {
        run_polish(classify(&sol), usize::MAX)
            .filter(|p| certified_optimal(&k, data, settings, p, certify_below))
    });
    match polished {
        Some(p) => Ok(DualSolution {
            beta: p.beta,
            bias: p.bias,
            solver: "interior point + polish",
            iterations,
            polished: true,
            kernel_matrix: Some(k),
            weights: p.weights,
        }),
        None if !sol.converged => Err(SvmError::NotConverged {
            solver: "interior point",
            iterations,
            gap: sol.gap,
            tolerance: settings.tolerance,
        }),
        None => {
            let beta = sol
                .alpha
                .iter()
                .zip(&sol.alpha_star)
                .map(|(a, s)| a - s)
                .collect();
            Ok(DualSolution {
                beta,
                bias: sol.bias,
                solver: "interior point",
                iterations,
                polished: false,
                kernel_matrix: Some(k),
                weights: None,
            })
        }
    }
}

/// Packages a solution as a model with its objectives, or refuses it when its own duality gap
/// does not vouch for it.
fn certify(
    kernel: &Kernel,
    data: &SvrData<'_>,
    settings: &DualSettings,
    solution: DualSolution,
) -> Result<SvrFit, SvmError> {
    let (x, dim, y) = (data.x, data.dim, data.y);
    let (c, epsilon) = (settings.c, settings.epsilon);
    let n = y.len();
    let DualSolution {
        beta,
        bias,
        solver,
        iterations,
        polished,
        kernel_matrix: k,
        weights,
    } = solution;
    let kernel = *kernel;

    // Objectives: from exact primal weights when we have them, else from K, else from kernel
    // evaluations.
    let mut kbeta = vec![0.0; n];
    match (&weights, &k) {
        (Some(w), _) => {
            for (i, kb) in kbeta.iter_mut().enumerate() {
                *kb = x[i * dim..(i + 1) * dim].iter().zip(w).map(|(a, b)| a * b).sum();
            }
        }
        (None, Some(k)) => ipm::mat_vec(k, &beta, &mut kbeta),
        (None, None) => {
            for i in 0..n {
                let xi = &x[i * dim..(i + 1) * dim];
                kbeta[i] = (0..n)
                    .filter(|&j| beta[j] != 0.0)
                    .map(|j| beta[j] * kernel.eval(&x[j * dim..(j + 1) * dim], xi))
                    .sum();
            }
        }
    }
    let quad = match &weights {
        Some(w) => 0.5 * w.iter().map(|v| v * v).sum::<f64>(),
        None => 0.5 * beta.iter().zip(&kbeta).map(|(b, kb)| b * kb).sum::<f64>(),
    };
    let dual_objective = quad + epsilon * beta.iter().map(|b| b.abs()).sum::<f64>()
        - beta.iter().zip(y).map(|(b, yi)| b * yi).sum::<f64>();
    let primal_objective = quad + c * (0..n).map(|i| slack(y[i], kbeta[i] + bias, epsilon)).sum::<f64>();

    // Never hand out an answer that its own duality gap does not vouch for (up to what the
    // arithmetic can resolve: at C ~ 1e11 the objectives' rounding error is part of the budget).
    // Each fitted value f(xᵢ) = Σⱼ βⱼKᵢⱼ + b carries ~ε_mach·Σⱼ|βⱼKᵢⱼ| of rounding, which the
    // loss multiplies by C.
    let abs_beta_sum: f64 = beta.iter().map(|b| b.abs()).sum();
    let f_rounding = if weights.is_some() {
        0.0
    } else {
        abs_beta_sum * kernel_scale(&kernel, x, dim) + bias.abs()
    };
    let rounding = 16.0
        * n as f64
        * f64::EPSILON
        * (abs_beta_sum * (1.0 + y.iter().fold(0.0f64, |m, v| m.max(v.abs())))
            + abs_beta_sum * abs_beta_sum * kernel_scale(&kernel, x, dim)
            + c * f_rounding);
    let gap = (primal_objective + dual_objective).abs();
    let within = gap <= ACCEPT_GAP * primal_objective.abs().max(1.0) + rounding;
    // (NaN fails `within` too.)
    if !within || !primal_objective.is_finite() {
        return Err(SvmError::NotConverged {
            solver,
            iterations,
            gap: gap / primal_objective.abs().max(1.0),
            tolerance: ACCEPT_GAP,
        });
    }

    let sv: Vec<usize> = (0..n).filter(|&i| beta[i] != 0.0).collect();
    let model = SvrModel {
        kernel,
        dim,
        support_vectors: sv
            .iter()
            .flat_map(|&i| x[i * dim..(i + 1) * dim].iter().copied())
            .collect(),
        coefficients: sv.iter().map(|&i| beta[i]).collect(),
        bias,
        weights,
    };
    Ok(SvrFit {
        n_bounded_sv: sv.iter().filter(|&&i| beta[i].abs() >= c * (1.0 - 1e-12)).count(),
        model,
        dual_objective,
        primal_objective,
        solver,
        iterations,
        polished,
        fit_seconds: 0.0,
    })
}

/// Whether a polished (β, b) is provably optimal: β is dual feasible (Σβ = 0, |β| ≤ C) and the
/// duality gap is below `relative_gap`. By weak duality no primal point can then do better
/// than `relative_gap`, whatever produced (β, b).
fn certified_optimal(
    k: &Mat<f64>,
    data: &SvrData<'_>,
    settings: &DualSettings,
    p: &polish::Polished,
    relative_gap: f64,
) -> bool {
    let c = settings.c;
    let total: f64 = p.beta.iter().map(|b| b.abs()).sum();
    let feasible =
        p.beta.iter().sum::<f64>().abs() <= 1e-12 * (1.0 + total) && p.beta.iter().all(|b| b.abs() <= c);
    let o = objectives(k, data, settings, p);
    feasible && (o.primal + o.dual).abs() <= relative_gap * o.primal.abs().max(1.0) + o.rounding
}

/// Primal and dual objectives of a solution, and a bound on the rounding error of their sum.
#[derive(Debug, Clone, Copy)]
struct Objectives {
    /// `½‖w‖² + C Σ max(0, |yᵢ − f(xᵢ)| − ε)`.
    primal: f64,
    /// `½βᵀKβ + εΣ|β| − yᵀβ`.
    dual: f64,
    /// Bound on the rounding error of `primal + dual`.
    rounding: f64,
}

/// Primal and dual objectives of a polished solution, and a bound on the rounding error of
/// their sum.
///
/// The dual is evaluated at β honestly. Its quadratic term is `½βᵀKβ`, but with β ~ C = 1e11
/// the entries of Kβ cancel to O(1) and carry errors ~ε_mach·|K||β| that βᵀ multiplies back up;
/// for a linear kernel it is evaluated through the feature map as `½‖Σβᵢxᵢ‖²`, which does not
/// amplify, and otherwise the rounding bound says how far the gap can be trusted.
fn objectives(k: &Mat<f64>, data: &SvrData<'_>, settings: &DualSettings, p: &polish::Polished) -> Objectives {
    let (x, dim, y) = (data.x, data.dim, data.y);
    let (c, epsilon) = (settings.c, settings.epsilon);
    let n = y.len();
    let abs_beta: Vec<f64> = p.beta.iter().map(|b| b.abs()).collect();
    let linear_term =
        epsilon * abs_beta.iter().sum::<f64>() - p.beta.iter().zip(y).map(|(b, yi)| b * yi).sum::<f64>();
    let mut rounding = 8.0
        * n as f64
        * f64::EPSILON
        * abs_beta
            .iter()
            .zip(y)
            .map(|(b, yi)| b * (yi.abs() + epsilon))
            .sum::<f64>();
    let mut kbeta = vec![0.0; n];
    ipm::mat_vec(k, &p.beta, &mut kbeta);
    let (dual_quad, primal) = match &p.weights {
        Some(w) => {
            let mut w_beta = vec![0.0; dim];
            for (i, b) in p.beta.iter().enumerate() {
                for (wk, xk) in w_beta.iter_mut().zip(&x[i * dim..(i + 1) * dim]) {
                    *wk += b * xk;
                }
            }
            let f = |i: usize| {
                x[i * dim..(i + 1) * dim]
                    .iter()
                    .zip(w)
                    .map(|(a, b)| a * b)
                    .sum::<f64>()
                    + p.bias
            };
            let primal = 0.5 * w.iter().map(|v| v * v).sum::<f64>()
                + c * (0..n).map(|i| slack(y[i], f(i), epsilon)).sum::<f64>();
            (0.5 * w_beta.iter().map(|v| v * v).sum::<f64>(), primal)
        }
        None => {
            let mut abs_k_beta = vec![0.0; n];
            for (j, &bj) in abs_beta.iter().enumerate() {
                for (i, o) in abs_k_beta.iter_mut().enumerate() {
                    *o += k[(i, j)].abs() * bj;
                }
            }
            rounding += 8.0
                * n as f64
                * f64::EPSILON
                * abs_beta.iter().zip(&abs_k_beta).map(|(a, b)| a * b).sum::<f64>();
            let quad = 0.5 * p.beta.iter().zip(&kbeta).map(|(b, kb)| b * kb).sum::<f64>();
            (
                quad,
                quad + c
                    * (0..n)
                        .map(|i| slack(y[i], kbeta[i] + p.bias, epsilon))
                        .sum::<f64>(),
            )
        }
    };
    Objectives {
        primal,
        dual: dual_quad + linear_term,
        rounding,
    }
}

/// The ε-insensitive loss `max(0, |y − f| − ε)`, with a residual that exceeds ε by less than
/// its own rounding error counted as on the tube. At C = 1e11 a boundary sample whose residual
/// came out one ulp (~1e-17) too large would otherwise add ~1e-6 to the objective: the optimum's
/// value would depend on the last bit of a subtraction.
pub fn slack(y: f64, f: f64, epsilon: f64) -> f64 {
    let excess = (y - f).abs() - epsilon;
    let rounding = 8.0 * f64::EPSILON * (y.abs() + f.abs() + epsilon);
    if excess <= rounding { 0.0 } else { excess }
}

/// The dense kernel matrix, or `None` if a value overflows.
pub(crate) fn kernel_matrix(kernel: &Kernel, x: &[f64], dim: usize) -> Option<Mat<f64>> {
    let n = x.len() / dim;
    let mut k = Mat::<f64>::zeros(n, n);
    for j in 0..n {
        let xj = &x[j * dim..(j + 1) * dim];
        for i in j..n {
            let v = kernel.eval(&x[i * dim..(i + 1) * dim], xj);
            if !v.is_finite() {
                return None;
            }
            k[(i, j)] = v;
            k[(j, i)] = v;
        }
    }
    Some(k)
}

/// Reads the active set off the interior point's last iterate: a bound is active when its
/// slack is smaller than its multiplier (strict complementarity makes one of them vanish).
fn classify(sol: &ipm::IpmSolution) -> Vec<Side> {
    (0..sol.alpha.len())
        .map(|i| {
            let a_upper = sol.slack_alpha[i] < sol.upper_alpha[i];
            let s_upper = sol.slack_alpha_star[i] < sol.upper_alpha_star[i];
            let a_active = sol.alpha[i] > sol.lower_alpha[i];
            let s_active = sol.alpha_star[i] > sol.lower_alpha_star[i];
            match (a_upper, s_upper, a_active, s_active) {
                (true, _, _, _) => Side::Above,
                (_, true, _, _) => Side::Below,
                (_, _, true, false) => Side::UpperFree,
                (_, _, false, true) => Side::LowerFree,
                (_, _, true, true) => {
                    if sol.alpha[i] >= sol.alpha_star[i] {
                        Side::UpperFree
                    } else {
                        Side::LowerFree
                    }
                }
                (_, _, false, false) => Side::Inside,
            }
        })
        .collect()
}
