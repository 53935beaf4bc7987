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
    /// Told after every change of the active set (swaps come only before it): until the next
    /// call, rows are asked for over the positions below `active`, or whole, so the matrix may
    /// compute them over those positions' samples only.
    fn focus(&mut self, active: usize) {
        let _ = active;
    }
    /// Adds `coefficient` times row `t` over every position to Ḡ = `C · Σ_{s at upper bound}
    /// Q₍·₎ₛ`, the gradient's part from the bounded variables, which the matrix keeps in the
    /// layout its rows make cheapest (so that the gradient of shrunk variables can be rebuilt
    /// from the free ones only).
    fn add_to_bar(&mut self, t: usize, coefficient: f64);
    /// Ḡ at position `t`.
    fn bar(&self, t: usize) -> f64;
}

/// What a solve asks, each time it has converged on every variable, of whoever called it:
/// `(α, ∇, stop)` in the caller's order → a smaller stop value to go on to, or `None` to
/// finish. The caller may correct ∇ (e.g. recompute it where Q's rows were rounded); the solve
/// goes on, and computes ρ, from the gradient it leaves.
pub(super) type Refine<'a> = dyn FnMut(&[f64], &mut [f64], f64) -> Option<f64> + 'a;

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
    /// `Qₜₜ`.
    diag: Vec<f64>,
    /// Caller's index at each position.
    original: Vec<usize>,
    active: usize,
    c: f64,
    /// The largest KKT violation over the active variables at the last selection.
    violation: f64,
}

/// The I_up scan's lanes: per lane (t mod [`LANES`]) the largest −yₜ∇ₜ so far and its
/// position (`usize::MAX` while none).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Up {
    lane_v: [f64; LANES],
    lane_t: [usize; LANES],
}

impl Up {
    const NONE: Self = Self {
        lane_v: [f64::NEG_INFINITY; LANES],
        lane_t: [usize::MAX; LANES],
    };
}

/// What the scans read of the active variables.
#[derive(Clone, Copy)]
struct Scanned<'a> {
    y: &'a [f64],
    alpha: &'a [f64],
    grad: &'a [f64],
    diag: &'a [f64],
    c: f64,
}

/// The I_low scan's lanes: per lane the largest yₜ∇ₜ, and the best decrease gd²/quad as
/// `best_gain / best_quad` (0 before any candidate) with its position.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Low {
    lane_max: [f64; LANES],
    best_gain: [f64; LANES],
    best_quad: [f64; LANES],
    best_t: [usize; LANES],
}

impl Low {
    const NONE: Self = Self {
        lane_max: [f64::NEG_INFINITY; LANES],
        best_gain: [0.0; LANES],
        best_quad: [1.0; LANES],
        best_t: [usize::MAX; LANES],
    };
}

/// The largest −yₜ∇ₜ over I_up in each lane, ties to the last (libsvm's `>=` scan), over
/// positions `from..` (`from` a multiple of [`LANES`]) continuing `up`. The lanes keep the
/// comparisons independent and the choice branch-free: whether a variable may move is as good
/// as random, and a mispredicted branch per variable was most of the scan's time.
fn scan_up_from(s: Scanned<'_>, mut up: Up, from: usize) -> Up {
    let Scanned {
        y, alpha, grad, c, ..
    } = s;
    for t in from..y.len() {
        let k = t % LANES;
        let (yt, a) = (y[t], alpha[t]);
        // In I_up: −yₜ∇ₜ can grow.
        let can_grow = if yt > 0.0 { a < c } else { a > 0.0 };
        let v = -yt * grad[t];
        if can_grow & (v >= up.lane_v[k]) {
            up.lane_v[k] = v;
            up.lane_t[k] = t;
        }
    }
    up
}

