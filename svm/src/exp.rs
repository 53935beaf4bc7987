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
    // (eʳ − 1 − r)/r² by Estrin's scheme: pairs, then pairs of pairs in r², r⁴, r⁸. Horner's
    // twelve steps each waited on the last, so a kernel row's exponentials ran at the latency
    // of a chain of 24 operations, not at the vector units' throughput: a row of 10,240 on 5
    // inputs took 4.3 ns an entry, 3.3 ns by Estrin (fastest of 25, one core), and an ε-SVR
    // fit on Friedman #1 at n = 10,245 8 % less time.
    let f = &INV_FACTORIAL;
    let (r2, pair) = (r * r, |i: usize| f[i] + f[i + 1] * r);
    let r4 = r2 * r2;
    let quads = [
        pair(0) + pair(2) * r2,
        pair(4) + pair(6) * r2,
        pair(8) + pair(10) * r2,
    ];
    let p = (quads[0] + quads[1] * r4) + quads[2] * (r4 * r4);
    let p = 1.0 + r * (1.0 + r * p);
    // 2ᵏ as two factors, each a normal number, so that results below 2⁻¹⁰²² round to their
    // subnormal once and results near the top stay exact until the last product.
    let half = (k * 0.5 + SHIFT) - SHIFT;
    let value = p * pow2(half + SHIFT) * pow2((k - half) + SHIFT);
    if x.is_nan() { x } else { value }
}

/// `round(x · log₂e)` in f32 by the shift trick: 1.5 · 2²³.
const SHIFT_F32: f32 = 12_582_912.0;
const LOG2_E_F32: f32 = std::f32::consts::LOG2_E;
/// ln 2 split so that `k · LN2_HI_F32` is exact for |k| < 2¹⁵ (its nine significant bits), as
/// Cephes' `expf` splits it.
const LN2_HI_F32: f32 = 0.693_359_4;
const LN2_LO_F32: f32 = -2.121_944_4e-4;
/// Below, eˣ rounds to 0 in f32; above, to infinity.
const LOWEST_F32: f32 = -104.0;
const HIGHEST_F32: f32 = 89.0;
/// Cephes' `expf` polynomial for (eʳ − 1 − r) / r² on |r| ≤ ln2/2, highest power first (its
/// last, 5.0000001e-1, is 0.5 in f32).
const EXPF_POLY: [f32; 6] = [
    1.987_569_1e-4,
    1.398_199_9e-3,
    8.333_452e-3,
    4.166_579_6e-2,
    1.666_666_5e-1,
    0.5,
];

/// `2ᵏ` in f32 for the integer `k` held as `k + SHIFT_F32` (|k| ≤ 126).
#[inline(always)]
fn pow2_f32(shifted: f32) -> f32 {
    let k = shifted.to_bits().wrapping_sub(SHIFT_F32.to_bits());
    f32::from_bits(k.wrapping_add(127) << 23)
}

/// `eˣ` in f32 arithmetic, for kernel rows held as f32: within an ulp of the exact value
/// rounded to f32 (checked in the tests), 0 below −103.3, infinity above 88.8, NaN for NaN.
/// The same reduction as [`exp`] with a degree-7 polynomial (Cephes' `expf`), eight lanes to a
/// vector where [`exp`] has four and a degree-13 one (`RbfColumns::row_f32` in
/// `crate::kernel` says what that saves).
#[inline(always)]
pub(crate) fn exp_f32(x: f32) -> f32 {
    let clamped = x.clamp(LOWEST_F32, HIGHEST_F32);
    let shifted = clamped * LOG2_E_F32 + SHIFT_F32;
    let k = shifted - SHIFT_F32;
    let r = (clamped - k * LN2_HI_F32) - k * LN2_LO_F32;
    let mut p = EXPF_POLY[0];
    for &c in &EXPF_POLY[1..] {
        p = p * r + c;
    }
    let p = (p * (r * r) + r) + 1.0;
    // 2ᵏ as two normal factors, as in [`exp`].
    let half = (k * 0.5 + SHIFT_F32) - SHIFT_F32;
    let value = p * pow2_f32(half + SHIFT_F32) * pow2_f32((k - half) + SHIFT_F32);
    if x.is_nan() { x } else { value }
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
    fn the_f32_exp_is_within_an_ulp_of_the_rounded_exact_value() {
        let f32_ulps = |a: f32, b: f32| a.to_bits().abs_diff(b.to_bits());
        let mut worst = 0;
        let mut x = -103.0f32;
        while x < 88.7 {
            x += 0.000_123_456_7 * std::f32::consts::PI;
            let exact = f64::from(x).exp() as f32;
            if exact.is_normal() {
                worst = worst.max(f32_ulps(exp_f32(x), exact));
            } else {
                // Subnormal results: within two units of the smallest subnormal.
                assert!((exp_f32(x) - exact).abs() <= 2.0 * f32::from_bits(1), "{x}");
            }
        }
        assert!(worst <= 1, "{worst} ulps");
        assert_eq!(exp_f32(0.0), 1.0);
        assert_eq!(exp_f32(-200.0), 0.0);
        assert_eq!(exp_f32(f32::NEG_INFINITY), 0.0);
        assert_eq!(exp_f32(100.0), f32::INFINITY);
        assert!(exp_f32(f32::NAN).is_nan());
    }
}
