//! A scene's model budget: `[models.NAME.budget]` picks C, ε, γ and the training size from the
//! trade `palpus bench trade` measured on the scene's own capture, the cheapest point that meets
//! the budget, and says which in the run report; a table measured on another capture, of
//! another model, or with no point within the budget is a typed error naming the table.
#![allow(clippy::unwrap_used)]

use crate::common;
use std::path::{Path, PathBuf};

use capture::sha256_hex;
use identify::{ModelKind, SearchPoint};
use palpus::models::{self, ModelError, ResolvedModel, Sources};
use palpus::scene::Scene;
use palpus::trade::{TradeRow, TradeTable, pareto_front};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn capture() -> PathBuf {
    root().join("assets/captures/li_bi/needle_train.csv")
}

/// A measured point (only its time, AISE and hyperparameters matter to the choice).
fn point(n: usize, gamma: f64, epsilon: f64, time_ns: f64, aise: f64) -> TradeRow {
    TradeRow {
        n,
        tol: None,
        max_sv: None,
        point: SearchPoint {
            c: 100.0,
            epsilon,
            gamma: Some(gamma),
            cv_aise: aise,
            n_sv: 50.0,
            fit_seconds: 0.01,
            predict_ns: time_ns,
            failed: None,
        },
        held_out: None,
        on_front: false,
    }
}

/// Writes a needle trade table over `capture_bytes` to `dir/trade.csv`.
fn write_table(dir: &Path, model: ModelKind, capture_bytes: &[u8]) -> PathBuf {
    let mut rows = vec![
        point(120, 30.0, 0.02, 400.0, 0.020),
        point(150, 100.0, 0.05, 600.0, 0.011),
        point(200, 100.0, 0.02, 900.0, 0.009),
    ];
    let front = pareto_front(&rows);
    rows.iter_mut().zip(front).for_each(|(r, f)| r.on_front = f);
    let path = dir.join("trade.csv");
    TradeTable {
        model,
        capture_sha256: sha256_hex(capture_bytes),
        rows,
    }
    .write(&path)
    .unwrap();
    path
}

/// The smooth-needle scene with its needle model given `budget` (TOML lines) instead of the
/// defaults, written to `dir`.
fn scene_with_budget(dir: &Path, budget: &str) -> PathBuf {
    let text = common::without_budgets(
        &std::fs::read_to_string(root().join("scenes/needle_liver_smooth.toml")).unwrap(),
    );
    let capture_line = "capture = \"../assets/captures/li_bi/needle_train.csv\"";
    assert!(
        text.contains(capture_line),
        "the smooth scene's needle capture moved"
    );
    let text = text
        .replace(
            capture_line,
            &format!("{capture_line}\n\n[models.needle_liver.budget]\n{budget}\n"),
        )
        .replace("\"../", &format!("\"{}/", root().display()));
    let path = dir.join("scene.toml");
    std::fs::write(&path, text).unwrap();
    path
}

fn resolve(scene: &Path, cache: &Path) -> Result<Vec<ResolvedModel>, ModelError> {
    models::resolve(
        &Scene::load(scene).unwrap(),
        cache,
        &mut Sources::default(),
        &mut |_| {},
    )
}

#[test]
fn the_budget_picks_the_cheapest_measured_point_and_the_model_is_fitted_with_it() {
    let dir = tempfile::tempdir().unwrap();
    let table = write_table(
        dir.path(),
        ModelKind::NeedlePuncture,
        &std::fs::read(capture()).unwrap(),
    );
    let front = format!("front = {:?}", table.to_str().unwrap());
    let scene = scene_with_budget(
        dir.path(),
        &format!("{front}\nmax_predict_ns = 1000\nmax_aise = 0.0115"),
    );
    let resolved = resolve(&scene, &dir.path().join("cache")).unwrap();
    let needle = resolved.iter().find(|m| m.name == "needle_liver").unwrap();
    let choice = needle.budget.as_ref().expect("a budget choice");
    // 600 ns at 0.011 is the cheapest of the two points within the budget.
    assert_eq!((choice.n, choice.gamma, choice.epsilon), (150, Some(100.0), 0.05));
    assert_eq!((choice.within, choice.measured), (2, 3));
    assert_eq!(choice.predict_ns, 600.0);
    // The model was identified with the chosen hyperparameters and training size.
    let svr = &needle.model.hyperparameters.svrs[0];
    assert_eq!((svr.c, svr.epsilon), (100.0, 0.05));
    assert!(format!("{:?}", svr.kernel).contains("100"), "{:?}", svr.kernel);
    assert!(needle.model.n_train <= 150, "{}", needle.model.n_train);
    let text = choice.to_string();
    assert!(
        text.contains("max_predict_ns = 1000") && text.contains("the cheapest of 2 of 3 points"),
        "{text}"
    );

    // Without a time limit the cheapest accurate enough; without an accuracy limit the fastest.
    for (budget, gamma, epsilon) in [
        ("max_aise = 0.01", 100.0, 0.02),
        ("max_predict_ns = 500", 30.0, 0.02),
    ] {
        let scene = scene_with_budget(dir.path(), &format!("{front}\n{budget}"));
        let resolved = resolve(&scene, &dir.path().join("cache")).unwrap();
        let choice = resolved[0].budget.as_ref().unwrap();
        assert_eq!((choice.gamma, choice.epsilon), (Some(gamma), epsilon), "{budget}");
    }
}

