//! Exact active-set polish of an approximate dual solution.
//!
//! An interior point approaches the optimum from inside the box, so its β is never exactly at
//! 0 or ±C and its accuracy is limited by the conditioning of the last Newton systems. Once it
//! has told which samples are inside the tube (β = 0), outside it (β = ±C) and on its boundary
//! (free), the optimum is the solution of one linear system: for free samples
//! `Σⱼ Kᵢⱼ βⱼ + b = yᵢ ∓ ε`, and `Σ β = 0`. Solving it and checking every KKT condition gives
//! the optimum to rounding error; a violated condition moves that sample to the right set and
//! the system is solved again (a few rounds of a primal active-set method).

use std::collections::HashSet;
use std::hash::{Hash, Hasher};

use faer::Mat;
use faer::linalg::solvers::Solve;

use super::bordered::{Singular, solve_bordered_counted, svd_solve};
use super::data::SvrData;
use super::ipm::NewtonOperator;
use super::params::DualSettings;

/// Where a sample sits at the optimum.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub(crate) enum Side {
    /// Inside the tube: β = 0.
    Inside,
    /// On the upper boundary (y − f = ε): 0 ≤ β ≤ C.
    UpperFree,
    /// On the lower boundary (y − f = −ε): −C ≤ β ≤ 0.
    LowerFree,
    /// Above the tube: β = C.
    Above,
    /// Below the tube: β = −C.
    Below,
}

/// A polished solution. For a linear kernel it carries the primal weights too, which are
/// exact where `Σ βᵢ xᵢ` would lose digits to cancellation (β ~ C = 1e11, w ~ 0.1).
#[derive(Debug, Clone)]
pub(crate) struct Polished {
    pub beta: Vec<f64>,
    pub bias: f64,
    pub weights: Option<Vec<f64>>,
}

/// The active sets a polish has tried. One move per round can cycle on a degenerate problem
/// (at C = 1e11 on the needle capture a sample went Above, then UpperFree, then Above, for all
/// 720 rounds of the final polish: 12 s of dense solves that could never settle); a set met
/// again means it will not settle, and the polish gives up at once.
#[derive(Debug, Default)]
struct Tried(HashSet<u64>);

impl Tried {
    /// Whether `sides` was tried before (and now it is).
    fn again(&mut self, sides: &[Side]) -> bool {
        let mut h = std::collections::hash_map::DefaultHasher::new();
        sides.hash(&mut h);
        !self.0.insert(h.finish())
    }
}

/// What a polish spent, in flops (its products with K and the factorisations it tried, as
/// [`crate::bordered::Bordered::flops`] counts them), and what it found.
#[derive(Debug, Clone)]
pub(crate) struct Spent {
    pub flops: f64,
    pub polished: Option<Polished>,
}

/// Tries to turn `sides` into an exact optimum (`polished` is `None` if the active set does not
/// settle), beginning no round once `max_flops` are spent: a round's products with K cost `2n`
/// per column they read (see [`polish_within`]) and its bordered solve what
/// [`solve_bordered_counted`] counts, from a Cholesky of the free samples (`m³/3`) to an
/// eigendecomposition where they are nearly dependent (`9m³`).
pub(crate) fn polish(
    k: &Mat<f64>,
    y: &[f64],
    settings: &DualSettings,
    mut sides: Vec<Side>,
    max_flops: f64,
) -> Spent {
    let mut flops = 0.0;
    let polished = polish_within(k, y, settings, &mut sides, max_flops, &mut flops);
    Spent { flops, polished }
}

