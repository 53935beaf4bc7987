//! `palpus recognize train` and `eval` end to end: Nakano's SOM on `palpus gen` rubbing
//! captures (train on run 0, evaluate on runs 1 and 2), Sinapov's k-NN and SVM on scratch captures
//! written through the library, and the errors a user meets with a bad model or capture.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use crate::common::{self, fails, json, nakano_captures, succeeds, text};
use capture::kind::{FRICTION_FORCE_N, NORMAL_FORCE_N, NORMAL_POSITION_M, TANGENTIAL_POSITION_M, TIME_S};
use serde_json::Value;
use sim::sinapov::scratch_capture;
use sim::{Behaviour, household_surfaces};

fn nakano_runs(dir: &Path) -> (Vec<PathBuf>, Vec<PathBuf>) {
    succeeds(&[
        "gen",
        "--out",
        &dir.to_string_lossy(),
        "--only",
        "nakano",
        "--quiet",
    ]);
    nakano_captures(dir)
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

/// A JSON file: a recognizer or a categories tree.
fn read_json(path: &Path) -> Value {
    serde_json::from_slice(&std::fs::read(path).expect("file")).expect("json")
}

/// `recognize train --method METHOD OPTIONS… --out MODEL`, the captures to follow.
fn train_head<'a>(method: &'a str, options: &[&'a str], model: &'a str) -> Vec<&'a str> {
    ["recognize", "train", "--method", method]
        .into_iter()
        .chain(options.iter().copied())
        .chain(["--out", model])
        .collect()
}

/// Trains a `method` recognizer on `captures` into `model`, which must succeed: what it printed,
/// and the file it wrote.
fn train_model(method: &str, options: &[&str], model: &Path, captures: &[String]) -> (String, Value) {
    let out = succeeds(&args(
        &train_head(method, options, &model.to_string_lossy()),
        captures,
    ));
    (text(&out), read_json(model))
}

