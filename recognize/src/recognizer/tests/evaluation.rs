//! Evaluation: the decisions over a stroke, when and how far into it they come, and their
//! calibration.

use super::*;

#[test]
fn evaluation_refuses_no_decisions_and_lists_captures_without_one() {
    let windowing = NakanoWindowing::new(0.5, 0.1, 1000.0).expect("valid");
    let model =
        RecognizerFile::train_som(&three_surfaces(4.0), windowing, SomParams::default()).expect("train");
    let short = [
        from(rubbing("fine", 5e-6, 0.3e-3, 0.10, 0.4), "fine-short.csv"),
        from(rubbing("coarse", 30e-6, 1.5e-3, 0.20, 0.3), "coarse-short.csv"),
    ];
    let err = model.evaluate(&short, None).expect_err("no decisions");
    let RecognizeError::Data(DataError::NoDecisions { captures }) = &err else {
        panic!("{err}");
    };
    let paths: Vec<&Path> = captures.iter().map(|w| w.path.as_path()).collect();
    assert_eq!(
        paths,
        [Path::new("fine-short.csv"), Path::new("coarse-short.csv")]
    );
    let text = err.to_string();
    assert!(
        text.contains("capture fine-short.csv is 0.400 s long; a decision window needs 0.5 s"),
        "{text}"
    );
    assert!(
        text.contains("capture coarse-short.csv is 0.300 s long"),
        "{text}"
    );
    // One short capture among others is scored as never correct and listed, not refused.
    let mut mixed = three_surfaces(3.0);
    mixed.push(short[0].clone());
    let eval = model.evaluate(&mixed, None).expect("other captures decide");
    assert_eq!(eval.windowless.len(), 1);
    assert_eq!(eval.windowless[0].path, Path::new("fine-short.csv"));
    assert_eq!((eval.captures, eval.never_correct), (4, 1));
}

#[test]
fn a_change_of_surface_is_read_from_the_metadata_and_checked() {
    let c = rubbing("fine", 5e-6, 0.3e-3, 0.10, 1.0);
    assert_eq!(c.change, None);
    let relabel = |extra: &[(&str, &str)]| {
        let mut meta = c.capture.metadata().clone();
        for (k, v) in extra {
            meta.insert(*k, v);
        }
        let capture =
            Capture::new(meta, c.capture.columns().to_vec(), c.capture.data().to_vec()).expect("valid");
        LabelledCapture::new(capture, Path::new("two.csv"), "00".into())
    };
    let two = relabel(&[(SURFACE_AFTER_KEY, "coarse"), (SURFACE_CHANGE_S_KEY, "0.5")]).expect("labelled");
    assert_eq!(
        two.change,
        Some(SurfaceChange {
            after: "coarse".into(),
            at_s: 0.5
        })
    );
    for (extra, says) in [
        (vec![(SURFACE_AFTER_KEY, "coarse")], "only one of"),
        (vec![(SURFACE_CHANGE_S_KEY, "0.5")], "only one of"),
        (
            vec![(SURFACE_AFTER_KEY, "coarse"), (SURFACE_CHANGE_S_KEY, "soon")],
            "surface_change_s",
        ),
        (
            vec![(SURFACE_AFTER_KEY, "coarse"), (SURFACE_CHANGE_S_KEY, "-1")],
            "surface_change_s",
        ),
    ] {
        let e = relabel(&extra).expect_err("refused").to_string();
        assert!(e.contains("two.csv") && e.contains(says), "{e}");
    }
    // A change onto a surface the recognizer does not know is refused by name.
    let windowing = NakanoWindowing::new(0.5, 0.1, 1000.0).expect("valid");
    let knn = RecognizerFile::train_knn_windows(
        &three_surfaces(4.0),
        windowing,
        FeatureSet::Nakano,
        3,
        Histogram::default(),
    )
    .expect("k-NN");
    let params = knn.sequential_params(3.0).expect("window probabilities");
    let unknown = relabel(&[(SURFACE_AFTER_KEY, "glass"), (SURFACE_CHANGE_S_KEY, "0.5")]).expect("labelled");
    let e = knn
        .evaluate_sequential(&[unknown], &[0.9], params)
        .expect_err("unknown surface")
        .to_string();
    assert!(e.contains("two.csv") && e.contains("glass"), "{e}");
    // A stroke of one surface labelled as changing onto another at 1 s: the decisions after
    // the change are scored against the new surface, so the names the recognizer keeps giving
    // the old one count as wrong, and the change is not followed.
    let stroke = |change: Option<&str>| {
        let c = rubbing("fine", 5e-6, 0.3e-3, 0.10, 4.0);
        let mut meta = c.capture.metadata().clone();
        if let Some(at) = change {
            meta.insert(SURFACE_AFTER_KEY, "coarse");
            meta.insert(SURFACE_CHANGE_S_KEY, at);
        }
        let capture =
            Capture::new(meta, c.capture.columns().to_vec(), c.capture.data().to_vec()).expect("valid");
        LabelledCapture::new(capture, Path::new("s.csv"), "00".into()).expect("labelled")
    };
    let plain = knn
        .evaluate_sequential(&[stroke(None)], &[0.9], params)
        .expect("eval");
    let changed = knn
        .evaluate_sequential(&[stroke(Some("1.0"))], &[0.9], params)
        .expect("eval");
    let (p, c) = (&plain.rows[0], &changed.rows[0]);
    assert_eq!((p.changes, c.changes, c.changes_not_followed), (0, 1, 1));
    assert_eq!(p.correct, p.decided);
    assert!(c.correct < c.decided, "{c:?}");
    assert_eq!(c.change_followed_s, None);
    // The stroke with a change is left out of the single-surface times.
    assert!(p.time_to_stable_correct_s.is_some() && c.time_to_stable_correct_s.is_none());
}

