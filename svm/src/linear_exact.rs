//! The linear-kernel ε-SVR solved exactly in the primal, for inputs of low dimension.
//!
//! With a linear kernel the primal `min ½‖w‖² + C Σ max(0, |yᵢ − w·xᵢ − b| − ε)` has only
//! d + 1 unknowns θ = (w, b). It is convex and piecewise quadratic: the breakpoint hyperplanes
//! `yᵢ − aᵢ·θ = ±ε` (aᵢ = (xᵢ, 1)) cut the space into cells on each of which it is one
//! quadratic. This is the primal active-set method on that structure (the textbook method for
//! a convex QP, here on the slack formulation with the slacks eliminated): the working set is a
//! set of samples held on a tube boundary; on it the quadratic is minimised exactly by one
//! small KKT solve; a step that would carry another sample across a boundary stops there and
//! adds it (ratio test); at the minimiser, a held sample whose multiplier βᵢ leaves its range
//! ([0, C] on the upper boundary, [−C, 0] on the lower, [−C, C] when ε = 0) is released to the
//! side its multiplier points to, which strictly decreases the objective. The multipliers are
//! the dual coefficients, so the answer comes with its own dual and a duality gap.
//!
//! Why not the dual solvers: at C = 1e11…1e15 the dual coefficients are ~C while w is O(1),
//! so any method iterating on β resolves w to ~ε_mach·C digits — none. Here θ at a vertex of
//! the working set (d + 1 samples on their boundaries, the generic optimum when C is large) is
//! the solution of a (d + 1)-square system of the data alone: C only enters the multipliers.
//! Why hand-written: the workspace has no QP or LP crate, and the systems are (d+1)-square
//! (plus at most d + 1 multipliers); the work per step is one pass over the samples.
//!
//! Degenerate data are handled by the working set staying linearly independent: a sample
//! whose row lies in the span of the held rows (a duplicate, or any sample once d + 1 are
//! held) cannot move relative to its boundary along a step, so it never blocks one.

use faer::Mat;
use faer::linalg::solvers::Solve;

use super::compensated::{Accumulator, two_sum};
use super::data::SvrData;
use super::error::SvmError;
use super::params::{DualSettings, FitProgress};

/// Input dimensions up to which a linear-kernel fit is solved here (the working set is at most
/// d + 1 samples; beyond a few dimensions the dual solvers are the better tool).
pub(crate) const MAX_DIM: usize = 8;

/// The solver's name in fits and errors.
pub(crate) const NAME: &str = "linear active set";

/// Where a sample sits relative to its tube.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Label {
    /// |r| < ε: β = 0.
    Inside,
    /// r > ε: β = C.
    Above,
    /// r < −ε: β = −C.
    Below,
    /// Held on the boundary r = σε (σ = ±1; with ε = 0 the two coincide).
    Held(i8),
}

/// The exact primal solution and its multipliers.
#[derive(Debug, Clone)]
pub(crate) struct LinearSolution {
    /// Weights w.
    pub weights: Vec<f64>,
    /// Bias b.
    pub bias: f64,
    /// Dual coefficients β (C or −C outside the tube, 0 inside, the multipliers on it).
    pub beta: Vec<f64>,
    /// Active-set steps taken.
    pub iterations: usize,
}

/// A solve that hit a limit: the error, and the solution of the working set it stopped at
/// (for the caller to certify, so that the error names the gap reached).
#[derive(Debug)]
pub(crate) struct Stopped {
    /// What stopped it.
    pub error: SvmError,
    /// The working set's solution at that point, when it has one.
    pub last: Option<Box<LinearSolution>>,
}

/// Inputs mapped to `x' = (x − offset) / scale` (per column, onto [−1, 1]): the active-set
/// systems are then well conditioned whatever the units (inputs ~1e6 with a spread of 1 would
/// otherwise make every pair of rows (xᵢ, 1) look parallel).
struct Rows {
    a: Vec<f64>,
    m: usize,
    offset: Vec<f64>,
    scale: Vec<f64>,
}

