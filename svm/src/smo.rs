//! Sequential minimal optimisation for the ε-SVR dual (Fan, Chen & Lin, "Working set selection
//! using second order information", JMLR 6, 2005 — libsvm's algorithm).
//!
//! Each iteration changes two of the 2n variables of the split dual analytically, chosen by the
//! second-order rule, so an iteration costs two kernel rows and O(n) gradient updates. That
//! scales to n where the dense interior point's n² memory and n³ factorisations do not; its
//! weakness is the iteration count at large C, which is why [`super::Solver::Auto`] uses it only
//! beyond [`super::SvrParams::DENSE_LIMIT`] samples. Kernel rows are cached (least recently used
//! slots within a memory budget).

use std::time::Instant;

use super::error::SvrError;
use super::kernel::Kernel;

pub(crate) const NAME: &str = "SMO";

/// Memory for cached kernel rows.
const CACHE_BYTES: usize = 256 << 20;
/// Curvature floor for non-positive-definite pairs (libsvm's τ).
const TAU: f64 = 1e-12;

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

/// Recomputes the gradient of every variable outside `active` from scratch,
/// `∇ₜ = pₜ + Σⱼ yₜ yⱼ K(sₜ, sⱼ) αⱼ`, over the non-zero α only.
#[allow(clippy::too_many_arguments)]
fn rebuild_gradient(
    grad: &mut [f64],
    alpha: &[f64],
    active: &[usize],
    cache: &mut RowCache<'_>,
    y: &[f64],
    epsilon: f64,
    n: usize,
) {
    let m = 2 * n;
    let mut inactive = vec![true; m];
    for &t in active {
        inactive[t] = false;
    }
    if !inactive.iter().any(|&v| v) {
        return;
    }
    for t in (0..m).filter(|&t| inactive[t]) {
        grad[t] = if t < n { epsilon - y[t] } else { epsilon + y[t - n] };
    }
    for (j, &aj) in alpha.iter().enumerate() {
        if aj == 0.0 {
            continue;
        }
        let (yj, sj) = if j < n { (1.0, j) } else { (-1.0, j - n) };
        let row = cache.row(sj);
        for t in (0..m).filter(|&t| inactive[t]) {
            let (yt, st) = if t < n { (1.0, t) } else { (-1.0, t - n) };
            grad[t] += yt * yj * row[st] * aj;
        }
    }
}

pub(crate) struct SmoSolution {
    pub beta: Vec<f64>,
    pub bias: f64,
    pub iterations: usize,
}

struct RowCache<'a> {
    kernel: &'a Kernel,
    x: &'a [f64],
    dim: usize,
    n: usize,
    slot_of: Vec<Option<usize>>,
    owner: Vec<usize>,
    last_used: Vec<u64>,
    rows: Vec<f64>,
    clock: u64,
}

impl<'a> RowCache<'a> {
    fn new(kernel: &'a Kernel, x: &'a [f64], dim: usize, n: usize) -> Self {
        let slots = (CACHE_BYTES / (8 * n.max(1))).clamp(2, n.max(2));
        Self {
            kernel,
            x,
            dim,
            n,
            slot_of: vec![None; n],
            owner: vec![usize::MAX; slots],
            last_used: vec![0; slots],
            rows: vec![0.0; slots * n],
            clock: 0,
        }
    }

    /// Row i of K (all n samples).
    fn row(&mut self, i: usize) -> &[f64] {
        self.clock += 1;
        let n = self.n;
        let slot = match self.slot_of[i] {
            Some(s) => s,
            None => {
                let s = (0..self.owner.len())
                    .min_by_key(|&s| self.last_used[s])
                    .unwrap_or(0);
                if self.owner[s] != usize::MAX {
                    self.slot_of[self.owner[s]] = None;
                }
                self.owner[s] = i;
                self.slot_of[i] = Some(s);
                let xi = &self.x[i * self.dim..(i + 1) * self.dim];
                for j in 0..n {
                    self.rows[s * n + j] = self.kernel.eval(xi, &self.x[j * self.dim..(j + 1) * self.dim]);
                }
                s
            }
        };
        self.last_used[slot] = self.clock;
        &self.rows[slot * n..(slot + 1) * n]
    }
}

