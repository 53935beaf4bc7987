//! Needle puncture rendered from an identified model of axial force against (depth, velocity).
//!
//! Li & Bi identify the puncture force as one RBF SVR on [insertion distance, velocity]
//! (Sec. III-D, Fig. 10). That surface holds the whole insertion — capsule loading, the drop at
//! puncture, cutting and shaft friction, and (from the withdrawal samples) friction on the way
//! out — but it has no memory: evaluated blindly, pulling back before the capsule ruptures would
//! give withdrawal friction through an intact membrane, and pushing back in after a withdrawal
//! would make the operator puncture the capsule a second time. The state machine here gives the
//! surface the memory the tissue has:
//!
//! | state | force on the needle |
//! |---|---|
//! | `Approach` (tip above the surface) | 0 |
//! | `CapsuleLoading` (membrane deflecting, intact) | `f(d, max(v, 0))`: the elastic loading branch, also when backing off |
//! | `Puncture` (from the detected rupture until 1 mm further) | `f(d, v)`: the model's own drop |
//! | `Insertion` into uncut tissue (deeper than ever before) | `f(d, v)` |
//! | `Insertion` along the cut channel | `−f(d, −v)`: the withdrawal friction mirrored, no second rupture |
//! | `Withdrawal` | `f(d, v)` (negative: friction pulls the needle in) |
//!
//! Rupture is detected as the loading force falling by [`NeedleLawConfig::rupture_drop`] of its
//! peak while the needle advances past the peak. Leaving the tissue (depth ≤ 0) returns to
//! `Approach` and the next entry is a fresh site. Inputs outside the model's training box are
//! clamped (the force at the box's edge) and flagged.
//!
//! Sign convention as in captures: depth positive inside tissue, velocity positive inserting,
//! force positive when it pushes the needle back out.

use super::model::{ScalarModel, eval_clamped};

/// Where the needle is in its insertion.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PunctureState {
    /// Tip in the air above the tissue.
    Approach,
    /// Tip pressing the intact capsule.
    CapsuleLoading,
    /// Capsule just ruptured; the force is relaxing.
    Puncture,
    /// Inside the tissue, advancing or held.
    Insertion,
    /// Inside the tissue, pulling out.
    Withdrawal,
}

impl PunctureState {
    /// A number for recording (0 approach … 4 withdrawal).
    pub fn code(self) -> f64 {
        match self {
            Self::Approach => 0.0,
            Self::CapsuleLoading => 1.0,
            Self::Puncture => 2.0,
            Self::Insertion => 3.0,
            Self::Withdrawal => 4.0,
        }
    }

    /// The state a recorded [`PunctureState::code`] stands for; `None` for any other number.
    pub fn from_code(code: f64) -> Option<Self> {
        [
            Self::Approach,
            Self::CapsuleLoading,
            Self::Puncture,
            Self::Insertion,
            Self::Withdrawal,
        ]
        .into_iter()
        .find(|s| s.code() == code)
    }
}

/// Tuning of the state machine.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NeedleLawConfig {
    /// Fraction of the peak loading force the force must lose for a rupture.
    pub rupture_drop: f64,
    /// Smallest peak that counts as a membrane (below it a dip is model noise), N.
    pub min_peak_n: f64,
    /// Depth travelled after a rupture before the state becomes `Insertion`, m.
    pub puncture_travel_m: f64,
    /// Speed below which the needle counts as held (no switch between insertion and
    /// withdrawal), m/s.
    pub hold_band_mps: f64,
}

impl Default for NeedleLawConfig {
    fn default() -> Self {
        Self {
            rupture_drop: 0.25,
            min_peak_n: 0.2,
            puncture_travel_m: 0.001,
            hold_band_mps: 2e-4,
        }
    }
}

/// One evaluation of the law.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NeedleOutput {
    /// Axial force, positive pushing the needle out, N.
    pub axial_force_n: f64,
    /// The state after this step.
    pub state: PunctureState,
    /// [`crate::safety::flag`] bits from the model evaluation.
    pub flags: u32,
}

/// A needle law the haptic thread steps: depth and velocity in, axial force and state out.
/// Allocation-free.
pub trait AxialLaw: Send {
    /// Advances the law with the needle at `depth_m` moving at `velocity_mps` (positive
    /// inserting).
    fn step(&mut self, depth_m: f64, velocity_mps: f64) -> NeedleOutput;
}

impl<M: ScalarModel<2> + Send> AxialLaw for NeedleLaw<M> {
    fn step(&mut self, depth_m: f64, velocity_mps: f64) -> NeedleOutput {
        NeedleLaw::step(self, depth_m, velocity_mps)
    }
}