/// Each round needs Kβ at every sample for the KKT check, and `(Kβ_bounded)_F` for the free
/// samples' equations. Between rounds β changes only on the free samples and the one sample
/// moved, so Kβ is updated by those columns of K rather than recomputed; `(Kβ_bounded)_F` is m
/// dot products. Recomputing both over all of K took two products of n² per round: on the
/// 1 kHz needle log at n = 476 a polish of 51 rounds spent 15 % of the fit's instructions there.
/// The update's rounding is bounded as it accumulates (`ε·nnz·max Kᵢᵢ·Σ|Δβ|` per update, as
/// `|Kᵢⱼ| ≤ max Kᵢᵢ` for a PSD K), and Kβ is recomputed whole once the bound reaches a hundredth
/// of the KKT check's tolerance: the first rounds' β can be far off (on the needle, free
/// coefficients 10⁵ C), and their updates alone would drift by 1e-8. A round that finds no
/// violation recomputes Kβ whole before it accepts.
fn polish_within(
    k: &Mat<f64>,
    y: &[f64],
    settings: &DualSettings,
    sides: &mut [Side],
    max_flops: f64,
    flops: &mut f64,
) -> Option<Polished> {
    let (c, epsilon) = (settings.c, settings.epsilon);
    let n = y.len();
    let y_scale = super::data::target_scale(y);
    let column = 2.0 * n as f64;
    let mut tried = Tried::default();
    // The last round's β and Kβ, from which the next round's Kβ is updated, and the bound on
    // that Kβ's rounding error.
    let mut last: Option<(Vec<f64>, Vec<f64>, f64)> = None;
    let k_max = k.diag_max();
    let drift_limit = 1e-2 * KKT_TOLERANCE * y_scale;
    for _ in 0..2 * n + 20 {
        if *flops >= max_flops || tried.again(sides) {
            return None;
        }
        let free: Vec<usize> = (0..n)
            .filter(|&i| matches!(sides[i], Side::UpperFree | Side::LowerFree))
            .collect();
        // Each round is a dense solve that cannot be interrupted; up to 2n + 20 of them must
        // not outlast the fit's budget, so one that would not end within it is not begun.
        if !settings.has_time_to_factor(free.len() + 1) {
            return None;
        }
        let mut beta = vec![0.0; n];
        for i in 0..n {
            beta[i] = match sides[i] {
                Side::Above => c,
                Side::Below => -c,
                _ => 0.0,
            };
        }
        let bias;
        if free.is_empty() {
            // K β over the bounded samples: the fixed part of every f(xᵢ).
            let mut g_fixed = vec![0.0; n];
            super::ipm::mat_vec(k, &beta, &mut g_fixed);
            *flops += column * nonzeros(&beta);
            // No free support vector: b is any point of the interval the other samples allow;
            // take its middle (libsvm's rule), which is also where the objective is flattest.
            let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
            for i in 0..n {
                let r0 = y[i] - g_fixed[i];
                match sides[i] {
                    Side::Inside => {
                        lo = lo.max(r0 - epsilon);
                        hi = hi.min(r0 + epsilon);
                    }
                    Side::Above => hi = hi.min(r0 - epsilon),
                    Side::Below => lo = lo.max(r0 + epsilon),
                    Side::UpperFree | Side::LowerFree => {}
                }
            }
            let bounded_sum: f64 = beta.iter().sum();
            if lo > hi + 1e-12 * y_scale || bounded_sum.abs() > 1e-9 * c.max(1.0) {
                // The sets are inconsistent: let one sample become free and retry.
                let worst = (0..n).filter(|&i| sides[i] != Side::Inside).max_by(|&a, &b| {
                    margin(y, &g_fixed, a, epsilon).total_cmp(&margin(y, &g_fixed, b, epsilon))
                });
                match worst {
                    Some(i) => {
                        sides[i] = if sides[i] == Side::Above {
                            Side::UpperFree
                        } else {
                            Side::LowerFree
                        };
                        continue;
                    }
                    None => return None,
                }
            }
            bias = if lo.is_finite() && hi.is_finite() {
                0.5 * (lo + hi)
            } else if lo.is_finite() {
                lo
            } else if hi.is_finite() {
                hi
            } else {
                0.0
            };
        } else {
            // Bordered system [K_FF 1; 1ᵀ 0] [β_F; b] = [y_F ∓ ε − (Kβ_bounded)_F; −Σβ_bounded].
            let m = free.len();
            let a = Mat::<f64>::from_fn(m + 1, m + 1, |r, col| match (r < m, col < m) {
                (true, true) => k[(free[r], free[col])],
                (true, false) | (false, true) => 1.0,
                (false, false) => 0.0,
            });
            let bounded_sum: f64 = beta.iter().sum();
            // K is symmetric: row i of K β_bounded is column i's dot with β.
            *flops += column * m as f64;
            let rhs = Mat::<f64>::from_fn(m + 1, 1, |r, _| {
                if r < m {
                    let i = free[r];
                    let target = if sides[i] == Side::UpperFree {
                        y[i] - epsilon
                    } else {
                        y[i] + epsilon
                    };
                    target - super::ipm::dot(k.col_as_slice(i), &beta)
                } else {
                    -bounded_sum
                }
            });
            // Singular (more free samples than the kernel's rank plus one, as with a linear
            // kernel): the minimum-norm least squares, judged by the KKT check below.
            let solved = solve_bordered_counted(&a, &rhs, 1e-10, Singular::LeastSquares);
            let x = match solved {
                Ok(solved) => {
                    *flops += solved.flops;
                    solved.x
                }
                Err(spent) => {
                    *flops += spent;
                    return None;
                }
            };
            for (r, &i) in free.iter().enumerate() {
                beta[i] = x[r];
            }
            bias = x[m];
        }

        // Check every KKT condition; move the worst violator to where it belongs. One move per
        // round, as an active-set method does: moving every violator at once can cycle.
        let update = last.take().and_then(|(last_beta, kbeta, drift)| {
            let delta: Vec<f64> = beta.iter().zip(&last_beta).map(|(b, l)| b - l).collect();
            let drift =
                drift + f64::EPSILON * nonzeros(&delta) * k_max * delta.iter().map(|d| d.abs()).sum::<f64>();
            (drift <= drift_limit).then_some((delta, kbeta, drift))
        });
        let (kbeta, drift) = match update {
            Some((delta, mut kbeta, drift)) => {
                let k_delta = product(k, &delta, flops);
                kbeta.iter_mut().zip(&k_delta).for_each(|(a, d)| *a += d);
                (kbeta, drift)
            }
            None => (product(k, &beta, flops), 0.0),
        };
        let updated = drift > 0.0;
        let mut worst = violation(sides, &beta, &kbeta, bias, y, settings, y_scale);
        let (kbeta, drift) = if worst.is_none() && updated {
            let fresh = product(k, &beta, flops);
            worst = violation(sides, &beta, &fresh, bias, y, settings, y_scale);
            (fresh, 0.0)
        } else {
            (kbeta, drift)
        };
        let changed = match worst {
            Some(v) => {
                sides[v.sample] = v.to;
                last = Some((beta.clone(), kbeta, drift));
                true
            }
            None => false,
        };
        if !changed {
            // Clip the free coefficients' rounding excursions back into the box.
            for b in &mut beta {
                *b = b.clamp(-c, c);
            }
            return Some(Polished {
                beta,
                bias,
                weights: None,
            });
        }
    }
    None
}

