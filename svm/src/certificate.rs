//! The one certificate every returned model carries, and the one rule that accepts it.
//!
//! For any β with `|βᵢ| ≤ C`, weak duality bounds the primal optimum from below:
//! `P* ≥ yᵀβ − ε‖β‖₁ − ½βᵀKβ − |b*|·|Σβ|` (the last term pays for Σβ ≠ 0, which rounding
//! leaves at ~ε_mach·C, with a bound on the optimal bias `|b*| ≤ |yᵢ| + √Kᵢᵢ·√(2P) + ε + P/C`
//! that follows from P* ≤ P). So `P(w, b) − P*` is at most
//!
//! `gap = P + D + |b*|·|Σβ| + (rounding bounds)`, with `D = ½βᵀKβ + ε‖β‖₁ − yᵀβ`,
//!
//! whatever produced (w, b, β). Every sum is compensated ([`super::compensated`]) and carries
//! its own error bound, which the gap includes: at C = 1e15 the terms of `P + D` are 1e13
//! times their sum, and a plain f64 evaluation would certify noise.
//!
//! One allowance is made, and reported: the *resolution* R, C times the rounding unit
//! `2u(|yᵢ| + |f(xᵢ)| + |b|)` of each residual that lies within that unit of the tube boundary.
//! The optimum pins such residuals at exactly ±ε; a model whose numbers are f64 can only meet
//! them to their last bit, and at C = 1e15 each bit costs ~0.1 in P. So the certified relative
//! gap is `max(0, gap − R) / max(1, |P|)`, and `P − P* ≤ relative_gap·max(1, |P|) + R` holds.
//!
//! The rule: a fit is returned only when that relative gap is at most [`ACCEPT_GAP`]; otherwise
//! the fit is an error that says why the solver stopped and the relative gap it had reached.

use super::compensated::Accumulator;

/// The acceptance threshold on the certified relative duality gap `gap / max(1, |P|)`: a model
/// is returned only at or below it (the rule is this one comparison; rounding is inside the gap,
/// not added to the threshold).
pub const ACCEPT_GAP: f64 = 1e-6;

/// Objectives and certified gap of a solution.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Certificate {
    /// `½‖w‖² + C Σ max(0, |yᵢ − f(xᵢ)| − ε)`.
    pub primal: f64,
    /// `½βᵀKβ + ε Σ|βᵢ| − yᵀβ`.
    pub dual: f64,
    /// Upper bound on `(P − P* − resolution) / max(1, |P|)`, floored at 0 (infinite when β
    /// leaves its box).
    pub relative_gap: f64,
    /// The objective's resolution in f64: C times the rounding unit of every residual that
    /// lies (to that unit) on the tube boundary. No model with f64 parameters can certify
    /// `P − P*` below it: at C = 1e15 one ulp of a boundary residual is worth 0.1.
    pub resolution: f64,
}

impl Certificate {
    /// Whether the rule accepts it.
    pub(crate) fn accepted(&self) -> bool {
        self.relative_gap <= ACCEPT_GAP
    }
}

/// What the certificate needs of a solution.
pub(crate) struct Solution<'a> {
    /// Targets.
    pub y: &'a [f64],
    /// C.
    pub c: f64,
    /// ε.
    pub epsilon: f64,
    /// Dual coefficients.
    pub beta: &'a [f64],
    /// Bias.
    pub bias: f64,
    /// `f(xᵢ) − b` per sample (`w·xᵢ` or `(Kβ)ᵢ`), compensated.
    pub fitted: &'a [Accumulator],
    /// `½‖w‖²` of the primal point, compensated, and a bound on its error beyond the
    /// accumulator's own.
    pub primal_quad: (Accumulator, f64),
    /// `½βᵀKβ` of the dual point, compensated, and a bound on its error beyond the
    /// accumulator's own (from inputs that were themselves compensated sums).
    pub dual_quad: (Accumulator, f64),
    /// `√K(xᵢ, xᵢ)` per sample (‖xᵢ‖ for a linear kernel).
    pub feature_norms: &'a [f64],
}

