//! k-nearest-neighbour classification with class probabilities, as Sinapov et al. used it
//! (IEEE T-RO 2011, Sec. IV-B).
//!
//! The paper used WEKA's `IBk` with `k = 3`: Euclidean distance on attributes that WEKA
//! min–max normalises over the training set by default, and class probabilities equal to the
//! neighbours' vote fractions ("if two of the three neighbours had class label A then
//! Pr(S = A) = 2/3"). [`FeatureScaling::MinMax`] reproduces that normalisation;
//! [`FeatureScaling::None`] uses raw distances.

use std::sync::OnceLock;

use crate::RecognizeError;
use crate::folds::group_folds;
use crate::{DataError, SettingError, UsageError};

use crate::vectors;

mod batch;
mod calibration;
mod tree;

pub use calibration::VoteCalibration;

use tree::{Best, KdTree, squared_distance};

/// Dimensions from which [`Knn::neighbours`] scans every training point instead of searching a
/// k-d tree. Measured (benches/knn.rs, 10 k points, 200 queries): at 5-D the tree answers 3–40×
/// faster than the scan (1 k–50 k points). From ~20-D its answer depends on the data: on 20
/// tight clusters it still beat the scan (2.8× at 20-D, 1.75× at 130-D), but on points spread
/// near uniformly its boxes bound almost nothing and it was 3× slower at 20-D and 1.75× slower
/// at 130-D. The scan is never far from its best, so it stays the path for the spectral
/// histograms.
const TREE_MAX_DIM: usize = 20;
pub use crate::vectors::FeatureScaling;

/// Neighbours the paper used.
pub const PAPER_K: usize = 3;

/// Hyperparameters of [`Knn`]; checked when fitting.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct KnnParams {
    k: usize,
    scaling: FeatureScaling,
}

impl Default for KnnParams {
    /// The paper's: `k = 3`, min–max scaling.
    fn default() -> Self {
        Self {
            k: PAPER_K,
            scaling: FeatureScaling::default(),
        }
    }
}

impl KnnParams {
    /// Number of neighbours.
    pub fn k(mut self, k: usize) -> Self {
        self.k = k;
        self
    }

    /// Feature scaling.
    pub fn scaling(mut self, scaling: FeatureScaling) -> Self {
        self.scaling = scaling;
        self
    }

    /// Fits a classifier: see [`Knn::fit`].
    pub fn fit<V: AsRef<[f64]>>(
        &self,
        features: &[V],
        labels: &[usize],
        classes: usize,
    ) -> Result<Knn, RecognizeError> {
        Knn::fit(*self, features, labels, classes)
    }
}

/// A fitted k-NN classifier: the (scaled) training set.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Knn {
    k: usize,
    classes: usize,
    dim: usize,
    /// Per feature `(offset, factor)`: scaled = (x − offset)·factor.
    scale: Vec<(f64, f64)>,
    /// Scaled training points, row-major.
    points: Vec<f64>,
    labels: Vec<usize>,
    /// Search index over `points`, built at the first query (so also for a classifier read
    /// from a file) and never stored.
    #[serde(skip)]
    index: SearchIndex,
}

/// The lazily built k-d tree of a [`Knn`]. It is derived from the training points alone, so
/// two classifiers are equal whether or not either has built it yet, and printing one says
/// only whether it is built (the tree repeats every training point).
#[derive(Clone, Default)]
struct SearchIndex(OnceLock<KdTree>);

impl std::fmt::Debug for SearchIndex {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(if self.0.get().is_some() {
            "SearchIndex(built)"
        } else {
            "SearchIndex(not built)"
        })
    }
}

