//! Needle insertion driven by the device itself, as Li & Bi's motor drives their needle: for
//! each speed, move above a fresh site, rest, insert to the target depth with a smooth
//! start, hold, withdraw. Position control (PD + DOB) on every axis; the axial force is the
//! RFOB's estimate, since the Omega.7 has no force sensor.

use glam::DVec3;

use crate::control::{AccelerationControl, MotionGains};
use crate::rt::{Controller, TickInput, TickOutput};

/// The insertion plan.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InsertionPlan {
    /// Insertion speeds, one insertion each, m/s.
    pub speeds_mps: &'static [f64],
    /// Height of the tissue surface in device coordinates, m.
    pub surface_z_m: f64,
    /// Distance between fresh sites along x, m.
    pub site_spacing_m: f64,
    /// Start height above the surface, m.
    pub start_above_m: f64,
    /// Target depth, m.
    pub target_depth_m: f64,
    /// Withdrawal speed, m/s.
    pub withdraw_mps: f64,
    /// Rest before, and hold at depth, s.
    pub rest_s: f64,
    /// Hold at depth, s.
    pub hold_s: f64,
    /// Smooth start of each motion, s.
    pub ramp_s: f64,
}

impl InsertionPlan {
    /// Three insertions (2, 5, 10 mm/s) to 25 mm, hold 0.5 s, withdraw at 10 mm/s.
    pub const DEFAULT: InsertionPlan = InsertionPlan {
        speeds_mps: &[0.002, 0.005, 0.010],
        surface_z_m: -0.02,
        site_spacing_m: 0.008,
        start_above_m: 0.002,
        target_depth_m: 0.025,
        withdraw_mps: 0.010,
        rest_s: 0.3,
        hold_s: 0.5,
        ramp_s: 0.05,
    };
}

/// Phase of the current insertion.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum InsertionPhase {
    /// Moving to the next site (not recorded).
    Move,
    /// At rest above the surface.
    Rest,
    /// Inserting.
    Insert,
    /// Held at depth.
    Hold,
    /// Withdrawing.
    Withdraw,
    /// All insertions done.
    Done,
}

/// Channels recorded by [`InsertionController`].
pub mod channel {
    /// Axial force estimated by the RFOB (positive pushing the needle out), N.
    pub const AXIAL_FORCE_N: usize = 0;
    /// Commanded insertion velocity (positive deeper), m/s.
    pub const COMMANDED_VELOCITY_MPS: usize = 1;
    /// Depth of the measured tip, m.
    pub const DEPTH_M: usize = 2;
    /// 1 while the sample belongs to an insertion (rest … withdrawal), 0 while moving.
    pub const RECORDING: usize = 3;
    /// Insertion index.
    pub const INSERTION: usize = 4;
}

/// Drives the insertions of an [`InsertionPlan`].
#[derive(Debug, Clone)]
pub struct InsertionController {
    plan: InsertionPlan,
    control: Option<AccelerationControl>,
    phase: InsertionPhase,
    phase_s: f64,
    index: usize,
    reference_m: DVec3,
    move_from_m: DVec3,
}

impl InsertionController {
    /// A controller for `plan`.
    pub fn new(plan: InsertionPlan) -> Self {
        Self {
            plan,
            control: None,
            phase: InsertionPhase::Move,
            phase_s: 0.0,
            index: 0,
            reference_m: DVec3::ZERO,
            move_from_m: DVec3::ZERO,
        }
    }

    /// The current phase.
    pub fn phase(&self) -> InsertionPhase {
        self.phase
    }

    fn start_point(&self) -> DVec3 {
        DVec3::new(
            self.index as f64 * self.plan.site_spacing_m,
            0.0,
            self.plan.surface_z_m + self.plan.start_above_m,
        )
    }

    fn enter(&mut self, phase: InsertionPhase) {
        self.phase = phase;
        self.phase_s = 0.0;
    }
}

fn smooth(u: f64) -> f64 {
    let u = u.clamp(0.0, 1.0);
    u * u * (3.0 - 2.0 * u)
}

impl Controller for InsertionController {
    fn tick(&mut self, input: &TickInput<'_>, out: &mut TickOutput) {
        let t = input.period_s;
        let s = input.state;
        if self.control.is_none() {
            self.reference_m = s.position_m;
            self.move_from_m = s.position_m;
        }
        let mut control = self
            .control
            .unwrap_or_else(|| AccelerationControl::new(MotionGains::NAKANO, input.specs.internal, t));
        let observed = control.observe(input.applied.force_n, s.velocity_mps);
        self.phase_s += t;
        let p = self.plan;
        let speed = p.speeds_mps.get(self.index).copied().unwrap_or(0.0);
        let depth_ref = p.surface_z_m - self.reference_m.z;
        let mut v_insert = 0.0;
        match self.phase {
            InsertionPhase::Move => {
                // One second, smooth, from wherever the tip is to above the next site.
                let target = self.start_point();
                let u = smooth(self.phase_s / 1.0);
                self.reference_m = self.move_from_m + (target - self.move_from_m) * u;
                if self.phase_s >= 1.0 {
                    self.enter(InsertionPhase::Rest);
                }
            }
            InsertionPhase::Rest => {
                if self.phase_s >= p.rest_s {
                    self.enter(InsertionPhase::Insert);
                }
            }
            InsertionPhase::Insert => {
                v_insert = speed * smooth(self.phase_s / p.ramp_s);
                if depth_ref >= p.target_depth_m {
                    v_insert = 0.0;
                    self.enter(InsertionPhase::Hold);
                }
            }
            InsertionPhase::Hold => {
                if self.phase_s >= p.hold_s {
                    self.enter(InsertionPhase::Withdraw);
                }
            }
            InsertionPhase::Withdraw => {
                v_insert = -p.withdraw_mps * smooth(self.phase_s / p.ramp_s);
                if depth_ref <= -p.start_above_m {
                    v_insert = 0.0;
                    self.index += 1;
                    self.move_from_m = self.reference_m;
                    if self.index >= p.speeds_mps.len() {
                        self.enter(InsertionPhase::Done);
                    } else {
                        self.enter(InsertionPhase::Move);
                    }
                }
            }
            InsertionPhase::Done => {}
        }
        self.reference_m.z -= v_insert * t;
        let v_ref = DVec3::new(0.0, 0.0, -v_insert);
        let a = control.position_accel(self.reference_m, v_ref, DVec3::ZERO, s.position_m, s.velocity_mps);
        out.command.force_n = control.motor_force(a);
        out.command.gripper_force_n = 0.0;
        self.control = Some(control);
        let recording = !matches!(self.phase, InsertionPhase::Move | InsertionPhase::Done);
        out.channels = [
            observed.external_n.z,
            v_insert,
            p.surface_z_m - s.position_m.z,
            if recording { 1.0 } else { 0.0 },
            self.index as f64,
            0.0,
            0.0,
            0.0,
            0.0,
            0.0,
            0.0,
            0.0,
        ];
    }

    fn finished(&self) -> bool {
        self.phase == InsertionPhase::Done
    }
}
