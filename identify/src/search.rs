//! Hyperparameter selection: k-fold cross-validation over a grid of (C, ε, γ).
//!
//! Folds are contiguous blocks in time, not shuffled samples: neighbouring samples of one
//! recording are nearly copies of each other, and a shuffled split would score interpolation
//! between them. The soft contact's second stage is validated leave-one-speed-out, on the
//! held-out segment's raw samples. Each explored point reports what a user trades: held-out
//! AISE, support vectors (the cost of every haptic evaluation), fit time and predict time.
//!
//! A point's folds are fitted side by side on rayon's pool (`palpus --threads`): each fold's
//! times are its own wall-clock, taken while the other folds share the machine, so they are
//! the times of a loaded machine; `--threads 1` times each fit alone.

use std::time::Instant;

use rayon::prelude::*;
use serde::Serialize;

use crate::contact_identification::stage_one;
use crate::error::IdentifyError;
use crate::identification::{
    DEFAULT_MAX_FIT_SAMPLES, FitLimits, FrictionData, KGF_N, SvrProblem, friction_data, metrics, svr_with,
};
use crate::model_file::ModelKind;
use crate::needle_identification::{needle_data, spread};
use capture::Capture;
use svm::{InputScaling, Kernel};

/// The grid to explore.
#[derive(Debug, Clone, PartialEq)]
pub struct SearchGrid {
    /// Values of C.
    pub c: Vec<f64>,
    /// Values of ε (target units).
    pub epsilon: Vec<f64>,
    /// Values of γ (ignored by the linear hard-contact model).
    pub gamma: Vec<f64>,
    /// Folds (the soft contact uses one per speed instead).
    pub folds: usize,
}

impl SearchGrid {
    /// A grid around each model's defaults, a decade or so each way.
    pub fn default_for(kind: ModelKind) -> Self {
        match kind {
            ModelKind::HardFriction => Self {
                c: [1e3, 1e7, 1e11].iter().map(|c| c / KGF_N).collect(),
                epsilon: [0.001, 0.003, 0.01].iter().map(|e| e * KGF_N).collect(),
                gamma: vec![1.0],
                folds: 5,
            },
            ModelKind::SoftFriction => Self {
                c: vec![1.0, 10.0, 100.0, 1000.0],
                epsilon: vec![0.001, 0.002, 0.005],
                gamma: vec![0.5, 2.0, 5.0, 10.0],
                folds: 0,
            },
            // The phase-aware needle is compared with the smooth SVR, whose grid this is.
            ModelKind::NeedlePuncture | ModelKind::NeedlePhases => Self {
                c: vec![10.0, 100.0, 1000.0],
                epsilon: vec![0.01, 0.02, 0.05],
                gamma: vec![10.0, 30.0, 50.0],
                folds: 5,
            },
        }
    }
}

/// One explored point.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SearchPoint {
    /// C.
    pub c: f64,
    /// ε.
    pub epsilon: f64,
    /// γ (absent for the linear model).
    pub gamma: Option<f64>,
    /// Mean held-out AISE over the folds, N².
    pub cv_aise: f64,
    /// Mean support vectors per fitted model.
    pub n_sv: f64,
    /// Mean fit time per fold, s.
    pub fit_seconds: f64,
    /// Mean time of one prediction, ns.
    pub predict_ns: f64,
    /// Why the point could not be evaluated, if it could not.
    pub failed: Option<String>,
}

struct Fold {
    aise: f64,
    n_sv: f64,
    fit_s: f64,
    predict_ns: f64,
}

fn mean_folds(folds: Vec<Fold>, c: f64, epsilon: f64, gamma: Option<f64>) -> SearchPoint {
    let k = folds.len().max(1) as f64;
    SearchPoint {
        c,
        epsilon,
        gamma,
        cv_aise: folds.iter().map(|f| f.aise).sum::<f64>() / k,
        n_sv: folds.iter().map(|f| f.n_sv).sum::<f64>() / k,
        fit_seconds: folds.iter().map(|f| f.fit_s).sum::<f64>() / k,
        predict_ns: folds.iter().map(|f| f.predict_ns).sum::<f64>() / k,
        failed: None,
    }
}

/// Contiguous fold `k` of `folds` over `n` samples: (training indices, validation indices).
fn split(n: usize, folds: usize, k: usize) -> (Vec<usize>, Vec<usize>) {
    let lo = k * n / folds;
    let hi = (k + 1) * n / folds;
    ((0..lo).chain(hi..n).collect(), (lo..hi).collect())
}

