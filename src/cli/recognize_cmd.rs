//! `palpus recognize`.

use std::path::PathBuf;

use anyhow::Context;
use clap::{Args, Subcommand, ValueEnum};
use recognize::protocol::{self, SINAPOV_FOLDS, Split};
use recognize::{
    CV_FOLDS, ConfusionMatrix, Evaluation, FeatureNeeds, FusedEvaluation, LabelledCapture, RecognizerBody,
    RecognizerFile, WINDOW_SVM_FALLBACK_C,
};

use super::kept_reading::keeping_each;
use super::train_args::{Method, Training};

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
    Cv(CvArgs),
    Categorize(super::categorize_cmd::CategorizeArgs),
}

/// Train a recognizer on captures and write it as JSON.
///
/// som: Nakano's five rubbing features (roughness and friction) over sliding windows, decided
/// every hop from 5 mm of travel on, and a 1-D SOM (12 nodes up to 7 surfaces, sized by the
/// training windows beyond, see --nodes; σ 1.6, 10 000 presentations or 500 per node) trained
/// on windows as long as the decision windows (--train-window-s 1 trains as the thesis does, on
/// more, shorter windows). Training warns when a surface owns no node of the map: the
/// recognizer can never name it.
/// knn: Sinapov's spectrotemporal histogram of each scratch, k-NN (k = 3) per behaviour.
/// svm: the same histograms, a one-vs-one C-SVC per behaviour (degree-2 polynomial kernel,
/// pairwise-coupled probabilities), C chosen per behaviour by cross-validation (see --c).
///
/// knn and svm also store each behaviour's accuracy under a cross-validation by trial (metadata
/// `trial`; at most 5 folds, trial t of every surface held out together) on the training
/// captures: its reliability weight when `eval` fuses the behaviours of a trial.
///
/// --features crosses methods and features. Default: both when the first capture carries the
/// columns of both and the windows hold a histogram (1.92 s), else the method's own, as above,
/// else the set the captures carry; a default other than the method's own is said on stderr.
/// nakano with knn/svm: windowed like the SOM (--window-s, --hop-s, training windows of the
/// decision length unless --train-window-s says otherwise), one classifier over all windows,
/// each feature log-scaled where positive, centred and divided by its pooled within-surface
/// standard deviation (the SOM's scaling, without unit length);
/// k-NN k = 3, or a C-SVC (degree-2 polynomial, γ = 1/5; 1/130 for both) whose C is
/// cross-validated with whole runs held out (metadata `trial` or `run`) when every surface has
/// two runs, else 10.
/// spectral with som: one map per behaviour over whole-scratch histograms (3 nodes per class,
/// at least 12; cells scaled like the rubbing map's features), one decision per scratch, fused
/// over a trial's behaviours (one-hot votes weighted by cross-validated reliability).
/// both: on rubbing captures that also carry accelerometer columns (three axes, or a single-axis
/// vibration_mps2), each window's five Nakano features followed by the 125-cell histogram of the
/// same window's acceleration (windows of at least 1.92 s: five 0.64 s frames at half a frame's
/// hop), each feature set weighing the same in k-NN's and the SVM's distances.
/// spectral: Sinapov's histogram defined in seconds and hertz (0.25 s moving average, 0.64 s
/// frames, 0–200 Hz in 25 bins), the paper's sample counts at its 400 Hz, the same physical
/// bands at any rate.
#[derive(Debug, Args)]
struct TrainArgs {
    /// Training captures.
    #[arg(required = true)]
    captures: Vec<PathBuf>,
    /// Write the recognizer here.
    #[arg(long, value_name = "MODEL.json")]
    out: PathBuf,
    #[command(flatten)]
    training: Training,
    #[command(flatten)]
    input: super::mapped_captures::MappedCaptures,
}

