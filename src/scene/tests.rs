//! The scene format's tests: every key read, checked and named in its errors.

use super::*;

fn default_text() -> String {
    std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join(DEFAULT_SCENE)).unwrap()
}

fn error(text: &str) -> String {
    Scene::parse(text, Path::new("scenes/x.toml"))
        .unwrap_err()
        .to_string()
}

#[test]
fn the_default_scenes_load() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    for name in [
        "needle_liver",
        "needle_liver_smooth",
        "surfaces_nakano",
        "friction_hard_soft",
    ] {
        let scene = Scene::load(&root.join("scenes").join(format!("{name}.toml"))).unwrap();
        assert_eq!(scene.name, name);
        assert!(scene.tool().is_some());
    }
    let needle = Scene::load(&root.join(DEFAULT_SCENE)).unwrap();
    let refs = needle.referenced_models();
    assert_eq!(refs.len(), 1);
    assert_eq!(
        (refs[0].0.as_str(), refs[0].1),
        ("needle_liver", ModelRole::Puncture)
    );
}

#[test]
fn a_goal_names_its_layers_and_every_error_names_its_key() {
    let text = default_text();
    let scene = Scene::parse(&text, Path::new("scenes/x.toml")).unwrap();
    let goal = scene.task.goal().expect("the default scene states a goal");
    assert_eq!(
        (goal.stop_after.as_str(), goal.layer_index("vessel_wall")),
        ("vessel_wall", Some(1))
    );
    let with = |old: &str, new: &str| {
        assert!(text.contains(old), "{old}");
        error(&text.replace(old, new))
    };
    for (old, new, key, says) in [
        (
            "stop_after = \"vessel_wall\"",
            "stop_after = \"kidney\"",
            "task.goal.stop_after",
            "not one of",
        ),
        (
            "layers = [\"capsule\", \"vessel_wall\"]",
            "layers = []",
            "task.goal.layers",
            "name the layers",
        ),
        (
            "layers = [\"capsule\", \"vessel_wall\"]",
            "layers = [\"capsule\", \"capsule\", \"vessel_wall\"]",
            "task.goal.layers[1]",
            "twice",
        ),
        (
            "within_m = 0.003",
            "within_m = 0.0",
            "task.goal.within_m",
            "more than 0",
        ),
        (
            "within_m = 0.003",
            "within_m = 0.003\nmust_not_puncture = [\"capsule\"]",
            "task.goal.must_not_puncture",
            "no attempt could pass",
        ),
        (
            "max_force_n = 4.0",
            "max_force_n = 40.0",
            "task.goal.max_force_n",
            "device's largest force",
        ),
        (
            "time_limit_s = 20.0",
            "time_limit_s = -1.0",
            "task.goal.time_limit_s",
            "positive",
        ),
        (
            "time_limit_s = 20.0",
            "time_limit_s = 20.0\nmode = \"quiz\"",
            "task.goal.mode",
            "neither `guided` nor `exam`",
        ),
        (
            "time_limit_s = 20.0",
            "time_limit_s = 20.0\nlimit = 1",
            "limit",
            "unknown field",
        ),
    ] {
        let e = with(old, new);
        assert!(e.contains(key) && e.contains(says), "{new}: {e}");
    }
    // `--set` replaces values as if the file said them, and is validated the same way.
    let set = |s: &str| s.parse::<SceneOverride>().unwrap();
    let scene = Scene::parse_with(&text, Path::new("scenes/x.toml"), &[set("task.depth_m=0.026")]).unwrap();
    assert!(matches!(scene.task, Task::Insertion { depth_m, .. } if depth_m == 0.026));
    let e = Scene::parse_with(
        &text,
        Path::new("scenes/x.toml"),
        &[set("task.goal.stop_after=\"liver\"")],
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("task.goal.stop_after"), "{e}");
    let e = Scene::parse_with(&text, Path::new("scenes/x.toml"), &[set("name.first=1")])
        .unwrap_err()
        .to_string();
    assert!(e.contains("`name` is not a table"), "{e}");
    for bad in ["depth_m", "=1", "task..depth_m=1", "task.depth_m=nope"] {
        assert!(bad.parse::<SceneOverride>().is_err(), "{bad}");
    }
}

