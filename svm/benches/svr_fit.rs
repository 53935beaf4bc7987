//! ε-SVR fit time on training sets written by `palpus bench svr-scale --dump DIR`.
//!
//! `cargo bench -p svm --bench svr_fit -- DIR/svr_scale_n3000.csv ...` fits each file with the
//! needle's defaults (C = 100, γ = 30, ε = 0.02) and every solver that applies, and prints
//! seconds, iterations, support vectors and the certified gap; without files it fits a
//! synthetic needle-like set of 2000 samples. Ratios against libsvm come from
//! scripts/bench_svr_scale.py, which runs scikit-learn on the same files.
#![allow(clippy::print_stdout, clippy::unwrap_used)]

use std::time::Instant;

use svm::{Kernel, Solver, SvrParams, fit};

/// Inputs (n × 2, row-major) and targets.
type Set = (Vec<f64>, Vec<f64>);

fn read(path: &str) -> Set {
    let text = std::fs::read_to_string(path).unwrap();
    let (mut x, mut y) = (Vec::new(), Vec::new());
    for line in text.lines().skip(1) {
        let v: Vec<f64> = line.split(',').map(|s| s.parse().unwrap()).collect();
        x.extend([v[0], v[1]]);
        y.push(v[2]);
    }
    (x, y)
}

/// A needle-like curve: force rising with depth, a fall at a puncture, a velocity term, noise
/// from a fixed linear congruential sequence.
fn synthetic(n: usize) -> Set {
    let mut rng = capture::rng::SplitMix64::new(12345u64);
    let mut noise = move || rng.next_f64() - 0.5;
    let (mut x, mut y) = (Vec::new(), Vec::new());
    for k in 0..n {
        let d = k as f64 / n as f64;
        let v = (k % 5) as f64 / 4.0;
        let puncture = if d > 0.4 { -0.5 } else { 0.0 };
        x.extend([d, v]);
        y.push(3.0 * d * d + 0.3 * v + puncture + 0.1 * noise());
    }
    (x, y)
}

fn main() {
    let files: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with("--"))
        .collect();
    let sets: Vec<(String, Set)> = if files.is_empty() {
        vec![("synthetic n=2000".into(), synthetic(2000))]
    } else {
        files.iter().map(|f| (f.clone(), read(f))).collect()
    };
    for (name, (x, y)) in &sets {
        for solver in [Solver::Smo, Solver::InteriorPoint] {
            if solver == Solver::InteriorPoint && y.len() > SvrParams::DENSE_LIMIT {
                continue;
            }
            let params = SvrParams::builder()
                .c(100.0)
                .epsilon(0.02)
                .kernel(Kernel::Rbf { gamma: 30.0 })
                .solver(solver)
                .time_budget(std::time::Duration::from_secs(600))
                .build()
                .unwrap();
            let t = Instant::now();
            match fit(&params, x, 2, y) {
                Ok(f) => println!(
                    "{name}: n {} {:>24} {:.4} s, {} iterations, {} SVs, gap {:.2e}",
                    y.len(),
                    f.solver,
                    t.elapsed().as_secs_f64(),
                    f.iterations,
                    f.model.coefficients.len(),
                    f.relative_gap()
                ),
                Err(e) => println!("{name}: n {} {solver:?} failed: {e}", y.len()),
            }
        }
    }
}
