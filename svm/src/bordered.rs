//! Dense solves of the bordered KKT system `[K_FF 1; 1ᵀ 0] [β_F; b] = rhs` over the free
//! samples, which both exact finishes (the dense polish and the low-rank interior point's
//! finish) factorise: Cholesky of `K_FF` with the border eliminated, LU with full pivoting
//! where that does not solve, and the minimum-norm least squares (by the symmetric
//! eigendecomposition) when the system is singular (more free samples than the kernel's rank
//! plus one, as with a linear kernel or repeated input rows).

use faer::linalg::solvers::Solve;
use faer::{Mat, Side};

/// What to do with a singular system's least-squares solution.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Singular {
    /// Take it, and let the caller's KKT check judge it (the polish).
    LeastSquares,
    /// Take it only if it solves the system to the tolerance (the finish, which certifies
    /// its result by the system's residual).
    MustSolve,
}

/// A solution of the bordered system and what finding it cost.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Bordered {
    /// `[β_F; b]`.
    pub x: Vec<f64>,
    /// Flops of every factorisation tried, by the textbook counts for an `m × m` matrix
    /// (Golub & Van Loan): Cholesky `m³/3`, LU `2m³/3`, the symmetric eigendecomposition with
    /// its eigenvectors `9m³`. Measured here on bordered RBF systems of 91 rows, the three took
    /// 0.05, 0.20 and 1.0 ms: the last costs more than half a dense Cholesky of 480 samples.
    pub flops: f64,
}

/// Flops of a Cholesky factorisation of an `m × m` matrix.
pub(crate) fn cholesky_flops(m: usize) -> f64 {
    (m as f64).powi(3) / 3.0
}

/// Solves `a x = rhs` (`rhs` one column, `a` symmetric): by LU with full pivoting when that
/// solves it to `tolerance × (1 + max |rhs|)` in every row, else by the minimum-norm least
/// squares, kept as `singular` says.
/// `None` when neither gives a finite (and, for [`Singular::MustSolve`], solving) `x`.
pub(crate) fn solve_bordered(
    a: &Mat<f64>,
    rhs: &Mat<f64>,
    tolerance: f64,
    singular: Singular,
) -> Option<Vec<f64>> {
    solve_bordered_counted(a, rhs, tolerance, singular)
        .ok()
        .map(|s| s.x)
}

/// [`solve_bordered`], with the flops its attempts took; `Err(flops)` where it found no `x`.
pub(crate) fn solve_bordered_counted(
    a: &Mat<f64>,
    rhs: &Mat<f64>,
    tolerance: f64,
    singular: Singular,
) -> Result<Bordered, f64> {
    let m = a.nrows();
    let cube = (m as f64).powi(3);
    let mut flops = cholesky_flops(m);
    let b: Vec<f64> = (0..m).map(|r| rhs[(r, 0)]).collect();
    let scale = 1.0 + b.iter().fold(0.0f64, |acc, v| acc.max(v.abs()));
    let solves = |x: &[f64]| {
        x.iter().all(|v| v.is_finite())
            && (0..m).all(|r| {
                let ax: f64 = (0..m).map(|s| a[(r, s)] * x[s]).sum();
                (ax - b[r]).abs() <= tolerance * scale
            })
    };
    if let Some(x) = border_eliminated(a, &b)
        && solves(&x)
    {
        return Ok(Bordered { x, flops });
    }
    flops += 2.0 * cube / 3.0;
    let lu = a.full_piv_lu().solve(rhs);
    let x: Vec<f64> = (0..m).map(|r| lu[(r, 0)]).collect();
    if solves(&x) {
        return Ok(Bordered { x, flops });
    }
    flops += 9.0 * cube;
    let Some(x) = symmetric_least_squares(a, &b, SINGULAR_CUTOFF) else {
        return Err(flops);
    };
    let kept = match singular {
        Singular::LeastSquares => x.iter().all(|v| v.is_finite()),
        Singular::MustSolve => solves(&x),
    };
    if kept {
        Ok(Bordered { x, flops })
    } else {
        Err(flops)
    }
}

