//! `palpus recognize eval`.

use std::path::PathBuf;

use anyhow::Context;
use clap::Args;
use recognize::{FeatureNeeds, LabelledCapture, RecognizerFile};

use super::kept_reading::read_keeping;
use super::mapped_captures::MappedCaptures;
use crate::tables::anytime::print_sequential;
use crate::tables::recognition::{
    fused_json, print_evaluation, print_fused, print_windows, to_json, warn_windowless,
};

/// Evaluate a recognizer on labelled captures: accuracy, per-class rates, confusion matrix,
/// decision latency, time to the first correct and to a stable decision, decision flips.
///
/// knn and svm: each scratch is first classified alone by its behaviour's classifier; then the
/// scratches of one trial (same `surface` and `trial` in the metadata; a capture without a trial
/// stands alone) are fused, their class probabilities averaged with the behaviours' stored
/// reliability weights, and each trial gets one decision ("fused over behaviours").
#[derive(Debug, Args)]
pub(crate) struct EvalArgs {
    /// The recognizer.
    model: PathBuf,
    /// Captures to evaluate on.
    #[arg(required = true)]
    captures: Vec<PathBuf>,
    /// Print one JSON object instead of the tables.
    #[arg(long)]
    json: bool,
    /// Windowed recognizers (som, or --features nakano|both): decide on windows of this length
    /// instead of the recognizer's, s. Several, comma-separated (`0.5,1,2,3`), evaluate each
    /// and print accuracy against window length (the trade of latency for accuracy).
    #[arg(long, value_name = "S[,S…]", value_delimiter = ',')]
    window_s: Vec<f64>,
    /// Also draw the confusion matrix (and, for a SOM, its topographic map and the
    /// evaluation windows' density over its nodes) as PNGs into this folder; with
    /// --sequential, the posterior's reliability diagram and the thresholds' trade.
    #[arg(long, value_name = "DIR")]
    plots: Option<PathBuf>,
    /// Anytime decisions (k-NN or SVM over windows): every window's probabilities, from
    /// contact on, multiplied into a posterior over the surfaces (each window weighing the
    /// weight fitted on held-out recordings in training, else hop / window, so overlapping
    /// windows count each sample once; probabilities floored at 1e-3);
    /// a surface is named once its posterior reaches the threshold, and held until it falls
    /// below half of it. Several thresholds, comma-separated (`0.5,0.9,0.99`), print accuracy
    /// against how soon a surface is named, and the posterior's calibration.
    #[arg(long, value_name = "P[,P…]", value_delimiter = ',')]
    sequential: Vec<f64>,
    /// With --sequential: seconds of windows whose evidence counts; older ones are forgotten,
    /// so a new surface under the tool is named within about this time. Over travel it is the
    /// travel of those seconds at the speed the windows were made for, at any speed.
    #[arg(long, value_name = "S", default_value_t = recognize::DEFAULT_MEMORY_S, requires = "sequential")]
    memory_s: f64,
    /// With --sequential: the likelihood ratio against the named surface at which the windows
    /// since the change test began are taken to be a new surface, and the evidence from before
    /// them is dropped; 0 for no change test (only the memory then follows a new surface).
    #[arg(long, value_name = "R", default_value_t = recognize::DEFAULT_CHANGE_ODDS, requires = "sequential")]
    change_odds: f64,
    /// With --sequential: the exponent each window's probabilities are raised to, in (0, 1];
    /// by default the one fitted on held-out recordings when the recognizer was trained, else
    /// hop / window, so that overlapping windows count each sample once.
    #[arg(long, value_name = "W", requires = "sequential", conflicts_with = "fuse")]
    window_weight: Option<f64>,
    /// With --sequential: fuse this recognizer's evidence into the posterior too (repeatable):
    /// a k-NN or SVM over windows of the same surfaces, trained on at least two runs or trials
    /// of each (so that its accuracy was cross-validated, and a k-NN's votes calibrated on
    /// held-out windows), over other features than the others (such as
    /// `--features vibration` beside `nakano`). Every recognizer's windows count in the order
    /// they are decided, each weighing its own fitted weight when every recognizer has one,
    /// else its weight alone times its cross-validated accuracy above chance relative to the
    /// most reliable recognizer's.
    #[arg(long, value_name = "MODEL.json", requires = "sequential")]
    fuse: Vec<PathBuf>,
    #[command(flatten)]
    input: MappedCaptures,
}