/// The second-order scan for j given i (row `qi` of Q over the active positions, `gmax` =
/// −yᵢ∇ᵢ) over positions `from..`, continuing `low`, in lanes as [`scan_up_from`].
fn scan_low_from<const NON_POSITIVE_TO_TAU: bool>(
    s: Scanned<'_>,
    qi: &[f64],
    (i, gmax): (usize, f64),
    mut low: Low,
    from: usize,
) -> Low {
    let Scanned {
        y,
        alpha,
        grad,
        diag,
        c,
    } = s;
    let (yi, di) = (y[i], diag[i]);
    for t in from..y.len() {
        let k = t % LANES;
        let (yt, a) = (y[t], alpha[t]);
        // In I_low: yₜ∇ₜ can shrink.
        let in_low = if yt > 0.0 { a > 0.0 } else { a < c };
        let v = yt * grad[t];
        if in_low {
            low.lane_max[k] = low.lane_max[k].max(v);
        }
        let grad_diff = gmax + v;
        // The largest decrease gd²/quad, compared as cross products: a division per
        // candidate was most of a fit's time.
        let quad = di + diag[t] - 2.0 * yi * yt * qi[t];
        let quad = if NON_POSITIVE_TO_TAU {
            if quad > 0.0 { quad } else { TAU }
        } else {
            quad.max(TAU)
        };
        let gain = grad_diff * grad_diff;
        if in_low & (grad_diff > 0.0) & (gain * low.best_quad[k] >= low.best_gain[k] * quad) {
            low.best_gain[k] = gain;
            low.best_quad[k] = quad;
            low.best_t[k] = t;
        }
    }
    low
}

/// [`scan_up_from`] from 0, in AVX2 where the CPU has it.
fn scan_up(s: Scanned<'_>) -> Up {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU supports AVX2, checked just above.
        return unsafe { avx2::scan_up(s) };
    }
    scan_up_from(s, Up::NONE, 0)
}

/// [`scan_low_from`] from 0, in AVX2 where the CPU has it.
fn scan_low<const NON_POSITIVE_TO_TAU: bool>(s: Scanned<'_>, qi: &[f64], pivot: (usize, f64)) -> Low {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU supports AVX2, checked just above.
        return unsafe { avx2::scan_low::<NON_POSITIVE_TO_TAU>(s, qi, pivot) };
    }
    scan_low_from::<NON_POSITIVE_TO_TAU>(s, qi, pivot, Low::NONE, 0)
}

/// The scans with the four lanes in one AVX2 register each. Written with intrinsics because
/// the compiler keeps the lanes' choices scalar; each lane makes the same comparisons and
/// rounds the same operations as the portable scan (no fused multiply-add), so both give the
/// same lanes to the bit (`the_avx2_scans_are_the_portable_ones`).
#[cfg(target_arch = "x86_64")]
mod avx2 {
    use std::arch::x86_64::*;

    use super::{LANES, Low, Scanned, TAU, Up, scan_low_from, scan_up_from};

    #[target_feature(enable = "avx2")]
    fn lanes_f64(v: __m256d) -> [f64; LANES] {
        let mut out = [0.0; LANES];
        // SAFETY: `out` holds four f64; unaligned store.
        unsafe { _mm256_storeu_pd(out.as_mut_ptr(), v) };
        out
    }

    #[target_feature(enable = "avx2")]
    fn lanes_usize(v: __m256i) -> [usize; LANES] {
        let mut out = [0i64; LANES];
        // SAFETY: `out` holds four i64; unaligned store.
        unsafe { _mm256_storeu_si256(out.as_mut_ptr().cast(), v) };
        out.map(|t| t as usize)
    }

    /// Per lane: `if take { index } else { kept }`, for positions held as i64.
    #[target_feature(enable = "avx2")]
    fn positions_where(take: __m256d, index: __m256i, kept: __m256i) -> __m256i {
        _mm256_castpd_si256(_mm256_blendv_pd(
            _mm256_castsi256_pd(kept),
            _mm256_castsi256_pd(index),
            take,
        ))
    }

    /// `v[start..start + 4]`.
    #[target_feature(enable = "avx2")]
    fn four(v: &[f64], start: usize) -> __m256d {
        assert!(start + 4 <= v.len());
        // SAFETY: the four values lie inside `v`, checked just above.
        unsafe { _mm256_loadu_pd(v.as_ptr().add(start)) }
    }

