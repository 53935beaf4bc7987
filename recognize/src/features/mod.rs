//! Features: Nakano's rubbing features ([`nakano`]), Sinapov's spectrotemporal histogram
//! ([`spectral`]), the windows a rubbing capture is cut into ([`NakanoWindowing`]) and the scaling of
//! windowed features ([`WindowScaling`]); and `--features`, which of them a recognizer computes,
//! independently of its classifier.
//!
//! Each method has its own features by default — the SOM Nakano's five rubbing features over
//! sliding windows, k-NN and SVM Sinapov's spectrotemporal histogram of a whole scratch — and
//! [`FeatureSet`] crosses them:
//!
//! - **k-NN / SVM on `nakano`** ([`RecognizerBody::KnnWindows`](crate::RecognizerBody::KnnWindows), [`RecognizerBody::SvmWindows`](crate::RecognizerBody::SvmWindows)):
//!   windowed exactly like the SOM (the same [`NakanoWindowing`]: trained on the training
//!   windows, deciding on the decision windows every hop from 5 mm of travel on), one
//!   classifier over all windows (rubbing has no behaviours), features scaled by
//!   [`WindowScaling`] (the SOM's `LogWithinClass`, without the unit length).
//! - **SOM on `spectral`** ([`RecognizerBody::SomScratches`](crate::RecognizerBody::SomScratches)): one map per behaviour over the
//!   histograms of whole scratches, one decision per scratch, fused over a trial's behaviours
//!   like k-NN and SVM (reliability from cross-validation by trial).
//! - **`both`** (k-NN, SVM: the window variants; SOM: [`RecognizerBody::SomWindows`](crate::RecognizerBody::SomWindows)): each
//!   window of a rubbing capture that also has accelerometer columns (three axes, or the
//!   single-axis `vibration_mps2`) gets Nakano's five features followed by the 125 cells of the
//!   spectrotemporal histogram of the same window's samples.
//! - **`vibration`** (k-NN, SVM: the window variants): each such window's vibration spectrum
//!   alone ([`window_spectrum`]), short enough for anytime decisions; its classifier's evidence
//!   is fused with a Nakano classifier's over time, each weighed by its measured reliability
//!   (`recognize eval --sequential --fuse`).
//! - **`nakano_spectrum`** (k-NN, SVM: the window variants): each window's Nakano features
//!   followed by the spectrum of the tip's height over the same samples ([`window_spectrum`]),
//!   one classifier over both. It needs no sensor beyond Nakano's, so a scene on any device
//!   decides on it live.

pub mod nakano;
mod played_path;
mod scaling;
pub mod spectral;
pub mod window_spectrum;
mod windowing;

use serde::{Deserialize, Serialize};

use crate::InputError;
use crate::{LabelledCapture, RecognizeError};
use nakano::{COMMAND_FORCE_COLUMN, FRICTION_COLUMN, HEIGHT_COLUMN, POSITION_COLUMN};
use spectral::{ACCEL_COLUMNS, FEATURE_LEN, Histogram, SpectrogramPlan, VIBRATION_COLUMN};
use window_spectrum::SPECTRUM_LEN;

pub use played_path::{PlayedPath, TRAVEL_PLAY_M};
pub use scaling::WindowScaling;
pub use windowing::{
    DECISION_WINDOW_S, HOP_S, NakanoWindowing, TRAINING_WINDOW_S, TooFastWindows, TravelWindows, WindowSpan,
    WindowlessCapture,
};
pub(crate) use windowing::{
    NakanoWindows, Travel, WindowVectors, window_vectors, window_vectors_from, windows,
};

/// Which features a recognizer computes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FeatureSet {
    /// Nakano's five rubbing features over sliding windows (the SOM's default).
    Nakano,
    /// Sinapov's spectrotemporal histogram of a whole scratch (k-NN's and SVM's default).
    Spectral,
    /// Per window of a rubbing capture with accelerometer columns (three axes, or a single
    /// vibration axis): the five Nakano features followed by the histogram of the window's
    /// acceleration (130 features).
    Both,
    /// Per window of a rubbing capture with accelerometer columns: the vibration spectrum of
    /// the window alone ([`window_spectrum`], 25 bands), for a classifier whose evidence is
    /// fused with a Nakano classifier's (`recognize eval --sequential --fuse`). The windows are
    /// placed as Nakano's are, so the capture needs their columns too.
    Vibration,
    /// Per window of a rubbing capture: Nakano's five features followed by the spectrum of the
    /// tip's height over the same window ([`window_spectrum`], 25 bands; 30 features). It reads
    /// only what Nakano's features read, the encoder at the loop rate, so every device has it:
    /// the spectrum says at which wavelengths the surface is rough, where Nakano's roughness
    /// says only how rough, and it speaks from the window's first millimetre.
    NakanoSpectrum,
}

