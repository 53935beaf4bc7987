//! Choosing C by cross-validation over a grid, with folds that keep a trial's scratches together.

use super::*;
use crate::fusion::BehaviourData;
use crate::{DataError, SettingError, SolverError, UsageError};

/// The values of C that [`select_c`] tries by default: 1 to 10⁵ in decades.
pub const C_GRID: [f64; 6] = [1.0, 10.0, 100.0, 1e3, 1e4, 1e5];

/// One C of a [`CSearch`] and its cross-validated accuracy.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CvPoint {
    /// The box constraint.
    pub c: f64,
    /// Fraction of held-out vectors classified correctly.
    pub accuracy: f64,
}

/// How C was chosen: each candidate's accuracy under cross-validation by group.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CSearch {
    /// Folds of the cross-validation (whole groups per fold, see
    /// [`crate::folds::group_folds`]).
    pub folds: usize,
    /// Every candidate that could be fitted, in the order tried (ascending C); one whose fit
    /// did not converge is left out (see [`select_c_observed`]).
    pub grid: Vec<CvPoint>,
    /// The most accurate candidate; ties go to the smaller C (the wider margin).
    pub chosen_c: f64,
    /// The smallest C at which no machine of any fold had a multiplier at its bound: every
    /// fold's classes were separated, so each larger candidate has the same machines and the
    /// same accuracy, and was entered in `grid` without being refitted. `None` if no candidate
    /// separated (or in files written before this was recorded).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub separable_from: Option<f64>,
    /// Where the search was over fewer vectors than the fit (windows far apart standing for
    /// all of them): each candidate C was fitted at C times this, all the vectors over those
    /// searched, at which they weigh the hinge loss as all the vectors do at C. `None`: every
    /// vector, at C.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub vector_weight: Option<f64>,
}

impl CSearch {
    /// Cross-validated accuracy of the chosen C.
    pub fn accuracy(&self) -> Option<f64> {
        self.grid
            .iter()
            .find(|p| p.c == self.chosen_c)
            .map(|p| p.accuracy)
    }

    /// Checks a search read from a file: `Err((field, reason))`.
    pub fn check(&self) -> Result<(), (&'static str, String)> {
        if self.folds < 2 {
            return Err(("folds", format!("{} folds; cross-validation needs 2", self.folds)));
        }
        if self.grid.is_empty() {
            return Err(("grid", "no candidate".into()));
        }
        if let Some(p) = self
            .grid
            .iter()
            .find(|p| !(p.c.is_finite() && p.c > 0.0 && (0.0..=1.0).contains(&p.accuracy)))
        {
            return Err((
                "grid",
                format!(
                    "C = {}, accuracy {}: C must be positive, accuracy in [0, 1]",
                    p.c, p.accuracy
                ),
            ));
        }
        if self.accuracy().is_none() {
            return Err(("chosen_c", format!("{} is not in the grid", self.chosen_c)));
        }
        if let Some(c) = self.separable_from
            && !self.grid.iter().any(|p| p.c == c)
        {
            return Err(("separable_from", format!("{c} is not in the grid")));
        }
        if let Some(w) = self.vector_weight
            && !(w.is_finite() && w >= 1.0)
        {
            return Err(("vector_weight", format!("{w}: must be finite and at least 1")));
        }
        Ok(())
    }
}

/// Accuracy of an SVC with `params` under cross-validation by group
/// ([`crate::folds::group_folds`]): all vectors of a group (a trial) are held out together.
///
/// A training fold that lacks some classes is fitted on the classes it has, and the held-out
/// vectors of the missing ones count as wrong (the classifier cannot name them); a fold with a
/// single class predicts it. Probabilities are not fitted (only votes are scored). The crate
/// itself scores C through [`select_c_observed`]; the tests call this directly.
#[cfg(test)]
pub fn cross_validated_accuracy<V: AsRef<[f64]>>(
    params: SvcParams,
    data: &BehaviourData<'_, V>,
    classes: usize,
    folds: usize,
) -> Result<f64, RecognizeError> {
    let (features, labels, groups) = (data.features, data.labels, data.groups);
    let (fold, folds) = cv_folds(features.len(), labels.len(), groups, folds)?;
    let params = SvcParams {
        probability: false,
        ..params
    };
    let mut correct = 0usize;
    for f in 0..folds {
        correct += fold_correct(params, features, labels, None, &fold, f, classes, &|| {})?.correct;
    }
    Ok(correct as f64 / features.len() as f64)
}