    /// Per lane, from labels and α: (in I_up, in I_low), i.e. whether −yₜ∇ₜ can grow and
    /// whether yₜ∇ₜ can shrink.
    #[target_feature(enable = "avx2")]
    fn movable(yv: __m256d, av: __m256d, cv: __m256d) -> (__m256d, __m256d) {
        let zero = _mm256_setzero_pd();
        let ypos = _mm256_cmp_pd::<_CMP_GT_OQ>(yv, zero);
        let (below_c, above_0) = (
            _mm256_cmp_pd::<_CMP_LT_OQ>(av, cv),
            _mm256_cmp_pd::<_CMP_GT_OQ>(av, zero),
        );
        (
            _mm256_blendv_pd(above_0, below_c, ypos),
            _mm256_blendv_pd(below_c, above_0, ypos),
        )
    }

    #[target_feature(enable = "avx2")]
    pub(super) fn scan_up(s: Scanned<'_>) -> Up {
        let Scanned {
            y, alpha, grad, c, ..
        } = s;
        let n = y.len().min(alpha.len()).min(grad.len());
        let whole = n / LANES * LANES;
        let cv = _mm256_set1_pd(c);
        let sign = _mm256_set1_pd(-0.0);
        let mut best_v = _mm256_set1_pd(f64::NEG_INFINITY);
        let mut best_t = _mm256_set1_epi64x(-1);
        let mut index = _mm256_set_epi64x(3, 2, 1, 0);
        let step = _mm256_set1_epi64x(LANES as i64);
        for start in (0..whole).step_by(LANES) {
            let [yv, av, gv] = [y, alpha, grad].map(|v| four(v, start));
            let (can_grow, _) = movable(yv, av, cv);
            let v = _mm256_mul_pd(_mm256_xor_pd(yv, sign), gv);
            let take = _mm256_and_pd(can_grow, _mm256_cmp_pd::<_CMP_GE_OQ>(v, best_v));
            best_v = _mm256_blendv_pd(best_v, v, take);
            best_t = positions_where(take, index, best_t);
            index = _mm256_add_epi64(index, step);
        }
        let up = Up {
            lane_v: lanes_f64(best_v),
            lane_t: lanes_usize(best_t),
        };
        scan_up_from(s, up, whole)
    }