/// `[A u; uᵀ d] [z; b] = [r; rₘ]` by a Cholesky factor of `A` (positive definite for an RBF
/// kernel's distinct samples): `z = A⁻¹r − b A⁻¹u` with `b` from the last row. Half the flops of
/// an LU and blocked where full pivoting is not: at 2,456 free samples of Friedman #1 one
/// solve took 2.3 s by full-pivot LU. `None` when `A` has no Cholesky factor or the border is
/// not symmetric; the caller checks the residual of what it returns.
fn border_eliminated(a: &Mat<f64>, b: &[f64]) -> Option<Vec<f64>> {
    let m = a.nrows().checked_sub(1)?;
    if (0..m).any(|s| a[(m, s)] != a[(s, m)]) {
        return None;
    }
    let llt = a.as_ref().submatrix(0, 0, m, m).llt(Side::Lower).ok()?;
    let both = Mat::<f64>::from_fn(m, 2, |r, k| if k == 0 { b[r] } else { a[(r, m)] });
    let z = llt.solve(&both);
    let (u_r, u_u): (f64, f64) = (0..m).fold((0.0, 0.0), |(p, q), r| {
        (p + a[(m, r)] * z[(r, 0)], q + a[(m, r)] * z[(r, 1)])
    });
    let bias = (b[m] - u_r) / (a[(m, m)] - u_u);
    let mut x: Vec<f64> = (0..m).map(|r| z[(r, 0)] - bias * z[(r, 1)]).collect();
    x.push(bias);
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// Singular values up to this times the largest count as zero in the least-squares solves.
const SINGULAR_CUTOFF: f64 = 1e-12;

/// Minimum-norm least-squares solution of `a x = b` by the thin SVD, singular values up to
/// [`SINGULAR_CUTOFF`] times the largest counted as zero.
pub(crate) fn svd_solve(a: &Mat<f64>, b: &[f64]) -> Option<Vec<f64>> {
    least_squares_svd(a, b, SINGULAR_CUTOFF).map(|s| s.x)
}

/// [`svd_solve`]'s minimum-norm least squares for a symmetric `a` (its lower triangle read),
/// by its eigendecomposition: a symmetric matrix's singular values are its eigenvalues'
/// magnitudes and its singular vectors its eigenvectors, so the pseudo-inverse is the same,
/// for about half the work. Measured on bordered RBF systems: 1.0 ms against the SVD's 1.9 ms
/// at 91 rows, 14 against 23 ms at 301; on the needle's nearly dependent free samples this
/// fallback is most of what a polish or a finish round costs.
fn symmetric_least_squares(a: &Mat<f64>, b: &[f64], relative_cutoff: f64) -> Option<Vec<f64>> {
    if b.len() != a.nrows() || a.nrows() != a.ncols() {
        return None;
    }
    let evd = a.self_adjoint_eigen(Side::Lower).ok()?;
    let (u, s) = (evd.U(), evd.S().column_vector());
    let largest = (0..s.nrows()).fold(0.0f64, |m, i| m.max(s[i].abs()));
    let cutoff = relative_cutoff * largest;
    let mut x = vec![0.0; a.ncols()];
    for i in 0..s.nrows() {
        if s[i].abs() > cutoff {
            let coefficient = (0..a.nrows()).map(|r| u[(r, i)] * b[r]).sum::<f64>() / s[i];
            for (row, xr) in x.iter_mut().enumerate() {
                *xr += u[(row, i)] * coefficient;
            }
        }
    }
    Some(x)
}

/// A least-squares solution by SVD and what it rests on.
#[derive(Debug, Clone, PartialEq)]
pub struct SvdSolution {
    /// The minimum-norm `x` minimising `‖a x − b‖`.
    pub x: Vec<f64>,
    /// How many singular values lie above the cutoff: `x`'s columns are independent when this
    /// equals their count.
    pub rank: usize,
    /// The largest singular value.
    pub sigma_max: f64,
}

/// Minimum-norm least-squares solution of `a x = b` by the thin SVD, singular values up to
/// `relative_cutoff ×` the largest counted as zero (the pseudo-inverse's rule); `None` when the
/// SVD does not converge or `b` is not as long as `a` is tall.
pub fn least_squares_svd(a: &Mat<f64>, b: &[f64], relative_cutoff: f64) -> Option<SvdSolution> {
    if b.len() != a.nrows() {
        return None;
    }
    let svd = a.thin_svd().ok()?;
    let (u, v) = (svd.U(), svd.V());
    let s = svd.S().column_vector();
    let sigma_max = (0..s.nrows()).fold(0.0f64, |m, i| m.max(s[i]));
    let cutoff = relative_cutoff * sigma_max;
    let mut x = vec![0.0; a.ncols()];
    let mut rank = 0;
    for i in 0..s.nrows() {
        if s[i] > cutoff {
            rank += 1;
            let coefficient = (0..a.nrows()).map(|r| u[(r, i)] * b[r]).sum::<f64>() / s[i];
            for (col, xc) in x.iter_mut().enumerate() {
                *xc += v[(col, i)] * coefficient;
            }
        }
    }
    Some(SvdSolution { x, rank, sigma_max })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The bordered system of a 1-D linear kernel over `xs`: rank 2 however many samples.
    fn linear_bordered(xs: &[f64]) -> Mat<f64> {
        let m = xs.len() + 1;
        Mat::from_fn(m, m, |r, c| match (r < xs.len(), c < xs.len()) {
            (true, true) => xs[r] * xs[c],
            (false, false) => 0.0,
            _ => 1.0,
        })
    }

    #[test]
    fn a_regular_system_is_solved_exactly_and_a_singular_one_as_asked() {
        // Two samples: regular, solved by the LU to rounding.
        let a = linear_bordered(&[1.0, 2.0]);
        let rhs = Mat::from_fn(3, 1, |r, _| [1.0, 3.0, 0.0][r]);
        for singular in [Singular::LeastSquares, Singular::MustSolve] {
            let x = solve_bordered(&a, &rhs, 1e-10, singular).expect("regular");
            for r in 0..3 {
                let ax: f64 = (0..3).map(|c| a[(r, c)] * x[c]).sum();
                assert!((ax - rhs[(r, 0)]).abs() < 1e-12, "{x:?}");
            }
        }
        // Three samples of a linear kernel: singular. Consistent right-hand side (in the
        // range): both take the minimum-norm solution, which solves it.
        let a = linear_bordered(&[1.0, 2.0, 3.0]);
        let consistent = Mat::from_fn(4, 1, |r, _| [1.0 + 0.5, 2.0 + 0.5, 3.0 + 0.5, 0.0][r]);
        let x = solve_bordered(&a, &consistent, 1e-9, Singular::MustSolve).expect("consistent");
        assert!(x.iter().all(|v| v.is_finite()));
        // Inconsistent (not in the range): the least squares is kept only when asked.
        let inconsistent = Mat::from_fn(4, 1, |r, _| [1.0, 0.0, 1.0, 0.0][r]);
        assert!(solve_bordered(&a, &inconsistent, 1e-9, Singular::MustSolve).is_none());
        let ls = solve_bordered(&a, &inconsistent, 1e-10, Singular::LeastSquares).expect("least squares");
        let svd = svd_solve(&a, &[1.0, 0.0, 1.0, 0.0]).expect("svd");
        for (e, s) in ls.iter().zip(&svd) {
            assert!(
                (e - s).abs() <= 1e-12 * (1.0 + s.abs()),
                "{ls:?} against the SVD's {svd:?}"
            );
        }
    }
}
