//! Training: which windows and trainer each method gets, and what a training says when a class
//! or a window cannot be used.

use super::*;

#[test]
fn trials_group_captures_in_numeric_order_and_trial_less_captures_stand_alone() {
    let with_trial = |trial: Option<&str>| {
        let mut c = rubbing("fine", 5e-6, 0.3e-3, 0.1, 0.1);
        let mut meta = c.capture.metadata().clone();
        if let Some(t) = trial {
            meta = meta.with(TRIAL_KEY, t);
        }
        c.capture =
            Capture::new(meta, c.capture.columns().to_vec(), c.capture.data().to_vec()).expect("capture");
        c
    };
    let captures: Vec<LabelledCapture> = [Some("10"), Some("2"), None, Some("2"), Some("0"), None]
        .into_iter()
        .map(with_trial)
        .collect();
    let refs: Vec<&LabelledCapture> = captures.iter().collect();
    assert_eq!(trial_groups(&refs), [2, 1, 3, 1, 0, 4]);
}

#[test]
fn train_picks_the_trainer_of_the_method_and_features() {
    let captures = three_surfaces(4.0);
    for (method, body) in [
        (Method::Som, "som"),
        (Method::Knn, "knn_windows"),
        (Method::Svm, "svm_windows"),
    ] {
        assert_eq!(method.trainer().method(), method);
        let settings = TrainSettings {
            window_s: 0.5,
            train_window_s: Some(0.5),
            features: FeatureSet::Nakano,
            ..TrainSettings::new(method)
        };
        let model = train(&captures, &settings).expect("train");
        assert_eq!(model.method(), method.name());
        assert_eq!(model.feature_set(), FeatureSet::Nakano);
        let json = serde_json::to_value(&model).expect("serialize");
        assert_eq!(json["body"]["method"], body);
    }
    // The method's own features by default; columns are checked before any trainer runs.
    assert_eq!(TrainSettings::new(Method::Knn).features, FeatureSet::Spectral);
    let err = train(&captures, &TrainSettings::new(Method::Svm)).expect_err("no accelerometer");
    assert!(
        matches!(err, RecognizeError::Input(InputError::MissingColumns { .. })),
        "{err}"
    );
}

#[test]
fn captures_that_carry_both_feature_sets_train_on_both_by_default() {
    let rubbing = three_surfaces(1.0).remove(0);
    let vibrating = with_vibration(rubbing.clone(), 40.0);
    // A scratch: position, force and the three accelerometer axes, no friction or height.
    let scratch = {
        let n: u32 = 400;
        let t: Vec<f64> = (0..n).map(|k| f64::from(k) / 400.0).collect();
        let columns: Vec<String> = [TIME_S, TANGENTIAL_POSITION_M, NORMAL_FORCE_N]
            .into_iter()
            .chain(crate::features::spectral::ACCEL_COLUMNS)
            .map(String::from)
            .collect();
        let mut data = vec![t.clone(), t.clone(), vec![1.0; n as usize]];
        data.extend((0..3).map(|_| t.iter().map(|t| (300.0 * t).sin()).collect()));
        let meta = Metadata::new(CaptureKind::Rubbing, "test", 400.0).with(LABEL_KEY, "cloth");
        let capture = Capture::new(meta, columns, data).expect("valid capture");
        LabelledCapture::new(capture, Path::new("cloth"), "00".into()).expect("labelled")
    };
    for method in [Method::Som, Method::Knn, Method::Svm] {
        assert_eq!(
            method.features_for(&vibrating, 3.0),
            FeatureSet::Both,
            "{method:?}"
        );
        // A window must hold a histogram's five frames (1.92 s) for both sets.
        assert_eq!(
            method.features_for(&vibrating, 1.92),
            FeatureSet::Both,
            "{method:?}"
        );
        assert_eq!(
            method.features_for(&vibrating, 1.9),
            method.default_features(),
            "{method:?}"
        );
        // One set only: the one the captures carry, the method's own first.
        assert_eq!(
            method.features_for(&rubbing, 3.0),
            FeatureSet::Nakano,
            "{method:?}"
        );
        assert_eq!(
            method.features_for(&scratch, 3.0),
            FeatureSet::Spectral,
            "{method:?}"
        );
    }
    // Neither: the method's own, whose missing columns training then names.
    let bare = {
        let meta = Metadata::new(CaptureKind::Rubbing, "test", 400.0).with(LABEL_KEY, "air");
        let columns = [TIME_S, TANGENTIAL_POSITION_M, NORMAL_FORCE_N]
            .map(String::from)
            .to_vec();
        let data = vec![vec![0.0, 0.01], vec![0.0, 1e-4], vec![1.0, 1.0]];
        let capture = Capture::new(meta, columns, data).expect("valid");
        LabelledCapture::new(capture, Path::new("air"), "00".into()).expect("labelled")
    };
    assert_eq!(Method::Som.features_for(&bare, 3.0), FeatureSet::Nakano);
    assert_eq!(Method::Knn.features_for(&bare, 3.0), FeatureSet::Spectral);
}

