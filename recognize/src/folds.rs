//! Cross-validation by group: every sample of a recording or trial stays on one side of a
//! split, so a model is never scored on the recording it learnt from.

use crate::DataError;
use crate::RecognizeError;

/// Fold of each sample when whole groups (recordings, trials) are dealt out to `folds` folds:
/// the distinct group ids, sorted, go round-robin to folds `0, 1, …`. All samples of a group
/// share a fold, so a recording is never on both sides of a split. With fewer groups than folds
/// each group is its own fold (leave-one-group-out).
pub fn group_folds(groups: &[u64], folds: usize) -> Result<(Vec<usize>, usize), RecognizeError> {
    let mut distinct: Vec<u64> = groups.to_vec();
    distinct.sort_unstable();
    distinct.dedup();
    if distinct.len() < 2 || folds < 2 {
        return Err(RecognizeError::Data(DataError::TooFewGroups {
            groups: distinct.len(),
            folds,
        }));
    }
    let folds = folds.min(distinct.len());
    let fold = groups
        .iter()
        .map(|g| distinct.binary_search(g).map_or(0, |rank| rank % folds))
        .collect();
    Ok((fold, folds))
}

/// Correct decisions on held-out samples under the folds of [`group_folds`] (`fold` of each
/// sample, `folds` of them): each fold is held out once, and each of its samples is predicted
/// (`predict`) by a model fitted (`fit`) on the other folds' samples.
pub(crate) fn held_out_correct<V, M, E>(
    features: &[V],
    labels: &[usize],
    fold: &[usize],
    folds: usize,
    fit: impl FnMut(&[&V], &[usize]) -> Result<M, E>,
    predict: impl Fn(&M, &V) -> Result<usize, E>,
) -> Result<usize, E> {
    let predicted = held_out(features, labels, fold, folds, fit, predict)?;
    Ok(predicted
        .iter()
        .zip(labels)
        .filter(|&(p, y)| *p == Some(*y))
        .count())
}

/// What `predict` says of each sample when its fold is held out, in the samples' order: each
/// fold (`fold` of each sample, `folds` of them) is held out once, and its samples are
/// predicted by a model fitted (`fit`) on the other folds' samples. A sample whose fold is not
/// below `folds` is never held out: `None`.
pub(crate) fn held_out<V, M, E, T>(
    features: &[V],
    labels: &[usize],
    fold: &[usize],
    folds: usize,
    mut fit: impl FnMut(&[&V], &[usize]) -> Result<M, E>,
    predict: impl Fn(&M, &V) -> Result<T, E>,
) -> Result<Vec<Option<T>>, E> {
    let mut out: Vec<Option<T>> = std::iter::repeat_with(|| None).take(features.len()).collect();
    for f in 0..folds {
        let (train_x, train_y): (Vec<&V>, Vec<usize>) = features
            .iter()
            .zip(labels)
            .zip(fold)
            .filter(|&(_, &g)| g != f)
            .map(|((x, &y), _)| (x, y))
            .unzip();
        let model = fit(&train_x, &train_y)?;
        for ((x, slot), _) in features.iter().zip(&mut out).zip(fold).filter(|&(_, &g)| g == f) {
            *slot = Some(predict(&model, x)?);
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn folds_keep_groups_together() {
        let groups = [7, 7, 3, 3, 9, 1, 1];
        let (fold, n) = group_folds(&groups, 3).expect("enough groups");
        assert_eq!(n, 3);
        // Sorted groups 1, 3, 7, 9 → folds 0, 1, 2, 0.
        assert_eq!(fold, vec![2, 2, 1, 1, 0, 0, 0]);
        let (_, n) = group_folds(&groups, 10).expect("enough groups");
        assert_eq!(n, 4, "leave-one-group-out when groups < folds");
        assert!(matches!(
            group_folds(&[5, 5], 10),
            Err(RecognizeError::Data(DataError::TooFewGroups {
                groups: 1,
                folds: 10
            }))
        ));
    }
}