impl Rows {
    fn new(x: &[f64], d: usize) -> Self {
        let n = x.len() / d;
        let m = d + 1;
        let mut offset = vec![0.0; d];
        let mut scale = vec![1.0; d];
        for k in 0..d {
            let col = x.iter().skip(k).step_by(d);
            let lo = col.clone().fold(f64::INFINITY, |a, &v| a.min(v));
            let hi = col.fold(f64::NEG_INFINITY, |a, &v| a.max(v));
            offset[k] = 0.5 * lo + 0.5 * hi;
            let half = 0.5 * hi - 0.5 * lo;
            if half > 0.0 {
                scale[k] = half;
            }
        }
        let mut a = vec![0.0; n * m];
        for i in 0..n {
            for k in 0..d {
                a[i * m + k] = (x[i * d + k] - offset[k]) / scale[k];
            }
            a[i * m + d] = 1.0;
        }
        Self { a, m, offset, scale }
    }

    fn row(&self, i: usize) -> &[f64] {
        &self.a[i * self.m..(i + 1) * self.m]
    }

    fn dot(&self, i: usize, v: &[f64]) -> f64 {
        self.row(i).iter().zip(v).map(|(a, b)| a * b).sum()
    }
}

/// Solves the primal exactly (to the rounding of a (d + 1)-square system), or says which limit
/// stopped it.
pub(crate) fn solve(
    data: &SvrData<'_>,
    settings: &DualSettings,
    observer: &dyn Fn(&FitProgress),
) -> Result<LinearSolution, Box<Stopped>> {
    let (x, d, y) = (data.x, data.dim, data.y);
    let (c, epsilon) = (settings.c, settings.epsilon);
    let n = y.len();
    let rows = Rows::new(x, d);
    let m = rows.m;
    // ½‖w‖² in the scaled coordinates: w'ₖ = wₖ·scaleₖ.
    let h: Vec<f64> = (0..m)
        .map(|k| {
            if k < d {
                1.0 / (rows.scale[k] * rows.scale[k])
            } else {
                0.0
            }
        })
        .collect();
    let max_iterations = if settings.max_iterations == 0 {
        50 * (n + m) + 1000
    } else {
        settings.max_iterations
    };

    // Start from the least-squares line (most samples already on their final side), or from
    // the median when it is not determined.
    let mut theta = least_squares(&rows, y).unwrap_or_else(|| {
        let mut t = vec![0.0; m];
        t[d] = median(y);
        t
    });
    let mut labels: Vec<Label> = (0..n)
        .map(|i| {
            let r = y[i] - rows.dot(i, &theta);
            if r > epsilon {
                Label::Above
            } else if r < -epsilon {
                Label::Below
            } else {
                Label::Inside
            }
        })
        .collect();
    let mut held: Vec<usize> = Vec::new();
    let mut residual = vec![0.0; n];
    let mut rate = vec![0.0; n];

    for iteration in 0..max_iterations {
        if iteration % 32 == 31 {
            observer(&FitProgress {
                solver: NAME,
                iterations: iteration,
                gap: f64::INFINITY,
                elapsed_s: settings.started.elapsed().as_secs_f64(),
            });
        }
        if iteration % 32 == 31 && settings.over_budget() {
            return Err(Box::new(Stopped {
                error: SvmError::Budget {
                    solver: NAME,
                    budget_s: settings.budget_s(),
                    iterations: iteration,
                    gap: f64::INFINITY,
                    measure: crate::error::NOTHING_TO_CERTIFY,
                },
                last: Some(Box::new(finish(
                    &rows, x, d, y, c, epsilon, &labels, &held, &h, iteration,
                ))),
            }));
        }
        let g = side_sums(&rows, x, &labels);
        // Minimiser of the current piece's quadratic on the working set, or a ray along
        // which it decreases without bound (nothing held and more samples on one side).
        let (direction, max_step, multipliers) = if held.is_empty() {
            let gb = g[d].value();
            if gb != 0.0 {
                let mut p = vec![0.0; m];
                p[d] = -gb.signum();
                (p, f64::INFINITY, None)
            } else {
                let p: Vec<f64> = (0..m)
                    .map(|k| {
                        if k < d {
                            -c * g[k].value() / h[k] - theta[k]
                        } else {
                            0.0
                        }
                    })
                    .collect();
                (p, 1.0, None)
            }
        } else {
            let solution = kkt(&rows, &h, c, &g, &held, &labels, y, epsilon).ok_or_else(|| {
                Box::new(Stopped {
                    error: SvmError::Numerical {
                        solver: NAME,
                        reason: format!("singular working-set system at step {iteration}"),
                    },
                    last: None,
                })
            })?;
            let p: Vec<f64> = solution.theta.iter().zip(&theta).map(|(t, v)| t - v).collect();
            (p, 1.0, Some(solution))
        };

        // Ratio test: the first sample a step along `direction` carries onto a boundary.
        let p_scale = direction.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let theta_scale = theta.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        for i in 0..n {
            residual[i] = y[i] - rows.dot(i, &theta);
            rate[i] = rows.dot(i, &direction);
        }
        let target_scale = theta
            .iter()
            .zip(&direction)
            .fold(0.0f64, |a, (t, p)| a.max((t + p).abs()));
        // Along the step r changes by −α·s; |s| at the rounding level of θ and of the step's
        // end means the row is (numerically) parallel to the held ones: it does not move.
        let noise =
            16.0 * f64::EPSILON * (m as f64) * (theta_scale + target_scale.min(p_scale.max(theta_scale)));
        let mut excluded = vec![false; n];
        let blocking = loop {
            let mut best: Option<(f64, usize, i8)> = None;
            for i in 0..n {
                let label = labels[i];
                if matches!(label, Label::Held(_)) || excluded[i] {
                    continue;
                }
                let s = rate[i];
                if s.abs() <= noise {
                    continue;
                }
                let r = residual[i];
                let hit = match label {
                    Label::Inside if s < 0.0 => Some(((epsilon - r) / -s, 1)),
                    Label::Inside => Some(((r + epsilon) / s, -1)),
                    Label::Above if s > 0.0 => Some(((r - epsilon) / s, 1)),
                    Label::Below if s < 0.0 => Some(((r + epsilon) / s, -1)),
                    _ => None,
                };
                if let Some((step, sigma)) = hit {
                    let step = step.max(0.0);
                    if step < max_step && best.is_none_or(|(b, _, _)| step < b) {
                        best = Some((step, i, sigma));
                    }
                }
            }
            match best {
                Some((_, i, _)) if !independent(&rows, &held, i) => excluded[i] = true,
                other => break other,
            }
        };

        match blocking {
            Some((step, i, sigma)) => {
                for (t, p) in theta.iter_mut().zip(&direction) {
                    *t += step * p;
                }
                labels[i] = Label::Held(if epsilon == 0.0 { 1 } else { sigma });
                held.push(i);
            }
            None if max_step.is_infinite() => {
                return Err(Box::new(Stopped {
                    error: SvmError::Numerical {
                        solver: NAME,
                        reason: "the objective decreases without bound along the bias".into(),
                    },
                    last: None,
                }));
            }
            None => {
                for (t, p) in theta.iter_mut().zip(&direction) {
                    *t += p;
                }
                // At the working set's minimiser: release the held sample whose multiplier is
                // furthest out of its range, or stop. β = Cμ + ν is compared with its bounds with
                // μ's part snapped to the bound where μ (O(1), from the data) sits on it to its
                // rounding: then ν alone decides, however large C is. Tolerances scale with the
                // terms each part is solved from, never with C alone.
                let mut worst: Option<(f64, usize, Label)> = None;
                if let Some(kkt) = &multipliers {
                    let mu_tol = 1e-12 * (1.0 + kkt.mu.iter().fold(0.0f64, |a, v| a.max(v.abs())));
                    let h_theta = h
                        .iter()
                        .zip(&theta)
                        .fold(0.0f64, |a, (hk, t)| a.max((hk * t).abs()));
                    let nu_tol = 1e-11 * (h_theta + kkt.nu.iter().fold(0.0f64, |a, v| a.max(v.abs())));
                    // How far C·μ_shift + ν is above 0, if it is.
                    let above = |mu_shift: f64, nu: f64| -> Option<f64> {
                        let mu_shift = if mu_shift.abs() <= mu_tol { 0.0 } else { mu_shift };
                        let value = c * mu_shift + nu;
                        (value > 1e-12 * c * mu_shift.abs() + nu_tol).then_some(value)
                    };
                    for (slot, ((&i, &mu), &nu)) in held.iter().zip(&kkt.mu).zip(&kkt.nu).enumerate() {
                        let Label::Held(sigma) = labels[i] else {
                            continue;
                        };
                        let (lo, hi) = range(sigma, epsilon, c);
                        let hi_unit = if hi == 0.0 { 0.0 } else { 1.0 };
                        let lo_unit = if lo == 0.0 { 0.0 } else { -1.0 };
                        let out = if let Some(size) = above(mu - hi_unit, nu) {
                            Some((size, if hi == 0.0 { Label::Inside } else { Label::Above }))
                        } else {
                            above(lo_unit - mu, -nu)
                                .map(|size| (size, if lo == 0.0 { Label::Inside } else { Label::Below }))
                        };
                        if let Some((size, to)) = out
                            && worst.is_none_or(|(s, _, _)| size > s)
                        {
                            worst = Some((size, slot, to));
                        }
                    }
                }
                match worst {
                    Some((_, slot, to)) => {
                        let i = held.remove(slot);
                        labels[i] = to;
                    }
                    None => return Ok(finish(&rows, x, d, y, c, epsilon, &labels, &held, &h, iteration)),
                }
            }
        }
    }
    Err(Box::new(Stopped {
        error: SvmError::NotConverged {
            solver: NAME,
            iterations: max_iterations,
            gap: f64::INFINITY,
            measure: crate::error::NOTHING_TO_CERTIFY,
            tolerance: settings.tolerance,
        },
        last: Some(Box::new(finish(
            &rows,
            x,
            d,
            y,
            c,
            epsilon,
            &labels,
            &held,
            &h,
            max_iterations,
        ))),
    }))
}

