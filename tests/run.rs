//! `palpus run`: the default scene in real time as README's first command runs it, the
//! record → identify → run loop, and the rubbing scenes.
#![allow(clippy::unwrap_used)]

mod common;

use std::path::{Path, PathBuf};

use common::text;
use identify::ModelFile;
use serde_json::Value;

/// The tests here run haptic loops and renderers. Those that time something (a loop's rate
/// in real time, a watchdog's stall) run alone, so that the 1 % rate check measures the loop
/// and not a neighbouring test hogging the cores; those that run unpaced may share the cores
/// with each other.
static CORES: std::sync::RwLock<()> = std::sync::RwLock::new(());

/// The cores to this test alone.
fn serial() -> std::sync::RwLockWriteGuard<'static, ()> {
    CORES.write().unwrap_or_else(|e| e.into_inner())
}

/// The cores shared with other untimed tests, never with a timed one.
fn untimed() -> std::sync::RwLockReadGuard<'static, ()> {
    CORES.read().unwrap_or_else(|e| e.into_inner())
}

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// `palpus SUBCOMMAND ARGS` in the repository root, with a private model cache.
fn palpus_at_root(subcommand: &str, args: &[&str], cache: &Path) -> std::process::Command {
    let mut command = common::palpus_command();
    command
        .arg(subcommand)
        .args(args)
        .current_dir(root())
        .env("PALPUS_CACHE_DIR", cache);
    command
}

/// Runs `palpus run ARGS` with a private model cache and no display.
fn run(args: &[&str], cache: &Path) -> std::process::Output {
    palpus_at_root("run", args, cache)
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .unwrap()
}

/// Runs `palpus run ARGS --headless --unpaced --report OUT` with a private model cache, checks
/// that it succeeded, and returns its report.
fn run_unpaced(args: &[&str], out: &Path, cache: &Path) -> Value {
    let report_args = ["--headless", "--unpaced", "--report", out.to_str().unwrap()];
    let o = run(&[args, &report_args[..]].concat(), cache);
    assert!(o.status.success(), "{}", text(&o));
    report(out)
}

/// The summary a run wrote.
fn printed_layers(dir: &Path) -> String {
    std::fs::read_to_string(dir.join("summary.txt")).unwrap()
}

/// The default scene, its paths absolute and without budgets, with `model_source` (a
/// `capture = …` or `file = …` line) in place of its model's capture, and without its goal: the
/// goal names the two membranes of the default model, and another model may find more.
fn needle_scene_with(model_source: &str) -> String {
    let text = std::fs::read_to_string(root().join("scenes/needle_liver.toml")).unwrap();
    let text = text.split("\n[task.goal]").next().unwrap_or_default();
    common::without_budgets(text)
        .replace("../", &format!("{}/", root().display()))
        .lines()
        .map(|l| {
            if l.starts_with("capture = ") {
                model_source.to_owned()
            } else {
                l.to_owned()
            }
        })
        .collect::<Vec<_>>()
        .join("\n")
}

fn report(dir: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("report.json")).unwrap()).unwrap()
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"))
}

/// The report of a real-time run, measured again (up to five runs in all, seconds apart) while
/// the first segment shows ticks over 2 ms late. A virtual machine is sometimes descheduled for
/// a hundred milliseconds or more, now and then for seconds on end: the loop then skips the
/// slots it missed, its mean rate says nothing about the loop, and the segment loses samples
/// its duration is checked on. Of the runs measured, the one least disturbed is returned: the
/// fewest late ticks, then the rate closest to nominal. A loop that is slow without ever being
/// late is judged on its first run.
fn real_time_report(rate_tolerance: f64, attempt: impl Fn() -> Value) -> Value {
    // Gigabytes of build output may still be waiting to be written back: flush them first, so
    // the kernel's writeback does not compete with the loop being measured.
    let settle = || {
        let _ = std::process::Command::new("sync").status();
    };
    let disturbance = |r: &Value| {
        let seg = &r["segments"][0];
        (f(&seg["late_over_2ms"]), f(&seg["rate_error"]))
    };
    settle();
    let mut best = attempt();
    // A shared machine's slow spells last tens of seconds: five tries, seconds apart.
    for _ in 1..5 {
        let (late, rate_error) = disturbance(&best);
        if late == 0.0 {
            break;
        }
        eprintln!(
            "the machine stalled during the run ({late} ticks over 2 ms late, rate error {rate_error:.4} against {rate_tolerance}); measuring again"
        );
        std::thread::sleep(std::time::Duration::from_secs(5));
        settle();
        let r = attempt();
        if disturbance(&r) < disturbance(&best) {
            best = r;
        }
    }
    best
}