    #[target_feature(enable = "avx2")]
    pub(super) fn scan_low<const NON_POSITIVE_TO_TAU: bool>(
        s: Scanned<'_>,
        qi: &[f64],
        (i, gmax): (usize, f64),
    ) -> Low {
        let Scanned {
            y,
            alpha,
            grad,
            diag,
            c,
        } = s;
        let n = y
            .len()
            .min(alpha.len())
            .min(grad.len())
            .min(diag.len())
            .min(qi.len());
        let whole = n / LANES * LANES;
        let (zero, cv, tau) = (_mm256_setzero_pd(), _mm256_set1_pd(c), _mm256_set1_pd(TAU));
        let neg_inf = _mm256_set1_pd(f64::NEG_INFINITY);
        let (gmaxv, di, two_yi) = (
            _mm256_set1_pd(gmax),
            _mm256_set1_pd(diag[i]),
            _mm256_set1_pd(2.0 * y[i]),
        );
        let mut lane_max = neg_inf;
        let mut best_gain = zero;
        let mut best_quad = _mm256_set1_pd(1.0);
        let mut best_t = _mm256_set1_epi64x(-1);
        let mut index = _mm256_set_epi64x(3, 2, 1, 0);
        let step = _mm256_set1_epi64x(LANES as i64);
        for start in (0..whole).step_by(LANES) {
            let [yv, av, gv, dv, qv] = [y, alpha, grad, diag, qi].map(|v| four(v, start));
            let (_, in_low) = movable(yv, av, cv);
            let v = _mm256_mul_pd(yv, gv);
            // max(lane, v) where in I_low, as f64::max: v is never NaN here.
            lane_max = _mm256_blendv_pd(lane_max, _mm256_max_pd(v, lane_max), in_low);
            let grad_diff = _mm256_add_pd(gmaxv, v);
            // di + diag[t] − ((2·yᵢ)·yₜ)·qᵢₜ, in the portable scan's order.
            let quad = _mm256_sub_pd(
                _mm256_add_pd(di, dv),
                _mm256_mul_pd(_mm256_mul_pd(two_yi, yv), qv),
            );
            let quad = if NON_POSITIVE_TO_TAU {
                _mm256_blendv_pd(tau, quad, _mm256_cmp_pd::<_CMP_GT_OQ>(quad, zero))
            } else {
                // f64::max(quad, τ): τ where quad is NaN, as MAXPD's second operand.
                _mm256_max_pd(quad, tau)
            };
            let gain = _mm256_mul_pd(grad_diff, grad_diff);
            let better =
                _mm256_cmp_pd::<_CMP_GE_OQ>(_mm256_mul_pd(gain, best_quad), _mm256_mul_pd(best_gain, quad));
            let take = _mm256_and_pd(
                _mm256_and_pd(in_low, _mm256_cmp_pd::<_CMP_GT_OQ>(grad_diff, zero)),
                better,
            );
            best_gain = _mm256_blendv_pd(best_gain, gain, take);
            best_quad = _mm256_blendv_pd(best_quad, quad, take);
            best_t = positions_where(take, index, best_t);
            index = _mm256_add_epi64(index, step);
        }
        let low = Low {
            lane_max: lanes_f64(lane_max),
            best_gain: lanes_f64(best_gain),
            best_quad: lanes_f64(best_quad),
            best_t: lanes_usize(best_t),
        };
        scan_low_from::<NON_POSITIVE_TO_TAU>(s, qi, (i, gmax), low, whole)
    }
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
    /// This is where a fit spends its time: see [`scan_up`] and [`scan_low`].
    fn select<const NON_POSITIVE_TO_TAU: bool>(&mut self) -> Option<(usize, usize, usize)> {
        let (n, c) = (self.active, self.c);
        let scanned = |n: usize| Scanned {
            y: &self.y[..n],
            alpha: &self.alpha[..n],
            grad: &self.grad[..n],
            diag: &self.diag[..n],
            c,
        };
        let Up { lane_v, lane_t } = scan_up(scanned(n));
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
        let Low {
            lane_max,
            best_gain,
            best_quad,
            best_t,
        } = scan_low::<NON_POSITIVE_TO_TAU>(scanned(n), qi, (i_sel, gmax));
        // The lanes' best, ties to the last position (as one scan with `>=` would have it).
        let (mut gain, mut quad, mut j_sel) = (0.0, 1.0, usize::MAX);
        for k in 0..LANES {
            let t = best_t[k];
            if t == usize::MAX {
                continue;
            }
            let (g, q) = (best_gain[k], best_quad[k]);
            let (lhs, rhs) = (g * quad, gain * q);
            if j_sel == usize::MAX || lhs > rhs || (lhs == rhs && t > j_sel) {
                (gain, quad, j_sel) = (g, q, t);
            }
        }
        let gmax2 = lane_max.into_iter().fold(f64::NEG_INFINITY, f64::max);
        self.violation = gmax + gmax2;
        (j_sel != usize::MAX).then_some((i_sel, hi, j_sel))
    }

