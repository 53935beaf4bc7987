//! Numerical stability at the extremes (C from 1e-6 to 1e11, ε from 0 to 1, γ from 1e-6 to 1e6,
//! one sample to 350, duplicated inputs, constant targets, unscaled inputs of magnitude 1e6):
//! every fit returns a model whose optimality the test certifies itself — a dual-feasible β
//! whose duality gap is within tolerance, computed here from the model alone — or a typed
//! error. Never NaN, never a panic; budgets bound the time.

#![allow(clippy::unwrap_used)] // A failed unwrap is a failed test.

use std::time::Duration;

use svm::{Kernel, SvmError, SvrParams, fit, slack};

/// Checks a fit independently: recomputes both objectives from the model and the data.
fn certify(
    x: &[f64],
    dim: usize,
    y: &[f64],
    c: f64,
    eps: f64,
    kernel: Kernel,
    ctx: &str,
) -> Result<(), SvmError> {
    let params = SvrParams::builder()
        .c(c)
        .epsilon(eps)
        .kernel(kernel)
        .time_budget(Duration::from_secs(5))
        .build()
        .unwrap();
    let f = match fit(&params, x, dim, y) {
        Ok(f) => f,
        Err(
            e @ (SvmError::NotConverged { .. }
            | SvmError::Budget { .. }
            | SvmError::Numerical { .. }
            | SvmError::Uncertified { .. }),
        ) => {
            return Err(e);
        }
        Err(e) => panic!("{ctx}: unexpected error {e}"),
    };
    let m = &f.model;
    assert!(
        m.bias.is_finite() && m.coefficients.iter().all(|b| b.is_finite()),
        "{ctx}: non-finite model"
    );
    let n = y.len();
    // β over all samples: support vectors are copies of training inputs.
    let sum: f64 = m.coefficients.iter().sum();
    let abs_sum: f64 = m.coefficients.iter().map(|b| b.abs()).sum();
    assert!(
        m.coefficients.iter().all(|b| b.abs() <= c * (1.0 + 1e-12)),
        "{ctx}: |β| > C"
    );
    assert!(sum.abs() <= 1e-9 * (1.0 + abs_sum), "{ctx}: Σβ = {sum}");
    let mut quad = 0.0;
    for i in 0..m.n_sv() {
        for j in 0..m.n_sv() {
            quad +=
                m.coefficients[i] * m.coefficients[j] * kernel.eval(m.support_vector(i), m.support_vector(j));
        }
    }
    quad *= 0.5;
    // Support vectors are the training samples with β ≠ 0, in order: match them up in order
    // (duplicated inputs with different targets must each keep their own target).
    let mut next = 0;
    let y_of_sv: f64 = (0..m.n_sv())
        .map(|i| {
            let sv = m.support_vector(i);
            let k = (next..n).find(|&k| &x[k * dim..(k + 1) * dim] == sv).unwrap();
            next = k + 1;
            m.coefficients[i] * y[k]
        })
        .sum();
    let dual = quad + eps * abs_sum - y_of_sv;
    let quad_primal = match m.linear_weights() {
        Some(w) if m.weights.is_some() => 0.5 * w.iter().map(|v| v * v).sum::<f64>(),
        _ => quad,
    };
    let primal = quad_primal
        + c * (0..n)
            .map(|i| slack(y[i], m.predict(&x[i * dim..(i + 1) * dim]), eps))
            .sum::<f64>();
    let ymax = y.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let kmax = x
        .chunks_exact(dim)
        .map(|r| kernel.eval(r, r).abs())
        .fold(1.0, f64::max);
    // What double precision can resolve: the objectives' own sums, and each fitted value's
    // rounding (~ε·Σ|βⱼKᵢⱼ|) multiplied by C in the loss.
    let f_rounding = if m.weights.is_some() {
        0.0
    } else {
        abs_sum * kmax + m.bias.abs()
    };
    let rounding =
        64.0 * n as f64 * f64::EPSILON * (abs_sum * (1.0 + ymax) + abs_sum * abs_sum * kmax + c * f_rounding);
    let gap = (primal + dual).abs();
    assert!(
        gap <= 1e-6 * primal.abs().max(1.0) + rounding,
        "{ctx}: P {primal} D {dual} gap {gap} (rounding {rounding})"
    );
    Ok(())
}

