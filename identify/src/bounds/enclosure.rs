//! The parts a force law evaluates, each with an enclosure of its output over a box of inputs.
//!
//! Linear, bilinear and the membranes' quadratic laws are enclosed exactly (their extremes lie
//! at a box's corners or at the parabola's vertex). An RBF SVR is enclosed by a second-order
//! Taylor form about the box's centre, intersected with the kernel-by-kernel interval: the
//! Taylor form's slack shrinks with the square of the box, so a branch and bound converges
//! even where large coefficients of both signs cancel; a polynomial kernel by interval
//! arithmetic. Every enclosure contains the true range (up to floating-point rounding, far
//! below the margins a force limit is checked with).

use svm::{Kernel, SvrModel};

/// A box of at most two inputs: `[lo, hi]` per input (a one-input part ignores the second).
pub(crate) type Bx = [[f64; 2]; 2];

/// Something a force law evaluates: its value at a point, an enclosure of its values over a
/// box, and what one enclosure costs (kernel evaluations).
pub(crate) trait Part {
    fn eval(&self, x: [f64; 2]) -> f64;
    fn enclose(&self, b: &Bx) -> [f64; 2];
    fn work(&self) -> usize;
}

/// `v` held to `range`, as the laws hold their velocity to the trained range.
fn clamp_interval(i: [f64; 2], range: [f64; 2]) -> [f64; 2] {
    [i[0].clamp(range[0], range[1]), i[1].clamp(range[0], range[1])]
}

fn hull(values: impl IntoIterator<Item = f64>) -> [f64; 2] {
    values
        .into_iter()
        .fold([f64::INFINITY, f64::NEG_INFINITY], |[lo, hi], v| {
            [lo.min(v), hi.max(v)]
        })
}

/// `c + a·d + b·v + e·d·v` with `d` held to `d_range` and `v` to `v_range`: a shaft law's
/// linear terms.
pub(crate) struct Bilinear {
    pub(crate) terms: [f64; 4],
    pub(crate) d_range: [f64; 2],
    pub(crate) v_range: [f64; 2],
}

impl Part for Bilinear {
    fn eval(&self, [d, v]: [f64; 2]) -> f64 {
        let [c, a, b, e] = self.terms;
        let d = d.clamp(self.d_range[0], self.d_range[1]);
        let v = v.clamp(self.v_range[0], self.v_range[1]);
        c + a * d + b * v + e * d * v
    }

    fn enclose(&self, bx: &Bx) -> [f64; 2] {
        // Linear in each input with the other fixed: the extremes lie at the corners.
        let d = clamp_interval(bx[0], self.d_range);
        let v = clamp_interval(bx[1], self.v_range);
        hull([[d[0], v[0]], [d[0], v[1]], [d[1], v[0]], [d[1], v[1]]].map(|x| self.eval(x)))
    }

    fn work(&self) -> usize {
        1
    }
}

/// `offset + a1·u + a2·u² + damping·v`, `u = min(d − contact, max_u)`, `v` held to
/// `v_range`: a membrane's loading.
pub(crate) struct Quadratic {
    pub(crate) terms: [f64; 4],
    pub(crate) contact_m: f64,
    pub(crate) max_u_m: f64,
    pub(crate) v_range: [f64; 2],
}

impl Part for Quadratic {
    fn eval(&self, [d, v]: [f64; 2]) -> f64 {
        let [offset, a1, a2, damping] = self.terms;
        let u = (d - self.contact_m).min(self.max_u_m);
        offset + a1 * u + a2 * u * u + damping * v.clamp(self.v_range[0], self.v_range[1])
    }

