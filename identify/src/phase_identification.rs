//! The phase-aware needle model identified from a capture and reported beside what it
//! replaces: Li & Bi's smooth ε-SVR, the RBF network and `F = Fc·sgn(v) + c·v + k·depth`, all
//! on the same in-tissue rows of the same evaluation capture.
//!
//! The phase model has memory, so it is evaluated along each capture's trajectory from a
//! fresh site ([`PhaseModel::simulate`]), exactly as the haptic thread renders it; the
//! smooth models are evaluated sample by sample as before.

use std::time::Instant;

use capture::{Capture, CaptureKind, kind};

use crate::error::IdentifyError;
use crate::error::check_series;
use crate::identification::{
    Identified, Job, capture_ref, check_written, metrics, model_column, out_of_domain, require_kind,
};
use crate::metrics::Metrics;
use crate::model_file::{Hyperparameters, MODEL_FORMAT, MODEL_VERSION, ModelBody, ModelFile, ModelKind};
use crate::needle_identification::{needle, needle_inputs, needle_output};
use crate::phases::{
    Domain, LayerModel, Loading, MAX_LAYERS, PhaseModel, ShaftLaw, Threshold, Varies, WithdrawalSource,
    fit_linear, fit_terms,
};
use crate::punctures::{PunctureParams, compare_punctures, detect_punctures, group_layers};

/// An insertion capture's whole series: time, depth, velocity, axial force.
struct Series {
    time_s: Vec<f64>,
    depth_m: Vec<f64>,
    velocity_mps: Vec<f64>,
    force_n: Vec<f64>,
}

fn series(c: &Capture) -> Result<Series, IdentifyError> {
    require_kind(
        c,
        CaptureKind::Insertion,
        "the needle model needs an insertion capture",
    )?;
    Ok(Series {
        time_s: c.time().to_vec(),
        depth_m: c.column(kind::DEPTH_M)?.to_vec(),
        velocity_mps: model_column(c, kind::VELOCITY_MPS)?,
        force_n: c.column(kind::AXIAL_FORCE_N)?.to_vec(),
    })
}

/// The model's metrics along `c`'s trajectory, over its in-tissue rows (the rows the smooth
/// models are scored on).
fn metrics_along(model: &PhaseModel, c: &Capture) -> Result<(Metrics, usize), IdentifyError> {
    let s = series(c)?;
    let steps = model.simulate(&s.depth_m, &s.velocity_mps);
    let rows: Vec<usize> = (0..s.depth_m.len()).filter(|&i| s.depth_m[i] > 0.0).collect();
    let pick = |x: &dyn Fn(usize) -> f64| rows.iter().map(|&i| x(i)).collect::<Vec<f64>>();
    let m = metrics(
        &pick(&|i| s.time_s[i]),
        &pick(&|i| s.force_n[i]),
        &pick(&|i| steps[i].force_n),
    )?;
    Ok((m, rows.len()))
}

