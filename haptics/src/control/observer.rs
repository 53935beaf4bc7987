//! Disturbance observer (DOB) and reaction-force observer (RFOB), Nakano ch. 2.
//!
//! The end effector along one axis obeys `M ẍ = f_m − f_load` (Eq. 2.1–2.4), with `f_m` the
//! actuator force and `f_load = f_ext + f_g + f_fric`. With nominal mass `M_n` the DOB
//! estimates the disturbance `f_dis = f_m − M_n ẍ` (Eq. 2.9) through a first-order low-pass
//! `g_dis/(s + g_dis)` (Eqs. 2.10–2.11). Acceleration is never differentiated explicitly: the
//! equivalent form of Fig. 2.4 filters `f_m + g·M_n·ẋ` and subtracts `g·M_n·ẋ`, which is the
//! same transfer function with the differentiation folded into the filter. Adding `f̂_dis` to
//! the actuator command (Eq. 2.12) leaves the plant a pure mass driven by the acceleration
//! reference, with the disturbance seen only through `s/(s + g_dis)` (Eq. 2.13).
//!
//! The RFOB is the same observer with the known internal forces (gravity, the device's own
//! friction) removed before filtering (Eq. 2.16), cut-off `g_reac` (Eq. 2.17).
//!
//! Sign: the observers here return the external force **acting on the end effector** (the
//! hand pushing it, the surface pushing back) — Nakano's `f_ext` with its sign reversed, so that
//! positive means "pushes the tool along +axis".
//!
//! Discretisation: backward Euler of the low-pass, `y += a·(u − y)` with `a = gT/(1 + gT)`,
//! stable for any `g·T`; at `g = 50 rad/s`, `T = 1 ms` the estimate lags a step by 20 ms.

use glam::DVec3;

pub use crate::device::InternalForces;

/// First-order low-pass `g/(s + g)` by backward Euler.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Lpf {
    a: f64,
    y: Option<f64>,
}

impl Lpf {
    fn new(cutoff_radps: f64, period_s: f64) -> Self {
        let gt = (cutoff_radps * period_s).max(0.0);
        Self {
            a: gt / (1.0 + gt),
            y: None,
        }
    }

    fn update(&mut self, u: f64, initial: f64) -> f64 {
        let y = self.y.unwrap_or(initial);
        let y = y + self.a * (u - y);
        self.y = Some(if y.is_finite() { y } else { initial });
        y
    }
}

/// Disturbance observer along one axis (Nakano Eqs. 2.9–2.12, Fig. 2.4).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DisturbanceObserver {
    mass_kg: f64,
    cutoff_radps: f64,
    lpf: Lpf,
}

impl DisturbanceObserver {
    /// An observer for nominal mass `mass_kg`, cut-off `cutoff_radps`, sampled every
    /// `period_s`.
    pub fn new(mass_kg: f64, cutoff_radps: f64, period_s: f64) -> Self {
        Self {
            mass_kg,
            cutoff_radps,
            lpf: Lpf::new(cutoff_radps, period_s),
        }
    }

    /// Feeds the actuator force applied over the last period and the velocity now; returns
    /// `f̂_dis`, the force to add to the actuator command to cancel the disturbance (Eq. 2.12
    /// with `K_tn I_cmp = f̂_dis`). Starts from zero disturbance.
    pub fn update(&mut self, motor_force_n: f64, velocity_mps: f64) -> f64 {
        let gmv = self.cutoff_radps * self.mass_kg * velocity_mps;
        self.lpf.update(motor_force_n + gmv, gmv) - gmv
    }
}

/// Reaction-force observer along one axis (Nakano Eqs. 2.15–2.17).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReactionForceObserver {
    mass_kg: f64,
    cutoff_radps: f64,
    internal: InternalForces,
    lpf: Lpf,
}

impl ReactionForceObserver {
    /// An observer for nominal mass `mass_kg`, cut-off `cutoff_radps`, internal forces
    /// `internal`, sampled every `period_s`.
    pub fn new(mass_kg: f64, cutoff_radps: f64, internal: InternalForces, period_s: f64) -> Self {
        Self {
            mass_kg,
            cutoff_radps,
            internal,
            lpf: Lpf::new(cutoff_radps, period_s),
        }
    }

