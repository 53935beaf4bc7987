//! The ε-SVR on [`super`]'s SMO: the split dual's variables, kernel rows cached within a
//! memory budget, and the refinement to the certificate's gap with the exact finish.

use super::rows::{KernelRows, RowStorage, RowValue, SampleQ};
use super::solver::solve;
use super::{SelectionCurvature, SmoSettings, libsvm_rho};
use crate::error::SvmError;
use crate::kernel::{Kernel, RowSource};

/// Memory for cached kernel rows of the ε-SVR (libsvm's `-m`; scikit-learn's default is 200 MB).
pub(crate) const CACHE_BYTES: usize = 256 << 20;
/// Kernel rows computed on demand and cached: least recently used rows are evicted so that the
/// rows held never take more than the byte budget given (at least two rows, the pair's). Rows
/// are computed in the precision they are held to: as `f64`, or within 2⁻²³ where held as
/// `f32` (`RowSource::row_f32`, in f32 exponents that cost half as much).
pub(crate) struct RowCache<'a, T> {
    kernel: &'a Kernel,
    x: &'a [f64],
    dim: usize,
    n: usize,
    /// Where whole rows come from.
    source: RowSource<'a>,
    /// Where rows come from while narrowed ([`KernelRows::narrow`]).
    window: Option<RowSource<'a>>,
    /// Values in a row held: `n`, or the window's samples.
    width: usize,
    /// Each sample's entry in a row held (`u32::MAX` if outside the window).
    entry_of: Vec<u32>,
    budget_bytes: usize,
    /// A whole row asked for while narrowed: computed, not held.
    whole: Vec<T>,
    diag: Vec<f64>,
    slot_of: Vec<Option<usize>>,
    owner: Vec<usize>,
    last_used: Vec<u64>,
    rows: Vec<T>,
    clock: u64,
    /// Rows computed (cache misses), for the tests and the benchmark.
    computed: usize,
    /// Times rows were narrowed, for the tests.
    narrowings: usize,
}

/// Samples above which a kernel row is computed on all cores: below, a thread hand-off costs
/// more than the row (measured with `palpus bench svr-scale`). On one thread a row is never
/// handed off: a join from outside a one-thread pool blocks on a thread switch per row, 13 %
/// of a Friedman fit at n = 30,000.
const PARALLEL_ROW: usize = 4096;

impl<'a, T: RowValue> RowCache<'a, T> {
    /// A cache of rows of `kernel` over the `n` samples in `x` (`n × dim`, row-major) holding
    /// at most `budget_bytes` of rows (but always two).
    pub(crate) fn new(kernel: &'a Kernel, x: &'a [f64], dim: usize, n: usize, budget_bytes: usize) -> Self {
        Self {
            kernel,
            x,
            dim,
            n,
            source: RowSource::new(kernel, &x[..n * dim], dim),
            window: None,
            width: n,
            entry_of: (0..n as u32).collect(),
            budget_bytes,
            whole: Vec::new(),
            diag: (0..n)
                .map(|i| kernel.eval(&x[i * dim..(i + 1) * dim], &x[i * dim..(i + 1) * dim]))
                .collect(),
            slot_of: vec![None; n],
            owner: Vec::new(),
            last_used: Vec::new(),
            rows: Vec::new(),
            clock: 0,
            computed: 0,
            narrowings: 0,
        }
        .emptied()
    }

    /// No row held, and slots for rows of the current width within the budget.
    fn emptied(mut self) -> Self {
        self.empty();
        self
    }

    /// Rows of the current width the budget holds (at least the pair's two, at most one per
    /// sample).
    fn slots(&self) -> usize {
        (self.budget_bytes / (size_of::<T>() * self.width.max(1))).clamp(2, self.n.max(2))
    }

    fn empty(&mut self) {
        let slots = self.slots();
        self.slot_of.fill(None);
        self.owner = vec![usize::MAX; slots];
        self.last_used = vec![0; slots];
        self.rows.clear();
    }

    /// Bytes of row storage allocated so far.
    #[cfg(test)]
    pub(crate) fn row_bytes(&self) -> usize {
        self.rows.capacity() * size_of::<T>()
    }

