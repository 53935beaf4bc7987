//! The last stage before a force reaches the operator: limits and a NaN guard. (The gate the
//! watchdog closes when the haptic thread stalls is the device's: [`crate::device::ForceGate`].)

use glam::DVec3;

use crate::device::{DeviceSpecs, ForceCommand};

/// Bits of [`SafetyFlags`].
pub mod flag {
    /// The force was larger than the device's limit and was scaled down.
    pub const FORCE_CLAMPED: u32 = 1 << 0;
    /// A force component was NaN or infinite; the force was replaced by zero.
    pub const FORCE_NOT_FINITE: u32 = 1 << 1;
    /// The gripper force was over its limit.
    pub const GRIPPER_CLAMPED: u32 = 1 << 2;
    /// The gripper force was NaN or infinite; replaced by zero.
    pub const GRIPPER_NOT_FINITE: u32 = 1 << 3;
    /// A force law was evaluated outside its model's training range (inputs clamped).
    pub const MODEL_INPUT_CLAMPED: u32 = 1 << 4;
    /// A force law's model returned a non-finite value (treated as zero).
    pub const MODEL_OUTPUT_NOT_FINITE: u32 = 1 << 5;
    /// The live surface recognizer was fed a non-finite sample (its decision stands).
    pub const RECOGNIZER_INPUT_NOT_FINITE: u32 = 1 << 6;
    /// The force was held below the command after a stall of the loop (zero on the tick
    /// after it, then ramping back).
    pub const STALL_RECOVERY: u32 = 1 << 7;
    /// The live surface recognizer could not read the window this sample completes (such as
    /// one slid faster than its spectra's bands reach): the window adds no evidence and the
    /// decision stands.
    pub const RECOGNIZER_WINDOW_UNREAD: u32 = 1 << 8;
}

/// `command` scaled by `scale`, read as 0–1 (NaN as 0). Scaling a filtered command keeps it
/// finite and within the limits, so the filter need not run again.
pub fn scale_command(command: &ForceCommand, scale: f64) -> ForceCommand {
    let s = if scale.is_nan() {
        0.0
    } else {
        scale.clamp(0.0, 1.0)
    };
    ForceCommand {
        force_n: command.force_n * s,
        gripper_force_n: command.gripper_force_n * s,
    }
}

/// What the safety filter changed, as [`flag`] bits.
pub type SafetyFlags = u32;

/// Makes any command safe to send: finite, within the device's force and gripper limits.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SafetyFilter {
    max_force_n: f64,
    max_gripper_force_n: f64,
}

impl SafetyFilter {
    /// A filter for a device with these specs. Non-finite or negative limits in the specs are
    /// read as 0 N: a device whose limits are unknown gets no force.
    pub fn new(specs: &DeviceSpecs) -> Self {
        let sane = |x: f64| if x.is_finite() && x > 0.0 { x } else { 0.0 };
        Self {
            max_force_n: sane(specs.max_force_n),
            max_gripper_force_n: sane(specs.max_gripper_force_n),
        }
    }

    /// Largest force norm let through, N.
    pub fn max_force_n(&self) -> f64 {
        self.max_force_n
    }

    /// Returns the command to send and what was changed. A force over the limit keeps its
    /// direction and is scaled to the limit; a force with any non-finite component becomes
    /// zero (its direction is meaningless).
    pub fn apply(&self, command: &ForceCommand) -> (ForceCommand, SafetyFlags) {
        let mut flags = 0;
        let f = command.force_n;
        let force_n = if !f.is_finite() {
            flags |= flag::FORCE_NOT_FINITE;
            DVec3::ZERO
        } else {
            // Scale by the largest component first so that the norm of huge finite values
            // (1e300) does not overflow to infinity.
            let largest = f.abs().max_element();
            if largest == 0.0 {
                DVec3::ZERO
            } else {
                let unit = f / largest;
                let norm = largest * unit.length();
                if norm > self.max_force_n {
                    flags |= flag::FORCE_CLAMPED;
                    // `unit.length()` ≥ 1, so this division is safe and the result's norm is
                    // the limit, up to rounding; the final min() removes that rounding.
                    let scaled = unit * (self.max_force_n / unit.length());
                    let n = scaled.length();
                    if n > self.max_force_n && n > 0.0 {
                        scaled * (self.max_force_n / n) * (1.0 - f64::EPSILON)
                    } else {
                        scaled
                    }
                } else {
                    f
                }
            }
        };
        let g = command.gripper_force_n;
        let gripper_force_n = if !g.is_finite() {
            flags |= flag::GRIPPER_NOT_FINITE;
            0.0
        } else if g.abs() > self.max_gripper_force_n {
            flags |= flag::GRIPPER_CLAMPED;
            g.clamp(-self.max_gripper_force_n, self.max_gripper_force_n)
        } else {
            g
        };
        (
            ForceCommand {
                force_n,
                gripper_force_n,
            },
            flags,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn filter() -> SafetyFilter {
        SafetyFilter::new(&DeviceSpecs::OMEGA7)
    }

    fn special() -> impl Strategy<Value = f64> {
        prop_oneof![
            Just(f64::NAN),
            Just(f64::INFINITY),
            Just(f64::NEG_INFINITY),
            Just(f64::MAX),
            Just(f64::MIN),
            Just(f64::MIN_POSITIVE),
            Just(-0.0),
            Just(1e300),
            Just(-1e300),
            -1e6..1e6f64,
            -20.0..20.0f64,
            any::<f64>(),
        ]
    }

    proptest! {
        #[test]
        fn any_command_becomes_finite_and_within_limits(
            x in special(), y in special(), z in special(), g in special()
        ) {
            let f = filter();
            let (out, flags) = f.apply(&ForceCommand { force_n: DVec3::new(x, y, z), gripper_force_n: g });
            prop_assert!(out.force_n.is_finite() && out.gripper_force_n.is_finite());
            prop_assert!(out.force_n.length() <= 12.0, "{out:?}");
            prop_assert!(out.gripper_force_n.abs() <= 8.0);
            let finite_in = x.is_finite() && y.is_finite() && z.is_finite();
            prop_assert_eq!(flags & flag::FORCE_NOT_FINITE != 0, !finite_in);
        }

        #[test]
        fn forces_within_limits_pass_unchanged(x in -6.0..6.0f64, y in -6.0..6.0f64, z in -6.0..6.0f64, g in -8.0..8.0f64) {
            let cmd = ForceCommand { force_n: DVec3::new(x, y, z), gripper_force_n: g };
            let (out, flags) = filter().apply(&cmd);
            prop_assert_eq!(out, cmd);
            prop_assert_eq!(flags, 0);
        }
    }

    #[test]
    fn clamping_keeps_the_direction() {
        let (out, flags) = filter().apply(&ForceCommand {
            force_n: DVec3::new(30.0, 0.0, -40.0),
            gripper_force_n: 0.0,
        });
        assert_eq!(flags, flag::FORCE_CLAMPED);
        assert!((out.force_n.length() - 12.0).abs() < 1e-9);
        assert!((out.force_n.normalize() - DVec3::new(0.6, 0.0, -0.8)).length() < 1e-12);
    }
}
