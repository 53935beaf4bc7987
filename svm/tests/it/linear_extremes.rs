//! The linear-kernel ε-SVR at the extremes against exact optima: C from 1e-6 to 1e15, ε from 0
//! to 1, one sample to 3000, duplicated inputs, constant targets, inputs of magnitude 1e6, and
//! the hard-contact captures of `palpus gen --seed 7` and of the committed Li & Bi capture.
//!
//! The references (`svm/fixtures/linear_extremes.json`) were computed once by
//! `svm/fixtures/make_linear_extremes.py`: exact rational minimisation of the primal, checked
//! against scipy's HiGHS LP (lexicographic) for C ≥ 1e11. Every case must return a model —
//! the linear path is exact, so none may be refused — whose w is the optimum's, whose b lies in
//! the optimal interval, and whose certificate brackets the exact optimal value.

#![allow(clippy::unwrap_used)] // A failed unwrap is a failed test.

use std::collections::HashMap;

use serde_json::Value;
use svm::{ACCEPT_GAP, Kernel, SvrParams, fit};

use crate::common::floats;

struct Case {
    dataset: String,
    c: f64,
    epsilon: f64,
    w: f64,
    b_lo: f64,
    b_hi: f64,
    objective: f64,
    highs_w: Option<f64>,
}

/// Each data set's inputs and targets, by name.
type Datasets = HashMap<String, (Vec<f64>, Vec<f64>)>;

fn load() -> (Datasets, Vec<Case>) {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/fixtures/linear_extremes.json");
    let json: Value = serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    let datasets = json["datasets"]
        .as_object()
        .unwrap()
        .iter()
        .map(|(k, v)| (k.clone(), (floats(&v["x"]), floats(&v["y"]))))
        .collect();
    let cases = json["cases"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| Case {
            dataset: c["dataset"].as_str().unwrap().to_owned(),
            c: c["c"].as_f64().unwrap(),
            epsilon: c["epsilon"].as_f64().unwrap(),
            w: c["w"].as_f64().unwrap(),
            b_lo: c["b_lo"].as_f64().unwrap(),
            b_hi: c["b_hi"].as_f64().unwrap(),
            objective: c["objective"].as_f64().unwrap(),
            highs_w: c.get("highs_w").and_then(Value::as_f64),
        })
        .collect();
    (datasets, cases)
}

/// One case: the fit, checked against its reference; returns a line for the failure report.
fn check(x: &[f64], y: &[f64], case: &Case) -> Result<(), String> {
    let ctx = format!(
        "{} n {} C {:e} ε {:e}",
        case.dataset,
        y.len(),
        case.c,
        case.epsilon
    );
    let params = SvrParams::builder()
        .c(case.c)
        .epsilon(case.epsilon)
        .kernel(Kernel::Linear)
        .build()
        .unwrap();
    let fitted = fit(&params, x, 1, y).map_err(|e| format!("{ctx}: {e}"))?;
    let w = fitted.model.linear_weights().unwrap()[0];
    let b = fitted.model.bias;
    let (p, d) = (fitted.primal_objective, fitted.dual_objective);
    let best = case.objective;
    if ![w, b, p, d, fitted.relative_gap()].iter().all(|v| v.is_finite()) {
        return Err(format!("{ctx}: non-finite w {w} b {b} P {p} D {d}"));
    }
    if (w - case.w).abs() > 1e-9 * case.w.abs().max(1.0) {
        return Err(format!("{ctx}: w {w} vs exact {}", case.w));
    }
    let x_max = x.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let b_tol = 1e-9 * (1.0 + b.abs() + case.w.abs() * x_max);
    if b < case.b_lo - b_tol || b > case.b_hi + b_tol {
        return Err(format!(
            "{ctx}: b {b} outside the optimal [{}, {}]",
            case.b_lo, case.b_hi
        ));
    }
    let slack = 1e-12 * best.abs().max(1.0);
    if -d > best + slack || best > p + slack {
        return Err(format!("{ctx}: −D {} ≤ P* {best} ≤ P {p} fails", -d));
    }
    if p - best > fitted.relative_gap() * p.abs().max(1.0) + fitted.resolution + slack {
        return Err(format!(
            "{ctx}: P − P* = {} beyond gap {} and resolution {}",
            p - best,
            fitted.relative_gap(),
            fitted.resolution
        ));
    }
    if fitted.relative_gap() > ACCEPT_GAP {
        return Err(format!("{ctx}: accepted with gap {}", fitted.relative_gap()));
    }
    if let Some(w_lp) = case.highs_w
        && (w - w_lp).abs() > 1e-6 * w_lp.abs().max(1.0)
    {
        return Err(format!("{ctx}: w {w} vs HiGHS {w_lp}"));
    }
    Ok(())
}

#[test]
fn every_extreme_case_is_the_exact_optimum() {
    let (datasets, cases) = load();
    assert!(cases.len() > 300, "{} cases", cases.len());
    let failures: Vec<String> = cases
        .iter()
        .filter_map(|case| {
            let (x, y) = &datasets[&case.dataset];
            check(x, y, case).err()
        })
        .collect();
    assert!(
        failures.is_empty(),
        "{} of {} failed:\n{}",
        failures.len(),
        cases.len(),
        failures.join("\n")
    );
}

/// The 3 × 3 table of extremes on the seed-7 hard contact: C ∈ {1e11, 1e13, 1e15} ×
/// ε ∈ {0, 1e-4, 0.0294} N, all exact (before: errors at C = 1e11, silently wrong w beyond).
#[test]
fn the_hard_contact_table_is_exact_in_all_nine_cells() {
    let (datasets, cases) = load();
    let (x, y) = &datasets["gen7_hard_contact"];
    let mut cells = 0;
    for case in cases.iter().filter(|c| {
        c.dataset == "gen7_hard_contact" && c.c >= 1e11 && [0.0, 1e-4, 0.0294].contains(&c.epsilon)
    }) {
        check(x, y, case).unwrap();
        cells += 1;
    }
    assert_eq!(cells, 9);
}

/// A limit is a typed error that names the certified gap of where the solver stopped, never a
/// model and never an unknown gap.
#[test]
fn a_linear_fit_stopped_by_its_iteration_limit_reports_the_gap_it_reached() {
    let (datasets, _) = load();
    let (x, y) = &datasets["line_n350"];
    let params = SvrParams::builder()
        .c(1e11)
        .epsilon(1e-4)
        .kernel(Kernel::Linear)
        .max_iterations(3)
        .build()
        .unwrap();
    match fit(&params, x, 1, y) {
        Err(svm::SvmError::NotConverged { iterations, gap, .. }) => {
            assert_eq!(iterations, 3);
            assert!(gap.is_finite() && gap > ACCEPT_GAP, "gap {gap}");
        }
        other => panic!("expected the iteration limit, got {other:?}"),
    }
}
