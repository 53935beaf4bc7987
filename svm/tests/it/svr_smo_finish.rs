//! The ε-SVR's SMO with its exact finish reaches the interior point's certified optimum on the
//! needle fixture (scikit-learn's data, C = 100): same objective, same predictions.
#![allow(clippy::unwrap_used)]

use serde_json::Value;
use svm::{ACCEPT_GAP, Kernel, Solver, SvrParams, fit};

use crate::common::floats;

#[test]
fn smo_and_the_interior_point_agree_on_the_needle() {
    let f: Value = serde_json::from_str(include_str!("../../fixtures/svr_needle_c1e2.json")).unwrap();
    let (x, y) = (floats(&f["x"]), floats(&f["y"]));
    let dim = f["dim"].as_u64().unwrap() as usize;
    let params = |solver| {
        SvrParams::builder()
            .c(f["c"].as_f64().unwrap())
            .epsilon(f["epsilon"].as_f64().unwrap())
            .kernel(Kernel::Rbf {
                gamma: f["gamma"].as_f64().unwrap(),
            })
            .solver(solver)
            .build()
            .unwrap()
    };
    let smo = fit(&params(Solver::Smo), &x, dim, &y).unwrap();
    let ipm = fit(&params(Solver::InteriorPoint), &x, dim, &y).unwrap();
    assert!(smo.solver.starts_with("SMO"), "{}", smo.solver);
    assert!(smo.relative_gap() <= ACCEPT_GAP, "{}", smo.relative_gap());
    let scale = ipm.primal_objective.abs().max(1.0);
    assert!(
        (smo.primal_objective - ipm.primal_objective).abs() <= 2.0 * ACCEPT_GAP * scale,
        "{} vs {}",
        smo.primal_objective,
        ipm.primal_objective
    );
    // Two certified optima of the same problem predict alike (the fit is unique up to the
    // gap; 1e-3 N is far above what the gap allows and far below the needle's forces).
    let worst = x
        .chunks_exact(dim)
        .map(|r| (smo.model.predict(r) - ipm.model.predict(r)).abs())
        .fold(0.0f64, f64::max);
    assert!(worst < 1e-3, "predictions differ by {worst}");
}
