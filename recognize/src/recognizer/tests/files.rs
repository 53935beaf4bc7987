//! The recognizer file: what it keeps, how it reads back, and how a bad one is refused.

use super::*;

/// A mirrored end is kept in the model file and decides each window at its last sample: the
/// same windows as without it, each a lookahead (0.27 s) sooner.
#[test]
fn a_mirrored_end_is_kept_and_decides_a_lookahead_sooner() {
    let train = three_surfaces(4.0);
    let plain = NakanoWindowing::new(0.5, 0.1, 1000.0).expect("valid");
    let windowing = NakanoWindowing {
        mirrored_end: true,
        ..plain
    };
    assert_eq!(windowing.decided_at(270), 769);
    assert_eq!(plain.decided_at(270), 1039);
    let model = RecognizerFile::train_som(&train, windowing, SomParams::default()).expect("train");
    let text = serde_json::to_string(&model).expect("serialize");
    assert!(text.contains("\"mirrored_end\":true"));
    let back = RecognizerFile::from_json(&text, Path::new("m.json")).expect("valid");
    assert_eq!(back, model);
    // A model without it reads as before (the field is left out of its file).
    let old = RecognizerFile::train_som(&train, plain, SomParams::default()).expect("train");
    assert!(
        !serde_json::to_string(&old)
            .expect("serialize")
            .contains("mirrored_end")
    );
    let eval = back.evaluate(&three_surfaces(3.0), None).expect("evaluate");
    let before = old.evaluate(&three_surfaces(3.0), None).expect("evaluate");
    assert!((eval.decision_latency_s - 0.5).abs() < 1e-12);
    assert!((before.decision_latency_s - 0.77).abs() < 1e-12);
    assert_eq!(eval.confusion.accuracy(), Some(1.0));
    let first = eval.time_to_first_correct_s.expect("correct decisions");
    assert!((first - (1.839 - 0.27)).abs() < 1e-9, "{first}");
}

#[test]
fn a_som_recognizer_round_trips_and_recognizes_distinct_surfaces() {
    let train = three_surfaces(4.0);
    let windowing = NakanoWindowing::new(0.5, 0.1, 1000.0).expect("valid");
    let model = RecognizerFile::train_som(&train, windowing, SomParams::default()).expect("train");
    assert_eq!(model.classes, ["coarse", "fine", "smooth"]);
    let text = serde_json::to_string(&model).expect("serialize");
    let back = RecognizerFile::from_json(&text, Path::new("m.json")).expect("valid");
    assert_eq!(back, model);
    let eval = back.evaluate(&three_surfaces(3.0), None).expect("evaluate");
    assert_eq!(eval.confusion.accuracy(), Some(1.0));
    assert_eq!((eval.never_correct, eval.not_stable), (0, 0));
    // The first decision window starts at 270 + 8 × 100 samples, the first hop after 5 mm
    // (1 s) of travel, and is decided 500 + 270 − 1 samples later.
    assert!((eval.decision_latency_s - 0.77).abs() < 1e-12);
    let first = eval.time_to_first_correct_s.expect("correct decisions");
    assert!((first - 1.839).abs() < 1e-9, "{first}");
    assert_eq!(eval.flips_per_s, 0.0);
    // A map names nodes, not a distribution over the surfaces: no window classifier.
    let refused = WindowClassifier::new(&back);
    assert!(
        matches!(
            refused,
            Err(RecognizeError::Setting(SettingError::NoWindowProbabilities {
                method: "som",
                ..
            }))
        ),
        "{refused:?}"
    );
}

