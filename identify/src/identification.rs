//! What Li & Bi's three identifications (Sec. II-B, III-B–D) share: their options and report,
//! the capture columns they read, the SVR fits with their limits, and the model file and report
//! each one ends in ([`finish`]). The fits themselves are in `contact_identification` (hard and
//! soft contact) and `needle_identification` (needle puncture); each is compared with the
//! baselines on held-out data.
//!
//! - **Hard contact**: friction against normal force with a linear kernel; the paper's
//!   C = 1e11, ε = 0.003 kgf are the defaults, solved in SI as the identical scaled problem
//!   (C/g on slacks in N, ε·g), which gives the same w and b = g·b_kgf.
//! - **Soft contact**, two stages: a linear ε-SVR per constant-speed segment gives (wᵥ, mᵥ);
//!   RBF ε-SVRs of speed then give w(v) and m(v); `F(v, P) = w(v)·P + m(v)`.
//! - **Needle puncture**: an RBF ε-SVR of [depth, velocity] (C = 100, γ = 30, ε = 0.02 N),
//!   inputs scaled to [0, 1], on up to 350 samples spread over the capture's in-tissue samples (the paper trains on 350).
//!
//! Every SVR trains on at most [`IdentifyOptions::max_fit_samples`] rows (default
//! [`DEFAULT_MAX_FIT_SAMPLES`]): a longer capture is thinned to evenly spaced rows (the first
//! and the last always kept), deterministically, and [`Report::n_rows`] next to
//! [`Report::n_train`] says how many of how many were used. The solvers grow faster than
//! linearly in the samples, so without a budget a 10⁶-row capture never finishes; metrics and
//! input ranges still use every row (they are linear). The soft contact's first stage also
//! caps each segment at [`MAX_SEGMENT_SAMPLES`].
//!
//! Velocity comes from the capture's velocity column, or from its position by the paper's
//! pseudo-differentiation (Eq. 13) when it has none.

use std::path::Path;
use std::time::{Duration, Instant};

use serde::Serialize;

use crate::baselines::{RbfNetwork, RbfNetworkParams};
use crate::error::IdentifyError;
use crate::metrics::Metrics;
use capture::kind;
use capture::{Capture, CaptureKind};
use capture::{CaptureRef, sha256_hex};

use crate::model_file::{
    Hyperparameters, MODEL_FORMAT, MODEL_VERSION, ModelBody, ModelFile, ModelKind, Quantity, ScaledSvr,
    SvrHyper,
};
use capture::pseudo_differentiate;
use svm::{FitProgress, InputScaling, Kernel, SvrFit, SvrParams, fit_observed};

/// Standard gravity, to express the paper's kgf hyperparameters in SI.
pub(crate) const KGF_N: f64 = 9.806_65;
/// Pseudo-differentiation time constant when a capture has no velocity column, s.
const PSEUDO_DIFF_TAU_S: f64 = 0.01;
/// Default budget of training rows per identification (see the module documentation): far
/// above the paper's captures (31, 360 and 350 samples), low enough that every model fits a
/// 10⁶-row capture in seconds.
pub const DEFAULT_MAX_FIT_SAMPLES: usize = 20_000;
/// Soft contact: most rows each constant-speed segment's first-stage fit trains on (evenly
/// spaced over the segment). Those fits run the dense interior point, O(n³) per iteration,
/// which takes seconds from a few hundred samples on; the paper's segments hold 40.
pub const MAX_SEGMENT_SAMPLES: usize = 200;

/// What to identify and with which hyperparameters (None: the defaults of that model).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IdentifyOptions {
    /// Which model.
    pub kind: ModelKind,
    /// C (soft contact: of the second stage).
    pub c: Option<f64>,
    /// ε in the target's unit (soft contact: of the second stage, both w and m).
    pub epsilon: Option<f64>,
    /// RBF γ on the scaled inputs (ignored by the linear hard-contact model).
    pub gamma: Option<f64>,
    /// Needle: at most this many training samples.
    pub max_samples: usize,
    /// Every model: at most this many training rows, evenly spaced over the capture (the
    /// needle model takes the smaller of this and `max_samples`).
    pub max_fit_samples: usize,
    /// Needle: fit the rows the outlier screen finds too (they are reported either way).
    pub keep_outliers: bool,
}

