//! Nakano's one-dimensional self-organizing map (thesis Sec. 2.3, Table 3.3, Eq. 3.1).
//!
//! Training, exactly as the thesis: `s` nodes on a line, each with a unit reference vector drawn
//! at random; `Z` times, a training vector `p` chosen at random is presented, the winner is the
//! node of largest inner product (Eq. 2.27), and every node `q` moves towards `p` by
//! `h_q = α_i · exp(−(q − c)² / 2σ²)` (Eq. 2.28) and is renormalised,
//! `m_q ← (m_q + h_q p) / ‖m_q + h_q p‖` (Eq. 2.29), with `α_i = α₀ (1 − i/Z)`, `i = 1…Z`
//! (Eq. 3.1). Defaults are Table 3.3's: 12 nodes, σ = 1.6, Z = 10 000, α₀ = 0.3.
//!
//! **Normalisation.** Eq. 2.26 scales each feature by its L2 norm over the data so every feature
//! has amplitude 1 ([`Normalization::ThesisColumnNorm`]); the winner then compares directions of
//! the scaled vectors. With Nakano's features, all positive, every vector lies in one orthant and
//! the directions crowd together. [`Normalization::Standardize`] centres and scales each feature
//! by the training set's mean and standard deviation, then normalises each vector to unit
//! length, which spreads the classes over the whole sphere. [`Normalization::LogWithinClass`]
//! (the default) goes two steps further, each for a reason that holds for any scale-type
//! feature, not for one data set:
//! - features positive throughout training (amplitudes, variances, wavelengths, mean friction)
//!   are compared on a log scale: their noise grows with their size (a variance estimated over
//!   a window has a relative, not an absolute, spread), and a log makes it uniform;
//! - each feature is divided by its *pooled within-class* standard deviation, not its total one:
//!   a feature then counts by how well it separates classes relative to its own noise (Fisher's
//!   criterion, diagonal). Nakano's mean friction varies by ~1 % within a surface and by ~10 %
//!   between surfaces; standardising by the total spread ranks it with the noisy roughness
//!   variances.
//!
//! Both are deviations from a literal reading of Eq. 2.26 (the map, its training and the
//! inner-product winner are the thesis's); the scaling is learned from the training data only
//! and applied unchanged to test data. `tests/it/recognition_nakano.rs` tabulates all three.
//!
//! **Labels.** Each node takes the majority label of the training vectors it wins (ties to the
//! smallest label); a node that wins none takes the label of the nearest labelled node along the
//! line (ties to the lower index), so every node answers.
//!
//! Randomness comes from `capture::rng::SplitMix64`: the map must be reproducible from its seed
//! alone, on every platform and across dependency upgrades.

use std::collections::BTreeMap;

use capture::rng::SplitMix64;
use serde::{Deserialize, Serialize};
// Partial sums from 16 features on: the winner search over a map of histograms is most of its
// training. Nakano's five features keep the running sum, and their maps the same bits.
use svm::dot;

use crate::RecognizeError;
use crate::svc::{FitEvent, Progress, no_progress};
use crate::{DataError, InputError, SettingError, UsageError};

/// How features are scaled before the map sees them (see the module doc).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum Normalization {
    /// Eq. 2.26 literally: each feature divided by its L2 norm over the training set.
    ThesisColumnNorm,
    /// Each feature standardised by the training set's mean and standard deviation, then each
    /// vector normalised to unit length.
    Standardize,
    /// Features positive over the whole training set replaced by their logarithm; each feature
    /// centred on the training mean and divided by its pooled within-class standard deviation;
    /// then each vector normalised to unit length.
    #[default]
    LogWithinClass,
}

/// SOM hyperparameters, validated by [`SomParams::check`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SomParams {
    /// Number of nodes `s` (Table 3.3: 12).
    pub nodes: usize,
    /// Standard deviation σ of the neighbourhood, in node spacings (Table 3.3: 1.6).
    pub sigma: f64,
    /// Training presentations `Z` (Table 3.3: 10 000).
    pub iterations: usize,
    /// Initial learning rate α₀ of Eq. 3.1 (0.3).
    pub initial_learning_rate: f64,
    /// How features are scaled.
    pub normalization: Normalization,
    /// Seed of the initial reference vectors and the order of presentation.
    pub seed: u64,
}