#[test]
fn som_train_and_eval_on_generated_rubbing_runs() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (train, test) = nakano_runs(dir.path());
    let model = dir.path().join("som.json");
    let model_s = model.to_string_lossy().into_owned();
    // The thesis's protocol: one 6 s run per surface trains on 1 s windows (259 of them; 3 s
    // windows, the default, leave 119).
    let (summary, file) = train_model("som", &["--train-window-s", "1"], &model, &strings(&train));
    assert!(summary.contains("7 classes"), "{summary}");

    // The file describes itself: method, classes, windowing, the map's scaling, hashes.
    assert_eq!(file["format"], "palpus-recognizer");
    assert_eq!(file["body"]["method"], "som");
    assert_eq!(file["classes"].as_array().expect("classes").len(), 7);
    // Trained on 1 s windows, deciding on 3 s ones.
    assert_eq!(file["body"]["windowing"]["window_samples"], 3000);
    assert_eq!(file["body"]["windowing"]["training_window_samples"], 1000);
    assert_eq!(file["body"]["som"]["scaling"]["normalization"], "LogWithinClass");
    assert_eq!(
        file["body"]["som"]["reference"].as_array().expect("nodes").len(),
        12
    );
    assert_eq!(file["training"].as_array().expect("captures").len(), 7);
    assert_eq!(file["training_sha256"].as_str().expect("hash").len(), 64);

    let test_s = strings(&test);
    let report = eval_json(&model_s, &test_s, &[]);
    assert_eq!(report["method"], "som");
    assert_eq!(report["window_s"], 3.0);
    assert!((report["decision_latency_s"].as_f64().expect("latency") - 3.27).abs() < 1e-12);
    let accuracy = report["accuracy"].as_f64().expect("accuracy");
    // One map (seed 0) of the 10 the protocol test pools at 99.7 %, worst surface 98.9 %.
    assert!(accuracy >= 0.95, "{report}");
    let per_class = report["per_class"].as_object().expect("per class");
    assert_eq!(per_class.len(), 7);
    for (surface, rate) in per_class {
        assert!(rate.as_f64().expect("rate") >= 0.9, "{surface}: {report}");
    }
    let confusion = report["confusion"].as_array().expect("confusion");
    let total = decisions(confusion);
    let diagonal: u64 = (0..7).map(|i| confusion[i][i].as_u64().expect("count")).sum();
    assert!((diagonal as f64 / total as f64 - accuracy).abs() < 1e-12);
    // 14 test runs of 6100 samples; 5 mm of travel is reached at 1.1 s (after the 0.2 s ramp),
    // so windows start at 1170, 1270, … 2770 (the last that ends 270 samples before the end).
    assert_eq!(total, 14 * 17, "{report}");
    // The first decision comes at 1.17 s + 3 s + 0.27 s; it is right.
    let first = report["time_to_first_correct_s"].as_f64().expect("first correct");
    assert!((4.4..4.5).contains(&first), "{report}");
    assert_flips_agree(&report);
    // The map's fit to the held-out windows.
    let qe = report["quantization_error"].as_f64().expect("quantization error");
    let te = report["topographic_error"].as_f64().expect("topographic error");
    assert!(qe > 0.0 && qe < 0.5, "{report}");
    assert!((0.0..0.1).contains(&te), "{report}");

    // Accuracy against window length: one row per window, the latency the window plus 0.27 s.
    let table = eval_json(&model_s, &test_s, &["--window-s", "0.5,1,2,3"]);
    let rows = table["windows"].as_array().expect("rows");
    assert_eq!(rows.len(), 4);
    for (row, window_s) in rows.iter().zip([0.5, 1.0, 2.0, 3.0]) {
        assert_eq!(row["window_s"], window_s);
        let latency = row["decision_latency_s"].as_f64().expect("latency");
        assert!((latency - window_s - 0.27).abs() < 1e-12, "{row}");
    }
    let acc = |i: usize| rows[i]["accuracy"].as_f64().expect("accuracy");
    assert_eq!(acc(3), accuracy);
    assert!(acc(3) > acc(0) + 0.05, "{table}");
    let shown = text(&succeeds(&args(
        &["recognize", "eval", &model_s, "--window-s", "0.5,3"],
        &test_s,
    )));
    assert!(shown.contains("accuracy against decision window"), "{shown}");
    assert!(
        shown.contains("   0.50 s    0.77 s") && shown.contains("   3.00 s    3.27 s"),
        "{shown}"
    );

    // Nakano's protocol over all three runs: each run trains in turn and the other two are
    // held out, three maps per fold, every decision pooled.
    let all_s = strings(&[train.clone(), test.clone()].concat());
    let train_on_one = |options: &[&'static str]| -> Vec<&'static str> {
        // The thesis's 1 s training windows.
        [
            "recognize",
            "cv",
            "--method",
            "som",
            "--split",
            "train-on-one",
            "--train-window-s",
            "1",
        ]
        .into_iter()
        .chain(options.iter().copied())
        .collect()
    };
    let cv = json(&args(&train_on_one(&["--seeds", "3", "--json"]), &all_s));
    assert_eq!(cv["split"], "train-on-one");
    assert_eq!(cv["folds"], 3);
    assert_eq!(cv["rounds"], 9);
    assert_eq!(cv["captures"], 9 * 14);
    let total = decisions(cv["confusion"].as_array().expect("confusion"));
    assert_eq!(total, 9 * 14 * 17);
    eprintln!(
        "som train-on-one x 3 seeds: {:.4}, worst {:.4}",
        cv["accuracy"].as_f64().expect("accuracy"),
        worst_class(&cv)
    );
    // Measured: 96.1 %, worst surface 80.4 % (sandpaper #120, taken for #80 by the maps
    // trained on runs 1 and 2: twelve nodes for seven surfaces leave those two without a
    // boundary on some maps; k-NN on the same windows keeps #120 at 100 %).
    assert!(cv["accuracy"].as_f64().expect("accuracy") >= 0.94, "{cv}");
    assert!(worst_class(&cv) >= 0.75, "{cv}");
    assert_eq!(cv["fused_by_count"].as_array().map(Vec::len), Some(0));
    // Nakano's own protocol: the first run trains, the other two test, maps pooled.
    let thesis = json(&args(
        &train_on_one(&["--fold", "1", "--seeds", "3", "--json"]),
        &all_s,
    ));
    assert_eq!(
        (thesis["rounds"].as_u64(), thesis["fold"].as_u64()),
        (Some(3), Some(1))
    );
    assert_eq!(thesis["captures"], 3 * 14);
    assert!(thesis["accuracy"].as_f64().expect("accuracy") >= 0.95, "{thesis}");
    assert!(worst_class(&thesis) >= 0.95, "{thesis}");
    fails_with(
        &args(&train_on_one(&["--fold", "4"]), &all_s),
        &["fold 4 asked for, but there are 3 folds"],
    );
    // A SOM's seeds matter; a k-NN's do not.
    fails_with(
        &args(&["recognize", "cv", "--method", "knn", "--seeds", "2"], &all_s),
        &["--seeds 2 applies to som only"],
    );
    fails_with(
        &args(&["recognize", "cv", "--method", "som", "--folds", "4"], &all_s),
        &["3 recordings", "into 4 folds"],
    );

    // Text output, and a shorter window on the same map.
    let shown = text(&succeeds(&args(
        &["recognize", "eval", &model_s, "--window-s", "0.5"],
        &test_s,
    )));
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
    let out = succeeds(&args(
        &["recognize", "eval", &model_s, "--plots", &plots_s],
        &test_s,
    ));
    let (nodes, classes) = (12, 7);
    for (name, size) in [
        ("confusion.png", palpus::plots::confusion_size(classes)),
        ("som_map.png", palpus::plots::som_map_size(nodes)),
        ("som_components.png", palpus::plots::som_components_size(5, nodes)),
        ("som_density.png", palpus::plots::som_density_size(classes, nodes)),
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
    fails_with(
        &args(&["recognize", "eval", &bad.to_string_lossy(), "--json"], &test_s),
        &["newer.json: field `version`: 99 is not supported"],
    );

    // A capture without a surface label cannot be evaluated.
    let capture = std::fs::read_to_string(&test[0]).expect("capture");
    let unlabelled = dir.path().join("unlabelled.csv");
    std::fs::write(&unlabelled, capture.replacen(" surface=", " material=", 1)).expect("write");
    fails_with(
        &["recognize", "eval", &model_s, &unlabelled.to_string_lossy()],
        &["unlabelled.csv: metadata has no `surface`"],
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
        train_model(method, &[], &model, &strings(&train));
        let report = eval_json(&model.to_string_lossy(), &test_s, &[]);
        assert_eq!(report["method"], method);
        assert_eq!(report["captures"], 12);
        let accuracy = report["accuracy"].as_f64().expect("accuracy");
        assert!(accuracy >= 0.75, "{method}: {report}");
        // One decision per scratch, made when it ends.
        assert_eq!(report["window_s"], report["decision_latency_s"]);
        assert!(report["window_s"].as_f64().expect("window") > 1.0, "{report}");
        // One behaviour: each (surface, trial) is one scratch, "fused" alone, which must
        // decide exactly as the scratch alone.
        assert_eq!(report["fused"]["groups"], 12, "{report}");
        assert_eq!(report["fused"]["multi_scratch_groups"], 0, "{report}");
        assert_eq!(report["fused"]["confusion"], report["confusion"], "{report}");
        assert_eq!(report["fused"]["accuracy"], report["accuracy"], "{report}");
    }
}

/// Trial number of a `palpus gen --only sinapov` capture, from its name `<behaviour>_tNN.csv`.
fn trial_of(path: &Path) -> u32 {
    let stem = path.file_stem().expect("name").to_string_lossy();
    stem.rsplit_once("_t")
        .and_then(|(_, t)| t.parse().ok())
        .expect("a trial number in the name")
}

/// `palpus gen --only sinapov`: every scratch capture, sorted. Generated once per test run
/// (two tests read the same 1,050 captures, 6 s of generation each), afresh, in cargo's
/// scratch folder for integration tests; no test writes into it.
fn generated_scratches() -> Vec<PathBuf> {
    static SCRATCHES: OnceLock<Vec<PathBuf>> = OnceLock::new();
    SCRATCHES
        .get_or_init(|| {
            let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("recognition_cli_sinapov");
            // A folder left by an earlier run may hold another version's captures.
            let _ = std::fs::remove_dir_all(&dir);
            succeeds(&[
                "gen",
                "--out",
                &dir.to_string_lossy(),
                "--only",
                "sinapov",
                "--quiet",
            ]);
            let mut paths = Vec::new();
            for surface in std::fs::read_dir(dir.join("sinapov")).expect("sinapov folder") {
                for capture in std::fs::read_dir(surface.expect("entry").path()).expect("surface folder") {
                    paths.push(capture.expect("entry").path());
                }
            }
            paths.sort();
            paths
        })
        .clone()
}

/// Sinapov's split of generated scratches: trials 0–6 train, 7–9 test.
fn sinapov_split(paths: Vec<PathBuf>) -> (Vec<String>, Vec<String>) {
    let (train, test): (Vec<PathBuf>, Vec<PathBuf>) = paths.into_iter().partition(|p| trial_of(p) < 7);
    (strings(&train), strings(&test))
}

/// Sinapov's protocol through the CLI on `palpus gen --only sinapov` (21 surfaces × 5
/// behaviours × 10 trials): train on trials 0–6, evaluate on 7–9. Each behaviour's stored
/// weight is its cross-validated accuracy on the training trials, the SVM's C is picked by the
/// same cross-validation, and fusing the five behaviours of a trial beats every behaviour alone
/// (k-NN) or equals the best one (SVM). About 10 s in release on two cores.
#[test]
fn knn_and_svm_fuse_behaviours_of_generated_scratch_trials() {
    let start = std::time::Instant::now();
    let dir = tempfile::tempdir().expect("tempdir");
    let paths = generated_scratches();
    assert_eq!(paths.len(), 21 * 5 * 10);
    let (train_s, test_s) = sinapov_split(paths);
    let grid = [1.0, 10.0, 100.0, 1e3, 1e4, 1e5];
    for method in ["knn", "svm"] {
        let model = dir.path().join(format!("{method}.json"));
        let model_s = model.to_string_lossy().into_owned();
        let (summary, file) = train_model(method, &[], &model, &train_s);
        assert!(
            summary.contains("reliability weights") && summary.contains("lateral_slow"),
            "{summary}"
        );

        // Each behaviour's weight: a 5-fold (7 trials) cross-validated accuracy on training.
        let behaviours = file["body"]["behaviours"].as_array().expect("behaviours");
        assert_eq!(behaviours.len(), 5);
        for b in behaviours {
            let w = b["reliability"].as_f64().expect("a stored weight");
            assert!(w > 0.0 && w <= 1.0, "{b}");
            // 147 held-out scratches (21 surfaces × 7 trials): an integer count of them.
            assert!(((w * 147.0).round() - w * 147.0).abs() < 1e-9, "{w}");
            if method == "knn" {
                assert_eq!(b["reliability_folds"], 5);
                continue;
            }
            // The SVM's C: the best of the grid under the same cross-validation, ties to the
            // smaller C; its accuracy is the weight.
            let search = &b["c_search"];
            assert_eq!(search["folds"], 5);
            let tried: Vec<(f64, f64)> = search["grid"]
                .as_array()
                .expect("grid")
                .iter()
                .map(|p| {
                    (
                        p["c"].as_f64().expect("c"),
                        p["accuracy"].as_f64().expect("accuracy"),
                    )
                })
                .collect();
            assert_eq!(tried.iter().map(|p| p.0).collect::<Vec<_>>(), grid);
            let chosen = search["chosen_c"].as_f64().expect("chosen C");
            let best = tried.iter().fold(tried[0], |b, p| if p.1 > b.1 { *p } else { b });
            assert_eq!((chosen, w), best, "{search}");
            assert!(grid.contains(&chosen));
            assert_eq!(b["svc"]["params"]["c"].as_f64(), Some(chosen));
        }

        let report = eval_json(&model_s, &test_s, &[]);
        for key in [
            "method",
            "accuracy",
            "per_class",
            "classes",
            "confusion",
            "window_s",
            "decision_latency_s",
            "captures",
        ] {
            assert!(report.get(key).is_some(), "{key}: {report}");
        }
        assert_eq!(report["method"], method);
        assert_eq!(report["captures"], 315);
        let fused = &report["fused"];
        assert_eq!(fused["groups"], 63, "21 surfaces × trials 7–9");
        assert_eq!(fused["multi_scratch_groups"], 63);
        assert_eq!(fused["per_class"].as_object().expect("per class").len(), 21);
        let confusion = fused["confusion"].as_array().expect("confusion");
        let total = decisions(confusion);
        let diagonal: u64 = (0..21).map(|i| confusion[i][i].as_u64().expect("count")).sum();
        let accuracy = fused["accuracy"].as_f64().expect("fused accuracy");
        assert_eq!(total, 63);
        assert!((diagonal as f64 / 63.0 - accuracy).abs() < 1e-12);
        // Each behaviour alone: 63 scratches; together they are the per-scratch report.
        let per_behaviour = fused["per_behaviour"].as_object().expect("per behaviour");
        assert_eq!(per_behaviour.len(), 5);
        let mut right = 0.0;
        let mut single = Vec::new();
        for (name, b) in per_behaviour {
            assert_eq!(b["scratches"], 63, "{name}");
            let a = b["accuracy"].as_f64().expect("accuracy");
            right += a * 63.0;
            single.push(a);
            let stored = behaviours
                .iter()
                .find(|s| s["behaviour"] == name.as_str())
                .expect("a trained behaviour");
            assert_eq!(b["weight"], stored["reliability"], "{name}");
        }
        let scratch_accuracy = report["accuracy"].as_f64().expect("accuracy");
        assert!((right / 315.0 - scratch_accuracy).abs() < 1e-9, "{report}");
        let best = single.iter().copied().fold(0.0, f64::max);
        let mean = single.iter().sum::<f64>() / 5.0;
        assert_eq!(fused["best_single_accuracy"].as_f64(), Some(best));
        eprintln!(
            "{method}: behaviours alone {single:.3?}, per scratch {scratch_accuracy:.3}, fused {accuracy:.3}"
        );
        // Measured: k-NN alone 90.5–95.2 %, fused 100 %; SVM alone 92.1–98.4 %, fused 98.4 %
        // (the one trial it misses, a soft cloth taken for cotton wool, is also the one the best
        // behaviour misses).
        if method == "knn" {
            assert!(accuracy > best, "fused {accuracy} vs best single {best}");
        } else {
            assert!(accuracy >= best, "fused {accuracy} vs best single {best}");
        }
        assert!(
            accuracy > mean + 0.03 && accuracy >= 0.98,
            "fused {accuracy}, mean single {mean}"
        );

        // Text: the per-scratch matrix, then each behaviour alone and the fused matrix.
        let shown = text(&succeeds(&args(&["recognize", "eval", &model_s], &test_s)));
        let fused_at = shown
            .find("fused over behaviours: 63 trials")
            .expect("a fused section");
        assert!(shown[..fused_at].contains("each behaviour alone"), "{shown}");
        assert!(
            shown[fused_at..].contains("accuracy") && shown[fused_at..].contains("wood"),
            "{shown}"
        );

        // A recognizer written before weights were stored still evaluates: equal weights.
        let mut old = file.clone();
        for b in old["body"]["behaviours"].as_array_mut().expect("behaviours") {
            let b = b.as_object_mut().expect("behaviour");
            for key in ["reliability", "reliability_folds", "c_search"] {
                b.remove(key);
            }
        }
        let old_path = dir.path().join(format!("{method}_old.json"));
        std::fs::write(&old_path, old.to_string()).expect("write");
        let report = eval_json(&old_path.to_string_lossy(), &test_s, &[]);
        assert!(
            report["fused"]["per_behaviour"]
                .as_object()
                .expect("per behaviour")
                .values()
                .all(|b| b["weight"] == 1.0),
            "{report}"
        );
        assert_eq!(report["accuracy"].as_f64(), Some(scratch_accuracy));

        // A weight that is not an accuracy is refused, naming the field.
        let mut bad = file.clone();
        bad["body"]["behaviours"][2]["reliability"] = 1.5.into();
        let bad_path = dir.path().join(format!("{method}_bad.json"));
        std::fs::write(&bad_path, bad.to_string()).expect("write");
        fails_with(
            &args(&["recognize", "eval", &bad_path.to_string_lossy()], &test_s),
            &["field `body.behaviours[2].reliability`: 1.5 is not an accuracy in [0, 1]"],
        );
    }

    // Sinapov's protocol itself: 10-fold cross-validation by trial over all 1050 scratches,
    // each behaviour alone (Table II) and every combination of behaviours fused (Fig. 6).
    let all_s = [train_s.clone(), test_s.clone()].concat();
    let cv = json(&args(&["recognize", "cv", "--method", "knn", "--json"], &all_s));
    assert_eq!(cv["split"], "k-fold");
    assert_eq!(
        (cv["folds"].as_u64(), cv["rounds"].as_u64()),
        (Some(10), Some(10))
    );
    assert_eq!(cv["captures"], 1050, "every scratch held out once");
    let singles: Vec<f64> = cv["per_behaviour"]
        .as_object()
        .expect("per behaviour")
        .values()
        .map(|b| {
            assert_eq!(b["scratches"], 210);
            b["accuracy"].as_f64().expect("accuracy")
        })
        .collect();
    assert_eq!(singles.len(), 5);
    let by_count = cv["fused_by_count"].as_array().expect("by count");
    let combinations: Vec<u64> = by_count
        .iter()
        .map(|c| c["combinations"].as_u64().expect("n"))
        .collect();
    assert_eq!(combinations, [5, 10, 10, 5, 1]);
    let mean: Vec<f64> = by_count
        .iter()
        .map(|c| c["mean_accuracy"].as_f64().expect("mean"))
        .collect();
    let fused_all = cv["fused"]["accuracy"].as_f64().expect("fused");
    let best_single = singles.iter().copied().fold(0.0, f64::max);
    eprintln!("knn 10-fold: singles {singles:.3?}, fused by count {mean:.3?}");
    assert_eq!(cv["fused"]["trials"], 210);
    assert!(fused_all > best_single, "{cv}");
    // More behaviours, better (Fig. 6); near saturation within one trial in 210.
    assert!(mean[1] > mean[0] + 0.01 && mean[2] > mean[1], "{mean:?}");
    assert!(
        mean[3] > mean[2] - 1.0 / 210.0 && mean[4] > mean[3] - 1.0 / 210.0,
        "{mean:?}"
    );

    // A whole-scratch recognizer has no window to change.
    let knn_s = dir.path().join("knn.json").to_string_lossy().into_owned();
    fails_with(
        &args(&["recognize", "eval", &knn_s, "--window-s", "1"], &test_s),
        &["decides on whole captures: --window-s does not apply"],
    );

    // Sinapov's categories: each surface left out of training in turn, so every one of its
    // 50 scratches is an error naming the known surface it resembles.
    let categories = dir.path().join("categories");
    let categories_s = categories.to_string_lossy().into_owned();
    succeeds(&args(
        &[
            "recognize",
            "categorize",
            "--leave-surface-out",
            "--method",
            "knn",
            "--out",
            &categories_s,
        ],
        &all_s,
    ));
    let tree = read_json(&categories.join("categories.json"));
    assert_eq!(tree["decisions"], 1050);
    assert_eq!(tree["accuracy"], 0.0, "a left-out surface can never be named");
    assert_eq!(tree["similarity"].as_array().map(Vec::len), Some(21));
    let leaves = leaves(&tree["tree"]);
    let together = |a: &str, b: &str| {
        leaves
            .iter()
            .any(|l| l.contains(&a.to_owned()) && l.contains(&b.to_owned()))
    };
    // Measured: 7 leaves, among them {air, paper_white, paper_yellow, table} and
    // {cotton_wool, soft_cloth}.
    assert!((4..=10).contains(&leaves.len()), "{leaves:?}");
    assert!(together("paper_white", "paper_yellow"), "{leaves:?}");
    assert!(together("cotton_wool", "soft_cloth"), "{leaves:?}");
    assert!(!together("paper_white", "cotton_wool"), "{leaves:?}");
    fails_with(
        &args(
            &[
                "recognize",
                "categorize",
                "--method",
                "knn",
                "--out",
                &categories_s,
            ],
            &all_s,
        ),
        &["--leave-surface-out"],
    );

    // A C given on the command line is used as it is, with its cross-validated accuracy.
    let model = dir.path().join("svm_c100.json");
    let model_s = model.to_string_lossy().into_owned();
    let (summary, file) = train_model("svm", &["--c", "100"], &model, &train_s);
    assert!(summary.contains("C = 1e2 (given)"), "{summary}");
    for b in file["body"]["behaviours"].as_array().expect("behaviours") {
        assert_eq!(b["c_search"]["chosen_c"], 100.0);
        assert_eq!(b["c_search"]["grid"].as_array().expect("grid").len(), 1);
        assert_eq!(b["reliability"], b["c_search"]["grid"][0]["accuracy"]);
    }
    fails_with(
        &args(&train_head("svm", &["--c", "0"], &model_s), &train_s),
        &["`0` is neither `auto` nor a positive number"],
    );
    eprintln!("{:.1} s", start.elapsed().as_secs_f64());
}

/// A researcher's logs read directly: other column names, units, delimiter and rate, laid out
/// as `SURFACE/RUN.csv`, trained and evaluated through `--map` without converting them.
#[test]
fn som_train_and_eval_on_foreign_logs_through_a_column_map() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (train, test) = nakano_runs(dir.path());
    let logs = dir.path().join("logs");
    // Each capture as a 2 kHz log (midpoints interpolated) in ms, mm, µm and mN, `;`-separated.
    let to_log = |path: &Path| -> PathBuf {
        let capture = capture::Capture::read_file(path, capture::CaptureKind::Rubbing).expect("capture");
        let surface = capture.metadata().get("surface").expect("surface").to_owned();
        let run = path.file_stem().expect("stem").to_string_lossy().into_owned();
        let col = |n: &str| capture.column(n).expect("column").to_vec();
        let (t, x, z, n, f) = (
            col("time_s"),
            col("tangential_position_m"),
            col("normal_position_m"),
            col("normal_force_n"),
            col("friction_force_n"),
        );
        let mut text =
            String::from("# exported by a lab logger\nt [ms];pos x [mm];height [um];Fn [mN];Ft [mN]\n");
        for i in 0..t.len() {
            let row = |k: f64| {
                let j = (i + 1).min(t.len() - 1);
                let at = |v: &[f64]| v[i] + k * (v[j] - v[i]);
                format!(
                    "{};{};{};{};{}\n",
                    at(&t) * 1e3,
                    at(&x) * 1e3,
                    at(&z) * 1e6,
                    at(&n) * 1e3,
                    at(&f) * 1e3
                )
            };
            text.push_str(&row(0.0));
            if i + 1 < t.len() {
                text.push_str(&row(0.5));
            }
        }
        let out = logs.join(&surface).join(format!("{run}.csv"));
        std::fs::create_dir_all(out.parent().expect("folder")).expect("mkdir");
        std::fs::write(&out, text).expect("log");
        out
    };
    let train_logs: Vec<String> = train
        .iter()
        .map(|p| to_log(p).to_string_lossy().into_owned())
        .collect();
    let test_logs: Vec<String> = test
        .iter()
        .map(|p| to_log(p).to_string_lossy().into_owned())
        .collect();
    let map = "time_s=t [ms][ms],tangential_position_m=pos x [mm][mm],normal_position_m=height [um][um],\
               normal_force_n=Fn [mN][mN],friction_force_n=Ft [mN][mN]";
    let model = dir.path().join("som.json");
    let model_s = model.to_string_lossy().into_owned();
    // Trained as the thesis trains (1 s windows), like the captures it is compared with.
    let mapped = ["--map", map, "--rate-hz", "1000", "--meta", "surface={dir}"];
    let training = [&mapped[..], &["--train-window-s", "1"]].concat();
    let (_, file) = train_model("som", &training, &model, &train_logs);
    assert!(
        file["classes"]
            .as_array()
            .expect("classes")
            .iter()
            .any(|c| c == "sandpaper_400"),
        "{}",
        file["classes"]
    );
    let report = eval_json(&model_s, &test_logs, &mapped);
    // Downsampled from 2 kHz through the anti-aliasing filter: the rubbing's roughness
    // (≤ 20 Hz at 5 mm/s) passes unchanged, so the recognizer does as well as on the captures.
    for (surface, rate) in report["per_class"].as_object().expect("per class") {
        assert!(rate.as_f64().expect("rate") >= 0.9, "{surface}: {report}");
    }
    assert!(report["accuracy"].as_f64().expect("accuracy") >= 0.95, "{report}");
    // Without the map the same files are not captures: a clear error naming one.
    fails_with(
        &args(&["recognize", "eval", &model_s], &test_logs[..1]),
        &[&test_logs[0]],
    );
}

