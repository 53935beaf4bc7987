//! A support-vector budget: a fitted kernel model replaced by one with at most `K` support
//! vectors, for a haptic tick whose time grows with their number.
//!
//! The reduced model is not an SVR solution, so it has no duality gap: what it carries instead
//! is its measured distance from the certified model, the largest and the RMS difference of the
//! two over the inputs given (the training inputs), so a user sees what the budget costs.
//!
//! Centres are chosen greedily among the model's support vectors (orthogonal matching
//! pursuit): each step adds the one whose kernel column best matches what the chosen ones leave
//! of the full model's outputs, and the coefficients and bias are refitted by least squares on
//! all the inputs. Keeping the largest |β| instead would keep the bounded support vectors,
//! the outliers at |β| = C, first. Written here because no crate does reduced-set SVR; faer
//! solves the small least-squares systems.

use faer::linalg::solvers::Solve;
use faer::{Mat, Side};

use super::error::SvmError;
use super::kernel::Kernel;
use super::model::SvrModel;

/// A model within a support-vector budget, and how far it is from the model it replaces.
#[derive(Debug, Clone, PartialEq)]
pub struct Reduction {
    /// The reduced model.
    pub model: SvrModel,
    /// Support vectors of the model it replaces.
    pub from_sv: usize,
    /// Largest |reduced − full| over the inputs, in the model's output unit.
    pub max_deviation: f64,
    /// RMS of reduced − full over the inputs.
    pub rms_deviation: f64,
}

/// `model` with at most `max_sv` support vectors, refitted to its own outputs at the `n × dim`
/// inputs `x` (the training inputs). A model within the budget, or a linear one (whose cost
/// does not grow with its support vectors), comes back unchanged with zero deviation.
pub fn reduce_support(model: &SvrModel, x: &[f64], dim: usize, max_sv: usize) -> Result<Reduction, SvmError> {
    if max_sv == 0 {
        return Err(SvmError::InvalidHyperparameter {
            name: "max_sv",
            value: 0.0,
            reason: "at least one support vector",
        });
    }
    if dim != model.dim || !x.len().is_multiple_of(dim.max(1)) {
        return Err(SvmError::Shape {
            array: "input",
            values: x.len(),
            rows_of: "inputs",
            rows: x.len() / dim.max(1),
            dim,
        });
    }
    let unchanged = || Reduction {
        model: model.clone(),
        from_sv: model.n_sv(),
        max_deviation: 0.0,
        rms_deviation: 0.0,
    };
    if model.n_sv() <= max_sv || model.kernel == Kernel::Linear || model.weights.is_some() {
        return Ok(unchanged());
    }
    let n = x.len() / dim;
    let full: Vec<f64> = x.chunks(dim).map(|xi| model.predict(xi)).collect();
    // Kernel columns of every candidate centre over the inputs, and their squared norms.
    let columns: Vec<Vec<f64>> = (0..model.n_sv())
        .map(|j| {
            let c = model.support_vector(j);
            x.chunks(dim).map(|xi| model.kernel.eval(c, xi)).collect()
        })
        .collect();
    let norms: Vec<f64> = columns.iter().map(|c| c.iter().map(|v| v * v).sum()).collect();
    let mut chosen: Vec<usize> = Vec::with_capacity(max_sv);
    let mut taken = vec![false; model.n_sv()];
    // The residual starts as the outputs less their mean (the bias is always in the fit).
    let mean = full.iter().sum::<f64>() / n as f64;
    let mut residual: Vec<f64> = full.iter().map(|f| f - mean).collect();
    let mut solution = (Vec::new(), mean);
    while chosen.len() < max_sv {
        let best = (0..model.n_sv())
            .filter(|&j| !taken[j] && norms[j] > 0.0)
            .map(|j| {
                let dot: f64 = columns[j].iter().zip(&residual).map(|(a, r)| a * r).sum();
                (j, dot * dot / norms[j])
            })
            .max_by(|a, b| a.1.total_cmp(&b.1).then(b.0.cmp(&a.0)));
        let Some((j, _)) = best else { break };
        taken[j] = true;
        chosen.push(j);
        solution = least_squares(&columns, &chosen, &full)?;
        let (coefficients, bias) = &solution;
        for (i, r) in residual.iter_mut().enumerate() {
            let fitted: f64 = chosen
                .iter()
                .zip(coefficients)
                .map(|(&c, b)| b * columns[c][i])
                .sum::<f64>()
                + bias;
            *r = full[i] - fitted;
        }
    }
    let (coefficients, bias) = solution;
    let support_vectors = chosen
        .iter()
        .flat_map(|&j| model.support_vector(j).iter().copied())
        .collect();
    let reduced = SvrModel {
        kernel: model.kernel,
        dim,
        support_vectors,
        coefficients,
        bias,
        weights: None,
    };
    let max_deviation = residual.iter().fold(0.0f64, |m, r| m.max(r.abs()));
    let rms_deviation = (residual.iter().map(|r| r * r).sum::<f64>() / n as f64).sqrt();
    if !(max_deviation.is_finite() && reduced.coefficients.iter().all(|b| b.is_finite())) {
        return Err(SvmError::Numerical {
            solver: "support-vector reduction",
            reason: "the least-squares refit is not finite".into(),
        });
    }
    Ok(Reduction {
        model: reduced,
        from_sv: model.n_sv(),
        max_deviation,
        rms_deviation,
    })
}