    fn enclose(&self, bx: &Bx) -> [f64; 2] {
        let [offset, a1, a2, damping] = self.terms;
        let [u0, u1] = [bx[0][0] - self.contact_m, bx[0][1] - self.contact_m].map(|u| u.min(self.max_u_m));
        let q = |u: f64| a1 * u + a2 * u * u;
        let vertex = (a2 != 0.0)
            .then(|| -a1 / (2.0 * a2))
            .filter(|u| (u0..=u1).contains(u));
        let [q0, q1] = hull([q(u0), q(u1)].into_iter().chain(vertex.map(q)));
        let v = clamp_interval(bx[1], self.v_range);
        let [w0, w1] = hull([damping * v[0], damping * v[1]]);
        [offset + q0 + w0, offset + q1 + w1]
    }

    fn work(&self) -> usize {
        1
    }
}

/// An SVR of its first `model.dim` inputs, each held to `clamp` and then scaled
/// (`(x − offset) / scale`), times `output_scale`.
pub(crate) struct Svr<'a> {
    pub(crate) model: &'a SvrModel,
    pub(crate) offset: [f64; 2],
    pub(crate) scale: [f64; 2],
    pub(crate) output_scale: f64,
    pub(crate) clamp: Bx,
}

impl Svr<'_> {
    fn dim(&self) -> usize {
        self.model.dim.min(2)
    }

    fn scaled(&self, x: [f64; 2]) -> [f64; 2] {
        let mut s = [0.0; 2];
        for k in 0..self.dim() {
            let c = self.clamp[k];
            s[k] = (x[k].clamp(c[0], c[1]) - self.offset[k]) / self.scale[k];
        }
        s
    }

    fn scaled_box(&self, bx: &Bx) -> Bx {
        let mut s = [[0.0; 2]; 2];
        for k in 0..self.dim() {
            let [lo, hi] = clamp_interval(bx[k], self.clamp[k]);
            s[k] = [
                (lo - self.offset[k]) / self.scale[k],
                (hi - self.offset[k]) / self.scale[k],
            ];
        }
        s
    }

    /// `b + w·s` over the scaled box, exactly.
    fn linear(&self, w: &[f64], s: &Bx) -> [f64; 2] {
        let (mut lo, mut hi) = (self.model.bias, self.model.bias);
        for (k, &wk) in w.iter().enumerate().take(self.dim()) {
            let [a, b] = hull([wk * s[k][0], wk * s[k][1]]);
            lo += a;
            hi += b;
        }
        [lo, hi]
    }

    /// The Taylor forms about the centre (second order with a Hessian bound; third order with
    /// the Hessian at the centre and a third-derivative bound), intersected with each other and
    /// with the kernel-by-kernel interval. The third-order form keeps the cancellation between
    /// large coefficients of both signs in its first two terms, where the others lose it.
    fn rbf(&self, gamma: f64, s: &Bx) -> [f64; 2] {
        let dim = self.dim();
        let centre = [0.5 * (s[0][0] + s[0][1]), 0.5 * (s[1][0] + s[1][1])];
        let half = [0.5 * (s[0][1] - s[0][0]), 0.5 * (s[1][1] - s[1][0])];
        let m = self.model;
        let (mut f, mut grad, mut hess) = (m.bias, [0.0; 2], [[0.0; 2]; 2]);
        let (mut second, mut third) = (0.0, 0.0);
        let (mut lo, mut hi) = (m.bias, m.bias);
        // The largest |φ‴(z)| of φ(z) = exp(−γz²), in units of γ^{3/2}: the largest
        // |8w³ − 12w|·exp(−w²) (3.9036 at w ≈ 0.5246), rounded up.
        let third_peak = 3.91 * gamma * gamma.sqrt();
        for (i, &beta) in m.coefficients.iter().enumerate() {
            let sv = m.support_vector(i);
            let (mut r2c, mut r2min, mut r2max) = (0.0, 0.0, 0.0);
            let mut diff = [0.0; 2];
            for k in 0..dim {
                let x = sv[k];
                diff[k] = centre[k] - x;
                r2c += diff[k] * diff[k];
                let near = x.clamp(s[k][0], s[k][1]) - x;
                let far = (s[k][0] - x).abs().max((s[k][1] - x).abs());
                r2min += near * near;
                r2max += far * far;
            }
            let bk = beta * (-gamma * r2c).exp();
            f += bk;
            for k in 0..dim {
                grad[k] += -2.0 * gamma * bk * diff[k];
                for l in 0..dim {
                    let delta = if k == l { 1.0 } else { 0.0 };
                    hess[k][l] += bk * (4.0 * gamma * gamma * diff[k] * diff[l] - 2.0 * gamma * delta);
                }
            }
            second += beta.abs() * 2.0 * gamma * hessian_factor(gamma * r2min, gamma * r2max);
            let k_max = (-gamma * r2min).exp();
            // Along any line the kernel is exp(−γp²)·φ(z), p and z the offsets across and along
            // it; |φ‴(z)|·exp(−γp²) ≤ (8γ³r³ + 12γ²r)·exp(−γr²) with r ≥ |z| the distance.
            let r_max = r2max.sqrt();
            let near_bound = (8.0 * gamma.powi(3) * r_max.powi(3) + 12.0 * gamma * gamma * r_max) * k_max;
            third += beta.abs() * near_bound.min(third_peak);
            let k_min = (-gamma * r2max).exp();
            if beta > 0.0 {
                lo += beta * k_min;
                hi += beta * k_max;
            } else {
                lo += beta * k_max;
                hi += beta * k_min;
            }
        }
        let slope: f64 = (0..dim).map(|k| grad[k].abs() * half[k]).sum();
        let reach2: f64 = (0..dim).map(|k| half[k] * half[k]).sum();
        let slack2 = slope + 0.5 * second * reach2;
        // ½δᵀHδ over the box, by interval arithmetic on its terms.
        let (mut q_lo, mut q_hi) = (0.0, 0.0);
        for k in 0..dim {
            for l in 0..dim {
                let h = 0.5 * hess[k][l];
                if k == l {
                    let sq = half[k] * half[k];
                    q_lo += h.min(0.0) * sq;
                    q_hi += h.max(0.0) * sq;
                } else {
                    let cross = h.abs() * half[k] * half[l];
                    q_lo -= cross;
                    q_hi += cross;
                }
            }
        }
        let slack3 = third * reach2 * reach2.sqrt() / 6.0;
        let (lo3, hi3) = (f - slope + q_lo - slack3, f + slope + q_hi + slack3);
        [lo.max(f - slack2).max(lo3), hi.min(f + slack2).min(hi3)]
    }

    /// Interval arithmetic through `(γ⟨x, xᵢ⟩ + coef0)^degree`.
    fn polynomial(&self, gamma: f64, coef0: f64, degree: u32, s: &Bx) -> [f64; 2] {
        let m = self.model;
        let (mut lo, mut hi) = (m.bias, m.bias);
        for (i, &beta) in m.coefficients.iter().enumerate() {
            let sv = m.support_vector(i);
            let [mut t0, mut t1] = [coef0, coef0];
            for k in 0..self.dim() {
                let [a, b] = hull([gamma * sv[k] * s[k][0], gamma * sv[k] * s[k][1]]);
                t0 += a;
                t1 += b;
            }
            let p = |t: f64| t.powi(degree as i32);
            let [p0, p1] = if degree.is_multiple_of(2) && t0 <= 0.0 && t1 >= 0.0 {
                [0.0, p(t0).max(p(t1))]
            } else {
                hull([p(t0), p(t1)])
            };
            let [a, b] = hull([beta * p0, beta * p1]);
            lo += a;
            hi += b;
        }
        [lo, hi]
    }
}

