//! A capture with its class and behaviour, as the recognizer sees it, and the classes of a set
//! of them.

use std::collections::BTreeSet;
use std::path::Path;
use std::sync::Arc;

use crate::InputError;
use crate::RecognizeError;
use crate::features::spectral::{FEATURE_LEN, Histogram};
use crate::features::{FeatureSet, NakanoWindowing, Travel, WindowVectors};
use capture::{Capture, CaptureKind, CaptureRef, sha256_hex};

/// Metadata key of a capture's class.
pub const LABEL_KEY: &str = "surface";
/// Metadata key of a scratch's exploratory behaviour.
pub const BEHAVIOUR_KEY: &str = "behaviour";
/// Metadata key of the surface a stroke slides onto part-way, when it does (its class after
/// the change; [`SURFACE_CHANGE_S_KEY`] says when).
pub const SURFACE_AFTER_KEY: &str = "surface_after";
/// Metadata key of the time, s from the capture's first sample, at which the tool passes onto
/// the surface [`SURFACE_AFTER_KEY`] names.
pub const SURFACE_CHANGE_S_KEY: &str = "surface_change_s";

/// A stroke that slides from its labelled surface onto another part-way.
#[derive(Debug, Clone, PartialEq)]
pub struct SurfaceChange {
    /// The class from the change on.
    pub after: String,
    /// When the change happens, s from the capture's first sample.
    pub at_s: f64,
}

/// A capture with its class, behaviour and hash, as the recognizer sees it.
///
/// [`LabelledCapture::keep_features`] computes the features a training or an evaluation will
/// read and drops the samples, so that many high-rate captures fit in memory.
#[derive(Debug, Clone)]
pub struct LabelledCapture {
    /// The capture; after [`LabelledCapture::keep_features`] only its header, its columns and
    /// its first sample ([`LabelledCapture::has_samples`] says which, and
    /// [`LabelledCapture::samples`] counts the samples it had).
    pub capture: Capture,
    /// Its class (metadata `surface`).
    pub label: String,
    /// Its exploratory behaviour (metadata `behaviour`), if any.
    pub behaviour: Option<String>,
    /// Where the stroke slides onto another surface (metadata `surface_after` and
    /// `surface_change_s`), if it does.
    pub change: Option<SurfaceChange>,
    /// Where it was read from, and the SHA-256 of its bytes.
    pub reference: CaptureRef,
    /// The features computed before the samples were dropped; `None` while it has them.
    pub(crate) kept: Option<Arc<KeptFeatures>>,
}

impl LabelledCapture {
    /// Reads a `rubbing` capture and its label; a capture without a `surface` in its metadata
    /// is an error naming the file.
    pub fn read(path: &Path) -> Result<Self, RecognizeError> {
        let bytes = std::fs::read(path).map_err(|source| {
            RecognizeError::Input(InputError::Io {
                path: path.to_owned(),
                source,
            })
        })?;
        let capture = Capture::read_from(bytes.as_slice(), path, Some(CaptureKind::Rubbing))?;
        Self::new(capture, path, sha256_hex(&bytes))
    }

    /// Labels a capture already in memory; `path` and `sha256` identify it in the model.
    pub fn new(capture: Capture, path: &Path, sha256: String) -> Result<Self, RecognizeError> {
        let meta = capture.metadata();
        let label = meta
            .get(LABEL_KEY)
            .filter(|l| !l.is_empty())
            .ok_or_else(|| {
                RecognizeError::Input(InputError::UnusableCapture {
                    path: path.to_owned(),
                    reason: format!("metadata has no `{LABEL_KEY}`: the class of a capture comes from it"),
                })
            })?
            .to_owned();
        let behaviour = meta.get(BEHAVIOUR_KEY).map(str::to_owned);
        let unusable = |reason: String| {
            RecognizeError::Input(InputError::UnusableCapture {
                path: path.to_owned(),
                reason,
            })
        };
        let change = match (meta.get(SURFACE_AFTER_KEY), meta.get(SURFACE_CHANGE_S_KEY)) {
            (None, None) => None,
            (Some(after), Some(at)) => {
                let at_s = at.trim().parse::<f64>().ok().filter(|t| t.is_finite() && *t >= 0.0).ok_or_else(|| {
                    unusable(format!(
                        "metadata `{SURFACE_CHANGE_S_KEY}` = `{at}`: expected the seconds into the capture at which the surface changes"
                    ))
                })?;
                Some(SurfaceChange {
                    after: after.to_owned(),
                    at_s,
                })
            }
            (Some(_), None) | (None, Some(_)) => {
                return Err(unusable(format!(
                    "metadata has only one of `{SURFACE_AFTER_KEY}` and `{SURFACE_CHANGE_S_KEY}`: a change of surface needs both"
                )));
            }
        };
        Ok(Self {
            capture,
            label,
            behaviour,
            change,
            reference: CaptureRef {
                path: path.to_owned(),
                sha256,
            },
            kept: None,
        })
    }
}

