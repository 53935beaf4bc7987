//! Each part of a phase model against the project's ε-SVR on the same samples, measured on
//! strokes the fit did not see, and the SVR put in where it clearly wins.
//!
//! The parts are the phases of the model's own reading of its training capture
//! ([`PhaseModel::simulate`]): every membrane's loading, the cutting below every layer and
//! the withdrawal. For each, leave-one-stroke-out: the part's parametric law and an ε-SVR of
//! [depth, velocity] (RBF, the smooth needle model's C = 100, γ = 30 on inputs scaled to
//! [0, 1], ε = 0.02 N, at most 350 samples) are fitted on the other strokes and predict the
//! held-out one; the RMS of those errors over all strokes is the part's score. A loading is
//! scored on what the membrane adds to the law before it, as it is fitted. Where the SVR's
//! RMS is below 90 % of the law's, a cutting or withdrawal law is replaced by an SVR fitted on
//! all of its samples (each part SVR is reduced to at most 32 support vectors, in the folds
//! too) (loadings stay parametric: their threshold and peak come from the same
//! stiffness terms). A part seen in one stroke only cannot be scored and stays parametric.

use serde::Serialize;

use crate::error::IdentifyError;
use crate::identification::{SvrProblem, even_indices, svr};
use crate::needle_identification::{NEEDLE_C, NEEDLE_EPSILON_N, NEEDLE_GAMMA, NEEDLE_SAMPLES};
use crate::phases::{Loading, PartSvr, Phase, PhaseModel, ShaftLaw, Varies, fit_terms};
use svm::{InputScaling, Kernel, reduce_support};

/// Fraction of the law's held-out RMS the SVR must beat to replace it: a clear win, not noise.
const SVR_MUST_BEAT: f64 = 0.9;
/// Most samples an SVR of one part trains on: the paper's needle SVR's.
const MAX_SVR_SAMPLES: usize = NEEDLE_SAMPLES;
/// Most support vectors of a part's SVR ([`svm::reduce_support`]): the haptic tick evaluates
/// it in f64, and 32 RBF terms keep that well under a microsecond. The held-out score is the
/// reduced model's, so the choice is made on what is rendered.
const MAX_PART_SV: usize = 32;

/// One part's score.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PartComparison {
    /// Which part ([`Phase::describe`]).
    pub part: String,
    /// Its samples in the training capture.
    pub samples: usize,
    /// Strokes they come from (the held-out folds).
    pub strokes: usize,
    /// Leave-one-stroke-out RMS error of the parametric law, N (`None`: one stroke only).
    pub parametric_rmse_n: Option<f64>,
    /// The same of the ε-SVR, N.
    pub svr_rmse_n: Option<f64>,
    /// `parametric` or `svr`: what the model renders for this part.
    pub uses: &'static str,
}

/// One sample of a part: stroke, depth, velocity, target (force, or for a loading what the
/// membrane adds).
type Sample = (usize, f64, f64, f64);