impl Default for SomParams {
    fn default() -> Self {
        Self {
            nodes: 12,
            sigma: 1.6,
            iterations: 10_000,
            initial_learning_rate: 0.3,
            normalization: Normalization::default(),
            seed: 0,
        }
    }
}

impl SomParams {
    /// Checks every parameter's range.
    pub fn check(&self) -> Result<(), RecognizeError> {
        let bad = |name, value, reason| {
            Err(RecognizeError::Setting(SettingError::Parameter {
                of: "SOM parameter",
                name,
                value,
                reason,
            }))
        };
        if self.nodes == 0 {
            return bad("nodes", 0.0, "at least 1");
        }
        if !(self.sigma.is_finite() && self.sigma > 0.0) {
            return bad("sigma", self.sigma, "positive and finite");
        }
        if !(self.initial_learning_rate.is_finite() && self.initial_learning_rate > 0.0) {
            return bad(
                "initial_learning_rate",
                self.initial_learning_rate,
                "positive and finite",
            );
        }
        Ok(())
    }
}

/// Feature scaling learned from training data.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Scaling {
    normalization: Normalization,
    offset: Vec<f64>,
    scale: Vec<f64>,
    /// Per feature, for [`Normalization::LogStandardize`]: `Some(floor)` when the feature is
    /// compared on a log scale (values below `floor` are taken as `floor`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    log_floor: Vec<Option<f64>>,
}

impl Scaling {
    /// Learns the scaling of `normalization` from `data` (non-empty, equal dimensions, finite).
    fn fit<L: Ord>(normalization: Normalization, data: &[Vec<f64>], labels: &[L]) -> Self {
        let dim = data.first().map_or(0, Vec::len);
        let n = data.len() as f64;
        let mut offset = vec![0.0; dim];
        let mut scale = vec![1.0; dim];
        let log_floor: Vec<Option<f64>> = if normalization == Normalization::LogWithinClass {
            (0..dim)
                .map(|j| {
                    let min = data.iter().map(|v| v[j]).fold(f64::INFINITY, f64::min);
                    // A thousandth of the smallest training value: far below every class seen,
                    // yet finite for a test window that is flatter than any training one.
                    (min > 0.0 && min.is_finite()).then_some(min * 1e-3)
                })
                .collect()
        } else {
            Vec::new()
        };
        let value = |j: usize, x: f64| match log_floor.get(j) {
            Some(Some(floor)) => x.max(*floor).ln(),
            _ => x,
        };
        for j in 0..dim {
            let column = data.iter().map(|v| value(j, v[j]));
            let (o, s) = match normalization {
                Normalization::ThesisColumnNorm => (0.0, column.map(|x| x * x).sum::<f64>().sqrt()),
                Normalization::Standardize => {
                    let mean = column.clone().sum::<f64>() / n;
                    (mean, (column.map(|x| (x - mean).powi(2)).sum::<f64>() / n).sqrt())
                }
                Normalization::LogWithinClass => {
                    let mean = column.clone().sum::<f64>() / n;
                    let mut by_class: BTreeMap<&L, (f64, f64)> = BTreeMap::new();
                    for (x, l) in column.zip(labels) {
                        let e = by_class.entry(l).or_default();
                        e.0 += 1.0;
                        e.1 += x;
                    }
                    let mut within = 0.0;
                    for (v, l) in data.iter().zip(labels) {
                        let (count, sum) = by_class[l];
                        within += (value(j, v[j]) - sum / count).powi(2);
                    }
                    (mean, (within / n).sqrt())
                }
            };
            offset[j] = o;
            // A constant (or all-zero) feature carries no information: leave it unscaled.
            scale[j] = if s > 0.0 && s.is_finite() { s } else { 1.0 };
        }
        Self {
            normalization,
            offset,
            scale,
            log_floor,
        }
    }

    /// The vector the map sees for `features`: scaled, then (except for Eq. 2.26's column norms) unit length.
    pub fn apply(&self, features: &[f64]) -> Vec<f64> {
        let mut v = vec![0.0; features.len().min(self.offset.len())];
        self.apply_into(features, &mut v);
        v
    }