/// The multiplier range of a held sample.
fn range(sigma: i8, epsilon: f64, c: f64) -> (f64, f64) {
    if epsilon == 0.0 {
        (-c, c)
    } else if sigma > 0 {
        (0.0, c)
    } else {
        (-c, 0.0)
    }
}

/// The target a held sample's equation pins: `aᵢ·θ = yᵢ − σε`, as an unevaluated pair.
fn held_target(y: f64, sigma: i8, epsilon: f64) -> (f64, f64) {
    two_sum(y, -f64::from(sigma) * epsilon)
}

/// The loss's linear part per unit C, `ĝ = Σ_below aᵢ − Σ_above aᵢ` (the gradient is Cĝ), in
/// the scaled coordinates. Kept apart from C so that the multipliers can be split as
/// `β = Cμ + ν`. Summed over the caller's inputs (compensated) and scaled once,
/// `(Σ±xᵢ − offset·Σ±1) / scale`: balanced sides then give exactly 0, as they must for the
/// optimum of the loss to be told apart from the rounding of scaled inputs at C = 1e13.
fn side_sums(rows: &Rows, x: &[f64], labels: &[Label]) -> Vec<Accumulator> {
    let m = rows.m;
    let d = m - 1;
    let mut sums = vec![Accumulator::new(); d];
    let mut count = 0i64;
    for (i, label) in labels.iter().enumerate() {
        let sign: i32 = match label {
            Label::Above => -1,
            Label::Below => 1,
            _ => continue,
        };
        count += i64::from(sign);
        for (k, acc) in sums.iter_mut().enumerate() {
            acc.add(f64::from(sign) * x[i * d + k]);
        }
    }
    let mut g: Vec<Accumulator> = sums
        .into_iter()
        .enumerate()
        .map(|(k, mut acc)| {
            acc.add_product(-rows.offset[k], count as f64);
            let mut scaled = Accumulator::new();
            scaled.add(acc.value() / rows.scale[k]);
            scaled
        })
        .collect();
    let mut b = Accumulator::new();
    b.add(count as f64);
    g.push(b);
    g
}

