//! The last stage before a force reaches the operator: limits, a NaN guard, and the gate the
//! watchdog closes when the haptic thread stalls.

use std::sync::atomic::{AtomicU64, Ordering};

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

/// Scales a device's applied force from any thread. The watchdog holds one to ramp force to
/// zero while the haptic thread is stalled and cannot send commands itself.
pub trait ForceOverride: Send + Sync + std::fmt::Debug {
    /// Sets the factor applied to the last commanded force (1: as commanded, 0: none) and
    /// applies it now. Values outside [0, 1] are clamped; NaN means 0.
    fn set_force_scale(&self, scale: f64);

    /// The current factor.
    fn force_scale(&self) -> f64;
}

/// The shared state behind a device's [`ForceOverride`]: the last command the haptic thread
/// sent and the factor the watchdog set, in atomics so that neither side ever waits.
///
/// A command and the scale are independent atomics; a reader may pair a new command with the
/// old scale for one tick, which is harmless because the scale only goes down during a run
/// (the watchdog's ramp); it is set back to 1 only when a new run starts.
#[derive(Debug)]
pub struct ForceGate {
    last: [AtomicU64; 4],
    scale: AtomicU64,
}

impl Default for ForceGate {
    fn default() -> Self {
        Self::new()
    }
}

impl ForceGate {
    /// An open gate (scale 1) with no command yet.
    pub fn new() -> Self {
        Self {
            last: [
                AtomicU64::new(0),
                AtomicU64::new(0),
                AtomicU64::new(0),
                AtomicU64::new(0),
            ],
            scale: AtomicU64::new(1f64.to_bits()),
        }
    }

    /// Remembers the command the haptic thread is sending and returns it scaled by the gate.
    pub fn pass(&self, command: &ForceCommand) -> ForceCommand {
        let values = [
            command.force_n.x,
            command.force_n.y,
            command.force_n.z,
            command.gripper_force_n,
        ];
        for (slot, v) in self.last.iter().zip(values) {
            slot.store(v.to_bits(), Ordering::Relaxed);
        }
        self.scaled(command)
    }

    /// The last command passed, scaled by the gate: what the actuators apply now.
    pub fn applied(&self) -> ForceCommand {
        let v = |i: usize| f64::from_bits(self.last[i].load(Ordering::Relaxed));
        self.scaled(&ForceCommand {
            force_n: DVec3::new(v(0), v(1), v(2)),
            gripper_force_n: v(3),
        })
    }

    fn scaled(&self, command: &ForceCommand) -> ForceCommand {
        let s = self.force_scale();
        ForceCommand {
            force_n: command.force_n * s,
            gripper_force_n: command.gripper_force_n * s,
        }
    }
}

impl ForceOverride for ForceGate {
    fn set_force_scale(&self, scale: f64) {
        let s = if scale.is_nan() {
            0.0
        } else {
            scale.clamp(0.0, 1.0)
        };
        self.scale.store(s.to_bits(), Ordering::Relaxed);
    }

    fn force_scale(&self) -> f64 {
        f64::from_bits(self.scale.load(Ordering::Relaxed))
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

    #[test]
    fn gate_scales_the_last_command_from_another_thread() {
        let gate = std::sync::Arc::new(ForceGate::new());
        let cmd = ForceCommand {
            force_n: DVec3::new(1.0, 2.0, 3.0),
            gripper_force_n: 1.0,
        };
        assert_eq!(gate.pass(&cmd), cmd);
        let g = gate.clone();
        std::thread::spawn(move || g.set_force_scale(0.5)).join().unwrap();
        assert_eq!(gate.applied().force_n, DVec3::new(0.5, 1.0, 1.5));
        gate.set_force_scale(f64::NAN);
        assert_eq!(gate.applied(), ForceCommand::ZERO);
        gate.set_force_scale(7.0);
        assert_eq!(gate.force_scale(), 1.0);
    }
}