/// Picks C from `grid` by [`cross_validated_accuracy`] with `params`' other settings: the most
/// accurate C, ties to the smaller one. [`select_c_observed`] without progress, for the tests.
#[cfg(test)]
pub fn select_c<V: AsRef<[f64]>>(
    params: SvcParams,
    grid: &[f64],
    data: &BehaviourData<'_, V>,
    classes: usize,
    folds: usize,
) -> Result<CSearch, RecognizeError> {
    select_c_observed(params, grid, data, classes, folds, &no_progress)
}

/// [`select_c`], reporting to `progress` one [`FitEvent::Step`] whose units are the binary
/// machines of every candidate's every fold.
///
/// A candidate whose fit does not converge (or fails numerically) in some fold is left out of
/// the search with a [`FitEvent::SkippedC`]: one C at which SMO cannot finish says nothing
/// about the others. Only when every candidate fails is it an error
/// ([`SolverError::EveryCFailed`], listing them); the result lists the candidates that
/// could be cross-validated.
///
/// Once a candidate's machines have no multiplier at the bound in any fold, the larger
/// candidates are not refitted: SMO's stopping test (the largest KKT violation) reads C only
/// through the multipliers that sit on it, so the same multipliers are a solution, to the same
/// tolerance, for every larger C. Those candidates enter the grid with that accuracy and
/// [`CSearch::separable_from`] says so. On classes a degree-2 kernel separates this skips the
/// largest Cs, whose fits are the slowest (and the likeliest not to converge).
pub fn select_c_observed<V: AsRef<[f64]>>(
    params: SvcParams,
    grid: &[f64],
    data: &BehaviourData<'_, V>,
    classes: usize,
    folds: usize,
    progress: Progress<'_>,
) -> Result<CSearch, RecognizeError> {
    select_c_trained_on(params, grid, data, None, classes, folds, progress)
}

/// [`select_c_observed`] with each fold's machines fitted only on the vectors `trains` marks,
/// at each candidate C times all the vectors over those marked ([`CSearch::vector_weight`]);
/// every held-out vector is scored. Where vectors nearly repeat their neighbours (windows
/// every 0.1 s), the marked ones stand for the rest in training at a fraction of the cost,
/// and scoring all of them keeps the accuracies as fine-grained as a search over all.
pub fn select_c_sparse<V: AsRef<[f64]>>(
    params: SvcParams,
    grid: &[f64],
    data: &BehaviourData<'_, V>,
    trains: &[bool],
    classes: usize,
    folds: usize,
    progress: Progress<'_>,
) -> Result<CSearch, RecognizeError> {
    if trains.len() != data.features.len() {
        return Err(RecognizeError::Usage(UsageError::Counts {
            features: data.features.len(),
            labels: trains.len(),
        }));
    }
    select_c_trained_on(params, grid, data, Some(trains), classes, folds, progress)
}

