//! `palpus recognize`.

use std::path::PathBuf;

use anyhow::Context;
use clap::{Args, Subcommand, ValueEnum};
use identify::recognition::knn::KnnParams;
use identify::recognition::model::{Evaluation, LabelledCapture, NakanoWindowing, RecognizerFile};
use identify::recognition::som::SomParams;
use identify::recognition::spectral::CellScale;
use identify::recognition::svc::SvcParams;

/// Train and evaluate surface recognizers.
///
/// A capture's class is the `surface` in its metadata (and, for scratches, its `behaviour`
/// picks which classifier answers), so `palpus gen` captures are used as they are.
#[derive(Debug, Args)]
pub(crate) struct RecognizeArgs {
    #[command(subcommand)]
    what: RecognizeWhat,
}

#[derive(Debug, Subcommand)]
enum RecognizeWhat {
    Train(TrainArgs),
    Eval(EvalArgs),
    Categorize(super::categorize_cmd::CategorizeArgs),
}

/// Train a recognizer on captures and write it as JSON.
///
/// som: Nakano's five rubbing features (roughness and friction) over sliding windows, decided
/// every hop from 5 mm of travel on, and a 1-D SOM (12 nodes, σ 1.6, 10 000 presentations).
/// knn: Sinapov's spectrotemporal histogram of each scratch, k-NN (k = 3) per behaviour.
/// svm: the same histograms, a one-vs-one C-SVC per behaviour (degree-2 polynomial kernel,
/// C = 10⁴, pairwise-coupled probabilities).
#[derive(Debug, Args)]
struct TrainArgs {
    /// Training captures.
    #[arg(required = true)]
    captures: Vec<PathBuf>,
    /// Which recognizer.
    #[arg(long, value_enum)]
    method: Method,
    /// Write the recognizer here.
    #[arg(long, value_name = "MODEL.json")]
    out: PathBuf,
    /// som: window length, s.
    #[arg(long, default_value_t = 1.0, value_name = "S")]
    window_s: f64,
    /// som: time between decisions, s.
    #[arg(long, default_value_t = 0.1, value_name = "S")]
    hop_s: f64,
    /// som: seed of the map's initial vectors and presentation order.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// knn: neighbours.
    #[arg(long, default_value_t = 3)]
    k: usize,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
enum Method {
    Som,
    Knn,
    Svm,
}

/// Evaluate a recognizer on labelled captures: accuracy, per-class rates, confusion matrix,
/// decision latency, time to the first correct and to a stable decision, decision flips.
#[derive(Debug, Args)]
struct EvalArgs {
    /// The recognizer.
    model: PathBuf,
    /// Captures to evaluate on.
    #[arg(required = true)]
    captures: Vec<PathBuf>,
    /// Print one JSON object instead of the tables.
    #[arg(long)]
    json: bool,
    /// som: evaluate with this window length instead of the trained one, s.
    #[arg(long, value_name = "S")]
    window_s: Option<f64>,
    /// Also draw the confusion matrix (and, for a SOM, its topographic map and the
    /// evaluation windows' density over its nodes) as PNGs into this folder.
    #[arg(long, value_name = "DIR")]
    plots: Option<PathBuf>,
}

pub(crate) fn run(args: &RecognizeArgs) -> anyhow::Result<()> {
    match &args.what {
        RecognizeWhat::Train(args) => train(args),
        RecognizeWhat::Eval(args) => eval(args),
        RecognizeWhat::Categorize(args) => super::categorize_cmd::run(args),
    }
}

fn read_all(paths: &[PathBuf]) -> anyhow::Result<Vec<LabelledCapture>> {
    paths
        .iter()
        .map(|p| LabelledCapture::read(p).with_context(|| format!("reading capture {}", p.display())))
        .collect()
}

fn train(args: &TrainArgs) -> anyhow::Result<()> {
    let captures = read_all(&args.captures)?;
    let model = match args.method {
        Method::Som => {
            let rate_hz = captures
                .first()
                .map(|c| c.capture.metadata().rate_hz())
                .context("no captures")?;
            let windowing = NakanoWindowing::new(args.window_s, args.hop_s, rate_hz)?;
            let params = SomParams {
                seed: args.seed,
                ..SomParams::default()
            };
            RecognizerFile::train_som(&captures, windowing, params)?
        }
        Method::Knn => RecognizerFile::train_knn(&captures, KnnParams::default().k(args.k), CellScale::Mean)?,
        Method::Svm => RecognizerFile::train_svm(&captures, SvcParams::default(), CellScale::Mean)?,
    };
    model
        .save(&args.out)
        .with_context(|| format!("writing {}", args.out.display()))?;
    println!(
        "trained {} on {} captures ({} vectors, {} classes: {}); wrote {}",
        model.method(),
        captures.len(),
        model.n_train,
        model.classes.len(),
        model.classes.join(", "),
        args.out.display()
    );
    Ok(())
}

fn eval(args: &EvalArgs) -> anyhow::Result<()> {
    let model = RecognizerFile::load(&args.model)?;
    let captures = read_all(&args.captures)?;
    let e = model.evaluate(&captures, args.window_s)?;
    let plots = match &args.plots {
        Some(dir) => crate::recognition_plots::write_eval_plots(
            dir,
            &model,
            &captures,
            &e.confusion.row_percent(),
            args.window_s,
        )?,
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
        println!("{}", serde_json::to_string_pretty(&to_json(&e))?);
        return Ok(());
    }
    println!(
        "{} on {} captures, {} decisions; window {:.3} s, decision latency {:.3} s",
        e.method,
        e.captures,
        e.confusion.total(),
        e.window_s,
        e.decision_latency_s
    );
    print!("{}", e.confusion.to_text());
    let secs = |v: Option<f64>| v.map_or_else(|| "-".to_owned(), |s| format!("{s:.3} s"));
    println!(
        "time to first correct {} ({} captures never correct), to stable {} ({} not stable at the end), {:.3} flips/s",
        secs(e.time_to_first_correct_s),
        e.never_correct,
        secs(e.time_to_stable_s),
        e.not_stable,
        e.flips_per_s
    );
    Ok(())
}

fn to_json(e: &Evaluation) -> serde_json::Value {
    let per_class: serde_json::Map<String, serde_json::Value> = e
        .confusion
        .classes()
        .iter()
        .zip(e.confusion.per_class_rates())
        .map(|(c, r)| (c.clone(), r.into()))
        .collect();
    serde_json::json!({
        "method": e.method,
        "accuracy": e.confusion.accuracy(),
        "per_class": per_class,
        "classes": e.confusion.classes(),
        "confusion": e.confusion.counts(),
        "window_s": e.window_s,
        "decision_latency_s": e.decision_latency_s,
        "time_to_first_correct_s": e.time_to_first_correct_s,
        "time_to_stable_s": e.time_to_stable_s,
        "flips_per_s": e.flips_per_s,
        "captures": e.captures,
        "never_correct": e.never_correct,
        "not_stable": e.not_stable,
    })
}
