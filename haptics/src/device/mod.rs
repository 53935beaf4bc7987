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
//! Axes are the Omega.7's: x towards the operator, y to the right, z up. Positions in metres,
//! velocities in m/s, forces in newtons, all as seen at the end effector.

pub mod fault;
pub mod hid;
pub mod omega7;
pub mod replay;
pub mod sim_omega7;

use std::sync::Arc;

use glam::DVec3;

use crate::safety::ForceOverride;

/// What a device can do: the limits every command is checked against.
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
}

impl DeviceSpecs {
    /// Force Dimension Omega.7, from the data sheet and CHAI3D's device table: 12 N, active
    /// gripper 8 N, a workspace of Ø 160 mm, 5000 N/m, 30 N·s/m.
    pub const OMEGA7: DeviceSpecs = DeviceSpecs {
        model: "omega.7",
        max_force_n: 12.0,
        max_gripper_force_n: 8.0,
        workspace_radius_m: 0.08,
        max_gripper_gap_m: 0.03,
        max_stiffness_npm: 5000.0,
        max_damping_nspm: 30.0,
    };
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

/// Why a device call failed. Errors the haptic thread can meet carry only static text, so
/// reporting one does not allocate.
#[derive(Debug, thiserror::Error)]
pub enum DeviceError {
    /// The vendor library could not be loaded.
    #[error(
        "the Force Dimension SDK (libdhd) was not found ({tried}): install the Force Dimension SDK or use --device sim"
    )]
    SdkMissing {
        /// What was tried and why each failed.
        tried: String,
    },
    /// The vendor library lacks a function the device needs.
    #[error(
        "libdhd at {library} has no `{symbol}`: install a Force Dimension SDK of version 3 or newer, or use --device sim"
    )]
    SymbolMissing {
        /// The library file.
        library: String,
        /// The missing function.
        symbol: &'static str,
    },
    /// The SDK loaded but found no device.
    #[error("no Omega.7 is connected ({detail}): connect and power it on, or use --device sim")]
    NoDevice {
        /// What the SDK said.
        detail: String,
    },
    /// A device call returned an error code.
    #[error("{call} failed (code {code})")]
    Call {
        /// The function that failed.
        call: &'static str,
        /// Its return code.
        code: i32,
    },
    /// The device stopped answering or reported a fault.
    #[error("device fault: {0}")]
    Fault(&'static str),
    /// The device was used after `close`.
    #[error("device is closed")]
    Closed,
    /// A replayed capture has no more samples: the normal end of a replay.
    #[error("the replayed capture has ended")]
    EndOfReplay,
    /// A capture could not be used for replay.
    #[error("cannot replay {source_name}: {reason}")]
    BadReplay {
        /// The capture's file.
        source_name: String,
        /// Why.
        reason: String,
    },
}

impl DeviceError {
    /// Whether this is the orderly end of a finite device (a replay), not a failure.
    pub fn is_end_of_stream(&self) -> bool {
        matches!(self, DeviceError::EndOfReplay)
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
    fn enable_forces(&mut self, enabled: bool) -> Result<(), DeviceError>;

    /// Reads position, velocity, gripper and buttons.
    fn read_state(&mut self) -> Result<DeviceState, DeviceError>;

    /// Applies a force until the next command. The command must already be within
    /// [`HapticDevice::specs`]; the haptic loop's safety filter sees to that.
    fn command(&mut self, command: &ForceCommand) -> Result<(), DeviceError>;

    /// A handle that scales the applied force from another thread (the watchdog's), even
    /// while the haptic thread is stalled.
    fn force_override(&self) -> Arc<dyn ForceOverride>;

    /// Zeroes the force, disables forces and releases the device. Further calls fail with
    /// [`DeviceError::Closed`]. Closing twice is not an error.
    fn close(&mut self) -> Result<(), DeviceError>;
}

impl<D: HapticDevice + ?Sized> HapticDevice for Box<D> {
    fn specs(&self) -> &DeviceSpecs {
        (**self).specs()
    }
    fn name(&self) -> &str {
        (**self).name()
    }
    fn enable_forces(&mut self, enabled: bool) -> Result<(), DeviceError> {
        (**self).enable_forces(enabled)
    }
    fn read_state(&mut self) -> Result<DeviceState, DeviceError> {
        (**self).read_state()
    }
    fn command(&mut self, command: &ForceCommand) -> Result<(), DeviceError> {
        (**self).command(command)
    }
    fn force_override(&self) -> Arc<dyn ForceOverride> {
        (**self).force_override()
    }
    fn close(&mut self) -> Result<(), DeviceError> {
        (**self).close()
    }
}