#[test]
fn a_point_measured_with_a_support_vector_budget_is_fitted_within_it() {
    let dir = tempfile::tempdir().unwrap();
    let bytes = std::fs::read(capture()).unwrap();
    let mut budgeted = point(350, 30.0, 0.02, 300.0, 0.012);
    budgeted.max_sv = Some(40);
    budgeted.tol = Some(1e-8);
    let mut rows = vec![point(350, 30.0, 0.02, 900.0, 0.010), budgeted];
    let front = pareto_front(&rows);
    rows.iter_mut().zip(front).for_each(|(r, f)| r.on_front = f);
    let table = dir.path().join("trade.csv");
    TradeTable {
        model: ModelKind::NeedlePuncture,
        capture_sha256: sha256_hex(&bytes),
        rows,
    }
    .write(&table)
    .unwrap();
    let scene = scene_with_budget(
        dir.path(),
        &format!("front = {:?}\nmax_aise = 0.0125", table.to_str().unwrap()),
    );
    let cache = dir.path().join("cache");
    let resolved = resolve(&scene, &cache).unwrap();
    let choice = resolved[0].budget.as_ref().unwrap();
    assert_eq!((choice.max_sv, choice.tol), (Some(40), Some(1e-8)));
    assert!(
        choice
            .to_string()
            .contains("tolerance 1e-8, at most 40 support vectors"),
        "{choice}"
    );
    let identify::ModelBody::Single(svr) = &resolved[0].model.body else {
        panic!("a needle model has one SVR");
    };
    assert_eq!(svr.svr.n_sv(), 40);
    // The unbudgeted point is cached apart: a tighter budget picks it and fits it anew.
    let scene = scene_with_budget(
        dir.path(),
        &format!("front = {:?}\nmax_aise = 0.011", table.to_str().unwrap()),
    );
    let resolved = resolve(&scene, &cache).unwrap();
    let identify::ModelBody::Single(svr) = &resolved[0].model.body else {
        panic!("a needle model has one SVR");
    };
    assert!(svr.svr.n_sv() > 40, "{}", svr.svr.n_sv());
    assert!(matches!(resolved[0].origin, models::Origin::Identified { .. }));
}

#[test]
fn a_table_that_does_not_fit_the_scene_or_the_budget_is_an_error_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    let bytes = std::fs::read(capture()).unwrap();
    let expect = |table: &Path, budget: &str, want: &str| {
        let front = format!("front = {:?}", table.to_str().unwrap());
        let scene = scene_with_budget(dir.path(), &format!("{front}\n{budget}"));
        let e = resolve(&scene, &cache).expect_err(want);
        let text = e.to_string();
        assert!(matches!(e, ModelError::Budget { .. }), "{text}");
        assert!(text.contains("trade.csv") && text.contains(want), "{text}");
    };
    let other_capture = write_table(dir.path(), ModelKind::NeedlePuncture, b"another capture");
    expect(&other_capture, "max_aise = 0.05", "measured on another capture");
    let hard = write_table(dir.path(), ModelKind::HardFriction, &bytes);
    expect(
        &hard,
        "max_aise = 0.05",
        "it measured a hard model, the scene's is needle",
    );
    let table = write_table(dir.path(), ModelKind::NeedlePuncture, &bytes);
    expect(
        &table,
        "max_predict_ns = 500\nmax_aise = 0.01",
        "none of the 3 measured points meets max_predict_ns = 500 and max_aise = 1e-2 N²: the fastest takes 400 ns",
    );
    std::fs::write(&table, "n,c\n1,2\n").unwrap();
    expect(&table, "max_aise = 0.05", "line 1: not a trade table");
    // No file at all names the file too.
    let e = resolve(
        &scene_with_budget(dir.path(), "front = \"nowhere.csv\"\nmax_aise = 0.05"),
        &cache,
    )
    .expect_err("missing");
    assert!(e.to_string().contains("nowhere.csv"), "{e}");
}