/// The histogram's band is kept beside its cell scaling, left out of the file when it is the
/// paper's (so files written before it could be chosen read as they did), and a band the
/// build does not know is refused, not read as the paper's.
#[test]
fn the_histogram_band_is_kept_in_the_file_and_an_unknown_one_is_refused() {
    for model in sinapov_recognizers() {
        let method = model.method();
        let json = serde_json::to_value(&model).expect("serialize");
        assert_eq!(json["body"]["cell_scale"], "mean", "{method}");
        assert!(json["body"].get("band").is_none(), "{method}");
        let mut wide = json.clone();
        wide["body"]["band"] = "nyquist".into();
        let back = RecognizerFile::from_json(&wide.to_string(), Path::new("m.json")).expect("valid");
        let needs = FeatureNeeds::evaluation(&back, &[]).expect("needs");
        assert_eq!(
            needs.histograms,
            [Histogram::default().over(crate::HistogramBand::Nyquist)],
            "{method}"
        );
        assert_eq!(
            serde_json::to_value(&back).expect("serialize")["body"]["band"],
            "nyquist"
        );
        wide["body"]["band"] = "wide".into();
        RecognizerFile::from_json(&wide.to_string(), Path::new("m.json")).expect_err("unknown band");
    }
}

#[test]
fn reliability_weights_round_trip_and_older_files_without_them_still_load() {
    for model in sinapov_recognizers() {
        let method = model.method();
        let json = serde_json::to_value(&model).expect("serialize");
        assert_eq!(json["body"]["behaviours"][0]["reliability"], 0.8, "{method}");
        assert!(
            json["body"]["behaviours"][1].get("reliability").is_none(),
            "{method}"
        );
        let back = RecognizerFile::from_json(&json.to_string(), Path::new("m.json")).expect("valid");
        assert_eq!(back, model);
        // `rub` has no weight of its own: it gets the mean of the others' (here `poke`'s).
        assert_eq!(back.fusion_weights(), [0.8, 0.8], "{method}");
        assert_eq!(back.behaviour_names(), [Some("poke"), Some("rub")]);

        // A file from before weights were stored: no `reliability`, `reliability_folds`,
        // `c_search` anywhere. It loads, and every behaviour weighs the same.
        let mut old = json.clone();
        for b in old["body"]["behaviours"].as_array_mut().expect("behaviours") {
            let b = b.as_object_mut().expect("behaviour");
            for key in ["reliability", "reliability_folds", "c_search"] {
                b.remove(key);
            }
        }
        let old = RecognizerFile::from_json(&old.to_string(), Path::new("old.json")).expect("old file");
        assert!(
            old.reliabilities()
                .iter()
                .all(|r| r.reliability.is_none() && r.c_search.is_none())
        );
        assert_eq!(old.fusion_weights(), [1.0, 1.0], "{method}");

        // Weights are accuracies.
        for bad in [serde_json::json!(1.5), serde_json::json!(-0.1)] {
            let mut edited = json.clone();
            edited["body"]["behaviours"][0]["reliability"] = bad;
            let err = RecognizerFile::from_json(&edited.to_string(), Path::new("r.json")).expect_err("range");
            assert!(
                err.to_string()
                    .contains("r.json: field `body.behaviours[0].reliability`"),
                "{err}"
            );
        }
    }
    // The SVM's search must name the classifier's C, from its grid.
    let json = serde_json::to_value(&sinapov_recognizers()[1]).expect("serialize");
    let mut edited = json.clone();
    edited["body"]["behaviours"][0]["c_search"]["chosen_c"] = 1.0.into();
    let err = RecognizerFile::from_json(&edited.to_string(), Path::new("r.json")).expect_err("C");
    assert!(
        err.to_string()
            .contains("field `body.behaviours[0].c_search.chosen_c`: 1 is not the classifier's C 10"),
        "{err}"
    );
    let mut edited = json;
    edited["body"]["behaviours"][0]["c_search"]["chosen_c"] = 100.0.into();
    let err = RecognizerFile::from_json(&edited.to_string(), Path::new("r.json")).expect_err("grid");
    assert!(
        err.to_string()
            .contains("c_search.chosen_c`: 100 is not in the grid"),
        "{err}"
    );
}

