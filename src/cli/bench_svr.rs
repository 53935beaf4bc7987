//! `palpus bench svr`: ε-SVR fit time against libsvm on the committed fixtures.

use std::time::Instant;

use clap::Args;
use serde_json::Value;
use svm::{Kernel, Solver, SvrParams, fit};

use crate::scale_sets::{ScaleSource, Table};

/// The fixtures with libsvm timings (made by svm/fixtures/make_svr_fixtures.py on this
/// project's development machine: scikit-learn's libsvm at tol 1e-3, its default, and 1e-9).
const FIXTURES: [&str; 3] = [
    include_str!("../../svm/fixtures/svr_needle_c1e2.json"),
    include_str!("../../svm/fixtures/svr_needle_c1e3.json"),
    include_str!("../../svm/fixtures/svr_needle_c1e4.json"),
];

/// Time ε-SVR fits on needle-like problems (n = 350, C = 1e2, 1e3, 1e4) against libsvm.
///
/// libsvm's times and objectives were recorded by svm/fixtures/make_svr_fixtures.py
/// (scikit-learn 1.9.1); rerun that script on the machine you benchmark on for ratios that
/// compare like with like. Our time is the median of --repeats fits with the interior point;
/// the objective columns show both reach the same optimum (ours is certified by its duality
/// gap; libsvm's stops at its tolerance).
#[derive(Debug, Args)]
pub(crate) struct SvrArgs {
    /// Fits per problem (median reported).
    #[arg(long, default_value_t = 5)]
    repeats: usize,
    /// Also time SMO (slow at large C, as libsvm).
    #[arg(long)]
    smo: bool,
}

fn floats(v: &Value) -> Vec<f64> {
    v.as_array()
        .map(|a| a.iter().filter_map(Value::as_f64).collect())
        .unwrap_or_default()
}

/// What repeated fits of one problem measured.
struct TimedFit {
    /// Median wall-clock seconds of one fit.
    median_s: f64,
    /// Dual objective of the last fit.
    dual_objective: f64,
}

fn median_fit(
    params: &SvrParams,
    x: &[f64],
    dim: usize,
    y: &[f64],
    repeats: usize,
) -> anyhow::Result<TimedFit> {
    let mut times = Vec::new();
    let mut objective = f64::NAN;
    for _ in 0..repeats.max(1) {
        let t = Instant::now();
        let f = fit(params, x, dim, y)?;
        times.push(t.elapsed().as_secs_f64());
        objective = f.dual_objective;
    }
    times.sort_by(f64::total_cmp);
    Ok(TimedFit {
        median_s: times[times.len() / 2],
        dual_objective: objective,
    })
}

pub(crate) fn run(args: &SvrArgs) -> anyhow::Result<()> {
    println!(
        "{:<14} {:>4} {:>7} {:>5} {:>5} | {:>9} {:>11} | {:>9} {:>7} | {:>9} {:>7} | {:>15}",
        "problem",
        "n",
        "C",
        "γ",
        "ε",
        "ours [s]",
        "solver",
        "libsvm¹",
        "ratio",
        "libsvm²",
        "ratio",
        "ours − libsvm²"
    );
    for text in FIXTURES {
        let f: Value = serde_json::from_str(text)?;
        let (x, y) = (floats(&f["x"]), floats(&f["y"]));
        let dim = f["dim"].as_u64().unwrap_or(1) as usize;
        let (c, gamma, epsilon) = (
            f["c"].as_f64().unwrap_or(1.0),
            f["gamma"].as_f64().unwrap_or(1.0),
            f["epsilon"].as_f64().unwrap_or(0.1),
        );
        let name = f["name"].as_str().unwrap_or("?");
        let lib_default = f["libsvm_default_tol"]["fit_seconds"]
            .as_f64()
            .unwrap_or(f64::NAN);
        let lib_tight = f["libsvm"]["fit_seconds"].as_f64().unwrap_or(f64::NAN);
        let lib_obj = f["libsvm"]["dual_objective"].as_f64().unwrap_or(f64::NAN);
        let mut solvers = vec![Solver::InteriorPoint];
        if args.smo {
            solvers.push(Solver::Smo);
        }
        for solver in solvers {
            let params = SvrParams::builder()
                .c(c)
                .epsilon(epsilon)
                .kernel(Kernel::Rbf { gamma })
                .solver(solver)
                .build()?;
            let TimedFit {
                median_s: ours,
                dual_objective: objective,
            } = match median_fit(&params, &x, dim, &y, args.repeats) {
                Ok(r) => r,
                Err(e) => {
                    println!(
                        "{name:<14} {:>4} {c:>7.0e} {gamma:>5} {epsilon:>5} | {solver:?}: {e}",
                        y.len()
                    );
                    continue;
                }
            };
            println!(
                "{name:<14} {:>4} {c:>7.0e} {gamma:>5} {epsilon:>5} | {ours:>9.4} {:>11} | {lib_default:>9.3} {:>6.1}× | {lib_tight:>9.3} {:>6.1}× | {:>+15.3e}",
                y.len(),
                if solver == Solver::Smo {
                    "SMO"
                } else {
                    "interior pt"
                },
                lib_default / ours,
                lib_tight / ours,
                (objective - lib_obj) / lib_obj.abs(),
            );
        }
    }
    println!("¹ scikit-learn/libsvm at its default tol = 1e-3   ² at tol = 1e-9 (converged objective)");
    println!("negative last column: our objective is lower (better) than libsvm's converged one");
    Ok(())
}