/// The needle-puncture force law over a model `f(depth_m, velocity_mps)`.
#[derive(Debug, Clone)]
pub struct NeedleLaw<M> {
    model: M,
    config: NeedleLawConfig,
    state: PunctureState,
    peak_n: f64,
    peak_depth_m: f64,
    rupture_depth_m: f64,
    deepest_m: f64,
}

impl<M: ScalarModel<2>> NeedleLaw<M> {
    /// A law over `model`, starting in `Approach`.
    pub fn new(model: M, config: NeedleLawConfig) -> Self {
        Self {
            model,
            config,
            state: PunctureState::Approach,
            peak_n: 0.0,
            peak_depth_m: 0.0,
            rupture_depth_m: 0.0,
            deepest_m: 0.0,
        }
    }

    /// The current state.
    pub fn state(&self) -> PunctureState {
        self.state
    }

    /// The model.
    pub fn model(&self) -> &M {
        &self.model
    }

    /// Depth at which the capsule ruptured in this insertion (0 before).
    pub fn rupture_depth_m(&self) -> f64 {
        self.rupture_depth_m
    }

    /// Back to a fresh site.
    pub fn reset(&mut self) {
        self.state = PunctureState::Approach;
        self.peak_n = 0.0;
        self.peak_depth_m = 0.0;
        self.rupture_depth_m = 0.0;
        self.deepest_m = 0.0;
    }

