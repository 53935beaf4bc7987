//! Fitting: validate, solve the dual, polish, and package the model with its objectives.

use std::time::Instant;

use faer::Mat;
use rayon::prelude::*;

use super::certificate::{self, ACCEPT_GAP, Certificate};
use super::compensated::Accumulator;
use super::data::SvrData;
use super::error::SvmError;
use super::ipm;
use super::kernel::Kernel;
use super::linear_exact;
use super::low_rank;
use super::model::SvrModel;
use super::params::{DualSettings, FitProgress, Solver, SvrParams};
use super::polish::{self, Side};
use super::reduce::reduce_support;
use super::smo;
use super::smo_finish;

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
    /// Certified bound on `(P − P* − resolution) / max(1, |P|)`: see [`SvrFit::relative_gap`].
    pub certified_gap: f64,
    /// The primal objective's resolution in f64 (C times the rounding unit of the residuals
    /// pinned on the tube boundary): `P − P* ≤ relative_gap()·max(1, |P|) + resolution`.
    pub resolution: f64,
    /// With a support-vector budget the solution exceeded: `model` is the reduced one, and
    /// this says from how many support vectors and how far it is from the certified solution
    /// (which the objectives and the gap describe).
    pub reduction: Option<ReductionReport>,
}

/// How a model was brought within its support-vector budget ([`crate::reduce_support`]).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ReductionReport {
    /// Support vectors of the certified solution.
    pub from_sv: usize,
    /// Largest |reduced − certified| over the training inputs.
    pub max_deviation: f64,
    /// RMS of reduced − certified over the training inputs.
    pub rms_deviation: f64,
}

impl SvrFit {
    /// Certified relative duality gap: an upper bound on how far the model's primal objective
    /// can be above the optimum beyond [`SvrFit::resolution`], relative to `max(1, |P|)`. It
    /// is `P + D` plus the rounding bounds of their compensated evaluation and the cost of Σβ
    /// missing 0 by rounding (see the `certificate` module), so it holds whatever produced the
    /// model; every returned fit has it at most [`ACCEPT_GAP`].
    pub fn relative_gap(&self) -> f64 {
        self.certified_gap
    }
}

/// How a fit the interior point handed back at its iteration limit, certified, names its solver.
const IPM_AT_LIMIT: &str = "interior point (at its iteration limit, certified)";
/// The ε-SVR's SMO stopped by its iteration limit, its last iterate certified.
const SMO_AT_LIMIT: &str = "SMO (at its iteration limit, certified)";

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
    /// The tolerance the interior point or SMO aimed for and stopped short of, at its
    /// iteration limit: a kept fit is named [`IPM_AT_LIMIT`] or [`SMO_AT_LIMIT`], a refused
    /// one is [`SvmError::NotConverged`] with its certified gap.
    short_of: Option<f64>,
    /// The dense kernel matrix, where the solver built one.
    kernel_matrix: Option<Mat<f64>>,
    /// Exact primal weights (linear kernel, polished).
    weights: Option<Vec<f64>>,
}

/// Fits an ε-SVR to `n` samples: `x` is `n × dim` row-major, `y` has `n` targets.
pub fn fit(params: &SvrParams, x: &[f64], dim: usize, y: &[f64]) -> Result<SvrFit, SvmError> {
    fit_observed(params, x, dim, y, &|_| {})
}

