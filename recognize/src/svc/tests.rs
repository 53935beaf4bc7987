//! The one-vs-one SVC against scikit-learn's decisions and probabilities, pairwise coupling,
//! the C search against a brute-force one (ties, separable folds, candidates that do not
//! converge), and bad input.

use super::*;
use crate::fusion::BehaviourData;
use crate::{DataError, InputError, SettingError, SolverError, UsageError};

/// The triple the cross-validations take, named.
fn data<'a, V>(x: &'a [V], y: &'a [usize], groups: &'a [u64]) -> BehaviourData<'a, V> {
    BehaviourData {
        features: x,
        labels: y,
        groups,
    }
}

#[derive(serde::Deserialize)]
struct Fixture {
    c: f64,
    gamma: f64,
    coef0: f64,
    classes: usize,
    x_train: Vec<Vec<f64>>,
    y_train: Vec<usize>,
    x_test: Vec<Vec<f64>>,
    decision_ovo: Vec<Vec<f64>>,
    predicted: Vec<usize>,
    n_support: Vec<usize>,
    coupling: Vec<Coupling>,
}

#[derive(serde::Deserialize)]
struct Coupling {
    r: Vec<Vec<f64>>,
    p: Vec<f64>,
}

fn fixture() -> Fixture {
    serde_json::from_str(include_str!("../../fixtures/svc_poly2_4class.json")).expect("fixture")
}

#[test]
fn decision_values_and_predictions_match_scikit_learn() {
    let f = fixture();
    let params = SvcParams {
        c: f.c,
        kernel: Kernel::Polynomial {
            gamma: f.gamma,
            coef0: f.coef0,
            degree: 2,
        },
        tolerance: 1e-10,
        scaling: FeatureScaling::None,
        probability: false,
        seed: 0,
        max_iterations: 0,
        time_budget: None,
    };
    let svc = Svc::fit(params, &f.x_train, &f.y_train, f.classes).expect("fit");
    let mut worst: f64 = 0.0;
    for ((x, expected), label) in f.x_test.iter().zip(&f.decision_ovo).zip(&f.predicted) {
        let dec = svc.decision_values(x).expect("query");
        for (a, b) in dec.iter().zip(expected) {
            worst = worst.max((a - b).abs());
        }
        assert_eq!(svc.predict(x).expect("query"), *label, "{dec:?} vs {expected:?}");
    }
    // libsvm caches the kernel matrix in single precision (`Qfloat`), so its decision
    // values carry errors of ~1e-7 relative per kernel entry; ours are in double.
    assert!(worst < 1e-5, "largest decision difference {worst}");
    // Support vectors per class, counted as libsvm does (a point is one if any pair uses it).
    // The classifier keeps only those points; each one's class is the side of a pair it
    // supports (`y α` positive for the pair's first class).
    let kept = svc.points.len() / svc.dim;
    let mut class_of = vec![None; kept];
    for m in svc.machines() {
        for &(t, coef) in &m.support {
            let class = if coef > 0.0 { m.classes.0 } else { m.classes.1 };
            assert!(class_of[t].is_none_or(|c| c == class), "point {t} on two sides");
            class_of[t] = Some(class);
        }
    }
    assert!(
        class_of.iter().all(Option::is_some),
        "a kept point no machine uses"
    );
    let per_class: Vec<usize> = (0..f.classes)
        .map(|c| class_of.iter().filter(|&&k| k == Some(c)).count())
        .collect();
    assert_eq!(per_class, f.n_support);
    assert!(kept < f.x_train.len(), "{kept} of {} kept", f.x_train.len());
    // Every kept point is a training point, in training order.
    let mut from = 0;
    for t in 0..kept {
        let row = &svc.points[t * svc.dim..(t + 1) * svc.dim];
        let found = (from..f.x_train.len())
            .find(|&u| f.x_train[u] == row)
            .expect("a training point");
        from = found + 1;
    }
}