#[test]
fn training_refuses_a_class_whose_captures_give_no_window() {
    // 0.4 s is shorter than one 0.5 s window with the filters' 0.27 s margin each side.
    let mut captures = three_surfaces(4.0);
    captures.push(from(rubbing("cork", 10e-6, 1e-3, 0.15, 0.4), "cork-a.csv"));
    captures.push(from(rubbing("cork", 10e-6, 1e-3, 0.15, 0.4), "cork-b.csv"));
    for method in [Method::Som, Method::Knn] {
        let settings = TrainSettings {
            window_s: 0.5,
            train_window_s: Some(0.5),
            features: FeatureSet::Nakano,
            ..TrainSettings::new(method)
        };
        let err = train(&captures, &settings).expect_err("cork has no window");
        let RecognizeError::Data(DataError::ClassWithoutWindows { class, captures: why }) = &err else {
            panic!("{method:?}: {err}");
        };
        assert_eq!(class, "cork");
        let paths: Vec<&Path> = why.iter().map(|w| w.path.as_path()).collect();
        assert_eq!(paths, [Path::new("cork-a.csv"), Path::new("cork-b.csv")]);
        let text = err.to_string();
        assert!(text.contains("class `cork` has no training vector"), "{text}");
        assert!(
            text.contains("capture cork-a.csv is 0.400 s long; a training window needs 0.5 s"),
            "{text}"
        );
    }
    // Long enough, but a tip that never slides gives no window either.
    let mut captures = three_surfaces(4.0);
    captures.push(from(rubbing_at("cork", 10e-6, 1e-3, 0.15, 4.0, 0.0), "still.csv"));
    let windowing = NakanoWindowing::new(0.5, 0.1, 1000.0).expect("valid");
    let err = RecognizerFile::train_som(&captures, windowing, SomParams::default()).expect_err("no travel");
    assert!(
        err.to_string()
            .contains("capture still.csv moves its tip only 0.000 mm"),
        "{err}"
    );
}

/// Over travel, a class whose captures were all rubbed well below the slowest speed the windows
/// read gives windows, but training leaves every one out: the error says so rather than blaming
/// the capture's length or travel.
#[test]
fn training_says_when_a_class_lost_every_window_to_a_tool_too_slow() {
    let mut captures = three_surfaces(4.0);
    // 0.5 mm/s: a window's 625 samples span a quarter of its 1.25 mm.
    captures.push(from(
        rubbing_at("cork", 10e-6, 1e-3, 0.15, 14.0, 0.5e-3),
        "cork-slow.csv",
    ));
    let settings = TrainSettings {
        features: FeatureSet::Nakano,
        window_s: 0.25,
        mirrored_end: true,
        windows_over_travel: true,
        slowest_speed_mps: Some(0.002),
        ..TrainSettings::new(Method::Knn)
    };
    let err = train(&captures, &settings).expect_err("cork has no window kept");
    let RecognizeError::Data(DataError::ClassWithoutWindows { class, captures: why }) = &err else {
        panic!("{err}");
    };
    assert_eq!(class, "cork");
    assert_eq!(why.len(), 1);
    assert_eq!(why[0].path, Path::new("cork-slow.csv"));
    let text = err.to_string();
    eprintln!("{text}");
    assert!(
        text.contains("capture cork-slow.csv gave ") && text.contains(" training windows, all left out"),
        "{text}"
    );
    assert!(
        text.contains("slowest speed the windows read (2.0 mm/s)"),
        "{text}"
    );
    // The same capture rubbed at 5 mm/s keeps its windows.
    captures.pop();
    captures.push(from(rubbing_at("cork", 10e-6, 1e-3, 0.15, 4.0, 5e-3), "cork.csv"));
    train(&captures, &settings).expect("cork rubbed at 5 mm/s");
}

