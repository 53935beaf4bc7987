//! Corrupted and absurd model files: a real needle model, identified here from the committed
//! generated capture, mutated one field at a time. Every reader refuses each mutation with the
//! file and the field named; what passes the file's own checks but would exceed the device's
//! force limit is refused where `run` and `render` load models, with the peak named.
#![allow(clippy::unwrap_used)]

use crate::common;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use capture::{Capture, CaptureKind};
use identify::{IdentifyOptions, ModelFile, ModelKind, identify};
use palpus::models::{self, ModelError, Sources};
use palpus::scene::Scene;
use serde_json::{Value, json};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The needle model identified from the Li & Bi training capture, as JSON (identified once).
fn needle_model() -> &'static Value {
    static MODEL: OnceLock<Value> = OnceLock::new();
    MODEL.get_or_init(|| {
        let train = Capture::read_file(
            root().join("assets/captures/li_bi/needle_train.csv"),
            CaptureKind::Insertion,
        )
        .unwrap();
        let model = identify(&train, None, &IdentifyOptions::new(ModelKind::NeedlePuncture))
            .unwrap()
            .model;
        serde_json::to_value(model).unwrap()
    })
}

/// The needle model with `edit` applied.
fn mutated(edit: impl FnOnce(&mut Value)) -> Value {
    let mut v = needle_model().clone();
    edit(&mut v);
    v
}

/// The model's one scaled SVR (the body's fields, beside its `structure` tag).
fn svr(v: &mut Value) -> &mut Value {
    &mut v["body"]
}

/// Loads `model` as the file `needle.json`; the error's text on failure.
fn load(model: &Value) -> Result<ModelFile, String> {
    let bytes = serde_json::to_vec(model).unwrap();
    ModelFile::from_slice(&bytes, Path::new("dir/needle.json")).map_err(|e| e.to_string())
}

/// Asserts that loading `model` fails naming the file and `field`.
fn refused(what: &str, model: &Value, field: &str) {
    let e = load(model).expect_err(what);
    assert!(e.contains("needle.json") && e.contains(field), "{what}: {e}");
}

/// Every mutation of (a) that the file's own checks refuse.
fn implausible() -> Vec<(&'static str, Value, &'static str)> {
    let mut out = vec![
        (
            "bias 1e300",
            mutated(|v| svr(v)["svr"]["bias"] = json!(1e300)),
            "svr.bias",
        ),
        (
            "coefficient 1e39",
            mutated(|v| svr(v)["svr"]["coefficients"][0] = json!(1e39)),
            "svr.coefficients[0]",
        ),
        (
            "support vector 1e39",
            mutated(|v| svr(v)["svr"]["support_vectors"][1] = json!(-1e39)),
            "svr.support_vectors[1]",
        ),
        (
            "input scale −0.5",
            mutated(|v| svr(v)["scaling"]["scale"][0] = json!(-0.5)),
            "scaling.scale[0]",
        ),
        (
            "input scale 1e-300",
            mutated(|v| svr(v)["scaling"]["scale"][1] = json!(1e-300)),
            "scaling.scale[1]",
        ),
        (
            "input scale 1e300",
            mutated(|v| svr(v)["scaling"]["scale"][1] = json!(1e300)),
            "scaling.scale[1]",
        ),
        (
            "input offset 1e300",
            mutated(|v| svr(v)["scaling"]["offset"][0] = json!(1e300)),
            "scaling.offset[0]",
        ),
        (
            "input range ±1e308",
            mutated(|v| v["input_range"][0] = json!([-1e308, 1e308])),
            "input_range[0]",
        ),
        (
            "input range a point",
            mutated(|v| v["input_range"][1] = json!([0.01, 0.01])),
            "input_range[1]",
        ),
        (
            "input range reversed",
            mutated(|v| v["input_range"][0] = json!([0.03, 0.0])),
            "input_range[0]",
        ),
        (
            "γ 1e-300",
            mutated(|v| svr(v)["svr"]["kernel"]["gamma"] = json!(1e-300)),
            "svr.kernel.gamma",
        ),
        (
            "γ 0",
            mutated(|v| svr(v)["svr"]["kernel"]["gamma"] = json!(0.0)),
            "svr.kernel.gamma",
        ),
        (
            "γ −30",
            mutated(|v| svr(v)["svr"]["kernel"]["gamma"] = json!(-30.0)),
            "svr.kernel.gamma",
        ),
        (
            "γ 1e300",
            mutated(|v| svr(v)["svr"]["kernel"]["gamma"] = json!(1e300)),
            "svr.kernel.gamma",
        ),
        (
            "training AISE −1",
            mutated(|v| v["train_metrics"]["aise"] = json!(-1.0)),
            "train_metrics.aise",
        ),
    ];
    for scale in [1e300, -1e300, 0.0, -1.0, 1e-300] {
        out.push((
            "output scale",
            mutated(|v| svr(v)["output_scale"] = json!(scale)),
            "output_scale",
        ));
    }
    let n = identify::Plausibility::MAX_SUPPORT_VECTORS + 1;
    out.push((
        "too many support vectors",
        mutated(|v| {
            svr(v)["svr"]["coefficients"] = json!(vec![0.0; n]);
            svr(v)["svr"]["support_vectors"] = json!(vec![0.5; 2 * n]);
        }),
        "svr.coefficients",
    ));
    out
}

