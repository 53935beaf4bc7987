//! The vibration spectrum of one short window (`--features vibration`): what the tool's
//! vibration says within a fraction of a second, for anytime decisions that cannot wait the
//! 1.92 s Sinapov's histogram needs for its five frames.
//!
//! It is the histogram's frequency axis for a single time bin: the window's signal (the
//! accelerometer's magnitude, or the single vibration axis) less its own mean (over a window
//! this short, the mean is what the histogram's 0.25 s moving average removes: gravity and the
//! contact force's slow changes), one periodic Hann frame over the whole window, `|X_k|`
//! scaled by `2 / Σ window` (a tone of amplitude `A` peaks at about `A`), and the mean
//! magnitude of each of [`FREQUENCY_BINS`] equal bands over 0 … [`BAND_HZ`] (8 Hz each, as the
//! histogram's), scaled as its cells are ([`CellScale`]).
//!
//! A window over travel has a length of its own: its frame is zero-padded to the longest
//! window's DFT, whose bins then fall into the same bands at every length, and the Hann frame
//! spans the window's own samples. A window must be long enough for the bands to be resolved
//! (a DFT bin no wider than a band: [`MIN_WINDOW_S`]).

use std::sync::Arc;

use realfft::{RealFftPlanner, RealToComplex};

use super::spectral::{BAND_HZ, CellScale, FREQUENCY_BINS, band_bins, cell_means, frequency_bin};
use crate::RecognizeError;

/// Length of the feature vector: one value per band.
pub const SPECTRUM_LEN: usize = FREQUENCY_BINS;

/// The shortest window whose DFT resolves the bands: one DFT bin per band, s.
pub const MIN_WINDOW_S: f64 = FREQUENCY_BINS as f64 / BAND_HZ;

/// The DFT of windows of up to a given length at one rate, and its buffers.
pub struct WindowSpectrumPlan {
    fft_len: usize,
    fft: Arc<dyn RealToComplex<f64>>,
    /// DFT bins inside the band (`0 … BAND_HZ`, or Nyquist if lower).
    band_bins: usize,
}

impl std::fmt::Debug for WindowSpectrumPlan {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("WindowSpectrumPlan")
            .field("fft_len", &self.fft_len)
            .field("band_bins", &self.band_bins)
            .finish()
    }
}

impl WindowSpectrumPlan {
    /// The plan for windows of at most `max_samples` at `rate_hz`. Too short a window (under
    /// [`MIN_WINDOW_S`]) is a typed error. Below 400 Hz the band stops at the Nyquist
    /// frequency, as the histogram's does.
    pub fn new(rate_hz: f64, max_samples: usize) -> Result<Self, RecognizeError> {
        if !(rate_hz.is_finite() && rate_hz > 0.0) {
            return Err(RecognizeError::Parameter {
                of: "setting",
                name: "rate_hz",
                value: rate_hz,
                reason: "must be positive and finite",
            });
        }
        let fft_len = max_samples.max(2);
        let band_bins = band_bins(rate_hz, fft_len);
        if band_bins < FREQUENCY_BINS {
            return Err(RecognizeError::Parameter {
                of: "vibration spectrum",
                name: "window_s",
                value: max_samples as f64 / rate_hz,
                reason: "too short to resolve 25 bands of 8 Hz: windows of at least 0.125 s",
            });
        }
        let fft = RealFftPlanner::<f64>::new().plan_fft_forward(fft_len);
        Ok(Self {
            fft_len,
            fft,
            band_bins,
        })
    }

    /// The longest window it takes, samples.
    pub fn max_samples(&self) -> usize {
        self.fft_len
    }