#[test]
fn pairwise_coupling_finds_the_method_2_minimiser() {
    for case in fixture().coupling {
        let p = pairwise_coupling(&case.r);
        assert!((p.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        for (a, b) in p.iter().zip(&case.p) {
            assert!((a - b).abs() < 1e-9, "{p:?} vs {:?}", case.p);
        }
    }
    // Consistent pairwise probabilities r_ij = p_i / (p_i + p_j) give p back exactly.
    let truth = [0.5, 0.3, 0.2];
    let r: Vec<Vec<f64>> = (0..3)
        .map(|i| {
            (0..3)
                .map(|j| {
                    if i == j {
                        0.0
                    } else {
                        truth[i] / (truth[i] + truth[j])
                    }
                })
                .collect()
        })
        .collect();
    let p = pairwise_coupling(&r);
    for (a, b) in p.iter().zip(truth) {
        assert!((a - b).abs() < 1e-10, "{p:?}");
    }
}

#[test]
fn probabilities_follow_the_classes_and_platt_fits_a_separable_sample() {
    let f = fixture();
    let svc = Svc::fit(
        SvcParams {
            c: f.c,
            kernel: Kernel::Polynomial {
                gamma: f.gamma,
                coef0: f.coef0,
                degree: 2,
            },
            scaling: FeatureScaling::None,
            ..SvcParams::default()
        },
        &f.x_train,
        &f.y_train,
        f.classes,
    )
    .expect("fit");
    let mut agree = 0;
    for x in &f.x_test {
        let p = svc.predict_proba(x).expect("probabilities");
        assert!((p.iter().sum::<f64>() - 1.0).abs() < 1e-9 && p.iter().all(|v| (0.0..=1.0).contains(v)));
        let best = p
            .iter()
            .enumerate()
            .fold(0, |b, (i, v)| if *v > p[b] { i } else { b });
        agree += usize::from(best == svc.predict(x).expect("predict"));
    }
    assert!(agree * 10 >= f.x_test.len() * 8, "{agree} of {}", f.x_test.len());
    // Separable decisions: a sigmoid falling through 0 (A < 0, B ≈ 0 by symmetry), kept
    // from a step by the fit's regularised targets (3 + 1)/(3 + 2) and 1/(3 + 2).
    let dec = [-2.0, -1.5, -1.0, 1.0, 1.5, 2.0];
    let y = [-1.0, -1.0, -1.0, 1.0, 1.0, 1.0];
    let (a, b) = sigmoid_train(&dec, &y);
    assert!(a < -0.5 && b.abs() < 1e-6, "{a} {b}");
    assert!(sigmoid_predict(2.0, a, b) > 0.75 && sigmoid_predict(-2.0, a, b) < 0.25);
}

/// Three overlapping classes in the plane, `per_group` points of each in each of `groups`
/// groups (trials), from a fixed seed.
/// A degree-2 polynomial SVC on unscaled inputs, as the blobs' C searches use it.
fn blob_params() -> SvcParams {
    SvcParams {
        kernel: Kernel::Polynomial {
            gamma: 1.0,
            coef0: 1.0,
            degree: 2,
        },
        scaling: FeatureScaling::None,
        ..SvcParams::default()
    }
}

fn overlapping_blobs(groups: u64, per_group: usize) -> (Vec<[f64; 2]>, Vec<usize>, Vec<u64>) {
    blobs(groups, per_group, 1.2)
}

/// Three classes around fixed centres, uniform within `spread` of them.
fn blobs(groups: u64, per_group: usize, spread: f64) -> (Vec<[f64; 2]>, Vec<usize>, Vec<u64>) {
    let centres = [[0.0, 0.0], [1.0, 0.2], [0.4, 0.9]];
    let mut rng = SplitMix64::new(7);
    let (mut x, mut y, mut g) = (Vec::new(), Vec::new(), Vec::new());
    for group in 0..groups {
        for (class, centre) in centres.iter().enumerate() {
            for _ in 0..per_group {
                let (a, b) = (rng.next_f64() - 0.5, rng.next_f64() - 0.5);
                x.push([centre[0] + spread * a, centre[1] + spread * b]);
                y.push(class);
                g.push(group);
            }
        }
    }
    (x, y, g)
}

fn triple<T: Copy>(v: &[T]) -> Vec<T> {
    v.iter().flat_map(|e| [*e; 3]).collect()
}

/// Every vector repeated three times is the same problem as each once at three times C: a
/// search trained on one of each three at C × 3 scores every held-out vector as the search
/// over all of them does, and says what it weighed.
#[test]
fn a_search_trained_on_one_of_each_repeat_scores_as_one_over_all() {
    let (x, y, groups) = overlapping_blobs(4, 6);
    let (x3, y3, g3): (Vec<[f64; 2]>, Vec<usize>, Vec<u64>) = (triple(&x), triple(&y), triple(&groups));
    let trains: Vec<bool> = (0..x3.len()).map(|i| i % 3 == 0).collect();
    let params = SvcParams {
        tolerance: 1e-6,
        ..blob_params()
    };
    let grid = [1e-1, 1.0, 10.0, 100.0];
    let full = select_c(params, &grid, &data(&x3, &y3, &g3), 3, 4).expect("all");
    let sparse = select_c_sparse(params, &grid, &data(&x3, &y3, &g3), &trains, 3, 4, &no_progress)
        .expect("one of three");
    assert_eq!(full.vector_weight, None);
    assert_eq!(sparse.vector_weight, Some(3.0));
    sparse.check().expect("valid");
    for (a, b) in full.grid.iter().zip(&sparse.grid) {
        assert_eq!(a.c, b.c);
        assert!((a.accuracy - b.accuracy).abs() < 1e-12, "{full:?} vs {sparse:?}");
    }
    assert_eq!(full.chosen_c, sparse.chosen_c);
    // Every vector marked: the plain search.
    let all = select_c_sparse(
        params,
        &grid,
        &data(&x3, &y3, &g3),
        &vec![true; x3.len()],
        3,
        4,
        &no_progress,
    )
    .expect("all marked");
    assert_eq!(all, full);
    assert!(
        select_c_sparse(
            params,
            &grid,
            &data(&x3, &y3, &g3),
            &trains[1..],
            3,
            4,
            &no_progress
        )
        .is_err()
    );
}

#[test]
fn inner_cross_validation_picks_the_c_of_a_brute_force_search() {
    let (x, y, groups) = overlapping_blobs(4, 6);
    let params = blob_params();
    let grid = [1e-2, 1e-1, 1.0, 10.0, 100.0, 1e3];
    // Brute force: leave each group out in turn (4 groups, 4 folds), fit on the rest with
    // every class present, count the held-out points classified right.
    let brute: Vec<f64> = grid
        .iter()
        .map(|&c| {
            let mut right = 0;
            for held in 0..4 {
                let train: Vec<usize> = (0..x.len()).filter(|&i| groups[i] != held).collect();
                let tx: Vec<[f64; 2]> = train.iter().map(|&i| x[i]).collect();
                let ty: Vec<usize> = train.iter().map(|&i| y[i]).collect();
                let svc = Svc::fit(SvcParams { c, ..params }, &tx, &ty, 3).expect("fit");
                right += (0..x.len())
                    .filter(|&i| groups[i] == held && svc.predict(&x[i]).expect("predict") == y[i])
                    .count();
            }
            right as f64 / x.len() as f64
        })
        .collect();
    let best = brute
        .iter()
        .enumerate()
        .fold(0, |b, (i, &a)| if a > brute[b] { i } else { b });
    // The grid (given unordered, with a repeat) is searched in ascending order.
    let unordered = [1e3, 1.0, 1e-2, 100.0, 1e-1, 10.0, 1.0];
    let search = select_c(params, &unordered, &data(&x, &y, &groups), 3, 4).expect("search");
    eprintln!("brute force {brute:?}, search {search:?}");
    assert_eq!(search.folds, 4);
    assert_eq!(search.grid.iter().map(|p| p.c).collect::<Vec<_>>(), grid);
    for (p, a) in search.grid.iter().zip(&brute) {
        assert!((p.accuracy - a).abs() < 1e-15, "{search:?} vs {brute:?}");
    }
    assert_eq!(search.chosen_c, grid[best]);
    assert_eq!(search.accuracy(), Some(brute[best]));
    assert!(search.check().is_ok());
    // The problem discriminates: the candidates do not all score the same, and the choice
    // is an inner one (neither the smallest nor the largest C).
    assert!(brute.iter().any(|&a| a != brute[0]), "{brute:?}");
    assert!(best > 0 && best < grid.len() - 1, "{brute:?}");
    // Measured: C = 100 and 1000 tie at 65/72; the tie goes to the smaller C.
    assert_eq!(brute[4], brute[5], "{brute:?}");
    assert_eq!(search.chosen_c, 100.0);

    // One group cannot be cross-validated; a class seen in one group only is held out
    // once with no training vector of its own and counts as wrong.
    assert!(matches!(
        select_c(params, &grid, &data(&x, &y, &[0; 72]), 3, 4),
        Err(RecognizeError::Data(DataError::TooFewGroups {
            groups: 1,
            folds: 4
        }))
    ));
    // Class 2 of group 0 relabelled as a class 3 found nowhere else.
    let lonely: Vec<usize> = (0..x.len())
        .map(|i| if groups[i] == 0 && y[i] == 2 { 3 } else { y[i] })
        .collect();
    let a = cross_validated_accuracy(SvcParams { c: 1.0, ..params }, &data(&x, &lonely, &groups), 4, 4)
        .expect("folds without class 3 still fit");
    assert!(a < brute[2], "{a} vs {}", brute[2]);
}

#[test]
fn larger_cs_than_the_first_that_separates_every_fold_are_not_refitted() {
    let (x, y, groups) = blobs(4, 6, 0.5);
    let params = blob_params();
    let grid = [1e-2, 1e-1, 1.0, 10.0, 100.0, 1e3, 1e4];
    let search = select_c(params, &grid, &data(&x, &y, &groups), 3, 4).expect("search");
    eprintln!("{search:?}");
    assert_eq!(search.grid.iter().map(|p| p.c).collect::<Vec<_>>(), grid);
    let from = search.separable_from.expect("these blobs are separable");
    assert!(from > grid[0] && from < grid[grid.len() - 1], "{search:?}");
    assert!(search.check().is_ok());
    // Each fold refitted at every C: below `from` some fold has a multiplier at C; from it
    // on none has, and every held-out prediction (so the accuracy) is the same.
    let fits = |c: f64| -> (bool, Vec<usize>) {
        let (mut at_bound, mut predicted) = (false, Vec::new());
        for held in 0..4 {
            let train: Vec<usize> = (0..x.len()).filter(|&i| groups[i] != held).collect();
            let tx: Vec<[f64; 2]> = train.iter().map(|&i| x[i]).collect();
            let ty: Vec<usize> = train.iter().map(|&i| y[i]).collect();
            let svc = Svc::fit(SvcParams { c, ..params }, &tx, &ty, 3).expect("fit");
            at_bound |= svc.any_multiplier_at_bound();
            predicted.extend(
                (0..x.len())
                    .filter(|&i| groups[i] == held)
                    .map(|i| svc.predict(&x[i]).expect("predict")),
            );
        }
        (at_bound, predicted)
    };
    let (_, at_from) = fits(from);
    for p in &search.grid {
        let (at_bound, predicted) = fits(p.c);
        if p.c < from {
            assert!(at_bound, "C = {} has no multiplier at its bound", p.c);
        } else {
            assert!(!at_bound, "C = {} has a multiplier at its bound", p.c);
            assert_eq!(predicted, at_from, "C = {}", p.c);
            let groups = &groups;
            let held_out_order: Vec<usize> = (0..4u64)
                .flat_map(|g| (0..x.len()).filter(move |&i| groups[i] == g))
                .collect();
            let right = held_out_order
                .iter()
                .zip(&predicted)
                .filter(|&(&i, &p)| y[i] == p)
                .count();
            assert_eq!(p.accuracy, right as f64 / x.len() as f64, "C = {}", p.c);
        }
    }
}

#[test]
fn a_candidate_that_does_not_converge_is_skipped_with_a_warning() {
    let (x, y, groups) = overlapping_blobs(4, 6);
    // On these overlapping classes 200 SMO iterations finish C = 10⁻² and 1 (about 50
    // needed) but not C ≥ 100 (over 500 needed): the large C stands for one whose fit
    // would run out the solver's budget.
    let params = SvcParams {
        max_iterations: 200,
        ..blob_params()
    };
    let events = std::sync::Mutex::new(Vec::new());
    let record = |e: FitEvent| events.lock().expect("events").push(e);
    let search = select_c_observed(params, &[1e4, 1e-2, 1.0], &data(&x, &y, &groups), 3, 4, &record)
        .expect("the converging candidates are searched");
    assert_eq!(search.grid.iter().map(|p| p.c).collect::<Vec<_>>(), [1e-2, 1.0]);
    assert_eq!(search.chosen_c, 1.0, "{search:?}");
    let events = events.into_inner().expect("events");
    let skipped: Vec<String> = events
        .iter()
        .filter_map(|e| match e {
            FitEvent::SkippedC { c, error } => Some(format!("{c:e}: {error}")),
            _ => None,
        })
        .collect();
    assert_eq!(skipped.len(), 1, "{events:?}");
    assert!(
        skipped[0].starts_with("1e4: SMO did not converge in 200 iterations at C = 1e4 (classes "),
        "{skipped:?}"
    );
    // One step whose units are the machines of every candidate and fold (3 pairs × 4
    // folds × 3 candidates); the skipped candidate stops at its first failure.
    assert!(
        matches!(events[0], FitEvent::Step { total: 36, .. }),
        "{events:?}"
    );
    let advanced = events.iter().filter(|e| matches!(e, FitEvent::Advance)).count();
    assert!((24..36).contains(&advanced), "{advanced}");

    // Every candidate failing is an error that lists each.
    match select_c(params, &[1e2, 1e4], &data(&x, &y, &groups), 3, 4) {
        Err(e @ RecognizeError::Solver(SolverError::EveryCFailed { .. })) => {
            let text = e.to_string();
            assert!(
                text.starts_with("every candidate C failed: C = 1e2: SMO did not converge")
                    && text.contains("; C = 1e4: SMO did not converge in 200 iterations at C = 1e4"),
                "{text}"
            );
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn a_fold_without_a_class_names_the_callers_classes() {
    let (x, y, _) = overlapping_blobs(2, 6);
    // Fold 0 holds every vector of class 0, so the fold's fit sees classes 1 and 2 as its
    // own 0 and 1; 5 iterations are too few for any pair.
    let fold: Vec<usize> = y.iter().map(|&l| usize::from(l != 0)).collect();
    let params = SvcParams {
        scaling: FeatureScaling::None,
        probability: false,
        max_iterations: 5,
        ..SvcParams::default()
    };
    assert!(matches!(
        c_search::fold_correct(params, &x, &y, None, &fold, 0, 3, &|| {}),
        Err(RecognizeError::Solver(SolverError::NotConverged {
            iterations: 5,
            first: 1,
            second: 2,
            ..
        }))
    ));
}

#[test]
fn bad_input_is_an_error() {
    let x = [vec![0.0, 1.0], vec![1.0, 0.0]];
    let fit = |p: SvcParams, labels: &[usize], classes| Svc::fit(p, &x, labels, classes).err();
    assert!(matches!(
        fit(
            SvcParams {
                c: 0.0,
                ..SvcParams::default()
            },
            &[0, 1],
            2
        ),
        Some(RecognizeError::Setting(SettingError::Parameter {
            of: "SVC parameter",
            name: "c",
            ..
        }))
    ));
    assert!(matches!(
        fit(SvcParams::default(), &[0, 2], 2),
        Some(RecognizeError::Usage(UsageError::LabelOutOfRange {
            index: 1,
            label: 2,
            classes: 2
        }))
    ));
    assert!(matches!(
        fit(SvcParams::default(), &[0, 0], 2),
        Some(RecognizeError::Data(DataError::EmptyClass { class: 1 }))
    ));
    assert!(matches!(
        fit(SvcParams::default(), &[0], 2),
        Some(RecognizeError::Usage(UsageError::Counts { .. }))
    ));
    let svc = Svc::fit(
        SvcParams {
            probability: false,
            ..SvcParams::default()
        },
        &x,
        &[0, 1],
        2,
    )
    .expect("fit");
    assert!(matches!(
        svc.predict_proba(&[0.0, 1.0]),
        Err(RecognizeError::Setting(SettingError::NoProbability))
    ));
    assert!(matches!(
        svc.predict(&[0.0]),
        Err(RecognizeError::Usage(UsageError::Dimension { got: 1, .. }))
    ));
    assert!(matches!(
        svc.predict(&[f64::NAN, 0.0]),
        Err(RecognizeError::Input(InputError::NonFinite { index: 0 }))
    ));
    assert_eq!(svc.predict(&[0.0, 1.0]).ok(), Some(0));
}