    /// Rows computed so far.
    #[cfg(test)]
    pub(crate) fn computed(&self) -> usize {
        self.computed
    }

    /// Computes row `i` into `out` by `fill(xᵢ, start, part)` (a [`RowSource`]'s rows).
    fn compute<O: Send>(&self, i: usize, out: &mut [O], fill: impl Fn(&[f64], usize, &mut [O]) + Sync) {
        let xi = &self.x[i * self.dim..(i + 1) * self.dim];
        let fill = |start: usize, out: &mut [O]| fill(xi, start, out);
        if out.len() >= PARALLEL_ROW && rayon::current_num_threads() > 1 {
            let half = out.len() / 2;
            let (a, b) = out.split_at_mut(half);
            rayon::join(|| fill(0, a), || fill(half, b));
        } else {
            fill(0, out);
        }
    }
}

impl<T: RowValue> RowCache<'_, T> {
    /// Makes row `i` held and returns its slot.
    fn fetch(&mut self, i: usize) -> usize {
        self.clock += 1;
        let n = self.width;
        let slot = match self.slot_of[i] {
            Some(s) => s,
            None => {
                // Slots are filled in order before any is reused, so the storage grows only
                // as far as the rows asked for.
                let used = self.rows.len() / n.max(1);
                let s = if used < self.owner.len() {
                    // Capacity doubles, capped at the budget's rows: growing by exactly one
                    // row moved the whole store on every new row (a tenth of a fit's time in
                    // the kernel's page remapping at n = 3,000), and doubling past the cap
                    // would overshoot the budget.
                    let (want, cap) = ((used + 1) * n, self.owner.len() * n);
                    if self.rows.capacity() < want {
                        let grown = (2 * self.rows.capacity()).clamp(want, cap.max(want));
                        self.rows.reserve_exact(grown - self.rows.len());
                    }
                    self.rows.resize(want, T::default());
                    used
                } else {
                    (0..self.owner.len())
                        .min_by_key(|&s| self.last_used[s])
                        .unwrap_or(0)
                };
                if self.owner[s] != usize::MAX {
                    self.slot_of[self.owner[s]] = None;
                }
                self.owner[s] = i;
                self.slot_of[i] = Some(s);
                let mut rows = std::mem::take(&mut self.rows);
                self.compute_into(i, &mut rows[s * n..(s + 1) * n], self.window.is_some());
                self.rows = rows;
                self.computed += 1;
                s
            }
        };
        self.last_used[slot] = self.clock;
        slot
    }

    /// Computes row `i` (over the window if `narrowed`, else whole) into `held`.
    fn compute_into(&self, i: usize, held: &mut [T], narrowed: bool) {
        let source = match &self.window {
            Some(window) if narrowed => window,
            _ => &self.source,
        };
        match T::storage(held) {
            RowStorage::Exact(held) => self.compute(i, held, |xi, start, out| source.row(xi, start, out)),
            RowStorage::Rounded(held) => {
                self.compute(i, held, |xi, start, out| source.row_f32(xi, start, out))
            }
        }
    }

    /// The row held in `slot`.
    fn get(&self, slot: usize) -> &[T] {
        &self.rows[slot * self.width..(slot + 1) * self.width]
    }
}

