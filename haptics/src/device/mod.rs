//! Haptic devices behind one small interface.
//!
//! The interface follows CHAI3D's `cGenericHapticDevice`: open, close, specs with limits, read
//! the state (position, velocity, gripper, buttons, time), command a force and a gripper force,
//! enable or disable forces. Implementations:
//! - [`sim_omega7::SimOmega7`]: a simulated Omega.7 touching the simulated world;
//! - [`omega7::Omega7`]: the real device through the vendor SDK, loaded at run time;
//! - [`replay::ReplayDevice`]: a capture played back at its recorded rate;
//! - [`fault::FaultyDevice`]: any device that fails on purpose after a number of ticks.
//!
//! The first three are [`Backend`]s of the [`Registry`] (CHAI3D's `cHapticDeviceHandler`): the
//! one list of devices that scenes and the commands read. A new vendor is one file defining its
//! `Backend` and one line in [`BUILTIN`].
//!
//! Axes are the Omega.7's: x towards the operator, y to the right, z up. Positions in metres,
//! velocities in m/s, forces in newtons, all as seen at the end effector.

mod backend;
pub mod fault;
pub mod hid;
pub mod omega7;
mod registry;
pub mod replay;
pub mod sim_omega7;
mod sim_world;

pub use backend::{Backend, BackendOption, Motion, OpenRequest, OpenedDevice, SimSetup};
pub use registry::{BUILTIN, DeviceChoice, Registry};

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Duration;

use glam::DVec3;

use crate::error::HapticsError;

/// What a device can do: the limits every command is checked against, and the forces of its
/// own mechanism that an observer must not mistake for the operator's.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DeviceSpecs {
    /// Model name, for reports and capture metadata.
    pub model: &'static str,
    /// Largest translational force the actuators deliver (norm), N.
    pub max_force_n: f64,
    /// Largest gripper force, N.
    pub max_gripper_force_n: f64,
    /// Radius of the sphere the end effector can reach around its centre, m.
    pub workspace_radius_m: f64,
    /// Largest gripper opening, m.
    pub max_gripper_gap_m: f64,
    /// Stiffest spring the device renders stably, N/m.
    pub max_stiffness_npm: f64,
    /// Largest damping the device renders stably, N·s/m.
    pub max_damping_nspm: f64,
    /// The mechanism's own friction and uncompensated load, as a reaction-force observer
    /// models it (the Omega.7's: [`omega7::OMEGA7_INTERNAL`]).
    pub internal: InternalForces,
}

/// The device's own forces a reaction-force observer must not report as external (Nakano
/// Eq. 2.16): gravity not compensated by the device, and its friction `b·v + C·tanh(v/v_s)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InternalForces {
    /// Viscous friction, N·s/m.
    pub viscous_nspm: f64,
    /// Coulomb friction, N.
    pub coulomb_n: f64,
    /// Speed over which Coulomb friction is smoothed, m/s.
    pub coulomb_band_mps: f64,
    /// Constant load (uncompensated gravity) along the axis, N, opposing +axis when positive.
    pub gravity_n: f64,
}

impl InternalForces {
    /// No internal forces.
    pub const NONE: InternalForces = InternalForces {
        viscous_nspm: 0.0,
        coulomb_n: 0.0,
        coulomb_band_mps: 1e-3,
        gravity_n: 0.0,
    };

    /// The load they put on the motor at velocity `v`, N (Nakano's `f_g + f_fric`).
    pub fn load_n(&self, v: f64) -> f64 {
        let band = self.coulomb_band_mps.max(1e-9);
        self.gravity_n + self.viscous_nspm * v + self.coulomb_n * (v / band).tanh()
    }
}

/// One reading of the device.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct DeviceState {
    /// Device clock, s (starts near 0 when the device is opened).
    pub time_s: f64,
    /// End-effector position, m.
    pub position_m: DVec3,
    /// End-effector velocity as the device estimates it, m/s.
    pub velocity_mps: DVec3,
    /// Gripper opening, m.
    pub gripper_gap_m: f64,
    /// Button bit mask (bit 0: the gripper's user button or a foot pedal).
    pub buttons: u32,
}

/// What the device is asked to apply.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ForceCommand {
    /// Force on the end effector, N.
    pub force_n: DVec3,
    /// Gripper force, N (positive opens).
    pub gripper_force_n: f64,
}

