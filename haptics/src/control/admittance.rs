//! Admittance rendering (Li & Bi Fig. 11): the operator's force minus the model's force drives
//! a virtual mass–damper; its motion is the reference an inner PD + DOB loop makes the device
//! follow.
//!
//! Per tick, with period T:
//! 1. The RFOB estimates the hand's force on the end effector, `f̂_h` (the Omega.7 has no force
//!    sensor; a device with one would use its reading).
//! 2. The environment (a force law in a geometry) gives its force on the *virtual* tool,
//!    `f_e(x_v, v_v)`.
//! 3. The virtual tool moves: `M_v v̇_v = f̂_h + f_e − B_v v_v`, integrated with the damping
//!    implicit and the position semi-implicit:
//!    `v_v ← (v_v + T (f̂_h + f_e)/M_v) / (1 + T B_v/M_v)`, `x_v ← x_v + T v_v`.
//! 4. The device tracks `(x_v, v_v, v̇_v)` with PD + DOB: `f_m = M_n (v̇_v + K_p (x_v − x) + K_v
//!    (v_v − v)) + f̂_dis`.
//!
//! # Stability limits
//! - The virtual mass–damper alone: with implicit damping its pole `1/(1 + T B_v/M_v)` is inside
//!   the unit circle for every positive `M_v`, `B_v`, `T`; explicit damping would need
//!   `B_v T / M_v < 2`.
//! - A stiff environment of stiffness `K_e` on the virtual mass (semi-implicit Euler) needs
//!   `T < 2 √(M_v/K_e)`, i.e. `M_v > K_e T²/4`: at 1 kHz and the Omega.7's 5000 N/m that is only
//!   1.25 g. The binding limits are the loops around it:
//! - The hand (stiffness `k_h`) on the virtual mass makes a resonance at `√(k_h/M_v)`; the
//!   inner loop (bandwidth `√K_p` = 30 rad/s with Nakano's gains) and the RFOB (`g_reac` = 50
//!   rad/s) add phase lag there. Keep `√((k_h + K_e)/M_v)` well below both (a factor of 3
//!   gives comfortable damping): `M_v ≥ 9 (k_h + K_e)/K_p`. For a firm grip (300 N/m) and the
//!   capsule's stiffest loading (≈ 250 N/m) that is ≈ 5 kg with Nakano's gains — too heavy
//!   to feel free — so the defaults raise the inner loop to `K_p` = 6400 s⁻², `K_v` = 160 s⁻¹
//!   (80 rad/s, critically damped) and the observers to 150 rad/s, which allows
//!   `M_v` ≈ 0.8 kg.
//! - The inner loop itself is discrete: `√K_p · T` and `K_v T` must stay well below 1 (here
//!   0.08 and 0.16 at 1 kHz); at 250 Hz the defaults would be marginal.
//! - `B_v` adds damping the operator feels as viscosity (`B_v v`); the defaults' 4 N·s/m is
//!   0.02 N at 5 mm/s, below the force resolution of the identified models.
//!
//! The `admittance` tests check on the simulated Omega.7 that the defaults are passive: with
//! the hand's target still, the energy stored in the hand, the device and the virtual tool
//! never grows.

use glam::DVec3;

use super::motion::{AccelerationControl, MotionGains};
use super::observer::InternalForces;
use crate::law::Environment;
use crate::rt::{Controller, TickInput, TickOutput};

/// Settings of the admittance renderer.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AdmittanceConfig {
    /// Virtual mass M_v, kg.
    pub virtual_mass_kg: f64,
    /// Virtual damping B_v, N·s/m.
    pub virtual_damping_nspm: f64,
    /// Inner PD + DOB loop and observers.
    pub gains: MotionGains,
    /// The device's own forces, removed by the RFOB; `None`: those of the device being driven
    /// ([`crate::device::DeviceSpecs::internal`], read at the first tick).
    pub internal: Option<InternalForces>,
}

