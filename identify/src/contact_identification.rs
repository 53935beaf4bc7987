//! Li & Bi's friction identifications (Sec. II-B, III-B–C): hard contact (a linear ε-SVR of
//! friction against normal force, the paper's C = 1e11, ε = 0.003 kgf) and soft contact in two
//! stages (a linear ε-SVR per constant-speed segment, then RBF ε-SVRs of speed for its slope and
//! offset), each compared with the friction baselines on held-out data.

use std::path::Path;
use std::time::Instant;

use crate::baselines::CoulombViscous;
use crate::error::IdentifyError;
use crate::identification::{
    BaselineNotFitted, Fitted, FrictionData, FrictionSets, Identified, Job, KGF_N, MAX_SEGMENT_SAMPLES,
    SvrProblem, baseline, even_indices, finish, metrics, range, rbf_network, scaled, svr, svr_with,
};
use crate::metrics::Metrics;
use crate::model_file::{ModelBody, ModelFile, ModelKind, Quantity, SvrHyper};
use capture::kind;
use svm::{InputScaling, Kernel, SvrFit};

/// Both baselines for friction data, evaluated on `eval`. The RBF network sees the inputs the
/// SVR model sees: normal force alone for hard contact (whose law ignores speed, and whose
/// held-out trajectory runs at other speeds), normal force and speed for soft contact.
/// A baseline that cannot be fitted on the data is left out with its reason in `skipped`.
fn friction_baselines(
    tr: &FrictionData,
    eval: &FrictionData,
    with_speed: bool,
    skipped: &mut Vec<BaselineNotFitted>,
) -> (Option<Metrics>, Option<Metrics>) {
    let cv = CoulombViscous::fit(&tr.normal_force_n, &tr.velocity_mps, &tr.friction_force_n).and_then(|cv| {
        let cv_pred: Vec<f64> = (0..eval.time_s.len())
            .map(|i| cv.predict(eval.normal_force_n[i], eval.velocity_mps[i]))
            .collect();
        metrics(&eval.time_s, &eval.friction_force_n, &cv_pred)
    });
    let inputs = |d: &FrictionData| -> Vec<f64> {
        (0..d.time_s.len())
            .flat_map(|i| {
                if with_speed {
                    vec![d.normal_force_n[i], d.velocity_mps[i]]
                } else {
                    vec![d.normal_force_n[i]]
                }
            })
            .collect()
    };
    let (x_tr, x_ev) = (inputs(tr), inputs(eval));
    let dim = if with_speed { 2 } else { 1 };
    let net = rbf_network(&x_tr, dim, &tr.friction_force_n, &x_ev)
        .and_then(|pred| metrics(&eval.time_s, &eval.friction_force_n, &pred));
    (
        baseline("coulomb_viscous", cv, skipped),
        baseline("rbf_network", net, skipped),
    )
}

/// Hard contact: one linear ε-SVR of friction against normal force (defaults: the paper's
/// C = 1e11, ε = 0.003 kgf, in SI).
pub(crate) fn hard(job: &Job<'_>) -> Result<Identified, IdentifyError> {
    let started = Instant::now();
    let (train, test, o, limits) = (job.train, job.test, job.options, job.limits);
    let sets = FrictionSets::of(job)?;
    let (all, tr, held_out, ev) = (&sets.all, &sets.fit, &sets.held_out, sets.eval());
    let (c, epsilon) = (o.c.unwrap_or(1e11 / KGF_N), o.epsilon.unwrap_or(0.003 * KGF_N));
    let f = svr_with(
        limits,
        "hard-contact SVR",
        SvrProblem {
            c,
            epsilon,
            kernel: Kernel::Linear,
            x: &tr.normal_force_n,
            dim: 1,
            y: &tr.friction_force_n,
        },
    )?;
    let w = f.model.linear_weights().map(|w| w[0]);
    let b = f.model.bias;
    let model = scaled(f.model.clone(), InputScaling::identity(1));
    let predict = |d: &FrictionData| -> Result<Metrics, IdentifyError> {
        let predicted: Vec<f64> = d.normal_force_n.iter().map(|p| model.predict(&[*p])).collect();
        metrics(&d.time_s, &d.friction_force_n, &predicted)
    };
    let train_metrics = predict(all)?;
    let svr_metrics = match &held_out {
        Some(t) => predict(t)?,
        None => train_metrics,
    };
    let mut skipped = Vec::new();
    let (cv, net) = friction_baselines(tr, ev, false, &mut skipped);
    let hyper = vec![SvrHyper {
        label: "svr".into(),
        c,
        epsilon,
        kernel: Kernel::Linear,
    }];
    finish(Fitted {
        kind: ModelKind::HardFriction,
        train,
        test,
        inputs: vec![Quantity {
            name: kind::NORMAL_FORCE_N.into(),
        }],
        output: Quantity {
            name: kind::FRICTION_FORCE_N.into(),
        },
        body: ModelBody::Single(model),
        hyper,
        n_train: tr.len(),
        n_rows: all.len(),
        n_fit_rows: tr.len(),
        train_metrics,
        svr_metrics,
        coulomb_viscous: cv,
        coulomb_viscous_stiffness: None,
        rbf_network: net,
        mean: None,
        baselines_not_fitted: skipped,
        fits: &[&f],
        started,
        input_range: range(&all.normal_force_n, 1),
        w,
        b: Some(b),
        stage1: Vec::new(),
    })
}