#[test]
fn extremes_grid_converges_to_certified_optima_or_says_why() {
    let mut rng = capture::rng::SplitMix64::new(7);
    let mut counts = (0usize, 0usize);
    for n in [1usize, 2, 31, 350] {
        let dim = 2;
        let x: Vec<f64> = (0..n * dim).map(|_| rng.next_f64()).collect();
        let y: Vec<f64> = (0..n)
            .map(|i| (3.0 * x[i * dim]).sin() + 0.1 * (rng.next_f64() - 0.5))
            .collect();
        let (cs, epss, gammas): (&[f64], &[f64], &[f64]) = if n == 350 {
            (&[1e-6, 1e11], &[0.0, 1.0], &[1e-6, 1e6])
        } else {
            (
                &[1e-6, 1e-3, 1.0, 1e3, 1e6, 1e11],
                &[0.0, 1e-9, 1e-6, 1e-3, 1.0],
                &[1e-6, 1e-3, 1.0, 1e3, 1e6],
            )
        };
        for &c in cs {
            for &eps in epss {
                for &gamma in gammas {
                    let ctx = format!("n {n} C {c:e} ε {eps:e} γ {gamma:e}");
                    match certify(&x, dim, &y, c, eps, Kernel::Rbf { gamma }, &ctx) {
                        Ok(()) => counts.0 += 1,
                        Err(e) => {
                            println!("{ctx}: {e}");
                            counts.1 += 1;
                        }
                    }
                }
            }
        }
    }
    println!("certified {} fits, {} typed errors", counts.0, counts.1);
    // Typed errors are allowed, but the grid must overwhelmingly converge.
    assert!(counts.1 * 20 <= counts.0 + counts.1, "{counts:?}");
}

#[test]
fn degenerate_data_duplicates_constants_and_huge_inputs() {
    // Duplicated inputs with conflicting targets.
    let x = [0.1, 0.1, 0.1, 0.5, 0.9];
    let y = [1.0, 1.2, 0.8, 0.0, -1.0];
    for c in [1e-3, 1.0, 1e11] {
        for eps in [0.0, 0.05] {
            // At C = 1e11 the RBF expansion's β ~ C fixes f(xᵢ) only to ε_mach·Σ|βⱼKᵢⱼ| ~ 1e-5,
            // which the loss multiplies by C: the certificate may refuse it (a typed error),
            // never return it unchecked.
            match certify(
                &x,
                1,
                &y,
                c,
                eps,
                Kernel::Rbf { gamma: 2.0 },
                &format!("duplicates C {c} ε {eps}"),
            ) {
                Ok(()) => {}
                Err(e @ SvmError::Uncertified { .. }) if c >= 1e11 => {
                    println!("duplicates C {c} ε {eps}: {e}")
                }
                Err(e) => panic!("duplicates C {c} ε {eps}: {e}"),
            }
            certify(
                &x,
                1,
                &y,
                c,
                eps,
                Kernel::Linear,
                &format!("duplicates linear C {c} ε {eps}"),
            )
            .unwrap();
        }
    }
    // Constant targets: the flat function, no support vector needed inside the tube.
    let xs: Vec<f64> = (0..31).map(|i| i as f64 / 30.0).collect();
    let ys = vec![2.5; 31];
    for eps in [0.0, 0.1] {
        let params = SvrParams::builder()
            .c(1e11)
            .epsilon(eps)
            .kernel(Kernel::Rbf { gamma: 1.0 })
            .build()
            .unwrap();
        let f = fit(&params, &xs, 1, &ys).unwrap();
        for xi in &xs {
            assert!(
                (f.model.predict(&[*xi]) - 2.5).abs() <= eps + 1e-9,
                "constant ε {eps}"
            );
        }
    }
    // Unscaled inputs of magnitude 1e6: linear kernel values ~1e12.
    let xb: Vec<f64> = (0..31).map(|i| 1e6 + 1e3 * i as f64).collect();
    let yb: Vec<f64> = xb.iter().map(|v| 1e-6 * v + 0.01 * ((v * 7.0).sin())).collect();
    for c in [1e-6, 1.0, 1e11] {
        match certify(&xb, 1, &yb, c, 1e-3, Kernel::Linear, &format!("1e6 inputs C {c}")) {
            Ok(()) => {}
            Err(e) => println!("1e6 inputs C {c}: {e}"),
        }
    }
    // Bad input is a typed error, not a panic.
    let p = SvrParams::builder().build().unwrap();
    assert!(matches!(fit(&p, &[], 1, &[]), Err(SvmError::NoSamples)));
    assert!(matches!(
        fit(&p, &[1.0, 2.0], 1, &[1.0]),
        Err(SvmError::Shape { .. })
    ));
    assert!(matches!(
        fit(&p, &[f64::NAN], 1, &[1.0]),
        Err(SvmError::NonFinite { row: 0, .. })
    ));
    assert!(matches!(
        fit(&p, &[1.0], 1, &[f64::INFINITY]),
        Err(SvmError::NonFinite { .. })
    ));
}
