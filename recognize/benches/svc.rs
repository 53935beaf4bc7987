//! C-SVC training against scikit-learn's `SVC` (libsvm) on the same vectors, in one run.
//!
//! Builds the exact vectors `palpus recognize train --method svm --features nakano` fits its SVC
//! on (the windows of the captures in `PALPUS_SVC_BENCH_CAPTURES`, scaled as the recognizer
//! scales them), writes them to a CSV, has `recognize/fixtures/bench_svc.py` time scikit-learn's
//! SVC with the same kernel, C, tolerance and probabilities, times [`Svc::fit`] on the same
//! vectors here (on all cores and on one), and prints the ratios. Then, for each run left out
//! in turn, both libraries are fitted on the other runs and their decisions on the left-out
//! run's vectors compared: predictions, accuracy, signs and size of the pairwise decision values.
//!
//! ```text
//! palpus gen --out /tmp/gen1 --only nakano
//! PALPUS_SVC_BENCH_CAPTURES=/tmp/gen1/nakano cargo bench -p recognize --bench svc
//! ```
//!
//! Settings (environment): `PALPUS_SVC_BENCH_C` (10), `PALPUS_SVC_BENCH_HOP_S` (0.02),
//! `PALPUS_SVC_BENCH_TRAIN_WINDOW_S` (1; 3,927 vectors from the generator's seed-1 Nakano set),
//! `PALPUS_SVC_BENCH_REPEATS` (5; the best time of each is compared), `PYTHON` (`python3`,
//! with numpy and scikit-learn). Timings are wall-clock seconds, so run it on an idle machine.

#![allow(clippy::print_stdout)] // the timings and agreement are this bench's report

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode};
use std::time::Instant;

use recognize::TrainingVectors;
use recognize::{FeatureSet, LabelledCapture, Method, Svc, SvcParams, SvmTrainer, TrainSettings};
use svm::Kernel;

fn env_or<T: std::str::FromStr>(name: &str, default: T) -> Result<T, String> {
    match std::env::var(name) {
        Ok(v) => v.parse().map_err(|_| format!("{name}={v} is not a valid value")),
        Err(_) => Ok(default),
    }
}

fn main() -> ExitCode {
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("svc bench: {e}");
            ExitCode::FAILURE
        }
    }
}

