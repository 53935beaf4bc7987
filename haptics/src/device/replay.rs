//! Playback of a capture as a device (HAPI's playback device): the loop sees the recorded
//! positions and velocities at the capture's own rate, whatever its own rate is, and the
//! commanded forces go nowhere.
//!
//! Axes: an insertion capture's `depth_m` is played along −z (the needle points down); a
//! rubbing capture's `tangential_position_m` along x and `normal_position_m` (if present) along
//! z. Between samples positions are interpolated linearly; velocities come from the capture's
//! velocity column when it has one, else from the interpolation's slope.

use std::sync::Arc;

use capture::kind::{
    DEPTH_M, NORMAL_POSITION_M, TANGENTIAL_POSITION_M, TANGENTIAL_VELOCITY_MPS, VELOCITY_MPS,
};
use capture::{Capture, CaptureKind};
use glam::DVec3;

use super::backend::{Backend, BackendOption, Motion, OpenRequest, OpenedDevice};
use super::{DeviceSpecs, DeviceState, ForceCommand, ForceGate, ForceOverride, HapticDevice};
use crate::error::HapticsError;

/// Replay in the device registry: `replay:FILE`.
pub static BACKEND: Backend = Backend {
    name: "replay",
    summary: "replay of a capture",
    specs: DeviceSpecs::OMEGA7,
    option: Some(BackendOption {
        value_name: "FILE",
        help: "the capture whose motion is played",
        required: true,
    }),
    simulated: true,
    motion: Motion::Recorded,
    open,
    probe: |file| match file {
        Some(file) => vec![format!("plays {file}")],
        None => vec!["plays a capture's motion: replay:FILE".into()],
    },
};

fn open(request: OpenRequest<'_>) -> Result<OpenedDevice, HapticsError> {
    let path = std::path::Path::new(request.option.unwrap_or_default());
    let capture = Capture::read_file(path, request.recording_kind)?;
    let device = ReplayDevice::new(&capture, request.period_s)?;
    Ok(OpenedDevice {
        script_end_s: Some(device.duration_s()),
        device: Box::new(device),
    })
}

/// A capture played back.
#[derive(Debug)]
pub struct ReplayDevice {
    specs: DeviceSpecs,
    time_s: Vec<f64>,
    position_m: Vec<DVec3>,
    velocity_mps: Option<Vec<DVec3>>,
    period_s: f64,
    tick: u64,
    cursor: usize,
    gate: Arc<ForceGate>,
    closed: bool,
}

impl ReplayDevice {
    /// Plays `capture`, read every `period_s` seconds of loop time.
    pub fn new(capture: &Capture, period_s: f64) -> Result<Self, HapticsError> {
        let bad = |reason: &str| HapticsError::BadReplay {
            source_name: capture.source().display().to_string(),
            reason: reason.to_owned(),
        };
        if !(period_s.is_finite() && period_s > 0.0) {
            return Err(bad("the loop period must be positive"));
        }
        let column = |name: &str| capture.column(name).ok();
        let n = capture.len();
        let zeros = vec![0.0; n];
        type Axes<'a> = (&'a [f64], &'a [f64], Option<&'a [f64]>, Option<&'a [f64]>);
        let (x, z, vx, vz): Axes<'_> = match capture.metadata().kind() {
            CaptureKind::Insertion => {
                let depth = column(DEPTH_M).ok_or_else(|| bad("no depth_m column"))?;
                (&zeros, depth, None, column(VELOCITY_MPS))
            }
            CaptureKind::Rubbing => {
                let x =
                    column(TANGENTIAL_POSITION_M).ok_or_else(|| bad("no tangential_position_m column"))?;
                (
                    x,
                    column(NORMAL_POSITION_M).unwrap_or(&zeros),
                    column(TANGENTIAL_VELOCITY_MPS),
                    None,
                )
            }
        };
        let insertion = capture.metadata().kind() == CaptureKind::Insertion;
        let sign_z = if insertion { -1.0 } else { 1.0 };
        let position_m = (0..n).map(|i| DVec3::new(x[i], 0.0, sign_z * z[i])).collect();
        let velocity_mps = match (vx, vz) {
            (Some(vx), _) => Some((0..n).map(|i| DVec3::new(vx[i], 0.0, 0.0)).collect()),
            (None, Some(vz)) => Some((0..n).map(|i| DVec3::new(0.0, 0.0, sign_z * vz[i])).collect()),
            (None, None) => None,
        };
        let t0 = capture.time()[0];
        Ok(Self {
            specs: DeviceSpecs::OMEGA7,
            time_s: capture.time().iter().map(|t| t - t0).collect(),
            position_m,
            velocity_mps,
            period_s,
            tick: 0,
            cursor: 0,
            gate: Arc::new(ForceGate::new()),
            closed: false,
        })
    }

    /// Length of the recording, s.
    pub fn duration_s(&self) -> f64 {
        self.time_s.last().copied().unwrap_or(0.0)
    }
}