#[test]
fn every_method_trains_on_windows_of_its_decision_length_unless_told_otherwise() {
    let captures = three_surfaces(4.0);
    for (method, expected_s) in [(Method::Knn, 0.6), (Method::Svm, 0.6), (Method::Som, 0.6)] {
        let settings = TrainSettings {
            window_s: 0.6,
            features: FeatureSet::Nakano,
            ..TrainSettings::new(method)
        };
        assert_eq!(settings.training_window_s(), expected_s, "{method:?}");
        let model = train(&captures, &settings).expect("train");
        let windowing = model.windowing().expect("windowed");
        assert!(
            (windowing.training_window_s() - expected_s).abs() < 1e-12,
            "{method:?}"
        );
        assert!((windowing.window_s() - 0.6).abs() < 1e-12, "{method:?}");
        // A training window set is the one used.
        let set = TrainSettings {
            train_window_s: Some(0.5),
            ..settings
        };
        assert_eq!(set.training_window_s(), 0.5);
        let model = train(&captures, &set).expect("train");
        let training_s = model.windowing().expect("windowed").training_window_s();
        assert!((training_s - 0.5).abs() < 1e-12, "{method:?}");
    }
}

#[test]
fn the_map_grows_with_the_classes_and_names_the_classes_it_cannot_answer() {
    // The thesis's 12 nodes up to its seven surfaces; beyond, the data's size, two per class at least.
    assert_eq!(window_som_nodes(3, 5000), 12);
    assert_eq!(window_som_nodes(7, 5000), 12);
    assert_eq!(window_som_nodes(8, 1), 16);
    assert_eq!(window_som_nodes(20, 1), 40);
    // ⌈5·780^0.54321⌉ and ⌈5·10 000^0.54321⌉: the SOM Toolbox's map sizes.
    assert_eq!(window_som_nodes(20, 780), 187);
    assert_eq!(window_som_nodes(20, 10_000), 745);
    let som_of = |model: &RecognizerFile| match &model.body {
        RecognizerBody::Som { som, .. } => som.node_labels().len(),
        other => panic!("not a SOM: {other:?}"),
    };
    let settings = TrainSettings {
        window_s: 0.5,
        train_window_s: Some(0.5),
        ..TrainSettings::new(Method::Som)
    };
    let paper = train(&three_surfaces(4.0), &settings).expect("train");
    assert_eq!(som_of(&paper), 12);
    assert_eq!(paper.classes_without_nodes(), []);
    // Fourteen surfaces: at least 28 nodes, as many as their windows call for; twelve could
    // not give each its own.
    let many = many_surfaces(14, 3.0);
    let grown = train(&many, &settings).expect("train");
    assert!(som_of(&grown) >= 28);
    assert_eq!(som_of(&grown), window_som_nodes(14, grown.n_train));
    let unmapped = grown.classes_without_nodes();
    let twelve = train(
        &many,
        &TrainSettings {
            som_nodes: Some(12),
            ..settings.clone()
        },
    )
    .expect("train");
    assert_eq!(som_of(&twelve), 12);
    let missing = twelve.classes_without_nodes();
    assert_eq!(missing.len(), 1, "{missing:?}");
    assert!(missing[0].classes.len() >= 2, "{missing:?}");
    assert_eq!((missing[0].behaviour, missing[0].nodes), (None, 12));
    assert!(
        unmapped.iter().map(|m| m.classes.len()).sum::<usize>() < missing[0].classes.len(),
        "{unmapped:?} vs {missing:?}"
    );
    // Fewer nodes than classes: the classes left out are named, in the recognizer's order.
    let two = train(
        &three_surfaces(4.0),
        &TrainSettings {
            som_nodes: Some(2),
            ..settings
        },
    )
    .expect("train");
    let missing = two.classes_without_nodes();
    assert_eq!(missing.len(), 1);
    assert_eq!(missing[0].classes.len(), 1, "{missing:?}");
    assert!(two.classes.iter().any(|c| c == missing[0].classes[0]));
    // Other recognizers have no map.
    let knn = train(
        &three_surfaces(4.0),
        &TrainSettings {
            window_s: 0.5,
            features: FeatureSet::Nakano,
            ..TrainSettings::new(Method::Knn)
        },
    )
    .expect("train");
    assert_eq!(knn.classes_without_nodes(), []);
}