/// The working set's minimiser and multipliers, `β = Cμ + ν`.
struct Kkt {
    theta: Vec<f64>,
    /// The multipliers' part proportional to C (from the loss's linear part).
    mu: Vec<f64>,
    /// The rest (from ½‖w‖² and the targets).
    nu: Vec<f64>,
}

/// Minimiser of `½θᵀHθ + Cĝᵀθ` subject to the held samples' equations, with their multipliers:
/// `[H −Aᵀ; A 0] [θ; β] = [−Cĝ; t]`. The system is linear in (Cĝ, t), so it is solved twice —
/// for `[−ĝ; 0]` (giving θ₁, μ) and for `[0; t]` (giving θ₂, ν) — and `θ = Cθ₁ + θ₂`,
/// `β = Cμ + ν`. At C = 1e13 the part of β that decides between two optima of the loss (ν,
/// from ½‖w‖²) is 1e-18 of β: only split is it resolved. Each solve is a pivoted LU with
/// iterative refinement on compensated residuals.
#[allow(clippy::too_many_arguments)]
fn kkt(
    rows: &Rows,
    h: &[f64],
    c: f64,
    g: &[Accumulator],
    held: &[usize],
    labels: &[Label],
    y: &[f64],
    epsilon: f64,
) -> Option<Kkt> {
    let m = rows.m;
    let k = held.len();
    let size = m + k;
    let matrix = Mat::<f64>::from_fn(size, size, |r, col| match (r < m, col < m) {
        (true, true) => {
            if r == col {
                h[r]
            } else {
                0.0
            }
        }
        (true, false) => -rows.row(held[col - m])[r],
        (false, true) => rows.row(held[r - m])[col],
        (false, false) => 0.0,
    });
    let targets: Vec<(f64, f64)> = held
        .iter()
        .map(|&i| {
            let Label::Held(sigma) = labels[i] else {
                return (y[i], 0.0);
            };
            held_target(y[i], sigma, epsilon)
        })
        .collect();
    let lu = matrix.full_piv_lu();
    let solve = |linear_part: bool| -> Option<Vec<f64>> {
        let mut solution = vec![0.0; size];
        for _round in 0..3 {
            // Residual of the full system at the current solution, compensated.
            let residual = Mat::<f64>::from_fn(size, 1, |r, _| {
                let mut acc = Accumulator::new();
                if r < m {
                    if linear_part {
                        acc.add_sum(&g[r].negated());
                    }
                    acc.add_product(-h[r], solution[r]);
                    for (j, &i) in held.iter().enumerate() {
                        acc.add_product(rows.row(i)[r], solution[m + j]);
                    }
                } else {
                    let j = r - m;
                    if !linear_part {
                        acc.add(targets[j].0);
                        acc.add(targets[j].1);
                    }
                    for (col, a) in rows.row(held[j]).iter().enumerate() {
                        acc.add_product(-a, solution[col]);
                    }
                }
                acc.value()
            });
            let correction = lu.solve(&residual);
            for (r, v) in solution.iter_mut().enumerate() {
                *v += correction[(r, 0)];
            }
            if solution.iter().any(|v| !v.is_finite()) {
                return None;
            }
        }
        Some(solution)
    };
    let mut first = solve(true)?;
    let second = solve(false)?;
    // θ₁ = 0 exactly when A is square (Aθ₁ = 0), and when the loss's gradient is balanced by the
    // held rows (Hθ₁ = Aᵀμ − ĝ = 0; H is definite on A's null space). Rounding leaves θ₁ at
    // ~1e-17 there, which C = 1e13 would turn into a step that swamps the ½‖w‖² part deciding
    // between optima of the loss.
    let g_scale = g.iter().fold(0.0f64, |a, v| a.max(v.value().abs()));
    let mu_scale = first[m..].iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let h_theta1 = (0..m).fold(0.0f64, |a, r| a.max((h[r] * first[r]).abs()));
    if k == m || h_theta1 <= 1e-12 * (g_scale + m as f64 * mu_scale) {
        first[..m].fill(0.0);
    }
    let theta: Vec<f64> = (0..m).map(|r| c * first[r] + second[r]).collect();
    theta.iter().all(|v| v.is_finite()).then(|| Kkt {
        theta,
        mu: first[m..].to_vec(),
        nu: second[m..].to_vec(),
    })
}

