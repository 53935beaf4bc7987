//! The two conventional identifications the paper compares ε-SVR against (Li & Bi Sec. III-C,
//! III-D; Tables I and II).
//!
//! * [`CoulombViscous`]: the physical friction model, fitted by linear least squares. The paper
//!   gives "the Coulomb friction as proportional to the normal pressure and the viscous friction
//!   as proportional to the relative velocity" and reports two parameters (0.7648 and 0.8333),
//!   so the default fit is `F = μ·P + c·v` with no intercept; [`CoulombViscous::fit_with_intercept`]
//!   adds a constant term for comparison. It does not apply to a needle (no normal force).
//! * [`CoulombViscousStiffness`]: the needle's physical baseline `F = Fc·sgn(v) + c·v + k·depth`.
//!   The paper calls a physical model "unsuitable" for the needle and compares only with the RBF
//!   network; this simplest one shows by how much.
//! * [`RbfNetwork`]: a Gaussian radial-basis-function network built the way it is usually done
//!   (the paper used MATLAB's toolbox): inputs scaled to the unit box, centres by seeded k-means
//!   (or an even grid), one shared width from the centres' spacing, and output weights plus a bias
//!   by (ridge-regularised) linear least squares.
//!
//! Least squares go through an SVD of the column-equilibrated design matrix (never the normal
//! equations, which square the condition number: pressures of ~10 N next to velocities of
//! ~0.01 m/s already give a condition number of ~10³ before squaring).

use capture::kind;
use capture::rng::SplitMix64;
use faer::Mat;
use serde::{Deserialize, Serialize};

use svm::InputScaling;

use crate::error::{IdentifyError, check_series};

// ---------------------------------------------------------------------------------------------
// Coulomb + viscous friction
// ---------------------------------------------------------------------------------------------

/// Coulomb + viscous friction `F = sgn(v)·(μ·P + b) + c·v`.
///
/// `F` follows the capture convention (`friction_force_n` is positive when it opposes the
/// motion, so `F·v ≥ 0`): the Coulomb part takes the sign of the velocity, the viscous part is
/// odd in `v` by itself. For motion in one direction (every Li & Bi protocol) `sgn(v) = 1` and
/// this is the paper's `F = μP + cv (+ b)`. At `v = 0` the Coulomb part is 0 (`sgn(0) = 0`):
/// static friction is not modelled.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CoulombViscous {
    /// Coulomb coefficient μ: newtons of friction per newton of normal force.
    pub coulomb: f64,
    /// Viscous coefficient, N·s/m.
    pub viscous_nspm: f64,
    /// Constant friction, N (0 for the paper's two-parameter fit).
    pub intercept_n: f64,
}

impl CoulombViscous {
    /// The paper's two-parameter least-squares fit of `F = sgn(v)·μP + cv`.
    pub fn fit(
        normal_force_n: &[f64],
        velocity_mps: &[f64],
        friction_force_n: &[f64],
    ) -> Result<Self, IdentifyError> {
        Self::fit_impl(normal_force_n, velocity_mps, friction_force_n, false)
    }

    /// Least-squares fit of `F = sgn(v)·(μP + b) + cv`, with a constant friction `b`.
    pub fn fit_with_intercept(
        normal_force_n: &[f64],
        velocity_mps: &[f64],
        friction_force_n: &[f64],
    ) -> Result<Self, IdentifyError> {
        Self::fit_impl(normal_force_n, velocity_mps, friction_force_n, true)
    }

    fn fit_impl(
        normal_force_n: &[f64],
        velocity_mps: &[f64],
        friction_force_n: &[f64],
        intercept: bool,
    ) -> Result<Self, IdentifyError> {
        let n = friction_force_n.len();
        if n == 0 {
            return Err(IdentifyError::Empty);
        }
        check_series(kind::NORMAL_FORCE_N, normal_force_n, n)?;
        check_series(kind::VELOCITY_MPS, velocity_mps, n)?;
        check_series(kind::FRICTION_FORCE_N, friction_force_n, n)?;
        let columns = if intercept { 3 } else { 2 };
        let a = Mat::from_fn(n, columns, |i, j| {
            let s = sign(velocity_mps[i]);
            match j {
                0 => s * normal_force_n[i],
                1 => velocity_mps[i],
                _ => s,
            }
        });
        let x = least_squares(a, friction_force_n, Rank::Required("Coulomb+viscous"))?;
        Ok(Self {
            coulomb: x[0],
            viscous_nspm: x[1],
            intercept_n: if intercept { x[2] } else { 0.0 },
        })
    }

    /// Friction force, N.
    pub fn predict(&self, normal_force_n: f64, velocity_mps: f64) -> f64 {
        sign(velocity_mps) * (self.coulomb * normal_force_n + self.intercept_n)
            + self.viscous_nspm * velocity_mps
    }