#[test]
fn window_classifiers_round_trip_and_recognize_distinct_surfaces() {
    let train = three_surfaces(4.0);
    let windowing = NakanoWindowing::new(0.5, 0.1, 1000.0).expect("valid");
    let knn =
        RecognizerFile::train_knn_windows(&train, windowing, FeatureSet::Nakano, 3, Histogram::default())
            .expect("k-NN");
    let svm = RecognizerFile::train_svm_windows(
        &train,
        windowing,
        FeatureSet::Nakano,
        &SvmC::auto(),
        Histogram::default(),
    )
    .expect("SVM");
    for model in [knn, svm] {
        assert_eq!(model.feature_set(), FeatureSet::Nakano);
        assert_eq!(model.windowing(), Some(&windowing));
        let json = serde_json::to_value(&model).expect("serialize");
        assert_eq!(json["features"], "nakano");
        let back = RecognizerFile::from_json(&json.to_string(), Path::new("m.json")).expect("valid");
        assert_eq!(back, model);
        let eval = back.evaluate(&three_surfaces(3.0), None).expect("evaluate");
        assert_eq!(eval.confusion.accuracy(), Some(1.0), "{}", model.method());
        // The SOM's windows: the same latency.
        assert!((eval.decision_latency_s - 0.77).abs() < 1e-12);
        // Each window's probabilities back its decision: same window, same label, the label's
        // probability as the confidence, probabilities summing to 1.
        for c in &three_surfaces(3.0) {
            let decisions = back.decisions(c, None).expect("decisions");
            let probabilities = back
                .window_probabilities(c, None)
                .expect("probabilities")
                .expect("windows");
            assert_eq!(decisions.len(), probabilities.len());
            for (d, w) in decisions.iter().zip(&probabilities) {
                let p = &w.probabilities;
                assert_eq!(*d, w.decision);
                assert_eq!(p[d.label], d.confidence);
                assert!((p.iter().sum::<f64>() - 1.0).abs() < 1e-9, "{p:?}");
            }
            // The allocation-free classifier gives the same probabilities, to the bit, on
            // buffers it keeps from one window to the next.
            let mut live = WindowClassifier::new(&back).expect("window classifier");
            let mut p = vec![0.0; live.classes()];
            let vectors = window_vectors(c, &windowing, FeatureSet::Nakano, Histogram::default())
                .expect("windows")
                .vectors;
            assert_eq!(vectors.len(), probabilities.len());
            for ((_, _, v), w) in vectors.iter().zip(&probabilities) {
                live.probabilities_into(v, &mut p).expect("classified");
                assert_eq!(p, w.probabilities);
            }
            let short = live.probabilities_into(&vectors[0].2[..4], &mut p);
            assert!(
                matches!(
                    short,
                    Err(RecognizeError::Usage(UsageError::Dimension {
                        got: 4,
                        expected: 5,
                        ..
                    }))
                ),
                "{short:?}"
            );
            let mut wrong = vec![0.0; live.classes() + 1];
            let wrong = live.probabilities_into(&vectors[0].2, &mut wrong);
            assert!(
                matches!(wrong, Err(RecognizeError::Usage(UsageError::Buffer { .. }))),
                "{wrong:?}"
            );
        }
        // Anytime decisions run from contact: windows before the 5 mm start travel count too.
        let params = back.sequential_params(3.0).expect("window probabilities");
        let sequential = back
            .evaluate_sequential(&three_surfaces(3.0), &[0.9], params)
            .expect("sequential");
        let from_start: usize = three_surfaces(3.0)
            .iter()
            .map(|c| back.decisions(c, None).expect("decisions").len())
            .sum();
        assert!(
            sequential.steps > from_start,
            "{} vs {from_start}",
            sequential.steps
        );
        assert_eq!(
            sequential.rows[0].correct, sequential.rows[0].decided,
            "{sequential:?}"
        );
        assert!((sequential.params.weight() - 0.2).abs() < 1e-12);
        assert_eq!(sequential.params.memory(), 30);
        assert!(
            back.evaluate_fused(&three_surfaces(3.0))
                .expect("fused")
                .is_none()
        );
        // Shapes are checked on load.
        let mut edited = json.clone();
        edited["body"]["scaling"]["scale"][0] = (-1.0).into();
        let err = RecognizerFile::from_json(&edited.to_string(), Path::new("r.json")).expect_err("scale");
        assert!(err.to_string().contains("field `body.scaling`"), "{err}");
        let mut edited = json;
        edited["features"] = "both".into();
        let err = RecognizerFile::from_json(&edited.to_string(), Path::new("r.json")).expect_err("features");
        assert!(err.to_string().contains("field `features`"), "{err}");
    }
    // No accelerometer in these captures: `both` names the capture and the columns.
    let err = RecognizerFile::train_knn_windows(&train, windowing, FeatureSet::Both, 3, Histogram::default())
        .expect_err("no accelerometer");
    assert!(
        matches!(&err, RecognizeError::Input(InputError::MissingColumns { missing, .. }) if missing.len() == 3),
        "{err}"
    );
    assert!(
        err.to_string()
            .starts_with("fine: `--features both` needs the columns accel_x_mps2"),
        "{err}"
    );
}