impl<T: RowValue> KernelRows for RowCache<'_, T> {
    type Value = T;

    fn samples(&self) -> usize {
        self.n
    }

    fn diagonal(&self, s: usize) -> f64 {
        self.diag[s]
    }

    fn row(&mut self, s: usize) -> &[T] {
        let slot = self.fetch(s);
        self.get(slot)
    }

    /// Rows held keep their values for the samples still in the window: they are moved, not
    /// recomputed, when the new window lies within the old one (as shrinking makes it).
    fn narrow(&mut self, window: &[u32]) -> bool {
        let samples: Vec<usize> = window.iter().map(|&s| s as usize).collect();
        let from: Option<Vec<usize>> = samples
            .iter()
            .map(|&s| (self.entry_of[s] != u32::MAX).then_some(self.entry_of[s] as usize))
            .collect();
        let (old, new) = (self.width, samples.len());
        match from {
            Some(from) if new <= old => {
                let used = self.rows.len() / old.max(1);
                let mut moved = vec![T::default(); new];
                for slot in 0..used {
                    // Slot `slot` moves down to `slot · new`; it ends at or before where its
                    // old place ended, so no later slot is overwritten before it is moved.
                    for (m, &f) in moved.iter_mut().zip(&from) {
                        *m = self.rows[slot * old + f];
                    }
                    self.rows[slot * new..(slot + 1) * new].copy_from_slice(&moved);
                }
                self.rows.truncate(used * new);
                self.width = new;
                let slots = self.slots();
                self.owner.resize(slots, usize::MAX);
                self.last_used.resize(slots, 0);
            }
            _ => {
                self.width = new;
                self.empty();
            }
        }
        self.entry_of.fill(u32::MAX);
        for (r, &s) in samples.iter().enumerate() {
            self.entry_of[s] = r as u32;
        }
        self.window = Some(RowSource::of(
            self.kernel,
            &self.x[..self.n * self.dim],
            self.dim,
            &samples,
        ));
        self.narrowings += 1;
        true
    }

    fn widen(&mut self) {
        if self.window.take().is_some() {
            self.width = self.n;
            self.empty();
            for (s, e) in self.entry_of.iter_mut().enumerate() {
                *e = s as u32;
            }
        }
    }

    fn whole_row(&mut self, s: usize) -> &[T] {
        if self.window.is_none() {
            return self.row(s);
        }
        let mut whole = std::mem::take(&mut self.whole);
        whole.resize(self.n, T::default());
        self.compute_into(s, &mut whole, false);
        self.computed += 1;
        self.whole = whole;
        &self.whole
    }
}

/// An ε-SVR solved by SMO.
#[derive(Debug, Clone)]
pub(crate) struct SvrSmoSolution {
    /// `β = α − α*`, one per sample.
    pub beta: Vec<f64>,
    /// The bias b = −ρ.
    pub bias: f64,
    /// Pair updates made.
    pub iterations: usize,
    /// Whether the exact finish on SMO's partition produced it.
    pub polished: bool,
    /// The stop value (a KKT violation) it was aiming for when its iteration limit stopped
    /// it; `None` when it converged.
    pub short_of: Option<f64>,
}

/// libsvm's default stop (its `-e`, scikit-learn's `tol`): the first pass ends at this maximal
/// KKT violation, in the units of the targets.
pub(crate) const LIBSVM_STOP: f64 = 1e-3;

/// The relative duality gap the ε-SVR's SMO aims for before it hands its answer to the fit's
/// certificate: a tenth of what the certificate accepts, so that the certificate's own,
/// independent evaluation (with its rounding bounds) passes.
pub(crate) const TARGET_GAP: f64 = 0.1 * crate::ACCEPT_GAP;

/// Relative duality gap `|P + D| / max(1, |P|)` of the split dual's α, read off its gradient:
/// for the first n variables `∇ₜ = ε − yₜ + (Kβ)ₜ`, so no kernel value is needed. `labels` are
/// the split dual's (+1 for α, −1 for α*).
fn svr_gap(alpha: &[f64], grad: &[f64], labels: &[f64], y: &[f64], c: f64, epsilon: f64) -> f64 {
    let n = y.len();
    let bias = -libsvm_rho(alpha, grad, labels, c);
    let (mut quad, mut linear, mut loss) = (0.0, 0.0, 0.0);
    for i in 0..n {
        let beta = alpha[i] - alpha[i + n];
        let k_beta = grad[i] - (epsilon - y[i]);
        quad += beta * k_beta;
        linear += epsilon * beta.abs() - beta * y[i];
        loss += crate::slack(y[i], k_beta + bias, epsilon);
    }
    let primal = 0.5 * quad + c * loss;
    let dual = 0.5 * quad + linear;
    let gap = (primal + dual).abs() / primal.abs().max(1.0);
    if gap.is_finite() { gap } else { f64::INFINITY }
}

