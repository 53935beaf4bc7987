//! The scripted trainee of headless runs: a hand target moving through timed waypoints.

use glam::DVec3;
use sim::Waypoints;

use crate::scene::Task;

/// Settle time at the start and end of a task, s.
const SETTLE_S: f64 = 0.3;

/// The hand's path for `task` on a surface at `surface_z_m` (device coordinates, z up),
/// holding the tool with a grip of `grip_npm`.
pub fn trainee(task: &Task, surface_z_m: f64, grip_npm: f64) -> Waypoints {
    match *task {
        Task::Insertion {
            start_above_m,
            depth_m,
            speed_mps,
            hold_s,
            withdraw_speed_mps,
            ..
        } => {
            let top = DVec3::new(0.0, 0.0, surface_z_m + start_above_m);
            let bottom = DVec3::new(0.0, 0.0, surface_z_m - depth_m);
            let stroke_m = start_above_m + depth_m;
            let t_in = SETTLE_S + stroke_m / speed_mps;
            let t_hold = t_in + hold_s;
            let t_out = t_hold + stroke_m / withdraw_speed_mps;
            Waypoints::new(&[
                (0.0, top),
                (SETTLE_S, top),
                (t_in, bottom),
                (t_hold, bottom),
                (t_out, top),
                (t_out + SETTLE_S, top),
            ])
        }
        Task::Rub {
            normal_force_n,
            stroke_m,
            speed_mps,
            strokes,
        } => {
            // The grip is a spring: to press with F the hand aims F/k below where the tool
            // rests, and the tool itself sinks a little into the contact spring.
            let press_m = normal_force_n / grip_npm.max(1.0) + 0.001;
            let left = -stroke_m / 2.0;
            let above = DVec3::new(left, 0.0, surface_z_m + 0.003);
            let pressed = |x: f64| DVec3::new(x, 0.0, surface_z_m - press_m);
            let mut points = vec![(0.0, above), (SETTLE_S, above), (SETTLE_S + 0.5, pressed(left))];
            let mut t = SETTLE_S + 0.8;
            points.push((t, pressed(left)));
            let mut x = left;
            for _ in 0..strokes {
                x = -x;
                t += stroke_m / speed_mps;
                points.push((t, pressed(x)));
            }
            points.push((t + 0.3, pressed(x)));
            points.push((t + 0.8, DVec3::new(x, 0.0, surface_z_m + 0.003)));
            Waypoints::new(&points)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use sim::HandScript;

    #[test]
    fn insertion_reaches_depth_at_speed_and_returns() {
        let task = Task::Insertion {
            start_above_m: 0.002,
            depth_m: 0.03,
            speed_mps: 0.01,
            hold_s: 1.0,
            withdraw_speed_mps: 0.02,
            goal: None,
        };
        let mut w = trainee(&task, -0.02, 300.0);
        assert!((w.end_s() - (0.3 + 3.2 + 1.0 + 1.6 + 0.3)).abs() < 1e-9);
        let mid = w.target(1.0);
        assert!((mid.velocity_mps.z + 0.01).abs() < 1e-12);
        assert!((w.target(3.5).position_m.z + 0.05).abs() < 1e-12);
        assert!((w.target(10.0).position_m.z + 0.018).abs() < 1e-12);
    }

    #[test]
    fn rubbing_presses_with_the_grip_and_strokes_back_and_forth() {
        let task = Task::Rub {
            normal_force_n: 1.5,
            stroke_m: 0.03,
            speed_mps: 0.01,
            strokes: 2,
        };
        let mut w = trainee(&task, 0.0, 300.0);
        let pressed = w.target(1.0).position_m;
        assert!((pressed.z + 0.006).abs() < 1e-12 && (pressed.x + 0.015).abs() < 1e-12);
        assert!((w.target(1.1 + 1.5).position_m.x - 0.0).abs() < 1e-9);
        assert!((w.target(1.1 + 3.0).position_m.x - 0.015).abs() < 1e-9);
        assert!((w.target(1.1 + 4.5).position_m.x - 0.0).abs() < 1e-9);
    }
}