#[test]
fn a_bad_file_names_the_field() {
    let windowing = NakanoWindowing::new(0.5, 0.1, 1000.0).expect("valid");
    let model =
        RecognizerFile::train_som(&three_surfaces(3.0), windowing, SomParams::default()).expect("train");
    let mut json = serde_json::to_value(&model).expect("serialize");
    json["version"] = 7.into();
    let err = RecognizerFile::from_json(&json.to_string(), Path::new("r.json")).expect_err("version");
    assert!(err.to_string().contains("r.json: field `version`"), "{err}");
    let mut json = serde_json::to_value(&model).expect("serialize");
    json["body"]["som"]["labels"][3] = 9.into();
    let err = RecognizerFile::from_json(&json.to_string(), Path::new("r.json")).expect_err("label");
    assert!(err.to_string().contains("field `body.som.labels`"), "{err}");
    let mut json = serde_json::to_value(&model).expect("serialize");
    json["body"]["som"]["reference"][0] = serde_json::json!([1.0, 0.0]);
    let err = RecognizerFile::from_json(&json.to_string(), Path::new("r.json")).expect_err("shape");
    assert!(err.to_string().contains("field `body.som.reference`"), "{err}");
    // Sizes past memory or past the filters' sample arithmetic are refused on load, with
    // the value, not allocated or overflowed.
    for (field, value, message) in [
        (
            "highpass_half_width",
            1e18,
            "body.windowing.filters.highpass_half_width`: 1000000000000000000 is not from 1 to 10^6",
        ),
        (
            "smoothing_half_width",
            2e6,
            "body.windowing.filters.smoothing_half_width`: 2000000 is not at most 10^6",
        ),
    ] {
        let mut json = serde_json::to_value(&model).expect("serialize");
        json["body"]["windowing"]["filters"][field] = (value as u64).into();
        let err = RecognizerFile::from_json(&json.to_string(), Path::new("r.json")).expect_err(field);
        assert!(err.to_string().contains(message), "{err}");
    }
    let mut json = serde_json::to_value(&model).expect("serialize");
    json["body"]["windowing"]["window_samples"] = 100_000_000.into();
    let err = RecognizerFile::from_json(&json.to_string(), Path::new("r.json")).expect_err("window");
    assert!(
        err.to_string()
            .contains("`body.windowing.window_samples`: 100000000 is not from 2 to 10^7"),
        "{err}"
    );
    let err = NakanoWindowing::new(0.5, 0.1, 1000.0)
        .and_then(|w| w.with_training_window_s(0.001))
        .expect_err("one sample");
    assert!(
        err.to_string()
            .contains("training_window_samples = 1: from 2 to 10^7"),
        "{err}"
    );
    let err = RecognizerFile::from_json("{\"format\": 1", Path::new("r.json")).expect_err("parse");
    assert!(
        matches!(err, RecognizeError::Input(InputError::Parse { line: 1, .. })),
        "{err}"
    );
    // A capture of a surface the map does not know.
    let unknown = rubbing("glass", 1e-6, 1e-3, 0.1, 3.0);
    let err = model.evaluate(&[unknown], None).expect_err("unknown surface");
    assert!(err.to_string().contains("surface `glass`"), "{err}");
}

