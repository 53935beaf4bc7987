//! The rubbing scenes: friction rendered, surfaces recognized live.

use super::*;

#[test]
fn rubbing_scenes_render_their_friction_and_recognize_their_surfaces() {
    let _shared = untimed();
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    let out = dir.path().join("friction");
    let r = run_unpaced(&["scenes/friction_hard_soft.toml"], &out, &cache);
    let (plate, sponge) = (&r["segments"][0], &r["segments"][1]);
    assert_eq!(
        (plate["object"].as_str(), sponge["object"].as_str()),
        (Some("plate"), Some("sponge"))
    );
    // Li & Bi Eq. 12 at 2 N: (0.1647·2 + 0.0324) / 2 = 0.181.
    let hard = f(&plate["mean_friction_ratio"]);
    assert!((hard - 0.181).abs() < 0.02, "plate friction ratio {hard}");
    // The sponge grips far harder than the plate.
    assert!(f(&sponge["mean_friction_ratio"]) > 2.0 * hard, "{sponge}");

    let out = dir.path().join("surfaces");
    let r = run_unpaced(&["scenes/surfaces_nakano.toml"], &out, &cache);
    assert_eq!(r["segments"].as_array().unwrap().len(), 7);
    let accuracy = f(&r["recognition_accuracy"]);
    assert!(accuracy > 0.9, "live recognition {accuracy}");
    // The scene's own choice, reported: an SVM naming a surface at a posterior of 0.9.
    assert_eq!(r["recognizer"]["method"], "svm");
    assert_eq!(f(&r["recognizer"]["threshold"]), 0.9);
    // Its SVM decides each window at its last sample, and the report says so.
    assert_eq!(f(&r["recognizer"]["decided_after_s"]), 0.0);
    // The committed SVM carries a weight fitted on held-out tracks, and the report says where
    // the weight it decides with came from: the file's fit, not hop / window.
    let model: Value =
        serde_json::from_str(&std::fs::read_to_string(root().join("assets/models/nakano_svm.json")).unwrap())
            .unwrap();
    let fitted = f(&model["posterior_weight"]["weight"]);
    let weight_from = &r["recognizer"]["window_weight_from"];
    assert_eq!(weight_from["from"], "held_out", "{weight_from}");
    assert_eq!(f(&r["recognizer"]["window_weight"]), fitted);
    assert_eq!(
        f(&weight_from["hop_weight"]),
        f(&model["posterior_weight"]["hop_weight"])
    );
    // With what its decisions needed on the tracks held out in training, in the summary too.
    let held_out = &model["posterior_weight"]["held_out"];
    assert_eq!(&weight_from["held_out"], held_out, "{weight_from}");
    let summary = std::fs::read_to_string(out.join("summary.txt")).unwrap();
    let said = format!(
        "in training, anytime decisions at 0.9 on {} held-out strokes: the stable \
         right surface {:.1} mm",
        held_out["strokes"],
        1e3 * f(&held_out["stable_right_m"])
    );
    assert!(summary.contains(&said), "{said}\n{summary}");
    // Every window of the plan's 5 mm/s strokes was read.
    assert_eq!(r["recognizer"]["features"], "nakano");
    assert_eq!(
        r["recognition_unread_windows"], 0,
        "{}",
        r["recognition_unread_windows"]
    );
    // Every surface ends named right, well before any decision on a fixed 3 s window could be
    // made (3 s plus the filters' 0.27 s look-ahead), and never before the first 0.25 s window
    // is in: the model decides each window at its last sample.
    let timing = r["recognition_timing"].as_array().unwrap();
    assert_eq!(timing.len(), 7);
    for t in timing {
        let stable = f(&t["stable_right_after_s"]);
        assert!((0.25..2.0).contains(&stable), "{t}");
        assert!(t["first_named_after_s"].as_f64().unwrap() <= stable, "{t}");
        // The same decision in travel: no farther than the plan's 5 mm/s reaches by then (the
        // stroke starts from rest), and not at rest.
        let travel_m = f(&t["stable_right_after_m"]);
        assert!(travel_m > 0.0 && travel_m <= 5e-3 * stable, "{t}");
    }
    // The timeline says "undecided" (an empty label) before each surface is named, with the
    // surface most likely so far and its probability.
    let timeline = std::fs::read_to_string(out.join("timeline.csv")).unwrap();
    assert!(timeline.lines().count() > 7 * 15, "{timeline}");
    assert!(timeline.starts_with("object,truth,time_s,label,best,confidence\n"));
    let undecided = timeline
        .lines()
        .filter(|l| l.split(',').nth(3) == Some(""))
        .count();
    assert!(undecided >= 7, "{timeline}");
}
