//! Fusing recognizers over time and senses, and the posterior weights they are fused by.

use super::*;

/// Anytime decisions fused over two senses: each recognizer's windows in the order they are
/// decided, each weighing its `hop / window` times its cross-validated accuracy above chance
/// relative to the most reliable one's (no weight fitted on held-out trials; see
/// [`fitted_posterior_weights_fuse_as_fitted`] for those).
#[test]
fn friction_and_vibration_fuse_over_time_weighted_by_reliability() {
    let train_set = with_tones(0..2, 4.0);
    let settings = |features| TrainSettings {
        fit_posterior_weight: false,
        ..short_windows(Method::Svm, features)
    };
    let nakano = train(&train_set, &settings(FeatureSet::Nakano)).expect("nakano");
    let vibration = train(&train_set, &settings(FeatureSet::Vibration)).expect("vibration");
    // The vibration's windows are decided at their last sample: nothing waits for a filter.
    assert!(vibration.windowing().expect("windows").mirrored_end);
    assert_eq!(vibration.feature_set().dim(), 25);

    let members = nakano.fusion_members(&[&vibration]).expect("members");
    assert_eq!(members.len(), 2);
    let accuracy = |m: &RecognizerFile| match &m.body {
        RecognizerBody::SvmWindows { c_search, .. } => c_search
            .as_ref()
            .and_then(CSearch::accuracy)
            .expect("cross-validated"),
        _ => panic!("an SVM over windows"),
    };
    let r = [nakano.clone(), vibration.clone()].map(|m| (accuracy(&m) - 1.0 / 3.0) / (1.0 - 1.0 / 3.0));
    assert!(r[0] > 0.95 && r[1] < 0.8, "{r:?}");
    let most = r[0].max(r[1]);
    for (m, r) in members.iter().zip(r) {
        assert_eq!(m.reliability, r);
        assert!((m.weight - 0.4 * r / most).abs() < 1e-15, "{m:?}");
    }
    let params = nakano
        .fused_sequential_params(&[&vibration], 3.0)
        .expect("params");
    assert_eq!(params.build().expect("valid").memory(), 60);

    let test_set = with_tones(2..3, 3.0);
    let alone = |m: &RecognizerFile| {
        m.evaluate_sequential(&test_set, &[0.9], m.sequential_params(3.0).expect("params"))
            .expect("alone")
    };
    let fused = nakano
        .evaluate_sequential_fused(&[&vibration], &test_set, &[0.9], params)
        .expect("fused");
    assert_eq!(fused.fused, members);
    assert_eq!(fused.steps, alone(&nakano).steps + alone(&vibration).steps);
    // The friction names every surface; the vibration, weighing less, does not overrule it.
    assert_eq!(fused.rows[0].correct, fused.rows[0].decided, "{fused:?}");
    assert_eq!(fused.rows[0].not_stable, 0, "{fused:?}");
    // Alone, the same as without fusion, to the bit.
    let none = nakano
        .evaluate_sequential_fused(
            &[],
            &test_set,
            &[0.9],
            nakano.sequential_params(3.0).expect("params"),
        )
        .expect("none fused");
    assert_eq!(format!("{none:?}"), format!("{:?}", alone(&nakano)));
    assert!(none.fused.is_empty());

    // Refused, saying why: other surfaces, no measured reliability, no window probabilities.
    let two: Vec<LabelledCapture> = train_set
        .iter()
        .filter(|c| c.label != "smooth")
        .cloned()
        .collect();
    let other_surfaces = train(&two, &settings(FeatureSet::Vibration)).expect("two surfaces");
    let err = nakano
        .fusion_members(&[&other_surfaces])
        .expect_err("other surfaces");
    assert!(
        matches!(
            err,
            RecognizeError::Input(InputError::FusionSurfaces { index: 1, .. })
        ),
        "{err}"
    );
    let one_trial: Vec<LabelledCapture> = train_set[..3].to_vec();
    let uncrossed = train(&one_trial, &settings(FeatureSet::Vibration)).expect("one trial");
    let err = nakano.fusion_members(&[&uncrossed]).expect_err("no reliability");
    assert!(
        matches!(
            err,
            RecognizeError::Input(InputError::NoReliability { index: 1, .. })
        ),
        "{err}"
    );
    assert!(err.to_string().contains("cross-validated accuracy"), "{err}");
    let som = train(
        &train_set,
        &TrainSettings {
            window_s: 0.5,
            ..TrainSettings::new(Method::Som)
        },
    )
    .expect("SOM");
    let err = nakano.fusion_members(&[&som]).expect_err("a SOM");
    assert!(
        matches!(
            err,
            RecognizeError::Setting(SettingError::NoWindowProbabilities { .. })
        ),
        "{err}"
    );
    // The same evidence twice would be counted twice.
    let err = nakano.fusion_members(&[&nakano]).expect_err("the same features");
    assert!(
        matches!(
            err,
            RecognizeError::Setting(SettingError::FusionOverlap {
                first: 0,
                second: 1,
                ..
            })
        ),
        "{err}"
    );
    let mut guess = vibration.clone();
    if let RecognizerBody::SvmWindows {
        c_search: Some(search),
        ..
    } = &mut guess.body
    {
        search.grid.iter_mut().for_each(|p| p.accuracy = 1.0 / 3.0);
    }
    let err = guess.fusion_members(&[&nakano]).expect_err("a guess");
    assert!(
        matches!(
            err,
            RecognizeError::Setting(SettingError::Unreliable { index: 0, .. })
        ),
        "{err}"
    );
    assert!(err.to_string().contains("33.3 %"), "{err}");
    // A SOM names a node, not a distribution: it does not train on the vibration alone.
    let err = train(
        &train_set,
        &TrainSettings {
            features: FeatureSet::Vibration,
            ..TrainSettings::new(Method::Som)
        },
    )
    .expect_err("SOM over vibration");
    assert!(err.to_string().contains("k-NN or an SVM"), "{err}");
}

