//! Nakano's protocol end to end on the simulated captures (thesis Sec. 3.2–3.3, Fig. 4.15):
//! generate the 7 surfaces × 3 rubbing runs (seed 1), cut each run into windows from x = 5 mm on
//! (the thesis starts recognising there), train a SOM on run 0 of every surface and recognise the
//! windows of runs 1 and 2 — split by recording, never windows of one run on both sides — with
//! 10 SOM seeds pooled, as Fig. 4.15 averages 10 maps.
//!
//! The training window (1000 samples = 5 mm of travel = 1 s) and the filters (2.5 mm cut-off,
//! 0.2 mm smoothing) were chosen by reasoning before looking at the test runs (see
//! `recognize::nakano`). The map decides on longer windows (3000 samples, the
//! recognizer's default): the table of accuracy against the decision window and the feature
//! scaling shows what that trade of latency for accuracy buys.
#![allow(clippy::print_stdout)] // the tables are this test's report

use std::sync::OnceLock;

use crate::common::nakano_captures;
use capture::{Capture, CaptureKind};
use recognize::{
    ConfusionMatrix, FEATURES, NakanoConfig, NakanoSignals, NakanoStream, Normalization, Som, SomParams,
};
use sim::{CaptureSet, generate};

/// Recognition starts after this much travel (thesis Sec. 4.3), m.
const START_TRAVEL_M: f64 = 0.005;
/// Windows start every 100 samples (0.5 mm, 0.1 s).
const HOP: usize = 100;
/// The training window: 1000 samples, 5 mm of travel at 5 mm/s.
const WINDOW: usize = 1000;
/// The decision window: 3000 samples, 15 mm of travel.
const DECISION_WINDOW: usize = 3000;
/// SOM seeds pooled, as Fig. 4.15.
const SEEDS: u64 = 10;

struct Run {
    surface: String,
    train: bool,
    capture: Capture,
}

fn runs() -> &'static [Run] {
    static RUNS: OnceLock<Vec<Run>> = OnceLock::new();
    RUNS.get_or_init(|| {
        let dir = tempfile::tempdir().expect("tempdir");
        generate(dir.path(), 1, &[CaptureSet::Nakano], &mut |_| {}).expect("generate");
        nakano_captures(dir.path())
            .iter()
            .map(|p| {
                let capture = Capture::read_file(p, CaptureKind::Rubbing).expect("capture");
                let meta = capture.metadata();
                Run {
                    surface: meta.get("surface").expect("surface").to_owned(),
                    train: meta.get("role") == Some("train"),
                    capture,
                }
            })
            .collect()
    })
}

/// The run's signals, and its first sample after [`START_TRAVEL_M`] of travel.
fn signals_from_start(run: &Run) -> (NakanoSignals<'_>, usize) {
    let signals = NakanoSignals::from_capture(&run.capture).expect("columns");
    let x = signals.position_m();
    let first = x
        .iter()
        .position(|&p| p - x[0] >= START_TRAVEL_M)
        .expect("5 mm of travel");
    (signals, first)
}

/// Feature vectors of `len`-sample windows every [`HOP`] samples from x = 5 mm on.
fn windows(run: &Run, len: usize, config: &NakanoConfig) -> Vec<Vec<f64>> {
    let (signals, first) = signals_from_start(run);
    let margin = config.lookahead_samples();
    let first = first.max(margin);
    (first..)
        .step_by(HOP)
        .take_while(|s| s + len + margin <= signals.len())
        .map(|s| signals.features(s, len, config).expect("in range").to_vec())
        .collect()
}

