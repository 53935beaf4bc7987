//! Trainees' attempts: scored against the scene's goal, kept in the history and drawn as a
//! learning curve, one per stroke of a session.

use super::*;

/// The default scene's goal (stop within 3 mm of where the vessel wall gives): the scripted
/// trainee stopping at 26 mm passes, the one pushing on to 30 mm overshoots; a forbidden layer
/// and a force limit fail it for their own reasons. Each attempt is scored in the report and
/// drawn over the expert reference; the two trainees' attempts are rows of the history, which
/// `palpus history` prints and draws.
#[test]
fn scored_attempts_pass_or_fail_for_their_reasons_and_are_kept_in_the_history() {
    let _shared = untimed();
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    let history = dir.path().join("history.sqlite");
    let attempt = |name: &str, trainee: &str, sets: &[&str]| {
        let out = dir.path().join(name);
        let mut args = vec!["--trainee", trainee, "--history", history.to_str().unwrap()];
        for s in sets {
            args.extend(["--set", s]);
        }
        let r = run_unpaced(&args, &out, &cache);
        assert!(out.join("attempt.png").exists(), "{name}: no attempt.png");
        let summary = std::fs::read_to_string(out.join("summary.txt")).unwrap();
        (r["score"].clone(), summary)
    };
    let (pass, summary) = attempt("pass", "ana", &["task.depth_m=0.026"]);
    assert_eq!(pass["passed"], true, "{pass}");
    let overshoot = pass["overshoot_m"].as_f64().unwrap();
    assert!(overshoot > 0.0 && overshoot < 0.003, "{pass}");
    assert_eq!(
        pass["layers_given"],
        serde_json::json!(["capsule", "vessel_wall"])
    );
    assert!(summary.contains("attempt PASSED: stopped"), "{summary}");
    let (fail, summary) = attempt("fail", "ben", &[]);
    assert_eq!(fail["passed"], false, "{fail}");
    assert!(fail["overshoot_m"].as_f64().unwrap() > 0.003, "{fail}");
    assert!(summary.contains("attempt FAILED: went"), "{summary}");
    // Where the wall gave does not depend on how deep the hand goes afterwards.
    let gave = |s: &Value| s["target_depth_m"].as_f64().unwrap();
    assert!((gave(&pass) - gave(&fail)).abs() < 2e-4, "{pass} {fail}");

    let (forbidden, _) = attempt(
        "forbidden",
        "carl",
        &[
            "task.goal.stop_after=\"capsule\"",
            "task.goal.within_m=0.02",
            "task.goal.must_not_puncture=[\"vessel_wall\"]",
        ],
    );
    assert_eq!(forbidden["passed"], false);
    assert_eq!(forbidden["verdict"], "punctured the vessel wall", "{forbidden}");
    let (forceful, _) = attempt(
        "forceful",
        "carl",
        &["task.depth_m=0.026", "task.goal.max_force_n=1.0"],
    );
    assert_eq!(forceful["passed"], false);
    assert!(
        forceful["verdict"]
            .as_str()
            .unwrap()
            .starts_with("the axial force reached 1.5"),
        "{forceful}"
    );

    // A goal naming more layers than the model renders is refused before anyone practises.
    let o = run(
        &[
            "--headless",
            "--unpaced",
            "--set",
            "task.goal.layers=[\"capsule\", \"vessel_wall\", \"back\"]",
        ],
        &cache,
    );
    let printed = text(&o);
    assert!(
        !o.status.success() && printed.contains("renders 2 membranes"),
        "{printed}"
    );

    // Sessions running at once, each adding its attempt to the same history: none is lost.
    let children: Vec<_> = ["dora", "emil", "finn"]
        .iter()
        .map(|trainee| {
            let out = dir.path().join(format!("at_once_{trainee}"));
            palpus_at_root(
                "run",
                &[
                    "--headless",
                    "--unpaced",
                    "--trainee",
                    trainee,
                    "--history",
                    history.to_str().unwrap(),
                    "--report",
                    out.to_str().unwrap(),
                ],
                &cache,
            )
            .env_remove("DISPLAY")
            .env_remove("WAYLAND_DISPLAY")
            .stdout(std::process::Stdio::null())
            .spawn()
            .unwrap()
        })
        .collect();
    for mut child in children {
        assert!(child.wait().unwrap().success());
    }

    let rows = palpus::history::History::open(&history)
        .unwrap()
        .attempts(None, None)
        .unwrap();
    let who: Vec<(&str, bool)> = rows
        .iter()
        .map(|a| (a.trainee.as_str(), a.score.passed))
        .collect();
    assert_eq!(
        who[..4],
        [("ana", true), ("ben", false), ("carl", false), ("carl", false)]
    );
    let mut at_once: Vec<&str> = who[4..].iter().map(|(t, _)| *t).collect();
    at_once.sort_unstable();
    assert_eq!(at_once, ["dora", "emil", "finn"]);
    assert!(
        rows.iter()
            .all(|a| a.scene == "needle_liver" && a.model_sha256.len() == 64)
    );
    let printed = draw_history(
        &history,
        &["--trainee", "carl"],
        &dir.path().join("curve.png"),
        &cache,
    );
    assert!(
        printed.contains("2 attempts") && printed.contains("passed 0 of 2"),
        "{printed}"
    );
}

/// `palpus history --history HISTORY FILTERS --plot PLOT`: checks that it succeeded and drew a
/// learning curve of at least 800 × 600, and returns what it printed.
fn draw_history(history: &Path, filters: &[&str], plot: &Path, cache: &Path) -> String {
    let args = [
        &["--history", history.to_str().unwrap()][..],
        filters,
        &["--plot", plot.to_str().unwrap()],
    ]
    .concat();
    let o = palpus_at_root("history", &args, cache).output().unwrap();
    let printed = text(&o);
    assert!(o.status.success(), "{printed}");
    let image = render::Image::load_png(plot).unwrap();
    assert!(image.width >= 800 && image.height >= 600);
    printed
}