#[test]
fn kept_features_train_and_evaluate_bit_identically_to_the_samples() {
    // Windows of 2 s: a window's histogram needs five 0.64 s frames at half a frame's hop.
    let train_set = vibrating_surfaces(5.0, 0..2);
    let mut held_out = vibrating_surfaces(4.0, 2..3);
    held_out.push(from(
        // Long enough for a whole-capture histogram, too short for a window after 5 mm.
        with_vibration(rubbing("fine", 5e-6, 0.3e-3, 0.10, 2.5), 40.0),
        "short.csv",
    ));
    let windowed = |method, features| TrainSettings {
        features,
        window_s: 2.0,
        train_window_s: Some(2.0),
        hop_s: 0.2,
        c: SvmC::Fixed(10.0),
        ..TrainSettings::new(method)
    };
    let settings = [
        windowed(Method::Som, FeatureSet::Nakano),
        windowed(Method::Som, FeatureSet::Both),
        windowed(Method::Knn, FeatureSet::Nakano),
        windowed(Method::Svm, FeatureSet::Both),
        windowed(Method::Knn, FeatureSet::Vibration),
        windowed(Method::Som, FeatureSet::Spectral),
        windowed(Method::Knn, FeatureSet::Spectral),
        windowed(Method::Svm, FeatureSet::Spectral),
    ];
    for s in &settings {
        let what = format!("{} over {}", s.method.name(), s.features);
        let needs = FeatureNeeds::training(s, 1000.0).expect("needs");
        let kept: Vec<LabelledCapture> = train_set
            .iter()
            .map(|c| c.clone().keep_features(&needs).expect("keeps"))
            .collect();
        assert!(
            kept.iter().all(|c| !c.has_samples() && c.capture.len() == 1),
            "{what}"
        );
        assert_eq!(kept[0].samples(), train_set[0].capture.len(), "{what}");
        let model = train(&train_set, s).expect("trains");
        assert_eq!(train(&kept, s).expect("trains on kept"), model, "{what}");
        assert_eq!(
            format!("{:?}", model.som_quality(&kept, true, None).expect("quality")),
            format!(
                "{:?}",
                model.som_quality(&train_set, true, None).expect("quality")
            ),
            "{what}"
        );

        let needs = FeatureNeeds::evaluation(&model, &[]).expect("needs");
        let kept: Vec<LabelledCapture> = held_out
            .iter()
            .map(|c| c.clone().keep_features(&needs))
            .collect::<Result<_, _>>()
            .unwrap_or_else(|e| panic!("{what}: {e}"));
        let (full, from_kept) = (
            model.evaluate(&held_out, None).expect("evaluates"),
            model.evaluate(&kept, None).expect("evaluates kept"),
        );
        assert_eq!(format!("{from_kept:?}"), format!("{full:?}"), "{what}");
        assert!(full.confusion.total() > 0, "{what}");
        // The plots' nodes per decision window, from kept features as from samples.
        for (k, whole) in kept.iter().zip(&held_out) {
            let nodes = model.som_winners(whole, None).expect("winners");
            assert_eq!(model.som_winners(k, None).expect("winners"), nodes, "{what}");
            match (&model.body, &nodes) {
                (RecognizerBody::Som { .. }, Some(nodes)) => {
                    let decisions = model.decisions(whole, None).expect("decisions");
                    assert_eq!(nodes.len(), decisions.len(), "{what}");
                }
                (RecognizerBody::Som { .. }, None) => panic!("{what}: a SOM without winners"),
                (_, found) => assert_eq!(found, &None, "{what}"),
            }
        }
        assert_eq!(
            format!("{:?}", model.evaluate_fused(&kept).expect("fuses")),
            format!("{:?}", model.evaluate_fused(&held_out).expect("fuses")),
            "{what}"
        );
        assert_eq!(
            format!("{:?}", model.som_quality(&kept, false, None).expect("quality")),
            format!(
                "{:?}",
                model.som_quality(&held_out, false, None).expect("quality")
            ),
            "{what}"
        );
        if let Some(w) = model.windowing() {
            // The short capture gives no window, and says why as it would with its samples.
            assert_eq!(full.windowless.len(), 1, "{what}");
            // A window length that was not kept is an error, not an evaluation of nothing.
            let err = model
                .evaluate(&kept, Some(w.window_s() / 2.0))
                .expect_err("not kept");
            assert!(
                matches!(err, RecognizeError::Usage(UsageError::FeaturesNotKept { .. })),
                "{what}: {err}"
            );
            assert!(err.to_string().contains("were not among them"), "{err}");
        }
    }
    let needs = FeatureNeeds::new().with_histogram(Histogram::default());
    let kept = train_set[0].clone().keep_features(&needs).expect("keeps");
    let err = kept.keep_features(&needs).expect_err("no samples left");
    assert!(
        matches!(err, RecognizeError::Usage(UsageError::FeaturesNotKept { .. })),
        "{err}"
    );
}

