//! Rubbing control (Nakano ch. 2–3): position control along x, force control along z, with a
//! DOB for robust acceleration control and an RFOB reading the reaction force — the friction
//! along x and the normal force along z — without a force sensor.
//!
//! Along z the loop is `a_z = −K_f (F_cmd − F̂_n)/M_n` (pressing is −z). With the DOB cancelling
//! the surface's reaction at low frequency and the RFOB's low-pass in the feedback path, the
//! closed loop against a surface of stiffness k is `M s³ + M g s² + k s + K_f g k` (g the
//! observer cut-off), which Routh's criterion makes stable exactly when `K_f < 1` — hence
//! Table 3.1's 0.8.
//!
//! A run: approach the surface slowly under velocity control until the RFOB feels half the
//! commanded force, let the force settle, rub the planned strokes (alternating direction, each
//! with a ramp up and a constant-deceleration stop), then lift off.

use glam::DVec3;

use super::motion::{AccelerationControl, MotionGains};
use crate::rt::{Controller, TickInput, TickOutput};

/// What to rub.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RubbingPlan {
    /// Speed of each stroke, m/s; strokes alternate direction (+x first).
    pub stroke_speeds_mps: &'static [f64],
    /// Length of each stroke, m.
    pub stroke_m: f64,
    /// Time to reach the stroke speed (and to stop), s.
    pub ramp_s: f64,
    /// Mean commanded normal force, N.
    pub normal_force_n: f64,
    /// Amplitude of a sinusoidal variation of the normal force, N.
    pub normal_force_amplitude_n: f64,
    /// Period of that variation, s.
    pub normal_force_period_s: f64,
}

impl RubbingPlan {
    /// Nakano Table 3.2: one 30 mm stroke at 5 mm/s under 0.3 N.
    pub const NAKANO: RubbingPlan = RubbingPlan {
        stroke_speeds_mps: &[0.005],
        stroke_m: 0.03,
        ramp_s: 0.2,
        normal_force_n: 0.3,
        normal_force_amplitude_n: 0.0,
        normal_force_period_s: 1.0,
    };

    /// Commanded normal force `t` seconds into the rubbing.
    pub fn normal_force_at(&self, t: f64) -> f64 {
        let period = self.normal_force_period_s.max(1e-3);
        self.normal_force_n + self.normal_force_amplitude_n * (std::f64::consts::TAU * t / period).sin()
    }
}

/// Where a run is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RubbingPhase {
    /// Descending towards the surface.
    Approach,
    /// In contact, force settling before moving.
    Settle,
    /// Rubbing.
    Rub,
    /// Lifting off.
    Lift,
    /// Finished.
    Done,
}

impl RubbingPhase {
    /// A number for recording.
    pub fn code(self) -> f64 {
        match self {
            Self::Approach => 0.0,
            Self::Settle => 1.0,
            Self::Rub => 2.0,
            Self::Lift => 3.0,
            Self::Done => 4.0,
        }
    }
}

/// Channels recorded by [`RubbingController`].
pub mod channel {
    /// Friction estimated by the RFOB, positive opposing the commanded motion, N.
    pub const FRICTION_N: usize = 0;
    /// Normal force estimated by the RFOB, positive pressing, N.
    pub const NORMAL_FORCE_N: usize = 1;
    /// Commanded velocity along x, m/s.
    pub const COMMANDED_VELOCITY_MPS: usize = 2;
    /// Position reference along x, m.
    pub const X_REFERENCE_M: usize = 3;
    /// Phase code ([`super::RubbingPhase::code`]).
    pub const PHASE: usize = 4;
    /// Commanded normal force, N.
    pub const NORMAL_COMMAND_N: usize = 5;
    /// Stroke index.
    pub const STROKE: usize = 6;
}

/// Nakano's rubbing controller.
#[derive(Debug, Clone)]
pub struct RubbingController {
    plan: RubbingPlan,
    gains: MotionGains,
    control: Option<AccelerationControl>,
    phase: RubbingPhase,
    phase_s: f64,
    rub_s: f64,
    hold_m: DVec3,
    stroke: usize,
    stroke_start_m: f64,
    x_ref_m: f64,
}

impl RubbingController {
    /// Runs `plan` with Nakano's gains (Table 3.1).
    pub fn new(plan: RubbingPlan) -> Self {
        Self::with_gains(plan, MotionGains::NAKANO)
    }

