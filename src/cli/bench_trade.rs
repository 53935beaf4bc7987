//! `palpus bench trade`: what a model's accuracy costs, over a grid of hyperparameters and
//! training sizes, and the points no other beats on both.

use std::path::{Path, PathBuf};

use anyhow::Context;
use capture::Capture;
use clap::Args;
use identify::{
    DEFAULT_MAX_FIT_SAMPLES, FitLimits, IdentifyOptions, SearchGrid, SearchPoint, identify_with, search_with,
    timed_predictions,
};
use indicatif::{ProgressBar, ProgressStyle};

use super::model_arg::{ModelArg, fit_set};
use crate::trade::{HeldOut, TradeRow, TradeTable, pareto_front};

/// Measure the speed/accuracy trade of a model's fit.
///
/// For every training size (--sizes, the needle's --max-samples), solver tolerance (--tols),
/// support-vector budget (--max-svs, beside no budget) and every point of the grid
/// (--grid, as for `identify`; the model's own grid by default) it cross-validates the fit on
/// the capture (5 contiguous folds; leave-one-speed-out for the soft contact), as `identify
/// --search` does, and with --test fits on the whole capture and measures it on the test one.
/// Each point records its fit time, time per prediction (what one haptic tick pays), support
/// vectors, cross-validated AISE and, with --test, held-out AISE, largest error, the error in
/// the peak force and the refitted model's time per prediction over the test capture, exact
/// and through the haptic loop's f32 fast path. Times per prediction are the fastest of 5
/// passes. The Pareto front over the exact time per prediction and AISE (held-out with
/// --test, else cross-validated) — the points that no other is both faster and
/// more accurate than — is printed, and every point is written to OUT/trade.csv (its first
/// line names the model and the capture's SHA-256, for a scene's `[models.NAME.budget]` to
/// pick from) with the front drawn in OUT/trade.png.
#[derive(Debug, Args)]
pub(crate) struct TradeArgs {
    /// Training capture.
    capture: PathBuf,
    /// Which model.
    #[arg(long, value_enum)]
    model: ModelArg,
    /// Held-out capture to measure each point's fit on.
    #[arg(long, value_name = "CSV")]
    test: Option<PathBuf>,
    /// The grid: `name=value` or `name=lo..hi:count` (log-spaced) for c, gamma and epsilon.
    #[arg(long, value_name = "SPEC")]
    grid: Option<String>,
    /// Training sizes (the needle's in-tissue samples; the other models use every row).
    #[arg(long, value_delimiter = ',', default_value = "350", value_name = "N,...")]
    sizes: Vec<usize>,
    /// Solver tolerances to sweep (as `identify --tol`); the library's default when not given.
    #[arg(long, value_delimiter = ',', value_name = "X,...")]
    tols: Vec<f64>,
    /// Support-vector budgets to sweep (as `identify --max-sv`), each a row of its own beside
    /// the unreduced one.
    #[arg(long, value_delimiter = ',', value_name = "K,...")]
    max_svs: Vec<usize>,
    /// Folder for trade.csv and trade.png.
    #[arg(long, default_value = "out/trade", value_name = "DIR")]
    out: PathBuf,
}

