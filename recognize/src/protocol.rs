//! The papers' evaluation protocols over many recordings: a recognizer is trained and tested
//! again and again on captures split by recording, and the decisions are pooled.
//!
//! - **k-fold by recording** (Sinapov Sec. V): the recordings (metadata `trial`, else `run`, else
//!   each capture alone) are dealt round-robin into `k` folds in their numeric order; each fold is
//!   held out once while the rest train. With `trial=0…9` and 10 folds, fold `t` is trial `t` of
//!   every surface, as Sinapov's 10-fold cross-validation. A scratch is never on both sides.
//! - **train on one** (Nakano Sec. 4.3): each fold trains alone and the others are held out —
//!   with Nakano's three runs per surface, one run trains and two test, three times over.
//!
//! A SOM is also trained with several seeds per fold and the decisions pooled, as Fig. 4.15
//! averages 10 maps (pooled counts over tests of equal size are the mean of their rates).
//!
//! Recognizers whose behaviours are fused (k-NN and SVM over scratches) are scored further as
//! Sinapov's Table II and Fig. 6 do: each behaviour alone, and every combination of `n` of the
//! behaviours fused (the held-out trial's scratches by those behaviours only), for each `n`.

use std::borrow::Borrow;
use std::collections::BTreeSet;

use super::eval::ConfusionMatrix;
use crate::RecognizeError;
use crate::recognizer::{Evaluation, LabelledCapture, RecognizerFile, recording_groups};
use crate::{DataError, InputError, SettingError};

/// Folds of Sinapov's cross-validation.
pub const SINAPOV_FOLDS: usize = 10;

/// Distinct recordings among `captures` (see [`recording_groups`]).
pub fn recordings(captures: &[LabelledCapture]) -> usize {
    recording_groups(captures).iter().collect::<BTreeSet<_>>().len()
}

/// Most behaviours whose every combination is fused (2¹⁰ − 1 = 1023 combinations).
pub const MAX_COMBINED_BEHAVIOURS: usize = 10;

/// How the recordings are split.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Split {
    /// Each fold held out once, the rest train (Sinapov).
    KFold {
        /// Folds.
        folds: usize,
    },
    /// Each fold trains once, the rest are held out (Nakano).
    TrainOnOne {
        /// Folds.
        folds: usize,
    },
}

impl Split {
    /// Number of folds.
    pub fn folds(self) -> usize {
        match self {
            Self::KFold { folds } | Self::TrainOnOne { folds } => folds,
        }
    }

    /// The name the command line and reports use.
    pub fn name(self) -> &'static str {
        match self {
            Self::KFold { .. } => "k-fold",
            Self::TrainOnOne { .. } => "train-on-one",
        }
    }
}

/// Fold (0-based) of each capture: its recording's rank among the distinct recordings, modulo
/// `folds`.
pub fn fold_of_each(captures: &[LabelledCapture], folds: usize) -> Result<Vec<usize>, RecognizeError> {
    let groups = recording_groups(captures);
    let recordings = recordings(captures);
    if folds < 2 || recordings < folds {
        return Err(RecognizeError::Data(DataError::Folds { recordings, folds }));
    }
    // Groups are numbered densely from 0 in the recordings' order.
    Ok(groups.iter().map(|&g| g as usize % folds).collect())
}

/// Behaviours fused together, and their pooled result.
#[derive(Debug, Clone)]
pub struct Combination {
    /// The behaviours' names (`None`: captures without a behaviour).
    pub behaviours: Vec<Option<String>>,
    /// One decision per held-out trial, fused over these behaviours' scratches, pooled over
    /// folds and seeds.
    pub confusion: ConfusionMatrix<String>,
}

/// Mean and range of the accuracies of every combination of `n` behaviours (Sinapov Fig. 6).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FusedByCount {
    /// Behaviours fused.
    pub behaviours: usize,
    /// Combinations of that many.
    pub combinations: usize,
    /// Mean accuracy over them.
    pub mean_accuracy: f64,
    /// The worst combination's accuracy.
    pub min_accuracy: f64,
    /// The best combination's accuracy.
    pub max_accuracy: f64,
}