impl FeatureSet {
    /// `nakano`, `spectral` or `both`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Nakano => "nakano",
            Self::Spectral => "spectral",
            Self::Both => "both",
            Self::Vibration => "vibration",
            Self::NakanoSpectrum => "nakano_spectrum",
        }
    }

    /// Length of the feature vector.
    pub fn dim(self) -> usize {
        match self {
            Self::Nakano => nakano::FEATURES,
            Self::Spectral => FEATURE_LEN,
            Self::Both => nakano::FEATURES + FEATURE_LEN,
            Self::Vibration => SPECTRUM_LEN,
            Self::NakanoSpectrum => nakano::FEATURES + SPECTRUM_LEN,
        }
    }

    /// Lengths of the feature sets the vector concatenates, in order.
    pub fn blocks(self) -> &'static [usize] {
        match self {
            Self::Nakano => &[nakano::FEATURES],
            Self::Spectral => &[FEATURE_LEN],
            Self::Both => &[nakano::FEATURES, FEATURE_LEN],
            Self::Vibration => &[SPECTRUM_LEN],
            Self::NakanoSpectrum => &[nakano::FEATURES, SPECTRUM_LEN],
        }
    }

    /// Names of the features, in vector order.
    pub fn feature_names(self) -> Vec<String> {
        let nakano = nakano::FEATURE_NAMES.iter().map(|s| (*s).to_owned());
        match self {
            Self::Nakano => nakano.collect(),
            Self::Spectral => histogram_names(),
            Self::Both => nakano.chain(histogram_names()).collect(),
            Self::Vibration => (0..SPECTRUM_LEN).map(|b| format!("spectrum_f{b}")).collect(),
            Self::NakanoSpectrum => nakano
                .chain((0..SPECTRUM_LEN).map(|b| format!("height_spectrum_f{b}")))
                .collect(),
        }
    }

    /// The columns of `capture` these features need but it lacks (empty when it has them all).
    /// Nakano's friction comes from `friction_force_n` or, without it, from the reaction-force
    /// observer over `tangential_command_force_n`. `spectral` and `both` read the three
    /// accelerometer axes or, without them, the single-axis `vibration_mps2`.
    pub fn missing_columns(self, capture: &LabelledCapture) -> Vec<String> {
        let has = |name: &str| capture.capture.columns().iter().any(|c| c == name);
        let mut missing = Vec::new();
        if matches!(
            self,
            Self::Nakano | Self::Both | Self::Vibration | Self::NakanoSpectrum
        ) {
            for name in [POSITION_COLUMN, HEIGHT_COLUMN] {
                if !has(name) {
                    missing.push(name.to_owned());
                }
            }
            if !has(FRICTION_COLUMN) && !has(COMMAND_FORCE_COLUMN) {
                missing.push(format!("{FRICTION_COLUMN} (or {COMMAND_FORCE_COLUMN})"));
            }
        }
        if matches!(self, Self::Spectral | Self::Both | Self::Vibration) {
            let before = missing.len();
            missing.extend(ACCEL_COLUMNS.iter().filter(|c| !has(c)).map(|c| (*c).to_owned()));
            // The histogram (of a whole scratch, or of each window for `both`) also works
            // from one axis.
            if missing.len() > before {
                if has(VIBRATION_COLUMN) {
                    missing.truncate(before);
                } else if let Some(last) = missing.last_mut() {
                    last.push_str(&format!(" (or, instead of the three axes, {VIBRATION_COLUMN})"));
                }
            }
        }
        missing
    }

    /// A typed error for the first capture that lacks a column these features need.
    pub fn check_columns(self, captures: &[LabelledCapture]) -> Result<(), RecognizeError> {
        for c in captures {
            let missing = self.missing_columns(c);
            if !missing.is_empty() {
                return Err(RecognizeError::Input(InputError::MissingColumns {
                    path: c.reference.path.clone(),
                    features: self.name(),
                    missing,
                }));
            }
        }
        Ok(())
    }
}

impl std::fmt::Display for FeatureSet {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Names of the spectrotemporal histogram's cells, time-major.
pub(crate) fn histogram_names() -> Vec<String> {
    (0..FEATURE_LEN)
        .map(|i| {
            format!(
                "histogram_t{}_f{}",
                i / spectral::FREQUENCY_BINS,
                i % spectral::FREQUENCY_BINS
            )
        })
        .collect()
}

/// Sinapov's histogram of a whole capture, at the capture's rate.
pub(crate) fn capture_histogram(
    c: &LabelledCapture,
    histogram: Histogram,
) -> Result<[f64; FEATURE_LEN], RecognizeError> {
    if let Some(kept) = c.kept() {
        return kept
            .histogram(histogram)
            .copied()
            .ok_or_else(|| c.not_kept(format!("the histogram of the whole capture ({histogram})")));
    }
    SpectrogramPlan::over_band(c.capture.metadata().rate_hz(), histogram.band)
        .and_then(|plan| plan.capture_features(&c.capture, histogram.cells))
        .map_err(|source| RecognizeError::Features {
            path: c.reference.path.clone(),
            features: "spectrotemporal",
            source: Box::new(source),
        })
}