    /// Advances the state machine with the needle at `depth_m` moving at `velocity_mps` and
    /// returns the force. Allocation-free.
    pub fn step(&mut self, depth_m: f64, velocity_mps: f64) -> NeedleOutput {
        let d = if depth_m.is_nan() { 0.0 } else { depth_m };
        let v = if velocity_mps.is_finite() {
            velocity_mps
        } else {
            0.0
        };
        let c = self.config;
        if d <= 0.0 {
            self.reset();
            return NeedleOutput {
                axial_force_n: 0.0,
                state: self.state,
                flags: 0,
            };
        }
        if self.state == PunctureState::Approach {
            self.state = PunctureState::CapsuleLoading;
        }
        let mut flags = 0;
        let mut eval = |d: f64, v: f64| {
            let e = eval_clamped(&self.model, &[d, v]);
            flags |= e.flags;
            e.value
        };
        let force = match self.state {
            PunctureState::Approach | PunctureState::CapsuleLoading => {
                let f = eval(d, v.max(0.0));
                if v > 0.0 && d >= self.peak_depth_m {
                    if f > self.peak_n {
                        self.peak_n = f;
                        self.peak_depth_m = d;
                    } else if self.peak_n >= c.min_peak_n && f < self.peak_n * (1.0 - c.rupture_drop) {
                        self.state = PunctureState::Puncture;
                        self.rupture_depth_m = d;
                    }
                }
                f
            }
            PunctureState::Puncture => {
                if v < -c.hold_band_mps {
                    self.state = PunctureState::Withdrawal;
                } else if d > self.rupture_depth_m + c.puncture_travel_m {
                    self.state = PunctureState::Insertion;
                }
                eval(d, v)
            }
            PunctureState::Insertion | PunctureState::Withdrawal => {
                if v < -c.hold_band_mps {
                    self.state = PunctureState::Withdrawal;
                } else if v > c.hold_band_mps {
                    self.state = PunctureState::Insertion;
                }
                if self.state == PunctureState::Insertion && d <= self.deepest_m && v > 0.0 {
                    // Along the channel already cut: friction only, which the model knows
                    // from the withdrawals; friction is odd in velocity.
                    -eval(d, -v)
                } else {
                    eval(d, v)
                }
            }
        };
        self.deepest_m = self.deepest_m.max(d);
        NeedleOutput {
            axial_force_n: force,
            state: self.state,
            flags,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::law::reference::NeedleQuasiStatic;
    use crate::safety::flag;
    use sim::NeedleTissue;

    fn law() -> NeedleLaw<NeedleQuasiStatic> {
        NeedleLaw::new(
            NeedleQuasiStatic::new(NeedleTissue::bovine_liver()),
            NeedleLawConfig::default(),
        )
    }

    /// Steps the law along a depth path at 1 kHz; returns (depth, force, state).
    fn drive(
        law: &mut NeedleLaw<NeedleQuasiStatic>,
        from: f64,
        to: f64,
        speed: f64,
    ) -> Vec<(f64, f64, PunctureState)> {
        let dt = 1e-3;
        let v = if to > from { speed } else { -speed };
        let n = ((to - from) / (v * dt)).abs().round() as usize;
        (1..=n)
            .map(|k| {
                let d = from + v * dt * k as f64;
                let o = law.step(d, v);
                (d, o.axial_force_n, o.state)
            })
            .collect()
    }

    #[test]
    fn a_full_insertion_goes_through_every_state_in_order() {
        use PunctureState::*;
        let mut l = law();
        assert_eq!(l.step(-0.001, 0.005).state, Approach);
        let mut trace = drive(&mut l, -0.001, 0.025, 0.005);
        // The rupture is where the truth punctures at this speed.
        let truth = NeedleTissue::bovine_liver().puncture_depth_m(0, 0.005).unwrap();
        assert!(
            (l.rupture_depth_m() - truth).abs() < 2e-5,
            "{} {truth}",
            l.rupture_depth_m()
        );
        trace.extend(drive(&mut l, 0.025, -0.001, 0.005));
        let mut states: Vec<PunctureState> = trace.iter().map(|t| t.2).collect();
        states.dedup();
        assert_eq!(
            states,
            [
                Approach,
                CapsuleLoading,
                Puncture,
                Insertion,
                Withdrawal,
                Approach
            ]
        );
        // Withdrawal pulls the needle in (negative), never pushes.
        assert!(trace.iter().filter(|t| t.2 == Withdrawal).all(|t| t.1 <= 0.0));
    }

    #[test]
    fn backing_off_before_rupture_unloads_elastically() {
        let mut l = law();
        drive(&mut l, -0.001, 0.006, 0.005);
        assert_eq!(l.state(), PunctureState::CapsuleLoading);
        let loaded = l.step(0.006, 0.0).axial_force_n;
        let back = drive(&mut l, 0.006, 0.003, 0.005);
        // Still intact, and pushing (elastic), never pulling like withdrawal friction.
        assert!(
            back.iter()
                .all(|t| t.2 == PunctureState::CapsuleLoading && t.1 >= 0.0)
        );
        assert!(back.last().unwrap().1 < loaded);
        // Pressing again reaches the rupture as before.
        drive(&mut l, 0.003, 0.02, 0.005);
        assert_eq!(l.state(), PunctureState::Insertion);
    }

    #[test]
    fn reinsertion_along_the_channel_does_not_rupture_again() {
        let mut l = law();
        drive(&mut l, -0.001, 0.02, 0.005);
        drive(&mut l, 0.02, 0.008, 0.005);
        let again = drive(&mut l, 0.008, 0.019, 0.005);
        assert!(again.iter().all(|t| t.2 == PunctureState::Insertion));
        // Friction only: small and positive, far below the capsule's peak.
        assert!(again.iter().all(|t| t.1 > 0.0 && t.1 < 0.6), "{again:?}");
    }

    #[test]
    fn inputs_outside_the_training_box_are_clamped_and_flagged() {
        let mut l = law();
        drive(&mut l, -0.001, 0.029, 0.005);
        let inside = l.step(0.0299, 0.005);
        assert_eq!(inside.flags, 0);
        let deep = l.step(0.2, 0.005);
        assert_ne!(deep.flags & flag::MODEL_INPUT_CLAMPED, 0);
        assert!((deep.axial_force_n - l.model().force_n(0.03, 0.005)).abs() < 1e-12);
        let fast = l.step(0.0299, 5.0);
        assert_ne!(fast.flags & flag::MODEL_INPUT_CLAMPED, 0);
        assert!(fast.axial_force_n.is_finite() && fast.axial_force_n < 3.0);
    }

    #[test]
    fn non_finite_inputs_and_outputs_give_a_finite_force() {
        let mut l = law();
        for (d, v) in [
            (f64::NAN, 0.0),
            (0.01, f64::NAN),
            (f64::INFINITY, f64::NEG_INFINITY),
        ] {
            assert!(l.step(d, v).axial_force_n.is_finite());
        }
        let b = crate::law::model::InputBox::new([0.0, -0.01], [0.03, 0.01]).unwrap();
        let mut broken = NeedleLaw::new(
            crate::law::model::FnModel::new(b, |_: &[f64; 2]| f64::INFINITY),
            NeedleLawConfig::default(),
        );
        let o = broken.step(0.01, 0.005);
        assert_eq!(o.axial_force_n, 0.0);
        assert_ne!(o.flags & flag::MODEL_OUTPUT_NOT_FINITE, 0);
    }
}