#[test]
fn the_default_scene_punctures_at_the_truth_depth_in_real_time() {
    let _serial = serial();
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("report");
    let attempt = || {
        let o = run(
            &["--headless", "--duration", "3", "--report", out.to_str().unwrap()],
            &dir.path().join("cache"),
        );
        let printed = text(&o);
        assert!(o.status.success(), "{printed}");
        assert!(
            printed.contains("scene needle_liver") && printed.contains("puncture 1"),
            "{printed}"
        );
        report(&out)
    };
    let r = real_time_report(0.01, attempt);
    let seg = &r["segments"][0];
    // Three seconds at 1 kHz, at the nominal rate within 1 %.
    assert!((f(&seg["duration_s"]) - 3.0).abs() < 0.01, "{seg}");
    assert!(f(&seg["rate_error"]) < 0.01, "{seg}");
    // Forces within the device's limits, never NaN.
    assert!(f(&seg["max_command_n"]) <= f(&seg["device_limit_n"]), "{seg}");
    assert_eq!(f(&seg["non_finite_commands"]), 0.0);
    // The capsule gives where the simulated liver the model was identified from gives (the
    // committed capture's header names the generator and its tissue).
    assert_eq!(seg["truth_tissue"], "liver", "{seg}");
    let p = &seg["punctures"][0];
    let (depth, truth) = (f(&p["depth_m"]), f(&p["truth_depth_m"]));
    assert!(
        (depth - truth).abs() < 0.001,
        "puncture at {depth} m, truth {truth} m"
    );
    assert!(
        (f(&p["peak_force_n"]) / f(&p["truth_peak_force_n"]) - 1.0).abs() < 0.05,
        "{p}"
    );
    // Beside it, the peak the simulated liver gives at that speed.
    let tissue = sim::NeedleTissue::bovine_liver();
    let speed = f(&p["speed_mps"]);
    let truth_peak = tissue.puncture_peak_force_n(0, speed).unwrap();
    assert!((f(&p["truth_peak_force_n"]) - truth_peak).abs() < 1e-12, "{p}");
    // Every membrane of that liver is listed, the capsule felt where the model's force gives.
    let layers = seg["layers"].as_array().unwrap();
    let names: Vec<&str> = layers.iter().map(|l| l["name"].as_str().unwrap()).collect();
    assert_eq!(names, ["capsule", "vessel_wall"], "{seg}");
    let capsule = &layers[0];
    assert_eq!(capsule["status"], "felt", "{capsule}");
    let felt_speed = f(&capsule["speed_mps"]);
    assert!(
        (f(&capsule["truth_depth_m"]) - tissue.puncture_depth_m(0, felt_speed).unwrap()).abs() < 1e-12
            && (f(&capsule["truth_peak_force_n"]) - tissue.puncture_peak_force_n(0, felt_speed).unwrap())
                .abs()
                < 1e-12,
        "{capsule}"
    );
    assert!(
        (f(&capsule["felt_depth_m"]) - f(&capsule["truth_depth_m"])).abs() < 0.003,
        "{capsule}"
    );
    // Three seconds take the needle to about the vessel wall: it is listed whatever came of it,
    // not silently dropped.
    assert!(
        ["felt", "missed", "not reached"].contains(&layers[1]["status"].as_str().unwrap()),
        "{}",
        layers[1]
    );
    assert!(printed_layers(&out).contains("layer vessel_wall:"));
    // The report folder is complete.
    for file in ["summary.txt", "report.json", "force.png"] {
        assert!(out.join(file).is_file(), "{file} missing");
    }
    assert!(out.join("frame.png").is_file() || out.join("frame.txt").is_file());
    assert!(["identified", "cache"].contains(&r["models"][0]["origin"].as_str().unwrap()));
}

