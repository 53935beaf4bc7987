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

    /// The largest |output| over a grid of `points_per_input` points on each input's
    /// [`ModelFile::input_range`] (the box a force law clamps its inputs to), with the input
    /// where it occurs. A non-finite output is returned as it is, so it is never below a limit.
    pub fn peak_output(&self, points_per_input: usize) -> (f64, Vec<f64>) {
        let n = points_per_input.max(2);
        let dim = self.input_range.len();
        let at = |index: usize| -> Vec<f64> {
            let mut rest = index;
            self.input_range
                .iter()
                .map(|&[lo, hi]| {
                    let k = rest % n;
                    rest /= n;
                    lo + (hi - lo) * k as f64 / (n - 1) as f64
                })
                .collect()
        };
        let total = n.saturating_pow(u32::try_from(dim).unwrap_or(u32::MAX));
        let mut peak = (0.0, at(0));
        for index in 0..total {
            let x = at(index);
            let y = self.predict(&x).abs();
            if y.is_nan() {
                return (f64::NAN, x);
            }
            if y > peak.0 {
                peak = (y, x);
            }
        }
        peak
    }
}

/// The bounds [`ModelFile::validate`] holds a model to. They come from the physics of what is
/// modelled (forces, depths and speeds at a hand-held haptic device) and from how models are
/// evaluated on the haptic thread (`svm::FastSvr`, in f32, every support vector every tick).
/// None of them is near what an identification from a real capture produces; each refuses a
/// corrupted or absurd number before it can become a force.
#[derive(Debug, Clone, Copy)]
pub struct Plausibility;

impl Plausibility {
    /// Largest |value| of an input bound or input offset, SI (m, m/s, N). Depths and speeds at
    /// a hand-held device stay below 1 m and 1 m/s and forces below 100 N; 10³ leaves
    /// decades of headroom and still refuses 1e308.
    pub const MAX_INPUT_MAGNITUDE: f64 = 1e3;
    /// Smallest input scale, SI: below 10⁻¹² (a picometre, a pN) the scaled inputs are
    /// rounding noise.
    pub const MIN_INPUT_SCALE: f64 = 1e-12;
    /// Largest input scale, SI: 10³ × [`Self::MAX_INPUT_MAGNITUDE`], beyond which every
    /// plausible input maps to the same point.
    pub const MAX_INPUT_SCALE: f64 = 1e6;
    /// Largest width of the training range in scaled units (`width / scale`): the fast path
    /// evaluates in f32, whose 24-bit mantissa resolves nothing of a kernel spread over more
    /// than ~10⁶ units. Identified models span 1 (min–max scaling) or ~10 (identity scaling
    /// of forces in N).
    pub const MAX_SCALED_SPAN: f64 = 1e6;
    /// Output scale, inclusive range. Positive: a sign flip belongs in the coefficients, and a
    /// zero scale renders no force at all. Identified models write 1.
    pub const OUTPUT_SCALE: [f64; 2] = [1e-6, 1e6];
    /// RBF/polynomial γ on the scaled inputs, inclusive range. At 10⁻⁶ the kernel is flat to
    /// 10⁻⁶ across a unit range (the model is its bias); at 10⁶ it is a spike a thousandth of
    /// the range wide. The paper's needle model uses 30, the search grid 0.5–50.
    pub const GAMMA: [f64; 2] = [1e-6, 1e6];
    /// Largest polynomial degree.
    pub const MAX_DEGREE: u32 = 10;
    /// Largest |value| of a coefficient, support vector, weight or bias: the f32 range, which
    /// the fast path evaluates in (a linear model at the paper's C ≈ 10¹⁰ has coefficients
    /// near C, so nothing tighter holds for every kernel; the device-limit check at load
    /// catches what is finite but too strong).
    pub const MAX_PARAMETER: f64 = f32::MAX as f64;
    /// Most support vectors in one SVR: the haptic thread evaluates every one of them each
    /// 1 ms tick, and identification fits at most `identify`'s sample budget.
    pub const MAX_SUPPORT_VECTORS: usize = 50_000;
}