    /// The spectrum of one window of a single signal (a single axis, or the three axes'
    /// magnitude): at least 2 and at most [`WindowSpectrumPlan::max_samples`] samples, all
    /// finite.
    pub fn features(&self, signal: &[f64], scale: CellScale) -> Result<[f64; SPECTRUM_LEN], RecognizeError> {
        let n = signal.len();
        if n < 2 {
            return Err(RecognizeError::WindowTooShort { len: n });
        }
        if n > self.fft_len {
            return Err(RecognizeError::Parameter {
                of: "vibration spectrum",
                name: "window samples",
                value: n as f64,
                reason: "longer than the longest window the plan was made for",
            });
        }
        if let Some(index) = signal.iter().position(|v| !v.is_finite()) {
            return Err(RecognizeError::NonFiniteSample { index });
        }
        let mean = signal.iter().sum::<f64>() / n as f64;
        let mut input = self.fft.make_input_vec();
        let mut output = self.fft.make_output_vec();
        let mut window_sum = 0.0;
        for (i, (dst, &s)) in input.iter_mut().zip(signal).enumerate() {
            let w = 0.5 - 0.5 * (2.0 * std::f64::consts::PI * i as f64 / n as f64).cos();
            window_sum += w;
            *dst = (s - mean) * w;
        }
        self.fft.process(&mut input, &mut output)?;
        let to_amplitude = 2.0 / window_sum;
        let (mut sum, mut count) = ([0.0; SPECTRUM_LEN], [0usize; SPECTRUM_LEN]);
        for (k, c) in output.iter().enumerate() {
            let Some(b) = frequency_bin(k, self.band_bins) else {
                break;
            };
            sum[b] += c.norm() * to_amplitude;
            count[b] += 1;
        }
        Ok(cell_means(sum, count, scale))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const RATE_HZ: f64 = 1000.0;

    fn tone(n: usize, freq_hz: f64, amp: f64, offset: f64) -> Vec<f64> {
        (0..n)
            .map(|i| offset + amp * (2.0 * std::f64::consts::PI * freq_hz * i as f64 / RATE_HZ).sin())
            .collect()
    }

    #[test]
    fn a_tone_lands_in_its_band_with_its_amplitude_whatever_the_offset() {
        let plan = WindowSpectrumPlan::new(RATE_HZ, 250).unwrap();
        // 52 Hz: band ⌊52 / 8⌋ = 6.
        let s = plan
            .features(&tone(250, 52.0, 0.3, 9.81), CellScale::Mean)
            .unwrap();
        let top = s.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1)).unwrap().0;
        assert_eq!(top, 6, "{s:?}");
        // The band's mean over its two DFT bins (4 Hz apart) holds about half the peak, and
        // the offset (gravity) leaves band 0 near zero.
        assert!(s[6] > 0.1 && s[6] < 0.3, "{}", s[6]);
        assert!(s[0] < 0.05 * s[6], "{s:?}");
        let unit = plan
            .features(&tone(250, 52.0, 0.3, 9.81), CellScale::UnitSum)
            .unwrap();
        assert!((unit.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        assert!((unit[6] - s[6] / s.iter().sum::<f64>()).abs() < 1e-12);
    }

    #[test]
    fn a_shorter_window_is_read_in_the_same_bands() {
        let plan = WindowSpectrumPlan::new(RATE_HZ, 400).unwrap();
        let long = plan
            .features(&tone(400, 101.0, 0.2, 0.0), CellScale::Mean)
            .unwrap();
        let short = plan
            .features(&tone(200, 101.0, 0.2, 0.0), CellScale::Mean)
            .unwrap();
        let top = |s: &[f64; SPECTRUM_LEN]| s.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1)).unwrap().0;
        assert_eq!(top(&long), 12);
        assert_eq!(top(&short), 12);
    }

    #[test]
    fn bad_windows_and_plans_are_typed_errors() {
        assert!(
            WindowSpectrumPlan::new(RATE_HZ, 100).is_err(),
            "0.1 s cannot resolve 8 Hz bands"
        );
        assert!(WindowSpectrumPlan::new(f64::NAN, 1000).is_err());
        let plan = WindowSpectrumPlan::new(RATE_HZ, 250).unwrap();
        assert!(matches!(
            plan.features(&[1.0], CellScale::Mean),
            Err(RecognizeError::WindowTooShort { len: 1 })
        ));
        assert!(plan.features(&vec![0.0; 251], CellScale::Mean).is_err());
        let mut bad = tone(250, 30.0, 1.0, 0.0);
        bad[17] = f64::NAN;
        assert!(matches!(
            plan.features(&bad, CellScale::Mean),
            Err(RecognizeError::NonFiniteSample { index: 17 })
        ));
    }
}