/// The largest `ψ(t) = e^{−t}·max(1, |2t − 1|)` for `t = γr²` in `[t0, t1]`: the Gaussian
/// kernel's Hessian has norm `2γ·ψ(γr²)` at distance `r` from its centre (eigenvalues
/// `2γK(2γr² − 1)` along the radius and `−2γK` across it). ψ falls on [0, 1], rises to its
/// local maximum at 1.5 and falls after, so its largest value lies at an end or at 1.5.
fn hessian_factor(t0: f64, t1: f64) -> f64 {
    let psi = |t: f64| (-t).exp() * (2.0 * t - 1.0).abs().max(1.0);
    let peak = (t0..=t1).contains(&1.5).then(|| psi(1.5));
    psi(t0).max(psi(t1)).max(peak.unwrap_or(0.0))
}

impl Part for Svr<'_> {
    fn eval(&self, x: [f64; 2]) -> f64 {
        let s = self.scaled(x);
        self.output_scale * self.model.predict(&s[..self.dim()])
    }

    fn enclose(&self, bx: &Bx) -> [f64; 2] {
        let s = self.scaled_box(bx);
        let [lo, hi] = match (&self.model.weights, self.model.kernel) {
            (Some(w), _) => self.linear(w, &s),
            (None, Kernel::Linear) => {
                let w = self.model.linear_weights().unwrap_or_default();
                self.linear(&w, &s)
            }
            (None, Kernel::Rbf { gamma }) => self.rbf(gamma, &s),
            (None, Kernel::Polynomial { gamma, coef0, degree }) => self.polynomial(gamma, coef0, degree, &s),
        };
        // The output scale is positive (checked when the file is read).
        [self.output_scale * lo, self.output_scale * hi]
    }

    fn work(&self) -> usize {
        if self.model.weights.is_some() {
            1
        } else {
            self.model.n_sv().max(1)
        }
    }
}