#[test]
fn the_identified_model_loads_and_every_implausible_mutation_is_refused_naming_file_and_field() {
    load(needle_model()).unwrap();
    for (what, model, field) in implausible() {
        refused(what, &model, field);
    }
    // A metric of null, as a fit whose metrics overflowed used to write.
    let null = mutated(|v| v["train_metrics"]["aise"] = Value::Null);
    assert!(load(&null).unwrap_err().contains("needle.json"));
}

/// The smooth-needle scene with its model read from `file`.
fn scene_with_model(file: &Path) -> Scene {
    let mut scene = Scene::load(&root().join("scenes/needle_liver_smooth.toml")).unwrap();
    if let Some(m) = scene.models.get_mut("needle_liver") {
        m.capture = None;
        m.file = Some(file.to_owned());
    }
    scene
}

/// Writes `model` to `dir/name` and resolves the default scene's models from it.
fn resolve(dir: &Path, name: &str, model: &Value) -> Result<Vec<models::ResolvedModel>, ModelError> {
    let path = dir.join(name);
    std::fs::write(&path, serde_json::to_vec_pretty(model).unwrap()).unwrap();
    models::resolve(
        &scene_with_model(&path),
        &dir.join("cache"),
        &mut Sources::default(),
        &mut |_| {},
    )
}

#[test]
fn a_model_stronger_than_the_device_is_refused_at_load_naming_file_part_and_place() {
    let dir = tempfile::tempdir().unwrap();
    let resolved = resolve(dir.path(), "needle.json", needle_model()).unwrap();
    assert_eq!(resolved[0].model.kind, ModelKind::NeedlePuncture);
    let strong = [
        ("bias 1e6", mutated(|v| svr(v)["svr"]["bias"] = json!(1e6))),
        ("bias −50", mutated(|v| svr(v)["svr"]["bias"] = json!(-50.0))),
        (
            "coefficients 1e6",
            mutated(|v| {
                for c in svr(v)["svr"]["coefficients"].as_array_mut().unwrap() {
                    *c = json!(1e6);
                }
            }),
        ),
        (
            "coefficients 1e38",
            mutated(|v| {
                for c in svr(v)["svr"]["coefficients"].as_array_mut().unwrap() {
                    *c = json!(1e38);
                }
            }),
        ),
        (
            "output scale 1e6",
            mutated(|v| svr(v)["output_scale"] = json!(1e6)),
        ),
    ];
    for (what, model) in strong {
        load(&model).unwrap_or_else(|e| panic!("{what} passes the file's own checks: {e}"));
        let e = resolve(dir.path(), "strong.json", &model).expect_err(what);
        let text = e.to_string();
        assert!(matches!(e, ModelError::Unsafe { .. }), "{what}: {text}");
        assert!(
            text.contains("strong.json") && text.contains("12 N"),
            "{what}: {text}"
        );
    }
    // The implausible ones are refused by the same load, the file named.
    for (what, model, field) in implausible() {
        let e = resolve(dir.path(), "absurd.json", &model)
            .expect_err(what)
            .to_string();
        assert!(e.contains("absurd.json") && e.contains(field), "{what}: {e}");
    }
}