/// Coefficients of the `chosen` columns and a bias that fit `target` best in least squares,
/// by the normal equations with a ridge of 1e-12 of their diagonal (the kernel columns of
/// nearby centres are nearly parallel).
fn least_squares(
    columns: &[Vec<f64>],
    chosen: &[usize],
    target: &[f64],
) -> Result<(Vec<f64>, f64), SvmError> {
    let k = chosen.len();
    let n = target.len();
    let col = |a: usize, i: usize| if a < k { columns[chosen[a]][i] } else { 1.0 };
    let mut gram = Mat::<f64>::zeros(k + 1, k + 1);
    let mut rhs = Mat::<f64>::zeros(k + 1, 1);
    for a in 0..=k {
        for b in 0..=a {
            let s: f64 = (0..n).map(|i| col(a, i) * col(b, i)).sum();
            gram[(a, b)] = s;
            gram[(b, a)] = s;
        }
        rhs[(a, 0)] = (0..n).map(|i| col(a, i) * target[i]).sum();
    }
    let scale = (0..=k).fold(0.0f64, |m, a| m.max(gram[(a, a)]));
    let mut ridge = 1e-12 * scale.max(1.0);
    while ridge < 1e-3 * scale.max(1.0) {
        let mut g = gram.clone();
        for a in 0..k {
            g[(a, a)] += ridge;
        }
        if let Ok(llt) = g.llt(Side::Lower) {
            let s = llt.solve(&rhs);
            return Ok(((0..k).map(|a| s[(a, 0)]).collect(), s[(k, 0)]));
        }
        ridge *= 100.0;
    }
    Err(SvmError::Numerical {
        solver: "support-vector reduction",
        reason: "the least-squares system is singular".into(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{SvrParams, fit};

    /// A smooth 2-D surface fitted with a narrow kernel: many support vectors.
    fn fitted() -> (SvrModel, Vec<f64>) {
        let n = 300;
        let x: Vec<f64> = (0..n)
            .flat_map(|i| {
                let t = i as f64 / n as f64;
                [t, (7.0 * t).sin() * 0.5 + 0.5]
            })
            .collect();
        let y: Vec<f64> = x
            .chunks(2)
            .map(|p| (3.0 * p[0]).sin() + 0.5 * p[1] * p[1])
            .collect();
        let params = SvrParams::builder()
            .c(100.0)
            .epsilon(1e-4)
            .kernel(Kernel::Rbf { gamma: 50.0 })
            .build()
            .expect("params");
        (fit(&params, &x, 2, &y).expect("fit").model, x)
    }

    #[test]
    fn a_budget_keeps_at_most_its_support_vectors_and_says_how_far_it_moved() {
        let (model, x) = fitted();
        assert!(model.n_sv() > 40, "{}", model.n_sv());
        let mut last = f64::INFINITY;
        for budget in [5, 10, 20, 40] {
            let r = reduce_support(&model, &x, 2, budget).expect("reduce");
            assert_eq!(r.model.n_sv(), budget);
            assert_eq!(r.from_sv, model.n_sv());
            // The stated deviation is the real one, recomputed here.
            let max = x
                .chunks(2)
                .map(|p| (r.model.predict(p) - model.predict(p)).abs())
                .fold(0.0f64, f64::max);
            assert!(
                (max - r.max_deviation).abs() <= 1e-9 * (1.0 + max),
                "{max} vs {}",
                r.max_deviation
            );
            assert!(r.rms_deviation <= r.max_deviation);
            // Each centre is one of the model's support vectors.
            for c in r.model.support_vectors.chunks(2) {
                assert!((0..model.n_sv()).any(|j| model.support_vector(j) == c));
            }
            // More support vectors never fit worse (the greedy choice only adds).
            assert!(
                r.rms_deviation <= last * (1.0 + 1e-9),
                "{budget}: {} > {last}",
                r.rms_deviation
            );
            last = r.rms_deviation;
        }
        // Forty centres reproduce the smooth surface closely.
        assert!(last < 1e-2, "{last}");
        // Within budget or linear: unchanged.
        let same = reduce_support(&model, &x, 2, model.n_sv()).expect("same");
        assert_eq!((same.model, same.max_deviation), (model.clone(), 0.0));
        assert!(matches!(
            reduce_support(&model, &x, 2, 0),
            Err(SvmError::InvalidHyperparameter { name: "max_sv", .. })
        ));
        assert!(matches!(
            reduce_support(&model, &x, 3, 10),
            Err(SvmError::Shape { .. })
        ));
    }
}
