//! Anytime decisions end to end on the simulated Nakano surfaces (7 surfaces × 3 runs, seed 1):
//! an SVM over short Nakano windows trained on run 0, its window probabilities accumulated from
//! contact on runs 1 and 2 (`recognize eval --sequential`). Compared, in the same run, with the
//! recognizer's default fixed 3 s window: the anytime decisions must be at least as often right
//! and reach the stable right surface sooner, and the posterior must be calibrated (expected
//! calibration error ≤ 5 %). Measured (seed 1, 0.25 s windows): at threshold 0.9, 100 % of
//! named windows right, stable right after 1.16 s on average, ECE 1.9 %; the 3 s window's first
//! correct decision comes after 4.4 s. On strokes that slide from one surface onto the next
//! (`gen --two-patch`), the change test names the new surface 1.09 s after the seam on average,
//! the memory alone after 2.12 s.

use crate::common::{fails, json, nakano_captures, succeeds, train_nakano_svm};

#[test]
fn anytime_decisions_are_right_sooner_than_a_fixed_window_and_calibrated() {
    let dir = tempfile::tempdir().expect("tempdir");
    let root = dir.path().to_string_lossy().into_owned();
    succeeds(&["gen", "--out", &root, "--only", "nakano", "-q"]);
    let captures = nakano_captures(dir.path());
    let paths = |run: &str| -> Vec<String> {
        captures
            .iter()
            .filter(|p| p.to_string_lossy().ends_with(&format!("{run}.csv")))
            .map(|p| p.to_string_lossy().into_owned())
            .collect()
    };
    let (train, test) = (paths("run0"), [paths("run1"), paths("run2")].concat());
    assert_eq!((train.len(), test.len()), (7, 14));
    let model = |name: &str, extra: &[&str]| train_nakano_svm(dir.path(), name, &train, extra);
    let fixed = model("fixed.json", &[]);
    let short = model("short.json", &["--window-s", "0.25"]);

    let mut args = vec!["recognize", "eval", fixed.as_str(), "--json"];
    args.extend(test.iter().map(String::as_str));
    let baseline = json(&args);
    let baseline_accuracy = baseline["accuracy"].as_f64().expect("accuracy");
    let baseline_first_s = baseline["time_to_first_correct_s"]
        .as_f64()
        .expect("first correct");

    let plots = dir.path().join("plots").to_string_lossy().into_owned();
    let mut args = vec![
        "recognize",
        "eval",
        short.as_str(),
        "--sequential",
        "0.5,0.9,0.99",
        "--plots",
        &plots,
        "--json",
    ];
    args.extend(test.iter().map(String::as_str));
    let e = json(&args);
    eprintln!("fixed 3 s window: accuracy {baseline_accuracy}, first correct {baseline_first_s} s");
    eprintln!("{}", serde_json::to_string_pretty(&e).expect("json"));
    // Three panels: the reliability diagram, the threshold's trade, and a bar per surface for
    // the path its decisions took (drawn in the bars' green, in the right third only).
    let png = dir.path().join("plots/sequential.png");
    let mut reader = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&png).expect("png")))
        .read_info()
        .expect("png header");
    let mut buf = vec![0; reader.output_buffer_size().expect("size")];
    let info = reader.next_frame(&mut buf).expect("png frame");
    assert_eq!((info.width, info.height), (1800, 540));
    let green_columns: Vec<usize> = buf[..info.buffer_size()]
        .chunks_exact(3)
        .enumerate()
        .filter(|(_, p)| *p == [90, 150, 90])
        .map(|(i, _)| i % info.width as usize)
        .collect();
    assert!(
        green_columns.len() > 7 * 100,
        "{} bar pixels",
        green_columns.len()
    );
    assert!(
        green_columns.iter().all(|&x| x >= 1200),
        "a bar outside the right panel"
    );
    assert_eq!(e["captures"], 14);
    let steps = e["steps"].as_f64().expect("steps");
    let rows = e["rows"].as_array().expect("rows");
    assert_eq!(rows.len(), 3);
    let field = |r: &serde_json::Value, k: &str| r[k].as_f64().unwrap_or_else(|| panic!("{k} in {r}"));
    // The posterior does not depend on the threshold, so a higher one names a surface later.
    let first: Vec<f64> = rows
        .iter()
        .map(|r| field(r, "time_to_first_decision_s"))
        .collect();
    assert!(first.windows(2).all(|w| w[0] <= w[1]), "{first:?}");
    let at_09 = &rows[1];
    assert_eq!(at_09["threshold"], 0.9);
    let accuracy = field(at_09, "correct") / field(at_09, "decided");
    assert!(
        accuracy >= baseline_accuracy.min(0.97),
        "{accuracy} vs {baseline_accuracy}"
    );
    assert!(field(at_09, "decided") > 0.7 * steps, "{at_09}");
    assert_eq!(at_09["not_stable"], 0, "{at_09}");
    let stable_s = field(at_09, "time_to_stable_correct_s");
    assert!(
        stable_s < 0.5 * baseline_first_s,
        "{stable_s} s vs {baseline_first_s} s"
    );
    let calibration = &e["calibration"];
    assert!(field(calibration, "ece") <= 0.05, "{calibration}");
    assert!(field(calibration, "brier") < 0.1, "{calibration}");

    // Strokes that slide from each surface onto the next halfway: the change test follows the
    // new surface sooner than the memory alone forgets the old one, and on the single-surface
    // runs it changes nothing (same rows as without it).
    succeeds(&["gen", "--out", &root, "--two-patch", "-q"]);
    let two_patch: Vec<String> = std::fs::read_dir(dir.path().join("nakano_two_patch"))
        .expect("two-patch strokes")
        .map(|e| e.expect("entry").path().to_string_lossy().into_owned())
        .collect();
    assert_eq!(two_patch.len(), 14);
    let followed = |extra: &[&str]| {
        let mut args = vec![
            "recognize",
            "eval",
            short.as_str(),
            "--sequential",
            "0.9",
            "--json",
        ];
        args.extend_from_slice(extra);
        args.extend(two_patch.iter().map(String::as_str));
        let e = json(&args);
        let row = e["rows"][0].clone();
        assert_eq!(row["changes"], 14, "{row}");
        assert!(row["changes_not_followed"].as_u64().expect("count") <= 1, "{row}");
        field(&row, "change_followed_s")
    };
    let (with_test, memory_only) = (followed(&[]), followed(&["--change-odds", "0"]));
    eprintln!("change followed after {with_test} s, {memory_only} s without the change test");
    assert!(with_test < 0.7 * memory_only, "{with_test} s vs {memory_only} s");
    let mut args = vec![
        "recognize",
        "eval",
        short.as_str(),
        "--sequential",
        "0.5,0.9,0.99",
        "--json",
    ];
    args.extend(["--change-odds", "0"]);
    args.extend(test.iter().map(String::as_str));
    let without = json(&args);
    for (a, b) in rows.iter().zip(without["rows"].as_array().expect("rows")) {
        for k in ["decided", "correct", "time_to_stable_correct_s", "flips_per_s"] {
            assert_eq!(a[k], b[k], "{k}: {a} vs {b}");
        }
    }

    // A SOM names nodes, not probabilities over the surfaces: refused, saying what would do.
    let som = dir.path().join("som.json").to_string_lossy().into_owned();
    let mut args = vec!["recognize", "train", "--method", "som", "--out", som.as_str()];
    args.extend(train.iter().map(String::as_str));
    succeeds(&args);
    let mut args = vec!["recognize", "eval", som.as_str(), "--sequential", "0.9"];
    args.extend(test.iter().map(String::as_str));
    let err = fails(&args);
    assert!(
        err.contains(
            "anytime decisions need each window's probability of every surface, which a k-NN or SVM"
        ),
        "{err}"
    );
}
