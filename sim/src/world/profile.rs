//! Band-limited random height profiles.
//!
//! A rubbed or scratched surface is modelled as a stationary random height process along the
//! path of the tool: its power spectral density is a log-normal band around a dominant
//! wavelength, and its RMS is fixed exactly. That gives each surface a roughness amplitude (RMS
//! roughness, Rq) and a dominant wavelength, the two things the thesis's roughness features
//! (mean absolute roughness, variance, mean wavelength; Nakano Eqs. 2.18–2.20) and the
//! spectrotemporal features of Sinapov et al. respond to.
//!
//! The profile is synthesised once on a periodic grid by shaping white Gaussian noise in the
//! frequency domain (realfft), so that evaluating it along a path costs one interpolation per
//! sample, whatever the spectrum.

use rand::Rng;
use rand_distr::{Distribution, StandardNormal};

/// Spectral description of one band of a random height profile.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Band {
    /// RMS height of this band (Rq), in metres.
    pub rms_m: f64,
    /// Wavelength at the peak of the power spectral density, in metres.
    pub wavelength_m: f64,
    /// Standard deviation of the log-wavenumber around the peak (dimensionless). 0.3 is a
    /// narrow, almost periodic band; 1.0 is broadband.
    pub log_width: f64,
}

/// A periodic height profile sampled on a uniform grid.
#[derive(Debug, Clone, PartialEq)]
pub struct Profile {
    spacing_m: f64,
    heights_m: Vec<f64>,
}

impl Profile {
    /// Synthesises a profile whose PSD is the sum of the given bands, on `n` points spaced
    /// `spacing_m` apart (so it repeats every `n * spacing_m`). Each band's RMS is exact on
    /// the grid; the bands are independent, so the total variance is the sum of theirs.
    ///
    /// `n` is rounded up to an even number so the real FFT has a Nyquist bin of its own.
    pub fn synthesize<R: Rng + ?Sized>(bands: &[Band], spacing_m: f64, n: usize, rng: &mut R) -> Self {
        let n = (n.max(4) + 1) & !1;
        let mut heights_m = vec![0.0; n];
        let inverse = fft::inverse_plan(n);
        let mut spectrum = inverse.make_input_vec();
        let mut band_heights = inverse.make_output_vec();
        let length_m = spacing_m * n as f64;
        for band in bands {
            if band.rms_m <= 0.0 {
                continue;
            }
            let peak_log_k = (1.0 / band.wavelength_m).ln();
            for (i, bin) in spectrum.iter_mut().enumerate() {
                // Bin 0 is the mean and the last bin (Nyquist) must stay real: both carry no
                // roughness.
                if i == 0 || i == n / 2 {
                    *bin = fft::Complex::new(0.0, 0.0);
                    continue;
                }
                let k = i as f64 / length_m;
                let z = (k.ln() - peak_log_k) / band.log_width;
                let amplitude = (-0.5 * z * z).exp().sqrt();
                let re: f64 = StandardNormal.sample(rng);
                let im: f64 = StandardNormal.sample(rng);
                *bin = fft::Complex::new(re * amplitude, im * amplitude);
            }
            // The spectrum was built by us with a real DC and Nyquist bin, which is all the
            // inverse transform checks, so this cannot fail.
            if inverse.process(&mut spectrum, &mut band_heights).is_err() {
                continue;
            }
            let rms = (band_heights.iter().map(|h| h * h).sum::<f64>() / n as f64).sqrt();
            if rms > 0.0 {
                let scale = band.rms_m / rms;
                for (h, b) in heights_m.iter_mut().zip(&band_heights) {
                    *h += b * scale;
                }
            }
        }
        Self { spacing_m, heights_m }
    }

    /// Height at arc length `s_m` along the profile (linear interpolation, periodic).
    pub fn height_m(&self, s_m: f64) -> f64 {
        let n = self.heights_m.len();
        let u = (s_m / self.spacing_m).rem_euclid(n as f64);
        let i = (u.floor() as usize).min(n - 1);
        let frac = u - i as f64;
        let a = self.heights_m[i];
        let b = self.heights_m[(i + 1) % n];
        a + (b - a) * frac
    }