#[test]
fn unreferenced_models_are_not_referenced() {
    let text = default_text().replace(
        "[task]",
        "[models.spare]\nkind = \"hard\"\ncapture = \"nowhere.csv\"\n\n[task]",
    );
    let scene = Scene::parse(&text, Path::new("scenes/x.toml")).unwrap();
    assert!(scene.models.contains_key("spare"));
    assert!(scene.referenced_models().iter().all(|(n, _, _)| n != "spare"));
}

#[test]
fn errors_name_the_file_and_the_key() {
    let text = default_text();
    let e = error(&text.replace("fov_deg = 40.0", "fov_deg = 40.0\nzoom = 2"));
    assert!(e.starts_with("scenes/x.toml:") && e.contains("zoom"), "{e}");
    let e = error(&text.replace("puncture = \"needle_liver\"", "puncture = \"kidney\""));
    assert!(
        e.contains("`materials.liver.puncture`") && e.contains("kidney"),
        "{e}"
    );
    let e = error(&text.replace("kind = \"needle_phases\"", "kind = \"hard\""));
    assert!(
        e.contains("materials.liver.puncture") && e.contains("hard model"),
        "{e}"
    );
    let e = error(&text.replace("rate_hz = 1000.0", "rate_hz = -5.0"));
    assert!(e.contains("`device.rate_hz`"), "{e}");
    let e = error(&text.replace("speed_mps = 0.010", "speed_mps = 0.0"));
    assert!(e.contains("`task.speed_mps`"), "{e}");
    let e = error(&text.replace("material = \"vessel\"", "material = \"bone\""));
    assert!(e.contains("`objects[1].material`") && e.contains("bone"), "{e}");
    let e = error(&text.replace(
        "capture = \"../assets/captures/li_bi/needle_train.csv\"",
        "capture = \"a.csv\"\nfile = \"b.json\"",
    ));
    assert!(
        e.contains("`models.needle_liver.file`") && e.contains("not both"),
        "{e}"
    );
    let e = error(&text.replace("depth_m = 0.030", "depth_m = 0.2"));
    assert!(e.contains("workspace"), "{e}");
    let e = error("name = \"x\"\n[camera]\n");
    assert!(e.contains("missing field"), "{e}");
    let e = error(&text.replace(
        "tool = true",
        "tool = true\n[[objects]]\nname = \"n2\"\nmesh = \"n.glb\"\nmaterial = \"steel\"\ntool = true",
    ));
    assert!(e.contains("at most one object"), "{e}");
}

/// Values that parse but would pin the device at its force limit, or grow memory without
/// bound, are refused at load with the key that carries them.
#[test]
fn implausible_values_are_refused_with_their_key() {
    let needle = default_text();
    let rub =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/friction_hard_soft.toml"))
            .unwrap();
    assert!(needle.contains("virtual_mass_kg = 0.8") && needle.contains("speed_mps = 0.010"));
    assert!(rub.contains("stroke_m = 0.03") && rub.contains("strokes = 4"));
    assert!(rub.contains("contact_stiffness_npm = 300.0"));
    for (text, key) in [
        (
            needle.replace("virtual_mass_kg = 0.8", "virtual_mass_kg = 1e-30"),
            "contact_stiffness_npm`",
        ),
        (
            needle.replace("virtual_mass_kg = 0.8", "virtual_mass_kg = 1e3"),
            "haptics.virtual_mass_kg`",
        ),
        (
            needle.replace("grip_stiffness_npm = 300.0", "grip_stiffness_npm = 1e12"),
            "haptics.grip_stiffness_npm`",
        ),
        (
            needle.replace("virtual_damping_nspm = 4.0", "virtual_damping_nspm = 1e9"),
            "haptics.virtual_damping_nspm`",
        ),
        (
            needle.replacen("speed_mps = 0.010", "speed_mps = 1e6", 1),
            "task.speed_mps`",
        ),
        (needle.replace("hold_s = ", "hold_s = 1e9 #"), "task.hold_s`"),
        (rub.replace("stroke_m = 0.03", "stroke_m = 1e3"), "task.stroke_m`"),
        (
            rub.replace("strokes = 4", "strokes = 4294967295"),
            "task.strokes`",
        ),
        (
            rub.replace("contact_stiffness_npm = 300.0", "contact_stiffness_npm = 1e30"),
            "contact_stiffness_npm`",
        ),
        // The hyperparameter rule of the command line and of trade tables.
        (
            rub.replace("kind = \"soft\"", "kind = \"soft\"\nc = 1e-300"),
            "models.soft_contact.c`: 1e-300: C must be in",
        ),
    ] {
        let e = error(&text);
        assert!(e.starts_with("scenes/x.toml: `") && e.contains(key), "{key}: {e}");
    }
}