/// Solves the ε-SVR dual of `data` by SMO with shrinking, rows from a [`RowCache`] of
/// `cache_bytes`: first to libsvm's stop ([`LIBSVM_STOP`]); each time it has converged, the
/// answer is its own if the duality gap read off the gradient is at most a tenth of
/// [`crate::ACCEPT_GAP`], else the exact finish on its partition if that one's gap is
/// (`smo_finish`), else SMO goes on from where it stopped with a stop ten times smaller (down to
/// `1e2 · tolerance · (1 + max|y|)`). The fit's certificate still decides acceptance.
///
/// Rows are held as `f64` while every row fits in `cache_bytes`, else as `f32`, twice as many:
/// at n = 30,000 on Friedman #1 with 10 inputs, one thread, the rows computed fell from
/// 227,774 to 52,804 when the rows held doubled (`palpus bench svr-scale`). Where rows round,
/// the gradient is recomputed from the exact kernel each time SMO has converged, so that the
/// gap, the exact finish and ρ are those of the problem asked, not its rounded neighbour's.
pub(crate) fn solve_svr(
    kernel: &Kernel,
    data: &crate::data::SvrData<'_>,
    settings: &crate::params::DualSettings,
    cache_bytes: usize,
    max_iterations: usize,
) -> Result<SvrSmoSolution, SvmError> {
    let n = data.y.len();
    if n.saturating_mul(n).saturating_mul(size_of::<f64>()) <= cache_bytes {
        solve_svr_holding::<f64>(kernel, data, settings, cache_bytes, max_iterations)
    } else {
        solve_svr_holding::<f32>(kernel, data, settings, cache_bytes, max_iterations)
    }
}

/// [`solve_svr`] with rows held as `T`.
fn solve_svr_holding<T: RowValue>(
    kernel: &Kernel,
    data: &crate::data::SvrData<'_>,
    settings: &crate::params::DualSettings,
    cache_bytes: usize,
    max_iterations: usize,
) -> Result<SvrSmoSolution, SvmError> {
    let (x, dim, y) = (data.x, data.dim, data.y);
    let n = y.len();
    let (c, epsilon) = (settings.c, settings.epsilon);
    let y_scale = crate::data::target_scale(y);
    let floor = 1e2 * settings.tolerance * y_scale;
    let smo = SmoSettings::builder()
        .c(c)
        .stop(LIBSVM_STOP.max(floor))
        .max_iterations(max_iterations)
        .shrinking(true)
        .time_budget(settings.started, settings.time_budget)
        .selection(SelectionCurvature::Clamped)
        .build()?;
    // Variable t < n is αₜ (label +1, p = ε − y), t ≥ n is α*ₜ₋ₙ (label −1, p = ε + y).
    let linear: Vec<f64> = (0..2 * n)
        .map(|t| if t < n { epsilon - y[t] } else { epsilon + y[t - n] })
        .collect();
    let labels: Vec<f64> = (0..2 * n).map(|t| if t < n { 1.0 } else { -1.0 }).collect();
    let mut cache = RowCache::<T>::new(kernel, x, dim, n, cache_bytes);
    // Each time SMO converges: done if its own gap is small enough; else try the exact finish
    // on the partition it has found; else go on with a tighter stop.
    let mut finished: Option<crate::smo_finish::Finished> = None;
    let mut refine = |alpha: &[f64], grad: &mut [f64], stop: f64| {
        if T::ROUNDS {
            let beta: Vec<f64> = (0..n).map(|i| alpha[i] - alpha[i + n]).collect();
            let k_beta = crate::low_rank::kernel_times(kernel, x, dim, &beta);
            for i in 0..n {
                grad[i] = epsilon - y[i] + k_beta[i];
                grad[i + n] = epsilon + y[i] - k_beta[i];
            }
        }
        let grad = &*grad;
        let gap = svr_gap(alpha, grad, &labels, y, c, epsilon);
        if gap <= TARGET_GAP {
            return None;
        }
        let beta: Vec<f64> = (0..n).map(|i| alpha[i] - alpha[i + n]).collect();
        let k_beta: Vec<f64> = (0..n).map(|i| grad[i] - (epsilon - y[i])).collect();
        if let Some(f) =
            crate::smo_finish::finish(kernel, data, settings, &beta, &k_beta, TARGET_GAP, usize::MAX)
            && f.gap <= TARGET_GAP
        {
            finished = Some(f);
            return None;
        }
        (stop > floor).then_some((0.1 * stop).max(floor))
    };
    // On a worker of the pool, so that each row's join is a local push, not a hand-off to the
    // pool and a wait.
    let sol = rayon::scope(|_| {
        solve(
            &mut SampleQ::new(&mut cache, &labels),
            &labels,
            &linear,
            &smo,
            &mut refine,
        )
    })?;
    if let Some(f) = finished {
        return Ok(SvrSmoSolution {
            beta: f.beta,
            bias: f.bias,
            iterations: sol.iterations,
            polished: true,
            short_of: None,
        });
    }
    let beta = (0..n).map(|i| sol.alpha[i] - sol.alpha[i + n]).collect();
    Ok(SvrSmoSolution {
        beta,
        bias: -sol.rho,
        iterations: sol.iterations,
        polished: false,
        short_of: (!sol.converged).then_some(sol.stop),
    })
}