/// `nakano_spectrum` windows: each window's five Nakano features, as `nakano` reads them,
/// followed by the spectrum of the same window's heights, whose strongest band is the one the
/// surface's wavelength vibrates in at the rubbing speed. A k-NN or SVM trains on them, decided
/// at each window's last sample; a SOM refuses them; fused beside a recognizer over Nakano's
/// features they would count the height and the friction twice, beside one over the
/// accelerometer they would not.
#[test]
fn nakano_spectrum_windows_read_the_heights_spectrum_after_nakanos_features() {
    let windowing = NakanoWindowing {
        mirrored_end: true,
        ..NakanoWindowing::new(0.25, 0.1, 1000.0).expect("valid")
    };
    // 5 mm/s over a sine of 0.3 mm (16.7 Hz) and of 1.5 mm (3.3 Hz): the strongest of the
    // bands of 8 Hz is within a DFT bin (4 Hz in 0.25 s) of that frequency.
    for (c, tone_hz) in three_surfaces(4.0)
        .iter()
        .zip([Some(5e-3 / 0.3e-3), Some(5e-3 / 1.5e-3), None])
    {
        let both = window_vectors(c, &windowing, FeatureSet::NakanoSpectrum, Histogram::default())
            .expect("windows")
            .vectors;
        let nakano = window_vectors(c, &windowing, FeatureSet::Nakano, Histogram::default())
            .expect("windows")
            .vectors;
        assert_eq!(both.len(), nakano.len());
        assert!(both.len() > 20, "{}", both.len());
        for ((s, span, v), (s_n, span_n, n)) in both.iter().zip(&nakano) {
            assert_eq!((s, span), (s_n, span_n));
            assert_eq!(v.len(), FeatureSet::NakanoSpectrum.dim());
            assert_eq!(&v[..5], &n[..]);
            let spectrum = &v[5..];
            let strongest = (0..spectrum.len())
                .max_by(|&a, &b| spectrum[a].total_cmp(&spectrum[b]))
                .expect("bands");
            if let Some(f) = tone_hz {
                let (lo, hi) = (8.0 * strongest as f64, 8.0 * (strongest + 1) as f64);
                let off_hz = (lo - f).max(f - hi).max(0.0);
                assert!(off_hz <= 4.0, "{}: band {strongest} of {spectrum:?}", c.label);
            }
        }
    }
    assert_eq!(FeatureSet::NakanoSpectrum.blocks(), [5, 25]);
    assert_eq!(
        FeatureSet::NakanoSpectrum.feature_names()[5],
        "height_spectrum_f0"
    );

    let train_set = with_tones(0..2, 4.0);
    let settings = |method, features| TrainSettings {
        fit_posterior_weight: false,
        ..short_windows(method, features)
    };
    let spectrum = train(&train_set, &settings(Method::Svm, FeatureSet::NakanoSpectrum)).expect("svm");
    assert_eq!(spectrum.feature_set(), FeatureSet::NakanoSpectrum);
    // Its spectrum is read from the window's own samples, so it is decided at its last one.
    assert!(spectrum.windowing().expect("windows").mirrored_end);
    let evaluation = spectrum
        .evaluate_sequential(
            &with_tones(2..3, 4.0),
            &[0.9],
            spectrum.sequential_params(3.0).expect("params"),
        )
        .expect("evaluated");
    assert_eq!(
        evaluation.rows[0].correct, evaluation.rows[0].decided,
        "{evaluation:?}"
    );
    assert!(evaluation.rows[0].decided > 0, "{evaluation:?}");
    let err = train(&train_set, &settings(Method::Som, FeatureSet::NakanoSpectrum)).expect_err("a SOM");
    assert!(
        matches!(err, RecognizeError::Setting(SettingError::Config { .. })),
        "{err}"
    );

    let nakano = train(&train_set, &settings(Method::Svm, FeatureSet::Nakano)).expect("nakano");
    let vibration = train(&train_set, &settings(Method::Svm, FeatureSet::Vibration)).expect("vibration");
    for (a, b) in [(&nakano, &spectrum), (&spectrum, &nakano)] {
        let err = a.fusion_members(&[b]).expect_err("the height twice");
        assert!(
            matches!(err, RecognizeError::Setting(SettingError::FusionOverlap { .. })),
            "{err}"
        );
    }
    assert_eq!(
        spectrum
            .fusion_members(&[&vibration])
            .expect("other senses")
            .len(),
        2
    );
}

