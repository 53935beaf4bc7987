//! The default needle scene: in real time, both of the liver's layers felt, a recorded session
//! re-identified, models from real-world-shaped records, and a bad scene's error.

use super::*;

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
    // At the nominal rate within 1 %.
    let r = real_time_report(0.01, attempt);
    let seg = &r["segments"][0];
    // Three seconds at 1 kHz.
    assert!((f(&seg["duration_s"]) - 3.0).abs() < 0.01, "{seg}");
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