#[test]
fn a_recognizer_takes_only_the_settings_its_method_has() {
    let svm =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/surfaces_nakano.toml"))
            .unwrap();
    assert!(svm.contains("method = \"svm\"") && svm.contains("threshold = 0.9"));
    let som = svm.replace("method = \"svm\"", "method = \"som\"");
    for (text, key) in [
        (som.clone(), "recognizer.threshold`"),
        (
            som.replace("threshold = 0.9", "memory_s = 2.0"),
            "recognizer.memory_s`",
        ),
        (
            svm.replace("threshold = 0.9", "threshold = 1.0"),
            "recognizer.threshold`",
        ),
        (
            svm.replace("threshold = 0.9", "threshold = nan"),
            "recognizer.threshold`",
        ),
        (
            svm.replace("threshold = 0.9", "memory_s = 0.0"),
            "recognizer.memory_s`",
        ),
        (
            svm.replace("threshold = 0.9", "window_s = 0.25"),
            "recognizer.window_s`",
        ),
        (
            svm.replace("method = \"svm\"", "method = \"tree\""),
            "recognizer.method`",
        ),
    ] {
        let e = error(&text);
        assert!(e.starts_with("scenes/x.toml: `") && e.contains(key), "{key}: {e}");
    }
    assert!(
        Scene::parse(
            &svm.replace("threshold = 0.9", "threshold = 0.5\nmemory_s = 1.5"),
            Path::new("x.toml")
        )
        .is_ok()
    );
}

#[test]
fn a_scene_name_is_one_plain_path_component() {
    let text = default_text();
    let line = text
        .lines()
        .find(|l| l.starts_with("name = "))
        .unwrap()
        .to_owned();
    for bad in [
        "../../../somewhere",
        "a/b",
        "a\\b",
        ".hidden",
        "",
        "x y",
        &"n".repeat(65),
    ] {
        let e = error(&text.replacen(&line, &format!("name = \"{bad}\""), 1));
        assert!(e.contains("`name`"), "{bad}: {e}");
    }
    for good in ["liver_2", "needle-liver.v2"] {
        let scene = Scene::parse(
            &text.replacen(&line, &format!("name = \"{good}\""), 1),
            Path::new("x.toml"),
        );
        assert_eq!(scene.unwrap().name, good);
    }
}

#[test]
fn paths_resolve_against_the_scene_folder() {
    let scene = Scene::parse(&default_text(), Path::new("/data/scenes/s.toml")).unwrap();
    assert_eq!(
        scene.resolve(Path::new("../a/b.csv")),
        Path::new("/data/scenes/../a/b.csv")
    );
    assert_eq!(scene.resolve(Path::new("/abs.csv")), Path::new("/abs.csv"));
    assert_eq!(
        scene.objects[0].mesh_parts(),
        ("../assets/meshes/liver.glb", Some("liver"))
    );
}