pub(crate) fn needle_phases(job: &Job<'_>) -> Result<Identified, IdentifyError> {
    let started = Instant::now();
    let Job { train, test, .. } = *job;
    // The smooth SVR and its baselines, on the same rows: what the phases must beat.
    let smooth = needle(job)?;
    let s = series(train)?;
    let fit = |form| {
        identify_phases(
            form,
            train.source(),
            &s.time_s,
            &s.depth_m,
            &s.velocity_mps,
            &s.force_n,
            &PunctureParams::default(),
        )
    };
    let mut phases = fit(PhaseForm::Full)?;
    let parts = crate::phase_parts::compare_parts(&mut phases, &s.depth_m, &s.velocity_mps, &s.force_n)?;
    // Okamura's piecewise model on the same data: the published form of what the phases
    // generalise.
    let okamura = fit(PhaseForm::Okamura)?;
    let okamura_metrics = metrics_along(&okamura, test.unwrap_or(train))?.0;
    let (train_metrics, n_rows) = metrics_along(&phases, train)?;
    let eval_metrics = match test {
        Some(t) => metrics_along(&phases, t)?.0,
        None => train_metrics,
    };
    let input_range = phases.input_range();
    let n_layers = phases.layers.len();
    let mut training = vec![capture_ref(train.source())];
    training.retain(|r| !r.path.as_os_str().is_empty());
    let model = ModelFile {
        format: MODEL_FORMAT.into(),
        version: MODEL_VERSION,
        kind: ModelKind::NeedlePhases,
        inputs: needle_inputs(),
        output: needle_output(),
        body: ModelBody::Phases(Box::new(phases)),
        hyperparameters: Hyperparameters::new(Vec::new()),
        training,
        n_train: n_rows,
        train_metrics: Some(train_metrics),
        test_metrics: test.map(|_| eval_metrics),
        input_range,
    };
    let mut report = smooth.report;
    let smooth_punctures = std::mem::take(&mut report.punctures);
    report.model = ModelKind::NeedlePhases.short_name().into();
    report.n_train = n_rows;
    report.n_rows = n_rows;
    report.n_fit_rows = n_rows;
    report.n_sv = 0;
    report.n_layers = Some(n_layers);
    report.parts = parts;
    report.dual_objective = 0.0;
    report.relative_gap = 0.0;
    report.reduction = None;
    report.hyperparameters = Vec::new();
    report.metrics.smooth_svr = Some(report.metrics.svr);
    report.metrics.svr = eval_metrics;
    report.metrics.okamura_piecewise = Some(okamura_metrics);
    report.fit_seconds = started.elapsed().as_secs_f64();
    check_written(&report, &model, train, test)?;
    report.test_out_of_domain = match test {
        Some(t) => out_of_domain(&model, t)?,
        None => Vec::new(),
    };
    if let (Some(t), ModelBody::Phases(p)) = (test, &model.body) {
        let s = series(t)?;
        report.test_out_of_phase_domain = p.domain_exits(&s.depth_m, &s.velocity_mps);
    }
    report.punctures = compare_punctures(&model, test.unwrap_or(train), &PunctureParams::default())?;
    // The same puncture table for the baselines that have punctures: Okamura's model (its own
    // ruptures) and the smooth SVR (the detector on its force).
    let okamura_file = ModelFile {
        body: ModelBody::Phases(Box::new(okamura)),
        ..model.clone()
    };
    report.baseline_punctures = vec![
        crate::identification::BaselinePunctures {
            model: "okamura_piecewise".into(),
            punctures: compare_punctures(&okamura_file, test.unwrap_or(train), &PunctureParams::default())?,
        },
        crate::identification::BaselinePunctures {
            model: "smooth_svr".into(),
            punctures: smooth_punctures,
        },
    ];
    Ok(Identified { model, report })
}

/// Fewest samples that fit one linear law (four coefficients, and a margin for noise).
const MIN_LAW_SAMPLES: usize = 8;

/// Fewest samples of cutting between two layers: a few suffice for its constant, and layers a
/// couple of millimetres apart on a digitized curve leave no more (its depth term needs
/// 3 mm of them anyway, see [`Varies`]).
const MIN_BEFORE_SAMPLES: usize = 4;

/// Candidate contact depths tried per layer.
const CONTACT_CANDIDATES: usize = 96;

/// What sample belongs to which phase of the training capture.
#[derive(Debug, Default)]
struct Buckets {
    /// Per count of punctured layers p: advancing samples into uncut tissue, as (d, v, f,
    /// depth of the stroke's event of layer p or ∞).
    advancing: Vec<Vec<[f64; 4]>>,
    /// Withdrawing samples in punctured tissue: (d, v, f).
    withdrawal: Vec<[f64; 3]>,
}

/// Which terms the phase laws may use.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PhaseForm {
    /// Every term the data determine (the module documentation's table).
    Full,
    /// Okamura, Simone & O'Leary's piecewise model as published, the baseline a reviewer asks
    /// for: stiffness `a1·u + a2·u²` before each puncture, a puncture at a constant deflection,
    /// after it a constant cutting force plus friction proportional to the inserted length
    /// (Karnopp friction in motion does not depend on speed); withdrawal friction likewise.
    Okamura,
}

