//! Sinapov et al.'s spectrotemporal features (IEEE T-RO 2011, Sec. IV-A) from a three-axis
//! accelerometer recording of one scratch:
//!
//! 1. magnitude `m_j = ‖a_j‖₂` per sample, so the feature ignores the sensor's orientation;
//! 2. deviation from a 100-sample moving average (0.25 s at 400 Hz), which removes gravity and
//!    the slow changes of the contact force and keeps the vibration;
//! 3. a spectrogram: real DFTs of 256-sample frames, i.e. the paper's 129 frequency bins;
//! 4. a 5 (time) × 25 (frequency) histogram of the spectrogram, the 125-vector the classifiers
//!    see.
//!
//! The paper fixes the counts (100, 129, 5, 25) but not the frame hop, the window function, the
//! moving average's edges or how a histogram cell is scaled; those choices are documented on the
//! items below.
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
use realfft::{RealFftPlanner, RealToComplex};

use capture::Capture;

/// Length of the moving average the magnitude is compared with (Sinapov: 100 samples, 0.25 s).
pub const MOVING_AVERAGE_LEN: usize = 100;
/// Samples per DFT frame: a 256-point real DFT has the paper's 129 bins (0 … Nyquist).
pub const FRAME_LEN: usize = 256;
/// Frequency bins of one frame's spectrum.
pub const SPECTRUM_BINS: usize = FRAME_LEN / 2 + 1;
/// Hop between frames: half a frame. With a Hann window this overlap weights every sample
/// (away from the ends) equally, so no part of the scratch is missed between frames.
pub const HOP_LEN: usize = FRAME_LEN / 2;
/// Time bins of the histogram (the paper's `k_t`).
pub const TIME_BINS: usize = 5;
/// Frequency bins of the histogram (the paper's `k_f`).
pub const FREQUENCY_BINS: usize = 25;
/// Length of the feature vector.
pub const FEATURE_LEN: usize = TIME_BINS * FREQUENCY_BINS;
/// The fewest frames a spectrogram needs: one per time bin, so that no histogram row is empty.
pub const MIN_FRAMES: usize = TIME_BINS;
/// The fewest samples a recording needs: [`MIN_FRAMES`] frames at [`HOP_LEN`] (768 samples,
/// 1.92 s at 400 Hz; the paper's shortest behaviour lasts 3.9 s).
pub const MIN_SAMPLES: usize = FRAME_LEN + (MIN_FRAMES - 1) * HOP_LEN;

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

/// Euclidean norm per sample.
pub fn magnitude(x: &[f64], y: &[f64], z: &[f64]) -> Result<Vec<f64>, RecognizeError> {
    if x.len() != y.len() || x.len() != z.len() {
        return Err(RecognizeError::AxisLengths {
            x: x.len(),
            y: y.len(),
            z: z.len(),
        });
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
                Err(RecognizeError::NonFiniteSample { index })
            }
        })
        .collect()
}

/// `m_j − m̄_j`, where `m̄_j` is the mean of the [`MOVING_AVERAGE_LEN`] samples centred on `j`
/// (indices `j − 50 … j + 49`).
///
/// Edges: near the ends the window is cut to the samples that exist and the mean is taken over
/// those. Padding with zeros would turn gravity (~9.8 m/s² in the magnitude) into a huge false
/// step at both ends; a causal window would delay the average by 50 samples and leak every force
/// change into the deviation. A recording shorter than the window is averaged as a whole.
pub fn moving_average_deviation(m: &[f64]) -> Vec<f64> {
    let n = m.len();
    let mut prefix = Vec::with_capacity(n + 1);
    prefix.push(0.0);
    let mut acc = 0.0;
    for &v in m {
        acc += v;
        prefix.push(acc);
    }
    let half = MOVING_AVERAGE_LEN / 2;
    (0..n)
        .map(|j| {
            let lo = j.saturating_sub(half);
            let hi = (j + MOVING_AVERAGE_LEN - half).min(n);
            let mean = (prefix[hi] - prefix[lo]) / (hi - lo) as f64;
            m[j] - mean
        })
        .collect()
}

/// Magnitude spectrogram: `frames × SPECTRUM_BINS` values, frame-major.
#[derive(Debug, Clone, PartialEq)]
pub struct Spectrogram {
    frames: usize,
    values: Vec<f64>,
}

impl Spectrogram {
    /// Number of frames (time axis).
    pub fn frames(&self) -> usize {
        self.frames
    }

    /// The [`SPECTRUM_BINS`] magnitudes of one frame, or `None` past the end.
    pub fn frame(&self, index: usize) -> Option<&[f64]> {
        self.values
            .get(index * SPECTRUM_BINS..(index + 1) * SPECTRUM_BINS)
    }
}