/// `K β`, counting its flops.
fn product(k: &Mat<f64>, beta: &[f64], flops: &mut f64) -> Vec<f64> {
    let mut kbeta = vec![0.0; beta.len()];
    super::ipm::mat_vec(k, beta, &mut kbeta);
    *flops += 2.0 * beta.len() as f64 * nonzeros(beta);
    kbeta
}

/// Entries [`super::ipm::mat_vec`] reads a column of K for.
fn nonzeros(v: &[f64]) -> f64 {
    v.iter().filter(|x| **x != 0.0).count() as f64
}

/// The worst KKT violation at β with `kbeta = Kβ` and bias b.
fn violation(
    sides: &[Side],
    beta: &[f64],
    kbeta: &[f64],
    bias: f64,
    y: &[f64],
    settings: &DualSettings,
    y_scale: f64,
) -> Option<Violation> {
    let residuals: Vec<f64> = (0..y.len()).map(|i| y[i] - kbeta[i] - bias).collect();
    worst_violation(sides, beta, &residuals, settings, y_scale)
}

/// How far a residual may stray past the tube, relative to the targets' scale, and a
/// coefficient past its box, relative to C, before the polish counts it a violation.
const KKT_TOLERANCE: f64 = 1e-9;

/// A violated KKT condition.
#[derive(Debug, Clone, Copy)]
struct Violation {
    /// How far it is violated: a residual's excess over the tube relative to the targets'
    /// scale, or a coefficient's excursion out of its box relative to C.
    size: f64,
    /// The sample.
    sample: usize,
    /// The set the sample belongs in.
    to: Side,
}