/// The first soft-contact stage: one linear ε-SVR per constant-speed segment.
pub(crate) struct StageOne {
    /// (mean measured speed m/s, w, m N) per segment.
    pub(crate) points: Vec<[f64; 3]>,
    /// The fits behind them.
    pub(crate) fits: Vec<SvrFit>,
    /// Sample indices of each segment.
    pub(crate) segments: Vec<Vec<usize>>,
    /// Rows the fits trained on, all segments together (at most [`MAX_SEGMENT_SAMPLES`] each).
    pub(crate) fit_rows: usize,
}

/// Stage 1 of the soft contact: friction against normal force per constant-speed segment,
/// with the paper's hard-contact hyperparameters (the same sensor measures both).
pub(crate) fn stage_one(tr: &FrictionData, source: &Path) -> Result<StageOne, IdentifyError> {
    let Some(commanded) = &tr.commanded_mps else {
        return Err(IdentifyError::Data {
            path: source.to_owned(),
            reason:
                "soft-contact identification needs constant-speed segments (column commanded_velocity_mps)"
                    .into(),
        });
    };
    let mut speeds: Vec<f64> = Vec::new();
    for &v in commanded {
        if !speeds.contains(&v) {
            speeds.push(v);
        }
    }
    let (c1, eps1) = (1e11 / KGF_N, 0.003 * KGF_N);
    let mut out = StageOne {
        points: Vec::new(),
        fits: Vec::new(),
        segments: Vec::new(),
        fit_rows: 0,
    };
    for &v in &speeds {
        let idx: Vec<usize> = (0..commanded.len()).filter(|&i| commanded[i] == v).collect();
        if idx.len() < 3 {
            continue;
        }
        let fit_idx: Vec<usize> = even_indices(idx.len(), MAX_SEGMENT_SAMPLES)
            .into_iter()
            .map(|k| idx[k])
            .collect();
        let p: Vec<f64> = fit_idx.iter().map(|&i| tr.normal_force_n[i]).collect();
        let f: Vec<f64> = fit_idx.iter().map(|&i| tr.friction_force_n[i]).collect();
        let speed = idx.iter().map(|&i| tr.velocity_mps[i]).sum::<f64>() / idx.len() as f64;
        let fitted = svr(
            &format!("stage-1 SVR at {v} m/s"),
            SvrProblem {
                c: c1,
                epsilon: eps1,
                kernel: Kernel::Linear,
                x: &p,
                dim: 1,
                y: &f,
            },
        )?;
        let w = fitted.model.linear_weights().map_or(0.0, |w| w[0]);
        out.points.push([speed, w, fitted.model.bias]);
        out.fits.push(fitted);
        out.fit_rows += fit_idx.len();
        out.segments.push(idx);
    }
    if out.points.len() < 3 {
        return Err(IdentifyError::Data {
            path: source.to_owned(),
            reason: format!(
                "{} constant-speed segments with ≥ 3 samples; the second stage needs at least 3",
                out.points.len()
            ),
        });
    }
    Ok(out)
}