/// Identifies a [`PhaseModel`] from an insertion recording (all rows, in time order; depth
/// ≤ 0 in air). `source` names the capture in errors; `form` restricts the laws ([`PhaseForm::Full`] for the phase-aware model itself).
pub fn identify_phases(
    form: PhaseForm,
    source: &std::path::Path,
    time_s: &[f64],
    depth_m: &[f64],
    velocity_mps: &[f64],
    force_n: &[f64],
    params: &PunctureParams,
) -> Result<PhaseModel, IdentifyError> {
    let okamura = form == PhaseForm::Okamura;
    let shaft = |d: &[f64], v: &[f64], f: &[f64]| ShaftLaw::fit_restricted(d, v, f, !okamura);
    let n = time_s.len();
    check_series("depth_m", depth_m, n)?;
    check_series("velocity_mps", velocity_mps, n)?;
    check_series("axial_force_n", force_n, n)?;
    let data_error = |reason: String| IdentifyError::Data {
        path: source.to_owned(),
        reason,
    };
    let detection = detect_punctures(time_s, depth_m, velocity_mps, force_n, params)?;
    let events = &detection.events;
    let mut layers = group_layers(events, params.layer_gap_m);
    if layers.is_empty() {
        return Err(data_error(
            "no puncture found (no force drop while advancing): the phase-aware needle model needs \
             at least one; the smooth model (`--model needle`) does not"
                .into(),
        ));
    }
    // A membrane of the tissue gives in most strokes that reach it; a drop seen in fewer than
    // half of them is something else (a stroke's own transient, cutting that stops where the
    // tip meets the next membrane).
    let mut entry_of = vec![usize::MAX; n];
    let mut deepest_of_entry: Vec<f64> = Vec::new();
    let mut inside = false;
    for i in 0..n {
        if depth_m[i] > 0.0 {
            if !inside {
                deepest_of_entry.push(0.0);
                inside = true;
            }
            let e = deepest_of_entry.len() - 1;
            entry_of[i] = e;
            deepest_of_entry[e] = deepest_of_entry[e].max(depth_m[i]);
        } else {
            inside = false;
        }
    }
    layers.retain(|l| {
        let reached = deepest_of_entry.iter().filter(|&&m| m >= l.min_depth_m).count();
        let felt: std::collections::BTreeSet<usize> =
            l.events.iter().map(|&e| entry_of[events[e].index]).collect();
        2 * felt.len() >= reached
    });
    if layers.is_empty() {
        return Err(data_error(
            "no layer gives in at least half of the strokes that reach it: the phase-aware needle \
             model needs one; the smooth model (`--model needle`) does not"
                .into(),
        ));
    }
    if layers.len() > MAX_LAYERS {
        return Err(data_error(format!(
            "{} layers found, at most {MAX_LAYERS} are modelled",
            layers.len()
        )));
    }
    // A layer whose fitted loading does not rise to its punctures is no membrane (a drop of
    // the force that was not a rupture: a surge slowing down, a slip): its events are taken
    // out and the rest fitted again.
    let hold_band_mps = params.min_speed_mps;
    let (b, mut models, above) = 'refit: loop {
        let mut above = None;
        let mut layer_of = vec![usize::MAX; events.len()];
        for (k, l) in layers.iter().enumerate() {
            for &e in &l.events {
                layer_of[e] = k;
            }
        }

        // Walk the recording as the state machine would, with the detected events as the
        // punctures: every advancing sample into uncut tissue goes to the bucket of the number of
        // layers punctured before it, with the depth of its stroke's next event.
        let nl = layers.len();
        let mut b = Buckets {
            advancing: vec![Vec::new(); nl + 1],
            withdrawal: Vec::new(),
        };
        let mut event_at = vec![usize::MAX; n];
        for (e, ev) in events.iter().enumerate() {
            event_at[ev.index] = e;
        }
        let mut pending: Vec<[f64; 4]> = Vec::new();
        let mut punctured = 0usize;
        let mut deepest = 0.0f64;
        let mut skip_until_m = f64::NEG_INFINITY;
        let flush = |pending: &mut Vec<[f64; 4]>, b: &mut Buckets, p: usize, event_depth: f64| {
            for mut s in pending.drain(..) {
                s[3] = event_depth;
                b.advancing[p].push(s);
            }
        };
        for i in 0..n {
            let (d, v, f) = (depth_m[i], velocity_mps[i], force_n[i]);
            if d <= 0.0 {
                flush(&mut pending, &mut b, punctured, f64::INFINITY);
                punctured = 0;
                deepest = 0.0;
                skip_until_m = f64::NEG_INFINITY;
                continue;
            }
            if v > hold_band_mps && d > deepest {
                if d > skip_until_m {
                    pending.push([d, v, f, f64::INFINITY]);
                }
                if event_at[i] != usize::MAX {
                    let k = layer_of[event_at[i]];
                    if k == punctured {
                        flush(&mut pending, &mut b, punctured, d);
                        punctured += 1;
                        deepest = d;
                        // The fall itself is neither law: the next one starts where the
                        // force stopped falling.
                        skip_until_m = events[event_at[i]].bottom_depth_m;
                    }
                }
            } else {
                if v < -hold_band_mps && punctured > 0 {
                    b.withdrawal.push([d, v, f]);
                }
                if v < -hold_band_mps {
                    // A withdrawal ends the advance: what was pending is cutting or loading of
                    // the next layer without its event.
                    flush(&mut pending, &mut b, punctured, f64::INFINITY);
                    deepest = deepest.max(d);
                }
            }
        }
        flush(&mut pending, &mut b, punctured, f64::INFINITY);

        let mut models: Vec<LayerModel> = Vec::with_capacity(nl);
        for (k, layer) in layers.iter().enumerate() {
            // Loading samples end at their stroke's event; samples of strokes whose event of this
            // layer was not detected are left out (past their event they would be cutting).
            let samples: Vec<[f64; 4]> = b.advancing[k]
                .iter()
                .copied()
                .filter(|s| s[3].is_finite() || s[0] < layer.min_depth_m)
                .collect();
            // The next membrane can be met as soon as the force has stopped falling after the
            // one above gave (the loading curve's restart), however close the two lie.
            let lo = models.last().map_or(0.0, |_| {
                layers[k - 1]
                    .events
                    .iter()
                    .map(|&e| events[e].bottom_depth_m)
                    .fold(layers[k - 1].max_depth_m, f64::max)
            });
            let hi = layer.min_depth_m - 1e-4;
            // A membrane's loading rises to its punctures without sagging first; a contact
            // whose split makes the loading sag (the fade of the cutting above read as a
            // negative stiffness) or not rise is no candidate.
            let membrane_like = |l: &Loading, c: f64| {
                let u_max = layer.max_depth_m - c;
                let elastic = |u: f64| l.a1_npm * u + l.a2_npm2 * u * u;
                // The lowest point of a1·u + a2·u² over [0, u_max], and the rise to the puncture.
                let u_low = if l.a2_npm2 > 0.0 {
                    (-l.a1_npm / (2.0 * l.a2_npm2)).clamp(0.0, u_max)
                } else {
                    u_max
                };
                let sag = elastic(u_low.min(u_max)).min(elastic(u_max));
                // Steep where it gives: over the last millimetre (the drop's own travel) the
                // membrane adds at least a puncture's worth of force. Cutting and shaft
                // friction rise slowly and steadily; a drop at their end (the cutting stopping
                // where the tip meets the next membrane) is no rupture.
                let last = elastic(u_max) - elastic((u_max - params.max_travel_m).max(0.0));
                sag >= -(3.0 * detection.noise_n).max(params.min_drop_n)
                    && elastic(u_max) >= detection.threshold_n
                    && last >= detection.threshold_n
            };
            let mut fitted_any = false;
            let mut best: Option<(f64, f64, Loading, Option<ShaftLaw>)> = None;
            for j in 0..CONTACT_CANDIDATES {
                let c = lo + (hi - lo) * j as f64 / (CONTACT_CANDIDATES - 1) as f64;
                if c < 0.0 || hi <= lo {
                    continue;
                }
                let (before, loading): (Vec<[f64; 4]>, Vec<[f64; 4]>) =
                    samples.iter().partition(|s| s[0] < c);
                let loading: Vec<[f64; 4]> = loading.into_iter().filter(|s| s[3].is_finite()).collect();
                if loading.len() < MIN_LAW_SAMPLES {
                    continue;
                }
                // The law before the contact: cutting below the layer above, fitted on the
                // samples before this candidate; above the first layer, the tissue over it
                // where the capture holds some (nothing where the membrane is the surface).
                let cut = if k == 0 {
                    if before.len() < MIN_BEFORE_SAMPLES {
                        None
                    } else {
                        let col = |q: usize| before.iter().map(|s| s[q]).collect::<Vec<f64>>();
                        Some(shaft(&col(0), &col(1), &col(2))?)
                    }
                } else {
                    if before.len() < MIN_BEFORE_SAMPLES {
                        continue;
                    }
                    let col = |q: usize| before.iter().map(|s| s[q]).collect::<Vec<f64>>();
                    Some(shaft(&col(0), &col(1), &col(2))?)
                };
                let base = |d: f64, v: f64| cut.as_ref().map_or(0.0, |(l, _)| l.eval_raw(d, v));
                let sse_before = match &cut {
                    Some((_, sse)) => *sse,
                    None => before.iter().map(|s| s[2] * s[2]).sum(),
                };
                let residual: Vec<f64> = loading.iter().map(|s| s[2] - base(s[0], s[1])).collect();
                let dl: Vec<f64> = loading.iter().map(|s| s[0]).collect();
                let vl: Vec<f64> = loading.iter().map(|s| s[1]).collect();
                // The stiffness terms always; the viscous one only over several speeds.
                let keep = [!okamura, true, true, !okamura && Varies::of(&dl, &vl).speed];
                let x = fit_terms(
                    loading.len(),
                    |i| Loading::features(loading[i][0] - c, loading[i][1]),
                    keep,
                    &residual,
                )?;
                let l = Loading {
                    offset_n: x[0],
                    a1_npm: x[1],
                    a2_npm2: x[2],
                    damping_nspm: x[3],
                    domain: Domain::of(&dl, &vl),
                };
                let sse_loading: f64 = loading
                    .iter()
                    .zip(&residual)
                    .map(|(s, r)| (r - l.eval_raw(s[0] - c, s[1])).powi(2))
                    .sum();
                let total = sse_before + sse_loading;
                fitted_any = true;
                if membrane_like(&l, c) && best.as_ref().is_none_or(|b| total < b.0) {
                    best = Some((total, c, l, cut.map(|(law, _)| law)));
                }
            }
            if best.is_none() && !fitted_any && k > 0 {
                // Two drops too close for the deeper one's loading to fit between them: the
                // smaller is the cutting stopping as the tip met the next membrane, or a
                // membrane too thin to model apart; the larger is kept.
                let drop = |l: &crate::punctures::Layer| {
                    l.events.iter().map(|&e| events[e].drop_n).fold(0.0, f64::max)
                };
                let smaller = if drop(&layers[k - 1]) < drop(layer) {
                    k - 1
                } else {
                    k
                };
                layers.remove(smaller);
                continue 'refit;
            }
            if best.is_none() && !fitted_any {
                return Err(data_error(format!(
                    "layer {} (punctures at {:.1}–{:.1} mm): too few advancing samples before its \
                 punctures to fit its loading",
                    k + 1,
                    layer.min_depth_m * 1e3,
                    layer.max_depth_m * 1e3
                )));
            }
            let Some((_, contact, loading, cut)) = best else {
                layers.remove(k);
                if layers.is_empty() {
                    return Err(data_error(
                        "no force drop while advancing follows a loading that rises to it: the \
                     phase-aware needle model needs at least one puncture; the smooth model \
                     (`--model needle`) does not"
                            .into(),
                    ));
                }
                continue 'refit;
            };
            match (cut, models.last_mut()) {
                (Some(cut), Some(prev)) => prev.after = cut,
                (cut, None) => above = cut,
                (None, Some(_)) => {}
            }
            // The threshold through the layer's events.
            let points: Vec<[f64; 2]> = layer
                .events
                .iter()
                .map(|&e| [events[e].speed_mps, events[e].depth_m - contact])
                .collect();
            let threshold = fit_threshold(&points, if okamura { 0 } else { 2 });
            models.push(LayerModel {
                contact_depth_m: contact,
                loading,
                threshold,
                // Replaced by the fit below the next layer's contact, or the last layer's below.
                after: ShaftLaw {
                    constant_n: 0.0,
                    per_depth_npm: 0.0,
                    per_speed_nspm: 0.0,
                    per_depth_speed_nspm2: 0.0,
                    domain: loading.domain,
                    svr: None,
                },
                events: layer.events.len(),
                peak_force_n: layer.peak_force_n,
            });
        }
        break (b, models, above);
    };
    let nl = layers.len();
    // Below the last layer: every advancing sample past its drop.
    let tail: Vec<[f64; 4]> = b.advancing[nl].clone();
    if tail.len() < MIN_LAW_SAMPLES {
        return Err(data_error(format!(
            "only {} advancing samples below the deepest layer ({:.1} mm): too few to fit the \
             force after its puncture",
            tail.len(),
            layers[nl - 1].max_depth_m * 1e3
        )));
    }
    let col = |s: &[[f64; 4]], q: usize| s.iter().map(|x| x[q]).collect::<Vec<f64>>();
    if let Some(last) = models.last_mut() {
        last.after = shaft(&col(&tail, 0), &col(&tail, 1), &col(&tail, 2))?.0;
    }
    let (withdrawal, withdrawal_source) = if b.withdrawal.len() >= MIN_LAW_SAMPLES {
        let w = &b.withdrawal;
        let law = shaft(
            &w.iter().map(|x| x[0]).collect::<Vec<_>>(),
            &w.iter().map(|x| x[1]).collect::<Vec<_>>(),
            &w.iter().map(|x| x[2]).collect::<Vec<_>>(),
        )?
        .0;
        (law, WithdrawalSource::Measured)
    } else {
        (
            withdrawal_from_insertion(models.last().map(|l| &l.after)),
            WithdrawalSource::FromInsertion,
        )
    };
    let model = PhaseModel {
        above,
        layers: models,
        withdrawal,
        withdrawal_source,
        hold_band_mps,
    };
    model.validate().map_err(|(field, reason)| {
        data_error(format!("the identified phases are not usable: {field}: {reason}"))
    })?;
    Ok(model)
}

