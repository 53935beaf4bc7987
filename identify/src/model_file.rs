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
}

impl ModelKind {
    /// `hard`, `soft`, `needle`.
    pub fn short_name(self) -> &'static str {
        match self {
            Self::HardFriction => "hard",
            Self::SoftFriction => "soft",
            Self::NeedlePuncture => "needle",
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

    /// Checks version and shapes; `Err((field, reason))`.
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
            ModelKind::SoftFriction | ModelKind::NeedlePuncture => 2,
        };
        if self.inputs.len() != expected_inputs || self.input_range.len() != expected_inputs {
            return bad(
                "inputs",
                format!("a {} model has {expected_inputs} inputs", self.kind),
            );
        }
        let check = |label: &str, m: &ScaledSvr, dim: usize| -> Result<(), (String, String)> {
            let field = |f: &str| format!("body.{label}.{f}");
            if m.svr.dim != dim || m.scaling.offset.len() != dim || m.scaling.scale.len() != dim {
                return Err((field("svr.dim"), format!("expected dimension {dim}")));
            }
            if m.svr.support_vectors.len() != m.svr.coefficients.len() * dim {
                return Err((field("svr.support_vectors"), "length is not n_sv × dim".into()));
            }
            let finite = m
                .svr
                .support_vectors
                .iter()
                .chain(&m.svr.coefficients)
                .chain(&m.scaling.offset)
                .all(|v| v.is_finite())
                && m.svr.bias.is_finite()
                && m.output_scale.is_finite()
                && m.scaling.scale.iter().all(|s| s.is_finite() && *s != 0.0);
            if !finite {
                return Err((field("svr"), "contains a non-finite value or a zero scale".into()));
            }
            if let Some(w) = &m.svr.weights
                && (w.len() != dim || !w.iter().all(|v| v.is_finite()))
            {
                return Err((field("svr.weights"), format!("expected {dim} finite weights")));
            }
            Ok(())
        };
        match (&self.body, self.kind) {
            (ModelBody::Single(m), ModelKind::HardFriction) => check("single", m, 1),
            (ModelBody::Single(m), ModelKind::NeedlePuncture) => check("single", m, 2),
            (ModelBody::TwoStage { slope, intercept }, ModelKind::SoftFriction) => {
                check("slope", slope, 1)?;
                check("intercept", intercept, 1)
            }
            _ => bad("body", format!("structure does not fit a {} model", self.kind)),
        }
    }
}