    /// [`CoulombViscous::predict`] over a capture.
    pub fn predict_many(
        &self,
        normal_force_n: &[f64],
        velocity_mps: &[f64],
    ) -> Result<Vec<f64>, IdentifyError> {
        check_series(kind::VELOCITY_MPS, velocity_mps, normal_force_n.len())?;
        Ok(normal_force_n
            .iter()
            .zip(velocity_mps)
            .map(|(&p, &v)| self.predict(p, v))
            .collect())
    }
}

// ---------------------------------------------------------------------------------------------
// Coulomb + viscous + stiffness (needle)
// ---------------------------------------------------------------------------------------------

/// The needle's physical baseline `F = Fc·sgn(v) + c·v + k·depth`, fitted by linear least
/// squares.
///
/// [`CoulombViscous`] is a friction law of velocity and normal force: a needle has no normal
/// force, and its axial force grows with depth while the shaft is in tissue. This is the
/// simplest law that says so: a constant friction on the shaft against the motion, a viscous
/// term, and a spring in depth (Okamura's stiffness and friction terms, linearised). It has no
/// puncture event, which is what the ε-SVR has to beat it on.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CoulombViscousStiffness {
    /// Coulomb force Fc, N: the constant part, against the motion.
    pub coulomb_n: f64,
    /// Viscous coefficient c, N·s/m.
    pub viscous_nspm: f64,
    /// Stiffness k, N/m of depth.
    pub stiffness_npm: f64,
}

impl CoulombViscousStiffness {
    /// Least-squares fit of `F = Fc·sgn(v) + c·v + k·depth` (no intercept: at rest at the
    /// surface the law gives no force).
    pub fn fit(depth_m: &[f64], velocity_mps: &[f64], force_n: &[f64]) -> Result<Self, IdentifyError> {
        let n = force_n.len();
        if n == 0 {
            return Err(IdentifyError::Empty);
        }
        check_series(kind::DEPTH_M, depth_m, n)?;
        check_series(kind::VELOCITY_MPS, velocity_mps, n)?;
        check_series(kind::AXIAL_FORCE_N, force_n, n)?;
        let a = Mat::from_fn(n, 3, |i, j| match j {
            0 => sign(velocity_mps[i]),
            1 => velocity_mps[i],
            _ => depth_m[i],
        });
        let x = least_squares(a, force_n, Rank::Required("Coulomb+viscous+stiffness"))?;
        Ok(Self {
            coulomb_n: x[0],
            viscous_nspm: x[1],
            stiffness_npm: x[2],
        })
    }

    /// Axial force, N.
    pub fn predict(&self, depth_m: f64, velocity_mps: f64) -> f64 {
        self.coulomb_n * sign(velocity_mps) + self.viscous_nspm * velocity_mps + self.stiffness_npm * depth_m
    }
}

fn sign(v: f64) -> f64 {
    if v > 0.0 {
        1.0
    } else if v < 0.0 {
        -1.0
    } else {
        0.0
    }
}

// ---------------------------------------------------------------------------------------------
// RBF network
// ---------------------------------------------------------------------------------------------

/// Where an [`RbfNetwork`] puts its centres (in the unit box the inputs are scaled to).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum CentrePlacement {
    /// k-means (k-means++ seeding from `seed`, then Lloyd iterations): centres follow the data,
    /// which is what matters when the samples cover the input space unevenly (a needle spends
    /// most samples at a few speeds). Deterministic for a given seed.
    KMeans {
        /// Seed of the k-means++ draws.
        seed: u64,
    },
    /// An even grid over the unit box with `m = ⌈k^(1/dim)⌉` points per axis, so `m^dim ≥ k`
    /// centres (a single centre sits at the box's middle).
    Grid,
}

/// Hyperparameters of an [`RbfNetwork`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RbfNetworkParams {
    /// Number of centres k (for [`CentrePlacement::Grid`], the grid is the smallest even grid
    /// with at least k points). Default 20: enough for the smooth 1-D and 2-D force maps of the
    /// paper, few enough that ~30 training samples per centre remain on the soft-contact set.
    pub centres: usize,
    /// How centres are placed. Default: k-means with seed 0.
    pub placement: CentrePlacement,
    /// Gaussian width σ as a multiple of the mean nearest-neighbour distance between centres
    /// (scaled units). Default 1: neighbouring Gaussians overlap at `e^{−½}`, which keeps the
    /// interpolant smooth without making the design matrix numerically singular.
    pub width_factor: f64,
    /// Ridge λ ≥ 0 on the output weights (not on the bias), relative to the mean squared
    /// residual: minimises `(1/n)‖Φw + b − y‖² + λ‖w‖²`. Default 1e-8: a guard against
    /// ill-conditioning that leaves well-posed fits unchanged.
    pub ridge: f64,
    /// Lloyd iterations at most (k-means stops earlier when no assignment changes). Default 100.
    pub max_iterations: usize,
}