/// Whether sample `i`'s row is linearly independent of the held rows (relative to its norm;
/// rows are scaled, so 1e-10 separates genuine from rounding-level independence).
fn independent(rows: &Rows, held: &[usize], i: usize) -> bool {
    let m = rows.m;
    if held.len() >= m {
        return false;
    }
    // Gram–Schmidt (twice, for stability) of the held rows, then the candidate's remainder.
    let mut basis: Vec<Vec<f64>> = Vec::with_capacity(held.len());
    let orthogonalise = |v: &mut Vec<f64>, basis: &[Vec<f64>]| {
        for _ in 0..2 {
            for q in basis {
                let proj: f64 = v.iter().zip(q).map(|(a, b)| a * b).sum();
                for (vk, qk) in v.iter_mut().zip(q) {
                    *vk -= proj * qk;
                }
            }
        }
    };
    for &j in held {
        let mut v = rows.row(j).to_vec();
        orthogonalise(&mut v, &basis);
        let norm = v.iter().map(|a| a * a).sum::<f64>().sqrt();
        if norm > 0.0 {
            basis.push(v.iter().map(|a| a / norm).collect());
        }
    }
    let mut v = rows.row(i).to_vec();
    let norm0 = v.iter().map(|a| a * a).sum::<f64>().sqrt();
    orthogonalise(&mut v, &basis);
    let norm = v.iter().map(|a| a * a).sum::<f64>().sqrt();
    norm > 1e-10 * norm0
}