    /// [`Scaling::apply`] into `out` without allocating; writes `min(len)` values of the three.
    pub fn apply_into(&self, features: &[f64], out: &mut [f64]) {
        for (j, (o, (x, (off, s)))) in out
            .iter_mut()
            .zip(features.iter().zip(self.offset.iter().zip(&self.scale)))
            .enumerate()
        {
            let x = match self.log_floor.get(j) {
                Some(Some(floor)) => x.max(*floor).ln(),
                _ => *x,
            };
            *o = (x - off) / s;
        }
        if self.normalization != Normalization::ThesisColumnNorm {
            normalize(out);
        }
    }

    /// Number of features.
    pub fn dim(&self) -> usize {
        self.offset.len()
    }

    /// How features are scaled.
    pub fn normalization(&self) -> Normalization {
        self.normalization
    }
}

/// Scales `v` to unit length; a zero vector stays zero (it matches every node equally).
fn normalize(v: &mut [f64]) -> bool {
    let norm = v.iter().map(|x| x * x).sum::<f64>().sqrt();
    if norm > 0.0 && norm.is_finite() {
        v.iter_mut().for_each(|x| *x /= norm);
        true
    } else {
        false
    }
}

/// A map's answer for one feature vector.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SomDecision {
    /// The winning node.
    pub node: usize,
    /// Half the inner-product margin over the best node of another label, in `[0, 1]`.
    pub confidence: f64,
}

/// A trained, labelled 1-D SOM.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Som<L> {
    params: SomParams,
    scaling: Scaling,
    /// Unit reference vectors, one per node, in line order.
    reference: Vec<Vec<f64>>,
    /// Label of each node.
    labels: Vec<L>,
    /// Training vectors each node won (the data-density histogram, Fig. 4.13).
    hits: Vec<usize>,
}

impl<L: Clone + Ord> Som<L> {
    /// Trains a map on `data` (one feature vector per row) and labels its nodes with `labels`.
    pub fn train(params: SomParams, data: &[Vec<f64>], labels: &[L]) -> Result<Self, RecognizeError> {
        Self::train_observed(params, data, labels, &no_progress)
    }

    /// [`Som::train`], telling `progress` of the presentations (one step of at most 100 units):
    /// a map sized by its data over both feature sets takes seconds.
    pub fn train_observed(
        params: SomParams,
        data: &[Vec<f64>],
        labels: &[L],
        progress: Progress<'_>,
    ) -> Result<Self, RecognizeError> {
        params.check()?;
        if data.is_empty() {
            return Err(RecognizeError::Data(DataError::Empty));
        }
        if data.len() != labels.len() {
            return Err(RecognizeError::Usage(UsageError::Counts {
                features: data.len(),
                labels: labels.len(),
            }));
        }
        let dim = data[0].len();
        for (index, v) in data.iter().enumerate() {
            if v.len() != dim {
                return Err(RecognizeError::Usage(UsageError::Dimension {
                    index,
                    got: v.len(),
                    expected: dim,
                }));
            }
            if v.iter().any(|x| !x.is_finite()) {
                return Err(RecognizeError::Input(InputError::NonFinite { index }));
            }
        }
        let scaling = Scaling::fit(params.normalization, data, labels);
        let inputs: Vec<Vec<f64>> = data.iter().map(|v| scaling.apply(v)).collect();
        let mut rng = SplitMix64::new(params.seed);
        // Random unit reference vectors, components uniform in [−1, 1) (redrawn if zero).
        let reference: Vec<Vec<f64>> = (0..params.nodes)
            .map(|_| {
                loop {
                    let mut m: Vec<f64> = (0..dim).map(|_| 2.0 * rng.next_f64() - 1.0).collect();
                    if normalize(&mut m) || dim == 0 {
                        break m;
                    }
                }
            })
            .collect();
        let mut som = Self {
            params,
            scaling,
            reference,
            labels: Vec::new(),
            hits: vec![0; params.nodes],
        };
        let z = params.iterations as f64;
        let two_sigma2 = 2.0 * params.sigma * params.sigma;
        let mut moved = vec![0.0; dim];
        // The neighbourhood is Gaussian, and nodes farther from the winner than `reach` would
        // move by h < α·2⁻⁵³, less than double precision resolves on a unit vector: they are
        // left out of the update. On a map sized by its data (246 nodes for 1,300 windows)
        // that is all but 27 of them, and most of the training's time.
        let reach = (two_sigma2 * 53.0 * std::f64::consts::LN_2).sqrt().floor() as usize;
        let every = params.iterations.div_ceil(100).max(1);
        progress(FitEvent::Step {
            what: "training the map",
            total: params.iterations / every,
        });
        for i in 1..=params.iterations {
            if i % every == 0 {
                progress(FitEvent::Advance);
            }
            let alpha = params.initial_learning_rate * (1.0 - i as f64 / z);
            let p = &inputs[rng.below(inputs.len())];
            let winner = som.winner_scaled(p);
            let (first, last) = (
                winner.saturating_sub(reach),
                winner.saturating_add(reach).min(params.nodes - 1),
            );
            for (q, m) in (first..=last).zip(&mut som.reference[first..=last]) {
                let d = q as f64 - winner as f64;
                let h = alpha * (-d * d / two_sigma2).exp();
                for ((out, mi), pi) in moved.iter_mut().zip(m.iter()).zip(p) {
                    *out = mi + h * pi;
                }
                // ‖m + h p‖ ≥ 1 − h > 0 for unit m and h ≤ α₀ < 1; if a huge α₀ cancels it
                // exactly, the node keeps its old vector.
                if normalize(&mut moved) {
                    m.copy_from_slice(&moved);
                }
            }
        }
        // Label nodes by majority vote of the training vectors they win.
        let mut votes: Vec<BTreeMap<&L, usize>> = vec![BTreeMap::new(); params.nodes];
        for (p, label) in inputs.iter().zip(labels) {
            let c = som.winner_scaled(p);
            som.hits[c] += 1;
            *votes[c].entry(label).or_default() += 1;
        }
        let majority: Vec<Option<L>> = votes
            .iter()
            .map(|v| {
                // max_by_key returns the last maximum; iterate in reverse for the smallest label.
                v.iter().rev().max_by_key(|(_, n)| **n).map(|(l, _)| (*l).clone())
            })
            .collect();
        som.labels = (0..params.nodes)
            .filter_map(|q| {
                (0..params.nodes)
                    .filter_map(|r| majority[r].as_ref().map(|l| (q.abs_diff(r), r, l)))
                    .min_by_key(|(d, r, _)| (*d, *r))
                    .map(|(_, _, l)| l.clone())
            })
            .collect();
        Ok(som)
    }

