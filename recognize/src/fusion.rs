//! Sinapov et al.'s reliability-weighted fusion of several behaviours' classifiers (IEEE T-RO
//! 2011, Sec. IV-C).
//!
//! Fusion: each behaviour `b`'s model gives `Pr_b(s | X_b)`; its weight `w_b` is the model's
//! own cross-validated accuracy on its training data, and the prediction maximises
//! `Σ_b w_b · Pr_b(s | X_b)`, so that an unreliable behaviour cannot outvote reliable ones.

use crate::RecognizeError;
#[cfg(doc)]
use crate::folds::group_folds;
use crate::knn::{Knn, KnnParams, held_out_votes};
use crate::{DataError, UsageError};

/// The index of the largest probability; ties go to the lowest class index. `None` for an
/// empty slice.
pub fn argmax(p: &[f64]) -> Option<usize> {
    p.iter()
        .enumerate()
        .fold(None, |best: Option<(usize, f64)>, (i, &v)| match best {
            Some((_, bv)) if bv >= v => best,
            _ => Some((i, v)),
        })
        .map(|(i, _)| i)
}

/// Accuracy of k-NN under cross-validation by group ([`group_folds`]): the reliability weight
/// of a behaviour's model in the paper's fusion.
pub fn cross_validated_accuracy<V: AsRef<[f64]>>(
    params: KnnParams,
    features: &[V],
    labels: &[usize],
    groups: &[u64],
    classes: usize,
    folds: usize,
) -> Result<f64, RecognizeError> {
    let (votes, _) = held_out_votes(params, features, labels, groups, classes, folds)?;
    let correct = votes.iter().zip(labels).filter(|((l, _), y)| l == *y).count();
    Ok(correct as f64 / features.len() as f64)
}

/// One behaviour's training data: a feature vector, label and group (recording or trial, for
/// the reliability cross-validation) per interaction.
#[derive(Debug, Clone, Copy)]
pub struct BehaviourData<'a, V> {
    /// Feature vectors.
    pub features: &'a [V],
    /// Class labels, `0..classes`.
    pub labels: &'a [usize],
    /// Groups: interactions sharing a group are never split between training and testing.
    pub groups: &'a [u64],
}

/// A k-NN model per behaviour and its reliability weight (Sinapov Sec. IV-C): the whole
/// recognizer for interactions that may use any subset of the behaviours.
#[derive(Debug, Clone, PartialEq)]
pub struct ReliabilityFusion {
    models: Vec<Knn>,
    weights: Vec<f64>,
}

