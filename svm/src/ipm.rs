//! Dense primal–dual interior point for the ε-SVR dual (Mehrotra predictor–corrector).
//!
//! The dual is solved in libsvm's split form, `z = (α, α*)`:
//! `min ½ zᵀQz + pᵀz` s.t. `aᵀz = 0`, `0 ≤ z ≤ C`, with `Q = [K −K; −K K]`, `p = (ε − y, ε + y)`,
//! `a = (1, −1)`. Why an interior point: SMO's iteration count grows with C and with the
//! conditioning of K (libsvm needs tens of millions of iterations on Li & Bi's hard-contact
//! problem at C = 1e11 and still stops far from the optimum), while a primal–dual interior
//! point converges in tens of iterations whatever C is, because each iteration is a Newton step
//! on the whole problem.
//!
//! The Newton system on the 2n variables reduces exactly to one n × n symmetric positive
//! definite system in `Δβ = Δα − Δα*`: with the barrier terms `Dα = sα/α + tα/(C − α)` (and
//! likewise `Dα*`), adding the two block rows gives `Dα Δα + Dα* Δα* = rα + rα*`, and
//! substituting back leaves `(K + H) Δβ + 1 Δλ = g` with `H = Dα Dα* / (Dα + Dα*)`, bordered by
//! the equality `1ᵀΔβ = −Σβ`. One factorisation of `K + H` per iteration serves the predictor,
//! the corrector and up to [`CENTRALITY_CORRECTORS`] of Gondzio's correctors, which lengthen
//! the step (on the needle at n = 350: 12 iterations without them, 10 with; at n = 8,000 on the
//! low-rank factor, 20 and 14).
//!
//! K enters only through [`NewtonOperator`]: the dense n × n matrix (one Cholesky per iteration,
//! O(n³)), or a low-rank factor `GGᵀ` (`crate::low_rank`, O(n r²) per iteration).

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt;
use faer::{Conj, Mat, MatMut, Par};

use super::error::SvmError;
use super::params::{DualSettings, FitProgress};

const NAME: &str = "interior point";

/// At most this many centrality correctors per iteration (Gondzio 1996).
const CENTRALITY_CORRECTORS: usize = 2;

/// Which correctors an iteration adds to Mehrotra's predictor–corrector.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Centring {
    /// Up to [`CENTRALITY_CORRECTORS`] of Gondzio's: fewer iterations, the default.
    Gondzio,
    /// Mehrotra's alone: another path to the same optimum, for a retry where a degenerate
    /// problem's end point on the first path could not be certified.
    MehrotraOnly,
}

/// The iterate at the end of the solve, with what the polish needs to read the active set.
#[derive(Debug, Clone)]
pub(crate) struct IpmSolution {
    /// α.
    pub alpha: Vec<f64>,
    /// α*.
    pub alpha_star: Vec<f64>,
    /// Multipliers of α ≥ 0 and α* ≥ 0.
    pub lower_alpha: Vec<f64>,
    pub lower_alpha_star: Vec<f64>,
    /// Slacks C − α, C − α* and their multipliers.
    pub slack_alpha: Vec<f64>,
    pub slack_alpha_star: Vec<f64>,
    pub upper_alpha: Vec<f64>,
    pub upper_alpha_star: Vec<f64>,
    /// Multiplier of Σβ = 0: the bias b.
    pub bias: f64,
    pub iterations: usize,
    /// Relative complementarity gap of this iterate.
    pub gap: f64,
    /// Whether the iterate met the solver's own criterion (else the iteration budget ran out
    /// and only a polish can still certify it).
    pub converged: bool,
}

struct Half {
    z: Vec<f64>,
    w: Vec<f64>,
    s: Vec<f64>,
    t: Vec<f64>,
}

struct Direction {
    dz: [Vec<f64>; 2],
    dw: [Vec<f64>; 2],
    ds: [Vec<f64>; 2],
    dt: [Vec<f64>; 2],
    dlambda: f64,
}

