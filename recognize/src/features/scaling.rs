//! The feature scaling of the k-NN and SVM over windows.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

#[cfg(doc)]
use crate::{knn::FeatureScaling, som::Normalization};

/// Feature scaling of the k-NN and SVM over windows, learned from the training windows: the
/// SOM's [`Normalization::LogWithinClass`] without its last step. A feature positive over all
/// training windows (amplitudes, variances, wavelengths, mean friction, histogram cells) is
/// replaced by its logarithm (values below a thousandth of the smallest training value are taken
/// as that floor); every feature is centred on the training mean and divided by its pooled
/// within-class standard deviation (a constant feature is left unscaled).
///
/// Unlike the SOM, vectors are *not* normalised to unit length: the map's winner is an inner
/// product of unit vectors, whereas k-NN's Euclidean distance and the SVM's polynomial kernel
/// use the whole vector, and a window's distance from the mean is information (a surface far
/// from all others on every feature). The classifiers themselves then scale nothing
/// ([`FeatureScaling::None`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct WindowScaling {
    /// Per feature: `Some(floor)` where the feature is taken on a log scale.
    pub log_floor: Vec<Option<f64>>,
    /// Per feature: the training mean (after the log).
    pub offset: Vec<f64>,
    /// Per feature: the pooled within-class standard deviation (after the log).
    pub scale: Vec<f64>,
}

impl WindowScaling {
    /// Learns the scaling from `data` (non-empty, equal dimensions, finite) and its labels.
    pub fn fit(data: &[Vec<f64>], labels: &[usize]) -> Self {
        let dim = data.first().map_or(0, Vec::len);
        let n = data.len().max(1) as f64;
        let log_floor: Vec<Option<f64>> = (0..dim)
            .map(|j| {
                let min = data.iter().map(|v| v[j]).fold(f64::INFINITY, f64::min);
                (min > 0.0 && min.is_finite()).then_some(min * 1e-3)
            })
            .collect();
        let value = |j: usize, x: f64| match log_floor[j] {
            Some(floor) => x.max(floor).ln(),
            None => x,
        };
        let mut offset = vec![0.0; dim];
        let mut scale = vec![1.0; dim];
        for j in 0..dim {
            let mut by_class: BTreeMap<usize, (f64, f64)> = BTreeMap::new();
            let mut total = 0.0;
            for (v, &l) in data.iter().zip(labels) {
                let x = value(j, v[j]);
                total += x;
                let e = by_class.entry(l).or_default();
                e.0 += 1.0;
                e.1 += x;
            }
            let within: f64 = data
                .iter()
                .zip(labels)
                .map(|(v, l)| {
                    let (count, sum) = by_class[l];
                    (value(j, v[j]) - sum / count).powi(2)
                })
                .sum();
            let s = (within / n).sqrt();
            offset[j] = total / n;
            scale[j] = if s > 0.0 && s.is_finite() { s } else { 1.0 };
        }
        Self {
            log_floor,
            offset,
            scale,
        }
    }

    /// The scaled vector.
    pub fn apply(&self, features: &[f64]) -> Vec<f64> {
        features
            .iter()
            .zip(self.log_floor.iter().zip(self.offset.iter().zip(&self.scale)))
            .map(|(&x, (floor, (o, s)))| {
                let x = match floor {
                    Some(floor) => x.max(*floor).ln(),
                    None => x,
                };
                (x - o) / s
            })
            .collect()
    }

    /// Number of features.
    pub fn dim(&self) -> usize {
        self.offset.len()
    }

    /// Checks a scaling read from a file against `dim` features: `Err(reason)`.
    pub fn check(&self, dim: usize) -> Result<(), String> {
        if self.offset.len() != dim || self.scale.len() != dim || self.log_floor.len() != dim {
            return Err(format!("expected {dim} log floors, offsets and scales"));
        }
        let ok = self.offset.iter().all(|o| o.is_finite())
            && self.scale.iter().all(|s| s.is_finite() && *s > 0.0)
            && self.log_floor.iter().flatten().all(|f| f.is_finite() && *f > 0.0);
        if ok {
            Ok(())
        } else {
            Err(
                "a non-finite offset, a scale that is not positive or a log floor that is not positive"
                    .into(),
            )
        }
    }
}