/// The thesis's reading of Eqs. 2.18–2.22 with `[n]`: features over every sample from the start
/// of the stroke (after the filter margin) up to the decision point, decisions every [`HOP`]
/// samples from x = 5 mm on — a growing window instead of a sliding one.
fn growing_windows(run: &Run, config: &NakanoConfig) -> Vec<Vec<f64>> {
    let (signals, first) = signals_from_start(run);
    let margin = config.lookahead_samples();
    (first..)
        .step_by(HOP)
        .take_while(|end| end + margin <= signals.len())
        .map(|end| {
            signals
                .features(margin, end - margin, config)
                .expect("in range")
                .to_vec()
        })
        .collect()
}

fn classes() -> Vec<String> {
    let mut classes: Vec<String> = runs()
        .iter()
        .filter(|r| r.train)
        .map(|r| r.surface.clone())
        .collect();
    classes.dedup();
    classes
}

/// Training set (run 0 of every surface) and test set (runs 1, 2).
type Labelled = (Vec<Vec<f64>>, Vec<String>);

/// Windows of `len` samples, or growing windows when `len` is `None`.
fn split(len: Option<usize>) -> (Labelled, Labelled) {
    let config = NakanoConfig::default();
    let (mut train, mut test): (Labelled, Labelled) = Default::default();
    for run in runs() {
        let set = if run.train { &mut train } else { &mut test };
        let features = match len {
            Some(len) => windows(run, len, &config),
            None => growing_windows(run, &config),
        };
        for w in features {
            set.0.push(w);
            set.1.push(run.surface.clone());
        }
    }
    (train, test)
}

/// Confusion over the test windows (`test_len` samples, or growing windows when `None`) of
/// maps trained on `train_len`-sample windows, pooled over [`SEEDS`] maps, and the mean
/// quantization and topographic errors on the training set.
fn evaluate(
    train_len: usize,
    test_len: Option<usize>,
    normalization: Normalization,
) -> (ConfusionMatrix<String>, f64, f64) {
    let ((train, train_labels), _) = split(Some(train_len));
    let (_, (test, test_labels)) = split(test_len);
    let mut pooled = ConfusionMatrix::new(classes()).expect("distinct");
    let (mut qe, mut te) = (0.0, 0.0);
    for seed in 0..SEEDS {
        let params = SomParams {
            seed,
            normalization,
            ..SomParams::default()
        };
        let som = Som::train(params, &train, &train_labels).expect("train");
        qe += som.quantization_error(&train).expect("qe") / SEEDS as f64;
        te += som.topographic_error(&train).expect("te") / SEEDS as f64;
        for (v, truth) in test.iter().zip(&test_labels) {
            pooled
                .add(truth, som.classify(v).expect("classify"))
                .expect("known");
        }
    }
    (pooled, qe, te)
}

fn worst(matrix: &ConfusionMatrix<String>) -> f64 {
    matrix
        .per_class_rates()
        .into_iter()
        .map(|r| r.expect("every surface has test windows"))
        .fold(1.0, f64::min)
}

#[test]
fn nakano_protocol_recognizes_every_surface() {
    let ((train, _), _) = split(Some(WINDOW));
    let (_, (test, _)) = split(Some(DECISION_WINDOW));
    assert_eq!(train[0].len(), FEATURES);
    println!(
        "Nakano protocol: {} training windows of {WINDOW} samples (run 0), {} decision windows of \
         {DECISION_WINDOW} samples (runs 1, 2), hop {HOP}",
        train.len(),
        test.len()
    );
    let (matrix, qe, te) = evaluate(WINDOW, Some(DECISION_WINDOW), Normalization::default());
    println!("default scaling (log, within-class), {SEEDS} SOM seeds pooled (percent of each true surface):");
    println!("{}", matrix.to_text());
    println!("training quantization error {qe:.4}, topographic error {te:.4}");
    for (class, rate) in matrix.classes().iter().zip(matrix.per_class_rates()) {
        let rate = rate.expect("every surface has test windows");
        assert!(rate >= 0.95, "{class}: {:.1} %", 100.0 * rate);
    }
    assert!(matrix.accuracy().expect("samples") >= 0.98);
    assert!(te < 0.05, "topographic error {te}");
}