/// The kernel matrix as the interior point uses it: products with a vector, and the reduced
/// Newton matrix `K + diag(h)` factorised and solved.
pub(crate) trait NewtonOperator {
    /// A factorisation of `K + diag(h)`.
    type Factor;
    /// Relative gap below which iterates are offered to the caller's exact finish: by then the
    /// active set is mostly settled. Where to start depends on what a failed attempt costs
    /// beside an iteration, so each operator says.
    const OFFER_BELOW: f64;
    /// `out = K v` and `out_abs ≥ |K| |v|` elementwise (the scale Kβ's rounding error is
    /// relative to), in one pass where the operator allows.
    fn mat_vec_with_abs(&self, v: &[f64], out: &mut [f64], out_abs: &mut [f64]);
    /// `max |Kᵢᵢ|`.
    fn diag_max(&self) -> f64;
    /// `K + diag(h)` factorised, `None` where rounding leaves it indefinite; `spare` is the
    /// previous iteration's factor, whose storage may be reused.
    fn factor(&self, h: &[f64], spare: Option<Self::Factor>) -> Option<Self::Factor>;
    /// `(K + diag(h))⁻¹` applied in place to each column of `columns` (n × m, column-major):
    /// one pass over the factor serves several right-hand sides.
    fn solve_columns(&self, factor: &Self::Factor, columns: &mut [f64]);
}

/// The dense `K + diag(h)` factorised in place in storage kept across iterations: a fresh
/// n × n matrix each iteration (a clone of K, then faer's own copy for `llt`) put a third of a
/// profile of n = 350 fits into copies, zeroing and page faults, more than the factorisation.
pub(crate) struct DenseLlt {
    lower: Mat<f64>,
}

impl NewtonOperator for Mat<f64> {
    type Factor = DenseLlt;
    /// An iteration is a Cholesky of K, and the polish's attempts are held together to what
    /// the iterations have spent. Counted in instructions (callgrind) on the three needle
    /// problems' training sets at n = 350, 408, 432, 481: against 1e-8, 1e-7 saved an
    /// iteration on five of the twelve and 1.6 % of their sum (−8 % at most, +1.3 % on one);
    /// 1e-6 saved one on seven but cost up to 2.5× on others, whose first attempts failed.
    const OFFER_BELOW: f64 = 1e-7;

    fn mat_vec_with_abs(&self, v: &[f64], out: &mut [f64], out_abs: &mut [f64]) {
        out.fill(0.0);
        out_abs.fill(0.0);
        // Column-major storage: column by column, so the inner loop is contiguous, and one
        // pass over K (from memory at every iteration) serves both products.
        for (j, &vj) in v.iter().enumerate() {
            if vj == 0.0 {
                continue;
            }
            let abs_vj = vj.abs();
            let col = self.col(j);
            for (i, (o, a)) in out.iter_mut().zip(out_abs.iter_mut()).enumerate() {
                let kij = col[i];
                *o += kij * vj;
                *a += kij.abs() * abs_vj;
            }
        }
    }

    fn diag_max(&self) -> f64 {
        (0..self.nrows()).fold(0.0f64, |m, i| m.max(self[(i, i)].abs()))
    }

    fn factor(&self, h: &[f64], spare: Option<DenseLlt>) -> Option<DenseLlt> {
        let n = self.nrows();
        let mut lower = match spare {
            Some(f) if f.lower.nrows() == n => f.lower,
            _ => Mat::zeros(n, n),
        };
        // faer's factorisation and its solves read the lower triangle only, so only it is
        // copied (at n = 432 the whole copy was 3.9 % of a dense fit's time, the half 2.5 %).
        for (j, hj) in h.iter().enumerate() {
            let (to, from) = (&mut lower.col_as_slice_mut(j)[j..], &self.col_as_slice(j)[j..]);
            to.copy_from_slice(from);
            to[0] += hj;
        }
        let mut scratch = MemBuffer::new(llt::factor::cholesky_in_place_scratch::<f64>(
            n,
            Par::Seq,
            Default::default(),
        ));
        llt::factor::cholesky_in_place(
            lower.as_mut(),
            Default::default(),
            Par::Seq,
            MemStack::new(&mut scratch),
            Default::default(),
        )
        .ok()?;
        Some(DenseLlt { lower })
    }

    fn solve_columns(&self, factor: &DenseLlt, columns: &mut [f64]) {
        let n = self.nrows();
        let m = columns.len() / n.max(1);
        llt::solve::solve_in_place_with_conj(
            factor.lower.as_ref(),
            Conj::No,
            MatMut::from_column_major_slice_mut(columns, n, m),
            Par::Seq,
            MemStack::new(&mut []),
        );
    }
}