#[test]
fn the_default_scene_feels_both_layers_where_and_as_hard_as_the_tissue_gives() {
    let _shared = untimed();
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("report");
    let r = run_unpaced(&[], &out, &dir.path().join("cache"));
    let seg = &r["segments"][0];
    let punctures = seg["punctures"].as_array().unwrap();
    assert_eq!(punctures.len(), 2, "{seg}");
    for p in punctures {
        assert!((f(&p["depth_m"]) - f(&p["truth_depth_m"])).abs() < 0.001, "{p}");
        assert!(
            (f(&p["peak_force_n"]) / f(&p["truth_peak_force_n"]) - 1.0).abs() < 0.05,
            "{p}"
        );
    }
    for layer in seg["layers"].as_array().unwrap() {
        assert_eq!(layer["status"], "felt", "{layer}");
    }
    // Along the whole run, against the simulated liver's own force on the same trajectory: no
    // pop the liver does not have, and a hold that does not chatter.
    let along = &seg["truth_along"];
    assert!(f(&along["ticks"]) > 5000.0, "{along}");
    assert!(f(&along["rmse_n"]) < 0.3, "{along}");
    assert_eq!(along["false_pops"].as_array().unwrap().len(), 0, "{along}");
    assert!(f(&along["held_ticks"]) > 300.0, "{along}");
    assert!(f(&along["held_ripple_n"]) < 0.02, "{along}");
    // Every tick whose inputs left the trained domain is accounted for by state.
    let explained: f64 = seg["out_of_domain"]
        .as_array()
        .unwrap()
        .iter()
        .map(|o| f(&o["ticks"]))
        .sum();
    assert_eq!(explained, f(&seg["model_clamps"]), "{seg}");
}

#[test]
fn a_recorded_session_re_identifies_to_the_same_model() {
    let _shared = untimed();
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    let session = dir.path().join("session.csv");
    let first = dir.path().join("first");
    let first_report = run_unpaced(&["--record", session.to_str().unwrap()], &first, &cache);
    let reidentified = dir.path().join("re.json");
    let o = common::palpus(&[
        "identify",
        session.to_str().unwrap(),
        "--model",
        "needle-phases",
        "--out",
        reidentified.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));

    // The same scene with the re-identified model file in place of the capture.
    let scene_text = needle_scene_with(&format!("file = {:?}", reidentified.display().to_string()));
    let scene = dir.path().join("re.toml");
    std::fs::write(&scene, scene_text).unwrap();
    let second = dir.path().join("second");
    let second_report = run_unpaced(&[scene.to_str().unwrap()], &second, &cache);
    assert_eq!(second_report["models"][0]["origin"], "file");

    // The two models agree along the trajectory the trainee took.
    let original = ModelFile::load(Path::new(first_report["models"][0]["path"].as_str().unwrap())).unwrap();
    let re = ModelFile::load(&reidentified).unwrap();
    let capture = capture::Capture::read_file(&session, capture::CaptureKind::Insertion).unwrap();
    let (depth, velocity) = (
        capture.column("depth_m").unwrap(),
        capture.column("velocity_mps").unwrap(),
    );
    // Both run along the recorded trajectory as the haptic thread runs them.
    let along = |m: &ModelFile| match &m.body {
        identify::ModelBody::Phases(p) => p.simulate(depth, velocity),
        _ => panic!("the default scene's model is the phase-aware one"),
    };
    let (a, b) = (along(&original), along(&re));
    let (mut sum, mut n) = (0.0, 0usize);
    for (x, y) in a.iter().zip(&b) {
        sum += (x.force_n - y.force_n).powi(2);
        n += 1;
    }
    let rms = (sum / n as f64).sqrt();
    assert!(n > 500 && rms < 0.2, "RMS difference {rms} N over {n} points");

    // And the trainee feels the same puncture.
    let (a, b) = (
        &first_report["segments"][0]["punctures"][0],
        &second_report["segments"][0]["punctures"][0],
    );
    assert!((f(&a["depth_m"]) - f(&b["depth_m"])).abs() < 0.0015, "{a} vs {b}");
    assert!(
        (f(&a["peak_force_n"]) - f(&b["peak_force_n"])).abs() < 0.15,
        "{a} vs {b}"
    );
}

