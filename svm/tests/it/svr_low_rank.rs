//! The low-rank interior point reaches the dense interior point's certified optimum on
//! needle-like data, `Solver::Auto` takes it at capture sizes, and a kernel matrix that is not
//! low-rank is a typed error for it and a fallback for `Auto`.
#![allow(clippy::unwrap_used)]

use svm::{ACCEPT_GAP, Kernel, Solver, SvmError, SvrParams, fit};

/// Deterministic values in [0, 1) with no lattice structure.
fn wiggle(i: usize, salt: f64) -> f64 {
    (i as f64 * 0.618_033_988_749_894_8 + salt).fract()
}

/// `n` needle-like samples on [depth, speed] in the unit box: speeds on a few levels, a force
/// that rises with depth, drops at two punctures, and carries ±0.05 N of deterministic noise.
fn needle_like(n: usize) -> (Vec<f64>, Vec<f64>) {
    let mut x = Vec::with_capacity(2 * n);
    let mut y = Vec::with_capacity(n);
    for i in 0..n {
        let depth = wiggle(i, 0.1);
        let speed = [0.2, 0.4, 0.6, 0.8][i % 4];
        let loading = if depth < 0.4 {
            1.5 * (depth / 0.4).powi(2)
        } else if depth < 0.75 {
            0.3 + 0.8 * ((depth - 0.4) / 0.35).powi(2)
        } else {
            0.5 + 0.2 * (depth - 0.75)
        };
        x.extend([depth, speed]);
        y.push(loading * (0.8 + 0.4 * speed) + 0.1 * (wiggle(i, 0.77) - 0.5));
    }
    (x, y)
}

fn params(solver: Solver, gamma: f64) -> SvrParams {
    SvrParams::builder()
        .c(100.0)
        .epsilon(0.02)
        .kernel(Kernel::Rbf { gamma })
        .solver(solver)
        .build()
        .unwrap()
}

#[test]
fn low_rank_and_dense_interior_points_agree() {
    let (x, y) = needle_like(1200);
    let low = fit(&params(Solver::LowRank, 30.0), &x, 2, &y).unwrap();
    let dense = fit(&params(Solver::InteriorPoint, 30.0), &x, 2, &y).unwrap();
    assert!(low.solver.starts_with("low-rank"), "{}", low.solver);
    assert!(low.relative_gap() <= ACCEPT_GAP, "{}", low.relative_gap());
    let scale = dense.primal_objective.abs().max(1.0);
    assert!(
        (low.primal_objective - dense.primal_objective).abs() <= 2.0 * ACCEPT_GAP * scale,
        "{} vs {}",
        low.primal_objective,
        dense.primal_objective
    );
    let worst = x
        .chunks_exact(2)
        .map(|r| (low.model.predict(r) - dense.model.predict(r)).abs())
        .fold(0.0f64, f64::max);
    assert!(worst < 1e-3, "predictions differ by {worst}");
    // Both are certified to 1e-6, not to the last bit, so only samples whose residual lies
    // within the two models' distance of the tube's edge may be a support vector in one and
    // not the other: strictly inside (β = 0) or outside (|β| = C) both fits alike otherwise.
    let at_edge = x
        .chunks_exact(2)
        .zip(&y)
        .filter(|(r, yi)| ((*yi - dense.model.predict(r)).abs() - 0.02).abs() <= worst)
        .count();
    let differ = low.model.n_sv().abs_diff(dense.model.n_sv());
    assert!(
        differ <= at_edge,
        "{differ} support vectors differ, {at_edge} samples at the edge"
    );
}

#[test]
fn auto_takes_the_low_rank_path_at_capture_sizes() {
    let (x, y) = needle_like(4000);
    let auto = fit(&params(Solver::Auto, 30.0), &x, 2, &y).unwrap();
    assert!(auto.solver.starts_with("low-rank"), "{}", auto.solver);
    assert!(auto.relative_gap() <= ACCEPT_GAP, "{}", auto.relative_gap());
    // Half the samples lie outside the ±0.02 N tube in ±0.05 N noise: a fit that had given up
    // on them would have far fewer support vectors.
    assert!(auto.model.n_sv() > 1000, "{}", auto.model.n_sv());
}

#[test]
fn a_kernel_matrix_that_is_not_low_rank_is_refused_by_name_and_handled_by_auto() {
    // γ = 1e5 on 1,200 points spread over the unit box: neighbours are ~0.03 apart, so the
    // kernel matrix is nearly the identity, of full numerical rank.
    let (_, y) = needle_like(1200);
    let spread: Vec<f64> = (0..1200)
        .flat_map(|i| [wiggle(i, 0.1), wiggle(i, 0.37) * 0.999])
        .collect();
    let err = fit(&params(Solver::LowRank, 1e5), &spread, 2, &y).unwrap_err();
    assert!(matches!(err, SvmError::Numerical { .. }), "{err}");
    assert!(err.to_string().contains("rank"), "{err}");
    let auto = fit(&params(Solver::Auto, 1e5), &spread, 2, &y).unwrap();
    assert!(!auto.solver.starts_with("low-rank"), "{}", auto.solver);
    assert!(auto.relative_gap() <= ACCEPT_GAP);
}
