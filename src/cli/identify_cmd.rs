//! `palpus identify`.

use std::path::PathBuf;
use std::time::Duration;

use anyhow::Context;
use capture::Capture;
use clap::Args;
use identify::{FitLimits, IdentifyOptions, ModelKind, SearchGrid, best, identify_with, search};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use super::model_arg::{ModelArg, fit_set};
use crate::fit_files::{write_libsvm_models, write_predictions};
use crate::tables::identification::{print_frontier, print_table, warn};

/// Identify a model from a capture with ε-SVR and compare it with the baselines.
///
/// hard: friction against normal force, linear kernel; defaults are Li & Bi's C = 1e11 and
/// ε = 0.003 kgf, solved in SI (C/g, ε·g) — the same optimum, reported with b in N and kgf.
/// soft: per constant-speed segment a linear fit (w, m), then RBF SVRs w(v), m(v); --c,
/// --epsilon and --gamma set the second stage. needle: RBF SVR of [depth, velocity] on inputs
/// scaled to [0, 1], at most --max-samples samples (default 350, as the paper).
///
/// Every model trains on at most --max-fit-samples rows: a longer capture is thinned to
/// evenly spaced rows (first and last kept, the same rows every run), and a line on stderr
/// says how many of how many were used. Metrics use every row.
///
/// The report compares the SVR with Coulomb+viscous least squares (friction models;
/// F = Fc·sgn(v) + c·v + k·depth for the needle) and an RBF network by AISE, error bound
/// max|F − F̂| and RMSE, on --test if given, else on the training capture. A warning on stderr
/// (and `test_out_of_domain` in --json) says which inputs of --test leave the training range
/// (by more than 5 % of its width).
///
/// --predictions and --plot show the fit against the data: every row the model describes
/// (needle: the in-tissue rows), not only the rows it was fitted on, of the training capture
/// and of --test.
#[derive(Debug, Args)]
pub(crate) struct IdentifyArgs {
    /// Training capture.
    capture: PathBuf,
    /// Which model.
    #[arg(long, value_enum)]
    model: ModelArg,
    /// Choose C, ε and γ by 5-fold cross-validation over a grid around the defaults (contiguous
    /// folds; leave-one-speed-out for the soft contact's second stage), print the explored
    /// frontier, and fit with the best point.
    #[arg(long, conflicts_with_all = ["c", "epsilon", "gamma"])]
    search: bool,
    /// The grid --search explores (implies --search): comma-separated `name=value` or
    /// `name=lo..hi:count` (count log-spaced values, both ends included) for c, gamma and
    /// epsilon, e.g. 'c=1e1..1e5:5,gamma=10..1000:5,epsilon=0.005..0.05:3'; a name left out
    /// keeps the model's own values.
    #[arg(long, value_name = "SPEC", conflicts_with_all = ["c", "epsilon", "gamma"])]
    grid: Option<String>,
    /// Regularisation constant C.
    #[arg(long = "c", value_name = "X")]
    c: Option<f64>,
    /// ε of the insensitive tube, in the target's SI unit (N; dimensionless for the slope).
    #[arg(long, value_name = "X")]
    epsilon: Option<f64>,
    /// RBF γ on the scaled inputs.
    #[arg(long, value_name = "X")]
    gamma: Option<f64>,
    /// Held-out capture to evaluate on.
    #[arg(long, value_name = "CAPTURE")]
    test: Option<PathBuf>,
    /// Write the model here (JSON).
    #[arg(long, value_name = "MODEL.json")]
    out: Option<PathBuf>,
    /// Also write the SVR in libsvm's model format (inputs scaled as the model file says;
    /// the soft model's two SVRs go to FILE.slope and FILE.intercept).
    #[arg(long, value_name = "FILE")]
    libsvm: Option<PathBuf>,
    /// Needle: at most this many training samples.
    #[arg(long, default_value_t = identify::NEEDLE_SAMPLES)]
    max_samples: usize,
    /// Every model: at most this many training rows, evenly spaced over the capture.
    #[arg(long, value_name = "N", default_value_t = identify::DEFAULT_MAX_FIT_SAMPLES)]
    max_fit_samples: usize,
    /// Write the model's prediction at every sample of the training and test captures (CSV:
    /// set, the model's inputs, measured force, predicted_<force>, residual).
    #[arg(long, value_name = "FILE.csv")]
    predictions: Option<PathBuf>,
    /// Draw measured against predicted force (PNG): needle against depth, friction against
    /// normal force (soft contact: coloured by speed band).
    #[arg(long, value_name = "FILE.png")]
    plot: Option<PathBuf>,
    /// Size of the --plot image.
    #[arg(long, value_name = "WxH", default_value = "1100x750", value_parser = super::parse_size)]
    plot_size: [u32; 2],
    /// Solver tolerance of every SVR fit (relative; the interior point's duality gap, SMO's KKT
    /// violation). Whatever it is, a model is returned only when its certified relative duality
    /// gap is at most 1e-6 (svm::ACCEPT_GAP); a fit that misses it is an error with the gap it
    /// reached.
    #[arg(long = "tol", value_name = "X")]
    tolerance: Option<f64>,
    /// Wall-clock budget of each SVR fit, in seconds (default 60); a fit that runs out is an
    /// error naming the gap it had reached.
    #[arg(long, value_name = "S")]
    max_seconds: Option<f64>,
    /// At most this many support vectors in each kernel SVR (the haptic tick's time grows with
    /// them): a larger certified solution is replaced by one over K of its support vectors,
    /// refitted by least squares to its outputs, and the report gives the largest and RMS
    /// difference between the two over the training inputs.
    #[arg(long, value_name = "K", value_parser = parse_max_sv)]
    max_sv: Option<usize>,
    /// Needle: fit the gross outliers too. By default every insertion capture is screened
    /// (a run of one or two samples off both neighbours by more than the puncture threshold,
    /// max(10σ, 0.05 N)) and the rows found are left out of every fit and metric; a warning
    /// and `outliers` in --json list them either way.
    #[arg(long)]
    keep_outliers: bool,
    /// Print one JSON object instead of the table.
    #[arg(long)]
    json: bool,
    /// Print nothing but errors: no progress, table or warnings (--json still prints its
    /// object, whose `test_out_of_domain` keeps the warnings).
    #[arg(long, short)]
    quiet: bool,
}

