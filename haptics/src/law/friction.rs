//! Surface friction rendered from identified models (Li & Bi Sec. III-B, III-C).
//!
//! - Hard contact: friction linear in the normal force, `F = f(P)`, identified with a linear
//!   kernel; independent of speed.
//! - Soft contact (two-stage): per speed a line in P, whose slope and intercept are RBF SVRs of
//!   the speed: `F = w(|v|)·P + m(|v|)`.
//!
//! Both give a magnitude; [`FrictionLaw::friction_n`] returns it, and the environment turns it
//! into a force opposing the sliding direction.

use super::model::{ScalarModel, eval_clamped};

/// A friction magnitude from normal force and sliding speed.
pub trait FrictionLaw: Send {
    /// Friction magnitude (≥ 0) for normal force `normal_force_n` (≥ 0) at sliding speed
    /// `speed_mps` (≥ 0), and the evaluation flags.
    fn friction_n(&self, normal_force_n: f64, speed_mps: f64) -> (f64, u32);
}

/// Hard contact: `F = f(P)`.
#[derive(Debug, Clone)]
pub struct HardFriction<M> {
    model: M,
}

impl<M: ScalarModel<1>> HardFriction<M> {
    /// The law over a model of friction against normal force.
    pub fn new(model: M) -> Self {
        Self { model }
    }
}

impl<M: ScalarModel<1>> FrictionLaw for HardFriction<M> {
    fn friction_n(&self, normal_force_n: f64, _speed_mps: f64) -> (f64, u32) {
        if normal_force_n.is_nan() || normal_force_n <= 0.0 {
            // Out of contact: no friction, whatever the model's intercept says.
            return (0.0, 0);
        }
        let e = eval_clamped(&self.model, &[normal_force_n]);
        (e.value.max(0.0), e.flags)
    }
}

/// Soft contact: `F = w(|v|)·P + m(|v|)`.
#[derive(Debug, Clone)]
pub struct SoftFriction<W, I> {
    slope: W,
    intercept: I,
    max_normal_force_n: f64,
}

impl<W: ScalarModel<1>, I: ScalarModel<1>> SoftFriction<W, I> {
    /// The law over models of slope and intercept against speed. The normal force is clamped
    /// to `max_normal_force_n`, the largest the slopes were fitted on.
    pub fn new(slope: W, intercept: I, max_normal_force_n: f64) -> Self {
        Self {
            slope,
            intercept,
            max_normal_force_n,
        }
    }
}

impl<W: ScalarModel<1>, I: ScalarModel<1>> FrictionLaw for SoftFriction<W, I> {
    fn friction_n(&self, normal_force_n: f64, speed_mps: f64) -> (f64, u32) {
        if normal_force_n.is_nan() || normal_force_n <= 0.0 {
            return (0.0, 0);
        }
        let mut flags = 0;
        let p = if normal_force_n > self.max_normal_force_n {
            flags |= crate::safety::flag::MODEL_INPUT_CLAMPED;
            self.max_normal_force_n
        } else {
            normal_force_n
        };
        let v = speed_mps.abs();
        let w = eval_clamped(&self.slope, &[v]);
        let m = eval_clamped(&self.intercept, &[v]);
        flags |= w.flags | m.flags;
        ((w.value * p + m.value).max(0.0), flags)
    }
}

/// No friction.
#[derive(Debug, Clone, Copy, Default)]
pub struct Frictionless;

impl FrictionLaw for Frictionless {
    fn friction_n(&self, _: f64, _: f64) -> (f64, u32) {
        (0.0, 0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::law::reference::{hard_contact_model, soft_contact_models};
    use crate::safety::flag;
    use sim::{HardContact, SoftContact};

    #[test]
    fn hard_friction_is_the_model_in_contact_and_zero_out_of_it() {
        let law = HardFriction::new(hard_contact_model(HardContact::li_bi()));
        assert_eq!(
            law.friction_n(5.0, 0.01),
            (HardContact::li_bi().friction_n(5.0), 0)
        );
        assert_eq!(law.friction_n(0.0, 0.01).0, 0.0);
        assert_eq!(law.friction_n(f64::NAN, 0.01).0, 0.0);
        let (f, flags) = law.friction_n(100.0, 0.01);
        assert_eq!(f, HardContact::li_bi().friction_n(20.0));
        assert_eq!(flags, flag::MODEL_INPUT_CLAMPED);
    }

    #[test]
    fn soft_friction_is_two_stage_and_clamps_speed() {
        let s = SoftContact::sponge();
        let (w, m) = soft_contact_models(s);
        let law = SoftFriction::new(w, m, 20.0);
        let (f, flags) = law.friction_n(3.0, 0.01);
        assert!((f - s.friction_n(0.01, 3.0)).abs() < 1e-12 && flags == 0);
        // Direction does not matter, only speed.
        assert_eq!(law.friction_n(3.0, -0.01).0, f);
        // Faster than trained: the value at 40 mm/s, flagged.
        let (f, flags) = law.friction_n(3.0, 0.5);
        assert!((f - s.friction_n(0.04, 3.0)).abs() < 1e-12);
        assert_eq!(flags, flag::MODEL_INPUT_CLAMPED);
    }
}
