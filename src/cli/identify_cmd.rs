//! `palpus identify`.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Duration;

use anyhow::Context;
use capture::Capture;
use clap::Args;
use identify::{
    FitLimits, IdentifyOptions, Metrics, ModelBody, ModelFile, ModelKind, OutOfDomain, Report, ScaledSvr,
    SearchGrid, SearchPoint, best, identify_with, search,
};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use svm::write_libsvm_model;

use super::model_arg::{ModelArg, fit_set};
use crate::plots::FitSet;

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
    let shown = std::cell::Cell::new(false);
    let observer = |what: &str, p: &svm::FitProgress| {
        if args.quiet || p.elapsed_s < 1.0 {
            return;
        }
        if !shown.replace(true) {
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
        match &identified.model.body {
            ModelBody::Single(m) => write_libsvm(m, path)?,
            ModelBody::TwoStage { slope, intercept } => {
                write_libsvm(slope, &with_suffix(path, "slope"))?;
                write_libsvm(intercept, &with_suffix(path, "intercept"))?;
            }
            ModelBody::Phases(_) => anyhow::bail!("--libsvm: the phase-aware needle model holds no SVR"),
        }
    }
    if !args.quiet {
        for w in &r.warnings {
            eprintln!("warning: {w}");
        }
        for o in &r.test_out_of_domain {
            eprintln!("warning: {}", out_of_domain_line(o));
        }
        for e in &r.test_out_of_phase_domain {
            eprintln!(
                "warning: {:.1} % of the test capture's rows in tissue ({}) lie outside what the \
                 phase `{}` was fitted on: {:.1}–{:.1} mm, {:.1}–{:.1} mm/s (rendered at the nearest \
                 trained velocity)",
                100.0 * e.fraction,
                e.rows,
                e.phase,
                e.depth_m[0] * 1e3,
                e.depth_m[1] * 1e3,
                e.velocity_mps[0] * 1e3,
                e.velocity_mps[1] * 1e3
            );
        }
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
        print_table(&identified.report, &identified.model.body, args);
    }
    Ok(())
}

/// Writes `sets` as CSV: `set`, the model's inputs and output under their capture column
/// names, `predicted_<output>` and `residual_<unit>` (measured − predicted), numbers in full
/// precision so that a reader recomputes the model's outputs exactly.
fn write_predictions(path: &Path, model: &ModelFile, sets: &[FitSet]) -> anyhow::Result<()> {
    let output = &model.output.name;
    // Column names end in their unit (`axial_force_n`).
    let unit = output.rsplit_once('_').map_or(output.as_str(), |(_, u)| u);
    capture::write_atomically(path, |w| -> std::io::Result<()> {
        write!(w, "set")?;
        for q in &model.inputs {
            write!(w, ",{}", q.name)?;
        }
        writeln!(w, ",{output},predicted_{output},residual_{unit}")?;
        for set in sets {
            for (r, (&measured, &predicted)) in set.measured.iter().zip(&set.predicted).enumerate() {
                write!(w, "{}", set.label)?;
                for col in &set.inputs {
                    write!(w, ",{}", col[r])?;
                }
                writeln!(w, ",{measured},{predicted},{}", measured - predicted)?;
            }
        }
        Ok(())
    })
    .with_context(|| format!("writing {}", path.display()))
}

fn with_suffix(path: &Path, suffix: &str) -> PathBuf {
    let mut s = path.as_os_str().to_owned();
    s.push(".");
    s.push(suffix);
    PathBuf::from(s)
}

fn write_libsvm(m: &ScaledSvr, path: &Path) -> anyhow::Result<()> {
    capture::write_atomically(path, |w| {
        write_libsvm_model(&m.svr, w).map_err(|e| std::io::Error::other(e.to_string()))
    })
    .with_context(|| format!("writing {}", path.display()))
}

fn print_frontier(points: &[SearchPoint]) {
    let mut sorted: Vec<&SearchPoint> = points.iter().collect();
    sorted.sort_by(|a, b| a.cv_aise.total_cmp(&b.cv_aise));
    println!("explored {} points (best first):", points.len());
    println!(
        "  {:>10} {:>10} {:>8} {:>12} {:>7} {:>9} {:>11}",
        "C", "ε", "γ", "CV AISE", "SVs", "fit [ms]", "predict [ns]"
    );
    for p in sorted {
        let gamma = p.gamma.map_or("-".to_owned(), |g| format!("{g}"));
        match &p.failed {
            None => println!(
                "  {:>10.3e} {:>10.3e} {gamma:>8} {:>12.4e} {:>7.1} {:>9.2} {:>11.0}",
                p.c,
                p.epsilon,
                p.cv_aise,
                p.n_sv,
                p.fit_seconds * 1e3,
                p.predict_ns
            ),
            Some(why) => println!("  {:>10.3e} {:>10.3e} {gamma:>8}  failed: {why}", p.c, p.epsilon),
        }
    }
}