#[test]
fn accuracy_against_decision_window_and_scaling() {
    let scalings = [
        ("eq_2_26", Normalization::ThesisColumnNorm),
        ("standardised", Normalization::Standardize),
        ("log_within_class", Normalization::LogWithinClass),
    ];
    let mut table =
        String::from("decision window, maps trained on 1000-sample windows: accuracy (worst surface)\n");
    table.push_str("window_samples  travel_mm");
    for (name, _) in &scalings {
        table.push_str(&format!("  {name:>20}"));
    }
    table.push('\n');
    let mut rows = Vec::new();
    for len in [250, 500, 1000, 2000, 3000] {
        table.push_str(&format!("{len:>14}  {:>9.2}", len as f64 * 5e-3));
        let mut row = Vec::new();
        for (_, n) in scalings {
            let (m, _, _) = evaluate(WINDOW, Some(len), n);
            let (a, w) = (m.accuracy().expect("samples"), worst(&m));
            table.push_str(&format!("  {:>9.1} % ({:>5.1} %)", 100.0 * a, 100.0 * w));
            row.push((a, w));
        }
        table.push('\n');
        rows.push(row);
    }
    println!("{table}");
    for row in &rows {
        // Standardising beats Eq. 2.26's column norms, and the log, within-class scaling beats
        // plain standardising, at every decision window.
        assert!(row[1].0 > row[0].0 + 0.05, "{row:?}");
        assert!(row[2].0 > row[1].0, "{row:?}");
    }
    // Longer decision windows average more roughness waves: accuracy rises with the window.
    assert!(rows[4][2].0 > rows[0][2].0 + 0.25, "{rows:?}");
    let (growing, _, _) = evaluate(WINDOW, None, Normalization::default());
    println!("growing window from the stroke's start (Eq. 2.18 with [n]), decisions from x = 5 mm on:");
    println!("{}", growing.to_text());
    assert!(growing.accuracy().expect("samples") >= 0.88);
}

#[test]
fn streaming_features_equal_batch_on_a_generated_run_and_the_latency_is_window_plus_lookahead() {
    let config = NakanoConfig::default();
    // A test run of sandpaper_400, the finest roughness (the most waves to count).
    let run = runs()
        .iter()
        .find(|r| r.surface == "sandpaper_400" && !r.train)
        .expect("sandpaper_400 test run");
    let signals = NakanoSignals::from_capture(&run.capture).expect("columns");
    let mut stream = NakanoStream::new(config, WINDOW).expect("valid");
    let (x, z, f) = (
        signals.position_m(),
        run.capture.column("normal_position_m").expect("height"),
        run.capture.column("friction_force_n").expect("friction"),
    );
    let mut compared = 0;
    for i in 0..signals.len() {
        let Some(w) = stream.push(x[i], z[i], f[i]) else {
            continue;
        };
        let start = w.start as usize;
        // Decided at sample i: the window's last sample plus the filters' lookahead.
        assert_eq!(i, start + WINDOW - 1 + config.lookahead_samples());
        if start < config.lookahead_samples() {
            continue;
        }
        let batch = signals.features(start, WINDOW, &config).expect("in range");
        for (a, b) in w.features.iter().zip(&batch) {
            assert!(
                (a - b).abs() <= 1e-9 * a.abs().max(b.abs()),
                "{start}: {a} vs {b}"
            );
        }
        compared += 1;
    }
    assert!(compared > 4000, "{compared}");
    let rate_hz = run.capture.metadata().rate_hz();
    let latency_s = (WINDOW + config.lookahead_samples()) as f64 / rate_hz;
    println!(
        "decision latency: window {:.3} s + lookahead {:.3} s = {latency_s:.3} s",
        WINDOW as f64 / rate_hz,
        config.lookahead_samples() as f64 / rate_hz
    );
    assert!((latency_s - 1.27).abs() < 1e-9);
}