/// [`fit`], calling `observer` as the solver advances (each interior-point iteration, every few
/// active-set steps), so that a caller can show progress on long fits.
pub fn fit_observed(
    params: &SvrParams,
    x: &[f64],
    dim: usize,
    y: &[f64],
    observer: &dyn Fn(&FitProgress),
) -> Result<SvrFit, SvmError> {
    let started = Instant::now();
    let data = SvrData::new(x, dim, y)?;
    let settings = params.dual_settings(started);
    let kernel = params.kernel();
    if kernel == Kernel::Linear && dim <= linear_exact::MAX_DIM && params.solver() == Solver::Auto {
        let sol = match linear_exact::solve(&data, &settings, observer) {
            Ok(sol) => sol,
            Err(stopped) => return Err(with_certified_gap(&kernel, &data, &settings, *stopped)),
        };
        let solution = DualSolution {
            beta: sol.beta,
            bias: sol.bias,
            solver: linear_exact::NAME,
            iterations: sol.iterations,
            polished: true,
            short_of: None,
            kernel_matrix: None,
            weights: Some(sol.weights),
        };
        let mut fit = certify(&kernel, &data, &settings, solution)?;
        fit.fit_seconds = started.elapsed().as_secs_f64();
        return Ok(fit);
    }
    let n = y.len();
    let low_rank_tried = match params.solver() {
        Solver::LowRank => true,
        Solver::Auto => kernel != Kernel::Linear && n >= low_rank::MIN_SAMPLES,
        Solver::Smo | Solver::InteriorPoint => false,
    };
    let low_rank_outcome = if low_rank_tried {
        solve_low_rank(&kernel, &data, &settings, observer)?
    } else {
        Ok(None)
    };
    // Measured by the factor: its residual fell ever slower (not merely past the rank allowed
    // at this n, as the needle's kernel at n = 500).
    // Below the factor's sizes, measured by its first columns alone: whether the kernel is
    // numerically full-rank (Friedman #1 at n = 350–476, where SMO took 3–9 ms against the
    // dense interior point's 8–16 ms), not merely beyond the rank allowed at this n.
    let far_from_low_rank = match low_rank_outcome {
        Err(low_rank::FactorMiss::SlowFall) => true,
        _ if !low_rank_tried && params.solver() == Solver::Auto && kernel != Kernel::Linear => {
            low_rank::numerically_full_rank(
                &kernel,
                x,
                dim,
                low_rank::tolerances(n, settings.c, super::data::target_scale(y))[0],
            )
        }
        _ => false,
    };
    let low_rank_solution = low_rank_outcome.ok().flatten();
    let use_smo = match params.solver() {
        Solver::Smo => true,
        Solver::InteriorPoint => false,
        Solver::LowRank => {
            if low_rank_solution.is_none() {
                return Err(SvmError::Numerical {
                    solver: low_rank::NAME,
                    reason: format!(
                        "the kernel matrix is not within {:e} of a rank ≤ {} matrix, or its interior \
                         point's active set could not be finished exactly; use another solver",
                        low_rank::TOLERANCE,
                        low_rank::max_rank(n)
                    ),
                });
            }
            false
        }
        Solver::Auto => n > SvrParams::DENSE_LIMIT,
    };
    let smo_solution = |max_iterations: usize| -> Result<DualSolution, SvmError> {
        let sol = smo::solve_svr(&kernel, &data, &settings, smo::CACHE_BYTES, max_iterations)?;
        Ok(DualSolution {
            beta: sol.beta,
            bias: sol.bias,
            solver: if sol.polished {
                smo::NAME_FINISHED
            } else {
                smo::NAME
            },
            iterations: sol.iterations,
            polished: sol.polished,
            short_of: sol.short_of,
            kernel_matrix: None,
            weights: None,
        })
    };
    // Where the kernel is far from low-rank, SMO first, for as many iterations as the dense
    // interior point would cost; the interior point only if it does not converge in them. (On
    // the needle at n = 500, whose factor only lacked rank, SMO spent 0.07 s before the
    // interior point's 0.03 s.)
    let smo_first = params.solver() == Solver::Auto && far_from_low_rank && !use_smo;
    let solution = if let Some(solution) = low_rank_solution {
        solution
    } else if use_smo {
        smo_solution(settings.max_iterations)?
    } else if let Some(solution) = smo_first
        .then(|| smo_solution(smo_iterations_for_dense_cost(n, dim)))
        .and_then(Result::ok)
        .filter(|s| s.short_of.is_none())
    {
        solution
    } else {
        solve_dense(&kernel, &data, &settings, observer)?
    };
    let mut fit = certify(&kernel, &data, &settings, solution)?;
    if let Some(max_sv) = params.max_sv()
        && fit.model.n_sv() > max_sv
    {
        let r = reduce_support(&fit.model, x, dim, max_sv)?;
        fit.reduction = Some(ReductionReport {
            from_sv: r.from_sv,
            max_deviation: r.max_deviation,
            rms_deviation: r.rms_deviation,
        });
        fit.model = r.model;
    }
    fit.fit_seconds = started.elapsed().as_secs_f64();
    Ok(fit)
}

