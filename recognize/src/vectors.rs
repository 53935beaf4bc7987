//! Input checks and feature scaling of the vector classifiers ([`crate::knn::Knn`] and
//! [`crate::svc::Svc`]): both take the same vectors, reject the same faults and scale
//! features the same way, so that a recognizer's k-NN and SVM see identical inputs.

use crate::RecognizeError;
use crate::{InputError, UsageError};

/// How features are scaled before distances are taken.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FeatureScaling {
    /// Raw values.
    None,
    /// Each feature mapped to `[0, 1]` by the training set's minimum and maximum (WEKA `IBk`'s
    /// default, hence the paper's). A feature that is constant in training maps to 0. Without it
    /// the few loud low-frequency cells would decide every distance.
    #[default]
    MinMax,
}

/// A caller's buffer of `got` values where the classifier needs `expected` (one per class, one
/// per feature, …) is refused, naming `what` it holds.
pub(crate) fn check_buffer(what: &'static str, got: usize, expected: usize) -> Result<(), RecognizeError> {
    if got == expected {
        Ok(())
    } else {
        Err(RecognizeError::Usage(UsageError::Buffer { what, got, expected }))
    }
}

/// The first fault of the training vectors in order: each must have `dim` finite values and a
/// label below `classes`.
pub(crate) fn check_labelled<V: AsRef<[f64]>>(
    features: &[V],
    labels: &[usize],
    dim: usize,
    classes: usize,
) -> Result<(), RecognizeError> {
    for (index, (f, &label)) in features.iter().zip(labels).enumerate() {
        check_vector(index, f.as_ref(), dim)?;
        if label >= classes {
            return Err(RecognizeError::Usage(UsageError::LabelOutOfRange {
                index,
                label,
                classes,
            }));
        }
    }
    Ok(())
}

/// A query must have `dim` finite values; it is reported as vector 0.
pub(crate) fn check_query(query: &[f64], dim: usize) -> Result<(), RecognizeError> {
    check_vector(0, query, dim)
}

fn check_vector(index: usize, f: &[f64], dim: usize) -> Result<(), RecognizeError> {
    if f.len() != dim {
        return Err(RecognizeError::Usage(UsageError::Dimension {
            index,
            expected: dim,
            got: f.len(),
        }));
    }
    if f.iter().any(|v| !v.is_finite()) {
        return Err(RecognizeError::Input(InputError::NonFinite { index }));
    }
    Ok(())
}

impl FeatureScaling {
    /// Per feature, the `(offset, factor)` that maps a value `v` to `(v − offset)·factor`,
    /// fitted on `features` (each of `dim` values).
    pub(crate) fn fit<V: AsRef<[f64]>>(self, features: &[V], dim: usize) -> Vec<(f64, f64)> {
        match self {
            Self::None => vec![(0.0, 1.0); dim],
            Self::MinMax => (0..dim)
                .map(|j| {
                    let (lo, hi) = features
                        .iter()
                        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), f| {
                            let v = f.as_ref()[j];
                            (lo.min(v), hi.max(v))
                        });
                    let range = hi - lo;
                    (lo, if range > 0.0 { 1.0 / range } else { 0.0 })
                })
                .collect(),
        }
    }
}

/// `features` scaled by `scale` ([`FeatureScaling::fit`]), one row after another.
pub(crate) fn scaled_rows<V: AsRef<[f64]>>(features: &[V], scale: &[(f64, f64)]) -> Vec<f64> {
    let mut points = Vec::with_capacity(features.len() * scale.len());
    for f in features {
        points.extend(scaled(f.as_ref(), scale));
    }
    points
}

/// `v` scaled by `scale` ([`FeatureScaling::fit`]).
pub(crate) fn scaled<'a>(v: &'a [f64], scale: &'a [(f64, f64)]) -> impl Iterator<Item = f64> + 'a {
    v.iter().zip(scale).map(|(v, (o, s))| (v - o) * s)
}
