//! An exact finish for the ε-SVR's SMO.
//!
//! SMO closes the duality gap slowly at large C: at libsvm's stop (a KKT violation of 1e-3) the
//! needle's relative gap is still ~1e-4, far from what the fit's certificate accepts, and each
//! further digit costs as many iterations again. But by then SMO has usually sorted the samples
//! right: inside the tube (β = 0), outside it (β = ±C) and on its boundary (free). With that
//! partition the optimum is the solution of one linear system over the free samples only,
//! `Σⱼ Kᵢⱼ βⱼ + b = yᵢ ∓ ε` for free i and `Σ β = 0`, the bounded samples' part of the left side
//! read off SMO's gradient. [`finish`] solves it and evaluates the duality gap of the result
//! over every sample; whoever called it keeps the result only if that gap is small enough, and
//! otherwise lets SMO go on (the partition was not yet right).

use faer::Mat;
use rayon::prelude::*;

use super::bordered::{Singular, solve_bordered};
use super::data::SvrData;
use super::kernel::{Kernel, RowSource};
use super::params::DualSettings;

/// Free samples above which no finish is tried: the system's matrix takes `m²` doubles
/// (4000² · 8 B = 128 MB) and its factorisation `m³` flops.
pub(crate) const MAX_FREE: usize = 4000;

/// Samples per parallel task when updating `Kβ`.
const CHUNK: usize = 1024;

/// A candidate optimum from [`finish`].
#[derive(Debug, Clone)]
pub(crate) struct Finished {
    /// `β`, one per sample.
    pub beta: Vec<f64>,
    /// The bias b.
    pub bias: f64,
    /// Relative duality gap `|P + D| / max(1, |P|)` of (β, b).
    pub gap: f64,
}

/// Where a sample sits in a partition.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Side {
    /// β = 0.
    Inside,
    /// Free on the upper boundary of the tube, f = y − ε, 0 ≤ β ≤ C.
    Upper,
    /// Free on the lower boundary, f = y + ε, −C ≤ β ≤ 0.
    Lower,
    /// β = C.
    Above,
    /// β = −C.
    Below,
}

/// Partition rounds [`finish`] tries before it gives up.
const MAX_ROUNDS: usize = 20;

