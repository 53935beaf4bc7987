//! Probabilities from decision values: Platt's sigmoid per pair of classes, then pairwise
//! coupling into one distribution (libsvm's method 2).

/// Platt's sigmoid `1 / (1 + exp(A f + B))` fitted to decision values `dec` with labels ±1 by
/// Lin, Lin & Weng's Newton method with backtracking (libsvm's `sigmoid_train`).
pub fn sigmoid_train(dec: &[f64], y: &[f64]) -> (f64, f64) {
    let prior1 = y.iter().filter(|&&v| v > 0.0).count() as f64;
    let prior0 = y.len() as f64 - prior1;
    let (max_iter, min_step, sigma, eps) = (100, 1e-10, 1e-12, 1e-5);
    let hi = (prior1 + 1.0) / (prior1 + 2.0);
    let lo = 1.0 / (prior0 + 2.0);
    let t: Vec<f64> = y.iter().map(|&v| if v > 0.0 { hi } else { lo }).collect();
    let objective = |a: f64, b: f64| -> f64 {
        dec.iter()
            .zip(&t)
            .map(|(d, ti)| {
                let f = d * a + b;
                if f >= 0.0 {
                    ti * f + (-f).exp().ln_1p()
                } else {
                    (ti - 1.0) * f + f.exp().ln_1p()
                }
            })
            .sum()
    };
    let (mut a, mut b) = (0.0, ((prior0 + 1.0) / (prior1 + 1.0)).ln());
    let mut fval = objective(a, b);
    for _ in 0..max_iter {
        let (mut h11, mut h22, mut h21, mut g1, mut g2) = (sigma, sigma, 0.0, 0.0, 0.0);
        for (d, ti) in dec.iter().zip(&t) {
            let f = d * a + b;
            let (p, q) = if f >= 0.0 {
                let e = (-f).exp();
                (e / (1.0 + e), 1.0 / (1.0 + e))
            } else {
                let e = f.exp();
                (1.0 / (1.0 + e), e / (1.0 + e))
            };
            let d2 = p * q;
            h11 += d * d * d2;
            h22 += d2;
            h21 += d * d2;
            let d1 = ti - p;
            g1 += d * d1;
            g2 += d1;
        }
        if g1.abs() < eps && g2.abs() < eps {
            break;
        }
        let det = h11 * h22 - h21 * h21;
        let da = -(h22 * g1 - h21 * g2) / det;
        let db = -(-h21 * g1 + h11 * g2) / det;
        let gd = g1 * da + g2 * db;
        let mut step = 1.0;
        while step >= min_step {
            let (na, nb) = (a + step * da, b + step * db);
            let nf = objective(na, nb);
            if nf < fval + 1e-4 * step * gd {
                (a, b, fval) = (na, nb, nf);
                break;
            }
            step /= 2.0;
        }
        if step < min_step {
            break;
        }
    }
    (a, b)
}

/// `1 / (1 + exp(A f + B))`, computed without overflow.
pub fn sigmoid_predict(dec: f64, a: f64, b: f64) -> f64 {
    let f = dec * a + b;
    if f >= 0.0 {
        let e = (-f).exp();
        e / (1.0 + e)
    } else {
        1.0 / (1.0 + f.exp())
    }
}

/// Wu, Lin & Weng's method 2: `p` minimising `Σ_i Σ_{j≠i} (r_ji p_i − r_ij p_j)²` with
/// `Σ p = 1`, from pairwise probabilities `r[i][j] ≈ P(i | i or j)` (`r[i][j] + r[j][i] = 1`).
/// libsvm's fixed-point iteration, run to a tight tolerance (see the module doc). The
/// classifier calls [`pairwise_coupling_into`] with its own scratch; the tests call this.
#[cfg(test)]
pub fn pairwise_coupling(r: &[Vec<f64>]) -> Vec<f64> {
    let k = r.len();
    let flat: Vec<f64> = r.iter().flat_map(|row| row.iter().copied()).collect();
    let mut scratch = CouplingScratch::new(k);
    let mut p = vec![0.0; k];
    pairwise_coupling_into(&flat, &mut scratch, &mut p);
    p
}

/// The buffers of [`pairwise_coupling_into`] for `k` classes.
#[derive(Debug, Clone)]
pub struct CouplingScratch {
    /// The method's `k × k` matrix, row-major.
    q: Vec<f64>,
    qp: Vec<f64>,
}

impl CouplingScratch {
    /// Buffers for `k` classes.
    pub fn new(k: usize) -> Self {
        Self {
            q: vec![0.0; k * k],
            qp: vec![0.0; k],
        }
    }
}

/// [`pairwise_coupling`] on its own buffers, for a thread that must not allocate: `r` is the
/// `k × k` matrix row-major, `k` is `p.len()`, and `scratch` was made for the same `k`.
pub fn pairwise_coupling_into(r: &[f64], scratch: &mut CouplingScratch, p: &mut [f64]) {
    let k = p.len();
    debug_assert_eq!(r.len(), k * k);
    debug_assert_eq!(scratch.qp.len(), k);
    if k == 0 {
        return;
    }
    let CouplingScratch { q, qp } = scratch;
    q.fill(0.0);
    for t in 0..k {
        for j in 0..k {
            if j != t {
                q[t * k + t] += r[j * k + t] * r[j * k + t];
                q[t * k + j] = -r[j * k + t] * r[t * k + j];
            }
        }
    }
    p.fill(1.0 / k as f64);
    let eps = 1e-12 / k as f64;
    for _ in 0..(1000 * k).max(1000) {
        let mut pqp = 0.0;
        for t in 0..k {
            qp[t] = (0..k).map(|j| q[t * k + j] * p[j]).sum();
            pqp += p[t] * qp[t];
        }
        let max_error = qp.iter().map(|v| (v - pqp).abs()).fold(0.0, f64::max);
        if max_error < eps {
            break;
        }
        for t in 0..k {
            let qtt = q[t * k + t];
            if qtt <= 0.0 {
                continue;
            }
            let diff = (-qp[t] + pqp) / qtt;
            p[t] += diff;
            pqp = (pqp + diff * (diff * qtt + 2.0 * qp[t])) / (1.0 + diff) / (1.0 + diff);
            for j in 0..k {
                qp[j] = (qp[j] + diff * q[t * k + j]) / (1.0 + diff);
                p[j] /= 1.0 + diff;
            }
        }
    }
}