impl IdentifyOptions {
    /// Defaults for `kind`.
    pub fn new(kind: ModelKind) -> Self {
        Self {
            kind,
            c: None,
            epsilon: None,
            gamma: None,
            max_samples: crate::NEEDLE_SAMPLES,
            max_fit_samples: DEFAULT_MAX_FIT_SAMPLES,
            keep_outliers: false,
        }
    }
}

/// Accuracy of the SVR model and of both baselines on the same data.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ComparedMetrics {
    /// The identified ε-SVR model.
    pub svr: Metrics,
    /// Coulomb (∝ normal force) + viscous (∝ velocity) least squares; friction models only.
    pub coulomb_viscous: Option<Metrics>,
    /// `F = Fc·sgn(v) + c·v + k·depth` least squares ([`CoulombViscousStiffness`](crate::CoulombViscousStiffness)); the
    /// needle only, whose force no friction law describes. `None` also where it could not be
    /// fitted (one speed: its three terms have rank 2; see [`Report::baselines_not_fitted`]).
    pub coulomb_viscous_stiffness: Option<Metrics>,
    /// RBF network (k-means centres, least-squares weights); `None` when it could not be
    /// fitted ([`Report::baselines_not_fitted`] says why).
    pub rbf_network: Option<Metrics>,
    /// The training force's mean as a constant: what any model must beat to say anything.
    /// The needle models.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mean: Option<Metrics>,
    /// Li & Bi's smooth ε-SVR over [depth, velocity], when the model is the phase-aware needle
    /// (whose own figures are then the ones under `svr`: the identified model's).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub smooth_svr: Option<Metrics>,
    /// Okamura's piecewise model fitted on the same layers ([`crate::PhaseForm::Okamura`]),
    /// with the phase-aware needle.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub okamura_piecewise: Option<Metrics>,
}

/// What an identification found, for people (a table) and programs (`--json`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Report {
    /// `hard`, `soft`, `needle`.
    pub model: String,
    /// Training samples of the final stage.
    pub n_train: usize,
    /// Rows of the training capture the fit could use (needle: in tissue); the fit trained
    /// on an evenly spaced `max_fit_samples` of them when there were more.
    pub n_rows: usize,
    /// Rows the SVR(s) trained on, at most `max_fit_samples` (soft contact: the first stage's,
    /// all segments together; for the others equal to `n_train`).
    pub n_fit_rows: usize,
    /// Support vectors (all SVRs of the model).
    pub n_sv: usize,
    /// The phase-aware needle: layers found.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub n_layers: Option<usize>,
    /// Linear model slope (hard contact).
    pub w: Option<f64>,
    /// Linear model intercept, N (hard contact).
    pub b: Option<f64>,
    /// The same intercept in kgf, to compare with the paper's Eq. 12.
    pub b_kgf: Option<f64>,
    /// Dual objective of the (final-stage) SVR(s), summed.
    pub dual_objective: f64,
    /// Relative duality gap, worst over the SVRs (of the certified solutions, before any
    /// support-vector budget reduced them).
    pub relative_gap: f64,
    /// With a support-vector budget that reduced a solution: from how many support vectors
    /// (all SVRs) and how far the reduced model is from the certified one.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reduction: Option<svm::ReductionReport>,
    /// Fit time of all SVRs, s.
    pub fit_seconds: f64,
    /// `test` when evaluated on a held-out capture, else `train`.
    pub evaluated_on: String,
    /// SVR and baselines on that data.
    pub metrics: ComparedMetrics,
    /// Soft contact: the first stage's (speed m/s, w, m N) per segment.
    pub stage1: Vec<[f64; 3]>,
    /// Hyperparameters used.
    pub hyperparameters: Vec<SvrHyper>,
    /// Inputs of which the test capture leaves the training domain (see [`out_of_domain`]):
    /// empty without a test capture or when it stays inside.
    pub test_out_of_domain: Vec<OutOfDomain>,
    /// The phase-aware needle: rows of the test capture outside the domain of the phase they
    /// were in, per phase (empty otherwise, or when every row stays inside).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub test_out_of_phase_domain: Vec<crate::PhaseExit>,
    /// The phase-aware needle: each part's parametric law against an ε-SVR on held-out
    /// strokes, and which one the model renders ([`crate::PartComparison`]).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub parts: Vec<crate::PartComparison>,
    /// The phase-aware needle: the same puncture table for the baselines that render
    /// punctures (Okamura's piecewise model, the smooth SVR).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub baseline_punctures: Vec<BaselinePunctures>,
    /// Needle: every puncture detected in the evaluation capture beside the model's along the
    /// same strokes ([`crate::compare_punctures`]); empty for the friction models.
    pub punctures: Vec<crate::PunctureComparison>,
    /// Baselines that could not be fitted on this capture, and why: the model is reported
    /// without them (their metrics are `null`).
    pub baselines_not_fitted: Vec<BaselineNotFitted>,
    /// Needle: the rows the outlier screen found in the training capture and in the test
    /// capture ([`crate::OutlierScreen`]), left out of every fit unless kept.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub outliers: Vec<crate::OutlierScreen>,
    /// What a user should know about the model before trusting it (a law that was not
    /// measured, a threshold measured at one speed only, outliers left out).
    pub warnings: Vec<String>,
}

