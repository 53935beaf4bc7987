//! Sinapov et al.'s spectrotemporal features (IEEE T-RO 2011, Sec. IV-A) from a three-axis
//! accelerometer recording of one scratch:
//!
//! 1. magnitude `m_j = ‖a_j‖₂` per sample, so the feature ignores the sensor's orientation;
//! 2. deviation from a [`MOVING_AVERAGE_S`] moving average, which removes gravity and the slow
//!    changes of the contact force and keeps the vibration;
//! 3. a spectrogram: real DFTs of [`FRAME_S`] frames;
//! 4. a 5 (time) × 25 (frequency) histogram of the spectrogram over 0 … [`BAND_HZ`], the
//!    125-vector the classifiers see.
//!
//! # In seconds and hertz, not samples
//! The paper states its counts in samples of its 400 Hz sensor: a 100-sample moving average,
//! DFTs with 129 bins (256-sample frames, 0 … 200 Hz) split into 25 frequency bins. Taken as
//! sample counts they would mean something else on every rig: at 2.2 kHz a 256-sample frame is
//! 0.12 s and its 25 bins are 44 Hz wide, most of them above anything sliding excites. So this
//! module keeps the paper's *physical* definition — a 0.25 s average, 0.64 s frames, 0 … 200 Hz
//! in 25 bins of 8 Hz — and derives the sample counts from each capture's rate
//! ([`SpectrogramPlan::at_rate`]). At 400 Hz that is exactly the paper's (100, 256, 129, 25);
//! at any other rate a recording has the histogram it would have had at 400 Hz, up to what a
//! slower sensor cannot see (the band stops at its Nyquist frequency).
//!
//! The paper fixes the counts but not the frame hop, the window function, the moving average's
//! edges or how a histogram cell is scaled; those choices are documented on the items below.
//!
//! # Single-axis sensors
//!
//! A rig with one vibration axis ([`VIBRATION_COLUMN`], m/s²) has no magnitude to take: its
//! signal `s_j` replaces `m_j` in step 1 and steps 2–4 are unchanged. This is the same
//! spectrogram as the three-axis one whenever the magnitude *is* that axis: for axes
//! `(0, 0, s)` the magnitude is `|s_j|`, which equals `s_j` when `s` never goes negative and
//! `−s_j` when it never goes positive (a DC-coupled sensor carrying gravity larger than the
//! vibration is one or the other), and a sign flip leaves every `|X_k|` unchanged — so both
//! give the same histogram, bit for bit. The signed signal rather than `|s_j|` is used because
//! an AC-coupled sensor oscillates around zero, and rectifying it would fold the vibration into
//! twice its frequency. A capture with both the three axes and the single one is read from the
//! three axes, so its features are those it had before the single axis existed.

use std::sync::Arc;

use crate::RecognizeError;
use crate::{InputError, SettingError};
use fft::RealToComplex;

use capture::Capture;

/// Length of the moving average the magnitude is compared with, s (Sinapov: 100 samples at
/// 400 Hz).
pub const MOVING_AVERAGE_S: f64 = 0.25;
/// Length of a DFT frame, s (Sinapov: 256 samples at 400 Hz, the DFT's 129 bins).
pub const FRAME_S: f64 = 0.64;
/// Top of the frequency band the histogram covers, Hz (Sinapov: the Nyquist frequency of the
/// 400 Hz sensor). DFT bins above it are not part of the feature.
pub const BAND_HZ: f64 = 200.0;
/// Time bins of the histogram (the paper's `k_t`).
pub const TIME_BINS: usize = 5;
/// Frequency bins of the histogram (the paper's `k_f`).
pub const FREQUENCY_BINS: usize = 25;
/// Length of the feature vector.
pub const FEATURE_LEN: usize = TIME_BINS * FREQUENCY_BINS;
/// The fewest frames a spectrogram needs: one per time bin, so that no histogram row is empty.
pub const MIN_FRAMES: usize = TIME_BINS;
/// The lowest sample rate with at least one DFT bin per frequency bin (`0.32·rate + 1 ≥ 25`),
/// Hz.
pub const MIN_RATE_HZ: f64 = 75.0;
/// The highest sample rate a plan is made for, Hz (a 0.64 s frame of 640 000 samples).
pub const MAX_RATE_HZ: f64 = 1e6;

/// The accelerometer columns of a scratch capture.
pub const ACCEL_COLUMNS: [&str; 3] = [
    capture::kind::ACCEL_X_MPS2,
    capture::kind::ACCEL_Y_MPS2,
    capture::kind::ACCEL_Z_MPS2,
];

/// The single-axis vibration column, the alternative to [`ACCEL_COLUMNS`] (see the
/// [module documentation](self#single-axis-sensors)).
pub const VIBRATION_COLUMN: &str = capture::kind::VIBRATION_MPS2;

/// How a histogram cell is scaled.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CellScale {
    /// Each cell is the *mean* spectrogram magnitude over its frames and DFT bins. The feature
    /// does not depend on the trial's length (a slow stroke has more frames, not larger cells)
    /// but keeps the vibration's amplitude, which separates rough from smooth surfaces. This is
    /// the default: the paper's histogram counts spectrogram intensity per cell and does not
    /// mention a normalisation, and amplitude is the most informative property of a scratch.
    #[default]
    Mean,
    /// The mean cells divided by their total, so the 125 values sum to one: only the *shape* of
    /// the spectrotemporal energy remains, independent of amplitude (e.g. of contact force or a
    /// sensor's gain). An all-zero histogram (a perfectly still sensor) stays zero.
    UnitSum,
}