/// The second procedure, epidural placement by loss of resistance: the scripted trainee stops
/// in the epidural space once the ligamentum flavum gives (passed), or pushes on through the
/// dura (failed); both attempts are rows of the history, which `palpus history` draws.
#[test]
fn the_epidural_scene_passes_a_stop_in_the_space_and_fails_a_dural_puncture() {
    let _shared = untimed();
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    let history = dir.path().join("history.sqlite");
    let attempt = |name: &str, sets: &[&str]| {
        let out = dir.path().join(name);
        let mut args = vec![
            "scenes/epidural_lumbar.toml",
            "--trainee",
            "ines",
            "--history",
            history.to_str().unwrap(),
        ];
        for s in sets {
            args.extend(["--set", s]);
        }
        let r = run_unpaced(&args, &out, &cache);
        assert!(out.join("attempt.png").exists(), "{name}: no attempt.png");
        (r["score"].clone(), printed_layers(&out))
    };
    let (pass, summary) = attempt("pass", &[]);
    assert_eq!(pass["passed"], true, "{pass}");
    assert_eq!(
        pass["layers_given"],
        serde_json::json!(["skin", "supraspinous_ligament", "ligamentum_flavum"])
    );
    // The flavum gave where the simulated spine gives at the speed it was pushed (about the
    // script's 3 mm/s), and the tip settled inside the 5 mm allowed, short of the dura.
    let tissue = sim::NeedleTissue::lumbar_epidural();
    let gave = pass["target_depth_m"].as_f64().unwrap();
    let truth = tissue.puncture_depth_m(2, 0.003).unwrap();
    assert!(
        (gave - truth).abs() < 5e-4,
        "gave at {gave}, the spine at {truth}"
    );
    let overshoot = pass["overshoot_m"].as_f64().unwrap();
    assert!(overshoot > 0.0 && overshoot < 0.005, "{pass}");
    assert!(
        pass["deepest_m"].as_f64().unwrap() < tissue.membranes[3].depth_m,
        "{pass}"
    );
    assert!(summary.contains("layer ligamentum_flavum: felt"), "{summary}");

    let (fail, summary) = attempt("dural_puncture", &["task.depth_m=0.052"]);
    assert_eq!(fail["passed"], false, "{fail}");
    assert!(
        fail["verdict"]
            .as_str()
            .unwrap()
            .starts_with("punctured the dura"),
        "{fail}"
    );
    assert_eq!(fail["layers_given"][3], "dura");
    assert!(
        summary.contains("attempt FAILED: punctured the dura"),
        "{summary}"
    );

    let rows = palpus::history::History::open(&history)
        .unwrap()
        .attempts(Some("ines"), Some("epidural_lumbar"))
        .unwrap();
    let passed: Vec<bool> = rows.iter().map(|a| a.score.passed).collect();
    assert_eq!(passed, [true, false]);
    let printed = draw_history(
        &history,
        &["--scene", "epidural_lumbar"],
        &dir.path().join("curve.png"),
        &cache,
    );
    assert!(printed.contains("passed 1 of 2"), "{printed}");
}

/// A session of several strokes (a window session where the trainee withdraws and tries again)
/// scores each stroke as an attempt and keeps each in the history: here the expert's recorded
/// attempt replayed twice, the needle leaving the tissue between the two.
#[test]
fn each_stroke_of_a_session_is_an_attempt_of_its_own() {
    let _shared = untimed();
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    let history = dir.path().join("history.sqlite");
    let expert = std::fs::read_to_string(root().join("assets/captures/expert/needle_liver.csv")).unwrap();
    let mut lines = expert.lines();
    let (meta, columns) = (lines.next().unwrap(), lines.next().unwrap());
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    let mut csv = format!("{meta}\n{columns}\n");
    let mut t_ms = 0i64;
    let mut row = |t_ms: i64, depth_m: f64, v: f64, f: f64| {
        csv.push_str(&format!("{},{depth_m},{v},{f}\n", t_ms as f64 / 1e3));
    };
    for _ in 0..2 {
        let last = rows[rows.len() - 1][1];
        for r in &rows {
            t_ms += 1;
            row(t_ms, r[1], r[2], r[3]);
        }
        // Out of the tissue to 2 mm above it, and a pause.
        for k in 1..=500 {
            t_ms += 1;
            row(t_ms, last - 0.002 * f64::from(k.min(200)) / 200.0, -0.01, 0.0);
        }
    }
    let replay = dir.path().join("two_strokes.csv");
    std::fs::write(&replay, csv).unwrap();
    let device = format!("replay:{}", replay.display());
    let out = dir.path().join("report");
    let r = run_unpaced(
        &["--device", &device, "--history", history.to_str().unwrap()],
        &out,
        &cache,
    );
    let attempts = r["attempts"].as_array().unwrap();
    assert_eq!(attempts.len(), 2, "{r}");
    for a in attempts {
        assert_eq!(a["passed"], true, "{a}");
        assert_eq!(a["layers_given"], serde_json::json!(["capsule", "vessel_wall"]));
        assert_eq!(a["withdrawals"], 0, "{a}");
    }
    assert_eq!(r["score"], attempts[1]);
    let summary = printed_layers(&out);
    assert!(
        summary.contains("attempt 1 PASSED") && summary.contains("attempt 2 PASSED"),
        "{summary}"
    );
    let rows = palpus::history::History::open(&history)
        .unwrap()
        .attempts(None, None)
        .unwrap();
    assert_eq!(rows.len(), 2);
}