#[test]
fn scenes_on_models_from_real_world_shaped_records_render_every_layer_bounded() {
    let _shared = untimed();
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    // One speed with no withdrawal, a digitized curve, layers 2 mm apart, a wall opening into
    // a lumen (assets/captures/needle_corpus).
    for record in ["one_speed", "digitized", "close_layers", "lumen"] {
        let capture = root().join(format!("assets/captures/needle_corpus/{record}_train.csv"));
        let text = needle_scene_with(&format!("capture = {:?}", capture.display().to_string()));
        let scene = dir.path().join(format!("{record}.toml"));
        std::fs::write(&scene, text).unwrap();
        let r = run_unpaced(&[scene.to_str().unwrap()], &dir.path().join(record), &cache);
        let seg = &r["segments"][0];
        assert_eq!(f(&seg["non_finite_commands"]), 0.0, "{record}: {seg}");
        assert!(
            f(&seg["max_command_n"]) <= f(&seg["device_limit_n"]) + 1e-9,
            "{record}: {seg}"
        );
        // The corpus is not the simulator's tissue (whatever tissue its header names): the
        // report compares these models with no simulated tissue.
        assert!(
            seg["truth_tissue"].is_null() && seg["truth_along"].is_null(),
            "{record}: {seg}"
        );
        assert!(seg["layers"].as_array().unwrap().is_empty(), "{record}: {seg}");
        assert!(
            seg["punctures"]
                .as_array()
                .unwrap()
                .iter()
                .all(|p| p["truth_depth_m"].is_null()),
            "{record}: {seg}"
        );
        // Every layer of the model the trainee's stroke reaches gives, once.
        let model = ModelFile::load(Path::new(r["models"][0]["path"].as_str().unwrap())).unwrap();
        let identify::ModelBody::Phases(p) = &model.body else {
            panic!("{record}: not a phase model")
        };
        let deepest = f(&seg["max_depth_m"]);
        let speed = f(&seg["punctures"][0]["speed_mps"]);
        let reached = p
            .layers
            .iter()
            .filter(|l| l.contact_depth_m + l.threshold.deflection_m(speed) < deepest)
            .count();
        assert!(reached >= 1, "{record}: no layer reached");
        assert_eq!(
            seg["punctures"].as_array().unwrap().len(),
            reached,
            "{record}: {seg}"
        );
    }
}

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

#[test]
fn a_bad_scene_is_a_clear_error() {
    let _shared = untimed();
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("bad.toml");
    let text_ = std::fs::read_to_string(root().join("scenes/needle_liver.toml"))
        .unwrap()
        .replace("puncture = \"needle_liver\"", "puncture = \"kidney\"");
    std::fs::write(&scene, text_).unwrap();
    let o = run(
        &[scene.to_str().unwrap(), "--headless"],
        &dir.path().join("cache"),
    );
    assert!(!o.status.success());
    let e = text(&o);
    assert!(
        e.contains("bad.toml") && e.contains("materials.liver.puncture") && e.contains("kidney"),
        "{e}"
    );
    let o = run(&["--headless", "--device", "replay:"], &dir.path().join("cache"));
    assert!(
        !o.status.success() && text(&o).contains("replay:FILE"),
        "{}",
        text(&o)
    );
}