fn row(name: &str, m: &Metrics) {
    println!(
        "  {name:<18} {:>12.4e} {:>12.4e} {:>12.4e}",
        m.aise, m.error_bound, m.rmse
    );
}

/// The layers of a phase-aware needle model, as a table.
fn print_phases(p: &identify::PhaseModel) {
    println!(
        "  {:>5} {:>11} {:>7} {:>14} {:>17} {:>22} {:>20}",
        "layer",
        "contact[mm]",
        "events",
        "peak meas.[N]",
        "a1 [N/m] a2[N/m²]",
        "gives at u [mm] (v)",
        "after: F0 [N] k[N/m]"
    );
    for (k, l) in p.layers.iter().enumerate() {
        let t = &l.threshold;
        println!(
            "  {:>5} {:>11.2} {:>7} {:>14.3} {:>8.1} {:>8.0} {:>9.2}–{:<5.2} ({:.1}–{:.1} mm/s) {:>8.3} {:>9.1}",
            k + 1,
            l.contact_depth_m * 1e3,
            l.events,
            l.peak_force_n,
            l.loading.a1_npm,
            l.loading.a2_npm2,
            t.deflection_m(t.speed_mps[0]) * 1e3,
            t.deflection_m(t.speed_mps[1]) * 1e3,
            t.speed_mps[0] * 1e3,
            t.speed_mps[1] * 1e3,
            l.after.constant_n,
            l.after.per_depth_npm,
        );
        if l.after.svr.is_some() {
            println!(
                "        (after layer {}: an ε-SVR of [depth, velocity], it predicted held-out strokes better)",
                k + 1
            );
        }
    }
    let w = &p.withdrawal;
    if w.svr.is_some() {
        println!("  withdrawal: an ε-SVR of [depth, velocity] (it predicted held-out strokes better)");
    } else {
        println!(
            "  withdrawal: F = {:.3} N + {:.1} N/m·d + {:.1} N·s/m·v + {:.0} N·s/m²·d·v",
            w.constant_n, w.per_depth_npm, w.per_speed_nspm, w.per_depth_speed_nspm2
        );
    }
}

/// The phase model's parts against an ε-SVR on held-out strokes.
fn print_parts(r: &Report) {
    if r.parts.is_empty() {
        return;
    }
    println!("  part (leave one stroke out)   samples strokes  law RMS [N]  SVR RMS [N]  renders");
    let n = |x: Option<f64>| x.map_or("-".to_owned(), |x| format!("{x:.4}"));
    for p in &r.parts {
        println!(
            "  {:<28} {:>8} {:>7} {:>12} {:>12}  {}",
            p.part,
            p.samples,
            p.strokes,
            n(p.parametric_rmse_n),
            n(p.svr_rmse_n),
            p.uses
        );
    }
}

fn print_table(r: &Report, body: &ModelBody, args: &IdentifyArgs) {
    println!(
        "{} model from {} ({} training samples)",
        r.model,
        args.capture.display(),
        r.n_train
    );
    for h in &r.hyperparameters {
        println!(
            "  {:<10} C = {:<12e} ε = {:<10e} kernel {:?}",
            h.label, h.c, h.epsilon, h.kernel
        );
    }
    if let (Some(w), Some(b), Some(b_kgf)) = (r.w, r.b, r.b_kgf) {
        println!(
            "  F = {w:.6}·P + {b:.6} N   (= {w:.6}·P + {b_kgf:.6} kgf; Li & Bi Eq. 12: 0.1647·P + 0.0033)"
        );
    }
    if !r.stage1.is_empty() {
        println!("  stage 1 (per speed):   v [mm/s]        w      m [N]");
        for s in &r.stage1 {
            println!("  {:>28.3} {:>8.4} {:>10.4}", s[0] * 1e3, s[1], s[2]);
        }
    }
    if let ModelBody::Phases(p) = body {
        print_phases(p);
        print_parts(r);
        println!(
            "  fit {:.3} s (with the smooth SVR it is compared with)",
            r.fit_seconds
        );
    } else {
        println!(
            "  support vectors {} / {}   dual objective {:.6e}   relative gap {:.1e}   fit {:.3} s",
            r.n_sv, r.n_train, r.dual_objective, r.relative_gap, r.fit_seconds
        );
    }
    if let Some(red) = &r.reduction {
        println!(
            "  reduced from {} support vectors (--max-sv): differs from the certified model by at most {:.3e} N (RMS {:.3e} N) on the training inputs",
            red.from_sv, red.max_deviation, red.rms_deviation
        );
    }
    println!(
        "on {} data:{:>15} {:>12} {:>12}",
        r.evaluated_on, "AISE [N²]", "max|e| [N]", "RMSE [N]"
    );
    if let Some(smooth) = &r.metrics.smooth_svr {
        row("phases", &r.metrics.svr);
        if let Some(okamura) = &r.metrics.okamura_piecewise {
            row("Okamura piecewise", okamura);
        }
        row("smooth ε-SVR", smooth);
    } else {
        row("ε-SVR", &r.metrics.svr);
    }
    if let Some(cv) = &r.metrics.coulomb_viscous {
        row("Coulomb+viscous", cv);
    }
    if let Some(law) = &r.metrics.coulomb_viscous_stiffness {
        row("Fc+c·v+k·depth", law);
    }
    if let Some(net) = &r.metrics.rbf_network {
        row("RBF network", net);
    }
    if let Some(mean) = &r.metrics.mean {
        row("mean force", mean);
    }
    for skipped in &r.baselines_not_fitted {
        let name = match skipped.baseline.as_str() {
            "coulomb_viscous" => "Coulomb+viscous",
            "coulomb_viscous_stiffness" => "Fc+c·v+k·depth",
            "rbf_network" => "RBF network",
            other => other,
        };
        println!("  {name:<18} {:>12}   not fitted: {}", "—", skipped.reason);
    }
    if r.metrics.coulomb_viscous.is_none()
        && !r
            .baselines_not_fitted
            .iter()
            .any(|b| b.baseline == "coulomb_viscous")
    {
        println!(
            "  (no Coulomb+viscous: it is a friction law of velocity and normal force and does not \
             apply to puncture force; Fc+c·v+k·depth is F = Fc·sgn(v) + c·v + k·depth by least squares)"
        );
    }
    print_punctures(r);
    print_baseline_punctures(r);
}