impl Default for RbfNetworkParams {
    fn default() -> Self {
        Self {
            centres: 20,
            placement: CentrePlacement::KMeans { seed: 0 },
            width_factor: 1.0,
            ridge: 1e-8,
            max_iterations: 100,
        }
    }
}

impl RbfNetworkParams {
    /// Largest number of centres (grid or k-means) accepted: beyond this the dense least-squares
    /// problem stops being a baseline and becomes a memory hazard.
    pub const MAX_CENTRES: usize = 4096;

    /// The defaults with the number of centres scaled to the data: `n / 10`, between 2 and 20.
    ///
    /// Twenty centres suit the soft-contact (320–360 samples) and needle (thousands) captures,
    /// but on the 31-sample hard-contact capture they interpolate the noise: held-out AISE was
    /// 1.06 N² with 20 centres against 7.6e-3 N² with 3 (and 2.1e-4 N² for Coulomb+viscous).
    /// About ten samples per centre keeps the least-squares problem well over-determined.
    pub fn for_samples(n: usize) -> Self {
        Self::default().centres((n / 10).clamp(2, 20))
    }

    /// Sets the number of centres.
    pub fn centres(mut self, centres: usize) -> Self {
        self.centres = centres;
        self
    }

    /// Sets the placement.
    pub fn placement(mut self, placement: CentrePlacement) -> Self {
        self.placement = placement;
        self
    }

    /// Sets the width factor.
    pub fn width_factor(mut self, width_factor: f64) -> Self {
        self.width_factor = width_factor;
        self
    }

    /// Sets the ridge.
    pub fn ridge(mut self, ridge: f64) -> Self {
        self.ridge = ridge;
        self
    }

    fn validate(&self) -> Result<(), IdentifyError> {
        let invalid = |name, value, reason| Err(IdentifyError::InvalidParameter { name, value, reason });
        if self.centres == 0 || self.centres > Self::MAX_CENTRES {
            return invalid("centres", self.centres as f64, "must be between 1 and 4096");
        }
        if !(self.width_factor.is_finite() && self.width_factor > 0.0) {
            return invalid("width_factor", self.width_factor, "must be finite and positive");
        }
        if !(self.ridge.is_finite() && self.ridge >= 0.0) {
            return invalid("ridge", self.ridge, "must be finite and non-negative");
        }
        Ok(())
    }
}

/// A fitted Gaussian RBF network `f(x) = b + Σⱼ wⱼ exp(−‖s(x) − cⱼ‖² / (2σ²))`, where `s` is
/// the input scaling fitted on the training inputs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RbfNetwork {
    /// Maps raw inputs onto the unit box of the training data.
    pub scaling: InputScaling,
    /// Input dimension.
    pub dim: usize,
    /// Centres in scaled coordinates, `k × dim`, row-major.
    pub centres: Vec<f64>,
    /// Shared Gaussian width σ, scaled units.
    pub width: f64,
    /// Output weights, one per centre.
    pub weights: Vec<f64>,
    /// Bias, in the target's unit.
    pub bias: f64,
}

impl RbfNetwork {
    /// Fits the network to the row-major `n × dim` inputs `x` and the `n` targets `y`.
    pub fn fit(x: &[f64], dim: usize, y: &[f64], params: &RbfNetworkParams) -> Result<Self, IdentifyError> {
        params.validate()?;
        if dim == 0 {
            return Err(IdentifyError::InvalidParameter {
                name: "dim",
                value: 0.0,
                reason: "must be at least 1",
            });
        }
        let n = y.len();
        if n == 0 {
            return Err(IdentifyError::Empty);
        }
        check_series("x", x, n * dim)?;
        check_series("y", y, n)?;

        let scaling = InputScaling::min_max(x, dim);
        let xs = scaling.apply(x);
        let centres = match params.placement {
            CentrePlacement::KMeans { seed } => kmeans(&xs, dim, params.centres, seed, params.max_iterations),
            CentrePlacement::Grid => grid_centres(dim, params.centres)?,
        };
        let k = centres.len() / dim;
        let spacing = mean_nearest_distance(&centres, dim);
        // One centre, or all on top of each other: fall back to the unit box's side.
        let width = params.width_factor * if spacing > 0.0 { spacing } else { 1.0 };

        let inv_two_sigma2 = 0.5 / (width * width);
        let rows = n + k;
        let lambda_rows = (params.ridge * n as f64).sqrt();
        let mut a = Mat::zeros(rows, k + 1);
        for i in 0..n {
            let xi = &xs[i * dim..(i + 1) * dim];
            for j in 0..k {
                a[(i, j)] = (-squared_distance(xi, &centres[j * dim..(j + 1) * dim]) * inv_two_sigma2).exp();
            }
            a[(i, k)] = 1.0;
        }
        for j in 0..k {
            a[(n + j, j)] = lambda_rows;
        }
        let mut b = vec![0.0; rows];
        b[..n].copy_from_slice(y);
        let solution = least_squares(a, &b, Rank::MinimumNorm)?;
        Ok(Self {
            scaling,
            dim,
            centres,
            width,
            weights: solution[..k].to_vec(),
            bias: solution[k],
        })
    }