pub(crate) fn run(args: &IdentifyArgs) -> anyhow::Result<()> {
    let kind = args.model.kind();
    let capture_kind = args.model.capture_kind();
    let train = Capture::read_file(&args.capture, capture_kind)?;
    let test = args
        .test
        .as_ref()
        .map(|p| Capture::read_file(p, capture_kind))
        .transpose()?;
    let mut options = IdentifyOptions {
        kind,
        c: args.c,
        epsilon: args.epsilon,
        gamma: args.gamma,
        max_samples: args.max_samples,
        max_fit_samples: args.max_fit_samples,
        keep_outliers: args.keep_outliers,
    };
    let explored = if args.search || args.grid.is_some() {
        let grid = match &args.grid {
            Some(spec) => SearchGrid::from_spec(kind, spec).with_context(|| format!("--grid {spec}"))?,
            None => SearchGrid::default_for(kind),
        };
        let bar = if args.quiet {
            ProgressBar::hidden()
        } else {
            ProgressBar::new(0)
        }
        .with_style(
            ProgressStyle::with_template("cross-validating {bar:30} {pos}/{len} grid points {elapsed}")
                .unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
        let points = search(kind, &train, args.max_samples, &grid, &mut |done, total| {
            bar.set_length(total as u64);
            bar.set_position(done as u64);
        })
        .context("searching hyperparameters")?;
        bar.finish_and_clear();
        let chosen = best(&points).context("no grid point could be fitted")?;
        options.c = Some(chosen.c);
        options.epsilon = Some(chosen.epsilon);
        options.gamma = chosen.gamma;
        points
    } else {
        Vec::new()
    };
    let time_budget = args
        .max_seconds
        .map(|s| {
            if s.is_finite() && s > 0.0 {
                Ok(Duration::from_secs_f64(s))
            } else {
                Err(anyhow::anyhow!(
                    "--max-seconds {s}: must be a positive number of seconds"
                ))
            }
        })
        .transpose()?;
    // A spinner that appears only once a fit has run for a second, with the solver's gap.
    let bar = ProgressBar::with_draw_target(None, ProgressDrawTarget::hidden()).with_style(
        ProgressStyle::with_template("{spinner} {msg} {elapsed}")
            .unwrap_or_else(|_| ProgressStyle::default_spinner()),
    );
    let shown = std::sync::atomic::AtomicBool::new(false);
    let observer = |what: &str, p: &svm::FitProgress| {
        if args.quiet || p.elapsed_s < 1.0 {
            return;
        }
        if !shown.swap(true, std::sync::atomic::Ordering::Relaxed) {
            bar.set_draw_target(ProgressDrawTarget::stderr());
            bar.enable_steady_tick(Duration::from_millis(200));
        }
        let gap = if p.gap.is_finite() {
            format!(", gap {:.2e}", p.gap)
        } else {
            String::new()
        };
        bar.set_message(format!("{what}: {} iteration {}{gap}", p.solver, p.iterations));
    };
    let limits = FitLimits {
        tolerance: args.tolerance,
        time_budget,
        max_sv: args.max_sv,
        observer: &observer,
    };
    let identified = identify_with(&train, test.as_ref(), &options, &limits);
    bar.finish_and_clear();
    let identified = identified.with_context(|| format!("identifying a {kind} model"))?;
    let r = &identified.report;
    if r.n_fit_rows < r.n_rows && !args.quiet {
        let limit = match kind {
            ModelKind::NeedlePuncture if args.max_samples <= args.max_fit_samples => "--max-samples",
            _ => "--max-fit-samples",
        };
        eprintln!(
            "fitted on {} of {} {}rows of {} (evenly spaced, {limit})",
            r.n_fit_rows,
            r.n_rows,
            if kind == ModelKind::NeedlePuncture {
                "in-tissue "
            } else {
                ""
            },
            args.capture.display(),
        );
    }
    if let Some(out) = &args.out {
        identified.model.save(out)?;
    }
    if args.predictions.is_some() || args.plot.is_some() {
        let model = &identified.model;
        let mut sets = vec![fit_set("train", &train, model)?];
        if let Some(t) = &test {
            sets.push(fit_set("test", t, model)?);
        }
        if let Some(path) = &args.predictions {
            write_predictions(path, model, &sets)?;
        }
        if let Some(path) = &args.plot {
            let [w, h] = args.plot_size;
            crate::plots::write_fit_plot(path, (w, h), model, &sets)?;
        }
    }
    if let Some(path) = &args.libsvm {
        write_libsvm_models(&identified.model.body, path)?;
    }
    if !args.quiet {
        warn(r);
    }
    if args.json {
        let mut report = serde_json::to_value(&identified.report)?;
        if let Some(object) = report.as_object_mut() {
            object.insert("search".into(), serde_json::to_value(&explored)?);
        }
        println!("{report}");
    } else if !args.quiet {
        if !explored.is_empty() {
            print_frontier(&explored);
        }
        print_table(&identified.report, &identified.model.body, &args.capture);
    }
    Ok(())
}

/// `--max-sv`: a positive count.
fn parse_max_sv(text: &str) -> Result<usize, String> {
    match text.parse::<usize>() {
        Ok(k) if k >= 1 => Ok(k),
        _ => Err(format!("`{text}` is not a support-vector count (at least 1)")),
    }
}