/// The interior point on the dense kernel matrix, with the polish tried on its late iterates.
fn solve_dense(
    kernel: &Kernel,
    data: &SvrData<'_>,
    settings: &DualSettings,
    observer: &dyn Fn(&FitProgress),
) -> Result<DualSolution, SvmError> {
    let (x, dim, y) = (data.x, data.dim, data.y);
    let k = crate::kernel::kernel_matrix(kernel, x, dim).ok_or_else(|| SvmError::Numerical {
        solver: "kernel",
        reason: "kernel values overflow; scale the inputs or lower gamma/degree".into(),
    })?;
    // Accept a polished iterate only when its own duality gap certifies it.
    let certify_below = (10.0 * settings.tolerance).max(1e-12);
    let linear = *kernel == Kernel::Linear;
    // The linear polish's rounds solve systems of d + 1 unknowns: it runs until it settles.
    let run_polish = |sides: Vec<Side>, max_flops: f64| {
        if linear {
            polish::Spent {
                flops: 0.0,
                polished: polish::polish_linear(data, settings, sides, usize::MAX),
            }
        } else {
            polish::polish(&k, y, settings, sides, max_flops)
        }
    };
    // Early attempts come only once the gap has shrunk tenfold since the last, and together
    // spend at most what the interior point has (a Cholesky of K per iteration), so that they
    // at most double the fit. A round's cost varies a hundredfold: on the needle's samples a
    // round with nearly dependent free samples falls back to a least squares that costs half
    // the whole Cholesky of K, while at n = 432 of the Li & Bi capture the attempt at iteration 10
    // needed ten rounds of small Cholesky factors; capped at five rounds, it and the next two
    // attempts failed, and the fit took three more iterations.
    let iteration_flops = crate::bordered::cholesky_flops(y.len());
    let run = |centring: ipm::Centring| -> Result<(ipm::IpmSolution, Option<polish::Polished>), SvmError> {
        let mut certified: Option<polish::Polished> = None;
        let mut last_attempt_gap = f64::INFINITY;
        let mut polish_flops = 0.0;
        let mut accept = |sol: &ipm::IpmSolution| {
            if sol.gap > 0.1 * last_attempt_gap {
                return false;
            }
            last_attempt_gap = sol.gap;
            let allowed = sol.iterations.max(1) as f64 * iteration_flops - polish_flops;
            let spent = run_polish(classify(sol), allowed);
            polish_flops += spent.flops;
            let Some(p) = spent.polished else {
                return false;
            };
            let ok = certified_optimal(&k, data, settings, kernel, &p, certify_below);
            if ok {
                certified = Some(p);
            }
            ok
        };
        let sol = ipm::solve(&k, y, settings, centring, &mut accept, observer)?;
        let polished = certified.or_else(|| {
            run_polish(classify(&sol), f64::INFINITY)
                .polished
                .filter(|p| certified_optimal(&k, data, settings, kernel, p, certify_below))
        });
        Ok((sol, polished))
    };
    // On degenerate problems (duplicated inputs at C = 1e11) the two paths end at different
    // points of the optimal face, and the polish can certify one and not the other: where the
    // faster path's end point is not certified, the other is tried before giving up.
    let (sol, polished) = match run(ipm::Centring::Gondzio) {
        Ok((sol, Some(p))) => (sol, Some(p)),
        Err(e @ SvmError::Budget { .. }) => return Err(e),
        first => match run(ipm::Centring::MehrotraOnly) {
            Ok(second) => second,
            Err(e @ SvmError::Budget { .. }) => return Err(e),
            // The retry failed outright: the first path's outcome stands, or else this error.
            Err(e) => first.map_err(|_| e)?,
        },
    };
    let iterations = sol.iterations;
    match polished {
        Some(p) => Ok(DualSolution {
            beta: p.beta,
            bias: p.bias,
            solver: "interior point + polish",
            iterations,
            polished: true,
            short_of: None,
            kernel_matrix: Some(k),
            weights: p.weights,
        }),
        // Converged or at its iteration limit, the last iterate goes to `certify` like every
        // solver's: kept when its certificate meets ACCEPT_GAP; refused at the limit, the error
        // names that certified gap, not the iterate's own complementarity (which at C = 1e11
        // read 7e-9 where the certificate of the same point read 4e-4).
        None => Ok(DualSolution {
            beta: sol
                .alpha
                .iter()
                .zip(&sol.alpha_star)
                .map(|(a, s)| a - s)
                .collect(),
            bias: sol.bias,
            solver: "interior point",
            iterations,
            polished: false,
            short_of: (!sol.converged).then_some(settings.tolerance),
            kernel_matrix: Some(k),
            weights: None,
        }),
    }
}