/// Strokes of three surfaces whose windows each report a calibrated likelihood of one symbol
/// drawn from the surface (its own with probability 1/2, each other one 1/4), every window
/// repeated `repeats` times in a row.
fn symbol_strokes(strokes: usize, windows: usize, repeats: usize) -> Vec<Stroke> {
    let mut rng = capture::rng::SplitMix64::new(7);
    (0..strokes)
        .map(|i| {
            let truth = i % 3;
            let mut stroke_windows = Vec::new();
            for w in 0..windows {
                let symbol = match rng.below(4) {
                    0 | 1 => truth,
                    u => (truth + u - 1) % 3,
                };
                let probabilities: Vec<f64> = (0..3).map(|c| if c == symbol { 0.5 } else { 0.25 }).collect();
                for r in 0..repeats {
                    stroke_windows.push(StrokeWindow {
                        at_s: (w * repeats + r) as f64 * 0.01,
                        travel_m: None,
                        scale: 1.0,
                        share: 1.0,
                        probabilities: probabilities.clone(),
                    });
                }
            }
            Stroke {
                truth,
                change: None,
                change_travel_m: None,
                duration_s: (windows * repeats) as f64 * 0.01,
                windows: stroke_windows,
            }
        })
        .collect()
}

/// On windows that are independent and calibrated, the posterior of whole windows is Bayes'
/// rule, the best a posterior can be under a proper score: the fit keeps the weight whole.
/// Each window said four times over says nothing new: the fit weighs it a quarter.
#[test]
fn the_posterior_weight_fitted_counts_independent_windows_whole_and_one_said_four_times_a_quarter() {
    // The weight is fitted below on strokes made here; the training's own fit is not needed.
    let settings = TrainSettings {
        fit_posterior_weight: false,
        ..short_windows(Method::Svm, FeatureSet::Nakano)
    };
    let model = train(&three_surfaces(3.0), &settings).expect("train");
    assert_eq!(model.classes.len(), 3);
    // No forgetting and no change test: the posterior is the product of every window so far.
    let base = crate::sequential::SequentialParams::builder()
        .memory(100_000)
        .without_change_test();
    let fit = |repeats| {
        model
            .least_brier_weight(&symbol_strokes(60, 40, repeats), base, 1.0)
            .expect("fit")
    };
    let (whole, row, at_whole) = fit(1);
    let brier = row.calibration.brier;
    assert!(whole >= 2f64.powf(-0.5), "independent windows weighed {whole}");
    assert!(brier <= at_whole);
    let (quarter, row, at_whole) = fit(4);
    let brier = row.calibration.brier;
    assert!(
        (2f64.powf(-2.5)..=2f64.powf(-1.5)).contains(&quarter),
        "windows said four times weighed {quarter}"
    );
    assert!(brier < at_whole, "{brier} against {at_whole} at 1");
}

