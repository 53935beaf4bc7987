use std::path::Path;

use super::*;
use crate::RecognizeError;
use crate::features::histogram_names;
use crate::features::spectral::Histogram;
use crate::features::{FeatureSet, NakanoWindowing, window_vectors};
use crate::knn::KnnParams;
use crate::recognizer::labelled::class_list;
use crate::recognizer::sequential_eval::{Stroke, StrokeWindow};
use crate::recognizer::train::training_windows;
use crate::som::SomParams;
use crate::svc::{CSearch, Svc, SvcParams};
use crate::{DataError, InputError, SettingError, UsageError};
use capture::kind::{FRICTION_FORCE_N, NORMAL_FORCE_N, NORMAL_POSITION_M, TANGENTIAL_POSITION_M, TIME_S};
use capture::{Capture, CaptureKind, Metadata};

/// A rubbing capture of a sine roughness of `amplitude_m` and `wavelength_m` with friction
/// `friction_n`, 5 mm/s at 1 kHz for `seconds`.
fn rubbing(
    surface: &str,
    amplitude_m: f64,
    wavelength_m: f64,
    friction_n: f64,
    seconds: f64,
) -> LabelledCapture {
    rubbing_at(surface, amplitude_m, wavelength_m, friction_n, seconds, 5e-3)
}

/// [`rubbing`] at `speed_m_s` (0: a tip that never slides).
fn rubbing_at(
    surface: &str,
    amplitude_m: f64,
    wavelength_m: f64,
    friction_n: f64,
    seconds: f64,
    speed_m_s: f64,
) -> LabelledCapture {
    let n = (seconds * 1000.0) as usize;
    let t: Vec<f64> = (0..n).map(|k| k as f64 * 1e-3).collect();
    let x: Vec<f64> = t.iter().map(|t| speed_m_s * t).collect();
    let z: Vec<f64> = x
        .iter()
        .map(|x| amplitude_m * (x * std::f64::consts::TAU / wavelength_m).sin())
        .collect();
    let f: Vec<f64> = (0..n)
        .map(|k| friction_n * (1.0 + 0.05 * ((k * 7919) % 13) as f64 / 13.0))
        .collect();
    let meta = Metadata::new(CaptureKind::Rubbing, "test", 1000.0).with(LABEL_KEY, surface);
    let columns = [
        TIME_S,
        TANGENTIAL_POSITION_M,
        NORMAL_POSITION_M,
        NORMAL_FORCE_N,
        FRICTION_FORCE_N,
    ]
    .map(String::from)
    .to_vec();
    let capture = Capture::new(meta, columns, vec![t, x, z, vec![0.3; n], f]).expect("valid capture");
    LabelledCapture::new(capture, Path::new(surface), "00".into()).expect("labelled")
}

fn three_surfaces(seconds: f64) -> Vec<LabelledCapture> {
    vec![
        rubbing("fine", 5e-6, 0.3e-3, 0.10, seconds),
        rubbing("coarse", 30e-6, 1.5e-3, 0.20, seconds),
        rubbing("smooth", 1e-6, 0.8e-3, 0.05, seconds),
    ]
}

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

/// One classifier per behaviour, `poke` then `rub`: `make` gets the behaviour and whether it
/// carries a reliability weight (only `poke` does).
fn poke_and_rub<T>(make: impl Fn(Option<String>, bool) -> T) -> Vec<T> {
    ["poke", "rub"]
        .map(|b| make(Some(b.to_owned()), b == "poke"))
        .into()
}