impl Default for AdmittanceConfig {
    fn default() -> Self {
        Self {
            virtual_mass_kg: 0.8,
            virtual_damping_nspm: 4.0,
            gains: MotionGains {
                kp_per_s2: 6400.0,
                kv_per_s: 160.0,
                kf: MotionGains::NAKANO.kf,
                g_dis_radps: 150.0,
                g_reac_radps: 150.0,
                mass_n_kg: MotionGains::NAKANO.mass_n_kg,
            },
            internal: None,
        }
    }
}

/// Channels recorded by [`Admittance`] (indices into [`crate::rt::HapticSample::channels`]).
pub mod channel {
    /// Estimated hand force, z, N.
    pub const HAND_FORCE_Z_N: usize = 0;
    /// Environment force on the virtual tool, z, N.
    pub const MODEL_FORCE_Z_N: usize = 1;
    /// Virtual tool position, z, m.
    pub const VIRTUAL_Z_M: usize = 2;
    /// Virtual tool velocity, z, m/s.
    pub const VIRTUAL_VZ_MPS: usize = 3;
    /// Environment state code (e.g. puncture state).
    pub const ENV_STATE: usize = 4;
    /// Environment's main input (needle depth, normal force).
    pub const ENV_INPUT: usize = 5;
    /// Estimated hand force, x, N.
    pub const HAND_FORCE_X_N: usize = 6;
    /// Environment force on the virtual tool, x, N.
    pub const MODEL_FORCE_X_N: usize = 7;
}

/// The admittance renderer of an environment `E`.
#[derive(Debug, Clone)]
pub struct Admittance<E> {
    config: AdmittanceConfig,
    environment: E,
    control: Option<AccelerationControl>,
    position_m: DVec3,
    velocity_mps: DVec3,
}

impl<E: Environment> Admittance<E> {
    /// Renders `environment` with `config`. The virtual tool starts where the device is at the
    /// first tick, at rest.
    pub fn new(environment: E, config: AdmittanceConfig) -> Self {
        Self {
            config,
            environment,
            control: None,
            position_m: DVec3::ZERO,
            velocity_mps: DVec3::ZERO,
        }
    }

    /// The environment.
    pub fn environment(&self) -> &E {
        &self.environment
    }

    /// The virtual tool's position and velocity.
    pub fn virtual_tool(&self) -> (DVec3, DVec3) {
        (self.position_m, self.velocity_mps)
    }
}

impl<E: Environment> Controller for Admittance<E> {
    fn tick(&mut self, input: &TickInput<'_>, out: &mut TickOutput) {
        let c = self.config;
        let t = input.period_s;
        let state = input.state;
        let control = match &mut self.control {
            Some(control) => control,
            None => {
                self.position_m = state.position_m;
                self.velocity_mps = DVec3::ZERO;
                self.control.insert(AccelerationControl::new(
                    c.gains,
                    c.internal.unwrap_or(input.specs.internal),
                    t,
                ))
            }
        };
        let observed = control.observe(input.applied.force_n, state.velocity_mps);
        let hand = observed.external_n;
        let env = self.environment.force(self.position_m, self.velocity_mps);
        let m = c.virtual_mass_kg.max(1e-6);
        let previous = self.velocity_mps;
        let mut v =
            (previous + t * (hand + env.force_n) / m) / (1.0 + t * c.virtual_damping_nspm.max(0.0) / m);
        if !v.is_finite() {
            v = DVec3::ZERO;
        }
        self.velocity_mps = v;
        self.position_m += t * v;
        let a_v = (v - previous) / t;
        let a_ref = control.position_accel(self.position_m, v, a_v, state.position_m, state.velocity_mps);
        out.command.force_n = control.motor_force(a_ref);
        out.command.gripper_force_n = 0.0;
        out.flags |= env.flags;
        out.channels = [
            hand.z,
            env.force_n.z,
            self.position_m.z,
            v.z,
            env.state,
            env.input,
            hand.x,
            env.force_n.x,
            0.0,
            0.0,
            0.0,
            0.0,
        ];
    }
}