/// A fitted weight read from a file is checked, and only a recognizer with window
/// probabilities may carry one.
#[test]
fn a_bad_posterior_weight_names_its_field() {
    let model = train(
        &with_tones(0..2, 3.0),
        &short_windows(Method::Svm, FeatureSet::Nakano),
    )
    .expect("train");
    assert!(model.posterior_weight.is_some());
    for (field, value) in [
        ("weight", 0.0),
        ("weight", 1.5),
        ("hop_brier", f64::NAN),
        ("folds", 1.0),
        ("memory_s", 0.0),
        ("held_out.threshold", 1.5),
        ("held_out.named_right", -0.1),
        ("held_out.not_stable", 99.0),
        ("held_out.stable_right_m", -1e-3),
        ("held_out.slowest_surface_s", -1.0),
    ] {
        let mut json = serde_json::to_value(&model).expect("serialize");
        let slot = match field.split_once('.') {
            Some((outer, inner)) => &mut json["posterior_weight"][outer][inner],
            None => &mut json["posterior_weight"][field],
        };
        *slot = if matches!(field, "folds" | "held_out.not_stable") {
            serde_json::json!(value as u64)
        } else {
            serde_json::json!(value)
        };
        let text = json.to_string();
        let err = RecognizerFile::from_json(&text, Path::new("m.json")).expect_err(field);
        assert!(
            err.to_string().contains(&format!("posterior_weight.{field}")) || field == "hop_brier",
            "{field}: {err}"
        );
    }
    let som = RecognizerFile::train_som(
        &three_surfaces(3.0),
        NakanoWindowing::new(0.5, 0.1, 1000.0).expect("valid"),
        SomParams::default(),
    )
    .expect("SOM");
    let mut json = serde_json::to_value(&som).expect("serialize");
    json["posterior_weight"] = serde_json::to_value(&model.posterior_weight).expect("serialize");
    let err = RecognizerFile::from_json(&json.to_string(), Path::new("m.json")).expect_err("a SOM");
    assert!(err.to_string().contains("field `posterior_weight`"), "{err}");
}

/// A version-1 file over Nakano's features alone reads as it did; one with histograms (whose
/// definition changed from samples to seconds and hertz) is refused, saying why.
#[test]
fn version_one_files_are_read_only_where_their_features_did_not_change() {
    let with_version = |model: &RecognizerFile, version: u32| {
        let mut value = serde_json::to_value(model).expect("serialize");
        value["version"] = version.into();
        RecognizerFile::from_json(&value.to_string(), Path::new("m.json"))
    };
    let windowing = NakanoWindowing::new(0.5, 0.1, 1000.0).expect("valid");
    let nakano =
        RecognizerFile::train_som(&three_surfaces(4.0), windowing, SomParams::default()).expect("train");
    assert_eq!(
        with_version(&nakano, 1).expect("still valid").classes,
        nakano.classes
    );
    assert!(with_version(&nakano, 3).is_err());

    let settings = TrainSettings {
        features: FeatureSet::Spectral,
        ..TrainSettings::new(Method::Knn)
    };
    let spectral = train(&vibrating_surfaces(5.0, 0..2), &settings).expect("train");
    assert!(with_version(&spectral, RECOGNIZER_VERSION).is_ok());
    let err = with_version(&spectral, 1).expect_err("histograms in samples");
    let text = err.to_string();
    assert!(
        text.contains("version")
            && text.contains("seconds and hertz")
            && text.contains("train the recognizer again"),
        "{text}"
    );
}