/// A k-NN and an SVM recognizer over two behaviours of three classes, built without
/// captures: `poke` has a reliability weight, `rub` (as in a file written before weights
/// were stored, or with too few trials) has none.
fn sinapov_recognizers() -> [RecognizerFile; 2] {
    use crate::svc::CvPoint;
    let x: Vec<Vec<f64>> = (0..6)
        .map(|i| {
            (0..crate::features::spectral::FEATURE_LEN)
                .map(|j| (i / 2) as f64 + 0.01 * ((i * 31 + j * 7) % 11) as f64)
                .collect()
        })
        .collect();
    let y = [0, 0, 1, 1, 2, 2];
    let knn = KnnParams::default().fit(&x, &y, 3).expect("k-NN");
    let params = SvcParams {
        c: 10.0,
        probability: false,
        ..SvcParams::default()
    };
    let svc = Svc::fit(params, &x, &y, 3).expect("SVC");
    let classes: Vec<String> = ["a", "b", "c"].map(String::from).to_vec();
    let knn_body = RecognizerBody::Knn {
        histogram: Histogram::default(),
        behaviours: poke_and_rub(|behaviour, weighted| BehaviourKnn {
            behaviour,
            knn: knn.clone(),
            reliability: weighted.then_some(0.8),
            reliability_folds: weighted.then_some(5),
        }),
    };
    let search = CSearch {
        folds: 5,
        grid: vec![
            CvPoint {
                c: 1.0,
                accuracy: 0.5,
            },
            CvPoint {
                c: 10.0,
                accuracy: 0.8,
            },
        ],
        chosen_c: 10.0,
        separable_from: None,
        vector_weight: None,
    };
    let svm_body = RecognizerBody::Svm {
        histogram: Histogram::default(),
        behaviours: poke_and_rub(|behaviour, weighted| BehaviourSvc {
            behaviour,
            svc: svc.clone(),
            reliability: weighted.then_some(0.8),
            c_search: weighted.then(|| search.clone()),
        }),
    };
    [knn_body, svm_body]
        .map(|body| RecognizerFile::assemble(classes.clone(), histogram_names(), body, &[], 6))
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

/// `c`, read from `path` instead.
fn from(mut c: LabelledCapture, path: &str) -> LabelledCapture {
    c.reference.path = path.into();
    c
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

/// Rubbing captures of `n` surfaces, `surface_00`…, each a different roughness and friction.
fn many_surfaces(n: usize, seconds: f64) -> Vec<LabelledCapture> {
    (0..n)
        .map(|i| {
            let i_f = i as f64;
            rubbing(
                &format!("surface_{i:02}"),
                2e-6 * (1.0 + i_f),
                0.3e-3 + 0.1e-3 * (i_f % 5.0),
                0.05 + 0.02 * i_f,
                seconds,
            )
        })
        .collect()
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

/// `c` with a single-axis vibration: gravity and a tone whose frequency tells the surface.
fn with_vibration(c: LabelledCapture, tone_hz: f64) -> LabelledCapture {
    let capture = &c.capture;
    let mut columns = capture.columns().to_vec();
    let mut data = capture.data().to_vec();
    let vibration = capture
        .time()
        .iter()
        .enumerate()
        .map(|(k, t)| {
            9.81 + 0.5 * (std::f64::consts::TAU * tone_hz * t).sin() + 0.05 * ((k * 7919) % 17) as f64 / 17.0
        })
        .collect();
    columns.push(capture::kind::VIBRATION_MPS2.to_owned());
    data.push(vibration);
    let meta = capture.metadata().clone();
    LabelledCapture {
        capture: Capture::new(meta, columns, data).expect("valid"),
        ..c
    }
}

/// Three surfaces with vibration, two trials each, `seconds` long.
pub(super) fn vibrating_surfaces(seconds: f64, trials: std::ops::Range<u32>) -> Vec<LabelledCapture> {
    let mut out = Vec::new();
    for t in trials {
        for (c, tone) in three_surfaces(seconds).into_iter().zip([40.0, 95.0, 150.0]) {
            let mut c = with_vibration(c, tone + f64::from(t));
            let meta = c.capture.metadata().clone().with(TRIAL_KEY, t);
            c.capture =
                Capture::new(meta, c.capture.columns().to_vec(), c.capture.data().to_vec()).expect("valid");
            c.reference.path = format!("{}_{t}.csv", c.label).into();
            out.push(c);
        }
    }
    out
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

/// [`three_surfaces`] as trials `trials`, each with a vibration tone: `fine` and `coarse` share
/// theirs (60 Hz), so the vibration cannot tell them apart; the friction can.
pub(super) fn with_tones(trials: std::ops::Range<u32>, seconds: f64) -> Vec<LabelledCapture> {
    trials
        .flat_map(|t| {
            three_surfaces(seconds)
                .into_iter()
                .zip([60.0, 60.0, 150.0])
                .map(move |(c, tone)| {
                    let mut c = with_vibration(c, tone);
                    let meta = c.capture.metadata().clone().with(TRIAL_KEY, t);
                    c.capture = Capture::new(meta, c.capture.columns().to_vec(), c.capture.data().to_vec())
                        .expect("valid");
                    c.reference.path = format!("{}_{t}.csv", c.label).into();
                    c
                })
        })
        .collect()
}

/// `method` over `features` in 0.25 s windows every 0.1 s, trained on windows of that length.
pub(super) fn short_windows(method: Method, features: FeatureSet) -> TrainSettings {
    TrainSettings {
        features,
        window_s: 0.25,
        train_window_s: Some(0.25),
        hop_s: 0.1,
        ..TrainSettings::new(method)
    }
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