#[cfg(test)]
mod tests {
    use std::time::Instant;

    use super::*;

    /// Inputs on a 1-D grid with a repeated row, so rows are distinguishable and one pair of
    /// rows is identical.
    fn grid(n: usize) -> Vec<f64> {
        (0..n).map(|i| (i.min(n - 2)) as f64 / n as f64).collect()
    }

    /// Rows held as `T` are the row function's values for exponents `t` (`value(t)`), within
    /// the budget.
    fn cache_holds_exact_rows_within_budget<T: RowValue + Into<f64>>(value: fn(f64) -> f64) {
        let kernel = Kernel::Rbf { gamma: 3.0 };
        let n = 50;
        let x = grid(n);
        // Room for 5 rows of 50 values, and a little over.
        let budget = 5 * n * size_of::<T>() + 7;
        let mut cache = RowCache::<T>::new(&kernel, &x, 1, n, budget);
        // Cycle through more rows than fit, twice, checking every value.
        for round in 0..2 {
            for i in (0..n).step_by(3) {
                let h = cache.fetch(i);
                let row = cache.get(h);
                for (j, &v) in row.iter().enumerate() {
                    // The row's exp, on the kernel's squared distance.
                    let d = x[i] - x[j];
                    assert_eq!(v.into(), value(-3.0 * (d * d)), "row {i} col {j} round {round}");
                }
                assert!(cache.row_bytes() <= budget, "{} > {budget}", cache.row_bytes());
            }
        }
        // Every fetch of a row not held computes it: 17 distinct rows > 5 slots, so the second
        // round recomputes them all.
        assert_eq!(cache.computed(), 2 * n.div_ceil(3));
        // A pair stays readable together whatever the budget.
        let mut tiny = RowCache::<T>::new(&kernel, &x, 1, n, 0);
        let (a, b) = (tiny.fetch(3), tiny.fetch(40));
        assert_eq!(tiny.get(a)[40].into(), tiny.get(b)[3].into());
        assert!(tiny.row_bytes() <= 2 * n * size_of::<T>());
    }

    #[test]
    fn the_row_cache_stays_within_its_budget_and_returns_exact_rows() {
        cache_holds_exact_rows_within_budget::<f64>(crate::exp::exp);
        cache_holds_exact_rows_within_budget::<f32>(|t| f64::from(crate::exp::exp_f32(t as f32)));
    }

    #[test]
    fn smo_past_its_budget_says_it_reached_a_kkt_violation_not_a_gap() {
        let n = 60;
        let x: Vec<f64> = (0..n).map(|i| i as f64 / n as f64).collect();
        let y: Vec<f64> = x.iter().map(|v| (6.0 * v).sin()).collect();
        let data = crate::data::SvrData::new(&x, 1, &y).unwrap();
        let params = crate::SvrParams::builder()
            .c(10.0)
            .epsilon(0.05)
            .kernel(Kernel::Rbf { gamma: 20.0 })
            .time_budget(std::time::Duration::from_nanos(1))
            .build()
            .unwrap();
        let settings = params.dual_settings(Instant::now());
        let err = solve_svr(
            &params.kernel(),
            &data,
            &settings,
            CACHE_BYTES,
            settings.max_iterations,
        )
        .expect_err("a budget of a nanosecond runs out");
        let SvmError::Budget { measure, gap, .. } = &err else {
            panic!("{err}");
        };
        assert_eq!(*measure, crate::error::KKT_VIOLATION);
        assert!(gap.is_infinite() || *gap > 0.0, "{gap}");
        assert!(err.to_string().contains("KKT violation"), "{err}");
    }