    /// Number of centres.
    pub fn n_centres(&self) -> usize {
        self.weights.len()
    }

    /// `f(x)` for one raw (unscaled) input of `dim` values.
    pub fn predict(&self, x: &[f64]) -> Result<f64, IdentifyError> {
        check_series("x", x, self.dim)?;
        let mut xs = vec![0.0; self.dim];
        self.scaling.apply_into(x, &mut xs);
        Ok(self.eval_scaled(&xs))
    }

    /// [`RbfNetwork::predict`] over row-major inputs.
    pub fn predict_many(&self, x: &[f64]) -> Result<Vec<f64>, IdentifyError> {
        if !x.len().is_multiple_of(self.dim) {
            return Err(IdentifyError::LengthMismatch {
                name: "x",
                found: x.len(),
                expected: x.len().div_ceil(self.dim) * self.dim,
            });
        }
        check_series("x", x, x.len())?;
        let mut xs = vec![0.0; self.dim];
        Ok(x.chunks_exact(self.dim)
            .map(|row| {
                self.scaling.apply_into(row, &mut xs);
                self.eval_scaled(&xs)
            })
            .collect())
    }

    fn eval_scaled(&self, xs: &[f64]) -> f64 {
        let inv_two_sigma2 = 0.5 / (self.width * self.width);
        self.bias
            + self
                .weights
                .iter()
                .zip(self.centres.chunks_exact(self.dim))
                .map(|(w, c)| w * (-squared_distance(xs, c) * inv_two_sigma2).exp())
                .sum::<f64>()
    }
}

fn squared_distance(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum()
}

/// Mean over centres of the distance to the nearest other centre; 0 for a single centre.
fn mean_nearest_distance(centres: &[f64], dim: usize) -> f64 {
    let k = centres.len() / dim;
    if k < 2 {
        return 0.0;
    }
    let total: f64 = (0..k)
        .map(|i| {
            let ci = &centres[i * dim..(i + 1) * dim];
            (0..k)
                .filter(|&j| j != i)
                .map(|j| squared_distance(ci, &centres[j * dim..(j + 1) * dim]))
                .fold(f64::INFINITY, f64::min)
                .sqrt()
        })
        .sum();
    total / k as f64
}

fn grid_centres(dim: usize, k: usize) -> Result<Vec<f64>, IdentifyError> {
    let mut m = 1usize;
    while m.checked_pow(dim as u32).is_some_and(|c| c < k) {
        m += 1;
    }
    let count = m
        .checked_pow(dim as u32)
        .filter(|&c| c <= RbfNetworkParams::MAX_CENTRES)
        .ok_or(IdentifyError::InvalidParameter {
            name: "centres",
            value: k as f64,
            reason: "an even grid with that many centres in this dimension exceeds 4096 centres",
        })?;
    let axis = |i: usize| if m == 1 { 0.5 } else { i as f64 / (m - 1) as f64 };
    let mut centres = Vec::with_capacity(count * dim);
    for idx in 0..count {
        let mut rest = idx;
        for _ in 0..dim {
            centres.push(axis(rest % m));
            rest /= m;
        }
    }
    Ok(centres)
}