/// The pooled result of a protocol.
#[derive(Debug, Clone)]
pub struct ProtocolResult {
    /// The split.
    pub split: Split,
    /// Seeds per fold (SOM maps pooled; 1 for deterministic recognizers).
    pub seeds: usize,
    /// Recognizers trained (folds × seeds).
    pub rounds: usize,
    /// Every decision of every round, pooled, with the time measures averaged over rounds
    /// weighted by the captures each counted (see [`pool`]).
    pub evaluation: Evaluation,
    /// Each behaviour alone (its classifier's own predictions), pooled; empty for a recognizer
    /// without fusion.
    pub per_behaviour: Vec<(Option<String>, ConfusionMatrix<String>)>,
    /// Every non-empty combination of behaviours fused, pooled (up to
    /// [`MAX_COMBINED_BEHAVIOURS`] behaviours; else only all of them); empty without fusion.
    pub combinations: Vec<Combination>,
}

impl ProtocolResult {
    /// For each number of behaviours, the mean, worst and best accuracy of its combinations.
    pub fn fused_by_count(&self) -> Vec<FusedByCount> {
        let most = self
            .combinations
            .iter()
            .map(|c| c.behaviours.len())
            .max()
            .unwrap_or(0);
        (1..=most)
            .filter_map(|n| {
                let acc: Vec<f64> = self
                    .combinations
                    .iter()
                    .filter(|c| c.behaviours.len() == n)
                    .filter_map(|c| c.confusion.accuracy())
                    .collect();
                (!acc.is_empty()).then(|| FusedByCount {
                    behaviours: n,
                    combinations: acc.len(),
                    mean_accuracy: acc.iter().sum::<f64>() / acc.len() as f64,
                    min_accuracy: acc.iter().copied().fold(f64::INFINITY, f64::min),
                    max_accuracy: acc.iter().copied().fold(f64::NEG_INFINITY, f64::max),
                })
            })
            .collect()
    }

    /// The combination of every behaviour, fused.
    pub fn fused_all(&self) -> Option<&Combination> {
        self.combinations.iter().max_by_key(|c| c.behaviours.len())
    }

    /// The best accuracy of a single behaviour alone.
    pub fn best_single_accuracy(&self) -> Option<f64> {
        self.per_behaviour
            .iter()
            .filter_map(|(_, m)| m.accuracy())
            .reduce(f64::max)
    }
}

/// Runs `split` over `captures` — every fold, or only fold `only` (from 1) — training each
/// round's recognizer with `train(training captures, seed)` for seeds `0..seeds`.
///
/// `train` is the same call `palpus recognize train` makes, so the protocol measures exactly
/// the recognizer a user would train. Nakano's own protocol is train-on-one with `only` the
/// fold of the first run and 10 seeds.
pub fn run<F>(
    captures: &[LabelledCapture],
    split: Split,
    seeds: u64,
    only: Option<usize>,
    mut train: F,
) -> Result<ProtocolResult, RecognizeError>
where
    F: FnMut(&[LabelledCapture], u64) -> Result<RecognizerFile, Box<RecognizeError>>,
{
    if seeds == 0 {
        return Err(RecognizeError::Setting(SettingError::NoSeeds));
    }
    let folds = split.folds();
    let fold_of = fold_of_each(captures, folds)?;
    if let Some(fold) = only
        && !(1..=folds).contains(&fold)
    {
        return Err(RecognizeError::Setting(SettingError::NoSuchFold { fold, folds }));
    }
    let mut evaluations = Vec::new();
    let mut per_behaviour: Vec<(Option<String>, ConfusionMatrix<String>)> = Vec::new();
    let mut combinations: Vec<Combination> = Vec::new();
    let mut classes: Option<Vec<String>> = None;
    for fold in (0..folds).filter(|f| only.is_none_or(|o| o == f + 1)) {
        let trains = |i: usize| match split {
            Split::KFold { .. } => fold_of[i] != fold,
            Split::TrainOnOne { .. } => fold_of[i] == fold,
        };
        let training: Vec<LabelledCapture> = (0..captures.len())
            .filter(|&i| trains(i))
            .map(|i| captures[i].clone())
            .collect();
        let held_out: Vec<&LabelledCapture> = (0..captures.len())
            .filter(|&i| !trains(i))
            .map(|i| &captures[i])
            .collect();
        for seed in 0..seeds {
            let at = |source: RecognizeError| RecognizeError::Fold {
                fold: fold + 1,
                folds,
                seed,
                source: Box::new(source),
            };
            let model = train(&training, seed).map_err(|source| RecognizeError::Fold {
                fold: fold + 1,
                folds,
                seed,
                source,
            })?;
            match &classes {
                None => classes = Some(model.classes.clone()),
                Some(expected) if *expected != model.classes => {
                    return Err(RecognizeError::Data(DataError::FoldClasses {
                        fold: fold + 1,
                        got: model.classes.clone(),
                        expected: expected.clone(),
                    }));
                }
                Some(_) => {}
            }
            evaluations.push(model.evaluate(&held_out, None).map_err(at)?);
            score_behaviours(&model, &held_out, &mut per_behaviour, &mut combinations).map_err(at)?;
        }
    }
    Ok(ProtocolResult {
        split,
        seeds: seeds as usize,
        rounds: evaluations.len(),
        evaluation: pool(&evaluations)
            .map_err(|e| RecognizeError::Fold {
                fold: 1,
                folds,
                seed: 0,
                source: Box::new(e),
            })?
            .ok_or(RecognizeError::Setting(SettingError::NoSeeds))?,
        per_behaviour,
        combinations,
    })
}