/// A baseline left out of a report ([`Report::baselines_not_fitted`]).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BaselineNotFitted {
    /// Which: `coulomb_viscous`, `coulomb_viscous_stiffness`, `rbf_network`.
    pub baseline: String,
    /// Why, as its fit said.
    pub reason: String,
}

/// A baseline's metrics, or its name and reason in `skipped` when it could not be fitted.
pub(crate) fn baseline(
    name: &str,
    result: Result<Metrics, IdentifyError>,
    skipped: &mut Vec<BaselineNotFitted>,
) -> Option<Metrics> {
    match result {
        Ok(m) => Some(m),
        Err(e) => {
            skipped.push(BaselineNotFitted {
                baseline: name.into(),
                reason: e.to_string(),
            });
            None
        }
    }
}

/// A baseline's punctures beside the measured ones ([`Report::baseline_punctures`]).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BaselinePunctures {
    /// `okamura_piecewise` or `smooth_svr`.
    pub model: String,
    /// As [`Report::punctures`].
    pub punctures: Vec<crate::PunctureComparison>,
}

/// How far past either end of a training range, as a fraction of its width, a value may lie
/// and still count as inside it in [`out_of_domain`]. The training range is the extreme of the
/// samples the model was fitted on (the needle's: 350 of thousands), so a held-out capture
/// of the same protocol grazes its ends by noise alone (the committed needle test capture by
/// 2e-6 m of depth, the hard-contact one by 0.01 N); an RBF kernel on inputs scaled to [0, 1]
/// still reaches a few per cent past them.
pub const DOMAIN_MARGIN: f64 = 0.05;

/// How far one input of a capture leaves a model's training domain
/// ([`ModelFile::input_range`]), over the rows the model describes ([`model_rows`]).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OutOfDomain {
    /// The input's column name.
    pub input: String,
    /// Fraction of the rows whose value lies outside `range` by more than [`DOMAIN_MARGIN`] of
    /// its width, in (0, 1].
    pub fraction: f64,
    /// Smallest value of the input over those rows (all of them, inside or not).
    pub min: f64,
    /// Largest value of the input over those rows.
    pub max: f64,
    /// The training range, `[lo, hi]`.
    pub range: [f64; 2],
}

/// The rows of `c` a model of `model_kind` describes: every row for the friction models, the rows
/// in tissue (depth > 0) for the needle, as identification selects them.
pub fn model_rows(model_kind: ModelKind, c: &Capture) -> Result<Vec<usize>, IdentifyError> {
    Ok(match model_kind {
        ModelKind::NeedlePuncture | ModelKind::NeedlePhases => {
            let depth = c.column(kind::DEPTH_M)?;
            (0..c.len()).filter(|&i| depth[i] > 0.0).collect()
        }
        ModelKind::HardFriction | ModelKind::SoftFriction => (0..c.len()).collect(),
    })
}

