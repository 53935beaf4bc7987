//! A device that fails on purpose: wraps any device and makes it fail after a number of ticks,
//! the way a USB cable pulled mid-run does, to test that the loop stops safely.

use std::sync::Arc;

use super::{DeviceSpecs, DeviceState, ForceCommand, ForceOverride, HapticDevice};
use crate::error::HapticsError;

/// Which call fails.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FaultPoint {
    /// `read_state` fails.
    Read,
    /// `command` fails.
    Command,
}

/// `D`, failing from tick `after` on.
#[derive(Debug)]
pub struct FaultyDevice<D> {
    inner: D,
    after: u64,
    point: FaultPoint,
    ticks: u64,
}

impl<D: HapticDevice> FaultyDevice<D> {
    /// Wraps `inner`; its `point` call fails once `after` ticks have completed.
    pub fn new(inner: D, after: u64, point: FaultPoint) -> Self {
        Self {
            inner,
            after,
            point,
            ticks: 0,
        }
    }

    /// The wrapped device.
    pub fn inner(&self) -> &D {
        &self.inner
    }
}

impl<D: HapticDevice> HapticDevice for FaultyDevice<D> {
    fn specs(&self) -> &DeviceSpecs {
        self.inner.specs()
    }

    fn name(&self) -> &str {
        self.inner.name()
    }

    fn enable_forces(&mut self, enabled: bool) -> Result<(), HapticsError> {
        self.inner.enable_forces(enabled)
    }

    fn read_state(&mut self) -> Result<DeviceState, HapticsError> {
        if self.point == FaultPoint::Read && self.ticks >= self.after {
            return Err(HapticsError::DeviceFault {
                what: "device stopped answering (injected)",
                tick: None,
            });
        }
        self.inner.read_state()
    }

    fn command(&mut self, command: &ForceCommand) -> Result<(), HapticsError> {
        if self.point == FaultPoint::Command && self.ticks >= self.after && *command != ForceCommand::ZERO {
            return Err(HapticsError::DeviceCall {
                call: "set force (injected)",
                code: -1,
                tick: None,
            });
        }
        self.ticks += 1;
        self.inner.command(command)
    }

    fn force_override(&self) -> Arc<dyn ForceOverride> {
        self.inner.force_override()
    }

    fn close(&mut self) -> Result<(), HapticsError> {
        self.inner.close()
    }
}
