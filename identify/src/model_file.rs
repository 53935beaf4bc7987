//! Identified models on disk: self-describing JSON, validated on load.
//!
//! A model file says what it models (kind, inputs and output with units), how to evaluate it
//! (input scaling, the SVR(s)), how it was made (hyperparameters, a SHA-256 of each training
//! capture and of the hyperparameters) and how well it fits (training and held-out metrics).
//! Loading checks the format version and every shape, so a truncated or hand-edited file is a
//! typed error naming the file and the field, never a wrong force on the haptic thread.

use std::fmt;
use std::path::Path;

use serde::{Deserialize, Serialize};

use capture::json_file;
use capture::{CaptureRef, sha256_hex};

use crate::error::IdentifyError;
use crate::metrics::Metrics;
use crate::phases::PhaseModel;
use crate::plausibility::{Plausibility, check_svr_parts};
use svm::{InputScaling, Kernel, SvrModel};

/// Format name in every model file.
pub const MODEL_FORMAT: &str = "palpus-model";
/// Current model file version.
pub const MODEL_VERSION: u32 = 1;

/// What a model computes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ModelKind {
    /// Hard-contact friction from normal force (linear kernel).
    HardFriction,
    /// Soft-contact friction from sliding speed and normal force (two-stage).
    SoftFriction,
    /// Needle axial force from depth and velocity (RBF kernel).
    NeedlePuncture,
    /// Needle axial force by phases: layers, their loading, puncture thresholds and the force
    /// after each ([`crate::PhaseModel`]).
    NeedlePhases,
}

impl ModelKind {
    /// `hard`, `soft`, `needle`.
    pub fn short_name(self) -> &'static str {
        match self {
            Self::HardFriction => "hard",
            Self::SoftFriction => "soft",
            Self::NeedlePuncture => "needle",
            Self::NeedlePhases => "needle-phases",
        }
    }
}

impl fmt::Display for ModelKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.short_name())
    }
}

/// One SVR with the affine maps around it: `y = output_scale · f((x − offset) / scale)`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ScaledSvr {
    /// Input scaling applied before the SVR.
    pub scaling: InputScaling,
    /// Factor applied to the SVR's output.
    pub output_scale: f64,
    /// The fitted SVR.
    pub svr: SvrModel,
}

impl ScaledSvr {
    /// Evaluates at `x` (same length as the scaling). Allocates; the haptic loop uses the fast
    /// path built from this.
    pub fn predict(&self, x: &[f64]) -> f64 {
        let mut scaled = vec![0.0; x.len()];
        self.scaling.apply_into(x, &mut scaled);
        self.output_scale * self.svr.predict(&scaled)
    }
}

/// How the model is evaluated.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "structure", rename_all = "snake_case")]
pub enum ModelBody {
    /// One SVR over all inputs.
    Single(ScaledSvr),
    /// Li & Bi's soft contact: `F(v, P) = w(v)·P + m(v)`, with w and m each an SVR of v.
    TwoStage {
        /// Slope w(v).
        slope: ScaledSvr,
        /// Intercept m(v), N.
        intercept: ScaledSvr,
    },
    /// The phase-aware needle model: a state machine over [depth, velocity].
    Phases(Box<PhaseModel>),
}

/// An input or output of a model.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Quantity {
    /// Name with unit suffix, as the capture column it comes from.
    pub name: String,
}

/// Hyperparameters, as used.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Hyperparameters {
    /// Per SVR: a label (`svr`, `slope`, `intercept`, `stage1`), C, ε and the kernel.
    pub svrs: Vec<SvrHyper>,
    /// SHA-256 of the canonical JSON of `svrs`.
    pub sha256: String,
}

/// One SVR's hyperparameters.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SvrHyper {
    /// Which SVR.
    pub label: String,
    /// C.
    pub c: f64,
    /// ε, in the unit of that SVR's target.
    pub epsilon: f64,
    /// Kernel.
    pub kernel: Kernel,
}

impl Hyperparameters {
    /// Packs the list with its hash.
    pub fn new(svrs: Vec<SvrHyper>) -> Self {
        let canonical = serde_json::to_string(&svrs).unwrap_or_default();
        Self {
            sha256: sha256_hex(canonical.as_bytes()),
            svrs,
        }
    }
}

/// A whole model file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ModelFile {
    /// Always [`MODEL_FORMAT`].
    pub format: String,
    /// Always [`MODEL_VERSION`] when written by this version.
    pub version: u32,
    /// What it models.
    pub kind: ModelKind,
    /// Inputs, in evaluation order.
    pub inputs: Vec<Quantity>,
    /// Output.
    pub output: Quantity,
    /// The model.
    pub body: ModelBody,
    /// How it was made.
    pub hyperparameters: Hyperparameters,
    /// What it was trained on.
    pub training: Vec<CaptureRef>,
    /// Number of training samples (of the final stage).
    pub n_train: usize,
    /// Accuracy on the training data.
    pub train_metrics: Option<Metrics>,
    /// Accuracy on held-out data, if evaluated.
    pub test_metrics: Option<Metrics>,
    /// Range of each input seen in training, for clamping out-of-range queries.
    pub input_range: Vec<[f64; 2]>,
}