/// The KKT condition violated most, and the set its sample belongs in.
fn worst_violation(
    sides: &[Side],
    beta: &[f64],
    residuals: &[f64],
    settings: &DualSettings,
    y_scale: f64,
) -> Option<Violation> {
    let (c, epsilon) = (settings.c, settings.epsilon);
    let tol_r = KKT_TOLERANCE * y_scale;
    let tol_b = KKT_TOLERANCE * c;
    let mut worst: Option<Violation> = None;
    for (i, (&side, &r)) in sides.iter().zip(residuals).enumerate() {
        // Violations are scaled to be comparable: residuals by the targets, β by C.
        let candidate = match side {
            Side::Inside if r > epsilon + tol_r => Some(((r - epsilon) / y_scale, Side::UpperFree)),
            Side::Inside if r < -epsilon - tol_r => Some(((-epsilon - r) / y_scale, Side::LowerFree)),
            Side::Above if r < epsilon - tol_r => Some(((epsilon - r) / y_scale, Side::UpperFree)),
            Side::Below if r > -epsilon + tol_r => Some(((r + epsilon) / y_scale, Side::LowerFree)),
            Side::UpperFree if beta[i] > c + tol_b => Some(((beta[i] - c) / c, Side::Above)),
            Side::UpperFree if r > epsilon + tol_r => Some(((r - epsilon) / y_scale, Side::Above)),
            Side::UpperFree if beta[i] < -tol_b => Some((-beta[i] / c, Side::Inside)),
            Side::UpperFree if r < epsilon - tol_r => Some(((epsilon - r) / y_scale, Side::Inside)),
            Side::LowerFree if beta[i] < -c - tol_b => Some(((-c - beta[i]) / c, Side::Below)),
            Side::LowerFree if r < -epsilon - tol_r => Some(((-epsilon - r) / y_scale, Side::Below)),
            Side::LowerFree if beta[i] > tol_b => Some((beta[i] / c, Side::Inside)),
            Side::LowerFree if r > -epsilon + tol_r => Some(((r + epsilon) / y_scale, Side::Inside)),
            _ => None,
        };
        if let Some((size, to)) = candidate
            && worst.is_none_or(|w| size > w.size)
        {
            worst = Some(Violation { size, sample: i, to });
        }
    }
    worst
}

/// The linear-kernel polish, in the primal: unknowns `(w, b, β_F)`.
///
/// With at least d + 1 free samples, `(w, b)` follows from their equations `xᵢ·w + b = yᵢ ∓ ε`
/// alone — data of order 1, no β involved — and the residuals `yᵢ − xᵢ·w − b` are then exact
/// to rounding. β_F comes from stationarity `Σ_F βᵢ xᵢ = w − Σ_U βᵢ xᵢ`, `Σ_F βᵢ = −Σ_U βᵢ`
/// (minimum norm when underdetermined); its cancellation error is far below the C-relative
/// tolerance it is checked with. With fewer free samples (moderate C), the full square system
/// is solved at once.
pub(crate) fn polish_linear(
    data: &SvrData<'_>,
    settings: &DualSettings,
    mut sides: Vec<Side>,
    max_rounds: usize,
) -> Option<Polished> {
    let (x, dim, y) = (data.x, data.dim, data.y);
    let (c, epsilon) = (settings.c, settings.epsilon);
    let n = y.len();
    let d = dim;
    let y_scale = super::data::target_scale(y);
    let row = |i: usize| &x[i * d..(i + 1) * d];
    let mut tried = Tried::default();
    for round in 0..max_rounds.min(2 * n + 20) {
        if (round > 0 && settings.over_budget()) || tried.again(&sides) {
            return None;
        }
        let free: Vec<usize> = (0..n)
            .filter(|&i| matches!(sides[i], Side::UpperFree | Side::LowerFree))
            .collect();
        let bound_beta = |i: usize| match sides[i] {
            Side::Above => c,
            Side::Below => -c,
            _ => 0.0,
        };
        let target = |i: usize| {
            if sides[i] == Side::UpperFree {
                y[i] - epsilon
            } else {
                y[i] + epsilon
            }
        };
        let bounded_sum: f64 = (0..n).map(bound_beta).sum();
        let mut bounded_moment = vec![0.0; d];
        for i in 0..n {
            let bi = bound_beta(i);
            if bi != 0.0 {
                for (m, xk) in bounded_moment.iter_mut().zip(row(i)) {
                    *m += bi * xk;
                }
            }
        }
        let (w, b, beta_free) = if free.len() > d {
            // (w, b) from the free samples' equations.
            let a = Mat::<f64>::from_fn(
                free.len(),
                d + 1,
                |r, col| {
                    if col < d { row(free[r])[col] } else { 1.0 }
                },
            );
            let t: Vec<f64> = free.iter().map(|&i| target(i)).collect();
            let wb = svd_solve(&a, &t)?;
            let w: Vec<f64> = wb.iter().take(d).copied().collect();
            let b = wb[d];
            // β_F: [x_F; 1]ᵀ β_F = [w − Σ_U βx; −Σ_U β], minimum norm.
            let s = Mat::<f64>::from_fn(
                d + 1,
                free.len(),
                |r, col| {
                    if r < d { row(free[col])[r] } else { 1.0 }
                },
            );
            let rhs: Vec<f64> = (0..=d)
                .map(|r| {
                    if r < d {
                        w[r] - bounded_moment[r]
                    } else {
                        -bounded_sum
                    }
                })
                .collect();
            (w, b, svd_solve(&s, &rhs)?)
        } else {
            // Square system in (w, b, β_F).
            let m = free.len();
            let size = d + 1 + m;
            let a = Mat::<f64>::from_fn(size, size, |r, col| {
                if r < m {
                    // xᵢ·w + b = tᵢ
                    if col < d {
                        row(free[r])[col]
                    } else if col == d {
                        1.0
                    } else {
                        0.0
                    }
                } else if r < m + d {
                    // w_k − Σ_F βᵢ x_ik = moment_k
                    let k = r - m;
                    if col == k {
                        1.0
                    } else if col > d {
                        -row(free[col - d - 1])[k]
                    } else {
                        0.0
                    }
                } else if col > d {
                    1.0
                } else {
                    0.0
                }
            });
            let rhs = Mat::<f64>::from_fn(size, 1, |r, _| {
                if r < m {
                    target(free[r])
                } else if r < m + d {
                    bounded_moment[r - m]
                } else {
                    -bounded_sum
                }
            });
            // A singular system gives non-finite values, refused below.
            let sol = a.full_piv_lu().solve(&rhs);
            (
                (0..d).map(|r| sol[(r, 0)]).collect(),
                sol[(d, 0)],
                (d + 1..size).map(|r| sol[(r, 0)]).collect(),
            )
        };
        if !b.is_finite() || w.iter().chain(&beta_free).any(|v| !v.is_finite()) {
            return None;
        }
        let mut beta: Vec<f64> = (0..n).map(bound_beta).collect();
        for (&i, &bf) in free.iter().zip(&beta_free) {
            beta[i] = bf;
        }
        let residuals: Vec<f64> = (0..n)
            .map(|i| y[i] - row(i).iter().zip(&w).map(|(a, b)| a * b).sum::<f64>() - b)
            .collect();
        let wv = worst_violation(&sides, &beta, &residuals, settings, y_scale);
        match wv {
            Some(v) if free.len() == d + 1 && matches!(v.to, Side::UpperFree | Side::LowerFree) => {
                pivot(&mut sides, &beta, &free, v, c, |k| row(k))?;
            }
            Some(v) => sides[v.sample] = v.to,
            None => {
                for v in &mut beta {
                    *v = v.clamp(-c, c);
                }
                return Some(Polished {
                    beta,
                    bias: b,
                    weights: Some(w),
                });
            }
        }
    }
    None
}

