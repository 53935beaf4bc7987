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

/// Independent sums a [`dot`] runs in before merging them.
const LANES: usize = 4;

/// `Σ aᵢ·bᵢ` as an accumulator (Ogita–Rump–Oishi's Dot2), over the shorter of the two.
///
/// In [`LANES`] interleaved Dot2 sums merged at the end: one sum is a chain of dependent
/// additions, and the certificate's `Kβ` at n = 30,000 is 570 million of them. Each lane is a
/// Dot2 of its own and the merge adds their parts as [`Accumulator::add_sum`] does, so the
/// bound of [`Accumulator::error_bound`] (which counts every term and merge) still holds. The
/// products' errors come from a fused multiply-add in hardware where the CPU has one, and the
/// same exact value otherwise: the same bits either way.
pub(crate) fn dot(a: &[f64], b: &[f64]) -> Accumulator {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma") {
        // SAFETY: the CPU supports AVX2 and FMA, checked just above.
        return unsafe { dot_fma(a, b) };
    }
    dot_in_lanes(a, b)
}

/// [`dot`] with the multiply-adds in hardware.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn dot_fma(a: &[f64], b: &[f64]) -> Accumulator {
    dot_in_lanes(a, b)
}

#[inline(always)]
fn dot_in_lanes(a: &[f64], b: &[f64]) -> Accumulator {
    let len = a.len().min(b.len());
    let whole = len / LANES * LANES;
    let (mut hi, mut lo, mut abs) = ([0.0; LANES], [0.0; LANES], [0.0; LANES]);
    for (ca, cb) in a[..whole].chunks_exact(LANES).zip(b[..whole].chunks_exact(LANES)) {
        for l in 0..LANES {
            let (p, e) = two_prod(ca[l], cb[l]);
            let (s, e_sum) = two_sum(hi[l], p);
            hi[l] = s;
            lo[l] = (lo[l] + e_sum) + e;
            abs[l] += p.abs();
        }
    }
    let mut acc = Accumulator::new();
    for l in 0..LANES {
        acc.add_sum(&Accumulator {
            hi: hi[l],
            lo: lo[l],
            abs: abs[l],
            count: whole / LANES,
        });
    }
    for (x, y) in a[whole..len].iter().zip(&b[whole..len]) {
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
    fn a_dot_in_lanes_keeps_every_digit_and_its_bound() {
        // Integer terms, so the exact sum is known in i128; the last product cancels the others
        // (~1e23) to within its own rounding, over lengths with and without a tail after the
        // lanes.
        let mut rng = capture::rng::SplitMix64::new(777);
        for len in [1, 3, 4, 5, 17, 64, 103] {
            let mut a: Vec<f64> = (0..len).map(|_| ((rng.next_u64() >> 40) as f64) - 8e6).collect();
            let mut b: Vec<f64> = (0..len).map(|_| ((rng.next_u64() >> 40) as f64) * 1e9).collect();
            let exact_of = |a: &[f64], b: &[f64]| -> i128 {
                a.iter().zip(b).map(|(&x, &y)| x as i128 * y as i128).sum()
            };
            let rest = exact_of(&a[..len - 1], &b[..len - 1]);
            b[len - 1] = 1.0;
            a[len - 1] = (3 - rest) as f64;
            let exact = exact_of(&a, &b) as f64;
            let d = dot(&a, &b);
            assert!((d.value() - exact).abs() <= d.error_bound(), "len {len}");
            assert!(
                (d.value() - exact).abs() <= 1e-9 * exact.abs().max(1.0),
                "len {len}"
            );
            if len > 3 {
                // A plain sum loses the remainder to cancellation.
                let plain: f64 = a.iter().zip(&b).map(|(x, y)| x * y).sum();
                assert!((plain - exact).abs() > 1.0, "len {len}: {plain} vs {exact}");
            }
            // The hardware's multiply-add and the library's give the same bits.
            let portable = dot_in_lanes(&a, &b);
            assert_eq!(d.value().to_bits(), portable.value().to_bits(), "len {len}");
            assert_eq!(
                d.error_bound().to_bits(),
                portable.error_bound().to_bits(),
                "len {len}"
            );
        }
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