impl ModelFile {
    /// Evaluates the model at `x` (inputs in the order of [`ModelFile::inputs`]).
    pub fn predict(&self, x: &[f64]) -> f64 {
        Self::predict_body(&self.body)(x)
    }

    /// The evaluation of a model body, as a closure.
    pub fn predict_body(body: &ModelBody) -> impl Fn(&[f64]) -> f64 + '_ {
        move |x: &[f64]| match body {
            ModelBody::Single(m) => m.predict(x),
            // Inputs: sliding speed, normal force.
            ModelBody::TwoStage { slope, intercept } => {
                slope.predict(&x[..1]) * x[1] + intercept.predict(&x[..1])
            }
            // Without a trajectory: a fresh site reached at constant speed.
            ModelBody::Phases(p) => p.steady(x[0], x[1]),
        }
    }

    /// Writes the model atomically.
    pub fn save(&self, path: &Path) -> Result<(), IdentifyError> {
        Ok(json_file::save_pretty(path, self)?)
    }

    /// Reads and validates a model file.
    pub fn load(path: &Path) -> Result<Self, IdentifyError> {
        Ok(json_file::load(path, Self::validate)?)
    }

    /// Parses and validates a model file's bytes; `path` names it in errors.
    pub fn from_slice(bytes: &[u8], path: &Path) -> Result<Self, IdentifyError> {
        Ok(json_file::parse(bytes, path, Self::validate)?)
    }

    /// Checks version, shapes and plausibility (see [`Plausibility`]); `Err((field, reason))`.
    /// Every reader of model files goes through this, so a corrupted or hand-edited number is
    /// refused with its field before it can reach a force law.
    pub fn validate(&self) -> Result<(), (String, String)> {
        let bad = |field: &str, reason: String| Err((field.to_owned(), reason));
        if self.format != MODEL_FORMAT {
            return bad("format", format!("`{}` is not `{MODEL_FORMAT}`", self.format));
        }
        if self.version != MODEL_VERSION {
            return bad(
                "version",
                format!(
                    "{} is not supported (this build reads {MODEL_VERSION})",
                    self.version
                ),
            );
        }
        let expected_inputs = match self.kind {
            ModelKind::HardFriction => 1,
            ModelKind::SoftFriction | ModelKind::NeedlePuncture | ModelKind::NeedlePhases => 2,
        };
        if self.inputs.len() != expected_inputs || self.input_range.len() != expected_inputs {
            return bad(
                "inputs",
                format!("a {} model has {expected_inputs} inputs", self.kind),
            );
        }
        for (k, &[lo, hi]) in self.input_range.iter().enumerate() {
            let field = format!("input_range[{k}]");
            if !(lo.is_finite() && hi.is_finite()) {
                return Err((field, format!("[{lo}, {hi}] is not finite")));
            }
            if lo.abs().max(hi.abs()) > Plausibility::MAX_INPUT_MAGNITUDE {
                return Err((
                    field,
                    format!(
                        "[{lo}, {hi}] exceeds ±{:e} (SI units: m, m/s, N)",
                        Plausibility::MAX_INPUT_MAGNITUDE
                    ),
                ));
            }
            if lo >= hi {
                return Err((
                    field,
                    format!("[{lo}, {hi}]: the lower bound must be below the upper"),
                ));
            }
        }
        for (field, m) in [
            ("train_metrics", &self.train_metrics),
            ("test_metrics", &self.test_metrics),
        ] {
            if let Some(m) = m
                && let Some((name, v)) = [("aise", m.aise), ("error_bound", m.error_bound), ("rmse", m.rmse)]
                    .into_iter()
                    .find(|(_, v)| !(v.is_finite() && *v >= 0.0))
            {
                return Err((
                    format!("{field}.{name}"),
                    format!("{v} is not a finite non-negative number"),
                ));
            }
        }
        // The speed range is the first input of the soft model's two SVRs.
        let ranges = &self.input_range;
        match (&self.body, self.kind) {
            (ModelBody::Single(m), ModelKind::HardFriction) => check_svr("single", m, 1, ranges),
            (ModelBody::Single(m), ModelKind::NeedlePuncture) => check_svr("single", m, 2, ranges),
            (ModelBody::TwoStage { slope, intercept }, ModelKind::SoftFriction) => {
                check_svr("slope", slope, 1, &ranges[..1])?;
                check_svr("intercept", intercept, 1, &ranges[..1])
            }
            (ModelBody::Phases(p), ModelKind::NeedlePhases) => p.validate(),
            _ => bad("body", format!("structure does not fit a {} model", self.kind)),
        }
    }
}

/// Checks one scaled SVR of dimension `dim` whose inputs range over `ranges`.
fn check_svr(label: &str, m: &ScaledSvr, dim: usize, ranges: &[[f64; 2]]) -> Result<(), (String, String)> {
    check_svr_parts(label, &m.scaling, m.output_scale, &m.svr, dim, ranges)
}