/// Computes the objectives and the certified relative gap.
pub(crate) fn certify(s: &Solution<'_>) -> Certificate {
    let (y, c, epsilon, beta) = (s.y, s.c, s.epsilon, s.beta);
    // Loss Σ max(0, |rᵢ| − ε) with rᵢ = yᵢ − fᵢ − b carried in double length: max(·, 0) and
    // |·| are 1-Lipschitz, so each term's error is at most its residual's.
    let mut loss = Accumulator::new();
    let mut loss_error = 0.0;
    let mut resolution = 0.0;
    let u = f64::EPSILON / 2.0;
    for (i, f) in s.fitted.iter().enumerate() {
        let mut r = Accumulator::new();
        r.add(y[i]);
        r.add_sum(&negated(f));
        r.add(-s.bias);
        let rv = r.value();
        // Both halves of fᵢ went in, so only the sum's own bound applies.
        let r_error = r.error_bound();
        // A residual the optimum pins on the tube boundary can only be met to the rounding of
        // the model's own numbers: C times that is the objective's resolution in f64.
        let rho = 2.0 * u * (y[i].abs() + f.value().abs() + s.bias.abs());
        if (rv.abs() - epsilon).abs() <= rho + r_error {
            resolution += c * (rho + r_error);
        }
        if rv.abs() - epsilon > -r_error {
            let sign = rv.signum();
            let excess = {
                let mut e = Accumulator::new();
                e.add(sign * rv);
                e.add(-epsilon);
                e
            };
            if excess.value() > 0.0 {
                loss.add_sum(&excess);
            }
            loss_error += r_error + excess.error_bound();
        }
    }
    let loss_value = loss.value();
    let loss_error = loss_error + loss.error_bound();

    let mut primal = Accumulator::new();
    primal.add_sum(&s.primal_quad.0);
    primal.add_product(c, loss_value);
    let primal_error =
        s.primal_quad.0.error_bound() + s.primal_quad.1 + c * loss_error + primal.error_bound();

    let mut dual = Accumulator::new();
    dual.add_sum(&s.dual_quad.0);
    let mut abs_beta = Accumulator::new();
    let mut sum_beta = Accumulator::new();
    let mut y_beta = Accumulator::new();
    let mut in_box = true;
    for (b, yi) in beta.iter().zip(y) {
        in_box &= b.abs() <= c;
        abs_beta.add(b.abs());
        sum_beta.add(*b);
        y_beta.add_product(*b, *yi);
    }
    dual.add_product(epsilon, abs_beta.value());
    dual.add_sum(&negated(&y_beta));
    let dual_error = s.dual_quad.0.error_bound()
        + s.dual_quad.1
        + epsilon * abs_beta.error_bound()
        + y_beta.error_bound()
        + dual.error_bound();

    let p = primal.value();
    let d = dual.value();
    // |b*| from P* ≤ P̄: ‖w*‖ ≤ √(2P̄) and every |rᵢ*| ≤ ε + P̄/C.
    let p_bar = (p + primal_error).max(0.0);
    let bias_bound = y
        .iter()
        .zip(s.feature_norms)
        .map(|(yi, ni)| yi.abs() + ni * (2.0 * p_bar).sqrt() + epsilon + p_bar / c)
        .fold(f64::INFINITY, f64::min);
    // Σβ = s ≠ 0 (rounding leaves ~ε_mach·C): either pay |b*|·|s|, or bound the dual at
    // β' = β − s·eⱼ, which is feasible in exact arithmetic when βⱼ has room for s. Its objective
    // differs from D(β) by at most |s|(|(Kβ)ⱼ| + |yⱼ| + ε) + ½s²Kⱼⱼ, with
    // |(Kβ)ⱼ| ≤ √(βᵀKβ)·√Kⱼⱼ (Cauchy–Schwarz in feature space): a bound that does not grow with
    // P as |b*|'s does.
    let s_value = sum_beta.value();
    let s_max = s_value.abs() + sum_beta.error_bound();
    let norm_k_beta = (2.0 * (s.dual_quad.0.value().abs() + s.dual_quad.1)).sqrt();
    let shift_cost = beta
        .iter()
        .zip(y)
        .zip(s.feature_norms)
        .filter(|((b, _), _)| (b.abs() + s_max) <= c || (b.signum() == s_value.signum() && s_max <= c))
        .map(|((_, yi), ni)| s_max * (norm_k_beta * ni + yi.abs() + epsilon) + 0.5 * s_max * s_max * ni * ni)
        .fold(f64::INFINITY, f64::min);
    let infeasibility_cost = (bias_bound * s_max).min(shift_cost);

    let mut gap = Accumulator::new();
    gap.add_sum(&primal);
    gap.add_sum(&dual);
    let bound = gap.value().abs() + gap.error_bound() + primal_error + dual_error + infeasibility_cost;
    let relative_gap = if in_box && bound.is_finite() {
        (bound - resolution).max(0.0) / p.abs().max(1.0)
    } else {
        f64::INFINITY
    };
    Certificate {
        primal: p,
        dual: d,
        relative_gap: if relative_gap.is_nan() {
            f64::INFINITY
        } else {
            relative_gap
        },
        resolution,
    }
}