pub(crate) fn run(args: &TradeArgs) -> anyhow::Result<()> {
    let kind = args.model.kind();
    if args.sizes.is_empty() || args.sizes.contains(&0) {
        anyhow::bail!("--sizes: give training sizes of at least 1");
    }
    let grid = match &args.grid {
        Some(spec) => SearchGrid::from_spec(kind, spec).with_context(|| format!("--grid {spec}"))?,
        None => SearchGrid::default_for(kind),
    };
    let read = |p: &Path| Capture::read_file(p, args.model.capture_kind());
    let train = read(&args.capture)?;
    let capture_sha256 = capture::sha256_hex(
        &std::fs::read(&args.capture).with_context(|| format!("reading {}", args.capture.display()))?,
    );
    let test = args.test.as_deref().map(read).transpose()?;

    let gammas = if kind == identify::ModelKind::HardFriction {
        1
    } else {
        grid.gamma.len()
    };
    if let Some(t) = args
        .tols
        .iter()
        .find(|t| !(t.is_finite() && **t > 0.0 && **t < 1.0))
    {
        anyhow::bail!("--tols: {t} is not a tolerance in (0, 1)");
    }
    if args.max_svs.contains(&0) {
        anyhow::bail!("--max-svs: give budgets of at least 1 support vector");
    }
    let tols: Vec<Option<f64>> = if args.tols.is_empty() {
        vec![None]
    } else {
        args.tols.iter().copied().map(Some).collect()
    };
    let budgets: Vec<Option<usize>> = std::iter::once(None)
        .chain(args.max_svs.iter().copied().map(Some))
        .collect();
    let combos = tols.len() * budgets.len();
    let total = (args.sizes.len() * combos * grid.c.len() * grid.epsilon.len() * gammas) as u64;
    let bar = ProgressBar::new(total).with_style(
        ProgressStyle::with_template("measuring {bar:30} {pos}/{len} points {elapsed} (eta {eta})")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let mut rows = Vec::new();
    for &n in &args.sizes {
        for &tol in &tols {
            for &max_sv in &budgets {
                let limits = FitLimits {
                    tolerance: tol,
                    max_sv,
                    ..FitLimits::default()
                };
                let done_before = bar.position();
                let explored = search_with(kind, &train, n, &grid, &limits, &mut |done, _| {
                    bar.set_position(done_before + done as u64)
                })
                .with_context(|| format!("cross-validating at n = {n}"))?;
                for point in explored {
                    let held_out = match (&test, point.failed.is_none()) {
                        (Some(test), true) => Some(held_out(&train, test, kind, n, &limits, &point)?),
                        _ => None,
                    };
                    rows.push(TradeRow {
                        n,
                        tol,
                        max_sv,
                        point,
                        held_out,
                        on_front: false,
                    });
                }
            }
        }
    }
    bar.finish_and_clear();

    let front = pareto_front(&rows);
    rows.iter_mut().zip(&front).for_each(|(r, &on)| r.on_front = on);
    let table = TradeTable {
        model: kind,
        capture_sha256,
        rows,
    };
    let points = &table.rows;
    std::fs::create_dir_all(&args.out).with_context(|| format!("creating {}", args.out.display()))?;
    let csv = args.out.join("trade.csv");
    table
        .write(&csv)
        .with_context(|| format!("writing {}", csv.display()))?;
    let png = args.out.join("trade.png");
    let cloud: Vec<(f64, f64, bool)> = points
        .iter()
        .zip(&front)
        .filter(|(p, _)| p.ok())
        .map(|(p, &on)| (p.time_ns(), p.aise(), on))
        .collect();
    let accuracy = if test.is_some() {
        "held-out AISE [N²]"
    } else {
        "cross-validated AISE [N²]"
    };
    crate::plots::write_trade_plot(&png, &cloud, accuracy)?;

    let failed = points.iter().filter(|p| !p.ok()).count();
    println!(
        "{} points ({} failed), {} on the front (fastest first; AISE {}):",
        points.len(),
        failed,
        front.iter().filter(|&&on| on).count(),
        if test.is_some() {
            "held out"
        } else {
            "cross-validated"
        }
    );
    println!(
        "  {:>6} {:>10} {:>10} {:>8} {:>7} {:>6} {:>12} {:>7} {:>9} {:>11} {:>8} {:>12} {:>11} {:>11}",
        "n",
        "C",
        "ε",
        "γ",
        "tol",
        "max SV",
        "CV AISE",
        "SVs",
        "fit [ms]",
        "predict [ns]",
        "f32 [ns]",
        "test AISE",
        "max |e|",
        "peak |e|"
    );
    let mut on_front: Vec<&TradeRow> = points.iter().filter(|p| p.on_front).collect();
    on_front.sort_by(|a, b| a.time_ns().total_cmp(&b.time_ns()));
    for r in on_front {
        let p = &r.point;
        let gamma = p.gamma.map_or("-".to_owned(), |g| format!("{g:.3e}"));
        let (aise, max_e, peak, f32_ns) =
            r.held_out
                .as_ref()
                .map_or(("-".into(), "-".into(), "-".into(), "-".into()), |h| {
                    (
                        format!("{:.4e}", h.aise),
                        format!("{:.3e}", h.max_error_n),
                        format!("{:.3e}", h.peak_error_n),
                        format!("{:.0}", h.predict_f32_ns),
                    )
                });
        let tol = r.tol.map_or("-".to_owned(), |t| format!("{t:.0e}"));
        let max_sv = r.max_sv.map_or("-".to_owned(), |k| k.to_string());
        println!(
            "  {:>6} {:>10.3e} {:>10.3e} {gamma:>8} {tol:>7} {max_sv:>6} {:>12.4e} {:>7.1} {:>9.2} {:>11.0} {f32_ns:>8} {aise:>12} {max_e:>11} {peak:>11}",
            r.n,
            p.c,
            p.epsilon,
            p.cv_aise,
            p.n_sv,
            p.fit_seconds * 1e3,
            r.time_ns()
        );
    }
    println!("wrote {} and {}", csv.display(), png.display());
    Ok(())
}

/// The point's hyperparameters fitted on the whole training capture (at most `n` samples) and
/// measured on `test`.
fn held_out(
    train: &Capture,
    test: &Capture,
    kind: identify::ModelKind,
    n: usize,
    limits: &FitLimits<'_>,
    point: &SearchPoint,
) -> anyhow::Result<HeldOut> {
    let options = IdentifyOptions {
        kind,
        c: Some(point.c),
        epsilon: Some(point.epsilon),
        gamma: point.gamma,
        max_samples: n,
        max_fit_samples: DEFAULT_MAX_FIT_SAMPLES,
        keep_outliers: false,
    };
    let identified = identify_with(train, Some(test), &options, limits)
        .with_context(|| format!("fitting C = {:e}, ε = {:e} at n = {n}", point.c, point.epsilon))?;
    let metrics = &identified.report.metrics.svr;
    let set = fit_set("test", test, &identified.model)?;
    let peak = |v: &[f64]| v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    // Row-major inputs, so that the timed loop does nothing but predict.
    let rows = set.measured.len();
    let x: Vec<f64> = (0..rows)
        .flat_map(|r| set.inputs.iter().map(move |col| col[r]))
        .collect();
    let dim = set.inputs.len().max(1);
    let (_, fastest) = timed_predictions(rows, || {
        x.chunks(dim).map(|row| identified.model.predict(row)).collect()
    });
    let fast = fast_predictor(&identified.model)?;
    let (_, fastest_f32) = timed_predictions(rows, || x.chunks(dim).map(&fast).collect());
    Ok(HeldOut {
        aise: metrics.aise,
        max_error_n: metrics.error_bound,
        peak_error_n: (peak(&set.predicted) - peak(&set.measured)).abs(),
        predict_ns: fastest,
        predict_f32_ns: fastest_f32,
    })
}

/// The model as the haptic loop evaluates it (f32 fast path, no allocation), taking the
/// inputs in [`identify::ModelFile::predict`]'s order.
/// One model evaluation at an input row.
type Predictor = Box<dyn Fn(&[f64]) -> f64>;

fn fast_predictor(model: &identify::ModelFile) -> anyhow::Result<Predictor> {
    use haptics::ScalarModel as _;
    use identify::ModelKind;
    Ok(match model.kind {
        ModelKind::NeedlePuncture => {
            let m = haptics::needle_model(model)?;
            Box::new(move |x: &[f64]| m.eval(&[x[0], x[1]]))
        }
        ModelKind::HardFriction => {
            let m = haptics::hard_friction_model(model)?;
            Box::new(move |x: &[f64]| m.eval(&[x[0]]))
        }
        ModelKind::SoftFriction => {
            let (w, m) = haptics::soft_friction_models(model)?;
            Box::new(move |x: &[f64]| w.eval(&[x[0]]) * x[1] + m.eval(&[x[0]]))
        }
        ModelKind::NeedlePhases => {
            anyhow::bail!("the trade is measured over the smooth models' hyperparameters")
        }
    })
}