/// The interior point on a pivoted incomplete Cholesky factor of K (`crate::low_rank`), its
/// active set finished exactly on the kernel itself (`smo_finish`): first on a factor as loose
/// as the data allow, then, when that one's active set does not finish, on the tightest
/// ([`low_rank::tolerances`]). `Err(miss)` when K is not low-rank enough for the factor to pay
/// (`miss` says how: the kernel far from low-rank, or only beyond the rank allowed at this n),
/// `Ok(None)` when no iterate's active set finishes into a small enough gap: the caller then
/// solves on the exact kernel from scratch.
fn solve_low_rank(
    kernel: &Kernel,
    data: &SvrData<'_>,
    settings: &DualSettings,
    observer: &dyn Fn(&FitProgress),
) -> Result<Result<Option<DualSolution>, low_rank::FactorMiss>, SvmError> {
    let (x, dim, y) = (data.x, data.dim, data.y);
    let n = y.len();
    let y_scale = super::data::target_scale(y);
    for tolerance in low_rank::tolerances(n, settings.c, y_scale) {
        let factor = match low_rank::pivoted_cholesky(kernel, x, dim, tolerance, low_rank::max_rank(n)) {
            Ok(factor) => factor,
            Err(miss) => return Ok(Err(miss)),
        };
        if let Some(solution) = solve_on_factor(kernel, data, settings, observer, &factor)? {
            return Ok(Ok(Some(solution)));
        }
    }
    Ok(Ok(None))
}