/// Cross-validates every grid point on `train`; `progress(done, total)` after each point.
pub fn search(
    kind: ModelKind,
    train: &Capture,
    max_samples: usize,
    grid: &SearchGrid,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<Vec<SearchPoint>, IdentifyError> {
    search_with(kind, train, max_samples, grid, &FitLimits::default(), progress)
}

/// [`search`] with every fold's fit under `limits` (a solver tolerance, a support-vector
/// budget), so that the cross-validated AISE is that of the models those limits give.
pub fn search_with(
    kind: ModelKind,
    train: &Capture,
    max_samples: usize,
    grid: &SearchGrid,
    limits: &FitLimits<'_>,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<Vec<SearchPoint>, IdentifyError> {
    let gammas: Vec<Option<f64>> = if kind == ModelKind::HardFriction {
        vec![None]
    } else {
        grid.gamma.iter().map(|g| Some(*g)).collect()
    };
    let total = grid.c.len() * grid.epsilon.len() * gammas.len();
    let mut points = Vec::with_capacity(total);
    let data = Data::load(kind, train, max_samples)?;
    for &c in &grid.c {
        for &epsilon in &grid.epsilon {
            for &gamma in &gammas {
                let point = match data.cross_validate(c, epsilon, gamma, grid.folds, limits) {
                    Ok(folds) => mean_folds(folds, c, epsilon, gamma),
                    Err(e) => SearchPoint {
                        c,
                        epsilon,
                        gamma,
                        cv_aise: f64::INFINITY,
                        n_sv: f64::NAN,
                        fit_seconds: f64::NAN,
                        predict_ns: f64::NAN,
                        failed: Some(e.to_string()),
                    },
                };
                points.push(point);
                progress(points.len(), total);
            }
        }
    }
    Ok(points)
}

/// Passes over the rows when timing predictions: the fastest is kept, so that one context
/// switch or a cold cache during a pass over a small fold does not decide a point's cost.
pub const PREDICT_TIMING_PASSES: usize = 5;

/// The predictions `predict` makes of `rows` rows, and the time of one, ns: the fastest of
/// [`PREDICT_TIMING_PASSES`] passes.
pub fn timed_predictions(rows: usize, mut predict: impl FnMut() -> Vec<f64>) -> (Vec<f64>, f64) {
    let mut fastest = f64::INFINITY;
    let mut predicted = Vec::new();
    for _ in 0..PREDICT_TIMING_PASSES {
        let started = Instant::now();
        predicted = std::hint::black_box(predict());
        fastest = fastest.min(started.elapsed().as_secs_f64() * 1e9 / rows.max(1) as f64);
    }
    (predicted, fastest)
}

/// The point with the lowest held-out AISE.
pub fn best(points: &[SearchPoint]) -> Option<&SearchPoint> {
    points
        .iter()
        .filter(|p| p.failed.is_none())
        .min_by(|a, b| a.cv_aise.total_cmp(&b.cv_aise))
}

enum Data {
    /// Row-major inputs, targets, time; inputs scaled per fold when `scale`.
    Regression {
        x: Vec<f64>,
        dim: usize,
        y: Vec<f64>,
        time: Vec<f64>,
        scale: bool,
    },
    /// Soft contact: the raw data and stage 1.
    Soft {
        raw: FrictionData,
        points: Vec<[f64; 3]>,
        segments: Vec<Vec<usize>>,
    },
}

impl Data {
    fn load(kind: ModelKind, train: &Capture, max_samples: usize) -> Result<Self, IdentifyError> {
        Ok(match kind {
            ModelKind::HardFriction => {
                // The same evenly spaced rows identification trains on by default.
                let d = friction_data(train)?.thinned(DEFAULT_MAX_FIT_SAMPLES);
                Self::Regression {
                    x: d.normal_force_n,
                    dim: 1,
                    y: d.friction_force_n,
                    time: d.time_s,
                    scale: false,
                }
            }
            ModelKind::NeedlePuncture | ModelKind::NeedlePhases => {
                let (time, x, y) = spread(&needle_data(train)?, max_samples);
                Self::Regression {
                    x,
                    dim: 2,
                    y,
                    time,
                    scale: true,
                }
            }
            ModelKind::SoftFriction => {
                let raw = friction_data(train)?.thinned(DEFAULT_MAX_FIT_SAMPLES);
                let one = stage_one(&raw, train.source())?;
                Self::Soft {
                    raw,
                    points: one.points,
                    segments: one.segments,
                }
            }
        })
    }

    fn cross_validate(
        &self,
        c: f64,
        epsilon: f64,
        gamma: Option<f64>,
        folds: usize,
        limits: &FitLimits<'_>,
    ) -> Result<Vec<Fold>, IdentifyError> {
        let kernel = gamma.map_or(Kernel::Linear, |gamma| Kernel::Rbf { gamma });
        match self {
            Self::Regression {
                x,
                dim,
                y,
                time,
                scale,
            } => {
                let (n, dim) = (y.len(), *dim);
                let folds = folds.clamp(2, n);
                (0..folds)
                    .into_par_iter()
                    .map(|k| {
                        let (tr, va) = split(n, folds, k);
                        let x_tr: Vec<f64> = tr
                            .iter()
                            .flat_map(|&i| x[i * dim..(i + 1) * dim].iter().copied())
                            .collect();
                        let y_tr: Vec<f64> = tr.iter().map(|&i| y[i]).collect();
                        let scaling = if *scale {
                            InputScaling::min_max(&x_tr, dim)
                        } else {
                            InputScaling::identity(dim)
                        };
                        let started = Instant::now();
                        let f = svr_with(
                            limits,
                            "cross-validation fold",
                            SvrProblem {
                                c,
                                epsilon,
                                kernel,
                                x: &scaling.apply(&x_tr),
                                dim,
                                y: &y_tr,
                            },
                        )?;
                        let fit_s = started.elapsed().as_secs_f64();
                        let mut scaled = vec![0.0; dim];
                        let (predicted, predict_ns) = timed_predictions(va.len(), || {
                            va.iter()
                                .map(|&i| {
                                    scaling.apply_into(&x[i * dim..(i + 1) * dim], &mut scaled);
                                    f.model.predict(&scaled)
                                })
                                .collect()
                        });
                        let t: Vec<f64> = va.iter().map(|&i| time[i]).collect();
                        let m: Vec<f64> = va.iter().map(|&i| y[i]).collect();
                        let aise = metrics(&t, &m, &predicted)?.aise;
                        Ok(Fold {
                            aise,
                            n_sv: f.model.n_sv() as f64,
                            fit_s,
                            predict_ns,
                        })
                    })
                    .collect()
            }
            Self::Soft {
                raw,
                points,
                segments,
            } => (0..points.len())
                .into_par_iter()
                .map(|k| {
                    let keep: Vec<&[f64; 3]> = points
                        .iter()
                        .enumerate()
                        .filter(|(j, _)| *j != k)
                        .map(|(_, p)| p)
                        .collect();
                    let v: Vec<f64> = keep.iter().map(|p| p[0]).collect();
                    let scaling = InputScaling::min_max(&v, 1);
                    let vs = scaling.apply(&v);
                    let started = Instant::now();
                    let fit_column = |name, column: usize| {
                        let targets: Vec<f64> = keep.iter().map(|p| p[column]).collect();
                        svr_with(
                            limits,
                            name,
                            SvrProblem {
                                c,
                                epsilon,
                                kernel,
                                x: &vs,
                                dim: 1,
                                y: &targets,
                            },
                        )
                    };
                    let w = fit_column("slope fold", 1)?;
                    let m = fit_column("intercept fold", 2)?;
                    let fit_s = started.elapsed().as_secs_f64();
                    let seg = &segments[k];
                    let (predicted, predict_ns) = timed_predictions(seg.len(), || {
                        seg.iter()
                            .map(|&i| {
                                let mut s = [0.0];
                                scaling.apply_into(&[raw.velocity_mps[i]], &mut s);
                                w.model.predict(&s) * raw.normal_force_n[i] + m.model.predict(&s)
                            })
                            .collect()
                    });
                    let t: Vec<f64> = seg.iter().map(|&i| raw.time_s[i]).collect();
                    let meas: Vec<f64> = seg.iter().map(|&i| raw.friction_force_n[i]).collect();
                    let aise = metrics(&t, &meas, &predicted)?.aise;
                    Ok(Fold {
                        aise,
                        n_sv: (w.model.n_sv() + m.model.n_sv()) as f64,
                        fit_s,
                        predict_ns,
                    })
                })
                .collect(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn folds_are_contiguous_and_cover_every_sample_once() {
        let mut seen = [0; 23];
        for k in 0..5 {
            let (tr, va) = split(23, 5, k);
            assert_eq!(tr.len() + va.len(), 23);
            assert!(va.windows(2).all(|w| w[1] == w[0] + 1));
            for i in va {
                seen[i] += 1;
            }
        }
        assert!(seen.iter().all(|&s| s == 1));
    }

    #[test]
    fn best_skips_failed_points() {
        let p = |aise: f64, failed: bool| SearchPoint {
            c: 1.0,
            epsilon: aise,
            gamma: None,
            cv_aise: aise,
            n_sv: 1.0,
            fit_seconds: 0.0,
            predict_ns: 0.0,
            failed: failed.then(|| "x".into()),
        };
        let points = [p(0.5, false), p(0.1, true), p(0.3, false)];
        assert_eq!(best(&points).unwrap().cv_aise, 0.3);
    }
}
