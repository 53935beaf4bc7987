//! The plans against the transform's closed forms.
#![allow(clippy::unwrap_used)] // A failed unwrap is a failed test.

use std::f64::consts::PI;

use fft::{Complex, forward_plan, inverse_plan};

/// A cosine of amplitude a at bin k puts a·n/2 in bin k and nothing elsewhere, for an even
/// length, an odd one and a prime one (realfft plans each differently).
#[test]
fn a_cosine_lands_in_its_bin_with_its_amplitude() {
    for (n, k, a) in [(64usize, 5usize, 1.5), (45, 7, 0.25), (31, 3, 2.0)] {
        let plan = forward_plan(n);
        let mut input: Vec<f64> = (0..n)
            .map(|i| a * (2.0 * PI * (k * i) as f64 / n as f64).cos())
            .collect();
        let mut spectrum = plan.make_output_vec();
        assert_eq!(spectrum.len(), n / 2 + 1);
        plan.process(&mut input, &mut spectrum).unwrap();
        for (bin, value) in spectrum.iter().enumerate() {
            let expected = if bin == k { a * n as f64 / 2.0 } else { 0.0 };
            assert!(
                (value.re - expected).abs() < 1e-9 * n as f64,
                "n {n} bin {bin}: {value}"
            );
            assert!(value.im.abs() < 1e-9 * n as f64, "n {n} bin {bin}: {value}");
        }
    }
}

/// The inverse of the forward transform gives the input back, times the length.
#[test]
fn the_inverse_undoes_the_forward_up_to_the_length() {
    let n = 50;
    let signal: Vec<f64> = (0..n).map(|i| ((i * 7919) % 13) as f64 - 6.0).collect();
    let mut input = signal.clone();
    let mut spectrum = forward_plan(n).make_output_vec();
    forward_plan(n).process(&mut input, &mut spectrum).unwrap();
    let inverse = inverse_plan(n);
    let mut back = inverse.make_output_vec();
    inverse.process(&mut spectrum, &mut back).unwrap();
    for (x, y) in signal.iter().zip(&back) {
        assert!((x * n as f64 - y).abs() < 1e-9, "{x} · {n} vs {y}");
    }
}

/// A spectrum whose DC bin is not real has no real inverse: an error, not a wrong signal.
#[test]
fn an_inverse_of_a_spectrum_with_an_imaginary_dc_bin_is_an_error() {
    let inverse = inverse_plan(8);
    let mut spectrum = inverse.make_input_vec();
    spectrum[0] = Complex::new(1.0, 1.0);
    let mut out = inverse.make_output_vec();
    assert!(inverse.process(&mut spectrum, &mut out).is_err());
}