/// Decisions in a JSON confusion matrix: the sum of its counts.
fn decisions(confusion: &[Value]) -> u64 {
    confusion
        .iter()
        .flat_map(|r| r.as_array().expect("row"))
        .map(|c| c.as_u64().expect("count"))
        .sum()
}

/// Runs palpus with `argv`, which must fail, printing each of `expected`.
fn fails_with(argv: &[&str], expected: &[&str]) {
    let shown = fails(argv);
    for e in expected {
        assert!(shown.contains(e), "{e}: {shown}");
    }
}

/// The leaf categories of a `categories.json` tree, each as its member names.
fn leaves(node: &Value) -> Vec<Vec<String>> {
    let children = node["children"].as_array().expect("children");
    if children.is_empty() {
        let members = node["members"].as_array().expect("members");
        return vec![
            members
                .iter()
                .map(|m| m.as_str().expect("name").to_owned())
                .collect(),
        ];
    }
    children.iter().flat_map(leaves).collect()
}

/// Flips and stability must agree with the accuracy: with every decision right nothing
/// flips and each capture is stable from its first decision; with some wrong and every capture
/// right at least once, some capture changed its mind.
fn assert_flips_agree(report: &Value) {
    let flips = report["flips_per_s"].as_f64().expect("flips");
    let accuracy = report["accuracy"].as_f64().expect("accuracy");
    if accuracy == 1.0 {
        assert_eq!(flips, 0.0, "{report}");
        assert_eq!(report["not_stable"], 0, "{report}");
        assert_eq!(
            report["time_to_stable_s"], report["time_to_first_correct_s"],
            "{report}"
        );
    } else if report["never_correct"] == 0 {
        assert!(flips > 0.0, "{report}");
    }
}