/// [`solve_low_rank`] on one factor.
fn solve_on_factor(
    kernel: &Kernel,
    data: &SvrData<'_>,
    settings: &DualSettings,
    observer: &dyn Fn(&FitProgress),
    factor: &low_rank::LowRank,
) -> Result<Option<DualSolution>, SvmError> {
    let (x, dim, y) = (data.x, data.dim, data.y);
    let (c, epsilon) = (settings.c, settings.epsilon);
    // The exact Kβ of the last rounded iterate tried: the next one differs from it in few
    // samples, so its Kβ is an update rather than n × (support vectors) kernel values again.
    let mut last: Option<(Vec<f64>, Vec<f64>)> = None;
    let mut last_attempt_gap = f64::INFINITY;
    let mut attempt = |sol: &ipm::IpmSolution, force: bool| -> Option<smo_finish::Finished> {
        if !force && sol.gap > 0.1 * last_attempt_gap {
            return None;
        }
        last_attempt_gap = sol.gap;
        let beta = rounded(sol, c);
        let k_beta = match &last {
            Some((old_beta, old_k_beta)) => {
                let delta: Vec<f64> = beta.iter().zip(old_beta).map(|(a, b)| a - b).collect();
                let k_delta = low_rank::kernel_times(kernel, x, dim, &delta);
                old_k_beta.iter().zip(&k_delta).map(|(a, b)| a + b).collect()
            }
            None => low_rank::kernel_times(kernel, x, dim, &beta),
        };
        // On a factor this close to K the iterate itself is often optimal on K to within the
        // acceptance gap; where it is not, the exact finish on its active set is.
        let bias = sol.bias;
        let own_gap = smo_finish::gap(&beta, &k_beta, bias, y, c, epsilon);
        let done = if own_gap <= smo::TARGET_GAP {
            Some(smo_finish::Finished {
                beta: beta.clone(),
                bias,
                gap: own_gap,
            })
        } else {
            smo_finish::finish(
                kernel,
                data,
                settings,
                &beta,
                &k_beta,
                smo::TARGET_GAP,
                finish_free_limit(sol.iterations, x.len() / dim.max(1), factor.rank()),
            )
            .filter(|f| f.gap <= smo::TARGET_GAP)
        };
        last = Some((beta, k_beta));
        done
    };
    let mut finished = None;
    let solved = ipm::solve(
        factor,
        y,
        settings,
        ipm::Centring::Gondzio,
        &mut |sol| {
            finished = attempt(sol, false);
            finished.is_some()
        },
        observer,
    );
    let sol = match solved {
        Ok(sol) => sol,
        Err(e @ SvmError::Budget { .. }) => return Err(e),
        Err(_) => return Ok(None),
    };
    // An iterate that met the interior point's own criterion gets a last try; one left at
    // the iteration limit has no settled active set, and a finish from it can cost n³.
    if finished.is_none() && sol.converged {
        finished = attempt(&sol, true);
    }
    Ok(finished.map(|f| DualSolution {
        beta: f.beta,
        bias: f.bias,
        solver: low_rank::NAME,
        iterations: sol.iterations,
        polished: true,
        short_of: None,
        kernel_matrix: None,
        weights: None,
    }))
}

/// SMO iterations that cost about what the dense interior point would on `n` samples of `dim`
/// inputs: about 12 iterations of an n³/3 Cholesky against an SMO iteration's two kernel rows
/// of n evaluations (each some dim + 20 flops). On Friedman #1 (five uniform inputs, C = 10)
/// SMO and its exact finish took 0.048 s at n = 1,000 (4,788 iterations; the budget here is
/// 80,000) where the dense interior point took 0.11 s, and 0.30 s at 3,000 against 3.1 s.
fn smo_iterations_for_dense_cost(n: usize, dim: usize) -> usize {
    let n = n as f64;
    (12.0 * n * n * n / 3.0 / (2.0 * n * (dim as f64 + 20.0))) as usize
}

/// The most free samples an exact finish after `iterations` of the interior point on a rank-`rank`
/// factor of `n` samples may solve for: a round factorises an `m × m` system, which should cost
/// no more than the interior point did (about n·rank² flops per iteration, at BLAS speed).
/// Measured on the needle capture when a round's only factorisation was LU with full pivoting,
/// which ran about 8 times slower per m³ than the interior point per n·rank², hence half the
/// cube root. A round now tries a Cholesky factor first (`bordered.rs`), about 13 times faster
/// where it solves, so the limit errs on the side of leaving a partition to the next iterate. There, at n = 3,000 the
/// finish's partition went from 28 free samples to 2,160 in one active-set step after a poor
/// iterate, and that round spent 6.9 s on a system it could not solve (at n = 2,750: 817 free,
/// 0.24 s), where the interior point had taken 0.1 s; the next iterate's partition finished in
/// one round of 98. A partition that swells past this is left for the next iterate.
fn finish_free_limit(iterations: usize, n: usize, rank: usize) -> usize {
    let flops = iterations.max(1) as f64 * n as f64 * (rank as f64).powi(2);
    (flops.cbrt() / 2.0) as usize
}