    /// Winner for an already scaled vector (Eq. 2.27; ties to the lower node).
    fn winner_scaled(&self, p: &[f64]) -> usize {
        let mut best = (0, f64::NEG_INFINITY);
        for (q, m) in self.reference.iter().enumerate() {
            let s = dot(m, p);
            if s > best.1 {
                best = (q, s);
            }
        }
        best.0
    }

    fn check_query(&self, features: &[f64]) -> Result<Vec<f64>, RecognizeError> {
        let expected = self.scaling.offset.len();
        if features.len() != expected {
            return Err(RecognizeError::Usage(UsageError::Dimension {
                index: 0,
                got: features.len(),
                expected,
            }));
        }
        if features.iter().any(|x| !x.is_finite()) {
            return Err(RecognizeError::Input(InputError::NonFinite { index: 0 }));
        }
        Ok(self.scaling.apply(features))
    }

    /// Winner and confidence for raw `features`, without allocating: `scratch` (one value per
    /// feature) receives the scaled vector. The winner is exactly [`Som::winner`]'s (same
    /// arithmetic in the same order), so a live recognizer that calls this decides as the
    /// offline pipeline does.
    ///
    /// The confidence is half the margin between the winner's inner product and the best inner
    /// product of a node with another label: all vectors have unit length, so it lies in
    /// `[0, 1]`; 0 means a node of another surface matches as well, and it is 1 when every node
    /// has the winner's label.
    pub fn decide_into(&self, features: &[f64], scratch: &mut [f64]) -> Result<SomDecision, RecognizeError> {
        let expected = self.scaling.dim();
        for found in [features.len(), scratch.len()] {
            if found != expected {
                return Err(RecognizeError::Usage(UsageError::Dimension {
                    index: 0,
                    got: found,
                    expected,
                }));
            }
        }
        if features.iter().any(|x| !x.is_finite()) {
            return Err(RecognizeError::Input(InputError::NonFinite { index: 0 }));
        }
        self.scaling.apply_into(features, scratch);
        let node = self.winner_scaled(scratch);
        let best = self.reference.get(node).map_or(0.0, |m| dot(m, scratch));
        let other = self
            .reference
            .iter()
            .zip(&self.labels)
            .filter(|(_, l)| self.labels.get(node) != Some(*l))
            .map(|(m, _)| dot(m, scratch))
            .fold(f64::NEG_INFINITY, f64::max);
        let confidence = if other.is_finite() {
            (0.5 * (best - other)).clamp(0.0, 1.0)
        } else {
            1.0
        };
        Ok(SomDecision { node, confidence })
    }