/// Solves the dual until the maximal KKT violation is below `1e2 · tolerance · (1 + max|y|)`
/// (1e-8 relative at the default tolerance 1e-10, which keeps the duality gap under
/// [`super::ACCEPT_GAP`]).
#[allow(clippy::too_many_arguments)]
pub(crate) fn solve(
    kernel: &Kernel,
    x: &[f64],
    dim: usize,
    y: &[f64],
    c: f64,
    epsilon: f64,
    tolerance: f64,
    max_iterations: usize,
    started: Instant,
    budget_s: f64,
) -> Result<SmoSolution, SvrError> {
    let n = y.len();
    let m = 2 * n;
    let stop = 1e2 * tolerance * (1.0 + y.iter().fold(0.0f64, |a, v| a.max(v.abs())));
    let max_iterations = if max_iterations == 0 {
        (100 * m).max(10_000_000)
    } else {
        max_iterations
    };
    // Variable t < n is αₜ (label +1, p = ε − y), t ≥ n is α*ₜ₋ₙ (label −1, p = ε + y).
    let label = |t: usize| if t < n { 1.0 } else { -1.0 };
    let sample = |t: usize| if t < n { t } else { t - n };
    let mut alpha = vec![0.0; m];
    let mut grad: Vec<f64> = (0..m)
        .map(|t| if t < n { epsilon - y[t] } else { epsilon + y[t - n] })
        .collect();
    let diag: Vec<f64> = (0..n)
        .map(|i| kernel.eval(&x[i * dim..(i + 1) * dim], &x[i * dim..(i + 1) * dim]))
        .collect();
    let mut cache = RowCache::new(kernel, x, dim, n);
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
    let mut ki = vec![0.0; n];
    let mut kj = vec![0.0; n];
    let mut iterations = 0;
    let mut violation = f64::INFINITY;
    while iterations < max_iterations {
        if iterations % 1000 == 0 && started.elapsed().as_secs_f64() > budget_s {
            return Err(SvrError::Budget {
                solver: NAME,
                budget_s,
                iterations,
                gap: violation,
            });
        }
        counter -= 1;
        if counter == 0 {
            counter = shrink_every;
            let (g_up, g_low) = extremes(&active, &alpha, &grad, label, in_up, in_low);
            if !unshrunk && g_up + g_low <= 10.0 * stop {
                // Close to the end: bring everything back once, with exact gradients.
                unshrunk = true;
                rebuild_gradient(&mut grad, &alpha, &active, &mut cache, y, epsilon, n);
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
        if i_sel != usize::MAX {
            ki.copy_from_slice(cache.row(sample(i_sel)));
            let si = sample(i_sel);
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
                    let a = (diag[si] + diag[st] - 2.0 * ki[st]).max(TAU);
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
                rebuild_gradient(&mut grad, &alpha, &active, &mut cache, y, epsilon, n);
                active = (0..m).collect();
                counter = shrink_every;
                continue;
            }
            break;
        }
        let yi = label(i_sel);
        let si = sample(i_sel);
        let yj = label(j_sel);
        let sj = sample(j_sel);
        kj.copy_from_slice(cache.row(sj));
        // Analytic two-variable step, clipped to the box (libsvm's update).
        let qii = diag[si];
        let qjj = diag[sj];
        let qij = yi * yj * ki[sj];
        let (old_i, old_j) = (alpha[i_sel], alpha[j_sel]);
        if yi != yj {
            let quad = (qii + qjj + 2.0 * qij).max(TAU);
            let delta = (-grad[i_sel] - grad[j_sel]) / quad;
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
            alpha[i_sel] = ai;
            alpha[j_sel] = aj;
        } else {
            let quad = (qii + qjj - 2.0 * qij).max(TAU);
            let delta = (grad[i_sel] - grad[j_sel]) / quad;
            let sum = old_i + old_j;
            let (mut ai, mut aj) = (old_i - delta, old_j + delta);
            if sum > c {
                if ai > c {
                    ai = c;
                    aj = sum - c;
                }
            } else if aj < 0.0 {
                aj = 0.0;
                ai = sum;
            }
            if sum > c {
                if aj > c {
                    aj = c;
                    ai = sum - c;
                }
            } else if ai < 0.0 {
                ai = 0.0;
                aj = sum;
            }
            alpha[i_sel] = ai;
            alpha[j_sel] = aj;
        }
        let (di, dj) = (alpha[i_sel] - old_i, alpha[j_sel] - old_j);
        for &t in &active {
            let st = sample(t);
            grad[t] += label(t) * (yi * ki[st] * di + yj * kj[st] * dj);
        }
        iterations += 1;
    }
    if violation >= stop && iterations >= max_iterations {
        return Err(SvrError::NotConverged {
            solver: NAME,
            iterations,
            gap: violation,
            tolerance: stop,
        });
    }

    // Bias: average over free variables of yₜ∇ₜ (libsvm's ρ, b = −ρ), else the middle of the
    // interval the bounded ones allow.
    let (mut ub, mut lb, mut sum_free, mut n_free) = (f64::INFINITY, f64::NEG_INFINITY, 0.0, 0usize);
    for t in 0..m {
        let yg = label(t) * grad[t];
        if alpha[t] >= c {
            if label(t) < 0.0 {
                ub = ub.min(yg)
            } else {
                lb = lb.max(yg)
            }
        } else if alpha[t] <= 0.0 {
            if label(t) > 0.0 {
                ub = ub.min(yg)
            } else {
                lb = lb.max(yg)
            }
        } else {
            n_free += 1;
            sum_free += yg;
        }
    }
    let rho = if n_free > 0 {
        sum_free / n_free as f64
    } else {
        0.5 * (ub + lb)
    };
    let beta = (0..n).map(|i| alpha[i] - alpha[i + n]).collect();
    Ok(SmoSolution {
        beta,
        bias: -rho,
        iterations,
    })
}