/// The interior point's iterate with its active set made exact: β = ±C, 0 or free as
/// [`classify`] reads it (the free ones strictly inside their half of the box).
fn rounded(sol: &ipm::IpmSolution, c: f64) -> Vec<f64> {
    let sides = classify(sol);
    let mut beta: Vec<f64> = sides
        .iter()
        .enumerate()
        .map(|(i, &side)| {
            let beta = sol.alpha[i] - sol.alpha_star[i];
            match side {
                Side::Inside => 0.0,
                Side::Above => c,
                Side::Below => -c,
                Side::UpperFree => beta.clamp(f64::MIN_POSITIVE, c.next_down()),
                Side::LowerFree => beta.clamp((-c).next_up(), -f64::MIN_POSITIVE),
            }
        })
        .collect();
    // Rounding moved Σβ off 0; the free coefficients take the difference back, as long as
    // they stay on their side of the box.
    let free: Vec<usize> = (0..beta.len())
        .filter(|&i| matches!(sides[i], Side::UpperFree | Side::LowerFree))
        .collect();
    if !free.is_empty() {
        let shift = -beta.iter().sum::<f64>() / free.len() as f64;
        for &i in &free {
            let moved = beta[i] + shift;
            if moved != 0.0 && moved.signum() == beta[i].signum() && moved.abs() < c {
                beta[i] = moved;
            }
        }
    }
    beta
}