#[test]
fn data_warnings_name_classes_with_few_vectors_and_constant_features() {
    let settings = |method| TrainSettings {
        window_s: 0.5,
        train_window_s: Some(0.5),
        features: FeatureSet::Nakano,
        ..TrainSettings::new(method)
    };
    // Four seconds of each surface give dozens of windows, and every feature varies.
    assert_eq!(
        settings(Method::Som)
            .data_warnings(&three_surfaces(4.0))
            .expect("warnings"),
        []
    );
    // 1.9 s of cork gives windows from 1 s of travel on, until the window and its margin end.
    let mut captures = three_surfaces(4.0);
    captures.push(from(rubbing("cork", 10e-6, 1e-3, 0.15, 1.9), "cork.csv"));
    let (x, y, _) = training_windows(
        &captures,
        &class_list(&captures),
        &settings(Method::Som).windowing(&captures).expect("windowing"),
        FeatureSet::Nakano,
        Histogram::default(),
    )
    .expect("windows");
    let cork_index = class_list(&captures)
        .iter()
        .position(|c| c == "cork")
        .expect("cork");
    let cork = y.iter().filter(|&&l| l == cork_index).count();
    assert!((1..FEW_TRAINING_VECTORS).contains(&cork), "{cork} of {}", x.len());
    for (method, least) in [(Method::Som, 5), (Method::Knn, 5), (Method::Svm, 5)] {
        let warnings = settings(method).data_warnings(&captures).expect("warnings");
        assert_eq!(
            warnings,
            [TrainingWarning::FewVectors {
                behaviour: None,
                class: "cork".into(),
                vectors: cork,
                least,
            }],
            "{method:?}"
        );
    }
    // A k-NN needs at least its k.
    let knn_k = TrainSettings {
        k: 7,
        ..settings(Method::Knn)
    };
    let warnings = knn_k.data_warnings(&captures).expect("warnings");
    assert!(
        matches!(&warnings[..], [TrainingWarning::FewVectors { least: 7, class, .. }] if class == "cork"),
        "{warnings:?}"
    );
    // A flat surface everywhere: the roughness features are 0 in every window.
    let flat: Vec<LabelledCapture> = [("a", 0.1), ("b", 0.2)]
        .map(|(s, f)| rubbing(s, 0.0, 1e-3, f, 4.0))
        .into();
    let warnings = settings(Method::Som).data_warnings(&flat).expect("warnings");
    let [TrainingWarning::ConstantFeatures { features, of: 5, .. }] = &warnings[..] else {
        panic!("{warnings:?}");
    };
    let names: Vec<&str> = features.iter().map(|(n, _)| n.as_str()).collect();
    assert!(
        names.contains(&"roughness_mean_abs_m") && names.contains(&"roughness_variance_m2"),
        "{names:?}"
    );
    assert!(!names.iter().any(|n| n.starts_with("friction")), "{names:?}");
    assert!(
        warnings[0].to_string().contains("constant over all"),
        "{}",
        warnings[0]
    );

    // Whole-scratch histograms: two per class, and a vibration that never changes.
    let spectral = TrainSettings::new(Method::Knn);
    let mut scratches = vibrating_surfaces(4.0, 0..2);
    let warnings = spectral.data_warnings(&scratches).expect("warnings");
    assert_eq!(warnings.len(), 3, "{warnings:?}");
    assert!(
        warnings.iter().all(|w| matches!(
            w,
            TrainingWarning::FewVectors {
                vectors: 2,
                least: 5,
                behaviour: None,
                ..
            }
        )),
        "{warnings:?}"
    );
    for c in &mut scratches {
        let mut data = c.capture.data().to_vec();
        let last = data.len() - 1;
        data[last].fill(9.81);
        c.capture =
            Capture::new(c.capture.metadata().clone(), c.capture.columns().to_vec(), data).expect("valid");
    }
    let warnings = spectral.data_warnings(&scratches).expect("warnings");
    let constant = warnings.iter().find_map(|w| match w {
        TrainingWarning::ConstantFeatures {
            features,
            of,
            vectors,
            ..
        } => Some((features.len(), *of, *vectors)),
        TrainingWarning::FewVectors { .. }
        | TrainingWarning::ShortOfTravel { .. }
        | TrainingWarning::TooFast(_) => None,
    });
    assert_eq!(constant, Some((125, 125, 6)), "{warnings:?}");
}