impl HapticDevice for ReplayDevice {
    fn specs(&self) -> &DeviceSpecs {
        &self.specs
    }

    fn name(&self) -> &str {
        "replay"
    }

    fn enable_forces(&mut self, _enabled: bool) -> Result<(), HapticsError> {
        Ok(())
    }

    fn read_state(&mut self) -> Result<DeviceState, HapticsError> {
        if self.closed {
            return Err(HapticsError::DeviceClosed { tick: None });
        }
        let t = self.tick as f64 * self.period_s;
        let n = self.time_s.len();
        if n == 0 || t > self.time_s[n - 1] {
            return Err(HapticsError::EndOfReplay);
        }
        while self.cursor + 1 < n && self.time_s[self.cursor + 1] <= t {
            self.cursor += 1;
        }
        let i = self.cursor;
        let (position_m, slope) = match (self.time_s.get(i + 1), self.position_m.get(i + 1)) {
            (Some(&t1), Some(&p1)) => {
                let (t0, p0) = (self.time_s[i], self.position_m[i]);
                let u = ((t - t0) / (t1 - t0)).clamp(0.0, 1.0);
                (p0 + (p1 - p0) * u, (p1 - p0) / (t1 - t0))
            }
            _ => (self.position_m[i], DVec3::ZERO),
        };
        let velocity_mps = self.velocity_mps.as_ref().map_or(slope, |v| v[i]);
        Ok(DeviceState {
            time_s: t,
            position_m,
            velocity_mps,
            gripper_gap_m: 0.0,
            buttons: 0,
        })
    }

    fn command(&mut self, command: &ForceCommand) -> Result<(), HapticsError> {
        if self.closed {
            return Err(HapticsError::DeviceClosed { tick: None });
        }
        self.gate.pass(command);
        self.tick += 1;
        Ok(())
    }

    fn force_override(&self) -> Arc<dyn ForceOverride> {
        self.gate.clone()
    }

    fn close(&mut self) -> Result<(), HapticsError> {
        self.closed = true;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rt::{self, LoopConfig, LoopIo, StopReason, ZeroForce};
    use capture::Metadata;

    #[test]
    fn plays_at_the_recorded_rate_and_ends_cleanly() {
        // 100 Hz insertion capture: depth goes 0 → 9.9 mm over 0.99 s.
        let n = 100;
        let time: Vec<f64> = (0..n).map(|i| i as f64 * 0.01).collect();
        let depth: Vec<f64> = (0..n).map(|i| i as f64 * 1e-4).collect();
        let force = vec![0.0; n];
        let capture = Capture::new(
            Metadata::new(CaptureKind::Insertion, "sim", 100.0),
            vec!["time_s".into(), "depth_m".into(), "axial_force_n".into()],
            vec![time, depth, force],
        )
        .unwrap();
        let mut device = ReplayDevice::new(&capture, 1e-3).unwrap();
        assert!((device.duration_s() - 0.99).abs() < 1e-12);
        // At 1 kHz, tick 505 is t = 0.505 s: depth 5.05 mm, interpolated, along −z.
        for _ in 0..505 {
            device.read_state().unwrap();
            device.command(&ForceCommand::ZERO).unwrap();
        }
        let s = device.read_state().unwrap();
        assert!((s.position_m.z + 0.00505).abs() < 1e-12, "{}", s.position_m.z);
        assert!((s.velocity_mps.z + 0.01).abs() < 1e-12);
        // Through the loop, unpaced: it ends by itself after 0.99 s of loop time.
        let device = ReplayDevice::new(&capture, 1e-3).unwrap();
        let config = LoopConfig::unpaced();
        let outcome = rt::spawn(device, ZeroForce, LoopIo::default(), config)
            .unwrap()
            .join()
            .unwrap();
        let summary = outcome.result.unwrap();
        assert_eq!(summary.reason, StopReason::EndOfStream);
        assert!((990..=991).contains(&summary.ticks), "{}", summary.ticks);
    }
}