/// Time the needle's ε-SVR fit at growing n on one insertion capture (or a regression table).
///
/// Picks `n` in-tissue samples spread evenly over the capture and scales them to the unit box,
/// as `palpus identify --model needle --max-samples n` does, then fits with the needle's
/// defaults (C = 100, γ = 30, ε = 0.02 N unless given); with `--data`, the table's first n rows.
/// Prints, per size: the fit's seconds, solver, iterations, support vectors, relative duality
/// gap and the process's peak resident memory so far. With `--dump DIR` it also writes each
/// training set and our predictions on it (`DIR/svr_scale_nN.csv` for size N: x0, x1, …, y, ours), from
/// which scripts/bench_svr_scale.py fits scikit-learn's libsvm on the same samples. Run one size
/// per process for per-size memory.
#[derive(Debug, Args)]
pub(crate) struct SvrScaleArgs {
    /// Insertion capture to train on (e.g. li_bi/needle_train.csv from `palpus gen`).
    #[arg(
        long,
        value_name = "CSV",
        required_unless_present = "data",
        conflicts_with = "data"
    )]
    capture: Option<std::path::PathBuf>,
    /// A regression problem instead of a capture: a CSV with a header, the inputs in every
    /// column but the last and the target in the last (e.g. Friedman #1 from
    /// scripts/friedman1.py). Its first n rows are fitted, inputs min-max scaled.
    #[arg(long, value_name = "CSV")]
    data: Option<std::path::PathBuf>,
    /// Training-set sizes (comma-separated; a size above the capture's in-tissue samples takes
    /// them all).
    #[arg(long, value_delimiter = ',', default_value = "350,1000,3000")]
    sizes: Vec<usize>,
    /// C.
    #[arg(long, default_value_t = 100.0)]
    c: f64,
    /// RBF γ on the scaled inputs.
    #[arg(long, default_value_t = 30.0)]
    gamma: f64,
    /// ε, N.
    #[arg(long, default_value_t = 0.02)]
    epsilon: f64,
    /// Solver: auto, smo, ipm or low-rank.
    #[arg(long, default_value = "auto")]
    solver: String,
    /// Fit time budget, s.
    #[arg(long, default_value_t = 600.0)]
    budget_s: f64,
    /// Write each training set with our predictions into this folder.
    #[arg(long, value_name = "DIR")]
    dump: Option<std::path::PathBuf>,
}

/// Peak resident memory of this process so far, bytes (Linux: VmHWM; `None` elsewhere).
fn peak_rss_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

pub(crate) fn run_scale(args: &SvrScaleArgs) -> anyhow::Result<()> {
    let solver = match args.solver.as_str() {
        "auto" => Solver::Auto,
        "smo" => Solver::Smo,
        "ipm" => Solver::InteriorPoint,
        "low-rank" => Solver::LowRank,
        other => anyhow::bail!("--solver {other}: expected auto, smo, ipm or low-rank"),
    };
    let source = match (&args.capture, &args.data) {
        (Some(path), _) => ScaleSource::Capture(capture::Capture::read_file(
            path,
            capture::CaptureKind::Insertion,
        )?),
        (None, Some(path)) => ScaleSource::Table(Table::read(path)?),
        (None, None) => anyhow::bail!("give --capture or --data"),
    };
    let params = SvrParams::builder()
        .c(args.c)
        .epsilon(args.epsilon)
        .kernel(Kernel::Rbf { gamma: args.gamma })
        .solver(solver)
        .time_budget(std::time::Duration::from_secs_f64(args.budget_s))
        .build()?;
    if let Some(dir) = &args.dump {
        std::fs::create_dir_all(dir)?;
    }
    let threads = rayon::current_num_threads();
    println!("{threads} solver thread{}", if threads == 1 { "" } else { "s" });
    println!(
        "{:>7} {:>9} {:>24} {:>10} {:>7} {:>9} {:>9}",
        "n", "ours [s]", "solver", "iterations", "SVs", "rel. gap", "peak MB"
    );
    for &n in &args.sizes {
        let (x, dim, y) = source.first(n)?;
        let f = fit(&params, &x, dim, &y)?;
        let peak = peak_rss_bytes().map_or(f64::NAN, |b| b as f64 / 1e6);
        println!(
            "{:>7} {:>9.4} {:>24} {:>10} {:>7} {:>9.2e} {:>9.1}",
            y.len(),
            f.fit_seconds,
            f.solver,
            f.iterations,
            f.model.coefficients.len(),
            f.relative_gap(),
            peak
        );
        if let Some(dir) = &args.dump {
            use std::io::Write;
            let path = dir.join(format!("svr_scale_n{}.csv", y.len()));
            let mut out = std::io::BufWriter::new(std::fs::File::create(&path)?);
            let names: Vec<String> = (0..dim).map(|k| format!("x{k}")).collect();
            writeln!(out, "{},y,ours", names.join(","))?;
            for (r, yi) in x.chunks_exact(dim).zip(&y) {
                let inputs: Vec<String> = r.iter().map(|v| format!("{v:?}")).collect();
                writeln!(out, "{},{yi:?},{:?}", inputs.join(","), f.model.predict(r))?;
            }
            out.flush()?;
        }
    }
    Ok(())
}