/// Windows over travel slid too fast for their bands are left out of training and counted in
/// a warning that names the speeds, not fatal: a rig's slow position stream can read a burst
/// of speed over a few samples, and one such window stopped the whole training.
#[test]
fn windows_too_fast_for_their_bands_are_left_out_and_counted() {
    use crate::recognizer::train::TrainingWarning;

    let mut captures = with_tones(0..2, 4.0);
    // A third trial of `fine` rubbed at 20 mm/s: past the 12.5 mm/s its bands read at 1 kHz.
    let mut fast = with_vibration(rubbing_at("fine", 5e-6, 0.3e-3, 0.10, 4.0, 0.02), 60.0);
    let meta = fast.capture.metadata().clone().with(TRIAL_KEY, 2);
    fast.capture = Capture::new(
        meta,
        fast.capture.columns().to_vec(),
        fast.capture.data().to_vec(),
    )
    .expect("valid");
    fast.reference.path = "fine_2.csv".into();
    captures.push(fast.clone());
    let settings = TrainSettings {
        windows_over_travel: true,
        ..short_windows(Method::Knn, FeatureSet::Vibration)
    };
    let model = train(&captures, &settings).expect("trains on the windows it can read");
    let training = model.windowing().expect("windows").training();
    let skipped =
        window_vectors(&fast, &training, FeatureSet::Vibration, Histogram::default()).expect("windows");
    assert!(skipped.vectors.is_empty());
    assert!(skipped.too_fast.count > 10, "{:?}", skipped.too_fast);
    let warnings = settings.data_warnings(&captures).expect("warnings");
    let counted = warnings
        .iter()
        .find_map(|w| match w {
            TrainingWarning::TooFast(t) => Some(*t),
            _ => None,
        })
        .expect("a warning counts them");
    assert_eq!(counted, skipped.too_fast);
    assert!((counted.fastest_mps - 0.02).abs() < 1e-3, "{counted:?}");
    assert!((counted.readable_up_to_mps - 0.0125).abs() < 1e-9, "{counted:?}");
    let text = TrainingWarning::TooFast(counted).to_string();
    assert!(
        text.contains("--fastest-speed-mps") && text.contains("12.5 mm/s"),
        "{text}"
    );
    // The other captures' windows are all read.
    for c in &captures[..6] {
        let w = window_vectors(c, &training, FeatureSet::Vibration, Histogram::default()).expect("windows");
        assert_eq!(w.too_fast.count, 0);
        assert!(!w.vectors.is_empty());
    }
}