/// Evaluate a recognizer on labelled captures: accuracy, per-class rates, confusion matrix,
/// decision latency, time to the first correct and to a stable decision, decision flips.
///
/// knn and svm: each scratch is first classified alone by its behaviour's classifier; then the
/// scratches of one trial (same `surface` and `trial` in the metadata; a capture without a trial
/// stands alone) are fused, their class probabilities averaged with the behaviours' stored
/// reliability weights, and each trial gets one decision ("fused over behaviours").
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
    #[arg(long, value_name = "S", default_value_t = recognize::sequential::DEFAULT_MEMORY_S, requires = "sequential")]
    memory_s: f64,
    /// With --sequential: the likelihood ratio against the named surface at which the windows
    /// since the change test began are taken to be a new surface, and the evidence from before
    /// them is dropped; 0 for no change test (only the memory then follows a new surface).
    #[arg(long, value_name = "R", default_value_t = recognize::sequential::DEFAULT_CHANGE_ODDS, requires = "sequential")]
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
    input: super::mapped_captures::MappedCaptures,
}

/// Run a paper's protocol: train and evaluate again and again on captures split by recording,
/// and pool the decisions.
///
/// Recordings are the captures' `trial` (else `run`, else each capture alone), dealt into
/// --folds folds in numeric order. k-fold (Sinapov): each fold is held out once while the
/// others train — with `palpus gen --only sinapov` and 10 folds, fold t is trial t of every
/// surface. train-on-one (Nakano): each fold trains once and the others are held out — with
/// Nakano's three runs per surface, one run trains and two test. --seeds trains that many maps
/// per fold (Fig. 4.15 pools 10). Each round trains exactly as `recognize train` would.
///
/// For knn and svm over scratches it also scores each behaviour alone (Table II) and every
/// combination of n behaviours fused, for each n (Fig. 6).
#[derive(Debug, Args)]
struct CvArgs {
    /// All the captures: every recording of every surface.
    #[arg(required = true)]
    captures: Vec<PathBuf>,
    /// How the recordings are split.
    #[arg(long, value_enum, default_value = "k-fold")]
    split: SplitArg,
    /// Folds. Default: 10 for k-fold; one per recording for train-on-one.
    #[arg(long)]
    folds: Option<usize>,
    /// Run only this fold (from 1): with train-on-one, `--fold 1 --seeds 10` is Nakano's own
    /// protocol (the first run trains, 10 maps).
    #[arg(long)]
    fold: Option<usize>,
    /// som: maps trained per fold, seeds --seed, --seed + 1, … (their decisions pooled).
    #[arg(long, default_value_t = 1)]
    seeds: u64,
    /// Print one JSON object instead of the tables.
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    training: Training,
    #[command(flatten)]
    input: super::mapped_captures::MappedCaptures,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
enum SplitArg {
    KFold,
    TrainOnOne,
}

pub(crate) fn run(args: &RecognizeArgs) -> anyhow::Result<()> {
    match &args.what {
        RecognizeWhat::Train(args) => train(args),
        RecognizeWhat::Eval(args) => eval(args),
        RecognizeWhat::Cv(args) => cv(args),
        RecognizeWhat::Categorize(args) => super::categorize_cmd::run(args),
    }
}

fn train(args: &TrainArgs) -> anyhow::Result<()> {
    let mut settings = None;
    let captures = read_keeping(&args.input, &args.captures, None, |first| {
        let settings = settings.insert(args.training.settings(first));
        Ok(FeatureNeeds::training(
            settings,
            first.capture.metadata().rate_hz(),
        )?)
    })?;
    let settings = settings.context("no captures to train on")?;
    for warning in settings.data_warnings(&captures)? {
        eprintln!("warning: {warning}");
    }
    let start = std::time::Instant::now();
    let model = Training::train_with_progress(&settings, &captures)?;
    let trained_s = start.elapsed().as_secs_f64();
    // The model keeps its classes in label order; people read them in natural order.
    let mut class_names: Vec<&str> = model.classes.iter().map(String::as_str).collect();
    class_names.sort_by(|a, b| recognize::natural_cmp(a, b));
    model
        .save(&args.out)
        .with_context(|| format!("writing {}", args.out.display()))?;
    println!(
        "trained {} over {} features on {} captures ({} vectors, {} classes: {}); wrote {}",
        model.method(),
        model.feature_set(),
        captures.len(),
        model.n_train,
        model.classes.len(),
        class_names.join(", "),
        args.out.display()
    );
    if let Some(q) = model.som_quality(&captures, true, None)? {
        println!(
            "map on its {} training windows: quantization error {:.4}, topographic error {:.4}",
            q.windows, q.quantization_error, q.topographic_error
        );
    }
    print_reliabilities(&model, trained_s);
    print_window_c(&model);
    print_vote_calibration(&model);
    print_posterior_weight(&model);
    warn_unmapped(&model);
    Ok(())
}

/// Reads `paths` one at a time and keeps of each only the features `needs` lists (asked once,
/// with the first capture), dropping its samples before the next is read: memory holds one
/// capture's samples at a time however many captures there are, and the results are those of
/// the whole captures. A bar on stderr counts the captures read (only on a terminal).
fn read_keeping(
    input: &super::mapped_captures::MappedCaptures,
    paths: &[PathBuf],
    default_rate_hz: Option<f64>,
    needs: impl FnMut(&LabelledCapture) -> anyhow::Result<FeatureNeeds>,
) -> anyhow::Result<Vec<LabelledCapture>> {
    keeping_each(
        paths,
        |path| input.read(std::slice::from_ref(path), default_rate_hz),
        needs,
    )
}

/// Warns on stderr about each SOM whose nodes leave classes unnamed, naming them.
fn warn_unmapped(model: &RecognizerFile) {
    for m in model.classes_without_nodes() {
        let map = m
            .behaviour
            .map_or_else(|| "the map".to_owned(), |b| format!("the map of behaviour {b}"));
        eprintln!(
            "warning: {} of {} classes own no node of {map} ({} nodes) and can never be recognized: {}; more nodes (--nodes) may help",
            m.classes.len(),
            model.classes.len(),
            m.nodes,
            m.classes.join(", ")
        );
    }
}

/// The C of an SVM over windows, and how it was chosen.
fn print_window_c(model: &RecognizerFile) {
    if let RecognizerBody::SvmWindows { svc, c_search, .. } = &model.body {
        let c = svc.params().c;
        match c_search {
            Some(search) if search.grid.len() > 1 => {
                let grid: Vec<String> = search
                    .grid
                    .iter()
                    .map(|p| format!("{:e}: {:.3}", p.c, p.accuracy))
                    .collect();
                println!(
                    "C = {c:e} chosen by {}-fold cross-validation by run from {}",
                    search.folds,
                    grid.join(", ")
                );
                if let Some(from) = search.separable_from
                    && search.grid.last().is_some_and(|p| p.c > from)
                {
                    println!(
                        "  from C = {from:e} on no multiplier reached C in any fold: the classes were \
                         separated, and each larger C has the same machines (not refitted)"
                    );
                }
            }
            Some(_) => println!("C = {c:e} (given)"),
            None if c == WINDOW_SVM_FALLBACK_C => {
                println!("C = {c:e} (not cross-validated: a surface has captures of a single run or trial)")
            }
            None => println!("C = {c:e} (given; not cross-validated)"),
        }
    }
}

/// How a k-NN over windows' votes became probabilities.
fn print_vote_calibration(model: &RecognizerFile) {
    if let RecognizerBody::KnnWindows { calibration, .. } = &model.body {
        match calibration {
            Some(c) => println!(
                "window probabilities: {:.3} × the vote fractions + {:.3} spread over the surfaces, fitted on {} windows \
                 held out in {}-fold cross-validation by run (accuracy {:.1} %, log-loss {:.3} nats; {:.1} % of them \
                 got no vote for their surface)",
                c.votes_weight,
                1.0 - c.votes_weight,
                c.windows,
                c.folds,
                100.0 * c.accuracy,
                c.log_loss,
                100.0 * c.unvoted
            ),
            None => println!(
                "window probabilities: the raw vote fractions (not calibrated: a surface has captures of a single \
                 run or trial, or holding one out leaves fewer windows than k), so this k-NN cannot be fused"
            ),
        }
    }
}

/// The weight of a window in anytime decisions, and how it was set.
fn print_posterior_weight(model: &RecognizerFile) {
    let Some(hop) = model.hop_weight() else {
        return;
    };
    match &model.posterior_weight {
        Some(p) => {
            println!(
                "posterior weight {:.3} a window (hop / window {hop:.3}), fitted on {} windows held out in {}-fold \
                 cross-validation by run, over a memory of {} s: Brier score {:.3} against {:.3}",
                p.weight, p.windows, p.folds, p.memory_s, p.brier, p.hop_brier
            );
            if let Some(h) = &p.held_out {
                println!("  anytime decisions at that weight, {h}");
            }
        }
        None => println!(
            "posterior weight hop / window, {hop:.3} a window (not fitted: a surface has captures of a single run \
             or trial, --no-weight-fit was given, or a fold's refit could not stand for this recognizer)"
        ),
    }
}

/// Each behaviour's cross-validated accuracy (its fusion weight) and, for an SVM, its C.
fn print_reliabilities(model: &RecognizerFile, trained_s: f64) {
    let reliabilities = model.reliabilities();
    if reliabilities.is_empty() {
        return;
    }
    println!(
        "trained in {trained_s:.2} s; reliability weights (accuracy under cross-validation by trial, at most {CV_FOLDS} folds):"
    );
    for r in &reliabilities {
        let name = r.behaviour.unwrap_or("(no behaviour)");
        let weight = match (r.reliability, r.folds) {
            (Some(a), Some(folds)) => format!("{a:.3} ({folds} folds)"),
            (Some(a), None) => format!("{a:.3}"),
            _ => "none (too few trials to cross-validate): fused with the mean of the others' weights, or all equal"
                .to_owned(),
        };
        let c = match (r.c, r.c_search) {
            (Some(c), Some(search)) if search.grid.len() > 1 => {
                let grid: Vec<String> = search
                    .grid
                    .iter()
                    .map(|p| format!("{:e}: {:.3}", p.c, p.accuracy))
                    .collect();
                format!("; C = {c:e} chosen from {}", grid.join(", "))
            }
            (Some(c), Some(_)) => format!("; C = {c:e} (given)"),
            (Some(c), None) => format!("; C = {c:e} (not cross-validated)"),
            (None, _) => String::new(),
        };
        println!("  {name:<16} {weight}{c}");
    }
}

fn eval(args: &EvalArgs) -> anyhow::Result<()> {
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
    // Over travel a window's weight is scaled by the share of its samples that are new.
    let scaled = if e.window_m.is_some() {
        ", scaled by the share of its samples that are new"
    } else {
        ""
    };
    let weighed = match (args.window_weight, &model.posterior_weight) {
        (Some(_), _) => " as given",
        (None, Some(_)) if others.is_empty() => ", fitted on held-out recordings",
        (None, None) if others.is_empty() => ", hop / window",
        _ => "",
    };
    println!(
        "{} on {} captures, anytime decisions over {} {} every {:.2} s from contact, \
         {} (each weighing {:.3}{weighed}{scaled}; evidence of the last {}):",
        model.method(),
        e.captures,
        e.steps,
        crate::session::report::windows_in_words(e.window_s, e.window_m, e.friction_cutoff_m),
        e.hop_s,
        crate::session::report::decided_after(e.decided_after_s),
        e.params.weight(),
        crate::session::report::memory_in_words(args.memory_s, e.window_s, e.window_m)
    );
    if !e.fused.is_empty() {
        println!(
            "fused with the evidence of (each window's weight: {}):",
            if e.fused.iter().all(|m| m.fitted) {
                "its own, fitted on held-out recordings"
            } else {
                "its weight alone × reliability over the most reliable's"
            }
        );
        for (path, m) in std::iter::once(&args.model).chain(&args.fuse).zip(&e.fused) {
            println!(
                "  {}: {} over {} windows of {} s every {:.2} s, cross-validated accuracy {:.1} %, \
                 reliability {:.3}, weight {:.3}",
                path.display(),
                m.method,
                m.features,
                m.window_s,
                m.hop_s,
                100.0 * m.accuracy,
                m.reliability,
                m.weight
            );
        }
    }
    println!(
        "{:>9} {:>8} {:>10} {:>12} {:>14} {:>12} {:>26} {:>27} {:>10} {:>8} {:>7} {:>7}",
        "threshold",
        "named",
        "accuracy",
        "first named",
        "stable right",
        "(travel)",
        "slowest surface",
        "most travel",
        "not right",
        "flips/s",
        "Brier",
        "ECE"
    );
    let secs = |v: Option<f64>| v.map_or_else(|| "-".to_owned(), |s| format!("{s:.2} s"));
    let mm = |v: Option<f64>| v.map_or_else(|| "-".to_owned(), |m| format!("{:.1} mm", 1e3 * m));
    for r in &e.rows {
        let slowest = r
            .worst_surface
            .as_ref()
            .map_or_else(|| "-".to_owned(), |(name, s)| format!("{name} {s:.2} s"));
        let farthest = r
            .worst_surface_travel
            .as_ref()
            .map_or_else(|| "-".to_owned(), |(name, m)| format!("{name} {:.1} mm", 1e3 * m));
        println!(
            "{:>9} {:>7.1}% {:>10} {:>12} {:>14} {:>12} {:>26} {:>27} {:>10} {:>8.3} {:>7.4} {:>6.2}%",
            r.threshold,
            100.0 * r.decided as f64 / e.steps as f64,
            percent(r.accuracy()),
            secs(r.time_to_first_decision_s),
            secs(r.time_to_stable_correct_s),
            mm(r.travel_to_stable_correct_m),
            slowest,
            farthest,
            r.not_stable,
            r.flips_per_s,
            r.calibration.brier,
            100.0 * r.calibration.ece
        );
    }
    if e.rows.iter().any(|r| r.changes > 0) {
        println!(
            "strokes that slide onto another surface part-way (above: the other strokes' times; \
             named right = right for the surface under the tool):"
        );
        println!(
            "{:>9} {:>8} {:>16} {:>12} {:>16} {:>12} {:>14}",
            "threshold",
            "strokes",
            "change followed",
            "(travel)",
            "slowest change",
            "(travel)",
            "not followed"
        );
        for r in &e.rows {
            println!(
                "{:>9} {:>8} {:>16} {:>12} {:>16} {:>12} {:>14}",
                r.threshold,
                r.changes,
                secs(r.change_followed_s),
                mm(r.change_followed_m),
                secs(r.slowest_change_s),
                mm(r.slowest_change_m),
                r.changes_not_followed
            );
        }
    }
    if e.short_of_travel > 0 {
        match model.sequential_windowing().and_then(|w| w.slowest_speed_mps()) {
            Some(v) => println!(
                "{} of {} windows were rubbed slower than the slowest speed the windows read ({:.1} mm/s): \
                 each counted for the share of its travel it covered, a tool at rest for nothing",
                e.short_of_travel,
                e.steps,
                v * 1e3
            ),
            None => println!(
                "{} of {} windows held the tool at rest (it never left the {:.1} mm play): they counted for \
                 nothing",
                e.short_of_travel,
                e.steps,
                recognize::TRAVEL_PLAY_M * 1e3
            ),
        }
    }
    if let Some(p) = &plot {
        println!(
            "wrote {} (the reliability diagram at threshold {})",
            p.display(),
            e.params.threshold()
        );
    }
    Ok(())
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
    println!(
        "{} on {} captures, accuracy against decision window:",
        model.method(),
        captures.len()
    );
    println!(
        "{:>9} {:>9} {:>10} {:>9} {:>14} {:>14} {:>8} {:>9}",
        "window", "latency", "accuracy", "worst", "first correct", "stable", "flips/s", "decisions"
    );
    let secs = |v: Option<f64>| v.map_or_else(|| "-".to_owned(), |s| format!("{s:.2} s"));
    for e in &evaluations {
        let worst = e
            .confusion
            .per_class_rates()
            .into_iter()
            .flatten()
            .reduce(f64::min);
        println!(
            "{:>7.2} s {:>7.2} s {:>10} {:>9} {:>14} {:>14} {:>8.2} {:>9}",
            e.window_s,
            e.decision_latency_s,
            percent(e.confusion.accuracy()),
            percent(worst),
            secs(e.time_to_first_correct_s),
            secs(e.time_to_stable_s),
            e.flips_per_s,
            e.confusion.total()
        );
    }
    Ok(())
}

/// Warns on stderr about each capture that gave no decision window (once per capture, however
/// many rounds held it out): the evaluation scores it as never correct rather than failing, so
/// that the other captures are still scored; with no decision at all, evaluating is an error.
fn warn_windowless(e: &Evaluation) {
    let mut seen = std::collections::BTreeSet::new();
    for w in e.windowless.iter().filter(|w| seen.insert(&w.path)) {
        eprintln!(
            "warning: {w}; it gives no decision at a {:.3} s window and counts as never correct",
            e.window_s
        );
    }
}

/// An evaluation's summary line, confusion matrix and timing.
fn print_evaluation(e: &Evaluation, what: &str) {
    println!(
        "{what}, {} decisions; window {:.3} s, decision latency {:.3} s",
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
}

fn cv(args: &CvArgs) -> anyhow::Result<()> {
    if args.seeds > 1 && !matches!(args.training.method, Method::Som) {
        anyhow::bail!(
            "--seeds {} applies to som only: knn and svm train the same way every time",
            args.seeds
        );
    }
    let mut settings = None;
    let captures = read_keeping(&args.input, &args.captures, None, |first| {
        // Each round's recognizer is scored window by window, which the posterior's weight
        // does not touch: fitting it would only refit every round once per fold.
        let settings = settings.insert(recognize::TrainSettings {
            fit_posterior_weight: false,
            ..args.training.settings(first)
        });
        Ok(FeatureNeeds::training_and_decisions(
            settings,
            first.capture.metadata().rate_hz(),
        )?)
    })?;
    let settings = settings.context("no captures to cross-validate on")?;
    let split = match (args.split, args.folds) {
        (SplitArg::KFold, folds) => Split::KFold {
            folds: folds.unwrap_or(SINAPOV_FOLDS),
        },
        (SplitArg::TrainOnOne, Some(folds)) => Split::TrainOnOne { folds },
        (SplitArg::TrainOnOne, None) => Split::TrainOnOne {
            folds: protocol::recordings(&captures),
        },
    };
    let start = std::time::Instant::now();
    let result = protocol::run(&captures, split, args.seeds, args.fold, |train, seed| {
        let settings = recognize::TrainSettings {
            seed: settings.seed + seed,
            ..settings.clone()
        };
        recognize::train(train, &settings).map_err(Box::new)
    })?;
    let elapsed_s = start.elapsed().as_secs_f64();
    let e = &result.evaluation;
    warn_windowless(e);
    let by_count = result.fused_by_count();
    if args.json {
        let mut json = to_json(e);
        if let Some(object) = json.as_object_mut() {
            object.insert("features".to_owned(), settings.features.name().into());
            object.insert("split".to_owned(), split.name().into());
            object.insert("folds".to_owned(), split.folds().into());
            object.insert("fold".to_owned(), args.fold.into());
            object.insert("seeds".to_owned(), result.seeds.into());
            object.insert("rounds".to_owned(), result.rounds.into());
            let per_behaviour: serde_json::Map<String, serde_json::Value> = result
                .per_behaviour
                .iter()
                .map(|(b, m)| {
                    (
                        b.clone().unwrap_or_default(),
                        serde_json::json!({
                            "accuracy": m.accuracy(),
                            "scratches": m.total(),
                            "per_class": per_class_json(m),
                        }),
                    )
                })
                .collect();
            object.insert("per_behaviour".to_owned(), per_behaviour.into());
            let counts: Vec<serde_json::Value> = by_count
                .iter()
                .map(|c| {
                    serde_json::json!({
                        "behaviours": c.behaviours,
                        "combinations": c.combinations,
                        "mean_accuracy": c.mean_accuracy,
                        "min_accuracy": c.min_accuracy,
                        "max_accuracy": c.max_accuracy,
                    })
                })
                .collect();
            object.insert("fused_by_count".to_owned(), counts.into());
            let combinations: Vec<serde_json::Value> = result
                .combinations
                .iter()
                .map(|c| {
                    serde_json::json!({
                        "behaviours": c.behaviours,
                        "accuracy": c.confusion.accuracy(),
                        "trials": c.confusion.total(),
                    })
                })
                .collect();
            object.insert("combinations".to_owned(), combinations.into());
            if let Some(all) = result.fused_all() {
                object.insert(
                    "fused".to_owned(),
                    serde_json::json!({
                        "accuracy": all.confusion.accuracy(),
                        "per_class": per_class_json(&all.confusion),
                        "confusion": all.confusion.counts(),
                        "trials": all.confusion.total(),
                        "best_single_accuracy": result.best_single_accuracy(),
                    }),
                );
            }
        }
        println!("{}", serde_json::to_string_pretty(&json)?);
        return Ok(());
    }
    print_evaluation(
        e,
        &format!(
            "{} over {} features, {} split, {} x {} seed(s) = {} recognizers in {elapsed_s:.1} s; pooled over {} evaluations of held-out captures",
            e.method,
            settings.features,
            split.name(),
            args.fold.map_or_else(
                || format!("{} folds", split.folds()),
                |f| format!("fold {f} of {}", split.folds())
            ),
            result.seeds,
            result.rounds,
            e.captures
        ),
    );
    if result.per_behaviour.is_empty() {
        return Ok(());
    }
    println!("each behaviour alone:");
    for (b, m) in &result.per_behaviour {
        println!(
            "  {:<16} {:>7} of {} scratches",
            b.as_deref().unwrap_or("(no behaviour)"),
            percent(m.accuracy()),
            m.total()
        );
    }
    println!("behaviours fused, by how many (mean, worst and best of every combination):");
    for c in &by_count {
        println!(
            "  {} ({:>2} combinations): {:>7}  [{} – {}]",
            c.behaviours,
            c.combinations,
            percent(Some(c.mean_accuracy)),
            percent(Some(c.min_accuracy)),
            percent(Some(c.max_accuracy))
        );
    }
    if let Some(all) = result.fused_all() {
        println!(
            "all {} fused, {} trials:",
            all.behaviours.len(),
            all.confusion.total()
        );
        print!("{}", all.confusion.to_text());
        println!(
            "fused {} vs best single behaviour {}",
            percent(all.confusion.accuracy()),
            percent(result.best_single_accuracy())
        );
    }
    Ok(())
}

fn percent(a: Option<f64>) -> String {
    a.map_or_else(|| "-".to_owned(), |a| format!("{:.1} %", 100.0 * a))
}

fn print_fused(f: &FusedEvaluation) {
    println!("each behaviour alone:");
    for b in &f.per_behaviour {
        println!(
            "  {:<16} {:>7} of {} scratches (fusion weight {:.3})",
            b.behaviour.as_deref().unwrap_or("(no behaviour)"),
            percent(b.confusion.accuracy()),
            b.confusion.total(),
            b.weight
        );
    }
    println!(
        "fused over behaviours: {} trials (surface, trial), {} of more than one scratch",
        f.groups, f.multi_scratch_groups
    );
    print!("{}", f.confusion.to_text());
    println!(
        "fused {} vs best single behaviour {}",
        percent(f.confusion.accuracy()),
        percent(f.best_single_accuracy())
    );
}

fn per_class_json(c: &ConfusionMatrix<String>) -> serde_json::Value {
    c.classes()
        .iter()
        .zip(c.per_class_rates())
        .map(|(c, r)| (c.clone(), r.into()))
        .collect::<serde_json::Map<String, serde_json::Value>>()
        .into()
}

fn fused_json(f: &FusedEvaluation) -> serde_json::Value {
    let per_behaviour: serde_json::Map<String, serde_json::Value> = f
        .per_behaviour
        .iter()
        .map(|b| {
            (
                b.behaviour.clone().unwrap_or_default(),
                serde_json::json!({
                    "accuracy": b.confusion.accuracy(),
                    "scratches": b.confusion.total(),
                    "weight": b.weight,
                    "per_class": per_class_json(&b.confusion),
                }),
            )
        })
        .collect();
    serde_json::json!({
        "accuracy": f.confusion.accuracy(),
        "per_class": per_class_json(&f.confusion),
        "classes": f.confusion.classes(),
        "confusion": f.confusion.counts(),
        "groups": f.groups,
        "multi_scratch_groups": f.multi_scratch_groups,
        "best_single_accuracy": f.best_single_accuracy(),
        "per_behaviour": per_behaviour,
    })
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