fn run() -> Result<(), String> {
    let Ok(dir) = std::env::var("PALPUS_SVC_BENCH_CAPTURES") else {
        eprintln!(
            "svc bench: set PALPUS_SVC_BENCH_CAPTURES to a folder of Nakano captures, e.g. after \
             `palpus gen --out /tmp/gen1 --only nakano`, PALPUS_SVC_BENCH_CAPTURES=/tmp/gen1/nakano; \
             nothing measured"
        );
        return Ok(());
    };
    let c: f64 = env_or("PALPUS_SVC_BENCH_C", 10.0)?;
    let hop_s: f64 = env_or("PALPUS_SVC_BENCH_HOP_S", 0.02)?;
    let train_window_s: f64 = env_or("PALPUS_SVC_BENCH_TRAIN_WINDOW_S", 1.0)?;
    let repeats: usize = env_or("PALPUS_SVC_BENCH_REPEATS", 5)?;
    let python = std::env::var("PYTHON").unwrap_or_else(|_| "python3".into());

    let captures = read_captures(Path::new(&dir))?;
    let settings = TrainSettings {
        features: FeatureSet::Nakano,
        hop_s,
        train_window_s: Some(train_window_s),
        ..TrainSettings::new(Method::Svm)
    };
    let (vectors, params) = SvmTrainer
        .window_vectors(&captures, &settings, c)
        .map_err(|e| e.to_string())?;
    let Kernel::Polynomial { gamma, coef0, degree } = params.kernel else {
        return Err(format!(
            "the window SVC's kernel is {}, not polynomial",
            params.kernel.name()
        ));
    };
    let (n, dim, k) = (vectors.x.len(), vectors.x[0].len(), vectors.classes.len());
    println!(
        "{n} vectors of {dim} features, {k} classes, from {} captures in {dir}; C = {c}, \
         ({gamma} a·b + {coef0})^{degree}, tolerance {}",
        captures.len(),
        params.tolerance
    );

    let csv = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("svc_bench_vectors.csv");
    write_vectors(&csv, &vectors)?;
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/bench_svc.py");
    let output = Command::new(&python)
        .arg(&script)
        .arg(&csv)
        .args(["--c", &c.to_string(), "--gamma", &gamma.to_string()])
        .args(["--coef0", &coef0.to_string(), "--degree", &degree.to_string()])
        .args([
            "--tol",
            &params.tolerance.to_string(),
            "--repeats",
            &repeats.to_string(),
        ])
        .output()
        .map_err(|e| format!("cannot run {python} {}: {e}", script.display()))?;
    if !output.status.success() {
        return Err(format!(
            "{python} {} failed: {}",
            script.display(),
            String::from_utf8_lossy(&output.stderr)
        ));
    }
    let theirs: serde_json::Value =
        serde_json::from_slice(&output.stdout).map_err(|e| format!("reading scikit-learn's results: {e}"))?;
    let best_of = |key: &str| -> Result<f64, String> {
        theirs["seconds"][key]
            .as_array()
            .and_then(|v| v.iter().filter_map(serde_json::Value::as_f64).reduce(f64::min))
            .ok_or_else(|| format!("no scikit-learn timing `{key}`"))
    };

    let all_cores = rayon::current_num_threads();
    let one_core = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .map_err(|e| e.to_string())?;
    println!("\nfit on all {n} vectors, best of {repeats} (wall-clock s; ratio = ours / scikit-learn's):");
    for probability in [true, false] {
        let p = SvcParams {
            probability,
            ..params
        };
        let sk = best_of(if probability { "probability" } else { "votes" })?;
        let ours = best_time(repeats, || fit(p, &vectors))?;
        let ours_1 = one_core.install(|| best_time(repeats, || fit(p, &vectors)))?;
        println!(
            "  {:<28} scikit-learn {sk:8.3}   ours ({all_cores} threads) {ours:8.3} (×{:.2})   ours (1 thread) {ours_1:8.3} (×{:.2})",
            if probability {
                "probability=True:"
            } else {
                "probability=False (votes):"
            },
            ours / sk,
            ours_1 / sk
        );
    }

    compare_held_out(&vectors, params, &theirs)
}

/// The `rubbing` captures (`*.csv`) of `dir`, in name order.
fn read_captures(dir: &Path) -> Result<Vec<LabelledCapture>, String> {
    let mut paths: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(|e| format!("{}: {e}", dir.display()))?
        .filter_map(|entry| entry.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "csv") && !p.ends_with("MANIFEST.csv"))
        .collect();
    paths.sort();
    if paths.is_empty() {
        return Err(format!("no captures (*.csv) in {}", dir.display()));
    }
    paths
        .iter()
        .map(|p| LabelledCapture::read(p).map_err(|e| e.to_string()))
        .collect()
}

fn write_vectors(path: &Path, v: &TrainingVectors) -> Result<(), String> {
    let dim = v.x[0].len();
    let mut out = String::from("group,label");
    for f in 0..dim {
        let _ = write!(out, ",f{f}");
    }
    out.push('\n');
    for ((x, y), g) in v.x.iter().zip(&v.y).zip(&v.groups) {
        let _ = write!(out, "{g},{y}");
        for value in x {
            // Shortest round-trip form: Python reads back the same doubles.
            let _ = write!(out, ",{value:?}");
        }
        out.push('\n');
    }
    std::fs::write(path, out).map_err(|e| format!("{}: {e}", path.display()))
}

fn fit(params: SvcParams, v: &TrainingVectors) -> Result<Svc, String> {
    Svc::fit(params, &v.x, &v.y, v.classes.len()).map_err(|e| e.to_string())
}