/// Unit-sum cells kept beside mean ones are derived from them, and equal those computed from
/// the samples to the bit, for every windowed set with cells; a set over the same windows
/// reuses their Nakano features and still matches.
#[test]
fn unit_sum_cells_derived_from_mean_ones_are_those_of_the_samples() {
    let captures = vibrating_surfaces(5.0, 0..1);
    let windowing = NakanoWindowing::new(2.0, 0.2, 1000.0).expect("valid");
    let mirrored = NakanoWindowing {
        mirrored_end: true,
        ..windowing
    };
    let mean = Histogram::default();
    let unit = Histogram::new(crate::CellScale::UnitSum);
    let mut needs = FeatureNeeds::new();
    for (w, f) in [
        (windowing, FeatureSet::Both),
        (windowing, FeatureSet::Nakano),
        (mirrored, FeatureSet::Vibration),
        (mirrored, FeatureSet::NakanoSpectrum),
    ] {
        needs = needs.with_windows(w, f, mean).with_windows(w, f, unit);
    }
    for c in &captures {
        let kept = c.clone().keep_features(&needs).expect("keeps");
        for &(w, f, h) in &needs.windows {
            let direct = window_vectors(c, &w, f, h).expect("windows");
            assert!(!direct.vectors.is_empty());
            assert_eq!(window_vectors(&kept, &w, f, h).expect("kept"), direct, "{f} {h}");
        }
    }
}

/// With nothing named, the search scores every set the captures carry by cross-validation by
/// recording, keeps the documented default unless another is clearly better, and its table
/// survives the model file; what is named is not varied.
#[test]
fn the_search_scores_the_candidates_by_recording_and_keeps_its_table() {
    let captures = vibrating_surfaces(5.0, 0..3);
    let base = TrainSettings {
        window_s: 2.0,
        hop_s: 0.2,
        fit_posterior_weight: false,
        ..TrainSettings::new(Method::Knn)
    };
    let named = Named {
        window_s: Some(2.0),
        band: Some(crate::HistogramBand::Paper),
        ..Default::default()
    };
    let search = DefaultSearch::new(base.clone(), named, &captures[0], 60.0);
    let sets: Vec<FeatureSet> = search.candidates().iter().map(|c| c.features).collect();
    assert_eq!(sets[0], FeatureSet::Both, "the documented default first");
    for f in [
        FeatureSet::Nakano,
        FeatureSet::Vibration,
        FeatureSet::NakanoSpectrum,
    ] {
        assert!(sets.contains(&f), "{f}");
    }
    // Windows are not weighed against whole captures.
    assert!(!sets.contains(&FeatureSet::Spectral));
    // Named: one window, one band; free: two cell scalings of each set with cells.
    assert!(search.candidates().iter().all(|c| c.window_s == Some(2.0)));
    assert_eq!(search.candidates().len(), 1 + 2 + 2 + 2);
    let needs = search.needs(1000.0);
    let kept: Vec<LabelledCapture> = captures
        .iter()
        .map(|c| c.clone().keep_features(&needs).expect("keeps"))
        .collect();
    let choice = search.run(&kept, &|_| {});
    assert_eq!(choice.folds, 3, "one fold per trial");
    assert_eq!(choice.hop_s, SPARSE_HOP_S);
    for row in &choice.rows {
        match &row.outcome {
            Outcome::Scored {
                accuracy, decisions, ..
            } => {
                assert!((0.0..=1.0).contains(accuracy));
                assert!(*decisions > 0);
            }
            other => panic!("{row:?}: {other:?}"),
        }
    }
    // The default stands, or was beaten.
    let first = choice.rows[0].accuracy().expect("scored");
    let chosen = choice.rows[choice.chosen].accuracy().expect("scored");
    assert!(
        choice.chosen == 0 || chosen > first,
        "{chosen} vs the default's {first}"
    );
    // The chosen settings train on the samples, and the table round-trips in the file.
    let mut model = train(&captures, &choice.chosen().settings(&base)).expect("trains");
    assert_eq!(model.feature_set(), choice.chosen().features);
    model.default_choice = Some(choice);
    let json = serde_json::to_string(&model).expect("serialize");
    let back = RecognizerFile::from_json(&json, Path::new("m.json")).expect("valid");
    assert_eq!(back, model);
    let mut edited = serde_json::to_value(&model).expect("json");
    edited["default_choice"]["chosen"] = 99.into();
    let err = RecognizerFile::from_json(&edited.to_string(), Path::new("m.json")).expect_err("row");
    assert!(err.to_string().contains("default_choice.chosen"), "{err}");
}