/// The anytime decisions say how far into the stroke they came as well as how soon: the path
/// through the play, which at a steady 5 mm/s from the first sample is 5 mm a second less the
/// play's first 0.1 mm; after a change, the path since it. A capture that kept only its
/// features says exactly the same.
#[test]
fn anytime_decisions_say_how_far_into_the_stroke_they_came() {
    let knn = RecognizerFile::train_knn_windows(
        &three_surfaces(4.0),
        NakanoWindowing::new(0.5, 0.1, 1000.0).expect("valid"),
        FeatureSet::Nakano,
        3,
        Histogram::default(),
    )
    .expect("k-NN");
    let params = knn.sequential_params(3.0).expect("window probabilities");
    let path_m = |t_s: f64| (5e-3 * t_s - crate::TRAVEL_PLAY_M / 2.0).max(0.0);
    // Fine for 3 s, then coarse for 4 s, on one steady stroke.
    let (fine, coarse) = (
        rubbing("fine", 5e-6, 0.3e-3, 0.10, 7.0),
        rubbing("coarse", 30e-6, 1.5e-3, 0.20, 7.0),
    );
    let mut data = fine.capture.data().to_vec();
    for (column, after) in data.iter_mut().zip(coarse.capture.data()) {
        column[3000..].copy_from_slice(&after[3000..]);
    }
    let mut meta = fine.capture.metadata().clone();
    meta.insert(SURFACE_AFTER_KEY, "coarse");
    meta.insert(SURFACE_CHANGE_S_KEY, "3.0");
    let two = Capture::new(meta, fine.capture.columns().to_vec(), data).expect("valid");
    let two = LabelledCapture::new(two, Path::new("two.csv"), "00".into()).expect("labelled");
    let set = vec![
        rubbing("fine", 5e-6, 0.3e-3, 0.10, 4.0),
        rubbing("coarse", 30e-6, 1.5e-3, 0.20, 4.0),
        two,
    ];
    let e = knn.evaluate_sequential(&set, &[0.9], params).expect("eval");
    let r = &e.rows[0];
    let (t_s, m) = (
        r.time_to_stable_correct_s.expect("both single strokes end right"),
        r.travel_to_stable_correct_m.expect("positions"),
    );
    // The mean of two paths is the path at the mean time where neither is within the play.
    assert!(t_s > 0.1 && (m - path_m(t_s)).abs() < 1e-12, "{t_s} s, {m} m");
    let (name, worst_m) = r.worst_surface_travel.clone().expect("worst surface");
    let (worst_name, worst_s) = r.worst_surface.clone().expect("worst surface");
    assert_eq!(name, worst_name);
    assert!(
        (worst_m - path_m(worst_s)).abs() < 1e-12,
        "{worst_m} m at {worst_s} s"
    );
    assert_eq!((r.changes, r.changes_not_followed), (1, 0), "{r:?}");
    let (after_s, after_m) = (
        r.change_followed_s.expect("followed"),
        r.change_followed_m.expect("positions"),
    );
    assert!(
        after_s > 0.0 && (after_m - 5e-3 * after_s).abs() < 1e-12,
        "{after_s} s, {after_m} m"
    );
    assert_eq!(r.slowest_change_m, Some(after_m));

    let needs = FeatureNeeds::sequential(&knn).expect("needs");
    let kept: Vec<LabelledCapture> = set
        .iter()
        .map(|c| c.clone().keep_features(&needs).expect("keeps"))
        .collect();
    let k = &knn
        .evaluate_sequential(&kept, &[0.9], params)
        .expect("eval kept")
        .rows[0];
    assert_eq!(k, r);
}

/// Each threshold's row carries the posterior's calibration at that threshold, the same as an
/// evaluation at that threshold alone; the evaluation's own is its first row's.
#[test]
fn each_threshold_has_its_own_calibration() {
    let nakano = train(
        &with_tones(0..2, 4.0),
        &short_windows(Method::Svm, FeatureSet::Nakano),
    )
    .expect("nakano");
    let test_set = with_tones(2..3, 3.0);
    let params = nakano.sequential_params(3.0).expect("params");
    let thresholds = [0.5, 0.99];
    let both = nakano
        .evaluate_sequential(&test_set, &thresholds, params)
        .expect("evaluated");
    assert_eq!(both.calibration, both.rows[0].calibration);
    for (row, t) in both.rows.iter().zip(thresholds) {
        let alone = nakano
            .evaluate_sequential(&test_set, &[t], params)
            .expect("evaluated");
        assert_eq!(*row, alone.rows[0]);
        assert_eq!(alone.calibration, alone.rows[0].calibration);
        let windows: usize = row.calibration.bins.iter().map(|b| b.count).sum();
        assert_eq!(windows, both.steps);
    }
    // Without thresholds, at the default one.
    let none = nakano
        .evaluate_sequential(&test_set, &[], params)
        .expect("evaluated");
    let default = nakano
        .evaluate_sequential(&test_set, &[crate::sequential::DEFAULT_THRESHOLD], params)
        .expect("evaluated");
    assert_eq!(none.calibration, default.calibration);
}