/// The top of the histogram's frequency band.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum HistogramBand {
    /// 0 … [`BAND_HZ`] (or Nyquist, if lower): the band of Sinapov's 400 Hz sensor, in 25 bins
    /// of 8 Hz at any rate. A texture slid at a few centimetres per second rings there.
    #[default]
    Paper,
    /// 0 … the capture's Nyquist frequency, in 25 bins of `rate / 50` Hz (44 Hz at 2.2 kHz):
    /// everything a faster sensor hears, for a rig whose surfaces differ above 200 Hz (a
    /// fingertip sensor's own resonances, fast strokes). At 400 Hz it is [`Self::Paper`].
    Nyquist,
}

impl HistogramBand {
    /// Both bands, the paper's first.
    pub const ALL: [Self; 2] = [Self::Paper, Self::Nyquist];

    /// `paper` or `nyquist`, as files and `--bands` spell it.
    pub fn name(self) -> &'static str {
        match self {
            Self::Paper => "paper",
            Self::Nyquist => "nyquist",
        }
    }

    /// Whether it is the paper's (which files leave unsaid).
    pub fn is_paper(&self) -> bool {
        *self == Self::Paper
    }

    /// The band's top at `rate_hz`, Hz.
    pub fn top_hz(self, rate_hz: f64) -> f64 {
        match self {
            Self::Paper => BAND_HZ.min(rate_hz / 2.0),
            Self::Nyquist => rate_hz / 2.0,
        }
    }
}

/// How a spectrotemporal histogram is defined beyond the paper's fixed frames: which band its
/// frequency bins cover and how its cells are scaled. Stored in a recognizer file as
/// `cell_scale` and (when not the paper's) `band`, so files written before the band could be
/// chosen read as they did.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
pub struct Histogram {
    /// How its cells are scaled.
    #[serde(rename = "cell_scale", default)]
    pub cells: CellScale,
    /// Which band its frequency bins cover.
    #[serde(default, skip_serializing_if = "HistogramBand::is_paper")]
    pub band: HistogramBand,
}

impl Histogram {
    /// The paper's band, cells scaled by `cells`.
    pub fn new(cells: CellScale) -> Self {
        Self {
            cells,
            band: HistogramBand::Paper,
        }
    }

    /// The same cells over `band`.
    pub fn over(self, band: HistogramBand) -> Self {
        Self { band, ..self }
    }
}

impl From<CellScale> for Histogram {
    fn from(cells: CellScale) -> Self {
        Self::new(cells)
    }
}

impl std::fmt::Display for Histogram {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let cells = match self.cells {
            CellScale::Mean => "mean",
            CellScale::UnitSum => "unit-sum",
        };
        write!(f, "{cells} cells, {} band", self.band.name())
    }
}

/// Euclidean norm per sample.
pub fn magnitude(x: &[f64], y: &[f64], z: &[f64]) -> Result<Vec<f64>, RecognizeError> {
    if x.len() != y.len() || x.len() != z.len() {
        return Err(RecognizeError::Input(InputError::AxisLengths {
            x: x.len(),
            y: y.len(),
            z: z.len(),
        }));
    }
    x.iter()
        .zip(y)
        .zip(z)
        .enumerate()
        .map(|(index, ((&ax, &ay), &az))| {
            let m = (ax * ax + ay * ay + az * az).sqrt();
            if m.is_finite() {
                Ok(m)
            } else {
                Err(RecognizeError::Input(InputError::NonFiniteSample { index }))
            }
        })
        .collect()
}

/// `m_j − m̄_j`, where `m̄_j` is the mean of the `len` samples centred on `j` (indices
/// `j − len/2 … j + len − len/2 − 1`).
///
/// Edges: near the ends the window is cut to the samples that exist and the mean is taken over
/// those. Padding with zeros would turn gravity (~9.8 m/s² in the magnitude) into a huge false
/// step at both ends; a causal window would delay the average by half its length and leak every
/// force change into the deviation. A recording shorter than the window is averaged as a whole.
pub fn moving_average_deviation(m: &[f64], len: usize) -> Vec<f64> {
    let n = m.len();
    let len = len.max(1);
    let mut prefix = Vec::with_capacity(n + 1);
    prefix.push(0.0);
    let mut acc = 0.0;
    for &v in m {
        acc += v;
        prefix.push(acc);
    }
    let half = len / 2;
    (0..n)
        .map(|j| {
            let lo = j.saturating_sub(half);
            let hi = (j + len - half).min(n);
            let mean = (prefix[hi] - prefix[lo]) / (hi - lo) as f64;
            m[j] - mean
        })
        .collect()
}

/// Magnitude spectrogram: `frames × bins` values, frame-major, `bins` the DFT's `0 … Nyquist`.
#[derive(Debug, Clone, PartialEq)]
pub struct Spectrogram {
    frames: usize,
    bins: usize,
    values: Vec<f64>,
}

