//! Resampling to the target rate: uniformity, interpolation and the anti-aliasing filter.

use super::*;

/// Whether every interval is within [`UNIFORM_TOLERANCE`] of the period `1 / rate_hz`.
pub(super) fn is_uniform(time: &[f64], rate_hz: f64) -> bool {
    let period = 1.0 / rate_hz;
    time.windows(2)
        .all(|pair| ((pair[1] - pair[0]) - period).abs() <= UNIFORM_TOLERANCE * period)
}

pub(super) fn interval_range(time: &[f64]) -> (f64, f64) {
    time.windows(2)
        .map(|pair| pair[1] - pair[0])
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), dt| {
            (lo.min(dt), hi.max(dt))
        })
}

/// A mean rate within [`UNIFORM_TOLERANCE`] of an integer is that integer (a 1 kHz log whose
/// times are written in decimal has a mean rate of 999.9999999997 Hz).
pub(super) fn snap_rate(rate_hz: f64) -> f64 {
    let rounded = rate_hz.round();
    if rounded > 0.0 && (rate_hz - rounded).abs() <= UNIFORM_TOLERANCE * rate_hz {
        rounded
    } else {
        rate_hz
    }
}

/// Linear interpolation of `(time, value)` at the ascending `at` times; outside the input's
/// span the end values are held (the grid only leaves it by rounding).
pub(super) fn interpolate(time: &[f64], value: &[f64], at: &[f64]) -> Vec<f64> {
    let last = time.len() - 1;
    let mut j = 0;
    at.iter()
        .map(|&t| {
            while j < last && time[j + 1] <= t {
                j += 1;
            }
            if j == last || t <= time[j] {
                return value[j];
            }
            let w = (t - time[j]) / (time[j + 1] - time[j]);
            value[j] + (value[j + 1] - value[j]) * w
        })
        .collect()
}

/// A cascade of biquads (direct form II transposed), run forwards and backwards.
///
/// Hand-written because neither [`crate::signal`] nor the workspace's dependencies have an
/// IIR low-pass, and two biquads do not justify a DSP crate.
#[derive(Debug, Clone)]
pub(super) struct LowPass {
    /// `[b0, b1, b2, a1, a2]` per section, normalised so `a0 = 1`.
    pub(super) sections: Vec<[f64; 5]>,
    /// Samples of odd-reflection padding at each end.
    pub(super) pad: usize,
}

impl LowPass {
    /// 4th-order Butterworth low-pass with −3 dB at `cutoff_hz` (−6 dB run forwards and
    /// backwards), by the bilinear transform with pre-warping (the RBJ cookbook biquad with
    /// the Butterworth pole-pair Qs `1 / (2 cos θ)`, θ = π/8, 3π/8).
    pub(super) fn butterworth4(cutoff_hz: f64, rate_hz: f64) -> Self {
        let w0 = 2.0 * std::f64::consts::PI * cutoff_hz / rate_hz;
        let (sin, cos) = w0.sin_cos();
        let sections = [1.0_f64, 3.0]
            .iter()
            .map(|k| {
                let q = 1.0 / (2.0 * (k * std::f64::consts::PI / 8.0).cos());
                let alpha = sin / (2.0 * q);
                let a0 = 1.0 + alpha;
                let b0 = (1.0 - cos) / 2.0 / a0;
                [b0, 2.0 * b0, b0, -2.0 * cos / a0, (1.0 - alpha) / a0]
            })
            .collect();
        let pad = (PAD_CUTOFF_PERIODS * rate_hz / cutoff_hz).ceil() as usize;
        LowPass { sections, pad }
    }

    /// Zero-phase filtering: forwards, then backwards, over the signal extended at both ends
    /// by its odd reflection (`2 x[0] − x[k]`), each pass starting in the steady state of its
    /// first sample. A constant or a straight line passes unchanged.
    pub(super) fn filtfilt(&self, x: &[f64]) -> Vec<f64> {
        let n = x.len();
        if n < 2 {
            return x.to_vec();
        }
        let pad = self.pad.min(n - 1);
        let (first, last) = (x[0], x[n - 1]);
        let mut ext = Vec::with_capacity(n + 2 * pad);
        ext.extend((1..=pad).rev().map(|k| 2.0 * first - x[k]));
        ext.extend_from_slice(x);
        ext.extend((1..=pad).map(|k| 2.0 * last - x[n - 1 - k]));
        self.run(&mut ext);
        ext.reverse();
        self.run(&mut ext);
        ext.reverse();
        ext[pad..pad + n].to_vec()
    }

    /// One causal pass in place, each section starting at the steady state for `x[0]` (the
    /// DC gain is 1, so every section sees the same constant).
    pub(super) fn run(&self, x: &mut [f64]) {
        let Some(&v) = x.first() else { return };
        for &[b0, b1, b2, a1, a2] in &self.sections {
            let mut z2 = (b2 - a2) * v;
            let mut z1 = (b1 - a1) * v + z2;
            for sample in x.iter_mut() {
                let input = *sample;
                let output = b0 * input + z1;
                z1 = b1 * input - a1 * output + z2;
                z2 = b2 * input - a2 * output;
                *sample = output;
            }
        }
    }

    /// Magnitude of one forward pass at `freq_hz` (for tests).
    #[cfg(test)]
    pub(super) fn gain(&self, freq_hz: f64, rate_hz: f64) -> f64 {
        let w = 2.0 * std::f64::consts::PI * freq_hz / rate_hz;
        let (s1, c1, s2, c2) = (w.sin(), w.cos(), (2.0 * w).sin(), (2.0 * w).cos());
        self.sections
            .iter()
            .map(|&[b0, b1, b2, a1, a2]| {
                let (nr, ni) = (b0 + b1 * c1 + b2 * c2, -(b1 * s1 + b2 * s2));
                let (dr, di) = (1.0 + a1 * c1 + a2 * c2, -(a1 * s1 + a2 * s2));
                ((nr * nr + ni * ni) / (dr * dr + di * di)).sqrt()
            })
            .product()
    }
}