pub(crate) fn run(args: &EvalArgs) -> anyhow::Result<()> {
    let model = RecognizerFile::load(&args.model)?;
    if !args.sequential.is_empty() {
        return eval_sequential(args, &model);
    }
    if !args.window_s.is_empty() && model.windowing().is_none() {
        anyhow::bail!(
            "{}: a {} recognizer over {} features decides on whole captures: --window-s does not apply",
            args.model.display(),
            model.method(),
            model.feature_set()
        );
    }
    if args.window_s.len() > 1 && args.plots.is_some() {
        anyhow::bail!("--plots draws one evaluation: give a single --window-s with it");
    }
    let rate_hz = model.windowing().map(|w| w.rate_hz);
    // Each capture is held only as the features the evaluation (and the plots, which find
    // each decision window's node again from the same features) read.
    let captures = read_keeping(&args.input, &args.captures, rate_hz, |_| {
        Ok(FeatureNeeds::evaluation(&model, &args.window_s)?)
    })?;
    if args.window_s.len() > 1 {
        return eval_windows(args, &model, &captures);
    }
    let window_s = args.window_s.first().copied();
    let e = model.evaluate(&captures, window_s)?;
    warn_windowless(&e);
    let fused = model.evaluate_fused(&captures)?;
    let quality = model.som_quality(&captures, false, window_s)?;
    let plots = match &args.plots {
        Some(dir) => {
            crate::plots::write_eval_plots(dir, &model, &captures, &e.confusion.row_percent(), window_s)?
        }
        None => Vec::new(),
    };
    // With --json, stdout holds only the JSON object, so the plots are named on stderr.
    for p in &plots {
        if args.json {
            eprintln!("wrote {}", p.display());
        } else {
            println!("wrote {}", p.display());
        }
    }
    if args.json {
        let mut json = to_json(&e);
        if let Some(object) = json.as_object_mut() {
            object.insert("features".to_owned(), model.feature_set().name().into());
            if let Some(f) = &fused {
                object.insert("fused".to_owned(), fused_json(f));
            }
            if let Some(q) = &quality {
                object.insert("quantization_error".to_owned(), q.quantization_error.into());
                object.insert("topographic_error".to_owned(), q.topographic_error.into());
            }
        }
        println!("{}", serde_json::to_string_pretty(&json)?);
        return Ok(());
    }
    print_evaluation(&e, &format!("{} on {} captures", e.method, e.captures));
    if let Some(q) = &quality {
        println!(
            "map on these {} windows: quantization error {:.4}, topographic error {:.4}",
            q.windows, q.quantization_error, q.topographic_error
        );
    }
    if let Some(f) = &fused {
        print_fused(f);
    }
    Ok(())
}

/// Anytime decisions at each threshold of `--sequential`, and the posterior's calibration.
fn eval_sequential(args: &EvalArgs, model: &RecognizerFile) -> anyhow::Result<()> {
    if !args.window_s.is_empty() {
        anyhow::bail!("--sequential decides on the recognizer's own windows: leave out --window-s");
    }
    let others = args
        .fuse
        .iter()
        .map(|path| RecognizerFile::load(path).with_context(|| path.display().to_string()))
        .collect::<anyhow::Result<Vec<_>>>()?;
    let others: Vec<&RecognizerFile> = others.iter().collect();
    let named = || {
        std::iter::once(&args.model)
            .chain(&args.fuse)
            .map(|p| p.display().to_string())
            .collect::<Vec<_>>()
            .join(", ")
    };
    let needs = FeatureNeeds::sequential_fused(model, &others).with_context(named)?;
    let params = if others.is_empty() {
        model
            .sequential_params(args.memory_s)
            .context("a recognizer with window probabilities")?
    } else {
        model
            .fused_sequential_params(&others, args.memory_s)
            .with_context(named)?
    };
    let params = if args.change_odds == 0.0 {
        params.without_change_test()
    } else {
        params.change_log_odds(args.change_odds.ln())
    };
    let params = match args.window_weight {
        Some(w) => params.weight(w),
        None => {
            let models = std::iter::once(model).chain(others.iter().copied());
            for (path, m) in std::iter::once(&args.model).chain(&args.fuse).zip(models) {
                if let Some(note) = crate::recognizer::weight_memory_note(m, args.memory_s) {
                    eprintln!("warning: {}: {note}", path.display());
                }
            }
            params
        }
    };
    let rate_hz = model.windowing().map(|w| w.rate_hz);
    let captures = read_keeping(&args.input, &args.captures, rate_hz, |_| Ok(needs.clone()))?;
    let e = model.evaluate_sequential_fused(&others, &captures, &args.sequential, params)?;
    let plot = match &args.plots {
        Some(dir) => {
            std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
            let path = dir.join("sequential.png");
            crate::plots::write_sequential_plot(&path, &e)?;
            Some(path)
        }
        None => None,
    };
    if args.json {
        if let Some(p) = &plot {
            eprintln!("wrote {}", p.display());
        }
        println!("{}", serde_json::to_string_pretty(&e)?);
        return Ok(());
    }
    print_sequential(
        &e,
        model,
        &others,
        args.window_weight.is_some(),
        args.memory_s,
        &paths(args),
    );
    if let Some(p) = &plot {
        println!(
            "wrote {} (the reliability diagram at threshold {})",
            p.display(),
            e.params.threshold()
        );
    }
    Ok(())
}

/// The recognizer and the ones fused into it, as given.
fn paths(args: &EvalArgs) -> Vec<&PathBuf> {
    std::iter::once(&args.model).chain(&args.fuse).collect()
}

/// Accuracy against decision window: one evaluation per window length.
fn eval_windows(args: &EvalArgs, model: &RecognizerFile, captures: &[LabelledCapture]) -> anyhow::Result<()> {
    let mut evaluations = Vec::with_capacity(args.window_s.len());
    for &w in &args.window_s {
        let e = model.evaluate(captures, Some(w))?;
        warn_windowless(&e);
        evaluations.push(e);
    }
    if args.json {
        let rows: Vec<serde_json::Value> = evaluations.iter().map(to_json).collect();
        let json = serde_json::json!({ "method": model.method(), "windows": rows });
        println!("{}", serde_json::to_string_pretty(&json)?);
        return Ok(());
    }
    print_windows(model.method(), captures.len(), &evaluations);
    Ok(())
}