/// For each baseline that renders punctures: how many of the measured ones it gives within
/// 1 mm, and its peak errors there.
fn print_baseline_punctures(r: &Report) {
    for b in &r.baseline_punctures {
        let found: Vec<f64> = b
            .punctures
            .iter()
            .filter_map(|p| {
                let d = p.predicted_depth_m?;
                ((d - p.measured_depth_m).abs() < 1e-3)
                    .then_some(p.predicted_peak_force_n? - p.measured_peak_force_n)
            })
            .collect();
        let worst = found.iter().fold(0.0f64, |m, e| m.max(e.abs()));
        println!(
            "  {}: {} of {} punctures within 1 mm{}",
            b.model.replace('_', " "),
            found.len(),
            b.punctures.len(),
            if found.is_empty() {
                String::new()
            } else {
                format!(", peak error up to {worst:.3} N")
            }
        );
    }
}

/// Needle: each puncture measured in the evaluation capture beside the model's along the same
/// stroke (`missed` where the model's force does not give way there).
fn print_punctures(r: &Report) {
    if r.punctures.is_empty() {
        return;
    }
    let how = if r.metrics.smooth_svr.is_some() {
        "its own ruptures along each stroke"
    } else {
        "the same detector on its force along each stroke"
    };
    println!("punctures on {} data (model: {how}):", r.evaluated_on);
    println!(
        "  {:>6} {:>8}  {:>21}  {:>27}  {:>17}",
        "stroke", "v [mm/s]", "depth [mm] meas/model", "peak [N] measured/model", "drop [N] meas/model"
    );
    for p in &r.punctures {
        let (depth, peak, drop) = match (p.predicted_depth_m, p.predicted_peak_force_n, p.predicted_drop_n) {
            (Some(d), Some(f), Some(drop)) => {
                (format!("{:.1}", d * 1e3), format!("{f:.3}"), format!("{drop:.3}"))
            }
            _ => (
                "missed".to_owned(),
                format!("missed, {:.3} there", p.model_force_at_measured_n),
                "-".to_owned(),
            ),
        };
        println!(
            "  {:>6} {:>8.2}  {:>8.1} / {:<10}  {:>6.3} / {:<18}  {:>6.3} / {}",
            p.stroke,
            p.speed_mps * 1e3,
            p.measured_depth_m * 1e3,
            depth,
            p.measured_peak_force_n,
            peak,
            p.measured_drop_n,
            drop
        );
    }
}

/// "12.3 % of test samples have velocity_mps outside the training range [0.001, 0.01] (up to
/// 0.025)".
fn out_of_domain_line(o: &OutOfDomain) -> String {
    let [lo, hi] = o.range;
    let reach = match (o.min < lo, o.max > hi) {
        (true, true) => format!("from {} to {}", sig(o.min), sig(o.max)),
        (true, false) => format!("down to {}", sig(o.min)),
        _ => format!("up to {}", sig(o.max)),
    };
    format!(
        "{:.1} % of test samples have {} outside the training range [{}, {}] ({reach})",
        o.fraction * 100.0,
        o.input,
        sig(lo),
        sig(hi)
    )
}

/// `x` to 3 significant digits, in the shortest form that shows them.
fn sig(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let scale = 10f64.powi(2 - x.abs().log10().floor() as i32);
    let rounded = (x * scale).round() / scale;
    if rounded.is_finite() && rounded != 0.0 {
        format!("{rounded}")
    } else {
        format!("{x:.2e}")
    }
}

/// `--max-sv`: a positive count.
fn parse_max_sv(text: &str) -> Result<usize, String> {
    match text.parse::<usize>() {
        Ok(k) if k >= 1 => Ok(k),
        _ => Err(format!("`{text}` is not a support-vector count (at least 1)")),
    }
}