/// k-means++ seeding then Lloyd iterations on row-major `x`. Returns at most `k` centres: fewer
/// when the data has fewer distinct points.
fn kmeans(x: &[f64], dim: usize, k: usize, seed: u64, max_iterations: usize) -> Vec<f64> {
    let n = x.len() / dim;
    let row = |i: usize| &x[i * dim..(i + 1) * dim];
    let mut rng = SplitMix64::new(seed);
    let first = ((rng.next_f64() * n as f64) as usize).min(n - 1);
    let mut centres: Vec<f64> = row(first).to_vec();
    let mut d2: Vec<f64> = (0..n).map(|i| squared_distance(row(i), row(first))).collect();
    while centres.len() / dim < k {
        let total: f64 = d2.iter().sum();
        if total <= 0.0 {
            break;
        }
        let target = rng.next_f64() * total;
        let mut acc = 0.0;
        let mut pick = n - 1;
        for (i, &d) in d2.iter().enumerate() {
            acc += d;
            if acc > target && d > 0.0 {
                pick = i;
                break;
            }
        }
        if d2[pick] <= 0.0 {
            // Rounding put the draw past the last positive weight: take the farthest point.
            pick = argmax(&d2);
        }
        centres.extend_from_slice(row(pick));
        for (i, d) in d2.iter_mut().enumerate() {
            *d = d.min(squared_distance(row(i), row(pick)));
        }
    }

    let k = centres.len() / dim;
    let mut assignment = vec![usize::MAX; n];
    for _ in 0..max_iterations {
        let mut changed = false;
        for (i, a) in assignment.iter_mut().enumerate() {
            let nearest = nearest_centre(row(i), &centres, dim);
            if nearest != *a {
                *a = nearest;
                changed = true;
            }
        }
        if !changed {
            break;
        }
        let mut sums = vec![0.0; k * dim];
        let mut counts = vec![0usize; k];
        for (i, &a) in assignment.iter().enumerate() {
            counts[a] += 1;
            for (s, v) in sums[a * dim..(a + 1) * dim].iter_mut().zip(row(i)) {
                *s += v;
            }
        }
        for j in 0..k {
            if counts[j] == 0 {
                // An emptied cluster takes the point worst served by its centre.
                let worst = argmax(
                    &(0..n)
                        .map(|i| {
                            squared_distance(row(i), &centres[assignment[i] * dim..(assignment[i] + 1) * dim])
                        })
                        .collect::<Vec<_>>(),
                );
                centres[j * dim..(j + 1) * dim].copy_from_slice(row(worst));
                assignment[worst] = j;
            } else {
                for (c, s) in centres[j * dim..(j + 1) * dim]
                    .iter_mut()
                    .zip(&sums[j * dim..(j + 1) * dim])
                {
                    *c = s / counts[j] as f64;
                }
            }
        }
    }
    centres
}

fn nearest_centre(p: &[f64], centres: &[f64], dim: usize) -> usize {
    let mut best = (0, f64::INFINITY);
    for (j, c) in centres.chunks_exact(dim).enumerate() {
        let d = squared_distance(p, c);
        if d < best.1 {
            best = (j, d);
        }
    }
    best.0
}

fn argmax(values: &[f64]) -> usize {
    let mut best = 0;
    for (i, &v) in values.iter().enumerate() {
        if v > values[best] {
            best = i;
        }
    }
    best
}

// ---------------------------------------------------------------------------------------------
// Shared helpers
// ---------------------------------------------------------------------------------------------