/// Sinapov's surface-based cross-validation (Sec. IV-D): for each surface, a recognizer is
/// trained with `train` on every other surface and classifies each decision of the left-out
/// surface's captures, so every decision is an error and shows which known surface the unknown
/// one resembles. Returns the confusion over all surfaces (rows: the left-out surface; its
/// diagonal is empty), the input of [`super::category::similarity_from_confusion`].
pub fn surface_confusion<F>(
    captures: &[LabelledCapture],
    mut train: F,
) -> Result<ConfusionMatrix<String>, RecognizeError>
where
    F: FnMut(&[LabelledCapture], u64) -> Result<RecognizerFile, Box<RecognizeError>>,
{
    let surfaces: Vec<String> = captures
        .iter()
        .map(|c| c.label.clone())
        .collect::<BTreeSet<_>>()
        .into_iter()
        .collect();
    if surfaces.len() < 3 {
        return Err(RecognizeError::Data(DataError::Surfaces {
            surfaces: surfaces.len(),
        }));
    }
    let folds = surfaces.len();
    let mut confusion = ConfusionMatrix::new(surfaces.clone()).map_err(|e| RecognizeError::Fold {
        fold: 1,
        folds,
        seed: 0,
        source: Box::new(e),
    })?;
    for (fold, surface) in surfaces.iter().enumerate() {
        let at = |source: Box<RecognizeError>| RecognizeError::Fold {
            fold: fold + 1,
            folds,
            seed: 0,
            source,
        };
        let training: Vec<LabelledCapture> =
            captures.iter().filter(|c| c.label != *surface).cloned().collect();
        let model = train(&training, 0).map_err(at)?;
        for c in captures.iter().filter(|c| c.label == *surface) {
            for d in model.decisions(c, None).map_err(|e| at(Box::new(e)))? {
                let predicted = model.classes.get(d.label).ok_or_else(|| {
                    at(Box::new(RecognizeError::Input(InputError::UnusableCapture {
                        path: c.reference.path.clone(),
                        reason: format!("decision names class {} of {}", d.label, model.classes.len()),
                    })))
                })?;
                confusion.add(surface, predicted).map_err(|e| at(Box::new(e)))?;
            }
        }
    }
    Ok(confusion)
}

/// Scores a fused recognizer's behaviours on the held-out captures: each alone, and every
/// combination fused; merged into the running totals.
fn score_behaviours(
    model: &RecognizerFile,
    held_out: &[&LabelledCapture],
    per_behaviour: &mut Vec<(Option<String>, ConfusionMatrix<String>)>,
    combinations: &mut Vec<Combination>,
) -> Result<(), RecognizeError> {
    let Some(all) = model.evaluate_fused(held_out)? else {
        return Ok(());
    };
    for b in &all.per_behaviour {
        merge_into(per_behaviour, &b.behaviour, &b.confusion)?;
    }
    // The behaviours the held-out captures show, in the recognizer's order.
    let present: Vec<Option<String>> = all.per_behaviour.iter().map(|b| b.behaviour.clone()).collect();
    let subsets: Vec<Vec<usize>> = if present.len() <= MAX_COMBINED_BEHAVIOURS {
        (1u32..1 << present.len())
            .map(|mask| (0..present.len()).filter(|&i| mask & (1 << i) != 0).collect())
            .collect()
    } else {
        vec![(0..present.len()).collect()]
    };
    for subset in subsets {
        let names: Vec<Option<String>> = subset.iter().map(|&i| present[i].clone()).collect();
        let confusion = if names.len() == present.len() {
            all.confusion.clone()
        } else {
            let chosen: Vec<&LabelledCapture> = held_out
                .iter()
                .copied()
                .filter(|c| names.contains(&c.behaviour))
                .collect();
            match model.evaluate_fused(&chosen)? {
                Some(f) => f.confusion,
                None => continue,
            }
        };
        match combinations.iter_mut().find(|c| c.behaviours == names) {
            Some(c) => c.confusion.merge(&confusion)?,
            None => combinations.push(Combination {
                behaviours: names,
                confusion,
            }),
        }
    }
    Ok(())
}

