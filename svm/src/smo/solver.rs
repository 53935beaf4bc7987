//! The one SMO of the crate, laid out as libsvm's `Solver` lays it out, so that an iteration
//! costs what the active set costs.
//!
//! Every array is kept by *position*: shrinking swaps the active variables to the front, and
//! the dual's matrix ([`QMatrix`]) swaps its own rows and columns with them, so selection and
//! the gradient update read the front of contiguous arrays and the front of two rows. A soft
//! margin needs 10⁵–10⁶ iterations while shrinking leaves a few dozen variables active; reading
//! those through an index list over whole rows was most of a fit's time.

use super::{NAME, PairStep, SelectionCurvature, SmoSettings, SmoSolution, TAU, libsvm_rho};
use crate::error::SvmError;

/// Independent accumulators in the working-set scans.
const LANES: usize = 4;

/// The dual's matrix `Qₜₛ = yₜ yₛ K(xₜ, xₛ)` by position, as the solver reads it: two rows at a
/// time, each over a prefix of the positions, through handles (so a cache can hand out its own
/// storage), with positions swapped when shrinking moves a variable.
pub(super) trait QMatrix {
    /// `Qₜₜ` at position `t` (read once, before any swap).
    fn diagonal(&self, t: usize) -> f64;
    /// Makes row `t` readable over positions `0..len` and returns its handle, valid until the
    /// fetch after the next.
    fn fetch(&mut self, t: usize, len: usize) -> usize;
    /// The row behind a handle from [`QMatrix::fetch`] (at least as long as asked for).
    fn get(&self, handle: usize) -> &[f64];
    /// Swaps positions `i < j`.
    fn swap(&mut self, i: usize, j: usize);
}

/// What a solve asks, each time it has converged on every variable, of whoever called it:
/// `(α, ∇, stop)` in the caller's order → a smaller stop value to go on to, or `None` to
/// finish.
pub(super) type Refine<'a> = dyn FnMut(&[f64], &[f64], f64) -> Option<f64> + 'a;

/// Solver state by position (libsvm's arrays; positions below `active` are the active set).
struct State<'q, Q> {
    q: &'q mut Q,
    /// Labels ±1.
    y: Vec<f64>,
    /// The linear term p.
    p: Vec<f64>,
    alpha: Vec<f64>,
    /// Gradient ∇ₜ = (Qα)ₜ + pₜ.
    grad: Vec<f64>,
    /// `C · Σ_{s at upper bound} Qₜₛ`: the part of the gradient the bounded variables give,
    /// kept so the gradient of shrunk variables can be rebuilt from the free ones only.
    grad_bar: Vec<f64>,
    /// `Qₜₜ`.
    diag: Vec<f64>,
    /// Caller's index at each position.
    original: Vec<usize>,
    active: usize,
    c: f64,
    /// The largest KKT violation over the active variables at the last selection.
    violation: f64,
}

