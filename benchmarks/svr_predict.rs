//! Cost of one ε-SVR prediction as the haptic loop makes it: an RBF model with 100 support
//! vectors on [depth, velocity] (the needle model's size in Li & Bi: 98 SVs), raw SI inputs.
//!
//! Variants, all from the same model:
//! * `plain_f64`: scale the input, then `SvrModel::predict` (the general path);
//! * `exact_f64`: `ExactSvr<2>` (folded scaling, SoA blocks, libm `exp`);
//! * `fast_f32`: `FastSvr<2>` (the same in `f32` with the polynomial `fast_exp2`).
//!
//! Run with `cargo bench -p benchmarks --bench svr_predict`. After criterion's own report, the
//! median time per evaluation of each variant and its speed-up over `plain_f64` are printed,
//! read back from criterion's estimates of this run.

use std::hint::black_box;
use std::path::PathBuf;

use criterion::Criterion;
use svm::{ExactSvr, FastSvr, InputScaling, SvrModel, needle_like_model};

const GROUP: &str = "svr_predict_rbf_100sv_2d";
const VARIANTS: [&str; 3] = ["plain_f64", "exact_f64", "fast_f32"];

/// 100 support vectors spread over the unit box of the scaled inputs (depth 0–30 mm, velocity
/// ±10 mm/s), γ = 10, coefficients within ±C = 100: the size and shape of a needle model.
fn model() -> (SvrModel, InputScaling) {
    needle_like_model(10.0, 100.0)
}

/// A stream of raw inputs along an insertion, so no call sees a constant.
fn inputs() -> Vec<[f64; 2]> {
    (0..64)
        .map(|i| {
            let s = i as f64 / 63.0;
            [0.03 * s, 0.01 * (6.0 * s).sin()]
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let (model, scaling) = model();
    let exact = ExactSvr::<2>::new(&model, &scaling).expect("a valid model");
    let fast = FastSvr::<2>::new(&model, &scaling).expect("a valid model");
    let xs = inputs();
    let mut group = c.benchmark_group(GROUP);
    group.bench_function(VARIANTS[0], |b| {
        let mut i = 0;
        let mut scaled = [0.0; 2];
        b.iter(|| {
            i = (i + 1) & 63;
            scaling.apply_into(black_box(&xs[i]), &mut scaled);
            black_box(model.predict(&scaled))
        })
    });
    group.bench_function(VARIANTS[1], |b| {
        let mut i = 0;
        b.iter(|| {
            i = (i + 1) & 63;
            black_box(exact.eval(black_box(&xs[i])))
        })
    });
    group.bench_function(VARIANTS[2], |b| {
        let mut i = 0;
        b.iter(|| {
            i = (i + 1) & 63;
            black_box(fast.eval(black_box(&xs[i])))
        })
    });
    group.finish();
}

/// Where criterion writes its estimates: `$CRITERION_HOME`, else `<target dir>/criterion`.
fn criterion_dir() -> Option<PathBuf> {
    if let Some(home) = std::env::var_os("CRITERION_HOME") {
        return Some(PathBuf::from(home));
    }
    if let Some(target) = std::env::var_os("CARGO_TARGET_DIR") {
        return Some(PathBuf::from(target).join("criterion"));
    }
    // The bench binary is <target>/<profile>/deps/predict-<hash>.
    let exe = std::env::current_exe().ok()?;
    Some(exe.parent()?.parent()?.parent()?.join("criterion"))
}

fn median_ns(dir: &std::path::Path, variant: &str) -> Option<f64> {
    let path = dir.join(GROUP).join(variant).join("new").join("estimates.json");
    let text = std::fs::read_to_string(path).ok()?;
    let json: serde_json::Value = serde_json::from_str(&text).ok()?;
    json["median"]["point_estimate"].as_f64()
}

#[allow(clippy::print_stdout)]
fn report_ratios() {
    let Some(dir) = criterion_dir() else { return };
    let times: Vec<Option<f64>> = VARIANTS.iter().map(|v| median_ns(&dir, v)).collect();
    let Some(plain) = times[0] else {
        println!("(no estimates under {} to compare)", dir.display());
        return;
    };
    println!("\n{GROUP}: median ns per evaluation, speed-up over plain_f64");
    for (variant, time) in VARIANTS.iter().zip(&times) {
        match time {
            Some(t) => println!("  {variant:<10} {t:>9.1} ns   ×{:.2}", plain / t),
            None => println!("  {variant:<10} (not run)"),
        }
    }
}

fn main() {
    let mut c = Criterion::default().configure_from_args();
    bench(&mut c);
    c.final_summary();
    // `cargo bench` passes --bench; without it (cargo test) criterion only smoke-runs each
    // benchmark and writes no estimates, so there is nothing of this run to compare.
    if std::env::args().any(|a| a == "--bench") {
        report_ratios();
    }
}