impl PartialEq for SearchIndex {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

/// The buffers one [`Knn`] needs to classify a query without allocating ([`Knn::scratch`]).
#[derive(Debug)]
pub struct KnnScratch {
    query: Vec<f64>,
    best: Best,
}

impl Knn {
    /// Stores the training set. Labels are `0..classes`.
    pub fn fit<V: AsRef<[f64]>>(
        params: KnnParams,
        features: &[V],
        labels: &[usize],
        classes: usize,
    ) -> Result<Self, RecognizeError> {
        if params.k == 0 {
            return Err(RecognizeError::Setting(SettingError::ZeroK));
        }
        if features.is_empty() {
            return Err(RecognizeError::Data(DataError::Empty));
        }
        if features.len() != labels.len() {
            return Err(RecognizeError::Usage(UsageError::Counts {
                features: features.len(),
                labels: labels.len(),
            }));
        }
        if features.len() < params.k {
            return Err(RecognizeError::Data(DataError::TooFewPoints {
                k: params.k,
                points: features.len(),
            }));
        }
        let dim = features[0].as_ref().len();
        if dim == 0 {
            return Err(RecognizeError::Usage(UsageError::ZeroDimension));
        }
        vectors::check_labelled(features, labels, dim, classes)?;
        let scale = params.scaling.fit(features, dim);
        let points = vectors::scaled_rows(features, &scale);
        Ok(Self {
            k: params.k,
            classes,
            dim,
            scale,
            points,
            labels: labels.to_vec(),
            index: SearchIndex::default(),
        })
    }

    /// Neighbours that vote.
    pub fn k(&self) -> usize {
        self.k
    }

    /// Number of classes.
    pub fn classes(&self) -> usize {
        self.classes
    }

    /// Dimension of the feature vectors.
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// Checks the shapes and values of a classifier read from a file: `Err((field, reason))`.
    pub fn check_shape(&self) -> Result<(), (&'static str, String)> {
        if self.k == 0 || self.labels.len() < self.k {
            return Err(("k", format!("k = {} with {} points", self.k, self.labels.len())));
        }
        if self.dim == 0 || self.scale.len() != self.dim {
            return Err((
                "scale",
                format!("{} scales for dimension {}", self.scale.len(), self.dim),
            ));
        }
        if self.points.len() != self.labels.len() * self.dim {
            return Err((
                "points",
                format!("length is not {} points × {}", self.labels.len(), self.dim),
            ));
        }
        if let Some(l) = self.labels.iter().find(|&&l| l >= self.classes) {
            return Err((
                "labels",
                format!("label {l} is not below the class count {}", self.classes),
            ));
        }
        let finite = self.points.iter().all(|v| v.is_finite())
            && self.scale.iter().all(|(o, s)| o.is_finite() && s.is_finite());
        if !finite {
            return Err(("points", "contains a non-finite value".into()));
        }
        Ok(())
    }

    /// Indices of the `k` nearest training points, nearest first. Equal distances are broken
    /// by training order (the earlier point is nearer), so results never depend on sorting
    /// internals. Below `TREE_MAX_DIM` (20) dimensions a k-d tree finds them; the answer is the
    /// same as [`Knn::neighbours_exhaustive`]'s, bit for bit.
    pub fn neighbours(&self, query: &[f64]) -> Result<Vec<usize>, RecognizeError> {
        let mut scratch = self.scratch();
        self.search_into(query, &mut scratch)?;
        Ok(scratch.best.into_indices())
    }

    /// [`Knn::neighbours`] by comparing the query with every training point: the reference
    /// the tree search is checked and measured against.
    pub fn neighbours_exhaustive(&self, query: &[f64]) -> Result<Vec<usize>, RecognizeError> {
        vectors::check_query(query, self.dim)?;
        let q: Vec<f64> = vectors::scaled(query, &self.scale).collect();
        let mut best = Best::new(self.k);
        self.scan(&q, &mut best);
        Ok(best.into_indices())
    }

    /// Buffers for [`Knn::predict_proba_into`]. The search tree is built here if it was not
    /// yet, so that a query on these buffers allocates nothing.
    pub fn scratch(&self) -> KnnScratch {
        if self.dim < TREE_MAX_DIM {
            self.tree();
        }
        KnnScratch {
            query: vec![0.0; self.dim],
            best: Best::new(self.k),
        }
    }

    fn tree(&self) -> &KdTree {
        self.index.0.get_or_init(|| KdTree::new(&self.points, self.dim))
    }