/// A k-NN or SVM over windows trained on two trials or more of each surface fits its
/// posterior's weight on the trials held out; anytime decisions and files take it, and a
/// single trial, or a training told not to, keeps `hop / window`.
#[test]
fn a_recognizer_trained_on_several_trials_fits_its_posterior_weight() {
    let train_set = with_tones(0..3, 3.0);
    for method in [Method::Svm, Method::Knn] {
        let settings = short_windows(method, FeatureSet::Nakano);
        let model = train(&train_set, &settings).expect("train");
        let fit = model.posterior_weight.clone().expect("fitted");
        assert_eq!(fit.hop_weight, 0.4);
        // The anytime decisions at the fitted weight on the held-out strokes, as an evaluation
        // of the same strokes would give them: the path at a steady 5 mm/s is 5 mm a second
        // less the play's first 0.1 mm (every stroke is named past it), and the slowest
        // surface takes the longest path.
        let h = fit.held_out.clone().expect("held-out decisions");
        assert_eq!(
            (h.threshold, h.strokes),
            (crate::sequential::DEFAULT_THRESHOLD, train_set.len())
        );
        assert!(
            h.not_stable < h.strokes && (0.0..=1.0).contains(&h.named_right),
            "{h:?}"
        );
        let path_m = |t_s: f64| 5e-3 * t_s - crate::TRAVEL_PLAY_M / 2.0;
        let (m, slowest_m) = (
            h.stable_right_m.expect("positions"),
            h.slowest_surface_m.expect("positions"),
        );
        assert!((m - path_m(h.stable_right_s)).abs() < 1e-6, "{h:?}");
        assert!((slowest_m - path_m(h.slowest_surface_s)).abs() < 1e-6, "{h:?}");
        assert!(
            slowest_m >= m && model.classes.contains(&h.slowest_surface),
            "{h:?}"
        );
        let said = h.to_string();
        assert!(
            said.starts_with(&format!("at 0.9 on {} held-out strokes", h.strokes))
                && said.contains(&format!(
                    "{:.1} mm ({:.2} s) into a stroke",
                    1e3 * m,
                    h.stable_right_s
                ))
                && said.contains(&format!("({})", h.slowest_surface)),
            "{said}"
        );
        assert_eq!(model.hop_weight(), Some(0.4));
        assert_eq!(fit.folds, 3);
        // Every held-out capture's windows, from contact on.
        let windowing = model.sequential_windowing().expect("windows");
        let held_out: usize = train_set
            .iter()
            .map(|c| {
                model
                    .window_probabilities(c, Some(&windowing))
                    .expect("windows")
                    .map_or(0, |w| w.len())
            })
            .sum();
        assert_eq!(fit.windows, held_out, "{method:?}");
        assert!(fit.brier <= fit.hop_brier, "{fit:?}");
        // On the grid: a whole number of quarter octaves from hop / window, or capped at 1.
        let steps = (fit.weight / fit.hop_weight).log2() * 4.0;
        assert!(
            fit.weight == 1.0 || ((steps - steps.round()).abs() < 1e-9 && (-12.0..=8.0).contains(&steps)),
            "{fit:?}"
        );
        let params = model
            .sequential_params(3.0)
            .expect("params")
            .build()
            .expect("valid");
        assert_eq!(params.weight(), fit.weight);
        assert_eq!(model.window_weight(), Some(fit.weight));
        let back =
            RecognizerFile::from_json(&serde_json::to_string(&model).expect("json"), Path::new("m.json"))
                .expect("round trip");
        assert_eq!(back.posterior_weight, Some(fit.clone()));
        // Fitted at the default memory, and it says so: a posterior keeping another memory is
        // outside what the fit measured. A file from before the field was fitted there too.
        assert_eq!(fit.memory_s, crate::sequential::DEFAULT_MEMORY_S);
        assert!(fit.fitted_at_memory(3.0) && !fit.fitted_at_memory(0.5));
        let mut json = serde_json::to_value(&model).expect("serialize");
        json["posterior_weight"]
            .as_object_mut()
            .expect("a fit")
            .remove("memory_s");
        json["posterior_weight"]
            .as_object_mut()
            .expect("a fit")
            .remove("held_out");
        let older = RecognizerFile::from_json(&json.to_string(), Path::new("m.json")).expect("older file");
        assert_eq!(
            older.posterior_weight,
            Some(PosteriorWeight {
                held_out: None,
                ..fit.clone()
            })
        );
        // Fitted at a shorter memory, the posterior is scored over that memory: a stroke of
        // 3 s keeps only its last 0.5 s of windows, so the Brier score at hop / window moves.
        let short = train(
            &train_set,
            &TrainSettings {
                weight_fit_memory_s: 0.5,
                ..settings.clone()
            },
        )
        .expect("train")
        .posterior_weight
        .expect("fitted");
        assert_eq!(short.memory_s, 0.5);
        assert_ne!(short.hop_brier, fit.hop_brier, "{short:?} against {fit:?}");
        let err = model
            .fit_posterior_weight(&train_set, 0.0, &crate::svc::no_progress)
            .expect_err("no memory");
        assert!(
            err.to_string()
                .contains("memory the posterior's weight is fitted at"),
            "{err}"
        );

        let unfitted = train(
            &train_set,
            &TrainSettings {
                fit_posterior_weight: false,
                ..settings.clone()
            },
        )
        .expect("train");
        assert_eq!(unfitted.posterior_weight, None);
        assert_eq!(unfitted.window_weight(), Some(0.4));
        let one_trial = train(&train_set[..3], &settings).expect("one trial");
        assert_eq!(one_trial.posterior_weight, None, "nothing to hold out");
    }
}