#[test]
fn a_budget_beside_given_hyperparameters_or_without_limits_is_refused_at_load() {
    let dir = tempfile::tempdir().unwrap();
    for (budget, extra, want) in [
        ("front = \"t.csv\"", "", "give max_predict_ns, max_aise or both"),
        ("front = \"t.csv\"\nmax_aise = -1", "", "budget.max_aise"),
        (
            "front = \"t.csv\"\nmax_aise = 0.01",
            "c = 100.0",
            "models.needle_liver.c",
        ),
        (
            "front = \"t.csv\"\nmax_aise = 0.01",
            "max_samples = 500",
            "models.needle_liver.max_samples",
        ),
        ("front = \"t.csv\"\nmax_aise = 0.01\nspeed = 1", "", "speed"),
    ] {
        let text = std::fs::read_to_string(scene_with_budget(dir.path(), budget)).unwrap();
        let text = text.replace(
            "[models.needle_liver]\n",
            &format!("[models.needle_liver]\n{extra}\n"),
        );
        let e = Scene::parse(&text, &dir.path().join("scene.toml")).expect_err(want);
        assert!(e.to_string().contains(want), "{want}: {e}");
    }
}

/// `palpus bench trade` writes the table a scene's budget reads, and `palpus run` reports the
/// choice.
#[test]
fn bench_trade_writes_the_table_a_scene_budget_picks_from_and_run_reports_it() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("trade");
    let capture = capture();
    common::succeeds(&[
        "bench",
        "trade",
        capture.to_str().unwrap(),
        "--model",
        "needle",
        "--test",
        root()
            .join("assets/captures/li_bi/needle_test.csv")
            .to_str()
            .unwrap(),
        "--grid",
        "c=100,gamma=30..100:2,epsilon=0.02",
        "--sizes",
        "120",
        "--max-svs",
        "20",
        "--out",
        out.to_str().unwrap(),
    ]);
    let table = out.join("trade.csv");
    let parsed = TradeTable::parse(&std::fs::read(&table).unwrap(), &table).unwrap();
    assert_eq!(
        parsed.capture_sha256,
        sha256_hex(&std::fs::read(&capture).unwrap())
    );
    // Two grid points, each without a budget and within 20 support vectors.
    assert_eq!(parsed.rows.len(), 4);
    for r in &parsed.rows {
        let h = r.held_out.expect("measured on the test capture");
        assert!(h.predict_f32_ns > 0.0 && h.predict_ns > 0.0, "{h:?}");
        if r.max_sv == Some(20) {
            assert!(r.point.n_sv <= 20.0, "{}", r.point.n_sv);
        } else {
            assert_eq!(r.max_sv, None);
            assert!(r.point.n_sv > 20.0, "{}", r.point.n_sv);
        }
    }
    let front = format!("front = {:?}", table.to_str().unwrap());
    let scene = scene_with_budget(dir.path(), &format!("{front}\nmax_aise = 1.0"));
    let fastest = parsed
        .rows
        .iter()
        .min_by(|a, b| a.time_ns().total_cmp(&b.time_ns()))
        .unwrap();
    let report = dir.path().join("report");
    let printed = common::text(&common::succeeds(&[
        "run",
        scene.to_str().unwrap(),
        "--headless",
        "--duration",
        "0.2",
        "--cache-dir",
        dir.path().join("cache").to_str().unwrap(),
        "--report",
        report.to_str().unwrap(),
    ]));
    let gamma = fastest.point.gamma.unwrap();
    let budget = fastest
        .max_sv
        .map_or(String::new(), |k| format!(", at most {k} support vectors"));
    assert!(
        printed.contains(&format!(
            "chosen for max_aise = 1e0 N²: n 120, C 1e2, ε 2e-2, γ {gamma:e}{budget}, measured"
        )) && printed.contains("the cheapest of 4 of 4 points"),
        "{printed}"
    );
}