/// What to do with a rank-deficient design.
#[derive(Clone, Copy)]
pub(crate) enum Rank {
    /// The coefficients have a physical meaning: refuse to pick one of many solutions.
    Required(&'static str),
    /// The weights are only means to an interpolant: take the minimum-norm solution.
    MinimumNorm,
}

/// `argmin ‖A x − b‖` by SVD of `A` with its columns scaled to unit norm (which makes the rank
/// decision independent of the regressors' units); singular values up to
/// `ε · max(rows, columns)` × the largest count as zero.
pub(crate) fn least_squares(mut a: Mat<f64>, b: &[f64], rank: Rank) -> Result<Vec<f64>, IdentifyError> {
    let columns = a.ncols();
    let mut norms = Vec::with_capacity(columns);
    for j in 0..columns {
        let norm = a.col(j).norm_l2();
        let s = if norm > 0.0 { norm } else { 1.0 };
        for i in 0..a.nrows() {
            a[(i, j)] /= s;
        }
        norms.push(s);
    }
    let relative_cutoff = f64::EPSILON * (columns.min(a.nrows()).max(b.len()) as f64);
    let solution =
        svm::least_squares_svd(&a, b, relative_cutoff).ok_or_else(|| IdentifyError::Numerical {
            reason: "the singular value decomposition did not converge".to_owned(),
        })?;
    if let Rank::Required(model) = rank
        && (solution.rank < columns || solution.sigma_max == 0.0)
    {
        return Err(IdentifyError::RankDeficient {
            model,
            rank: solution.rank,
            columns,
        });
    }
    let mut x = solution.x;
    for (xi, s) in x.iter_mut().zip(&norms) {
        *xi /= s;
    }
    if x.iter().all(|v| v.is_finite()) {
        Ok(x)
    } else {
        Err(IdentifyError::Numerical {
            reason: "the solution is not finite".to_owned(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Pressures and velocities that vary independently, like a soft-contact protocol.
    fn friction_inputs(n: usize) -> (Vec<f64>, Vec<f64>) {
        let p = (0..n)
            .map(|i| 1.0 + 9.0 * ((i * 37) % n) as f64 / n as f64)
            .collect();
        let v = (0..n)
            .map(|i| 0.002 + 0.038 * (i / 10) as f64 / (n / 10) as f64)
            .collect();
        (p, v)
    }

    fn noise(i: usize) -> f64 {
        // Deterministic, zero-mean-ish, bounded by 0.05.
        0.05 * (((i * 7919) % 101) as f64 / 50.0 - 1.0)
    }

    #[test]
    fn coulomb_viscous_recovers_exact_coefficients() {
        let (p, v) = friction_inputs(320);
        let f: Vec<f64> = p.iter().zip(&v).map(|(p, v)| 0.7648 * p + 0.8333 * v).collect();
        let m = CoulombViscous::fit(&p, &v, &f).unwrap();
        assert!((m.coulomb - 0.7648).abs() < 1e-12, "{m:?}");
        assert!((m.viscous_nspm - 0.8333).abs() < 1e-10, "{m:?}");
        assert_eq!(m.intercept_n, 0.0);
        let f: Vec<f64> = f.iter().map(|f| f + 0.05).collect();
        let m = CoulombViscous::fit_with_intercept(&p, &v, &f).unwrap();
        assert!(
            (m.coulomb - 0.7648).abs() < 1e-12 && (m.intercept_n - 0.05).abs() < 1e-11,
            "{m:?}"
        );
        assert!((m.viscous_nspm - 0.8333).abs() < 1e-9, "{m:?}");
        assert!((m.predict(2.0, 0.01) - (0.7648 * 2.0 + 0.008333 + 0.05)).abs() < 1e-10);
    }

    #[test]
    fn coulomb_viscous_matches_the_two_by_two_normal_equations() {
        // Independent reference: Cramer's rule on AᵀA x = Aᵀb (fine at this conditioning).
        let (p, v) = friction_inputs(200);
        let f: Vec<f64> = (0..200)
            .map(|i| 0.6 * p[i] + 30.0 * v[i] + 0.3 + noise(i))
            .collect();
        let (mut spp, mut spv, mut svv, mut spf, mut svf) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for i in 0..200 {
            spp += p[i] * p[i];
            spv += p[i] * v[i];
            svv += v[i] * v[i];
            spf += p[i] * f[i];
            svf += v[i] * f[i];
        }
        let det = spp * svv - spv * spv;
        let mu = (spf * svv - spv * svf) / det;
        let c = (spp * svf - spv * spf) / det;
        let m = CoulombViscous::fit(&p, &v, &f).unwrap();
        assert!((m.coulomb - mu).abs() < 1e-10 * mu.abs(), "{} vs {mu}", m.coulomb);
        assert!(
            (m.viscous_nspm - c).abs() < 1e-8 * c.abs(),
            "{} vs {c}",
            m.viscous_nspm
        );
        // The residual is orthogonal to both regressors (the least-squares optimality condition).
        let r: Vec<f64> = (0..200).map(|i| f[i] - m.predict(p[i], v[i])).collect();
        let rp: f64 = r.iter().zip(&p).map(|(r, p)| r * p).sum();
        let rv: f64 = r.iter().zip(&v).map(|(r, v)| r * v).sum();
        assert!(rp.abs() < 1e-9 && rv.abs() < 1e-11, "{rp} {rv}");
    }

    #[test]
    fn coulomb_part_opposes_motion_in_both_directions() {
        let p: [f64; 6] = [1.0, 2.0, 3.0, 1.0, 2.0, 3.0];
        let v: [f64; 6] = [0.03, 0.01, 0.02, -0.02, -0.03, -0.01];
        let f: Vec<f64> = p
            .iter()
            .zip(&v)
            .map(|(p, v)| v.signum() * 0.4 * p + 2.0 * v)
            .collect();
        let m = CoulombViscous::fit(&p, &v, &f).unwrap();
        assert!(
            (m.coulomb - 0.4).abs() < 1e-12 && (m.viscous_nspm - 2.0).abs() < 1e-10,
            "{m:?}"
        );
        assert!((m.predict(2.0, -0.02) - (-0.8 - 0.04)).abs() < 1e-12);
        assert_eq!(m.predict(2.0, 0.0), 0.0);
    }

    #[test]
    fn coulomb_viscous_refuses_undetermined_coefficients() {
        let p: Vec<f64> = (1..20).map(f64::from).collect();
        let v: Vec<f64> = p.iter().map(|p| 0.01 * p).collect();
        let f: Vec<f64> = p.iter().map(|p| 0.5 * p).collect();
        assert!(matches!(
            CoulombViscous::fit(&p, &v, &f),
            Err(IdentifyError::RankDeficient {
                model: "Coulomb+viscous",
                rank: 1,
                columns: 2
            })
        ));
        // Constant velocity next to an intercept.
        let v = vec![0.01; p.len()];
        assert!(matches!(
            CoulombViscous::fit_with_intercept(&p, &v, &f),
            Err(IdentifyError::RankDeficient {
                rank: 2,
                columns: 3,
                ..
            })
        ));
    }

    #[test]
    fn coulomb_viscous_rejects_bad_input() {
        assert!(matches!(
            CoulombViscous::fit(&[], &[], &[]),
            Err(IdentifyError::Empty)
        ));
        assert!(matches!(
            CoulombViscous::fit(&[1.0, 2.0], &[0.1], &[1.0, 2.0]),
            Err(IdentifyError::LengthMismatch {
                name: "velocity_mps",
                found: 1,
                expected: 2
            })
        ));
        assert!(matches!(
            CoulombViscous::fit(&[1.0, f64::NAN], &[0.1, 0.2], &[1.0, 2.0]),
            Err(IdentifyError::NonFinite {
                name: "normal_force_n",
                index: 1,
                ..
            })
        ));
    }

    #[test]
    fn grid_network_reproduces_a_function_in_its_span() {
        // 1-D grid of 5 centres at 0, ¼, ½, ¾, 1 (the data spans [0, 1], so scaling is the
        // identity); σ = mean spacing = ¼. Targets built from known weights are fitted exactly.
        let w = [0.3, -1.2, 0.8, 2.0, -0.5];
        let bias = 0.7;
        let x: Vec<f64> = (0..=60).map(|i| f64::from(i) / 60.0).collect();
        let phi = |x: f64, j: usize| (-(x - j as f64 * 0.25).powi(2) / (2.0 * 0.0625)).exp();
        let y: Vec<f64> = x
            .iter()
            .map(|&x| bias + (0..5).map(|j| w[j] * phi(x, j)).sum::<f64>())
            .collect();
        let params = RbfNetworkParams::default()
            .centres(5)
            .placement(CentrePlacement::Grid)
            .ridge(0.0);
        let net = RbfNetwork::fit(&x, 1, &y, &params).unwrap();
        assert_eq!(net.centres, vec![0.0, 0.25, 0.5, 0.75, 1.0]);
        assert!((net.width - 0.25).abs() < 1e-15);
        for (got, want) in net.weights.iter().zip(&w) {
            assert!((got - want).abs() < 1e-8, "{got} vs {want}");
        }
        assert!((net.bias - bias).abs() < 1e-8);
        let probe = 0.4321;
        let expected = bias + (0..5).map(|j| w[j] * phi(probe, j)).sum::<f64>();
        assert!((net.predict(&[probe]).unwrap() - expected).abs() < 1e-9);
    }

    #[test]
    fn kmeans_finds_separated_clusters_and_is_deterministic() {
        // Three tight clusters in 2-D; with k = 3 the centres are the clusters' means.
        let clusters = [(0.0, 0.0), (10.0, 0.0), (5.0, 8.0)];
        let mut x = Vec::new();
        for &(cx, cy) in &clusters {
            for i in 0..30 {
                let a = f64::from(i) * 0.7;
                x.extend([cx + 0.1 * a.cos(), cy + 0.1 * a.sin()]);
            }
        }
        let scaling = InputScaling::min_max(&x, 2);
        let xs = scaling.apply(&x);
        let means: Vec<[f64; 2]> = (0..3)
            .map(|c| {
                let rows = &xs[c * 60..(c + 1) * 60];
                let (sx, sy) = rows
                    .chunks_exact(2)
                    .fold((0.0, 0.0), |(sx, sy), r| (sx + r[0], sy + r[1]));
                [sx / 30.0, sy / 30.0]
            })
            .collect();
        for seed in [0, 1, 42] {
            let centres = kmeans(&xs, 2, 3, seed, 100);
            assert_eq!(centres.len(), 6);
            for m in &means {
                let d = centres
                    .chunks_exact(2)
                    .map(|c| squared_distance(c, m))
                    .fold(f64::INFINITY, f64::min);
                assert!(d < 1e-24, "seed {seed}: no centre at {m:?}: {centres:?}");
            }
        }
        let y: Vec<f64> = (0..90).map(|i| f64::from(i % 7)).collect();
        let params = RbfNetworkParams::default().centres(6);
        let fit = || RbfNetwork::fit(&x, 2, &y, &params).map_err(|e| e.to_string());
        assert_eq!(fit(), fit());
        // Fewer distinct points than centres: as many centres as distinct points.
        assert_eq!(kmeans(&[1.0, 1.0, 2.0, 2.0], 1, 3, 0, 10).len(), 2);
    }

    #[test]
    fn network_interpolates_a_smooth_surface_on_held_out_points() {
        let f = |a: f64, b: f64| (3.0 * a).sin() * (2.0 * b).cos() + 0.5 * a * b;
        let train: Vec<f64> = (0..400)
            .flat_map(|i| [f64::from(i % 20) / 19.0, f64::from(i / 20) / 19.0])
            .collect();
        let y: Vec<f64> = train.chunks_exact(2).map(|r| f(r[0], r[1])).collect();
        let test: Vec<f64> = (0..100)
            .flat_map(|i| [(f64::from(i % 10) + 0.5) / 10.0, (f64::from(i / 10) + 0.5) / 10.0])
            .collect();
        let held_out_rmse = |centres: usize| {
            let net = RbfNetwork::fit(&train, 2, &y, &RbfNetworkParams::default().centres(centres)).unwrap();
            assert_eq!(net.n_centres(), centres);
            let pred = net.predict_many(&test).unwrap();
            let sum: f64 = test
                .chunks_exact(2)
                .zip(&pred)
                .map(|(r, p)| (f(r[0], r[1]) - p).powi(2))
                .sum();
            (sum / 100.0).sqrt()
        };
        let rmse: Vec<f64> = [9, 25, 49].into_iter().map(held_out_rmse).collect();
        eprintln!("held-out RMSE for 9, 25, 49 centres: {rmse:?}");
        assert!(rmse[0] < 0.06 && rmse[1] < 0.03 && rmse[2] < 0.018, "{rmse:?}");
        assert!(rmse[0] > rmse[1] && rmse[1] > rmse[2], "{rmse:?}");
    }

    #[test]
    fn a_huge_ridge_leaves_only_the_bias_at_the_mean() {
        let x: Vec<f64> = (0..50).map(|i| f64::from(i) * 0.1).collect();
        let y: Vec<f64> = x.iter().map(|x| x.sin() + 2.0).collect();
        let mean = y.iter().sum::<f64>() / 50.0;
        let net = RbfNetwork::fit(&x, 1, &y, &RbfNetworkParams::default().centres(8).ridge(1e12)).unwrap();
        assert!(net.weights.iter().all(|w| w.abs() < 1e-9), "{:?}", net.weights);
        assert!((net.bias - mean).abs() < 1e-8, "{} vs {mean}", net.bias);
    }

    #[test]
    fn centre_count_follows_the_sample_count() {
        let centres = |n| RbfNetworkParams::for_samples(n).centres;
        assert_eq!(
            [centres(5), centres(31), centres(150), centres(360), centres(8146)],
            [2, 3, 15, 20, 20]
        );
        assert_eq!(RbfNetworkParams::for_samples(360), RbfNetworkParams::default());
    }

    #[test]
    fn network_rejects_bad_input() {
        let p = RbfNetworkParams::default();
        assert!(matches!(
            RbfNetwork::fit(&[], 1, &[], &p),
            Err(IdentifyError::Empty)
        ));
        assert!(matches!(
            RbfNetwork::fit(&[1.0, 2.0, 3.0], 2, &[1.0, 2.0], &p),
            Err(IdentifyError::LengthMismatch {
                name: "x",
                found: 3,
                expected: 4
            })
        ));
        assert!(matches!(
            RbfNetwork::fit(&[1.0, 2.0], 0, &[1.0, 2.0], &p),
            Err(IdentifyError::InvalidParameter { name: "dim", .. })
        ));
        assert!(matches!(
            RbfNetwork::fit(&[1.0, 2.0], 1, &[1.0, f64::INFINITY], &p),
            Err(IdentifyError::NonFinite {
                name: "y",
                index: 1,
                ..
            })
        ));
        for bad in [p.centres(0), p.width_factor(-1.0), p.ridge(f64::NAN)] {
            assert!(matches!(
                RbfNetwork::fit(&[1.0, 2.0], 1, &[1.0, 2.0], &bad),
                Err(IdentifyError::InvalidParameter { .. })
            ));
        }
        assert!(matches!(
            RbfNetwork::fit(
                &[0.0; 8],
                8,
                &[1.0],
                &p.centres(4000).placement(CentrePlacement::Grid)
            ),
            Err(IdentifyError::InvalidParameter { name: "centres", .. })
        ));
        let net = RbfNetwork::fit(&[0.0, 1.0, 2.0], 1, &[1.0, 2.0, 3.0], &p.centres(2)).unwrap();
        assert!(matches!(
            net.predict(&[1.0, 2.0]),
            Err(IdentifyError::LengthMismatch { .. })
        ));
        assert!(matches!(
            net.predict(&[f64::NAN]),
            Err(IdentifyError::NonFinite { .. })
        ));
        assert!(matches!(net.predict_many(&[1.0, 2.0, 3.0]), Ok(v) if v.len() == 3));
    }
}