/// A sample enters a free set that already determines (w, b) (d + 1 samples): the simplex
/// pivot. Its β moves off its bound along the one direction that keeps stationarity and
/// Σβ = 0 (`δ_F = −A_F⁻¹ aᵢ` with `A_F = [x_F; 1]`), and the first free β to reach 0 or ±C
/// leaves the free set (ratio test). Adding it without one leaving would make the free
/// equations inconsistent and the active set cycle.
fn pivot<'a>(
    sides: &mut [Side],
    beta: &[f64],
    free: &[usize],
    entering: Violation,
    c: f64,
    row: impl Fn(usize) -> &'a [f64],
) -> Option<()> {
    let Violation {
        sample: entering, to, ..
    } = entering;
    let m = free.len();
    let d = m - 1;
    let a = Mat::<f64>::from_fn(m, m, |r, col| if r < d { row(free[col])[r] } else { 1.0 });
    let minus_ai = Mat::<f64>::from_fn(m, 1, |r, _| if r < d { -row(entering)[r] } else { -1.0 });
    let solved = a.partial_piv_lu().solve(&minus_ai);
    let delta: Vec<f64> = (0..m).map(|r| solved[(r, 0)]).collect();
    // A singular basis gives non-finite values: no pivot.
    if delta.iter().any(|v| !v.is_finite()) {
        return None;
    }
    // Direction of the entering β: off its current value into the side it is entering.
    let sign = if to == Side::UpperFree { 1.0 } else { -1.0 };
    let from_bound = matches!(sides[entering], Side::Above | Side::Below);
    let s = if from_bound { -sign } else { sign };
    let mut step = c;
    let mut leaving: Option<(usize, Side)> = None;
    for (r, &k) in free.iter().enumerate() {
        let rate = s * delta[r];
        let (lo, hi) = if sides[k] == Side::UpperFree {
            (0.0, c)
        } else {
            (-c, 0.0)
        };
        let t = if rate > 0.0 {
            (hi - beta[k]) / rate
        } else if rate < 0.0 {
            (lo - beta[k]) / rate
        } else {
            continue;
        };
        if t.max(0.0) < step {
            step = t.max(0.0);
            let hit_zero = (rate > 0.0 && hi == 0.0) || (rate < 0.0 && lo == 0.0);
            let side = if hit_zero {
                Side::Inside
            } else if rate > 0.0 {
                Side::Above
            } else {
                Side::Below
            };
            leaving = Some((k, side));
        }
    }
    match leaving {
        Some((k, side)) => {
            sides[k] = side;
            sides[entering] = to;
        }
        // The entering β crosses its whole range first: it moves to the other bound.
        None => {
            sides[entering] = match (from_bound, to) {
                (true, _) => Side::Inside,
                (false, Side::UpperFree) => Side::Above,
                (false, _) => Side::Below,
            };
        }
    }
    Some(())
}

