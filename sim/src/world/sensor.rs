//! Sensor models: what a measuring device does to the true signal.
//!
//! Every capture column passes through one of these, so the identification and recognition
//! code downstream sees the same artefacts it would see on hardware: encoder quantization,
//! additive noise, the finite bandwidth of observers, velocity obtained by differentiating a
//! quantized position, and instruments that report a fixed number of decimals.

use rand::Rng;
use rand_distr::{Distribution, Normal};

/// An incremental encoder read as a position: the true position rounded to the nearest count.
///
/// The Omega.7's translational resolution is given by Force Dimension as < 0.01 mm, which is
/// the default quantum here ([`Encoder::OMEGA7_QUANTUM_M`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Encoder {
    /// Size of one count, in metres.
    pub quantum_m: f64,
}

impl Encoder {
    /// Omega.7 translational resolution (Force Dimension data sheet: "< 0.01 mm").
    pub const OMEGA7_QUANTUM_M: f64 = 1e-5;

    /// Reads a position: `round(x / q) * q`, returned as the double nearest to that decimal
    /// when `q` is a power of ten, so captures print short numbers.
    pub fn read(&self, position_m: f64) -> f64 {
        round_to(position_m, self.quantum_m)
    }
}

/// Rounds `value` to a multiple of `quantum`.
///
/// When `1 / quantum` is an integer (10^k, say) the result is computed as `round(value * 10^k) / 10^k`: both the
/// scale and the division are correctly rounded, so the result is the double nearest to the
/// decimal and prints with at most k decimals.
pub fn round_to(value: f64, quantum: f64) -> f64 {
    let inverse = (1.0 / quantum).round();
    if (1.0..1e15).contains(&inverse) && (inverse * quantum - 1.0).abs() < 1e-12 {
        (value * inverse).round() / inverse
    } else {
        (value / quantum).round() * quantum
    }
}

/// Zero-mean Gaussian noise of a fixed standard deviation.
#[derive(Debug, Clone, Copy)]
pub struct Noise {
    normal: Option<Normal<f64>>,
}

impl Noise {
    /// Noise with standard deviation `std` (0 gives silence; a negative or non-finite value is
    /// treated as 0, since a world table is code, not input).
    pub fn new(std: f64) -> Self {
        let normal = (std.is_finite() && std > 0.0)
            .then(|| Normal::new(0.0, std).ok())
            .flatten();
        Self { normal }
    }

    /// One draw.
    pub fn sample<R: Rng + ?Sized>(&self, rng: &mut R) -> f64 {
        self.normal.map_or(0.0, |n| n.sample(rng))
    }
}

/// A strain-gauge force sensor read through an ADC: additive noise, quantization to the ADC's
/// least significant bit, clipping at the range, and a value reported with a fixed number of
/// decimals.
#[derive(Debug, Clone, Copy)]
pub struct ForceSensor {
    noise: Noise,
    /// Standard deviation of the additive noise, N.
    pub noise_std_n: f64,
    /// ADC least significant bit, N.
    pub lsb_n: f64,
    /// Full scale (symmetric), N.
    pub range_n: f64,
    /// Resolution the acquisition software reports, N.
    pub report_quantum_n: f64,
}

impl ForceSensor {
    /// A sensor with the given noise, ADC resolution over ±`range_n`, and report quantum.
    pub fn new(noise_std_n: f64, adc_bits: u32, range_n: f64, report_quantum_n: f64) -> Self {
        let lsb_n = 2.0 * range_n / f64::from(1u32 << adc_bits.min(31));
        Self {
            noise: Noise::new(noise_std_n),
            noise_std_n,
            lsb_n,
            range_n,
            report_quantum_n,
        }
    }

    /// Li & Bi's 3-axis strain-gauge sensor: range ±2 kgf per axis with linearity errors below
    /// 0.5 % of span (their Sec. III-A). The ADC width (12 bits) and the noise (0.0015 kgf,
    /// half of their ε = 0.003 kgf) are our assumptions: the paper gives neither.
    pub fn li_bi() -> Self {
        let kgf = 9.806_65;
        Self::new(0.0015 * kgf, 12, 2.0 * kgf, 1e-4)
    }

    /// One reading of the true force `force_n`.
    pub fn read<R: Rng + ?Sized>(&self, force_n: f64, rng: &mut R) -> f64 {
        let noisy = (force_n + self.noise.sample(rng)).clamp(-self.range_n, self.range_n);
        round_to(round_to(noisy, self.lsb_n), self.report_quantum_n)
    }
}