/// The windows of one windowing kept for a capture.
#[derive(Debug)]
pub(crate) struct KeptWindows {
    pub(super) windowing: NakanoWindowing,
    pub(super) features: FeatureSet,
    pub(super) histogram: Histogram,
    /// Start, span and feature vector of each readable window, and those left out.
    pub(super) vectors: WindowVectors,
}

/// The features a capture kept when its samples were dropped.
#[derive(Debug)]
pub(crate) struct KeptFeatures {
    /// Samples the capture had.
    pub(super) samples: usize,
    /// How far its tip travelled, for the reason a capture gave no window.
    pub(super) travel: Travel,
    /// Its tool's path ([`LabelledCapture::played_path`]) at each sample a kept window is
    /// decided at and at its change of surface, in order of sample, m: how far a decision came
    /// into a stroke.
    pub(super) path_m: Vec<(usize, f64)>,
    pub(super) windows: Vec<KeptWindows>,
    pub(super) histograms: Vec<(Histogram, [f64; FEATURE_LEN])>,
}

impl KeptFeatures {
    /// Samples the capture had.
    pub(crate) fn samples(&self) -> usize {
        self.samples
    }

    /// How far its tip travelled.
    pub(crate) fn travel(&self) -> &Travel {
        &self.travel
    }

    /// The kept vectors of the windows `windowing` picks, of `features` (`histogram` matters
    /// for [`FeatureSet::Both`] only). Nakano's five features are also the first five of
    /// `both`'s vectors, so either serves a request for them.
    pub(crate) fn windows(
        &self,
        windowing: &NakanoWindowing,
        features: FeatureSet,
        histogram: Histogram,
    ) -> Option<&WindowVectors> {
        self.windows
            .iter()
            .find(|k| {
                k.windowing == *windowing
                    && match features {
                        FeatureSet::Nakano => matches!(k.features, FeatureSet::Nakano | FeatureSet::Both),
                        _ => k.features == features && k.histogram == histogram,
                    }
            })
            .map(|k| &k.vectors)
    }

    /// The kept histogram of cells scaled by `histogram`.
    pub(crate) fn histogram(&self, histogram: Histogram) -> Option<&[f64; FEATURE_LEN]> {
        self.histograms
            .iter()
            .find(|(s, _)| *s == histogram)
            .map(|(_, h)| h)
    }
}

/// The sorted distinct labels of `captures`.
pub(crate) fn class_list(captures: &[LabelledCapture]) -> Vec<String> {
    let set: BTreeSet<&str> = captures.iter().map(|c| c.label.as_str()).collect();
    set.into_iter().map(str::to_owned).collect()
}

/// Index of the capture's class among `classes`.
pub(crate) fn class_index(classes: &[String], c: &LabelledCapture) -> Result<usize, RecognizeError> {
    class_position(classes, &c.label, c, "surface")
}

/// The index of `name` among `classes`, for capture `c`'s change of surface.
pub(crate) fn class_named(
    classes: &[String],
    name: &str,
    c: &LabelledCapture,
) -> Result<usize, RecognizeError> {
    class_position(classes, name, c, &format!("`{SURFACE_AFTER_KEY}`"))
}

/// The index of `name` among `classes`; an error names capture `c` and `what` `name` is.
fn class_position(
    classes: &[String],
    name: &str,
    c: &LabelledCapture,
    what: &str,
) -> Result<usize, RecognizeError> {
    classes.iter().position(|l| l == name).ok_or_else(|| {
        RecognizeError::Input(InputError::UnusableCapture {
            path: c.reference.path.clone(),
            reason: format!("{what} `{name}` is not one the recognizer was trained on"),
        })
    })
}

/// A capture must be sampled at the rate the windows are counted at.
pub(crate) fn check_rate(c: &LabelledCapture, rate_hz: f64) -> Result<(), RecognizeError> {
    let found = c.capture.metadata().rate_hz();
    if (found - rate_hz).abs() > 1e-9 * rate_hz {
        return Err(RecognizeError::Input(InputError::UnusableCapture {
            path: c.reference.path.clone(),
            reason: format!("sampled at {found} Hz; the recognizer's windows are counted at {rate_hz} Hz"),
        }));
    }
    Ok(())
}