    /// The number of features the map takes.
    pub fn dim(&self) -> usize {
        self.scaling.dim()
    }

    /// The feature scaling learned from the training data.
    pub fn scaling(&self) -> &Scaling {
        &self.scaling
    }

    /// Checks the shapes and values of a map read from a file, whose labels must be below
    /// `classes`: `Err((field, reason))`.
    pub fn check_shape(&self, classes: usize) -> Result<(), (&'static str, String)>
    where
        L: Copy + Into<usize>,
    {
        let (nodes, dim) = (self.params.nodes, self.scaling.dim());
        if let Err(e) = self.params.check() {
            return Err(("params", e.to_string()));
        }
        if self.reference.len() != nodes || self.reference.iter().any(|m| m.len() != dim) {
            return Err(("reference", format!("expected {nodes} vectors of {dim} values")));
        }
        if self.labels.len() != nodes || self.hits.len() != nodes {
            return Err(("labels", format!("expected {nodes} node labels and hit counts")));
        }
        if let Some(l) = self.labels.iter().map(|&l| l.into()).find(|&l| l >= classes) {
            return Err((
                "labels",
                format!("label {l} is not below the class count {classes}"),
            ));
        }
        if self.scaling.scale.len() != dim || dim == 0 {
            return Err((
                "scaling",
                format!("expected {dim} offsets and scales, at least 1"),
            ));
        }
        let log_ok = match self.scaling.normalization {
            Normalization::LogWithinClass => {
                self.scaling.log_floor.len() == dim
                    && self
                        .scaling
                        .log_floor
                        .iter()
                        .flatten()
                        .all(|f| f.is_finite() && *f > 0.0)
            }
            Normalization::ThesisColumnNorm | Normalization::Standardize => self.scaling.log_floor.is_empty(),
        };
        if !log_ok {
            return Err((
                "scaling",
                format!(
                    "{:?} needs {} log floors (each absent or positive), other scalings none",
                    self.scaling.normalization, dim
                ),
            ));
        }
        let finite = self
            .reference
            .iter()
            .flatten()
            .chain(&self.scaling.offset)
            .all(|v| v.is_finite())
            && self.scaling.scale.iter().all(|s| s.is_finite() && *s != 0.0);
        if !finite {
            return Err(("reference", "a non-finite value or a zero scale".into()));
        }
        Ok(())
    }

    /// The winning node for raw `features` (Eq. 2.27).
    pub fn winner(&self, features: &[f64]) -> Result<usize, RecognizeError> {
        Ok(self.winner_scaled(&self.check_query(features)?))
    }

    /// The label of the winning node for raw `features`.
    pub fn classify(&self, features: &[f64]) -> Result<&L, RecognizeError> {
        let c = self.winner(features)?;
        Ok(&self.labels[c])
    }

    /// Each node's label, in line order.
    pub fn node_labels(&self) -> &[L] {
        &self.labels
    }

    /// Each node's unit reference vector, in the scaled feature space (the topographic map,
    /// Fig. 4.12).
    pub fn reference_vectors(&self) -> &[Vec<f64>] {
        &self.reference
    }

    /// Training vectors each node won (the data-density histogram, Fig. 4.13).
    pub fn training_hits(&self) -> &[usize] {
        &self.hits
    }

    /// The parameters it was trained with.
    pub fn params(&self) -> &SomParams {
        &self.params
    }

    /// Quantization error: mean Euclidean distance from each scaled vector to its winner's
    /// reference vector.
    pub fn quantization_error(&self, data: &[Vec<f64>]) -> Result<f64, RecognizeError> {
        if data.is_empty() {
            return Err(RecognizeError::Data(DataError::Empty));
        }
        let mut total = 0.0;
        for (index, v) in data.iter().enumerate() {
            let p = self.check_query(v).map_err(|e| reindex(e, index))?;
            let m = &self.reference[self.winner_scaled(&p)];
            total += m.iter().zip(&p).map(|(a, b)| (a - b).powi(2)).sum::<f64>().sqrt();
        }
        Ok(total / data.len() as f64)
    }

    /// Topographic error: fraction of vectors whose best and second-best nodes are not
    /// neighbours on the line.
    pub fn topographic_error(&self, data: &[Vec<f64>]) -> Result<f64, RecognizeError> {
        if data.is_empty() {
            return Err(RecognizeError::Data(DataError::Empty));
        }
        if self.reference.len() < 2 {
            return Ok(0.0);
        }
        let mut errors = 0usize;
        for (index, v) in data.iter().enumerate() {
            let p = self.check_query(v).map_err(|e| reindex(e, index))?;
            let mut scores: Vec<(f64, usize)> = self
                .reference
                .iter()
                .enumerate()
                .map(|(q, m)| (dot(m, &p), q))
                .collect();
            scores.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
            errors += usize::from(scores[0].1.abs_diff(scores[1].1) > 1);
        }
        Ok(errors as f64 / data.len() as f64)
    }
}

fn reindex(e: RecognizeError, index: usize) -> RecognizeError {
    match e {
        RecognizeError::Usage(UsageError::Dimension { got, expected, .. }) => {
            RecognizeError::Usage(UsageError::Dimension { index, got, expected })
        }
        RecognizeError::Input(InputError::NonFinite { .. }) => {
            RecognizeError::Input(InputError::NonFinite { index })
        }
        other => other,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One presentation by hand, Eqs. 2.27–2.29 with α_i = 0.3(1 − i/Z): with Z = 2 the first
    /// presentation moves the map with α₁ = 0.15 and the second with α₂ = 0, so the trained map
    /// is the seeded random unit vectors after exactly one update of the thesis's rule.
    #[test]
    fn one_presentation_follows_the_thesis_update_rule() {
        let data = vec![vec![1.0, 2.0, 0.5], vec![3.0, -1.0, 2.5]];
        let params = SomParams {
            nodes: 5,
            iterations: 2,
            normalization: Normalization::Standardize,
            seed: 42,
            ..SomParams::default()
        };
        let som = Som::train(params, &data, &[0u8, 1]).expect("train");
        // The generator's draws in training's order: the initial vectors, then the input.
        let mut rng = SplitMix64::new(42);
        let mut reference: Vec<Vec<f64>> = (0..5)
            .map(|_| {
                let mut m: Vec<f64> = (0..3).map(|_| 2.0 * rng.next_f64() - 1.0).collect();
                assert!(normalize(&mut m));
                m
            })
            .collect();
        let p = som.scaling().apply(&data[rng.below(2)]);
        let winner = (0..5)
            .max_by(|&a, &b| dot(&reference[a], &p).total_cmp(&dot(&reference[b], &p)))
            .expect("nodes");
        let alpha = 0.3 * (1.0 - 1.0 / 2.0);
        for (q, m) in reference.iter_mut().enumerate() {
            let d = q as f64 - winner as f64;
            let h = alpha * (-d * d / (2.0 * 1.6 * 1.6)).exp();
            let moved: Vec<f64> = m.iter().zip(&p).map(|(mi, pi)| mi + h * pi).collect();
            let norm = moved.iter().map(|x| x * x).sum::<f64>().sqrt();
            *m = moved.iter().map(|x| x / norm).collect();
        }
        for (q, (got, want)) in som.reference_vectors().iter().zip(&reference).enumerate() {
            for (g, w) in got.iter().zip(want) {
                assert!((g - w).abs() < 1e-12, "node {q}: {got:?} vs {want:?}");
            }
        }
    }

    /// Three well-separated clusters in 3-D with features on very different scales.
    fn clusters(seed: u64, per: usize) -> (Vec<Vec<f64>>, Vec<u8>) {
        let mut rng = SplitMix64::new(seed);
        let centres = [[1e-5, 0.1, 3.0], [3e-5, 0.2, 1.0], [2e-5, 0.4, 2.0]];
        let mut data = Vec::new();
        let mut labels = Vec::new();
        for (label, c) in centres.iter().enumerate() {
            for _ in 0..per {
                data.push(
                    c.iter()
                        .map(|x| x * (1.0 + 0.05 * (rng.next_f64() - 0.5)))
                        .collect(),
                );
                labels.push(label as u8);
            }
        }
        (data, labels)
    }

    #[test]
    fn learning_separates_clusters_with_a_topology_preserving_map() {
        let (train, labels) = clusters(1, 50);
        let (test, truth) = clusters(2, 30);
        for seed in 0..5 {
            let params = SomParams {
                seed,
                ..SomParams::default()
            };
            let som = Som::train(params, &train, &labels).expect("valid");
            let correct = test
                .iter()
                .zip(&truth)
                .filter(|(v, t)| som.classify(v).expect("dimension") == *t)
                .count();
            assert_eq!(correct, test.len(), "seed {seed}");
            assert!(som.topographic_error(&train).expect("data") < 0.05);
            let qe = som.quantization_error(&train).expect("data");
            assert!(qe > 0.0 && qe < 0.3, "{qe}");
            assert_eq!(som.training_hits().iter().sum::<usize>(), train.len());
            for m in som.reference_vectors() {
                assert!((dot(m, m) - 1.0).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn training_is_reproducible_from_the_seed_and_seeds_differ() {
        let (train, labels) = clusters(1, 20);
        let a = Som::train(SomParams::default(), &train, &labels).expect("valid");
        let b = Som::train(SomParams::default(), &train, &labels).expect("valid");
        let c = Som::train(
            SomParams {
                seed: 9,
                ..SomParams::default()
            },
            &train,
            &labels,
        )
        .expect("valid");
        assert_eq!(a, b);
        assert_ne!(a.reference_vectors(), c.reference_vectors());
    }

    #[test]
    fn unlabelled_nodes_take_the_nearest_labelled_nodes_label() {
        // One training vector: a single node wins it, every node takes its label.
        let som = Som::train(SomParams::default(), &[vec![1.0, 2.0]], &["a"]).expect("valid");
        assert_eq!(som.node_labels(), &["a"; 12]);
        assert_eq!(som.training_hits().iter().filter(|h| **h > 0).count(), 1);
    }

    #[test]
    fn the_thesis_normalisation_scales_each_feature_to_unit_amplitude() {
        let data = vec![vec![3.0, 1e-6], vec![4.0, 0.0]];
        let s = Scaling::fit(Normalization::ThesisColumnNorm, &data, &vec![0; data.len()]);
        let p = s.apply(&data[0]);
        assert!((p[0] - 0.6).abs() < 1e-15 && (p[1] - 1.0).abs() < 1e-15, "{p:?}");
    }

    #[test]
    fn bad_input_is_an_error() {
        let ok = vec![vec![1.0, 2.0]];
        let bad = |p: SomParams| Som::train(p, &ok, &[0]).err();
        assert!(matches!(
            bad(SomParams {
                nodes: 0,
                ..SomParams::default()
            }),
            Some(RecognizeError::Setting(SettingError::Parameter {
                of: "SOM parameter",
                ..
            }))
        ));
        assert!(matches!(
            bad(SomParams {
                sigma: f64::NAN,
                ..SomParams::default()
            }),
            Some(RecognizeError::Setting(SettingError::Parameter {
                of: "SOM parameter",
                ..
            }))
        ));
        assert!(matches!(
            Som::<u8>::train(SomParams::default(), &[], &[]).err(),
            Some(RecognizeError::Data(DataError::Empty))
        ));
        assert!(matches!(
            Som::train(SomParams::default(), &ok, &[0, 1]).err(),
            Some(RecognizeError::Usage(UsageError::Counts {
                features: 1,
                labels: 2
            }))
        ));
        assert!(matches!(
            Som::train(SomParams::default(), &[vec![1.0], vec![1.0, 2.0]], &[0, 1]).err(),
            Some(RecognizeError::Usage(UsageError::Dimension { index: 1, .. }))
        ));
        assert!(matches!(
            Som::train(SomParams::default(), &[vec![f64::INFINITY]], &[0]).err(),
            Some(RecognizeError::Input(InputError::NonFinite { index: 0 }))
        ));
        let som = Som::train(SomParams::default(), &ok, &[0]).expect("valid");
        assert!(matches!(
            som.classify(&[1.0]),
            Err(RecognizeError::Usage(UsageError::Dimension {
                got: 1,
                expected: 2,
                ..
            }))
        ));
        assert!(matches!(
            som.quantization_error(&[vec![1.0, 2.0], vec![f64::NAN, 0.0]]),
            Err(RecognizeError::Input(InputError::NonFinite { index: 1 }))
        ));
    }
}
