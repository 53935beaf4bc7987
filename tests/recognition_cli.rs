//! `palpus recognize train` and `eval` end to end: Nakano's SOM on `palpus gen` rubbing
//! captures (train on run 0, evaluate on runs 1 and 2), Sinapov's k-NN and SVM on scratch captures
//! written through the library, and the errors a user meets with a bad model or capture.

mod common;

use std::path::{Path, PathBuf};

use common::{palpus, text};
use haptics::sim::protocols::sinapov::scratch_capture;
use haptics::sim::world::scratch::{Behaviour, household_surfaces};
use serde_json::Value;

fn nakano_runs(dir: &Path) -> (Vec<PathBuf>, Vec<PathBuf>) {
    let out = palpus(&[
        "gen",
        "--out",
        &dir.to_string_lossy(),
        "--only",
        "nakano",
        "--quiet",
    ]);
    assert!(out.status.success(), "{}", text(&out));
    let mut paths: Vec<PathBuf> = std::fs::read_dir(dir.join("nakano"))
        .expect("nakano folder")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "csv"))
        .collect();
    paths.sort();
    assert_eq!(paths.len(), 21);
    paths
        .into_iter()
        .partition(|p| p.to_string_lossy().ends_with("run0.csv"))
}

fn args<'a>(head: &[&'a str], paths: &'a [String]) -> Vec<&'a str> {
    head.iter()
        .copied()
        .chain(paths.iter().map(String::as_str))
        .collect()
}

fn strings(paths: &[PathBuf]) -> Vec<String> {
    paths.iter().map(|p| p.to_string_lossy().into_owned()).collect()
}

#[test]
fn som_train_and_eval_on_generated_rubbing_runs() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (train, test) = nakano_runs(dir.path());
    let model = dir.path().join("som.json");
    let model_s = model.to_string_lossy().into_owned();
    let train_s = strings(&train);
    let out = palpus(&args(
        &["recognize", "train", "--method", "som", "--out", &model_s],
        &train_s,
    ));
    assert!(out.status.success(), "{}", text(&out));
    assert!(text(&out).contains("7 classes"), "{}", text(&out));

    // The file describes itself: method, classes, windowing, the map's scaling, hashes.
    let file: Value = serde_json::from_slice(&std::fs::read(&model).expect("model")).expect("json");
    assert_eq!(file["format"], "palpus-recognizer");
    assert_eq!(file["body"]["method"], "som");
    assert_eq!(file["classes"].as_array().expect("classes").len(), 7);
    assert_eq!(file["body"]["windowing"]["window_samples"], 1000);
    assert_eq!(
        file["body"]["som"]["reference"].as_array().expect("nodes").len(),
        12
    );
    assert_eq!(file["training"].as_array().expect("captures").len(), 7);
    assert_eq!(file["training_sha256"].as_str().expect("hash").len(), 64);

    let test_s = strings(&test);
    let out = palpus(&args(&["recognize", "eval", &model_s, "--json"], &test_s));
    assert!(out.status.success(), "{}", text(&out));
    let report: Value = serde_json::from_slice(&out.stdout).expect("json report");
    assert_eq!(report["method"], "som");
    assert_eq!(report["window_s"], 1.0);
    assert!((report["decision_latency_s"].as_f64().expect("latency") - 1.27).abs() < 1e-12);
    let accuracy = report["accuracy"].as_f64().expect("accuracy");
    // One map (seed 0) of the 10 the protocol test pools at 85 %.
    assert!(accuracy >= 0.75, "{report}");
    let per_class = report["per_class"].as_object().expect("per class");
    assert_eq!(per_class.len(), 7);
    let confusion = report["confusion"].as_array().expect("confusion");
    let total: u64 = confusion
        .iter()
        .flat_map(|r| r.as_array().expect("row"))
        .map(|c| c.as_u64().expect("count"))
        .sum();
    let diagonal: u64 = (0..7).map(|i| confusion[i][i].as_u64().expect("count")).sum();
    assert!((diagonal as f64 / total as f64 - accuracy).abs() < 1e-12);
    // 14 test runs of 6100 samples; 5 mm of travel is reached at 1.1 s (after the 0.2 s ramp),
    // so windows start at 1170, 1270, … 4770 (the last that ends 270 samples before the end).
    assert_eq!(total, 14 * 37, "{report}");
    let first = report["time_to_first_correct_s"].as_f64().expect("first correct");
    assert!((2.0..4.0).contains(&first), "{report}");
    assert!(report["flips_per_s"].as_f64().expect("flips") >= 0.0);

    // Text output, and a shorter window on the same map.
    let out = palpus(&args(
        &["recognize", "eval", &model_s, "--window-s", "0.5"],
        &test_s,
    ));
    assert!(out.status.success(), "{}", text(&out));
    let shown = text(&out);
    assert!(
        shown.contains("window 0.500 s, decision latency 0.770 s"),
        "{shown}"
    );
    assert!(
        shown.contains("accuracy") && shown.contains("sandpaper_80"),
        "{shown}"
    );

    // Plots, into a folder that does not exist yet.
    let plots = dir.path().join("plots").join("som");
    let plots_s = plots.to_string_lossy().into_owned();
    let out = palpus(&args(
        &["recognize", "eval", &model_s, "--plots", &plots_s],
        &test_s,
    ));
    assert!(out.status.success(), "{}", text(&out));
    let (nodes, classes) = (12, 7);
    for (name, size) in [
        (
            "confusion.png",
            palpus::recognition_plots::confusion_size(classes),
        ),
        ("som_map.png", palpus::recognition_plots::som_map_size(nodes)),
        (
            "som_density.png",
            palpus::recognition_plots::som_density_size(classes, nodes),
        ),
    ] {
        let path = plots.join(name);
        assert!(text(&out).contains(&path.display().to_string()), "{}", text(&out));
        let image = render::Image::load_png(&path).expect("a PNG");
        assert_eq!((image.width, image.height), size, "{name}");
        // Drawn, not blank: the cells, bars and antialiased text give many distinct colours.
        let colours = image
            .rgba
            .chunks(4)
            .map(|p| (p[0], p[1], p[2]))
            .collect::<std::collections::HashSet<_>>()
            .len();
        assert!(colours > 20, "{name}: {colours} colours");
    }

    // A model from a newer version is refused, naming the file and the field.
    let mut newer = file.clone();
    newer["version"] = 99.into();
    let bad = dir.path().join("newer.json");
    std::fs::write(&bad, newer.to_string()).expect("write");
    let out = palpus(&args(
        &["recognize", "eval", &bad.to_string_lossy(), "--json"],
        &test_s,
    ));
    assert!(!out.status.success());
    assert!(
        text(&out).contains("newer.json: field `version`: 99 is not supported"),
        "{}",
        text(&out)
    );

    // A capture without a surface label cannot be evaluated.
    let capture = std::fs::read_to_string(&test[0]).expect("capture");
    let unlabelled = dir.path().join("unlabelled.csv");
    std::fs::write(&unlabelled, capture.replacen(" surface=", " material=", 1)).expect("write");
    let out = palpus(&["recognize", "eval", &model_s, &unlabelled.to_string_lossy()]);
    assert!(!out.status.success());
    assert!(
        text(&out).contains("unlabelled.csv: metadata has no `surface`"),
        "{}",
        text(&out)
    );
}