/// Computes spectrograms with a planned 256-point real FFT, reusing its buffers.
pub struct SpectrogramPlan {
    fft: Arc<dyn RealToComplex<f64>>,
    window: Vec<f64>,
}

impl std::fmt::Debug for SpectrogramPlan {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SpectrogramPlan")
            .field("frame_len", &FRAME_LEN)
            .field("hop_len", &HOP_LEN)
            .finish()
    }
}

impl Default for SpectrogramPlan {
    fn default() -> Self {
        Self::new()
    }
}

impl SpectrogramPlan {
    /// Plans the FFT. The window is a periodic Hann window: it keeps a tone's energy within
    /// ±1 DFT bin (a rectangular window would spread it over the whole spectrum and blur the 25
    /// frequency bins), and at 50 % overlap its copies sum to a constant.
    pub fn new() -> Self {
        let fft = RealFftPlanner::<f64>::new().plan_fft_forward(FRAME_LEN);
        let window = (0..FRAME_LEN)
            .map(|i| {
                let phase = 2.0 * std::f64::consts::PI * i as f64 / FRAME_LEN as f64;
                0.5 - 0.5 * phase.cos()
            })
            .collect();
        Self { fft, window }
    }

    /// Spectrogram of `signal` (normally the moving-average deviation): frames start every
    /// [`HOP_LEN`] samples, as many as fit entirely (the tail shorter than a hop is dropped).
    /// Magnitudes are `|X_k|` scaled by `2 / Σ window`, so a tone of amplitude `A` peaks at
    /// about `A` whatever the frame length.
    pub fn spectrogram(&self, signal: &[f64]) -> Result<Spectrogram, RecognizeError> {
        if signal.len() < MIN_SAMPLES {
            return Err(RecognizeError::TooShort {
                samples: signal.len(),
                needed: MIN_SAMPLES,
            });
        }
        if let Some(index) = signal.iter().position(|v| !v.is_finite()) {
            return Err(RecognizeError::NonFiniteSample { index });
        }
        let frames = (signal.len() - FRAME_LEN) / HOP_LEN + 1;
        let scale = 2.0 / self.window.iter().sum::<f64>();
        let mut input = self.fft.make_input_vec();
        let mut output = self.fft.make_output_vec();
        let mut values = Vec::with_capacity(frames * SPECTRUM_BINS);
        for f in 0..frames {
            let start = f * HOP_LEN;
            for ((dst, &s), &w) in input
                .iter_mut()
                .zip(&signal[start..start + FRAME_LEN])
                .zip(&self.window)
            {
                *dst = s * w;
            }
            self.fft.process(&mut input, &mut output)?;
            values.extend(output.iter().map(|c| c.norm() * scale));
        }
        Ok(Spectrogram { frames, values })
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
        // Checked before the moving average, which would smear one bad sample over 100.
        if let Some(index) = signal.iter().position(|v| !v.is_finite()) {
            return Err(RecognizeError::NonFiniteSample { index });
        }
        self.signal_features(signal, scale)
    }

    /// Steps 2–4 on a finite per-sample signal (the magnitude, or a single axis).
    fn signal_features(&self, m: &[f64], scale: CellScale) -> Result<[f64; FEATURE_LEN], RecognizeError> {
        if m.len() < MIN_SAMPLES {
            return Err(RecognizeError::TooShort {
                samples: m.len(),
                needed: MIN_SAMPLES,
            });
        }
        let d = moving_average_deviation(m);
        Ok(histogram(&self.spectrogram(&d)?, scale))
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
                .map_err(RecognizeError::NoAccelerometer)?;
            return self.single_axis_features(signal, scale);
        }
        let [x, y, z] = ACCEL_COLUMNS;
        let column = |name| capture.column(name).map_err(RecognizeError::NoAccelerometer);
        self.features(column(x)?, column(y)?, column(z)?, scale)
    }
}

/// Histogram bin of DFT bin `k`: the 129 bins are split into 25 runs of (almost) equal width
/// (5 or 6 DFT bins, 7.8–9.4 Hz at 400 Hz), `⌊k·25/129⌋`.
pub fn frequency_bin(k: usize) -> usize {
    k * FREQUENCY_BINS / SPECTRUM_BINS
}

/// Time bin of frame `f` of `frames`: `⌊f·5/frames⌋`, so each bin holds a fifth of the
/// recording's frames (±1) whatever its length.
pub fn time_bin(f: usize, frames: usize) -> usize {
    f * TIME_BINS / frames.max(1)
}

