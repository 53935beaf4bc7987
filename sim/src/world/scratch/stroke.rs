//! The arm's motion along one stroke.

use std::f64::consts::PI;

use super::RAMP_S;

/// A straight stroke of fixed length played back in a given time: raised-cosine speed ramps at
/// both ends around a constant-speed middle. The plateau speed is `length / (duration − ramp)`
/// since each half-cosine ramp covers half the distance of a constant-speed one. The
/// acceleration is continuous, as a PID tracking a smooth recorded trajectory would give.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Stroke {
    pub(super) length_m: f64,
    pub(super) duration_s: f64,
    pub(super) ramp_s: f64,
    pub(super) speed_mps: f64,
}

impl Stroke {
    pub(super) fn new(length_m: f64, duration_s: f64) -> Self {
        let ramp_s = RAMP_S.min(0.25 * duration_s);
        Self {
            length_m,
            duration_s,
            ramp_s,
            speed_mps: length_m / (duration_s - ramp_s),
        }
    }

    /// Arc length, speed and acceleration at time `t_s`.
    pub(super) fn at(&self, t_s: f64) -> (f64, f64, f64) {
        let t = t_s.clamp(0.0, self.duration_s);
        let (v, tr) = (self.speed_mps, self.ramp_s);
        if t < tr {
            let (sin, cos) = (PI * t / tr).sin_cos();
            (
                0.5 * v * (t - tr / PI * sin),
                0.5 * v * (1.0 - cos),
                0.5 * v * PI / tr * sin,
            )
        } else if t > self.duration_s - tr {
            let tau = self.duration_s - t;
            let (sin, cos) = (PI * tau / tr).sin_cos();
            (
                self.length_m - 0.5 * v * (tau - tr / PI * sin),
                0.5 * v * (1.0 - cos),
                -0.5 * v * PI / tr * sin,
            )
        } else {
            (0.5 * v * tr + v * (t - tr), v, 0.0)
        }
    }
}