    /// Slope dh/ds at `s_m` (the slope of the interpolating segment).
    pub fn slope(&self, s_m: f64) -> f64 {
        let n = self.heights_m.len();
        let u = (s_m / self.spacing_m).rem_euclid(n as f64);
        let i = (u.floor() as usize).min(n - 1);
        (self.heights_m[(i + 1) % n] - self.heights_m[i]) / self.spacing_m
    }

    /// RMS height over the whole grid.
    pub fn rms_m(&self) -> f64 {
        (self.heights_m.iter().map(|h| h * h).sum::<f64>() / self.heights_m.len() as f64).sqrt()
    }

    /// Length after which the profile repeats.
    pub fn period_m(&self) -> f64 {
        self.spacing_m * self.heights_m.len() as f64
    }

    /// Grid spacing.
    pub fn spacing_m(&self) -> f64 {
        self.spacing_m
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    fn zero_crossings(p: &Profile) -> usize {
        let n = (p.period_m() / p.spacing_m()).round() as usize;
        (0..n)
            .filter(|&i| {
                let a = p.height_m(i as f64 * p.spacing_m());
                let b = p.height_m((i + 1) as f64 * p.spacing_m());
                a < 0.0 && b >= 0.0
            })
            .count()
    }

    #[test]
    fn rms_is_exact_and_bands_add_in_variance() {
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let one = Band {
            rms_m: 20e-6,
            wavelength_m: 0.5e-3,
            log_width: 0.4,
        };
        let p = Profile::synthesize(&[one], 5e-6, 1 << 14, &mut rng);
        assert!((p.rms_m() - 20e-6).abs() < 1e-12);
        let two = Band {
            rms_m: 15e-6,
            wavelength_m: 5e-3,
            log_width: 0.4,
        };
        let q = Profile::synthesize(&[one, two], 5e-6, 1 << 14, &mut rng);
        // Independent bands: variances add, up to their sample cross-correlation.
        let expected = (20e-6f64.powi(2) + 15e-6f64.powi(2)).sqrt();
        assert!((q.rms_m() - expected).abs() / expected < 0.05, "{}", q.rms_m());
    }

    #[test]
    fn dominant_wavelength_shows_in_the_zero_crossing_rate() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        for wavelength_m in [0.3e-3, 1e-3, 3e-3] {
            let band = Band {
                rms_m: 10e-6,
                wavelength_m,
                log_width: 0.25,
            };
            let p = Profile::synthesize(&[band], 5e-6, 1 << 16, &mut rng);
            let measured = p.period_m() / zero_crossings(&p) as f64;
            assert!(
                (measured / wavelength_m - 1.0).abs() < 0.15,
                "wavelength {wavelength_m}: measured {measured}"
            );
        }
    }

    #[test]
    fn interpolation_is_periodic_and_matches_grid_points() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let band = Band {
            rms_m: 1e-5,
            wavelength_m: 1e-3,
            log_width: 0.5,
        };
        let p = Profile::synthesize(&[band], 1e-5, 1000, &mut rng);
        for s in [0.0, 0.123e-3, 4.5e-3] {
            assert!((p.height_m(s) - p.height_m(s + p.period_m())).abs() < 1e-15);
            assert!((p.height_m(s) - p.height_m(s - 3.0 * p.period_m())).abs() < 1e-15);
        }
        let mid = p.height_m(0.5e-5);
        assert!((mid - 0.5 * (p.height_m(0.0) + p.height_m(1e-5))).abs() < 1e-18);
    }

    #[test]
    fn same_seed_same_profile() {
        let band = Band {
            rms_m: 1e-5,
            wavelength_m: 1e-3,
            log_width: 0.5,
        };
        let a = Profile::synthesize(&[band], 1e-5, 512, &mut ChaCha8Rng::seed_from_u64(9));
        let b = Profile::synthesize(&[band], 1e-5, 512, &mut ChaCha8Rng::seed_from_u64(9));
        assert_eq!(a, b);
    }
}
