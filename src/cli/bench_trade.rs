//! `palpus bench trade`: what a model's accuracy costs, over a grid of hyperparameters and
//! training sizes, and the points no other beats on both.

use std::path::{Path, PathBuf};

use anyhow::Context;
use capture::Capture;
use clap::Args;
use identify::{
    DEFAULT_MAX_FIT_SAMPLES, IdentifyOptions, SearchGrid, SearchPoint, identify, search, timed_predictions,
};
use indicatif::{ProgressBar, ProgressStyle};

use super::identify_cmd::{ModelArg, fit_set};

/// Measure the speed/accuracy trade of a model's fit.
///
/// For every training size (--sizes, the needle's --max-samples) and every point of the grid
/// (--grid, as for `identify`; the model's own grid by default) it cross-validates the fit on
/// the capture (5 contiguous folds; leave-one-speed-out for the soft contact), as `identify
/// --search` does, and with --test fits on the whole capture and measures it on the test one.
/// Each point records its fit time, time per prediction (what one haptic tick pays), support
/// vectors, cross-validated AISE and, with --test, held-out AISE, largest error, the error in
/// the peak force and the refitted model's time per prediction over the test capture. Times per
/// prediction are the fastest of 5 passes. The Pareto front over time per prediction and AISE
/// (held-out with --test, else cross-validated) — the points that no other is both faster and
/// more accurate than — is printed, and every point is written to OUT/trade.csv with the front
/// drawn in OUT/trade.png.
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
    /// Folder for trade.csv and trade.png.
    #[arg(long, default_value = "out/trade", value_name = "DIR")]
    out: PathBuf,
}

/// One measured point: a grid point at a training size, and its held-out measures.
struct TradePoint {
    n: usize,
    point: SearchPoint,
    /// Held-out AISE, largest error and error in the peak force.
    held_out: Option<HeldOut>,
}

struct HeldOut {
    aise: f64,
    max_error: f64,
    peak_error: f64,
    /// Time of one prediction of the refitted model, ns: the fastest of
    /// [`identify::PREDICT_TIMING_PASSES`] passes over the test capture's rows.
    predict_ns: f64,
}

impl TradePoint {
    /// The accuracy the front is drawn over.
    fn aise(&self) -> f64 {
        self.held_out.as_ref().map_or(self.point.cv_aise, |h| h.aise)
    }

    /// The time per prediction the front is drawn over: the refitted model's, timed over the
    /// test capture, else the cross-validation folds' mean.
    fn predict_ns(&self) -> f64 {
        self.held_out
            .as_ref()
            .map_or(self.point.predict_ns, |h| h.predict_ns)
    }

    fn ok(&self) -> bool {
        self.point.failed.is_none() && self.aise().is_finite() && self.predict_ns().is_finite()
    }
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
    let test = args.test.as_deref().map(read).transpose()?;