    /// Feeds the actuator force applied over the last period and the velocity now; returns
    /// the estimated external force acting on the end effector along the axis.
    pub fn update(&mut self, motor_force_n: f64, velocity_mps: f64) -> f64 {
        let gmv = self.cutoff_radps * self.mass_kg * velocity_mps;
        let load = self
            .lpf
            .update(motor_force_n + gmv - self.internal.load_n(velocity_mps), gmv)
            - gmv;
        -load
    }
}

/// A DOB and an RFOB on each of x, y, z.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Observers3 {
    dob: [DisturbanceObserver; 3],
    rfob: [ReactionForceObserver; 3],
}

/// One update of [`Observers3`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Observed {
    /// Disturbance to add to the actuator command, N.
    pub disturbance_n: DVec3,
    /// External force on the end effector, N.
    pub external_n: DVec3,
}

impl Observers3 {
    /// Observers for nominal mass `mass_kg`, cut-offs `g_dis`, `g_reac`, the same internal
    /// forces on every axis.
    pub fn new(
        mass_kg: f64,
        g_dis_radps: f64,
        g_reac_radps: f64,
        internal: InternalForces,
        period_s: f64,
    ) -> Self {
        Self {
            dob: [DisturbanceObserver::new(mass_kg, g_dis_radps, period_s); 3],
            rfob: [ReactionForceObserver::new(mass_kg, g_reac_radps, internal, period_s); 3],
        }
    }

    /// Feeds the applied actuator force and the measured velocity.
    pub fn update(&mut self, motor_force_n: DVec3, velocity_mps: DVec3) -> Observed {
        let f = motor_force_n.to_array();
        let v = velocity_mps.to_array();
        let mut dis = [0.0; 3];
        let mut ext = [0.0; 3];
        for i in 0..3 {
            dis[i] = self.dob[i].update(f[i], v[i]);
            ext[i] = self.rfob[i].update(f[i], v[i]);
        }
        Observed {
            disturbance_n: DVec3::from_array(dis),
            external_n: DVec3::from_array(ext),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 0.3 kg mass pushed by a motor and a constant external force, integrated finely.
    #[test]
    fn observers_recover_a_constant_external_force_with_their_time_constant() {
        let (m, dt) = (0.3, 1e-3);
        let mut dob = DisturbanceObserver::new(m, 50.0, dt);
        let mut rfob = ReactionForceObserver::new(m, 50.0, InternalForces::NONE, dt);
        let external = 0.7;
        let (mut v, mut motor) = (0.0, 0.0);
        let (mut d, mut e) = (0.0, 0.0);
        for k in 0..400 {
            // Motor: a sine, so the velocity is not trivial.
            let next_motor = 0.2 * (k as f64 * 0.05).sin();
            for _ in 0..10 {
                v += (motor + external) / m * dt / 10.0;
            }
            d = dob.update(motor, v);
            e = rfob.update(motor, v);
            if k == 20 {
                // After one time constant (20 ms): 1 − 1/e of the step.
                assert!((e / external - (1.0 - (-1.0f64).exp())).abs() < 0.05, "{e}");
            }
            motor = next_motor;
        }
        assert!((e - external).abs() < 1e-3, "{e}");
        // The DOB reports the load opposing the motor: the negative of the push.
        assert!((d + external).abs() < 1e-3, "{d}");
    }

    #[test]
    fn rfob_removes_the_internal_friction() {
        let (m, dt) = (0.3, 1e-3);
        let internal = InternalForces {
            viscous_nspm: 2.0,
            coulomb_n: 0.1,
            coulomb_band_mps: 1e-3,
            gravity_n: 0.0,
        };
        let mut rfob = ReactionForceObserver::new(m, 50.0, internal, dt);
        // Constant velocity: the motor balances the internal friction exactly.
        let v = 0.05;
        let motor = internal.load_n(v);
        let mut e = 1.0;
        for _ in 0..500 {
            e = rfob.update(motor, v);
        }
        assert!(e.abs() < 1e-9, "{e}");
    }
}
