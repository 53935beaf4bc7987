//! The plausibility bounds every reader of a model file holds it to, and the one rule for an
//! SVR's hyperparameters wherever they are written.

use svm::{InputScaling, Kernel, SvrModel};

impl Plausibility {
    /// The one rule for an SVR's hyperparameters wherever they are written (a command line,
    /// a scene, a search grid, a trade table): `Err((name, value, reason))`.
    pub fn check_hyperparameters(
        c: Option<f64>,
        epsilon: Option<f64>,
        gamma: Option<f64>,
    ) -> Result<(), (&'static str, f64, &'static str)> {
        let [c_lo, c_hi] = Self::C;
        let [g_lo, g_hi] = Self::GAMMA;
        let checks: [(&'static str, Option<f64>, bool, &'static str); 3] = [
            (
                "c",
                c,
                c.is_none_or(|v| (c_lo..=c_hi).contains(&v)),
                "C must be in [1e-6, 1e15]: below, the model is its bias",
            ),
            (
                "epsilon",
                epsilon,
                epsilon.is_none_or(|v| (0.0..=Self::MAX_EPSILON).contains(&v)),
                "ε must be in [0, 1e3] (the target's unit)",
            ),
            (
                "gamma",
                gamma,
                gamma.is_none_or(|v| (g_lo..=g_hi).contains(&v)),
                "γ must be in [1e-6, 1e6] (on the scaled inputs)",
            ),
        ];
        match checks.into_iter().find(|(_, _, ok, _)| !ok) {
            Some((name, value, _, reason)) => Err((name, value.unwrap_or(f64::NAN), reason)),
            None => Ok(()),
        }
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
    /// Regularisation constant C, inclusive range. Below 10⁻⁶ every dual coefficient is below
    /// a millionth of the target's unit: the model is its bias (C = 1e-300 rendered 0 N
    /// everywhere). Li & Bi's hard contact uses 1e11 kgf⁻¹ ≈ 1.0e10 N⁻¹; 10¹⁵ leaves room
    /// above it and refuses a C whose coefficients would overflow f32.
    pub const C: [f64; 2] = [1e-6, 1e15];
    /// Largest ε, in the target's unit (N): a tube wider than any force a hand-held device
    /// renders fits nothing.
    pub const MAX_EPSILON: f64 = 1e3;
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

/// The checks of one SVR of a model file, wherever it sits (a smooth model's, a phase's part):
/// shapes, the support-vector cap, scaling, kernel and parameters. `label` is its field under
/// `body`.
pub(crate) fn check_svr_parts(
    label: &str,
    scaling: &InputScaling,
    output_scale: f64,
    svr: &SvrModel,
    dim: usize,
    ranges: &[[f64; 2]],
) -> Result<(), (String, String)> {
    let field = |f: &str| format!("body.{label}.{f}");
    if svr.dim != dim || scaling.offset.len() != dim || scaling.scale.len() != dim {
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
    if !(output_scale.is_finite() && (lo..=hi).contains(&output_scale)) {
        return Err((
            field("output_scale"),
            format!(
                "{} is not in [{lo:e}, {hi:e}] (positive: a sign belongs in the coefficients)",
                output_scale
            ),
        ));
    }
    for (k, (&offset, &scale)) in scaling.offset.iter().zip(&scaling.scale).enumerate() {
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