impl Spectrogram {
    /// Number of frames (time axis).
    pub fn frames(&self) -> usize {
        self.frames
    }

    /// The magnitudes of one frame (DFT bins `0 … Nyquist`), or `None` past the end.
    pub fn frame(&self, index: usize) -> Option<&[f64]> {
        self.values.get(index * self.bins..(index + 1) * self.bins)
    }
}

/// The spectrotemporal pipeline at one sample rate: the paper's lengths in samples at that rate
/// and a planned real FFT of one frame, reused for every frame.
pub struct SpectrogramPlan {
    rate_hz: f64,
    moving_average_len: usize,
    frame_len: usize,
    hop_len: usize,
    /// DFT bins `0 … band_bins − 1` lie in `0 … BAND_HZ` (and below Nyquist).
    band_bins: usize,
    fft: Arc<dyn RealToComplex<f64>>,
    window: Vec<f64>,
}

impl std::fmt::Debug for SpectrogramPlan {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SpectrogramPlan")
            .field("rate_hz", &self.rate_hz)
            .field("moving_average_len", &self.moving_average_len)
            .field("frame_len", &self.frame_len)
            .field("hop_len", &self.hop_len)
            .field("band_bins", &self.band_bins)
            .finish()
    }
}

impl SpectrogramPlan {
    /// The pipeline for a recording sampled at `rate_hz`: [`MOVING_AVERAGE_S`] and [`FRAME_S`]
    /// rounded to whole samples, a hop of half a frame, and the DFT bins up to [`BAND_HZ`] (or
    /// Nyquist, if lower). A rate below [`MIN_RATE_HZ`] (fewer DFT bins than frequency bins)
    /// or above [`MAX_RATE_HZ`] is a typed error.
    ///
    /// The window is a periodic Hann window: it keeps a tone's energy within ±1 DFT bin (a
    /// rectangular window would spread it over the whole spectrum and blur the 25 frequency
    /// bins), and at the 50 % overlap its copies sum to a constant, so every sample (away from
    /// the ends) weighs the same and no part of the scratch is missed between frames.
    pub fn at_rate(rate_hz: f64) -> Result<Self, RecognizeError> {
        Self::over_band(rate_hz, HistogramBand::Paper)
    }

    /// As [`SpectrogramPlan::at_rate`], its 25 frequency bins over `band` instead of the
    /// paper's.
    pub fn over_band(rate_hz: f64, band: HistogramBand) -> Result<Self, RecognizeError> {
        if !(rate_hz.is_finite() && (MIN_RATE_HZ..=MAX_RATE_HZ).contains(&rate_hz)) {
            return Err(RecognizeError::Setting(SettingError::Parameter {
                of: "setting",
                name: "rate_hz",
                value: rate_hz,
                reason: "75 Hz to 10^6 Hz for the spectrotemporal histogram (at least one DFT bin \
                         per frequency bin)",
            }));
        }
        let frame_len = ((FRAME_S * rate_hz).round() as usize).max(2);
        let band_bins = band_bins_to(band.top_hz(rate_hz), rate_hz, frame_len);
        let fft = fft::forward_plan(frame_len);
        let window = (0..frame_len)
            .map(|i| {
                let phase = 2.0 * std::f64::consts::PI * i as f64 / frame_len as f64;
                0.5 - 0.5 * phase.cos()
            })
            .collect();
        Ok(Self {
            rate_hz,
            moving_average_len: ((MOVING_AVERAGE_S * rate_hz).round() as usize).max(1),
            frame_len,
            hop_len: frame_len / 2,
            band_bins,
            fft,
            window,
        })
    }

    /// The rate the plan was made for, Hz.
    pub fn rate_hz(&self) -> f64 {
        self.rate_hz
    }

    /// Samples per DFT frame.
    pub fn frame_len(&self) -> usize {
        self.frame_len
    }

    /// Samples between frames.
    pub fn hop_len(&self) -> usize {
        self.hop_len
    }

    /// Samples of the moving average.
    pub fn moving_average_len(&self) -> usize {
        self.moving_average_len
    }

    /// DFT bins inside the histogram's band (`0 … BAND_HZ`, or Nyquist if lower).
    pub fn band_bins(&self) -> usize {
        self.band_bins
    }

    /// The fewest samples a recording needs: [`MIN_FRAMES`] frames (1.92 s at any rate).
    pub fn min_samples(&self) -> usize {
        self.frame_len + (MIN_FRAMES - 1) * self.hop_len
    }

    /// Histogram bin of DFT bin `k`, or `None` above the band: the band's DFT bins are split
    /// into 25 runs of (almost) equal width, `⌊k·25/band_bins⌋` (5 or 6 DFT bins, 7.8–9.4 Hz).
    pub fn frequency_bin(&self, k: usize) -> Option<usize> {
        frequency_bin(k, self.band_bins)
    }