impl<Q: QMatrix> State<'_, Q> {
    #[inline]
    fn upper(&self, t: usize) -> bool {
        self.alpha[t] >= self.c
    }

    #[inline]
    fn lower(&self, t: usize) -> bool {
        self.alpha[t] <= 0.0
    }

    /// libsvm's `select_working_set`: the pair `(i, j)` and the handle of row i, or `None`
    /// when no pair can decrease the objective; [`State::violation`] is set either way.
    /// `NON_POSITIVE_TO_TAU` is [`SelectionCurvature::NonPositiveToTau`].
    ///
    /// The scans avoid branches on the data where they can (whether a variable may move up or
    /// down is as good as random): this is where a fit spends its time.
    fn select<const NON_POSITIVE_TO_TAU: bool>(&mut self) -> Option<(usize, usize, usize)> {
        let (n, c) = (self.active, self.c);
        // The largest −yₜ∇ₜ over I_up, ties to the last such t (libsvm's `>=` scan), kept in
        // independent lanes so the comparisons do not wait on each other.
        let mut lane_v = [f64::NEG_INFINITY; LANES];
        let mut lane_t = [usize::MAX; LANES];
        {
            let (y, alpha, grad) = (&self.y[..n], &self.alpha[..n], &self.grad[..n]);
            for (chunk, ((ys, als), gs)) in y
                .chunks(LANES)
                .zip(alpha.chunks(LANES))
                .zip(grad.chunks(LANES))
                .enumerate()
            {
                for k in 0..ys.len() {
                    let (yt, a) = (ys[k], als[k]);
                    // In I_up: −yₜ∇ₜ can grow.
                    let up = if yt > 0.0 { a < c } else { a > 0.0 };
                    let v = -yt * gs[k];
                    if up & (v >= lane_v[k]) {
                        lane_v[k] = v;
                        lane_t[k] = chunk * LANES + k;
                    }
                }
            }
        }
        let mut gmax = f64::NEG_INFINITY;
        let mut i_sel = usize::MAX;
        for (&v, &t) in lane_v.iter().zip(&lane_t) {
            if t != usize::MAX && (i_sel == usize::MAX || v > gmax || (v == gmax && t > i_sel)) {
                gmax = v;
                i_sel = t;
            }
        }
        if i_sel == usize::MAX {
            self.violation = f64::NEG_INFINITY;
            return None;
        }
        let hi = self.q.fetch(i_sel, n);
        let qi = &self.q.get(hi)[..n];
        let (y, alpha, grad, diag) = (&self.y[..n], &self.alpha[..n], &self.grad[..n], &self.diag[..n]);
        let (yi, di) = (y[i_sel], diag[i_sel]);
        let mut lane_max = [f64::NEG_INFINITY; LANES];
        // The best decrease so far, best_gain / best_quad (0 before any candidate).
        let (mut best_gain, mut best_quad) = (0.0, 1.0);
        let mut j_sel = usize::MAX;
        for t in 0..n {
            let (yt, a) = (y[t], alpha[t]);
            // In I_low: yₜ∇ₜ can shrink.
            let low = if yt > 0.0 { a > 0.0 } else { a < c };
            let v = yt * grad[t];
            let lane = &mut lane_max[t % LANES];
            *lane = lane.max(if low { v } else { f64::NEG_INFINITY });
            let grad_diff = gmax + v;
            if low & (grad_diff > 0.0) {
                // The largest decrease gd²/quad, compared as cross products: a division per
                // candidate was most of a fit's time.
                let quad = di + diag[t] - 2.0 * yi * yt * qi[t];
                let quad = if NON_POSITIVE_TO_TAU {
                    if quad > 0.0 { quad } else { TAU }
                } else {
                    quad.max(TAU)
                };
                let gain = grad_diff * grad_diff;
                if gain * best_quad >= best_gain * quad {
                    best_gain = gain;
                    best_quad = quad;
                    j_sel = t;
                }
            }
        }
        let gmax2 = lane_max.into_iter().fold(f64::NEG_INFINITY, f64::max);
        self.violation = gmax + gmax2;
        (j_sel != usize::MAX).then_some((i_sel, hi, j_sel))
    }

    /// The analytic two-variable step, the gradient update over the active set, and
    /// `grad_bar` for a variable that reached or left the upper bound; `hi` is the handle of
    /// row i from the selection.
    fn update(&mut self, i: usize, hi: usize, j: usize) {
        let (n, c) = (self.active, self.c);
        let hj = self.q.fetch(j, n);
        let qij = self.q.get(hi)[j];
        let (old_i, old_j) = (self.alpha[i], self.alpha[j]);
        let (was_upper_i, was_upper_j) = (self.upper(i), self.upper(j));
        let [ai, aj] = PairStep {
            same_label: self.y[i] == self.y[j],
            q: [self.diag[i], self.diag[j], qij],
            grad: [self.grad[i], self.grad[j]],
            alpha: [old_i, old_j],
        }
        .clipped(c);
        self.alpha[i] = ai;
        self.alpha[j] = aj;
        let (di, dj) = (ai - old_i, aj - old_j);
        let (qi, qj) = (&self.q.get(hi)[..n], &self.q.get(hj)[..n]);
        for ((g, a), b) in self.grad[..n].iter_mut().zip(qi).zip(qj) {
            *g += a * di + b * dj;
        }
        for (t, was_upper) in [(i, was_upper_i), (j, was_upper_j)] {
            if was_upper != self.upper(t) {
                let all = self.alpha.len();
                let h = self.q.fetch(t, all);
                let sign = if was_upper { -c } else { c };
                for (gb, q) in self.grad_bar.iter_mut().zip(&self.q.get(h)[..all]) {
                    *gb += sign * q;
                }
            }
        }
    }

    /// Swaps positions `i < j` in every array.
    fn swap(&mut self, i: usize, j: usize) {
        self.q.swap(i, j);
        self.y.swap(i, j);
        self.p.swap(i, j);
        self.alpha.swap(i, j);
        self.grad.swap(i, j);
        self.grad_bar.swap(i, j);
        self.diag.swap(i, j);
        self.original.swap(i, j);
    }

    /// libsvm's `reconstruct_gradient`: the exact gradient of the shrunk variables, from
    /// `grad_bar` and the free variables, by rows of whichever side is cheaper.
    fn reconstruct_gradient(&mut self) {
        let (n, all, c) = (self.active, self.alpha.len(), self.c);
        if n == all {
            return;
        }
        for t in n..all {
            self.grad[t] = self.grad_bar[t] + self.p[t];
        }
        let free = (0..n).filter(|&t| !self.upper(t) && !self.lower(t)).count();
        if free * all > 2 * n * (all - n) {
            for t in n..all {
                let h = self.q.fetch(t, n);
                let g: f64 = self.q.get(h)[..n]
                    .iter()
                    .zip(&self.alpha[..n])
                    .filter(|&(_, &a)| a > 0.0 && a < c)
                    .map(|(q, a)| a * q)
                    .sum();
                self.grad[t] += g;
            }
        } else {
            for s in 0..n {
                let a = self.alpha[s];
                if a > 0.0 && a < c {
                    let h = self.q.fetch(s, all);
                    for (g, q) in self.grad[n..].iter_mut().zip(&self.q.get(h)[n..all]) {
                        *g += a * q;
                    }
                }
            }
        }
    }

    fn be_shrunk(&self, t: usize, gmax1: f64, gmax2: f64) -> bool {
        let (g, positive) = (self.grad[t], self.y[t] > 0.0);
        if self.upper(t) {
            if positive { -g > gmax1 } else { -g > gmax2 }
        } else if self.lower(t) {
            if positive { g > gmax2 } else { g > gmax1 }
        } else {
            false
        }
    }

    /// libsvm's `do_shrinking`; `unshrunk` is whether the one full rebuild near the end was
    /// done.
    fn shrink(&mut self, stop: f64, unshrunk: &mut bool) {
        let (mut gmax1, mut gmax2) = (f64::NEG_INFINITY, f64::NEG_INFINITY);
        for t in 0..self.active {
            let g = self.grad[t];
            if self.y[t] > 0.0 {
                if !self.upper(t) {
                    gmax1 = gmax1.max(-g);
                }
                if !self.lower(t) {
                    gmax2 = gmax2.max(g);
                }
            } else {
                if !self.upper(t) {
                    gmax2 = gmax2.max(-g);
                }
                if !self.lower(t) {
                    gmax1 = gmax1.max(g);
                }
            }
        }
        if !*unshrunk && gmax1 + gmax2 <= 10.0 * stop {
            *unshrunk = true;
            self.reconstruct_gradient();
            self.active = self.alpha.len();
        }
        let mut t = 0;
        while t < self.active {
            if self.be_shrunk(t, gmax1, gmax2) {
                self.active -= 1;
                while self.active > t {
                    if !self.be_shrunk(self.active, gmax1, gmax2) {
                        self.swap(t, self.active);
                        break;
                    }
                    self.active -= 1;
                }
            }
            t += 1;
        }
    }

    /// Every variable active again, with exact gradients.
    fn unshrink(&mut self) {
        self.reconstruct_gradient();
        self.active = self.alpha.len();
    }

    /// A per-position array back in the caller's order.
    fn in_caller_order(&self, values: &[f64]) -> Vec<f64> {
        let mut out = vec![0.0; values.len()];
        for (&t, &v) in self.original.iter().zip(values) {
            out[t] = v;
        }
        out
    }
}