/// How far a bounded sample's residual sits on the wrong side of its tube boundary.
fn margin(y: &[f64], g: &[f64], i: usize, epsilon: f64) -> f64 {
    (y[i] - g[i]).abs() - epsilon
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_active_set_met_again_is_told_apart_from_a_new_one() {
        let mut tried = Tried::default();
        let a = [Side::Inside, Side::UpperFree, Side::Above];
        let b = [Side::Inside, Side::Above, Side::Above];
        assert!(!tried.again(&a) && !tried.again(&b));
        assert!(tried.again(&a) && tried.again(&b));
        assert!(!tried.again(&[Side::Inside, Side::LowerFree, Side::Above]));
    }

    /// Started from the optimum's active set with every third sample outside the tube put
    /// back inside it, the polish moves one violator a round, on Kβ updated by columns; where it
    /// settles must be the optimum the interior point's certified fit finds (β is unique: the RBF
    /// kernel of distinct inputs is positive definite).
    #[test]
    fn a_long_polish_on_updated_products_reaches_the_certified_optimum() {
        let n = 120;
        let x: Vec<f64> = (0..n).map(|i| i as f64 / (n - 1) as f64).collect();
        // A fixed scatter of ±0.1 about a smooth curve puts most samples outside the tube.
        let y: Vec<f64> = (0..n)
            .map(|i| (6.0 * x[i]).sin() + 0.2 * ((i * 7919 % 101) as f64 / 100.0 - 0.5))
            .collect();
        let kernel = crate::Kernel::Rbf { gamma: 30.0 };
        let (c, epsilon) = (10.0, 0.05);
        let params = crate::SvrParams::builder()
            .c(c)
            .epsilon(epsilon)
            .kernel(kernel)
            .solver(crate::Solver::InteriorPoint)
            .build()
            .unwrap();
        let fitted = crate::fit(&params, &x, 1, &y).unwrap();
        assert!(fitted.relative_gap() <= 1e-9, "{}", fitted.relative_gap());
        let f: Vec<f64> = x
            .iter()
            .map(|xi| fitted.model.predict(std::slice::from_ref(xi)))
            .collect();
        let mut outside = 0;
        let sides: Vec<Side> = (0..n)
            .map(|i| {
                let r = y[i] - f[i];
                let side = match r {
                    r if r > epsilon + 1e-7 => Side::Above,
                    r if r < -epsilon - 1e-7 => Side::Below,
                    r if r > epsilon - 1e-7 => Side::UpperFree,
                    r if r < -epsilon + 1e-7 => Side::LowerFree,
                    _ => Side::Inside,
                };
                if side == Side::Inside {
                    return side;
                }
                outside += 1;
                if outside % 3 == 0 { Side::Inside } else { side }
            })
            .collect();
        assert!(outside >= 30, "{outside} samples outside the tube");

        let k = crate::kernel::kernel_matrix(&kernel, &x, 1).unwrap();
        let settings = params.dual_settings(std::time::Instant::now());
        let spent = polish(&k, &y, &settings, sides, f64::INFINITY);
        let polished = spent.polished.expect("the active set settles");
        let mut kbeta = vec![0.0; n];
        crate::ipm::mat_vec(&k, &polished.beta, &mut kbeta);
        for i in 0..n {
            let ours = kbeta[i] + polished.bias;
            assert!((ours - f[i]).abs() <= 1e-8, "sample {i}: {ours} against {}", f[i]);
        }
    }
}
