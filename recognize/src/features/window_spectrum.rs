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
//! spans the window's own samples. Its bands are over travel too
//! ([`WindowSpectrumPlan::features_over_travel`]): in cycles per metre, 0–200 Hz at the
//! windows' reference speed, so a texture is read in the same band at any sliding speed. A window must be long enough for the bands to be resolved
//! (a DFT bin no wider than a band: [`MIN_WINDOW_S`]).

use std::sync::Arc;

use fft::{Complex, RealToComplex};

use super::spectral::{
    BAND_HZ, CellScale, FREQUENCY_BINS, band_bins, band_bins_to, cell_means, frequency_bin,
};
use crate::RecognizeError;
use crate::{InputError, SettingError, UsageError};

/// Length of the feature vector: one value per band.
pub const SPECTRUM_LEN: usize = FREQUENCY_BINS;

/// The DFT of windows of up to a given length at one rate, and its buffers.
pub struct WindowSpectrumPlan {
    rate_hz: f64,
    fft_len: usize,
    fft: Arc<dyn RealToComplex<f64>>,
    /// DFT bins inside the band (`0 … BAND_HZ`, or Nyquist if lower).
    band_bins: usize,
}

/// The buffers one window's DFT works in ([`WindowSpectrumPlan::scratch`]): a recognizer that
/// must not allocate per window keeps one.
#[derive(Clone)]
pub struct SpectrumScratch {
    input: Vec<f64>,
    output: Vec<Complex<f64>>,
    fft: Vec<Complex<f64>>,
}

impl std::fmt::Debug for SpectrumScratch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SpectrumScratch")
            .field("input", &self.input.len())
            .finish_non_exhaustive()
    }
}