fn select_c_trained_on<V: AsRef<[f64]>>(
    params: SvcParams,
    grid: &[f64],
    data: &BehaviourData<'_, V>,
    trains: Option<&[bool]>,
    classes: usize,
    folds: usize,
    progress: Progress<'_>,
) -> Result<CSearch, RecognizeError> {
    let (features, labels, groups) = (data.features, data.labels, data.groups);
    let (fold, used) = cv_folds(features.len(), labels.len(), groups, folds)?;
    let marked = trains.map_or(features.len(), |t| t.iter().filter(|&&t| t).count());
    let weight = repeat_weight(features.len(), marked);
    let mut order: Vec<f64> = grid.to_vec();
    order.sort_by(f64::total_cmp);
    order.dedup();
    if order.is_empty() {
        return Err(RecognizeError::Setting(SettingError::Parameter {
            of: "SVC parameter",
            name: "c",
            value: f64::NAN,
            reason: "an empty grid of C values",
        }));
    }
    let machines: usize = (0..used)
        .map(|f| {
            let mut present: Vec<usize> = labels
                .iter()
                .zip(&fold)
                .enumerate()
                .filter(|&(i, (_, &g))| g != f && trains.is_none_or(|t| t[i]))
                .map(|(_, (&y, _))| y)
                .collect();
            present.sort_unstable();
            present.dedup();
            present.len() * present.len().saturating_sub(1) / 2
        })
        .sum();
    progress(FitEvent::Step {
        what: "searching C (machines × folds × candidates)",
        total: machines * order.len(),
    });
    let tick = || progress(FitEvent::Advance);
    let params = SvcParams {
        probability: false,
        ..params
    };
    let mut points = Vec::with_capacity(order.len());
    let mut failures = Vec::new();
    let mut separable_from: Option<CvPoint> = None;
    for &c in &order {
        if let Some(separable) = separable_from {
            points.push(CvPoint { c, ..separable });
            for _ in 0..machines {
                tick();
            }
            continue;
        }
        let mut correct = 0usize;
        let mut at_bound = false;
        let mut failed = None;
        for f in 0..used {
            match fold_correct(
                SvcParams {
                    c: c * weight,
                    ..params
                },
                features,
                labels,
                trains,
                &fold,
                f,
                classes,
                &tick,
            ) {
                Ok(score) => {
                    correct += score.correct;
                    at_bound |= score.at_bound;
                }
                Err(RecognizeError::Solver(SolverError::NotConverged {
                    iterations,
                    c: _,
                    first,
                    second,
                    violation,
                    stop,
                })) => {
                    failed = Some((iterations, first, second, violation, stop));
                    break;
                }
                Err(e) => return Err(e),
            }
        }
        match failed {
            None => {
                let point = CvPoint {
                    c,
                    accuracy: correct as f64 / features.len() as f64,
                };
                points.push(point);
                if !at_bound {
                    separable_from = Some(point);
                }
            }
            Some((iterations, first, second, violation, stop)) => {
                let error = || {
                    RecognizeError::Solver(SolverError::NotConverged {
                        iterations,
                        c,
                        first,
                        second,
                        violation,
                        stop,
                    })
                };
                progress(FitEvent::SkippedC { c, error: error() });
                failures.push((c, error()));
            }
        }
    }
    // Ascending C, so a strict improvement is needed to move to a larger one.
    let Some(&first) = points.first() else {
        return Err(RecognizeError::Solver(SolverError::EveryCFailed { failures }));
    };
    let best = points.iter().fold(
        first,
        |best, p| if p.accuracy > best.accuracy { *p } else { best },
    );
    Ok(CSearch {
        folds: used,
        grid: points,
        chosen_c: best.c,
        separable_from: separable_from.map(|p| p.c),
        vector_weight: (marked < features.len()).then_some(weight),
    })
}

/// The factor on C at which `kept` of `all` near-repeating vectors weigh the hinge loss as all
/// of them do at C: repeating each vector k times weighs it as multiplying C by k does.
pub(crate) fn repeat_weight(all: usize, kept: usize) -> f64 {
    all as f64 / kept.max(1) as f64
}

