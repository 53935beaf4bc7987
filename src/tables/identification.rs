//! What `palpus identify` prints: the model's table against the baselines, its phases and
//! parts, the punctures found, the explored hyperparameters, and the warnings.

use std::path::Path;

use identify::{Metrics, ModelBody, OutOfDomain, Report, SearchPoint};

pub(crate) fn print_frontier(points: &[SearchPoint]) {
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

pub(crate) fn row(name: &str, m: &Metrics) {
    println!(
        "  {name:<18} {:>12.4e} {:>12.4e} {:>12.4e}",
        m.aise, m.error_bound, m.rmse
    );
}

/// The layers of a phase-aware needle model, as a table.
pub(crate) fn print_phases(p: &identify::PhaseModel) {
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
pub(crate) fn print_parts(r: &Report) {
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

pub(crate) fn print_table(r: &Report, body: &ModelBody, capture: &Path) {
    println!(
        "{} model from {} ({} training samples)",
        r.model,
        capture.display(),
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
pub(crate) fn print_baseline_punctures(r: &Report) {
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
pub(crate) fn print_punctures(r: &Report) {
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
pub(crate) fn out_of_domain_line(o: &OutOfDomain) -> String {
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
pub(crate) fn sig(x: f64) -> String {
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

/// The report's warnings, on stderr: the fit's own, and where the test capture leaves what the
/// model was fitted on.
pub(crate) fn warn(r: &Report) {
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