fn best_time(repeats: usize, mut f: impl FnMut() -> Result<Svc, String>) -> Result<f64, String> {
    let mut best = f64::INFINITY;
    for _ in 0..repeats.max(1) {
        let started = Instant::now();
        std::hint::black_box(f()?);
        best = best.min(started.elapsed().as_secs_f64());
    }
    Ok(best)
}

/// Both libraries fitted without one group (run) and asked about its vectors.
fn compare_held_out(
    v: &TrainingVectors,
    params: SvcParams,
    theirs: &serde_json::Value,
) -> Result<(), String> {
    let held_out = theirs["held_out"]
        .as_array()
        .ok_or("no held-out results from scikit-learn")?;
    println!("\nheld-out decisions (fit on the other runs, probabilities off):");
    let params = SvcParams {
        probability: false,
        ..params
    };
    let (mut total, mut same, mut ours_right, mut theirs_right, mut signs, mut pairs) = (0, 0, 0, 0, 0, 0);
    let mut worst: f64 = 0.0;
    for fold in held_out {
        let group = fold["group"]
            .as_u64()
            .ok_or("a held-out fold without its group")?;
        let (train, test): (Vec<usize>, Vec<usize>) = (0..v.x.len()).partition(|&t| v.groups[t] != group);
        let tx: Vec<&[f64]> = train.iter().map(|&t| v.x[t].as_slice()).collect();
        let ty: Vec<usize> = train.iter().map(|&t| v.y[t]).collect();
        let svc = Svc::fit(params, &tx, &ty, v.classes.len()).map_err(|e| e.to_string())?;
        let predicted = fold["predicted"].as_array().ok_or("no predictions")?;
        let decisions = fold["decision"].as_array().ok_or("no decision values")?;
        if predicted.len() != test.len() || decisions.len() != test.len() {
            return Err(format!(
                "group {group}: scikit-learn answered for another number of vectors"
            ));
        }
        let (mut g_same, mut g_ours, mut g_theirs) = (0, 0, 0);
        for ((&t, p), d) in test.iter().zip(predicted).zip(decisions) {
            let ours = svc.predict(&v.x[t]).map_err(|e| e.to_string())?;
            let their = p.as_u64().ok_or("a prediction that is not a class")? as usize;
            g_same += usize::from(ours == their);
            g_ours += usize::from(ours == v.y[t]);
            g_theirs += usize::from(their == v.y[t]);
            let dec = svc.decision_values(&v.x[t]).map_err(|e| e.to_string())?;
            for (a, b) in dec.iter().zip(d.as_array().ok_or("decision values")?) {
                let b = b.as_f64().ok_or("a decision value that is not a number")?;
                signs += usize::from((*a > 0.0) == (b > 0.0));
                pairs += 1;
                worst = worst.max((a - b).abs());
            }
        }
        println!(
            "  run {group} held out: {} vectors, predictions agree {g_same} ({:.2} %), accuracy ours {:.2} %, scikit-learn {:.2} %",
            test.len(),
            100.0 * g_same as f64 / test.len() as f64,
            100.0 * g_ours as f64 / test.len() as f64,
            100.0 * g_theirs as f64 / test.len() as f64
        );
        total += test.len();
        same += g_same;
        ours_right += g_ours;
        theirs_right += g_theirs;
    }
    if total == 0 {
        return Err("no group could be held out (every class needs vectors in two runs)".into());
    }
    println!(
        "  all: {total} vectors, predictions agree {:.2} %, accuracy ours {:.2} %, scikit-learn {:.2} %; \
         pairwise decision signs agree {:.3} % of {pairs}, largest |difference| {worst:.2e} \
         (both stop at a KKT violation of {})",
        100.0 * same as f64 / total as f64,
        100.0 * ours_right as f64 / total as f64,
        100.0 * theirs_right as f64 / total as f64,
        100.0 * signs as f64 / pairs.max(1) as f64,
        params.tolerance
    );
    Ok(())
}