/// Soft contact: [`stage_one`]'s per-segment lines, then RBF ε-SVRs of speed for their slope
/// and offset.
pub(crate) fn soft(job: &Job<'_>) -> Result<Identified, IdentifyError> {
    let started = Instant::now();
    let (train, test, o, limits) = (job.train, job.test, job.options, job.limits);
    let sets = FrictionSets::of(job)?;
    let (all, tr, held_out, ev) = (&sets.all, &sets.fit, &sets.held_out, sets.eval());
    let StageOne {
        points: stage1,
        fits,
        fit_rows,
        ..
    } = stage_one(tr, train.source())?;
    // Stage 2: RBF ε-SVRs of speed for w and m, on speeds scaled to [0, 1].
    let v: Vec<f64> = stage1.iter().map(|s| s[0]).collect();
    let scaling = InputScaling::min_max(&v, 1);
    let v_scaled = scaling.apply(&v);
    let (c2, gamma) = (o.c.unwrap_or(100.0), o.gamma.unwrap_or(2.0));
    let eps_w = o.epsilon.unwrap_or(0.002);
    let eps_m = o.epsilon.unwrap_or(0.002);
    let ws: Vec<f64> = stage1.iter().map(|s| s[1]).collect();
    let ms: Vec<f64> = stage1.iter().map(|s| s[2]).collect();
    let fw = svr_with(
        limits,
        "slope SVR w(v)",
        SvrProblem {
            c: c2,
            epsilon: eps_w,
            kernel: Kernel::Rbf { gamma },
            x: &v_scaled,
            dim: 1,
            y: &ws,
        },
    )?;
    let fm = svr_with(
        limits,
        "intercept SVR m(v)",
        SvrProblem {
            c: c2,
            epsilon: eps_m,
            kernel: Kernel::Rbf { gamma },
            x: &v_scaled,
            dim: 1,
            y: &ms,
        },
    )?;
    let body = ModelBody::TwoStage {
        slope: scaled(fw.model.clone(), scaling.clone()),
        intercept: scaled(fm.model.clone(), scaling),
    };
    let model_eval = |d: &FrictionData| -> Vec<f64> {
        let mf = ModelFile::predict_body(&body);
        (0..d.time_s.len())
            .map(|i| mf(&[d.velocity_mps[i], d.normal_force_n[i]]))
            .collect()
    };
    let train_metrics = metrics(&all.time_s, &all.friction_force_n, &model_eval(all))?;
    let svr_metrics = match &held_out {
        Some(t) => metrics(&t.time_s, &t.friction_force_n, &model_eval(t))?,
        None => train_metrics,
    };
    let mut skipped = Vec::new();
    let (cv, net) = friction_baselines(tr, ev, true, &mut skipped);
    let hyper = vec![
        SvrHyper {
            label: "stage1".into(),
            c: 1e11 / KGF_N,
            epsilon: 0.003 * KGF_N,
            kernel: Kernel::Linear,
        },
        SvrHyper {
            label: "slope".into(),
            c: c2,
            epsilon: eps_w,
            kernel: Kernel::Rbf { gamma },
        },
        SvrHyper {
            label: "intercept".into(),
            c: c2,
            epsilon: eps_m,
            kernel: Kernel::Rbf { gamma },
        },
    ];
    let mut all_fits = vec![&fw, &fm];
    all_fits.extend(fits.iter());
    let x_range: Vec<f64> = (0..all.len())
        .flat_map(|i| [all.velocity_mps[i], all.normal_force_n[i]])
        .collect();
    finish(Fitted {
        kind: ModelKind::SoftFriction,
        train,
        test,
        inputs: vec![
            Quantity {
                name: kind::TANGENTIAL_VELOCITY_MPS.into(),
            },
            Quantity {
                name: kind::NORMAL_FORCE_N.into(),
            },
        ],
        output: Quantity {
            name: kind::FRICTION_FORCE_N.into(),
        },
        body,
        hyper,
        n_train: stage1.len(),
        n_rows: all.len(),
        n_fit_rows: fit_rows,
        train_metrics,
        svr_metrics,
        coulomb_viscous: cv,
        coulomb_viscous_stiffness: None,
        rbf_network: net,
        mean: None,
        baselines_not_fitted: skipped,
        fits: &all_fits,
        started,
        input_range: range(&x_range, 2),
        w: None,
        b: None,
        stage1,
    })
}