    /// The analytic two-variable step, the gradient update over the active set, and
    /// Ḡ for a variable that reached or left the upper bound; `hi` is the handle of
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
                self.q.add_to_bar(t, if was_upper { -c } else { c });
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
        self.diag.swap(i, j);
        self.original.swap(i, j);
    }

    /// libsvm's `reconstruct_gradient`: the exact gradient of the shrunk variables, from
    /// Ḡ and the free variables, by rows of whichever side is cheaper.
    fn reconstruct_gradient(&mut self) {
        let (n, all, c) = (self.active, self.alpha.len(), self.c);
        if n == all {
            return;
        }
        for t in n..all {
            self.grad[t] = self.q.bar(t) + self.p[t];
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
                measure: crate::error::KKT_VIOLATION,
            });
        }
        if settings.shrinking {
            counter -= 1;
            if counter == 0 {
                counter = period;
                s.shrink(stop, &mut unshrunk);
                s.q.focus(s.active);
            }
        }
        let mut pair = s.select::<NON_POSITIVE_TO_TAU>();
        if pair.is_none() || s.violation < stop {
            if s.active < m {
                // Converged on the active set: every variable again, with exact gradients.
                s.unshrink();
                s.q.focus(s.active);
                pair = s.select::<NON_POSITIVE_TO_TAU>();
                counter = 1;
            }
            if pair.is_none() || s.violation < stop {
                // Converged on every variable: finished, unless the caller wants more.
                if pair.is_none() {
                    break;
                }
                let (alpha, mut grad) = (s.in_caller_order(&s.alpha), s.in_caller_order(&s.grad));
                let tighter = refine(&alpha, &mut grad, stop);
                for (g, &t) in s.grad.iter_mut().zip(&s.original) {
                    *g = grad[t];
                }
                match tighter {
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Active variables as a solve leaves them: labels ±1, α at 0, at C or between, gradients
    /// of both signs, ties among them, and a row of Q.
    fn state(n: usize, seed: u64) -> [Vec<f64>; 5] {
        let mut rng = capture::rng::SplitMix64::new(seed);
        let c = 10.0;
        let y = (0..n)
            .map(|_| if rng.below(2) == 0 { 1.0 } else { -1.0 })
            .collect();
        let alpha = (0..n)
            .map(|_| match rng.below(3) {
                0 => 0.0,
                1 => c,
                _ => c * rng.next_f64(),
            })
            .collect();
        // A coarse grid of gradients, so that lanes meet ties.
        let grad = (0..n).map(|_| (rng.below(9) as f64 - 4.0) * 0.25).collect();
        let diag = (0..n).map(|_| 1.0 + rng.below(2) as f64 * 1e-13).collect();
        let qi = (0..n)
            .map(|_| {
                if rng.below(5) == 0 {
                    1.0
                } else {
                    rng.next_f64() - 0.5
                }
            })
            .collect();
        [y, alpha, grad, diag, qi]
    }

    #[test]
    fn the_avx2_scans_are_the_portable_ones() {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // Scans that choose nothing compare nothing: most must choose a j.
            let (mut chosen, mut tried) = (0, 0);
            for n in (1..=13).chain([64, 1001]) {
                for seed in 0..20 {
                    let [y, alpha, grad, diag, qi] = state(n, seed);
                    let s = Scanned {
                        y: &y,
                        alpha: &alpha,
                        grad: &grad,
                        diag: &diag,
                        c: 10.0,
                    };
                    // SAFETY: the CPU supports AVX2, checked above.
                    let wide = unsafe { avx2::scan_up(s) };
                    assert_eq!(wide, scan_up_from(s, Up::NONE, 0), "n {n} seed {seed}");
                    let i = seed as usize % n;
                    let pivot = (i, -y[i] * grad[i]);
                    // SAFETY: as above.
                    let (a, b) = unsafe {
                        (
                            avx2::scan_low::<false>(s, &qi, pivot),
                            avx2::scan_low::<true>(s, &qi, pivot),
                        )
                    };
                    assert_eq!(
                        a,
                        scan_low_from::<false>(s, &qi, pivot, Low::NONE, 0),
                        "n {n} seed {seed}"
                    );
                    assert_eq!(
                        b,
                        scan_low_from::<true>(s, &qi, pivot, Low::NONE, 0),
                        "n {n} seed {seed}"
                    );
                    chosen += usize::from(a.best_t.iter().any(|&t| t != usize::MAX));
                    tried += 1;
                }
            }
            assert!(2 * chosen > tried, "{chosen} of {tried}");
        }
    }
}