/// The inputs of `model` that `test` takes outside the training domain (by more than
/// [`DOMAIN_MARGIN`] of a range's width), in the model's input order; empty when every
/// described row lies inside. An SVR extrapolates to its bias away
/// from its support vectors, so a held-out score on such data says little about the model:
/// whoever reports it should say so.
pub fn out_of_domain(model: &ModelFile, test: &Capture) -> Result<Vec<OutOfDomain>, IdentifyError> {
    let rows = model_rows(model.kind, test)?;
    let mut out = Vec::new();
    if rows.is_empty() {
        return Ok(out);
    }
    for (q, &[lo, hi]) in model.inputs.iter().zip(&model.input_range) {
        let column = model_column(test, &q.name)?;
        let values = rows.iter().map(|&i| column[i]);
        let margin = DOMAIN_MARGIN * (hi - lo);
        let outside = values
            .clone()
            .filter(|&v| v < lo - margin || v > hi + margin)
            .count();
        if outside == 0 {
            continue;
        }
        out.push(OutOfDomain {
            input: q.name.clone(),
            fraction: outside as f64 / rows.len() as f64,
            min: values.clone().fold(f64::INFINITY, f64::min),
            max: values.fold(f64::NEG_INFINITY, f64::max),
            range: [lo, hi],
        });
    }
    Ok(out)
}

/// A model and its report.
#[derive(Debug, Clone)]
pub struct Identified {
    /// The model file to save.
    pub model: ModelFile,
    /// The report.
    pub report: Report,
}

/// The samples a friction model needs.
pub(crate) struct FrictionData {
    pub(crate) time_s: Vec<f64>,
    pub(crate) normal_force_n: Vec<f64>,
    pub(crate) velocity_mps: Vec<f64>,
    pub(crate) friction_force_n: Vec<f64>,
    pub(crate) commanded_mps: Option<Vec<f64>>,
}

/// Column `name` of `c` as identification reads it: the column itself, or — for a velocity the
/// capture does not record — its position pseudo-differentiated (Li & Bi Eq. 13), so that
/// whoever evaluates a model on a capture sees the inputs it was fitted on.
pub fn model_column(c: &Capture, name: &str) -> Result<Vec<f64>, IdentifyError> {
    match name {
        kind::TANGENTIAL_VELOCITY_MPS => velocity(c, name, kind::TANGENTIAL_POSITION_M),
        kind::VELOCITY_MPS => velocity(c, name, kind::DEPTH_M),
        _ => Ok(c.column(name)?.to_vec()),
    }
}

pub(crate) fn velocity(
    c: &Capture,
    velocity_column: &str,
    position_column: &str,
) -> Result<Vec<f64>, IdentifyError> {
    if c.has_column(velocity_column) {
        return Ok(c.column(velocity_column)?.to_vec());
    }
    pseudo_differentiate(c.time(), c.column(position_column)?, PSEUDO_DIFF_TAU_S).map_err(|e| {
        IdentifyError::Data {
            path: c.source().to_owned(),
            reason: e.to_string(),
        }
    })
}

/// One identification to run: what every model kind's entry point reads.
#[derive(Clone, Copy)]
pub(crate) struct Job<'a> {
    /// The capture the model is fitted on.
    pub train: &'a Capture,
    /// The capture it is evaluated on (the training capture when `None`).
    pub test: Option<&'a Capture>,
    /// The model kind and its hyperparameters.
    pub options: &'a IdentifyOptions,
    /// Tolerance, budgets and progress of every SVR fit.
    pub limits: &'a FitLimits<'a>,
}

