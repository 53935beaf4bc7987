//! The operator's hand, simulated: a spring–damper from the end effector to a hand target that
//! a script (or, later, live UI input) moves.
//!
//! Grip impedance: a relaxed precision grip on a stylus is a few hundred N/m with a few N·s/m
//! (Hajian & Howe 1997 measured 200–800 N/m at the fingertip); the defaults sit at the low end,
//! a light grip.

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

use glam::DVec3;

/// Impedance of the hand holding the end effector.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HandImpedance {
    /// Grip stiffness, N/m.
    pub stiffness_npm: f64,
    /// Grip damping, N·s/m.
    pub damping_nspm: f64,
}

impl Default for HandImpedance {
    fn default() -> Self {
        Self {
            stiffness_npm: 300.0,
            damping_nspm: 4.0,
        }
    }
}

/// Where the hand wants the end effector to be.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct HandTarget {
    /// Target position, m.
    pub position_m: DVec3,
    /// Target velocity, m/s.
    pub velocity_mps: DVec3,
    /// Gripper opening the fingers aim for, m.
    pub gripper_gap_m: f64,
}

/// Moves the hand target over time. Called on the haptic thread (inside the simulated device):
/// allocation-free.
pub trait HandScript: Send {
    /// The target at time `time_s`.
    fn target(&mut self, time_s: f64) -> HandTarget;
}

/// A piecewise-linear path through timed waypoints, held at the last one.
#[derive(Debug, Clone, PartialEq)]
pub struct Waypoints {
    points: Vec<(f64, DVec3)>,
    gripper_gap_m: f64,
    cursor: usize,
}

impl Waypoints {
    /// A path through `(time_s, position_m)` points; times must increase (later points with
    /// earlier times are ignored). An empty path holds the origin.
    pub fn new(points: &[(f64, DVec3)]) -> Self {
        let mut kept: Vec<(f64, DVec3)> = Vec::with_capacity(points.len());
        for &(t, p) in points {
            if t.is_finite() && p.is_finite() && kept.last().is_none_or(|&(last, _)| t > last) {
                kept.push((t, p));
            }
        }
        Self {
            points: kept,
            gripper_gap_m: 0.01,
            cursor: 0,
        }
    }

    /// Time of the last waypoint.
    pub fn end_s(&self) -> f64 {
        self.points.last().map_or(0.0, |p| p.0)
    }
}

impl HandScript for Waypoints {
    fn target(&mut self, time_s: f64) -> HandTarget {
        let hold = |p: DVec3, gap| HandTarget {
            position_m: p,
            velocity_mps: DVec3::ZERO,
            gripper_gap_m: gap,
        };
        let Some(&(t0, p0)) = self.points.first() else {
            return hold(DVec3::ZERO, self.gripper_gap_m);
        };
        if time_s <= t0 {
            return hold(p0, self.gripper_gap_m);
        }
        if self.cursor >= self.points.len() || self.points[self.cursor].0 > time_s {
            self.cursor = 0;
        }
        while self.cursor + 1 < self.points.len() && self.points[self.cursor + 1].0 <= time_s {
            self.cursor += 1;
        }
        let (ta, pa) = self.points[self.cursor];
        match self.points.get(self.cursor + 1) {
            None => hold(pa, self.gripper_gap_m),
            Some(&(tb, pb)) => {
                let v = (pb - pa) / (tb - ta);
                HandTarget {
                    position_m: pa + v * (time_s - ta),
                    velocity_mps: v,
                    gripper_gap_m: self.gripper_gap_m,
                }
            }
        }
    }
}

/// A hand target set from another thread (the UI's input), read lock-free by the simulator.
#[derive(Debug, Default)]
pub struct LiveHand {
    position: [AtomicU64; 3],
    gap: AtomicU64,
}

impl LiveHand {
    /// A live target at the origin.
    pub fn new() -> Arc<Self> {
        Arc::new(Self::default())
    }

    /// Moves the target (from any thread).
    pub fn set(&self, position_m: DVec3, gripper_gap_m: f64) {
        for (slot, v) in self.position.iter().zip(position_m.to_array()) {
            slot.store(v.to_bits(), Ordering::Relaxed);
        }
        self.gap.store(gripper_gap_m.to_bits(), Ordering::Relaxed);
    }
}

impl HandScript for Arc<LiveHand> {
    fn target(&mut self, _time_s: f64) -> HandTarget {
        let p = |i: usize| f64::from_bits(self.position[i].load(Ordering::Relaxed));
        HandTarget {
            position_m: DVec3::new(p(0), p(1), p(2)),
            velocity_mps: DVec3::ZERO,
            gripper_gap_m: f64::from_bits(self.gap.load(Ordering::Relaxed)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn waypoints_interpolate_and_hold() {
        let mut w = Waypoints::new(&[
            (0.0, DVec3::ZERO),
            (1.0, DVec3::new(0.0, 0.0, -0.01)),
            (0.5, DVec3::ONE),
            (2.0, DVec3::new(0.0, 0.0, -0.01)),
        ]);
        assert_eq!(w.end_s(), 2.0);
        let t = w.target(0.5);
        assert!((t.position_m.z + 0.005).abs() < 1e-15 && (t.velocity_mps.z + 0.01).abs() < 1e-15);
        assert_eq!(w.target(1.5).velocity_mps, DVec3::ZERO);
        assert_eq!(w.target(5.0).position_m.z, -0.01);
        // Going back in time works too.
        assert_eq!(w.target(0.0).position_m, DVec3::ZERO);
        let live = LiveHand::new();
        live.set(DVec3::X, 0.02);
        let mut script = live.clone();
        assert_eq!(script.target(0.0).position_m, DVec3::X);
    }
}