impl ForceCommand {
    /// No force at all.
    pub const ZERO: ForceCommand = ForceCommand {
        force_n: DVec3::ZERO,
        gripper_force_n: 0.0,
    };
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

/// A haptic device. Called from the haptic thread once per tick: `read_state`, then `command`.
/// Implementations must not allocate, lock, log or do file I/O in those two calls.
pub trait HapticDevice: Send {
    /// Limits and geometry.
    fn specs(&self) -> &DeviceSpecs;

    /// Short name for reports and capture metadata (`sim-omega7`, `omega7`, `replay`).
    fn name(&self) -> &str;

    /// Switches force output on or off. Devices start with forces off: a force reaches the
    /// operator only after an explicit `enable_forces(true)`.
    fn enable_forces(&mut self, enabled: bool) -> Result<(), HapticsError>;

    /// Reads position, velocity, gripper and buttons.
    fn read_state(&mut self) -> Result<DeviceState, HapticsError>;

    /// Applies a force until the next command. The command must already be within
    /// [`HapticDevice::specs`]; the haptic loop's safety filter sees to that.
    fn command(&mut self, command: &ForceCommand) -> Result<(), HapticsError>;

    /// A handle that scales the applied force from another thread (the watchdog's), even
    /// while the haptic thread is stalled.
    fn force_override(&self) -> Arc<dyn ForceOverride>;

    /// Zeroes the force, disables forces and releases the device. Further calls fail with
    /// [`HapticsError::DeviceClosed`]. Closing twice is not an error.
    fn close(&mut self) -> Result<(), HapticsError>;

    /// Arms the device's own watchdog, where it has one: the device releases the force by
    /// itself when no command has come for `period` (rounded up to its resolution), however
    /// long the host stalls (a stalled host stalls the software watchdog with it). Returns
    /// the period armed; `None` where the device has no such watchdog.
    fn arm_watchdog(&mut self, period: Duration) -> Result<Option<Duration>, HapticsError> {
        let _ = period;
        Ok(None)
    }

    /// The device's own watchdog, once armed, and what it did where the device tells.
    fn hardware_watchdog(&self) -> Option<HardwareWatchdog> {
        None
    }
}

/// A device's own watchdog ([`HapticDevice::arm_watchdog`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HardwareWatchdog {
    /// The period armed.
    pub period: Duration,
    /// The longest silence between two commands and the force norm the device held when it
    /// began, N, where the device reports it (the simulated Omega.7 does; the SDK does not).
    pub longest_gap: Option<(Duration, f64)>,
    /// Silences longer than `period`, each ended by the device releasing the force, where
    /// the device reports them.
    pub trips: Option<u32>,
}

/// An Omega.7's watchdog counts in steps of 125 µs, one byte of them (SDK 3.3.2's
/// `dhdSetWatchdog`): the steps for `period`, rounded up, within 1..=255.
pub fn watchdog_steps(period: Duration) -> u8 {
    let steps = (period.as_secs_f64() / WATCHDOG_STEP.as_secs_f64()).ceil();
    steps.clamp(1.0, 255.0) as u8
}

/// The resolution of an Omega.7's watchdog.
pub const WATCHDOG_STEP: Duration = Duration::from_micros(125);

impl<D: HapticDevice + ?Sized> HapticDevice for Box<D> {
    fn specs(&self) -> &DeviceSpecs {
        (**self).specs()
    }
    fn name(&self) -> &str {
        (**self).name()
    }
    fn enable_forces(&mut self, enabled: bool) -> Result<(), HapticsError> {
        (**self).enable_forces(enabled)
    }
    fn read_state(&mut self) -> Result<DeviceState, HapticsError> {
        (**self).read_state()
    }
    fn command(&mut self, command: &ForceCommand) -> Result<(), HapticsError> {
        (**self).command(command)
    }
    fn force_override(&self) -> Arc<dyn ForceOverride> {
        (**self).force_override()
    }
    fn close(&mut self) -> Result<(), HapticsError> {
        (**self).close()
    }
    fn arm_watchdog(&mut self, period: Duration) -> Result<Option<Duration>, HapticsError> {
        (**self).arm_watchdog(period)
    }
    fn hardware_watchdog(&self) -> Option<HardwareWatchdog> {
        (**self).hardware_watchdog()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gate_scales_the_last_command_from_another_thread() {
        let gate = Arc::new(ForceGate::new());
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