/// Fold of each vector and the number of folds, after checking the counts.
pub(super) fn cv_folds(
    features: usize,
    labels: usize,
    groups: &[u64],
    folds: usize,
) -> Result<(Vec<usize>, usize), RecognizeError> {
    if features == 0 || features != labels || groups.len() != features {
        return Err(RecognizeError::Usage(UsageError::Counts {
            features,
            labels: if labels == features { groups.len() } else { labels },
        }));
    }
    crate::folds::group_folds(groups, folds).map_err(|_| {
        let mut distinct = groups.to_vec();
        distinct.sort_unstable();
        distinct.dedup();
        RecognizeError::Data(DataError::TooFewGroups {
            groups: distinct.len(),
            folds,
        })
    })
}

/// How an SVC fitted on the other folds did on fold `f`.
pub(super) struct FoldScore {
    /// Held-out vectors classified correctly.
    pub(super) correct: usize,
    /// Whether a machine has a multiplier at its bound C ([`Svc::any_multiplier_at_bound`]).
    pub(super) at_bound: bool,
}

/// [`FoldScore`] of fold `f`, trained on the other folds' vectors (those `trains` marks);
/// `tick` after each binary machine.
#[allow(clippy::too_many_arguments)]
pub(super) fn fold_correct<V: AsRef<[f64]>>(
    params: SvcParams,
    features: &[V],
    labels: &[usize],
    trains: Option<&[bool]>,
    fold: &[usize],
    f: usize,
    classes: usize,
    tick: &(dyn Fn() + Sync),
) -> Result<FoldScore, RecognizeError> {
    let (train_x, train_y): (Vec<&[f64]>, Vec<usize>) = features
        .iter()
        .zip(labels)
        .zip(fold)
        .enumerate()
        .filter(|&(i, (_, &g))| g != f && trains.is_none_or(|t| t[i]))
        .map(|(_, ((x, &y), _))| (x.as_ref(), y))
        .unzip();
    // The classes present in training, relabelled 0..m for the fit.
    let mut present: Vec<usize> = train_y.clone();
    present.sort_unstable();
    present.dedup();
    if let Some(&label) = present.iter().find(|&&l| l >= classes) {
        return Err(RecognizeError::Usage(UsageError::LabelOutOfRange {
            index: labels.iter().position(|&l| l == label).unwrap_or(0),
            label,
            classes,
        }));
    }
    let held_out = features
        .iter()
        .zip(labels)
        .zip(fold)
        .filter(|&(_, &g)| g == f)
        .map(|((x, &y), _)| (x.as_ref(), y));
    if present.len() < 2 {
        let only = present.first().copied();
        return Ok(FoldScore {
            correct: held_out.filter(|&(_, y)| Some(y) == only).count(),
            at_bound: false,
        });
    }
    let compact: Vec<usize> = train_y
        .iter()
        .map(|y| present.binary_search(y).unwrap_or(0))
        .collect();
    // The fit sees the fold's classes as 0..m; its errors name the caller's classes.
    let global = |i: usize| present.get(i).copied().unwrap_or(i);
    let svc = Svc::fit_pairs(params, &train_x, &compact, present.len(), tick).map_err(|e| match e {
        RecognizeError::Solver(SolverError::NotConverged {
            iterations,
            c,
            first,
            second,
            violation,
            stop,
        }) => RecognizeError::Solver(SolverError::NotConverged {
            iterations,
            c,
            first: global(first),
            second: global(second),
            violation,
            stop,
        }),
        RecognizeError::Data(DataError::EmptyClass { class }) => {
            RecognizeError::Data(DataError::EmptyClass { class: global(class) })
        }
        e => e,
    })?;
    // The held-out vectors on all cores: with a sparse search they are five times those trained.
    let held_out: Vec<(&[f64], usize)> = held_out.collect();
    let correct = held_out
        .par_iter()
        .map(|&(x, y)| svc.predict(x).map(|p| usize::from(present[p] == y)))
        .sum::<Result<usize, RecognizeError>>()?;
    Ok(FoldScore {
        correct,
        at_bound: svc.any_multiplier_at_bound(),
    })
}