/// Solves the dual to relative gap `tolerance`, with the kernel matrix `k`.
///
/// Once the gap is below [`NewtonOperator::OFFER_BELOW`], `accept` is shown each iterate; when it returns true
/// (the caller polished that iterate into a certified optimum) the solve stops there.
pub(crate) fn solve<K: NewtonOperator>(
    k: &K,
    y: &[f64],
    settings: &DualSettings,
    centring: Centring,
    accept: &mut dyn FnMut(&IpmSolution) -> bool,
    observer: &dyn Fn(&FitProgress),
) -> Result<IpmSolution, SvmError> {
    let n = y.len();
    let correctors = match centring {
        Centring::Gondzio => CENTRALITY_CORRECTORS,
        Centring::MehrotraOnly => 0,
    };
    let (c, epsilon, tolerance) = (settings.c, settings.epsilon, settings.tolerance);
    let max_iterations = if settings.max_iterations == 0 {
        200
    } else {
        settings.max_iterations
    };
    // p for each half: α carries ε − y, α* carries ε + y.
    let p = [
        y.iter().map(|yi| epsilon - yi).collect::<Vec<_>>(),
        y.iter().map(|yi| epsilon + yi).collect::<Vec<_>>(),
    ];
    let p_scale = 1.0 + p.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    let y_mean = y.iter().sum::<f64>() / n as f64;

    // Start on the central path of a well-scaled point: z well inside the box, all
    // complementarity products equal. Bounded samples end at β = C, so starting near the
    // middle of the box (capped at the scale targets can justify) saves the tens of iterations
    // a start at 1 spends growing towards C: 14–16 iterations instead of 51–82 on the needle
    // fixtures.
    let z0 = (0.5 * c).min(1e3 * (1.0 + y.iter().fold(0.0f64, |m, v| m.max(v.abs()))));
    let mu0 = z0 * p_scale;
    let start = || Half {
        z: vec![z0; n],
        w: vec![c - z0; n],
        s: vec![mu0 / z0; n],
        t: vec![mu0 / (c - z0); n],
    };
    let mut h = [start(), start()];
    let mut lambda = y_mean;
    let mut kbeta = vec![0.0; n];
    let mut kbeta_abs = vec![0.0; n];
    let mut gap = f64::INFINITY;
    let mut spare = None;

    for iteration in 0..max_iterations {
        let beta: Vec<f64> = (0..n).map(|i| h[0].z[i] - h[1].z[i]).collect();
        k.mat_vec_with_abs(&beta, &mut kbeta, &mut kbeta_abs);
        // Residuals of the KKT conditions.
        let rd: [Vec<f64>; 2] = [
            (0..n)
                .map(|i| kbeta[i] + p[0][i] + lambda - h[0].s[i] + h[0].t[i])
                .collect(),
            (0..n)
                .map(|i| -kbeta[i] + p[1][i] - lambda - h[1].s[i] + h[1].t[i])
                .collect(),
        ];
        let re: f64 = beta.iter().sum();
        let ru: [Vec<f64>; 2] = [0, 1].map(|j| (0..n).map(|i| h[j].z[i] + h[j].w[i] - c).collect());
        let complementarity: f64 = h
            .iter()
            .map(|x| {
                x.z.iter().zip(&x.s).map(|(a, b)| a * b).sum::<f64>()
                    + x.w.iter().zip(&x.t).map(|(a, b)| a * b).sum::<f64>()
            })
            .sum();
        let mu = complementarity / (4 * n) as f64;
        let objective = 0.5 * dot(&beta, &kbeta)
            + (0..n)
                .map(|i| p[0][i] * h[0].z[i] + p[1][i] * h[1].z[i])
                .sum::<f64>();
        gap = complementarity / objective.abs().max(1.0);
        // Relative to the terms it balances. Kβ can be small while β ~ C = 1e11 (the terms
        // cancel), so its rounding error is ~ε_mach·Σ|Kᵢⱼβⱼ|, not ~ε_mach·|Kβ|.
        let term_scale = p_scale
            + kbeta_abs.iter().fold(0.0f64, |m, v| m.max(*v))
            + lambda.abs()
            + h.iter()
                .flat_map(|x| x.s.iter().chain(&x.t))
                .fold(0.0f64, |m, v| m.max(v.abs()));
        let dual_residual = rd.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs())) / term_scale;
        let bound_residual = ru.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs())) / (1.0 + c);
        let equality_residual = re.abs() / (1.0 + beta.iter().map(|b| b.abs()).sum::<f64>());
        let feasible = dual_residual < 1e-9 && bound_residual < 1e-12 && equality_residual < 1e-12;
        // Past 1e-100 the barrier terms head for underflow; whatever the residuals, the iterate
        // cannot improve further in double precision.
        // The caller's polish certifies optimality exactly; the iterate's own criterion is
        // only a fallback, so it is held to a tighter gap (at C = 1e11 the gap is relative to
        // an objective ~1e11 and is met long before the active set is clear).
        if (gap < tolerance * 1e-4 && feasible) || mu < 1e-100 {
            return Ok(finish(h, lambda, iteration, gap, true));
        }
        observer(&FitProgress {
            solver: NAME,
            iterations: iteration,
            gap,
            elapsed_s: settings.started.elapsed().as_secs_f64(),
        });
        if gap < K::OFFER_BELOW {
            let snapshot = finish(
                [
                    Half {
                        z: h[0].z.clone(),
                        w: h[0].w.clone(),
                        s: h[0].s.clone(),
                        t: h[0].t.clone(),
                    },
                    Half {
                        z: h[1].z.clone(),
                        w: h[1].w.clone(),
                        s: h[1].s.clone(),
                        t: h[1].t.clone(),
                    },
                ],
                lambda,
                iteration,
                gap,
                true,
            );
            if accept(&snapshot) {
                return Ok(snapshot);
            }
        }
        if settings.over_budget() {
            return Err(SvmError::Budget {
                solver: NAME,
                budget_s: settings.budget_s(),
                iterations: iteration,
                gap,
                measure: crate::error::RELATIVE_GAP,
            });
        }

        // Barrier terms and the reduced matrix K + H, factorised once for both solves.
        let d: [Vec<f64>; 2] = [0, 1].map(|j| {
            (0..n)
                .map(|i| h[j].s[i] / h[j].z[i] + h[j].t[i] / h[j].w[i])
                .collect()
        });
        let llt = factorize(k, &d, spare.take()).ok_or_else(|| SvmError::Numerical {
            solver: NAME,
            reason: format!(
                "reduced Newton matrix not positive definite at iteration {iteration}, even regularised"
            ),
        })?;
        // r = −r_d + Z⁻¹ r_zs − W⁻¹ (r_wt + T r_u) per half; the reduced right-hand side g
        // and the sum of the halves rs.
        let reduced_rhs = |rzs: &[Vec<f64>; 2], rwt: &[Vec<f64>; 2]| -> (Vec<f64>, Vec<f64>) {
            let r: [Vec<f64>; 2] = [0, 1].map(|j| {
                (0..n)
                    .map(|i| {
                        -rd[j][i] + rzs[j][i] / h[j].z[i] - (rwt[j][i] + h[j].t[i] * ru[j][i]) / h[j].w[i]
                    })
                    .collect()
            });
            let rs: Vec<f64> = (0..n).map(|i| r[0][i] + r[1][i]).collect();
            let g: Vec<f64> = (0..n)
                .map(|i| r[0][i] - d[0][i] * rs[i] / (d[0][i] + d[1][i]))
                .collect();
            (rs, g)
        };

        // Predictor: pure Newton step towards complementarity 0. Its solve shares one pass
        // over the factor with M x = 1, which the corrector reuses.
        let rzs_aff: [Vec<f64>; 2] = [0, 1].map(|j| (0..n).map(|i| -h[j].z[i] * h[j].s[i]).collect());
        let rwt_aff: [Vec<f64>; 2] = [0, 1].map(|j| (0..n).map(|i| -h[j].w[i] * h[j].t[i]).collect());
        let (rs_aff, g_aff) = reduced_rhs(&rzs_aff, &rwt_aff);
        let mut columns = vec![1.0; n];
        columns.extend_from_slice(&g_aff);
        k.solve_columns(&llt, &mut columns);
        let (m_inv_ones, m_inv_g_aff) = columns.split_at(n);
        let ones_m_inv_ones: f64 = m_inv_ones.iter().sum();

        let direction =
            |rzs: &[Vec<f64>; 2], rwt: &[Vec<f64>; 2], rs: &[f64], m_inv_g: &[f64]| -> Direction {
                let sum_g: f64 = m_inv_g.iter().sum();
                let dlambda = (sum_g + re) / ones_m_inv_ones;
                let dbeta: Vec<f64> = (0..n).map(|i| m_inv_g[i] - dlambda * m_inv_ones[i]).collect();
                let dz = [
                    (0..n)
                        .map(|i| (rs[i] + d[1][i] * dbeta[i]) / (d[0][i] + d[1][i]))
                        .collect::<Vec<_>>(),
                    (0..n)
                        .map(|i| (rs[i] - d[0][i] * dbeta[i]) / (d[0][i] + d[1][i]))
                        .collect::<Vec<_>>(),
                ];
                let ds = [0, 1].map(|j| {
                    (0..n)
                        .map(|i| (rzs[j][i] - h[j].s[i] * dz[j][i]) / h[j].z[i])
                        .collect::<Vec<_>>()
                });
                let dw = [0, 1].map(|j| (0..n).map(|i| -ru[j][i] - dz[j][i]).collect::<Vec<_>>());
                let dt = [0, 1].map(|j| {
                    (0..n)
                        .map(|i| (rwt[j][i] - h[j].t[i] * dw[j][i]) / h[j].w[i])
                        .collect::<Vec<_>>()
                });
                Direction {
                    dz,
                    dw,
                    ds,
                    dt,
                    dlambda,
                }
            };

        let aff = direction(&rzs_aff, &rwt_aff, &rs_aff, m_inv_g_aff);
        let step_aff = max_step(&h, &aff);
        let mu_aff: f64 = (0..2)
            .map(|j| {
                (0..n)
                    .map(|i| {
                        (h[j].z[i] + step_aff * aff.dz[j][i]) * (h[j].s[i] + step_aff * aff.ds[j][i])
                            + (h[j].w[i] + step_aff * aff.dw[j][i]) * (h[j].t[i] + step_aff * aff.dt[j][i])
                    })
                    .sum::<f64>()
            })
            .sum::<f64>()
            / (4 * n) as f64;
        let sigma = (mu_aff / mu).clamp(0.0, 1.0).powi(3);
        // Corrector: centring plus the second-order term of the predictor.
        let rzs: [Vec<f64>; 2] = [0, 1].map(|j| {
            (0..n)
                .map(|i| -h[j].z[i] * h[j].s[i] - aff.dz[j][i] * aff.ds[j][i] + sigma * mu)
                .collect()
        });
        let rwt: [Vec<f64>; 2] = [0, 1].map(|j| {
            (0..n)
                .map(|i| -h[j].w[i] * h[j].t[i] - aff.dw[j][i] * aff.dt[j][i] + sigma * mu)
                .collect()
        });
        let solve_for = |rzs: &[Vec<f64>; 2], rwt: &[Vec<f64>; 2]| {
            let (rs, mut m_inv_g) = reduced_rhs(rzs, rwt);
            k.solve_columns(&llt, &mut m_inv_g);
            direction(rzs, rwt, &rs, &m_inv_g)
        };
        let mut dir = solve_for(&rzs, &rwt);
        let mut reach = max_step(&h, &dir);
        // Gondzio's centrality correctors: the factor is already paid for, and a solve on it
        // costs a fraction of one, so aim a longer step at products pulled back into a band
        // around σμ, and keep the corrected direction while it does step further.
        let (mut rzs, mut rwt) = (rzs, rwt);
        for _ in 0..correctors {
            if reach >= 1.0 {
                break;
            }
            let aim = (reach + 0.2).min(1.0);
            let target = sigma * mu;
            let correction = |v: f64| (v.clamp(0.1 * target, 10.0 * target) - v).max(-10.0 * target);
            let rzs_c: [Vec<f64>; 2] = [0, 1].map(|j| {
                (0..n)
                    .map(|i| {
                        rzs[j][i]
                            + correction((h[j].z[i] + aim * dir.dz[j][i]) * (h[j].s[i] + aim * dir.ds[j][i]))
                    })
                    .collect()
            });
            let rwt_c: [Vec<f64>; 2] = [0, 1].map(|j| {
                (0..n)
                    .map(|i| {
                        rwt[j][i]
                            + correction((h[j].w[i] + aim * dir.dw[j][i]) * (h[j].t[i] + aim * dir.dt[j][i]))
                    })
                    .collect()
            });
            let corrected = solve_for(&rzs_c, &rwt_c);
            let corrected_reach = max_step(&h, &corrected);
            if corrected_reach < reach + 0.1 * (aim - reach) {
                break;
            }
            (dir, reach, rzs, rwt) = (corrected, corrected_reach, rzs_c, rwt_c);
        }
        spare = Some(llt);
        let step = (0.995 * reach).min(1.0);
        for (j, half) in h.iter_mut().enumerate() {
            for i in 0..n {
                half.z[i] += step * dir.dz[j][i];
                half.w[i] += step * dir.dw[j][i];
                half.s[i] += step * dir.ds[j][i];
                half.t[i] += step * dir.dt[j][i];
            }
        }
        lambda += step * dir.dlambda;
        if !lambda.is_finite()
            || h.iter().any(|x| {
                x.z.iter()
                    .chain(&x.s)
                    .chain(&x.w)
                    .chain(&x.t)
                    .any(|v| !v.is_finite())
            })
        {
            return Err(SvmError::Numerical {
                solver: NAME,
                reason: format!("iterate became non-finite at iteration {iteration}"),
            });
        }
    }
    Ok(finish(h, lambda, max_iterations, gap, false))
}