    /// The `k` nearest neighbours of `query` into `scratch.best`.
    fn search_into(&self, query: &[f64], scratch: &mut KnnScratch) -> Result<(), RecognizeError> {
        vectors::check_query(query, self.dim)?;
        vectors::check_buffer("k-NN scratch", scratch.query.len(), self.dim)?;
        for (q, v) in scratch.query.iter_mut().zip(vectors::scaled(query, &self.scale)) {
            *q = v;
        }
        scratch.best.clear();
        if self.dim >= TREE_MAX_DIM {
            self.scan(&scratch.query, &mut scratch.best);
        } else {
            self.tree().search(&scratch.query, &mut scratch.best);
        }
        Ok(())
    }

    /// Offers every training point to `best` for the scaled query `q`, keeping only the best
    /// `k` (distance, index) pairs rather than sorting every distance.
    fn scan(&self, q: &[f64], best: &mut Best) {
        for (i, p) in self.points.chunks_exact(self.dim).enumerate() {
            best.offer(squared_distance(p, q), i);
        }
    }

    /// [`Knn::predict_proba`] into `p` (one per class) on `scratch` (from [`Knn::scratch`]),
    /// allocating nothing: for a thread that must not.
    pub fn predict_proba_into(
        &self,
        query: &[f64],
        scratch: &mut KnnScratch,
        p: &mut [f64],
    ) -> Result<(), RecognizeError> {
        vectors::check_buffer("class probability", p.len(), self.classes)?;
        self.search_into(query, scratch)?;
        p.fill(0.0);
        // Summed a vote at a time, as `votes` does, so the two agree to the bit.
        for i in scratch.best.indices() {
            p[self.labels[i]] += 1.0 / self.k as f64;
        }
        Ok(())
    }

    /// Class probabilities: the fraction of the `k` neighbours with each label (the paper's and
    /// WEKA's, unweighted by distance).
    pub fn predict_proba(&self, query: &[f64]) -> Result<Vec<f64>, RecognizeError> {
        Ok(self.votes(&self.neighbours(query)?).1)
    }

    /// [`Knn::predict`] and [`Knn::predict_proba`] from one neighbour search.
    pub fn predict_with_proba(&self, query: &[f64]) -> Result<(usize, Vec<f64>), RecognizeError> {
        Ok(self.votes(&self.neighbours(query)?))
    }

    /// [`Knn::predict_with_proba`] of every query, to the bit, on all cores: by the tree per
    /// query below [`TREE_MAX_DIM`] dimensions, else screened by a matrix product (`batch`).
    pub fn predict_with_proba_many<V: AsRef<[f64]> + Sync>(
        &self,
        queries: &[V],
    ) -> Result<Vec<(usize, Vec<f64>)>, RecognizeError> {
        use rayon::prelude::*;
        if self.dim < TREE_MAX_DIM {
            return queries
                .par_iter()
                .map(|q| self.predict_with_proba(q.as_ref()))
                .collect();
        }
        let mut scaled = Vec::with_capacity(queries.len() * self.dim);
        for q in queries {
            vectors::check_query(q.as_ref(), self.dim)?;
            scaled.extend(vectors::scaled(q.as_ref(), &self.scale));
        }
        Ok(batch::neighbours(&self.points, self.dim, self.k, &scaled)
            .iter()
            .map(|n| self.votes(n))
            .collect())
    }

    /// The label and the class probabilities the `neighbours` of a query vote for.
    fn votes(&self, neighbours: &[usize]) -> (usize, Vec<f64>) {
        let mut votes = vec![0usize; self.classes];
        for &i in neighbours {
            votes[self.labels[i]] += 1;
        }
        let best = votes.iter().copied().max().unwrap_or(0);
        // `neighbours` is non-empty (k ≥ 1 and at least k points), so `find` succeeds; the
        // fallback only keeps this free of panics.
        let label = neighbours
            .iter()
            .map(|&i| self.labels[i])
            .find(|&l| votes[l] == best)
            .unwrap_or(0);
        // Summed a vote at a time, as always: `n / k` can differ in the last bit.
        let mut p = vec![0.0; self.classes];
        for &i in neighbours {
            p[self.labels[i]] += 1.0 / self.k as f64;
        }
        (label, p)
    }

