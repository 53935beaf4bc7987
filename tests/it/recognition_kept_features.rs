//! `palpus recognize train`, `eval` and `cv` keep each capture only as the features they read
//! (dropping its samples before reading the next), and their results are exactly those of the
//! library on the whole captures; training warns of thin or constant training data, and the
//! map's size is `--nodes` (or `--som-nodes`).

use std::path::{Path, PathBuf};

use crate::common::{SineRub, fails, rub_wobble, sine_rub, succeeds};
use capture::kind::{
    FRICTION_FORCE_N, NORMAL_FORCE_N, NORMAL_POSITION_M, TANGENTIAL_POSITION_M, TIME_S, VIBRATION_MPS2,
};
use capture::{Capture, CaptureKind, Metadata};
use recognize::{FeatureSet, LabelledCapture, Method, RecognizerFile, TrainSettings};

/// Writes a rub of `surface` at 5 mm/s, 1 kHz, `seconds` long, with a roughness of
/// `amplitude_m` and a single-axis vibration of tone `tone_hz`, trial `trial`.
fn write_rub(dir: &Path, surface: &str, amplitude_m: f64, tone_hz: f64, trial: u32, seconds: f64) -> PathBuf {
    let SineRub { t, x, z, f } = sine_rub(amplitude_m, seconds, trial);
    let n = t.len();
    let v: Vec<f64> = t
        .iter()
        .enumerate()
        .map(|(k, t)| 9.81 + 0.5 * (std::f64::consts::TAU * tone_hz * t).sin() + 0.1 * rub_wobble(k, trial))
        .collect();
    let meta = Metadata::new(CaptureKind::Rubbing, "test", 1000.0)
        .with("surface", surface)
        .with("trial", trial);
    let columns = [
        TIME_S,
        TANGENTIAL_POSITION_M,
        NORMAL_POSITION_M,
        NORMAL_FORCE_N,
        FRICTION_FORCE_N,
        VIBRATION_MPS2,
    ]
    .map(String::from)
    .to_vec();
    let path = dir.join(format!("{surface}_{trial}.csv"));
    Capture::new(meta, columns, vec![t, x, z, vec![0.3; n], f, v])
        .expect("capture")
        .write_file(&path)
        .expect("write");
    path
}

/// Three surfaces, trials `trials`, 4 s each.
fn write_surfaces(dir: &Path, trials: std::ops::Range<u32>) -> Vec<PathBuf> {
    let mut paths = Vec::new();
    for trial in trials {
        for (surface, amplitude_m, tone_hz) in [
            ("fine", 5e-6, 40.0),
            ("coarse", 30e-6, 95.0),
            ("mid", 12e-6, 150.0),
        ] {
            paths.push(write_rub(dir, surface, amplitude_m, tone_hz, trial, 4.0));
        }
    }
    paths
}

fn strings(paths: &[PathBuf]) -> Vec<String> {
    paths.iter().map(|p| p.to_string_lossy().into_owned()).collect()
}

fn read_all(paths: &[PathBuf]) -> Vec<LabelledCapture> {
    paths
        .iter()
        .map(|p| LabelledCapture::read(p).expect("capture"))
        .collect()
}

/// `palpus recognize train --method METHOD OPTIONS --out MODEL CAPTURES…`: what it printed on
/// stderr, and the recognizer it wrote.
fn train_cli(method: &str, options: &[&str], model: &Path, captures: &[String]) -> (String, RecognizerFile) {
    let model_s = model.to_string_lossy().into_owned();
    let mut argv = vec!["recognize", "train", "--method", method, "--out", &model_s];
    argv.extend(options);
    argv.extend(captures.iter().map(String::as_str));
    let out = succeeds(&argv);
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    (stderr, RecognizerFile::load(model).expect("written recognizer"))
}