    /// Narrowed rows hold the whole rows' values: an SMO whose rows narrow once shrinking has
    /// left few samples active takes the same steps as one over the whole Gram matrix, which
    /// never narrows.
    #[test]
    fn narrowed_rows_give_the_same_smo_as_whole_ones() {
        let (n, dim) = (600, 2);
        let x: Vec<f64> = (0..n)
            .flat_map(|i| {
                let t = i as f64 / n as f64;
                [t, (17.0 * t).sin()]
            })
            .collect();
        let y: Vec<f64> = (0..n)
            .map(|i| {
                let t = i as f64 / n as f64;
                (6.0 * t).sin() + 0.5 * (91.0 * t).sin()
            })
            .collect();
        let kernel = Kernel::Rbf { gamma: 5.0 };
        let (c, epsilon) = (10.0, 0.1);
        let linear: Vec<f64> = (0..2 * n)
            .map(|t| if t < n { epsilon - y[t] } else { epsilon + y[t - n] })
            .collect();
        let labels: Vec<f64> = (0..2 * n).map(|t| if t < n { 1.0 } else { -1.0 }).collect();
        let settings = SmoSettings::builder()
            .c(c)
            .stop(1e-8)
            .max_iterations(10_000_000)
            .shrinking(true)
            .selection(SelectionCurvature::Clamped)
            .build()
            .unwrap();
        let mut cache = RowCache::<f64>::new(&kernel, &x, dim, n, CACHE_BYTES);
        let gram: Vec<f64> = (0..n).flat_map(|i| cache.row(i).to_vec()).collect();
        let narrowed = solve(
            &mut SampleQ::new(&mut cache, &labels),
            &labels,
            &linear,
            &settings,
            &mut |_, _, _| None,
        )
        .unwrap();
        assert!(cache.narrowings >= 2, "rows narrowed {} times", cache.narrowings);
        let whole = solve(
            &mut SampleQ::new(&mut super::super::GramRows::new(&gram, n).unwrap(), &labels),
            &labels,
            &linear,
            &settings,
            &mut |_, _, _| None,
        )
        .unwrap();
        assert!(narrowed.converged && whole.converged);
        assert_eq!(narrowed.iterations, whole.iterations);
        assert_eq!(narrowed.alpha, whole.alpha);
        assert_eq!(narrowed.rho, whole.rho);
    }

    #[test]
    fn a_small_cache_gives_the_same_svr_solution_as_a_large_one() {
        let n = 120;
        let x: Vec<f64> = (0..n).map(|i| i as f64 / n as f64).collect();
        let y: Vec<f64> = x
            .iter()
            .map(|v| (6.0 * v).sin() + 0.3 * (37.0 * v).cos())
            .collect();
        let data = crate::data::SvrData::new(&x, 1, &y).unwrap();
        let params = crate::SvrParams::builder()
            .c(10.0)
            .epsilon(0.05)
            .kernel(Kernel::Rbf { gamma: 20.0 })
            .build()
            .unwrap();
        let settings = params.dual_settings(Instant::now());
        let kernel = params.kernel();
        let big = solve_svr(&kernel, &data, &settings, CACHE_BYTES, settings.max_iterations).unwrap();
        let small = solve_svr(
            &kernel,
            &data,
            &settings,
            3 * n * size_of::<f64>(),
            settings.max_iterations,
        )
        .unwrap();
        let largest = big.beta.iter().fold(0.0f64, |m, b| m.max(b.abs()));
        assert!(largest > 1.0, "a trivial solution tests nothing");
        for (a, b) in big.beta.iter().zip(&small.beta) {
            assert!((a - b).abs() <= 1e-6 * 10.0, "{a} vs {b}");
        }
        assert!((big.bias - small.bias).abs() <= 1e-6);
    }
}