    /// Runs `plan` with other gains.
    pub fn with_gains(plan: RubbingPlan, gains: MotionGains) -> Self {
        Self {
            plan,
            gains,
            control: None,
            phase: RubbingPhase::Approach,
            phase_s: 0.0,
            rub_s: 0.0,
            hold_m: DVec3::ZERO,
            stroke: 0,
            stroke_start_m: 0.0,
            x_ref_m: 0.0,
        }
    }

    /// The current phase.
    pub fn phase(&self) -> RubbingPhase {
        self.phase
    }

    fn enter(&mut self, phase: RubbingPhase) {
        self.phase = phase;
        self.phase_s = 0.0;
    }

    /// Commanded velocity along x in the current stroke, from the distance covered so far.
    fn stroke_velocity(&self, covered_m: f64, stroke_s: f64) -> f64 {
        let Some(&speed) = self.plan.stroke_speeds_mps.get(self.stroke) else {
            return 0.0;
        };
        let ramp = self.plan.ramp_s.max(1e-3);
        let remaining = (self.plan.stroke_m - covered_m).max(0.0);
        let up = (stroke_s / ramp).min(1.0);
        // Constant deceleration `speed/ramp` stops exactly at the stroke's end.
        let down = (2.0 * remaining * ramp / speed.max(1e-9)).sqrt() / ramp;
        let direction = if self.stroke.is_multiple_of(2) { 1.0 } else { -1.0 };
        direction * speed * up.min(down).min(1.0)
    }
}

impl Controller for RubbingController {
    fn tick(&mut self, input: &TickInput<'_>, out: &mut TickOutput) {
        let t = input.period_s;
        let s = input.state;
        let gains = self.gains;
        if self.control.is_none() {
            self.hold_m = s.position_m;
            self.x_ref_m = s.position_m.x;
        }
        let mut control = self
            .control
            .unwrap_or_else(|| AccelerationControl::new(gains, input.specs.internal, t));
        let observed = control.observe(input.applied.force_n, s.velocity_mps);
        let normal_n = observed.external_n.z;
        self.phase_s += t;
        let mut v_cmd = 0.0;
        let mut force_cmd = self.plan.normal_force_n;
        let a_z = match self.phase {
            RubbingPhase::Approach => {
                if normal_n > 0.5 * self.plan.normal_force_n {
                    self.enter(RubbingPhase::Settle);
                }
                gains.kv_per_s * (-0.005 - s.velocity_mps.z)
            }
            RubbingPhase::Settle | RubbingPhase::Rub => {
                if self.phase == RubbingPhase::Settle && self.phase_s >= 0.3 {
                    self.enter(RubbingPhase::Rub);
                    self.stroke_start_m = self.x_ref_m;
                }
                if self.phase == RubbingPhase::Rub {
                    self.rub_s += t;
                    force_cmd = self.plan.normal_force_at(self.rub_s);
                    let covered = (self.x_ref_m - self.stroke_start_m).abs();
                    v_cmd = self.stroke_velocity(covered, self.phase_s);
                    self.x_ref_m += v_cmd * t;
                    if covered >= self.plan.stroke_m - 1e-9 || v_cmd == 0.0 && self.phase_s > self.plan.ramp_s
                    {
                        self.stroke += 1;
                        self.phase_s = 0.0;
                        self.stroke_start_m = self.x_ref_m;
                        if self.stroke >= self.plan.stroke_speeds_mps.len() {
                            self.enter(RubbingPhase::Lift);
                        }
                    }
                }
                -control.force_accel(force_cmd, normal_n)
            }
            RubbingPhase::Lift | RubbingPhase::Done => {
                if self.phase == RubbingPhase::Lift && self.phase_s >= 0.3 {
                    self.enter(RubbingPhase::Done);
                }
                gains.kv_per_s * (0.01 - s.velocity_mps.z)
            }
        };
        let x_ref = DVec3::new(self.x_ref_m, self.hold_m.y, s.position_m.z);
        let v_ref = DVec3::new(v_cmd, 0.0, s.velocity_mps.z);
        let mut a = control.position_accel(x_ref, v_ref, DVec3::ZERO, s.position_m, s.velocity_mps);
        a.z = a_z;
        out.command.force_n = control.motor_force(a);
        out.command.gripper_force_n = 0.0;
        self.control = Some(control);
        let direction = if self.stroke.is_multiple_of(2) { 1.0 } else { -1.0 };
        out.channels = [
            -observed.external_n.x * direction,
            normal_n,
            v_cmd,
            self.x_ref_m,
            self.phase.code(),
            force_cmd,
            self.stroke as f64,
            0.0,
            0.0,
            0.0,
            0.0,
            0.0,
        ];
    }

    fn finished(&self) -> bool {
        self.phase == RubbingPhase::Done
    }
}