#[test]
fn train_eval_and_cv_on_kept_features_match_the_library_on_whole_captures() {
    let dir = tempfile::tempdir().expect("tempdir");
    let train_paths = write_surfaces(dir.path(), 0..2);
    let test_paths = write_surfaces(dir.path(), 2..3);
    let (train_s, test_s) = (strings(&train_paths), strings(&test_paths));
    let (whole_train, whole_test) = (read_all(&train_paths), read_all(&test_paths));
    // 2 s windows: a window's histogram (k-NN over both) needs 1.92 s.
    let window = ["--window-s", "2", "--train-window-s", "2", "--hop-s", "0.2"];
    let cases: [(&str, Method, FeatureSet, &[&str]); 3] = [
        ("som", Method::Som, FeatureSet::Nakano, &window),
        ("knn", Method::Knn, FeatureSet::Both, &window),
        ("svm", Method::Svm, FeatureSet::Spectral, &["--c", "10"]),
    ];
    for (method, library_method, features, options) in cases {
        let model = dir.path().join(format!("{method}.json"));
        let mut options = options.to_vec();
        // The library's documented defaults, not a search's choice among them.
        options.extend(["--features", features.name(), "--search-budget-s", "0"]);
        let (_, from_cli) = train_cli(method, &options, &model, &train_s);
        let settings = TrainSettings {
            features,
            window_s: 2.0,
            train_window_s: (features != FeatureSet::Spectral).then_some(2.0),
            hop_s: 0.2,
            c: recognize::SvmC::Fixed(10.0),
            ..TrainSettings::new(library_method)
        };
        let reference = recognize::train(&whole_train, &settings).expect("library trains");
        assert_eq!(from_cli, reference, "{method} over {features}");

        let model_s = model.to_string_lossy().into_owned();
        let mut argv = vec!["recognize", "eval", "--json", &model_s];
        argv.extend(test_s.iter().map(String::as_str));
        let shown: serde_json::Value =
            serde_json::from_slice(&succeeds(&argv).stdout).expect("eval prints JSON");
        let expected = reference.evaluate(&whole_test, None).expect("library evaluates");
        assert_eq!(
            shown["confusion"],
            serde_json::json!(expected.confusion.counts()),
            "{method}"
        );
        assert_eq!(
            shown["flips_per_s"],
            serde_json::json!(expected.flips_per_s),
            "{method}"
        );
        assert_eq!(
            shown["time_to_first_correct_s"],
            serde_json::json!(expected.time_to_first_correct_s),
            "{method}"
        );
        assert!(expected.confusion.total() > 0, "{method}");
    }

    // cv trains and decides on kept features too: the pooled confusion of a train-on-one split
    // is the library's on whole captures.
    let all: Vec<PathBuf> = train_paths.iter().chain(&test_paths).cloned().collect();
    let mut argv = vec![
        "recognize",
        "cv",
        "--json",
        "--method",
        "knn",
        "--split",
        "train-on-one",
    ];
    argv.extend(["--features", "both", "--window-s", "2", "--hop-s", "0.2"]);
    let all_s = strings(&all);
    argv.extend(all_s.iter().map(String::as_str));
    let shown: serde_json::Value = serde_json::from_slice(&succeeds(&argv).stdout).expect("cv prints JSON");
    let settings = TrainSettings {
        features: FeatureSet::Both,
        window_s: 2.0,
        hop_s: 0.2,
        ..TrainSettings::new(Method::Knn)
    };
    let whole = read_all(&all);
    let split = recognize::Split::TrainOnOne {
        folds: recognize::protocol::recordings(&whole),
    };
    let expected = recognize::protocol::run(&whole, split, 1, None, |train, _| {
        recognize::train(train, &settings).map_err(Box::new)
    })
    .expect("library cross-validates");
    assert_eq!(
        shown["confusion"],
        serde_json::json!(expected.evaluation.confusion.counts())
    );
}

#[test]
fn training_warns_of_a_class_with_few_vectors_and_the_map_size_is_nodes() {
    let dir = tempfile::tempdir().expect("tempdir");
    let mut paths = write_surfaces(dir.path(), 0..1);
    // 1 s windows (decided on and so trained on): the 4 s captures have room for several.
    let one_s = ["--window-s", "1"];
    let (_, plain) = train_cli("som", &one_s, &dir.path().join("plain.json"), &strings(&paths));
    assert_eq!(plain.classes.len(), 3);
    // 2.5 s of cork: its 1 s training windows start after 1 s of travel and end 0.27 s before
    // the capture does, so only two fit.
    paths.push(write_rub(dir.path(), "cork", 10e-6, 70.0, 0, 2.5));
    let model = dir.path().join("som.json");
    let (warned, _) = train_cli("som", &one_s, &model, &strings(&paths));
    assert!(
        warned.contains("warning: class cork has 2 training vectors")
            && warned.contains("training vector")
            && warned.contains("(fewer than 5)"),
        "{warned}"
    );
    assert!(!warned.contains("class fine has"), "{warned}");

    // --nodes and its old name --som-nodes size the map; two nodes cannot name four classes.
    for option in ["--nodes", "--som-nodes"] {
        let (warned, file) = train_cli(
            "som",
            &[option, "2", one_s[0], one_s[1]],
            &model,
            &strings(&paths),
        );
        let recognize::RecognizerBody::Som { som, .. } = &file.body else {
            panic!("not a SOM");
        };
        assert_eq!(som.node_labels().len(), 2, "{option}");
        assert!(
            warned.contains("of 4 classes own no node of the map (2 nodes)")
                && warned.contains("more nodes (--nodes) may help"),
            "{option}: {warned}"
        );
    }
    let model_s = model.to_string_lossy().into_owned();
    let shown = fails(&[
        "recognize",
        "train",
        "--method",
        "som",
        "--nodes",
        "0",
        "--out",
        &model_s,
    ]);
    assert!(shown.contains("--nodes"), "{shown}");
}