/// The exact optimum reached from the partition SMO's `β` implies, given `k_beta = Kβ` at that
/// `β`: a primal–dual active-set method (solve the free samples' system, move every sample
/// whose coefficient left its box or whose residual left its side of the tube, repeat) for at
/// most [`MAX_ROUNDS`] rounds, each begun only if it can end within the fit's time budget.
/// `None` when no round gave a dual-feasible point whose gap is at most `target_gap`, the free
/// samples grow beyond `max_free` (or [`MAX_FREE`]), or the budget left is too short for the
/// next round.
pub(crate) fn finish(
    kernel: &Kernel,
    data: &SvrData<'_>,
    settings: &DualSettings,
    beta: &[f64],
    k_beta: &[f64],
    target_gap: f64,
    max_free: usize,
) -> Option<Finished> {
    let (x, dim, y) = (data.x, data.dim, data.y);
    let (c, epsilon) = (settings.c, settings.epsilon);
    let n = y.len();
    let y_scale = super::data::target_scale(y);
    let tol_r = 1e-12 * y_scale;
    let mut sides: Vec<Side> = beta
        .iter()
        .map(|&b| {
            if b >= c {
                Side::Above
            } else if b <= -c {
                Side::Below
            } else if b > 0.0 {
                Side::Upper
            } else if b < 0.0 {
                Side::Lower
            } else {
                Side::Inside
            }
        })
        .collect();
    let mut beta = beta.to_vec();
    let mut k_beta = k_beta.to_vec();
    let row = |i: usize| &x[i * dim..(i + 1) * dim];
    for _ in 0..MAX_ROUNDS {
        let free: Vec<usize> = (0..n)
            .filter(|&i| matches!(sides[i], Side::Upper | Side::Lower))
            .collect();
        let m = free.len();
        if m == 0 || m > MAX_FREE.min(max_free) {
            return None;
        }
        // A round factorises an (m + 1)² system, which cannot be interrupted: one that would
        // not end within the fit's budget is not begun (at m = 3,000 it takes minutes).
        if !settings.has_time_to_factor(m + 1) {
            return None;
        }
        let mut new_beta: Vec<f64> = sides
            .iter()
            .zip(&beta)
            .map(|(side, &b)| match side {
                Side::Inside => 0.0,
                Side::Above => c,
                Side::Below => -c,
                Side::Upper | Side::Lower => b,
            })
            .collect();
        // Bordered system [K_FF 1; 1ᵀ 0] [β_F; b] = [y_F ∓ ε − (Kβ_bounded)_F; −Σβ_bounded].
        let mut a = Mat::<f64>::from_fn(m + 1, m + 1, |r, s| match (r < m, s < m) {
            (true, true) => 0.0,
            (true, false) | (false, true) => 1.0,
            (false, false) => 0.0,
        });
        let free_rows = RowSource::of(kernel, x, dim, &free);
        let mut values = vec![0.0; m];
        for (s, &j) in free.iter().enumerate() {
            free_rows.row(row(j), 0, &mut values);
            for (r, &v) in values.iter().enumerate() {
                a[(r, s)] = v;
            }
        }
        // (Kβ)_F at the bounded samples' new values and the free ones' old: K β_old plus the
        // bounded samples' changes.
        let moved: Vec<(usize, f64)> = (0..n)
            .filter(|&i| !matches!(sides[i], Side::Upper | Side::Lower) && new_beta[i] != beta[i])
            .map(|i| (i, new_beta[i] - beta[i]))
            .collect();
        let bounded_sum: f64 = (0..n)
            .filter(|&i| matches!(sides[i], Side::Above | Side::Below))
            .map(|i| new_beta[i])
            .sum();
        // Solved for the change from the current β_F and a bias b₀ rather than for β_F and b
        // themselves: near the optimum K_FF is nearly singular (close free samples), and a
        // solve's error along its near-null directions scales with the size of what it
        // solves for, which the change keeps tiny.
        let miss: Vec<f64> = free
            .iter()
            .map(|&i| {
                let moved_part: f64 = moved.iter().map(|&(j, d)| d * kernel.eval(row(i), row(j))).sum();
                let target = if sides[i] == Side::Upper {
                    y[i] - epsilon
                } else {
                    y[i] + epsilon
                };
                target - (k_beta[i] + moved_part)
            })
            .collect();
        let bias0 = miss.iter().sum::<f64>() / m as f64;
        let free_sum: f64 = free.iter().map(|&i| beta[i]).sum();
        let rhs = Mat::<f64>::from_fn(m + 1, 1, |r, _| {
            if r == m {
                -(bounded_sum + free_sum)
            } else {
                miss[r] - bias0
            }
        });
        // The finish certifies by the residual: a least squares that does not solve is no use.
        let solution = solve_bordered(&a, &rhs, 1e-9, Singular::MustSolve)?;
        for (r, &i) in free.iter().enumerate() {
            new_beta[i] = beta[i] + solution[r];
        }
        let bias = bias0 + solution[m];
        // Kβ at the new β: the old plus every change.
        let (moved_samples, changes): (Vec<usize>, Vec<f64>) = (0..n)
            .filter(|&i| new_beta[i] != beta[i])
            .map(|i| (i, new_beta[i] - beta[i]))
            .unzip();
        let delta_rows = RowSource::of(kernel, x, dim, &moved_samples);
        k_beta.par_chunks_mut(CHUNK).enumerate().for_each_init(
            || vec![0.0; changes.len()],
            |values, (chunk, out)| {
                for (o, kb) in out.iter_mut().enumerate() {
                    delta_rows.row(row(chunk * CHUNK + o), 0, values);
                    *kb += crate::kernel::dot(values, &changes);
                }
            },
        );
        beta = new_beta;
        // Move the samples on the wrong side (a primal–dual active-set step). A free
        // coefficient out of its box goes to the bound it crossed first, alone: moving the
        // residual violators in the same round too makes the steps overshoot and the free
        // set swell on nearly singular systems.
        let slack_b = 1e-9 * c;
        let out_of_box = |side: Side, b: f64| match side {
            Side::Upper => !(-slack_b..=c + slack_b).contains(&b),
            Side::Lower => !(-c - slack_b..=slack_b).contains(&b),
            _ => false,
        };
        let feasible = !(0..n).any(|i| out_of_box(sides[i], beta[i]));
        let mut changed = false;
        for i in 0..n {
            let r = y[i] - k_beta[i] - bias;
            let b = beta[i];
            let to = match sides[i] {
                Side::Upper if out_of_box(Side::Upper, b) => {
                    if b > c {
                        Side::Above
                    } else {
                        Side::Inside
                    }
                }
                Side::Lower if out_of_box(Side::Lower, b) => {
                    if b < -c {
                        Side::Below
                    } else {
                        Side::Inside
                    }
                }
                _ if !feasible => sides[i],
                Side::Inside if r > epsilon + tol_r => Side::Upper,
                Side::Inside if r < -epsilon - tol_r => Side::Lower,
                Side::Above if r < epsilon - tol_r => Side::Upper,
                Side::Below if r > -epsilon + tol_r => Side::Lower,
                side => side,
            };
            if to != sides[i] {
                sides[i] = to;
                changed = true;
            }
        }
        if feasible {
            let clipped: Vec<f64> = beta.iter().map(|b| b.clamp(-c, c)).collect();
            let gap = gap(&clipped, &k_beta, bias, y, c, epsilon);
            if gap <= target_gap {
                return Some(Finished {
                    beta: clipped,
                    bias,
                    gap,
                });
            }
        }
        if !changed {
            return None;
        }
    }
    None
}