/// Least-squares θ in the scaled coordinates (normal equations, well conditioned there), or
/// `None` when the rows do not determine it.
fn least_squares(rows: &Rows, y: &[f64]) -> Option<Vec<f64>> {
    let m = rows.m;
    let n = y.len();
    if n < m {
        return None;
    }
    let mut ata = Mat::<f64>::zeros(m, m);
    let mut aty = Mat::<f64>::zeros(m, 1);
    for (i, yi) in y.iter().enumerate() {
        let a = rows.row(i);
        for r in 0..m {
            aty[(r, 0)] += a[r] * yi;
            for col in 0..m {
                ata[(r, col)] += a[r] * a[col];
            }
        }
    }
    let sol = ata.full_piv_lu().solve(&aty);
    let theta: Vec<f64> = (0..m).map(|r| sol[(r, 0)]).collect();
    let scale = 1.0 + y.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    theta
        .iter()
        .all(|v| v.is_finite() && v.abs() < 1e12 * scale)
        .then_some(theta)
}

fn median(y: &[f64]) -> f64 {
    let mut s = y.to_vec();
    s.sort_by(f64::total_cmp);
    s[s.len() / 2]
}

/// The solution in the caller's coordinates, with every sample's β.
#[allow(clippy::too_many_arguments)]
fn finish(
    rows: &Rows,
    x: &[f64],
    d: usize,
    y: &[f64],
    c: f64,
    epsilon: f64,
    labels: &[Label],
    held: &[usize],
    h: &[f64],
    iterations: usize,
) -> LinearSolution {
    let m = rows.m;
    let n = y.len();
    let g = side_sums(rows, x, labels);
    let (theta, multipliers) = if held.is_empty() {
        // Nothing held: w' = −g'/h, and b' anywhere that keeps every sample on its side — the
        // midpoint of the feasible interval.
        let w: Vec<f64> = (0..d).map(|k| -c * g[k].value() / h[k]).collect();
        let mut theta = w.clone();
        theta.push(0.0);
        let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
        for i in 0..n {
            let r0 = y[i] - rows.dot(i, &theta);
            let (l, u) = match labels[i] {
                Label::Inside => (r0 - epsilon, r0 + epsilon),
                Label::Above => (f64::NEG_INFINITY, r0 - epsilon),
                Label::Below => (r0 + epsilon, f64::INFINITY),
                Label::Held(_) => continue,
            };
            lo = lo.max(l);
            hi = hi.min(u);
        }
        theta[d] = match (lo.is_finite(), hi.is_finite()) {
            (true, true) => 0.5 * (lo + hi),
            (true, false) => lo,
            (false, true) => hi,
            (false, false) => 0.0,
        };
        (theta, Vec::new())
    } else {
        // The last step ended at exactly this system's solution.
        match kkt(rows, h, c, &g, held, labels, y, epsilon) {
            Some(k) => {
                let beta = k.mu.iter().zip(&k.nu).map(|(mu, nu)| c * mu + nu).collect();
                (k.theta, beta)
            }
            None => (vec![0.0; m], vec![0.0; held.len()]),
        }
    };
    let mut beta: Vec<f64> = labels
        .iter()
        .map(|l| match l {
            Label::Above => c,
            Label::Below => -c,
            _ => 0.0,
        })
        .collect();
    for (&i, &b) in held.iter().zip(&multipliers) {
        let Label::Held(sigma) = labels[i] else {
            continue;
        };
        let (lo, hi) = range(sigma, epsilon, c);
        beta[i] = b.clamp(lo, hi);
    }
    // Σβ = 0 to the last bit the held multipliers allow: the one with the most room absorbs
    // the compensated remainder (clipping and rounding leave ~ε_mach·C).
    let mut sum = Accumulator::new();
    for b in &beta {
        sum.add(*b);
    }
    let s = sum.value();
    if s != 0.0
        && let Some(&j) = held.iter().max_by(|&&a, &&b| {
            let room = |i: usize| {
                let Label::Held(sigma) = labels[i] else {
                    return 0.0;
                };
                let (lo, hi) = range(sigma, epsilon, c);
                (beta[i] - lo).min(hi - beta[i])
            };
            room(a).total_cmp(&room(b))
        })
        && let Label::Held(sigma) = labels[j]
    {
        let (lo, hi) = range(sigma, epsilon, c);
        beta[j] = (beta[j] - s).clamp(lo, hi);
    }
    // Back to the caller's units: w = w'/scale, b = b' − w·offset.
    let mut weights: Vec<f64> = (0..d).map(|k| theta[k] / rows.scale[k]).collect();
    let mut bias = {
        let mut acc = Accumulator::new();
        acc.add(theta[d]);
        for (w, o) in weights.iter().zip(&rows.offset) {
            acc.add_product(-w, *o);
        }
        acc.value()
    };
    if held.len() == m {
        refine_vertex(rows, x, d, y, epsilon, labels, held, &mut weights, &mut bias);
    }
    LinearSolution {
        weights,
        bias,
        beta,
        iterations,
    }
}