#[test]
fn the_force_check_proves_the_bound_for_the_device_it_runs_on() {
    let model: ModelFile = serde_json::from_value(needle_model().clone()).unwrap();
    let omega7 = haptics::DeviceSpecs::OMEGA7;
    let bound = model
        .certify(&identify::DeviceEnvelope {
            max_force_n: omega7.max_force_n,
            stroke_m: 2.0 * omega7.workspace_radius_m,
        })
        .unwrap()
        .bound_n;
    assert!(bound > 0.5 && bound < 12.0, "{bound}");
    models::check_renderable("needle", Path::new("needle.json"), &model, &omega7).unwrap();
    // A device that gives less than the model's largest force (a 2-D grid finds at least that
    // much) cannot render it, and the refusal names the file and the part.
    let [d, v] = [model.input_range[0], model.input_range[1]];
    let at = |r: [f64; 2], k: usize| r[0] + (r[1] - r[0]) * k as f64 / 32.0;
    let peak = (0..=32)
        .flat_map(|i| (0..=32).map(move |j| (i, j)))
        .map(|(i, j)| model.predict(&[at(d, i), at(v, j)]).abs())
        .fold(0.0, f64::max);
    let weak = haptics::DeviceSpecs {
        max_force_n: 0.99 * peak,
        ..omega7
    };
    let e = models::check_renderable("needle", Path::new("needle.json"), &model, &weak).unwrap_err();
    assert!(
        e.to_string().contains("needle.json") && e.to_string().contains("body.single"),
        "{e}"
    );
}

/// The smooth-needle scene's text with its model read from `model` and every relative path
/// made absolute, written to `dir`.
fn scene_file(dir: &Path, model: &Path) -> PathBuf {
    let text = std::fs::read_to_string(root().join("scenes/needle_liver_smooth.toml")).unwrap();
    let text = common::without_budgets(&text)
        .replace(
            "capture = \"../assets/captures/li_bi/needle_train.csv\"",
            &format!("file = {:?}", model.to_str().unwrap()),
        )
        .replace("\"../", &format!("\"{}/", root().display()));
    let path = dir.join("scene.toml");
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn run_and_render_refuse_a_corrupted_model_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    let cache = cache.to_str().unwrap();
    for (name, model) in [
        ("bias.json", mutated(|v| svr(v)["svr"]["bias"] = json!(1e6))),
        (
            "gamma.json",
            mutated(|v| svr(v)["svr"]["kernel"]["gamma"] = json!(-1.0)),
        ),
    ] {
        let path = dir.path().join(name);
        std::fs::write(&path, serde_json::to_vec_pretty(&model).unwrap()).unwrap();
        let scene = scene_file(dir.path(), &path);
        let scene = scene.to_str().unwrap();
        let out = dir.path().join("frame.png");
        for args in [
            vec![
                "run",
                scene,
                "--headless",
                "--duration",
                "0.1",
                "--cache-dir",
                cache,
            ],
            vec![
                "render",
                scene,
                "--out",
                out.to_str().unwrap(),
                "--cache-dir",
                cache,
            ],
        ] {
            let e = common::fails(&args);
            assert!(e.contains(name), "{args:?}: {e}");
        }
    }
}