    /// Most likely class. When several classes share the most votes (e.g. three different
    /// labels with `k = 3`), the one of the nearest neighbour among them wins — the 1-NN answer
    /// restricted to the tie, rather than an arbitrary class index.
    pub fn predict(&self, query: &[f64]) -> Result<usize, RecognizeError> {
        Ok(self.votes(&self.neighbours(query)?).0)
    }
}

/// A k-NN's label for one query and every class's vote fraction.
pub type Votes = (usize, Vec<f64>);

/// Each sample's k-NN label and vote fractions when its fold is held out, under
/// cross-validation by group ([`group_folds`], at most `folds` folds): a k-NN with `params`
/// fitted on the other folds' samples. Returns them in the samples' order, and the folds used.
pub fn held_out_votes<V: AsRef<[f64]>>(
    params: KnnParams,
    features: &[V],
    labels: &[usize],
    groups: &[u64],
    classes: usize,
    folds: usize,
) -> Result<(Vec<Votes>, usize), RecognizeError> {
    for n in [labels.len(), groups.len()] {
        if n != features.len() {
            return Err(RecognizeError::Usage(UsageError::Counts {
                features: features.len(),
                labels: n,
            }));
        }
    }
    let (fold, folds) = group_folds(groups, folds)?;
    let mut votes: Vec<Option<Votes>> = vec![None; features.len()];
    for f in 0..folds {
        let (train_x, train_y): (Vec<&[f64]>, Vec<usize>) = features
            .iter()
            .zip(labels)
            .zip(&fold)
            .filter(|&(_, &g)| g != f)
            .map(|((x, &y), _)| (x.as_ref(), y))
            .unzip();
        let held: Vec<usize> = (0..features.len()).filter(|&i| fold[i] == f).collect();
        let queries: Vec<&[f64]> = held.iter().map(|&i| features[i].as_ref()).collect();
        let knn = Knn::fit(params, &train_x, &train_y, classes)?;
        for (i, v) in held.into_iter().zip(knn.predict_with_proba_many(&queries)?) {
            votes[i] = Some(v);
        }
    }
    // `group_folds` puts every sample in a fold below `folds`: each was held out once.
    let votes: Vec<_> = votes.into_iter().flatten().collect();
    Ok((votes, folds))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::InputError;
    use proptest::strategy::Strategy;

    /// Points on a line: class 0 at 0, 1, 2; class 1 at 10, 11; class 2 at 20.
    fn line() -> (Vec<[f64; 1]>, Vec<usize>) {
        (
            vec![[0.0], [1.0], [2.0], [10.0], [11.0], [20.0]],
            vec![0, 0, 0, 1, 1, 2],
        )
    }

    #[test]
    fn vote_fractions_on_a_hand_example() {
        let (x, y) = line();
        let knn = KnnParams::default()
            .scaling(FeatureScaling::None)
            .fit(&x, &y, 3)
            .expect("valid");
        // Nearest to 1.2: 1, 2, 0 — all class 0.
        assert_eq!(knn.neighbours(&[1.2]).expect("ok"), vec![1, 2, 0]);
        assert_eq!(knn.predict_proba(&[1.2]).expect("ok"), vec![1.0, 0.0, 0.0]);
        // Nearest to 9: 10 (1), 11 (2), 2 (7) → 1/3 class 0, 2/3 class 1.
        let p = knn.predict_proba(&[9.0]).expect("ok");
        assert!((p[0] - 1.0 / 3.0).abs() < 1e-12 && (p[1] - 2.0 / 3.0).abs() < 1e-12 && p[2] == 0.0);
        assert_eq!(knn.predict(&[9.0]).expect("ok"), 1);
        // Nearest to 15.4: 11 (4.4), 20 (4.6), 10 (5.4) → class 1 twice, class 2 once.
        assert_eq!(knn.predict(&[15.4]).expect("ok"), 1);
    }

    #[test]
    fn three_way_tie_goes_to_the_nearest_neighbour() {
        let x = [[0.0], [5.0], [11.0]];
        let y = [0, 1, 2];
        let knn = KnnParams::default()
            .scaling(FeatureScaling::None)
            .fit(&x, &y, 3)
            .expect("valid");
        let p = knn.predict_proba(&[6.0]).expect("ok");
        assert!(p.iter().all(|&v| (v - 1.0 / 3.0).abs() < 1e-12));
        assert_eq!(knn.predict(&[6.0]).expect("ok"), 1);
        assert_eq!(knn.predict(&[10.0]).expect("ok"), 2);
        // Exactly equidistant points: the earlier training point counts as nearer.
        let knn1 = KnnParams::default()
            .k(1)
            .scaling(FeatureScaling::None)
            .fit(&[[0.0], [2.0]], &[1, 0], 2)
            .expect("valid");
        assert_eq!(knn1.predict(&[1.0]).expect("ok"), 1);
    }

    #[test]
    fn min_max_scaling_equalises_features() {
        // Feature 0 spans 0..1000, feature 1 spans 0..1 and carries the class.
        let x = [[0.0, 0.0], [1000.0, 0.1], [0.0, 1.0], [900.0, 0.9]];
        let y = [0, 0, 1, 1];
        let raw = KnnParams::default()
            .k(1)
            .scaling(FeatureScaling::None)
            .fit(&x, &y, 2)
            .expect("valid");
        let scaled = KnnParams::default().k(1).fit(&x, &y, 2).expect("valid");
        let q = [980.0, 0.9];
        // Raw: (1000, 0.1) is 400.64 away in squares, (900, 0.9) 6400.
        assert_eq!(raw.predict(&q).expect("ok"), 0, "raw distance follows feature 0");
        // Scaled: (0.98, 0.9) is 0.6404 from (1, 0.1) and 0.0064 from (0.9, 0.9).
        assert_eq!(scaled.predict(&q).expect("ok"), 1);
    }

    #[test]
    fn bad_input_is_a_typed_error() {
        let (x, y) = line();
        let p = KnnParams::default();
        assert!(matches!(
            p.k(0).fit(&x, &y, 3),
            Err(RecognizeError::Setting(SettingError::ZeroK))
        ));
        assert!(matches!(
            p.fit::<[f64; 1]>(&[], &[], 3),
            Err(RecognizeError::Data(DataError::Empty))
        ));
        assert!(matches!(
            p.fit(&x, &y[..5], 3),
            Err(RecognizeError::Usage(UsageError::Counts {
                features: 6,
                labels: 5
            }))
        ));
        assert!(matches!(
            p.k(7).fit(&x, &y, 3),
            Err(RecognizeError::Data(DataError::TooFewPoints { k: 7, points: 6 }))
        ));
        assert!(matches!(
            p.fit(&x, &y, 2),
            Err(RecognizeError::Usage(UsageError::LabelOutOfRange {
                index: 5,
                label: 2,
                classes: 2
            }))
        ));
        let ragged: Vec<Vec<f64>> = vec![vec![0.0], vec![1.0, 2.0], vec![3.0]];
        assert!(matches!(
            p.fit(&ragged, &[0, 0, 0], 1),
            Err(RecognizeError::Usage(UsageError::Dimension {
                index: 1,
                expected: 1,
                got: 2
            }))
        ));
        assert!(matches!(
            p.fit(&[[0.0], [f64::NAN], [1.0]], &[0, 0, 0], 1),
            Err(RecognizeError::Input(InputError::NonFinite { index: 1 }))
        ));
        let empty: [[f64; 0]; 3] = [[], [], []];
        assert!(matches!(
            p.fit(&empty, &[0, 0, 0], 1),
            Err(RecognizeError::Usage(UsageError::ZeroDimension))
        ));
        let knn = p.fit(&x, &y, 3).expect("valid");
        assert!(matches!(
            knn.predict(&[1.0, 2.0]),
            Err(RecognizeError::Usage(UsageError::Dimension { .. }))
        ));
        assert!(matches!(
            knn.predict_proba(&[f64::INFINITY]),
            Err(RecognizeError::Input(InputError::NonFinite { index: 0 }))
        ));
    }

    /// The search as it was first written: every distance (the one expression), sorted by
    /// (distance, index).
    fn sorted_reference(knn: &Knn, query: &[f64]) -> Vec<usize> {
        let q: Vec<f64> = vectors::scaled(query, &knn.scale).collect();
        let mut dist: Vec<(f64, usize)> = knn
            .points
            .chunks_exact(knn.dim)
            .enumerate()
            .map(|(i, p)| (squared_distance(p, &q), i))
            .collect();
        dist.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        dist.into_iter().take(knn.k).map(|(_, i)| i).collect()
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(256))]

