//! `eˣ` to about an ulp, in plain f64 arithmetic that the compiler vectorises.
//!
//! Hand-written because a kernel row is tens of thousands of `exp` calls, and the C math
//! library's `exp` is one call per value: on Friedman #1 at n = 30,000 it and the distance
//! loop around it were 45 % of an ε-SVR fit. This one is a Cody–Waite reduction and a Taylor
//! polynomial, branch-free, so a loop over a row compiles to vector code. It uses no fused
//! multiply-add and no table, so it gives the same bits on every x86-64 and every build.
//! Kernel rows (the solvers' matrices and the certificate) come from it; a single kernel value
//! ([`crate::Kernel::eval`], e.g. a model's prediction) still calls the C library, whose
//! table-driven `exp` is twice as fast one value at a time. The two agree to two ulps.

/// `round(x · log₂e)` by the shift trick: adding 1.5 · 2⁵² rounds to an integer held in the
/// low mantissa bits (exact for |x · log₂e| < 2⁵¹, far beyond the clamp below).
const SHIFT: f64 = 6_755_399_441_055_744.0;
const LOG2_E: f64 = std::f64::consts::LOG2_E;
/// ln 2 split so that `k · LN2_HI` is exact for |k| < 2²¹ (fdlibm's constants, by their bits:
/// LN2_HI's low 32 bits are zero).
const LN2_HI: f64 = f64::from_bits(0x3fe6_2e42_fee0_0000);
const LN2_LO: f64 = f64::from_bits(0x3dea_39ef_3579_3c76);
/// Below, eˣ rounds to 0; above, to infinity. Clamping to them keeps 2ᵏ's exponent in range.
const LOWEST: f64 = -746.0;
const HIGHEST: f64 = 710.0;
/// 1/k! for k = 2..=13: the Taylor polynomial of eʳ on |r| ≤ ln2/2 to 13th order, whose
/// truncation error (0.35¹⁴/14! ≈ 4e-18) is below half an ulp of its value.
const INV_FACTORIAL: [f64; 12] = [
    1.0 / 2.0,
    1.0 / 6.0,
    1.0 / 24.0,
    1.0 / 120.0,
    1.0 / 720.0,
    1.0 / 5_040.0,
    1.0 / 40_320.0,
    1.0 / 362_880.0,
    1.0 / 3_628_800.0,
    1.0 / 39_916_800.0,
    1.0 / 479_001_600.0,
    1.0 / 6_227_020_800.0,
];

/// `2ᵏ` for the integer `k` held as `k + SHIFT` (|k| ≤ 1022).
#[inline(always)]
fn pow2(shifted: f64) -> f64 {
    let k = shifted.to_bits().wrapping_sub(SHIFT.to_bits());
    f64::from_bits(k.wrapping_add(1023) << 52)
}

/// `eˣ`, within about an ulp of the exact value (2 ulp at most, checked against the C library
/// in the tests); 0 below −745.2, infinity above 709.8, NaN for NaN.
#[inline(always)]
pub(crate) fn exp(x: f64) -> f64 {
    let clamped = x.clamp(LOWEST, HIGHEST);
    let shifted = clamped * LOG2_E + SHIFT;
    let k = shifted - SHIFT;
    let r = (clamped - k * LN2_HI) - k * LN2_LO;
    let mut p = INV_FACTORIAL[11];
    for &f in INV_FACTORIAL[..11].iter().rev() {
        p = p * r + f;
    }
    let p = 1.0 + r * (1.0 + r * p);
    // 2ᵏ as two factors, each a normal number, so that results below 2⁻¹⁰²² round to their
    // subnormal once and results near the top stay exact until the last product.
    let half = (k * 0.5 + SHIFT) - SHIFT;
    let value = p * pow2(half + SHIFT) * pow2((k - half) + SHIFT);
    if x.is_nan() { x } else { value }
}

/// `values[i] ← exp(scale · values[i])`: a kernel row's exponents in one vectorised pass.
#[inline(always)]
pub(crate) fn exp_scaled_in_place(values: &mut [f64], scale: f64) {
    for v in values {
        *v = exp(scale * *v);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Distance in ulps between two finite positive values.
    fn ulps(a: f64, b: f64) -> u64 {
        a.to_bits().abs_diff(b.to_bits())
    }

    #[test]
    fn matches_the_c_library_to_two_ulps_over_the_whole_range() {
        let mut worst = 0;
        let mut x = -745.0f64;
        while x < 709.7 {
            // An irrational step so the points do not share a pattern with ln 2.
            x += 0.001_234_567_89 * std::f64::consts::PI;
            let (ours, libm) = (exp(x), x.exp());
            worst = worst.max(ulps(ours, libm));
        }
        // Where a kernel's arguments lie: −γ‖a − b‖² near 0.
        for i in 0..200_000 {
            let x = -(i as f64) * 1.7e-6;
            worst = worst.max(ulps(exp(x), x.exp()));
        }
        assert!(worst <= 2, "{worst} ulps");
    }

    #[test]
    fn exact_points_limits_and_nan() {
        assert_eq!(exp(0.0), 1.0);
        assert_eq!(exp(-0.0), 1.0);
        assert_eq!(exp(f64::NEG_INFINITY), 0.0);
        assert_eq!(exp(-746.0), 0.0);
        assert_eq!(exp(f64::INFINITY), f64::INFINITY);
        assert_eq!(exp(710.0), f64::INFINITY);
        assert!(exp(f64::NAN).is_nan());
        // Subnormal results: within one unit of the smallest subnormal.
        for x in [-709.0, -720.0, -740.0, -745.0] {
            assert!((exp(x) - x.exp()).abs() <= f64::from_bits(1), "{x}");
            assert!(exp(x) > 0.0, "{x}");
        }
        let largest = exp(709.7);
        assert!(largest.is_finite() && ulps(largest, 709.7f64.exp()) <= 2);
    }

    #[test]
    fn the_row_pass_is_the_scalar_function() {
        let mut row: Vec<f64> = (0..1000).map(|i| (i as f64 * 0.37).sin().abs() * 3.0).collect();
        let expected: Vec<f64> = row.iter().map(|&d| exp(-2.5 * d)).collect();
        exp_scaled_in_place(&mut row, -2.5);
        assert_eq!(row, expected);
    }
}