/// `−acc`, keeping its error bound.
fn negated(acc: &Accumulator) -> Accumulator {
    acc.negated()
}

/// The linear-kernel ingredients from primal weights: `w·xᵢ`, `½‖w‖²`, and `½‖Σβᵢxᵢ‖²` with
/// `Σβᵢxᵢ` compensated (its terms are ~C).
pub(crate) fn linear_parts(x: &[f64], dim: usize, w: &[f64], beta: &[f64]) -> LinearParts {
    let fitted: Vec<Accumulator> = x
        .chunks_exact(dim)
        .map(|row| super::compensated::dot(row, w))
        .collect();
    let mut primal_quad = Accumulator::new();
    for v in w {
        primal_quad.add_product(0.5 * v, *v);
    }
    let mut u = vec![Accumulator::new(); dim];
    for (row, b) in x.chunks_exact(dim).zip(beta) {
        if *b != 0.0 {
            for (uk, xk) in u.iter_mut().zip(row) {
                uk.add_product(*b, *xk);
            }
        }
    }
    let mut dual_quad = Accumulator::new();
    let mut extra = 0.0;
    for uk in &u {
        let (v, e) = (uk.value(), uk.error_bound());
        dual_quad.add_product(0.5 * v, v);
        extra += v.abs() * e + 0.5 * e * e;
    }
    let norms = x
        .chunks_exact(dim)
        .map(|row| row.iter().map(|v| v * v).sum::<f64>().sqrt() * (1.0 + 1e-15))
        .collect();
    LinearParts {
        fitted,
        primal_quad: (primal_quad, 0.0),
        dual_quad: (dual_quad, extra),
        norms,
    }
}

/// What [`linear_parts`] computes for a [`Solution`].
pub(crate) struct LinearParts {
    /// `w·xᵢ`.
    pub fitted: Vec<Accumulator>,
    /// `½‖w‖²`.
    pub primal_quad: (Accumulator, f64),
    /// `½‖Σβᵢxᵢ‖²`.
    pub dual_quad: (Accumulator, f64),
    /// `‖xᵢ‖`.
    pub norms: Vec<f64>,
}

/// The kernel ingredients from `(Kβ)ᵢ` rows computed by the caller as compensated sums:
/// `½βᵀKβ` for both objectives.
pub(crate) fn kernel_quad(beta: &[f64], k_beta: &[Accumulator]) -> (Accumulator, f64) {
    let mut quad = Accumulator::new();
    let mut extra = 0.0;
    for (b, kb) in beta.iter().zip(k_beta) {
        if *b != 0.0 {
            quad.add_product(0.5 * b, kb.value());
            extra += 0.5 * b.abs() * kb.error_bound();
        }
    }
    (quad, extra)
}
