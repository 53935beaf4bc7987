//! Running the `palpus` binary from chain tests, and finding the captures it generates.
// Each test binary uses some of these, none all of them.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use recognize::{LabelledCapture, RecognizerFile, SequentialParams, SequentialState, SequentialStep};

/// The trainees' history every test's `palpus run` adds its scored attempts to, instead of
/// the user's own.
pub const HISTORY: &str = concat!(env!("CARGO_TARGET_TMPDIR"), "/history.sqlite");

/// The `palpus` binary, its scored attempts going to [`HISTORY`].
pub fn palpus_command() -> Command {
    let mut command = Command::new(env!("CARGO_BIN_EXE_palpus"));
    command.env("PALPUS_HISTORY", HISTORY);
    command
}

/// Runs `palpus ARGS` without a vendor library configured in the environment.
pub fn palpus(args: &[&str]) -> Output {
    palpus_command()
        .args(args)
        .env_remove("PALPUS_DHD_LIBRARY")
        .output()
        .expect("the palpus binary runs")
}

/// `o`, which must be a success (else the test fails, showing what it printed).
pub fn success(o: Output) -> Output {
    assert!(o.status.success(), "{}", text(&o));
    o
}

/// Runs `palpus ARGS`, which must succeed.
pub fn succeeds(args: &[&str]) -> Output {
    success(palpus(args))
}

/// Runs `palpus ARGS`, which must succeed, and reads what it printed as JSON.
pub fn json(args: &[&str]) -> serde_json::Value {
    serde_json::from_slice(&succeeds(args).stdout).expect("json")
}

/// Runs `palpus ARGS`, which must fail; returns what it printed.
pub fn fails(args: &[&str]) -> String {
    let o = palpus(args);
    assert!(!o.status.success(), "{args:?} succeeded");
    text(&o)
}

/// `f` of every item, in order, run on as many threads as the machine has cores. For a test
/// that is a chain of independent `palpus` runs: the test harness runs one test binary at a
/// time, so a binary with one long test otherwise keeps a single core busy.
pub fn parallel_map<T: Sync, R: Send>(items: &[T], f: impl Fn(&T) -> R + Sync) -> Vec<R> {
    use std::sync::atomic::{AtomicUsize, Ordering};
    let workers = std::thread::available_parallelism()
        .map_or(1, usize::from)
        .min(items.len())
        .max(1);
    let next = AtomicUsize::new(0);
    let mut done: Vec<(usize, R)> = std::thread::scope(|s| {
        let handles: Vec<_> = (0..workers)
            .map(|_| {
                s.spawn(|| {
                    let mut done = Vec::new();
                    loop {
                        let i = next.fetch_add(1, Ordering::Relaxed);
                        let Some(item) = items.get(i) else {
                            break done;
                        };
                        done.push((i, f(item)));
                    }
                })
            })
            .collect();
        handles
            .into_iter()
            .flat_map(|h| h.join().unwrap_or_else(|panic| std::panic::resume_unwind(panic)))
            .collect()
    });
    done.sort_by_key(|&(i, _)| i);
    done.into_iter().map(|(_, r)| r).collect()
}

/// Everything it printed, stdout then stderr.
pub fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

/// The 21 rubbing captures (7 surfaces × 3 runs) that `palpus gen --only nakano` writes under
/// `dir`, sorted by name.
pub fn nakano_captures(dir: &Path) -> Vec<PathBuf> {
    let mut paths: Vec<PathBuf> = std::fs::read_dir(dir.join("nakano"))
        .expect("nakano folder")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "csv"))
        .collect();
    paths.sort();
    assert_eq!(paths.len(), 21);
    paths
}

/// Trains an SVM over Nakano's windows on `train` with `extra` options into `dir/name`
/// (`palpus recognize train … --method svm --features nakano`), and returns the model's path.
pub fn train_nakano_svm(dir: &Path, name: &str, train: &[String], extra: &[&str]) -> String {
    train_svm(dir, name, "nakano", train, extra)
}

/// Trains an SVM over windows of `features` on `train` with `extra` options into `dir/name`
/// (`palpus recognize train … --method svm --features F`), and returns the model's path.
pub fn train_svm<S: AsRef<str>>(
    dir: &Path,
    name: &str,
    features: &str,
    train: &[S],
    extra: &[&str],
) -> String {
    let out = dir.join(name).to_string_lossy().into_owned();
    let mut args = vec![
        "recognize",
        "train",
        "--method",
        "svm",
        "--features",
        features,
        "--out",
        &out,
    ];
    args.extend_from_slice(extra);
    args.extend(train.iter().map(AsRef::as_ref));
    succeeds(&args);
    out
}

/// One trial of the logs that `palpus gen --only multistream` writes under `dir`: its surface
/// (`mat07`), trial number (from 1) and its four files, in the order force, position,
/// velocity, vibration.
pub struct MultistreamTrial {
    /// Surface as the file names give it: `mat07`.
    pub surface: String,
    /// Trial number as the file names give it, from 1.
    pub trial: u32,
    /// `…_force.csv`, `…_position.csv`, `…_velocity.csv`, `…_vibration.csv`.
    pub files: [PathBuf; 4],
}