/// Checks one scaled SVR of dimension `dim` whose inputs range over `ranges`.
fn check_svr(label: &str, m: &ScaledSvr, dim: usize, ranges: &[[f64; 2]]) -> Result<(), (String, String)> {
    let field = |f: &str| format!("body.{label}.{f}");
    let svr = &m.svr;
    if svr.dim != dim || m.scaling.offset.len() != dim || m.scaling.scale.len() != dim {
        return Err((field("svr.dim"), format!("expected dimension {dim}")));
    }
    if svr.support_vectors.len() != svr.coefficients.len() * dim {
        return Err((field("svr.support_vectors"), "length is not n_sv × dim".into()));
    }
    if svr.n_sv() > Plausibility::MAX_SUPPORT_VECTORS {
        return Err((
            field("svr.coefficients"),
            format!(
                "{} support vectors; at most {} can be evaluated on the haptic thread",
                svr.n_sv(),
                Plausibility::MAX_SUPPORT_VECTORS
            ),
        ));
    }
    let [lo, hi] = Plausibility::OUTPUT_SCALE;
    if !(m.output_scale.is_finite() && (lo..=hi).contains(&m.output_scale)) {
        return Err((
            field("output_scale"),
            format!(
                "{} is not in [{lo:e}, {hi:e}] (positive: a sign belongs in the coefficients)",
                m.output_scale
            ),
        ));
    }
    for (k, (&offset, &scale)) in m.scaling.offset.iter().zip(&m.scaling.scale).enumerate() {
        if !(offset.is_finite() && offset.abs() <= Plausibility::MAX_INPUT_MAGNITUDE) {
            return Err((
                field(&format!("scaling.offset[{k}]")),
                format!(
                    "{offset} is not finite within ±{:e}",
                    Plausibility::MAX_INPUT_MAGNITUDE
                ),
            ));
        }
        let (min, max) = (Plausibility::MIN_INPUT_SCALE, Plausibility::MAX_INPUT_SCALE);
        if !(scale.is_finite() && (min..=max).contains(&scale)) {
            return Err((
                field(&format!("scaling.scale[{k}]")),
                format!("{scale} is not in [{min:e}, {max:e}]"),
            ));
        }
        if let Some([a, b]) = ranges.get(k)
            && (b - a) / scale > Plausibility::MAX_SCALED_SPAN
        {
            return Err((
                field(&format!("scaling.scale[{k}]")),
                format!(
                    "{scale} spreads the input range [{a}, {b}] over more than {:e} units, \
                     beyond what f32 evaluation resolves",
                    Plausibility::MAX_SCALED_SPAN
                ),
            ));
        }
    }
    let [g_lo, g_hi] = Plausibility::GAMMA;
    let gamma_ok = |g: f64| g.is_finite() && (g_lo..=g_hi).contains(&g);
    match svr.kernel {
        Kernel::Linear => {}
        Kernel::Rbf { gamma } if !gamma_ok(gamma) => {
            return Err((
                field("svr.kernel.gamma"),
                format!("{gamma} is not in [{g_lo:e}, {g_hi:e}]"),
            ));
        }
        Kernel::Polynomial { gamma, coef0, degree } => {
            if !gamma_ok(gamma) {
                return Err((
                    field("svr.kernel.gamma"),
                    format!("{gamma} is not in [{g_lo:e}, {g_hi:e}]"),
                ));
            }
            if !(coef0.is_finite() && coef0.abs() <= Plausibility::MAX_INPUT_MAGNITUDE) {
                return Err((
                    field("svr.kernel.coef0"),
                    format!("{coef0} is not finite within ±1e3"),
                ));
            }
            if degree > Plausibility::MAX_DEGREE {
                return Err((
                    field("svr.kernel.degree"),
                    format!("{degree} exceeds {}", Plausibility::MAX_DEGREE),
                ));
            }
        }
        Kernel::Rbf { .. } => {}
    }
    let in_f32 = |v: &f64| v.is_finite() && v.abs() <= Plausibility::MAX_PARAMETER;
    let parameters: [(&str, &[f64]); 3] = [
        ("svr.support_vectors", &svr.support_vectors),
        ("svr.coefficients", &svr.coefficients),
        ("svr.weights", svr.weights.as_deref().unwrap_or(&[])),
    ];
    for (name, values) in parameters {
        if let Some(i) = values.iter().position(|v| !in_f32(v)) {
            return Err((
                field(&format!("{name}[{i}]")),
                format!(
                    "{} is not finite within the f32 range the haptic thread evaluates in",
                    values[i]
                ),
            ));
        }
    }
    if !in_f32(&svr.bias) {
        return Err((
            field("svr.bias"),
            format!(
                "{} is not finite within the f32 range the haptic thread evaluates in",
                svr.bias
            ),
        ));
    }
    if let Some(w) = &svr.weights
        && w.len() != dim
    {
        return Err((field("svr.weights"), format!("expected {dim} finite weights")));
    }
    Ok(())
}