/// The 5 × 25 spectrotemporal histogram, time-major (`index = t·25 + f`). Each cell is first the
/// mean magnitude of its (frame, DFT bin) pairs, then scaled as `scale` says.
pub fn histogram(spec: &Spectrogram, scale: CellScale) -> [f64; FEATURE_LEN] {
    let mut sum = [0.0; FEATURE_LEN];
    let mut count = [0usize; FEATURE_LEN];
    for f in 0..spec.frames {
        let t = time_bin(f, spec.frames);
        let row = &spec.values[f * SPECTRUM_BINS..(f + 1) * SPECTRUM_BINS];
        for (k, &v) in row.iter().enumerate() {
            let cell = t * FREQUENCY_BINS + frequency_bin(k);
            sum[cell] += v;
            count[cell] += 1;
        }
    }
    let mut out = [0.0; FEATURE_LEN];
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

    fn cell(h: &[f64; FEATURE_LEN], t: usize, f: usize) -> f64 {
        h[t * FREQUENCY_BINS + f]
    }

    #[test]
    fn bins_cover_the_spectrum_evenly() {
        assert_eq!(SPECTRUM_BINS, 129);
        assert_eq!(MIN_SAMPLES, 768);
        assert_eq!(frequency_bin(0), 0);
        assert_eq!(frequency_bin(128), 24);
        for b in 0..FREQUENCY_BINS {
            let width = (0..SPECTRUM_BINS).filter(|&k| frequency_bin(k) == b).count();
            assert!((5..=6).contains(&width), "bin {b} has {width} DFT bins");
        }
        assert_eq!(time_bin(0, 10), 0);
        assert_eq!(time_bin(9, 10), 4);
    }

    #[test]
    fn moving_average_removes_gravity_and_keeps_vibration() {
        let [x, y, z] = tone(1000, 78.125, 0.5, 0);
        let d = moving_average_deviation(&magnitude(&x, &y, &z).expect("equal axes"));
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
        assert_eq!(frequency_bin(50), 9);
        let [x, y, z] = tone(2000, 78.125, 0.5, 0);
        let h = SpectrogramPlan::new()
            .features(&x, &y, &z, CellScale::Mean)
            .expect("long enough");
        for t in 0..TIME_BINS {
            let target = cell(&h, t, 9);
            // Amplitude 0.5 peaks at 0.5 in DFT bin 50, 0.25 in 49 and 51: mean over 5 bins 0.2.
            assert!((target - 0.2).abs() < 0.02, "time bin {t}: {target}");
            for f in (0..FREQUENCY_BINS).filter(|&f| f != 9) {
                assert!(cell(&h, t, f) < 0.01 * target, "leak into ({t}, {f})");
            }
        }
        let unit = SpectrogramPlan::new()
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
        let h = SpectrogramPlan::new()
            .features(&x, &y, &z, CellScale::Mean)
            .expect("long enough");
        let f = frequency_bin((150.0 * FRAME_LEN as f64 / RATE_HZ).round() as usize);
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
        let plan = SpectrogramPlan::new();
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
        let plan = SpectrogramPlan::new();
        let short = vec![0.0; MIN_SAMPLES - 1];
        assert!(matches!(
            plan.features(&short, &short, &short, CellScale::Mean),
            Err(RecognizeError::TooShort {
                samples: 767,
                needed: 768
            })
        ));
        let ok = vec![0.0; MIN_SAMPLES];
        assert!(matches!(
            plan.features(&ok, &short, &ok, CellScale::Mean),
            Err(RecognizeError::AxisLengths {
                x: 768,
                y: 767,
                z: 768
            })
        ));
        let mut nan = ok.clone();
        nan[5] = f64::NAN;
        assert!(matches!(
            plan.features(&ok, &nan, &ok, CellScale::Mean),
            Err(RecognizeError::NonFiniteSample { index: 5 })
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
        let n = MIN_SAMPLES;
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
        let err = SpectrogramPlan::new()
            .capture_features(&capture, CellScale::Mean)
            .expect_err("no y axis");
        assert!(matches!(err, RecognizeError::NoAccelerometer(_)), "{err:?}");
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
        let plan = SpectrogramPlan::new();
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
            plan.single_axis_features(&z[..MIN_SAMPLES - 1], CellScale::Mean),
            Err(RecognizeError::TooShort {
                samples: 767,
                needed: 768
            })
        ));
        let mut nan = z;
        nan[7] = f64::INFINITY;
        assert!(matches!(
            plan.single_axis_features(&nan, CellScale::Mean),
            Err(RecognizeError::NonFiniteSample { index: 7 })
        ));
    }

    #[test]
    fn three_axis_captures_keep_their_features() {
        let plan = SpectrogramPlan::new();
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
            let before = histogram(
                &plan.spectrogram(&moving_average_deviation(&m)).expect("long"),
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
        let plan = SpectrogramPlan::new();
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
        let capture = accel_capture(vec![(capture::kind::FRICTION_FORCE_N, vec![0.0; MIN_SAMPLES])]);
        let err = SpectrogramPlan::new()
            .capture_features(&capture, CellScale::Mean)
            .expect_err("no accelerometer");
        assert!(matches!(err, RecognizeError::NoAccelerometer(_)), "{err:?}");
    }
}