/// A friction job's data: every training row, the rows the fits train on, the held-out rows.
pub(crate) struct FrictionSets {
    /// Every row of the training capture.
    pub all: FrictionData,
    /// The rows the fits train on ([`FrictionData::thinned`] to the options' limit).
    pub fit: FrictionData,
    /// The test capture's rows, when there is one.
    pub held_out: Option<FrictionData>,
}

impl FrictionSets {
    /// The training capture's friction data, and the test capture's when there is one.
    pub(crate) fn of(job: &Job<'_>) -> Result<Self, IdentifyError> {
        let all = friction_data(job.train)?;
        let held_out = job.test.map(friction_data).transpose()?;
        let fit = all.thinned(job.options.max_fit_samples);
        Ok(Self { all, fit, held_out })
    }

    /// The rows models are evaluated on: the held-out ones, else every training row.
    pub(crate) fn eval(&self) -> &FrictionData {
        self.held_out.as_ref().unwrap_or(&self.all)
    }
}

/// `n` indices spread evenly over `0..n_all` (all of them when `n ≥ n_all`), first and last
/// included.
pub(crate) fn even_indices(n_all: usize, n: usize) -> Vec<usize> {
    if n >= n_all {
        return (0..n_all).collect();
    }
    let n = n.max(2);
    (0..n)
        .map(|k| ((k as f64) * n_all.saturating_sub(1) as f64 / (n - 1) as f64).round() as usize)
        .collect()
}

impl FrictionData {
    /// Rows.
    pub(crate) fn len(&self) -> usize {
        self.time_s.len()
    }

    /// At most `max_rows` rows, evenly spaced (see [`even_indices`]).
    pub(crate) fn thinned(&self, max_rows: usize) -> Self {
        let pick = even_indices(self.len(), max_rows);
        let take = |v: &[f64]| -> Vec<f64> { pick.iter().map(|&i| v[i]).collect() };
        Self {
            time_s: take(&self.time_s),
            normal_force_n: take(&self.normal_force_n),
            velocity_mps: take(&self.velocity_mps),
            friction_force_n: take(&self.friction_force_n),
            commanded_mps: self.commanded_mps.as_deref().map(take),
        }
    }
}

/// Refuses a capture of another kind than `expected`, saying what needed it.
pub(crate) fn require_kind(c: &Capture, expected: CaptureKind, reason: &str) -> Result<(), IdentifyError> {
    if c.metadata().kind() == expected {
        Ok(())
    } else {
        Err(IdentifyError::Data {
            path: c.source().to_owned(),
            reason: reason.into(),
        })
    }
}

pub(crate) fn friction_data(c: &Capture) -> Result<FrictionData, IdentifyError> {
    require_kind(c, CaptureKind::Rubbing, "friction models need a rubbing capture")?;
    Ok(FrictionData {
        time_s: c.time().to_vec(),
        normal_force_n: c.column(kind::NORMAL_FORCE_N)?.to_vec(),
        velocity_mps: velocity(c, kind::TANGENTIAL_VELOCITY_MPS, kind::TANGENTIAL_POSITION_M)?,
        friction_force_n: c.column(kind::FRICTION_FORCE_N)?.to_vec(),
        commanded_mps: c
            .has_column(kind::COMMANDED_VELOCITY_MPS)
            .then(|| c.column(kind::COMMANDED_VELOCITY_MPS).map(<[f64]>::to_vec))
            .transpose()?,
    })
}

/// How hard each SVR of an identification may work, and who watches it: the solver tolerance
/// and wall-clock budget of [`SvrParams`] (None: the library's defaults), and an observer shown
/// each fit's progress with the fit's name.
#[derive(Clone, Copy)]
pub struct FitLimits<'a> {
    /// Solver tolerance ([`svm::SvrParamsBuilder::tolerance`]).
    pub tolerance: Option<f64>,
    /// Wall-clock budget of each fit ([`svm::SvrParamsBuilder::time_budget`]); a fit that
    /// exceeds it is an error naming the gap it had reached.
    pub time_budget: Option<Duration>,
    /// Support-vector budget of each kernel SVR ([`svm::SvrParamsBuilder::max_sv`]): a larger
    /// solution is reduced, and the report says how far the reduced model is from it.
    pub max_sv: Option<usize>,
    /// Called as each fit advances, from whichever thread runs the fit (cross-validation
    /// folds run side by side).
    pub observer: &'a (dyn Fn(&str, &FitProgress) + Sync),
}