fn merge_into(
    totals: &mut Vec<(Option<String>, ConfusionMatrix<String>)>,
    behaviour: &Option<String>,
    confusion: &ConfusionMatrix<String>,
) -> Result<(), RecognizeError> {
    match totals.iter_mut().find(|(b, _)| b == behaviour) {
        Some((_, m)) => m.merge(confusion)?,
        None => totals.push((behaviour.clone(), confusion.clone())),
    }
    Ok(())
}

/// Pools evaluations of one recognizer kind: confusions summed; the time to the first correct
/// and to a stable decision averaged over the captures that had one, flips per second and the
/// window averaged over rounds weighted by their captures; captures without a decision listed
/// as each round found them (a capture held out in several rounds, once per round, as it is
/// counted in `captures`). `None` for no evaluations.
pub fn pool<E: Borrow<Evaluation>>(evaluations: &[E]) -> Result<Option<Evaluation>, RecognizeError> {
    let mut it = evaluations.iter().map(Borrow::borrow);
    let Some(first) = it.next() else {
        return Ok(None);
    };
    let mut out = first.clone();
    let weighted = |v: Option<f64>, n: usize| v.map(|v| (v * n as f64, n));
    let mut first_correct = weighted(
        first.time_to_first_correct_s,
        first.captures - first.never_correct,
    );
    let mut stable = weighted(first.time_to_stable_s, first.captures - first.not_stable);
    let mut flips = first.flips_per_s * first.captures as f64;
    let (mut window, mut latency) = (
        first.window_s * first.captures as f64,
        first.decision_latency_s * first.captures as f64,
    );
    let add = |acc: &mut Option<(f64, usize)>, v: Option<(f64, usize)>| {
        if let Some((s, n)) = v {
            let (a, m) = acc.get_or_insert((0.0, 0));
            *a += s;
            *m += n;
        }
    };
    for e in it {
        out.confusion.merge(&e.confusion)?;
        add(
            &mut first_correct,
            weighted(e.time_to_first_correct_s, e.captures - e.never_correct),
        );
        add(
            &mut stable,
            weighted(e.time_to_stable_s, e.captures - e.not_stable),
        );
        flips += e.flips_per_s * e.captures as f64;
        window += e.window_s * e.captures as f64;
        latency += e.decision_latency_s * e.captures as f64;
        out.captures += e.captures;
        out.never_correct += e.never_correct;
        out.not_stable += e.not_stable;
        out.windowless.extend(e.windowless.iter().cloned());
    }
    let mean = |acc: Option<(f64, usize)>| acc.and_then(|(s, n)| (n > 0).then(|| s / n as f64));
    let n = out.captures.max(1) as f64;
    out.time_to_first_correct_s = mean(first_correct);
    out.time_to_stable_s = mean(stable);
    out.flips_per_s = flips / n;
    out.window_s = window / n;
    out.decision_latency_s = latency / n;
    Ok(Some(out))
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use super::*;
    use capture::{Capture, CaptureKind, Metadata};

    /// A two-sample rubbing capture of `surface`, with `key=value` metadata if given.
    fn capture(surface: &str, recording: Option<(&str, &str)>) -> LabelledCapture {
        let kind = CaptureKind::Rubbing;
        let mut meta = Metadata::new(kind, "test", 1000.0).with("surface", surface);
        if let Some((key, value)) = recording {
            meta = meta.with(key, value);
        }
        let columns: Vec<String> = kind.required_columns().iter().map(|c| (*c).to_owned()).collect();
        let data = columns
            .iter()
            .map(|c| {
                if c == "time_s" {
                    vec![0.0, 1e-3]
                } else {
                    vec![0.0; 2]
                }
            })
            .collect();
        let capture = Capture::new(meta, columns, data).expect("capture");
        LabelledCapture::new(capture, Path::new("c.csv"), String::new()).expect("labelled")
    }

    #[test]
    fn folds_hold_whole_recordings_dealt_in_numeric_order() {
        // Trials 0..12 of two surfaces, listed out of order: trial t of both surfaces shares
        // its fold, and trial 10 follows 9 (numeric, not string, order).
        let mut captures = Vec::new();
        for t in [10, 3, 0, 11, 7, 1, 2, 9, 4, 5, 6, 8] {
            for surface in ["a", "b"] {
                captures.push(capture(surface, Some(("trial", &t.to_string()))));
            }
        }
        let folds = fold_of_each(&captures, 5).expect("12 trials in 5 folds");
        for (c, fold) in captures.iter().zip(&folds) {
            let trial: usize = c
                .capture
                .metadata()
                .get("trial")
                .expect("trial")
                .parse()
                .expect("number");
            assert_eq!(*fold, trial % 5, "trial {trial}");
        }
        assert_eq!(recordings(&captures), 12);
        // Runs count as recordings when there is no trial; a capture with neither is its own.
        let runs = [
            capture("a", Some(("run", "0"))),
            capture("a", Some(("run", "1"))),
            capture("b", Some(("run", "1"))),
            capture("b", None),
        ];
        assert_eq!(fold_of_each(&runs, 3).expect("3 recordings"), [0, 1, 1, 2]);
        assert!(matches!(
            fold_of_each(&runs, 4),
            Err(RecognizeError::Data(DataError::Folds {
                recordings: 3,
                folds: 4
            }))
        ));
        assert!(matches!(
            fold_of_each(&runs, 1),
            Err(RecognizeError::Data(DataError::Folds { folds: 1, .. }))
        ));
    }

    #[test]
    fn leaving_a_surface_out_needs_three() {
        let two = [capture("a", None), capture("b", None)];
        let mut trained = 0;
        let result = surface_confusion(&two, |_, _| {
            trained += 1;
            Err(Box::new(RecognizeError::Data(DataError::NoTrainingData)))
        });
        assert!(matches!(
            result,
            Err(RecognizeError::Data(DataError::Surfaces { surfaces: 2 }))
        ));
        assert_eq!(trained, 0);
        // With three, a training failure names its fold.
        let three = [capture("a", None), capture("b", None), capture("c", None)];
        let result = surface_confusion(&three, |_, _| {
            Err(Box::new(RecognizeError::Data(DataError::NoTrainingData)))
        });
        assert!(matches!(
            result,
            Err(RecognizeError::Fold {
                fold: 1,
                folds: 3,
                ..
            })
        ));
    }

    #[test]
    fn pooled_evaluations_sum_decisions_and_weigh_times_by_captures() {
        let classes = vec!["a".to_owned(), "b".to_owned()];
        let evaluation = |right: usize, wrong: usize, captures: usize, first_s: Option<f64>, never: usize| {
            let mut confusion = ConfusionMatrix::new(classes.clone()).expect("classes");
            for _ in 0..right {
                confusion.add(&classes[0], &classes[0]).expect("add");
            }
            for _ in 0..wrong {
                confusion.add(&classes[1], &classes[0]).expect("add");
            }
            Evaluation {
                method: "som",
                confusion,
                window_s: captures as f64,
                decision_latency_s: captures as f64 + 0.27,
                time_to_first_correct_s: first_s,
                time_to_stable_s: first_s,
                flips_per_s: 0.1 * captures as f64,
                captures,
                never_correct: never,
                not_stable: never,
                windowless: Vec::new(),
            }
        };
        let pooled = pool(&[
            evaluation(9, 1, 2, Some(4.0), 0),
            evaluation(5, 5, 4, Some(7.0), 2),
            evaluation(0, 3, 1, None, 1),
        ])
        .expect("same classes")
        .expect("three");
        assert_eq!(pooled.confusion.counts(), [vec![14, 0], vec![9, 0]]);
        assert_eq!(pooled.captures, 7);
        assert_eq!(pooled.never_correct, 3);
        // (2 × 4 s + 2 × 7 s) / 4 captures that were ever right.
        assert!((pooled.time_to_first_correct_s.expect("some") - 5.5).abs() < 1e-12);
        // (2 × 0.2 + 4 × 0.4 + 1 × 0.1) / 7.
        assert!((pooled.flips_per_s - 2.1 / 7.0).abs() < 1e-12);
        // Windows of 2, 4 and 1 s, weighted by their 2, 4 and 1 captures: 21 / 7 s.
        assert!((pooled.window_s - 3.0).abs() < 1e-12);
        assert!((pooled.decision_latency_s - 3.27).abs() < 1e-12);
        assert!(pool::<Evaluation>(&[]).expect("nothing to merge").is_none());
    }
}