/// Packages a solution as a model with its certificate, or refuses it when the certificate
/// misses [`ACCEPT_GAP`].
fn certify(
    kernel: &Kernel,
    data: &SvrData<'_>,
    settings: &DualSettings,
    solution: DualSolution,
) -> Result<SvrFit, SvmError> {
    let (x, dim) = (data.x, data.dim);
    let c = settings.c;
    let n = data.y.len();
    let DualSolution {
        beta,
        bias,
        solver,
        iterations,
        polished,
        short_of,
        kernel_matrix: k,
        weights,
    } = solution;
    let kernel = *kernel;
    let cert = certificate_of(
        &kernel,
        data,
        settings,
        &beta,
        bias,
        k.as_ref(),
        weights.as_deref(),
    );
    if let (false, Some(tolerance)) = (cert.accepted(), short_of) {
        return Err(SvmError::NotConverged {
            solver,
            iterations,
            gap: cert.relative_gap,
            measure: crate::error::CERTIFIED_MISS,
            tolerance,
        });
    }
    if !cert.accepted() {
        return Err(SvmError::Uncertified {
            solver,
            stopped: if polished {
                "its exact active set was optimal to its own tolerance"
            } else {
                "its own stopping rule was met"
            },
            iterations,
            gap: cert.relative_gap,
            threshold: ACCEPT_GAP,
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
        dual_objective: cert.dual,
        primal_objective: cert.primal,
        solver: match short_of {
            Some(_) if solver == smo::NAME => SMO_AT_LIMIT,
            Some(_) => IPM_AT_LIMIT,
            None => solver,
        },
        iterations,
        polished,
        fit_seconds: 0.0,
        certified_gap: cert.relative_gap,
        resolution: cert.resolution,
        reduction: None,
    })
}

/// A linear solve that hit a limit, as its error with the certified gap of where it stopped.
fn with_certified_gap(
    kernel: &Kernel,
    data: &SvrData<'_>,
    settings: &DualSettings,
    stopped: linear_exact::Stopped,
) -> SvmError {
    let linear_exact::Stopped { error, last } = stopped;
    let Some(last) = last else {
        return error;
    };
    let reached = certificate_of(
        kernel,
        data,
        settings,
        &last.beta,
        last.bias,
        None,
        Some(&last.weights),
    )
    .relative_gap;
    match error {
        SvmError::Budget {
            solver,
            budget_s,
            iterations,
            ..
        } => SvmError::Budget {
            solver,
            budget_s,
            iterations,
            gap: reached,
            measure: crate::error::CERTIFIED_GAP,
        },
        SvmError::NotConverged {
            solver,
            iterations,
            tolerance,
            ..
        } => SvmError::NotConverged {
            solver,
            iterations,
            gap: reached,
            measure: crate::error::CERTIFIED_MISS,
            tolerance,
        },
        other => other,
    }
}

/// The certificate of (β, b): from exact primal weights when the solver has them (linear
/// kernel), else from the kernel matrix, else from kernel evaluations. Every `(Kβ)ᵢ` is a
/// compensated sum: with β ~ C = 1e11 its terms cancel to O(1).
fn certificate_of(
    kernel: &Kernel,
    data: &SvrData<'_>,
    settings: &DualSettings,
    beta: &[f64],
    bias: f64,
    k: Option<&Mat<f64>>,
    weights: Option<&[f64]>,
) -> Certificate {
    let (x, dim, y) = (data.x, data.dim, data.y);
    let n = y.len();
    let row = |i: usize| &x[i * dim..(i + 1) * dim];
    let solution = |fitted: &[Accumulator], primal_quad, dual_quad, feature_norms: &[f64]| {
        certificate::certify(&certificate::Solution {
            y,
            c: settings.c,
            epsilon: settings.epsilon,
            beta,
            bias,
            fitted,
            primal_quad,
            dual_quad,
            feature_norms,
        })
    };
    if let Some(w) = weights {
        let parts = certificate::linear_parts(x, dim, w, beta);
        return solution(&parts.fitted, parts.primal_quad, parts.dual_quad, &parts.norms);
    }
    let support: Vec<usize> = (0..n).filter(|&j| beta[j] != 0.0).collect();
    let support_beta: Vec<f64> = support.iter().map(|&j| beta[j]).collect();
    // Without the matrix, a row over the support at a time (an RBF's in a vector loop, the same
    // bits as one by one).
    let source = k
        .is_none()
        .then(|| crate::kernel::RowSource::of(kernel, x, dim, &support));
    let k_beta: Vec<Accumulator> = (0..n)
        .into_par_iter()
        .map_init(
            || vec![0.0; support.len()],
            |values, i| {
                if let Some(k) = k {
                    for (v, &j) in values.iter_mut().zip(&support) {
                        *v = k[(i, j)];
                    }
                } else if let Some(source) = &source {
                    source.row(row(i), 0, values);
                }
                crate::compensated::dot(values, &support_beta)
            },
        )
        .collect();
    let norms: Vec<f64> = (0..n)
        .map(|i| {
            let kii = match k {
                Some(k) => k[(i, i)],
                None => kernel.eval(row(i), row(i)),
            };
            kii.abs().sqrt() * (1.0 + 1e-15)
        })
        .collect();
    let quad = certificate::kernel_quad(beta, &k_beta);
    solution(&k_beta, quad, quad, &norms)
}

/// Whether a polished (β, b) is provably optimal to `relative_gap`: the same certificate as
/// every returned fit, held to the solver's own tolerance instead of [`ACCEPT_GAP`]. By weak
/// duality no primal point can then do better, whatever produced (β, b).
fn certified_optimal(
    k: &Mat<f64>,
    data: &SvrData<'_>,
    settings: &DualSettings,
    kernel: &Kernel,
    p: &polish::Polished,
    relative_gap: f64,
) -> bool {
    let cert = certificate_of(
        kernel,
        data,
        settings,
        &p.beta,
        p.bias,
        Some(k),
        p.weights.as_deref(),
    );
    cert.relative_gap <= relative_gap
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