/// Relative duality gap `|P + D| / max(1, |P|)` of (β, b) with `k_beta = Kβ`.
pub(crate) fn gap(beta: &[f64], k_beta: &[f64], bias: f64, y: &[f64], c: f64, epsilon: f64) -> f64 {
    let (mut quad, mut linear, mut loss) = (0.0, 0.0, 0.0);
    for i in 0..y.len() {
        quad += beta[i] * k_beta[i];
        linear += epsilon * beta[i].abs() - beta[i] * y[i];
        loss += crate::slack(y[i], k_beta[i] + bias, epsilon);
    }
    let primal = 0.5 * quad + c * loss;
    let dual = 0.5 * quad + linear;
    let gap = (primal + dual).abs() / primal.abs().max(1.0);
    if gap.is_finite() { gap } else { f64::INFINITY }
}

#[cfg(test)]
mod tests {
    use std::time::Instant;

    use super::*;

    #[test]
    fn a_partition_with_more_free_samples_than_allowed_is_not_solved() {
        // Samples far apart for the kernel's width (a well-conditioned K) at moderate C: the
        // exact optimum has free samples.
        let n = 30;
        let x: Vec<f64> = (0..n).map(|i| i as f64 / n as f64).collect();
        let y: Vec<f64> = x.iter().map(|v| (5.0 * v).sin()).collect();
        let data = SvrData::new(&x, 1, &y).unwrap();
        let params = crate::SvrParams::builder()
            .c(10.0)
            .epsilon(0.01)
            .kernel(Kernel::Rbf { gamma: 1000.0 })
            .build()
            .unwrap();
        let settings = params.dual_settings(Instant::now());
        let kernel = params.kernel();
        // Every sample starts free, a little off zero: the first round solves for all 30.
        let beta = vec![1e-3; n];
        let k_beta: Vec<f64> = (0..n)
            .map(|i| (0..n).map(|j| beta[j] * kernel.eval(&x[i..=i], &x[j..=j])).sum())
            .collect();
        assert!(finish(&kernel, &data, &settings, &beta, &k_beta, 1e-7, n - 1).is_none());
        let done = finish(&kernel, &data, &settings, &beta, &k_beta, 1e-7, n).expect("finishes");
        assert!(done.gap <= 1e-7, "{}", done.gap);
    }
}