/// Solves `min ½ αᵀQα + pᵀα`, `yᵀα = 0`, `0 ≤ α ≤ C` for labels `y` (±1) and linear term `p`,
/// one per variable in the caller's order (position t of `q` at the start is variable t).
/// Each time it has converged on every variable, `refine` may give a smaller stop value to go
/// on to. At the iteration limit it returns its last iterate (`converged: false`), with exact
/// gradients and ρ over every variable, as libsvm does; past the time budget,
/// [`SvmError::Budget`].
pub(super) fn solve<Q: QMatrix>(
    q: &mut Q,
    y: &[f64],
    p: &[f64],
    settings: &SmoSettings,
    refine: &mut Refine<'_>,
) -> Result<SmoSolution, SvmError> {
    match settings.selection {
        SelectionCurvature::Clamped => solve_with::<Q, false>(q, y, p, settings, refine),
        SelectionCurvature::NonPositiveToTau => solve_with::<Q, true>(q, y, p, settings, refine),
    }
}

/// [`solve`] with the selection's curvature rule fixed at compile time.
fn solve_with<Q: QMatrix, const NON_POSITIVE_TO_TAU: bool>(
    q: &mut Q,
    y: &[f64],
    p: &[f64],
    settings: &SmoSettings,
    refine: &mut Refine<'_>,
) -> Result<SmoSolution, SvmError> {
    let m = y.len();
    let diag = (0..m).map(|t| q.diagonal(t)).collect();
    let mut s = State {
        q,
        y: y.to_vec(),
        p: p.to_vec(),
        alpha: vec![0.0; m],
        grad: p.to_vec(),
        grad_bar: vec![0.0; m],
        diag,
        original: (0..m).collect(),
        active: m,
        c: settings.c,
        violation: f64::INFINITY,
    };
    let max_iterations = settings.iteration_budget(m);
    let mut stop = settings.stop;
    // libsvm's shrinking period.
    let period = m.clamp(1, 1000);
    let mut counter = period + 1;
    let mut unshrunk = false;
    let mut iterations = 0;
    while iterations < max_iterations {
        if let Some((started, budget_s)) = settings.budget
            && iterations % 1000 == 0
            && started.elapsed().as_secs_f64() > budget_s
        {
            return Err(SvmError::Budget {
                solver: NAME,
                budget_s,
                iterations,
                gap: s.violation,
            });
        }
        if settings.shrinking {
            counter -= 1;
            if counter == 0 {
                counter = period;
                s.shrink(stop, &mut unshrunk);
            }
        }
        let mut pair = s.select::<NON_POSITIVE_TO_TAU>();
        if pair.is_none() || s.violation < stop {
            if s.active < m {
                // Converged on the active set: every variable again, with exact gradients.
                s.unshrink();
                pair = s.select::<NON_POSITIVE_TO_TAU>();
                counter = 1;
            }
            if pair.is_none() || s.violation < stop {
                // Converged on every variable: finished, unless the caller wants more.
                if pair.is_none() {
                    break;
                }
                let (alpha, grad) = (s.in_caller_order(&s.alpha), s.in_caller_order(&s.grad));
                match refine(&alpha, &grad, stop) {
                    Some(tighter) if tighter < stop => {
                        stop = tighter;
                        unshrunk = false;
                        counter = period;
                        continue;
                    }
                    _ => break,
                }
            }
        }
        let Some((i, hi, j)) = pair else { break };
        s.update(i, hi, j);
        iterations += 1;
    }
    s.unshrink();
    let rho = libsvm_rho(&s.alpha, &s.grad, &s.y, s.c);
    Ok(SmoSolution {
        alpha: s.in_caller_order(&s.alpha),
        rho,
        iterations,
        violation: s.violation,
        converged: s.violation < stop || iterations < max_iterations,
        stop,
    })
}
