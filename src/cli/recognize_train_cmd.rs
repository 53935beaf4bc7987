//! `palpus recognize train`.

use std::path::PathBuf;

use anyhow::Context;
use clap::Args;
use recognize::{FeatureNeeds, LabelledCapture};

use super::chosen_training::{ChosenTraining, read_and_choose};
use super::kept_reading::read_keeping;
use super::mapped_captures::MappedCaptures;
use super::train_args::Training;
use crate::tables::recognition::{
    print_posterior_weight, print_reliabilities, print_vote_calibration, print_window_c, warn_unmapped,
};

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
/// Defaults chosen on the training captures: what --features, --cells, --bands and --window-s
/// leave unnamed is chosen by cross-validation by recording on the captures themselves (see
/// --search-budget-s), among the feature sets the captures carry that decide as the documented
/// default does (windows, or whole captures), each histogram's cell scaling and band, and
/// windows of 3 s and 2 s. The documented default stands unless another candidate is more
/// accurate by two standard errors of the difference (windows counted by how much they
/// overlap); the table is printed and kept in the model file (`default_choice`). An option
/// given is never varied.
///
/// --features crosses methods and features. The documented default: both when the first
/// capture carries the columns of both and the windows hold a histogram (1.92 s), else the
/// method's own, as above, else the set the captures carry.
/// nakano with knn/svm: windowed like the SOM (--window-s, --hop-s, training windows of the
/// decision length unless --train-window-s says otherwise), one classifier over all windows,
/// each feature log-scaled where positive, centred and divided by its pooled within-surface
/// standard deviation (the SOM's scaling, without unit length);
/// k-NN k = 3, or a C-SVC (degree-2 polynomial, γ = 1/5; 1/130 for both) whose C is
/// cross-validated with whole runs held out (metadata `trial` or `run`) on windows 0.5 s apart
/// when every surface has two runs, else 10.
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
pub(crate) struct TrainArgs {
    /// Training captures.
    #[arg(required = true)]
    captures: Vec<PathBuf>,
    /// Write the recognizer here.
    #[arg(long, value_name = "MODEL.json")]
    out: PathBuf,
    #[command(flatten)]
    training: Training,
    #[command(flatten)]
    input: MappedCaptures,
}

pub(crate) fn run(args: &TrainArgs) -> anyhow::Result<()> {
    let read = |needs: &mut dyn FnMut(&LabelledCapture) -> anyhow::Result<FeatureNeeds>| {
        read_keeping(&args.input, &args.captures, None, needs)
    };
    let ChosenTraining {
        settings,
        captures,
        choice,
    } = read_and_choose(
        &args.training.options,
        args.training.method,
        &read,
        &|settings| settings,
        &FeatureNeeds::training,
    )?;
    for warning in settings.data_warnings(&captures)? {
        eprintln!("warning: {warning}");
    }
    let start = std::time::Instant::now();
    let mut model = crate::training::train_with_progress(&settings, &captures)?;
    model.default_choice = choice;
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