/// Recognizers whose weights were all fitted on held-out trials fuse with those weights: the
/// fit has measured what a reliability weighting would guess.
#[test]
fn fitted_posterior_weights_fuse_as_fitted() {
    let train_set = with_tones(0..3, 3.0);
    let settings = |features| short_windows(Method::Svm, features);
    let nakano = train(&train_set, &settings(FeatureSet::Nakano)).expect("nakano");
    let vibration = train(&train_set, &settings(FeatureSet::Vibration)).expect("vibration");
    let members = nakano.fusion_members(&[&vibration]).expect("members");
    for (m, model) in members.iter().zip([&nakano, &vibration]) {
        assert!(m.fitted);
        assert_eq!(Some(m.weight), model.posterior_weight.as_ref().map(|p| p.weight));
    }
    // One without a fit: every weight is its own times its reliability over the most reliable.
    let unfitted = train(
        &train_set,
        &TrainSettings {
            fit_posterior_weight: false,
            ..settings(FeatureSet::Vibration)
        },
    )
    .expect("vibration");
    let members = nakano.fusion_members(&[&unfitted]).expect("members");
    let most = members[0].reliability.max(members[1].reliability);
    let own = [nakano.window_weight(), unfitted.window_weight()].map(|w| w.expect("weight"));
    for (m, w) in members.iter().zip(own) {
        assert!((m.weight - w * m.reliability / most).abs() < 1e-15, "{m:?}");
    }
    assert!(members[0].fitted && !members[1].fitted);
}