fn ignore_progress(_: &str, _: &FitProgress) {}

impl Default for FitLimits<'_> {
    fn default() -> Self {
        Self {
            tolerance: None,
            time_budget: None,
            max_sv: None,
            observer: &ignore_progress,
        }
    }
}

impl std::fmt::Debug for FitLimits<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("FitLimits")
            .field("tolerance", &self.tolerance)
            .field("time_budget", &self.time_budget)
            .field("max_sv", &self.max_sv)
            .finish_non_exhaustive()
    }
}

/// One ε-SVR fit to make: hyperparameters and samples, named so that no call site passes seven
/// positional numbers and slices.
pub(crate) struct SvrProblem<'a> {
    pub c: f64,
    pub epsilon: f64,
    pub kernel: Kernel,
    /// Inputs, row-major, `dim` per sample.
    pub x: &'a [f64],
    pub dim: usize,
    pub y: &'a [f64],
}

/// [`svr_with`] under the default limits.
pub(crate) fn svr(what: &str, problem: SvrProblem<'_>) -> Result<SvrFit, IdentifyError> {
    svr_with(&FitLimits::default(), what, problem)
}

/// Fits `problem` under `limits`; a failure names `what` was being fitted.
pub(crate) fn svr_with(
    limits: &FitLimits<'_>,
    what: &str,
    problem: SvrProblem<'_>,
) -> Result<SvrFit, IdentifyError> {
    let SvrProblem {
        c,
        epsilon,
        kernel,
        x,
        dim,
        y,
    } = problem;
    let mut builder = SvrParams::builder().c(c).epsilon(epsilon).kernel(kernel);
    if let Some(t) = limits.tolerance {
        builder = builder.tolerance(t);
    }
    if let Some(b) = limits.time_budget {
        builder = builder.time_budget(b);
    }
    builder = builder.max_sv(limits.max_sv);
    let params = builder.build().map_err(|source| IdentifyError::Svr {
        what: what.into(),
        source,
    })?;
    fit_observed(&params, x, dim, y, &|p| (limits.observer)(what, p)).map_err(|source| IdentifyError::Svr {
        what: what.into(),
        source,
    })
}

/// How the final SVRs were reduced to their support-vector budget, all together: the
/// support vectors before (`n_sv` after, those not reduced counted as they are), the largest
/// deviation and the RMS over the SVRs' own. `None` when none was reduced.
fn reduction_of(fits: &[&&SvrFit], n_sv: usize) -> Option<svm::ReductionReport> {
    let reduced: Vec<&svm::ReductionReport> = fits.iter().filter_map(|f| f.reduction.as_ref()).collect();
    if reduced.is_empty() {
        return None;
    }
    let removed: usize = reduced.iter().map(|r| r.from_sv).sum::<usize>()
        - fits
            .iter()
            .filter(|f| f.reduction.is_some())
            .map(|f| f.model.n_sv())
            .sum::<usize>();
    Some(svm::ReductionReport {
        from_sv: n_sv + removed,
        max_deviation: reduced.iter().map(|r| r.max_deviation).fold(0.0, f64::max),
        rms_deviation: reduced.iter().map(|r| r.rms_deviation).fold(0.0, f64::max),
    })
}

/// [`Metrics::compute`], a failure wrapped so that the message says the metrics failed.
pub(crate) fn metrics(time_s: &[f64], measured: &[f64], predicted: &[f64]) -> Result<Metrics, IdentifyError> {
    Metrics::compute(time_s, measured, predicted).map_err(|source| IdentifyError::Metrics {
        source: Box::new(source),
    })
}

pub(crate) fn capture_ref(path: &Path) -> CaptureRef {
    CaptureRef {
        path: path.to_owned(),
        sha256: std::fs::read(path).map(|b| sha256_hex(&b)).unwrap_or_default(),
    }
}