/// Runs `palpus recognize eval MODEL CAPTURES --json [EXTRA…]` and returns its report.
fn eval_json(model: &str, captures: &[String], extra: &[&str]) -> Value {
    let head: Vec<&str> = ["recognize", "eval", model, "--json"]
        .into_iter()
        .chain(extra.iter().copied())
        .collect();
    json(&args(&head, captures))
}

fn worst_class(report: &Value) -> f64 {
    report["per_class"]
        .as_object()
        .expect("per class")
        .values()
        .map(|r| r.as_f64().expect("rate"))
        .fold(1.0, f64::min)
}

/// k-NN and SVM over Nakano's windowed features (`--features nakano`), on the SOM's split:
/// trained on run 0, evaluated on runs 1–2, the SOM's windows (1 s to train, 3 s to decide,
/// every 0.1 s from 5 mm on). Measured: k-NN 99.6 % of 238 decisions (worst surface 97.1 %),
/// SVM (C = 10, not cross-validated with one run per surface) 96.6 % (worst 76.5 %); the SOM
/// 100 %. Also: the feature set is in the file, a file without it still loads, and features
/// the captures cannot give are a typed error naming the capture and the columns.
#[test]
fn knn_and_svm_over_nakano_windows_on_generated_rubbing_runs() {
    let start = std::time::Instant::now();
    let dir = tempfile::tempdir().expect("tempdir");
    let (train, test) = nakano_runs(dir.path());
    let (train_s, test_s) = (strings(&train), strings(&test));
    for (method, floor, worst_floor) in [("knn", 0.98, 0.95), ("svm", 0.93, 0.7)] {
        let model = dir.path().join(format!("{method}_nakano.json"));
        let model_s = model.to_string_lossy().into_owned();
        // The SOM's 1 s training windows, set apart from the 3 s decision windows (k-NN and
        // SVM would train on 3 s ones by default): training says so.
        let options = ["--features", "nakano", "--train-window-s", "1"];
        let out = succeeds(&args(&train_head(method, &options, &model_s), &train_s));
        let (summary, file) = (text(&out), read_json(&model));
        let warned = String::from_utf8_lossy(&out.stderr).into_owned();
        assert!(
            warned.contains("warning: training on 1 s windows but deciding on 3 s ones"),
            "{warned}"
        );
        assert!(summary.contains("over nakano features"), "{summary}");
        assert_eq!(file["features"], "nakano");
        assert_eq!(file["body"]["method"], format!("{method}_windows"));
        assert_eq!(file["body"]["features"], "nakano");
        assert_eq!(file["feature_names"].as_array().expect("names").len(), 5);
        assert_eq!(file["body"]["windowing"]["window_samples"], 3000);
        assert_eq!(file["body"]["windowing"]["training_window_samples"], 1000);
        assert_eq!(
            file["body"]["scaling"]["scale"].as_array().expect("scale").len(),
            5
        );
        // One training vector per 1 s window, as many as the SOM's.
        assert_eq!(file["n_train"], 259, "{}", file["n_train"]);

        let report = eval_json(&model_s, &test_s, &[]);
        assert_eq!(report["method"], method);
        assert_eq!(report["features"], "nakano");
        assert_eq!(report["window_s"], 3.0);
        assert!((report["decision_latency_s"].as_f64().expect("latency") - 3.27).abs() < 1e-12);
        assert_eq!(report["captures"], 14);
        assert!(report.get("fused").is_none(), "{report}");
        let confusion = report["confusion"].as_array().expect("confusion");
        let total = decisions(confusion);
        // The SOM's decision windows: 17 per test run.
        assert_eq!(total, 14 * 17, "{report}");
        let (accuracy, worst) = (
            report["accuracy"].as_f64().expect("accuracy"),
            worst_class(&report),
        );
        eprintln!("{method} --features nakano: {accuracy:.3}, worst surface {worst:.3}");
        assert!(accuracy >= floor, "{method}: {report}");
        assert!(worst >= worst_floor, "{method}: {report}");
        let first = report["time_to_first_correct_s"].as_f64().expect("first correct");
        assert!((4.4..4.6).contains(&first), "{report}");
        assert_flips_agree(&report);
        // A shorter decision window on the same classifier.
        let short = eval_json(&model_s, &test_s, &["--window-s", "1"]);
        assert_eq!(short["window_s"], 1.0);
        assert!((short["decision_latency_s"].as_f64().expect("latency") - 1.27).abs() < 1e-12);
        assert!(short["accuracy"].as_f64().expect("accuracy") >= 0.85, "{short}");
    }

    // A file written before `features` existed (the SOM's default) still loads.
    let som = dir.path().join("som.json");
    let som_s = som.to_string_lossy().into_owned();
    let (_, mut file) = train_model("som", &[], &som, &train_s);
    assert_eq!(file["features"], "nakano");
    file.as_object_mut().expect("object").remove("features");
    std::fs::write(&som, serde_json::to_vec(&file).expect("json")).expect("write");
    let report = eval_json(&som_s, &test_s[..2], &[]);
    assert_eq!(report["features"], "nakano");
    // A file whose feature set contradicts its body is refused, naming the field.
    file["features"] = "spectral".into();
    std::fs::write(&som, serde_json::to_vec(&file).expect("json")).expect("write");
    fails_with(
        &args(&["recognize", "eval", &som_s], &test_s[..1]),
        &["field `features`"],
    );

    // Rubbing captures have no accelerometer: no spectral features.
    let x_s = dir.path().join("x.json").to_string_lossy().into_owned();
    for method in ["knn", "som"] {
        let shown = fails(&args(
            &train_head(method, &["--features", "spectral"], &x_s),
            &train_s,
        ));
        assert!(
            shown.contains(&train_s[0])
                && shown.contains(
                    "`--features spectral` needs the columns accel_x_mps2, accel_y_mps2, accel_z_mps2"
                ),
            "{shown}"
        );
    }

    // Nakano's features followed by the height's spectrum: windows over travel whose bands
    // reach 25 mm/s, decided at their last sample, anytime.
    let spectrum = dir.path().join("svm_nakano_spectrum.json");
    let spectrum_s = spectrum.to_string_lossy().into_owned();
    let options = [
        "--features",
        "nakano-spectrum",
        "--window-s",
        "0.25",
        "--mirrored-end",
        "--windows-over-travel",
        "--fastest-speed-mps",
        "0.025",
    ];
    let (summary, file) = train_model("svm", &options, &spectrum, &train_s);
    assert!(summary.contains("over nakano_spectrum features"), "{summary}");
    assert_eq!(file["features"], "nakano_spectrum");
    assert_eq!(file["feature_names"].as_array().expect("names").len(), 30);
    assert_eq!(file["body"]["windowing"]["mirrored_end"], true);
    assert_eq!(file["body"]["windowing"]["travel"]["fastest_speed_mps"], 0.025);
    let report = eval_json(&spectrum_s, &test_s, &["--sequential", "0.9"]);
    let row = &report["rows"][0];
    let (right, named) = (
        row["correct"].as_u64().expect("right"),
        row["decided"].as_u64().expect("named"),
    );
    eprintln!("svm --features nakano-spectrum, anytime at 0.9: {right} of {named} named right");
    assert!(named > 0 && right as f64 >= 0.95 * named as f64, "{report}");
    fails_with(
        &args(
            &train_head(
                "knn",
                &["--features", "nakano-spectrum", "--fastest-speed-mps", "0.025"],
                &x_s,
            ),
            &train_s,
        ),
        &["--windows-over-travel"],
    );
    fails_with(
        &args(
            &train_head("som", &["--features", "nakano-spectrum"], &x_s),
            &train_s,
        ),
        &["trains a k-NN or an SVM"],
    );
    // Nakano's features alone read no spectrum: a fastest speed would go unread.
    let nakano_fast = options.map(|o| if o == "nakano-spectrum" { "nakano" } else { o });
    fails_with(
        &args(&train_head("svm", &nakano_fast, &x_s), &train_s),
        &["fastest_speed_mps", "only a spectrum reads it"],
    );
    eprintln!("took {:.1} s", start.elapsed().as_secs_f64());
}