    /// Spectrogram of `signal` (normally the moving-average deviation): frames start every
    /// [`SpectrogramPlan::hop_len`] samples, as many as fit entirely (the tail shorter than a hop
    /// is dropped). Magnitudes are `|X_k|` scaled by `2 / Σ window`, so a tone of amplitude `A`
    /// peaks at about `A` whatever the frame length.
    pub fn spectrogram(&self, signal: &[f64]) -> Result<Spectrogram, RecognizeError> {
        self.check_length(signal.len())?;
        if let Some(index) = signal.iter().position(|v| !v.is_finite()) {
            return Err(RecognizeError::Input(InputError::NonFiniteSample { index }));
        }
        let frames = (signal.len() - self.frame_len) / self.hop_len + 1;
        let bins = self.frame_len / 2 + 1;
        let scale = 2.0 / self.window.iter().sum::<f64>();
        let mut input = self.fft.make_input_vec();
        let mut output = self.fft.make_output_vec();
        let mut values = Vec::with_capacity(frames * bins);
        for f in 0..frames {
            let start = f * self.hop_len;
            for ((dst, &s), &w) in input
                .iter_mut()
                .zip(&signal[start..start + self.frame_len])
                .zip(&self.window)
            {
                *dst = s * w;
            }
            self.fft.process(&mut input, &mut output)?;
            values.extend(output.iter().map(|c| c.norm() * scale));
        }
        Ok(Spectrogram { frames, bins, values })
    }

    /// The full pipeline on three accelerometer axes: magnitude, moving-average deviation,
    /// spectrogram, histogram.
    pub fn features(
        &self,
        x: &[f64],
        y: &[f64],
        z: &[f64],
        scale: CellScale,
    ) -> Result<[f64; FEATURE_LEN], RecognizeError> {
        let m = magnitude(x, y, z)?;
        self.signal_features(&m, scale)
    }

    /// The pipeline on a single-axis vibration signal: the signal takes the magnitude's place,
    /// then moving-average deviation, spectrogram, histogram (see the
    /// [module documentation](self#single-axis-sensors) for how it relates to three axes).
    pub fn single_axis_features(
        &self,
        signal: &[f64],
        scale: CellScale,
    ) -> Result<[f64; FEATURE_LEN], RecognizeError> {
        // Checked before the moving average, which would smear one bad sample over many.
        if let Some(index) = signal.iter().position(|v| !v.is_finite()) {
            return Err(RecognizeError::Input(InputError::NonFiniteSample { index }));
        }
        self.signal_features(signal, scale)
    }

    /// Steps 2–4 on a finite per-sample signal (the magnitude, or a single axis).
    fn signal_features(&self, m: &[f64], scale: CellScale) -> Result<[f64; FEATURE_LEN], RecognizeError> {
        self.check_length(m.len())?;
        let d = moving_average_deviation(m, self.moving_average_len);
        Ok(self.histogram(&self.spectrogram(&d)?, scale))
    }

    fn check_length(&self, samples: usize) -> Result<(), RecognizeError> {
        let needed = self.min_samples();
        if samples < needed {
            return Err(RecognizeError::Input(InputError::TooShort { samples, needed }));
        }
        Ok(())
    }

    /// Features of a capture's [`ACCEL_COLUMNS`] when it has all three, else of its
    /// [`VIBRATION_COLUMN`]. A capture with neither fails on its first missing axis.
    pub fn capture_features(
        &self,
        capture: &Capture,
        scale: CellScale,
    ) -> Result<[f64; FEATURE_LEN], RecognizeError> {
        let has_axes = ACCEL_COLUMNS.iter().all(|name| capture.has_column(name));
        if !has_axes && capture.has_column(VIBRATION_COLUMN) {
            let signal = capture
                .column(VIBRATION_COLUMN)
                .map_err(|e| RecognizeError::Input(InputError::NoAccelerometer(Box::new(e))))?;
            return self.single_axis_features(signal, scale);
        }
        let [x, y, z] = ACCEL_COLUMNS;
        let column = |name| {
            capture
                .column(name)
                .map_err(|e| RecognizeError::Input(InputError::NoAccelerometer(Box::new(e))))
        };
        self.features(column(x)?, column(y)?, column(z)?, scale)
    }

    /// The 5 × 25 spectrotemporal histogram, time-major (`index = t·25 + f`). Each cell is
    /// first the mean magnitude of its (frame, DFT bin) pairs, then scaled as `scale` says.
    pub fn histogram(&self, spec: &Spectrogram, scale: CellScale) -> [f64; FEATURE_LEN] {
        let mut sum = [0.0; FEATURE_LEN];
        let mut count = [0usize; FEATURE_LEN];
        for f in 0..spec.frames {
            let t = time_bin(f, spec.frames);
            let row = &spec.values[f * spec.bins..(f + 1) * spec.bins];
            for (k, &v) in row.iter().enumerate() {
                let Some(b) = self.frequency_bin(k) else { break };
                let cell = t * FREQUENCY_BINS + b;
                sum[cell] += v;
                count[cell] += 1;
            }
        }
        cell_means(sum, count, scale)
    }
}

/// DFT bins of a `frame_len`-sample frame at `rate_hz` inside the band `0 … BAND_HZ` (or up to
/// Nyquist, if lower).
pub(crate) fn band_bins(rate_hz: f64, frame_len: usize) -> usize {
    band_bins_to(BAND_HZ, rate_hz, frame_len)
}

