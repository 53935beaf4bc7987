//! Compensated (error-free transformation) sums and dot products.
//!
//! At C = 1e15 the dual coefficients are ~C while the quantities they combine into (the
//! weights `Σβᵢxᵢ`, the bias equation `Σβᵢ = 0`, the objectives) are O(1): a plain f64 sum loses
//! every digit to cancellation, and a duality gap computed that way certifies nothing. These
//! routines carry the rounding error of each operation alongside the result (Knuth's two-sum,
//! Dekker's two-product via fused multiply-add; Ogita, Rump & Oishi 2005, "Accurate sum and dot
//! product"), so the result is as accurate as if computed in twice the working precision and
//! then rounded. No crate in the workspace provides them, and they are a dozen lines.

/// `a + b = s + e` exactly (Knuth's two-sum).
#[inline]
pub(crate) fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let bb = s - a;
    let e = (a - (s - bb)) + (b - bb);
    (s, e)
}

/// `a · b = p + e` exactly (barring underflow), by fused multiply-add.
#[inline]
pub(crate) fn two_prod(a: f64, b: f64) -> (f64, f64) {
    let p = a * b;
    (p, a.mul_add(b, -p))
}

/// A running sum carried as an unevaluated pair `hi + lo`, with `Σ|terms|` for error bounds.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Accumulator {
    hi: f64,
    lo: f64,
    abs: f64,
    count: usize,
}

impl Accumulator {
    /// An empty sum.
    pub(crate) fn new() -> Self {
        Self::default()
    }

    /// Adds one term.
    #[inline]
    pub(crate) fn add(&mut self, v: f64) {
        let (s, e) = two_sum(self.hi, v);
        self.hi = s;
        self.lo += e;
        self.abs += v.abs();
        self.count += 1;
    }

    /// Adds `a · b` with its product's rounding error.
    #[inline]
    pub(crate) fn add_product(&mut self, a: f64, b: f64) {
        let (p, e) = two_prod(a, b);
        self.add(p);
        self.lo += e;
    }

    /// Adds another accumulator (its bound included).
    pub(crate) fn add_sum(&mut self, other: &Accumulator) {
        self.add(other.hi);
        self.lo += other.lo;
        self.abs += other.abs - other.hi.abs();
        self.count += other.count;
    }

    /// `−self`, with the same error bound.
    pub(crate) fn negated(&self) -> Self {
        Self {
            hi: -self.hi,
            lo: -self.lo,
            abs: self.abs,
            count: self.count,
        }
    }

    /// The sum, rounded once.
    pub(crate) fn value(&self) -> f64 {
        self.hi + self.lo
    }

    /// A bound on `|value() − exact sum|`: the final rounding plus the second-order error of
    /// the compensation (Ogita, Rump & Oishi, Prop. 4.5 and 5.5, with their γ constants rounded
    /// up): `ε|s| + γ²ₙ Σ|terms|` with `γₙ = n·ε/(1 − n·ε)`, ε = 2⁻⁵³.
    pub(crate) fn error_bound(&self) -> f64 {
        let u = f64::EPSILON / 2.0;
        let n = (2 * self.count + 2) as f64;
        let gamma = n * u / (1.0 - n * u).max(0.5);
        2.0 * u * self.value().abs() + 2.0 * gamma * gamma * self.abs + f64::MIN_POSITIVE
    }
}

/// `Σ aᵢ·bᵢ` as an accumulator (Ogita–Rump–Oishi's Dot2).
pub(crate) fn dot(a: &[f64], b: &[f64]) -> Accumulator {
    let mut acc = Accumulator::new();
    for (x, y) in a.iter().zip(b) {
        acc.add_product(*x, *y);
    }
    acc
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cancellation_keeps_every_digit() {
        // 1e16 + 1 − 1e16 is 0 in f64, 1 exactly here.
        let mut acc = Accumulator::new();
        for v in [1e16, 1.0, -1e16] {
            acc.add(v);
        }
        assert_eq!(acc.value(), 1.0);
        assert!(acc.error_bound() < 1e-13);
        // (1 + 2⁻³⁰)² − 1 − 2⁻²⁹: the product's low bits (2⁻⁶⁰) survive.
        let a = 1.0 + 2f64.powi(-30);
        let d = dot(&[a, -1.0, -1.0], &[a, 1.0, 2f64.powi(-29)]);
        assert_eq!(d.value(), 2f64.powi(-60));
    }

    #[test]
    fn the_error_bound_holds_against_exact_integers() {
        // Sums of integers below 2⁵³ are exact in i128: the bound must cover the f64 result.
        let mut rng = capture::rng::SplitMix64::new(12345);
        for _ in 0..200 {
            let mut acc = Accumulator::new();
            let mut exact: i128 = 0;
            for _ in 0..50 {
                let state = rng.next_u64();
                let v = ((state >> 11) as i64 - (1i64 << 52)) as f64 * 2f64.powi(((state >> 3) % 40) as i32);
                acc.add(v);
                exact += v as i128;
            }
            assert!((acc.value() - exact as f64).abs() <= acc.error_bound());
        }
    }
}