/// A factorisation of `K + H + δI`. K is only positive semi-definite (a linear kernel in d dimensions
/// has rank d) and H can be tiny where both bounds are far, so rounding can leave a pivot ≤ 0;
/// a small diagonal shift (primal regularisation, as in most interior-point codes) restores
/// definiteness at the cost of a slightly inexact direction, which later iterations correct.
fn factorize<K: NewtonOperator>(k: &K, d: &[Vec<f64>; 2], mut spare: Option<K::Factor>) -> Option<K::Factor> {
    let scale = 1.0 + k.diag_max();
    let mut shift = 1e-14 * scale;
    while shift < 1e-4 * scale {
        let h: Vec<f64> = d[0]
            .iter()
            .zip(&d[1])
            .map(|(a, b)| a * b / (a + b) + shift)
            .collect();
        if let Some(factor) = k.factor(&h, spare.take()) {
            return Some(factor);
        }
        shift *= 100.0;
    }
    None
}

/// Largest step in (0, 1/0.995] keeping every variable of `h` non-negative along `d`.
fn max_step(h: &[Half; 2], d: &Direction) -> f64 {
    let mut step: f64 = 1.0 / 0.995;
    for (j, half) in h.iter().enumerate() {
        for (v, dv) in [
            (&half.z, &d.dz[j]),
            (&half.w, &d.dw[j]),
            (&half.s, &d.ds[j]),
            (&half.t, &d.dt[j]),
        ] {
            for (x, dx) in v.iter().zip(dv.iter()) {
                if *dx < 0.0 {
                    step = step.min(-x / dx);
                }
            }
        }
    }
    step
}

fn finish(h: [Half; 2], bias: f64, iterations: usize, gap: f64, converged: bool) -> IpmSolution {
    let [a, s] = h;
    IpmSolution {
        alpha: a.z,
        alpha_star: s.z,
        lower_alpha: a.s,
        lower_alpha_star: s.s,
        slack_alpha: a.w,
        slack_alpha_star: s.w,
        upper_alpha: a.t,
        upper_alpha_star: s.t,
        bias,
        iterations,
        gap,
        converged,
    }
}

pub(crate) fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// `out = K v` for the dense symmetric K.
pub(crate) fn mat_vec(k: &Mat<f64>, v: &[f64], out: &mut [f64]) {
    let n = v.len();
    for o in out.iter_mut() {
        *o = 0.0;
    }
    // Column-major storage: accumulate column by column so the inner loop is contiguous.
    for (j, &vj) in v.iter().enumerate() {
        if vj == 0.0 {
            continue;
        }
        let col = k.col(j);
        for i in 0..n {
            out[i] += col[i] * vj;
        }
    }
}