/// As [`band_bins`], for a band over 0 … `top_hz` instead of 0 … [`BAND_HZ`] (a window's
/// bands over travel, stretched by its speed).
pub(crate) fn band_bins_to(top_hz: f64, rate_hz: f64, frame_len: usize) -> usize {
    let spectrum_bins = frame_len / 2 + 1;
    // The small slack keeps a band edge that falls exactly on a bin (200 Hz at 400 Hz or
    // 2.2 kHz) inside the band despite rounding in the division.
    let in_band = (top_hz * frame_len as f64 / rate_hz + 1e-9).floor() as usize + 1;
    in_band.min(spectrum_bins)
}

/// Frequency bin of DFT bin `k` of a band of `band_bins` DFT bins, or `None` above it:
/// `⌊k·25/band_bins⌋`.
pub(crate) fn frequency_bin(k: usize, band_bins: usize) -> Option<usize> {
    (k < band_bins).then(|| k * FREQUENCY_BINS / band_bins)
}

/// Each cell's mean magnitude (`sum / count`; an empty cell is 0), then scaled as `scale`
/// says.
pub(crate) fn cell_means<const N: usize>(sum: [f64; N], count: [usize; N], scale: CellScale) -> [f64; N] {
    let mut out = [0.0; N];
    for ((o, s), c) in out.iter_mut().zip(sum).zip(count) {
        if c > 0 {
            *o = s / c as f64;
        }
    }
    if scale == CellScale::UnitSum {
        let total: f64 = out.iter().sum();
        if total > 0.0 {
            out.iter_mut().for_each(|v| *v /= total);
        }
    }
    out
}

/// Time bin of frame `f` of `frames`: `⌊f·5/frames⌋`, so each bin holds a fifth of the
/// recording's frames (±1) whatever its length.
pub fn time_bin(f: usize, frames: usize) -> usize {
    f * TIME_BINS / frames.max(1)
}

#[cfg(test)]
mod tests {
    use super::*;

    const RATE_HZ: f64 = 400.0;
    const G: f64 = 9.80665;

    /// Gravity on z plus a tone of `amp` at `freq_hz` starting at sample `onset`.
    fn tone(n: usize, freq_hz: f64, amp: f64, onset: usize) -> [Vec<f64>; 3] {
        let z = (0..n)
            .map(|i| {
                let t = i as f64 / RATE_HZ;
                let v = if i >= onset {
                    amp * (2.0 * std::f64::consts::PI * freq_hz * t).sin()
                } else {
                    0.0
                };
                G + v
            })
            .collect();
        [vec![0.0; n], vec![0.0; n], z]
    }

    /// The paper's pipeline: 400 Hz, where its sample counts hold.
    fn plan() -> SpectrogramPlan {
        SpectrogramPlan::at_rate(RATE_HZ).expect("a valid rate")
    }

    fn cell(h: &[f64; FEATURE_LEN], t: usize, f: usize) -> f64 {
        h[t * FREQUENCY_BINS + f]
    }

    #[test]
    fn at_400_hz_the_counts_are_the_papers_and_bins_cover_the_spectrum_evenly() {
        let plan = plan();
        assert_eq!(plan.moving_average_len(), 100);
        assert_eq!(plan.frame_len(), 256);
        assert_eq!(plan.hop_len(), 128);
        assert_eq!(plan.band_bins(), 129);
        assert_eq!(plan.min_samples(), 768);
        assert_eq!(plan.frequency_bin(0), Some(0));
        assert_eq!(plan.frequency_bin(128), Some(24));
        assert_eq!(plan.frequency_bin(129), None);
        for b in 0..FREQUENCY_BINS {
            let width = (0..129).filter(|&k| plan.frequency_bin(k) == Some(b)).count();
            assert!((5..=6).contains(&width), "bin {b} has {width} DFT bins");
        }
        assert_eq!(time_bin(0, 10), 0);
        assert_eq!(time_bin(9, 10), 4);
    }

    #[test]
    fn moving_average_removes_gravity_and_keeps_vibration() {
        let [x, y, z] = tone(1000, 78.125, 0.5, 0);
        let d = moving_average_deviation(&magnitude(&x, &y, &z).expect("equal axes"), 100);
        // Constant part gone everywhere, edges included (truncated window, not zero padding).
        let mean = d.iter().sum::<f64>() / d.len() as f64;
        assert!(mean.abs() < 0.01, "mean {mean}");
        assert!(d.iter().all(|v| v.abs() < 0.6), "deviation exceeds the tone");
        let peak = d[200..800].iter().fold(0.0_f64, |a, v| a.max(v.abs()));
        assert!(peak > 0.45, "peak {peak}");
    }

