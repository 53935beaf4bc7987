//! Identified models as force-law inputs: a model file's SVR through the allocation-free fast
//! path, with the box it was trained on.

use identify::{ModelBody, ModelFile, ModelKind, ScaledSvr};
use svm::FastSvr;

use super::model::{InputBox, ScalarModel};
use crate::error::HapticsError;

/// One SVR of a model file, evaluated by [`FastSvr`] (f32, SIMD, no allocation).
#[derive(Debug, Clone)]
pub struct SvrForceModel<const D: usize> {
    fast: FastSvr<D>,
    output_scale: f64,
    input_box: InputBox<D>,
}

impl<const D: usize> SvrForceModel<D> {
    /// From one scaled SVR and the training range of its inputs.
    pub fn new(svr: &ScaledSvr, range: &[[f64; 2]]) -> Result<Self, HapticsError> {
        let mut lo = [0.0; D];
        let mut hi = [0.0; D];
        for k in 0..D {
            let [a, b] = range.get(k).copied().unwrap_or([f64::NAN, f64::NAN]);
            lo[k] = a;
            hi[k] = b;
        }
        Ok(Self {
            fast: FastSvr::new(&svr.svr, &svr.scaling)?,
            output_scale: svr.output_scale,
            input_box: InputBox::new(lo, hi)?,
        })
    }
}

impl<const D: usize> ScalarModel<D> for SvrForceModel<D> {
    fn eval(&self, x: &[f64; D]) -> f64 {
        self.output_scale * self.fast.eval(x)
    }

    fn input_box(&self) -> InputBox<D> {
        self.input_box
    }
}

/// The one SVR of a model file that must be of `kind`.
fn single_model<const D: usize>(file: &ModelFile, kind: ModelKind) -> Result<SvrForceModel<D>, HapticsError> {
    match &file.body {
        ModelBody::Single(svr) if file.kind == kind => SvrForceModel::new(svr, &file.input_range),
        _ => Err(HapticsError::WrongModelKind {
            expected: kind,
            found: file.kind,
        }),
    }
}

/// The needle-puncture model of a model file, for [`super::needle::NeedleLaw`].
pub fn needle_model(file: &ModelFile) -> Result<SvrForceModel<2>, HapticsError> {
    single_model(file, ModelKind::NeedlePuncture)
}

/// The hard-contact friction model (normal force → friction) of a model file.
pub fn hard_friction_model(file: &ModelFile) -> Result<SvrForceModel<1>, HapticsError> {
    single_model(file, ModelKind::HardFriction)
}

/// The soft-contact model's slope w(v) and intercept m(v) (each of sliding speed).
pub fn soft_friction_models(file: &ModelFile) -> Result<(SvrForceModel<1>, SvrForceModel<1>), HapticsError> {
    match (&file.body, file.kind) {
        (ModelBody::TwoStage { slope, intercept }, ModelKind::SoftFriction) => {
            let speed = &file.input_range[..1];
            Ok((
                SvrForceModel::new(slope, speed)?,
                SvrForceModel::new(intercept, speed)?,
            ))
        }
        _ => Err(HapticsError::WrongModelKind {
            expected: ModelKind::SoftFriction,
            found: file.kind,
        }),
    }
}