/// At a vertex (d + 1 held samples) θ is the solution of their equations alone; the
/// conversion back to the caller's units rounds it, so the equations are re-solved there by
/// iterative refinement: residuals in the caller's units (compensated), corrections through
/// the scaled system (well conditioned) mapped back.
#[allow(clippy::too_many_arguments)]
fn refine_vertex(
    rows: &Rows,
    x: &[f64],
    d: usize,
    y: &[f64],
    epsilon: f64,
    labels: &[Label],
    held: &[usize],
    weights: &mut [f64],
    bias: &mut f64,
) {
    let m = rows.m;
    let lu = Mat::<f64>::from_fn(m, m, |r, col| rows.row(held[r])[col]).full_piv_lu();
    for _round in 0..2 {
        let residual = Mat::<f64>::from_fn(m, 1, |r, _| {
            let i = held[r];
            let sigma = match labels[i] {
                Label::Held(s) => s,
                _ => 0,
            };
            let (t, t_lo) = held_target(y[i], sigma, epsilon);
            let mut acc = Accumulator::new();
            acc.add(t);
            acc.add(t_lo);
            acc.add(-*bias);
            for k in 0..d {
                acc.add_product(-x[i * d + k], weights[k]);
            }
            acc.value()
        });
        let delta = lu.solve(&residual);
        let dw: Vec<f64> = (0..d).map(|k| delta[(k, 0)] / rows.scale[k]).collect();
        let mut db = Accumulator::new();
        db.add(delta[(d, 0)]);
        for (w, o) in dw.iter().zip(&rows.offset) {
            db.add_product(-w, *o);
        }
        if dw.iter().any(|v| !v.is_finite()) || !db.value().is_finite() {
            return;
        }
        for (w, v) in weights.iter_mut().zip(&dw) {
            *w += v;
        }
        *bias += db.value();
    }
}