    #[test]
    fn pure_tone_lands_in_its_frequency_bin() {
        // 78.125 Hz is DFT bin 50 of 256 at 400 Hz; histogram bin ⌊50·25/129⌋ = 9 holds DFT
        // bins 47…51, so the Hann main lobe (49…51) stays inside.
        assert_eq!(plan().frequency_bin(50), Some(9));
        let [x, y, z] = tone(2000, 78.125, 0.5, 0);
        let h = plan().features(&x, &y, &z, CellScale::Mean).expect("long enough");
        for t in 0..TIME_BINS {
            let target = cell(&h, t, 9);
            // Amplitude 0.5 peaks at 0.5 in DFT bin 50, 0.25 in 49 and 51: mean over 5 bins 0.2.
            assert!((target - 0.2).abs() < 0.02, "time bin {t}: {target}");
            for f in (0..FREQUENCY_BINS).filter(|&f| f != 9) {
                assert!(cell(&h, t, f) < 0.01 * target, "leak into ({t}, {f})");
            }
        }
        let unit = plan()
            .features(&x, &y, &z, CellScale::UnitSum)
            .expect("long enough");
        let in_bin: f64 = (0..TIME_BINS).map(|t| cell(&unit, t, 9)).sum();
        assert!((unit.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        assert!(in_bin > 0.97, "share in bin 9: {in_bin}");
    }

    #[test]
    fn late_tone_shows_only_in_late_time_bins() {
        let n = 4000;
        let [x, y, z] = tone(n, 150.0, 1.0, n / 2);
        let h = plan().features(&x, &y, &z, CellScale::Mean).expect("long enough");
        let f = plan()
            .frequency_bin((150.0 * 256.0 / RATE_HZ).round() as usize)
            .expect("in the band");
        let early = cell(&h, 0, f).max(cell(&h, 1, f));
        let late = cell(&h, 3, f).min(cell(&h, 4, f));
        assert!(late > 0.2, "late {late}");
        assert!(early < 1e-3 * late, "early {early} vs late {late}");
        // Time bin 2 straddles the onset: some energy, less than a full bin.
        let middle = cell(&h, 2, f);
        assert!(middle > 0.1 * late && middle < 0.9 * late, "middle {middle}");
    }

    #[test]
    fn features_do_not_depend_on_length() {
        let plan = plan();
        for scale in [CellScale::Mean, CellScale::UnitSum] {
            let [x, y, z] = tone(1560, 61.0, 0.3, 0);
            let short = plan.features(&x, &y, &z, scale).expect("long enough");
            let [x, y, z] = tone(5880, 61.0, 0.3, 0);
            let long = plan.features(&x, &y, &z, scale).expect("long enough");
            let norm = short.iter().map(|v| v * v).sum::<f64>().sqrt();
            let diff = short
                .iter()
                .zip(&long)
                .map(|(a, b)| (a - b) * (a - b))
                .sum::<f64>()
                .sqrt();
            assert!(diff < 0.02 * norm, "{scale:?}: |Δ| {diff} vs |x| {norm}");
        }
    }

    #[test]
    fn bad_input_is_a_typed_error() {
        let plan = plan();
        let short = vec![0.0; 767];
        assert!(matches!(
            plan.features(&short, &short, &short, CellScale::Mean),
            Err(RecognizeError::Input(InputError::TooShort {
                samples: 767,
                needed: 768
            }))
        ));
        let ok = vec![0.0; 768];
        assert!(matches!(
            plan.features(&ok, &short, &ok, CellScale::Mean),
            Err(RecognizeError::Input(InputError::AxisLengths {
                x: 768,
                y: 767,
                z: 768
            }))
        ));
        let mut nan = ok.clone();
        nan[5] = f64::NAN;
        assert!(matches!(
            plan.features(&ok, &nan, &ok, CellScale::Mean),
            Err(RecognizeError::Input(InputError::NonFiniteSample { index: 5 }))
        ));
        // A still sensor gives an all-zero feature, not a division by zero.
        let still = plan
            .features(&ok, &ok, &ok, CellScale::UnitSum)
            .expect("long enough");
        assert!(still.iter().all(|&v| v == 0.0));
    }

    #[test]
    fn capture_without_accelerometer_is_a_typed_error() {
        use capture::{CaptureKind, Metadata};
        let n = 768;
        let capture = Capture::new(
            Metadata::new(CaptureKind::Rubbing, "test", RATE_HZ),
            [
                "time_s",
                "tangential_position_m",
                "normal_force_n",
                "accel_x_mps2",
            ]
            .map(String::from)
            .to_vec(),
            vec![
                (0..n).map(|i| i as f64 / RATE_HZ).collect(),
                vec![0.0; n],
                vec![0.0; n],
                vec![0.0; n],
            ],
        )
        .expect("a valid rubbing capture");
        let err = plan()
            .capture_features(&capture, CellScale::Mean)
            .expect_err("no y axis");
        assert!(
            matches!(err, RecognizeError::Input(InputError::NoAccelerometer(_))),
            "{err:?}"
        );
    }

    /// A rubbing capture at 400 Hz carrying `accel` as `(column, samples)` pairs.
    fn accel_capture(accel: Vec<(&str, Vec<f64>)>) -> Capture {
        use capture::{CaptureKind, Metadata};
        let n = accel[0].1.len();
        let mut names = vec![
            capture::kind::TIME_S.to_owned(),
            capture::kind::TANGENTIAL_POSITION_M.to_owned(),
            capture::kind::NORMAL_FORCE_N.to_owned(),
        ];
        let mut columns = vec![
            (0..n).map(|i| i as f64 / RATE_HZ).collect(),
            vec![0.0; n],
            vec![0.0; n],
        ];
        for (name, values) in accel {
            names.push(name.to_owned());
            columns.push(values);
        }
        Capture::new(
            Metadata::new(CaptureKind::Rubbing, "test", RATE_HZ),
            names,
            columns,
        )
        .expect("a valid rubbing capture")
    }

    /// Two tones on different axes plus gravity on z, so the magnitude mixes all three.
    fn three_axes(n: usize) -> [Vec<f64>; 3] {
        let wave = |freq_hz: f64, amp: f64| -> Vec<f64> {
            (0..n)
                .map(|i| amp * (2.0 * std::f64::consts::PI * freq_hz * i as f64 / RATE_HZ).sin())
                .collect()
        };
        let z = wave(43.0, 0.4).into_iter().map(|v| G + v).collect();
        [wave(120.0, 0.7), wave(17.0, 0.2), z]
    }

    #[test]
    fn a_single_axis_capture_gives_the_spectrum_of_that_axis() {
        let plan = plan();
        let [_, _, z] = tone(2000, 78.125, 0.5, 0);
        let capture = accel_capture(vec![(VIBRATION_COLUMN, z.clone())]);
        for scale in [CellScale::Mean, CellScale::UnitSum] {
            let h = plan.capture_features(&capture, scale).expect("single axis");
            assert_eq!(h, plan.single_axis_features(&z, scale).expect("long enough"));
            // The tone, in its bin, as on three axes.
            let in_bin: f64 = (0..TIME_BINS).map(|t| cell(&h, t, 9)).sum();
            let total: f64 = h.iter().sum();
            assert!(in_bin > 0.97 * total, "{scale:?}: {in_bin} of {total}");
        }
        // Length and finiteness are checked as on three axes.
        assert!(matches!(
            plan.single_axis_features(&z[..767], CellScale::Mean),
            Err(RecognizeError::Input(InputError::TooShort {
                samples: 767,
                needed: 768
            }))
        ));
        let mut nan = z;
        nan[7] = f64::INFINITY;
        assert!(matches!(
            plan.single_axis_features(&nan, CellScale::Mean),
            Err(RecognizeError::Input(InputError::NonFiniteSample { index: 7 }))
        ));
    }

    #[test]
    fn three_axis_captures_keep_their_features() {
        let plan = plan();
        let [x, y, z] = three_axes(3000);
        let axes = accel_capture(vec![
            (ACCEL_COLUMNS[0], x.clone()),
            (ACCEL_COLUMNS[1], y.clone()),
            (ACCEL_COLUMNS[2], z.clone()),
        ]);
        // A single axis next to the three is ignored: the three axes win.
        let both = accel_capture(vec![
            (ACCEL_COLUMNS[0], x.clone()),
            (ACCEL_COLUMNS[1], y.clone()),
            (ACCEL_COLUMNS[2], z.clone()),
            (VIBRATION_COLUMN, x.clone()),
        ]);
        for scale in [CellScale::Mean, CellScale::UnitSum] {
            // The three-axis pipeline as it was: magnitude, deviation, spectrogram, histogram.
            let m = magnitude(&x, &y, &z).expect("equal axes");
            let before = plan.histogram(
                &plan
                    .spectrogram(&moving_average_deviation(&m, 100))
                    .expect("long"),
                scale,
            );
            assert_eq!(plan.features(&x, &y, &z, scale).expect("long"), before);
            assert_eq!(plan.capture_features(&axes, scale).expect("axes"), before);
            assert_eq!(plan.capture_features(&both, scale).expect("axes"), before);
            assert_ne!(plan.single_axis_features(&x, scale).expect("long"), before);
        }
    }

    /// The identity between the pipelines: for axes `(0, 0, s)` with `s` of one sign, the
    /// magnitude is `±s` exactly, and `|X_k|` of `−s` is that of `s`, so the histograms agree
    /// bit for bit. A signal that crosses zero is rectified by the magnitude, and differs.
    #[test]
    fn one_nonzero_axis_of_one_sign_gives_the_single_axis_histogram() {
        let plan = plan();
        let n = 2500;
        let [zero, _, up] = tone(n, 61.0, 0.8, 300);
        let down: Vec<f64> = up.iter().map(|v| -v).collect();
        let crossing: Vec<f64> = up.iter().map(|v| v - G).collect();
        for scale in [CellScale::Mean, CellScale::UnitSum] {
            for s in [&up, &down] {
                let single = accel_capture(vec![(VIBRATION_COLUMN, s.clone())]);
                let axes = accel_capture(vec![
                    (ACCEL_COLUMNS[0], zero.clone()),
                    (ACCEL_COLUMNS[1], zero.clone()),
                    (ACCEL_COLUMNS[2], s.clone()),
                ]);
                assert_eq!(
                    plan.capture_features(&single, scale).expect("single axis"),
                    plan.capture_features(&axes, scale).expect("three axes"),
                    "{scale:?}"
                );
            }
            assert_ne!(
                plan.single_axis_features(&crossing, scale).expect("long"),
                plan.features(&zero, &zero, &crossing, scale).expect("long"),
            );
        }
    }

    #[test]
    fn a_capture_with_neither_is_a_typed_error() {
        let capture = accel_capture(vec![(capture::kind::FRICTION_FORCE_N, vec![0.0; 768])]);
        let err = plan()
            .capture_features(&capture, CellScale::Mean)
            .expect_err("no accelerometer");
        assert!(
            matches!(err, RecognizeError::Input(InputError::NoAccelerometer(_))),
            "{err:?}"
        );
    }

    /// The same vibration recorded at 400 Hz and at 2.2 kHz: the same histogram, because the
    /// pipeline is defined in seconds and hertz. A 256-sample frame at 2.2 kHz would have
    /// put both tones into the first frequency bin.
    #[test]
    fn the_histogram_does_not_depend_on_the_sample_rate() {
        let signal = |rate_hz: f64| -> Vec<f64> {
            let n = (6.0 * rate_hz) as usize;
            (0..n)
                .map(|i| {
                    let t = i as f64 / rate_hz;
                    let tau = 2.0 * std::f64::consts::PI;
                    G + 0.5 * (tau * 37.0 * t).sin() + 0.2 * (tau * 151.0 * t).sin()
                })
                .collect()
        };
        let slow = plan();
        let fast = SpectrogramPlan::at_rate(2200.0).expect("a valid rate");
        assert_eq!(fast.frame_len(), 1408);
        assert_eq!(fast.band_bins(), 129);
        let a = slow
            .single_axis_features(&signal(400.0), CellScale::Mean)
            .expect("long");
        let b = fast
            .single_axis_features(&signal(2200.0), CellScale::Mean)
            .expect("long");
        let norm = a.iter().map(|v| v * v).sum::<f64>().sqrt();
        let diff = a
            .iter()
            .zip(&b)
            .map(|(x, y)| (x - y) * (x - y))
            .sum::<f64>()
            .sqrt();
        assert!(diff < 0.02 * norm, "|Δ| {diff} vs |x| {norm}");
        for t in 0..TIME_BINS {
            // 37 Hz is in bin ⌊37/8⌋ = 4, 151 Hz in bin 18, at both rates.
            let top = |h: &[f64; FEATURE_LEN]| {
                let mut order: Vec<usize> = (0..FREQUENCY_BINS).collect();
                order.sort_by(|&i, &j| cell(h, t, j).total_cmp(&cell(h, t, i)));
                let mut two = [order[0], order[1]];
                two.sort_unstable();
                two
            };
            assert_eq!(top(&a), [4, 18]);
            assert_eq!(top(&b), [4, 18]);
        }
    }

    /// The Nyquist band reads what the paper's band cannot: at 2.2 kHz a 600 Hz ring lands in
    /// bin ⌊600 / 44⌋ = 13 of 25 and leaves the paper's 0–200 Hz bins as they were without it;
    /// at 400 Hz both bands are the same plan.
    #[test]
    fn the_nyquist_band_reads_a_fast_sensor_up_to_its_nyquist_frequency() {
        let rate_hz = 2200.0;
        let n = (6.0 * rate_hz) as usize;
        let tau = 2.0 * std::f64::consts::PI;
        let with_ring: Vec<f64> = (0..n)
            .map(|i| G + 0.5 * (tau * 600.0 * i as f64 / rate_hz).sin())
            .collect();
        let paper = SpectrogramPlan::at_rate(rate_hz).expect("a valid rate");
        let nyquist = SpectrogramPlan::over_band(rate_hz, HistogramBand::Nyquist).expect("a valid rate");
        assert_eq!(paper.band_bins(), 129);
        assert_eq!(nyquist.band_bins(), 705);
        let wide = nyquist
            .single_axis_features(&with_ring, CellScale::Mean)
            .expect("long");
        let narrow = paper
            .single_axis_features(&with_ring, CellScale::Mean)
            .expect("long");
        for t in 0..TIME_BINS {
            let loudest = (0..FREQUENCY_BINS)
                .max_by(|&i, &j| cell(&wide, t, i).total_cmp(&cell(&wide, t, j)))
                .expect("bins");
            assert_eq!(loudest, 13, "time bin {t}");
            // A cell is the mean of its 28 DFT bins, the tone's ~0.5 shared by about two.
            assert!(cell(&wide, t, 13) > 0.02, "time bin {t}: {}", cell(&wide, t, 13));
            // Below 200 Hz only the tone's leakage and the moving average's edges remain.
            let narrow_max = (0..FREQUENCY_BINS)
                .map(|b| cell(&narrow, t, b))
                .fold(0.0, f64::max);
            assert!(
                narrow_max < 0.01 * cell(&wide, t, 13),
                "time bin {t}: {narrow_max}"
            );
        }
        let slow = SpectrogramPlan::over_band(400.0, HistogramBand::Nyquist).expect("a valid rate");
        assert_eq!(slow.band_bins(), plan().band_bins());
        let h = Histogram::new(CellScale::UnitSum).over(HistogramBand::Nyquist);
        assert_eq!(h.to_string(), "unit-sum cells, nyquist band");
    }

    #[test]
    fn a_slow_sensor_covers_up_to_its_nyquist_and_a_too_slow_one_is_refused() {
        let plan = SpectrogramPlan::at_rate(100.0).expect("a valid rate");
        assert_eq!(plan.frame_len(), 64);
        assert_eq!(plan.band_bins(), 33);
        assert!((0..FREQUENCY_BINS).all(|b| (0..33).any(|k| plan.frequency_bin(k) == Some(b))));
        for bad in [74.0, 0.0, -400.0, f64::NAN, f64::INFINITY, 2e6] {
            assert!(
                matches!(
                    SpectrogramPlan::at_rate(bad),
                    Err(RecognizeError::Setting(SettingError::Parameter {
                        name: "rate_hz",
                        ..
                    }))
                ),
                "{bad}"
            );
        }
    }
}