    let gammas = if kind == identify::ModelKind::HardFriction {
        1
    } else {
        grid.gamma.len()
    };
    let total = (args.sizes.len() * grid.c.len() * grid.epsilon.len() * gammas) as u64;
    let bar = ProgressBar::new(total).with_style(
        ProgressStyle::with_template("measuring {bar:30} {pos}/{len} points {elapsed} (eta {eta})")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let mut points = Vec::new();
    for &n in &args.sizes {
        let done_before = bar.position();
        let explored = search(kind, &train, n, &grid, &mut |done, _| {
            bar.set_position(done_before + done as u64)
        })
        .with_context(|| format!("cross-validating at n = {n}"))?;
        for point in explored {
            let held_out = match (&test, point.failed.is_none()) {
                (Some(test), true) => Some(held_out(&train, test, kind, n, &point)?),
                _ => None,
            };
            points.push(TradePoint { n, point, held_out });
        }
    }
    bar.finish_and_clear();

    let front = pareto_front(&points);
    std::fs::create_dir_all(&args.out).with_context(|| format!("creating {}", args.out.display()))?;
    let csv = args.out.join("trade.csv");
    write_csv(&csv, &points, &front)?;
    let png = args.out.join("trade.png");
    let cloud: Vec<(f64, f64, bool)> = points
        .iter()
        .zip(&front)
        .filter(|(p, _)| p.ok())
        .map(|(p, &on)| (p.predict_ns(), p.aise(), on))
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
        "  {:>6} {:>10} {:>10} {:>8} {:>12} {:>7} {:>9} {:>11} {:>12} {:>11} {:>11}",
        "n", "C", "ε", "γ", "CV AISE", "SVs", "fit [ms]", "predict [ns]", "test AISE", "max |e|", "peak |e|"
    );
    let mut on_front: Vec<&TradePoint> = points
        .iter()
        .zip(&front)
        .filter(|(_, on)| **on)
        .map(|(p, _)| p)
        .collect();
    on_front.sort_by(|a, b| a.predict_ns().total_cmp(&b.predict_ns()));
    for p in on_front {
        let q = &p.point;
        let gamma = q.gamma.map_or("-".to_owned(), |g| format!("{g:.3e}"));
        let (aise, max_e, peak) = p
            .held_out
            .as_ref()
            .map_or(("-".into(), "-".into(), "-".into()), |h| {
                (
                    format!("{:.4e}", h.aise),
                    format!("{:.3e}", h.max_error),
                    format!("{:.3e}", h.peak_error),
                )
            });
        println!(
            "  {:>6} {:>10.3e} {:>10.3e} {gamma:>8} {:>12.4e} {:>7.1} {:>9.2} {:>11.0} {aise:>12} {max_e:>11} {peak:>11}",
            p.n,
            q.c,
            q.epsilon,
            q.cv_aise,
            q.n_sv,
            q.fit_seconds * 1e3,
            p.predict_ns()
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
    point: &SearchPoint,
) -> anyhow::Result<HeldOut> {
    let options = IdentifyOptions {
        kind,
        c: Some(point.c),
        epsilon: Some(point.epsilon),
        gamma: point.gamma,
        max_samples: n,
        max_fit_samples: DEFAULT_MAX_FIT_SAMPLES,
    };
    let identified = identify(train, Some(test), &options)
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
    Ok(HeldOut {
        aise: metrics.aise,
        max_error: metrics.error_bound,
        peak_error: (peak(&set.predicted) - peak(&set.measured)).abs(),
        predict_ns: fastest,
    })
}

/// Whether each point is on the Pareto front over (time per prediction, AISE): no other point
/// is at least as good on both and better on one. Failed points are never on it.
fn pareto_front(points: &[TradePoint]) -> Vec<bool> {
    points
        .iter()
        .map(|p| {
            p.ok()
                && !points.iter().any(|q| {
                    q.ok()
                        && q.predict_ns() <= p.predict_ns()
                        && q.aise() <= p.aise()
                        && (q.predict_ns() < p.predict_ns() || q.aise() < p.aise())
                })
        })
        .collect()
}

fn write_csv(path: &Path, points: &[TradePoint], front: &[bool]) -> anyhow::Result<()> {
    use std::io::Write as _;
    capture::write_atomically(path, |w| {
        writeln!(
            w,
            "n,c,epsilon,gamma,cv_aise,n_sv,fit_s,predict_ns,test_aise,test_max_error,test_peak_error,test_predict_ns,on_front,failed"
        )?;
        let num = |v: f64| if v.is_finite() { format!("{v:e}") } else { String::new() };
        for (p, &on) in points.iter().zip(front) {
            let q = &p.point;
            let (aise, max_e, peak, time) = p.held_out.as_ref().map_or(
                (String::new(), String::new(), String::new(), String::new()),
                |h| (num(h.aise), num(h.max_error), num(h.peak_error), num(h.predict_ns)),
            );
            let failed = q.failed.as_deref().unwrap_or("").replace(['"', '\n'], " ");
            writeln!(
                w,
                "{},{},{},{},{},{},{},{},{aise},{max_e},{peak},{time},{on},\"{failed}\"",
                p.n,
                num(q.c),
                num(q.epsilon),
                q.gamma.map_or(String::new(), num),
                num(q.cv_aise),
                num(q.n_sv),
                num(q.fit_seconds),
                num(q.predict_ns),
            )?;
        }
        Ok::<(), std::io::Error>(())
    })
    .with_context(|| format!("writing {}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(predict_ns: f64, aise: f64, failed: bool) -> TradePoint {
        TradePoint {
            n: 10,
            point: SearchPoint {
                c: 1.0,
                epsilon: 0.1,
                gamma: None,
                cv_aise: aise,
                n_sv: 1.0,
                fit_seconds: 0.0,
                predict_ns,
                failed: failed.then(|| "no".to_owned()),
            },
            held_out: None,
        }
    }

    #[test]
    fn the_front_holds_exactly_the_points_nothing_beats_on_both() {
        let points = [
            point(10.0, 5.0, false), // fastest: on
            point(20.0, 2.0, false), // on
            point(30.0, 2.0, false), // as accurate as the one before, slower: off
            point(40.0, 1.0, false), // most accurate: on
            point(25.0, 4.0, false), // beaten by (20, 2): off
            point(5.0, 0.5, true),   // failed: never on, and beats nothing
            point(10.0, 5.0, false), // a tie with the first: both on
        ];
        assert_eq!(
            pareto_front(&points),
            [true, true, false, true, false, false, true]
        );
    }
}
