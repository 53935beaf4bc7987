//! ε-support-vector regression (Li & Bi Sec. II, Eqs. 8–10).
//!
//! Primal: `min ½‖w‖² + C Σ(ξᵢ + ξᵢ*)` subject to `|yᵢ − f(xᵢ)| ≤ ε + ξ`, `ξ, ξ* ≥ 0`.
//! Dual (what is solved): `min ½ βᵀKβ + ε Σ|βᵢ| − yᵀβ` subject to `Σ βᵢ = 0`, `−C ≤ βᵢ ≤ C`,
//! with `f(x) = Σ βᵢ K(xᵢ, x) + b`.
//!
//! One SMO (libsvm's solver and memory layout) serves the ε-SVR beyond the interior point's
//! reach and `recognize`'s pairwise C-SVCs ([`solve_svc`]); [`solve_smo`] runs it over any
//! [`KernelRows`].
//!
//! Every fallible function of the crate (fits, libsvm model files, the fast evaluators) returns
//! the one error type [`SvmError`].
//!
//! Imports no other palpus crate: identification (`identify`) and surface recognition
//! (`recognize`) both build on it.

mod bordered;
mod certificate;
mod compensated;
mod data;
mod error;
mod exp;
mod export;
mod fast;
mod fit;
mod ipm;
mod kernel;
mod linear_exact;
mod low_rank;
mod model;
mod params;
mod polish;
mod reduce;
mod sample;
mod smo;
mod smo_finish;

pub use bordered::{SvdSolution, least_squares_svd};
pub use certificate::ACCEPT_GAP;
pub use error::SvmError;
pub use export::{read_libsvm_model, read_libsvm_model_with_dim, to_libsvm_string, write_libsvm_model};
pub use fast::{ExactSvr, FAST_EXP2_MAX_REL_ERROR, FastSvr, LANES, fast_exp2};
pub use fit::{ReductionReport, SvrFit, fit, fit_observed, slack};
pub use kernel::{Kernel, dot};
pub use model::{InputScaling, SvrModel};
pub use params::{FitProgress, Solver, SvrParams, SvrParamsBuilder};
pub use reduce::{Reduction, reduce_support};
#[doc(hidden)]
pub use sample::needle_like_model;
pub use smo::{
    GramRows, KernelRows, PairStep, RowStorage, RowValue, SelectionCurvature, SmoSettings,
    SmoSettingsBuilder, SmoSolution, libsvm_rho, solve_smo, solve_svc,
};