impl std::fmt::Debug for WindowSpectrumPlan {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("WindowSpectrumPlan")
            .field("rate_hz", &self.rate_hz)
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
            return Err(RecognizeError::Setting(SettingError::Parameter {
                of: "setting",
                name: "rate_hz",
                value: rate_hz,
                reason: "must be positive and finite",
            }));
        }
        let fft_len = max_samples.max(2);
        let band_bins = band_bins(rate_hz, fft_len);
        if band_bins < FREQUENCY_BINS {
            return Err(RecognizeError::Setting(SettingError::Parameter {
                of: "vibration spectrum",
                name: "window_s",
                value: max_samples as f64 / rate_hz,
                reason: "too short to resolve 25 bands of 8 Hz: windows of at least 0.125 s",
            }));
        }
        let fft = fft::forward_plan(fft_len);
        Ok(Self {
            rate_hz,
            fft_len,
            fft,
            band_bins,
        })
    }

    /// The longest window it takes, samples.
    pub fn max_samples(&self) -> usize {
        self.fft_len
    }

    /// Buffers for [`WindowSpectrumPlan::features_with`] and
    /// [`WindowSpectrumPlan::features_over_travel_with`].
    pub fn scratch(&self) -> SpectrumScratch {
        SpectrumScratch {
            input: self.fft.make_input_vec(),
            output: self.fft.make_output_vec(),
            fft: self.fft.make_scratch_vec(),
        }
    }

    /// The spectrum of one window of a single signal (a single axis, or the three axes'
    /// magnitude): at least 2 and at most [`WindowSpectrumPlan::max_samples`] samples, all
    /// finite.
    pub fn features(&self, signal: &[f64], scale: CellScale) -> Result<[f64; SPECTRUM_LEN], RecognizeError> {
        self.features_with(signal, scale, &mut self.scratch())
    }

    /// [`WindowSpectrumPlan::features`] in `scratch` (from this plan): no allocation.
    pub fn features_with(
        &self,
        signal: &[f64],
        scale: CellScale,
        scratch: &mut SpectrumScratch,
    ) -> Result<[f64; SPECTRUM_LEN], RecognizeError> {
        self.spectrum(signal, self.band_bins, scale, scratch)
    }

    /// The spectrum of one window over travel, its bands in cycles per metre: 0 …
    /// [`BAND_HZ`] at `reference_speed_mps`, so 0 … `BAND_HZ · speed / reference` Hz for a
    /// window slid at `speed_mps` (its path length over its duration). A texture of
    /// wavelength `λ` vibrates at `v / λ` Hz, so it lands in the same band at any speed; at
    /// the reference speed the bands are exactly [`WindowSpectrumPlan::features`]'s. What
    /// speed does to the vibration's *amplitude* depends on the rig (a stiff stylus tracing
    /// the relief accelerates with `v²`, a resonance does not) and is kept;
    /// [`CellScale::UnitSum`] removes it.
    ///
    /// A window slid so slowly that its band holds fewer DFT bins than there are bands (a
    /// still tool) reads each empty band at the bin of its centre. A window slid so fast that
    /// its band passes the Nyquist frequency cannot be read in these bands: a typed error
    /// naming its speed.
    pub fn features_over_travel(
        &self,
        signal: &[f64],
        speed_mps: f64,
        reference_speed_mps: f64,
        scale: CellScale,
    ) -> Result<[f64; SPECTRUM_LEN], RecognizeError> {
        self.features_over_travel_with(signal, speed_mps, reference_speed_mps, scale, &mut self.scratch())
    }

    /// [`WindowSpectrumPlan::features_over_travel`] in `scratch` (from this plan): no
    /// allocation.
    pub fn features_over_travel_with(
        &self,
        signal: &[f64],
        speed_mps: f64,
        reference_speed_mps: f64,
        scale: CellScale,
        scratch: &mut SpectrumScratch,
    ) -> Result<[f64; SPECTRUM_LEN], RecognizeError> {
        let bad = |name, value| {
            RecognizeError::Setting(SettingError::Parameter {
                of: "vibration spectrum",
                name,
                value,
                reason: "finite and not negative (a reference speed: positive)",
            })
        };
        if !(speed_mps.is_finite() && speed_mps >= 0.0) {
            return Err(bad("speed_mps", speed_mps));
        }
        if !(reference_speed_mps.is_finite() && reference_speed_mps > 0.0) {
            return Err(bad("reference_speed_mps", reference_speed_mps));
        }
        let band_hz = BAND_HZ * speed_mps / reference_speed_mps;
        let nyquist_hz = self.rate_hz / 2.0;
        if band_hz > nyquist_hz * (1.0 + 1e-9) {
            return Err(RecognizeError::Setting(SettingError::TooFastForBands {
                speed_mps,
                max_speed_mps: reference_speed_mps * nyquist_hz / BAND_HZ,
                rate_hz: self.rate_hz,
            }));
        }
        self.spectrum(
            signal,
            band_bins_to(band_hz, self.rate_hz, self.fft_len),
            scale,
            scratch,
        )
    }

    /// The bands' mean magnitudes, the DFT bins `0 .. band_bins` split evenly among them.
    fn spectrum(
        &self,
        signal: &[f64],
        band_bins: usize,
        scale: CellScale,
        scratch: &mut SpectrumScratch,
    ) -> Result<[f64; SPECTRUM_LEN], RecognizeError> {
        let n = signal.len();
        if n < 2 {
            return Err(RecognizeError::Setting(SettingError::WindowTooShort { len: n }));
        }
        if n > self.fft_len {
            return Err(RecognizeError::Setting(SettingError::Parameter {
                of: "vibration spectrum",
                name: "window samples",
                value: n as f64,
                reason: "longer than the longest window the plan was made for",
            }));
        }
        if let Some(index) = signal.iter().position(|v| !v.is_finite()) {
            return Err(RecognizeError::Input(InputError::NonFiniteSample { index }));
        }
        let SpectrumScratch { input, output, fft } = scratch;
        if input.len() != self.fft_len || output.len() != self.fft_len / 2 + 1 {
            return Err(RecognizeError::Usage(UsageError::Buffer {
                what: "vibration spectrum scratch",
                got: input.len(),
                expected: self.fft_len,
            }));
        }
        let mean = signal.iter().sum::<f64>() / n as f64;
        let mut window_sum = 0.0;
        for (i, (dst, &s)) in input.iter_mut().zip(signal).enumerate() {
            let w = 0.5 - 0.5 * (2.0 * std::f64::consts::PI * i as f64 / n as f64).cos();
            window_sum += w;
            *dst = (s - mean) * w;
        }
        // The DFT leaves the input as scratch: the zero padding is written anew every time.
        input[n..].fill(0.0);
        self.fft.process_with_scratch(input, output, fft)?;
        let to_amplitude = 2.0 / window_sum;
        let (mut sum, mut count) = ([0.0; SPECTRUM_LEN], [0usize; SPECTRUM_LEN]);
        for (k, c) in output.iter().enumerate() {
            let Some(b) = frequency_bin(k, band_bins) else {
                break;
            };
            sum[b] += c.norm() * to_amplitude;
            count[b] += 1;
        }
        // Only a band narrower than a DFT bin (a window over travel slid very slowly) is empty.
        for (b, (s, c)) in sum.iter_mut().zip(&mut count).enumerate() {
            if *c == 0 {
                let centre = ((2 * b + 1) * band_bins / (2 * SPECTRUM_LEN)).min(output.len() - 1);
                *s = output[centre].norm() * to_amplitude;
                *c = 1;
            }
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

    /// Buffers kept from window to window give what fresh ones give, to the bit, a shorter
    /// window after a longer one included (its zero padding is written anew).
    #[test]
    fn kept_buffers_read_as_fresh_ones() {
        let plan = WindowSpectrumPlan::new(RATE_HZ, 400).unwrap();
        let mut scratch = plan.scratch();
        for (n, freq_hz) in [(400, 101.0), (200, 37.0), (333, 64.0), (150, 150.0)] {
            let signal = tone(n, freq_hz, 0.2, 1.0);
            let kept = plan
                .features_with(&signal, CellScale::Mean, &mut scratch)
                .unwrap();
            assert_eq!(kept, plan.features(&signal, CellScale::Mean).unwrap(), "{n}");
            let over = plan
                .features_over_travel_with(&signal, 0.004, 0.005, CellScale::Mean, &mut scratch)
                .unwrap();
            let fresh = plan
                .features_over_travel(&signal, 0.004, 0.005, CellScale::Mean)
                .unwrap();
            assert_eq!(over, fresh, "{n}");
        }
        let other = WindowSpectrumPlan::new(RATE_HZ, 300).unwrap().scratch();
        let wrong = plan.features_with(&tone(200, 50.0, 0.2, 0.0), CellScale::Mean, &mut other.clone());
        assert!(
            matches!(wrong, Err(RecognizeError::Usage(UsageError::Buffer { .. }))),
            "{wrong:?}"
        );
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

    /// A texture of wavelength `wavelength_m` slid over `travel_m` at `speed_mps`, sampled at
    /// `rate_hz`.
    fn texture(wavelength_m: f64, travel_m: f64, speed_mps: f64, rate_hz: f64) -> Vec<f64> {
        let n = (travel_m / speed_mps * rate_hz).round() as usize;
        (0..n)
            .map(|i| (std::f64::consts::TAU * speed_mps * i as f64 / rate_hz / wavelength_m).sin())
            .collect()
    }

    fn top(s: &[f64; SPECTRUM_LEN]) -> usize {
        s.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1)).unwrap().0
    }

    #[test]
    fn a_texture_lands_in_its_band_over_travel_at_any_speed() {
        // 2.2 kHz; windows of 6.25 mm, up to 1.25 s (6.25 mm at 5 mm/s); reference 25 mm/s, so
        // the bands are 0.32 cycles/mm wide over 0–8 cycles/mm. A 0.48 mm texture is at
        // 2.08 cycles/mm, the middle of band 6 (52.1 Hz at 25 mm/s).
        let (rate, reference) = (2200.0, 0.025);
        let plan = WindowSpectrumPlan::new(rate, 2750).unwrap();
        let at = |speed_mps: f64| texture(0.48e-3, 6.25e-3, speed_mps, rate);
        let over_travel = |speed_mps: f64| {
            plan.features_over_travel(&at(speed_mps), speed_mps, reference, CellScale::UnitSum)
                .unwrap()
        };
        let in_hz = |speed_mps: f64| plan.features(&at(speed_mps), CellScale::UnitSum).unwrap();
        for speed_mps in [0.0125, 0.025, 0.05, 0.1] {
            assert_eq!(top(&over_travel(speed_mps)), 6, "{speed_mps}");
        }
        // In hertz the texture moves with the speed: 26, 52 and 104 Hz (the bands split the DFT
        // bins up to 200 Hz evenly, 8.03 Hz each).
        assert_eq!(top(&in_hz(0.0125)), 3);
        assert_eq!(top(&in_hz(0.025)), 6);
        assert_eq!(top(&in_hz(0.05)), 12);
        // The shape over travel is the same within a few percent of its peak band at half and
        // twice the speed (the window's edges fall on other phases of the wave).
        let reference_shape = over_travel(0.025);
        for speed_mps in [0.0125, 0.05] {
            let shape = over_travel(speed_mps);
            for (b, (x, y)) in shape.iter().zip(&reference_shape).enumerate() {
                assert!(
                    (x - y).abs() < 0.05 * reference_shape[6],
                    "{speed_mps} band {b}: {x} vs {y}"
                );
            }
        }
        // At the reference speed the bands are those in hertz, to the bit.
        let signal = at(reference);
        assert_eq!(
            plan.features_over_travel(&signal, reference, reference, CellScale::Mean)
                .unwrap(),
            plan.features(&signal, CellScale::Mean).unwrap()
        );
    }

    #[test]
    fn too_fast_a_window_is_a_typed_error_and_a_still_one_reads_zero() {
        let plan = WindowSpectrumPlan::new(2200.0, 2750).unwrap();
        let signal = texture(0.45e-3, 6.25e-3, 0.025, 2200.0);
        // 0–200 Hz at 25 mm/s is 0–1100 Hz at 137.5 mm/s: the Nyquist frequency.
        assert!(
            plan.features_over_travel(&signal, 0.1375, 0.025, CellScale::Mean)
                .is_ok()
        );
        match plan.features_over_travel(&signal, 0.14, 0.025, CellScale::Mean) {
            Err(RecognizeError::Setting(SettingError::TooFastForBands {
                speed_mps,
                max_speed_mps,
                rate_hz,
            })) => {
                assert_eq!((speed_mps, rate_hz), (0.14, 2200.0));
                assert!((max_speed_mps - 0.1375).abs() < 1e-12);
            }
            other => panic!("{other:?}"),
        }
        for bad in [f64::NAN, -0.01, f64::INFINITY] {
            assert!(
                plan.features_over_travel(&signal, bad, 0.025, CellScale::Mean)
                    .is_err()
            );
            assert!(
                plan.features_over_travel(&signal, 0.025, bad, CellScale::Mean)
                    .is_err()
            );
        }
        // Slid at a hundredth of the reference, the band is 2 Hz wide, under a DFT bin per
        // band: every band is read (at its centre's bin), none is left empty.
        let slow_signal = texture(0.48e-3, 0.3125e-3, 0.00025, 2200.0);
        assert_eq!(slow_signal.len(), 2750);
        let slow = plan
            .features_over_travel(&slow_signal, 0.00025, 0.025, CellScale::Mean)
            .unwrap();
        assert!(slow.iter().all(|v| v.is_finite() && *v > 0.0), "{slow:?}");
        // A still tool: every band is read at 0 Hz, where a steady signal (gravity) is removed
        // with the mean.
        let still = plan
            .features_over_travel(&[9.81; 550], 0.0, 0.025, CellScale::Mean)
            .unwrap();
        assert!(still.iter().all(|v| *v < 1e-12), "{still:?}");
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
            Err(RecognizeError::Setting(SettingError::WindowTooShort { len: 1 }))
        ));
        assert!(plan.features(&vec![0.0; 251], CellScale::Mean).is_err());
        let mut bad = tone(250, 30.0, 1.0, 0.0);
        bad[17] = f64::NAN;
        assert!(matches!(
            plan.features(&bad, CellScale::Mean),
            Err(RecognizeError::Input(InputError::NonFiniteSample { index: 17 }))
        ));
    }
}