impl ReliabilityFusion {
    /// Fits each behaviour's model on all its data and weighs it by its accuracy under
    /// `folds`-fold cross-validation by group on that same data ([`cross_validated_accuracy`]).
    pub fn fit<V: AsRef<[f64]>>(
        params: KnnParams,
        behaviours: &[BehaviourData<'_, V>],
        classes: usize,
        folds: usize,
    ) -> Result<Self, RecognizeError> {
        if behaviours.is_empty() {
            return Err(RecognizeError::Usage(UsageError::NothingToFuse));
        }
        let mut models = Vec::with_capacity(behaviours.len());
        let mut weights = Vec::with_capacity(behaviours.len());
        for (behaviour, d) in behaviours.iter().enumerate() {
            let wrap = |source| RecognizeError::FusedBehaviour {
                behaviour,
                source: Box::new(source),
            };
            models.push(Knn::fit(params, d.features, d.labels, classes).map_err(wrap)?);
            weights.push(
                cross_validated_accuracy(params, d.features, d.labels, d.groups, classes, folds)
                    .map_err(wrap)?,
            );
        }
        Ok(Self { models, weights })
    }

    /// The behaviours' models, in the order given to [`ReliabilityFusion::fit`].
    pub fn models(&self) -> &[Knn] {
        &self.models
    }

    /// The behaviours' reliability weights (cross-validated accuracies).
    pub fn weights(&self) -> &[f64] {
        &self.weights
    }

    /// Fused class probabilities of one surface: `queries[b]` is the feature vector from
    /// behaviour `b`, or `None` where that behaviour was not performed. Fails with
    /// [`UsageError::NothingToFuse`] when no behaviour was, and [`DataError::ZeroTotalWeight`] when
    /// only behaviours that never classified correctly were.
    pub fn predict_proba(&self, queries: &[Option<&[f64]>]) -> Result<Vec<f64>, RecognizeError> {
        if queries.len() != self.models.len() {
            return Err(RecognizeError::Usage(UsageError::QueryCount {
                queries: queries.len(),
                behaviours: self.models.len(),
            }));
        }
        let mut probabilities = Vec::new();
        let mut weights = Vec::new();
        for (behaviour, (q, (model, &w))) in queries
            .iter()
            .zip(self.models.iter().zip(&self.weights))
            .enumerate()
        {
            if let Some(q) = q {
                probabilities.push(model.predict_proba(q).map_err(|source| {
                    RecognizeError::FusedBehaviour {
                        behaviour,
                        source: Box::new(source),
                    }
                })?);
                weights.push(w);
            }
        }
        fuse(&probabilities, &weights)
    }

    /// The most likely class: [`fused_label`] of the behaviours performed, so that one
    /// behaviour alone answers exactly as its own [`Knn::predict`].
    pub fn predict(&self, queries: &[Option<&[f64]>]) -> Result<usize, RecognizeError> {
        if queries.len() != self.models.len() {
            return Err(RecognizeError::Usage(UsageError::QueryCount {
                queries: queries.len(),
                behaviours: self.models.len(),
            }));
        }
        let (mut labels, mut probabilities, mut weights) = (Vec::new(), Vec::new(), Vec::new());
        for (behaviour, (q, (model, &w))) in queries
            .iter()
            .zip(self.models.iter().zip(&self.weights))
            .enumerate()
        {
            if let Some(q) = q {
                let wrap = |source| RecognizeError::FusedBehaviour {
                    behaviour,
                    source: Box::new(source),
                };
                labels.push(model.predict(q).map_err(wrap)?);
                probabilities.push(model.predict_proba(q).map_err(wrap)?);
                weights.push(w);
            }
        }
        fused_label(&labels, &probabilities, &weights)
    }
}

/// The decision of fused scratches, each given as its classifier's own decision (`labels`),
/// its class probabilities and its weight: the argmax of [`fuse`], classes within 1e-12 of
/// the best counting as tied and the tie going to the decision of the heaviest scratch among
/// them (the first, among equal weights), else to the lowest class index.
///
/// A single scratch keeps its own decision: with nothing to fuse, fusing must not change it,
/// and a classifier's decision need not be the lowest-index argmax of its probabilities
/// (k-NN breaks a tie of votes by the nearest neighbour; an SVM votes one-vs-one while its
/// probabilities are pairwise-coupled).
pub fn fused_label<P: AsRef<[f64]>>(
    labels: &[usize],
    probabilities: &[P],
    weights: &[f64],
) -> Result<usize, RecognizeError> {
    if labels.len() != probabilities.len() {
        return Err(RecognizeError::Usage(UsageError::LabelCount {
            probabilities: probabilities.len(),
            labels: labels.len(),
        }));
    }
    let fused = fuse(probabilities, weights)?;
    if let [only] = labels {
        return Ok(*only);
    }
    let best = fused.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let tied = |l: usize| fused.get(l).is_some_and(|&v| v >= best - 1e-12);
    let mut order: Vec<usize> = (0..labels.len()).collect();
    // Stable: among equal weights the earlier scratch stays first.
    order.sort_by(|&a, &b| weights[b].total_cmp(&weights[a]));
    order
        .into_iter()
        .map(|i| labels[i])
        .find(|&l| tied(l))
        .or_else(|| argmax(&fused))
        .ok_or(RecognizeError::Usage(UsageError::NothingToFuse))
}

/// Reliability-weighted fusion: `Σ_b w_b·p_b / Σ_b w_b`, a probability vector again when the
/// inputs are. Weights are the behaviours' cross-validated accuracies
/// ([`cross_validated_accuracy`]); dividing by their sum keeps the result comparable across
/// different numbers of behaviours without changing its argmax.
pub fn fuse<P: AsRef<[f64]>>(probabilities: &[P], weights: &[f64]) -> Result<Vec<f64>, RecognizeError> {
    if probabilities.is_empty() {
        return Err(RecognizeError::Usage(UsageError::NothingToFuse));
    }
    if probabilities.len() != weights.len() {
        return Err(RecognizeError::Usage(UsageError::WeightCount {
            probabilities: probabilities.len(),
            weights: weights.len(),
        }));
    }
    let classes = probabilities[0].as_ref().len();
    let mut out = vec![0.0; classes];
    let mut total = 0.0;
    for (index, (p, &w)) in probabilities.iter().zip(weights).enumerate() {
        let p = p.as_ref();
        if p.len() != classes {
            return Err(RecognizeError::Usage(UsageError::FusionClasses {
                index,
                expected: classes,
                got: p.len(),
            }));
        }
        if !(w.is_finite() && w >= 0.0) {
            return Err(RecognizeError::Usage(UsageError::BadWeight { index, weight: w }));
        }
        total += w;
        for (o, v) in out.iter_mut().zip(p) {
            *o += w * v;
        }
    }
    if total <= 0.0 {
        return Err(RecognizeError::Data(DataError::ZeroTotalWeight));
    }
    out.iter_mut().for_each(|v| *v /= total);
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::knn::FeatureScaling;

    #[test]
    fn cross_validated_accuracy_counts_held_out_predictions() {
        // Two classes, three trials each; trial 2 of class 1 sits among class 0.
        let x = [[0.0], [0.1], [0.2], [5.0], [5.1], [0.25]];
        let y = [0, 0, 0, 1, 1, 1];
        let groups = [0, 1, 2, 0, 1, 2];
        let params = KnnParams::default().k(1).scaling(FeatureScaling::None);
        let acc = cross_validated_accuracy(params, &x, &y, &groups, 2, 3).expect("valid");
        // Fold 2 holds out 0.2 (class 0, nearest 0.1 → right) and 0.25 (class 1, nearest 0.1
        // → wrong); folds 0 and 1 are all right: 5 of 6.
        assert!((acc - 5.0 / 6.0).abs() < 1e-12, "{acc}");
    }

    #[test]
    fn fusion_weights_reliable_behaviours() {
        // Behaviour A (reliable, w = 0.9) says class 1; behaviour B (w = 0.3) is sure of 0.
        let a = [0.0, 2.0 / 3.0, 1.0 / 3.0];
        let b = [1.0, 0.0, 0.0];
        let fused = fuse(&[a, b], &[0.9, 0.3]).expect("valid");
        let expected = [0.3 / 1.2, 0.6 / 1.2, 0.3 / 1.2];
        for (f, e) in fused.iter().zip(expected) {
            assert!((f - e).abs() < 1e-12, "{fused:?}");
        }
        assert_eq!(argmax(&fused), Some(1));
        assert!((fused.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        // With equal weights B's certainty would win: (1, 2/3, 1/3) / 2.
        assert_eq!(argmax(&fuse(&[a, b], &[0.5, 0.5]).expect("valid")), Some(0));
        // A useless behaviour (weight 0) changes nothing.
        let alone = fuse(&[a, b], &[0.9, 0.0]).expect("valid");
        assert!(
            alone.iter().zip(a).all(|(f, e)| (f - e).abs() < 1e-12),
            "{alone:?}"
        );
    }

    #[test]
    fn fusing_one_behaviour_keeps_its_own_decision() {
        // Near the origin, the three nearest points are one of each class (k = 3): k-NN names
        // the nearest neighbour's class, while the lowest-index argmax of the probabilities
        // would name class 0. With nothing to fuse, fusion must agree with k-NN. The far points
        // give the cross-validation (by group) of the weight enough to train on.
        static X: [[f64; 1]; 6] = [[0.0], [5.0], [10.0], [-100.0], [100.0], [110.0]];
        let labels = [0, 1, 2, 0, 1, 2];
        let groups = [0, 0, 0, 1, 1, 1];
        let params = KnnParams::default().k(3).scaling(FeatureScaling::None);
        let data = BehaviourData {
            features: &X,
            labels: &labels,
            groups: &groups,
        };
        let knn = Knn::fit(params, &X, &labels, 3).expect("valid");
        let fusion = ReliabilityFusion::fit(params, &[data], 3, 3).expect("valid");
        for q in [[9.0], [4.0], [0.5], [7.6]] {
            let p = knn.predict_proba(&q).expect("valid");
            let single = knn.predict(&q).expect("valid");
            assert_eq!(fusion.predict(&[Some(&q)]).expect("valid"), single, "{q:?}");
            assert_eq!(
                fused_label(&[single], &[&p], &[0.7]).expect("valid"),
                single,
                "{q:?}"
            );
        }
        assert_eq!(argmax(&knn.predict_proba(&[9.0]).expect("valid")), Some(0));
        assert_eq!(knn.predict(&[9.0]).expect("valid"), 2);
        // A single scratch keeps its decision whatever its probabilities say (an SVM's vote).
        assert_eq!(fused_label(&[1], &[[0.6, 0.3, 0.1]], &[1.0]).expect("valid"), 1);
        // Several: a tie goes to the heaviest scratch's decision among the tied classes.
        let tie = [[0.5, 0.5, 0.0], [0.5, 0.5, 0.0]];
        assert_eq!(fused_label(&[0, 1], &tie, &[0.4, 0.8]).expect("valid"), 1);
        assert_eq!(fused_label(&[0, 1], &tie, &[0.8, 0.4]).expect("valid"), 0);
        // No scratch's decision among the tied classes: the lowest index.
        assert_eq!(fused_label(&[2, 2], &tie, &[0.8, 0.4]).expect("valid"), 0);
        assert!(matches!(
            fused_label(&[0], &tie, &[1.0, 1.0]),
            Err(RecognizeError::Usage(UsageError::LabelCount {
                probabilities: 2,
                labels: 1
            }))
        ));
    }

    #[test]
    fn fitted_fusion_weighs_behaviours_by_their_cross_validated_accuracy() {
        // Two classes, three trials (groups). Behaviour 0 separates them perfectly; behaviour 1
        // puts class 1's trial 2 among class 0 (accuracy 5/6, as in the CV test above).
        static GOOD: [[f64; 1]; 6] = [[0.0], [0.1], [0.2], [5.0], [5.1], [5.2]];
        static POOR: [[f64; 1]; 6] = [[0.0], [0.1], [0.2], [5.0], [5.1], [0.25]];
        let (good, poor) = (&GOOD, &POOR);
        let labels = [0, 0, 0, 1, 1, 1];
        let groups = [0, 1, 2, 0, 1, 2];
        let data = |features: &'static [[f64; 1]]| BehaviourData {
            features,
            labels: &labels,
            groups: &groups,
        };
        let params = KnnParams::default().k(1).scaling(FeatureScaling::None);
        let fusion = ReliabilityFusion::fit(params, &[data(good), data(poor)], 2, 3).expect("valid");
        assert_eq!(fusion.weights(), &[1.0, 5.0 / 6.0]);
        // Behaviour 0 says 1 (near 5), behaviour 1 says 0 (near 0.1): the reliable one wins
        // with 1/(1 + 5/6) = 6/11.
        let p = fusion
            .predict_proba(&[Some(&[4.9]), Some(&[0.12])])
            .expect("valid");
        assert!((p[1] - 6.0 / 11.0).abs() < 1e-12, "{p:?}");
        assert_eq!(fusion.predict(&[Some(&[4.9]), Some(&[0.12])]).expect("valid"), 1);
        // Only behaviour 1 performed: its answer alone.
        assert_eq!(fusion.predict(&[None, Some(&[0.12])]).expect("valid"), 0);
        assert!(matches!(
            fusion.predict(&[None, None]),
            Err(RecognizeError::Usage(UsageError::NothingToFuse))
        ));
        assert!(matches!(
            fusion.predict(&[None]),
            Err(RecognizeError::Usage(UsageError::QueryCount {
                queries: 1,
                behaviours: 2
            }))
        ));
        assert!(
            matches!(fusion.predict(&[Some(&[1.0, 2.0]), None]), Err(RecognizeError::FusedBehaviour {
            behaviour: 0,
            source }) if matches!(*source, RecognizeError::Usage(UsageError::Dimension {
                index: 0,
                expected: 1,
                got: 2
            })))
        );
        let one_group = [0, 0, 0, 0, 0, 0];
        let bad = BehaviourData {
            features: good,
            labels: &labels,
            groups: &one_group,
        };
        assert!(
            matches!(ReliabilityFusion::fit(params, &[data(good), bad], 2, 3), Err(RecognizeError::FusedBehaviour {
                behaviour: 1,
                source }) if matches!(*source, RecognizeError::Data(DataError::TooFewGroups { groups: 1, folds: 3 })))
        );
    }

    #[test]
    fn fusion_rejects_bad_input() {
        let a = [0.5, 0.5];
        assert!(matches!(
            fuse::<[f64; 2]>(&[], &[]),
            Err(RecognizeError::Usage(UsageError::NothingToFuse))
        ));
        assert!(matches!(
            fuse(&[a], &[1.0, 1.0]),
            Err(RecognizeError::Usage(UsageError::WeightCount {
                probabilities: 1,
                weights: 2
            }))
        ));
        assert!(matches!(
            fuse(&[&a[..], &[1.0][..]], &[1.0, 1.0]),
            Err(RecognizeError::Usage(UsageError::FusionClasses {
                index: 1,
                expected: 2,
                got: 1
            }))
        ));
        assert!(matches!(
            fuse(&[a], &[-0.1]),
            Err(RecognizeError::Usage(UsageError::BadWeight {
                index: 0,
                weight: -0.1
            }))
        ));
        assert!(matches!(
            fuse(&[a, a], &[0.0, 0.0]),
            Err(RecognizeError::Data(DataError::ZeroTotalWeight))
        ));
        assert_eq!(argmax(&[]), None);
        assert_eq!(argmax(&[0.2, 0.4, 0.4]), Some(1));
    }
}