/// One SOM per behaviour over whole-scratch histograms (`--features spectral`) on Sinapov's
/// split of `palpus gen --only sinapov` (trials 0–6 to train, 7–9 to evaluate). Measured:
/// 90.8 % of 315 scratches alone, 96.8 % of 63 trials fused (k-NN: 100 %, SVM 98.4 %).
#[test]
fn som_over_spectral_histograms_of_generated_scratch_trials() {
    let start = std::time::Instant::now();
    let dir = tempfile::tempdir().expect("tempdir");
    let (train_s, test_s) = sinapov_split(generated_scratches());
    let model = dir.path().join("som_spectral.json");
    let model_s = model.to_string_lossy().into_owned();
    let (summary, file) = train_model("som", &["--features", "spectral"], &model, &train_s);
    assert!(summary.contains("reliability weights"), "{summary}");
    assert_eq!(file["features"], "spectral");
    assert_eq!(file["body"]["method"], "som_scratches");
    assert_eq!(file["feature_names"].as_array().expect("names").len(), 125);
    let behaviours = file["body"]["behaviours"].as_array().expect("behaviours");
    assert_eq!(behaviours.len(), 5);
    for b in behaviours {
        // Three nodes per surface.
        assert_eq!(b["som"]["reference"].as_array().expect("nodes").len(), 63);
        let w = b["reliability"].as_f64().expect("a stored weight");
        assert!(w > 0.5 && w <= 1.0, "{b}");
        assert_eq!(b["reliability_folds"], 5);
    }

    let report = eval_json(&model_s, &test_s, &[]);
    assert_eq!(report["method"], "som");
    assert_eq!(report["features"], "spectral");
    assert_eq!(report["captures"], 315);
    let accuracy = report["accuracy"].as_f64().expect("accuracy");
    let fused = report["fused"]["accuracy"].as_f64().expect("fused");
    assert_eq!(report["fused"]["groups"], 63);
    eprintln!("som --features spectral: per scratch {accuracy:.3}, fused {fused:.3}");
    assert!(accuracy >= 0.85, "{report}");
    assert!(fused >= 0.93 && fused >= accuracy, "{report}");

    // Scratch captures carry no height or friction: no Nakano features.
    let x_s = dir.path().join("x.json").to_string_lossy().into_owned();
    let shown = fails(&args(
        &train_head("knn", &["--features", "nakano"], &x_s),
        &train_s[..3],
    ));
    assert!(
        shown.contains(&train_s[0])
            && shown.contains("`--features nakano` needs the columns normal_position_m, friction_force_n"),
        "{shown}"
    );
    eprintln!("took {:.1} s", start.elapsed().as_secs_f64());
}