/// First-order low-pass filter `g / (s + g)`, discretised by backward Euler.
///
/// This is the bandwidth of the disturbance and reaction-force observers (Nakano Eqs. 2.10,
/// 2.16: the estimate is the true disturbance through `g / (s + g)`), so a force "measured"
/// by an RFOB is the true force through this filter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LowPass {
    alpha: f64,
    state: Option<f64>,
}

impl LowPass {
    /// A filter with cut-off `cutoff_radps` (rad/s) run every `period_s` seconds.
    pub fn new(cutoff_radps: f64, period_s: f64) -> Self {
        let gt = cutoff_radps * period_s;
        Self {
            alpha: gt / (1.0 + gt),
            state: None,
        }
    }

    /// Feeds one sample, returns the filtered value. The first sample initialises the state,
    /// as an observer started at rest on a steady force would.
    pub fn update(&mut self, x: f64) -> f64 {
        let y = match self.state {
            None => x,
            Some(y) => y + self.alpha * (x - y),
        };
        self.state = Some(y);
        y
    }
}

/// Pseudo-differentiation of a measured position (Li & Bi Eq. 13); the identification side
/// owns it, since captures without a velocity column are differentiated there too.
pub use capture::PseudoDifferentiator;

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn encoder_rounds_to_counts_and_prints_short() {
        let e = Encoder {
            quantum_m: Encoder::OMEGA7_QUANTUM_M,
        };
        assert_eq!(e.read(0.012_344_9), 0.01234);
        assert_eq!(e.read(-0.000_015_1), -0.00002);
        assert_eq!(format!("{}", e.read(0.1 + 0.2)), "0.3");
        assert_eq!(round_to(1.23456, 0.25), 1.25);
    }

    #[test]
    fn noise_has_the_requested_spread() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let noise = Noise::new(0.02);
        let n = 20_000;
        let draws: Vec<f64> = (0..n).map(|_| noise.sample(&mut rng)).collect();
        let mean = draws.iter().sum::<f64>() / n as f64;
        let std = (draws.iter().map(|d| (d - mean).powi(2)).sum::<f64>() / n as f64).sqrt();
        assert!(mean.abs() < 0.001 && (std - 0.02).abs() < 0.001, "{mean} {std}");
        assert_eq!(Noise::new(0.0).sample(&mut rng), 0.0);
        assert_eq!(Noise::new(f64::NAN).sample(&mut rng), 0.0);
    }

    #[test]
    fn force_sensor_quantizes_clips_and_reports_four_decimals() {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let quiet = ForceSensor::new(0.0, 12, 19.6133, 1e-4);
        let lsb = quiet.lsb_n;
        assert!((lsb - 2.0 * 19.6133 / 4096.0).abs() < 1e-15);
        let r = quiet.read(1.0, &mut rng);
        assert!((r - 1.0).abs() <= lsb / 2.0 + 5e-5, "{r}");
        assert_eq!(r, round_to(r, 1e-4));
        assert_eq!(
            quiet.read(100.0, &mut rng),
            round_to(round_to(19.6133, lsb), 1e-4)
        );
        let noisy = ForceSensor::li_bi();
        let n = 5000;
        let errs: Vec<f64> = (0..n).map(|_| noisy.read(3.0, &mut rng) - 3.0).collect();
        let std = (errs.iter().map(|e| e * e).sum::<f64>() / n as f64).sqrt();
        // Noise plus uniform quantization error: sqrt(σ² + lsb²/12).
        let expected = (noisy.noise_std_n.powi(2) + noisy.lsb_n.powi(2) / 12.0).sqrt();
        assert!((std / expected - 1.0).abs() < 0.1, "{std} {expected}");
    }

    #[test]
    fn low_pass_step_response_has_the_cutoff_time_constant() {
        // 50 rad/s: after 1/g = 20 ms a step reaches 1 - 1/e.
        let mut f = LowPass::new(50.0, 1e-4);
        f.update(0.0);
        let mut y = 0.0;
        for _ in 0..200 {
            y = f.update(1.0);
        }
        assert!((y - (1.0 - (-1.0f64).exp())).abs() < 0.01, "{y}");
    }

    #[test]
    fn pseudo_differentiator_tracks_a_ramp_after_its_time_constant() {
        let mut d = PseudoDifferentiator::new(1e-3, 5e-3);
        let mut v = 0.0;
        for k in 0..100 {
            v = d.update(0.004 * k as f64 * 1e-3);
        }
        assert!((v - 0.004).abs() < 1e-9, "{v}");
        // A constant position gives zero velocity at steady state.
        let mut d = PseudoDifferentiator::new(1e-3, 5e-3).with_initial_velocity(1.0);
        for _ in 0..200 {
            v = d.update(0.5);
        }
        assert!(v.abs() < 1e-9);
    }
}