/// Every trial of the multistream logs under `dir`, sorted by surface then trial, found as a
/// user's shell loop would find them: by the `matNN_trialTT_force.csv` files.
pub fn multistream_trials(dir: &Path) -> Vec<MultistreamTrial> {
    let folder = dir.join("multistream");
    let mut trials: Vec<MultistreamTrial> = std::fs::read_dir(&folder)
        .expect("multistream folder")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .filter_map(|name| {
            let stem = name.strip_suffix("_force.csv")?.to_owned();
            let (surface, trial) = stem.split_once("_trial")?;
            Some(MultistreamTrial {
                surface: surface.to_owned(),
                trial: trial.parse().expect("trial number"),
                files: ["force", "position", "velocity", "vibration"]
                    .map(|stream| folder.join(format!("{stem}_{stream}.csv"))),
            })
        })
        .collect();
    trials.sort_by(|a, b| (&a.surface, a.trial).cmp(&(&b.surface, b.trial)));
    trials
}

/// A rub at 5 mm/s sampled at 1 kHz for `seconds`: a sine roughness of `amplitude_m` with a
/// 1 mm wavelength, and a friction force proportional to it with a 5 % deterministic wobble
/// that differs between trials. Columns: time, tangential position, normal position (the
/// tip's height), friction force.
pub struct SineRub {
    pub t: Vec<f64>,
    pub x: Vec<f64>,
    pub z: Vec<f64>,
    pub f: Vec<f64>,
}

/// The wobble of [`sine_rub`] at sample `k` of trial `trial`, in [0, 1).
pub fn rub_wobble(k: usize, trial: u32) -> f64 {
    ((k * 7919 + trial as usize * 31) % 13) as f64 / 13.0
}

/// See [`SineRub`].
pub fn sine_rub(amplitude_m: f64, seconds: f64, trial: u32) -> SineRub {
    let n = (seconds * 1000.0) as usize;
    let t: Vec<f64> = (0..n).map(|k| k as f64 * 1e-3).collect();
    let x: Vec<f64> = t.iter().map(|t| 5e-3 * t).collect();
    let z: Vec<f64> = x
        .iter()
        .map(|x| amplitude_m * (x * std::f64::consts::TAU / 1e-3).sin())
        .collect();
    let f: Vec<f64> = (0..n)
        .map(|k| 1e4 * amplitude_m * (1.0 + 0.05 * rub_wobble(k, trial)))
        .collect();
    SineRub { t, x, z, f }
}

/// `scene` (a scene file's text) without its `[models.*.budget]` tables, so that a test may
/// give a model its hyperparameters or a model file instead.
pub fn without_budgets(scene: &str) -> String {
    let mut out = Vec::new();
    let mut in_budget = false;
    for line in scene.lines() {
        if line.starts_with('[') {
            in_budget = line.starts_with("[models.") && line.ends_with(".budget]");
        }
        if !in_budget {
            out.push(line);
        }
    }
    out.join("\n") + "\n"
}

/// The offline fused anytime decisions on `c` (as `recognize eval --sequential --fuse` makes
/// them): every recognizer's windows in the order they are decided, the first recognizer's
/// first at the same sample, each weighing `factors` of the first's and taking its own
/// evidence scale's share of the memory, into a fresh posterior.
pub fn offline_fused_steps(
    models: &[&RecognizerFile],
    factors: &[f64],
    c: &LabelledCapture,
    params: SequentialParams,
) -> Vec<(usize, SequentialStep)> {
    let mut windows = Vec::new();
    for (model, factor) in models.iter().zip(factors) {
        let windowing = model.sequential_windowing().expect("window probabilities");
        for w in model
            .window_probabilities(c, Some(&windowing))
            .expect("probabilities")
            .expect("windows")
        {
            windows.push((
                w.decision.decided_at,
                w.evidence_scale * factor,
                w.evidence_scale,
                w.probabilities,
            ));
        }
    }
    windows.sort_by_key(|w| w.0);
    let mut state = SequentialState::new(params, models[0].classes.len()).expect("state");
    windows
        .into_iter()
        .map(|(at, scale, share, p)| (at, state.push_window(&p, scale, share).expect("finite")))
        .collect()
}

/// `steps` as a live recognizer answers them: at a sample that completes several windows, the
/// posterior after the last.
pub fn last_per_sample(steps: Vec<(usize, SequentialStep)>) -> Vec<(usize, SequentialStep)> {
    let mut last: Vec<(usize, SequentialStep)> = Vec::with_capacity(steps.len());
    for (at, step) in steps {
        match last.last_mut() {
            Some(l) if l.0 == at => l.1 = step,
            _ => last.push((at, step)),
        }
    }
    last
}