/// A sum of parts: the force of a membrane over the law of the tissue above it.
pub(crate) struct Sum<'a>(pub(crate) Vec<Box<dyn Part + 'a>>);

impl Part for Sum<'_> {
    fn eval(&self, x: [f64; 2]) -> f64 {
        self.0.iter().map(|p| p.eval(x)).sum()
    }

    fn enclose(&self, bx: &Bx) -> [f64; 2] {
        self.0.iter().fold([0.0, 0.0], |[lo, hi], p| {
            let [a, b] = p.enclose(bx);
            [lo + a, hi + b]
        })
    }

    fn work(&self) -> usize {
        self.0.iter().map(|p| p.work()).sum()
    }
}

/// Li & Bi's soft contact, inputs `[speed, normal force]`: `slope(v)·P + intercept(v)`.
pub(crate) struct SoftContact<'a> {
    pub(crate) slope: Svr<'a>,
    pub(crate) intercept: Svr<'a>,
    /// The normal force is held to this range.
    pub(crate) force_range: [f64; 2],
}

impl Part for SoftContact<'_> {
    fn eval(&self, x: [f64; 2]) -> f64 {
        let p = x[1].clamp(self.force_range[0], self.force_range[1]);
        self.slope.eval(x) * p + self.intercept.eval(x)
    }

    fn enclose(&self, bx: &Bx) -> [f64; 2] {
        let [w0, w1] = self.slope.enclose(bx);
        let [p0, p1] = clamp_interval(bx[1], self.force_range);
        let [a, b] = hull([w0 * p0, w0 * p1, w1 * p0, w1 * p1]);
        let [m0, m1] = self.intercept.enclose(bx);
        [a + m0, b + m1]
    }

    fn work(&self) -> usize {
        self.slope.work() + self.intercept.work()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every enclosure holds every value on a fine grid of its box, and shrinks onto the value
    /// at a point.
    fn encloses(part: &dyn Part, bx: Bx) {
        let [lo, hi] = part.enclose(&bx);
        let n = 60;
        for i in 0..=n {
            for j in 0..=n {
                let t = |r: [f64; 2], k: usize| r[0] + (r[1] - r[0]) * k as f64 / n as f64;
                let y = part.eval([t(bx[0], i), t(bx[1], j)]);
                let tol = 1e-9 * (1.0 + y.abs());
                assert!(y >= lo - tol && y <= hi + tol, "{y} outside [{lo}, {hi}]");
            }
        }
        let centre = [0.5 * (bx[0][0] + bx[0][1]), 0.5 * (bx[1][0] + bx[1][1])];
        let point = [[centre[0]; 2], [centre[1]; 2]];
        let [a, b] = part.enclose(&point);
        let y = part.eval(centre);
        assert!((a - y).abs() <= 1e-9 * (1.0 + y.abs()) && (b - y).abs() <= 1e-9 * (1.0 + y.abs()));
    }

    fn rbf_model() -> SvrModel {
        SvrModel {
            kernel: Kernel::Rbf { gamma: 30.0 },
            dim: 2,
            support_vectors: vec![0.1, 0.2, 0.5, 0.5, 0.9, 0.1, 0.4, 0.8],
            coefficients: vec![50.0, -80.0, 40.0, -7.0],
            bias: 1.5,
            weights: None,
        }
    }

    #[test]
    fn enclosures_contain_the_values() {
        let bx = [[0.0, 0.02], [-0.01, 0.03]];
        encloses(
            &Bilinear {
                terms: [0.3, 40.0, -20.0, 900.0],
                d_range: [0.005, 0.015],
                v_range: [0.0, 0.02],
            },
            bx,
        );
        encloses(
            &Quadratic {
                terms: [-0.1, 30.0, -2000.0, 5.0],
                contact_m: 0.004,
                max_u_m: 0.01,
                v_range: [0.001, 0.02],
            },
            bx,
        );
        let model = rbf_model();
        let svr = Svr {
            model: &model,
            offset: [0.0, -0.01],
            scale: [0.02, 0.04],
            output_scale: 1.0,
            clamp: [[f64::NEG_INFINITY, f64::INFINITY], [0.0, 0.02]],
        };
        encloses(&svr, bx);
        encloses(&svr, [[0.004, 0.006], [0.0, 0.001]]);
        let poly = SvrModel {
            kernel: Kernel::Polynomial {
                gamma: 2.0,
                coef0: -0.5,
                degree: 3,
            },
            ..rbf_model()
        };
        encloses(&Svr { model: &poly, ..svr }, bx);
    }

    #[test]
    fn the_taylor_forms_tighten_faster_than_the_box_shrinks() {
        // Two large coefficients of opposite sign 1 µm apart: each kernel's own interval is
        // wide, their sum tiny. Kernel by kernel the enclosure cannot see the cancellation;
        // the Taylor forms about the centre can, and what they add to the true range (sampled
        // finely) grows with the square of the box or faster: doubling the box multiplies it
        // by 4 (second order) to 8 (third order).
        let model = SvrModel {
            kernel: Kernel::Rbf { gamma: 30.0 },
            dim: 2,
            support_vectors: vec![0.5, 0.5, 0.5, 0.501],
            coefficients: vec![1000.0, -1000.0],
            bias: 0.0,
            weights: None,
        };
        let svr = Svr {
            model: &model,
            offset: [0.0; 2],
            scale: [1.0; 2],
            output_scale: 1.0,
            clamp: [[f64::NEG_INFINITY, f64::INFINITY]; 2],
        };
        let excess = |h: f64| {
            let bx = [[0.3 - h, 0.3 + h], [0.4 - h, 0.4 + h]];
            let [lo, hi] = svr.enclose(&bx);
            let n = 200;
            let t = |r: [f64; 2], k: usize| r[0] + (r[1] - r[0]) * k as f64 / n as f64;
            let values = (0..=n).flat_map(|i| (0..=n).map(move |j| (i, j)));
            let [a, b] = hull(values.map(|(i, j)| svr.eval([t(bx[0], i), t(bx[1], j)])));
            (hi - lo) - (b - a)
        };
        let (e1, e2) = (excess(1e-3), excess(2e-3));
        assert!(e1 > 0.0 && e2 > 3.5 * e1 && e2 < 9.0 * e1, "{e1} {e2}");
        // Kernel by kernel, each term's interval over that box is ~16 wide (1000 × its slope
        // of ~2.9 × the box's ~5.6e-3 diagonal): the Taylor form is far inside that.
        assert!(e2 < 1.0, "{e2}");
    }
}