/// Scores every part of `model` on its training trajectory and puts an SVR in where it wins.
pub(crate) fn compare_parts(
    model: &mut PhaseModel,
    depth_m: &[f64],
    velocity_mps: &[f64],
    force_n: &[f64],
) -> Result<Vec<PartComparison>, IdentifyError> {
    let steps = model.simulate(depth_m, velocity_mps);
    let mut parts: Vec<(Phase, Vec<Sample>)> = Vec::new();
    let mut stroke = 0usize;
    for i in 0..steps.len() {
        if i > 0 && depth_m[i] > 0.0 && depth_m[i - 1] <= 0.0 {
            stroke += 1;
        }
        let (d, v, f) = (depth_m[i], velocity_mps[i], force_n[i]);
        let phase = steps[i].phase;
        let target = match phase {
            Phase::Loading(k) => f - base(model, k, d, v),
            Phase::Cutting(_) | Phase::Withdrawal if !steps[i].ruptured => f,
            _ => continue,
        };
        match parts.iter_mut().find(|(p, _)| *p == phase) {
            Some((_, samples)) => samples.push((stroke, d, v, target)),
            None => parts.push((phase, vec![(stroke, d, v, target)])),
        }
    }
    let mut out = Vec::with_capacity(parts.len());
    for (phase, samples) in parts {
        let mut strokes: Vec<usize> = samples.iter().map(|s| s.0).collect();
        strokes.sort_unstable();
        strokes.dedup();
        let mut row = PartComparison {
            part: phase.describe(),
            samples: samples.len(),
            strokes: strokes.len(),
            parametric_rmse_n: None,
            svr_rmse_n: None,
            uses: "parametric",
        };
        if strokes.len() >= 2 {
            let contact = match phase {
                Phase::Loading(k) => model.layers[k].contact_depth_m,
                _ => 0.0,
            };
            let (mut law_sse, mut svr_sse, mut n) = (0.0, 0.0, 0usize);
            for &held in &strokes {
                let (fit_on, test_on): (Vec<Sample>, Vec<Sample>) = samples.iter().partition(|s| s.0 != held);
                let law = parametric(phase, contact, &fit_on)?;
                let smooth = part_svr(&fit_on)?;
                for &(_, d, v, y) in &test_on {
                    law_sse += (y - law(d, v)).powi(2);
                    svr_sse += (y - smooth.eval(d, v)).powi(2);
                    n += 1;
                }
            }
            let (law_rmse, svr_rmse) = ((law_sse / n as f64).sqrt(), (svr_sse / n as f64).sqrt());
            row.parametric_rmse_n = Some(law_rmse);
            row.svr_rmse_n = Some(svr_rmse);
            let shaft = match phase {
                Phase::Cutting(k) => Some(&mut model.layers[k].after),
                Phase::Withdrawal => Some(&mut model.withdrawal),
                _ => None,
            };
            if let Some(law) = shaft
                && svr_rmse < SVR_MUST_BEAT * law_rmse
            {
                law.svr = Some(part_svr(&samples)?);
                row.uses = "svr";
            }
        }
        out.push(row);
    }
    Ok(out)
}

/// The force below layer `k`'s membrane before it loads: the cutting law of the layer above.
fn base(model: &PhaseModel, k: usize, d: f64, v: f64) -> f64 {
    k.checked_sub(1)
        .and_then(|j| model.layers.get(j))
        .map_or(0.0, |l| l.after.eval_raw(d, v))
}

/// The part's parametric form fitted on `samples`, as a predictor.
fn parametric(
    phase: Phase,
    contact_m: f64,
    samples: &[Sample],
) -> Result<Box<dyn Fn(f64, f64) -> f64>, IdentifyError> {
    let d: Vec<f64> = samples.iter().map(|s| s.1).collect();
    let v: Vec<f64> = samples.iter().map(|s| s.2).collect();
    let y: Vec<f64> = samples.iter().map(|s| s.3).collect();
    Ok(match phase {
        Phase::Loading(_) => {
            let keep = [true, true, true, Varies::of(&d, &v).speed];
            let x = fit_terms(y.len(), |i| Loading::features(d[i] - contact_m, v[i]), keep, &y)?;
            Box::new(move |dd: f64, vv: f64| {
                let f = Loading::features(dd - contact_m, vv);
                (0..4).map(|j| x[j] * f[j]).sum()
            })
        }
        _ => {
            let (law, _) = ShaftLaw::fit_restricted(&d, &v, &y, true)?;
            Box::new(move |dd: f64, vv: f64| law.linear(dd, vv))
        }
    })
}

/// An ε-SVR of the part's samples (see the module documentation).
fn part_svr(samples: &[Sample]) -> Result<PartSvr, IdentifyError> {
    let pick = even_indices(samples.len(), MAX_SVR_SAMPLES.min(samples.len()));
    let x: Vec<f64> = pick.iter().flat_map(|&i| [samples[i].1, samples[i].2]).collect();
    let y: Vec<f64> = pick.iter().map(|&i| samples[i].3).collect();
    let scaling = InputScaling::min_max(&x, 2);
    let xs = scaling.apply(&x);
    let fit = svr(
        "phase part SVR",
        SvrProblem {
            c: NEEDLE_C,
            epsilon: NEEDLE_EPSILON_N,
            kernel: Kernel::Rbf { gamma: NEEDLE_GAMMA },
            x: &xs,
            dim: 2,
            y: &y,
        },
    )?;
    let reduced = reduce_support(&fit.model, &xs, 2, MAX_PART_SV).map_err(|source| IdentifyError::Svr {
        what: "phase part SVR's support-vector budget".into(),
        source,
    })?;
    Ok(PartSvr {
        scaling,
        svr: reduced.model,
    })
}
