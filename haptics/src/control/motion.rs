//! Acceleration-based motion control with a disturbance observer (Nakano ch. 2): position
//! control by PD on an acceleration reference, force control by a proportional force gain,
//! and the DOB turning the acceleration reference into an actuator force robustly.

use glam::DVec3;

use super::observer::{InternalForces, Observed, Observers3};

/// The gains and observer settings of Nakano's Table 3.1.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MotionGains {
    /// Position gain K_p, s⁻².
    pub kp_per_s2: f64,
    /// Velocity gain K_v, s⁻¹.
    pub kv_per_s: f64,
    /// Force gain K_f (dimensionless: force error to force reference).
    pub kf: f64,
    /// DOB cut-off g_dis, rad/s.
    pub g_dis_radps: f64,
    /// RFOB cut-off g_reac, rad/s.
    pub g_reac_radps: f64,
    /// Nominal mass M_n, kg.
    pub mass_n_kg: f64,
}

impl MotionGains {
    /// Nakano Table 3.1: K_p 900 s⁻², K_v 60 s⁻¹ (critically damped at 30 rad/s), K_f 0.8,
    /// g_dis = g_reac = 50 rad/s, M_n 0.3 kg.
    pub const NAKANO: MotionGains = MotionGains {
        kp_per_s2: 900.0,
        kv_per_s: 60.0,
        kf: 0.8,
        g_dis_radps: 50.0,
        g_reac_radps: 50.0,
        mass_n_kg: 0.3,
    };
}

/// PD + DOB on three axes, with an RFOB for the external force.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AccelerationControl {
    gains: MotionGains,
    observers: Observers3,
    observed: Observed,
}

impl AccelerationControl {
    /// A controller with `gains`, internal forces `internal` (the device's:
    /// [`crate::device::DeviceSpecs::internal`]), sampled every `period_s`.
    pub fn new(gains: MotionGains, internal: InternalForces, period_s: f64) -> Self {
        Self {
            gains,
            observers: Observers3::new(
                gains.mass_n_kg,
                gains.g_dis_radps,
                gains.g_reac_radps,
                internal,
                period_s,
            ),
            observed: Observed {
                disturbance_n: DVec3::ZERO,
                external_n: DVec3::ZERO,
            },
        }
    }

    /// The gains.
    pub fn gains(&self) -> &MotionGains {
        &self.gains
    }

    /// Updates the observers with the force applied last period and the velocity now; call
    /// once per tick before the `*_accel` and `motor_force` calls.
    pub fn observe(&mut self, applied_force_n: DVec3, velocity_mps: DVec3) -> Observed {
        self.observed = self.observers.update(applied_force_n, velocity_mps);
        self.observed
    }

    /// The latest observation.
    pub fn observed(&self) -> Observed {
        self.observed
    }

    /// PD acceleration reference to track `(x_ref, v_ref)` with feed-forward `a_ref`.
    pub fn position_accel(&self, x_ref: DVec3, v_ref: DVec3, a_ff: DVec3, x: DVec3, v: DVec3) -> DVec3 {
        a_ff + self.gains.kp_per_s2 * (x_ref - x) + self.gains.kv_per_s * (v_ref - v)
    }

    /// Force-control acceleration reference along one axis: `K_f (f_cmd − f_res) / M_n`,
    /// where `f_res` is the force the tool exerts on the environment.
    pub fn force_accel(&self, force_cmd_n: f64, force_res_n: f64) -> f64 {
        self.gains.kf * (force_cmd_n - force_res_n) / self.gains.mass_n_kg
    }

    /// Actuator force for acceleration reference `a_ref`: `M_n a_ref + f̂_dis`.
    pub fn motor_force(&self, a_ref: DVec3) -> DVec3 {
        self.gains.mass_n_kg * a_ref + self.observed.disturbance_n
    }
}