        /// Coordinates from a handful of values make many duplicate points and many equal
        /// distances, the cases where only the index tie-break decides; a few wide ones give
        /// the tree real splits.
        #[test]
        fn tree_search_returns_the_exhaustive_neighbours(
            dim in 1usize..7,
            k in 1usize..12,
            cells in proptest::collection::vec(proptest::prop_oneof![
                4 => (0i32..4).prop_map(f64::from),
                1 => -1e3f64..1e3,
            ], 1..1400),
            queries in proptest::collection::vec(proptest::prop_oneof![
                3 => (-1i32..5).prop_map(|v| f64::from(v) * 0.5),
                1 => -1e3f64..1e3,
            ], 1..60),
            min_max in proptest::prelude::any::<bool>(),
        ) {
            use proptest::prelude::{prop_assert_eq, prop_assume};
            let rows: Vec<&[f64]> = cells.chunks_exact(dim).collect();
            prop_assume!(rows.len() >= k);
            let labels: Vec<usize> = (0..rows.len()).map(|i| i % 3).collect();
            let scaling = if min_max { FeatureScaling::MinMax } else { FeatureScaling::None };
            let knn = KnnParams::default().k(k).scaling(scaling).fit(&rows, &labels, 3).expect("valid");
            for q in queries.chunks_exact(dim) {
                let expected = sorted_reference(&knn, q);
                prop_assert_eq!(&knn.neighbours(q).expect("valid"), &expected);
                prop_assert_eq!(&knn.neighbours_exhaustive(q).expect("valid"), &expected);
                // One search for both answers gives each answer bit for bit.
                let (label, p) = knn.predict_with_proba(q).expect("valid");
                prop_assert_eq!(label, knn.predict(q).expect("valid"));
                prop_assert_eq!(p, knn.predict_proba(q).expect("valid"));
            }
        }
    }

    #[test]
    fn every_point_identical_and_high_dimensions_match_the_reference() {
        // 500 copies of one point (a leaf that cannot be split) and a query on it: the first
        // k training indices, in order.
        let same = vec![[0.25, -1.0, 3.0]; 500];
        let labels = vec![0; 500];
        let knn = KnnParams::default().k(7).fit(&same, &labels, 1).expect("valid");
        assert_eq!(
            knn.neighbours(&[0.25, -1.0, 3.0]).expect("ok"),
            (0..7).collect::<Vec<_>>()
        );
        // Above the tree's dimensions the scan answers; same results as the reference.
        let wide: Vec<Vec<f64>> = (0..300)
            .map(|i| {
                (0..TREE_MAX_DIM + 5)
                    .map(|j| f64::from((i * 7 + j * 3) as u32 % 5))
                    .collect()
            })
            .collect();
        let labels: Vec<usize> = (0..300).map(|i| i % 4).collect();
        let knn = KnnParams::default().k(5).fit(&wide, &labels, 4).expect("valid");
        for q in wide.iter().step_by(37) {
            assert_eq!(knn.neighbours(q).expect("ok"), sorted_reference(&knn, q));
        }
    }

    #[test]
    fn a_classifier_read_back_searches_as_the_one_written() {
        let (x, y) = line();
        let knn = KnnParams::default().fit(&x, &y, 3).expect("valid");
        let before = knn.neighbours(&[9.0]).expect("ok");
        let json = serde_json::to_string(&knn).expect("serialises");
        assert!(
            !json.contains("index"),
            "the search index is never stored: {json}"
        );
        let back: Knn = serde_json::from_str(&json).expect("reads");
        assert_eq!(back, knn);
        assert_eq!(back.neighbours(&[9.0]).expect("ok"), before);
    }
}