#[test]
fn the_window_opens_under_xvfb_and_shows_the_needle() {
    let _serial = serial();
    if std::process::Command::new("xvfb-run")
        .arg("--help")
        .output()
        .is_err()
    {
        // `.ci/run` installs Xvfb; without it there is no display to test against.
        eprintln!("xvfb-run not installed: the window test needs it (apt-get install xvfb xauth)");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("report");
    let attempt = || {
        let o = std::process::Command::new("xvfb-run")
            .args([
                "-a",
                "-s",
                "-screen 0 1280x720x24",
                env!("CARGO_BIN_EXE_palpus"),
                "run",
            ])
            .args([
                "--autopilot",
                "--duration",
                "2.5",
                "--report",
                out.to_str().unwrap(),
            ])
            .current_dir(root())
            .env("PALPUS_CACHE_DIR", dir.path().join("cache"))
            .output()
            .unwrap();
        let printed = text(&o);
        assert!(o.status.success(), "{printed}");
        assert!(printed.contains("in a window"), "{printed}");
        report(&out)
    };
    let r = real_time_report(0.02, attempt);
    let shot = render::Image::load_png(&out.join("window.png")).unwrap();
    assert_eq!((shot.width, shot.height), (1280, 720));
    // The scripted trainee pushed the needle into the capsule while the window drew.
    let seg = &r["segments"][0];
    assert!(f(&seg["max_model_force_n"]) > 0.5, "{seg}");
    assert!(f(&seg["rate_error"]) < 0.02, "{seg}");
}

#[test]
fn palpus_render_draws_each_default_scene_and_the_dimple() {
    let _shared = untimed();
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    let render_ = |args: &[&str]| palpus_at_root("render", args, &cache).output().unwrap();
    for scene in ["needle_liver", "surfaces_nakano", "friction_hard_soft"] {
        let out = dir.path().join(format!("{scene}.png"));
        let o = render_(&[
            &format!("scenes/{scene}.toml"),
            "--out",
            out.to_str().unwrap(),
            "--size",
            "320x240",
            "--msaa",
            "1",
        ]);
        assert!(o.status.success(), "{}", text(&o));
        let image = render::Image::load_png(&out).unwrap();
        assert_eq!((image.width, image.height), (320, 240));
        // Something besides the background was drawn.
        let background = image.pixel(0, 0).unwrap();
        let drawn = image.rgba.chunks(4).filter(|p| p[..3] != background[..3]).count();
        assert!(drawn > 320 * 240 / 20, "{scene}: {drawn} pixels drawn");
    }
    let state = dir.path().join("state.json");
    std::fs::write(
        &state,
        r#"{"object": "liver", "tool_position_m": [0, 0, -0.03], "law_state": "capsule_loading"}"#,
    )
    .unwrap();
    let pressed = dir.path().join("pressed.png");
    let o = render_(&[
        "scenes/needle_liver.toml",
        "--out",
        pressed.to_str().unwrap(),
        "--size",
        "320x240",
        "--msaa",
        "1",
        "--state",
        state.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let rest = render::Image::load_png(&dir.path().join("needle_liver.png")).unwrap();
    let pressed = render::Image::load_png(&pressed).unwrap();
    let changed = rest
        .rgba
        .chunks(4)
        .zip(pressed.rgba.chunks(4))
        .filter(|(a, b)| a != b)
        .count();
    assert!(changed > 200, "a 10 mm dimple changed only {changed} pixels");

    std::fs::write(
        &state,
        r#"{"tool_position_m": [0, 0, -0.03], "law_state": "squeezed"}"#,
    )
    .unwrap();
    let o = render_(&[
        "scenes/needle_liver.toml",
        "--out",
        dir.path().join("x.png").to_str().unwrap(),
        "--state",
        state.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    assert!(
        text(&o).contains("state.json") && text(&o).contains("squeezed"),
        "{}",
        text(&o)
    );
}

/// Stops process `pid` (SIGSTOP) for `how_long`, then lets it go on (SIGCONT): every thread of
/// it, the haptic loop and its watchdog included, stalls at once.
fn stall(pid: u32, how_long: std::time::Duration) {
    let signal = |name: &str| {
        let sent = std::process::Command::new("kill")
            .args([name, &pid.to_string()])
            .status();
        assert!(sent.unwrap().success(), "kill {name} {pid}");
    };
    signal("-STOP");
    std::thread::sleep(how_long);
    signal("-CONT");
}

/// `palpus run --headless ARGS` without a display, stalled ([`stall`]) for 2 s once `after`
/// has passed since its first line: that line, the rest of its output, and how it ended.
fn stalled_headless_run(
    args: &[&str],
    cache: &Path,
    after: std::time::Duration,
) -> (String, String, std::process::Output) {
    use std::io::{BufRead, BufReader};
    use std::process::Stdio;
    let mut child = palpus_at_root("run", &[&["--headless"], args].concat(), cache)
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut stdout = BufReader::new(child.stdout.take().unwrap());
    let mut first = String::new();
    stdout.read_line(&mut first).unwrap();
    std::thread::sleep(after);
    stall(child.id(), std::time::Duration::from_secs(2));
    let mut rest = String::new();
    std::io::Read::read_to_string(&mut stdout, &mut rest).unwrap();
    (first, rest, child.wait_with_output().unwrap())
}

#[test]
fn a_part_the_watchdog_ended_ends_the_session_there() {
    let _one = serial();
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    let scene = "scenes/friction_hard_soft.toml";
    // The models are identified and cached first, so that the stop below lands in the loop.
    run_unpaced(&[scene, "--duration", "0.2"], &dir.path().join("warm"), &cache);
    let report_dir = dir.path().join("report");
    // 1.5 s into the first part (the plate), of 4 s.
    let (first, rest, o) = stalled_headless_run(
        &[scene, "--duration", "4", "--report", report_dir.to_str().unwrap()],
        &cache,
        std::time::Duration::from_millis(1500),
    );
    assert!(first.contains("(2 parts)"), "{first}");
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(3), "{first}{rest}{stderr}");
    assert!(
        rest.contains("part `plate` ended early: the session stops after 1 of 2 parts"),
        "{rest}"
    );
    let r = report(&report_dir);
    let segments = r["segments"].as_array().unwrap();
    assert_eq!(segments.len(), 1, "the sponge was not run: {r}");
    assert_eq!(segments[0]["object"], "plate");
}

#[test]
fn a_session_the_watchdog_ended_exits_3_and_names_its_recording() {
    let _one = serial();
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    // The model is identified and cached first, so that the stop below lands in the loop.
    run_unpaced(&["--duration", "0.2"], &dir.path().join("warm"), &cache);
    let target = dir.path().join("session.csv");
    // 2.5 s in, the scripted needle is in the liver, pressing on it.
    let report_dir = dir.path().join("report");
    let (first, rest, o) = stalled_headless_run(
        &[
            "--duration",
            "6",
            "--record",
            target.to_str().unwrap(),
            "--report",
            report_dir.to_str().unwrap(),
        ],
        &cache,
        std::time::Duration::from_millis(2500),
    );
    assert!(first.starts_with("running scene"), "{first}");
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(3), "{first}{rest}{stderr}");
    let partial = format!("{}.partial", target.display());
    assert!(
        stderr.contains("stalled") && stderr.contains(&partial),
        "the error names the stall and the recording: {stderr}"
    );
    assert!(
        !target.exists(),
        "a session that ended early does not stand in for a whole one"
    );
    assert!(Path::new(&partial).exists());
    assert!(
        dir.path().join("report/report.json").exists(),
        "the report is written first"
    );
    // The simulated Omega.7's own watchdog, armed at the software watchdog's period (250 ms
    // for a simulator, held to the 255 × 125 µs an Omega.7's allows), saw the 2 s silence: the
    // report says what the device would have held, and for how long.
    let report: Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("report/report.json")).unwrap()).unwrap();
    let w = &report["segments"][0]["device_watchdog"];
    assert_eq!(w["period_ms"].as_f64(), Some(31.875), "{w}");
    assert!(w["trips"].as_u64().unwrap() >= 1, "{w}");
    assert!(w["longest_silence_ms"].as_f64().unwrap() > 1900.0, "{w}");
    assert!(
        w["held_force_n"].as_f64().unwrap() > 0.05,
        "in tissue, a force was held: {w}"
    );
    assert!(rest.contains("device watchdog armed at 31.875 ms"), "{rest}");
}

#[test]
fn a_loop_benchmark_the_watchdog_ended_exits_3() {
    let _one = serial();
    let child = common::palpus_command()
        .args(["bench", "loop", "--seconds", "4", "--no-realtime"])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(std::time::Duration::from_millis(1500));
    stall(child.id(), std::time::Duration::from_millis(500));
    let o = child.wait_with_output().unwrap();
    let printed = text(&o);
    assert_eq!(o.status.code(), Some(3), "{printed}");
    assert!(
        printed.contains("ended early") && printed.contains("stalled"),
        "{printed}"
    );
}

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