/// Adds accelerometer columns to a `palpus gen --only nakano` rubbing capture. A synthetic test
/// signal, not a model of a sensor: `accel_z` is gravity plus the second derivative of the
/// height column at the sample rate plus a surface-dependent vibration (a 0.3 m/s² tone at
/// 60 + 25 · `surface_id` Hz, amplitude-modulated with the tangential speed so it starts with
/// the motion, and ±0.05 m/s² of deterministic noise); `accel_x` and `accel_y` are zero.
fn with_accelerometer(src: &Path, dst: &Path) {
    use capture::{Capture, CaptureKind};
    let capture = Capture::read_file(src, CaptureKind::Rubbing).expect("capture");
    let meta = capture.metadata().clone();
    let rate = meta.rate_hz();
    let id: f64 = meta
        .get("surface_id")
        .and_then(|s| s.parse().ok())
        .expect("surface_id");
    let speed = meta
        .get("command.speed_mps")
        .and_then(|s| s.parse::<f64>().ok())
        .expect("speed");
    let h = capture.column("normal_position_m").expect("height");
    let v = capture.column("tangential_velocity_mps").expect("velocity");
    let n = h.len();
    let mut noise = 0x2545_f491_4f6c_dd1d_u64 ^ (id as u64);
    let accel_z: Vec<f64> = (0..n)
        .map(|k| {
            let curvature = if k == 0 || k + 1 == n {
                0.0
            } else {
                (h[k + 1] - 2.0 * h[k] + h[k - 1]) * rate * rate
            };
            noise ^= noise << 13;
            noise ^= noise >> 7;
            noise ^= noise << 17;
            let u = (noise >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
            let t = k as f64 / rate;
            let tone =
                0.3 * (v[k] / speed).clamp(0.0, 1.0) * (std::f64::consts::TAU * (60.0 + 25.0 * id) * t).sin();
            9.81 + curvature + tone + 0.1 * u
        })
        .collect();
    let mut columns = capture.columns().to_vec();
    let mut data = capture.data().to_vec();
    for (name, values) in [
        ("accel_x_mps2", vec![0.0; n]),
        ("accel_y_mps2", vec![0.0; n]),
        ("accel_z_mps2", accel_z),
    ] {
        columns.push(name.to_owned());
        data.push(values);
    }
    Capture::new(meta, columns, data)
        .expect("capture with accelerometer")
        .write_file(dst)
        .expect("write");
}

/// `--features both` on rubbing captures that also carry (synthetic, see
/// [`with_accelerometer`]) accelerometer columns: 5 + 125 features per window, for k-NN, SVM
/// and SOM, trained on run 0 and evaluated on runs 1–2.
#[test]
fn both_feature_sets_on_rubbing_runs_with_accelerometer_columns() {
    let start = std::time::Instant::now();
    let dir = tempfile::tempdir().expect("tempdir");
    let (train, test) = nakano_runs(dir.path());
    let convert = |paths: &[PathBuf]| -> Vec<String> {
        paths
            .iter()
            .map(|p| {
                let dst = dir.path().join(format!(
                    "accel_{}",
                    p.file_name().expect("name").to_string_lossy()
                ));
                with_accelerometer(p, &dst);
                dst.to_string_lossy().into_owned()
            })
            .collect()
    };
    let (train_s, test_s) = (convert(&train), convert(&test));
    for method in ["knn", "svm", "som"] {
        let model = dir.path().join(format!("{method}_both.json"));
        let model_s = model.to_string_lossy().into_owned();
        // All three on 2 s training windows (the shortest length a window's histogram takes
        // in whole frames), so that each trains on the same vectors.
        let options = ["--features", "both", "--train-window-s", "2"];
        let (_, file) = train_model(method, &options, &model, &train_s);
        assert_eq!(file["features"], "both");
        assert_eq!(file["body"]["method"], format!("{method}_windows"));
        let names = file["feature_names"].as_array().expect("names");
        assert_eq!(names.len(), 130);
        assert_eq!(names[0], "roughness_mean_abs_m");
        assert_eq!(names[5], "histogram_t0_f0");
        assert_eq!(file["n_train"], 189);
        let dim = match method {
            "som" => file["body"]["som"]["reference"][0]
                .as_array()
                .expect("node")
                .len(),
            _ => file["body"]["scaling"]["offset"]
                .as_array()
                .expect("offsets")
                .len(),
        };
        assert_eq!(dim, 130);

        let report = eval_json(&model_s, &test_s, &[]);
        assert_eq!(report["features"], "both");
        assert_eq!(report["window_s"], 3.0);
        let (accuracy, worst) = (
            report["accuracy"].as_f64().expect("accuracy"),
            worst_class(&report),
        );
        eprintln!("{method} --features both: {accuracy:.3}, worst surface {worst:.3}");
        assert!(accuracy >= 0.9, "{method}: {report}");

        // A 0.5 s window is shorter than the histogram's 1.92 s (1920 samples at 1 kHz).
        let shown = fails(&args(
            &["recognize", "eval", &model_s, "--window-s", "0.5"],
            &test_s[..1],
        ));
        assert!(
            shown.contains(&test_s[0]) && shown.contains("needs at least 1920"),
            "{shown}"
        );
    }
    // The generated captures alone lack the accelerometer.
    let x_s = dir.path().join("x.json").to_string_lossy().into_owned();
    fails_with(
        &args(
            &train_head("svm", &["--features", "both"], &x_s),
            &strings(&train),
        ),
        &["`--features both` needs the columns accel_x_mps2"],
    );
    eprintln!("took {:.1} s", start.elapsed().as_secs_f64());
}

/// Writes a rubbing capture of `surface` to `dir/name`: a sine roughness of `amplitude_m` under
/// a tip sliding at 5 mm/s, 1 kHz, for `seconds`. Returns its path.
fn write_rubbing(dir: &Path, name: &str, surface: &str, amplitude_m: f64, seconds: f64) -> String {
    use capture::{Capture, CaptureKind, Metadata};
    let common::SineRub { t, x, z, f } = common::sine_rub(amplitude_m, seconds, 0);
    let n = t.len();
    let meta = Metadata::new(CaptureKind::Rubbing, "test", 1000.0).with("surface", surface);
    let columns = [
        TIME_S,
        TANGENTIAL_POSITION_M,
        NORMAL_POSITION_M,
        NORMAL_FORCE_N,
        FRICTION_FORCE_N,
    ]
    .map(String::from)
    .to_vec();
    let path = dir.join(name);
    Capture::new(meta, columns, vec![t, x, z, vec![0.3; n], f])
        .expect("capture")
        .write_file(&path)
        .expect("write");
    path.to_string_lossy().into_owned()
}

/// Captures too short for one window: training refuses their class, naming it and them, and
/// evaluating only such captures is an error, not "0 decisions"; one among others is a warning.
#[test]
fn captures_without_a_window_are_named_in_train_and_eval() {
    let dir = tempfile::tempdir().expect("tempdir");
    let d = dir.path();
    let long: Vec<String> = [("fine", 5e-6), ("coarse", 30e-6)]
        .iter()
        .map(|(s, a)| write_rubbing(d, &format!("{s}.csv"), s, *a, 4.0))
        .collect();
    let cork = write_rubbing(d, "cork.csv", "cork", 10e-6, 0.4);
    let model = d.join("m.json").to_string_lossy().into_owned();
    let windows = ["--window-s", "0.5", "--train-window-s", "0.5"];
    let with_cork: Vec<String> = long.iter().cloned().chain([cork.clone()]).collect();
    fails_with(
        &args(&train_head("som", &windows, &model), &with_cork),
        &[
            "class `cork` has no training vector",
            "cork.csv is 0.400 s long; a training window needs 0.5 s",
        ],
    );
    succeeds(&args(&train_head("som", &windows, &model), &long));

    let short = vec![
        write_rubbing(d, "fine-short.csv", "fine", 5e-6, 0.4),
        write_rubbing(d, "coarse-short.csv", "coarse", 30e-6, 0.3),
    ];
    let eval = ["recognize", "eval", &model];
    fails_with(
        &args(&eval, &short),
        &[
            "no decisions to evaluate",
            "fine-short.csv is 0.400 s long; a decision window needs 0.5 s",
            "coarse-short.csv is 0.300 s long",
        ],
    );
    let mixed: Vec<String> = long.iter().cloned().chain([short[0].clone()]).collect();
    let shown = text(&succeeds(&args(&eval, &mixed)));
    assert!(
        shown.contains("warning: capture") && shown.contains("fine-short.csv is 0.400 s long"),
        "{shown}"
    );
}

/// Defaults that follow the data: k-NN over windows trains on windows of its decision length
/// (and says nothing), a map too small for its surfaces names those it can never answer, and
/// confusion tables list surfaces in natural order (sandpaper #80 before #120).
#[test]
fn training_windows_map_size_and_table_order_follow_the_data() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (train, test) = nakano_runs(dir.path());
    let (train_s, test_s) = (strings(&train), strings(&test));

    let knn = dir.path().join("knn.json");
    let knn_s = knn.to_string_lossy().into_owned();
    let out = succeeds(&args(
        &train_head("knn", &["--features", "nakano", "--window-s", "2"], &knn_s),
        &train_s,
    ));
    assert!(!text(&out).contains("warning"), "{}", text(&out));
    let file = read_json(&knn);
    assert_eq!(file["body"]["windowing"]["window_samples"], 2000);
    assert_eq!(file["body"]["windowing"]["training_window_samples"], 2000);

    // Two nodes for seven surfaces: five can never be named, and training names them.
    let som = dir.path().join("som.json");
    let som_s = som.to_string_lossy().into_owned();
    let out = succeeds(&args(&train_head("som", &["--som-nodes", "2"], &som_s), &train_s));
    let file = read_json(&som);
    assert_eq!(file["body"]["som"]["reference"].as_array().map(Vec::len), Some(2));
    let warned = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(
        warned.contains("warning: 5 of 7 classes own no node of the map (2 nodes)"),
        "{warned}"
    );
    let labels: Vec<usize> = file["body"]["som"]["labels"]
        .as_array()
        .map(|l| l.iter().filter_map(Value::as_u64).map(|l| l as usize).collect())
        .unwrap_or_default();
    assert_eq!(labels.len(), 2, "{file}");
    let classes = file["classes"].as_array().expect("classes");
    for (i, class) in classes.iter().enumerate() {
        let name = class.as_str().expect("name");
        assert_eq!(!labels.contains(&i), warned.contains(name), "{name}: {warned}");
    }
    fails_with(
        &args(&train_head("som", &["--som-nodes", "0"], &som_s), &train_s),
        &["--som-nodes"],
    );

    // The table lists #80 before #120 though the classes sort the other way as text.
    let shown = text(&succeeds(&args(&["recognize", "eval", &knn_s], &test_s)));
    let row = |name: &str| {
        shown
            .find(&format!("  {name} "))
            .unwrap_or_else(|| panic!("{name}: {shown}"))
    };
    assert!(row("sandpaper_80") < row("sandpaper_120"), "{shown}");
    assert!(row("sandpaper_240") < row("sandpaper_400"), "{shown}");
    assert!(
        shown.contains(" decisions\n") && !shown.contains(" samples\n"),
        "{shown}"
    );
}