pub(crate) fn scaled(svr: svm::SvrModel, scaling: InputScaling) -> ScaledSvr {
    ScaledSvr {
        scaling,
        output_scale: 1.0,
        svr,
    }
}

pub(crate) fn range(x: &[f64], dim: usize) -> Vec<[f64; 2]> {
    (0..dim)
        .map(|k| {
            let col = x.iter().skip(k).step_by(dim);
            [
                col.clone().fold(f64::INFINITY, |a, &v| a.min(v)),
                col.fold(f64::NEG_INFINITY, |a, &v| a.max(v)),
            ]
        })
        .collect()
}

/// The RBF-network baseline fitted on (`x_train`, `y_train`) and evaluated at `x_eval`.
pub(crate) fn rbf_network(
    x_train: &[f64],
    dim: usize,
    y_train: &[f64],
    x_eval: &[f64],
) -> Result<Vec<f64>, IdentifyError> {
    let baseline = |source| IdentifyError::Baseline {
        what: "RBF network",
        source: Box::new(source),
    };
    RbfNetwork::fit(
        x_train,
        dim,
        y_train,
        &RbfNetworkParams::for_samples(y_train.len()),
    )
    .map_err(baseline)?
    .predict_many(x_eval)
    .map_err(baseline)
}

/// What one identification produced, for [`finish`] to assemble into a model file and its
/// report.
pub(crate) struct Fitted<'a> {
    pub(crate) kind: ModelKind,
    /// The capture it was fitted on.
    pub(crate) train: &'a Capture,
    /// The capture it is evaluated on, if not the training one.
    pub(crate) test: Option<&'a Capture>,
    pub(crate) inputs: Vec<Quantity>,
    pub(crate) output: Quantity,
    pub(crate) body: ModelBody,
    pub(crate) hyper: Vec<SvrHyper>,
    /// Training vectors (rows, or stage-1 points for the soft contact).
    pub(crate) n_train: usize,
    /// Rows of the training capture that the model applies to.
    pub(crate) n_rows: usize,
    /// Rows the SVR fits trained on, all of them together.
    pub(crate) n_fit_rows: usize,
    /// The SVR on the training capture, and on the evaluated one.
    pub(crate) train_metrics: Metrics,
    pub(crate) svr_metrics: Metrics,
    /// The baselines on the evaluated capture (the ones that apply to this model).
    pub(crate) coulomb_viscous: Option<Metrics>,
    pub(crate) coulomb_viscous_stiffness: Option<Metrics>,
    pub(crate) rbf_network: Option<Metrics>,
    pub(crate) mean: Option<Metrics>,
    /// Baselines that could not be fitted.
    pub(crate) baselines_not_fitted: Vec<BaselineNotFitted>,
    /// Every SVR fit behind the model (the soft contact's final two first).
    pub(crate) fits: &'a [&'a SvrFit],
    pub(crate) started: Instant,
    /// Per input, the [min, max] the model was fitted over.
    pub(crate) input_range: Vec<[f64; 2]>,
    /// A linear model's slope and intercept.
    pub(crate) w: Option<f64>,
    pub(crate) b: Option<f64>,
    /// The soft contact's stage-1 points (speed, w, m).
    pub(crate) stage1: Vec<[f64; 3]>,
}