/// A k-NN over windows trained on two trials calibrates its votes on windows held out by
/// trial, which also measures the reliability it is fused by; one trained on a single trial
/// keeps its raw votes and cannot be fused.
#[test]
fn a_knn_over_windows_calibrates_its_votes_and_can_be_fused() {
    use crate::fusion::cross_validated_accuracy;
    use crate::knn::{FeatureScaling, VoteCalibration};
    use crate::recognizer::train::{CV_FOLDS, scaled_training_windows};

    let train_set = with_tones(0..2, 4.0);
    let settings = |features| short_windows(Method::Knn, features);
    // One neighbour: every held-out window's vote is all or nothing.
    let one_nn = TrainSettings {
        k: 1,
        ..settings(FeatureSet::Vibration)
    };
    let vibration = train(&train_set, &one_nn).expect("vibration");
    let calibration = |m: &RecognizerFile| match &m.body {
        RecognizerBody::KnnWindows { calibration, .. } => *calibration,
        _ => panic!("a k-NN over windows"),
    };
    let c = calibration(&vibration).expect("two trials: calibrated");
    // `fine` and `coarse` ring alike: many held-out windows name the other one.
    assert_eq!(c.folds, 2);
    assert!(
        c.unvoted > 0.0 && c.votes_weight > 0.0 && c.votes_weight < 1.0,
        "{c:?}"
    );
    // Its accuracy is the k-NN's under the same folds, counted by the fusion's own function.
    let windowing = *vibration.windowing().expect("windows");
    let w = scaled_training_windows(
        &train_set,
        &windowing,
        FeatureSet::Vibration,
        Histogram::default(),
    )
    .expect("windows");
    let params = KnnParams::default().k(1).scaling(FeatureScaling::None);
    let accuracy = cross_validated_accuracy(params, &w.x, &w.y, &w.groups, 3, CV_FOLDS).expect("cv");
    assert_eq!(c.accuracy, accuracy);
    assert!(accuracy > 0.5 && accuracy < 0.9, "{accuracy}");
    assert_eq!(c.windows, w.x.len());

    // Each window's probabilities are the raw votes blended, and the live classifier's are
    // the same to the bit.
    let mut raw = vibration.clone();
    if let RecognizerBody::KnnWindows { calibration, .. } = &mut raw.body {
        *calibration = None;
    }
    let test_set = with_tones(2..3, 3.0);
    let mut live = WindowClassifier::new(&vibration).expect("window classifier");
    let sequential = vibration.sequential_windowing().expect("windows");
    let mut p = vec![0.0; 3];
    for capture in &test_set {
        let blended = vibration
            .window_probabilities(capture, None)
            .expect("probabilities")
            .expect("windows");
        let votes = raw
            .window_probabilities(capture, None)
            .expect("probabilities")
            .expect("windows");
        for (b, v) in blended.iter().zip(&votes) {
            let mut expected = v.probabilities.clone();
            c.apply(&mut expected);
            assert_eq!(b.probabilities, expected);
            assert_eq!(b.decision.label, v.decision.label);
            assert_eq!(b.decision.confidence, expected[b.decision.label]);
            assert!(v.probabilities.iter().all(|&q| q == 0.0 || q == 1.0));
        }
        let vectors = window_vectors(capture, &sequential, FeatureSet::Vibration, Histogram::default())
            .expect("windows")
            .vectors;
        let offline = vibration
            .window_probabilities(capture, Some(&sequential))
            .expect("probabilities")
            .expect("windows");
        for ((_, _, v), w) in vectors.iter().zip(&offline) {
            live.probabilities_into(v, &mut p).expect("classified");
            assert_eq!(p, w.probabilities);
        }
    }

    // Kept in the file; a calibration out of its bounds is refused when read.
    let json = serde_json::to_value(&vibration).expect("serialize");
    assert_eq!(json["body"]["calibration"]["votes_weight"], c.votes_weight);
    let back = RecognizerFile::from_json(&json.to_string(), Path::new("m.json")).expect("valid");
    assert_eq!(back, vibration);
    let mut bad = json.clone();
    bad["body"]["calibration"]["votes_weight"] = serde_json::json!(1.5);
    let err = RecognizerFile::from_json(&bad.to_string(), Path::new("m.json")).expect_err("out of bounds");
    assert!(err.to_string().contains("calibration"), "{err}");

    // Fused with a k-NN over friction, weighed by its measured reliability, the two name every
    // surface of the held-out trial.
    let nakano = train(&train_set, &settings(FeatureSet::Nakano)).expect("nakano");
    let members = nakano.fusion_members(&[&vibration]).expect("members");
    assert_eq!(members[1].accuracy, c.accuracy);
    assert!(members[1].weight < members[0].weight, "{members:?}");
    let params = nakano
        .fused_sequential_params(&[&vibration], 3.0)
        .expect("params");
    let fused = nakano
        .evaluate_sequential_fused(&[&vibration], &test_set, &[0.9], params)
        .expect("fused");
    assert_eq!(fused.rows[0].correct, fused.rows[0].decided, "{fused:?}");
    assert!(fused.rows[0].decided > 0, "{fused:?}");

    // One trial: nothing to hold out, raw votes, and no reliability to be fused by.
    let one_trial: Vec<LabelledCapture> = train_set[..3].to_vec();
    let uncrossed = train(&one_trial, &one_nn).expect("one trial");
    assert_eq!(calibration(&uncrossed), None::<VoteCalibration>);
    // More neighbours than one trial's windows, fewer than both trials': trained, with its
    // votes raw.
    let k = w.x.len() * 2 / 3;
    let wide = train(
        &train_set,
        &TrainSettings {
            k,
            ..settings(FeatureSet::Vibration)
        },
    )
    .expect("k within the training windows");
    assert_eq!(calibration(&wide), None::<VoteCalibration>);
    let err = nakano.fusion_members(&[&uncrossed]).expect_err("no reliability");
    assert!(
        matches!(
            err,
            RecognizeError::Input(InputError::NoReliability { index: 1, .. })
        ),
        "{err}"
    );
}