/// The withdrawal law of a capture without withdrawal ([`WithdrawalSource::FromInsertion`]):
/// the depth term of the deepest layer's cutting law, with the sign of the motion.
fn withdrawal_from_insertion(deepest: Option<&ShaftLaw>) -> ShaftLaw {
    let (per_depth_npm, domain) = match deepest {
        Some(after) => (
            after.per_depth_npm.max(0.0),
            Domain {
                depth_m: after.domain.depth_m,
                velocity_mps: [-after.domain.velocity_mps[1], -after.domain.velocity_mps[0]],
            },
        ),
        None => (
            0.0,
            Domain {
                depth_m: [0.0, 0.0],
                velocity_mps: [0.0, 0.0],
            },
        ),
    };
    ShaftLaw {
        constant_n: 0.0,
        per_depth_npm: -per_depth_npm,
        per_speed_nspm: 0.0,
        per_depth_speed_nspm2: 0.0,
        domain,
        svr: None,
    }
}

/// Deflection at puncture against speed: a polynomial of degree up to `max_degree` (2), lower
/// when the events hold fewer distinct speeds (a speed within 10 % of the range of another
/// counts as the same).
fn fit_threshold(points: &[[f64; 2]], max_degree: usize) -> Threshold {
    let speeds: Vec<f64> = points.iter().map(|p| p[0]).collect();
    let lo = speeds.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = speeds.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let mut sorted = speeds.clone();
    sorted.sort_by(f64::total_cmp);
    let tol = 0.1 * (hi - lo);
    let distinct = 1 + sorted.windows(2).filter(|w| w[1] - w[0] > tol).count();
    let degree = distinct.saturating_sub(1).min(max_degree);
    let targets: Vec<f64> = points.iter().map(|p| p[1]).collect();
    let coefficients = fit_linear(
        points.len(),
        |i| (0..=degree).map(|e| points[i][0].powi(e as i32)).collect(),
        &targets,
    )
    .unwrap_or_else(|_| vec![targets.iter().sum::<f64>() / targets.len().max(1) as f64]);
    let mut t = Threshold {
        coefficients,
        speed_mps: [lo, hi],
        rms_m: 0.0,
    };
    t.rms_m = (points
        .iter()
        .map(|p| (t.deflection_m(p[0]) - p[1]).powi(2))
        .sum::<f64>()
        / points.len().max(1) as f64)
        .sqrt();
    t
}