#[test]
fn knn_and_svm_train_and_eval_on_scratch_captures() {
    let dir = tempfile::tempdir().expect("tempdir");
    let surfaces = household_surfaces();
    let behaviour = Behaviour::ALL[0];
    // Four surfaces, trials 0-6 to train and 7-9 to test, one behaviour.
    let (mut train, mut test) = (Vec::new(), Vec::new());
    for surface in surfaces.iter().take(4) {
        for trial in 0..10 {
            let capture = scratch_capture(surface, behaviour, trial, 1).expect("capture");
            let path = dir.path().join(format!("{}_{trial}.csv", surface.name));
            capture.write_file(&path).expect("write");
            if trial < 7 { &mut train } else { &mut test }.push(path);
        }
    }
    let test_s = strings(&test);
    for method in ["knn", "svm"] {
        let model = dir.path().join(format!("{method}.json"));
        let model_s = model.to_string_lossy().into_owned();
        let out = palpus(&args(
            &["recognize", "train", "--method", method, "--out", &model_s],
            &strings(&train),
        ));
        assert!(out.status.success(), "{}", text(&out));
        let out = palpus(&args(&["recognize", "eval", &model_s, "--json"], &test_s));
        assert!(out.status.success(), "{}", text(&out));
        let report: Value = serde_json::from_slice(&out.stdout).expect("json report");
        assert_eq!(report["method"], method);
        assert_eq!(report["captures"], 12);
        let accuracy = report["accuracy"].as_f64().expect("accuracy");
        assert!(accuracy >= 0.75, "{method}: {report}");
        // One decision per scratch, made when it ends.
        assert_eq!(report["window_s"], report["decision_latency_s"]);
        assert!(report["window_s"].as_f64().expect("window") > 1.0, "{report}");
    }
}
