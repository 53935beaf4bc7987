//! The ε-SVR against libsvm (through scikit-learn) on committed fixtures: the same problems,
//! the same dual objective to 1e-6 relative. `svm/fixtures/make_svr_fixtures.py` made them.

#![allow(clippy::unwrap_used)] // A failed unwrap is a failed test.

use std::path::Path;

use serde_json::Value;
use svm::{Kernel, Solver, SvrParams, fit};

use crate::common::floats;

fn fixtures() -> Vec<Value> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures");
    let mut out: Vec<Value> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| {
            p.file_name().unwrap().to_string_lossy().starts_with("svr_")
                && p.extension().is_some_and(|e| e == "json")
        })
        .map(|p| serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap())
        .collect();
    out.sort_by_key(|v| v["name"].as_str().unwrap().to_owned());
    out
}

/// A fixture's data and hyperparameters, for `solver`.
fn problem(f: &Value, solver: Solver) -> (Vec<f64>, Vec<f64>, usize, SvrParams) {
    let params = SvrParams::builder()
        .c(f["c"].as_f64().unwrap())
        .epsilon(f["epsilon"].as_f64().unwrap())
        .kernel(Kernel::Rbf {
            gamma: f["gamma"].as_f64().unwrap(),
        })
        .solver(solver)
        .build()
        .unwrap();
    (
        floats(&f["x"]),
        floats(&f["y"]),
        f["dim"].as_u64().unwrap() as usize,
        params,
    )
}

#[test]
fn dual_objective_equals_libsvm_on_every_fixture() {
    let all = fixtures();
    assert!(
        all.len() >= 6,
        "fixtures missing: run svm/fixtures/make_svr_fixtures.py"
    );
    for f in all {
        let name = f["name"].as_str().unwrap();
        let (x, y, dim, params) = problem(&f, Solver::InteriorPoint);
        let ours = fit(&params, &x, dim, &y).unwrap();
        let reference = f["libsvm"]["dual_objective"].as_f64().unwrap();
        let relative = (ours.dual_objective - reference).abs() / reference.abs();
        println!(
            "{name}: ours {:.12e} libsvm {reference:.12e} rel {relative:.1e}; SVs {} vs {}; {} iterations, polished {}",
            ours.dual_objective,
            ours.model.n_sv(),
            f["libsvm"]["n_sv"],
            ours.iterations,
            ours.polished
        );
        // Equal to libsvm's, or lower with a duality gap that proves ours optimal (libsvm at
        // tol 1e-9 still stops 2e-6 short on the C = 1e3 needle problem).
        let certified_better = ours.dual_objective < reference && ours.polished && ours.relative_gap() < 1e-9;
        assert!(
            relative < 1e-6 || certified_better,
            "{name}: {} vs {reference}",
            ours.dual_objective
        );
        assert!(
            ours.dual_objective <= reference + 1e-9 * reference.abs(),
            "{name}: worse than libsvm"
        );
        assert!(ours.relative_gap() < 1e-6, "{name}: gap {}", ours.relative_gap());
        // Predictions agree where both models are accurate.
        if relative >= 1e-6 {
            continue;
        }
        let support = f["libsvm"]["support"].as_array().unwrap();
        let coef = floats(&f["libsvm"]["dual_coef"]);
        let b_ref = f["libsvm"]["intercept"].as_f64().unwrap();
        let gamma = f["gamma"].as_f64().unwrap();
        for probe in 0..y.len().min(20) {
            let xp = &x[probe * dim..(probe + 1) * dim];
            let reference: f64 = support
                .iter()
                .zip(&coef)
                .map(|(i, c)| {
                    let i = i.as_u64().unwrap() as usize;
                    let d2: f64 = x[i * dim..(i + 1) * dim]
                        .iter()
                        .zip(xp)
                        .map(|(a, b)| (a - b) * (a - b))
                        .sum();
                    c * (-gamma * d2).exp()
                })
                .sum::<f64>()
                + b_ref;
            let scale = 1.0 + y.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            assert!(
                (ours.model.predict(xp) - reference).abs() < 1e-4 * scale,
                "{name} sample {probe}"
            );
        }
    }
}

#[test]
fn smo_reaches_the_same_objective_on_the_small_fixtures() {
    for f in fixtures()
        .into_iter()
        .filter(|f| f["c"].as_f64().unwrap() <= 100.0)
    {
        let name = f["name"].as_str().unwrap();
        let (x, y, dim, params) = problem(&f, Solver::Smo);
        let ours = fit(&params, &x, dim, &y).unwrap_or_else(|e| panic!("{name}: {e}"));
        let reference = f["libsvm"]["dual_objective"].as_f64().unwrap();
        let relative = (ours.dual_objective - reference).abs() / reference.abs();
        println!(
            "{name}: SMO {:.12e} libsvm {reference:.12e} rel {relative:.1e}, {} iterations",
            ours.dual_objective, ours.iterations
        );
        assert!(relative < 1e-6, "{name}: {} vs {reference}", ours.dual_objective);
    }
}