pub(crate) fn finish(fitted: Fitted<'_>) -> Result<Identified, IdentifyError> {
    let Fitted {
        kind,
        train,
        test,
        inputs,
        output,
        body,
        hyper,
        n_train,
        n_rows,
        n_fit_rows,
        train_metrics,
        svr_metrics,
        coulomb_viscous,
        coulomb_viscous_stiffness,
        rbf_network,
        mean,
        baselines_not_fitted,
        fits,
        started,
        input_range,
        w,
        b,
        stage1,
    } = fitted;
    let n_sv = match &body {
        ModelBody::Single(m) => m.svr.n_sv(),
        ModelBody::TwoStage { slope, intercept } => slope.svr.n_sv() + intercept.svr.n_sv(),
        ModelBody::Phases(_) => 0,
    };
    let final_fits: Vec<&&SvrFit> = if kind == ModelKind::SoftFriction {
        fits.iter().take(2).collect()
    } else {
        fits.iter().collect()
    };
    let mut report = Report {
        model: kind.short_name().into(),
        n_train,
        n_rows,
        n_fit_rows,
        n_sv,
        n_layers: None,
        w,
        b,
        b_kgf: b.map(|b| b / KGF_N),
        dual_objective: final_fits.iter().map(|f| f.dual_objective).sum(),
        relative_gap: fits.iter().map(|f| f.relative_gap()).fold(0.0, f64::max),
        reduction: reduction_of(&final_fits, n_sv),
        fit_seconds: started.elapsed().as_secs_f64(),
        evaluated_on: if test.is_some() { "test" } else { "train" }.into(),
        metrics: ComparedMetrics {
            svr: svr_metrics,
            coulomb_viscous,
            coulomb_viscous_stiffness,
            rbf_network,
            mean,
            smooth_svr: None,
            okamura_piecewise: None,
        },
        stage1,
        hyperparameters: hyper.clone(),
        test_out_of_domain: Vec::new(),
        test_out_of_phase_domain: Vec::new(),
        parts: Vec::new(),
        baseline_punctures: Vec::new(),
        punctures: Vec::new(),
        baselines_not_fitted,
        outliers: Vec::new(),
        warnings: Vec::new(),
    };
    let mut training = vec![capture_ref(train.source())];
    training.retain(|r| !r.path.as_os_str().is_empty());
    let model = ModelFile {
        format: MODEL_FORMAT.into(),
        version: MODEL_VERSION,
        kind,
        inputs,
        output,
        body,
        hyperparameters: Hyperparameters::new(hyper),
        training,
        n_train,
        train_metrics: Some(train_metrics),
        test_metrics: test.map(|_| svr_metrics),
        input_range,
    };
    check_written(&report, &model, train, test)?;
    if let Some(t) = test {
        report.test_out_of_domain = out_of_domain(&model, t)?;
    }
    if kind == ModelKind::NeedlePuncture {
        report.punctures =
            crate::compare_punctures(&model, test.unwrap_or(train), &crate::PunctureParams::default())?;
    }
    Ok(Identified { model, report })
}

/// Refuses a fit that would write a non-finite metric (JSON has no infinity, so the file
/// could not be read back) or a model that [`ModelFile::validate`] would refuse on load,
/// naming the capture whose data made it so.
pub(crate) fn check_written(
    report: &Report,
    model: &ModelFile,
    train: &Capture,
    test: Option<&Capture>,
) -> Result<(), IdentifyError> {
    let eval = test.unwrap_or(train);
    let m = &report.metrics;
    let mut all = vec![
        ("training", "ε-SVR", train, model.train_metrics),
        (report.evaluated_on.as_str(), "ε-SVR", eval, Some(m.svr)),
        (report.evaluated_on.as_str(), "RBF network", eval, m.rbf_network),
        (report.evaluated_on.as_str(), "mean force", eval, m.mean),
    ];
    all.push((
        report.evaluated_on.as_str(),
        "Coulomb+viscous",
        eval,
        m.coulomb_viscous,
    ));
    all.push((
        report.evaluated_on.as_str(),
        "Coulomb+viscous+stiffness",
        eval,
        m.coulomb_viscous_stiffness,
    ));
    for (data, model_name, capture, metrics) in all {
        let Some(metrics) = metrics else { continue };
        for (name, value) in [
            ("AISE", metrics.aise),
            ("error bound", metrics.error_bound),
            ("RMSE", metrics.rmse),
        ] {
            if !value.is_finite() {
                return Err(IdentifyError::NonFiniteMetric {
                    path: capture.source().to_owned(),
                    what: format!("{name} of the {model_name} on the {data} data"),
                    value,
                });
            }
        }
    }
    model.validate().map_err(|(field, reason)| IdentifyError::Data {
        path: train.source().to_owned(),
        reason: format!("the fitted model would not load again: {field}: {reason}"),
    })
}
